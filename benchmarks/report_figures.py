"""Report page figures: the fixed grid layout (``viz/report/grid.py``) against
``tight_layout`` (the layout before it), in the same process, on the same session.

A synthetic session of TRIALS walking trials (windows of ``sample_data/walking.c3d``,
FRAMES frames) is reported ``--uncertainty none`` (the pages are then mostly figure
drawing) REPEATS times each way, alternating; the median wall times and their ratio.

    .venv/bin/python benchmarks/report_figures.py [--trials 2] [--frames 200] [--repeats 3]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from batch_report_scaling import make_session
from matplotlib.figure import Figure

from fuzzygait.viz.report import figures, session, sources
from fuzzygait.viz.report.grid import GridMargins, place_grid
from fuzzygait.workflows.batch_report import BatchReportRequest, write_batch_report

CALLERS = (figures, sources, session)


def tight(fig: Figure, top: float, margins: GridMargins | None = None) -> None:
    """The layout before the fixed grids: matplotlib's tight_layout below ``top``."""
    fig.tight_layout(rect=(0, 0, 1, top))


def use(layout: Callable[..., None]) -> None:
    for module in CALLERS:
        module.place_grid = layout  # type: ignore[attr-defined]


def timed(folder: Path, out: Path, n_trials: int) -> float:
    shutil.rmtree(out, ignore_errors=True)
    started = time.perf_counter()
    summary = write_batch_report(BatchReportRequest([folder], out, uncertainty="none", workers=1))
    elapsed = time.perf_counter() - started
    assert summary.n_ok == n_trials, summary
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=2)
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = make_session(Path(tmp) / "visit", args.trials, args.frames)
        times: dict[str, list[float]] = {"tight_layout": [], "fixed grid": []}
        timed(folder, Path(tmp) / "warm-up", args.trials)  # imports, font cache
        for _ in range(args.repeats):
            for name, layout in (("tight_layout", tight), ("fixed grid", place_grid)):
                use(layout)
                times[name].append(timed(folder, Path(tmp) / "report", args.trials))
        use(place_grid)
    median = {name: statistics.median(values) for name, values in times.items()}
    print(f"session of {args.trials} trials x {args.frames} frames, --uncertainty none, 1 worker, "
          f"{args.repeats} runs each (alternating):")  # fmt: skip
    for name, values in times.items():
        print(f"  {name:13s} median {median[name]:6.2f} s  ({', '.join(f'{v:.2f}' for v in values)})")
    print(f"  ratio fixed / tight_layout: {median['fixed grid'] / median['tight_layout']:.2f}")


if __name__ == "__main__":
    main()
