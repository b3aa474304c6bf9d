"""The kinetics of a trial in its Rerun recording (:func:`fuzzygait.viz.rerun_log.log_trial`
with ``kinetics``; rerun-sdk 0.41): the ground reaction on each force plate as an arrow
at its centre of pressure, the joint moments and powers as time series.

Input: the dataset of :class:`fuzzygait.workflows.kinetics.TrialKinetics` (``data``):
``plate_force (plate, axis, frame)`` N and ``plate_cop (plate, axis, frame)`` mm in the
laboratory frame, ``plate_corners (plate, corner, axis)`` mm, ``moment (side, joint,
axis, frame)`` N·m/kg, ``power (side, joint, frame)`` W/kg.

Entity layout::

    world/force_plates/outlines             LineStrips3D (static): each plate's surface
                                            outline, labelled "plate <n>"
    world/force_plates/grf                  Arrows3D, one row per frame: one arrow per
                                            plate in contact, from its centre of pressure,
                                            GRF_MM_PER_N mm per newton (1 mm per N: a body
                                            weight of 700 N is a 0.7 m arrow), labelled
                                            "plate <n>"; plates without contact are left out
    kinetics/moment/<Joint>/<X|Y|Z>/<L|R>   Scalars: the joint moment, N·m/kg (X sagittal,
                                            + extensor / plantarflexor, as Nexus)
    kinetics/power/<Joint>/<L|R>            Scalars: the joint power, W/kg (+ generation)

Left red, right green as the angle series. The blueprint tab "Kinetics"
(:func:`kinetics_views`): rows Hip, Knee, Ankle; columns the moment's X, Y, Z and the power.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["GRF_MM_PER_N", "kinetics_views", "log_kinetics"]

#: Length of the drawn ground reaction arrows, mm per newton.
GRF_MM_PER_N = 1.0

_SIDES = {"L": ("Left", (214, 39, 40)), "R": ("Right", (44, 160, 44))}
_GRF_COLOUR = (255, 200, 0)
_GRF_RADIUS_MM = 6.0
_OUTLINE_COLOUR = (150, 150, 150)
_OUTLINE_RADIUS_MM = 2.0
_WIDTH = 2.0
#: Joints from the top of the leg, as the clinical pages order them.
_ROWS = ("Hip", "Knee", "Ankle")
_MEANING = {"X": "sagittal, + extensor/plantarflexor", "Y": "frontal", "Z": "transverse"}


def _log_plates(rec: Any, rr: Any, data: xr.Dataset, indexes: list[Any]) -> None:
    """The plates' outlines (static) and per frame the GRF arrows at the COPs."""
    plates = [int(p) for p in data["plate"].values]
    labels = [f"plate {p}" for p in plates]
    corners = data["plate_corners"].transpose("plate", "corner", "axis").values
    strips = [np.vstack([c, c[:1]]) for c in corners]  # closed outline
    rec.log("world/force_plates/outlines", rr.LineStrips3D(strips, colors=[_OUTLINE_COLOUR], radii=[_OUTLINE_RADIUS_MM],
                                                           labels=labels), static=True, strict=True)  # fmt: skip
    cop = data["plate_cop"].transpose("frame", "plate", "axis").values
    force = data["plate_force"].transpose("frame", "plate", "axis").values * GRF_MM_PER_N
    valid = np.all(np.isfinite(cop), axis=2) & np.all(np.isfinite(force), axis=2)
    rec.log("world/force_plates/grf", rr.Arrows3D.from_fields(colors=[_GRF_COLOUR], radii=[_GRF_RADIUS_MM]),
            static=True, strict=True)  # fmt: skip
    names = np.broadcast_to(np.array(labels, dtype=object), valid.shape)
    columns = rr.Arrows3D.columns(origins=cop[valid], vectors=force[valid], labels=names[valid].tolist())
    rec.send_columns("world/force_plates/grf", indexes=indexes, columns=columns.partition(valid.sum(axis=1)),
                     strict=True)  # fmt: skip


def _series(rec: Any, rr: Any, entity: str, indexes: list[Any], values: np.ndarray, name: str,
            colour: tuple[int, int, int]) -> None:  # fmt: skip
    rec.log(entity, rr.SeriesLines(names=name, colors=[colour], widths=_WIDTH), static=True, strict=True)
    rec.send_columns(entity, indexes=indexes, columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)),
                     strict=True)  # fmt: skip


def log_kinetics(rec: Any, rr: Any, data: xr.Dataset, indexes: list[Any]) -> None:
    """Log a trial's kinetics (module docstring) into ``rec`` on the trial's ``indexes``
    (its ``frame`` and ``time`` columns; ``data``'s frames are the trial's)."""
    if data.sizes.get("plate", 0):
        _log_plates(rec, rr, data, indexes)
    for side, (word, colour) in _SIDES.items():
        for joint in data["joint"].values:
            for axis in data["axis"].values:
                values = data["moment"].sel(side=side, joint=joint, axis=axis).values
                _series(rec, rr, f"kinetics/moment/{joint}/{axis}/{side}", indexes, values,
                        f"{word} {joint.lower()} moment {axis}", colour)  # fmt: skip
            power = data["power"].sel(side=side, joint=joint).values
            _series(rec, rr, f"kinetics/power/{joint}/{side}", indexes, power, f"{word} {joint.lower()} power", colour)


def kinetics_views(rrb: Any) -> Any:
    """The blueprint tab "Kinetics": a row per joint (hip, knee, ankle), the moment's X,
    Y, Z (N·m/kg) and the power (W/kg), left and right in each."""
    rows = []
    for joint in _ROWS:
        views = [rrb.TimeSeriesView(origin=f"/kinetics/moment/{joint}/{axis}",
                                    name=f"{joint} moment {axis} (N·m/kg, {meaning})")
                 for axis, meaning in _MEANING.items()]  # fmt: skip
        views.append(rrb.TimeSeriesView(origin=f"/kinetics/power/{joint}", name=f"{joint} power (W/kg, + generation)"))
        rows.append(rrb.Horizontal(*views, name=joint))
    return rrb.Vertical(*rows, name="Kinetics")
