"""Synthetic CGM 2.4 sessions (static + walking) with exactly known angles and centres.

The CGM 2.4 marker set (Leboeuf et al. 2019; thesis Figure 3.8), prefix ``L``/``R``:
pelvis ASI/PSI; thigh THAP, THAD, THI, KNE; shank TIAP, TIAD, TIB, ANK; foot HEE, TOE,
FMH, SMH, VMH; the medial KNM and MED in the static trial only.  Every marker sits
rigidly on the hidden skeleton of :mod:`fuzzygait.synthetic.leg_model` (same pelvis,
thigh, shank and foot frames, angle curves, timing and sign conventions as the Plug-in
Gait trials), plus a forefoot.  Nothing is solved with :mod:`fuzzygait.kinematics` (the
code this data tests); the CGM 2.x definitions used are pyCGM2's (as summarised in the
project's CGM 2.x notes: Hara HJC, medial KJC/AJC, CGM 2.4 forefoot).

Frames and units
----------------
Lab: X = walking direction, Y = left, Z = up; mm, degrees.  Segment frames as in
:mod:`~fuzzygait.synthetic.leg_model`: pelvis/thigh/shank x anterior, y left, z
proximal; foot (= the **hindfoot**, pyCGM2's "Left/Right Foot") x anterior along the
foot, y left, z dorsal; origins ASIS midpoint, HJC, KJC, AJC.  ``s = +1`` left, ``-1``
right; "lateral" = ``+s y``, "medial" = ``-s y``; ``r`` = marker radius (7 mm).  Local
positions below are of the **left** side (the right side mirrors y); ``L_t`` = 410 mm,
``L_s`` = 395 mm = thigh (HJC-KJC) and shank (KJC-AJC) lengths.

Marker placement (default :class:`Cgm24Geometry`)
-------------------------------------------------
* **LASI/RASI/LPSI/RPSI**: as Plug-in Gait, pelvis frame: ASIS ``(0, ±125, 0)``, PSIS
  ``(-160, ±45, 0)``.
* **True hip joint centre** (``hjc=``), pelvis frame: ``"hara"`` (default) -- Hara et al.
  2016 as pyCGM2's CGM 2.1+ applies it (:func:`hara_hjc`): ``(11 - 0.063 LL - 7 - 2, s (8
  + 0.086 LL), -9 - 0.078 LL)`` with ``LL`` the side's leg length and pyCGM2's fixed 14
  mm marker / 2 mm base plate, = ``(-54.7, ±85.4, -79.2)`` for LL = 900; ``"davis"`` --
  Plug-in Gait's Davis regression (:func:`~fuzzygait.synthetic.leg_model.davis_hjc`),
  ``(-46.8, ±82.7, -96.6)``.  The walking trial is lowered by
  :meth:`Cgm24Geometry.height_shift` (-17.385 mm for Hara, 0 for Davis) and the static
  trial stands with its soles on the floor.
* Cluster layout: that of a real CGM 2.4 session's clusters (the shared Qualisys
  session's static cluster calibration, mean of both sides, heights as a fraction of its
  segment lengths, rounded; its walking trial's markers in its segment frames agree to
  about 20 mm) -- a lateral wand marker (THI, TIB) about 110 mm out and two anterior
  markers on each segment.  An earlier, more compact layout (THI/TIB 75/65 mm lateral,
  the shank's anterior pair 12 and 28 mm lateral: a shank cross-section of rms 26 mm
  against the real session's 41-49 mm) let a Table 3.1 ball turn the shank cluster about
  its long axis by 74 deg.
* Thigh (thigh frame, origin KJC): THI ``(0, 110, 0.24 L_t)`` (in the thigh's y-z plane,
  ThighRotation 0) and KNE ``(0, KneeWidth/2 + r, 0)`` (as Plug-in Gait); **THAP** ``(63,
  -23, 0.71 L_t)`` (anterior, a little medial); **THAD** ``(80, -20, 0.33 L_t)``.  Static
  **KNM** ``(0, -(KneeWidth/2 + r), 0)``: KNE and KNM on the knee flexion axis (thigh y),
  symmetric about the true KJC, so their midpoint -- and pyCGM2's ``KNE + (KneeWidth +
  d)/2 unit(KNM - KNE)`` -- is the KJC.
* Shank (shank frame, origin AJC): TIB ``(0, 108, 0.47 L_s)`` and ANK ``(0, AnkleWidth/2
  + r, 0)`` (as Plug-in Gait); **TIAP** ``(62, -18, 0.725 L_s)`` and **TIAD** ``(62, -9,
  0.425 L_s)`` (on the tibial crest); static **MED** ``(0, -(AnkleWidth/2 + r), 0)``
  (ankle axis = shank y, no tibial torsion): the ANK-MED midpoint is the AJC.  Smallest
  singular value of the centred 4-marker cluster: 21.9 mm (thigh), 13.5 mm (shank).
* Hindfoot (foot frame, origin AJC): CGM 2.4's TOE sits on the dorsal mid-foot (pyCGM2
  "TOE = CUN"): **TOE** ``(95, 0, -40)``; **HEE** ``(-50, 0, -40)`` (same height, so
  HEE->TOE is the foot's x axis, as pyCGM2's anatomical hindfoot needs); the sole is 90
  mm below the AJC (TOE and HEE 50 mm above the floor standing).  These differ from the
  Plug-in Gait subject's TOE ``(140, 0, -60)``/HEE ``(-50, 0, -60)``; the static
  plantarflexion offset follows (0.398 rad) and is in the parameters.
* Forefoot, positions in the hindfoot frame of the static pose: **FMH** ``(150, -35,
  -68)`` (medial, 1st metatarsal head), **SMH** ``(150, -5, -60)`` (dorsum of the 2nd
  metatarsal head), **VMH** ``(135, 38, -70)`` (lateral, 5th metatarsal head).  The
  forefoot rotates about the TOE marker centre (the mid-foot joint; pyCGM2 builds both
  foot segments from TOE, so it must belong to both): ``m(t) = TOE(t) + R_forefoot(t)
  Q^T (m_static - TOE_static)``.

Forefoot definition
-------------------
``R_forefoot = R_hindfoot @ forefoot_rotation(ForeFootAngles)`` *is* pyCGM2's CGM 2.4
forefoot anatomical frame (axes written in this package's foot convention), so the
ForeFootAngles of the truth are exactly what pyCGM2's construction yields on the exact
markers:

* FJC = ``TOE - 14 z`` with ``z = -/+ unit(unit(VMH - TOE) x unit(FMH - TOE))`` (L/R), a
  point fixed in the hindfoot (truth columns ``L/RFJC_*``);
* technical frame [FMH, TOE, VMH] (``Z = unit(TOE - FMH)``, ``X = -/+ unit(Z x (VMH -
  FMH))``); vSMH = SMH projected onto the TOE-FMH-VMH plane;
* anatomical frame [vSMH, FJC, VMH]: ``Z = unit(FJC - vSMH)``, ``X = -/+ unit(Z x (VMH -
  vSMH))``, ``Y = Z x X`` (pyCGM2 axes: X dorsal, Y left, Z posterior);
* ForeFootAngles: ``R_rel = R_hindfoot^T R_forefoot`` (pyCGM2 axes), intrinsic Y-X-Z
  Cardan ``(e1, e2, e3)``, left ``(-e1, -e3, -e2)``, right ``(-e1, +e3, +e2)`` = this
  package's ankle convention (:func:`forefoot_rotation`).

``Q`` (:func:`forefoot_static_axes`) is that frame in the static pose; its angles
(:func:`neutral_forefoot_angles`, ``(-17.831, -5.038, 4.561)`` deg on both sides) are
the static trial's ForeFootAngles.  Walking: ``ForeFootAngles = neutral +``
:data:`FOREFOOT_DEVIATION_CURVES` (a few degrees, limb phase).  pyCGM2's own sign
descriptor for the forefoot carries a "TODO check" in its source; the convention above is
the one written there.

Tibial torsion (opt-in, ``Cgm24Geometry(tibial_torsion=(τ_L, τ_R))``, rad; default 0)
--------------------------------------------------------------------------------------
The tibia's ankle axis is its knee axis turned about the tibia's long axis: the posed
shank frame (``R_shank``, whose y axis carries ANK, MED, TIB, TIAP, TIAD and the foot) is
``R_knee @ R_z(-s τ)`` with ``R_knee`` the frame the knee angles carry from the thigh
(pyCGM2's "proximal shank", Nexus' untorsioned tibia).  It is posed by adding ``τ`` (deg)
to the knee's rotation curve (static trial included: its knee rotation is ``τ``), so the
truth knee angles are thigh -> ``R_shank``, what CGM 2.x's knee reports; ``τ < 0`` turns
the ankle axis externally (lateral malleolus posterior).  KNE/KNM stay on the thigh's y
axis and ANK/MED on the shank's, so in the static trial the angle between the two
flexion axes about the shank's long axis -- pyCGM2's tibial torsion, ``s (φ - 90°)``
with ``φ`` the azimuth of the thigh's y axis in the shank's x-y plane -- is ``τ``.  The
subject parameters keep ``TibialTorsion`` 0: the CGM 2.x static calibration must find it
from KNM/MED.  The posed hindfoot is built on the shank's own ankle axis as above (what
pyCGM2's CGM 2.4 hindfoot takes); pyCGM2's **CGM 2.3** foot instead takes the knee axis
``y_knee`` and a static correction: ``U(TOE, AJC, y_knee) R_z(δ) R_y R_x`` with ``U`` the
uncorrected foot (z from TOE to AJC, x = ``unit(y × z)``) and ``R_z(δ) = U(y_knee)^T
U(y_shank)`` in the static pose.  Both share the long axis ``z_u = unit(AJC - TOE)``; the
CGM 2.3 foot is the posed hindfoot turned about ``z_u`` by ``δ - γ(t)``, ``γ`` the angle
about ``z_u`` from ``x(y_knee)`` to ``x(y_shank)`` (``δ`` = ``γ`` of the static pose), which
:func:`cgm23_foot_rotation` computes; ``make_cgm24_walking(foot_truth="cgm2.3")`` gives
its ankle and foot-progression angles as the truth (the markers are the same).

Truth table (walking)
---------------------
``frame``, ``time_s``, :func:`~fuzzygait.synthetic.generate.angle_columns` (pelvis,
hip, knee, ankle = shank -> hindfoot, with the conventions of
:mod:`~fuzzygait.synthetic.leg_model`; the pelvis angles are Plug-in Gait's
tilt-obliquity-rotation sequence, not CGM 2.x's rotation-obliquity-tilt),
:func:`~fuzzygait.synthetic.generate.joint_centre_columns` (HJC at the chosen
regression, KJC, AJC; mm), :func:`forefoot_angle_columns` (``L/RForeFootAngles_X/Y/Z``,
deg), :func:`fjc_columns` (``L/RFJC_X/Y/Z``, pyCGM2's forefoot joint centre, mm) and
``L/RFootProgressAngles_X/Y/Z`` (the hindfoot in the lab = progression frame, Vicon's
convention: :func:`~fuzzygait.synthetic.leg_model.foot_progression_angles`; deg).  With
``foot_truth="cgm2.3"`` the ankle and foot-progression columns are those of the CGM 2.3
foot (section above; the same as the hindfoot's without torsion).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.trial import Trial
from fuzzygait.synthetic.gait_curves import (
    JOINTS,
    STRIDE_TIME_S,
    FourierCurve,
    limb_phase,
)
from fuzzygait.synthetic.generate import (
    JOINT_CENTRE_NAMES,
    LEAD_IN_CYCLES,
    LEAD_OUT_CYCLES,
    SEGMENT_ANGLE_NAMES,
    SUBJECT_NAME,
    WALKING_SPEED_MM_S,
    gait_events,
    walking_state,
)
from fuzzygait.synthetic.leg_model import (
    SIDES,
    Pose,
    SubjectGeometry,
    _apply,
    _side_factor,
    foot_progression_angles,
    joint_angles_from_rotation,
    joint_rotation,
    pose_lower_body,
    rot_z,
)

#: Hip joint centre regressions of :func:`make_cgm24_static` / :func:`make_cgm24_walking`.
HJC_METHODS = ("davis", "hara")

#: Per-side marker labels of the CGM 2.4 dynamic trial, in column order.
CGM24_SIDE_LABELS: tuple[str, ...] = (
    "THAP", "THAD", "THI", "KNE", "TIAP", "TIAD", "TIB", "ANK",
    "HEE", "TOE", "FMH", "SMH", "VMH",
)  # fmt: skip
#: CGM 2.4 dynamic-trial labels, in column order.
CGM24_DYNAMIC_LABELS: tuple[str, ...] = (
    ("LASI", "RASI", "LPSI", "RPSI")
    + tuple("L" + m for m in CGM24_SIDE_LABELS)
    + tuple("R" + m for m in CGM24_SIDE_LABELS)
)
#: Medial markers of the CGM 2.4 static trial only.
CGM24_MEDIAL_LABELS: tuple[str, ...] = ("LKNM", "RKNM", "LMED", "RMED")
#: CGM 2.4 static-trial labels, in column order.
CGM24_STATIC_LABELS: tuple[str, ...] = CGM24_DYNAMIC_LABELS + CGM24_MEDIAL_LABELS
#: Markers of the forefoot segment; TOE, the mid-foot joint (rotation centre), is on the
#: hindfoot too, HEE only on the hindfoot.
FOREFOOT_MARKERS: tuple[str, ...] = ("TOE", "FMH", "SMH", "VMH")

#: Forefoot-marker excursion from the static pose during walking: ForeFootAngles
#: (degrees, ``(X, Y, Z)``) minus the static (neutral) ones, as functions of the limb's
#: own phase; a few degrees, smooth, periodic.
FOREFOOT_DEVIATION_CURVES: tuple[FourierCurve, FourierCurve, FourierCurve] = (
    FourierCurve(1.0, (1.5, -1.0), (-2.5, 0.5)),
    FourierCurve(-0.5, (1.0, 0.3), (2.0, -0.4)),
    FourierCurve(0.5, (-1.5, 0.5), (1.0, 0.2)),
)
#: Diameter pyCGM2 uses to put the forefoot joint centre below TOE, mm (its default).
FJC_MARKER_DIAMETER = 14.0
#: ``foot_truth`` values of :func:`make_cgm24_walking`.
FOOT_TRUTHS = ("hindfoot", "cgm2.3")
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
            defaults of a real CGM 2.4 session's wand markers (module docstring).
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
            = external; module docstring, "Tibial torsion"); default none.
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


def _cluster_local(spec: tuple[float, float, float], length: float, s: float) -> np.ndarray:
    anterior, lateral, fraction = spec
    return np.array([anterior, s * lateral, fraction * length])


# ----------------------------------------------------------------------------- forefoot
def forefoot_rotation(angles: np.ndarray, side: str) -> np.ndarray:
    """Forefoot relative to hindfoot, ``(n, 3, 3)``, from ForeFootAngles ``(n, 3)`` (deg).

    pyCGM2's CGM 2.4 definition (``R_rel = R_hindfoot^T R_forefoot`` of its anatomical
    frames, intrinsic Y-X-Z Cardan ``(e1, e2, e3)``, left output ``(-e1, -e3, -e2)``, right
    ``(-e1, +e3, +e2)``; both frames with Z along the foot, posterior, X dorsal, Y left)
    written in this package's foot frames (x anterior, y left, z dorsal = pyCGM2's frame
    turned by ``R_y(90 deg)``) is the ankle's Y-Z-X sequence with the ankle's signs:
    ``R_y(-X) @ R_z(-s Z) @ R_x(s Y)`` (``s = +1`` left, ``-1`` right), i.e.
    :func:`~fuzzygait.synthetic.leg_model.joint_rotation` with ``joint="ankle"``.  So X
    + = forefoot dorsiflexion (toes up), Y + = the forefoot's lateral border up
    (eversion-like, as the Plug-in Gait ankle Y), Z + = forefoot adduction (toes medial).
    """
    a = np.atleast_2d(np.asarray(angles, dtype=float))
    return joint_rotation(a[:, 0], a[:, 1], a[:, 2], side, "ankle")


def forefoot_angles_from_rotation(rotation: np.ndarray, side: str) -> np.ndarray:
    """ForeFootAngles ``(n, 3)`` in degrees of ``R_hindfoot^T @ R_forefoot``.

    The exact inverse of :func:`forefoot_rotation` (for ``|Y| < 90`` deg).
    """
    return joint_angles_from_rotation(rotation, side, "ankle")


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


#: pyCGM2's foot axes (X dorsal, Y left, Z posterior) in this package's foot axes (x
#: anterior, y left, z dorsal): ``R_pyCGM2 = R_here @ _PYCGM2_FOOT_AXES``.
_PYCGM2_FOOT_AXES = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


def pycgm2_forefoot_frame(
    toe: np.ndarray, fmh: np.ndarray, vmh: np.ndarray, smh: np.ndarray, side: str,
    diameter: float = FJC_MARKER_DIAMETER,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """pyCGM2's CGM 2.4 forefoot construction on one set of marker positions (3-vectors).

    * FJC: ``n = unit(VMH - TOE) x unit(FMH - TOE)``, ``z = -n`` (left) / ``+n`` (right),
      ``FJC = TOE - diameter z``;
    * technical frame [FMH, TOE, VMH]: ``Z = unit(TOE - FMH)``, ``X = -/+ unit(Z x (VMH -
      FMH))`` (left/right), ``Y = Z x X``; vSMH = SMH with its local X set to 0 (SMH
      projected onto the TOE-FMH-VMH plane);
    * anatomical frame [vSMH, FJC, VMH]: ``Z = unit(FJC - vSMH)``, ``X = -/+ unit(Z x
      (VMH - vSMH))``, ``Y = Z x X``, origin vSMH.

    Returns ``(fjc, vsmh, axes)`` with ``axes`` the anatomical frame in **this package's
    foot-axis convention** (columns x anterior, y left, z dorsal: pyCGM2's ``[X Y Z] @
    _PYCGM2_FOOT_AXES.T``), in the coordinates the points are given in.
    """
    sign = -_side_factor(side)  # pyCGM2: ZXiY (X = -a2) on the left, ZXY on the right
    n = np.cross(_unit(vmh - toe), _unit(fmh - toe))
    fjc = toe - diameter * (sign * n)

    def frame(a1: np.ndarray, v: np.ndarray) -> np.ndarray:
        z = _unit(a1)
        x = sign * _unit(np.cross(z, v))
        return np.stack([x, np.cross(z, x), z], axis=-1)

    technical = frame(toe - fmh, vmh - fmh)
    local = technical.T @ (smh - toe)
    vsmh = toe + technical @ np.array([0.0, local[1], local[2]])
    anatomical = frame(fjc - vsmh, vmh - vsmh)
    return fjc, vsmh, anatomical @ _PYCGM2_FOOT_AXES.T


def forefoot_static_axes(geometry: Cgm24Geometry, side: str) -> np.ndarray:
    """``Q``: pyCGM2's forefoot anatomical frame in the static hindfoot frame, ``(3, 3)``."""
    local = geometry.foot_local(side)
    return pycgm2_forefoot_frame(local["TOE"], local["FMH"], local["VMH"], local["SMH"], side)[2]


