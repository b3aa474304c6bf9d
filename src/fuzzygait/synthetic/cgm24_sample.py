"""The CGM 2.4 session of ``sample_data/`` (``cgm24_*`` files) and its README section.

The trials are :func:`~fuzzygait.synthetic.cgm24.make_cgm24_static` and
:func:`~fuzzygait.synthetic.cgm24.make_cgm24_walking` with the default geometry (Hara
hip centres).  The truth tables written here differ from the generator's ``truth`` frame
in one respect: the pelvis angles are in CGM 2.x's order (rotation, obliquity, tilt;
Baker 2001, "ROT"), what every model version after ``cgm1.0`` reports, re-decomposed
from the generator's Plug-in Gait order (tilt, obliquity, rotation) by
:func:`rot_pelvis_angles` -- independently of :mod:`fuzzygait.kinematics`.  The pelvis
motion is that of the Plug-in Gait walking trial, so the Plug-in Gait-order values are
``walking_truth_angles.csv``'s pelvis columns (same frames).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from fuzzygait.core.trial import Trial
from fuzzygait.synthetic.cgm24 import (
    CGM24_DYNAMIC_LABELS,
    CGM24_MEDIAL_LABELS,
    CGM24_SIDE_LABELS,
    Cgm24Geometry,
    fjc_local,
    make_cgm24_static,
    make_cgm24_walking,
    neutral_forefoot_angles,
)
from fuzzygait.synthetic.leg_model import SIDES, static_offsets

#: Files :func:`write_cgm24_sample_data` writes, in order.
CGM24_SAMPLE_FILES: tuple[str, ...] = (
    "cgm24_static.c3d",
    "cgm24_walking.c3d",
    "cgm24_subject.toml",
    "cgm24_walking_truth_angles.csv",
    "cgm24_walking_truth_joint_centres.csv",
)
#: Angles of the CGM 2.4 truth table, per side in this order (``L`` then ``R``).
CGM24_TRUTH_ANGLES: tuple[str, ...] = ("Pelvis", "Hip", "Knee", "Ankle", "FootProgress", "ForeFoot")
#: Joint centres of the CGM 2.4 truth table, per side in this order.
CGM24_TRUTH_CENTRES: tuple[str, ...] = ("HJC", "KJC", "AJC", "FJC")


def rot_pelvis_angles(tor: np.ndarray, side: str) -> np.ndarray:
    """Pelvis angles ``(n, 3)`` (deg) in Plug-in Gait's order re-decomposed in CGM 2.x's.

    Plug-in Gait (tilt X, obliquity Y, rotation Z): ``R = R_y(X) R_x(s Y) R_z(-s Z)``
    (intrinsic, ``s = +1`` left, ``-1`` right, the signs of
    :mod:`~fuzzygait.synthetic.leg_model`).  CGM 1.1+ (Baker 2001) decomposes the same
    rotation as ``R = R_z(-s Z') R_x(s Y') R_y(X')``: rotation first, tilt last.
    """
    x, y, z = np.radians(np.atleast_2d(np.asarray(tor, dtype=float))).T
    s = 1.0 if side == "L" else -1.0
    rotation = Rotation.from_euler("YXZ", np.stack([x, s * y, -s * z], axis=1))
    c, b, a = rotation.as_euler("ZXY").T
    return np.degrees(np.stack([a, s * b, -s * c], axis=1))


def cgm24_truth_angle_columns() -> list[str]:
    """``LPelvisAngles_X`` ... ``LForeFootAngles_Z`` (:data:`CGM24_TRUTH_ANGLES`), then the
    same for ``R`` (degrees)."""
    return [f"{side}{name}Angles_{axis}" for side in SIDES for name in CGM24_TRUTH_ANGLES for axis in "XYZ"]


def cgm24_joint_centre_columns() -> list[str]:
    """``LHJC_X`` ... ``LFJC_Z``, then the same for ``R`` (mm)."""
    return [f"{side}{jc}_{axis}" for side in SIDES for jc in CGM24_TRUTH_CENTRES for axis in "XYZ"]


def cgm24_truth_angles(truth: pd.DataFrame) -> pd.DataFrame:
    """``frame``, ``time_s`` and :func:`cgm24_truth_angle_columns` from the generator's
    truth (pelvis in the ROT order, :func:`rot_pelvis_angles`)."""
    table = truth[["frame", "time_s"]].copy()
    for side in SIDES:
        tor = truth[[f"{side}PelvisAngles_{a}" for a in "XYZ"]].to_numpy()
        rot = rot_pelvis_angles(tor, side)
        for name in CGM24_TRUTH_ANGLES:
            for i, axis in enumerate("XYZ"):
                column = f"{side}{name}Angles_{axis}"
                table[column] = rot[:, i] if name == "Pelvis" else truth[column]
    return table


def _csv_text(frame: pd.DataFrame, float_format: str) -> str:
    return frame.to_csv(index=False, float_format=float_format, lineterminator="\n")


def cgm24_truth_angles_csv_text(truth: pd.DataFrame) -> str:
    """CSV text of :func:`cgm24_truth_angles` (degrees, 9 decimals)."""
    return _csv_text(cgm24_truth_angles(truth), "%.9f")


def cgm24_truth_joint_centres_csv_text(truth: pd.DataFrame) -> str:
    """CSV text of ``frame, time_s`` and :func:`cgm24_joint_centre_columns` (mm, 6 decimals)."""
    return _csv_text(truth[["frame", "time_s", *cgm24_joint_centre_columns()]], "%.6f")


def cgm24_session() -> tuple[Trial, Trial, pd.DataFrame]:
    """``(static, walking, truth)`` of the bundled session (generator truth, TOR pelvis)."""
    walking, truth = make_cgm24_walking()
    return make_cgm24_static(), walking, truth


def write_cgm24_sample_data(out: Path) -> list[Path]:
    """Write :data:`CGM24_SAMPLE_FILES` into ``out`` (which exists); returns the paths."""
    from fuzzygait.io.c3d import write_c3d  # deferred: keeps the generator importable
    from fuzzygait.synthetic.generate import subject_toml_text

    static, walking, truth = cgm24_session()
    paths = [out / name for name in CGM24_SAMPLE_FILES]
    write_c3d(static, paths[0])
    write_c3d(walking, paths[1])
    texts = (
        subject_toml_text(walking.parameters, title="CGM 2.4 subject: subject.toml with the CGM 2.4 TOE/HEE offsets"),
        cgm24_truth_angles_csv_text(truth),
        cgm24_truth_joint_centres_csv_text(truth),
    )
    for path, text in zip(paths[2:], texts, strict=True):
        path.write_text(text, encoding="utf-8", newline="\n")
    return paths


def readme_rows(walking: Trial) -> str:
    """Rows of the sample-data README's file table for the ``cgm24_*`` files."""
    side = " ".join(CGM24_SIDE_LABELS)
    medial = " ".join(CGM24_MEDIAL_LABELS)
    return _ROWS.format(rate=walking.rate, n_frames=walking.n_frames, duration=walking.times[-1],
                        n_markers=len(CGM24_DYNAMIC_LABELS), side=side, medial=medial)  # fmt: skip


def readme_section() -> str:
    """The sample-data README's "CGM 2.4 session" section."""
    g = Cgm24Geometry()
    hjc = g.hjc_local("L")
    return _SECTION.format(
        hjc=f"({hjc[0]:.3f}, +-{hjc[1]:.3f}, {hjc[2]:.3f})",
        shift=-g.height_shift(),
        standing=g.standing_pelvis_height(),
        toe=g.toe_local, hee=g.hee_local, fmh=g.fmh_local, smh=g.smh_local, vmh=g.vmh_local,
        thap=g.thap, thad=g.thad, tiap=g.tiap, tiad=g.tiad, thi_offset=g.thi_offset,
        thi_fraction=g.thi_fraction, tib_offset=g.tib_offset, tib_fraction=g.tib_fraction,
        pf_rad=static_offsets(g)["plantarflexion"],
        fjc="({:.6f}, {:.6f}, {:.6f})".format(*fjc_local(g, "L")),
        fjc_depth=float(np.linalg.norm(fjc_local(g, "L") - np.asarray(g.toe_local))),
        neutral="({:.4f}, {:.4f}, {:.4f})".format(*neutral_forefoot_angles(g, "L")),
    )  # fmt: skip


_ROWS = """\
| `cgm24_static.c3d` | CGM 2.4 standing trial, {rate:g} Hz, 2 s, every frame identical, all angles 0 as in \
`static.c3d` (forefoot at its neutral ForeFootAngles, see below). Markers: LASI RASI LPSI RPSI, per side \
(L then R) {side}, + medial {medial}. No events. |
| `cgm24_walking.c3d` | clean CGM 2.4 walking trial, {rate:g} Hz, {n_frames} frames (0 .. {duration:.2f} s), \
same timing, events and angles as `walking.c3d` (but ankle Y, which follows the static plantarflexion \
offset), the {n_markers} dynamic markers of the CGM 2.4 set (no KNM/MED). |
| `cgm24_subject.toml` | its subject parameters (as `subject.toml` but `L/RStaticPlantFlex` of the CGM 2.4 \
TOE/HEE), also stored in both `cgm24_*.c3d`. |
| `cgm24_walking_truth_angles.csv` | exact angles of `cgm24_walking.c3d`: `frame`, `time_s`, \
`LPelvisAngles_X/Y/Z` (**CGM 2.x order**: rotation-obliquity-tilt, see below), `LHipAngles_*`, \
`LKneeAngles_*`, `LAnkleAngles_*`, `LFootProgressAngles_*`, `LForeFootAngles_*`, then the same for R; degrees. |
| `cgm24_walking_truth_joint_centres.csv` | exact joint centres of `cgm24_walking.c3d`: `frame`, `time_s`, \
`LHJC_X/Y/Z` (Hara), `LKJC_*`, `LAJC_*`, `LFJC_*` (forefoot joint centre), then the same for R; mm, lab frame. |
"""

_SECTION = """\
## CGM 2.4 session (`cgm24_*`)

The thesis' marker set (Leboeuf et al. 2019): thigh and shank clusters, medial knee and
ankle markers in the static trial, a forefoot. Generated by
`fuzzygait.synthetic.cgm24` (its docstring has every definition), same skeleton, angle
curves, timing and sign conventions as the Plug-in Gait trials above, except:

* Hip joint centres at Hara et al. (2016) as pyCGM2 (CGM 2.1+) applies it (fixed 14 mm
  marker, 2 mm base plate): {hjc} mm in the pelvis frame (leg
  length 900 mm). The walking trial is {shift:.6f} mm lower than `walking.c3d`; the static
  pelvis stands at Z = {standing:.3f} mm, soles on the floor.
* Clusters (segment frame, left side, mm; y lateral, a negative value is medial), laid out as
  the calibrated clusters of a real CGM 2.4 session (mean of both sides): THI {thi_offset:g} lateral
  at {thi_fraction:g} of the thigh above the KJC, THAP {thap[0]:g} anterior, {thap[1]:g} lateral at
  {thap[2]:g}, THAD {thad[0]:g}, {thad[1]:g} at {thad[2]:g}; TIB {tib_offset:g} lateral at {tib_fraction:g} of the
  shank above the AJC, TIAP {tiap[0]:g}, {tiap[1]:g} at {tiap[2]:g} and TIAD {tiad[0]:g}, {tiad[1]:g} at
  {tiad[2]:g} (on the tibial crest). KNE and ANK as in the Plug-in Gait trials; KNM/MED mirror
  KNE/ANK on the knee/ankle axis (their midpoints are the KJC/AJC).
* Hindfoot (foot frame, origin AJC, mm): TOE {toe} (CGM 2.4's mid-foot TOE), HEE
  {hee}; static plantarflexion offset {pf_rad:.6f} rad (in the parameters).
  Forefoot markers in the static hindfoot frame: FMH {fmh}, SMH {smh},
  VMH {vmh}; the forefoot turns about TOE.
* ForeFootAngles: pyCGM2's CGM 2.4 forefoot (anatomical frame [vSMH, FJC, VMH]) relative
  to the hindfoot, intrinsic Y-X-Z, the ankle's signs: + X forefoot dorsiflexion, + Y its
  lateral border up, + Z adduction (toes medial). Static (neutral) values
  {neutral} deg on both sides; walking = neutral + a few degrees.
  FJC (pyCGM2's): TOE + 14 mm x (unit(VMH - TOE) x unit(FMH - TOE)) on the left (- on the
  right; below TOE; the cross product is not normalised, so FJC is {fjc_depth:.3f} mm from TOE), a
  point of the hindfoot: {fjc} mm in the left hindfoot frame.
* FootProgressAngles: the hindfoot (= the Plug-in Gait foot) in the lab, which is the
  progression frame here (walking along +X), Vicon's convention
  (`fuzzygait.synthetic.leg_model.foot_progression_angles`): X = -90 + the foot's pitch
  (toes down +), Z + = toes turned medially (internal), both sides.
* Pelvis angles in the truth table: CGM 1.1+'s order (rotation Z, obliquity Y, tilt X;
  `R = R_z(-sZ) R_x(sY) R_y(X)`, s = +1 left, -1 right), re-decomposed from the Plug-in
  Gait order (`fuzzygait.synthetic.cgm24_sample.rot_pelvis_angles`). The Plug-in
  Gait-order values, what `cgm1.0` reports, are `walking_truth_angles.csv`'s pelvis columns
  (same motion, same frames).

Which model version reproduces which truth columns (from the C3D files, no low-pass;
float32 markers; checked by `tests/synthetic/test_cgm24_sample.py`):

| columns | reproduced (<= 0.01 deg, <= 1e-3 mm) by | not by |
|---|---|---|
| `L/RPelvisAngles_*` | `cgm1.1`, `cgm2.1`, `cgm2.3`, `cgm2.4` | `cgm1.0` (Plug-in Gait order, see above) |
| `L/RHipAngles_*`, `KneeAngles_*`, `AnkleAngles_*`, `FootProgressAngles_*`; HJC, KJC, AJC | `cgm2.1`, `cgm2.3`, \
`cgm2.4` | `cgm1.0`, `cgm1.1`: Davis hip centres, 18 mm from Hara's, angles degrees off |
| `L/RForeFootAngles_*`, FJC | `cgm2.4` only | every other version (no forefoot) |

`make_cgm24_walking(hjc="davis")` / `make_cgm24_static(hjc="davis")` give the same
session with Davis hip centres, which `cgm1.0`/`cgm1.1` reproduce (not bundled).
"""
