"""Known joint-angle curves of the synthetic walker, as exact functions of gait phase.

Every curve is a truncated Fourier series (at most 6 harmonics) of the gait-cycle phase
``p`` (dimensionless, one stride = 1):

    value(p) = mean + sum_k  cos_k * cos(2*pi*k*p) + sin_k * sin(2*pi*k*p)     [degrees]

so it is smooth, periodic and can be evaluated exactly at any time.  The coefficients
were fitted once (offline) to hand-placed key points of a typical adult normal gait and
then rounded to 0.001 deg; the rounded numbers below *are* the definition.

Phase and timing conventions
----------------------------
* The walker's global phase ``p`` is the **left** limb's phase: left Foot Strike at
  ``p = 0, 1, 2, ...`` and left Foot Off at ``p = k + FOOT_OFF_PHASE``.
* The right limb runs half a cycle later: its own phase is ``p - 0.5`` (right Foot
  Strike at ``p = k + 0.5``, right Foot Off at ``p = k + 0.1``).  The same curves are
  used for both limbs, evaluated at each limb's own phase (perfectly symmetric gait).
* One stride lasts :data:`STRIDE_TIME_S` seconds.

Angle meanings (clinical, identical on both sides; signs are realised geometrically by
:func:`fuzzygait.synthetic.leg_model.joint_rotation`):

* hip / knee / ankle ``flexion``: hip flexion +, knee flexion +, ankle dorsiflexion +;
* ``adduction``: hip adduction +, knee varus (adduction) +; for the ankle, Plug-in Gait's
  "inversion" (Y) output, which is not a free curve: Plug-in Gait's foot has only the TOE
  marker and the ankle joint centre, so its roll about the long axis follows the tibia's
  flexion axis and the ankle Y it reports is a fixed function of the ankle rotation Z and
  the static plantarflexion offset (:func:`plug_in_gait_ankle_y`);
* ``rotation``: internal rotation + (for the ankle: toe pointing medially +).

Pelvis curves are given for the **left** side, relative to the laboratory frame, whose
+X axis is the walking direction (= progression frame): anterior tilt +, obliquity +
when the left side is up, rotation + when the left ASIS is forward.  The right-side
pelvis angles are the same rotation seen from the right: ``(tilt, -obliquity,
-rotation)``.  The pelvis curves contain only even harmonics (tilt, vertical bounce) or
only odd harmonics (obliquity, rotation, lateral sway), so the right-side values also
equal the left-side curves shifted by half a cycle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Duration of one stride (gait cycle) in seconds.
STRIDE_TIME_S = 1.1
#: Phase of Foot Off within a limb's own cycle (Foot Strike at 0).
FOOT_OFF_PHASE = 0.6
#: Phase lag of the right limb behind the left one.
RIGHT_PHASE_SHIFT = 0.5
#: Joints whose curves are defined, in output order.
JOINTS = ("hip", "knee", "ankle")
#: Angle components in output order (C3D X, Y, Z of PiG's ``*Angles`` outputs).
COMPONENTS = ("flexion", "adduction", "rotation")


@dataclass(frozen=True)
class FourierCurve:
    """``mean + sum_k cos[k-1]*cos(2 pi k p) + sin[k-1]*sin(2 pi k p)``.

    Attributes:
        mean: constant term (unit of the curve, usually degrees).
        cos: cosine coefficients of harmonics 1, 2, ...
        sin: sine coefficients of harmonics 1, 2, ... (same length as ``cos``).
    """

    mean: float
    cos: tuple[float, ...] = ()
    sin: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if len(self.cos) != len(self.sin):
            raise ValueError("cos and sin coefficient tuples must have the same length")
        if len(self.cos) > 6:
            raise ValueError("at most 6 harmonics")

    def __call__(self, phase: np.ndarray | float) -> np.ndarray:
        """Curve value at ``phase`` (cycles; any real number, periodic with period 1)."""
        p = np.asarray(phase, dtype=float)
        out = np.full(p.shape, float(self.mean))
        for k, (a, b) in enumerate(zip(self.cos, self.sin, strict=True), start=1):
            w = 2.0 * np.pi * k * p
            out = out + a * np.cos(w) + b * np.sin(w)
        return out

    def derivative(self, phase: np.ndarray | float) -> np.ndarray:
        """d(value)/d(phase) at ``phase`` (unit of the curve per cycle)."""
        p = np.asarray(phase, dtype=float)
        out = np.zeros(p.shape)
        for k, (a, b) in enumerate(zip(self.cos, self.sin, strict=True), start=1):
            w = 2.0 * np.pi * k * p
            out = out + 2.0 * np.pi * k * (-a * np.sin(w) + b * np.cos(w))
        return out


# --------------------------------------------------------------------- joint curves (deg)
#: Joint angle curves in degrees of a limb's own phase, keyed ``(joint, component)``.
JOINT_CURVES: dict[tuple[str, str], FourierCurve] = {
    # hip flexion: ~+30 at initial contact, -10 at terminal stance (~50 %), ~33 late swing
    ("hip", "flexion"): FourierCurve(
        15.003,
        (20.076, -5.050, 0.024, -0.144, 0.005, 0.003),
        (-3.666, -1.216, 0.486, 0.191, 0.121, 0.032),
    ),
    # knee flexion: ~5 at IC, ~18 loading peak (13 %), ~5 mid stance, ~60 in swing (71 %)
    ("knee", "flexion"): FourierCurve(
        21.943,
        (-4.289, -13.709, 0.507, 0.100, 0.036, 0.074),
        (-18.009, 9.761, 3.483, 0.407, 0.182, 0.202),
    ),
    # ankle dorsiflexion: ~0 at IC, -7 loading, +10 late stance, ~-15 at toe off, ~0 swing
    ("ankle", "flexion"): FourierCurve(
        -0.340,
        (-1.603, 0.578, -1.964, 2.545, -0.251, 0.631),
        (4.673, -7.242, 1.913, -1.637, -0.770, 0.430),
    ),
    # hip adduction: ~+6 in loading response, ~-6 in swing
    ("hip", "adduction"): FourierCurve(
        0.651, (1.437, 0.410, -0.317), (5.252, -0.114, -0.487)
    ),
    # hip internal rotation: about +-4
    ("hip", "rotation"): FourierCurve(
        0.849, (2.864, -0.336, -0.353), (2.430, -0.993, -0.021)
    ),
    # knee varus: 0.5..5 (peak in swing)
    ("knee", "adduction"): FourierCurve(
        1.893, (-0.098, -1.164, 0.205), (-1.035, 0.827, 0.413)
    ),
    # knee internal rotation: -6..+5
    ("knee", "rotation"): FourierCurve(
        -0.733, (-0.948, -0.046, -0.141), (5.362, -0.295, -0.119)
    ),
    # ankle (foot) internal rotation: -8..-2 (toe out)
    ("ankle", "rotation"): FourierCurve(
        -4.652, (1.312, -0.364, -0.248), (2.444, -0.501, 0.024)
    ),
}

# --------------------------------------------------------------------- pelvis (left side)
#: Left-side pelvis angle curves in degrees of the global (left) phase.
PELVIS_CURVES: dict[str, FourierCurve] = {
    # anterior tilt 5 +- 1.5 deg, twice per stride (peaks near 47 % and 97 %)
    "tilt": FourierCurve(5.0, (0.0, 1.2), (0.0, -0.9)),
    # left side up during left stance, peak ~4 deg near 17 %
    "obliquity": FourierCurve(0.0, (2.0,), (3.5,)),
    # left ASIS forward at left initial contact, +-4.1 deg
    "rotation": FourierCurve(0.0, (4.0,), (-1.0,)),
}

#: Pelvis (ASIS midpoint) displacement curves in mm of the global (left) phase, added to
#: the constant-speed forward motion and the mean height.
PELVIS_TRANSLATION_CURVES: dict[str, FourierCurve] = {
    # lateral sway +-20 mm (towards the stance limb, +Y = left), once per stride
    "lateral": FourierCurve(0.0, (0.0,), (20.0,)),
    # vertical bounce -15 cos(4 pi (p - 0.05)) mm: twice per stride, lowest at double
    # support (5 %, 55 %)
    "vertical": FourierCurve(0.0, (0.0, -15.0 * np.cos(4 * np.pi * 0.05)),
                             (0.0, -15.0 * np.sin(4 * np.pi * 0.05))),
}


def limb_phase(phase: np.ndarray | float, side: str) -> np.ndarray:
    """A limb's own phase from the global (left) phase: ``p`` (L) or ``p - 0.5`` (R)."""
    p = np.asarray(phase, dtype=float)
    if side == "L":
        return p
    if side == "R":
        return p - RIGHT_PHASE_SHIFT
    raise ValueError(f"side must be 'L' or 'R'; got {side!r}")


