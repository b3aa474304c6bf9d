"""Kinetics on the report (issue 39 items 4 and 6): the trial page's figures (mean of the
cycles on a force plate), its section with the per-contact table, the sentence of a trial
without force plates, the session page's figures, and normative kinetics built from
trials."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.lines import Line2D

from fuzzygait.core.names import Side
from fuzzygait.gait.cycles import GaitCycle, gait_cycles, normalise_cycles
from fuzzygait.gait.normative import build_normative, kinetic_cycles, read_normative, write_normative
from fuzzygait.viz.report.kinetics import (
    KINETIC_COLUMNS,
    KINETIC_ROWS,
    KineticCycles,
    dataset_components,
    grf_figure,
    kinetics_figure,
    session_kinetics_figure,
)
from fuzzygait.viz.report.kinetics_section import NO_PLATES
from fuzzygait.workflows.angles import AnglesRun, run_angles
from fuzzygait.workflows.pdf import _PageText
from fuzzygait.workflows.report_folder import ReportItem, kinetics_page, write_report
from support import SAMPLE_DATA, FakeAnalysis, needs_shared, shared_file


@pytest.fixture(scope="module")
def movement() -> tuple[Path, AnglesRun]:
    path = shared_file("vicon", "Movement_trial.c3d")
    return path, run_angles(path)


def _cycles(run: AnglesRun) -> dict[str, list[GaitCycle]]:
    return {side: gait_cycles(run.trial, run.events, side) for side in "LR"}


def _on_plate(run: AnglesRun, side: str, cycle: GaitCycle) -> bool:
    """Independently of the report: a used contact of the side covers 20, 30 and 40 % of
    the cycle."""
    assert run.kinetics is not None
    frames = [int(round(cycle.start + p / 100 * (cycle.end - cycle.start))) for p in (20, 30, 40)]
    used = [c for c in run.kinetics.contacts if c.side is Side(side)]
    return all(any(c.first <= f <= c.last for c in used) for f in frames)


def _mean_line(ax, side: str) -> np.ndarray:
    lines = [line for line in ax.get_lines() if isinstance(line, Line2D) and line.get_gid() == f"mean-{side}"]
    assert len(lines) == 1
    return np.asarray(lines[0].get_ydata(), dtype=float)


@needs_shared
def test_figure_mean_is_the_mean_of_the_cycles_on_a_plate(movement: tuple[Path, AnglesRun]) -> None:
    _, run = movement
    assert run.kinetics is not None
    cycles = _cycles(run)
    kinetics = KineticCycles.of(dataset_components(run.kinetics.data), cycles)
    on = {s: [c for c in cycles[s] if _on_plate(run, s, c)] for s in "LR"}
    assert kinetics.counted == {"L": len(on["L"]), "R": len(on["R"])} == {"L": 1, "R": 2}
    figure = kinetics_figure(kinetics, "Movement_trial")
    axes = np.asarray(figure.axes[: len(KINETIC_ROWS) * len(KINETIC_COLUMNS)]).reshape(len(KINETIC_ROWS), -1)
    data = run.kinetics.data
    for r, joint in enumerate(KINETIC_ROWS):
        for c, (output, axis, _, _) in enumerate(KINETIC_COLUMNS):
            for side in "LR":
                if output == "Moment":
                    values = data["moment"].sel(side=side, joint=joint, axis=axis).values  # N·m/kg
                else:
                    values = data["power"].sel(side=side, joint=joint).values  # W/kg
                truth = normalise_cycles(values, on[side], 101).mean(axis=0)
                np.testing.assert_allclose(_mean_line(axes[r, c], side), truth, rtol=1e-12, atol=1e-12)
    # the right knee extensor moment peaks in early stance within a walking range (N·m/kg, not N·mm/kg)
    assert 0.3 < float(np.max(_mean_line(axes[1, 0], "R"))) < 1.5
    assert "N·m/kg" in axes[1, 0].get_ylabel() and "W/kg" in axes[1, 3].get_ylabel()
    grf = grf_figure(kinetics.cycles, "GRF")
    assert grf is not None and "% body weight" in grf.axes[2].get_ylabel()
    vertical = _mean_line(grf.axes[2], "R")
    assert 100 < vertical.max() < 150 and vertical[0] < 15 and vertical[-1] < 15  # over stance on the plate


@needs_shared
def test_trial_page_has_the_section_and_a_row_per_contact(movement: tuple[Path, AnglesRun], tmp_path: Path) -> None:
    path, run = movement
    index = write_report([ReportItem(path, FakeAnalysis(run, None, pd.DataFrame()))], tmp_path / "out")
    html = (index.parent / "Movement_trial.html").read_text(encoding="utf-8")
    section = html.split('<h2 id="kinetics">')[1].split("<h2 ")[0]
    assert "kinetics.png" in section and "grf.png" in section and NO_PLATES not in section
    assert (index.parent / "Movement_trial_files" / "grf.svg").is_file()
    rows = re.findall(r"<tr>(.*?)</tr>", section.split("Force-plate contacts")[1])[1:]
    cells = [re.sub(r"<[^>]+>", "", "|".join(re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", row))) for row in rows]
    first = run.trial.first_frame
    expected = [f"{c.plate}|{c.side.word}|{first + c.first}–{first + c.last}" for c in
                sorted(run.kinetics.contacts, key=lambda c: c.first)]  # fmt: skip
    assert [cell.rsplit("|", 2)[0] for cell in cells] == expected
    assert expected[0] == "4|Right|732–820" and len(cells) == 4
    # plate 1 is still loaded at the recording's last frame (1017): that contact is cut, its duration no stance's
    cut = [cell for cell in cells if cell.startswith("1|Left|925–1017|")]
    assert len(cut) == 1 and cut[0].endswith("used for the left foot (the recording ends during it)")
    assert cut[0].split("|")[3].endswith("+")
    assert all(cell.endswith(f"used for the {cell.split('|')[1].lower()} foot") for cell in cells if cell not in cut)
    assert "Cycles with their stance on a force plate: left 1 of 1, right 2 of 2" in section
    # the PDF (printed from the page; without Chromium each of its figures on a page of its own)
    parser = _PageText()
    parser.feed(html)
    assert {"Movement_trial_files/kinetics.png", "Movement_trial_files/grf.png"} <= set(parser.images)
    assert any(tag == "tr" and "732–820" in text and "used for the right foot" in text for tag, text in parser.blocks)


def test_trial_without_plates_says_so(tmp_path: Path) -> None:
    source = SAMPLE_DATA / "cgm24_walking.c3d"  # the CGM 2.4 sample has no force plates
    run = run_angles(source, static=SAMPLE_DATA / "cgm24_static.c3d", subject_file=SAMPLE_DATA / "cgm24_subject.toml",
                     model="auto")  # fmt: skip
    assert run.kinetics is None
    page = kinetics_page(run, _cycles(run))
    assert page.cycles is None and page.missing == NO_PLATES
    index = write_report([ReportItem(source, FakeAnalysis(run, None, pd.DataFrame()))], tmp_path / "out")
    html = (index.parent / "cgm24_walking.html").read_text(encoding="utf-8")
    assert NO_PLATES in html.split('<h2 id="kinetics">')[1].split("<h2 ")[0]
    assert not (index.parent / "cgm24_walking_files" / "grf.png").exists()


def test_session_figure_draws_mean_and_sd() -> None:
    rng = np.random.default_rng(3)
    stacks = {"LKneeMoment_X": rng.normal(0.4, 0.1, (5, 101)), "RKneeMoment_X": rng.normal(0.6, 0.1, (3, 101))}
    figure = session_kinetics_figure(stacks, "session")
    assert figure is not None
    knee = figure.axes[len(KINETIC_COLUMNS)]  # row Knee, column sagittal moment
    np.testing.assert_allclose(_mean_line(knee, "L"), stacks["LKneeMoment_X"].mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(_mean_line(knee, "R"), stacks["RKneeMoment_X"].mean(axis=0), rtol=1e-12)
    assert session_kinetics_figure({"LNormalisedGRF_Z": stacks["LKneeMoment_X"]}, "no moments") is None


def _synthetic(values: dict[str, list[float]], loaded: dict[str, list[bool]]) -> tuple[dict, dict]:
    """A made-up trial: per side cycles of 100 frames (apart: no data between them), each
    cycle's moment and power a constant, its foot on a plate (vertical GRF 100 % BW over
    its first 60 frames) or not."""
    n = 1 + 150 * max(len(v) for v in values.values()) + 10
    outputs, cycles = {}, {}
    for side, levels in values.items():
        moment, power, grf = np.full(n, np.nan), np.full(n, np.nan), np.zeros(n)
        cycles[side] = []
        for k, (level, on) in enumerate(zip(levels, loaded[side], strict=True)):
            start = 1 + 150 * k
            moment[start : start + 101] = level
            power[start : start + 101] = -2 * level
            if on:
                grf[start : start + 61] = 100.0
            cycles[side].append(GaitCycle(side, k, start, start + 100, 100.0, foot_off=start + 60))
        outputs[side] = {"KneeMoment_X": moment, "KneePower_Z": power, "NormalisedGRF_Z": grf}
    return outputs, cycles


def test_normative_kinetics_from_two_synthetic_trials(tmp_path: Path) -> None:
    first = _synthetic({"L": [0.4, 0.4, 9.0]}, {"L": [True, True, False]})  # the third cycle is on no plate
    second = _synthetic({"L": [1.0], "R": [0.7]}, {"L": [True], "R": [True]})
    trials = [kinetic_cycles(*first), kinetic_cycles(*second)]
    assert trials[0]["LKneeMoment_X"].shape == (2, 101)
    data = read_normative(write_normative(build_normative(trials), tmp_path / "norm.csv"))
    pooled = np.array([0.4, 0.4, 1.0, 0.7])
    mean, sd = data.curve("LKneeMoment_X")
    np.testing.assert_allclose(mean, pooled.mean(), rtol=1e-12)
    np.testing.assert_allclose(sd, pooled.std(ddof=1), rtol=1e-12)
    mean, sd = data.curve("RKneePower_Z")
    np.testing.assert_allclose(mean, -2 * pooled.mean(), rtol=1e-12)
    assert data.cycles["KneeMoment_X"] == 4
    mean, sd = data.curve("LNormalisedGRF_Z")  # over stance on the plate: 100 % BW (the spline rings at its ends)
    np.testing.assert_allclose(mean[30:71], 100.0, rtol=1e-3)


def test_normative_band_where_the_file_has_the_variable() -> None:
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import to_rgba

    from fuzzygait.gait.normative import NormativeData
    from fuzzygait.viz.report.figures import NORMATIVE_COLOUR

    mean, sd = np.linspace(-0.2, 0.8, 101), np.full(101, 0.15)
    normative = NormativeData({"KneeMoment_X": (mean, sd)}, {"KneeMoment_X": 20}, "controls.csv")
    cycles = KineticCycles({"LKneeMoment_X": np.zeros((2, 101)), "LHipMoment_X": np.zeros((2, 101))}, {"L": 2})
    figure = kinetics_figure(cycles, "with norms", normative)
    grey = to_rgba(NORMATIVE_COLOUR)

    def bands(ax) -> list[np.ndarray]:
        return [c.get_paths()[0].vertices for c in ax.collections
                if isinstance(c, PolyCollection) and np.allclose(c.get_facecolor()[0], grey)]  # fmt: skip

    knee, hip = figure.axes[len(KINETIC_COLUMNS)], figure.axes[0]
    assert len(bands(knee)) == 1 and not bands(hip)  # only where the file has the variable
    vertices = bands(knee)[0]
    assert np.isclose(vertices[:, 1].max(), (mean + sd).max()) and np.isclose(vertices[:, 1].min(), (mean - sd).min())
    labels = [t.get_text() for legend in figure.legends for t in legend.get_texts()]
    assert "normative mean ± 1 SD" in labels
