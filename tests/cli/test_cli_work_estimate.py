"""Issue 37 point 6: the heavy commands say their work before they start, and refuse the
absurd in one line before any work.

* ``--alphas`` with more than 20 α-levels below 1 (``uncertainty``, ``report``,
  ``fuzzy-sim``, ``frv-sim``) and ``frv-sim --samples`` above 10⁶ without ``--force``:
  one error line naming the option, the limit and what to do (in-process, fast).
* A short real run of each command prints ``estimate: …`` first — forward simulations for
  ``fuzzy-sim`` (an upper bound, checked against the count run) and ``frv-sim`` (exact for
  a new one-parameter study, a bound for an extension and for several parameters), α-level
  optimisations (frames × α-levels × components) for ``uncertainty`` and ``report``.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fuzzygait.cli.options import parse_alphas
from fuzzygait.uncertainty.frv.store import read_meta
from fuzzygait.uncertainty.storage import load_result
from fuzzygait.workflows.work_estimate import MAX_ALPHA_LEVELS, MAX_FRV_SAMPLES
from support import SAMPLE_DATA, assert_one_line_error, run_here, trial_window

MANY = ",".join(f"{i / 1000:g}" for i in range(1000))  # the 1,000 levels
CALIBRATION = ("--static", SAMPLE_DATA / "static.c3d", "--subject", SAMPLE_DATA / "subject.toml")
#: A stance study that runs in about a second (6 blade nodes, 20 time steps).
STUDY = ("stance", "--duration", "0.02", "--nodes", "6", "--set", "E=59.958e9", "--workers", "1")


def _estimate(stdout: str) -> str:
    """The estimate line: the first line of the output."""
    first = stdout.splitlines()[0] if stdout else ""
    assert first.startswith("estimate: "), stdout
    return first


def _number(pattern: str, text: str) -> int:
    found = re.search(pattern, text)
    assert found, (pattern, text)
    return int(found[1].replace(",", ""))


# ---------------------------------------------------------------------------- limits
@pytest.mark.parametrize(
    "args",
    [
        ("uncertainty", SAMPLE_DATA / "walking.c3d", "--out", "{tmp}/fuzzy.nc"),
        ("report", SAMPLE_DATA / "walking.c3d", "--out", "{tmp}/report"),
        ("fuzzy-sim", "stance", "--fuzzy", "E=10%", "--out", "{tmp}/fuzzy.nc"),
        ("frv-sim", "stance", "--out", "{tmp}/study.zarr"),
    ],
    ids=lambda args: str(args[0]),
)
def test_more_than_20_alpha_levels_is_one_line(tmp_path: Path, args: tuple) -> None:
    given = [str(a).replace("{tmp}", str(tmp_path)) for a in args]
    result = run_here(*given, "--alphas", MANY)
    assert_one_line_error(result, "--alphas gives 1000 α-levels below 1", f"at most {MAX_ALPHA_LEVELS}",
                          "give fewer, e.g. 0,0.25,0.5,0.75")  # fmt: skip
    assert result.stdout == "" and not list(tmp_path.iterdir())


def test_20_alpha_levels_are_taken_and_1_is_not_counted() -> None:
    twenty = ",".join(f"{i / 20:g}" for i in range(20)) + ",1"
    assert len(parse_alphas(twenty)) == 21
    with pytest.raises(Exception, match="21 α-levels below 1"):
        parse_alphas(",".join(f"{i / 21:g}" for i in range(21)))


def test_more_than_a_million_frv_samples_is_one_line_unless_forced(tmp_path: Path) -> None:
    store = tmp_path / "study.zarr"
    result = run_here("frv-sim", "stance", "--samples", str(MAX_FRV_SAMPLES + 1), "--out", store)
    assert_one_line_error(result, f"--samples {MAX_FRV_SAMPLES + 1}", "more than 1,000,000 FRV samples",
                          "give at most 1000000", "--force")  # fmt: skip
    assert result.stdout == "" and not list(tmp_path.iterdir())
    # at the limit, and above it with --force, the count passes: the next check (--out's suffix) speaks
    at_limit = run_here("frv-sim", "stance", "--samples", str(MAX_FRV_SAMPLES), "--out", tmp_path / "x.nc")
    assert_one_line_error(at_limit, "--out must be a .zarr directory")
    forced = run_here("frv-sim", "stance", "--samples", str(10 * MAX_FRV_SAMPLES), "--force",
                      "--out", tmp_path / "x.nc")  # fmt: skip
    assert_one_line_error(forced, "--out must be a .zarr directory")
    assert not list(tmp_path.iterdir())


# ---------------------------------------------------------------------------- the estimates of real runs
@pytest.mark.slow
def test_fuzzy_sim_says_at_most_how_many_simulations(tmp_path: Path) -> None:
    out = tmp_path / "fuzzy.nc"
    result = run_here("fuzzy-sim", "swing", "--fuzzy", "E=10%,rho=5%", "--duration", "0.1", "--nodes", "6",
                      "--stride", "20", "--workers", "1", "--out", out)  # fmt: skip
    assert result.returncode == 0, result.stderr
    line = [x for x in result.stdout.splitlines() if not x.startswith("note:")][0]
    assert line.startswith("estimate: at most ") and "each (extrapolated from its first 10 of 100 steps" in line
    bound = _number(r"at most ([\d,]+) forward simulations of the swing", line)
    optimisations = _number(r"\(([\d,]+) α-level optimisations: 2 α-levels × 2 bounds × 6 time nodes", line)
    done = load_result(out).attrs
    assert optimisations == done["optimisations"] == 24
    assert bound == 1 + 4 * optimisations and 1 < done["forward_simulations"] <= bound


@pytest.mark.slow
def test_frv_sim_says_how_many_simulations(tmp_path: Path) -> None:
    store = tmp_path / "study.zarr"
    new = run_here("frv-sim", *STUDY, "--disc", "8", "--samples", "20", "--out", store)
    assert new.returncode == 0, new.stderr
    line = _estimate(new.stdout)
    assert line.startswith("estimate: 7 forward simulations of the stance (one per grouping bin: --disc 8 points)")
    assert "then the hulls of 20 samples" in line
    assert read_meta(store)["counts"]["forward_simulations"] == 7  # exactly the estimate
    more = run_here("frv-sim", "stance", "--samples", "500", "--workers", "1", "--out", store)  # an extension
    assert more.returncode == 0, more.stderr
    line = _estimate(more.stdout)
    counts = read_meta(store)["counts"]
    if line.startswith("estimate: no new forward simulations"):
        assert counts["last_forward_simulations"] == 0
    else:
        bound = _number(r"^estimate: at most ([\d,]+) forward simulations", line)
        assert "simulated before" in line and counts["last_forward_simulations"] <= bound
    several = tmp_path / "several.zarr"
    boxes = run_here("frv-sim", *STUDY, "--frv", "E,rho", "--disc", "5,4", "--samples", "10", "--out", several)
    assert boxes.returncode == 0, boxes.stderr
    line = _estimate(boxes.stdout)
    bound = _number(r"^estimate: at most ([\d,]+) forward simulations", line)
    assert "≤ 12 grid points inside the occurring boxes of 4 × 3 bins" in line
    assert 12 <= read_meta(several)["counts"]["forward_simulations"] <= bound


@pytest.mark.slow
def test_uncertainty_says_its_optimisations(tmp_path: Path) -> None:
    out = tmp_path / "fuzzy.nc"
    result = run_here("uncertainty", SAMPLE_DATA / "walking.c3d", *CALIBRATION, "--angles", "LKneeAngles",
                      "--alphas", "0.5", "--tolerance", "0", "--no-per-source", "--workers", "1",
                      "--out", out)  # fmt: skip
    assert result.returncode == 0, result.stderr
    line = _estimate(result.stdout)
    assert line == ("estimate: 1,536 α-level optimisations of the fuzzy angles (512 frames × 1 α-level × 3 angle "
                    "components, each for the upper and the lower bound)")  # fmt: skip
    fuzzy = load_result(out)
    analysed = fuzzy["hull"].sel(alpha=0.5).notnull().all("bound").sum().item()  # component × frame
    assert analysed == 1536


@pytest.mark.slow
def test_report_says_its_optimisations(tmp_path: Path) -> None:
    trial = trial_window(SAMPLE_DATA / "walking.c3d", tmp_path / "short.c3d", 100, 30)
    result = run_here("report", trial, *CALIBRATION, "--uncertainty", "fast", "--workers", "1",
                      "--out", tmp_path / "report")  # fmt: skip
    assert result.returncode == 0, result.stderr
    line = _estimate(result.stdout)
    assert line.startswith("estimate: 1 trial, 30 frames in all: ≈ 360 α-level optimisations of the fuzzy angles "
                           "(frames × 2 α-levels × 6 angle components")  # fast: hip, knee, ankle flexion, α = 0, 0.5
    assert line.endswith("trials unchanged since the last run on --out are reused")
    assert "report: 1 session(s), 1 of 1 trials OK" in result.stdout
