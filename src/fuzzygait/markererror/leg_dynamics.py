"""The dynamics of one leg's row in the fuzzy kinetics
(:class:`~fuzzygait.markererror.moment_model.LegKineticsModel`): Plug-in Gait's foot, tibia
and femur on a row's nine-frame window, their angular velocities from the rotations'
differences, Newton–Euler from the ground up, and how far each segment frame turned from
the measured one.  Written on ``autograd.numpy`` so that the same code runs on numbers,
on autograd's traced arrays and on CasADi symbols (:mod:`.symbols`).
"""

from __future__ import annotations

from typing import NamedTuple

import autograd.numpy as anp
import numpy as np

from fuzzygait.kinetics.inverse_dynamics import GRAVITY
from fuzzygait.kinetics.segments import PLUG_IN_GAIT_TABLE

#: Frames either side of a frame its kinetics need (Nexus' derivatives lose four).
HALF_WINDOW = 4
_FIVE_POINT = np.array([1.0, -8.0, 0.0, 8.0, -1.0]) / 12.0
#: The five-point first difference applied twice: weights of the nine frames (× rate²).
SECOND_DIFFERENCE = np.convolve(_FIVE_POINT, _FIVE_POINT)


class Loads(NamedTuple):
    """The ground's load on the foot at the rows' frames: ``force`` ``(k, 3)`` N,
    ``moment`` ``(k, 3)`` N·m about the laboratory origin, ``shares`` ``(plates, k, 3)``
    N each plate's share of the force."""

    force: np.ndarray
    moment: np.ndarray
    shares: np.ndarray


class Constants(NamedTuple):
    """What every row shares: ``rate`` Hz, body ``mass`` kg, ``foot_length`` m and the
    plates' in-plane axes ``plane`` ``(plates, 2, 3)``."""

    rate: float
    mass: float
    foot_length: float
    plane: np.ndarray


def apply_rows(matrices: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """``matrices @ vectors`` over the leading axes (``(..., 3, 3)`` and ``(..., 3)``)."""
    return anp.sum(matrices * vectors[..., None, :], axis=-1)


def angular_velocities(frames: np.ndarray, rate: float) -> np.ndarray:
    """``(k, s, 3, 3)`` rad/s: the angular velocity at window offsets −2, 0, +2 of the
    ``(k, s, 5, 3, 3)`` rotations of ``s`` segments at offsets −4, −2, 0, 2, 4: the axial
    vector of ``Ṙ Rᵀ`` with ``Ṙ`` the two-frame difference
    (:func:`~fuzzygait.kinetics.inverse_dynamics.angular_velocity`)."""
    ahead, behind, centre = frames[:, :, 2:5], frames[:, :, 0:3], frames[:, :, 1:4]
    w = anp.matmul((ahead - behind) * (rate / 4.0), anp.swapaxes(centre, -1, -2))
    return 0.5 * anp.stack([w[..., 2, 1] - w[..., 1, 2], w[..., 0, 2] - w[..., 2, 0], w[..., 1, 0] - w[..., 0, 1]],
                           axis=-1)  # fmt: skip


class Segments(NamedTuple):
    """Foot, tibia and femur over each row's nine frames, SI units, laboratory frame."""

    mass: np.ndarray  # (3,) kg
    com: np.ndarray  # (k, 3, 9, 3) m
    inertia: np.ndarray  # (k, 3, 3) kg·m² at the centre frame, principal x, y, z
    joint: np.ndarray  # (k, 3, 3) m, each segment's proximal joint centre at the centre frame


def leg_segments(parts: dict[str, np.ndarray], foot_length: float, body_mass: float) -> Segments:
    """Foot, tibia and femur as :mod:`fuzzygait.kinetics.segments` builds them (the
    foot's centre of mass on its long axis, the long segments' lengths per frame)."""
    foot, tibia, femur = (PLUG_IN_GAIT_TABLE[name] for name in ("foot", "tibia", "femur"))
    ajc, kjc, hjc = parts["AJC"], parts["KJC"], parts["HJC"]
    com = anp.stack([ajc - (1.0 - foot.com_from_distal) * foot_length * parts["foot"][..., 2],
                     ajc + tibia.com_from_distal * (kjc - ajc),
                     kjc + femur.com_from_distal * (hjc - kjc)], axis=1)  # fmt: skip
    joint = anp.stack([ajc[:, HALF_WINDOW], kjc[:, HALF_WINDOW], hjc[:, HALF_WINDOW]], axis=1)
    lengths = anp.stack([foot_length * anp.ones(joint.shape[0]),
                         anp.sqrt(anp.sum((joint[:, 1] - joint[:, 0]) ** 2, axis=1)),
                         anp.sqrt(anp.sum((joint[:, 2] - joint[:, 1]) ** 2, axis=1))], axis=1)  # fmt: skip
    mass = body_mass * np.array([foot.mass_fraction, tibia.mass_fraction, femur.mass_fraction])
    gyration = np.array([foot.gyration, tibia.gyration, femur.gyration])
    across = mass * (gyration * lengths) ** 2
    return Segments(mass, com, anp.stack([across, across, anp.zeros_like(across)], axis=2), joint)


def newton_euler(segments: Segments, rotations: np.ndarray, omega: np.ndarray, force: np.ndarray,
                  moment: np.ndarray, rate: float) -> np.ndarray:  # fmt: skip
    """``(k, 3, 3)``: per joint (ankle, knee, hip) the joint moment (N·m about the joint
    centre, laboratory frame, of the proximal segment on the distal one) at the window's
    centre, from the ground load (``force`` N, ``moment`` N·m about the laboratory
    origin) up: :func:`~fuzzygait.kinetics.inverse_dynamics.newton_euler` with its
    derivatives (``rotations`` ``(k, 4, 5, 3, 3)`` at the even offsets and ``omega``
    :func:`angular_velocities` of foot, tibia, femur and pelvis)."""
    acceleration = anp.einsum("w,kswi->ksi", SECOND_DIFFERENCE * rate**2, segments.com)
    alpha = (omega[:, :3, 2] - omega[:, :3, 0]) * (rate / 4.0)
    rotation, inertia = rotations[:, :3, 2], segments.inertia
    transposed = anp.swapaxes(rotation, -1, -2)
    w_local = apply_rows(transposed, omega[:, :3, 1])
    a_local = apply_rows(transposed, alpha)
    h_dot = apply_rows(rotation, inertia * a_local + anp.cross(w_local, inertia * w_local))
    weight = segments.mass[None, :, None] * (acceleration - GRAVITY)
    centre = segments.com[:, :, HALF_WINDOW]
    out = []
    point: np.ndarray = np.zeros(np.shape(force))
    distal_force, distal_moment = force, moment
    for s in range(3):
        f = weight[:, s] - distal_force
        joint, c = segments.joint[:, s], centre[:, s]
        m = h_dot[:, s] - distal_moment - anp.cross(point - c, distal_force) - anp.cross(joint - c, f)
        out.append(m)
        point, distal_force, distal_moment = joint, -f, -m
    return anp.stack(out, axis=1)


def turn_cosines(rotations: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """``(k, n)``: the cosine of the angle each of the ``(k, …, 3, 3)`` rotations turned
    from the ``measured`` ones (same shape; ``n`` their product over the middle axes),
    ``(trace(R Mᵀ) − 1) / 2``, unclipped (rounding can pass ±1)."""
    k = np.shape(rotations)[0]
    return anp.reshape((anp.sum(anp.sum(rotations * measured, axis=-1), axis=-1) - 1.0) / 2.0, (k, -1))
