"""The clinical content of a trial page (issue 16 Deliver 3 and 7): header, spatio-temporal
table, kinematics grid with foot off, SD, side-coloured bands and normative band, GPS/MAP,
kinetics, data quality of the model's markers, plain words and footnotes; rendered in
headless Chromium."""

from __future__ import annotations

import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.colors import to_rgb
from matplotlib.patches import Patch

from fuzzygait.gait.cycles import normalise_cycles
from fuzzygait.gait.normative import build_normative, normalised_cycles, read_normative, write_normative
from fuzzygait.viz.layout import SIDE_STYLE
from fuzzygait.viz.report.bands import TrialData
from fuzzygait.viz.report.clinical import ClinicalData
from fuzzygait.viz.report.figures import cycle_figure
from fuzzygait.viz.report.kinetics_section import NO_PLATES
from fuzzygait.workflows.angles import AnglesRun, run_angles
from fuzzygait.workflows.report_folder import ReportItem, ReportWriter, write_report
from support import SAMPLE_DATA, FakeAnalysis, needs_shared, shared_file
from viz.test_report import check_html, fake_analysis

CHROMIUM = Path("/usr/bin/chromium")
#: Section ids every trial page with bands and normative data shows.
SECTIONS = ("guide", "spatiotemporal", "cycles", "gps", "kinetics", "allowable", "delta-phi", "time-series",
            "quality", "subject", "references")  # fmt: skip