def fjc_local(geometry: Cgm24Geometry, side: str) -> np.ndarray:
    """pyCGM2's forefoot joint centre in the hindfoot frame (AJC origin), mm."""
    local = geometry.foot_local(side)
    return pycgm2_forefoot_frame(local["TOE"], local["FMH"], local["VMH"], local["SMH"], side)[0]


def neutral_forefoot_angles(geometry: Cgm24Geometry | None, side: str) -> np.ndarray:
    """ForeFootAngles ``(3,)`` (deg) of the static pose (forefoot markers as placed)."""
    g = geometry or Cgm24Geometry()
    return forefoot_angles_from_rotation(forefoot_static_axes(g, side)[None], side)[0]


def forefoot_angle_curves(
    phase: np.ndarray | float, side: str, geometry: Cgm24Geometry | None = None
) -> np.ndarray:
    """Known ForeFootAngles ``(n, 3)`` (deg) at the global ``phase`` for ``side``:
    :func:`neutral_forefoot_angles` + :data:`FOREFOOT_DEVIATION_CURVES`."""
    p = limb_phase(np.atleast_1d(np.asarray(phase, dtype=float)), side)
    deviation = np.stack([curve(p) for curve in FOREFOOT_DEVIATION_CURVES], axis=-1)
    return neutral_forefoot_angles(geometry, side) + deviation


