"""Batch report scaling (issue 16 Deliver 6): a session of N synthetic walking trials
(windows of ``sample_data/walking.c3d``, FRAMES frames each, different start frames) with
``--uncertainty fast`` in this process (1 worker) and on a local Dask cluster of 2
workers; wall times, whether every page's data (``data.npz``) is bit-identical, and a
re-run on the same folder (every trial reused).  Optionally also the
``--uncertainty none`` run over ``../shared/data/vicon`` and ``pig-options`` (--shared).

    .venv/bin/python benchmarks/batch_report_scaling.py [--trials 20] [--frames 40] [--shared]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import shutil
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


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--shared", action="store_true")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        session = make_session(root / "session", args.trials, args.frames)
        print(f"{args.trials} synthetic trials of {args.frames} frames, --uncertainty fast; {os.cpu_count()} cores")
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
