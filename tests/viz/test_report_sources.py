"""The report's per-source part (issue 15 Deliver 4, thesis Fig. 5.9): the flexion angles
with the α = 0 band of each error source alone and of all together, the table "widest
α = 0 band per source" naming the dominating source, placed after the first screen;
undetermined bands hatched, never stretching an axis; the demo's sentence.

The fake analysis is the sample trial's flexion angles ± (1 − α)·k deg per source
(measurement 1, placement 4, STA 7, all together 10 deg), the STA band of left knee
flexion undetermined (bounds ±175°) on a stretch of frames, so nothing depends on the
optimiser.
"""

from __future__ import annotations

import html
import re
import subprocess
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from fuzzygait.markererror.analysis import relative_envelope_width
from fuzzygait.markererror.per_source import FLEXION_COMPONENTS, source_bands_dataset, widest_source_bands
from fuzzygait.markererror.result import AngleAxes, MarkerErrorResult, fuzzy_angles_dataset, with_error_sources
from fuzzygait.viz.report.bands import TrialData
from fuzzygait.viz.report.sources import _tint, dominant_sentence, source_figure
from fuzzygait.workflows.angles import AnglesRun
from fuzzygait.workflows.demo import uncertainty_lines
from fuzzygait.workflows.report_folder import ReportItem, write_report
from support import SAMPLE_DATA, FakeAnalysis

ALPHAS = np.array([0.0, 0.5, 1.0])
SOURCE_ALPHAS = np.array([0.0, 1.0])
HALF = {"measurement": 1.0, "placement": 4.0, "sta": 7.0}  # deg at α = 0
ALL_HALF = 10.0
STRETCH = slice(150, 190)
FLIP = 175.0
CHROMIUM = Path("/usr/bin/chromium")


def _hull(measured: np.ndarray, alphas: np.ndarray, half: float, flip: slice | None = None) -> np.ndarray:
    widths = (1.0 - alphas)[:, None] * np.full(measured.size, half)
    if flip is not None:
        widths[0, flip] = FLIP
    return np.stack([measured - widths, measured + widths], axis=1)


def source_analysis(run: AnglesRun, per_source: bool = True) -> FakeAnalysis:
    table = run.angle_table()
    names = [*FLEXION_COMPONENTS, "LKneeAngles_Y"]
    hulls = {n: _hull(table[n].to_numpy(), ALPHAS, ALL_HALF) for n in names}
    fuzzy = fuzzy_angles_dataset(hulls, AngleAxes(alphas=ALPHAS, frames=run.trial.frames, times=run.trial.times,
                                 markers=list(run.trial.marker_labels), ball_radius=np.full(run.trial.n_markers, 32.0)),
                                 attrs={"trial": run.trial.name})  # fmt: skip
    fuzzy = with_error_sources(fuzzy, ("measurement", "placement", "sta"))
    if per_source:
        bands = {s: {n: _hull(table[n].to_numpy(), SOURCE_ALPHAS, h,
                              STRETCH if (s, n) == ("sta", "LKneeAngles_X") else None)
                     for n in FLEXION_COMPONENTS} for s, h in HALF.items()}  # fmt: skip
        sizes = (("measurement", 2.0), ("placement", 10.0), ("sta", 20.0))
        radii = {s: np.full(run.trial.n_markers, r) for s, r in sizes}
        sources = source_bands_dataset(fuzzy, bands, SOURCE_ALPHAS, radii=radii)
        return FakeAnalysis(run, fuzzy, relative_envelope_width(fuzzy), ["fake per-source analysis"],
                            MarkerErrorResult(fuzzy, sources=sources))  # fmt: skip
    return FakeAnalysis(run, fuzzy, relative_envelope_width(fuzzy), ["fake per-source analysis"])


@pytest.fixture(scope="module")
def analysis(angles_run: AnglesRun) -> FakeAnalysis:
    return source_analysis(angles_run)


