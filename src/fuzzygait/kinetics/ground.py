"""The ground's load on a foot at the marker frames, from force-plate signals.

A plate's signals (force, centre of pressure, free moment: the reaction of the ground on
the body, laboratory frame, N and mm as :class:`fuzzygait.io.force_plates.ForcePlate`
holds them) become one :class:`~fuzzygait.kinetics.inverse_dynamics.Load` per marker
frame: the force and its moment about the laboratory origin, ``COP x F + T``.

Nexus' Plug-in Gait takes, for marker frame ``i``, the mean of the analog samples
centred on that frame's first sample ``i * r`` (``r`` analog samples per frame; samples
``i r - r//2 ... i r + r//2``: 9 samples at r = 9, 11 at r = 10) of the force and of the
moment about a fixed point — not the mean of the centre of pressure.  Measured on
``Movement_trial.c3d`` (1080 Hz analog, 120 Hz markers) and ``PiGKad_Motion.c3d`` (1000 Hz,
100 Hz): the stored ``L/RGroundReactionForce`` equal this mean to the stored precision,
and the ankle moments agree to 1e-3 N·m/kg only with the moment averaged, not the
centre of pressure (see ``docs/kinetics.md``).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError
from fuzzygait.kinetics.inverse_dynamics import Load
from fuzzygait.kinetics.segments import MM

Array = NDArray[np.float64]


class PlateSignals(Protocol):
    """What the kinetics read of a force plate (a :class:`fuzzygait.io.force_plates.ForcePlate`
    has it): its 1-based ``number``, ``rate`` Hz; ``force`` ``(m, 3)`` N, ``cop`` ``(m, 3)``
    mm (NaN without contact), ``free_moment`` ``(m, 3)`` N·mm, ``contact`` ``(m,)`` bool;
    laboratory frame."""

    @property
    def number(self) -> int: ...

    @property
    def rate(self) -> float: ...
    @property
    def force(self) -> Array: ...
    @property
    def cop(self) -> Array: ...
    @property
    def free_moment(self) -> Array: ...
    @property
    def contact(self) -> NDArray[np.bool_]: ...


def samples_per_frame(plate_rate: float, marker_rate: float) -> int:
    """The whole number of plate samples per marker frame.

    Raises:
        ParameterError: the plate rate is not a whole multiple of the marker rate.
    """
    ratio = plate_rate / marker_rate
    if marker_rate <= 0 or ratio < 1 or abs(ratio - round(ratio)) > 1e-6:
        raise ParameterError(f"force-plate rate {plate_rate:g} Hz is not a whole multiple of the marker rate "
                             f"{marker_rate:g} Hz")  # fmt: skip
    return int(round(ratio))


def frame_means(samples: Array, ratio: int, n_frames: int) -> Array:
    """``(n_frames, ...)``: the mean of the samples centred on each frame's first sample,
    ``i*ratio - ratio//2`` to ``i*ratio + ratio//2`` (``ratio`` samples when it is odd,
    ``ratio + 1`` when even), the window cut at the ends of the record."""
    half = ratio // 2
    index = (np.arange(n_frames) * ratio)[:, None] + np.arange(-half, half + 1)[None, :]
    inside = (index >= 0) & (index < len(samples))
    picked = samples[np.clip(index, 0, len(samples) - 1)]
    weights = inside / np.maximum(inside.sum(axis=1, keepdims=True), 1)
    return np.einsum("fk,fk...->f...", weights, picked)


def plate_load(plate: PlateSignals, n_frames: int, marker_rate: float) -> Load:
    """The ground's load from ``plate`` at ``n_frames`` marker frames (the plate's first
    sample at the first frame): force (N) and moment about the laboratory origin (N·m),
    zero on the samples without contact."""
    ratio = samples_per_frame(plate.rate, marker_rate)
    contact = np.asarray(plate.contact, dtype=bool) & np.all(np.isfinite(plate.cop), axis=1)
    force = np.where(contact[:, None], plate.force, 0.0)
    cop = np.where(contact[:, None], plate.cop, 0.0) * MM
    moment = np.cross(cop, force) + np.where(contact[:, None], plate.free_moment, 0.0) * MM
    return Load(np.zeros((n_frames, 3)), frame_means(force, ratio, n_frames), frame_means(moment, ratio, n_frames))


def no_load(n_frames: int) -> Load:
    """No ground contact at any frame."""
    zero = np.zeros((n_frames, 3))
    return Load(zero, zero, zero.copy())


def masked(load: Load, frames: NDArray[np.bool_]) -> Load:
    """``load`` on the ``frames`` (``(n,)`` bool) and zero elsewhere."""
    keep = np.asarray(frames, dtype=bool)[:, None]
    return Load(load.point, np.where(keep, load.force, 0.0), np.where(keep, load.moment, 0.0))


def summed(loads: list[Load]) -> Load:
    """The sum of loads about the same point (a foot on more than one plate)."""
    first = loads[0]
    return Load(first.point, sum((x.moved_to(first.point).force for x in loads), np.zeros_like(first.force)),
                sum((x.moved_to(first.point).moment for x in loads), np.zeros_like(first.moment)))  # fmt: skip
