"""Load: a session folder of many trials through ``fuzzygait report --uncertainty fast``
on 2 workers, one broken trial among them -- wall time and peak memory.

    .venv/bin/python benchmarks/report_load.py [--trials 200] [--frames 120] [--workers 2]

Makes a session folder (the sample static trial, its subject file and ``--trials``
windows of ``sample_data/walking.c3d`` of ``--frames`` frames each, one of them
truncated to a broken file), runs the command as a user would (a subprocess) and samples
every 0.5 s the resident memory of the command and every process it started (its Dask
nanny and workers). Prints the wall time, the peak resident memory of the whole process
tree and of its largest process, the number of trials reported and failed, and the
command's error lines (the broken trial's one line). Memory bounded means: the peak does
not grow with the number of trials (compare ``--trials 20`` with ``--trials 200``).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil
from batch_report_scaling import make_session


def tree_rss(process: psutil.Process, peaks: dict[str, int]) -> tuple[int, int]:
    """Total and largest resident set size (bytes) of ``process`` and its descendants;
    ``peaks`` gathers each process's peak by role (``command`` or the child's kind)."""
    sizes = []
    for p in [process, *process.children(recursive=True)]:
        try:
            rss = p.memory_info().rss
            role = "command" if p.pid == process.pid else _role(p.cmdline())
        except psutil.Error:
            continue
        sizes.append(rss)
        peaks[role] = max(peaks.get(role, 0), rss)
    return sum(sizes), max(sizes, default=0)


def _role(cmdline: list[str]) -> str:
    text = " ".join(cmdline)
    for role in ("nanny", "worker", "resource_tracker", "spawn_main", "forkserver"):
        if role in text:
            return role
    return text[:40]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=200)
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = make_session(Path(tmp) / "visit", args.trials, args.frames)
        broken = folder / "walk00.c3d"
        broken.write_bytes(broken.read_bytes()[:700])  # a header and a cut parameter section
        command = [sys.executable, "-m", "fuzzygait", "report", str(folder), "--out", str(Path(tmp) / "report"),
                   "--uncertainty", "fast", "--workers", str(args.workers)]  # fmt: skip
        start = time.perf_counter()
        proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        watched = psutil.Process(proc.pid)
        peak_total = peak_single = 0
        roles: dict[str, int] = {}
        while proc.poll() is None:
            total, single = tree_rss(watched, roles)
            peak_total, peak_single = max(peak_total, total), max(peak_single, single)
            time.sleep(0.5)
        out, err = proc.communicate()
        seconds = time.perf_counter() - start
    errors = [line for line in err.splitlines() if "error" in line or "failed" in line]
    summary = [line for line in out.splitlines() if line.startswith("report:")]
    print(f"{args.trials} trials of {args.frames} frames, --uncertainty fast --workers {args.workers}: "
          f"exit {proc.returncode}, {seconds:.1f} s wall ({seconds / args.trials:.2f} s per trial)")
    print(f"peak resident memory: whole process tree {peak_total / 2**20:.0f} MiB, largest process "
          f"{peak_single / 2**20:.0f} MiB; by role: "
          + ", ".join(f"{role} {size / 2**20:.0f} MiB" for role, size in sorted(roles.items())))
    print("\n".join(summary + errors[:5]))


if __name__ == "__main__":
    main()
