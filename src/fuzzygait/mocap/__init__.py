"""Motion-capture pre-processing (gap filling, zero-lag low-pass), gait events and
gait-cycle normalisation."""

from fuzzygait.mocap.cycles import (
    GaitCycle,
    cycle_statistics,
    gait_cycles,
    mean_sd_table,
    normalise_cycles,
    normalised_angle_table,
)
from fuzzygait.mocap.events import (
    SOURCE_DETECTED,
    SOURCE_FILE,
    detect_gait_events,
    trial_gait_events,
)
from fuzzygait.mocap.filtering import (
    ShortRunWarning,
    butterworth_lowpass,
    combined_gain_db,
    design_cutoff,
    filter_trial,
    min_run_length,
)
from fuzzygait.mocap.gaps import (
    Gap,
    GapRun,
    fill_gaps,
    fill_trial_gaps,
    find_gaps,
    gap_report_table,
    methods_used,
)

__all__ = [
    "SOURCE_DETECTED",
    "SOURCE_FILE",
    "GaitCycle",
    "cycle_statistics",
    "detect_gait_events",
    "gait_cycles",
    "mean_sd_table",
    "normalise_cycles",
    "normalised_angle_table",
    "trial_gait_events",
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
    "methods_used",
    "min_run_length",
]
