"""Tests of the synthetic CGM 2.4 session against independent reconstructions."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from fuzzygait.synthetic import DYNAMIC_LABELS, make_walking_trial
from fuzzygait.synthetic.cgm24 import (
    CGM24_DYNAMIC_LABELS,
    CGM24_STATIC_LABELS,
    Cgm24Geometry,
    cgm24_static_pose,
    forefoot_angle_columns,
    make_cgm24_static,
    make_cgm24_walking,
    neutral_forefoot_angles,
)
from fuzzygait.synthetic.generate import angle_columns, joint_centre_columns
from fuzzygait.synthetic.leg_model import SubjectGeometry

SIDE_MARKERS = ["THAP", "THAD", "THI", "KNE", "TIAP", "TIAD", "TIB", "ANK",
                "HEE", "TOE", "FMH", "SMH", "VMH"]  # fmt: skip


# --------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def walking():
    return make_cgm24_walking()


@pytest.fixture(scope="module")
def trial(walking):
    return walking[0]


@pytest.fixture(scope="module")
def truth(walking):
    return walking[1]


@pytest.fixture(scope="module")
def static():
    return make_cgm24_static()


def jc(truth, name: str) -> np.ndarray:
    return truth[[f"{name}_X", f"{name}_Y", f"{name}_Z"]].to_numpy()


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# --------------------------------------------------------------------------- marker sets
def test_marker_sets(trial, static):
    pelvis = ["LASI", "RASI", "LPSI", "RPSI"]
    per_side = [s + m for s in "LR" for m in SIDE_MARKERS]
    medial = ["LKNM", "RKNM", "LMED", "RMED"]
    assert trial.marker_labels == pelvis + per_side == list(CGM24_DYNAMIC_LABELS)
    assert static.marker_labels == pelvis + per_side + medial == list(CGM24_STATIC_LABELS)
    assert not set(medial) & set(trial.marker_labels)
    assert np.all(np.isfinite(trial.markers)) and np.all(np.isfinite(static.markers))
    assert trial.n_frames == 512 and static.n_frames == 200
    assert len(trial.events) > 0 and not static.events


def test_truth_columns(truth):
    expected = ["frame", "time_s", *angle_columns(), *joint_centre_columns(),
                *forefoot_angle_columns(), *[f"{s}FJC_{a}" for s in "LR" for a in "XYZ"],
                *[f"{s}FootProgressAngles_{a}" for s in "LR" for a in "XYZ"]]  # fmt: skip
    assert list(truth.columns) == expected
    assert np.all(np.isfinite(truth.to_numpy()))


# --------------------------------------------------------------------------- static
@pytest.mark.parametrize("hjc", ["hara", "davis"])
def test_medial_midpoints_are_joint_centres(hjc):
    static = make_cgm24_static(hjc=hjc)
    pose = cgm24_static_pose(hjc=hjc)
    p = static.parameters
    d = p["MarkerDiameter"]
    for side in "LR":
        kne, knm = static.marker(side + "KNE"), static.marker(side + "KNM")
        ank, med = static.marker(side + "ANK"), static.marker(side + "MED")
        kjc, ajc = pose.joint_centres[side + "KJC"], pose.joint_centres[side + "AJC"]
        np.testing.assert_allclose((kne + knm) / 2, kjc, atol=1e-9, rtol=0)
        np.testing.assert_allclose((ank + med) / 2, ajc, atol=1e-9, rtol=0)
        # each at width/2 + marker radius from the centre; pyCGM2's widthFromMp formula
        np.testing.assert_allclose(np.linalg.norm(kne - kjc, axis=1), (p[side + "KneeWidth"] + d) / 2,
                                   atol=1e-9)  # fmt: skip
        np.testing.assert_allclose(np.linalg.norm(ank - ajc, axis=1), (p[side + "AnkleWidth"] + d) / 2,
                                   atol=1e-9)  # fmt: skip
        np.testing.assert_allclose(kne + (p[side + "KneeWidth"] + d) / 2 * unit(knm - kne), kjc,
                                   atol=1e-9)  # fmt: skip
        # KNE-KNM along the thigh's flexion axis: perpendicular to HJC-KJC
        thigh = unit(pose.joint_centres[side + "HJC"] - kjc)
        assert np.abs(np.sum(unit(kne - knm) * thigh, axis=1)).max() < 1e-12
        shank = unit(kjc - ajc)
        assert np.abs(np.sum(unit(ank - med) * shank, axis=1)).max() < 1e-12


def test_static_stands_on_the_floor_every_frame_equal(static):
    assert np.ptp(static.markers, axis=0).max() == 0.0
    g = Cgm24Geometry()
    for side in "LR":
        # HEE and TOE (dorsal mid-foot) at the same height above the floor
        hee, toe = static.marker(side + "HEE")[0], static.marker(side + "TOE")[0]
        assert hee[2] == pytest.approx(g.sole_depth + g.hee_local[2], abs=1e-9)
        assert toe[2] == pytest.approx(hee[2], abs=1e-9)
        for m in ("FMH", "SMH", "VMH"):
            assert 0.0 < static.marker(side + m)[0, 2] < toe[2]


# --------------------------------------------------------------------------- rigid bodies
def test_rigid_placement(trial, truth):
    m = {label: trial.marker(label) for label in trial.marker_labels}
    m.update({n: jc(truth, n) for s in "LR" for n in (s + "HJC", s + "KJC", s + "AJC", s + "FJC")})
    segments = [["LASI", "RASI", "LPSI", "RPSI", "LHJC", "RHJC"]]
    for s in "LR":
        segments += [
            [s + n for n in ("HJC", "KJC", "THAP", "THAD", "THI", "KNE")],
            [s + n for n in ("KJC", "AJC", "TIAP", "TIAD", "TIB", "ANK")],
            [s + n for n in ("AJC", "FJC", "HEE", "TOE")],  # hindfoot
            [s + n for n in ("TOE", "FMH", "SMH", "VMH")],  # forefoot (rotates about TOE)
        ]
    for seg in segments:
        for a, b in itertools.combinations(seg, 2):
            d = np.linalg.norm(m[a] - m[b], axis=1)
            assert np.ptp(d) < 1e-9, (a, b, np.ptp(d))
            assert d.min() > 10.0, (a, b)
    # the forefoot really moves relative to the hindfoot
    for s in "LR":
        for fore in ("FMH", "SMH", "VMH"):
            spread = [np.ptp(np.linalg.norm(m[s + fore] - m[s + h], axis=1)) for h in ("HEE", "AJC")]
            assert max(spread) > 0.5, (fore, spread)


def test_static_and_walking_share_the_skeleton(trial, static):
    # distances within rigid groups equal between the static and the walking trial
    pairs = [("THAP", "KNE"), ("THAD", "THI"), ("TIAP", "ANK"), ("TIAD", "TIB"),
             ("HEE", "TOE"), ("FMH", "VMH"), ("SMH", "TOE"), ("FMH", "TOE")]  # fmt: skip
    for s in "LR":
        for a, b in pairs:
            dw = np.linalg.norm(trial.marker(s + a) - trial.marker(s + b), axis=1)
            ds = np.linalg.norm(static.marker(s + a) - static.marker(s + b), axis=1)
            assert dw[0] == pytest.approx(ds[0], abs=1e-9)


# --------------------------------------------------------------------------- clusters
@pytest.mark.parametrize("side", ["L", "R"])
def test_clusters_not_coplanar(trial, side):
    for names in (("THAP", "THAD", "THI", "KNE"), ("TIAP", "TIAD", "TIB", "ANK")):
        X = np.stack([trial.marker(side + n)[0] for n in names])
        sv = np.linalg.svd(X - X.mean(axis=0), compute_uv=False)
        assert sv[-1] > 5.0, (names, sv)
    # THAP/THAD anterior of the thigh axis, THAP proximal of THAD (TIAP/TIAD likewise)
    static = make_cgm24_static()
    pose = cgm24_static_pose()
    for prox_m, dist_m, prox, dist in (("THAP", "THAD", "HJC", "KJC"), ("TIAP", "TIAD", "KJC", "AJC")):
        a, b = static.marker(side + prox_m)[0], static.marker(side + dist_m)[0]
        top, bottom = pose.joint_centres[side + prox][0], pose.joint_centres[side + dist][0]
        assert bottom[2] < b[2] < a[2] < top[2]
        assert a[0] > top[0] + 30 and b[0] > bottom[0] + 30


# --------------------------------------------------------------------------- HJC
def _pelvis_frame(trial) -> tuple[np.ndarray, np.ndarray]:
    lasi, rasi = trial.marker("LASI"), trial.marker("RASI")
    sacr = (trial.marker("LPSI") + trial.marker("RPSI")) / 2
    origin = (lasi + rasi) / 2
    y = unit(lasi - rasi)
    z = unit(np.cross(y, sacr - rasi))
    return origin, np.stack([np.cross(y, z), y, z], axis=-1)


def _hara_expected(leg: float, side: str) -> np.ndarray:
    """Hara et al. 2016 as pyCGM2's haraRegression (14 mm markers, 2 mm base plate)."""
    sign = 1.0 if side == "L" else -1.0
    return np.array([11.0 - 0.063 * leg - 7.0 - 2.0, sign * (8.0 + 0.086 * leg), -9.0 - 0.078 * leg])


