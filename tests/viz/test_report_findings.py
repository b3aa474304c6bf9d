"""The report reads the run's typed findings, never their text: the index entry's moved
segments come from the moved-markers findings' ``segment``, the trial page's "Gaps and
filter" row from the gap-filling finding's ``max_gap``/``method`` and the low-pass one."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.viz.report.bands import TrialData, TrialEntry, delta_phi_table
from fuzzygait.viz.report.clinical_html import _processing_text
from fuzzygait.workflows.angles import AnglesRun
from fuzzygait.workflows.report_folder import angles_only
from support import FakeAnalysis


def test_the_entrys_moved_segments_come_from_the_moved_markers_findings(angles_run: AnglesRun) -> None:
    moved = Finding(FindingKind.MOVED_MARKERS, "(any text)", Severity.WARNING, side="right", segment="right shank")
    lookalike = Finding(FindingKind.STATIC_TRIAL, "left foot markers sit elsewhere than in the static trial s.c3d")
    run = replace(angles_run, notes=[*angles_run.notes, lookalike, moved])
    analysis = angles_only(FakeAnalysis(run, None, None, list(run.notes)))
    data = TrialData.of(analysis)
    entry = TrialEntry.of(Path("walking.c3d"), "walking.html", data, delta_phi_table(analysis, data))
    assert entry.moved == ("right shank",)
    plain = angles_only(FakeAnalysis(angles_run, None, None, list(angles_run.notes)))
    data = TrialData.of(plain)
    assert TrialEntry.of(Path("walking.c3d"), "walking.html", data, delta_phi_table(plain, data)).moved == ()


def test_the_processing_row_comes_from_the_typed_settings(angles_run: AnglesRun) -> None:
    # the sample run: gap filling at the defaults, the 6 Hz filter, as the page shows them today
    text = _processing_text(angles_run)
    assert text.startswith("gaps of up to 10 frames filled (method auto); what was filled: Data quality<br>")
    assert "Butterworth low-pass 6 Hz, 4th order zero-lag" in text
    # the settings are the finding's fields, not its words
    gap = Finding(FindingKind.GAP_FILLING, "gap filling: 0 of 0 gaps filled (max_gap=10 frames, method=auto)",
                  max_gap=7, method="pattern")  # fmt: skip
    low = Finding(FindingKind.LOW_PASS, "Butterworth low-pass 8 Hz, 4th order zero-lag", cutoff_hz=8.0, order=4)
    decoy = Finding(FindingKind.STATIC_TRIAL, "gap filling: 0 of 0 gaps filled (max_gap=0 frames, method=spline)")
    trial = replace(angles_run.trial, notes=[gap, decoy, low])
    assert _processing_text(replace(angles_run, trial=trial)) == (
        "gaps of up to 7 frames filled (method pattern); what was filled: Data quality<br>"
        "Butterworth low-pass 8 Hz, 4th order zero-lag"
    )
    off = replace(gap, max_gap=0)
    assert _processing_text(replace(angles_run, trial=replace(trial, notes=[off]))) == (
        "gap filling: off (max_gap 0)<br>no low-pass filter"
    )
    assert _processing_text(replace(angles_run, trial=replace(trial, notes=[decoy]))) == (
        "gap filling: not applied<br>no low-pass filter"
    )