# ----------------------------------------------------------------------------- CGM 2.3 foot
def _turn_about(axis: np.ndarray, from_axis: np.ndarray, to_axis: np.ndarray) -> np.ndarray:
    """Per row, the angle (rad) about the unit ``axis`` from ``unit(from_axis × axis)`` to
    ``unit(to_axis × axis)``: how far the uncorrected-foot x axis built on ``to_axis``
    is turned from the one built on ``from_axis``."""
    a = np.cross(from_axis, axis)
    b = np.cross(to_axis, axis)
    a /= np.linalg.norm(a, axis=-1, keepdims=True)
    b /= np.linalg.norm(b, axis=-1, keepdims=True)
    return np.arctan2(np.einsum("ni,ni->n", axis, np.cross(a, b)), np.einsum("ni,ni->n", a, b))


def _knee_axis_in_shank(geometry: Cgm24Geometry, side: str) -> np.ndarray:
    """The knee flexion axis in the posed shank's frame: ``R_z(s τ) e_y``, ``(3,)``."""
    return rot_z(_side_factor(side) * geometry.torsion(side))[0] @ np.array([0.0, 1.0, 0.0])


def cgm23_static_correction(geometry: Cgm24Geometry, side: str) -> float:
    """``δ`` (rad): :func:`_turn_about` of the static pose (foot = shank frame, TOE at
    ``toe_local`` from the AJC), from the knee axis to the shank's y axis."""
    long_axis = -np.asarray(geometry.foot_local(side)["TOE"], dtype=float)
    long_axis /= np.linalg.norm(long_axis)
    knee = _knee_axis_in_shank(geometry, side)
    return float(_turn_about(long_axis[None], knee[None], np.array([[0.0, 1.0, 0.0]]))[0])


