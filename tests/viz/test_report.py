"""The clinicians' batch report (``fuzzygait report``, :mod:`fuzzygait.viz.report`).

The page tests use a fake marker-error analysis built from a real pipeline run on the
sample trial (angles ± (1 − α)·k deg), so they do not depend on the optimiser; the
end-to-end test runs the real command once ``fuzzygait.markererror.analysis`` exists.
"""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import tempfile
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.markererror.result import AngleAxes, fuzzy_angles_dataset, with_error_sources
from fuzzygait.viz.report import component_label, cycle_bands
from fuzzygait.workflows.angles import AnglesRun, run_angles
from fuzzygait.workflows.report_folder import ReportItem, write_report
from support import SAMPLE_DATA, FakeAnalysis, assert_one_line_error, run, run_here

ALPHAS = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
CHROMIUM = Path("/usr/bin/chromium")
HAS_ANALYSIS = importlib.util.find_spec("fuzzygait.markererror.analysis") is not None




def spread(name: str) -> float:
    """Half-width (deg) of the fake α = 0 band of one component: 2, 3 or 4 deg."""
    return 2.0 + "XYZ".index(name[-1])


def fake_analysis(run_: AnglesRun, alphas: np.ndarray = ALPHAS) -> FakeAnalysis:
    table = run_.angle_table()
    names = [c for c in table.columns if c not in ("frame", "time") and table[c].notna().any()]
    markers = list(run_.trial.marker_labels)
    hulls: dict[str, np.ndarray] = {}
    delta_phi = {}
    for name in names:
        det = table[name].to_numpy()
        half = (1.0 - alphas)[:, None] * spread(name)
        hulls[name] = np.stack([det - half, det + half], axis=1)
        width = 2.0 * half[:, 0]
        delta_phi[name] = 100.0 * width / np.nanmax(np.abs(det))
    deviation = np.zeros((alphas.size, 2, run_.trial.n_frames, len(markers)))
    fuzzy = fuzzy_angles_dataset(hulls, AngleAxes(alphas=alphas, frames=run_.trial.frames, times=run_.trial.times,
                                 markers=markers, ball_radius=np.linspace(7.0, 32.0, len(markers))),
                                 deviations={name: deviation for name in names},
                                 attrs={"trial": run_.trial.name})  # fmt: skip
    fuzzy = with_error_sources(fuzzy, ("measurement", "placement", "sta"))
    keep = alphas < 1
    frame = pd.DataFrame({n: v[keep] for n, v in delta_phi.items()}, index=alphas[keep]).T
    note = Finding(FindingKind.UNCERTAINTY, "fake analysis for the report tests")
    return FakeAnalysis(run_, fuzzy, frame, notes=[note])


@pytest.fixture(scope="module")
def noisy_run() -> AnglesRun:
    return run_angles(
        SAMPLE_DATA / "walking_noisy.c3d",
        static=SAMPLE_DATA / "static.c3d",
        subject_file=SAMPLE_DATA / "subject.toml",
    )


@pytest.fixture(scope="module")
def report_dir(noisy_run: AnglesRun, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("report") / "out"
    items = [
        ReportItem(SAMPLE_DATA / "walking_noisy.c3d", fake_analysis(noisy_run), None),
        ReportItem(Path("data/broken trial.c3d"), None, "broken trial.c3d: not a C3D file <bad header>"),
    ]
    index = write_report(items, out)
    assert index == out / "index.html"
    return out


class _Checker(HTMLParser):
    """Collects links/images and checks that the elements nest properly."""

    VOID = {"meta", "img", "br", "link", "hr", "input", "source", "wbr"}

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.links: list[str] = []
        self.images: list[str] = []
        self.ids: list[str] = []
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if tag in ("script", "iframe", "object", "embed"):
            self.errors.append(f"<{tag}> is not allowed")
        if tag == "a" and values.get("href"):
            self.links.append(values["href"] or "")
        if tag == "img":
            self.images.append(values.get("src") or "")
            if not values.get("alt"):
                self.errors.append("img without alt")
        if values.get("id"):
            self.ids.append(values["id"] or "")
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag: str) -> None:
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else None}>")
            return
        self.stack.pop()

    def handle_data(self, data: str) -> None:
        self.text.append(data)


def check_html(path: Path) -> _Checker:
    source = path.read_text(encoding="utf-8")
    assert source.startswith("<!DOCTYPE html>")
    assert '<html lang="en">' in source and '<meta charset="utf-8">' in source
    checker = _Checker()
    checker.feed(source)
    checker.close()
    assert not checker.errors, checker.errors
    assert not checker.stack, f"unclosed {checker.stack}"
    assert len(checker.ids) == len(set(checker.ids)), "duplicate ids"
    for url in checker.links + checker.images:  # self-contained: nothing external
        assert not re.match(r"^[a-z]+:", url), url
    assert "http://" not in source and "https://" not in source
    return checker


