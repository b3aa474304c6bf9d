"""CPU time of the default marker-error analysis, old code against new, alternated
(issue 40, item 3); with ``--command``, the wall time of the user's command.

Run:  .venv/bin/python benchmarks/markererror_cpu.py [--old COMMIT] [--repeats 2] [--trial walking|cgm24]
          [--command]

The source tree of ``--old`` (a commit of this repository, ``git archive``) is unpacked
to a temporary folder; then, ``--repeats`` times, old and new in turn, a fresh process
runs what ``fuzzygait uncertainty sample_data/walking.c3d`` runs with its defaults (the
joint-angle pipeline, the bands at α = 0, 0.25, 0.5, 0.75, 1, the allowable error for
±2.5°, the per-source bands; :func:`~fuzzygait.workflows.marker_uncertainty.analyse_run`)
on one worker.  Its CPU time (user + system, ``resource.getrusage(RUSAGE_CHILDREN)``: the
whole process, imports included) is printed per run, and the medians.  CPU time, not
wall: the machine is shared (the lead measures wall time on a quiet machine).

``--command``: instead, the command itself as a user types it, ``fuzzygait uncertainty
sample_data/walking.c3d --static sample_data/static.c3d --subject sample_data/subject.toml
--out …`` (its defaults: up to 2 workers), wall seconds (and CPU of the process and its
workers) per run and the medians — on a quiet machine only.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

CHILD = """
import sys
sys.path.insert(0, {here!r})
from _setup import one_thread
one_thread()
from markererror_work import trial_run
from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings, analyse_run
analyse_run(trial_run({trial!r}), MarkerErrorSettings(workers=1))
"""


def child_cpu(src: Path, trial: str) -> float:
    """CPU seconds of one fresh process running the analysis with the package in ``src``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = {**os.environ, "PYTHONPATH": str(src)}
    subprocess.run([sys.executable, "-c", CHILD.format(here=str(HERE), trial=trial)], env=env, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def command_wall(src: Path, trial: str) -> tuple[float, float]:
    """Wall and CPU seconds of ``fuzzygait uncertainty`` on the sample trial with the package in ``src``."""
    prefix = "" if trial == "walking" else "cgm24_"
    data = ROOT / "sample_data"
    with tempfile.TemporaryDirectory() as out:
        argv = [sys.executable, "-m", "fuzzygait", "uncertainty", str(data / f"{prefix}walking.c3d"),
                "--static", str(data / f"{prefix}static.c3d"), "--subject", str(data / f"{prefix}subject.toml"),
                "--out", str(Path(out) / "fuzzy.nc")]  # fmt: skip
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        subprocess.run(argv, env={**os.environ, "PYTHONPATH": str(src)}, check=True, capture_output=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", default="077d2d6", help="commit of the old code (default: before issue 40)")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--trial", default="walking", choices=("walking", "cgm24"))
    parser.add_argument("--command", action="store_true", help="the wall time of `fuzzygait uncertainty` instead")
    args = parser.parse_args()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.old, "src"], check=True,
                             capture_output=True).stdout  # fmt: skip
    with tempfile.TemporaryDirectory() as folder:
        with tarfile.open(fileobj=BytesIO(archive)) as tar:
            tar.extractall(folder, filter="data")
        sources = {"old": Path(folder) / "src", "new": ROOT / "src"}
        cpu: dict[str, list[float]] = {"old": [], "new": []}
        wall: dict[str, list[float]] = {"old": [], "new": []}
        for i in range(args.repeats):
            for name, src in sources.items():
                if args.command:
                    seconds, used = command_wall(src, args.trial)
                    wall[name].append(seconds)
                    cpu[name].append(used)
                    print(f"run {i + 1} {name}: {seconds:.1f} s wall, {used:.1f} s CPU", flush=True)
                else:
                    cpu[name].append(child_cpu(src, args.trial))
                    print(f"run {i + 1} {name}: {cpu[name][-1]:.1f} s CPU", flush=True)
    old, new = statistics.median(cpu["old"]), statistics.median(cpu["new"])
    print(f"{args.trial}: old {args.old} median {old:.1f} s CPU, new median {new:.1f} s CPU: {old / new:.2f}x")
    if args.command:
        old, new = statistics.median(wall["old"]), statistics.median(wall["new"])
        print(f"{args.trial}: `fuzzygait uncertainty` wall, old median {old:.1f} s, new median {new:.1f} s: "
              f"{old / new:.2f}x")  # fmt: skip


if __name__ == "__main__":
    main()