def cgm23_foot_rotation(pose: Pose, geometry: Cgm24Geometry, side: str) -> np.ndarray:
    """pyCGM2's CGM 2.3 foot of a posed walker, ``(n, 3, 3)`` in this package's foot axes:
    the posed hindfoot turned about ``z_u = unit(AJC - TOE)`` by ``δ - γ(t)`` (module
    docstring, "Tibial torsion"); the posed hindfoot itself without torsion."""
    R_foot = pose.rotations[side + "Foot"]
    if geometry.torsion(side) == 0.0:
        return R_foot
    R_shank = pose.rotations[side + "Shank"]
    long_axis = pose.joint_centres[side + "AJC"] - pose.markers[side + "TOE"]
    long_axis = long_axis / np.linalg.norm(long_axis, axis=-1, keepdims=True)
    knee = _apply(R_shank, _knee_axis_in_shank(geometry, side))
    angle = cgm23_static_correction(geometry, side) - _turn_about(long_axis, knee, R_shank[:, :, 1])
    c, s_ = np.cos(angle)[:, None, None], np.sin(angle)[:, None, None]
    k = long_axis
    skew = np.zeros(k.shape + (3,))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    skew -= np.swapaxes(skew, 1, 2)
    turn = c * np.eye(3) + s_ * skew + (1.0 - c) * np.einsum("ni,nj->nij", k, k)
    return turn @ R_foot


