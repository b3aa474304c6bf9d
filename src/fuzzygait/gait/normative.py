"""Normative gait data (a lab's reference mean ± SD per % of the gait cycle) and the Gait
Profile Score / Movement Analysis Profile of Baker et al. (2009).

Normative file (CSV)
--------------------
One row per angle component and percentage of the gait cycle, comma-separated, a header
line, no comment lines::

    variable,percent,mean,sd,cycles
    KneeAngles_X,0,4.812,3.1,48
    KneeAngles_X,1,5.37,3.2,48
    ...

* ``variable``: a joint-angle component as the angle tables name it, either without side
  (``KneeAngles_X``: left and right cycles pooled, the usual normative data; Plug-in
  Gait's right-side angles already carry the left side's signs) or with it
  (``LKneeAngles_X``: that side only).  A side's curve is looked up with its side first,
  then without.
* ``percent``: 0 to 100 (% of the gait cycle, foot strike to the next foot strike of the
  same side); any grid that covers 0 and 100, interpolated linearly onto 0, 1, ..., 100.
* ``mean``, ``sd``: in the variable's unit (sd >= 0; the sample SD over the reference
  cycles): degrees for the angles.
* ``cycles`` (optional): number of reference cycles at that point.

Kinetic variables (Plug-in Gait's, :func:`kinetic_cycles`) are named as the angles are:
``KneeMoment_X`` ... (joint moment, N·m per kg body mass, components X sagittal, Y
frontal, Z transverse as Plug-in Gait signs them), ``KneePower_Z`` (joint power, W/kg,
positive = generated) over the gait cycle, and ``NormalisedGRF_X/_Y/_Z`` (ground reaction,
% body weight; forward, medial, up) over the **stance** phase as the plate measured it
(``percent`` 0 = first, 100 = last frame of the foot's load on the plate).  Only cycles
whose stance was on a force plate count.

:func:`write_normative` writes every float with 17 significant digits, so a file read
back gives the very numbers that were written.

Gait Profile Score
------------------
The Gait Variable Score of one variable is the RMS difference, over the gait cycle sampled
every 2 % (51 points, 0..100 %), between the trial's mean curve (mean over its cycles of
that side) and the normative mean (Baker et al. 2009, Gait Posture 30:265-269):
``GVS = sqrt(mean_t (x_t - xref_t)^2)`` in degrees.  The nine variables
(:data:`GPS_VARIABLES`) are pelvic tilt, obliquity and rotation, hip flexion, ab/adduction
and rotation, knee flexion, ankle dorsiflexion and foot progression.  A side's GPS is
the RMS of its nine GVS; the overall GPS is the RMS of fifteen: the left side's nine and
the right side's six that are not pelvic (the pelvis moves as one, so its variables are
counted once, from the left side, as Baker et al. do).  The Movement Analysis Profile
(MAP) is the set of GVS per variable and side, with the GPS beside them.  A GVS (and a
GPS using it) is NaN where the trial's mean curve or the normative curve is missing.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.trial import Event, Trial
from fuzzygait.gait.cycles import GaitCycle, cycle_statistics, gait_cycles, normalise_cycles, percent_points

__all__ = [
    "COLUMNS",
    "GPS_VARIABLES",
    "GaitProfile",
    "NormativeData",
    "build_normative",
    "gait_profile",
    "gait_variable_score",
    "kinetic_cycles",
    "loaded_cycles",
    "mean_curves",
    "normalised_cycles",
    "read_normative",
    "write_normative",
]

#: Samples of a normalised cycle (0, 1, ..., 100 %).
N_POINTS = 101
#: Columns of the normative file (``cycles`` optional when read).
COLUMNS = ("variable", "percent", "mean", "sd", "cycles")
#: Baker et al.'s nine variables: (angle without side, component, name).
GPS_VARIABLES: tuple[tuple[str, str, str], ...] = (
    ("PelvisAngles", "X", "Pelvic tilt"),
    ("PelvisAngles", "Y", "Pelvic obliquity"),
    ("PelvisAngles", "Z", "Pelvic rotation"),
    ("HipAngles", "X", "Hip flexion"),
    ("HipAngles", "Y", "Hip ab/adduction"),
    ("HipAngles", "Z", "Hip rotation"),
    ("KneeAngles", "X", "Knee flexion"),
    ("AnkleAngles", "X", "Ankle dorsiflexion"),
    ("FootProgressAngles", "Z", "Foot progression"),
)
#: The GVS grid: every 2 % of the cycle (indices into the 101-point curves).
GVS_POINTS = np.arange(0, N_POINTS, 2)
#: Percentages of the gait cycle (mid-stance) at which the foot must be on a force plate
#: for the cycle's kinetics to count (a foot that struck no plate still gets small,
#: inertial moments; one that reaches a plate only at the next strike must not count).
STANCE_CHECKS = (20.0, 30.0, 40.0)
#: Vertical ground reaction (% body weight) above which the foot is on a force plate.
MIN_LOAD_PERCENT = 1.0
#: The kinetic output cut over the stance phase instead of the whole cycle.
STANCE_OUTPUT = "NormalisedGRF"
#: The ground reaction's outputs (% body weight, N/kg): cut into the stance the plate measured.
GROUND_OUTPUTS = (STANCE_OUTPUT, "GroundReactionForce")


@dataclass
class NormativeData:
    """Reference mean ± SD curves per angle component.

    Attributes:
        curves: variable (``"KneeAngles_X"`` pooled, or ``"LKneeAngles_X"``) ->
            ``(mean (101,), sd (101,))`` in degrees at 0, 1, ..., 100 % of the cycle.
        cycles: variable -> reference cycles (the largest count over the cycle; 0
            when the file does not say).
        source: where the data come from (file name, or the trials it was built from).
    """

    curves: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    cycles: dict[str, int] = field(default_factory=dict)
    source: str = ""

    def curve(self, component: str) -> tuple[np.ndarray, np.ndarray] | None:
        """``(mean, sd)`` (deg, 101 points) for a sided component such as
        ``"LKneeAngles_X"``: the side's own curve, else the pooled one, else None."""
        if component in self.curves:
            return self.curves[component]
        if component[:1] in "LR" and component[1:] in self.curves:
            return self.curves[component[1:]]
        return None

    def variables(self) -> list[str]:
        """The variables held, in file order."""
        return list(self.curves)

    def table(self) -> pd.DataFrame:
        """The data in the file's long format (:data:`COLUMNS`)."""
        percent = percent_points(N_POINTS)
        parts = [pd.DataFrame({"variable": name, "percent": percent, "mean": mean, "sd": sd,
                               "cycles": self.cycles.get(name, 0)})
                 for name, (mean, sd) in self.curves.items()]  # fmt: skip
        if not parts:
            return pd.DataFrame({c: pd.Series(dtype=float) for c in COLUMNS})
        return pd.concat(parts, ignore_index=True)[list(COLUMNS)]


