"""Issue 36 (point 6): the CGM 2.3 foot with medial malleolus markers.

pyCGM2 calibrates a tibial torsion when the static trial has MED (the static angle
between the thigh's and the shank's flexion axes about the shank's long axis) and builds
its CGM 2.3 foot on the shank's ankle axis turned by it, times a constant static
correction; its CGM 2.4 hindfoot keeps the shank's own axis
(:mod:`fuzzygait.kinematics.clusters`).  The synthetic CGM 2.4 session with a known
tibial torsion (:mod:`fuzzygait.synthetic.cgm24`, ``Cgm24Geometry(tibial_torsion=...)``)
holds the truth of both feet."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.kinematics import compute_lower_body
from fuzzygait.kinematics.calibration_file import cluster_table, clusters_from_table
from fuzzygait.kinematics.clusters import ClusterChain, calibrate_clusters
from fuzzygait.kinematics.knee_ankle import calibration_chain
from fuzzygait.kinematics.segments import flexion_axis_torsion, untorsioned_tibia
from fuzzygait.kinematics.vectors import axis_rotation
from fuzzygait.synthetic.cgm24 import Cgm24Geometry, cgm23_static_correction, make_cgm24_static, make_cgm24_walking
from fuzzygait.workflows.angles import Preprocessing, calibrate_static, resolve_subject, run_angles
from fuzzygait.workflows.calibrate import calibrate_to_file
from support import rot_pelvis_truth

BOUND_DEG = 0.01
NO_FILTER = Preprocessing(filter=False)
#: Known tibial torsions (rad), left and right: external, 20 and 11.5 degrees.
TORSION = (-0.35, -0.2)
GEOMETRY = Cgm24Geometry(tibial_torsion=TORSION)
FOOT_OUTPUTS = ("LAnkleAngles", "RAnkleAngles", "LFootProgressAngles", "RFootProgressAngles")


@pytest.fixture(scope="module")
def session():
    """The twisted session: static, walking, the CGM 2.3 foot's truth, the hindfoot's truth."""
    walking, cgm23 = make_cgm24_walking(n_cycles=2, geometry=GEOMETRY, foot_truth="cgm2.3")
    _, hindfoot = make_cgm24_walking(n_cycles=2, geometry=GEOMETRY)
    return make_cgm24_static(geometry=GEOMETRY), walking, cgm23, hindfoot


def _expected(truth, name: str) -> np.ndarray:
    if name.endswith("PelvisAngles"):
        return rot_pelvis_truth(truth, name[0])
    return truth[[f"{name}_{a}" for a in "XYZ"]].to_numpy()


def _worst(result, truth) -> dict[str, float]:
    return {name: float(np.abs(values - _expected(truth, name)).max()) for name, values in result.angles.items()}


# ------------------------------------------------------------------------ calibration
@pytest.mark.parametrize("model", ["cgm2.3", "cgm2.4"])
def test_the_static_calibration_recovers_the_known_torsion(session, model: str) -> None:
    """TibialTorsion among the calibrated offsets, the cluster calibration's copy and the
    CGM 2.3 foot's static correction equal the generator's (1e-9 rad)."""
    static, walking, _, _ = session
    run = calibrate_static(static, resolve_subject(walking, None), model=model)
    assert walking.parameters["LTibialTorsion"] == 0.0  # found from KNM/MED, not read
    assert run.clusters is not None
    for side, known in zip("LR", TORSION, strict=True):
        assert run.subject.side(side).tibial_torsion == pytest.approx(known, abs=1e-9)
        torsion = run.clusters.shank_torsions[side]
        assert torsion.tibial_torsion == run.subject.side(side).tibial_torsion
        assert torsion.foot_correction == pytest.approx(cgm23_static_correction(GEOMETRY, side), abs=1e-9)
        assert abs(torsion.foot_correction) > 1e-3


def test_the_turned_axis_is_the_knee_axis_in_the_static_trial(session) -> None:
    """Sign check: the tibia turned by the calibrated torsion (pyCGM2's "proximal shank",
    our untorsioned tibia) has the thigh's y axis (1e-12); turned the other way it is
    twice the torsion off."""
    static, walking, _, _ = session
    subject = resolve_subject(walking, None)
    chain = calibration_chain(static, subject, "medial", hip="hara", single_tibia=True)
    for side, known in zip("LR", TORSION, strict=True):
        thigh, tibia = chain.thigh(side), chain.torsioned_tibia(side)
        torsion = float(flexion_axis_torsion(thigh, tibia, side).mean())
        assert torsion == pytest.approx(known, abs=1e-12)
        assert np.abs(untorsioned_tibia(tibia, torsion, side)[:, :, 1] - thigh[:, :, 1]).max() < 1e-12
        wrong = untorsioned_tibia(tibia, -torsion, side)[:, :, 1]
        angle = np.degrees(np.arccos(np.clip(np.sum(wrong * thigh[:, :, 1], axis=1), -1.0, 1.0)))
        assert angle == pytest.approx(np.full(len(angle), abs(np.degrees(2 * known))), abs=1e-9)


@pytest.mark.parametrize("side", ["L", "R"])
@pytest.mark.parametrize("degrees", [-30.0, -5.0, 0.0, 12.0, 179.0])
def test_flexion_axis_torsion_of_constructed_frames(side: str, degrees: float) -> None:
    """A tibia turned from the thigh by ``R_z(-s τ)`` about their common long axis has the
    torsion ``τ`` (wrapped into [-180, 180) deg)."""
    s = 1.0 if side == "L" else -1.0
    thigh = np.eye(3)[None]
    tibia = thigh @ axis_rotation(2, -s * np.radians(degrees))
    assert np.degrees(flexion_axis_torsion(thigh, tibia, side))[0] == pytest.approx(degrees, abs=1e-9)


# ------------------------------------------------------------------------ angles
def test_cgm23_with_med_recovers_every_angle_of_its_foot(session) -> None:
    """CGM 2.3 on the twisted session: every angle component within 0.01 deg of the CGM
    2.3 truth (the knee is thigh -> marker-based shank, the foot on the turned axis), every
    joint centre within 1e-6 mm."""
    static, walking, cgm23, _ = session
    run = run_angles(walking, static=static, preprocessing=NO_FILTER, model="cgm2.3")
    assert run.result.unavailable == {} and len(run.result.angles) == 10
    worst = _worst(run.result, cgm23)
    assert max(worst.values()) <= BOUND_DEG, worst
    for centre in (side + c for side in "LR" for c in ("HJC", "KJC", "AJC")):
        expected = cgm23[[f"{centre}_{a}" for a in "XYZ"]].to_numpy()
        assert np.abs(run.result.joint_centres[centre] - expected).max() < 1e-6, centre


def test_cgm24_hindfoot_keeps_the_shanks_own_axis(session) -> None:
    """CGM 2.4 on the same session: every angle (forefoot included) within 0.01 deg of the
    hindfoot truth, as pyCGM2's CGM 2.4 hindfoot ignores the torsion."""
    static, walking, _, hindfoot = session
    run = run_angles(walking, static=static, preprocessing=NO_FILTER, model="cgm2.4")
    assert run.result.unavailable == {} and len(run.result.angles) == 12
    worst = _worst(run.result, hindfoot)
    assert max(worst.values()) <= BOUND_DEG, worst


