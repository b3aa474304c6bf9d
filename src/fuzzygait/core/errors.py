"""Exception types.

Every error the package raises on bad input derives from :class:`FuzzyGaitError` and
carries a one-line message that names the offending file, marker or parameter and says
what to do.  The command line prints exactly that line and exits with a non-zero code.
"""

from __future__ import annotations


class FuzzyGaitError(Exception):
    """Base class of all user-facing errors of fuzzygait."""


class C3DError(FuzzyGaitError):
    """A C3D file cannot be read or written (names the file and the problem)."""


class MarkerError(FuzzyGaitError):
    """A required marker is missing or unusable (names the marker)."""


class ParameterError(FuzzyGaitError, ValueError):
    """An argument or subject parameter is impossible (names the parameter)."""


class SimulationError(FuzzyGaitError):
    """A simulation step failed (names the time, the residual and the parameter values)."""


class EventError(FuzzyGaitError):
    """Gait events are missing or do not make a usable gait cycle (names the file and
    what to add)."""