def plug_in_gait_ankle_y(rotation_deg: np.ndarray, plantar_flex_offset: float) -> np.ndarray:
    """Ankle Y (degrees) that Plug-in Gait reports for ankle rotation ``rotation_deg`` (Z).

    Plug-in Gait builds the foot from AJC->TOE and the tibia's flexion axis, then turns it
    by the static plantarflexion offset ``beta`` (rad; the static rotation offset is 0
    here).  Every such foot has, in Vicon's decomposition, ``Y = atan2(-sin(b0) sin(beta),
    cos(b0))`` with ``sin(b0) = sin(Z) / cos(beta)`` on either side: the "inversion"
    output is cross-talk of the foot rotation through the offset, independent of the
    dorsiflexion.
    """
    z = np.radians(np.asarray(rotation_deg, dtype=float))
    b0 = np.arcsin(np.sin(z) / np.cos(plantar_flex_offset))
    return np.degrees(np.arctan2(-np.sin(b0) * np.sin(plantar_flex_offset), np.cos(b0)))


def joint_angle_curves(
    phase: np.ndarray | float, joint: str, plantar_flex_offset: float | None = None
) -> np.ndarray:
    """Clinical angles of ``joint`` at a limb's own ``phase``.

    Args:
        phase: limb phase in cycles (scalar or ``(n,)``).
        joint: ``"hip"``, ``"knee"`` or ``"ankle"``.
        plantar_flex_offset: static plantarflexion offset (rad) of the ankle Y
            (:func:`plug_in_gait_ankle_y`); default: that of the default
            :class:`~fuzzygait.synthetic.leg_model.SubjectGeometry`.

    Returns:
        ``(n, 3)`` degrees: flexion (dorsiflexion), adduction (varus; ankle: Plug-in
        Gait's Y), internal rotation.
    """
    if joint not in JOINTS:
        raise ValueError(f"joint must be one of {JOINTS}; got {joint!r}")
    p = np.atleast_1d(np.asarray(phase, dtype=float))
    if joint != "ankle":
        return np.stack([JOINT_CURVES[(joint, c)](p) for c in COMPONENTS], axis=-1)
    if plantar_flex_offset is None:
        from fuzzygait.synthetic.leg_model import static_offsets

        plantar_flex_offset = static_offsets()["plantarflexion"]
    flexion, rotation = JOINT_CURVES[("ankle", "flexion")](p), JOINT_CURVES[("ankle", "rotation")](p)
    inversion = plug_in_gait_ankle_y(rotation, plantar_flex_offset)
    return np.stack([flexion, inversion, rotation], axis=-1)


