"""Motion-capture pre-processing of marker signals: gap filling and zero-lag low-pass.

Gait events and cycles are in :mod:`fuzzygait.gait` (they need the kinematics)."""

from fuzzygait.mocap.filtering import (
    ShortRunWarning,
    butterworth_lowpass,
    combined_gain_db,
    design_cutoff,
    filter_trial,
    min_run_length,
)
from fuzzygait.mocap.gap_plan import GapRun, find_gaps
from fuzzygait.mocap.gaps import (
    Gap,
    fill_gaps,
    fill_trial_gaps,
    gap_report_table,
    is_unlabelled,
    labelled_markers,
    methods_used,
)

__all__ = [
    "Gap",
    "GapRun",
    "ShortRunWarning",
    "butterworth_lowpass",
    "combined_gain_db",
    "design_cutoff",
    "fill_gaps",
    "fill_trial_gaps",
    "filter_trial",
    "find_gaps",
    "gap_report_table",
    "is_unlabelled",
    "labelled_markers",
    "methods_used",
    "min_run_length",
]
