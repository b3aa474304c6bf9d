"""The allowable-marker-error table on the report's first screen (issue 15): the
knee-flexion sentences lead the trial page, the table follows with mm, % of Table 3.1 and
per-segment columns in report order, the index shows knee flexion's allowable error;
status cells ("≥", "<", "—") from the dataset's outcome.

The analysis is real but small: the sample trial cut to 6 frames, left knee, α = 0 and
0.5, one worker (as tests/markererror/test_allowable.py).
"""

from __future__ import annotations

import dataclasses
import html
import re
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.markererror.allowable import allowable_table
from fuzzygait.markererror.result import MarkerErrorResult
from fuzzygait.viz.report.allowable import allowable_summary
from fuzzygait.workflows.angles import AnglesRun
from fuzzygait.workflows.marker_uncertainty import MarkerErrorAnalysis
from fuzzygait.workflows.report_folder import ReportItem, write_report
from support import SAMPLE_DATA, sparse_knee_analysis


@pytest.fixture(scope="module")
def analysis(angles_run: AnglesRun) -> MarkerErrorAnalysis:
    return sparse_knee_analysis(angles_run)


@pytest.fixture(scope="module")
def report(analysis: MarkerErrorAnalysis, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("report") / "out"
    write_report([ReportItem(SAMPLE_DATA / "walking.c3d", analysis)], out)
    return out


def _text(path: Path) -> str:
    """The page's text, tags dropped, entities decoded, whitespace collapsed."""
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", path.read_text(encoding="utf-8"))).split())


@pytest.mark.slow  # writes the trial's report end to end (~9 s)
def test_trial_page_leads_with_the_flexion_sentence_and_the_table(report: Path,
                                                                  analysis: MarkerErrorAnalysis) -> None:  # fmt: skip
    table = allowable_table(analysis.result)
    sentence = str(table.at["LKneeAngles_X", "text"])
    assert sentence.startswith("Left knee, sagittal (+ flexion): known within ±2.5° if every marker stays within")
    source = (report / "walking.html").read_text(encoding="utf-8")
    assert source.split("<main>", 1)[1].lstrip().startswith('<div class="lead-box">')  # first in the page body
    text = _text(report / "walking.html")
    main = text.split("(measured)", 1)[0]  # the lead box, before the facts table
    assert sentence in main
    # the sentence leads; the table follows the clinical sections (kinematics first)
    assert text.index(sentence) < text.index("Kinematics over the gait cycle") < text.index("Allowable marker error (±2.5°)")
    header = "Angle Max error (mm) % of Table 3.1 pelvis (mm) thigh (mm) shank (mm) ankle (mm) foot (mm)"
    assert header in text
    for name in ("LKneeAngles_X", "LKneeAngles_Y", "LKneeAngles_Z"):  # report order: planes, side
        row = table.loc[name]
        percent = 100 * row["allowable_scale"]
        cells = [f"{row['allowable_mm']:.1f}", f"{percent:.{1 if percent < 10 else 0}f}"]
        cells += [f"{row[f'{s}_mm']:.1f}" for s in ("pelvis", "thigh", "shank", "ankle")]
        assert f"{row['label']} " + " ".join(cells) in text, name  # foot blank: the knee uses none
        assert f'<span title="{name}">' in (report / "walking.html").read_text(encoding="utf-8")
    index = _text(report / "index.html")
    assert f"L {table.at['LKneeAngles_X', 'allowable_mm']:.1f} mm" in index and "knee flexion ±2.5°" in index


def _with_status(result: MarkerErrorResult, component: str, status: str, scale: float,
                 failing: float) -> MarkerErrorResult:  # fmt: skip
    assert result.allowable is not None
    out = result.allowable.copy(deep=True)
    at = {"component": component}
    out["status"] = out["status"].astype(object)  # not truncated to the longest status
    out["status"].loc[at] = status
    out["scale"].loc[at] = scale
    out["failing_scale"].loc[at] = failing
    out["mm"].loc[at] = scale * float(out["segment_radius"].sel(at).max())
    return dataclasses.replace(result, allowable=out)


def test_status_cells(analysis: MarkerErrorAnalysis) -> None:
    assert analysis.result is not None
    fuzzy = _with_status(analysis.result, "LKneeAngles_Y", "full table passes", 1.0, np.nan)
    fuzzy = _with_status(fuzzy, "LKneeAngles_Z", "smallest fails", 0.0, 0.01)
    fuzzy = _with_status(fuzzy, "LKneeAngles_X", "no data", np.nan, np.nan)
    summary = allowable_summary(fuzzy)
    assert summary is not None
    rows = {row.component: row for row in summary.rows}
    assert (rows["LKneeAngles_Y"].mm, rows["LKneeAngles_Y"].percent) == ("≥ 32.0", "≥ 100")
    assert rows["LKneeAngles_Y"].note == "Table 3.1 passes" and rows["LKneeAngles_Y"].segments["foot"] == ""
    assert (rows["LKneeAngles_Z"].mm, rows["LKneeAngles_Z"].percent) == ("< 0.32", "< 1.0")
    assert (rows["LKneeAngles_X"].mm, rows["LKneeAngles_X"].percent) == ("—", "—")
    assert summary.lead_sentences() == [rows["LKneeAngles_X"].text]
    assert allowable_summary(MarkerErrorResult(analysis.fuzzy)) is None and allowable_summary(None) is None