# ----------------------------------------------------------------------------- pose
def add_cgm24_markers(
    pose: Pose, forefoot_angles: dict[str, np.ndarray], geometry: Cgm24Geometry
) -> Pose:
    """Add the CGM 2.4 markers and the forefoot to a posed skeleton, in place.

    ``pose`` comes from :func:`~fuzzygait.synthetic.leg_model.pose_lower_body` with
    ``geometry``; ``forefoot_angles`` are ``(n, 3)`` degrees keyed ``"L"``/``"R"``.
    Adds THAP, THAD, TIAP, TIAD, FMH, SMH, VMH, moves TOE (and the toe sole point) onto
    the forefoot, adds the rotations ``"LHindFoot"`` (= ``"LFoot"``) and
    ``"LForeFoot"`` and the joint centre ``"LMFJC"`` (likewise ``R``).
    """
    g = geometry
    m = pose.markers
    for side in SIDES:
        s = _side_factor(side)
        R_thigh = pose.rotations[side + "Thigh"]
        R_shank = pose.rotations[side + "Shank"]
        R_hind = pose.rotations[side + "Foot"]
        kjc = pose.joint_centres[side + "KJC"]
        ajc = pose.joint_centres[side + "AJC"]
        m[side + "THAP"] = kjc + _apply(R_thigh, _cluster_local(g.thap, g.thigh_length, s))
        m[side + "THAD"] = kjc + _apply(R_thigh, _cluster_local(g.thad, g.thigh_length, s))
        m[side + "TIAP"] = ajc + _apply(R_shank, _cluster_local(g.tiap, g.shank_length, s))
        m[side + "TIAD"] = ajc + _apply(R_shank, _cluster_local(g.tiad, g.shank_length, s))

        local = g.foot_local(side)
        Q = forefoot_static_axes(g, side)
        # skeleton forefoot frame = pyCGM2's forefoot anatomical frame; rotates about TOE
        R_fore = R_hind @ forefoot_rotation(forefoot_angles[side], side)
        toe = m[side + "TOE"]  # placed on the hindfoot by pose_lower_body
        for label in ("FMH", "SMH", "VMH"):
            m[side + label] = toe + _apply(R_fore, Q.T @ (local[label] - local["TOE"]))
        pose.rotations[side + "HindFoot"] = R_hind
        pose.rotations[side + "ForeFoot"] = R_fore
        pose.joint_centres[side + "FJC"] = ajc + _apply(R_hind, fjc_local(g, side))
    return pose


