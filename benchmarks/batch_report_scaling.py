"""Batch report scaling (issue 16 Deliver 6): a session of N synthetic walking trials
(windows of ``sample_data/walking.c3d``, FRAMES frames each, different start frames) with
``--uncertainty fast`` in this process (1 worker) and on a local Dask cluster of 2
workers; wall times, whether every page's data (``data.npz``) is bit-identical, and a
re-run on the same folder (every trial reused).  Optionally also the
``--uncertainty none`` run over ``../shared/data/vicon`` and ``pig-options`` (--shared).

    .venv/bin/python benchmarks/batch_report_scaling.py [--trials 20] [--frames 40] [--shared]
    .venv/bin/python benchmarks/batch_report_scaling.py --commands [--trials 10] [--frames 40] [--repeats 3]

In the default mode the 2-worker batch runs after the 1-worker one in the same process, so
its pool starts from a process that has already imported and loaded everything.
``--commands``: instead, ``fuzzygait report SESSION --uncertainty fast --workers W`` as a
user types it, each run a fresh process, ``W`` = 1 and 2 alternated ``--repeats`` times;
wall seconds per run and the medians' ratio.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")  # the same BLAS threading as the pool's workers
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from fuzzygait.io import read_c3d, write_c3d  # noqa: E402
from fuzzygait.workflows.batch_report import BatchReportRequest, load_page_data, write_batch_report  # noqa: E402
from fuzzygait.workflows.marker_uncertainty import DEFAULT_SETTINGS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "sample_data"
SHARED = ROOT.parent / "shared" / "data"


def make_session(folder: Path, n_trials: int, frames: int) -> Path:
    """Static, subject file and ``n_trials`` walking windows of ``frames`` frames."""
    folder.mkdir(parents=True)
    shutil.copy(SAMPLE / "static.c3d", folder / "static.c3d")
    shutil.copy(SAMPLE / "subject.toml", folder / "Synthetic.toml")
    trial = read_c3d(SAMPLE / "walking.c3d")
    for k in range(n_trials):
        start = (k * 17) % (trial.n_frames - frames)
        t0, t1 = start / trial.rate, (start + frames) / trial.rate
        events = [dataclasses.replace(e, time=e.time - t0) for e in trial.events if t0 <= e.time < t1]
        write_c3d(dataclasses.replace(trial, markers=trial.markers[start:start + frames], outputs={},
                                      output_kinds={}, events=events), folder / f"walk{k:02d}.c3d")  # fmt: skip
    return folder


def timed(label: str, **kwargs: object) -> float:
    """One batch as ``fuzzygait report --workers W`` runs it: ``W`` also bounds the
    processes of a trial's own analysis (the command passes it in the settings)."""
    settings = dataclasses.replace(DEFAULT_SETTINGS, workers=int(kwargs["workers"]))  # type: ignore[call-overload]
    start = time.perf_counter()
    result = write_batch_report(BatchReportRequest(settings=settings, **kwargs))  # type: ignore[arg-type]
    seconds = time.perf_counter() - start
    print(f"{label}: {seconds:.1f} s wall, {result.n_ok} of {len(result.outcomes)} OK, {result.n_skipped} reused, "
          f"trial seconds {np.mean([o.seconds for o in result.outcomes if not o.skipped] or [0]):.2f} mean")
    return seconds


def command_wall(session: Path, out: Path, workers: int) -> float:
    """Wall seconds of one ``fuzzygait report`` of ``session`` into a new ``out``."""
    argv = [sys.executable, "-m", "fuzzygait", "report", str(session), "--out", str(out), "--uncertainty", "fast",
            "--workers", str(workers)]  # fmt: skip
    start = time.perf_counter()
    subprocess.run(argv, check=True, capture_output=True)
    return time.perf_counter() - start


def commands(root: Path, session: Path, repeats: int) -> None:
    """The user's command, fresh processes, 1 and 2 workers alternated (``--commands``)."""
    walls: dict[int, list[float]] = {1: [], 2: []}
    for i in range(repeats):
        for workers in (1, 2):
            walls[workers].append(command_wall(session, root / f"out-{workers}-{i}", workers))
            print(f"run {i + 1}, --workers {workers}: {walls[workers][-1]:.1f} s wall", flush=True)
    one, two = statistics.median(walls[1]), statistics.median(walls[2])
    trials = len(list(session.glob("walk*.c3d")))
    print(f"`fuzzygait report`: --workers 1 median {one:.1f} s, --workers 2 median {two:.1f} s "
          f"({two / trials:.2f} s per trial): speed-up {one / two:.2f}x")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--shared", action="store_true")
    parser.add_argument("--commands", action="store_true", help="the user's command, fresh processes, alternated")
    parser.add_argument("--repeats", type=int, default=3, help="alternations of --commands")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        session = make_session(root / "session", args.trials, args.frames)
        print(f"{args.trials} synthetic trials of {args.frames} frames, --uncertainty fast; {os.cpu_count()} cores")
        if args.commands:
            commands(root, session, args.repeats)
            return
        one = timed("1 worker (in process)", inputs=[session], out_dir=root / "one", uncertainty="fast", workers=1)
        two = timed("2 workers (LocalCluster)", inputs=[session], out_dir=root / "two", uncertainty="fast", workers=2)
        print(f"speed-up {one / two:.2f}x")
        same = True
        for k in range(args.trials):
            a = load_page_data(root / "one" / "session", f"walk{k:02d}")
            b = load_page_data(root / "two" / "session", f"walk{k:02d}")
            same &= sorted(a) == sorted(b) and all(np.array_equal(a[key], b[key]) for key in a)
        print(f"page data bit-identical with 1 and 2 workers: {same}")
        timed("re-run on the same folder", inputs=[session], out_dir=root / "two", uncertainty="fast", workers=2)
        if args.shared:
            inputs = [SHARED / "vicon", SHARED / "pig-options"]
            seconds = timed("shared vicon + pig-options, --uncertainty none, 2 workers", inputs=inputs,
                            out_dir=root / "shared", uncertainty="none", workers=2)  # fmt: skip
            print(f"  = {seconds / 6:.1f} s per trial (6 trials, incl. the cluster's start)")


if __name__ == "__main__":
    main()
