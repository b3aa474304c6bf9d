"""CGM 2.3 against pyCGM2's CGM 2.3 output of the shared Qualisys session
(``../shared/data/cgm2``; ``benchmarks/cgm2_pycgm2.py`` prints the table of
``benchmarks/RESULTS.md``), and the knee/ankle centre rules of the cluster calibration
(:mod:`fuzzygait.kinematics.knee_ankle`) on the synthetic CGM 2.4 session.

(A) is the run the issue asks for: cgm2.3 (rule ``"pycgm2"``) on pyCGM2's IK-fitted
markers, calibrated on the session's static trial.  (B) is the same run calibrated on
pyCGM2's own geometry: its fitted markers at the static trial's frames as the static
trial, and the two foot offsets per side that its ankle angles imply."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.trial import Trial
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import subject_from_processing
from fuzzygait.kinematics import ANGLE_NAMES, compute_lower_body, static_calibration
from fuzzygait.kinematics.angles import ANGLE_TABLE, LEFT_MIRROR, wrap_degrees
from fuzzygait.kinematics.clusters import ClusterChain, calibrate_clusters
from fuzzygait.kinematics.joint_centres import chord_joint_centre
from fuzzygait.kinematics.knee_ankle import ClusterChordChain, knee_ankle_rule
from fuzzygait.kinematics.segments import side_sign
from fuzzygait.synthetic.cgm24 import make_cgm24_static, make_cgm24_walking
from fuzzygait.workflows.angles import calibrate_static, resolve_subject
from support import needs_shared, shared_file

CGM2 = "cgm2/qualisys-cgm24-input"
#: session.xml: leg length 1000 mm, knee 95, ankle 65, 14 mm markers.
CGM2_SUBJECT = {"Bodymass": 70.0, "Height": 1800.0, "LLegLength": 1000.0, "RLegLength": 1000.0,
                "LKneeWidth": 95.0, "RKneeWidth": 95.0, "LAnkleWidth": 65.0, "RAnkleWidth": 65.0,
                "MarkerDiameter": 14.0}  # fmt: skip
#: The static trial's frames in the walking recording's numbering.
STATIC_FRAMES = slice(539 - 430, 543 - 430 + 1)
TARGET_DEG = 0.1
#: (A), RMS per component (deg) as benchmarks/RESULTS.md shows them: the static trial is
#: not the one pyCGM2 calibrated on (test_the_static_trial_is_not_pycgm2s_calibration_input).
A_RMS_DEG = {
    "LHipAngles": (5.584, 6.512, 13.685), "RHipAngles": (0.481, 3.705, 4.413),
    "LKneeAngles": (17.794, 3.6, 16.698), "RKneeAngles": (0.537, 6.602, 7.595),
    "LAnkleAngles": (98.141, 93.781, 5.455), "RAnkleAngles": (67.744, 82.932, 42.204),
    "LFootProgressAngles": (75.767, 67.281, 46.763), "RFootProgressAngles": (123.797, 12.166, 153.915),
}  # fmt: skip
#: (A), joint centre distances (mm): constant, the centres are fixed in rigid segments.
A_CENTRE_MM = {"LKJC": 44.041, "RKJC": 27.855, "LAJC": 15.192, "RAJC": 41.209}


@pytest.fixture(scope="module")
def session():
    folder = Path(shared_file(CGM2, "Static - CGM2 1.c3d")).parent
    output = read_c3d(next(folder.glob("*pyCGM2*.c3d")))
    raw = read_c3d(folder / "Gait - CGM2 1.c3d")
    fitted = output.select_markers([m for m in raw.marker_labels if output.has_marker(m)])
    return read_c3d(folder / "Static - CGM2 1.c3d"), fitted, output, raw, subject_from_processing(CGM2_SUBJECT)


def _rms_max(result, output, name):
    diff = np.abs(wrap_degrees(result.angles[name] - output.outputs[name]))
    return np.sqrt(np.mean(diff**2, axis=0)), diff.max(axis=0)


def _centre_distance(result, output, name):
    return np.linalg.norm(result.joint_centres[name] - output.marker(name), axis=1)


def _pycgm2_foot_offsets(tracked: ClusterChain, output: Trial, subject):
    """The subject with the foot offsets pyCGM2's ankle angles imply, and per side the
    largest SD of the two offsets over the frames and the largest third angle (deg)."""
    order, table_signs, offsets = ANGLE_TABLE["Ankle"]
    spread = []
    for side in "LR":
        signs = np.asarray(table_signs) * (LEFT_MIRROR if side == "L" else 1.0)
        components = np.empty((output.n_frames, 3))
        components[:, list(order)] = (output.outputs[side + "AnkleAngles"] - np.asarray(offsets)) / signs
        foot = tracked.ankle_tibia(side) @ Rotation.from_euler("YXZ", components, degrees=True).as_matrix()
        relative = np.einsum("nji,njk->nik", tracked.uncorrected_foot(side), foot)
        yxz = Rotation.from_matrix(relative).as_euler("YXZ", degrees=True)
        spread.append((yxz[:, :2].std(axis=0).max(), np.abs(yxz[:, 2]).max()))
        subject = subject.with_side(side, static_plant_flex=float(np.radians(-yxz[:, 0].mean())),
                                    static_rot_off=float(np.radians(-side_sign(side) * yxz[:, 1].mean())))  # fmt: skip
    return subject, spread


# ----------------------------------------------------------------------- the shared session
@needs_shared
def test_pycgm2_knee_and_ankle_centres_are_the_chord_with_thap_and_tiap(session) -> None:
    """On all 272 frames of the fitted markers, chord(THI, THAP, KNE) and chord(TIB, TIAP,
    ANK) at width/2 + 7 mm are pyCGM2's KJC and AJC to float32 precision; Plug-in Gait's
    chord (with HJC, KJC) is 6-43 mm away, and 13/15 mm markers 0.5 mm."""
    _, fitted, output, _, subject = session
    chain = ClusterChordChain(fitted, subject, hip="hara", single_tibia=True)
    for side in "LR":
        for centre, ours in (("KJC", chain.kjc(side)), ("AJC", chain.ajc(side))):
            assert np.linalg.norm(ours - output.marker(side + centre), axis=1).max() < 5e-4, side + centre
        pig = chord_joint_centre(fitted.marker(side + "TIB"), output.marker(side + "KJC"), fitted.marker(side + "ANK"),
                                 39.5)  # fmt: skip
        assert np.linalg.norm(pig - output.marker(side + "AJC"), axis=1).min() > 5.0
        wider = chord_joint_centre(*(fitted.marker(side + m) for m in ("THI", "THAP", "KNE")), 47.5 + 7.5)
        assert np.linalg.norm(wider - output.marker(side + "KJC"), axis=1).min() > 0.4


@needs_shared
def test_cgm23_on_pycgm2s_own_geometry_reproduces_it(session) -> None:
    """(B): every angle component within 1e-3 deg (max) and every joint centre within 5e-4
    mm of pyCGM2's — except RFootProgressAngles, which pyCGM2 reports as the other Cardan
    solution (a + 180, 180 - b, c + 180) of the same foot with the left side's frontal and
    transverse signs: pyCGM2 = (X + 180, -180 - Y, Z + 180) of ours to 5e-3 deg, while
    ours (Nexus' convention) differ from it by 180 deg in X.  The foot offsets come from
    pyCGM2's ankle angles (so the ankle rows test the foot construction only): its foot
    is our uncorrected foot turned by one constant R_y R_x on every frame."""
    _, fitted, output, _, subject = session
    geometry = Trial(fitted.markers[STATIC_FRAMES], list(fitted.marker_labels), fitted.rate, first_frame=539)
    calibration = calibrate_clusters(geometry, subject, "pycgm2")
    offsets, spread = _pycgm2_foot_offsets(ClusterChain(fitted, subject, calibration), output, subject)
    assert max(sd for sd, _ in spread) < 1e-3 and max(third for _, third in spread) < 2e-3
    assert np.degrees(offsets.left.static_plant_flex) == pytest.approx(-50.061, abs=1e-3)
    assert np.degrees(offsets.right.static_rot_off) == pytest.approx(30.089, abs=1e-3)
    result = compute_lower_body(fitted, offsets, model="cgm2.3", clusters=calibration)
    for name in ANGLE_NAMES:
        if name != "RFootProgressAngles":
            assert _rms_max(result, output, name)[1].max() < 1e-3, name
    for name in ("LHJC", "RHJC", "LKJC", "RKJC", "LAJC", "RAJC"):
        assert _centre_distance(result, output, name).max() < 5e-4, name
    x, y, z = result.angles["RFootProgressAngles"].T
    other_solution = np.stack([x + 180.0, -180.0 - y, z + 180.0], axis=1)
    assert np.abs(wrap_degrees(output.outputs["RFootProgressAngles"] - other_solution)).max() < 5e-3
    assert _rms_max(result, output, "RFootProgressAngles")[0][0] == pytest.approx(180.0, abs=0.1)


@needs_shared
def test_cgm23_with_the_sessions_static_trial(session) -> None:
    """(A): pelvis angles and hip centres meet the 0.1 deg target (1e-4 deg, 1e-3 mm); the
    other outputs differ at the sizes of benchmarks/RESULTS.md (within 2 % + 0.01), the
    knee/ankle centres by constant distances: the static trial is not pyCGM2's
    calibration input (next test)."""
    static, fitted, output, _, subject = session
    calibrated = static_calibration(static, subject, model="cgm2.3", knee_ankle_centres="pycgm2", flat_foot=True)
    clusters = calibrate_clusters(static, calibrated, "pycgm2")
    result = compute_lower_body(fitted, calibrated, model="cgm2.3", clusters=clusters)
    for side in "LR":
        assert _rms_max(result, output, side + "PelvisAngles")[1].max() < 1e-4
        assert _centre_distance(result, output, side + "HJC").max() < 1e-3
    for name, expected in A_RMS_DEG.items():
        rms = _rms_max(result, output, name)[0]
        assert rms == pytest.approx(expected, rel=0.02, abs=0.01), name
        assert rms.max() > TARGET_DEG, name
    for name, expected in A_CENTRE_MM.items():
        distance = _centre_distance(result, output, name)
        assert np.ptp(distance) < 0.01 and distance.mean() == pytest.approx(expected, abs=0.01), name


@needs_shared
def test_the_static_trial_is_not_pycgm2s_calibration_input(session) -> None:
    """pyCGM2's fitted thigh and shank are rigid (inter-marker distances constant to 1e-4
    mm), but the static trial's distances differ from them by 44-107 mm per cluster; its
    MED markers are the walking trial's TOE markers at frames 539-543 (0 mm), and its
    knee markers are 137-143 mm apart for a 95 mm knee."""
    static, fitted, _, raw, _ = session
    for side in "LR":
        for cluster in (("THAP", "THAD", "THI", "KNE"), ("TIAP", "TIAD", "TIB", "ANK")):
            worst = 0.0
            for i, a in enumerate(cluster):
                for b in cluster[i + 1 :]:
                    fit = np.linalg.norm(fitted.marker(side + a) - fitted.marker(side + b), axis=1)
                    assert fit.std() < 1e-4
                    stat = np.linalg.norm(static.marker(side + a) - static.marker(side + b), axis=1).mean()
                    worst = max(worst, abs(stat - fit.mean()))
            assert worst > 40.0, (side, cluster)
        toe = raw.marker(side + "TOE")[STATIC_FRAMES]
        assert np.abs(static.marker(side + "MED") - toe).max() < 1e-3
        knee = np.linalg.norm(static.marker(side + "KNM") - static.marker(side + "KNE"), axis=1)
        assert knee.min() > 130.0


# ----------------------------------------------------------------------- the rules themselves
@pytest.fixture(scope="module")
def synthetic():
    walking, _ = make_cgm24_walking()
    static = make_cgm24_static()
    return static, walking, resolve_subject(walking, None)


def test_default_rule_is_medial_with_knm_med_and_chord_without(synthetic) -> None:
    static, _, subject = synthetic
    assert knee_ankle_rule(static, None) == "medial"
    without = static.select_markers([m for m in static.marker_labels if not m.endswith(("KNM", "MED"))])
    assert knee_ankle_rule(without, None) == "chord"
    default, medial = calibrate_clusters(static, subject), calibrate_clusters(static, subject, "medial")
    for key, cluster in default.segments.items():
        assert np.array_equal(cluster.local, medial.segments[key].local), key


def test_pycgm2_rule_puts_the_centres_on_the_thap_tiap_chord(synthetic) -> None:
    """Calibrated with ``"pycgm2"``, the tracked KJC/AJC of the (rigid, noise-free) walking
    trial are chord(THI, THAP, KNE) and chord(TIB, TIAP, ANK) of each frame (1e-6 mm), a
    different place from the medial rule's."""
    static, walking, subject = synthetic
    calibrated = static_calibration(static, subject, model="cgm2.3", knee_ankle_centres="pycgm2")
    tracked = ClusterChain(walking, calibrated, calibrate_clusters(static, calibrated, "pycgm2"))
    medial = ClusterChain(walking, subject, calibrate_clusters(static, subject, "medial"))
    m, r = walking.marker, subject.marker_radius
    for side in "LR":
        params = subject.side(side)
        kjc = chord_joint_centre(m(side + "THI"), m(side + "THAP"), m(side + "KNE"), params.knee_width / 2 + r)
        ajc = chord_joint_centre(m(side + "TIB"), m(side + "TIAP"), m(side + "ANK"), params.ankle_width / 2 + r)
        assert np.abs(tracked.kjc(side) - kjc).max() < 1e-6 and np.abs(tracked.ajc(side) - ajc).max() < 1e-6
        assert np.linalg.norm(medial.kjc(side) - kjc, axis=1).min() > 1.0


