"""Spatio-temporal parameters against Vicon Nexus' own values (issue 16).

Run:  .venv/bin/python benchmarks/gait_parameters_nexus.py

For every C3D file under ``../shared/data`` whose ``ANALYSIS`` group holds Nexus' (or
Vicon Workstation's) spatio-temporal parameters, prints one Markdown table per file and
side: our value of the cycle the reference program reports, with its definitions
(:func:`~fuzzygait.gait.spatiotemporal.reference_convention`: Nexus -- the side's first
complete gait cycle, the command's ``--cycles nexus``; Vicon Workstation -- the first
cycle with Workstation's step and opposite-foot-off definitions, ``--cycles
workstation``), Nexus' value converted to Nexus 2 units
(:func:`~fuzzygait.gait.spatiotemporal.nexus_reference`), the difference and whether it
is within issue 16's tolerance (one frame for times and phases, 1 % otherwise).

Then the Nexus definitions beside a Workstation file's values (what differs), and every
cycle's stride/step lengths from the toe, heel and ankle markers.
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
    reference_convention,
    side_parameters,
    spatiotemporal_parameters,
)
from fuzzygait.io import read_c3d

DATA = VICON.parent


def _fmt(value: float) -> str:
    return "–" if not math.isfinite(value) else f"{value:.6g}"


def side_table(trial: Trial, code: str, convention: str) -> list[str]:
    """Ours against the reference, with the definitions of ``convention``."""
    result = spatiotemporal_parameters(trial).sides[code]
    reference = nexus_reference(trial)[code]
    cycle = result.first_complete if convention == "nexus" else result.first
    assert cycle is not None
    values = cycle.values if convention == "nexus" else cycle.workstation
    which = (f"first complete of {len(result.cycles)}" if convention == "nexus" else
             f"first of {len(result.cycles)}, {'complete' if cycle.complete else 'not complete'}")  # fmt: skip
    lines = [
        f"**{trial.name}, {SIDE_CONTEXTS[code]}, {convention} definitions** — our cycle {cycle.index} "
        f"({cycle.start_time:.4f}–{cycle.end_time:.4f} s, {which}), {trial.rate:g} Hz",
        "",
        "| parameter | unit | ours | reference | ours − reference | tolerance | within |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in NAMES:
        ours, theirs = values[name], reference.get(name, math.nan)
        tol = agreement_tolerance(name, theirs, trial.rate, values["Stride Time"])
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
        convention = reference_convention(trial)
        for code in SIDE_CONTEXTS:
            print("\n".join(side_table(trial, code, convention)) + "\n")
        if convention != "nexus":  # what Nexus' definitions would give instead
            for code in SIDE_CONTEXTS:
                print("\n".join(side_table(trial, code, "nexus")) + "\n")
        print("\n".join(explanations(trial)) + "\n")


if __name__ == "__main__":
    main()