def test_hara_hjc(trial, truth, static):
    origin, R = _pelvis_frame(trial)
    leg = trial.parameters["LLegLength"]
    assert trial.parameters["RLegLength"] == leg == 900.0
    for side in "LR":
        local = np.einsum("nji,nj->ni", R, jc(truth, side + "HJC") - origin)
        np.testing.assert_allclose(local, np.tile(_hara_expected(leg, side), (trial.n_frames, 1)),
                                   atol=1e-9)  # fmt: skip
    # pyCGM2's reference subject (LL = 1000 mm): (-61, +-94, -87)
    np.testing.assert_allclose(_hara_expected(1000.0, "R"), [-61.0, -94.0, -87.0], atol=1e-12)
    # the static trial too
    origin, R = _pelvis_frame(static)
    pose = cgm24_static_pose()
    for side in "LR":
        local = np.einsum("nji,nj->ni", R, pose.joint_centres[side + "HJC"] - origin)
        np.testing.assert_allclose(local[0], _hara_expected(leg, side), atol=1e-9)


def test_davis_option_reproduces_plug_in_gait_trial():
    """With ``hjc="davis"`` and the Plug-in Gait foot (TOE, HEE) the shared skeleton and its
    truth are exactly those of the (unchanged) Plug-in Gait generator."""
    plug_in_gait = SubjectGeometry()  # its THI/TIB wands (the CGM 2.4 defaults are a real session's)
    pig_foot = Cgm24Geometry(toe_local=(140.0, 0.0, -60.0), hee_local=(-50.0, 0.0, -60.0),
                             fmh_local=(185.0, -35.0, -72.0), smh_local=(190.0, -5.0, -65.0),
                             vmh_local=(170.0, 38.0, -74.0),
                             thi_fraction=plug_in_gait.thi_fraction, thi_offset=plug_in_gait.thi_offset,
                             tib_fraction=plug_in_gait.tib_fraction, tib_offset=plug_in_gait.tib_offset)  # fmt: skip
    trial, truth = make_cgm24_walking(geometry=pig_foot, hjc="davis")
    pig, pig_truth = make_walking_trial()
    assert pig.marker_labels == list(DYNAMIC_LABELS)
    assert pig.n_frames == trial.n_frames == 512
    for label in DYNAMIC_LABELS:
        assert np.array_equal(trial.marker(label), pig.marker(label)), label
    cols = ["frame", "time_s", *angle_columns(), *joint_centre_columns()]
    assert list(pig_truth.columns) == cols
    assert np.array_equal(truth[cols].to_numpy(), pig_truth[cols].to_numpy())
    assert trial.parameters == pig.parameters
    assert [(e.label, e.context, e.time) for e in trial.events] == [
        (e.label, e.context, e.time) for e in pig.events
    ]
    # the default CGM 2.4 subject: pelvis, hip and knee truth the same; Hara moves the
    # HJC, the walker is lowered by the standing-height difference
    default_davis = make_cgm24_walking(hjc="davis")[1]
    hara = make_cgm24_walking()[1]
    same = [c for c in angle_columns() if "Ankle" not in c]
    assert np.array_equal(default_davis[same].to_numpy(), pig_truth[same].to_numpy())
    assert np.array_equal(hara[same].to_numpy(), pig_truth[same].to_numpy())
    shift = Cgm24Geometry().height_shift()
    assert shift == pytest.approx(-96.585468734 + 79.2, abs=1e-6)
    assert not np.allclose(jc(hara, "LHJC"), jc(default_davis, "LHJC"))


