"""Fuzzy joint moments and powers: the marker-error balls of Table 3.1 and a
centre-of-pressure error ball on each loaded plate through Plug-in Gait's inverse
dynamics with the Graph Follower algorithm (issue 39 item 5).

Each leg is one :class:`~fuzzygait.markererror.moment_model.LegKineticsModel` whose
components (``LAnkleMoment_X`` … ``LHipMoment_Z``, or the powers ``LAnklePower_Z`` …)
are optimised side by side in direct mode
(:class:`~fuzzygait.uncertainty.BatchedDirect`): every model call serves all of them.

Result layout: that of the fuzzy joint angles
(:func:`~fuzzygait.markererror.result.fuzzy_angles_dataset`, the ``dataset.fuzzy``
schema) with the kinetic units:

* ``hull (component, alpha, bound, frame)`` in N·m/kg (moments) or W/kg (powers),
  components ``LKneeMoment_X`` … (coordinates ``angle`` — the output, ``LKneeMoment`` —
  ``axis`` and ``label``); NaN on frames where the kinetics are not defined (the first
  and last four, a marker missing in the nine frames around, no ground load);
* ``deviation (component, alpha, bound, frame, marker)``: the norm (mm) of each ball's
  deviation at the bound, the ``marker`` dimension holding the markers and ``COP<n>``
  per plate (its deviation in the plate's plane);
* ``ball_radius (marker)``: α = 0 radii (mm): Σ of Table 3.1, ``cop_error_mm`` for the
  plates; coordinate ``cop (marker)``: True for the centre-of-pressure balls;
* ``undetermined (component, alpha, frame)``: at a bound's deviation a segment frame the
  leg's kinetics use (pelvis, thigh, tibia, foot, over the nine frames) is turned more
  than 90° from the measured one — it can flip inside the ball, the band is no band
  (the angles' rule, :data:`~fuzzygait.markererror.undetermined.UNDETERMINED_DEG`);
* attributes as the angles' (``trial``, ``sources``, ``strategy``, counts, ``seconds``),
  ``output`` ``"joint moment"``/``"joint power"``, ``units``, ``cop_error_mm``.

ΔΦ (Eq. 5.3) is ``dataset.fuzzy.delta_phi()``; :func:`allowable_kinetic_error` answers
the inverse question on the dataset's α-levels.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import AngleComponent, Side
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics import CGMResult
from fuzzygait.kinetics.assignment import PlateContact, assigned_ground
from fuzzygait.kinetics.plug_in_gait import JOINTS
from fuzzygait.markererror.analysis import SearchOptions
from fuzzygait.markererror.moment_model import (
    DEFAULT_COP_ERROR_MM,
    HALF_WINDOW,
    KINDS,
    LegKineticsModel,
    PlateShare,
    plate_shares,
)
from fuzzygait.markererror.result import AngleAxes, fuzzy_angles_dataset, with_error_sources
from fuzzygait.markererror.sources import parse_sources
from fuzzygait.markererror.undetermined import UNDETERMINED_DEG
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, graph_follower

Array = NDArray[np.float64]
DEFAULT_ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: Default tolerance of :func:`allowable_kinetic_error`, N·m/kg.
DEFAULT_TOLERANCE = 0.1


@dataclass(frozen=True)
class FootGround:
    """The ground's load on one foot and the plates it came from.

    Attributes:
        force: ``(n_frames, 3)`` N, laboratory frame, at the trial's frames (zero off the
            plates).
        moment: ``(n_frames, 3)`` N·m about the laboratory origin.
        plates: each loaded plate's share (:class:`~fuzzygait.markererror.moment_model.PlateShare`).
    """

    force: Array
    moment: Array
    plates: tuple[PlateShare, ...] = ()


def foot_ground(plates: Sequence[object], plate: NDArray[np.int_], rate: float) -> FootGround:
    """The load of the foot whose plate on each frame is ``plate`` (``(n,)`` 1-based
    numbers, 0: off the plates; :func:`~fuzzygait.kinetics.assignment.assigned_ground`)
    from ``plates`` read at the analog rate; ``rate``: the marker rate, Hz."""
    load = assigned_ground(plates, np.asarray(plate), rate)  # type: ignore[arg-type]
    return FootGround(load.force, load.moment, plate_shares(plates, np.asarray(plate), rate))


def contacts_ground(plates: Sequence[object], contacts: Sequence[PlateContact], side: Side, n_frames: int,
                    rate: float) -> FootGround:  # fmt: skip
    """:func:`foot_ground` of the ``side`` foot from the automatic assignment's ``contacts``
    (as :func:`~fuzzygait.kinetics.assignment.contact_ground`)."""
    plate = np.zeros(n_frames, dtype=int)
    for c in contacts:
        if c.side is side:
            plate[c.first : c.last + 1] = c.plate
    return foot_ground(plates, plate, rate)


@dataclass(frozen=True)
class FuzzyKineticsOptions(SearchOptions):
    """Options of the fuzzy kinetics: the search of the fuzzy angles
    (:class:`~fuzzygait.markererror.analysis.SearchOptions`: α-levels, marker error
    sources and model, the batched Graph Follower's settings) and

    Attributes:
        cop_error_mm: the centre-of-pressure error ball's radius at α = 0, mm, in the
            plate's plane (:data:`~fuzzygait.markererror.moment_model.DEFAULT_COP_ERROR_MM`).
        kind: ``"Moment"`` (N·m/kg) or ``"Power"`` (W/kg).
    """

    cop_error_mm: float = DEFAULT_COP_ERROR_MM
    kind: str = "Moment"


def requested_components(names: Sequence[str] | None, kind: str) -> dict[Side, list[tuple[str, int]]]:
    """Per side the ``(joint, axis)`` pairs of ``names`` — outputs (``"LKneeMoment"``: X,
    Y, Z; powers Z) or components (``"LKneeMoment_X"``); None: every joint of both legs.

    Raises:
        ParameterError: a name that is no ``kind`` output of a leg joint.
    """
    axes = (0, 1, 2) if kind == "Moment" else (2,)
    wanted = names or [f"{s.value}{j}{kind}" for s in Side for j in JOINTS]
    out: dict[Side, list[tuple[str, int]]] = {}
    for name in wanted:
        component = AngleComponent.maybe(name)
        output, picked = (component.angle, (component.axis.column,)) if component else (str(name), axes)
        side, joint = output[:1], output[1:].removesuffix(kind)
        if side not in ("L", "R") or joint not in JOINTS or not output.endswith(kind) or set(picked) - set(axes):
            raise ParameterError(f"{name!r} is not a {kind.lower()} output of a leg joint (e.g. L{joint or 'Knee'}"
                                 f"{kind}{'_X' if kind == 'Moment' else '_Z'})")  # fmt: skip
        pairs = out.setdefault(Side(side), [])
        pairs += [(joint, a) for a in picked if (joint, a) not in pairs]
    return out


def leg_model(trial: Trial, subject: SubjectParameters, side: Side, components: Sequence[tuple[str, int]],
              ground: FootGround, kind: str, model: str, frames: NDArray[np.int_] | None = None) -> LegKineticsModel:
    """The side's model on the frames where its kinetics are defined at zero deviation
    (of ``frames``, 0-based, if given)."""  # fmt: skip
    inside = np.arange(HALF_WINDOW, trial.n_frames - HALF_WINDOW)
    if frames is not None:
        inside = np.intersect1d(inside, np.asarray(frames, dtype=int))
    if inside.size == 0:
        raise ParameterError(f"{trial.name}: no frame {HALF_WINDOW} frames inside the trial to compute kinetics on")
    probe = LegKineticsModel(trial, subject, side, tuple(components), inside, ground.force, ground.moment,
                             ground.plates, kind=kind, model=model)  # fmt: skip
    values = np.asarray(probe.outputs(np.zeros((inside.size, probe.n_parameters)), inside), dtype=float)
    usable = inside[np.all(np.isfinite(values), axis=(1, 2))]
    if usable.size == 0:
        raise ParameterError(f"{trial.name}: the {side.word.lower()} leg's kinetics are defined on no frame")
    return LegKineticsModel(trial, subject, side, tuple(components), usable, ground.force, ground.moment,
                            ground.plates, kind=kind, model=model)  # fmt: skip


@dataclass
class _LegRun:
    """One leg's Graph Follower run: its model, ball names and radii, the hull
    ``(alpha, bound, nodes)``, ball deviation norms ``(alpha, bound, nodes, balls)``,
    the undetermined flags ``(alpha, nodes)`` and the work counts."""

    model: LegKineticsModel
    balls: list[str]
    radii: Array
    hull: Array
    norms: Array
    flags: NDArray[np.bool_]
    counts: dict[str, int]


def run_leg(model: LegKineticsModel, radii: Array, options: FuzzyKineticsOptions, alphas: Array) -> _LegRun:
    """The α-level optimisation of every component of ``model`` (balls of α = 0 radii
    ``radii`` mm, one per :attr:`~LegKineticsModel.ball_names`)."""
    balls = model.ball_names
    params = FuzzyBalls(np.zeros((len(balls), 3)), radii, tuple(balls))
    result = graph_follower(model, params, tuple(alphas), strategy=options.strategy())
    hull = result["hull"].to_numpy()
    extremiser = result["extremiser"].to_numpy()  # (alpha, bound, nodes, n_p)
    coordinates = extremiser.reshape(*hull.shape, len(balls), 3).copy()
    coordinates[..., len(model.markers) :, 2] = 0.0  # a COP's normal coordinate moves nothing: the in-plane norm
    norms = np.linalg.norm(coordinates, axis=-1)
    frames = np.tile(model.frames, model.blocks)
    turn = np.stack([[model.frame_turn(extremiser[a, b], frames) for b in range(2)] for a in range(alphas.size)])
    flags = np.any(turn > UNDETERMINED_DEG, axis=1)
    counts = {key: int(result.attrs[key]) for key in ("forward_simulations", "node_evaluations", "node_gradients")}
    return _LegRun(model, balls, np.asarray(radii, dtype=float), hull, norms, flags, counts)


def fuzzy_joint_moments(trial: Trial, subject: SubjectParameters, result: CGMResult, ground: Mapping[Side, FootGround],
                        options: FuzzyKineticsOptions = FuzzyKineticsOptions(), outputs: Sequence[str] | None = None,
                        frames: NDArray[np.int_] | None = None) -> xr.Dataset:  # fmt: skip
    """Fuzzy joint moments (or powers, ``options.kind``) of a trial (layout in the module
    docstring).

    Args:
        trial: the pre-processed trial ``result`` was computed from.
        subject: its subject parameters (body mass, static offsets).
        result: :func:`~fuzzygait.kinematics.compute_lower_body` of ``trial`` (its model
            version).
        ground: per side the ground's load on that foot (:func:`foot_ground`,
            :func:`contacts_ground`); a side absent here is never on a plate.
        options: α-levels, error sources and radii, the centre-of-pressure error.
        outputs: ``"LKneeMoment"`` (X, Y, Z) or ``"LKneeMoment_X"`` …; None: every joint
            of both legs.
        frames: 0-based trial frames to compute (default: every frame where defined).

    Raises:
        ParameterError: an unknown kind or output, a cluster model, a leg without its
            markers, a non-positive body mass or COP radius.
    """
    if options.kind not in KINDS:
        raise ParameterError(f"kind must be one of {', '.join(KINDS)}; got {options.kind!r}")
    if not np.isfinite(options.cop_error_mm) or options.cop_error_mm < 0:
        raise ParameterError(f"the centre-of-pressure error must be a distance >= 0 mm; got {options.cop_error_mm}")
    if not np.isfinite(subject.body_mass) or subject.body_mass <= 0:
        raise ParameterError(f"body mass must be positive (kg) for kinetics; got {subject.body_mass}")
    sources = parse_sources(options.sources)
    alphas = np.union1d(np.asarray(options.alphas, dtype=float), [1.0])
    start = time.perf_counter()
    runs = []
    for side, components in requested_components(outputs, options.kind).items():
        none = FootGround(np.zeros((trial.n_frames, 3)), np.zeros((trial.n_frames, 3)))
        model = leg_model(trial, subject, side, components, ground.get(side, none), options.kind, result.model, frames)
        radii = np.array([options.error_model.radius(m, sources) for m in model.markers]
                         + [options.cop_error_mm] * len(model.plates))  # fmt: skip
        runs.append(run_leg(model, radii, options, alphas))
    attrs = {"trial": trial.name, "model": result.model, "method": "cartesian",
             "starts": options.starts, "output": f"joint {options.kind.lower()}", "strategy": BatchedDirect.name,
             "cop_error_mm": float(options.cop_error_mm), "seconds": round(time.perf_counter() - start, 3)}  # fmt: skip
    return with_error_sources(_assemble(trial, runs, alphas, KINDS[options.kind], attrs), sources)


def kinetic_label(side: Side, joint: str, axis: int, kind: str) -> str:
    """``(Side.LEFT, "Knee", 0, "Moment")`` -> ``"Left knee moment, sagittal (+ extensor)"``
    (the signs of :data:`~fuzzygait.kinetics.plug_in_gait.MOMENT_AXES`)."""
    if kind == "Power":
        return f"{side.word} {joint.lower()} power (+ generation)"
    plane = ("sagittal", "frontal", "transverse")[axis]
    positive = {"Ankle": "plantarflexor", "Knee": "extensor", "Hip": "extensor"}[joint] if axis == 0 else ""
    return f"{side.word} {joint.lower()} moment, {plane}" + (f" (+ {positive})" if positive else "")


def _assemble(trial: Trial, runs: list[_LegRun], alphas: Array, units: str, attrs: dict[str, object]) -> xr.Dataset:
    """The runs' hulls, deviations and flags on the trial's frames, in the angles' layout."""
    balls: list[str] = []
    radius: dict[str, float] = {}
    cop: dict[str, bool] = {}
    for run in runs:
        for k, (name, r) in enumerate(zip(run.balls, run.radii, strict=True)):
            if name not in radius:
                balls.append(name)
                radius[name] = float(r)
                cop[name] = k >= len(run.model.markers)
    hulls, deviations, flags, labels = {}, {}, {}, []
    totals = dict.fromkeys(("forward_simulations", "node_evaluations", "node_gradients"), 0)
    n = trial.n_frames
    for run in runs:
        frames, k = run.model.frames, run.model.frames.size
        columns = np.asarray([balls.index(b) for b in run.balls])
        labels += [kinetic_label(run.model.side, j, a, run.model.kind) for j, a in run.model.components]
        for b, component in enumerate(run.model.component_labels()):
            nodes = slice(b * k, (b + 1) * k)
            hulls[component] = np.full((alphas.size, 2, n), np.nan)
            hulls[component][:, :, frames] = run.hull[..., nodes]
            deviations[component] = np.full((alphas.size, 2, n, len(balls)), np.nan)
            deviations[component][:, :, frames[:, None], columns[None, :]] = run.norms[:, :, nodes]
            flags[component] = np.zeros((alphas.size, n), dtype=bool)
            flags[component][:, frames] = run.flags[:, nodes]
        for key in totals:
            totals[key] += run.counts[key]
    axes = AngleAxes(alphas=alphas, frames=trial.frames, times=trial.times, markers=balls,
                     ball_radius=[radius[b] for b in balls])  # fmt: skip
    ds = fuzzy_angles_dataset(hulls, axes, deviations=deviations, attrs={**attrs, **totals}, undetermined=flags)
    ds = ds.assign_coords(label=("component", labels), cop=("marker", [cop[b] for b in balls]))
    ds["hull"].attrs.update(units=units, long_name=f"{attrs['output']} bounds of the α-level")
    ds["undetermined"].attrs["long_name"] = "band undetermined: a segment frame turns more than 90 deg in the ball"
    ds["ball_radius"].attrs["long_name"] = "marker and centre-of-pressure error ball radius at α = 0"
    ds.attrs["units"] = units
    return ds