# ============================================================================ cycles
def normalised_cycles(angles: Mapping[str, np.ndarray], trial: Trial, events: Sequence[Event]) -> dict[str, np.ndarray]:
    """Every angle component of ``angles`` (``{"LKneeAngles": (n_frames, 3) deg}``) cut
    into its side's gait cycles and normalised: ``{"LKneeAngles_X": (n_cycles, 101)}``
    in degrees (NaN rows: cycles with missing data)."""
    out: dict[str, np.ndarray] = {}
    cycles = {side: gait_cycles(trial, events, side) for side in "LR"}
    for name, values in angles.items():
        side = name[:1]
        if side not in cycles:
            continue
        values = np.asarray(values, dtype=float)
        if values.ndim != 2 or values.shape[1] != 3:
            continue
        normalised = normalise_cycles(values, cycles[side], N_POINTS)  # (c, p, 3)
        for k, axis in enumerate("XYZ"):
            out[f"{name}_{axis}"] = normalised[:, :, k]
    return out


def loaded_cycles(cycles: Sequence[GaitCycle], vertical: np.ndarray) -> list[GaitCycle]:
    """The ``cycles`` whose foot stood on a force plate in mid-stance: the side's vertical
    ground reaction ``vertical`` (``(n_frames,)``, % body weight; 0 or NaN off the plates)
    above :data:`MIN_LOAD_PERCENT` at each of :data:`STANCE_CHECKS` % of the cycle
    (nearest frame)."""
    load = np.nan_to_num(np.asarray(vertical, dtype=float))
    kept = []
    for cycle in cycles:
        frames = [int(round(cycle.start + p / 100.0 * (cycle.end - cycle.start))) for p in STANCE_CHECKS]
        if all(0 <= f < load.size and load[f] > MIN_LOAD_PERCENT for f in frames):
            kept.append(cycle)
    return kept


