"""How long a user waits for the one-line error of a mistyped path, old code against new,
alternated: an output with a suffix the command does not write, an input file that is
not there.

Run:  .venv/bin/python benchmarks/cli_path_errors.py [--old COMMIT] [--repeats 3]

Each case is the ``fuzzygait`` command as a user types it (``python -m fuzzygait …`` in
a fresh process, in an empty temporary folder); ``--old``: the same with the package of
that commit (``git archive`` of its ``src``, on ``PYTHONPATH``), run alternately with the
new.  Printed per case: the median wall seconds of each and the error line (the new
code's).  Wall time of short processes: run on a quiet machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

from _setup import ROOT

WALKING, STATIC = ROOT / "sample_data" / "walking.c3d", ROOT / "sample_data" / "static.c3d"
CASES: list[tuple[str | Path, ...]] = [
    ("uncertainty", WALKING, "--out", "x.csv"),
    ("angles", WALKING, "--out", "x.txt"),
    ("preprocess", WALKING, "--out", "x.txt"),
    ("calibrate", STATIC, "--out", "x.txt"),
    ("gait-parameters", WALKING, "--out", "x.txt"),
    ("normative", WALKING, "--out", "x.txt"),
    ("simulate", "swing", "--out", "x.txt"),
    ("uncertainty", "nope.c3d", "--out", "x.nc"),
    ("angles", WALKING, "--static", "nope.c3d"),
    ("calibrate", "nope.c3d", "--out", "x.toml"),
    ("report", ROOT / "sample_data", "--static", "nope.c3d", "--out", "report"),
]


def timed(args: tuple[str | Path, ...], src: Path) -> tuple[float, str]:
    """Wall seconds of one command and its last stderr line, with the package in ``src``."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    with tempfile.TemporaryDirectory() as work:
        start = time.perf_counter()
        result = subprocess.run([sys.executable, "-m", "fuzzygait", *map(str, args)], capture_output=True,
                                text=True, env=env, cwd=work, timeout=600)  # fmt: skip
        wall = time.perf_counter() - start
    lines = result.stderr.strip().splitlines()
    return wall, lines[-1] if lines else f"(exit {result.returncode}, no error line)"


def old_source(commit: str, into: Path) -> Path:
    """The ``src`` folder of ``commit``, unpacked into ``into``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", commit, "src"], capture_output=True, check=True)
    with tarfile.open(fileobj=BytesIO(archive.stdout)) as tar:
        tar.extractall(into, filter="data")
    return into / "src"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", default=None, help="a commit to compare with")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        trees = {"new": ROOT / "src"}
        if args.old:
            trees = {"old": old_source(args.old, Path(folder)), **trees}
        print("| command | " + " | ".join(f"{name}, s" for name in trees) + " | error line (new) |")
        print("|---|" + "---|" * len(trees) + "---|")
        for case in CASES:
            walls: dict[str, list[float]] = {name: [] for name in trees}
            line = ""
            for _ in range(args.repeats):
                for name, src in trees.items():
                    wall, line = timed(case, src)
                    walls[name].append(wall)
            shown = " ".join(Path(a).name if isinstance(a, Path) else a for a in case)
            medians = " | ".join(f"{statistics.median(w):.2f}" for w in walls.values())
            print(f"| `fuzzygait {shown}` | {medians} | {line.removeprefix('fuzzygait: error: ')} |", flush=True)


if __name__ == "__main__":
    main()