def _shifted(pose: Pose, dz: float) -> Pose:
    if dz == 0.0:
        return pose
    shift = np.array([0.0, 0.0, dz])
    return Pose(
        rotations=pose.rotations,
        joint_centres={k: v + shift for k, v in pose.joint_centres.items()},
        markers={k: v + shift for k, v in pose.markers.items()},
        sole_points={k: v + shift for k, v in pose.sole_points.items()},
    )


def _geometry(geometry: Cgm24Geometry | None, hjc: str | None) -> Cgm24Geometry:
    g = geometry or Cgm24Geometry()
    if not isinstance(g, Cgm24Geometry):
        raise ParameterError("geometry must be a Cgm24Geometry")
    return g if hjc is None else replace(g, hjc=hjc)


def forefoot_angle_columns() -> list[str]:
    """Truth forefoot columns ``LForeFootAngles_X`` ... ``RForeFootAngles_Z`` (degrees)."""
    return [f"{side}ForeFootAngles_{axis}" for side in SIDES for axis in "XYZ"]


def fjc_columns() -> list[str]:
    """Truth forefoot joint centre columns ``LFJC_X`` ... ``RFJC_Z`` (mm)."""
    return [f"{side}FJC_{axis}" for side in SIDES for axis in "XYZ"]


def forefoot_truth(pose: Pose) -> dict[str, np.ndarray]:
    """ForeFootAngles ``(n, 3)`` (deg) per side computed from the posed skeleton."""
    return {
        side: forefoot_angles_from_rotation(
            np.swapaxes(pose.rotations[side + "HindFoot"], 1, 2)
            @ pose.rotations[side + "ForeFoot"],
            side,
        )
        for side in SIDES
    }