def test_the_turned_axis_changes_only_the_foot(session) -> None:
    """The check above is not trivially met: the two feet differ by degrees (the torsion
    effect, ankle and foot progression only); pelvis, hip and knee truths are equal."""
    static, walking, cgm23, hindfoot = session
    run = run_angles(walking, static=static, preprocessing=NO_FILTER, model="cgm2.3")
    off = _worst(run.result, hindfoot)
    assert min(off[name] for name in FOOT_OUTPUTS) > 1.0 and max(off[name] for name in FOOT_OUTPUTS) < 10.0
    for name in ("LPelvisAngles", "RHipAngles", "LKneeAngles", "RKneeAngles"):
        assert np.array_equal(_expected(cgm23, name), _expected(hindfoot, name)), name
        assert off[name] <= BOUND_DEG


# ------------------------------------------------------------------------ without MED
def test_without_med_there_is_no_torsion_and_the_foot_is_unchanged(session) -> None:
    """A static trial without KNM/MED (chord centres): no torsion calibrated, TibialTorsion
    kept (0), and the CGM 2.3 foot is the Plug-in Gait foot on the shank's own axis, bit
    for bit what the chain gives with the turned axis switched off; it matches the
    hindfoot truth."""
    static, walking, _, hindfoot = session
    plain = static.select_markers([m for m in static.marker_labels if m[1:] not in ("KNM", "MED")])
    run = calibrate_static(plain, resolve_subject(walking, None), model="cgm2.3")
    assert run.clusters is not None and run.clusters.shank_torsions == {}
    assert run.subject.left.tibial_torsion == 0.0 and run.subject.right.tibial_torsion == 0.0
    turned = ClusterChain(walking, run.subject, run.clusters, foot_torsion=True)
    unturned = ClusterChain(walking, run.subject, run.clusters, foot_torsion=False)
    for side in "LR":
        assert np.array_equal(turned.uncorrected_foot(side), unturned.uncorrected_foot(side))
    result = compute_lower_body(walking, run.subject, model="cgm2.3", clusters=run.clusters)
    worst = _worst(result, hindfoot)
    assert max(worst.values()) <= BOUND_DEG, worst


