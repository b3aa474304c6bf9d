"""The clinical content of a trial page, as numbers: spatio-temporal parameters, foot off,
stride-to-stride mean ± SD, normative curves and the Gait Profile Score, kinetics stored
in the file, and the markers the model uses (the data-quality section is restricted to
them).

Kinetics
--------
Vicon Nexus stores Plug-in Gait's joint moments and powers as model outputs
(``LKneeMoment``, ``LKneePower``; :attr:`fuzzygait.core.trial.Trial.outputs` of kind
``moment``/``power``).  Its C3D labels them ``Nmm`` and ``W`` (``POINT:MOMENT_UNITS``,
``POWER_UNITS``), but Plug-in Gait divides them by the body mass: in the reference files
the knee moment peaks near 1000 and the knee power near 3, i.e. N·mm/kg and W/kg.  The
report shows moments in N·m/kg (stored value / 1000) and powers in W/kg when the stored
moments stay below :data:`PER_KG_LIMIT` N·mm (no walking moment reaches 20 N·m/kg), and
in N·m and W otherwise (a file that was not mass-normalised).  The power is the output's
Z component (Plug-in Gait's total joint power; X and Y are 0).  A cycle enters a
kinetic curve only when the side's stored ground reaction force (``LGroundReactionForce``)
exceeds :data:`MIN_GRF` N at 20, 30 and 40 % of it (its own stance on a plate, not only the
next strike) — Nexus still writes the (small, inertial)
moments of a foot that struck no plate: Movement_trial's left cycle peaks at 209 N·mm/kg
without any force, the right one with a plate at 959 — and the output is finite and not
identically 0 over the cycle (files without the force output: this rule alone).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from fuzzygait.gait.cycles import GaitCycle, cycle_statistics, normalise_cycles
from fuzzygait.gait.normative import GaitProfile, NormativeData, gait_profile
from fuzzygait.gait.spatiotemporal import TrialParameters, spatiotemporal_parameters
from fuzzygait.kinematics.labels import ANGLE_ROWS, ROW_TITLES
from fuzzygait.markererror.angle_model import model_angle_markers

if TYPE_CHECKING:
    from fuzzygait.mocap.gaps import Gap
    from fuzzygait.viz.report.bands import ReportRun

__all__ = ["ClinicalData", "KineticCurve", "grid_rows", "model_markers"]

#: Largest |moment| (N·mm) taken as per kg of body mass (see the module docstring).
PER_KG_LIMIT = 20000.0
#: Ground reaction force (N) above which a foot is on a force plate.
MIN_GRF = 1.0
#: Percentages of the cycle (mid-stance) at which the force must be there.
STANCE_CHECKS = (20.0, 30.0, 40.0)
#: Joints of the kinetics grid.
KINETIC_JOINTS = ("Hip", "Knee", "Ankle")
#: Samples of a normalised cycle.
N_POINTS = 101


def grid_rows(run: ReportRun) -> list[tuple[str, str]]:
    """Rows of the kinematics grid: pelvis, hip, knee, ankle, foot progression, and the
    forefoot when the model computed it (CGM 2.4)."""
    rows = list(ANGLE_ROWS)
    if any(f"{s}ForeFootAngles" in run.result.angles for s in "LR"):
        rows.append(("ForeFootAngles", ROW_TITLES["ForeFootAngles"]))
    return rows


def model_markers(run: ReportRun) -> list[str]:
    """The dynamic markers the model's angles are computed from (every angle it computed
    or tried), in the trial's marker order; every labelled marker if that fails."""
    clusters = getattr(run, "clusters", None)
    wanted: set[str] = set()
    for name in [*run.result.angles, *run.result.unavailable]:
        try:
            wanted.update(model_angle_markers(run.trial, name, run.result.model, clusters))
        except Exception:  # noqa: BLE001 - a model that cannot name them: keep every marker
            return list(run.trial.marker_labels)
    return [m for m in run.trial.marker_labels if m in wanted] or list(run.trial.marker_labels)


@dataclass(frozen=True)
class KineticCurve:
    """Mean ± SD over the cycles with kinetics of one output component of one side.

    Attributes:
        mean, sd: ``(101,)`` in :attr:`unit` (SD NaN with fewer than two cycles).
        cycles: cycles used (with force-plate data).
        unit: ``"N·m/kg"``, ``"W/kg"``, ``"N·m"`` or ``"W"``.
    """

    mean: np.ndarray
    sd: np.ndarray
    cycles: int
    unit: str


def _contact(grf: np.ndarray | None, cycles: Sequence[GaitCycle]) -> np.ndarray:
    """Per cycle whether the side's stored ground reaction force (N, ``(n_frames, 3)``)
    exceeds :data:`MIN_GRF` at each of :data:`STANCE_CHECKS` % of the cycle (the foot
    stood on a force plate during this cycle's stance, not only at the next strike); all
    True without a stored force."""
    if grf is None:
        return np.ones(len(cycles), dtype=bool)
    magnitude = np.linalg.norm(np.nan_to_num(np.asarray(grf, dtype=float)), axis=1)
    out = np.zeros(len(cycles), dtype=bool)
    for k, cycle in enumerate(cycles):
        frames = [int(round(cycle.start + p / 100.0 * (cycle.end - cycle.start))) for p in STANCE_CHECKS]
        out[k] = all(0 <= f < magnitude.size and magnitude[f] > MIN_GRF for f in frames)
    return out


