"""Typed data-quality and processing findings: what the reader, the content checks, the
processing steps and the workflows have to say about a trial.

A :class:`Finding` is made once, where the thing is found, with its human text
(``message``, shown as it is in the terminal, on the report pages and in the summaries)
and, where a consumer needs structure, typed fields (the side, segment or marker it is
about; the gap-filling and filter settings).  Code that needs to know something selects
findings by :class:`FindingKind` and reads the typed fields; the message is never parsed
back.  ``str(finding)`` is its message.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass

__all__ = ["Finding", "FindingKind", "Severity", "messages", "of_kind"]


class FindingKind(enum.Enum):
    """What a finding is about."""

    #: The synthetic-data generator made the trial (and with what noise and gaps).
    SYNTHETIC = "synthetic"
    #: The reader had to assume or repair something of the file's format (rate, labels,
    #: frame counts, parameter and ANALYSIS groups, the fallback reader used).
    FILE_FORMAT = "file_format"
    #: The marker positions were converted to millimetres, or their unit was assumed.
    UNITS = "units"
    #: The gait events: how the file stores them, or where the run's events come from.
    EVENTS = "events"
    #: Implausible marker samples (beyond the capture volume, or too-fast jumps) blanked.
    SPIKES = "spikes"
    #: Gap filling applied (its settings in :attr:`Finding.max_gap` and
    #: :attr:`Finding.method`).
    GAP_FILLING = "gap_filling"
    #: A low-pass filter applied (its cut-off in :attr:`Finding.cutoff_hz`).
    LOW_PASS = "low_pass"
    #: Marker labels read as the model's (aliases renamed).
    MARKER_LABELS = "marker_labels"
    #: The model version used and why.
    MODEL = "model"
    #: The marker diameter used and where it comes from.
    MARKER_DIAMETER = "marker_diameter"
    #: A subject parameter measured, defaulted or taken from a subject file (e.g. the
    #: inter-ASIS distance, a calibration file made for another model).
    SUBJECT = "subject"
    #: Where the static offsets come from (the static calibration, foot flat).
    STATIC_CALIBRATION = "static_calibration"
    #: A finding of the content checks on the static trial.
    STATIC_TRIAL = "static_trial"
    #: Markers of a segment sit elsewhere than in the static trial (:attr:`Finding.segment`
    #: names the segment).
    MOVED_MARKERS = "moved_markers"
    #: A remark of the model computation (an unseen cluster marker, no progression
    #: frame, a missing marker's virtual markers not produced).
    KINEMATICS = "kinematics"
    #: An angle that could not be computed, and why.
    ANGLE_NOT_COMPUTED = "angle_not_computed"
    #: The comparison with the file's own stored model outputs.
    CROSSCHECK = "crosscheck"
    #: Spatio-temporal parameters that could not be computed.
    SPATIOTEMPORAL = "spatiotemporal"
    #: What a written output file could not carry over from its input.
    OUTPUT_FILE = "output_file"
    #: The settings and extent of the marker-error (uncertainty) analysis.
    UNCERTAINTY = "uncertainty"
    #: The allowable-marker-error search.
    ALLOWABLE_ERROR = "allowable_error"
    #: What the discovery of a session folder could not decide.
    SESSION = "session"
    #: A force plate's reading: its offsets removed, its type or parameters
    #: (:mod:`fuzzygait.io.force_plates`).
    FORCE_PLATE = "force_plate"
    #: A force plate that cannot be used: no or zero calibration, missing channels.
    FORCE_PLATE_CALIBRATION = "force_plate_calibration"
    #: A force-plate channel at its converter's limit (the forces there are wrong).
    FORCE_PLATE_SATURATED = "force_plate_saturated"
    #: A force plate that carries no load during the trial.
    FORCE_PLATE_UNLOADED = "force_plate_unloaded"
    #: A force plate's channel units read otherwise than labelled.
    FORCE_PLATE_UNITS = "force_plate_units"
    #: A force-plate contact and the foot it is assigned to, or why it is not used
    #: (:class:`fuzzygait.kinetics.assignment.PlateContact`; :attr:`Finding.side` the foot).
    FORCE_PLATE_ASSIGNMENT = "force_plate_assignment"
    #: The joint kinetics of a trial: not computed and why (no force plates, a side's
    #: markers missing), the units they were computed in (:mod:`fuzzygait.workflows.kinetics`).
    KINETICS = "kinetics"


class Severity(enum.Enum):
    """How much a finding matters: ``INFO`` records what was done, ``WARNING`` something
    the user should check (the data were repaired, assumed or are unreliable)."""

    INFO = "info"
    WARNING = "warning"


@dataclass(frozen=True)
class Finding:
    """One data-quality or processing finding.

    Attributes:
        kind: what it is about.
        message: the human text, as shown in the terminal and on the report pages.
        severity: :attr:`Severity.INFO` (what was done) or :attr:`Severity.WARNING`.
        side: ``"left"`` or ``"right"`` when it concerns one side, else None.
        segment: the segment it concerns (``"pelvis"``, ``"left foot"`` ...), else None.
        marker: the marker label it concerns, else None.
        max_gap: gap filling: the longest gap filled, in frames (0: filling off).
        method: gap filling: the method asked for (``"auto"``, ``"spline"``,
            ``"pattern"``).
        cutoff_hz: low-pass filter: the -3 dB cut-off frequency in Hz.
        order: low-pass filter: the effective zero-lag order.
    """

    kind: FindingKind
    message: str
    severity: Severity = Severity.INFO
    side: str | None = None
    segment: str | None = None
    marker: str | None = None
    max_gap: int | None = None
    method: str | None = None
    cutoff_hz: float | None = None
    order: int | None = None

    def __str__(self) -> str:
        return self.message


def of_kind(findings: Iterable[Finding], kind: FindingKind) -> list[Finding]:
    """The findings of ``findings`` of ``kind``, in order."""
    return [f for f in findings if f.kind is kind]


def messages(findings: Iterable[Finding]) -> list[str]:
    """The messages of ``findings``, in order (for the text at the edges)."""
    return [f.message for f in findings]