def test_bands_are_the_mean_of_the_normalised_hulls(noisy_run: AnglesRun) -> None:
    from fuzzygait.gait.cycles import gait_cycles, normalise_cycles

    cycles = gait_cycles(noisy_run.trial, noisy_run.events, "L")
    knee = noisy_run.result.angles["LKneeAngles"][:, 0]
    hull = np.stack([np.stack([knee - 3 * (1 - a), knee + 3 * (1 - a)]) for a in (0.0, 0.5)])
    mean, band, used = cycle_bands(knee, hull, cycles)
    complete = np.isfinite(normalise_cycles(knee, cycles)).all(axis=1)
    assert used == complete.sum() == len(cycles) - 1 >= 3  # LANK gap: the last cycle has no knee
    stats = noisy_run.cycle_statistics()
    expected = stats[stats["angle"] == "LKneeAngles_X"]["mean"].to_numpy()
    np.testing.assert_allclose(mean, expected, atol=1e-9)
    np.testing.assert_allclose(band[0, 0], mean - 3.0, atol=1e-9)
    np.testing.assert_allclose(band[1, 1], mean + 1.5, atol=1e-9)
    # a hull missing in one cycle drops that cycle from mean and band alike
    gappy = hull.copy()
    start = int(np.ceil(cycles[1].start)) + 5
    gappy[0, 1, start] = np.nan
    mean2, band2, used2 = cycle_bands(knee, gappy, cycles)
    assert used2 == used - 1  # normalise_cycles drops the whole cycle of that hull
    assert (band2[0, 0] <= mean2 + 1e-9).all() and (mean2 <= band2[0, 1] + 1e-9).all()


def test_component_labels() -> None:
    assert component_label("LKneeAngles_X") == "Left knee, sagittal (+ flexion)"
    assert component_label("RFootProgressAngles_Z") == "Right foot progression, transverse (+ internal)"
    assert component_label("Whatever") == "Whatever"


def test_pages_index_figures_and_delta_phi_table(report_dir: Path, noisy_run: AnglesRun) -> None:
    index = check_html(report_dir / "index.html")
    assert "walking_noisy.html" in index.links
    page_path = report_dir / "walking_noisy.html"
    page = check_html(page_path)
    assert "index.html" in page.links
    assert len(page.images) == 4  # angles over the cycle, kinetics and GRF (the sample's plates), whole trial
    for url in page.images + [u for u in page.links if not u.startswith("#")]:
        target = (page_path.parent / url.split("#")[0]).resolve()
        assert target.is_file() and target.stat().st_size > 1000 or url == "index.html", url
    files = report_dir / "walking_noisy_files"
    assert sorted(p.name for p in files.iterdir()) == [
        "cycles.png", "cycles.svg", "grf.png", "grf.svg", "kinetics.png", "kinetics.svg", "time_series.png",
        "time_series.svg",
    ]  # fmt: skip
    text = page_path.read_text(encoding="utf-8")
    # ΔΦ of the fake: 100 * 2 (1 - α) spread / max Φ; e.g. left knee flexion at α = 0
    knee_max = np.nanmax(np.abs(noisy_run.result.angles["LKneeAngles"][:, 0]))
    row = re.search(r"Left knee, sagittal.*?</tr>", text, re.S)
    assert row is not None
    cells = re.findall(r'<td class="num">([^<]*)</td>', row.group(0))
    expected = [100 * 2 * (1 - a) * 2.0 / knee_max for a in (0.75, 0.5, 0.25, 0.0)]
    assert cells[:4] == [f"{v:.0f}" for v in expected]
    assert cells[4] == f"{knee_max:.1f}" and cells[5] == "4.0"  # reference max |Φ|, widest band
    # header, subject, data quality
    for needle in ("512 (C3D frames 1–512)", "100 Hz", "Static plantarflexion offset", "23.20",
                   "static offsets calibrated from static.c3d", "LANK", "not filled: longer than max_gap=10",
                   "Foot strikes", "fake analysis for the report tests", "(1 − α)",
                   "selected error sources: measurement system, marker placement, soft-tissue artefact)"):  # fmt: skip
        assert needle in text, needle
    # no files left behind by the atomic writing
    assert not list(report_dir.parent.glob(".out.*"))


def test_failed_item_is_listed_with_its_error(report_dir: Path) -> None:
    text = (report_dir / "index.html").read_text(encoding="utf-8")
    assert "broken trial.c3d" in text
    assert "not a C3D file &lt;bad header&gt;" in text
    assert re.search(r'class="failed">failed<', text)
    assert "1 OK" in text and "1 failed" in text
    assert not (report_dir / "broken trial.html").exists()