def test_unknown_hjc_rejected():
    from fuzzygait.core.errors import ParameterError

    with pytest.raises(ParameterError):
        make_cgm24_static(hjc="bell")


# --------------------------------------------------------------------------- forefoot
def _frame(a1: np.ndarray, v: np.ndarray, side: str) -> np.ndarray:
    """pyCGM2 ZXiY (left) / ZXY (right) frame from a1 (Z) and v, columns (X, Y, Z)."""
    z = unit(a1)
    x = unit(np.cross(z, v)) * (-1.0 if side == "L" else 1.0)
    return np.stack([x, np.cross(z, x), z], axis=-1)


def _cardan_yxz(R: np.ndarray) -> np.ndarray:
    e1 = np.arctan2(R[:, 0, 2], R[:, 2, 2])
    e2 = np.arcsin(-R[:, 1, 2])
    e3 = np.arctan2(R[:, 1, 0], R[:, 1, 1])
    return np.degrees(np.stack([e1, e2, e3], axis=-1))


def _descriptor(e: np.ndarray, side: str) -> np.ndarray:
    """pyCGM2 LForeFoot/RForeFoot descriptor: order [0,2,1], signs L (-,-,-), R (-,+,+)."""
    out = e[:, [0, 2, 1]].copy()
    out *= np.array([-1.0, -1.0, -1.0]) if side == "L" else np.array([-1.0, 1.0, 1.0])
    return out