def pelvis_angle_curves(phase: np.ndarray | float, side: str = "L") -> np.ndarray:
    """Pelvis angles relative to the lab/progression frame at global ``phase``.

    Returns:
        ``(n, 3)`` degrees ``(tilt, obliquity, rotation)`` with the sign meanings of
        ``side``: for ``"L"`` anterior tilt +, left side up +, left ASIS forward +; for
        ``"R"`` anterior tilt +, right side up +, right ASIS forward + (i.e. the left
        values with obliquity and rotation negated).
    """
    p = np.atleast_1d(np.asarray(phase, dtype=float))
    out = np.stack([PELVIS_CURVES[c](p) for c in ("tilt", "obliquity", "rotation")], axis=-1)
    if side == "R":
        out[:, 1:] *= -1.0
    elif side != "L":
        raise ValueError(f"side must be 'L' or 'R'; got {side!r}")
    return out


def pelvis_translation_curves(phase: np.ndarray | float) -> np.ndarray:
    """Pelvis oscillation ``(n, 2)`` in mm at global ``phase``: lateral (+Y), vertical (+Z)."""
    p = np.atleast_1d(np.asarray(phase, dtype=float))
    return np.stack(
        [PELVIS_TRANSLATION_CURVES["lateral"](p), PELVIS_TRANSLATION_CURVES["vertical"](p)],
        axis=-1,
    )
