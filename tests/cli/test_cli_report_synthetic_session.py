"""Issue 16's synthetic-session acceptance, end to end as a user runs it: a session folder
(static, two walking trials, subject file) generated from the bundled synthetic walker,
``fuzzygait normative`` built from one of its trials, ``fuzzygait report SESSION
--normative NORM.csv --uncertainty fast``; the spatio-temporal parameters against the
walker's known foot placement and event times, the GPS against a normative file of the
same trial, every section on the pages, and the pages rendered in headless Chromium."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from support import run, synthetic_session
from fuzzygait.gait.spatiotemporal import NAMES, UNITS
from fuzzygait.synthetic.gait_curves import FOOT_OFF_PHASE, RIGHT_PHASE_SHIFT, STRIDE_TIME_S
from fuzzygait.synthetic.generate import WALKING_SPEED_MM_S
from fuzzygait.workflows.batch_report import load_entry

CHROMIUM = Path("/usr/bin/chromium")
#: What a trial page with fast bands and normative data shows.
TRIAL_SECTIONS = ("guide", "spatiotemporal", "cycles", "gps", "kinetics", "allowable", "delta-phi", "time-series",
                  "quality", "subject", "references")  # fmt: skip
SESSION_SECTIONS = ("session", "spatiotemporal", "cycles", "trials")


def _by_hand() -> dict[str, float]:
    """The walker's parameters from its generator: a foot advances v T per stride and the
    right limb repeats the left one half a cycle later (a step is v T / 2); the opposite
    Foot Off is the other limb's, (0.5 + 0.6) mod 1 of the cycle."""
    t = STRIDE_TIME_S
    opposite_off = (RIGHT_PHASE_SHIFT + FOOT_OFF_PHASE) % 1.0
    return {
        "Cadence": 120.0 / t, "Walking Speed": WALKING_SPEED_MM_S / 1000.0, "Stride Time": t,
        "Step Time": (1.0 - RIGHT_PHASE_SHIFT) * t, "Opposite Foot Off": 100.0 * opposite_off,
        "Opposite Foot Contact": 100.0 * RIGHT_PHASE_SHIFT, "Foot Off": 100.0 * FOOT_OFF_PHASE,
        "Single Support": (RIGHT_PHASE_SHIFT - opposite_off) * t,
        "Double Support": (opposite_off + FOOT_OFF_PHASE - RIGHT_PHASE_SHIFT) * t,
        "Stride Length": WALKING_SPEED_MM_S * t / 1000.0, "Step Length": WALKING_SPEED_MM_S * t / 2000.0,
    }  # fmt: skip


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("synthetic-session")
    session = synthetic_session(root / "visit-1", 240)  # 240 frames: a complete cycle per side
    norm = root / "norm.csv"
    built = run("normative", session / "walk01.c3d", "--static", session / "cal01.c3d",
                "--subject", session / "Synthetic.toml", "--per-side", "--out", norm)  # fmt: skip
    assert built.returncode == 0, built.stderr
    out = root / "report"
    result = run("report", session, "--out", out, "--normative", norm, "--uncertainty", "fast", "--workers", "1")
    assert result.returncode == 0, result.stderr
    assert "report: 1 session(s), 2 of 2 trials OK" in result.stdout
    return out / "visit-1"


def _text(path: Path) -> str:
    return re.sub(r"\s+", " ", path.read_text(encoding="utf-8"))


@pytest.mark.slow
def test_spatiotemporal_parameters_match_the_generator(report: Path) -> None:
    expected = _by_hand()
    for trial in ("walk01", "walk02"):
        with np.load(report / f"{trial}_files" / "data.npz") as data:
            for code in ("L", "R"):
                cycles = data[f"spatiotemporal/{code}"]  # every complete cycle the page averages
                assert cycles.shape[0] >= 1, (trial, code)
                for k, name in enumerate(NAMES):
                    if UNITS[name] == "m":
                        assert np.abs(cycles[:, k] - expected[name]).max() <= 1e-3, (trial, code, name)  # 1 mm
                    else:
                        assert np.abs(cycles[:, k] / expected[name] - 1).max() <= 0.01, (trial, code, name)
    session = _text(report / "index.html")
    assert "Spatio-temporal parameters: all trials" in session
    assert "109.1" in session  # Cadence 120 / 1.1 s, mean over every cycle of both trials


@pytest.mark.slow
def test_gps_against_the_trials_own_normative_file_is_zero(report: Path) -> None:
    html = _text(report / "walk01.html")
    assert "Overall GPS: <b>0.0°</b>" in html and 'against the normative data <span class="mono">norm.csv' in html
    entry = load_entry(report, "walk01")  # the unrounded score behind the page (entry.json)
    assert entry.gps == pytest.approx(0.0, abs=1e-9)


@pytest.mark.slow
def test_pages_show_every_section(report: Path) -> None:
    trial = report.joinpath("walk01.html").read_text(encoding="utf-8")
    for section in TRIAL_SECTIONS:
        assert re.search(rf'<h2 id="{section}">[^<]+', trial), section
    session = report.joinpath("index.html").read_text(encoding="utf-8")
    for section in SESSION_SECTIONS:
        assert re.search(rf'<h2 id="{section}">[^<]+', session), section
    for figure in ("cycles.png", "time_series.png", "profile.png"):
        assert (report / "walk01_files" / figure).is_file(), figure
    assert (report / "session_files" / "cycles.png").is_file()


@pytest.mark.skipif(not CHROMIUM.exists(), reason=f"{CHROMIUM} is not installed (headless screenshots)")
@pytest.mark.slow
def test_session_and_trial_pages_render(report: Path, tmp_path: Path) -> None:
    from viz.test_report_content import _screenshot

    import matplotlib.image

    for page, height in (("walk01.html", 9000), ("index.html", 3000)):
        png = tmp_path / f"{page}.png"
        _screenshot((report / page).resolve().as_uri(), png, height)
        assert png.is_file(), f"chromium wrote no screenshot of {page}"
        pixels = matplotlib.image.imread(png)[..., :3]
        inked = np.flatnonzero((pixels < 0.95).any(axis=(1, 2)))
        end = int(inked[-1]) if inked.size else 0
        assert end > height // 2, f"{page} renders (nearly) blank"
        for top in range(0, end - 400, 1600):
            assert float(np.var(pixels[top : top + 1600])) > 1e-3, f"{page}: blank from {top} px"