def test_rerun_replaces_pages_and_keeps_folder_intact_on_error(
    report_dir: Path, noisy_run: AnglesRun, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from fuzzygait.workflows import report_folder as report

    def quick_files(figure: object, stem: Path, dpi: int) -> None:  # figures are tested above
        for suffix in (".png", ".svg"):
            stem.with_suffix(suffix).write_bytes(b"x")

    monkeypatch.setattr(report, "save_figure_files", quick_files)
    out = tmp_path / "out"
    shutil.copytree(report_dir, out)
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}

    def items():
        yield ReportItem(SAMPLE_DATA / "walking_noisy.c3d", fake_analysis(noisy_run), None)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_report(items(), out)
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # staging folder removed
    # a second run into an existing folder replaces the pages
    write_report([ReportItem(Path("x/only.c3d"), None, "only failed")], out)
    assert "only failed" in (out / "index.html").read_text(encoding="utf-8")
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def _screenshot(url: str, png: Path) -> None:
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run(
            [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
             "--no-first-run", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", f"--user-data-dir={profile}", f"--screenshot={png}",
             "--window-size=1200,1600", url],
            capture_output=True, timeout=60, check=False,
        )  # fmt: skip


@pytest.mark.skipif(not CHROMIUM.exists(), reason=f"{CHROMIUM} is not installed (headless screenshots)")
def test_pages_render_in_chromium(report_dir: Path, tmp_path: Path) -> None:
    import matplotlib.image

    for page in ("index.html", "walking_noisy.html"):
        png = tmp_path / f"{page}.png"
        _screenshot((report_dir / page).resolve().as_uri(), png)
        assert png.is_file(), f"chromium wrote no screenshot of {page}"
        pixels = matplotlib.image.imread(png)
        assert pixels.shape[0] >= 1000 and pixels.shape[1] >= 1000
        assert float(np.var(pixels[..., :3])) > 1e-3, f"{page} renders blank"


@pytest.mark.skipif(not HAS_ANALYSIS, reason="fuzzygait.markererror.analysis is not written yet")
@pytest.mark.slow
def test_report_command_end_to_end(tmp_path: Path) -> None:
    corrupt = tmp_path / "corrupt.c3d"
    corrupt.write_bytes(b"this is not a C3D file" * 20)
    out = tmp_path / "report"
    result = run(
        "report", SAMPLE_DATA / "walking.c3d", SAMPLE_DATA / "walking_noisy.c3d", corrupt,
        "--out", out, "--static", SAMPLE_DATA / "static.c3d",
        "--subject", SAMPLE_DATA / "subject.toml", "--alphas", "0,0.5", "--angles", "LKneeAngles",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stdout + result.stderr
    assert str(out / "index.html") in result.stdout
    index = check_html(out / "index.html")
    assert {"walking.html", "walking_noisy.html"} <= set(index.links)
    text = (out / "index.html").read_text(encoding="utf-8")
    row = re.search(r"<tr[^>]*>(?:(?!</tr>).)*corrupt\.c3d(?:(?!</tr>).)*</tr>", text, re.S)
    assert row is not None and ">failed<" in row.group(0)
    assert "corrupt.c3d" in result.stderr
    page = check_html(out / "walking.html")
    assert page.images == ["walking_files/cycles.png", "walking_files/kinetics.png", "walking_files/grf.png",
                           "walking_files/sources.png", "walking_files/time_series.png"]  # fmt: skip
    text = (out / "walking.html").read_text(encoding="utf-8")
    assert "α = 0.5" in text and "LKneeAngles_X" in text
    assert "No uncertainty band (not analysed)" in text  # the other angles: curves only


@pytest.mark.skipif(not HAS_ANALYSIS, reason="fuzzygait.markererror.analysis is not written yet")
def test_report_command_exits_1_when_every_trial_fails(tmp_path: Path) -> None:
    corrupt = tmp_path / "corrupt.c3d"
    corrupt.write_bytes(b"junk")
    result = run("report", corrupt, "--out", tmp_path / "r")
    assert result.returncode == 1
    assert "Traceback" not in result.stdout + result.stderr
    assert "failed" in (tmp_path / "r" / "index.html").read_text(encoding="utf-8")


@pytest.mark.parametrize(("option", "value"), [("--alphas", "0,1.5"), ("--angles", "LKnee")])
def test_report_command_rejects_bad_options(tmp_path: Path, option: str, value: str) -> None:
    result = run_here("report", SAMPLE_DATA / "walking.c3d", "--out", tmp_path / "r", option, value)
    assert_one_line_error(result, option)
    assert not (tmp_path / "r").exists()
