"""Gait events and gait cycles: foot strikes and foot offs (from the file or detected
from the heel/toe markers), 0-100 % cycle normalisation of joint angles, and the
spatio-temporal parameters Vicon Nexus reports."""

from fuzzygait.gait.cycles import (
    GaitCycle,
    cycle_statistics,
    gait_cycles,
    mean_sd_table,
    normalise_cycles,
    normalised_angle_table,
)
from fuzzygait.gait.events import (
    SOURCE_DETECTED,
    SOURCE_FILE,
    detect_gait_events,
    trial_gait_events,
)
from fuzzygait.gait.spatiotemporal import parameters_table, spatiotemporal_parameters

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
    "parameters_table",
    "spatiotemporal_parameters",
    "trial_gait_events",
]