@pytest.mark.parametrize("side", ["L", "R"])
def test_forefoot_angles_pycgm2_construction(trial, truth, static, side):
    """Rebuild pyCGM2's hindfoot and forefoot frames from the markers (static calibration,
    then per walking frame) and compare the ForeFootAngles with the truth."""
    sign = -1.0 if side == "L" else 1.0

    def hindfoot(hee, toe, ajc):
        z = unit(hee - toe)
        up = (ajc - hee) - np.sum((ajc - hee) * z, axis=1, keepdims=True) * z
        x = unit(up)
        return np.stack([x, np.cross(z, x), z], axis=-1)

    def markers(trl):
        return [trl.marker(side + n) for n in ("HEE", "TOE", "FMH", "VMH", "SMH")]

    # static calibration
    hee0, toe0, fmh0, vmh0, smh0 = markers(static)
    ajc0 = (static.marker(side + "ANK") + static.marker(side + "MED")) / 2
    H0 = hindfoot(hee0, toe0, ajc0)
    n = np.cross(unit(vmh0 - toe0), unit(fmh0 - toe0))
    fjc0 = toe0 - 14.0 * sign * n
    assert fjc0[0, 2] < toe0[0, 2] - 5.0  # FJC plantar of TOE
    T0 = _frame(toe0 - fmh0, vmh0 - fmh0, side)
    loc = np.einsum("nji,nj->ni", T0, smh0 - toe0)
    loc[:, 0] = 0.0
    vsmh0 = toe0 + np.einsum("nij,nj->ni", T0, loc)
    A0 = _frame(fjc0 - vsmh0, vmh0 - vsmh0, side)
    R_TA = (np.swapaxes(T0, 1, 2) @ A0)[0]
    static_angles = _descriptor(_cardan_yxz(np.swapaxes(H0, 1, 2) @ A0), side)
    np.testing.assert_allclose(static_angles[0], neutral_forefoot_angles(None, side), atol=1e-9)
    # FJC is a hindfoot node: its static local coordinates give the truth FJC
    fjc_local = H0[0].T @ (fjc0[0] - toe0[0])

    # walking
    hee, toe, fmh, vmh, _ = markers(trial)
    H = hindfoot(hee, toe, jc(truth, side + "AJC"))
    A = _frame(toe - fmh, vmh - fmh, side) @ R_TA
    angles = _descriptor(_cardan_yxz(np.swapaxes(H, 1, 2) @ A), side)
    expected = truth[[f"{side}ForeFootAngles_{a}" for a in "XYZ"]].to_numpy()
    np.testing.assert_allclose(angles, expected, atol=1e-9, rtol=0)
    assert np.ptp(expected, axis=0).min() > 2.0  # a few degrees of motion per component
    assert np.abs(expected - static_angles[0]).max() < 10.0
    np.testing.assert_allclose(toe + np.einsum("nij,j->ni", H, fjc_local), jc(truth, side + "FJC"),
                               atol=1e-9)  # fmt: skip