# ----------------------------------------------------------------------------- trials
def cgm24_walking_state(
    times: np.ndarray,
    geometry: Cgm24Geometry | None = None,
    first_strike_time: float = LEAD_IN_CYCLES * STRIDE_TIME_S,
    x_offset: float = 0.0,
    hjc: str | None = None,
) -> tuple[Pose, dict[tuple[str, str], np.ndarray], dict[str, np.ndarray], np.ndarray]:
    """Exact CGM 2.4 walker at ``times`` (s): ``(pose, angles, forefoot_angles, phase)``.

    The pelvis, hip, knee and ankle motion is that of
    :func:`~fuzzygait.synthetic.generate.walking_state` (the knee rotation plus the
    geometry's tibial torsion); the pose is lowered by :meth:`Cgm24Geometry.height_shift`;
    ``forefoot_angles`` are the known curves.
    """
    g = _geometry(geometry, hjc)
    pose, angles, phase = walking_state(times, g, first_strike_time, x_offset)
    if g.has_torsion:  # re-pose with the shank on the ankle axis (module docstring)
        for side in SIDES:
            angles[(side, "knee")] = g.knee_with_torsion(angles[(side, "knee")], side)
        origin = 0.5 * (pose.markers["LASI"] + pose.markers["RASI"])
        pose = pose_lower_body(origin, angles[("L", "pelvis")], angles, g)
    forefoot = {side: forefoot_angle_curves(phase, side, g) for side in SIDES}
    add_cgm24_markers(pose, forefoot, g)
    return _shifted(pose, g.height_shift()), angles, forefoot, phase


def make_cgm24_walking(
    n_cycles: int = 4,
    rate: float = 100.0,
    geometry: Cgm24Geometry | None = None,
    hjc: str | None = None,
    foot_truth: str = "hindfoot",
) -> tuple[Trial, pd.DataFrame]:
    """Clean CGM 2.4 walking trial with exactly known angles (deterministic).

    Timing, events and the pelvis/hip/knee/ankle curves as
    :func:`~fuzzygait.synthetic.generate.make_walking_trial`.

    Args:
        n_cycles, rate: as for ``make_walking_trial``.
        geometry: :class:`Cgm24Geometry` (default one; its ``tibial_torsion`` twists
            the tibiae, module docstring).
        hjc: ``"hara"`` or ``"davis"`` (default: the geometry's, ``"hara"``).
        foot_truth: what the truth's ankle and foot-progression columns are of:
            ``"hindfoot"`` the posed hindfoot (every model version's foot, and CGM 2.3's
            without a tibial torsion), ``"cgm2.3"`` pyCGM2's CGM 2.3 foot on the ankle
            axis turned by the torsion (:func:`cgm23_foot_rotation`).  The markers are
            the same.

    Returns:
        ``(trial, truth)``: the markers of :data:`CGM24_DYNAMIC_LABELS`, events and
        subject parameters; ``truth`` as described in the module docstring.
    """
    if n_cycles < 1:
        raise ParameterError(f"n_cycles must be >= 1; got {n_cycles}")
    if not np.isfinite(rate) or rate <= 0:
        raise ParameterError(f"rate must be a positive number of Hz; got {rate}")
    if foot_truth not in FOOT_TRUTHS:
        raise ParameterError(f"foot_truth must be one of {FOOT_TRUTHS}; got {foot_truth!r}")
    g = _geometry(geometry, hjc)
    first_strike = LEAD_IN_CYCLES * STRIDE_TIME_S
    duration = (LEAD_IN_CYCLES + n_cycles + LEAD_OUT_CYCLES) * STRIDE_TIME_S
    n_frames = int(np.floor(duration * rate + 1e-9)) + 1
    times = np.arange(n_frames) / rate
    x_offset = -WALKING_SPEED_MM_S * times[-1] / 2.0
    pose, angles, _, _ = cgm24_walking_state(times, g, first_strike, x_offset)

    markers = np.stack([pose.markers[label] for label in CGM24_DYNAMIC_LABELS], axis=1)
    trial = Trial(
        markers=markers,
        marker_labels=list(CGM24_DYNAMIC_LABELS),
        rate=float(rate),
        first_frame=1,
        events=gait_events(times[0], times[-1], first_strike),
        parameters=g.parameters(),
        subject=SUBJECT_NAME,
        notes=[f"synthetic CGM 2.4 walking trial generated by fuzzygait.synthetic (clean, "
               f"{g.hjc} HJC)"],
    )  # fmt: skip
    return trial, _walking_truth(pose, angles, times, g, foot_truth)


