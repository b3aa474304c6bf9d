"""In-memory representation of one motion-capture trial.

Conventions used throughout fuzzygait:

* marker positions are in **millimetres** in the laboratory frame of the file;
* arrays are indexed ``[frame, marker, xyz]``; a missing sample is ``NaN`` in all three
  coordinates;
* ``first_frame`` is the 1-based C3D frame number of the first sample (as Vicon Nexus and
  Mokka show it), so sample ``i`` is C3D frame ``first_frame + i``;
* event times are in seconds on the C3D clock, where C3D frame ``n`` lies at
  ``(n - 1) / rate`` seconds.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from fuzzygait.core.arrays import floats
from fuzzygait.core.errors import MarkerError, ParameterError
from fuzzygait.core.findings import Finding

#: Kinds of model-output points, after the ``POINT`` group's type lists of Vicon files.
OUTPUT_KINDS = ("angle", "force", "moment", "power", "scalar", "modeled_marker", "segment_frame")

#: Physical unit of each output kind as written to C3D files.
OUTPUT_UNITS = {
    "angle": "deg",
    "force": "N",
    "moment": "Nmm",
    "power": "W",
    "scalar": "mm",
    "modeled_marker": "mm",
    "segment_frame": "mm",
}


#: Vicon's ``EVENT:ICON_IDS`` of the gait events, by label.
LABEL_ICONS = {"Foot Strike": 1, "Foot Off": 2}


@dataclass(frozen=True)
class Event:
    """A gait event as stored in the C3D ``EVENT`` group.

    Attributes:
        label: event name, e.g. ``"Foot Strike"`` or ``"Foot Off"``.
        context: ``"Left"``, ``"Right"`` or ``"General"``.
        time: seconds on the C3D clock (C3D frame ``n`` is at ``(n - 1) / rate``).
        subject: subject name the event belongs to (may be empty).
        description: free text.
        icon: Vicon's ``EVENT:ICON_IDS`` where the file gives another than the label's
            (:meth:`icon_id`); None: the label's.
        flag: ``EVENT:GENERIC_FLAGS`` (0 unless the file says otherwise).
    """

    label: str
    context: str
    time: float
    subject: str = ""
    description: str = ""
    icon: int | None = None
    flag: int = 0

    def icon_id(self) -> int:
        """The icon Vicon Nexus shows the event with: :attr:`icon`, else by the label
        (as Nexus writes them: 1 a foot strike, 2 a foot off, 0 any other event)."""
        return self.icon if self.icon is not None else LABEL_ICONS.get(self.label, 0)

    def frame(self, rate: float) -> float:
        """1-based C3D frame number of the event (may be fractional) at ``rate`` Hz."""
        return self.time * rate + 1.0


@dataclass(frozen=True)
class AnalysisValue:
    """One value of the C3D ``ANALYSIS`` group, where Vicon Nexus stores the
    spatio-temporal parameters it computed (``Generate Gait Cycle Parameters``).

    Attributes:
        name: parameter name as stored, e.g. ``"Cadence"``, ``"Stride Length"``.
        context: ``"Left"``, ``"Right"`` or ``"General"``.
        unit: the unit string as stored (e.g. ``"steps/min"``, ``"m"``; older Vicon
            software wrote ``"1/s"``, ``"mm"``, ``"%"``); ``""`` when absent.
        value: the number in that unit (NaN when the file holds none for it).
        subject: subject name the value belongs to (may be empty).
        description: free text (may be empty).
    """

    name: str
    context: str
    unit: str
    value: float
    subject: str = ""
    description: str = ""


@dataclass
class Trial:
    """Markers, model outputs, events and subject parameters of one trial.

    Attributes:
        markers: ``(n_frames, n_markers, 3)`` positions in mm, NaN where missing.
        marker_labels: marker names with any subject prefix removed, one per column.
        rate: point sampling rate in Hz.
        first_frame: 1-based C3D frame number of the first sample.
        outputs: model-output points (e.g. ``"LKneeAngles"``), each ``(n_frames, 3)`` in
            the unit given by :data:`OUTPUT_UNITS` for its kind; NaN where missing.
        output_kinds: kind of each output, one of :data:`OUTPUT_KINDS`.
        events: gait events sorted by time.
        parameters: subject parameters (C3D ``PROCESSING`` group): lengths in mm,
            angles in rad, mass in kg.
        analysis: the C3D ``ANALYSIS`` group (values another program, e.g. Vicon Nexus,
            computed: spatio-temporal parameters), in the file's order and units; empty
            when the file has none.
        subject: subject name, if the file names one.
        label_prefix: subject prefix stripped from the labels (e.g. ``"A22:"``), or ``""``.
        source: file the trial was read from, if any.
        notes: data-quality and processing findings (:class:`~fuzzygait.core.findings.Finding`)
            gathered while reading and processing (unit conversions, renamed duplicate
            labels, fallback reader used, spikes blanked, gap filling, filter, ...).
    """

    markers: np.ndarray
    marker_labels: list[str]
    rate: float
    first_frame: int = 1
    outputs: dict[str, np.ndarray] = field(default_factory=dict)
    output_kinds: dict[str, str] = field(default_factory=dict)
    events: list[Event] = field(default_factory=list)
    parameters: dict[str, float] = field(default_factory=dict)
    analysis: list[AnalysisValue] = field(default_factory=list)
    subject: str = ""
    label_prefix: str = ""
    source: Path | None = None
    notes: list[Finding] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.markers = floats(self.markers)  # a traced array stays traced (fuzzygait.core.arrays)
        if self.markers.ndim != 3 or self.markers.shape[2] != 3:
            raise ParameterError(
                f"markers must have shape (frames, markers, 3); got {self.markers.shape}"
            )
        if self.markers.shape[1] != len(self.marker_labels):
            raise ParameterError(
                f"{self.markers.shape[1]} marker columns but {len(self.marker_labels)} labels"
            )
        if len(set(self.marker_labels)) != len(self.marker_labels):
            dupes = sorted({m for m in self.marker_labels if self.marker_labels.count(m) > 1})
            raise ParameterError(f"duplicate marker labels {dupes}; rename them")
        if not np.isfinite(self.rate) or self.rate <= 0:
            raise ParameterError(f"rate must be a positive number of Hz; got {self.rate}")
        for name, values in self.outputs.items():
            values = np.asarray(values, dtype=float)
            if values.shape != (self.n_frames, 3):
                raise ParameterError(
                    f"output {name!r} must have shape ({self.n_frames}, 3); got {values.shape}"
                )
            self.outputs[name] = values
            kind = self.output_kinds.setdefault(name, "scalar")
            if kind not in OUTPUT_KINDS:
                raise ParameterError(f"output {name!r} has unknown kind {kind!r}")
        self.events = sorted(self.events, key=lambda e: e.time)

    # ------------------------------------------------------------------ sizes and time
    @property
    def n_frames(self) -> int:
        """Number of samples."""
        return int(self.markers.shape[0])

    @property
    def n_markers(self) -> int:
        """Number of marker trajectories."""
        return int(self.markers.shape[1])

    @property
    def frames(self) -> np.ndarray:
        """1-based C3D frame numbers of the samples."""
        return self.first_frame + np.arange(self.n_frames)

    @property
    def times(self) -> np.ndarray:
        """Sample times in seconds on the C3D clock (frame ``n`` at ``(n-1)/rate``)."""
        return (self.frames - 1) / self.rate

    @property
    def name(self) -> str:
        """A short name for messages: the file stem, or ``"<trial>"``."""
        return self.source.name if self.source is not None else "<trial>"

    def event_index(self, event: Event) -> float:
        """Fractional sample index of ``event`` in this trial's arrays."""
        return event.frame(self.rate) - self.first_frame

    # ------------------------------------------------------------------ markers
    def has_marker(self, label: str) -> bool:
        """Whether a marker column named ``label`` exists."""
        return label in self.marker_labels

    def _column(self, label: str) -> int:
        try:
            return self.marker_labels.index(label)
        except ValueError:
            raise MarkerError(
                f"{self.name}: marker {label!r} is missing "
                f"(have: {', '.join(self.marker_labels) or 'none'}); "
                "label it in your capture software or choose a model that does not need it"
            ) from None

    def marker(self, label: str) -> np.ndarray:
        """Trajectory ``(n_frames, 3)`` in mm of marker ``label`` (a view).

        Raises:
            MarkerError: when the trial has no such marker.
        """
        return self.markers[:, self._column(label), :]

    def _copy(self, markers: np.ndarray, labels: list[str], notes: list[Finding]) -> Trial:
        return replace(
            self,
            markers=np.array(markers, dtype=float),
            marker_labels=list(labels),
            outputs={k: v.copy() for k, v in self.outputs.items()},
            output_kinds=dict(self.output_kinds),
            events=list(self.events),
            parameters=dict(self.parameters),
            analysis=list(self.analysis),
            notes=notes,
        )

    def with_markers(self, markers: np.ndarray, note: Finding | None = None) -> Trial:
        """A copy of this trial with the marker array replaced (same labels), and
        ``note`` added to its notes when given."""
        notes = [*self.notes, note] if note is not None else list(self.notes)
        return self._copy(markers, self.marker_labels, notes)

    def select_markers(self, labels: list[str]) -> Trial:
        """A copy holding only the markers ``labels``, in that order.

        Raises:
            MarkerError: when one of them is missing.
        """
        columns = [self._column(lbl) for lbl in labels]
        return self._copy(self.markers[:, columns, :], labels, list(self.notes))

    def missing_mask(self) -> np.ndarray:
        """``(n_frames, n_markers)`` boolean: True where a marker sample is missing."""
        return ~np.all(np.isfinite(self.markers), axis=2)