@pytest.fixture(scope="module")
def report(analysis: FakeAnalysis, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("sources") / "report"
    write_report([ReportItem(SAMPLE_DATA / "walking.c3d", analysis)], out)
    return out


def _text(page: str) -> str:
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", page)).split())


def test_widest_bands_and_the_dominating_source(analysis: FakeAnalysis) -> None:
    table = widest_source_bands(analysis.result)
    for name in FLEXION_COMPONENTS:
        for source, half in (*HALF.items(), ("all", ALL_HALF)):
            assert table.width(name, source) == pytest.approx(2 * half), (name, source)
        assert table.dominant(name) == "sta"
    assert table.frames_undetermined("LKneeAngles_X", "sta") == STRETCH.stop - STRETCH.start
    assert table.frames_undetermined("LKneeAngles_X", "placement") == 0


@pytest.mark.slow  # the report with its figures: ~4 s
def test_page_has_the_section_after_the_first_screen(report: Path, analysis: FakeAnalysis) -> None:
    page = (report / "walking.html").read_text(encoding="utf-8")
    assert (report / "walking_files" / "sources.png").is_file() and (report / "walking_files" / "sources.svg").is_file()
    assert 'src="walking_files/sources.png"' in page and 'href="#sources"' in page
    text = _text(page)
    # the clinical sections lead (kinematics grid first); the per-source section after the allowable error and ΔΦ
    assert text.index("Kinematics over the gait cycle") < text.index("Relative envelope width ΔΦ")
    assert text.index("Relative envelope width ΔΦ") < text.index("Which error source dominates") < text.index(
        "Whole trial The same angles")  # fmt: skip
    header = ("Angle measurement system alone marker placement alone soft-tissue artefact alone "
              "all sources together Dominates")  # fmt: skip (the <br> in the headers drop out with the tags)
    assert header in text
    n = analysis.run.trial.n_frames
    flipped = STRETCH.stop - STRETCH.start
    assert (f"Left knee, sagittal (+ flexion) 2.0 8.0 14.0 undetermined on {flipped} of {n} frames "
            "20.0 soft-tissue artefact") in text  # fmt: skip
    assert "Right hip, sagittal (+ flexion) 2.0 8.0 14.0 20.0 soft-tissue artefact" in text
    assert "measurement system 2 mm, marker placement 10 mm, soft-tissue artefact 20 mm" in text
    assert "<b>14.0</b>" in page  # the dominating source in bold


@pytest.mark.slow  # a second report: ~3 s
def test_no_per_source_bands_no_section(angles_run: AnglesRun, tmp_path: Path) -> None:
    out = tmp_path / "report"
    write_report([ReportItem(SAMPLE_DATA / "walking.c3d", source_analysis(angles_run, per_source=False))], out)
    page = (out / "walking.html").read_text(encoding="utf-8")
    assert 'id="sources"' not in page and 'href="#sources"' not in page
    assert not (out / "walking_files" / "sources.png").exists()


def test_figure_panels_legend_and_unstretched_axes(analysis: FakeAnalysis) -> None:
    fig = source_figure(TrialData.of(analysis), "test")
    try:
        assert len(fig.axes) == 6  # hip, knee, ankle x left, right
        assert [ax.get_title() for ax in fig.axes[:2]] == ["Left", "Right"]
        assert fig.axes[2].get_ylabel().startswith("Knee (deg)") and "flexion" in fig.axes[2].get_ylabel()
        assert fig.axes[4].get_xlabel().startswith("gait cycle (%)")
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        for label in ("measurement system alone", "marker placement alone", "soft-tissue artefact alone",
                      "all sources together"):  # fmt: skip
            assert label in labels
        assert any(label.startswith("undetermined") for label in labels)
        knee = analysis.run.result.angles["LKneeAngles"][:, 0]
        low, high = fig.axes[2].get_ylim()  # left knee: the STA band flips on a stretch
        assert high < np.nanmax(knee) + ALL_HALF + 25.0 and low > np.nanmin(knee) - ALL_HALF - 25.0
        assert any(p.get_hatch() for p in fig.axes[2].patches)  # the hatched strip is there
        assert not any(p.get_hatch() for p in fig.axes[3].patches)  # right knee: all determined
    finally:
        plt.close(fig)


def test_demo_sentence_names_the_dominating_source(analysis: FakeAnalysis) -> None:
    sentence = dominant_sentence(analysis.result, "Knee")
    assert sentence is not None and sentence.startswith("Knee flexion: soft-tissue artefact dominates")
    assert "measurement system 2.0°/2.0°" in sentence and "all sources together 20.0°/20.0°" in sentence
    assert any(line.endswith(sentence) for line in uncertainty_lines(analysis))
    plain = source_analysis(analysis.run, per_source=False)
    assert dominant_sentence(plain.result) is None
    assert not any("dominates" in line for line in uncertainty_lines(plain))


@pytest.mark.slow  # the report and a browser: ~8 s
@pytest.mark.skipif(not CHROMIUM.exists(), reason=f"{CHROMIUM} is not installed (headless screenshots)")
def test_section_renders_in_chromium(report: Path, tmp_path: Path) -> None:
    import matplotlib.image

    png = tmp_path / "page.png"
    subprocess.run(["/usr/bin/chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                    "--no-first-run", "--disable-background-networking", "--disable-component-update",
                    "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}", "--window-size=1280,9000",
                    f"--screenshot={png}", (report / "walking.html").resolve().as_uri()],
                   capture_output=True, timeout=120, check=False)  # fmt: skip
    assert png.is_file(), "chromium wrote no screenshot"
    pixels = matplotlib.image.imread(png)[..., :3]
    assert pixels.shape[0] == 9000
    # the page is drawn all the way down past the per-source figure (its purple and orange bands)
    purple = (np.abs(pixels - np.array(_tint("sta"))).max(axis=-1) < 0.04).sum(axis=1)  # the STA bands' fill
    assert purple[:1600].sum() == 0 and purple[1600:].sum() > 10_000, "no per-source figure after the first screen"


def test_a_far_wider_all_sources_band_leaves_the_axis() -> None:
    """The sources alone stay readable: the all-sources band widens the y-axis by at most
    half the sources' range, and a note says how far it reaches."""
    from fuzzygait.viz.report.sources import _limit

    x = np.linspace(0, 100, 11)
    curve = np.sin(x / 20)
    fig, ax = plt.subplots()
    try:
        bands = {"sta": np.stack([curve - 5, curve + 5]), "all": np.stack([curve - 85, curve + 8])}
        _limit(ax, curve, bands)
        low, high = ax.get_ylim()
        span = (curve + 5).max() - (curve - 5).min()
        assert low >= (curve - 5).min() - 0.5 * span - 0.1 * span and high >= (curve + 8).max()
        assert [t.get_text() for t in ax.texts] == ["all together reaches -86° to 9° (beyond the axis)"]
        ax.texts[0].remove()
        _limit(ax, curve, {"sta": bands["sta"], "all": np.stack([curve - 8, curve + 8])})  # within: no note
        assert not ax.texts and ax.get_ylim()[0] < (curve - 8).min()
    finally:
        plt.close(fig)
