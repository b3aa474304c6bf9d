"""Spatio-temporal gait parameters as Vicon Nexus computes and names them.

Per side and per gait cycle (Foot Strike to the next Foot Strike of that side; events
from the file, or detected: :func:`fuzzygait.gait.events.trial_gait_events`) the eleven
parameters of Nexus' "Generate Gait Cycle Parameters", in the units Nexus 1.x/2.x writes
to the C3D ``ANALYSIS`` group:

=======================  =========  ======================================================
name                     unit       definition (cycle from strike ``s`` to strike ``e``,
                                    ``T = e - s``; OFO/OFC the opposite foot's Off/Strike
                                    and FO this foot's Off inside the cycle)
=======================  =========  ======================================================
Cadence                  steps/min  ``120 / T`` (two steps per stride)
Walking Speed            m/s        Stride Length / ``T``
Stride Time              s          ``T``
Step Time                s          ``e - OFC``
Opposite Foot Off        %          ``100 (OFO - s) / T``
Opposite Foot Contact    %          ``100 (OFC - s) / T``
Foot Off                 %          ``100 (FO - s) / T``
Single Support           s          ``OFC - OFO`` (the opposite foot in swing)
Double Support           s          ``(OFO - s) + (FO - OFC)``
Stride Length            m          ``|TOE(e) - TOE(s)|``, 3-D
Step Length              m          ``(TOE(e) - TOE_opposite(OFC)) . u``, ``u`` the unit
                                    stride vector ``TOE(e) - TOE(s)``
=======================  =========  ======================================================

Marker positions are taken at the frame nearest each event (``TOE`` of the cycle's side
and of the opposite side; ``foot_marker`` chooses another one).  These definitions were
inferred from Nexus' own values in the reference files, no constant fitted:

* ``PiG_Motion-FlatFoot-Full.c3d`` (Nexus 1.4, events on frames): every parameter of
  both sides is reproduced to float32 precision (lengths within 1e-4 mm) by the
  *first complete cycle* of each side (:attr:`SideParameters.first_complete`); the mean
  over cycles is not what Nexus stores (left stride 1.03 s, the mean of both complete
  left cycles 1.015 s).  A cycle is *complete* when OFO < OFC < FO all lie inside it.
  The lengths are those of the toe markers: the heel markers give strides 0.7 % shorter
  (and the left step 1.5 %), the ankle markers a left stride 0.3 % shorter.  The stride
  is the 3-D distance (its horizontal part is 0.05 mm shorter than Nexus'); the step is
  measured along that stride vector (along the horizontal stride: up to 0.03 mm off).
* ``gait-pig.c3d`` (Vicon Workstation, 50 Hz, sub-frame events, older units ``1/s``
  = strides per second, ``mm``, ``mm/s`` and ``%`` of the cycle for Step Time and the
  support times): Workstation's definitions differ in three points, all reproduced within
  0.005 % on both sides (:attr:`CycleParameters.workstation`, ``--cycles workstation``):
  it reports each side's *first* cycle, complete or not; its Opposite Foot Off is the
  first opposite Foot Off after the cycle's start even beyond its end (left: 109.6 %,
  Double Support 121.8 %, no Single Support); and its **Step Length** of a side is the
  3-D distance from *this* toe at the cycle's opening strike to the opposite toe at the
  opposite strike, ``|TOE_opposite(OFC) - TOE(s)|`` -- the step the opposite foot takes
  (689.11 and 650.76 mm against Workstation's 689.13 and 650.75; Nexus' step, the one
  ending at this foot's strike, gives 633 and 638 mm).  The lengths use the toe
  positions at the nearest frame (0.6 % off with linear interpolation between frames).

:func:`nexus_reference` converts a file's ``ANALYSIS`` values (either generation of
units) to the units above for comparison.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from fuzzygait.core.errors import EventError, ParameterError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.trial import Event, Trial
from fuzzygait.gait.cycles import gait_cycles, side_code
from fuzzygait.gait.event_labels import SIDE_CONTEXTS, GaitEvent, GaitEventKind, gait_events
from fuzzygait.gait.events import trial_gait_events_typed

#: The parameters in Nexus' order, with the unit Nexus writes.
PARAMETERS: tuple[tuple[str, str], ...] = (
    ("Cadence", "steps/min"),
    ("Walking Speed", "m/s"),
    ("Stride Time", "s"),
    ("Step Time", "s"),
    ("Opposite Foot Off", "%"),
    ("Opposite Foot Contact", "%"),
    ("Foot Off", "%"),
    ("Single Support", "s"),
    ("Double Support", "s"),
    ("Stride Length", "m"),
    ("Step Length", "m"),
)
UNITS = dict(PARAMETERS)
NAMES = tuple(UNITS)
#: Parameters that are event times (s) or event phases (% of the cycle).
TIMES = tuple(n for n, u in PARAMETERS if u == "s")
PHASES = tuple(n for n, u in PARAMETERS if u == "%")
#: Marker whose positions at the foot strikes give stride and step length (Nexus: toe).
FOOT_MARKER = "TOE"
#: Cycle selections of :func:`parameters_table`: mean ± SD over complete cycles, the
#: first complete cycle of each side (what Nexus stores), or the first cycle with Vicon
#: Workstation's definitions (what Workstation stored; module docstring).
SELECTIONS = ("all", "nexus", "workstation")
_OPPOSITE = {"L": "R", "R": "L"}


@dataclass(frozen=True)
class CycleParameters:
    """The parameters of one gait cycle of one side.

    Attributes:
        side: ``"L"`` or ``"R"``.
        index: 0-based number of the cycle among the side's cycles.
        start_time: the opening Foot Strike, s on the C3D clock.
        end_time: the closing Foot Strike, s.
        complete: whether the opposite Foot Off, the opposite Foot Strike and this
            side's Foot Off all lie inside the cycle, in that order.
        values: parameter name -> value in :data:`UNITS`; NaN where the events or
            markers it needs are missing.
        workstation: the same with Vicon Workstation's definitions (module docstring:
            Opposite Foot Off may lie beyond the cycle, Step Length is the opposite
            foot's step); equal to ``values`` but for those and what derives from them.
    """

    side: str
    index: int
    start_time: float
    end_time: float
    complete: bool
    values: dict[str, float]
    workstation: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class SideParameters:
    """Every cycle of one side, and their summary.

    Attributes:
        side: ``"L"`` or ``"R"``.
        cycles: all cycles of the side in time order (complete or not).
    """

    side: str
    cycles: list[CycleParameters] = field(default_factory=list)

    @property
    def complete_cycles(self) -> list[CycleParameters]:
        """The complete cycles: the ones the summary uses."""
        return [c for c in self.cycles if c.complete]

    @property
    def first_complete(self) -> CycleParameters | None:
        """The first complete cycle (the one Vicon Nexus reports), or ``None``."""
        complete = self.complete_cycles
        return complete[0] if complete else None

    @property
    def first(self) -> CycleParameters | None:
        """The first cycle, complete or not (the one Vicon Workstation reported)."""
        return self.cycles[0] if self.cycles else None

    def _column(self, name: str) -> np.ndarray:
        values = np.array([c.values[name] for c in self.complete_cycles], dtype=float)
        return values[np.isfinite(values)]

    def mean(self) -> dict[str, float]:
        """Mean over the complete cycles per parameter (NaN with none), :data:`UNITS`."""
        return {n: float(v.mean()) if (v := self._column(n)).size else math.nan for n in NAMES}

    def sd(self) -> dict[str, float]:
        """Sample SD (ddof 1) over the complete cycles (NaN with fewer than two)."""
        return {n: float(v.std(ddof=1)) if (v := self._column(n)).size > 1 else math.nan for n in NAMES}


@dataclass(frozen=True)
class TrialParameters:
    """Spatio-temporal parameters of one trial.

    Attributes:
        trial: the trial's name (file name) for tables and messages.
        sides: ``"L"``/``"R"`` -> :class:`SideParameters`.
        event_source: where the events came from (``"file"`` or the detection method).
        notes: findings on what could not be computed and why (missing markers,
            incomplete cycles).
    """

    trial: str
    sides: dict[str, SideParameters]
    event_source: str
    notes: list[Finding] = field(default_factory=list)


def _times(events: Sequence[GaitEvent], kind: GaitEventKind, side: str) -> np.ndarray:
    """Sorted times (s) of the events of ``kind`` of ``side`` (``"L"``/``"R"``)."""
    return np.sort([g.time for g in events if g.kind is kind and g.side == side])


def _first_inside(times: np.ndarray, low: float, high: float) -> float:
    inside = times[(times > low) & (times < high)]
    return float(inside[0]) if inside.size else math.nan


def _position(trial: Trial, label: str, time: float) -> np.ndarray:
    """``label``'s position (mm, lab frame) at the frame nearest ``time`` (s); NaN when
    the marker is absent, the frame outside the trial or the sample missing."""
    if not (trial.has_marker(label) and np.isfinite(time)):
        return np.full(3, np.nan)
    index = round(time * trial.rate + 1.0 - trial.first_frame)
    if not 0 <= index < trial.n_frames:
        return np.full(3, np.nan)
    return np.asarray(trial.marker(label)[index], dtype=float)


def _one_cycle(trial: Trial, events: Sequence[GaitEvent], side: str, index: int, start: float,
               end: float, foot_marker: str) -> CycleParameters:  # fmt: skip
    other = _OPPOSITE[side]
    strike, off = GaitEventKind.FOOT_STRIKE, GaitEventKind.FOOT_OFF
    contact = _first_inside(_times(events, strike, other), start, end)
    opposite_off = _first_inside(_times(events, off, other), start, contact if np.isfinite(contact) else end)
    foot_off = _first_inside(_times(events, off, side), start, end)
    complete = bool(np.isfinite([contact, opposite_off, foot_off]).all() and opposite_off < contact < foot_off)

    first, last = (_position(trial, side + foot_marker, t) for t in (start, end))
    stride = last - first
    stride_mm = float(np.linalg.norm(stride))
    opposite = _position(trial, other + foot_marker, contact)
    step_mm = float((last - opposite) @ stride) / stride_mm if stride_mm > 0 else math.nan
    values = _cycle_values(start, end, contact, opposite_off, foot_off, stride_mm, step_mm)
    # Vicon Workstation: the opposite Foot Off may come after the cycle; the step is the
    # opposite foot's, from this toe at the opening strike (module docstring)
    late_off = _first_inside(_times(events, off, other), start, math.inf)
    workstation = _cycle_values(start, end, contact, late_off, foot_off, stride_mm,
                                float(np.linalg.norm(opposite - first)))  # fmt: skip
    if workstation["Single Support"] < 0:  # the opposite foot never in swing inside the cycle
        workstation["Single Support"] = math.nan
    return CycleParameters(side, index, start, end, complete, values, workstation)


def _cycle_values(start: float, end: float, contact: float, opposite_off: float, foot_off: float,
                  stride_mm: float, step_mm: float) -> dict[str, float]:  # fmt: skip
    """The eleven parameters (:data:`UNITS`) from a cycle's event times (s) and its
    stride and step lengths (mm)."""
    stride_time = end - start
    return {
        "Cadence": 120.0 / stride_time,
        "Walking Speed": stride_mm / 1000.0 / stride_time,
        "Stride Time": stride_time,
        "Step Time": end - contact,
        "Opposite Foot Off": 100.0 * (opposite_off - start) / stride_time,
        "Opposite Foot Contact": 100.0 * (contact - start) / stride_time,
        "Foot Off": 100.0 * (foot_off - start) / stride_time,
        "Single Support": contact - opposite_off,
        "Double Support": (opposite_off - start) + (foot_off - contact),
        "Stride Length": stride_mm / 1000.0,
        "Step Length": step_mm / 1000.0,
    }


def side_parameters(trial: Trial, events: Sequence[Event | GaitEvent], side: str,
                    foot_marker: str = FOOT_MARKER) -> SideParameters:  # fmt: skip
    """The parameters of every gait cycle of one side (see the module docstring).

    Args:
        trial: markers in mm; needs ``L``/``R`` + ``foot_marker`` for the lengths (NaN
            without them).
        events: foot strike / foot off events of both sides (times in s), in any
            spelling :func:`fuzzygait.gait.event_labels.gait_events` reads (labels read once
            here), or its typed values.
        side: ``"L"``/``"Left"`` or ``"R"``/``"Right"``.
        foot_marker: marker (without the side letter) whose positions at the strikes give
            the lengths; Nexus uses ``"TOE"``.
    """
    code = side_code(side)
    typed = gait_events(events)
    cycles = [
        _one_cycle(trial, typed, code, cycle.index, cycle.start_time, cycle.end_time, foot_marker)
        for cycle in gait_cycles(trial, typed, code)
    ]
    return SideParameters(code, cycles)


def spatiotemporal_parameters(trial: Trial, events: Sequence[Event | GaitEvent] | None = None,
                              foot_marker: str = FOOT_MARKER) -> TrialParameters:  # fmt: skip
    """Both sides' spatio-temporal parameters of a trial.

    Args:
        events: the gait events (any spelling :func:`~fuzzygait.gait.event_labels.gait_events`
            reads; labels read once here); ``None`` takes the file's, in any such
            spelling, or detects them (:func:`~fuzzygait.gait.events.trial_gait_events`;
            the source, ``"file"`` or the detection method, is
            :attr:`TrialParameters.event_source`).

    Raises:
        EventError: naming the file, when neither side has a complete gait cycle (what
            to add is said).
        MarkerError: the file has no events and they cannot be detected.
    """
    if events is None:
        typed, source = trial_gait_events_typed(trial)
    else:
        typed, source = gait_events(events), "given"
    sides = {code: side_parameters(trial, typed, code, foot_marker) for code in SIDE_CONTEXTS}
    if not any(s.complete_cycles for s in sides.values()):
        counts = ", ".join(f"{len(s.cycles)} {SIDE_CONTEXTS[c].lower()}" for c, s in sides.items())
        raise EventError(
            f"{trial.name}: no complete gait cycle ({counts} cycles from {len(typed)} events, "
            f"{source}): a cycle needs a Foot Strike, the opposite Foot Off and Foot Strike, "
            "this foot's Foot Off and its next Foot Strike; add the missing events (e.g. "
            "with Nexus' gait-event detection) or trim the trial to whole cycles"
        )
    notes: list[Finding] = []
    for code, result in sides.items():
        name = SIDE_CONTEXTS[code].lower()
        if not result.complete_cycles:
            notes.append(Finding(FindingKind.SPATIOTEMPORAL, f"{name}: no complete gait cycle; its parameters are NaN",
                                 Severity.WARNING, side=name))  # fmt: skip
        elif not np.isfinite(result.first_complete.values["Stride Length"]):  # type: ignore[union-attr]
            notes.append(Finding(FindingKind.SPATIOTEMPORAL, f"{name}: {code}{foot_marker} missing at a foot strike; "
                                 "lengths and speed are NaN", Severity.WARNING, side=name,
                                 marker=code + foot_marker))  # fmt: skip
    return TrialParameters(trial.name, sides, source, notes)


def pooled_parameters(name: str, cycles: dict[str, np.ndarray], source: str = "pooled") -> TrialParameters:
    """Complete cycles of several trials as one :class:`TrialParameters` (e.g. a session's
    mean ± SD over every cycle of every trial).

    Args:
        name: what the result is of (e.g. the session's name).
        cycles: ``"L"``/``"R"`` -> ``(n_cycles, 11)`` parameter values in :data:`NAMES`
            order and :data:`UNITS`; a side left out has no cycles.
        source: where the cycles' events came from, for :attr:`TrialParameters.event_source`.
    """
    sides = {}
    for code in SIDE_CONTEXTS:
        rows = np.asarray(cycles.get(code, np.empty((0, len(NAMES)))), dtype=float).reshape(-1, len(NAMES))
        sides[code] = SideParameters(code, [CycleParameters(code, k, math.nan, math.nan, True, dict(zip(NAMES, row)))
                                            for k, row in enumerate(rows.tolist())])  # fmt: skip
    return TrialParameters(name, sides, source)


def column_name(name: str, statistic: str = "") -> str:
    """Table header of a parameter: ``"Cadence (steps/min)"``, ``"Cadence SD (steps/min)"``."""
    return f"{name}{' ' + statistic if statistic else ''} ({UNITS[name]})"


def parameters_table(results: Sequence[TrialParameters], selection: str = "all") -> pd.DataFrame:
    """One row per trial and side: ``trial``, ``side`` (Left/Right), ``cycles``, then per
    parameter its value and SD (columns :func:`column_name`, units in the header).

    Args:
        selection: ``"all"`` -- mean and SD over the side's complete cycles (``cycles``
            counts them); ``"nexus"`` -- the first complete cycle, as Vicon Nexus stores
            it (``cycles`` 1, SD NaN); ``"workstation"`` -- the first cycle, complete or
            not, with Vicon Workstation's definitions (:attr:`CycleParameters.workstation`).

    Raises:
        ParameterError: for an unknown selection.
    """
    if selection not in SELECTIONS:
        raise ParameterError(f"cycle selection must be one of {', '.join(SELECTIONS)}; got {selection!r}")
    rows = []
    for result in results:
        for code, side in result.sides.items():
            row: dict[str, object] = {"trial": result.trial, "side": SIDE_CONTEXTS[code]}
            if selection in ("nexus", "workstation"):
                first = side.first_complete if selection == "nexus" else side.first
                mean = (first.values if selection == "nexus" else first.workstation) if first else (
                    dict.fromkeys(NAMES, math.nan))
                sd = dict.fromkeys(NAMES, math.nan)
                row["cycles"] = int(first is not None)
            else:
                mean, sd = side.mean(), side.sd()
                row["cycles"] = len(side.complete_cycles)
            for name in NAMES:
                row[column_name(name)] = mean[name]
                row[column_name(name, "SD")] = sd[name]
            rows.append(row)
    return pd.DataFrame(rows, columns=["trial", "side", "cycles",
                                       *[column_name(n, s) for n in NAMES for s in ("", "SD")]])  # fmt: skip


def nexus_reference(trial: Trial) -> dict[str, dict[str, float]]:
    """The spatio-temporal parameters the file's ``ANALYSIS`` group holds, per side
    (``"L"``/``"R"``), converted to :data:`UNITS`.

    Nexus 1.x/2.x units are taken as they are; older Vicon (Workstation) units are
    converted: Cadence ``1/s`` (strides per second, = 1/Stride Time) x 120, lengths
    ``mm`` and speeds ``mm/s`` / 1000, Step Time and the support times in ``%`` of the
    cycle x Stride Time / 100.  Values under other names or in unknown units are left out.
    """
    result: dict[str, dict[str, float]] = {code: {} for code in SIDE_CONTEXTS}
    sides = {context: code for code, context in SIDE_CONTEXTS.items()}
    raw = [(sides[v.context], v.name, v.unit.strip(), v.value) for v in trial.analysis
           if v.context in sides and v.name in UNITS]  # fmt: skip
    scale = {("steps/min", "steps/min"): 1.0, ("1/s", "steps/min"): 120.0,
             ("m/s", "m/s"): 1.0, ("mm/s", "m/s"): 1e-3, ("m", "m"): 1.0, ("mm", "m"): 1e-3,
             ("s", "s"): 1.0, ("%", "%"): 1.0}  # fmt: skip
    for code, name, unit, value in raw:
        if (unit, UNITS[name]) in scale:
            result[code][name] = value * scale[(unit, UNITS[name])]
    for code, name, unit, value in raw:  # % of the cycle -> s, once Stride Time is known
        stride = result[code].get("Stride Time")
        if unit == "%" and UNITS[name] == "s" and stride is not None:
            result[code][name] = value * stride / 100.0
    return result


def reference_convention(trial: Trial) -> str:
    """Which definitions the file's ``ANALYSIS`` values follow: ``"workstation"`` when
    they are in the older Vicon Workstation units (Cadence in ``1/s``), else ``"nexus"``
    -- the :data:`SELECTIONS` entry to compare them with."""
    units = {v.name: v.unit.strip() for v in trial.analysis}
    return "workstation" if units.get("Cadence") == "1/s" else "nexus"


def agreement_tolerance(name: str, reference: float, rate: float, stride_time: float) -> float:
    """How far a parameter may differ from a reference value (issue 16's acceptance):
    one frame for times (``1 / rate`` s) and phases (``100 / (rate T)`` %), 1 % of the
    reference for cadence, speed and lengths."""
    unit = UNITS[name]
    if unit == "s":
        return 1.0 / rate
    if unit == "%":
        return 100.0 / (rate * stride_time)
    return 0.01 * abs(reference)


__all__ = [
    "FOOT_MARKER",
    "NAMES",
    "PARAMETERS",
    "PHASES",
    "SELECTIONS",
    "TIMES",
    "UNITS",
    "CycleParameters",
    "SideParameters",
    "TrialParameters",
    "agreement_tolerance",
    "column_name",
    "nexus_reference",
    "parameters_table",
    "pooled_parameters",
    "reference_convention",
    "side_parameters",
    "spatiotemporal_parameters",
]
