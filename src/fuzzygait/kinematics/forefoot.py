"""The CGM 2.4 forefoot: its anatomical frame, joint centre and static calibration.

CGM 2.4 (Leboeuf et al. 2019; pyCGM2's documentation) splits the Plug-in Gait foot in
two.  The **hindfoot** is the Plug-in Gait foot (TOE, AJC, the tibia's ankle axis and
the static offsets; CGM 2.4 puts TOE on the dorsal mid-foot), so the ankle angles are
shank -> hindfoot as in CGM 2.3.  The **forefoot** is built from TOE and the metatarsal
heads FMH (first), SMH (second) and VMH (fifth) of the static trial (``s = +1`` left,
``-1`` right; every axis in the Plug-in Gait foot orientation, x dorsal, y left, z
posterior along the foot):

* forefoot joint centre: ``n = unit(VMH - TOE) × unit(FMH - TOE)`` (normal to the
  TOE-VMH-FMH plane, pointing down on the left foot, up on the right), ``FJC = TOE + s d
  n`` with ``d`` the marker diameter.  As in pyCGM2's construction the cross product of
  the two unit vectors is *not* normalised, so FJC lies ``d sin θ`` below the TOE marker
  centre, ``θ`` the FMH-TOE-VMH angle (about 0.93 d for a typical foot);
* technical frame [FMH, TOE, VMH]: z = ``unit(TOE - FMH)``, x = ``-s unit(z × (VMH -
  FMH))``, y = z × x; the *virtual* second metatarsal head vSMH is SMH projected onto
  the plane of that frame's y and z axes through TOE;
* anatomical frame [vSMH, FJC, VMH]: z = ``unit(FJC - vSMH)``, x = ``-s unit(z × (VMH -
  vSMH))``, y = z × x, origin vSMH.

The static calibration (:func:`calibrate_forefoot`) stores TOE, FMH, SMH and VMH in that
anatomical frame (means over the static frames), and the FJC in the hindfoot frame
(origin AJC).  In a dynamic trial the forefoot is the least-squares rigid fit of its
visible markers (at least three of the four; :func:`~fuzzygait.kinematics.rigid.fit_rigid`)
and the FJC moves with the hindfoot.  ``L/RForeFootAngles`` are the forefoot relative
to the hindfoot with the ankle's decomposition and signs but no 90° offset (both frames
run along the foot): X = forefoot dorsiflexion (+ toes up), Y = rotation about the
forefoot's long axis, Z = rotation about the floating axis (pyCGM2's Y-X-Z sequence,
components in the order [0, 2, 1], signs left (-, -, -), right (-, +, +)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzygait.core.errors import MarkerError
from fuzzygait.core.options import Option
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.rigid import MIN_MARKERS
from fuzzygait.kinematics.segments import side_sign
from fuzzygait.kinematics.vectors import cross, frame_from_axes, to_lab, to_local, unit

#: Forefoot tracking markers (after the side letter), CGM 2.4.
FOREFOOT_MARKERS: tuple[str, ...] = ("TOE", "FMH", "SMH", "VMH")


@dataclass(frozen=True)
class ForefootConstruction:
    """The CGM 2.4 forefoot of one trial and side, per frame.

    Attributes:
        fjc: ``(n, 3)`` mm, the forefoot joint centre.
        vsmh: ``(n, 3)`` mm, the virtual second metatarsal head (the frame's origin).
        frame: ``(n, 3, 3)`` anatomical forefoot axes (columns x dorsal, y left, z
            posterior) in lab coordinates.
    """

    fjc: np.ndarray
    vsmh: np.ndarray
    frame: np.ndarray


def _plane_frame(along_z: np.ndarray, towards_lateral: np.ndarray, side: str) -> np.ndarray:
    """Frame with z = ``unit(along_z)``, x = ``-s unit(z × towards_lateral)``, y = z × x."""
    z = unit(along_z)
    x = -side_sign(side) * unit(cross(z, towards_lateral))
    return frame_from_axes(x, cross(z, x), z)


def forefoot_construction(
    toe: np.ndarray, fmh: np.ndarray, smh: np.ndarray, vmh: np.ndarray, side: str, marker_diameter: float
) -> ForefootConstruction:
    """The CGM 2.4 forefoot joint centre and anatomical frame (module docstring).

    Args:
        toe, fmh, smh, vmh: ``(n, 3)`` mm, lab frame.
        side: ``"L"`` or ``"R"``.
        marker_diameter: mm, the TOE-to-FJC distance.
    """
    normal = cross(unit(vmh - toe), unit(fmh - toe))  # |normal| = sin(FMH-TOE-VMH angle), as pyCGM2
    fjc = toe + side_sign(side) * marker_diameter * normal
    technical = _plane_frame(toe - fmh, vmh - fmh, side)
    local = to_local(technical, toe, smh)
    local[:, 0] = 0.0
    vsmh = to_lab(technical, toe, local)
    return ForefootConstruction(fjc, vsmh, _plane_frame(fjc - vsmh, vmh - vsmh, side))


def _seen_mean(local: np.ndarray) -> np.ndarray:
    seen = np.all(np.isfinite(local), axis=1)
    return np.asarray(local[seen].mean(axis=0)) if seen.any() else np.full(3, np.nan)


def calibrate_forefoot(
    static: Trial, side: str, hindfoot: np.ndarray, ajc: np.ndarray, marker_diameter: float
) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
    """Calibrate one forefoot on the static trial.

    Args:
        static: the static trial, mm; needs TOE, FMH, SMH and VMH of ``side``.
        side: ``"L"`` or ``"R"``.
        hindfoot: ``(n, 3, 3)`` the static trial's hindfoot (Plug-in Gait foot) frames.
        ajc: ``(n, 3)`` mm, its ankle joint centres (the hindfoot origin).
        marker_diameter: mm.

    Returns:
        ``(labels, local, fjc)``: the forefoot markers, their ``(4, 3)`` mm positions in
        the forefoot anatomical frame (origin vSMH) and the FJC ``(3,)`` mm in the
        hindfoot frame (origin AJC), means over the frames where they are seen.

    Raises:
        MarkerError: a forefoot marker absent from the static trial (named), or never seen.
    """
    labels = tuple(side + m for m in FOREFOOT_MARKERS)
    missing = [m for m in labels if not static.has_marker(m)]
    if missing:
        raise MarkerError(
            f"{static.name}: the CGM 2.4 forefoot calibration needs {', '.join(labels)}; "
            f"{', '.join(missing)} missing (label them, or use {Option.MODEL} cgm2.3)"
        )
    toe, fmh, smh, vmh = (static.marker(m) for m in labels)
    construction = forefoot_construction(toe, fmh, smh, vmh, side, marker_diameter)
    local = np.stack([_seen_mean(to_local(construction.frame, construction.vsmh, static.marker(m))) for m in labels])
    fjc = _seen_mean(to_local(hindfoot, ajc, construction.fjc))
    if not (np.all(np.isfinite(local)) and np.all(np.isfinite(fjc))):
        raise MarkerError(f"{static.name}: no static frame shows the {side} hindfoot and {', '.join(labels)} together")
    assert len(labels) >= MIN_MARKERS
    return labels, local, fjc


__all__ = ["FOREFOOT_MARKERS", "ForefootConstruction", "calibrate_forefoot", "forefoot_construction"]