def test_calibrate_static_takes_the_rule_and_names_it(synthetic) -> None:
    static, _, subject = synthetic
    run = calibrate_static(static, subject, model="cgm2.3", knee_ankle_centres="pycgm2")
    assert run.method == "cgm2.3 clusters, pyCGM2 THAP/TIAP chord knee/ankle centres"
    direct = calibrate_clusters(static, run.subject, "pycgm2")
    assert run.clusters is not None
    for key, cluster in direct.segments.items():
        assert np.array_equal(run.clusters.segments[key].local, cluster.local), key
    assert run.subject == static_calibration(static, subject, model="cgm2.3", knee_ankle_centres="pycgm2")
    assert calibrate_static(static, subject, model="cgm2.3").method == "cgm2.3 clusters, KNM/MED knee/ankle centres"


def test_unknown_rule_and_a_rule_for_plug_in_gait_are_refused(synthetic) -> None:
    static, _, subject = synthetic
    with pytest.raises(ParameterError, match="unknown knee/ankle centre rule 'mid'; choose one of medial, chord"):
        calibrate_clusters(static, subject, "mid")
    with pytest.raises(ParameterError, match="cgm1.0 places the knee and ankle centres by the chord"):
        static_calibration(static, subject, knee_ankle_centres="pycgm2")
