"""``--tolerance`` of ``uncertainty`` and ``report`` and what ``uncertainty`` prints: ΔΦ
"undetermined" exactly where the dataset says so, the allowable-marker-error table.

The text is checked on a 6-frame analysis in this process (fast); one end-to-end run of
the command is ``slow``.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.cli.marker_errors import _allowable_text, _delta_phi_text
from fuzzygait.cli.options import parse_tolerance
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.markererror.allowable import allowable_table
from fuzzygait.markererror.analysis import relative_envelope_width, undetermined_levels
from fuzzygait.markererror.result import MarkerErrorResult, read_marker_result
from fuzzygait.workflows.angles import AnglesRun
from fuzzygait.workflows.marker_uncertainty import MarkerErrorAnalysis
from support import SAMPLE_DATA, assert_one_line_error, run, run_here, sparse_knee_analysis

SAMPLE_ARGS = ("--static", SAMPLE_DATA / "static.c3d", "--subject", SAMPLE_DATA / "subject.toml")


@pytest.mark.parametrize("command", ["uncertainty", "report"])
@pytest.mark.parametrize("value", ["-1", "nan", "inf"])
def test_bad_tolerance_is_one_line(command: str, value: str, tmp_path: Path) -> None:
    out = tmp_path / ("x.nc" if command == "uncertainty" else "r")
    result = run_here(command, SAMPLE_DATA / "walking.c3d", "--out", out, f"--tolerance={value}")
    assert_one_line_error(result, "--tolerance", "≥ 0")
    assert not list(tmp_path.iterdir())


def test_parse_tolerance() -> None:
    assert parse_tolerance(2.5) == 2.5 and parse_tolerance(0.0) is None
    for value in (-0.1, math.nan, math.inf):
        with pytest.raises(FuzzyGaitError, match="--tolerance"):
            parse_tolerance(value)


@pytest.fixture(scope="module")
def analysis(angles_run: AnglesRun) -> MarkerErrorAnalysis:
    return sparse_knee_analysis(angles_run)


def _cells(text: str) -> dict[str, list[str]]:
    """The ΔΦ text as rows of cells (first row: the header)."""
    rows = {}
    for line in text.splitlines()[1:]:
        name, *cells = line.split()
        rows[name] = cells
    return rows


def test_delta_phi_undetermined_where_the_dataset_says(analysis: MarkerErrorAnalysis) -> None:
    flags = undetermined_levels(analysis.fuzzy)
    assert flags.to_numpy().any() and not flags.to_numpy().all()  # the check is not vacuous
    rows = _cells(_delta_phi_text(analysis.fuzzy, analysis.delta_phi))
    for name in flags.index:
        for alpha, cell in zip(analysis.delta_phi.columns, rows[name], strict=True):
            if flags.at[name, alpha]:
                assert cell == "undetermined", (name, alpha)
            else:
                assert cell == f"{analysis.delta_phi.at[name, alpha]:.1f}", (name, alpha)
    # also where ΔΦ has a number (some frames determined) or NaN (none)
    fuzzy = analysis.fuzzy.copy()
    fuzzy["undetermined"] = fuzzy["undetermined"].copy(data=np.zeros(fuzzy["undetermined"].shape, bool))
    fuzzy["undetermined"].loc[{"component": "LKneeAngles_Y", "alpha": 0.5}] = True
    text = _delta_phi_text(fuzzy, relative_envelope_width(fuzzy))
    assert _cells(text)["LKneeAngles_Y"][0] == "undetermined" and "nan" not in text.lower()


def test_allowable_table_text(analysis: MarkerErrorAnalysis) -> None:
    text = _allowable_text(analysis.result)
    assert text is not None
    title, header, *lines = text.splitlines()
    assert title.startswith("Allowable marker error for ±2.5°") and "% of Table 3.1" in title
    assert "mm" in header and "% of Table 3.1" in header
    assert analysis.result is not None
    table = allowable_table(analysis.result)
    for line, (name, row) in zip(lines, table.iterrows(), strict=True):
        assert line.startswith(f"{name}  {row['label']}")
        assert re.search(rf"\s{row['allowable_mm']:.1f}\s", line), line
    assert _allowable_text(MarkerErrorResult(analysis.fuzzy)) is None and _allowable_text(None) is None


@pytest.mark.slow
def test_uncertainty_prints_undetermined_and_the_allowable_table(tmp_path: Path) -> None:
    """The command end to end: ΔΦ cells "undetermined" where the saved dataset says so,
    the allowable table after ΔΦ, the note with the refinement's runs."""
    out, short = tmp_path / "fuzzy.nc", tmp_path / "short.c3d"
    trial = read_c3d(SAMPLE_DATA / "walking.c3d")
    n = int(1.5 * trial.rate)  # the first 1.5 s (a cheap trial), with its events
    write_c3d(dataclasses.replace(trial, markers=trial.markers[:n], outputs={}, output_kinds={},
                                  events=[e for e in trial.events if e.time < n / trial.rate]), short)  # fmt: skip
    result = run("uncertainty", short, *SAMPLE_ARGS, "--angles", "LKneeAngles", "--alphas", "0,0.5", "--out", out,
                 "--workers", "1")  # fmt: skip
    assert result.returncode == 0, result.stderr
    text = result.stdout
    assert "note: allowable marker error for ±2.5°: " in text
    delta, allowable = text.split("ΔΦ, relative envelope width")[1].split("Allowable marker error for ±2.5°")
    allowable = allowable.split("Widest α =")[0]  # the per-source table follows (knee flexion rows again)
    saved = read_marker_result(out)
    dataset = saved.bands
    flags, dataset_dphi = undetermined_levels(dataset), relative_envelope_width(dataset)
    for name in ("LKneeAngles_X", "LKneeAngles_Y", "LKneeAngles_Z"):
        (line,) = [line for line in delta.splitlines() if line.startswith(name)]
        assert line.split()[1:] == ["undetermined" if flags.at[name, a] else f"{dataset_dphi.at[name, a]:.1f}"
                                    for a in (0.5, 0.0)], line  # fmt: skip
        assert "nan" not in line.lower()
        (row,) = [line for line in allowable.splitlines() if line.startswith(name)]
        assert f"{allowable_table(saved).at[name, 'allowable_mm']:.1f}" in row or "≥" in row or "<" in row
