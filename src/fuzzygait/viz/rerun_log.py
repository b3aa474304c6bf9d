"""Rerun recordings (``.rrd``) of a gait trial: markers, model, joint angles and, with
force plates, the kinetics (:mod:`fuzzygait.viz.rerun_kinetics`: ground reaction arrows
at the centres of pressure, ``world/force_plates/...``; moments and powers,
``kinetics/...``; a "Kinetics" tab).

:func:`log_trial` logs one trial, its Plug-in Gait model result and optionally the fuzzy
joint-angle envelopes into a Rerun recording stream, :func:`trial_blueprint` is the
viewer's layout (a grid of joint-angle plots); this module writes no file:
:func:`fuzzygait.workflows.rerun_recordings.write_recording` writes the ``.rrd`` that
opens in the Rerun viewer (``rerun trial.rrd``), through
:func:`fuzzygait.io.rerun_files.recording_file`.  It needs the optional ``rerun-sdk``
package (written against rerun-sdk 0.41).

Units and frames: positions in **millimetres** in the **laboratory frame** of the C3D
file (Rerun's 3D view works in mm; ``world`` carries
``ViewCoordinates.RIGHT_HAND_Z_UP``), angles in **degrees**.

Timelines: every time-varying row carries ``frame`` (sequence: the 1-based C3D frame
number, :attr:`Trial.frames <fuzzygait.io.Trial.frames>`) and ``time`` (duration: seconds
on the C3D clock, :attr:`Trial.times <fuzzygait.io.Trial.times>`).  Styling (colours,
radii, series names) is logged as static data.

Entity layout::

    world                                   ViewCoordinates RIGHT_HAND_Z_UP (static)
    world/markers                           Points3D, one row per frame, labelled with the
                                            marker names; missing (NaN) markers are left
                                            out of that frame's row
    world/marker_balls                      (with ``fuzzy``) Ellipsoids3D centred on the
                                            markers, half sizes = the alpha = 0 ball radius
                                            of each marker (``ball_radius``), semi-
                                            transparent solid fill
    world/joint_centres                     Points3D of LHJC, LKJC, LAJC, RHJC, ... labelled
    world/segments/<segment>                Arrows3D: the segment's x (red), y (green) and z
                                            (blue) axes, 100 mm long, from the segment
                                            origin (pelvis: LASI/RASI midpoint, else the HJC
                                            midpoint; thigh: KJC; tibia, torsioned tibia and
                                            foot: AJC); an empty row where the frame is NaN
    angles/<Angle>/<X|Y|Z>/deterministic    Scalars: the computed angle (e.g.
                                            ``angles/LKneeAngles/X/deterministic``), NaN kept
    angles/<Angle>/<X|Y|Z>/alpha_<a>/upper  (with ``fuzzy``) Scalars: upper and lower bound
    angles/<Angle>/<X|Y|Z>/alpha_<a>/lower  of the alpha-cut ``a`` (``alpha_0``,
                                            ``alpha_0.5``, ...; formatted with ``:g``)
                                            for each shown alpha < 1, on the fuzzy
                                            result's own frames; NaN (a gap in the
                                            line) where the band is undetermined
    angles/<Angle>/<X|Y|Z>/alpha_<a>/undetermined
                                            (only when there are some) Scalars drawn as
                                            points (SeriesPoints, crosses in the side's
                                            dark colour) at the measured angle, on the
                                            frames where the alpha-cut is undetermined
                                            (the segment frame can flip: the bounds mean
                                            nothing there)

Series colours follow the gait-report convention (left red, right green); the envelope
lines of an alpha-cut use the side's colour lightened the more the lower the alpha, the
undetermined markers the side's colour darkened.

Blueprint (stored in the file as the default blueprint of the application id, so the
viewer opens on it): tab "Joint angles" (active) = a 5 x 3 grid of time-series plots,
rows Pelvis, Hip, Knee, Ankle, Foot progression and columns sagittal (X), frontal (Y),
transverse (Z), each showing left and right with their envelopes; tab "3D" = a 3D view
of ``world``.  The time panel starts on the ``frame`` timeline.

The recording is written through a dedicated :class:`rerun.RecordingStream` (never the
global one) with a file sink only (:mod:`fuzzygait.io.rerun_files`): no viewer is
spawned and no network is used.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import AngleComponent
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.model import CGMResult
from fuzzygait.markererror.result import angle_components, ball_radius, component_hull, component_undetermined

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "AXIS_LENGTH_MM",
    "check_recording",
    "log_trial",
    "trial_blueprint",
]

from fuzzygait.viz.layout import ANGLE_ROWS, PLANES  # noqa: E402
from fuzzygait.viz.rerun_kinetics import kinetics_views, log_kinetics  # noqa: E402

#: Length of the drawn segment axes, mm.
AXIS_LENGTH_MM = 100.0

_SIDES = {"L": ("Left", (214, 39, 40)), "R": ("Right", (44, 160, 44))}
_AXIS_COLOURS = [(230, 50, 50), (40, 190, 60), (50, 110, 240)]  # x, y, z
_MARKER_COLOUR = (210, 210, 210)
_MARKER_RADIUS_MM = 7.0
_JOINT_COLOUR = (255, 165, 0)
_JOINT_RADIUS_MM = 11.0
_BALL_COLOUR = (90, 160, 255, 70)  # RGBA; alpha is honoured by solid ellipsoids
_ARROW_RADIUS_MM = 3.0
_DETERMINISTIC_WIDTH = 2.5
_ENVELOPE_WIDTH = 1.0
_UNDETERMINED_MARKER = "cross"
_UNDETERMINED_SIZE = 3.0


# ----------------------------------------------------------------------------- inputs
def _segment_origin(name: str, trial: Trial, result: CGMResult) -> np.ndarray | None:
    """``(n_frames, 3)`` origin of segment ``name`` in mm, or None when unknown."""
    jc = result.joint_centres
    if name == "pelvis":
        if trial.has_marker("LASI") and trial.has_marker("RASI"):
            return 0.5 * (trial.marker("LASI") + trial.marker("RASI"))
        if "LHJC" in jc and "RHJC" in jc:
            return 0.5 * (jc["LHJC"] + jc["RHJC"])
        return None
    side = {"left": "L", "right": "R"}.get(name.split("_", 1)[0])
    if side is None:
        return None
    if name.endswith("_thigh"):
        return jc.get(side + "KJC")
    if name.endswith(("_tibia", "_tibia_torsioned", "_foot")):
        return jc.get(side + "AJC")
    return None


def _alpha_label(alpha: float) -> str:
    return f"{alpha:g}"


def _fuzzy_parts(
    fuzzy: xr.Dataset, trial: Trial, alphas_to_show: Iterable[float] | None
) -> tuple[list[float], list[str], np.ndarray, np.ndarray]:
    """Checked alpha levels to show, angle variables, frames and times of ``fuzzy``."""
    name = fuzzy.attrs.get("trial", "fuzzy result")
    for dim in ("alpha", "bound", "frame"):
        if dim not in fuzzy.dims:
            raise ParameterError(f"{name}: the fuzzy result has no {dim!r} dimension")
    bounds = [str(b) for b in fuzzy["bound"].values]
    if not {"lower", "upper"} <= set(bounds):
        raise ParameterError(f"{name}: bound must hold 'lower' and 'upper'; got {bounds}")
    levels = [float(a) for a in fuzzy["alpha"].values]
    below_one = [a for a in levels if a < 1.0 - 1e-12]
    if alphas_to_show is None:
        alphas = below_one
    else:
        alphas = []
        for wanted in alphas_to_show:
            wanted = float(wanted)
            if wanted >= 1.0 - 1e-12:
                continue  # alpha = 1 is the deterministic series, logged anyway
            match = [a for a in below_one if abs(a - wanted) <= 1e-9]
            if not match:
                raise ParameterError(
                    f"{name}: alphas_to_show holds {wanted:g}, which is not an alpha level of the "
                    f"fuzzy result (have {', '.join(_alpha_label(a) for a in levels)})"
                )
            if match[0] not in alphas:
                alphas.append(match[0])
        alphas.sort()
    variables = angle_components(fuzzy)
    frames = np.asarray(fuzzy["frame"].values, dtype=np.int64)
    if "time" in fuzzy.coords:
        times = np.asarray(fuzzy["time"].values, dtype=float)
    else:
        times = (frames - 1) / trial.rate
    return alphas, variables, frames, times


def _check_shapes(trial: Trial, result: CGMResult) -> None:
    n = trial.n_frames
    tables = {**result.angles, **result.joint_centres}
    for key, values in tables.items():
        if np.shape(values) != (n, 3):
            raise ParameterError(
                f"{trial.name}: model output {key!r} has shape {np.shape(values)}; expected ({n}, 3) "
                "(was the model run on this trial?)"
            )
    for key, frames in result.segment_frames.items():
        if np.shape(frames) != (n, 3, 3):
            raise ParameterError(
                f"{trial.name}: segment frame {key!r} has shape {np.shape(frames)}; expected ({n}, 3, 3)"
            )


# ----------------------------------------------------------------------------- styling
def _lighten(colour: tuple[int, int, int], amount: float) -> tuple[int, int, int]:
    """``colour`` blended towards white by ``amount`` in [0, 1]."""
    return tuple(int(round(c + (255 - c) * amount)) for c in colour)  # type: ignore[return-value]


def _envelope_colour(side_colour: tuple[int, int, int], alpha: float) -> tuple[int, int, int]:
    return _lighten(side_colour, 0.2 + 0.55 * (1.0 - alpha))


def _darken(colour: tuple[int, int, int], amount: float) -> tuple[int, int, int]:
    """``colour`` blended towards black by ``amount`` in [0, 1]."""
    return tuple(int(round(c * (1.0 - amount))) for c in colour)  # type: ignore[return-value]


# ----------------------------------------------------------------------------- logging
def _log_points(rec: Any, rr: Any, entity: str, indexes: list[Any], positions: np.ndarray,
                labels: list[str], radius: float, colour: tuple[int, int, int]) -> None:  # fmt: skip
    """Labelled points ``(n_frames, n_points, 3)`` (mm) with a static style; NaN points
    are left out of their frame."""
    valid = np.all(np.isfinite(positions), axis=2)
    names = np.broadcast_to(np.array(labels, dtype=object), valid.shape)
    rec.log(entity, rr.Points3D.from_fields(radii=[radius], colors=[colour]), static=True, strict=True)
    _send_instances(rec, entity, indexes, rr.Points3D.columns, {"positions": positions, "labels": names}, valid)


def _send_instances(
    rec: Any,
    entity: str,
    indexes: list[Any],
    columns_of: Any,
    fields: dict[str, np.ndarray],
    valid: np.ndarray,
) -> None:
    """Send a per-frame batch of instances: ``fields[k]`` is ``(n_frames, n_inst, ...)``
    and only the instances where ``valid`` ``(n_frames, n_inst)`` holds are kept."""
    lengths = valid.sum(axis=1)
    flat = {}
    for key, values in fields.items():
        kept = values[valid]
        flat[key] = kept.tolist() if kept.dtype == object else kept
    columns = columns_of(**flat).partition(lengths)
    rec.send_columns(entity, indexes=indexes, columns=columns, strict=True)


def _log_world(
    rec: Any, rr: Any, trial: Trial, result: CGMResult, fuzzy: xr.Dataset | None, indexes: list[Any]
) -> None:
    n = trial.n_frames
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True, strict=True)

    markers = trial.markers
    valid = np.all(np.isfinite(markers), axis=2)
    _log_points(rec, rr, "world/markers", indexes, markers, trial.marker_labels, _MARKER_RADIUS_MM, _MARKER_COLOUR)

    balls = ball_radius(fuzzy) if fuzzy is not None else None
    if balls is not None:
        radius_of = {str(label): float(r) for label, r in zip(balls["marker"].values, balls.values, strict=True)}
        radii = np.array([radius_of.get(label, np.nan) for label in trial.marker_labels])
        has_ball = np.isfinite(radii) & (radii > 0)
        if has_ball.any():
            rec.log(
                "world/marker_balls",
                rr.Ellipsoids3D.from_fields(colors=[_BALL_COLOUR], fill_mode=rr.components.FillMode.Solid),
                static=True,
                strict=True,
            )
            half_sizes = np.broadcast_to(np.repeat(radii[:, None], 3, axis=1), markers.shape)
            _send_instances(
                rec, "world/marker_balls", indexes, rr.Ellipsoids3D.columns,
                {"centers": markers, "half_sizes": half_sizes}, valid & has_ball[None, :],
            )  # fmt: skip

    if result.joint_centres:
        names = list(result.joint_centres)
        centres = np.stack([result.joint_centres[k] for k in names], axis=1)
        _log_points(rec, rr, "world/joint_centres", indexes, centres, names, _JOINT_RADIUS_MM, _JOINT_COLOUR)

    for name, rotation in result.segment_frames.items():
        origin = _segment_origin(name, trial, result)
        if origin is None:
            continue
        entity = f"world/segments/{name}"
        vectors = AXIS_LENGTH_MM * np.swapaxes(np.asarray(rotation, dtype=float), 1, 2)  # rows = axes
        origins = np.broadcast_to(origin[:, None, :], (n, 3, 3))
        ok = np.all(np.isfinite(vectors), axis=(1, 2)) & np.all(np.isfinite(origin), axis=1)
        rec.log(
            entity,
            rr.Arrows3D.from_fields(radii=[_ARROW_RADIUS_MM], colors=_AXIS_COLOURS),
            static=True,
            strict=True,
        )
        _send_instances(
            rec, entity, indexes, rr.Arrows3D.columns,
            {"origins": origins, "vectors": vectors}, np.repeat(ok[:, None], 3, axis=1),
        )  # fmt: skip


def _log_series(
    rec: Any, rr: Any, entity: str, indexes: list[Any], values: np.ndarray, name: str,
    colour: tuple[int, int, int], width: float,
) -> None:  # fmt: skip
    rec.log(entity, rr.SeriesLines(names=name, colors=[colour], widths=width), static=True, strict=True)
    rec.send_columns(
        entity,
        indexes=indexes,
        columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)),
        strict=True,
    )


def _log_undetermined(
    rec: Any, rr: Any, entity: str, frames: np.ndarray, times: np.ndarray, values: np.ndarray, name: str,
    colour: tuple[int, int, int],
) -> None:  # fmt: skip
    """Points (crosses) at ``values`` on the given frames only: where a band is undetermined."""
    rec.log(entity, rr.SeriesPoints(names=name, colors=[colour], markers=_UNDETERMINED_MARKER,
                                    marker_sizes=_UNDETERMINED_SIZE), static=True, strict=True)  # fmt: skip
    rec.send_columns(
        entity,
        indexes=[rr.TimeColumn("frame", sequence=frames), rr.TimeColumn("time", duration=times)],
        columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)),
        strict=True,
    )


def _measured_angle(data: xr.DataArray) -> np.ndarray:
    """The measured angle of a hull ``(alpha, bound, frame)``: the midpoint of its highest
    α-level (α = 1, where both bounds are the measured angle)."""
    top = data.sel(alpha=float(data["alpha"].max()))
    return np.asarray(0.5 * (top.sel(bound="lower") + top.sel(bound="upper")).transpose("frame").values, dtype=float)


def _side_style(angle: str) -> tuple[str, tuple[int, int, int]]:
    return _SIDES.get(angle[:1], (angle, (120, 120, 120)))


def _log_angles(
    rec: Any, rr: Any, trial: Trial, result: CGMResult, fuzzy: xr.Dataset | None,
    alphas_to_show: Iterable[float] | None, indexes: list[Any],
) -> None:  # fmt: skip
    for angle, values in result.angles.items():
        side_name, colour = _side_style(angle)
        for k, axis in enumerate("XYZ"):
            _log_series(
                rec, rr, f"angles/{angle}/{axis}/deterministic", indexes, values[:, k],
                f"{side_name}", colour, _DETERMINISTIC_WIDTH,
            )  # fmt: skip
    if fuzzy is None:
        return
    alphas, variables, frames, times = _fuzzy_parts(fuzzy, trial, alphas_to_show)
    fuzzy_indexes = [rr.TimeColumn("frame", sequence=frames), rr.TimeColumn("time", duration=times)]
    for variable in variables:
        component = AngleComponent.maybe(variable)
        if component is None:
            continue
        angle, axis = component.angle, component.axis.value
        side_name, colour = _side_style(angle)
        data = component_hull(fuzzy, variable)
        flags = component_undetermined(fuzzy, variable)
        measured = _measured_angle(data)
        for alpha in alphas:
            cut = data.sel(alpha=alpha)
            mask = np.asarray(flags.sel(alpha=alpha).transpose("frame").values, dtype=bool)
            envelope_colour = _envelope_colour(colour, alpha)
            entity = f"angles/{angle}/{axis}/alpha_{_alpha_label(alpha)}"
            for bound in ("upper", "lower"):
                values = np.asarray(cut.sel(bound=bound).transpose("frame").values, dtype=float)
                _log_series(
                    rec, rr, f"{entity}/{bound}", fuzzy_indexes, np.where(mask, np.nan, values),
                    f"{side_name} α={_alpha_label(alpha)} {bound}", envelope_colour, _ENVELOPE_WIDTH,
                )  # fmt: skip
            if mask.any():
                _log_undetermined(
                    rec, rr, f"{entity}/undetermined", frames[mask], times[mask], measured[mask],
                    f"{side_name} α={_alpha_label(alpha)} undetermined", _darken(colour, 0.45),
                )  # fmt: skip


def _blueprint(rrb: Any, result: CGMResult, kinetics: bool = False) -> Any:
    rows = []
    for angle, title in ANGLE_ROWS:
        present = [side + angle for side in _SIDES if side + angle in result.angles]
        if not present:
            continue
        views = []
        for axis, plane, meaning in PLANES:
            label = meaning[title]
            views.append(
                rrb.TimeSeriesView(
                    origin="/angles",
                    contents=[f"/angles/{name}/{axis}/**" for name in present],
                    name=f"{title} {plane} (deg{', + ' + label if label else ''})",
                )
            )
        rows.append(rrb.Horizontal(*views, name=title))
    angle_tab = rrb.Vertical(*rows, name="Joint angles") if rows else rrb.TimeSeriesView(
        origin="/angles", name="Joint angles"
    )
    world_tab = rrb.Spatial3DView(origin="/world", name="3D (lab frame, mm)")
    kinetic_tabs = [kinetics_views(rrb)] if kinetics else []
    return rrb.Blueprint(
        rrb.Tabs(angle_tab, *kinetic_tabs, world_tab, active_tab=0),
        rrb.TimePanel(timeline="frame"),
    )


# ----------------------------------------------------------------------------- public
def check_recording(trial: Trial, result: CGMResult, fuzzy: xr.Dataset | None = None,
                    alphas_to_show: Iterable[float] | None = None) -> None:  # fmt: skip
    """Check the inputs of :func:`log_trial` before anything is written.

    Raises:
        ParameterError: the result does not belong to the trial, or ``fuzzy`` lacks a
            dimension / holds no requested alpha level.
    """
    _check_shapes(trial, result)
    if fuzzy is not None:
        _fuzzy_parts(fuzzy, trial, alphas_to_show)


def trial_blueprint(rrb: Any, result: CGMResult, kinetics: bool = False) -> Any:
    """The default blueprint of a trial's recording (module docstring): the joint-angle
    grid of the angles ``result`` has, with ``kinetics`` the kinetics tab
    (:func:`~fuzzygait.viz.rerun_kinetics.kinetics_views`), and the 3D view of ``world``;
    ``rrb`` is ``rerun.blueprint``."""
    return _blueprint(rrb, result, kinetics)


def log_trial(
    rec: Any,
    rr: Any,
    trial: Trial,
    result: CGMResult,
    fuzzy: xr.Dataset | None = None,
    *,
    alphas_to_show: Iterable[float] | None = None,
    kinetics: xr.Dataset | None = None,
) -> None:
    """Log ``trial``, its model ``result`` and optional fuzzy envelopes into the Rerun
    recording stream ``rec`` (``rr``: the ``rerun`` module); writes no file (the stream's
    sink does: :func:`fuzzygait.io.rerun_files.recording_file`).

    The entity layout, units and timelines are described in the module docstring.

    Args:
        trial: the (pre-processed) trial the model ran on; markers in mm.
        result: :func:`~fuzzygait.kinematics.compute_lower_body` output for ``trial``.
        fuzzy: fuzzy joint-angle result (:mod:`fuzzygait.markererror.analysis`: hulls in
            degrees per angle component, ball radii in mm); adds the alpha-cut envelope
            series (broken, with "undetermined" points, where a band is undetermined)
            and the marker balls. The deviation norms are not logged.
        alphas_to_show: alpha levels of ``fuzzy`` whose envelopes are logged; None for
            every level below 1 (alpha = 1 is the deterministic series, always logged;
            ignored without ``fuzzy``).
        kinetics: the trial's kinetics (:attr:`TrialKinetics.data
            <fuzzygait.workflows.kinetics.TrialKinetics.data>`, on the trial's frames): the
            ground reactions as arrows at the plates' centres of pressure and the joint
            moments and powers as series (:mod:`fuzzygait.viz.rerun_kinetics`).
    """
    indexes = [
        rr.TimeColumn("frame", sequence=trial.frames.astype(np.int64)),
        rr.TimeColumn("time", duration=np.asarray(trial.times, dtype=float)),
    ]
    _log_world(rec, rr, trial, result, fuzzy, indexes)
    _log_angles(rec, rr, trial, result, fuzzy, alphas_to_show, indexes)
    if kinetics is not None:
        log_kinetics(rec, rr, kinetics, indexes)
