"""The input's point block as a C3D written from it carries it over
(:mod:`fuzzygait.io.c3d_writeback`): per point its residuals, cameras and description,
and the file's length and residual units, so that what the writer does not change is
written back as stored and what it changes is marked computed (C3D: residual 0)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fuzzygait.core.trial import Trial


class CarryError(Exception):
    """Something of the input cannot be carried over (message: why)."""


@dataclass
class InputPoints:
    """The input's point block over the trial's frames as ezc3d reads it: what a written
    point that is one of the input's own keeps (:func:`point_meta`).

    Attributes:
        columns: each stored label (stripped, subject prefix included) -> its column.
        values: ``(frames, points, 3)`` positions in the file's units, NaN where invalid.
        residuals: ``(frames, points)``: -1 invalid, 0 computed or interpolated, > 0 measured.
        masks: ``(7, points, frames)``: the cameras that saw each sample.
        descriptions: ``POINT:DESCRIPTIONS`` per column ('' where none).
        unit: ``POINT:UNITS`` as the reader takes it (``mm`` when not stated).
        to_mm: its factor to millimetres.
        residual_scale: ``|POINT:SCALE|``, the unit of a stored residual (1 when not
            stated): the written file's too, so that residuals are kept exactly.
    """

    columns: dict[str, int]
    values: np.ndarray
    residuals: np.ndarray
    masks: np.ndarray
    descriptions: list[str]
    unit: str = "mm"
    to_mm: float = 1.0
    residual_scale: float = 1.0


def point_meta(points: InputPoints, labels: list[str],
               data: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str]]:  # fmt: skip
    """Residuals ``(frames, n)``, camera masks ``(7, n, frames)`` and descriptions of the
    written points ``labels`` (prefix included) with positions ``data`` ``(frames, n, 3)``
    in the file's units.

    A sample the input holds unchanged (the same float32 coordinates, or a gap in both)
    keeps its residual and cameras;
    a changed or filled one is valid with residual 0 (C3D's mark of a computed or
    interpolated point); a gap is -1, except the input's own gaps marked by zeros (0, 0, 0
    with a residual >= 0, which the reader reads as gaps: Nexus' outputs where it computed
    none), written back as they were.  A sample that replaces a measured one keeps its
    cameras; a filled one has none.  A point the input does not hold gets no description."""
    n_frames, n = data.shape[:2]
    valid = np.all(np.isfinite(data), axis=2)
    residuals = np.where(valid, 0.0, -1.0)
    masks = np.zeros((7, n, n_frames), dtype=bool)
    descriptions = [""] * n
    for j, label in enumerate(labels):
        i = points.columns.get(label)
        if i is None:
            continue
        theirs = points.values[:, i]
        stated = points.residuals[:, i] >= 0
        zero = stated & np.all(theirs == 0.0, axis=1)
        measured = stated & ~zero
        with np.errstate(invalid="ignore"):
            same = valid[:, j] & measured & np.all(data[:, j].astype(np.float32) == theirs.astype(np.float32), axis=1)
        zero_gap = ~valid[:, j] & zero
        unchanged = same | zero_gap | (~valid[:, j] & ~stated)  # the last: a gap that stays one
        residuals[unchanged, j] = points.residuals[unchanged, i]
        masks[:, j] = points.masks[:, i] & (unchanged | (valid[:, j] & measured))[None]
        descriptions[j] = points.descriptions[i]
    return residuals, masks, descriptions


def trial_window(c: Any, trial: Trial) -> slice:
    """The input's frames (columns of ezc3d's data) the trial covers.

    Raises:
        CarryError: the trial's frames are not all the input's."""
    n_frames = int(np.shape(c["data"]["points"])[2])
    first = int(c["header"]["points"]["first_frame"]) + 1
    start = trial.first_frame - first
    if start < 0 or start + trial.n_frames > n_frames:
        raise CarryError(
            f"the trial's frames {trial.first_frame}-{trial.first_frame + trial.n_frames - 1} are not all among "
            f"the file's frames {first}-{first + n_frames - 1}"
        )
    return slice(start, start + trial.n_frames)


def input_points(c: Any, trial: Trial) -> InputPoints:
    """The input's point block over the trial's frames (:class:`InputPoints`).

    Raises:
        CarryError: the trial's frames are not the file's, or its units are unknown."""
    from fuzzygait.io.c3d import LENGTH_UNITS_TO_MM

    window = trial_window(c, trial)
    point = c["parameters"]["POINT"]
    labels = [str(label).strip() for label in point["LABELS"]["value"]] if "LABELS" in point else []
    stored = point["DESCRIPTIONS"]["value"] if "DESCRIPTIONS" in point else []
    units = point["UNITS"]["value"] if "UNITS" in point else []
    unit = str(units[0]).strip().lower() if len(units) else ""
    if unit and unit not in LENGTH_UNITS_TO_MM:
        raise CarryError(f"its POINT:UNITS {unit!r} are not a length unit")
    values = np.asarray(c["data"]["points"], dtype=float)[:3, :, window].transpose(2, 1, 0)
    columns: dict[str, int] = {}
    for i, label in enumerate(labels[: values.shape[1]]):
        columns.setdefault(label, i)
    descriptions = [str(d).strip() for d in stored] + [""] * max(0, values.shape[1] - len(stored))
    meta = c["data"]["meta_points"]
    stated = np.ravel(point["SCALE"]["value"]) if "SCALE" in point else np.zeros(0)
    scale = abs(float(stated[0])) if stated.size else 1.0
    return InputPoints(columns, values, np.asarray(meta["residuals"], dtype=float)[0, :, window].T,
                       np.asarray(meta["camera_masks"], dtype=bool)[:, :, window], descriptions, unit or "mm",
                       LENGTH_UNITS_TO_MM.get(unit or "mm", 1.0),
                       scale if math.isfinite(scale) and scale > 0 else 1.0)  # fmt: skip
