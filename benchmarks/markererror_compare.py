"""Before/after check of a change to the marker-error analysis (issue 40, item 2): the
default analysis of the sample trials saved, and two saved sets compared.

Run:  .venv/bin/python benchmarks/markererror_compare.py save DIR [--trials walking cgm24]
      .venv/bin/python benchmarks/markererror_compare.py compare BEFORE_DIR AFTER_DIR

``save``: per sample trial (``walking``: ``sample_data/walking.c3d``, cgm1.0;
``cgm24``: the synthetic CGM 2.4 session) the analysis of ``fuzzygait uncertainty`` with
its defaults (:func:`~fuzzygait.workflows.marker_uncertainty.analyse_run`: bands at α = 0,
0.25, 0.5, 0.75, 1, the allowable error for ±2.5°, the per-source bands), one worker, to
``DIR/<trial>.nc``, with its CPU seconds (``time.process_time``) in ``DIR/<trial>.cpu``.
``compare``: per trial the largest difference of the bands (deg, over every component,
α, bound and frame with a value in both), the undetermined flags that differ, the largest
difference of the allowable errors (mm, scale), the refined levels, and of the per-source
bands (deg); where the new bands are narrower or wider than the old (a narrower band
misses an extreme the old one found), and the CPU seconds of both.
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.markererror.result import read_marker_result, save_marker_result  # noqa: E402
from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings, analyse_run  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from markererror_work import trial_run  # noqa: E402

TRIALS = ("walking", "cgm24")


def save(directory: Path, trials: list[str]) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    for name in trials:
        run = trial_run(name)
        start = time.process_time()
        analysis = analyse_run(run, MarkerErrorSettings(workers=1))
        cpu = time.process_time() - start
        assert analysis.result is not None
        save_marker_result(analysis.result, directory / f"{name}.nc")
        (directory / f"{name}.cpu").write_text(f"{cpu:.2f}\n")
        print(f"{name}: CPU {cpu:.1f} s -> {directory / f'{name}.nc'}")


def _largest(a: np.ndarray, b: np.ndarray) -> tuple[float, int]:
    """Largest |a − b| where both are finite, and where one is finite and the other not."""
    both = np.isfinite(a) & np.isfinite(b)
    differ = int(np.count_nonzero(np.isfinite(a) != np.isfinite(b)))
    return (float(np.max(np.abs(a[both] - b[both]))) if both.any() else 0.0), differ


def compare(before: Path, after: Path) -> None:
    for name in TRIALS:
        if not (before / f"{name}.nc").exists() or not (after / f"{name}.nc").exists():
            continue
        old, new = read_marker_result(before / f"{name}.nc"), read_marker_result(after / f"{name}.nc")
        h0, h1 = old.bands["hull"].to_numpy(), new.bands["hull"].to_numpy()
        diff, nan = _largest(h0, h1)
        sign = np.array([-1.0, 1.0])[None, None, :, None]  # lower, upper: + = wider
        wider = (h1 - h0) * sign
        flags = int(np.count_nonzero(old.bands["undetermined"].to_numpy() != new.bands["undetermined"].to_numpy()))
        print(f"{name}: bands largest difference {diff:.2e} deg (NaN pattern differs at {nan}); new narrower by at "
              f"most {-np.nanmin(wider):.2e} deg, wider by at most {np.nanmax(wider):.2e} deg; "
              f"undetermined flags differing: {flags}")  # fmt: skip
        if old.allowable is not None and new.allowable is not None:
            mm, _ = _largest(old.allowable["mm"].to_numpy(), new.allowable["mm"].to_numpy())
            scale, _ = _largest(old.allowable["scale"].to_numpy(), new.allowable["scale"].to_numpy())
            runs = (old.allowable.attrs.get("runs"), new.allowable.attrs.get("runs"))
            status = int(np.count_nonzero(old.allowable["status"].to_numpy() != new.allowable["status"].to_numpy()))
            rh, rnan = _largest(old.allowable["hull"].to_numpy(), new.allowable["hull"].to_numpy())
            print(f"  refined levels' hulls: largest difference {rh:.2e} deg (NaN pattern differs at {rnan})")
            print(f"  allowable: largest difference {mm:.2e} mm (scale {scale:.2e}); status differing {status}; "
                  f"runs {runs[0]} -> {runs[1]}")  # fmt: skip
        if old.sources is not None and new.sources is not None:
            sd, snan = _largest(old.sources["hull"].to_numpy(), new.sources["hull"].to_numpy())
            print(f"  per-source bands: largest difference {sd:.2e} deg (NaN pattern differs at {snan})")
        files = [d / f"{name}.cpu" for d in (before, after)]
        cpu = [f.read_text().strip() if f.exists() else "?" for f in files]
        print(f"  CPU s: {cpu[0]} -> {cpu[1]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    s = sub.add_parser("save")
    s.add_argument("directory", type=Path)
    s.add_argument("--trials", nargs="+", default=list(TRIALS), choices=TRIALS)
    c = sub.add_parser("compare")
    c.add_argument("before", type=Path)
    c.add_argument("after", type=Path)
    args = parser.parse_args()
    if args.command == "save":
        save(args.directory, args.trials)
    else:
        compare(args.before, args.after)


if __name__ == "__main__":
    main()