def _stance(cycle: GaitCycle, load: np.ndarray) -> GaitCycle | None:
    """The stance of a counted ``cycle`` as the plate measured it: the run of frames
    around 30 % of the cycle where the vertical ground reaction ``load`` (% BW) exceeds
    :data:`MIN_LOAD_PERCENT` (independent of how well the gait events were placed)."""
    middle = int(round(cycle.start + 0.3 * (cycle.end - cycle.start)))
    on = np.nan_to_num(np.asarray(load, dtype=float)) > MIN_LOAD_PERCENT
    if not on[middle]:
        return None
    first, last = middle, middle
    while first > 0 and on[first - 1]:
        first -= 1
    while last < on.size - 1 and on[last + 1]:
        last += 1
    return GaitCycle(cycle.side, cycle.index, first, last, cycle.rate, cycle.first_frame) if last > first else None


def kinetic_cycles(outputs: Mapping[str, Mapping[str, np.ndarray]],
                   cycles: Mapping[str, Sequence[GaitCycle]]) -> dict[str, np.ndarray]:  # fmt: skip
    """Kinetic components cut into the cycles whose stance was on a force plate.

    Args:
        outputs: side (``"L"``, ``"R"``) -> component without side (``"KneeMoment_X"``
            N·m/kg, ``"KneePower_Z"`` W/kg, ``"NormalisedGRF_Z"`` % body weight ...) ->
            ``(n_frames,)`` at the trial's frames (NaN where not computed).  The side's
            ``NormalisedGRF_Z`` (vertical) decides which of its cycles count
            (:func:`loaded_cycles`); a side without it has none.
        cycles: side -> its gait cycles of the same trial.

    Returns:
        Sided component (``"LKneeMoment_X"``) -> ``(n_cycles, 101)`` in its unit, one row
        per counted cycle with a value on every frame of its span (cycles reaching into
        frames without kinetics, e.g. the first and last four, are left out): moments
        and powers over 0..100 % of the gait cycle, ``NormalisedGRF`` (and
        ``GroundReactionForce``) over 0..100 % of the stance phase as the plate measured
        it (the frames around mid-stance with a vertical ground reaction above
        :data:`MIN_LOAD_PERCENT`).  Components without any such cycle are absent.
    """
    out: dict[str, np.ndarray] = {}
    for side, components in outputs.items():
        vertical = components.get(f"{STANCE_OUTPUT}_Z")
        if vertical is None:
            continue
        kept = loaded_cycles(cycles.get(side, ()), vertical)
        stances = [s for s in (_stance(c, vertical) for c in kept) if s is not None]
        grf = {f"{quantity}_{axis}" for quantity in GROUND_OUTPUTS for axis in "XYZ"}
        for name, values in components.items():
            stack = normalise_cycles(np.asarray(values, dtype=float), stances if name in grf else kept, N_POINTS)
            stack = stack[np.isfinite(stack).all(axis=1)]
            if len(stack):
                out[side + name] = stack
    return out