@dataclass(frozen=True)
class AllowableKinetics:
    """The allowable-error answer of one component on a dataset's α-levels.

    Attributes:
        component: ``"LKneeMoment_X"``.
        tolerance: in the dataset's units, either side of the measured value.
        scale: the largest error scale ``1 − α`` evaluated whose band stays within the
            tolerance on every frame (0: none but α = 1); the allowable scale lies between
            it and ``failing`` (the next scale evaluated, NaN when α = 0 passes).
        marker_mm: the largest marker ball at that scale (mm); ``cop_mm``: the COP ball.
        sentence: the answer in words.
    """

    component: str
    tolerance: float
    scale: float
    failing: float
    marker_mm: float
    cop_mm: float
    sentence: str


def allowable_kinetic_error(fuzzy: xr.Dataset, component: str,
                            tolerance: float = DEFAULT_TOLERANCE) -> AllowableKinetics:  # fmt: skip
    """How small the errors must be for ``component`` to be known within ``tolerance``
    (the dataset's units, N·m/kg for moments): the largest scale of Table 3.1's balls and
    of the COP ball, among the dataset's α-levels, at which the band stays within the
    tolerance of the measured value on every frame and is determined there (the angles'
    excursion, :func:`fuzzygait.markererror.allowable.band_excursion`).  The bands are
    nested, so the true allowable scale lies between ``scale`` and ``failing``."""
    from fuzzygait.markererror.allowable import band_excursion

    excursion = band_excursion(fuzzy, component)
    scales = 1.0 - excursion.index.to_numpy(dtype=float)
    passing = excursion.to_numpy() <= tolerance
    order = np.argsort(scales)
    scale, failing = 0.0, float("nan")
    for i in order:
        if passing[i]:
            scale = float(scales[i])
        else:
            failing = float(scales[i])
            break
    balls = [str(b) for b in fuzzy["marker"].to_numpy()]
    deviation = fuzzy["deviation"].sel(component=component) if "deviation" in fuzzy.data_vars else None
    used = [b for b in balls if deviation is None or bool(np.isfinite(deviation.sel(marker=b)).any())]
    radius = {b: float(fuzzy["ball_radius"].sel(marker=b)) for b in used}
    is_cop = {str(b): bool(c) for b, c in zip(balls, fuzzy["cop"].to_numpy(), strict=True)}
    marker = scale * max([r for b, r in radius.items() if not is_cop[b]] + [0.0])
    cop = scale * max([r for b, r in radius.items() if is_cop[b]] + [0.0])
    units = str(fuzzy.attrs.get("units", ""))
    label = str(fuzzy["label"].sel(component=component).item()) if "label" in fuzzy.coords else component
    if np.isnan(failing):
        text = (f"{label}: known within ±{tolerance:g} {units} even with the full errors (markers {marker:.0f} mm, "
                f"COP {cop:.0f} mm).")  # fmt: skip
    elif scale == 0.0:
        text = (f"{label}: not known within ±{tolerance:g} {units} even at the smallest errors evaluated "
                f"({100 * failing:.0f} % of the full balls).")  # fmt: skip
    else:
        text = (f"{label}: known within ±{tolerance:g} {units} if every marker stays within {marker:.1f} mm and the "
                f"centre of pressure within {cop:.1f} mm ({100 * scale:.0f} % of the full balls; "
                f"{100 * failing:.0f} % fails).")  # fmt: skip
    return AllowableKinetics(component, tolerance, scale, failing, marker, cop, text)


__all__ = ["AllowableKinetics", "FootGround", "FuzzyKineticsOptions", "allowable_kinetic_error",
           "contacts_ground", "foot_ground", "fuzzy_joint_moments", "requested_components"]  # fmt: skip
