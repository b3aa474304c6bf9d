"""A mistyped path — an output with a suffix the command does not write, an input file
that is not there — is answered before any work and before the imports of the libraries
that would read or write it (xarray, pandas, scipy: about 1.5 s of a command's start):
one line, in a fresh process as a user runs it, with none of those modules loaded."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from support import SAMPLE_DATA

#: Modules a command must not have imported when it refuses an output path.
HEAVY = ("xarray", "pandas", "scipy.signal", "matplotlib", "distributed")

#: Run the command's entry point in this fresh interpreter, then report what it imported.
PROBE = """
import sys
from fuzzygait.cli.app import main
sys.argv = ["fuzzygait", *sys.argv[1:]]
try:
    main()
except SystemExit as exit:
    code = exit.code
else:
    code = 0
print("exit", code, "loaded", *sorted(m for m in {heavy!r} if m in sys.modules), file=sys.stderr)
"""

WALKING, STATIC = SAMPLE_DATA / "walking.c3d", SAMPLE_DATA / "static.c3d"


CASES = [
    (("uncertainty", WALKING, "--out", "x.csv"), "--out must end in .nc or .zarr"),
    (("uncertainty", WALKING, "--out", "x.nc", "--rrd", "x.txt"), "--rrd must end in .rrd"),
    (("angles", WALKING, "--out", "x.txt"), "--out must end in .csv or .parquet"),
    (("angles", WALKING, "--cycles", "x.txt"), "--cycles must end in .csv or .parquet"),
    (("angles", WALKING, "--c3d-out", "x.txt"), "--c3d-out must name a .c3d file"),
    (("preprocess", WALKING, "--out", "x.txt"), "--out must name a .c3d file"),
    (("calibrate", STATIC, "--out", "x.txt"), "--out must name a .toml or .vsk subject file"),
    (("gait-parameters", WALKING, "--out", "x.txt"), "--out must end in .csv or .parquet"),
    (("normative", WALKING, "--out", "x.txt"), "the normative file is a .csv file"),
    (("simulate", "swing", "--out", "x.txt"), "--out must end in .nc or .zarr"),
    (("fuzzy-sim", "swing", "--fuzzy", "E=10%", "--out", "x.nc", "--plot", "x.txt"), "--plot must end in .png, "),
    (("compare", WALKING, "--out", "x.txt"), "--out must end in .csv or .parquet"),
    (("uncertainty", "nope.c3d", "--out", "x.nc"), "nope.c3d: no such file; check the path"),
    (("angles", WALKING, "--static", "nope.c3d"), "nope.c3d: no such file; check the path"),
    (("angles", WALKING, "--subject", "nope.vsk"), "nope.vsk: no such subject file; check the path"),
    (("compare", WALKING, "--subject", "nope.txt"), "nope.txt: unknown subject file type '.txt'"),
    (("preprocess", "nope.c3d", "--out", "x.c3d"), "nope.c3d: no such file"),
    (("calibrate", "nope.c3d", "--out", "x.toml"), "nope.c3d: no such file"),
    (("calibrate", STATIC, "--subject", ".", "--out", "x.toml"), ".: is a folder, not a subject file"),
    (("report", SAMPLE_DATA, "--static", "nope.c3d", "--out", "rep"), "nope.c3d: no such file"),
    (("report", SAMPLE_DATA, "--subject", "nope.toml", "--out", "rep"), "nope.toml: no such subject file"),
    (("normative", WALKING, "--static", "nope.c3d", "--out", "n.csv"), "nope.c3d: no such file"),
]  # fmt: skip


@pytest.mark.parametrize(("args", "needle"), CASES, ids=[f"{args[0]} {needle.split(':')[0]}" for args, needle in CASES])
def test_a_mistyped_path_is_refused_before_the_heavy_imports(tmp_path: Path, args: tuple, needle: str) -> None:
    command = [sys.executable, "-c", PROBE.format(heavy=HEAVY), *map(str, args)]
    result = subprocess.run(command, capture_output=True, text=True, timeout=120, cwd=tmp_path)
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 2, result.stderr
    assert lines[0].startswith("fuzzygait: error: ") and needle in lines[0]
    assert lines[1] == "exit 1 loaded", f"{args[0]} imported {lines[1].split('loaded')[1].strip()} before refusing"
    assert not list(tmp_path.iterdir())
