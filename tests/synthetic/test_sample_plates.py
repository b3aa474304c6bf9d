"""The sample walking trial's synthetic force plates (fuzzygait.synthetic.force_plates):
the loads as designed, read back from the committed files as written, each stance on its
own plate under its own foot, and the demo's kinetics lines."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.kinetics.plates import read_force_plates
from fuzzygait.synthetic.force_plates import (
    FOOT_OFF_PHASE,
    PLATE_AXES,
    SAMPLES_PER_FRAME,
    STRIDE_TIME_S,
    G,
    SyntheticPlate,
    sample_walking_plates,
    stance_cop,
    stance_loads,
)
from fuzzygait.synthetic.generate import LEAD_IN_CYCLES, WALKING_SPEED_MM_S, walking_state
from fuzzygait.synthetic.leg_model import SubjectGeometry
from support import SAMPLE_DATA

MASS = SubjectGeometry().bodymass
N_FRAMES, RATE = 512, 100.0


def test_both_feet_carry_the_body_weight_over_a_stride_with_no_net_braking():
    """Left and right stances over one stride (right half a stride later): the mean vertical
    force is the weight, the anterior-posterior and medio-lateral impulses cancel."""
    t = np.linspace(0.0, STRIDE_TIME_S, 200_001)[:-1]
    phase = t / STRIDE_TIME_S
    left, _ = stance_loads(phase / FOOT_OFF_PHASE, MASS, "L")
    right, _ = stance_loads(((phase - 0.5) % 1.0) / FOOT_OFF_PHASE, MASS, "R")
    mean = (left + right).mean(axis=0)  # N: mean over the stride
    assert mean[2] == pytest.approx(MASS * G, rel=1e-9)
    assert abs(mean[0]) < 1e-6 and abs(mean[1]) < 1e-6
    # braking first (against +X), propulsion later; the left foot pushed towards -Y (medial)
    assert left[int(0.1 * len(t)), 0] < 0 < left[int(0.5 * len(t)), 0] and left[int(0.3 * len(t)), 1] < 0
    # a double hump: two peaks of 1.14 body weights, 0.71 between
    fz = left[: int(FOOT_OFF_PHASE * len(t)), 2] / (MASS * G)
    assert fz.max() == pytest.approx(1.1402, abs=1e-3) and fz[len(fz) // 2] == pytest.approx(0.709, abs=1e-3)


def test_the_centre_of_pressure_runs_from_heel_to_toe_on_the_floor():
    s = np.array([-0.1, 0.0, 0.5, 1.0, 1.1])
    heel, toe = np.tile([0.0, 0.0, 30.0], (5, 1)), np.tile([200.0, 20.0, 40.0], (5, 1))
    cop = stance_cop(s, heel, toe)
    assert np.all(np.isnan(cop[[0, 4]]))
    np.testing.assert_allclose(cop[1:4], [[10.0, 1.0, 0.0], [100.0, 10.0, 0.0], [190.0, 19.0, 0.0]], atol=1e-12)


def test_type2_channels_give_back_force_cop_and_free_moment():
    """The C3D type-2 rule applied to the channels (COP = (-My, Mx) / Fz about the surface
    centre, the moment about the transducer 41 mm below) returns the loads."""
    plate = SyntheticPlate((-100.0, 50.0, 0.0))
    force = np.array([[30.0, -20.0, 600.0], [-50.0, 10.0, 250.0]])
    cop = np.array([[-150.0, 80.0, 0.0], [20.0, 40.0, 0.0]])
    free = np.array([1200.0, -800.0])
    ch = plate.channels(force, cop, free)
    f_p, m_c = ch[:, :3], ch[:, 3:] + np.cross([0.0, 0.0, 41.0], ch[:, :3])
    x, y = -m_c[:, 1] / f_p[:, 2], m_c[:, 0] / f_p[:, 2]
    np.testing.assert_allclose(f_p @ PLATE_AXES.T, force, rtol=1e-14)
    np.testing.assert_allclose(np.column_stack([x, y, np.zeros(2)]) @ PLATE_AXES.T + plate.centre, cop, atol=1e-12)
    tz = m_c[:, 2] - (x * f_p[:, 1] - y * f_p[:, 0])  # about the plate's z (down)
    np.testing.assert_allclose(-tz, free, rtol=1e-12)
    assert np.all(f_p[:, 2] < 0)  # the reaction on the body: Fz < 0 in the plate frame (z down)


def test_the_body_mass_must_be_positive():
    with pytest.raises(ParameterError, match="body mass"):
        sample_walking_plates(N_FRAMES, RATE, 0.0)


@pytest.fixture(scope="module")
def generated():
    return sample_walking_plates(N_FRAMES, RATE, MASS)


def test_the_committed_trials_hold_the_generated_plates(generated):
    for name in ("walking.c3d", "walking_noisy.c3d"):
        plates = read_force_plates(SAMPLE_DATA / name)
        assert [(p.number, p.kind, p.rate) for p in plates] == [(1, 2, 1000.0), (2, 2, 1000.0)]
        for plate, rec in zip(plates, generated, strict=True):
            assert not plate.findings
            np.testing.assert_allclose(plate.corners, rec.plate.corners(), atol=1e-4)
            force = rec.channels[:, :3] @ PLATE_AXES.T
            np.testing.assert_allclose(plate.force, force, atol=1e-4 * np.abs(force).max())  # float32
            assert plate.contact.sum() == np.count_nonzero(-rec.channels[:, 2] > 10.0) == 657


def test_each_stance_is_on_its_plate_under_its_own_foot(generated):
    """Plate 1 under the second left stance, plate 2 under the right one after it: the
    loaded samples' centre of pressure lies on the plate, on the foot's heel-toe line."""
    plates = read_force_plates(SAMPLE_DATA / "walking.c3d")
    times = np.arange(N_FRAMES * SAMPLES_PER_FRAME) / (RATE * SAMPLES_PER_FRAME)
    x_offset = -WALKING_SPEED_MM_S * (N_FRAMES - 1) / RATE / 2  # the walk centred on X = 0, as generated
    pose, _, _ = walking_state(times, None, LEAD_IN_CYCLES * STRIDE_TIME_S, x_offset)
    for plate, side in zip(plates, "LR", strict=True):
        loaded = plate.contact & (plate.force[:, 2] > 50.0)  # N, the reaction up
        heel, toe = pose.markers[side + "HEE"][loaded], pose.markers[side + "TOE"][loaded]
        cop = plate.cop[loaded]
        lo, hi = plate.corners.min(axis=0), plate.corners.max(axis=0)
        assert np.all((cop[:, :2] > lo[:2] + 100) & (cop[:, :2] < hi[:2] - 100))
        d = (toe - heel)[:, :2]
        r = (cop - heel)[:, :2]
        off_line = np.abs(d[:, 0] * r[:, 1] - d[:, 1] * r[:, 0]) / np.linalg.norm(d, axis=1)
        assert off_line.max() < 0.05  # mm: float32 moments over Fz
        start = np.flatnonzero(plate.contact)[0] / (RATE * SAMPLES_PER_FRAME)
        strike = LEAD_IN_CYCLES * STRIDE_TIME_S + (1.0 if side == "L" else 1.5) * STRIDE_TIME_S
        assert start == pytest.approx(strike, abs=0.01)


def test_the_pipeline_assigns_each_plate_to_its_foot_and_the_demo_reports_the_peaks():
    from fuzzygait.workflows.angles import run_angles
    from fuzzygait.workflows.demo import kinetics_lines

    run = run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d",
                     subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip
    kinetics = run.kinetics
    assert kinetics is not None and not kinetics.unused()
    assert kinetics.plates_used(Side.LEFT) == (1,) and kinetics.plates_used(Side.RIGHT) == (2,)
    lines = kinetics_lines(run)
    assert any(line.startswith("- The forces are synthetic") for line in lines)
    left = next(line for line in lines if line.startswith("| left | 1 |"))
    contact = next(c for c in kinetics.contacts if c.side is Side.LEFT)
    ankle = kinetics.data["moment"].sel(side="L", joint="Ankle", axis="X").values[contact.first : contact.last + 1]
    assert left.split(" | ")[2] == f"{np.nanmax(ankle):.2f} / {np.nanmin(ankle):.2f}"
    assert 0.8 < np.nanmax(ankle) < 1.6  # a plausible peak plantarflexor moment, N·m/kg
