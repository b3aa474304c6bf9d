"""Fuzzy joint moments in the outputs (issue 39 item 5): ``MarkerErrorSettings.kinetics``
runs them on the run's plates and contacts, the result's ``/kinetics`` group, what
``uncertainty --kinetics`` prints, the trial page's bands and allowable answer.

Speed: the sample walking trial (synthetic plates: plate 1 under the left foot on frames
122-186, plate 2 under the right) with every marker NaN outside the 40 frames 128-167 of
the left stance, the left knee angles only, α = 0 and 0.5, one worker.

Truth: α = 1 is the measured value, so the hull there must be the pipeline's Plug-in
Gait kinetics (computed independently by :func:`fuzzygait.kinetics.plug_in_gait.
plug_in_gait_kinetics`, tests/kinetics check them against Nexus); the page's band over
the one counted left cycle is that cycle's hull resampled to 0-100 %.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from fuzzygait.cli.marker_errors import DEFAULT_COP_ERROR_MM, DEFAULT_KINETIC_TOLERANCE, kinetics_text
from fuzzygait.core.findings import messages
from fuzzygait.gait.cycles import gait_cycles
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.markererror import fuzzy_kinetics, moment_model
from fuzzygait.markererror.fuzzy_kinetics import allowable_kinetic_error
from fuzzygait.markererror.result import error_sources, kinetic_part, read_marker_result, save_marker_result
from fuzzygait.testing import check_result
from fuzzygait.workflows import trial_inputs
from fuzzygait.workflows.angles import AnglesRun, run_angles
from fuzzygait.workflows.marker_uncertainty import MarkerErrorAnalysis, MarkerErrorSettings, analyse_run
from support import SAMPLE_DATA, run_here

WINDOW = slice(128, 168)
SETTINGS = MarkerErrorSettings(alphas=(0.0, 0.5), angles=("LKneeAngles",), workers=1, tolerance=None,
                               per_source=False, kinetics=True)  # fmt: skip
MOMENTS = [f"{s}{j}Moment_X" for s in "LR" for j in ("Ankle", "Knee", "Hip")]
POWERS = [f"{s}{j}Power_Z" for s in "LR" for j in ("Ankle", "Knee", "Hip")]


def cut(run: AnglesRun) -> AnglesRun:
    markers = np.full_like(run.trial.markers, np.nan)
    markers[WINDOW] = run.trial.markers[WINDOW]
    return dataclasses.replace(run, trial=run.trial.with_markers(markers))


@pytest.fixture(scope="module")
def stance_run(angles_run: AnglesRun) -> AnglesRun:
    return cut(angles_run)


class Stages:
    """Records the stages and updates a workflow reports."""

    def __init__(self) -> None:
        self.seen: list[tuple[str, int | None]] = []

    def stage(self, description: str, total: int | None = None) -> None:
        self.seen.append((description, total))

    def update(self, completed: int, total: int | None = None) -> None:
        self.seen.append(("update", completed))


STAGES = Stages()


@pytest.fixture(scope="module")
def analysis(stance_run: AnglesRun) -> MarkerErrorAnalysis:
    return analyse_run(stance_run, SETTINGS, stages=STAGES)


def test_defaults_are_the_librarys() -> None:
    assert DEFAULT_COP_ERROR_MM == moment_model.DEFAULT_COP_ERROR_MM == MarkerErrorSettings().cop_error_mm
    assert DEFAULT_KINETIC_TOLERANCE == fuzzy_kinetics.DEFAULT_TOLERANCE == MarkerErrorSettings().kinetic_tolerance
    assert MarkerErrorSettings().kinetics is False  # opt-in: ~14x the fuzzy angles' time


def test_the_group_holds_moments_and_powers_at_the_measured_kinetics(analysis: MarkerErrorAnalysis,
                                                                     stance_run: AnglesRun) -> None:  # fmt: skip
    assert analysis.result is not None and analysis.result.kinetics is not None
    kinetics = analysis.result.kinetics
    assert [str(c) for c in kinetics["component"].to_numpy()] == MOMENTS + POWERS
    assert list(kinetics["units"].to_numpy()) == ["N·m/kg"] * 6 + ["W/kg"] * 6
    np.testing.assert_array_equal(kinetics["alpha"], [0.0, 0.5, 1.0])
    assert float(kinetics["ball_radius"].sel(marker="COP1")) == 10.0 and bool(kinetics["cop"].sel(marker="COP2"))
    # α = 1 is the pipeline's Plug-in Gait kinetics (its contacts' loads) on the frames whose
    # nine-frame window lies in the cut; within 5e-4 N·m/kg (W/kg; 1.2e-4 found, largest at
    # the cut's edges): the model's subject measures (inter-ASIS distance, foot length) are
    # means over the cut's frames, the pipeline's over the whole trial (uncut, the model
    # equals the kinetics to 1e-12: tests/markererror/test_fuzzy_kinetics.py)
    assert stance_run.kinetics is not None
    data = stance_run.kinetics.data
    inside = np.arange(WINDOW.start + 4, WINDOW.stop - 4)
    for side in "LR":
        for joint in ("Ankle", "Knee", "Hip"):
            for name, expected in ((f"{side}{joint}Moment_X", data["moment"].sel(side=side, joint=joint, axis="X")),
                                   (f"{side}{joint}Power_Z", data["power"].sel(side=side, joint=joint))):  # fmt: skip
                hull = kinetics["hull"].sel(component=name, alpha=1.0).to_numpy()
                np.testing.assert_array_equal(hull[0], hull[1])
                np.testing.assert_allclose(hull[0, inside], expected.to_numpy()[inside], rtol=0, atol=5e-4)
                outside = np.setdiff1d(np.arange(hull.shape[1]), inside)
                assert np.isnan(hull[:, outside]).all(), name
    # nested bands around the measured value
    hull = kinetics["hull"].isel(frame=inside)
    assert bool((hull.sel(alpha=0.0, bound="lower") <= hull.sel(alpha=0.5, bound="lower") + 1e-9).all())
    assert bool((hull.sel(alpha=0.5, bound="upper") <= hull.sel(alpha=0.0, bound="upper") + 1e-9).all())
    assert bool((hull.sel(alpha=0.5, bound="lower") <= hull.sel(alpha=1.0, bound="lower") + 1e-9).all())
    # the accessor in each kind's units; the allowable answer stored per moment, NaN for powers
    moments, powers = kinetic_part(kinetics, "N·m/kg"), kinetic_part(kinetics, "W/kg")
    assert (moments.fuzzy.units, powers.fuzzy.units) == ("N·m/kg", "W/kg")
    assert moments.fuzzy.delta_phi().sizes == {"component": 6, "alpha": 2}
    for name in MOMENTS:
        answer = allowable_kinetic_error(moments, name, 0.1)
        assert float(kinetics["allowable_scale"].sel(component=name)) == answer.scale
        assert float(kinetics["allowable_cop_mm"].sel(component=name)) == answer.cop_mm
    assert np.isnan(kinetics["allowable_scale"].sel(component=POWERS).to_numpy()).all()
    start = STAGES.seen.index(("fuzzy kinetics", 2))  # after the angles, the moments then the powers
    assert STAGES.seen[start:] == [("fuzzy kinetics", 2), ("update", 1), ("update", 2)]
    (note,) = [n for n in messages(analysis.notes) if n.startswith("fuzzy kinetics")]
    assert note.startswith("fuzzy kinetics: sagittal moments and powers of 6 joints with a 10 mm centre-of-pressure "
                           "ball per loaded plate (plates 1, 2), ")  # fmt: skip


def test_the_group_is_written_and_read_back_equal(analysis: MarkerErrorAnalysis, tmp_path: Path) -> None:
    assert analysis.result is not None
    for suffix in (".nc", ".zarr"):
        path = save_marker_result(analysis.result, tmp_path / f"fuzzy{suffix}")
        again = read_marker_result(path)
        assert again.kinetics is not None and analysis.result.kinetics is not None
        xr.testing.assert_identical(again.kinetics, analysis.result.kinetics)
        xr.testing.assert_identical(again.bands, analysis.result.bands)
        assert error_sources(again.kinetics) == error_sources(again.bands) == ("measurement", "placement", "sta")
    report = check_result(analysis.result)
    assert report["largest_violation"] == 0.0
    assert {"/", "/kinetics/N·m/kg", "/kinetics/W/kg"} <= set(analysis.result.parts())
    # a file without the group reads as before
    plain = save_marker_result(dataclasses.replace(analysis.result, kinetics=None), tmp_path / "plain.nc")
    assert read_marker_result(plain).kinetics is None


def test_a_trial_without_force_plates_gets_one_note(tmp_path: Path) -> None:
    """walking.c3d written again without its plates: one note, the bands as without --kinetics."""
    copy = tmp_path / "no_plates.c3d"
    write_c3d(read_c3d(SAMPLE_DATA / "walking.c3d"), copy)
    run = cut(run_angles(copy, static=SAMPLE_DATA / "static.c3d", subject_file=SAMPLE_DATA / "subject.toml"))
    assert run.kinetics is None
    with_kinetics = analyse_run(run, SETTINGS)
    without = analyse_run(run, dataclasses.replace(SETTINGS, kinetics=False))
    assert with_kinetics.result is not None and with_kinetics.result.kinetics is None
    assert messages(with_kinetics.notes) == [*messages(without.notes),
                                             "fuzzy kinetics: not computed (no force plates in no_plates.c3d)"]
    xr.testing.assert_identical(with_kinetics.fuzzy.drop_attrs(), without.fuzzy.drop_attrs())  # but the seconds


def test_the_command_prints_the_moments_and_the_allowable_answer(stance_run: AnglesRun, tmp_path: Path,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    """``uncertainty --kinetics`` (the cut run standing in for the pipeline): ΔΦ per
    moment and power and α, one allowable sentence per moment; the file has the group."""
    monkeypatch.setattr(trial_inputs, "run_angles", lambda *args, **kwargs: stance_run)
    out = tmp_path / "fuzzy.nc"
    result = run_here("uncertainty", SAMPLE_DATA / "walking.c3d", "--out", out, "--angles", "LKneeAngles",
                      "--alphas", "0,0.5", "--tolerance", "0", "--no-per-source", "--workers", "1", "--kinetics",
                      "--kinetic-tolerance", "0.2")  # fmt: skip
    assert result.returncode == 0, result.stderr
    saved = read_marker_result(out)
    assert saved.kinetics is not None and saved.kinetics.attrs["kinetic_tolerance"] == 0.2
    lines = result.stdout.splitlines()
    assert "Fuzzy joint moments (N·m/kg), ΔΦ, % of the largest |value|, over the determined frames:" in lines
    assert "Fuzzy joint powers (W/kg), ΔΦ, % of the largest |value|, over the determined frames:" in lines
    moments = kinetic_part(saved.kinetics, "N·m/kg")
    delta = moments.fuzzy.delta_phi()
    undetermined = moments.fuzzy.undetermined(0.5).any("frame")
    (row,) = [line.split() for line in lines if line.startswith("RHipMoment_X ")]
    expected = "undetermined" if bool(undetermined.sel(component="RHipMoment_X")) else \
        f"{float(delta.sel(component='RHipMoment_X', alpha=0.5)):.1f}"  # fmt: skip
    assert row[1] == expected
    for name in MOMENTS:
        assert f"  {allowable_kinetic_error(moments, name, 0.2).sentence}" in lines
    assert any(line.startswith("  Right knee moment, sagittal (+ extensor): ") and "±0.2 N·m/kg" in line
               for line in lines)  # fmt: skip
    assert kinetics_text(saved.kinetics) in result.stdout


def test_bad_kinetic_options_are_one_line(tmp_path: Path) -> None:
    for args, text in ((("--cop-error", "-1"), "--cop-error must be a distance ≥ 0 mm; got -1.0"),
                       (("--kinetic-tolerance", "0"), "--kinetic-tolerance must be a number of N·m/kg > 0; got 0.0")):
        result = run_here("uncertainty", SAMPLE_DATA / "walking.c3d", "--out", tmp_path / "x.nc", "--kinetics", *args)
        assert result.returncode != 0 and result.stderr.strip().endswith(text), result.stderr
    assert not list(tmp_path.iterdir())


def test_the_page_draws_the_bands_and_gives_the_allowable_answer(
    analysis: MarkerErrorAnalysis, stance_run: AnglesRun, tmp_path: Path
) -> None:
    """The trial page: data.npz holds the kinetic bands the figure draws — over the one
    left cycle on plate 1 its hull resampled to the cycle, NaN where the cut left no
    band or a band is undetermined — and the section gives the allowable sentences."""
    from fuzzygait.workflows.report_folder import ReportItem, run_kinetic_cycles, write_report
    from fuzzygait.workflows.trial_job import page_data

    data = page_data(analysis)
    np.testing.assert_array_equal(data["kinetic_alpha"], [0.0, 0.5])
    assert {f"kinetic_band/{c}" for c in MOMENTS + POWERS if c[0] == "L"} <= set(data)
    (cycle,) = [c for c in gait_cycles(stance_run.trial, stance_run.events, "L") if c.start <= 128 and c.end >= 168]
    assert analysis.result is not None and analysis.result.kinetics is not None
    kinetics = analysis.result.kinetics
    inside = np.arange(132, 164)
    flags = kinetics["undetermined"].sel(alpha=0.5).to_numpy()[:, inside].any(axis=1)
    determined = [str(c) for c, f in zip(kinetics["component"].to_numpy(), flags, strict=True) if c[0] == "L" and not f]
    undetermined = [str(c) for c, f in zip(kinetics["component"].to_numpy(), flags, strict=True) if c[0] == "L" and f]
    assert determined and undetermined  # this cut has both kinds at α = 0.5
    hull = kinetics["hull"].sel(component=determined[0]).to_numpy()  # (alpha, bound, frame)
    band = data[f"kinetic_band/{determined[0]}"]
    shown = np.isfinite(band[1]).all(axis=0)
    # the points between two analysed frames of the cycle (frames 121-231: sample 121 + 1.1 p)
    samples = cycle.start + np.arange(101) / 100.0 * (cycle.end - cycle.start)
    between = (np.floor(samples + 1e-9) >= inside[0]) & (np.ceil(samples - 1e-9) <= inside[-1])
    np.testing.assert_array_equal(shown, between)
    assert 25 <= shown.sum() <= 30
    # where a point falls on a frame the band is that frame's hull (10, 20, 30 %: frames 132, 143, 154)
    for point in (10, 20, 30):
        frame = int(round(samples[point]))
        assert abs(samples[point] - frame) < 1e-5 and shown[point]  # (event times in float32)
        np.testing.assert_allclose(band[1, :, point], hull[1, :, frame], rtol=0, atol=1e-5)
    # α = 0 (Table 3.1's full balls) is undetermined on analysed frames: no band there, marked
    d = determined[0]
    assert kinetics["undetermined"].sel(alpha=0.0, component=d).to_numpy()[inside].any()
    cycles = {side: gait_cycles(stance_run.trial, stance_run.events, side) for side in "LR"}
    fuzzy = run_kinetic_cycles(stance_run, cycles, kinetics).fuzzy  # what the figure draws
    assert fuzzy is not None
    np.testing.assert_array_equal(fuzzy.bands[d], band)
    np.testing.assert_array_equal(fuzzy.undetermined[d][0], shown & ~np.isfinite(band[0]).all(axis=0))
    assert fuzzy.undetermined[d][0].any() and not fuzzy.undetermined[d][1].any()
    # an α = 0.5 band undetermined on some analysed frame: left out and marked at that point
    name = undetermined[0]
    frame = inside[np.flatnonzero(kinetics["undetermined"].sel(alpha=0.5, component=name).to_numpy()[inside])[0]]
    point = int(round(100.0 * (frame - cycle.start) / (cycle.end - cycle.start)))
    assert fuzzy.undetermined[name][1, point] and np.isnan(fuzzy.bands[name][1, :, point]).all()
    out = write_report([ReportItem(SAMPLE_DATA / "walking.c3d", analysis)], tmp_path / "report")
    html = (out.parent / "walking.html").read_text()
    assert "How small the errors must be (allowable error of the sagittal moments)" in html
    # ΔΦ of every moment and power on the page, as the dataset gives it
    assert "Relative band width ΔΦ of the moments and powers (%)" in html
    delta, flags = kinetic_part(kinetics, "N·m/kg").fuzzy.delta_phi(), kinetic_part(kinetics, "N·m/kg").fuzzy
    rows = {label: (units, cells) for label, units, cells in fuzzy.delta_phi}
    assert len(rows) == 12 and rows["Right hip moment, sagittal (+ extensor)"][0] == "N·m/kg"
    for name, label in (("RHipMoment_X", "Right hip moment, sagittal (+ extensor)"),
                        ("LAnkleMoment_X", "Left ankle moment, sagittal (+ plantarflexor)")):  # fmt: skip
        undetermined_half = bool(flags.undetermined(0.5).sel(component=name).any())
        value = float(delta.sel(component=name, alpha=0.5))
        assert rows[label][1][0] == ("undetermined" if undetermined_half else f"{value:.0f}")
        assert rows[label][1][1] == "undetermined"  # α = 0
    assert "Left hip moment, sagittal (+ extensor): " in html and "centre of pressure within 10 mm" in html
    assert (out.parent / "walking_files" / "kinetics.png").is_file()


@pytest.mark.parametrize("switch", [(), ("--kinetics",)])
def test_report_passes_the_switch_to_its_trials(switch: tuple[str, ...], tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    """``report --kinetics``: the trials' marker-error settings ask for the fuzzy kinetics
    (the jobs run :func:`analyse_run` with them and the pages draw what it returns)."""
    from fuzzygait.core.errors import FuzzyGaitError
    from fuzzygait.workflows import batch_report, trial_job

    seen = []

    def stop(request: batch_report.BatchReportRequest, **kwargs: object) -> None:
        seen.append(request)
        raise FuzzyGaitError("stopped before any trial")

    monkeypatch.setattr(batch_report, "write_batch_report", stop)
    result = run_here("report", SAMPLE_DATA / "walking.c3d", "--out", tmp_path / "r", "--workers", "1", *switch)
    assert "stopped before any trial" in result.stderr
    (request,) = seen
    settings = request.analysis()
    assert settings is not None and settings.kinetics is bool(switch)
    fast = trial_job.mode_settings("fast", settings)
    assert fast is not None and fast.kinetics is bool(switch)


def test_a_band_whose_wider_level_is_undetermined_keeps_its_shade() -> None:
    """Left α = 0.5 drawn where α = 0 is left out: two layers there (the legend swatch of
    α = 0.5 is two layers), one where α = 0 is drawn beneath it; the strip marks α = 0."""
    from matplotlib.collections import PolyCollection

    from fuzzygait.viz.report.kinetics import KineticBands, KineticCycles, kinetics_figure

    x = np.arange(101.0)
    curve = np.sin(x / 16.0)
    band = np.stack([np.stack([curve - 0.4, curve + 0.4]), np.stack([curve - 0.2, curve + 0.2])])
    band[0, :, 50:] = np.nan  # α = 0 undetermined on the second half
    flags = np.zeros((2, 101), dtype=bool)
    flags[0, 50:] = True
    fuzzy = KineticBands(np.array([0.0, 0.5]), {"LKneeMoment_X": band}, {"LKneeMoment_X": flags})
    cycles = KineticCycles({"LKneeMoment_X": curve[None, :]}, {"L": 1}, {"L": 1}, fuzzy=fuzzy)
    figure = kinetics_figure(cycles, "t")
    ax = figure.axes[1 * 4 + 0]  # knee row, sagittal column
    fills = [c for c in ax.collections if isinstance(c, PolyCollection) and c.get_facecolor()[0][3] > 0]
    layers = np.zeros(101)
    for fill in fills:
        for path in fill.get_paths():
            xs = path.vertices[:, 0]
            layers[(x >= xs.min()) & (x <= xs.max())] += 1
    assert (layers[:49] == 2).all() and (layers[51:] == 2).all()  # α = 0 + α = 0.5, or α = 0.5 twice
    labels = [t.get_text() for t in figure.legends[0].get_texts()]
    assert "Left α = 0.5" in labels and "α = 0 undetermined: no band" in labels
    assert not any(t.startswith("Right α") for t in labels)  # no right band drawn


def test_legs_without_kinetics_are_left_out(stance_run: AnglesRun) -> None:
    """A leg whose kinetics were not computed gets no fuzzy kinetics; neither: one note."""
    from fuzzygait.core.names import Side
    from fuzzygait.workflows.marker_uncertainty import fuzzy_kinetics as run_fuzzy_kinetics

    assert stance_run.kinetics is not None
    neither = dataclasses.replace(stance_run, kinetics=dataclasses.replace(
        stance_run.kinetics, unavailable={Side.LEFT: "no LHEE", Side.RIGHT: "no RHEE"}))  # fmt: skip
    group, note = run_fuzzy_kinetics(neither, SETTINGS)
    assert group is None and note.message == "fuzzy kinetics: not computed (neither leg's kinetics were)"
    right = dataclasses.replace(stance_run, kinetics=dataclasses.replace(
        stance_run.kinetics, unavailable={Side.LEFT: "no LHEE"}))  # fmt: skip
    group, note = run_fuzzy_kinetics(right, dataclasses.replace(SETTINGS, alphas=(0.5,)))
    assert group is not None and {str(c)[0] for c in group["component"].to_numpy()} == {"R"}
    assert "of 3 joints" in note.message
