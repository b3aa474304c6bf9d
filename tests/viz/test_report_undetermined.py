"""Undetermined bands in the report: not drawn, not averaged into the cycle bands, no axis
stretched by them, "undetermined" in the ΔΦ table and key numbers of determined bands.

The fake analysis is the sample trial's angles ± (1 − α)·k deg with an undetermined
stretch whose bounds are ±175° from the measured angle (what a flipping frame gives), so
nothing depends on the optimiser.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.gait.cycles import gait_cycles
from fuzzygait.markererror.analysis import relative_envelope_width
from fuzzygait.markererror.result import AngleAxes, fuzzy_angles_dataset, with_error_sources
from fuzzygait.viz.report import cycle_bands
from fuzzygait.viz.report.bands import TrialData, delta_phi_table, headline
from fuzzygait.viz.report.figures import cycle_figure, time_series_figure
from fuzzygait.workflows.angles import AnglesRun, run_angles
from fuzzygait.workflows.report_folder import ReportItem, write_report
from support import SAMPLE_DATA, FakeAnalysis

ALPHAS = np.array([0.0, 0.5, 1.0])
#: α = 0 of left knee flexion is undetermined on these frames (0-based).
STRETCH = slice(150, 190)
FLIP = 175.0  # deg: a bound this far from the measured angle (the frame flipped)




@pytest.fixture(scope="module")
def noisy_run() -> AnglesRun:
    return run_angles(SAMPLE_DATA / "walking_noisy.c3d", static=SAMPLE_DATA / "static.c3d",
                      subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip


def undetermined_analysis(run: AnglesRun) -> FakeAnalysis:
    """Knee angles ± 3 (1 − α) deg; left knee flexion undetermined at α = 0 on STRETCH,
    right knee rotation undetermined at α = 0 and 0.5 everywhere (bounds ±FLIP)."""
    table = run.angle_table()
    names = [f"{side}KneeAngles_{axis}" for side in "LR" for axis in "XYZ"]
    hulls, flags = {}, {}
    for name in names:
        measured = table[name].to_numpy()
        half = (1.0 - ALPHAS)[:, None] * np.full(measured.size, 3.0)
        flag = np.zeros((ALPHAS.size, measured.size), dtype=bool)
        if name == "LKneeAngles_X":
            flag[0, STRETCH] = True
        if name == "RKneeAngles_Z":
            flag[:2, :] = True
        half = np.where(flag, FLIP, half)
        hulls[name] = np.stack([measured - half, measured + half], axis=1)
        flags[name] = flag
    fuzzy = fuzzy_angles_dataset(hulls, AngleAxes(alphas=ALPHAS, frames=run.trial.frames, times=run.trial.times,
                                 markers=list(run.trial.marker_labels),
                                 ball_radius=np.full(run.trial.n_markers, 20.0)),
                                 attrs={"trial": run.trial.name}, undetermined=flags)  # fmt: skip
    fuzzy = with_error_sources(fuzzy, ("measurement", "placement", "sta"))
    note = Finding(FindingKind.UNCERTAINTY, "fake undetermined analysis")
    return FakeAnalysis(run, fuzzy, relative_envelope_width(fuzzy), [note])


@pytest.fixture(scope="module")
def analysis(noisy_run: AnglesRun) -> FakeAnalysis:
    return undetermined_analysis(noisy_run)


@pytest.fixture(scope="module")
def report(analysis: FakeAnalysis, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("undetermined") / "report"
    write_report([ReportItem(SAMPLE_DATA / "walking_noisy.c3d", analysis)], out)
    return out


def test_cycle_bands_leave_undetermined_points_out(noisy_run: AnglesRun) -> None:
    cycles = gait_cycles(noisy_run.trial, noisy_run.events, "L")
    knee = noisy_run.result.angles["LKneeAngles"][:, 0]
    clean = np.stack([np.stack([knee - 3 * (1 - a), knee + 3 * (1 - a)]) for a in (0.0, 0.5)])
    flags = np.zeros((2, knee.size), dtype=bool)
    flags[0, STRETCH] = True
    flipped = clean.copy()
    flipped[0, 0, STRETCH] -= FLIP
    flipped[0, 1, STRETCH] += FLIP
    mean0, band0, used0 = cycle_bands(knee, clean, cycles)
    mean, band, used = cycle_bands(knee, flipped, cycles, undetermined=flags)
    np.testing.assert_array_equal(mean, mean0)  # the curve is not touched
    assert used == used0
    gone = ~np.isfinite(band[0, 0])
    assert gone.any() and (gone == ~np.isfinite(band[0, 1])).all()
    # a point is undetermined when it is in any cycle: the stretch lies in one cycle only
    inside = [c for c in cycles if c.start <= STRETCH.start and STRETCH.stop <= c.end]
    assert len(inside) == 1
    span = (np.array([STRETCH.start, STRETCH.stop - 1]) - inside[0].start) / (inside[0].end - inside[0].start)
    percent = np.linspace(0, 100, band.shape[-1])
    assert gone[(percent > 100 * span[0] + 1) & (percent < 100 * span[1] - 1)].all()
    # elsewhere the band is the clean one (the flipped bounds do not leak through the splines)
    np.testing.assert_allclose(band[0][:, ~gone], band0[0][:, ~gone], atol=1e-9)
    np.testing.assert_allclose(band[1], band0[1], atol=1e-9)  # α = 0.5 is determined


def _ylim(fig, row: int, column: int) -> tuple[float, float]:
    return fig.axes[3 * row + column].get_ylim()


def test_figures_are_not_stretched_by_undetermined_frames(analysis: FakeAnalysis) -> None:
    data = TrialData.of(analysis)
    knee = analysis.run.result.angles["LKneeAngles"][:, 0]
    for figure in (cycle_figure, time_series_figure):
        fig = figure(data, "test")
        low, high = _ylim(fig, 2, 0)  # knee, sagittal
        # the determined data reach about max(knee) + 3 deg; a drawn flipped bound would be +175
        assert high < np.nanmax(knee) + 3.0 + 20.0, (figure.__name__, high)
        assert low > np.nanmin(knee) - 3.0 - 20.0, (figure.__name__, low)
        low, high = _ylim(fig, 2, 2)  # knee, transverse: right undetermined at α = 0 and 0.5
        rotation = analysis.run.result.angles["LKneeAngles"][:, 2]
        assert high < np.nanmax(rotation) + 3.0 + 10.0 and low > np.nanmin(rotation) - 3.0 - 10.0
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        assert "α = 0 undetermined: no band" in labels and "α = 0.5 undetermined too" in labels
        import matplotlib.pyplot as plt

        plt.close(fig)


def test_delta_phi_table_and_headline(analysis: FakeAnalysis) -> None:
    data = TrialData.of(analysis)
    table = delta_phi_table(analysis, data)
    assert table.is_undetermined("LKneeAngles_X", 0.0) and not table.is_undetermined("LKneeAngles_X", 0.5)
    assert table.is_undetermined("RKneeAngles_Z", 0.5)
    assert table.frames_undetermined("LKneeAngles_X", 0.0) == STRETCH.stop - STRETCH.start
    assert table.widest_band("LKneeAngles_X", 0.0) == pytest.approx(6.0)  # over the determined frames
    head = headline(table)
    # left knee flexion is undetermined at α = 0: the largest determined flexion ΔΦ is the right's
    assert head.largest is not None and head.largest[1:] == ("RKneeAngles_X", 0.0)
    assert head.undetermined == ["LKneeAngles_X", "RKneeAngles_Z"] and head.n_components == 6
    assert head.flexion_undetermined == ["LKneeAngles_X"]
    assert head.widest is not None and head.widest[0] == pytest.approx(6.0)


def test_pages_say_undetermined_and_never_360_or_999(report: Path) -> None:
    page = (report / "walking_noisy.html").read_text(encoding="utf-8")
    index = (report / "index.html").read_text(encoding="utf-8")
    for text in (page, index):
        assert "undetermined" in text.lower()
        assert not re.search(r"(?<![\d.])(360|999)(?![\d])", re.sub(r"<[^>]+>", " ", text))
    row = re.search(r"Left knee, sagittal.*?</tr>", page, re.S)
    assert row is not None
    cells = re.findall(r'<td class="num">(.*?)</td>', row.group(0))
    assert re.sub(r"<[^>]+>", "", cells[1]) == "undetermined"  # α = 0
    assert re.fullmatch(r"\d+", cells[0])  # α = 0.5: a number
    assert cells[-1] == f"{STRETCH.stop - STRETCH.start} of 512"
    rotation = re.search(r"Right knee, transverse.*?</tr>", page, re.S)
    assert rotation is not None and rotation.group(0).count("undetermined") == 3  # α 0.5, 0, widest
    assert "Undetermined at α = 0: <b>2 of 6</b>" in page and "knee flexion (L)" in page
    assert "Largest ΔΦ of hip/knee/ankle flexion (determined bands)" in page
    assert "2 of 6" in index and "Right knee, sagittal (+ flexion)" in index