@pytest.fixture(scope="module")
def noisy_run() -> AnglesRun:
    return run_angles(SAMPLE_DATA / "walking_noisy.c3d", static=SAMPLE_DATA / "static.c3d",
                      subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip


@pytest.fixture(scope="module")
def self_normative(noisy_run: AnglesRun, tmp_path_factory: pytest.TempPathFactory):
    cycles = normalised_cycles(noisy_run.result.angles, noisy_run.trial, noisy_run.events)
    path = tmp_path_factory.mktemp("norm") / "self.csv"
    return read_normative(write_normative(build_normative([cycles], per_side=True, source="self.csv"), path))


@pytest.fixture(scope="module")
def content_dir(noisy_run: AnglesRun, self_normative, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("content") / "out"
    with ReportWriter(out, normative=self_normative, strict=True) as writer:
        entry = writer.add(ReportItem(SAMPLE_DATA / "walking_noisy.c3d", fake_analysis(noisy_run),
                                      session="2024-03-05 visit", warnings=["subject name differs"]))  # fmt: skip
        angles_only = FakeAnalysis(noisy_run, None, pd.DataFrame(), ["angles only"])
        writer.add(ReportItem(Path("copy/walking_noisy.c3d"), angles_only))
        writer.finish()
    assert entry.gps == 0.0  # GPS against normative data built from the same trial
    return out


def _text(path: Path) -> str:
    return re.sub(r"\s+", " ", path.read_text(encoding="utf-8"))


def test_page_shows_every_section(content_dir: Path) -> None:
    page = content_dir / "walking_noisy.html"
    checker = check_html(page)
    for section in SECTIONS:
        assert section in checker.ids, section
    html = _text(page)
    for fact in ("Subject", "Session", "2024-03-05 visit", "Model", "CGM 1.0", "Marker set", "Gaps and filter",
                 "Butterworth low-pass 6 Hz", "gaps of up to 10 frames filled (method auto)",
                 "subject name differs"):  # fmt: skip
        assert fact in html, fact
    assert "Cadence" in html and "steps/min" in html and "Step Length" in html
    assert "Overall GPS: <b>0.0°</b>" in html and "Knee flexion" in html
    # plain words; thesis references only in the footnotes
    assert "not a confidence interval" in html and "“Undetermined”" in html
    body = html.split('<section class="footnotes')[0]
    assert "thesis" not in body.lower()
    assert html.lower().count("thesis") >= 3
    for figure in ("cycles.png", "time_series.png", "profile.png"):
        assert (content_dir / "walking_noisy_files" / figure).is_file()
    # the synthetic walker steps on two force plates: kinetics computed, not the stored ones
    assert "Force-plate contacts" in html and NO_PLATES not in html and "stored there" not in html
    assert (content_dir / "walking_noisy_files" / "kinetics.png").is_file()


def test_angles_only_page_has_no_uncertainty_sections(content_dir: Path) -> None:
    checker = check_html(content_dir / "walking_noisy-2.html")
    assert "cycles" in checker.ids and "gps" in checker.ids and "spatiotemporal" in checker.ids
    assert "delta-phi" not in checker.ids and "allowable" not in checker.ids and "assumptions" not in checker.ids
    html = _text(content_dir / "walking_noisy-2.html")
    assert "no bands are shown" in html


def test_index_shows_the_gps(content_dir: Path) -> None:
    html = _text(content_dir / "index.html")
    assert ">GPS<" in html and "0.0°" in html and "not confidence intervals" in html


def test_grid_legend_bands_and_foot_off(noisy_run: AnglesRun, self_normative) -> None:
    data = TrialData.of(fake_analysis(noisy_run))
    clinical = ClinicalData.of(noisy_run, data.cycles, normative=self_normative)
    assert clinical.foot_off == {"L": pytest.approx(60.0, abs=1.0), "R": pytest.approx(60.0, abs=1.0)}
    fig = cycle_figure(data, "test", clinical)
    assert len(fig.axes) == 15
    patches = [h for h in fig.legends[0].legend_handles if isinstance(h, Patch) and h.get_label().strip()]
    red, green = to_rgb(SIDE_STYLE["L"][1]), to_rgb(SIDE_STYLE["R"][1])
    left = [p for p in patches if p.get_label().startswith("Left α")]
    right = [p for p in patches if p.get_label().startswith("Right α")]
    assert len(left) == len(right) == 4
    for p in left:  # filled in the left colour
        assert to_rgb(p.get_facecolor()) == pytest.approx(red)
    for p in right:  # hatched in the right colour, never a grey fill
        assert to_rgb(p.get_edgecolor()) == pytest.approx(green) and p.get_hatch()
        assert to_rgb(p.get_facecolor()) == pytest.approx((1.0, 1.0, 1.0))
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "foot off (vertical, per side)" in labels and "normative mean ± 1 SD" in labels
    knee = fig.axes[6]  # knee, sagittal
    vertical = [ln for ln in knee.lines if np.allclose(ln.get_xdata(), ln.get_xdata()[0])]
    assert {round(float(ln.get_xdata()[0]), 6) for ln in vertical} == {round(v, 6) for v in clinical.foot_off.values()}


def test_cgm24_grid_has_the_forefoot_row() -> None:
    run = run_angles(SAMPLE_DATA / "cgm24_walking.c3d", static=SAMPLE_DATA / "cgm24_static.c3d",
                     subject_file=SAMPLE_DATA / "cgm24_subject.toml", model="auto")  # fmt: skip
    data = TrialData.of(FakeAnalysis(run, None, pd.DataFrame()))
    clinical = ClinicalData.of(run, data.cycles)
    assert clinical.rows[-1] == ("ForeFootAngles", "Forefoot")
    fig = cycle_figure(data, "cgm24", clinical)
    assert len(fig.axes) == 18 and "Forefoot" in fig.axes[15].get_ylabel()
    assert "LFMH" in clinical.markers and "LTHAP" in clinical.markers


@needs_shared
@pytest.mark.slow
def test_real_trial_kinetics_and_model_marker_quality(tmp_path: Path) -> None:
    trial = shared_file("vicon", "Movement_trial.c3d")
    run = run_angles(trial, static=shared_file("vicon", "Static_trial.c3d"))
    out = write_report([ReportItem(trial, FakeAnalysis(run, None, pd.DataFrame()))], tmp_path / "out")
    data = TrialData.of(FakeAnalysis(run, None, pd.DataFrame()))
    clinical = ClinicalData.of(run, data.cycles)
    knee = clinical.kinetics[("Knee", "moment", "R", "X")]
    assert knee.unit == "N·m/kg" and 0.1 < np.nanmax(np.abs(knee.mean)) < 5  # N·mm/kg stored, shown / 1000
    assert clinical.kinetics[("Knee", "power", "R", "Z")].unit == "W/kg"
    stored = normalise_cycles(run.raw.outputs["RKneeMoment"][:, 0], data.cycles["R"])  # N·mm/kg, (cycles, 101)
    grf = run.raw.outputs["RGroundReactionForce"]
    plate = [bool(np.nan_to_num(grf[int(c.start) : int(np.ceil(c.end)) + 1]).any()) for c in data.cycles["R"]]
    used = stored[np.asarray(plate) & np.isfinite(stored).all(axis=1)]
    assert knee.cycles == len(used) == 1 < len(data.cycles["R"])  # the cycle without a plate is left out
    assert not [k for k in clinical.kinetics if k[2] == "L"]  # the left foot struck no plate
    np.testing.assert_allclose(knee.mean, used.mean(axis=0) / 1000.0, rtol=1e-12)
    html = _text(out.parent / "Movement_trial.html")
    assert "kinetics.png" in html and (out.parent / "Movement_trial_files" / "kinetics.png").is_file()
    assert "*1" not in html.split('id="quality"')[1].split('id="subject"')[0]
    assert "gaps: 0 filled" in _text(out)


def _screenshot(url: str, png: Path, height: int) -> None:
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run(
            [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
             "--no-first-run", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", f"--user-data-dir={profile}", f"--screenshot={png}",
             f"--window-size=1280,{height}", url],
            capture_output=True, timeout=120, check=False,
        )  # fmt: skip


@pytest.mark.skipif(not CHROMIUM.exists(), reason=f"{CHROMIUM} is not installed (headless screenshots)")
@pytest.mark.slow
def test_sections_render_in_chromium(content_dir: Path, tmp_path: Path) -> None:
    """One tall screenshot per page (headless Chromium ignores #fragments): every
    1600-px slice down to the page's end holds something (no blank stretch: figures and
    tables drawn), and each section heading is in the page."""
    import matplotlib.image

    for page, sections in (("walking_noisy.html", SECTIONS), ("walking_noisy-2.html", ("spatiotemporal", "gps"))):
        png = tmp_path / f"{page}.png"
        _screenshot((content_dir / page).resolve().as_uri(), png, 9000)
        assert png.is_file(), f"chromium wrote no screenshot of {page}"
        pixels = matplotlib.image.imread(png)[..., :3]
        assert pixels.shape[0] >= 9000 and pixels.shape[1] >= 1200
        inked = np.flatnonzero((pixels < 0.95).any(axis=(1, 2)))
        end = int(inked[-1]) if inked.size else 0  # the page's end (or 9000 px)
        assert end > 5000, f"{page} renders (nearly) blank"
        for top in range(0, end - 400, 1600):
            assert float(np.var(pixels[top : top + 1600])) > 1e-3, f"{page}: blank from {top} px"
        html = (content_dir / page).read_text(encoding="utf-8")
        for section in sections:
            assert re.search(rf'<h2 id="{section}">[^<]+', html), section


def test_subject_row_names_the_subject_or_where_its_parameters_came_from() -> None:
    from types import SimpleNamespace

    from fuzzygait.viz.report.clinical_html import _subject_text

    def run(name: str, source: str) -> SimpleNamespace:
        return SimpleNamespace(trial=SimpleNamespace(subject=name), raw=SimpleNamespace(subject=""),
                               subject=SimpleNamespace(source=source))  # fmt: skip

    assert _subject_text(run("A22", "/lab/visit/session.xml")) == "A22"
    assert _subject_text(run("", "/lab/visit/session.xml")) == "not named in the C3D file (parameters from session.xml)"
    assert _subject_text(run("", "Movement_trial.c3d PROCESSING group")) == "not named in the C3D file"
    assert _subject_text(run("", "")) == "not named in the C3D file"
    assert _subject_text(run("<b>", "")) == "&lt;b&gt;"


def test_moved_markers_lead_the_first_screen(content_dir: Path, tmp_path: Path) -> None:
    """A walking trial whose LTOE sits 30 mm further along the foot than in its static
    trial: the page's key box says first that markers of the left foot moved and the
    ankle and foot angles are unreliable, linking to the data quality notes that give the
    distances; the sample's own page says nothing of it."""
    from dataclasses import replace

    from fuzzygait.io import read_c3d

    walking = read_c3d(SAMPLE_DATA / "walking_noisy.c3d")
    markers = walking.markers.copy()
    toe, heel = walking.marker_labels.index("LTOE"), walking.marker_labels.index("LHEE")
    axis = markers[:, toe] - markers[:, heel]
    markers[:, toe] += 30.0 * axis / np.linalg.norm(axis, axis=1, keepdims=True)
    run = run_angles(replace(walking, markers=markers), static=SAMPLE_DATA / "static.c3d",
                     subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip
    out = tmp_path / "moved"
    with ReportWriter(out, strict=True) as writer:
        writer.add(ReportItem(SAMPLE_DATA / "walking_noisy.c3d", FakeAnalysis(run, None, pd.DataFrame(), [])))
        writer.finish()
    html = _text(out / "walking_noisy.html")
    key = html.split("How to read this page")[0]
    assert ("<b>Markers moved</b> between the static trial and this one (left foot): the static calibration "
            "does not fit them, so the ankle and foot angles are unreliable") in key  # fmt: skip
    assert key.index("Markers moved") < key.index("Gaps in the model's markers")  # the box's first line
    assert "left foot markers sit elsewhere than in the static trial static.c3d (LHEE-LTOE 220 mm, static 190 mm)" \
        in html
    assert "Markers moved" not in _text(content_dir / "walking_noisy.html")
    index = _text(out / "index.html")  # the batch's index flags the trial in its row
    assert ("warning: markers moved since the static trial (left foot): the ankle and foot angles are unreliable"
            in index)  # fmt: skip
    assert "markers moved" not in _text(content_dir / "index.html")
