"""When a fuzzy joint-angle band is *undetermined*: a bound past a quarter turn from the
measured angle (the segment frame can flip inside the ball), or a middle Cardan component
near ±90° (the Cardan singularity).  The rules, their margins and the excursion limit the
optimisers stop a bound at (:attr:`~fuzzygait.markererror.angle_model.JointAngleModel.excursion_limit`)."""

from __future__ import annotations

import numpy as np

from fuzzygait.core.names import AXES, angle_names
from fuzzygait.kinematics.angles import ANGLE_TABLE

#: Excursion (degrees) of a hull bound from the measured angle beyond which the band is
#: *undetermined*: the segment frame turns more than a quarter turn inside the ball, which
#: for a frame built from two markers and a joint centre means it can flip (the angle
#: then jumps by about 180°; a bound found on the far side of the jump is not an extreme
#: of a continuous band).
UNDETERMINED_DEG = 90.0
#: Where the optimisers stop a bound (the angle models' ``excursion_limit``, degrees from
#: the model's own angle at zero deviation): a bound beyond :data:`UNDETERMINED_DEG` makes
#: the band undetermined whatever its value, so searching further only costs time (a
#: quarter of the gradient rows of the sample trial's bands went into such bounds,
#: ``benchmarks/RESULTS.md``).  The 1° margin keeps the flag where the measured angle
#: and the model's angle at zero deviation differ by rounding.
EXCURSION_LIMIT_DEG = UNDETERMINED_DEG + 1.0


def undetermined(lower: np.ndarray, upper: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """Where a band ``[lower, upper]`` around ``measured`` (degrees, broadcasting) is
    undetermined: a bound more than :data:`UNDETERMINED_DEG` from the measured angle."""
    with np.errstate(invalid="ignore"):
        return (np.asarray(upper) - measured > UNDETERMINED_DEG) | (measured - np.asarray(lower) > UNDETERMINED_DEG)


#: Margin (degrees) from the Cardan singularity: where the band of an angle's middle
#: Cardan component (the ``asin`` one, within ±90°) comes this close to ±90°, the segment
#: frame passes (near) the singularity inside the ball and all three components are
#: *undetermined* at that α-level and frame.  At the singularity only the sum or difference
#: of the first and third is defined — each alone can take any value inside the ball — and
#: close to it they turn so fast that their extremes sit in slivers of the ball the local
#: optimiser does not reliably find (benchmarks/RESULTS.md, "Soundness": every missed
#: extreme of the real CGM 2.4 session had its middle angle at 75.7-89.5°); the middle
#: component's far bound is then short too (SLSQP from the Graph Follower's extremisers
#: widened 861 of 1,148 such forefoot bounds, by up to 19.5°).
GIMBAL_MARGIN_DEG = 15.0


def middle_component(name: str) -> int:
    """Output index (0, 1, 2 = X, Y, Z) of the middle Cardan angle of ``name``
    (``"LKneeAngles"``: Y; ankle, foot progression, forefoot: Z)."""
    joint = name[1:].removesuffix("Angles")
    return ANGLE_TABLE[joint][0].index(1)


def _near_caps(lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the lower / upper bound (degrees) comes within :data:`GIMBAL_MARGIN_DEG` of
    −90° / +90° (NaN: False)."""
    with np.errstate(invalid="ignore"):
        return np.asarray(lower) < GIMBAL_MARGIN_DEG - 90.0, np.asarray(upper) > 90.0 - GIMBAL_MARGIN_DEG


def near_gimbal_lock(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Where a middle Cardan component's band ``[lower, upper]`` (degrees) comes within
    :data:`GIMBAL_MARGIN_DEG` of ±90°."""
    low, high = _near_caps(lower, upper)
    return low | high


def gimbal_undetermined(hulls: dict[str, np.ndarray], flags: dict[str, np.ndarray], measured_index: int) -> None:
    """The Cardan-singularity rule, in place, for every angle whose middle component is in
    ``hulls`` (``{"LKneeAngles_Y": (alpha, bound, frame)}``, degrees) and ``flags``
    (``(alpha, frame)`` bool): where the middle component's band comes within
    :data:`GIMBAL_MARGIN_DEG` of ±90° (:func:`near_gimbal_lock`), every component of the
    angle present in ``flags`` is marked undetermined, and the middle band is closed at
    ±90° there (the ``asin`` cannot pass it: the stored bound is a sound one).  The α-level
    ``measured_index`` (α = 1, the measured angle) is left as it is."""
    for name in angle_names(hulls):
        columns = [f"{name}_{a}" for a in AXES]
        middle = middle_component(name)
        if columns[middle] not in hulls:
            continue
        band = hulls[columns[middle]]
        lower, upper = _near_caps(band[:, 0], band[:, 1])
        upper[measured_index] = lower[measured_index] = False
        lock = upper | lower
        band[:, 1][upper] = 90.0
        band[:, 0][lower] = -90.0
        for column in columns:
            if column in flags:
                flags[column] = flags[column] | lock