def _walking_truth(
    pose: Pose, angles: dict[tuple[str, str], np.ndarray], times: np.ndarray, g: Cgm24Geometry, foot_truth: str
) -> pd.DataFrame:
    """The truth table of :func:`make_cgm24_walking` (module docstring)."""
    columns: dict[str, np.ndarray] = {
        "frame": np.arange(1, len(times) + 1),
        "time_s": np.round(times, 9),
    }
    feet = {side: pose.rotations[side + "HindFoot"] for side in SIDES}
    for side in SIDES:
        if foot_truth == "cgm2.3" and g.torsion(side) != 0.0:  # else the same foot
            feet[side] = cgm23_foot_rotation(pose, g, side)
            relative = np.swapaxes(pose.rotations[side + "Shank"], 1, 2) @ feet[side]
            angles = {**angles, (side, "ankle"): joint_angles_from_rotation(relative, side, "ankle")}
    for side in SIDES:
        for joint, name in SEGMENT_ANGLE_NAMES.items():
            for i, axis in enumerate("XYZ"):
                columns[f"{side}{name}Angles_{axis}"] = angles[(side, joint)][:, i]
    for side in SIDES:
        for jc in JOINT_CENTRE_NAMES:
            for i, axis in enumerate("XYZ"):
                columns[f"{side}{jc}_{axis}"] = pose.joint_centres[side + jc][:, i]
    forefoot = forefoot_truth(pose)
    for side in SIDES:
        for i, axis in enumerate("XYZ"):
            columns[f"{side}ForeFootAngles_{axis}"] = forefoot[side][:, i]
    for side in SIDES:
        for i, axis in enumerate("XYZ"):
            columns[f"{side}FJC_{axis}"] = pose.joint_centres[side + "FJC"][:, i]
    for side in SIDES:
        progression = foot_progression_angles(feet[side], side)
        for i, axis in enumerate("XYZ"):
            columns[f"{side}FootProgressAngles_{axis}"] = progression[:, i]
    return pd.DataFrame(columns)


def make_cgm24_static(
    rate: float = 100.0,
    duration_s: float = 2.0,
    geometry: Cgm24Geometry | None = None,
    hjc: str | None = None,
) -> Trial:
    """CGM 2.4 static standing trial: joint and pelvis angles 0 (the knee rotation: the
    geometry's tibial torsion, module docstring), pelvis level.

    The forefoot markers are where :class:`Cgm24Geometry` puts them (ForeFootAngles =
    :func:`neutral_forefoot_angles`); :func:`cgm24_static_pose` gives the skeleton.

    The ASIS midpoint stands at X = Y = 0 and at the height that puts the soles on the
    floor; feet along +X; includes LKNM, RKNM, LMED, RMED (:data:`CGM24_STATIC_LABELS`).
    Every frame identical, no events.
    """
    if not np.isfinite(rate) or rate <= 0:
        raise ParameterError(f"rate must be a positive number of Hz; got {rate}")
    if not np.isfinite(duration_s) or duration_s <= 0:
        raise ParameterError(f"duration_s must be positive; got {duration_s}")
    g = _geometry(geometry, hjc)
    pose = cgm24_static_pose(rate, duration_s, g)
    markers = np.stack([pose.markers[label] for label in CGM24_STATIC_LABELS], axis=1)
    return Trial(
        markers=markers,
        marker_labels=list(CGM24_STATIC_LABELS),
        rate=float(rate),
        first_frame=1,
        parameters=g.parameters(),
        subject=SUBJECT_NAME,
        notes=[f"synthetic CGM 2.4 static trial generated by fuzzygait.synthetic ({g.hjc} HJC)"],
    )


def cgm24_static_pose(
    rate: float = 100.0,
    duration_s: float = 2.0,
    geometry: Cgm24Geometry | None = None,
    hjc: str | None = None,
) -> Pose:
    """The posed skeleton of :func:`make_cgm24_static` (joint centres, frames), for truth."""
    g = _geometry(geometry, hjc)
    n = max(int(round(duration_s * rate)), 1)
    origin = np.tile([0.0, 0.0, g.standing_pelvis_height()], (n, 1))
    zeros = np.zeros((n, 3))
    angles = {(side, joint): zeros for side in SIDES for joint in JOINTS}
    if g.has_torsion:
        angles.update({(side, "knee"): g.knee_with_torsion(zeros, side) for side in SIDES})
    pose = pose_lower_body(origin, zeros, angles, g, medial_markers=True)
    neutral = {side: np.tile(neutral_forefoot_angles(g, side), (n, 1)) for side in SIDES}
    return add_cgm24_markers(pose, neutral, g)