def _kinetic_curve(values: np.ndarray, cycles: Sequence[GaitCycle], kind: str, per_kg: bool,
                   contact: np.ndarray) -> KineticCurve | None:  # fmt: skip
    """The kinetic curve of one component ``values (n_frames,)`` as stored, over the
    cycles with force-plate ``contact``."""
    normalised = normalise_cycles(values, cycles, N_POINTS)  # (c, p)
    keep = contact & np.isfinite(normalised).all(axis=1) & (np.abs(normalised).max(axis=1, initial=0.0) > 0)
    if not keep.any():
        return None
    scale = 1e-3 if kind == "moment" else 1.0
    mean, sd = cycle_statistics(normalised[keep] * scale)
    unit = ("N·m" if kind == "moment" else "W") + ("/kg" if per_kg else "")
    return KineticCurve(mean, sd, int(keep.sum()), unit)


@dataclass
class ClinicalData:
    """The clinical numbers of one trial page.

    Attributes:
        parameters: spatio-temporal parameters (None when no side has a complete cycle;
            ``parameters_error`` says why).
        foot_off: side -> mean Foot Off over its cycles (% of the cycle), when known.
        curves: sided angle component -> ``(mean, sd)`` over the side's cycles (deg,
            101 points; the curves the GPS compares).
        normative: the reference data, or None.
        profile: GVS/GPS against ``normative`` (None without it).
        kinetics: (joint, "moment"|"power", side, axis) -> curve, for the outputs stored.
        markers: the markers the model uses (:func:`model_markers`).
        rows: the kinematics grid rows (:func:`grid_rows`).
    """

    parameters: TrialParameters | None
    parameters_error: str | None
    foot_off: dict[str, float]
    curves: dict[str, tuple[np.ndarray, np.ndarray]]
    normative: NormativeData | None
    profile: GaitProfile | None
    kinetics: dict[tuple[str, str, str, str], KineticCurve] = field(default_factory=dict)
    markers: list[str] = field(default_factory=list)
    rows: list[tuple[str, str]] = field(default_factory=list)

    @classmethod
    def of(cls, run: ReportRun, cycles: dict[str, list[GaitCycle]], *, parameters: TrialParameters | None = None,
           normative: NormativeData | None = None) -> ClinicalData:  # fmt: skip
        """The clinical numbers of ``run`` cut into ``cycles`` (per side)."""
        error = None
        if parameters is None:
            try:
                parameters = spatiotemporal_parameters(run.trial, run.events)
            except Exception as exc:  # noqa: BLE001 - a page without the table, saying why
                parameters, error = None, str(exc)
        foot_off = {}
        for side, side_cycles in cycles.items():
            offs = [c.foot_off_percent for c in side_cycles if c.foot_off_percent is not None]
            if offs:
                foot_off[side] = float(np.mean(offs))
        curves: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for name, values in run.result.angles.items():
            side = name[:1]
            if side not in cycles or name in run.result.unavailable or not cycles[side]:
                continue
            normalised = normalise_cycles(np.asarray(values, dtype=float), cycles[side], N_POINTS)
            for k, axis in enumerate("XYZ"):
                mean, sd = cycle_statistics(normalised[:, :, k])
                if np.isfinite(mean).any():
                    curves[f"{name}_{axis}"] = (mean, sd)
        profile = None
        if normative is not None:
            profile = gait_profile({n: m for n, (m, _) in curves.items()}, normative)
        data = cls(parameters, error, foot_off, curves, normative, profile,
                   markers=model_markers(run), rows=grid_rows(run))  # fmt: skip
        data.kinetics = _kinetics(run, cycles)
        return data

    def model_gaps(self, gaps: Sequence[Gap]) -> list[Gap]:
        """The gaps of the markers the model uses."""
        used = set(self.markers)
        return [g for g in gaps if g.marker in used]

    def has_kinetics(self) -> bool:
        """Whether the file holds moments or powers with at least one usable cycle."""
        return bool(self.kinetics)


def _kinetics(run: ReportRun, cycles: dict[str, list[GaitCycle]]) -> dict[tuple[str, str, str, str], KineticCurve]:
    """Every hip/knee/ankle moment (X, Y, Z) and power (Z) stored in the raw trial."""
    outputs, kinds = run.raw.outputs, run.raw.output_kinds
    moments = [np.asarray(outputs[f"{s}{j}Moment"], dtype=float) for s in "LR" for j in KINETIC_JOINTS
               if kinds.get(f"{s}{j}Moment") == "moment"]  # fmt: skip
    peak = max((float(np.nanmax(np.abs(m))) for m in moments if np.isfinite(m).any()), default=math.nan)
    per_kg = not (peak > PER_KG_LIMIT)
    out: dict[tuple[str, str, str, str], KineticCurve] = {}
    for side, side_cycles in cycles.items():
        if not side_cycles:
            continue
        grf = outputs.get(f"{side}GroundReactionForce") if kinds.get(f"{side}GroundReactionForce") == "force" else None
        contact = _contact(grf, side_cycles)
        for joint in KINETIC_JOINTS:
            for kind, axes in (("moment", "XYZ"), ("power", "Z")):
                name = f"{side}{joint}{kind.capitalize()}"
                if kinds.get(name) != kind or name not in outputs:
                    continue
                values = np.asarray(outputs[name], dtype=float)
                if values.ndim != 2 or values.shape[0] != run.trial.n_frames:
                    continue
                for axis in axes:
                    curve = _kinetic_curve(values[:, "XYZ".index(axis)], side_cycles, kind, per_kg, contact)
                    if curve is not None:
                        out[(joint, kind, side, axis)] = curve
    return out