def mean_curves(cycles: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Mean over cycles of each component of :func:`normalised_cycles` (deg, 101
    points; NaN where no cycle has a value) — the curves the GPS compares."""
    return {name: cycle_statistics(stack)[0] for name, stack in cycles.items()}


def build_normative(trials: Iterable[Mapping[str, np.ndarray]], *, per_side: bool = False,
                    source: str = "") -> NormativeData:  # fmt: skip
    """Normative data from reference trials.

    Args:
        trials: per trial its :func:`normalised_cycles` (component -> ``(n_cycles, 101)``
            deg).
        per_side: keep left and right apart (``LKneeAngles_X``, ...); default: pool the
            cycles of both sides per component (``KneeAngles_X``).
        source: what the data were built from (kept in :attr:`NormativeData.source`).

    Returns:
        Mean and sample SD (ddof = 1; 0 with a single cycle) over every cycle of every
        trial per component and percentage; components without any valid cycle are
        left out.
    """
    stacks: dict[str, list[np.ndarray]] = {}
    for cycles in trials:
        for name, stack in cycles.items():
            key = name if per_side else name[1:]
            stacks.setdefault(key, []).append(np.asarray(stack, dtype=float).reshape(-1, N_POINTS))
    data = NormativeData(source=source)
    for key, parts in stacks.items():
        stack = np.concatenate(parts, axis=0)
        mean, sd = cycle_statistics(stack)
        count = np.isfinite(stack).sum(axis=0)
        if not np.isfinite(mean).all():  # a cycle is all NaN or all finite: no valid cycle
            continue
        sd = np.where(np.isfinite(mean) & (count == 1), 0.0, sd)
        data.curves[key] = (mean, sd)
        data.cycles[key] = int(count.max())
    return data


# ============================================================================ file
def write_normative(data: NormativeData, path: str | os.PathLike[str]) -> Path:
    """Write ``data`` as a normative CSV (format in the module docstring), atomically
    (a temporary file renamed into place); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        data.table().to_csv(temporary, index=False, float_format="%.17g")
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)
    return path


def _fail(path: Path, why: str) -> FuzzyGaitError:
    return FuzzyGaitError(f"{path}: {why} (the format: docs/reports.md, 'Normative data')")


def read_normative(path: str | os.PathLike[str]) -> NormativeData:
    """Read a normative CSV (format in the module docstring).

    Raises:
        FuzzyGaitError: one line naming the file and what is wrong (missing file or
            columns, non-numbers, percentages outside 0..100 or not covering both ends,
            a negative SD, duplicate rows).
    """
    path = Path(path)
    try:
        table = pd.read_csv(path)
    except FileNotFoundError:
        raise FuzzyGaitError(f"{path}: no such normative file") from None
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise _fail(path, f"not a readable CSV file ({str(exc).splitlines()[0] if str(exc) else exc})") from None
    missing = [c for c in COLUMNS[:4] if c not in table.columns]
    if missing:
        raise _fail(path, f"missing column(s) {', '.join(missing)}; found {', '.join(map(str, table.columns))}")
    if table.empty:
        raise _fail(path, "no rows")
    numbers = {}
    for column in ("percent", "mean", "sd") + (("cycles",) if "cycles" in table.columns else ()):
        values = pd.to_numeric(table[column], errors="coerce")
        if values.isna().any():
            row = int(np.flatnonzero(values.isna().to_numpy())[0]) + 2
            raise _fail(path, f"line {row}: {column} is not a number ({table[column].iloc[row - 2]!r})")
        numbers[column] = values.to_numpy(dtype=float)
    if (numbers["sd"] < 0).any() or not np.isfinite(numbers["mean"]).all():
        raise _fail(path, "sd must be >= 0 and mean finite (in the variable's unit)")
    data = NormativeData(source=path.name)
    grid = percent_points(N_POINTS)
    variables = table["variable"].astype(str).str.strip().to_numpy()
    for name in dict.fromkeys(variables):
        rows = variables == name
        percent = numbers["percent"][rows]
        order = np.argsort(percent, kind="stable")
        percent = percent[order]
        if np.any(np.diff(percent) == 0):
            raise _fail(path, f"{name}: a percentage appears twice")
        if percent[0] != 0 or percent[-1] != 100:
            raise _fail(path, f"{name}: the percentages must run from 0 to 100; found "
                              f"{percent[0]:g} to {percent[-1]:g}")  # fmt: skip
        mean, sd = numbers["mean"][rows][order], numbers["sd"][rows][order]
        if percent.size != N_POINTS or not np.array_equal(percent, grid):
            mean, sd = np.interp(grid, percent, mean), np.interp(grid, percent, sd)
        data.curves[name] = (mean, sd)
        data.cycles[name] = int(numbers["cycles"][rows].max()) if "cycles" in numbers else 0
    return data


