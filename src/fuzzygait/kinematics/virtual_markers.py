"""Vicon-style virtual markers of the Plug-in Gait segments and joint centres.

Vicon Nexus exports each segment frame as four points: origin ``O`` and the tips of the
x, y and z axes ``A`` (anterior), ``L`` (lateral, i.e. +y, which points medially on the
right leg) and ``P`` (proximal); the axes are drawn with the segment's length, not a
fixed 100 mm.  The lengths and origins below were measured on Nexus output
(``Movement_trial.c3d`` and ``Static_trial.c3d``; they agree to float32 precision):

=======  ==================================  ==========================================
prefix   origin                              axis length
=======  ==================================  ==========================================
PEL      midpoint of the hip joint centres   distance between the hip joint centres
L/RFE    KJC                                 ``|HJC - KJC|`` (per frame)
L/RTI    AJC (untorsioned tibia axes)        ``|KJC - AJC| - KneeWidth / 5`` (per frame)
L/RFO    AJC - R_foot @ (L/169)(11, -11 s,   ``L`` = trial mean of ``|HEE - TOE|`` minus
         120) (foot axes)                    the marker radius
L/RTO    FO origin - (L/3) z_foot            ``L / 3``
=======  ==================================  ==========================================

(``s = +1`` left, ``-1`` right.)  The foot markers need HEE; without it they are not
produced.  Joint centres are exported as ``LHJC``, ``RHJC``, ``LKJC``, ``RKJC``,
``LAJC``, ``RAJC``.  All positions in mm, lab frame, ``(n, 3)``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fuzzygait.kinematics.segments import side_sign
from fuzzygait.kinematics.vectors import norm, to_lab

#: Axis-tip suffixes in x, y, z order.
AXIS_SUFFIXES = ("A", "L", "P")
#: Foot "bone" shape used by Nexus: AJC in foot coordinates relative to FOO is
#: ``L / 169 * (11, -11 s, 120)``.
FOOT_AJC_LOCAL = np.array([11.0, -11.0, 120.0]) / 169.0


def segment_markers(
    prefix: str, origin: np.ndarray, frame: np.ndarray, length: np.ndarray | float
) -> dict[str, np.ndarray]:
    """``{prefix+"O": origin, prefix+"A": origin + length*x, "L": ... y, "P": ... z}``.

    Args:
        prefix: e.g. ``"LFE"``.
        origin: ``(n, 3)`` mm.
        frame: ``(n, 3, 3)`` (columns = axes).
        length: axis length in mm, scalar or ``(n,)``.
    """
    scale = np.broadcast_to(np.asarray(length, dtype=float), origin.shape[:1])[:, None]
    out = {prefix + "O": origin}
    for i, suffix in enumerate(AXIS_SUFFIXES):
        out[prefix + suffix] = origin + scale * frame[:, :, i]
    return out


def foot_bone_length(hee: np.ndarray, toe: np.ndarray, marker_radius: float) -> float:
    """Nexus foot length: mean ``|HEE - TOE|`` over the frames where both are seen, minus
    the marker radius (mm); NaN if they are never seen together."""
    d = norm(hee - toe)
    d = d[np.isfinite(d)]
    return float(d.mean() - marker_radius) if d.size else float("nan")


def foot_markers(side: str, ajc: np.ndarray, foot: np.ndarray, length: float) -> dict[str, np.ndarray]:
    """``L/RFO*`` and ``L/RTO*`` markers of one foot (see the module table)."""
    local = FOOT_AJC_LOCAL * np.array([1.0, side_sign(side), 1.0]) * length
    origin = to_lab(foot, ajc, -local)
    out = segment_markers(side + "FO", origin, foot, length)
    out.update(segment_markers(side + "TO", origin - (length / 3.0) * foot[:, :, 2], foot, length / 3.0))
    return out


def pelvis_markers(hjc_left: np.ndarray, hjc_right: np.ndarray, pelvis: np.ndarray) -> dict[str, np.ndarray]:
    """``PELO/PELA/PELL/PELP``."""
    return segment_markers("PEL", 0.5 * (hjc_left + hjc_right), pelvis, norm(hjc_left - hjc_right))


def thigh_markers(side: str, hjc: np.ndarray, kjc: np.ndarray, thigh: np.ndarray) -> dict[str, np.ndarray]:
    """``L/RFEO...``."""
    return segment_markers(side + "FE", kjc, thigh, norm(hjc - kjc))


def tibia_markers(
    side: str, kjc: np.ndarray, ajc: np.ndarray, tibia: np.ndarray, knee_width: float
) -> dict[str, np.ndarray]:
    """``L/RTIO...`` (untorsioned tibia)."""
    return segment_markers(side + "TI", ajc, tibia, norm(kjc - ajc) - knee_width / 5.0)


# ---------------------------------------------------------------------------- reading back
def frame_from_virtual_markers(
    virtual: Mapping[str, np.ndarray], prefix: str
) -> tuple[np.ndarray, np.ndarray]:
    """Origin ``(n, 3)`` and frame ``(n, 3, 3)`` of the segment ``prefix`` (e.g. ``"LFE"``).

    The axis directions ``A - O``, ``L - O``, ``P - O`` are made into the nearest rotation
    matrix (polar decomposition), which matters for files that store points with little
    precision (e.g. integer-scaled C3D).  Frames with a missing point are NaN.
    """
    origin = np.asarray(virtual[prefix + "O"], dtype=float)
    axes = np.stack([np.asarray(virtual[prefix + s], dtype=float) - origin for s in AXIS_SUFFIXES], axis=-1)
    frames = np.full(axes.shape, np.nan)
    ok = np.all(np.isfinite(axes), axis=(1, 2))
    if ok.any():
        u, _, vt = np.linalg.svd(axes[ok])
        frames[ok] = u @ vt
    return origin, frames


def angles_from_virtual_markers(virtual: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Plug-in Gait angles from Vicon segment virtual markers (``PELO``..., ``LFEO``...).

    Computes every output whose segments are present: pelvis and foot progression need
    ``PEL*`` (the progression frame comes from the travel of ``PELO``), hip ``PEL*`` and
    ``L/RFE*``, knee ``L/RFE*`` and ``L/RTI*``, ankle ``L/RTI*`` and ``L/RFO*``.  Vicon
    exports the untorsioned tibia, so the ankle angles are right only when the tibial
    torsion is 0.

    Args:
        virtual: name -> ``(n, 3)`` positions, mm (e.g. ``trial.outputs``).

    Returns:
        ``{name: (n, 3) degrees}`` in the order of :data:`~fuzzygait.kinematics.ANGLE_NAMES`.
    """
    from fuzzygait.kinematics.angles import joint_angles
    from fuzzygait.kinematics.model import ANGLE_NAMES  # model imports this module
    from fuzzygait.kinematics.progression import progression_frame

    def have(prefix: str) -> bool:
        return all(prefix + s in virtual for s in ("O", *AXIS_SUFFIXES))

    frames = {p: frame_from_virtual_markers(virtual, p)[1] for p in
              ["PEL"] + [s + seg for s in "LR" for seg in ("FE", "TI", "FO")] if have(p)}  # fmt: skip
    out: dict[str, np.ndarray] = {}
    progression = None
    if "PEL" in frames:
        progression = progression_frame(np.asarray(virtual["PELO"], dtype=float), frames["PEL"][:, :, 0])
    for side in "LR":
        pairs = {
            "Pelvis": (progression, frames.get("PEL")),
            "Hip": (frames.get("PEL"), frames.get(side + "FE")),
            "Knee": (frames.get(side + "FE"), frames.get(side + "TI")),
            "Ankle": (frames.get(side + "TI"), frames.get(side + "FO")),
            "FootProgress": (progression, frames.get(side + "FO")),
        }
        for joint, (proximal, distal) in pairs.items():
            if proximal is not None and distal is not None:
                out[side + joint + "Angles"] = joint_angles(proximal, distal, joint, side)
    return {name: out[name] for name in ANGLE_NAMES if name in out}
