"""Which plate's load acts on which foot, frame by frame.

:func:`stored_assignment` reads the assignment Nexus made from the ground reaction it
stored (``L/RGroundReactionForce``, N/kg): on each frame where Nexus has a value, the
plate whose frame load (:func:`fuzzygait.kinetics.ground.plate_load`) equals it is the
one on that foot.  It reproduces Nexus' ground load to recompute its kinetics, and shows
where Nexus changed plates within one of its windows (``PiGKadMed_Motion.c3d``: the left
foot's window holds the end of one contact on plate 2 and a whole contact on plate 1).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.names import Side
from fuzzygait.kinetics.ground import PlateSignals, no_load, plate_load
from fuzzygait.kinetics.inverse_dynamics import Load

#: How far (N/kg) a plate's frame force may be from the stored ground reaction and still
#: be the plate Nexus used (the stored values are single-precision floats).
MATCH_TOLERANCE = 1e-3


@dataclass(frozen=True)
class StoredAssignment:
    """Nexus' plate assignment of one side.

    Attributes:
        plate: ``(n,)`` int, the 1-based plate number on each frame, 0 where Nexus has no
            ground reaction for this foot.
        unmatched: ``(n,)`` bool, frames where Nexus has a ground reaction that no single
            plate's load matches (``plate`` is then the nearest).
    """

    plate: NDArray[np.int_]
    unmatched: NDArray[np.bool_]


def stored_assignment(plates: Sequence[PlateSignals], outputs: Mapping[str, NDArray[np.float64]], side: Side,
                      body_mass: float, rate: float) -> StoredAssignment:  # fmt: skip
    """The plates Nexus put under the ``side`` foot, from its stored ground reaction.

    Args:
        plates: the trial's plates at their own rate (their first sample at the first
            frame), read with every sample in contact (threshold 0 N): Nexus' ground
            reaction includes the noise of a plate before and after the foot's contact.
        outputs: the trial's stored outputs (``L/RGroundReactionForce`` in N/kg).
        side: the foot.
        body_mass: kg, the mass Nexus normalised with.
        rate: marker frames per second.
    """
    stored = outputs[side.value + "GroundReactionForce"] * body_mass
    n = len(stored)
    window = np.all(np.isfinite(stored), axis=1)
    if not plates:
        return StoredAssignment(np.zeros(n, dtype=int), window.copy())
    loads = [plate_load(p, n, rate) for p in plates]
    distance = np.stack([np.linalg.norm(load.force - np.nan_to_num(stored), axis=1) for load in loads], axis=1)
    best = np.argmin(distance, axis=1)
    unmatched = window & (distance[np.arange(n), best] > MATCH_TOLERANCE * body_mass)
    return StoredAssignment(np.where(window, np.array([p.number for p in plates])[best], 0), unmatched)


def assigned_ground(plates: Sequence[PlateSignals], plate: NDArray[np.int_], rate: float) -> Load:
    """The ground's load on a foot whose plate on each frame is ``plate`` (``(n,)``
    1-based numbers, 0: off the plates)."""
    n = len(plate)
    force, moment = np.zeros((n, 3)), np.zeros((n, 3))
    for p in plates:
        on = plate == p.number
        if on.any():
            load = plate_load(p, n, rate)
            force[on], moment[on] = load.force[on], load.moment[on]
    return Load(np.zeros((n, 3)), force, moment) if plates else no_load(n)
