"""The CGM 2.4 subject of :mod:`fuzzygait.synthetic.cgm24`: where its markers sit on the
hidden skeleton (:class:`Cgm24Geometry`, the Plug-in Gait subject plus the thigh and shank
clusters, CGM 2.4's TOE/HEE and the forefoot markers), the Hara hip joint centre
(:func:`hara_hjc`) and the tibial torsion the shank is posed with.

The definitions (frames, units, every marker position and the torsion's sign) are in the
:mod:`~fuzzygait.synthetic.cgm24` docstring ("Marker placement", "Tibial torsion").
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.synthetic.leg_model import SubjectGeometry, _side_factor

#: Hip joint centre regressions of :func:`~fuzzygait.synthetic.cgm24.make_cgm24_static` /
#: :func:`~fuzzygait.synthetic.cgm24.make_cgm24_walking`.
HJC_METHODS = ("davis", "hara")
#: Largest tibial torsion the generator takes, rad (a torsion is tens of degrees).
MAX_TIBIAL_TORSION = np.pi / 4


# ----------------------------------------------------------------------------- HJC
def hara_hjc(
    leg_length: float,
    side: str,
    marker_diameter: float = 14.0,
    base_plate: float = 2.0,
) -> np.ndarray:
    """Hara et al. (2016) hip joint centre in the pelvis frame, mm, as pyCGM2 (CGM 2.1+).

    Pelvis frame: origin ASIS midpoint (marker centres), y = RASI -> LASI, x anterior, z
    up.  With ``LL`` = that side's leg length, ``d`` = marker diameter, ``t`` = base plate
    and ``s = +1`` left, ``-1`` right::

        x = 11 - 0.063 LL - d/2 - t
        y = s (8 + 0.086 LL)
        z = -9 - 0.078 LL

    pyCGM2's HJC decorator uses its defaults ``d = 14``, ``t = 2`` mm whatever the
    session's marker diameter (so ``x = 2 - 0.063 LL``); so do the defaults here.
    (pyCGM2 output for LL = 1000 mm: ``(-61, +-94, -87)``.)
    """
    s = _side_factor(side)
    x = 11.0 - 0.063 * leg_length - marker_diameter / 2.0 - base_plate
    y = s * (8.0 + 0.086 * leg_length)
    z = -9.0 - 0.078 * leg_length
    return np.array([x, y, z])


# ----------------------------------------------------------------------------- geometry
@dataclass(frozen=True)
class Cgm24Geometry(SubjectGeometry):
    """:class:`~fuzzygait.synthetic.leg_model.SubjectGeometry` plus the CGM 2.4 markers.

    Local positions are of the left side (the right side mirrors y), mm.

    Attributes:
        hjc: ``"hara"`` or ``"davis"``: where the true hip joint centre is.
        thi_fraction, thi_offset, tib_fraction, tib_offset: as in ``SubjectGeometry``,
            defaults of a real CGM 2.4 session's wand markers (``cgm24`` docstring).
        thap, thad: thigh cluster markers ``(anterior, lateral, fraction)``: ``anterior``
            and ``lateral`` in mm along the thigh's x and ``s y``, ``fraction`` = height
            above the KJC as a fraction of the thigh length.
        tiap, tiad: the same for the shank cluster (height above the AJC / shank length).
        toe_local, hee_local: as in ``SubjectGeometry`` but CGM 2.4's TOE sits on the
            dorsal mid-foot (pyCGM2: "TOE = CUN"), HEE at the same height (so HEE->TOE
            stays parallel to the foot x axis).  TOE is also the mid-foot joint: the
            forefoot rotates about it.
        fmh_local, smh_local, vmh_local: forefoot markers in the hindfoot frame relative
            to the AJC in the static pose, left side (``y < 0`` = medial).
        hara_marker_diameter, hara_base_plate: marker diameter and base plate of the
            Hara regression, mm (pyCGM2's fixed 14 and 2, not the session's diameter).
        tibial_torsion: ``(left, right)`` rad, the angle from the knee flexion axis to
            the ankle axis about the shank's long axis, Nexus' / pyCGM2's sign (negative
            = external; ``cgm24`` docstring, "Tibial torsion"); default none.
    """

    hjc: str = "hara"
    thi_fraction: float = 0.24
    thi_offset: float = 110.0
    tib_fraction: float = 0.47
    tib_offset: float = 108.0
    thap: tuple[float, float, float] = (63.0, -23.0, 0.71)
    thad: tuple[float, float, float] = (80.0, -20.0, 0.33)
    tiap: tuple[float, float, float] = (62.0, -18.0, 0.725)
    tiad: tuple[float, float, float] = (62.0, -9.0, 0.425)
    toe_local: tuple[float, float, float] = (95.0, 0.0, -40.0)
    hee_local: tuple[float, float, float] = (-50.0, 0.0, -40.0)
    fmh_local: tuple[float, float, float] = (150.0, -35.0, -68.0)
    smh_local: tuple[float, float, float] = (150.0, -5.0, -60.0)
    vmh_local: tuple[float, float, float] = (135.0, 38.0, -70.0)
    hara_marker_diameter: float = 14.0
    hara_base_plate: float = 2.0
    tibial_torsion: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if self.hjc not in HJC_METHODS:
            raise ParameterError(f"hjc must be one of {HJC_METHODS}; got {self.hjc!r}")
        torsion = np.asarray(self.tibial_torsion, dtype=float)
        if torsion.shape != (2,) or not np.all(np.abs(torsion) <= MAX_TIBIAL_TORSION):
            raise ParameterError(
                f"tibial_torsion must be (left, right) in rad within ±{MAX_TIBIAL_TORSION:.3f}; "
                f"got {self.tibial_torsion!r}"
            )

    def torsion(self, side: str) -> float:
        """The tibial torsion of ``side``, rad."""
        return float(self.tibial_torsion[0 if _side_factor(side) > 0 else 1])

    @property
    def has_torsion(self) -> bool:
        """Either tibia is twisted."""
        return any(t != 0.0 for t in self.tibial_torsion)

    def knee_with_torsion(self, knee: np.ndarray, side: str) -> np.ndarray:
        """Knee angles ``(n, 3)`` (deg) from the thigh to the posed (ankle-axis) shank:
        ``knee`` (thigh to the knee-axis frame) with the torsion added to the rotation,
        since ``R_knee @ R_z(-s τ)`` is ``R_z(rs r) @ R_z(rs τ)`` in the knee's sequence
        (``rs = -s``)."""
        out = np.array(knee, dtype=float)
        out[:, 2] += np.degrees(self.torsion(side))
        return out

    def hjc_local(self, side: str) -> np.ndarray:
        """True hip joint centre of ``side`` in the pelvis frame (``hjc`` regression), mm."""
        if self.hjc == "hara":
            return hara_hjc(
                self.leg_length, side, self.hara_marker_diameter, self.hara_base_plate
            )
        return super().hjc_local(side)

    def height_shift(self) -> float:
        """Standing-height difference to the Davis (Plug-in Gait) subject, mm (<= 0 Hara)."""
        return self.standing_pelvis_height() - replace(self, hjc="davis").standing_pelvis_height()

    def foot_local(self, side: str) -> dict[str, np.ndarray]:
        """HEE, TOE, FMH, SMH, VMH of ``side`` in the static hindfoot frame (AJC origin)."""
        mirror = np.array([1.0, _side_factor(side), 1.0])
        return {
            "HEE": np.asarray(self.hee_local, dtype=float) * mirror,
            "TOE": np.asarray(self.toe_local, dtype=float) * mirror,
            "FMH": np.asarray(self.fmh_local, dtype=float) * mirror,
            "SMH": np.asarray(self.smh_local, dtype=float) * mirror,
            "VMH": np.asarray(self.vmh_local, dtype=float) * mirror,
        }