def test_left_right_symmetric_neutral_forefoot():
    np.testing.assert_allclose(neutral_forefoot_angles(None, "L"), neutral_forefoot_angles(None, "R"),
                               atol=1e-12)  # fmt: skip


# --------------------------------------------------------------------------- misc
def test_deterministic_and_feet_above_floor(trial, truth):
    again, truth2 = make_cgm24_walking()
    assert np.array_equal(again.markers, trial.markers)
    assert truth2.equals(truth)
    # no contact model: the forefoot markers dip at most a few mm below the floor at push
    # off (the Plug-in Gait trial's sole points dip about as much)
    assert trial.markers[:, :, 2].min() > -10.0
    for side in "LR":
        assert np.median(trial.marker(side + "FMH")[:, 2]) > 10.0
    # walking forward
    assert np.all(np.diff(trial.marker("LASI")[:, 0]) > 0)


@pytest.mark.parametrize("side", ["L", "R"])
def test_hindfoot_is_the_cgm1_foot(trial, truth, side):
    """The hindfoot (HEE, TOE on the dorsal mid-foot, AJC) is also what the CGM1 foot
    construction (TOE, AJC, shank flexion axis, StaticPlantFlex) gives, and the ankle angles
    of the truth are shank -> hindfoot."""
    s = 1.0 if side == "L" else -1.0
    kjc, ajc = jc(truth, side + "KJC"), jc(truth, side + "AJC")
    toe, hee = trial.marker(side + "TOE"), trial.marker(side + "HEE")
    z_s = unit(kjc - ajc)
    x_s = unit(np.cross(unit(s * (trial.marker(side + "ANK") - ajc)), z_s))
    shank = np.stack([x_s, np.cross(z_s, x_s), z_s], axis=-1)
    # hindfoot from HEE -> TOE and the AJC above them
    x_h = unit(toe - hee)
    y_h = unit(np.cross(ajc - hee, x_h))
    hind = np.stack([x_h, y_h, np.cross(x_h, y_h)], axis=-1)
    # CGM1 uncorrected foot: forward along AJC -> TOE, y = shank y made perpendicular
    u = unit(toe - ajc)
    y_s = shank[:, :, 1]
    y_u = unit(y_s - np.sum(y_s * u, axis=1, keepdims=True) * u)
    U = np.stack([u, y_u, np.cross(u, y_u)], axis=-1)
    beta = trial.parameters[side + "StaticPlantFlex"]
    c, sn = np.cos(-beta), np.sin(-beta)
    Ry = np.array([[c, 0.0, sn], [0.0, 1.0, 0.0], [-sn, 0.0, c]])
    np.testing.assert_allclose(U @ Ry, hind, atol=1e-9)
    # ankle angles: Y-Z-X with the Plug-in Gait signs (-1, +s, -s)
    R = np.swapaxes(shank, 1, 2) @ hind
    a = np.arctan2(-R[:, 2, 0], R[:, 0, 0])
    b = np.arcsin(R[:, 1, 0])
    cc = np.arctan2(-R[:, 1, 2], R[:, 1, 1])
    angles = np.degrees(np.stack([a, cc, b], axis=-1)) * np.array([-1.0, s, -s])
    expected = truth[[f"{side}AnkleAngles_{ax}" for ax in "XYZ"]].to_numpy()
    np.testing.assert_allclose(angles, expected, atol=1e-9)


