"""Input/output: C3D trials and subject parameters."""

from fuzzygait.core.trial import OUTPUT_KINDS, OUTPUT_UNITS, AnalysisValue, Event, Trial
from fuzzygait.io.c3d import read_c3d, write_c3d

__all__ = ["OUTPUT_KINDS", "OUTPUT_UNITS", "AnalysisValue", "Event", "Trial", "read_c3d", "write_c3d"]