# ============================================================================ GPS / MAP
@dataclass(frozen=True)
class GaitProfile:
    """Baker et al.'s scores of one trial against normative data (degrees).

    Attributes:
        gvs: side -> variable name (:data:`GPS_VARIABLES`) -> GVS (NaN: not available).
        gps: side -> that side's GPS (RMS of its nine GVS).
        overall: RMS of the left nine and the right six non-pelvic GVS.
        normative: :attr:`NormativeData.source`.
    """

    gvs: dict[str, dict[str, float]]
    gps: dict[str, float]
    overall: float
    normative: str = ""

    def table(self) -> pd.DataFrame:
        """The Movement Analysis Profile: one row per variable (and ``GPS``), columns
        ``L`` and ``R`` (deg)."""
        names = [name for _, _, name in GPS_VARIABLES]
        frame = pd.DataFrame({side: [self.gvs[side][n] for n in names] for side in "LR"}, index=names)
        frame.loc["GPS"] = [self.gps["L"], self.gps["R"]]
        return frame


def gait_variable_score(curve: np.ndarray, reference: np.ndarray) -> float:
    """GVS (deg): RMS of ``curve - reference`` (both 101 points, deg) every 2 % of the
    cycle; NaN when either is missing at one of those points."""
    diff = np.asarray(curve, dtype=float)[GVS_POINTS] - np.asarray(reference, dtype=float)[GVS_POINTS]
    return float(np.sqrt(np.mean(diff**2))) if np.isfinite(diff).all() else math.nan


def _rms(values: Sequence[float]) -> float:
    return float(np.sqrt(np.mean(np.square(values)))) if values else math.nan


def gait_profile(curves: Mapping[str, np.ndarray], normative: NormativeData) -> GaitProfile:
    """GVS per variable and side, GPS per side and overall (see the module docstring).

    Args:
        curves: sided component -> the trial's mean curve over its cycles (deg, 101
            points; :func:`mean_curves`).
        normative: the reference curves.
    """
    gvs: dict[str, dict[str, float]] = {}
    for side in "LR":
        scores = {}
        for base, axis, name in GPS_VARIABLES:
            component = f"{side}{base}_{axis}"
            ref = normative.curve(component)
            curve = curves.get(component)
            scores[name] = math.nan if ref is None or curve is None else gait_variable_score(curve, ref[0])
        gvs[side] = scores
    gps = {side: _rms(list(scores.values())) for side, scores in gvs.items()}
    pelvic = {name for base, _, name in GPS_VARIABLES if base == "PelvisAngles"}
    fifteen = list(gvs["L"].values()) + [v for n, v in gvs["R"].items() if n not in pelvic]
    return GaitProfile(gvs, gps, _rms(fifteen), normative.source)