# --------------------------------------------------------------------------- foot progression
@pytest.mark.parametrize("side", ["L", "R"])
def test_foot_progression_meaning(trial, truth, side):
    """From the markers, not the definition: Z + = toes medial, X = -90 + toes-down pitch."""
    s = 1.0 if side == "L" else -1.0
    heading = unit(trial.marker(side + "TOE") - trial.marker(side + "HEE"))  # along the foot
    toe_in = np.degrees(np.arctan2(-s * heading[:, 1], heading[:, 0]))
    down = np.degrees(np.arcsin(-heading[:, 2]))
    angles = truth[[f"{side}FootProgressAngles_{a}" for a in "XYZ"]].to_numpy()
    # the heading's azimuth is Z only for a nearly level foot (Z is about the pitched
    # dorsal axis); its feet roll only a few degrees
    level = np.abs(down) < 10.0
    assert level.sum() > 100
    assert np.abs(angles[level, 2] - toe_in[level]).max() < 0.5
    assert np.abs(angles[:, 0] - (down - 90.0)).max() < 5.0  # roll and yaw mix in a little
    assert np.ptp(angles[:, 0]) > 20.0 and np.ptp(angles[:, 2]) > 5.0


def test_foot_progression_single_turns():
    from fuzzygait.synthetic.leg_model import foot_progression_angles, rot_y, rot_z

    for side, s in (("L", 1.0), ("R", -1.0)):
        turned = rot_z(np.radians(-s * 10.0))[None]  # toes 10 deg medial
        np.testing.assert_allclose(foot_progression_angles(turned, side), [[-90.0, 0.0, 10.0]], atol=1e-12)
        up = rot_y(np.radians(-15.0))[None]  # toes 15 deg up (about +y, x -> z is negative)
        np.testing.assert_allclose(foot_progression_angles(up, side), [[-105.0, 0.0, 0.0]], atol=1e-12)


@pytest.mark.parametrize(("hjc", "model"), [("davis", "cgm1.0"), ("hara", "cgm2.4")])
def test_foot_progression_reproduced(hjc, model):
    """cgm1.0 on the Davis session and cgm2.4 on the Hara session reproduce it (<= 0.01 deg)."""
    from fuzzygait.workflows.angles import Preprocessing, run_angles

    trial, truth = make_cgm24_walking(hjc=hjc)
    run = run_angles(trial, static=make_cgm24_static(hjc=hjc), preprocessing=Preprocessing(filter=False),
                     model=model)  # fmt: skip
    for side in "LR":
        expected = truth[[f"{side}FootProgressAngles_{a}" for a in "XYZ"]].to_numpy()
        assert np.abs(run.result.angles[side + "FootProgressAngles"] - expected).max() <= 0.01