def test_a_zero_torsion_changes_no_marker_and_no_truth() -> None:
    """``tibial_torsion=(0, 0)`` is the default session, and its CGM 2.3 foot truth is the
    hindfoot's."""
    default, truth = make_cgm24_walking(n_cycles=1)
    zero, zero_truth = make_cgm24_walking(n_cycles=1, geometry=Cgm24Geometry(tibial_torsion=(0.0, 0.0)),
                                          foot_truth="cgm2.3")  # fmt: skip
    assert np.array_equal(default.markers, zero.markers)
    assert np.array_equal(make_cgm24_static().markers, make_cgm24_static(geometry=Cgm24Geometry()).markers)
    assert truth.equals(zero_truth)


# ------------------------------------------------------------------------ subject file
def test_the_torsion_goes_through_the_subject_file(session, tmp_path: Path) -> None:
    """``calibrate`` writes the torsion (TibialTorsion and the cluster table), and walking
    trials processed from the file alone get the static trial's angles."""
    static, walking, _, _ = session
    written = calibrate_to_file(static, tmp_path / "cal.toml", model="cgm2.3")
    assert "shank_torsion" in (tmp_path / "cal.toml").read_text()
    with_static = run_angles(walking, static=static, model="cgm2.3", preprocessing=NO_FILTER)
    from_file = run_angles(walking, subject_file=tmp_path / "cal.toml", model="cgm2.3", preprocessing=NO_FILTER)
    assert written.calibration.clusters is not None
    assert from_file.subject.left.tibial_torsion == pytest.approx(TORSION[0], abs=1e-9)
    for name, values in with_static.result.angles.items():
        assert np.array_equal(values, from_file.result.angles[name]), name


def test_the_table_round_trips_and_refuses_malformed_torsions(session) -> None:
    static, walking, _, _ = session
    clusters = calibrate_clusters(static, resolve_subject(walking, None), "medial")
    table = cluster_table(clusters)
    again = clusters_from_table(table, "cal.toml")
    assert again is not None and again.shank_torsions == clusters.shank_torsions
    without = clusters_from_table({k: v for k, v in table.items() if k != "shank_torsion"}, "old.toml")
    assert without is not None and without.shank_torsions == {}
    bad = {**table, "shank_torsion": {"L": {"tibial_torsion": 12.0, "foot_correction": 0.0}}}
    with pytest.raises(ParameterError, match=r"\[calibration.shank_torsion\] L must be"):
        clusters_from_table(bad, "cal.toml")
    with pytest.raises(ParameterError, match="must hold L and/or R"):
        clusters_from_table({**table, "shank_torsion": {"X": {}}}, "cal.toml")
