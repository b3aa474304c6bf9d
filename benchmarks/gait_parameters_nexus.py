"""Spatio-temporal parameters against Vicon Nexus' own values (issue 16).

Run:  .venv/bin/python benchmarks/gait_parameters_nexus.py

For every C3D file under ``../shared/data`` whose ``ANALYSIS`` group holds Nexus' (or
Vicon Workstation's) spatio-temporal parameters, prints one Markdown table per file and
side: our value of the side's first complete gait cycle (what Nexus reports; the
library's :func:`~fuzzygait.gait.spatiotemporal.spatiotemporal_parameters`, the command's
``--cycles nexus``), Nexus' value converted to Nexus 2 units
(:func:`~fuzzygait.gait.spatiotemporal.nexus_reference`), the difference and whether it
is within issue 16's tolerance (one frame for times and phases, 1 % otherwise).

Then, for the files with sub-frame events or a cycle choice of their own, what explains
a disagreement: our values of the cycle the reference used, and the stride/step lengths
from the heel and ankle markers instead of the toe.
"""

from __future__ import annotations

import math

from _setup import VICON

from fuzzygait.core.trial import Trial
from fuzzygait.gait.events import SIDE_CONTEXTS, trial_gait_events
from fuzzygait.gait.spatiotemporal import (
    NAMES,
    UNITS,
    agreement_tolerance,
    nexus_reference,
    side_parameters,
    spatiotemporal_parameters,
)
from fuzzygait.io import read_c3d

DATA = VICON.parent


def _fmt(value: float) -> str:
    return "–" if not math.isfinite(value) else f"{value:.6g}"


def reference_cycle(trial: Trial, code: str) -> int | None:
    """The cycle whose stride time is the reference's, when that is not the first
    complete one (Workstation reported a first cycle that is not complete)."""
    result = spatiotemporal_parameters(trial).sides[code]
    stride = nexus_reference(trial)[code].get("Stride Time", math.nan)
    first = result.first_complete
    if first is None or abs(first.values["Stride Time"] - stride) < 1e-4:
        return None
    matching = [c.index for c in result.cycles if abs(c.values["Stride Time"] - stride) < 1e-4]
    return matching[0] if matching else None


def side_table(trial: Trial, code: str, index: int | None = None) -> list[str]:
    """Ours against the reference for the first complete cycle (or cycle ``index``)."""
    result = spatiotemporal_parameters(trial).sides[code]
    reference = nexus_reference(trial)[code]
    cycle = result.first_complete if index is None else result.cycles[index]
    assert cycle is not None
    which = f"first complete of {len(result.cycles)}" if index is None else (
        f"{'complete' if cycle.complete else 'not complete'}: the cycle the reference used")
    lines = [
        f"**{trial.name}, {SIDE_CONTEXTS[code]}** — our cycle {cycle.index} "
        f"({cycle.start_time:.4f}–{cycle.end_time:.4f} s, {which}), {trial.rate:g} Hz",
        "",
        "| parameter | unit | ours | Nexus | ours − Nexus | tolerance | within |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in NAMES:
        ours, theirs = cycle.values[name], reference.get(name, math.nan)
        tol = agreement_tolerance(name, theirs, trial.rate, cycle.values["Stride Time"])
        diff = ours - theirs
        ok = "–" if not math.isfinite(diff) else ("yes" if abs(diff) <= tol else "**no**")
        rel = f" ({100 * diff / theirs:+.3f} %)" if math.isfinite(diff) and theirs else ""
        shown = f"{diff:+.3g}{rel}" if math.isfinite(diff) else "–"
        lines.append(f"| {name} | {UNITS[name]} | {_fmt(ours)} | {_fmt(theirs)} | {shown} | {tol:.3g} | {ok} |")
    return lines


def explanations(trial: Trial) -> list[str]:
    """Our values of every cycle (toe, heel, ankle lengths) against the reference."""
    events, _ = trial_gait_events(trial)
    reference = nexus_reference(trial)
    lines = [f"**{trial.name}: every cycle** (lengths in mm from the toe / heel / ankle markers; "
             "times in s; reference in the last row)", "",
             "| side | cycle | complete | stride time | opp. foot off % "
             "| stride TOE | HEE | ANK | step TOE | HEE | ANK |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for code in SIDE_CONTEXTS:
        by_marker = {m: side_parameters(trial, events, code, m) for m in ("TOE", "HEE", "ANK")}
        for k, cycle in enumerate(by_marker["TOE"].cycles):
            stride = [1000 * by_marker[m].cycles[k].values["Stride Length"] for m in by_marker]
            step = [1000 * by_marker[m].cycles[k].values["Step Length"] for m in by_marker]
            lines.append(f"| {SIDE_CONTEXTS[code]} | {k} | {'yes' if cycle.complete else 'no'} | "
                         f"{cycle.values['Stride Time']:.4f} | {_fmt(cycle.values['Opposite Foot Off'])} | "
                         + " | ".join(_fmt(v) for v in stride + step) + " |")  # fmt: skip
        ref = reference[code]
        lines.append(f"| {SIDE_CONTEXTS[code]} | reference | | {_fmt(ref.get('Stride Time', math.nan))} | "
                     f"{_fmt(ref.get('Opposite Foot Off', math.nan))} | "
                     f"{_fmt(1000 * ref.get('Stride Length', math.nan))} | | | "
                     f"{_fmt(1000 * ref.get('Step Length', math.nan))} | | |")  # fmt: skip
    return lines


def main() -> None:
    files = sorted(p for p in DATA.rglob("*") if p.suffix.lower() == ".c3d")
    if not files:
        print(f"{DATA} is absent: nothing to compare")
        return
    for path in files:
        try:
            trial = read_c3d(path)
        except Exception as exc:  # the broken format samples: not ours to compare
            print(f"<!-- {path.name}: not read ({type(exc).__name__}) -->")
            continue
        if not any(v.context in ("Left", "Right") for v in trial.analysis):
            continue
        print(f"### {path.relative_to(DATA)}\n")
        for code in SIDE_CONTEXTS:
            print("\n".join(side_table(trial, code)) + "\n")
        for code in SIDE_CONTEXTS:
            if (index := reference_cycle(trial, code)) is not None:
                print("\n".join(side_table(trial, code, index)) + "\n")
        print("\n".join(explanations(trial)) + "\n")


if __name__ == "__main__":
    main()
