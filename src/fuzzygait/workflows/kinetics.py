"""Plug-in Gait kinetics of one trial in the pipeline: plates read, feet assigned, both
sides' joint moments, powers and ground reactions (issue 39).

:func:`trial_kinetics` takes an :class:`~fuzzygait.workflows.angles.AnglesRun` (the model
result, the pre-processed trial the model saw, the subject) and the trial's C3D file: the
force plates at the analog rate (:func:`fuzzygait.kinetics.plates.read_force_plates`),
each contact given to a foot automatically
(:func:`fuzzygait.kinetics.assignment.automatic_assignment`) and
:func:`fuzzygait.kinetics.plug_in_gait.plug_in_gait_kinetics`. The result,
:class:`TrialKinetics`, holds the kinetics as an :class:`xarray.Dataset` with named
dimensions in the units the pages use (N·m/kg, W/kg, % body weight); Nexus' names and
units (``LAnkleMoment`` in N·mm/kg ...) are made only at the edges
(:meth:`TrialKinetics.nexus_outputs`: the C3D written back and the tables' columns).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
import xarray as xr
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind, Severity, of_kind
from fuzzygait.core.names import Axis, Side
from fuzzygait.core.trial import Event, Trial
from fuzzygait.io.force_plates import ForcePlate, ForcePlateError
from fuzzygait.io.subject import read_force_plate_assignment
from fuzzygait.kinetics.assignment import (
    Foot,
    PlateContact,
    automatic_assignment,
    contact_findings,
    contact_ground,
    over_plate,
)
from fuzzygait.kinetics.ground import frame_means, samples_per_frame
from fuzzygait.kinetics.inverse_dynamics import ComDerivative
from fuzzygait.kinetics.plates import DEFAULT_THRESHOLD_N, read_force_plates
from fuzzygait.kinetics.plug_in_gait import JOINTS, KineticsResult, plug_in_gait_kinetics
from fuzzygait.workflows.plate_events import contact_edges

if TYPE_CHECKING:
    from fuzzygait.workflows.angles import AnglesRun

__all__ = ["JOINTS", "LONGEST_KINETIC_NAME", "NEXUS_QUANTITIES", "TrialKinetics", "run_kinetics", "trial_kinetics"]

Array = NDArray[np.float64]
AXES = tuple(a.value for a in Axis)
SIDES = tuple(s.value for s in Side)

#: Loaded samples (normal force above this, N) whose centre of pressure is checked to lie
#: on its plate, and how far beyond the plate's edge it may lie (mm).
COP_CHECK_N = 100.0
COP_MARGIN_MM = 50.0
#: Fewer of those samples on the plate than this fraction: the plate's lengths and
#: moments are in different units.
COP_ON_PLATE = 0.9

#: The dataset's variables: name -> (unit, Nexus output suffix, Nexus kind, factor to
#: Nexus' unit). The ground reactions' names are per side (no joint).
NEXUS_QUANTITIES: dict[str, tuple[str, str, str, float]] = {
    "moment": ("N·m/kg", "Moment", "moment", 1e3),
    "joint_force": ("N/kg", "Force", "force", 1.0),
    "power": ("W/kg", "Power", "power", 1.0),
    "ground_force": ("N/kg", "GroundReactionForce", "force", 1.0),
    "grf": ("% BW", "NormalisedGRF", "force", 1.0),
}
#: Characters of the longest kinetic output name (``RGroundReactionForce``).
LONGEST_KINETIC_NAME = max(len(Side.RIGHT.value + joint + NEXUS_QUANTITIES[var][1]) for var, joints in
                           (("moment", JOINTS), ("joint_force", JOINTS), ("power", JOINTS), ("ground_force", ("",)),
                            ("grf", ("",))) for joint in joints)  # fmt: skip
#: Nexus' unit of each output kind written (C3D ``POINT:<KIND>_UNITS`` says N, Nmm, W).
NEXUS_UNITS = {"Moment": "N·mm/kg", "Force": "N/kg", "Power": "W/kg", "GroundReactionForce": "N/kg",
               "NormalisedGRF": "% BW"}  # fmt: skip


@dataclass(frozen=True)
class TrialKinetics:
    """Plug-in Gait kinetics of one trial.

    Attributes:
        data: dims ``side`` (``"L"``, ``"R"``), ``joint`` (``"Ankle"``, ``"Knee"``,
            ``"Hip"``), ``axis`` (``"X"``, ``"Y"``, ``"Z"``: Nexus' components), ``frame``
            (C3D frame numbers; coordinate ``time`` s), ``plate`` (1-based numbers).
            Variables (units in each one's ``attrs["units"]``):
            ``moment (side, joint, axis, frame)`` N·m/kg, the internal joint moment in the
            distal segment's frame (X sagittal, + extensor/plantarflexor);
            ``joint_force (side, joint, axis, frame)`` N/kg, distal frame;
            ``power (side, joint, frame)`` W/kg, + generation;
            ``grf (side, axis, frame)`` % body weight, X forward, Y medial, Z up;
            ``ground_force (side, axis, frame)`` N/kg, laboratory frame;
            ``plate_force (plate, axis, frame)`` N, the reaction on the body, laboratory
            frame, and ``plate_cop (plate, axis, frame)`` mm, laboratory frame (NaN without
            contact), each the mean of the analog samples of the frame;
            ``plate_corners (plate, corner, axis)`` mm, the surface corners as the file
            lists them (laboratory frame).
            NaN on the first and last four frames and for a side not computed.
            ``attrs["body_mass"]`` kg.
        contacts: every contact of every plate, the foot it went to or why not used.
        findings: the plates' findings, one per contact, the sides not computed.
        unavailable: side -> why its kinetics were not computed.
        edges: per contact (as ``contacts``), when it began and ended, s on the C3D clock,
            from the plate's analog contact (NaN: with the trial's first or last frame;
            :func:`~fuzzygait.workflows.plate_events.contact_edges`).
        force_plates: the plates as read (analog rate; :func:`~fuzzygait.kinetics.plates.read_force_plates`),
            for the analyses that need their samples again (the fuzzy kinetics).
    """

    data: xr.Dataset
    contacts: tuple[PlateContact, ...] = ()
    findings: tuple[Finding, ...] = ()
    unavailable: Mapping[Side, str] = field(default_factory=dict)
    edges: tuple[tuple[float, float], ...] = ()
    force_plates: tuple[ForcePlate, ...] = ()

    @property
    def body_mass(self) -> float:
        """kg, the mass the outputs are normalised by."""
        return float(self.data.attrs["body_mass"])

    @property
    def plates(self) -> tuple[int, ...]:
        """The plate numbers read."""
        return tuple(int(p) for p in self.data["plate"].values)

    def plates_used(self, side: Side) -> tuple[int, ...]:
        """The plates whose contacts act on the ``side`` foot, in order."""
        return tuple(dict.fromkeys(c.plate for c in self.contacts if c.side is side))

    def unused(self) -> tuple[PlateContact, ...]:
        """The contacts not used (:attr:`PlateContact.reason`)."""
        return tuple(c for c in self.contacts if c.side is None)

    def summary(self) -> str:
        """One line: the plates used per side and the contacts not used."""
        sides = []
        for side in Side:
            plates = self.plates_used(side)
            what = ("plate " + ", ".join(map(str, plates))) if plates else "no plate"
            sides.append(f"{side.word.lower()} {what}" + (" (not computed)" if side in self.unavailable else ""))
        unused = len(self.unused())
        return (f"kinetics ({len(self.plates)} force plates, {self.body_mass:g} kg): " + "; ".join(sides)
                + (f"; {unused} contact{'s' if unused != 1 else ''} not used" if unused else ""))  # fmt: skip

    def _nexus(self, suffix: str = "") -> list[tuple[str, str, Array, str]]:
        """``(name, Nexus quantity, (n, 3) in Nexus' unit, C3D kind)`` of every output."""
        out: list[tuple[str, str, Array, str]] = []
        for side in Side:
            for joint in JOINTS:
                for var in ("moment", "joint_force", "power"):
                    _, quantity, kind, factor = NEXUS_QUANTITIES[var]
                    values = self.data[var].sel(side=side.value, joint=joint).values
                    if var == "power":
                        zero = np.where(np.isnan(values), np.nan, 0.0)  # X = Y = 0 where Z is known
                        values = np.stack([zero, zero, values])
                    out.append((side.value + joint + quantity + suffix, quantity, values.T * factor, kind))
            for var in ("ground_force", "grf"):
                _, quantity, kind, factor = NEXUS_QUANTITIES[var]
                values = self.data[var].sel(side=side.value).values.T * factor
                values[np.all(values == 0.0, axis=1)] = np.nan  # no plate under the foot: unknown, as Nexus leaves it
                out.append((side.value + quantity + suffix, quantity, values, kind))
        return out

    def nexus_outputs(self, suffix: str = "") -> dict[str, tuple[Array, str]]:
        """The kinetics as Nexus names and stores them: ``LAnkleMoment`` N·mm/kg,
        ``LAnkleForce`` N/kg, ``LAnklePower`` W/kg (in Z; X = Y = 0 where Z is known), ``LGroundReactionForce``
        N/kg, ``LNormalisedGRF`` % BW (missing where no plate carries the foot: in swing
        and on the floor between plates, as Nexus leaves them), each ``(n, 3)`` with
        ``suffix`` appended, and its C3D output kind (``"moment"``, ``"power"``, ``"force"``)."""
        return {name: (np.ascontiguousarray(values), kind) for name, _, values, kind in self._nexus(suffix)}

    def cycle_table(self, trial: Trial, events: Sequence[Event]) -> pd.DataFrame:
        """The :meth:`columns` cut into the gait cycles whose stance was on a force plate,
        as the pages and the normative data take them
        (:func:`~fuzzygait.gait.normative.kinetic_cycles`): moments, powers and joint forces
        over 0..100 % of the gait cycle, the ground reaction over 0..100 % of the stance the
        plate measured; the long table of :func:`~fuzzygait.gait.cycles.normalised_angle_table`
        (``angle`` the column's name, ``cycle`` its index among the counted cycles), in
        Nexus' units (:data:`NEXUS_UNITS`)."""
        from fuzzygait.gait.cycles import TABLE_COLUMNS, gait_cycles, percent_points
        from fuzzygait.gait.event_labels import gait_events
        from fuzzygait.gait.normative import N_POINTS, kinetic_cycles

        typed = gait_events(events)
        columns = self.columns()
        components = {side.value: {name[1:]: values for name, (values, _) in columns.items() if name[0] == side.value}
                      for side in Side}  # fmt: skip
        cycles = {side: gait_cycles(trial, typed, side) for side in components}
        stacks = kinetic_cycles(components, cycles)
        percent = percent_points(N_POINTS)
        parts = [pd.DataFrame({"angle": name, "side": name[0], "cycle": np.repeat(np.arange(len(stack)), percent.size),
                               "percent": np.tile(percent, len(stack)), "value": stack.ravel()})
                 for name in columns if (stack := stacks.get(name)) is not None]  # fmt: skip
        return pd.concat(parts, ignore_index=True)[TABLE_COLUMNS] if parts else pd.DataFrame(columns=TABLE_COLUMNS)

    def columns(self) -> dict[str, tuple[Array, str]]:
        """Per-frame table columns named as Nexus (``LAnkleMoment_X`` ...; powers Z only)
        -> values in Nexus' units and the unit (:data:`NEXUS_UNITS`)."""
        out: dict[str, tuple[Array, str]] = {}
        for name, quantity, values, _ in self._nexus():
            for k, axis in enumerate(AXES):
                if quantity != "Power" or axis == "Z":
                    out[f"{name}_{axis}"] = (values[:, k], NEXUS_UNITS[quantity])
        return out


def check_units(plate: ForcePlate, path: Path) -> None:
    """Refuse a plate whose loaded centre of pressure lies off its own surface: its
    corners (``POINT:UNITS``) and its moments (``ANALOG:UNITS``) are in different units
    (e.g. corners in m labelled mm), so every moment computed from it would be wrong.

    Raises:
        ForcePlateError: naming the file, the plate and what to check.
    """
    loaded = np.asarray(plate.contact, dtype=bool) & (np.linalg.norm(plate.force, axis=1) > COP_CHECK_N)
    loaded &= np.all(np.isfinite(plate.cop), axis=1)
    if loaded.sum() < 10:
        return
    on = over_plate(plate.cop[loaded], plate.corners, COP_MARGIN_MM)
    if on.mean() < COP_ON_PLATE:
        sides = np.linalg.norm(plate.corners[[0, 1]] - plate.corners[[1, 2]], axis=1)
        raise ForcePlateError(f"{path}: force plate {plate.number}: the centre of pressure lies off the plate on "
                              f"{1 - on.mean():.0%} of the loaded samples (the plate read as {sides[0]:.3g} x "
                              f"{sides[1]:.3g} mm): its corners and moment channels are in different units - check "
                              "POINT:UNITS and the moment channels' ANALOG:UNITS")  # fmt: skip


def _plate_frames(plates: Sequence[ForcePlate], n_frames: int, rate: float) -> tuple[Array, Array]:
    """``(plate, axis, frame)`` force N and COP mm at the marker frames: the means of each
    frame's analog samples (:func:`~fuzzygait.kinetics.ground.frame_means`), the COP over
    the samples in contact (NaN without)."""
    forces, cops = [], []
    for p in plates:
        ratio = samples_per_frame(p.rate, rate)
        contact = np.asarray(p.contact, dtype=bool) & np.all(np.isfinite(p.cop), axis=1)
        forces.append(frame_means(np.where(contact[:, None], p.force, 0.0), ratio, n_frames))
        weight = frame_means(contact.astype(float), ratio, n_frames)
        cop = frame_means(np.where(contact[:, None], p.cop, 0.0), ratio, n_frames)
        cops.append(np.where(weight[:, None] > 0, cop / np.maximum(weight, 1e-12)[:, None], np.nan))
    shape = (0, 3, n_frames)
    if not plates:
        return np.zeros(shape), np.zeros(shape)
    return np.stack(forces).transpose(0, 2, 1), np.stack(cops).transpose(0, 2, 1)


def _dataset(out: KineticsResult, trial: Trial, plates: Sequence[ForcePlate], body_mass: float) -> xr.Dataset:
    """The :attr:`TrialKinetics.data` of ``out`` (Nexus' names and units) and the plates."""
    n = trial.n_frames
    nan = np.full((n, 3), np.nan)

    def get(name: str, factor: float = 1.0) -> Array:
        return np.asarray(out.outputs.get(name, nan), dtype=float).T / factor

    moment = np.array([[get(s + j + "Moment", 1e3) for j in JOINTS] for s in SIDES])
    force = np.array([[get(s + j + "Force") for j in JOINTS] for s in SIDES])
    power = np.array([[get(s + j + "Power")[2] for j in JOINTS] for s in SIDES])
    ground = np.array([get(s + "GroundReactionForce") for s in SIDES])
    grf = np.array([get(s + "NormalisedGRF") for s in SIDES])
    plate_force, plate_cop = _plate_frames(plates, n, trial.rate)
    data = xr.Dataset(
        {"moment": (("side", "joint", "axis", "frame"), moment),
         "joint_force": (("side", "joint", "axis", "frame"), force),
         "power": (("side", "joint", "frame"), power), "ground_force": (("side", "axis", "frame"), ground),
         "grf": (("side", "axis", "frame"), grf), "plate_force": (("plate", "axis", "frame"), plate_force),
         "plate_cop": (("plate", "axis", "frame"), plate_cop),
         "plate_corners": (("plate", "corner", "axis"), np.array([p.corners for p in plates]).reshape(-1, 4, 3))},
        coords={"side": list(SIDES), "joint": list(JOINTS), "axis": list(AXES), "frame": trial.frames,
                "time": ("frame", trial.times), "plate": [p.number for p in plates], "corner": [1, 2, 3, 4]},
        attrs={"body_mass": float(body_mass), "model": "Plug-in Gait kinetics", "rate": float(trial.rate)},
    )  # fmt: skip
    for var, (unit, *_) in NEXUS_QUANTITIES.items():
        data[var].attrs["units"] = unit
    data["plate_force"].attrs["units"] = "N"
    data["plate_cop"].attrs["units"] = data["plate_corners"].attrs["units"] = "mm"
    return data


#: The markers a foot's contacts with the plates are found from (:func:`_feet`).
FOOT_MARKERS = ("HEE", "TOE", "ANK")


def _unseen_foot_markers(trial: Trial, side: Side) -> list[str]:
    """The side's :data:`FOOT_MARKERS` the trial lacks or never sees."""
    return [side.value + m for m in FOOT_MARKERS
            if not (trial.has_marker(side.value + m) and np.isfinite(trial.marker(side.value + m)).any())]  # fmt: skip


def _feet(trial: Trial) -> dict[Side, Foot]:
    """The feet whose heel, toe and ankle markers the trial has (each seen at least once)."""
    return {side: Foot(*(trial.marker(side.value + m) for m in FOOT_MARKERS))
            for side in Side if not _unseen_foot_markers(trial, side)}  # fmt: skip


def foot_marker_findings(trial: Trial) -> list[Finding]:
    """One warning per foot whose plate contacts cannot be found for want of a marker."""
    return [Finding(FindingKind.KINETICS, f"the {side.word.lower()} foot's contacts with the force plates cannot be "
                    f"found: {', '.join(missing)} {'is' if len(missing) == 1 else 'are'} not in the trial (a "
                    "contact is told by the heel, toe and ankle markers)", Severity.WARNING)
            for side in Side if (missing := _unseen_foot_markers(trial, side))]  # fmt: skip


def _check_mass(body_mass: float, path: Path, subject_file: str | os.PathLike[str] | None) -> None:
    if not (np.isfinite(body_mass) and body_mass > 0):
        where = f"in the subject file {subject_file}" if subject_file is not None else \
            f"in a subject file (.toml or .vsk) or the PROCESSING group of {path.name}"
        raise ParameterError(f"{path}: has force plates but the body mass is {body_mass:g} kg: set Bodymass (kg) "
                             f"{where} for the kinetics")  # fmt: skip


def trial_kinetics(run: AnglesRun, path: str | os.PathLike[str] | None = None, *,
                   threshold_n: float = DEFAULT_THRESHOLD_N,
                   subject_file: str | os.PathLike[str] | None = None) -> TrialKinetics | None:  # fmt: skip
    """The Plug-in Gait kinetics of a run's trial.

    Args:
        run: the angles run (its pre-processed ``trial``, ``result``, ``subject``).
        path: the trial's C3D file (default: the file it was read from).
        threshold_n: the plates' contact threshold, N.
        subject_file: its ``[force_plates]`` table assigns plates to feet in place of the
            automatic rule (:func:`fuzzygait.io.subject.read_force_plate_assignment`); named
            in the body-mass error.

    Returns:
        None when the trial has no file or no force plates.

    Raises:
        ParameterError: the trial has plates but no positive body mass (names where to set
            ``Bodymass``).
        ForcePlateError: no plate can be used (each plate's reason), or a plate's centre of
            pressure lies off the plate (lengths and moments in different units,
            :func:`check_units`).
    """
    source = Path(path) if path is not None else run.raw.source
    if source is None:
        return None
    plates = read_force_plates(source, threshold_n=threshold_n)
    if not plates:
        return None
    _check_mass(run.subject.body_mass, source, subject_file)
    for plate in plates:
        check_units(plate, source)
    trial = run.trial
    override = read_force_plate_assignment(subject_file) if subject_file is not None else {}
    contacts = automatic_assignment(plates, _feet(trial), trial.rate, threshold_n, override=override)
    ground = {side: contact_ground(plates, contacts, side, trial.n_frames, trial.rate) for side in Side}
    out = plug_in_gait_kinetics(run.result, trial, run.subject, ground, ComDerivative.GCV_SPLINE)  # as Nexus
    findings = [f for p in plates for f in p.findings] + foot_marker_findings(trial) + contact_findings(
        contacts, trial.first_frame)
    if of_kind(run.raw.notes, FindingKind.UNITS) and not any(f.severity is Severity.WARNING
                                                             for f in of_kind(run.raw.notes, FindingKind.UNITS)):
        findings.append(Finding(FindingKind.KINETICS, "kinetics in mm: the marker positions and the plates' corners "
                                "were both converted to mm (POINT:UNITS), the forces are in N"))  # fmt: skip
    for side in Side:
        if side in out.unavailable:
            findings.append(Finding(FindingKind.KINETICS, f"{side.word.lower()} kinetics not computed: "
                                    f"{out.unavailable[side]}", Severity.WARNING, side=side.word.lower()))  # fmt: skip
        elif not any(c.side is side for c in contacts):
            findings.append(Finding(FindingKind.KINETICS, f"the {side.word.lower()} foot is on no force plate: its "
                                    "moments hold no ground reaction (right in swing only)", Severity.WARNING,
                                    side=side.word.lower()))  # fmt: skip
    edges = tuple(contact_edges(plates, contacts, trial.rate, trial.first_frame))
    return TrialKinetics(_dataset(out, trial, plates, run.subject.body_mass), tuple(contacts), tuple(findings),
                         dict(out.unavailable), edges, tuple(plates))  # fmt: skip


def run_kinetics(run: AnglesRun, subject_file: str | os.PathLike[str] | None = None,
                 ) -> tuple[TrialKinetics | None, list[Finding]]:  # fmt: skip
    """:func:`trial_kinetics` as the angles pipeline runs it: the kinetics (None without
    plates) and the notes for the run. A trial read from a file without force plates, or
    given without its file, gets one note; kinetics that cannot be computed (no body
    mass, no usable plate, units that disagree) are a warning note with the error's line
    and no kinetics - the angles stand."""
    from fuzzygait.core.errors import FuzzyGaitError

    try:
        kinetics = trial_kinetics(run, subject_file=subject_file)
    except FuzzyGaitError as exc:
        return None, [Finding(FindingKind.KINETICS, f"kinetics not computed: {exc}", Severity.WARNING)]
    if kinetics is None:
        source = run.raw.source
        why = ("the trial was given without its C3D file (Trial.source), where the force plates are read from"
               if source is None else f"no force plates in {source.name}")
        return None, [Finding(FindingKind.KINETICS, f"{why}: no kinetics")]
    return kinetics, list(kinetics.findings)
