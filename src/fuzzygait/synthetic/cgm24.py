"""Synthetic CGM 2.4 sessions (static + walking) with exactly known angles and centres.

The CGM 2.4 marker set (Leboeuf et al. 2019; thesis Figure 3.8), prefix ``L``/``R``:
pelvis ASI/PSI; thigh THAP, THAD, THI, KNE; shank TIAP, TIAD, TIB, ANK; foot HEE, TOE,
FMH, SMH, VMH; the medial KNM and MED in the static trial only.  Every marker sits
rigidly on the hidden skeleton of :mod:`fuzzygait.synthetic.leg_model` (same pelvis,
thigh, shank and foot frames, angle curves, timing and sign conventions as the Plug-in
Gait trials), plus a forefoot.  Nothing is solved with :mod:`fuzzygait.kinematics` (the
code this data tests); the CGM 2.x definitions used are pyCGM2's (as summarised in the
project's CGM 2.x notes: Hara HJC, medial KJC/AJC, CGM 2.4 forefoot).

The subject's geometry is :mod:`~fuzzygait.synthetic.cgm24_geometry`, the forefoot and
the CGM 2.3 foot :mod:`~fuzzygait.synthetic.cgm24_foot` (their names importable from here
too); this docstring defines all three.

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

from dataclasses import replace

import numpy as np
import pandas as pd

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.core.trial import Trial
from fuzzygait.synthetic.cgm24_foot import (
    FJC_MARKER_DIAMETER,
    FOREFOOT_DEVIATION_CURVES,
    cgm23_foot_rotation,
    cgm23_static_correction,
    fjc_local,
    forefoot_angle_curves,
    forefoot_angles_from_rotation,
    forefoot_rotation,
    forefoot_static_axes,
    neutral_forefoot_angles,
    pycgm2_forefoot_frame,
)
from fuzzygait.synthetic.cgm24_geometry import HJC_METHODS, MAX_TIBIAL_TORSION, Cgm24Geometry, hara_hjc
from fuzzygait.synthetic.gait_curves import JOINTS, STRIDE_TIME_S
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
    _apply,
    _side_factor,
    foot_progression_angles,
    joint_angles_from_rotation,
    pose_lower_body,
)

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
#: ``foot_truth`` values of :func:`make_cgm24_walking`.
FOOT_TRUTHS = ("hindfoot", "cgm2.3")


# ----------------------------------------------------------------------------- pose
def _cluster_local(spec: tuple[float, float, float], length: float, s: float) -> np.ndarray:
    anterior, lateral, fraction = spec
    return np.array([anterior, s * lateral, fraction * length])


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
        notes=[Finding(FindingKind.SYNTHETIC, f"synthetic CGM 2.4 walking trial generated by fuzzygait.synthetic "
                       f"(clean, {g.hjc} HJC)")],
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
        notes=[Finding(FindingKind.SYNTHETIC,
                       f"synthetic CGM 2.4 static trial generated by fuzzygait.synthetic ({g.hjc} HJC)")],
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


#: The session's public names, with the geometry (:mod:`~fuzzygait.synthetic.cgm24_geometry`)
#: and the feet (:mod:`~fuzzygait.synthetic.cgm24_foot`) it is built from.
__all__ = [
    "CGM24_DYNAMIC_LABELS",
    "CGM24_MEDIAL_LABELS",
    "CGM24_SIDE_LABELS",
    "CGM24_STATIC_LABELS",
    "FJC_MARKER_DIAMETER",
    "FOOT_TRUTHS",
    "FOREFOOT_DEVIATION_CURVES",
    "FOREFOOT_MARKERS",
    "HJC_METHODS",
    "MAX_TIBIAL_TORSION",
    "Cgm24Geometry",
    "add_cgm24_markers",
    "cgm23_foot_rotation",
    "cgm23_static_correction",
    "cgm24_static_pose",
    "cgm24_walking_state",
    "fjc_columns",
    "fjc_local",
    "forefoot_angle_columns",
    "forefoot_angle_curves",
    "forefoot_angles_from_rotation",
    "forefoot_rotation",
    "forefoot_static_axes",
    "forefoot_truth",
    "hara_hjc",
    "make_cgm24_static",
    "make_cgm24_walking",
    "neutral_forefoot_angles",
    "pycgm2_forefoot_frame",
]
