"""``frv-sim`` on an existing study (issue 17): the study records the options it was made
with; extending it with any different one is refused in one line naming the option, its
recorded and its given value — before anything is simulated or written (the store is
untouched, byte for byte). A store without a record, or not a study, is refused too.

In-process and fast: the study's record is written by ``FRVStudy.create`` on a cheap
model with the options ``run_frv_leg`` would record for the leg (the refusal reads only
the record; the end-to-end runs are in ``test_cli_frv_sim_crash.py``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from fuzzygait.cli import app
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.uncertainty import FunctionModel
from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy, StudyOptions
from fuzzygait.workflows.frv_leg import FRVRequest, study_options
from fuzzygait.workflows.fuzzy_dynamics import LegSetup

MODULUS = 59.958e9  # Pa, Table 5.3
SETTINGS = SolverSettings(duration=0.02, scheme="energy-momentum")
MADE = ("stance", "--disc", "6", "--duration", "0.02", "--nodes", "6", "--set", f"E={MODULUS}")
runner = CliRunner()


def _model() -> FunctionModel:
    times = np.linspace(0.0, 1.0, 5)
    return FunctionModel(lambda p: np.sin(p[..., :1] * 1e-10 * times), times)


def _study(path: Path, options: dict | None) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    FRVStudy.create(_model(), FRVSpec("E", MODULUS), 30, StudyOptions(n_disc=6, record=options), store=path)
    return path


@pytest.fixture(scope="module")
def store(tmp_path_factory: pytest.TempPathFactory) -> Path:
    setup = LegSetup("stance", nodes=6, values={"E": MODULUS}, solver=SETTINGS)
    options = study_options(setup, FRVRequest(disc=6))
    assert options["set"]["eta"] == 1.0 and options["dt"] == 0.001  # the scenario's, resolved
    return _study(tmp_path_factory.mktemp("options") / "study.zarr", options)


def _files(path: Path) -> dict[str, bytes]:
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


def _refusal(store: Path, *args: str) -> str:
    before = _files(store)
    result = runner.invoke(app, ["frv-sim", *args, "--samples", "10", "--workers", "1", "--out", str(store)])
    assert result.exit_code == 1, result.output
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and result.stdout == "", result.output
    assert _files(store) == before  # nothing written
    assert sorted(p.name for p in store.parent.iterdir()) == [store.name]  # nothing beside it
    return lines[0]


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (("--frv", "rho"), "made with --frv E; given rho. To extend it, leave --frv out"),
        (("--value", "6e10"), "made with --value 5.9958e+10; given 6e+10. To extend it, leave --value out"),
        (("--set", "E=6e10"), "made with --set E=5.9958e+10; given E=6e+10. To extend it, leave --set E out"),
        (("--set", "eta=2"), "made with --set eta=1; given eta=2. To extend it, leave --set eta out"),
        (("--set", "rho=8550.000001"), "made with --set rho=8550; given rho=8550.000001."),
        (("--target", "last_node_x"), "made with --target max_element_energy; given last_node_x."),
        (("--alphas", "0,0.5"), "made with --alphas 0,0.25,0.5,0.75,1; given 0,0.5,1."),
        (("--seed", "1"), "made with --seed 0; given 1."),
        (("--distribution", "beta"), "made with --distribution normal; given beta."),
        (("--sampling", "lhs"), "made with --sampling random; given lhs."),
        (("--disc", "100"), "made with --disc 6; given 100."),
        (("--nodes", "20"), "made with --nodes 6; given 20."),
        (("--dt", "0.0005"), "made with --dt 0.001; given 0.0005."),
        (("--duration", "2"), "made with --duration 0.02; given 2."),
        (("--scheme", "variational"), "made with --scheme energy-momentum; given variational."),
    ],
)  # fmt: skip
def test_an_extension_with_another_option_is_refused_naming_it(store: Path, args: tuple[str, ...], named: str) -> None:
    line = _refusal(store, "stance", *args)
    assert line.startswith(f"fuzzygait: error: {store}: this study was {named}")
    assert line.endswith("or start a new study (another --out, or --overwrite)")


def test_options_given_as_made_pass_the_check(store: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The same options, given or left out, reach the study run unchanged (the run itself
    is replaced here: it would simulate the leg)."""
    import fuzzygait.mechanics.fuzzy_dynamics as mechanics

    seen: list[dict] = []
    monkeypatch.setattr(mechanics, "leg_frv_study", lambda *a, **k: seen.append(k) or FRVStudy.open(store, _model()))
    for args in (("stance",), MADE, ("stance", "--set", "eta=1", "--scheme", "energy-momentum", "--frv", "E")):
        result = runner.invoke(app, ["frv-sim", *args, "--samples", "0", "--workers", "1", "--out", str(store)])
        assert result.exit_code == 0, result.output
    assert len(seen) == 3 and all(k["study"].record == seen[0]["study"].record for k in seen)
    assert seen[0]["study"].record == FRVStudy.open(store, _model()).options


def test_the_scenario_is_checked_too(store: Path) -> None:
    line = _refusal(store, "swing")
    assert "made with SCENARIO stance; given swing. To extend it, give SCENARIO stance, or start a new" in line


def test_a_study_without_a_record_or_not_a_study_is_refused(tmp_path: Path) -> None:
    bare = _study(tmp_path / "bare" / "study.zarr", None)
    line = _refusal(bare, *MADE)
    assert "does not record the options it was made with" in line and "another --out, or --overwrite" in line
    other = tmp_path / "other" / "x.zarr"
    other.mkdir(parents=True)
    (other / "notes.txt").write_text("not a study")
    assert "not an FRV study" in _refusal(other, *MADE)


# ---------------------------------------------------------------------------- several FRVs (--frv E,rho)
RHO = 8550.0  # kg/m³, the stance scenario's


@pytest.fixture(scope="module")
def multi_store(tmp_path_factory: pytest.TempPathFactory) -> Path:
    setup = LegSetup("stance", nodes=6, values={"E": MODULUS}, solver=SETTINGS)
    options = study_options(setup, FRVRequest("E,rho", disc=6))
    assert options["frv"] == "E,rho" and options["value"] == [MODULUS, options["set"]["rho"]]
    times = np.linspace(0.0, 1.0, 5)
    model = FunctionModel(lambda p: np.sin(p[..., :1] * 1e-10 * times) + p[..., 1:2] * 1e-4 * times, times)
    path = tmp_path_factory.mktemp("multi") / "study.zarr"
    specs = [FRVSpec("E", MODULUS, alphas=(0.0, 0.25, 0.5, 0.75, 1.0)),
             FRVSpec("rho", options["set"]["rho"], alphas=(0.0, 0.25, 0.5, 0.75, 1.0))]  # fmt: skip
    FRVStudy.create(model, specs, 30, StudyOptions(n_disc=6, record=options), store=path)
    return path


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (("--frv", "E"), "made with --frv E,rho; given E. To extend it, leave --frv out"),
        (("--set", "rho=9000"), f"made with --set rho={RHO:g}; given rho=9000. To extend it, leave --set rho out"),
        (("--disc", "7"), "made with --disc 6; given 7."),
    ],
)  # fmt: skip
def test_an_extension_of_several_frvs_with_another_option_is_refused(multi_store: Path, args: tuple[str, ...],
                                                                     named: str) -> None:  # fmt: skip
    line = _refusal(multi_store, "stance", *args)
    assert line.startswith(f"fuzzygait: error: {multi_store}: this study was {named}")


def test_several_frvs_take_no_value_and_unknown_or_repeated_names_are_refused(tmp_path: Path) -> None:
    for args, said in ((("--frv", "E,rho", "--value", "6e10"), "--value applies to one --frv parameter"),
                       (("--frv", "E,foo"), "--frv 'foo': unknown parameter"),
                       (("--frv", "E,E"), "a parameter is named twice")):  # fmt: skip
        result = runner.invoke(app, ["frv-sim", "stance", *args, "--samples", "10", "--workers", "1",
                                     "--out", str(tmp_path / "new.zarr")])  # fmt: skip
        assert result.exit_code == 1 and said in result.stderr, result.output
        assert not (tmp_path / "new.zarr").exists()


def test_a_study_recorded_before_the_sampling_option_counts_as_random(tmp_path: Path) -> None:
    setup = LegSetup("stance", nodes=6, values={"E": MODULUS}, solver=SETTINGS)
    options = study_options(setup, FRVRequest(disc=6))
    del options["sampling"]  # as recorded before --sampling existed
    old = _study(tmp_path / "old" / "study.zarr", options)
    assert "made with --sampling random; given lhs." in _refusal(old, "stance", "--sampling", "lhs")
    result = runner.invoke(app, ["frv-sim", "stance", "--sampling", "sobol", "--samples", "10", "--workers", "1",
                                 "--out", str(tmp_path / "new.zarr")])  # fmt: skip
    assert result.exit_code == 1 and "sampling must be 'random' or 'lhs'" in result.stderr, result.output
    assert not (tmp_path / "new.zarr").exists()


def test_disc_per_parameter_reaches_the_grids_and_the_record(tmp_path: Path) -> None:
    from fuzzygait.uncertainty.frv.store import read_meta

    out = tmp_path / "boxes.zarr"
    args = ["--frv", "E,rho", "--disc", "5,4", "--samples", "40", "--duration", "0.02", "--nodes", "6"]
    result = runner.invoke(app, ["frv-sim", "stance", *args, "--workers", "1", "--out", str(out)])
    assert result.exit_code == 0, result.output
    meta = read_meta(out)
    assert meta["options"]["disc"] == [5, 4] and meta["n_disc"] == [5, 4]
    study = FRVStudy.open(out, FunctionModel(lambda p: p, np.linspace(0.0, 0.02, 21)))
    assert study.several and [g.n_points for g in study.grids] == [5, 4]
    assert study.grids[0].spacing != study.grids[1].spacing
    assert study.refine is True  # the leg's sensitivities refine the study
    line = _refusal(out, "stance", "--disc", "5")
    assert line.startswith(f"fuzzygait: error: {out}: this study was made with --disc 5,4; given 5."), line


@pytest.mark.parametrize("disc", ["6,5,4", "1", "x", "6,1"])
def test_a_disc_that_does_not_fit_the_parameters_is_refused(tmp_path: Path, disc: str) -> None:
    result = runner.invoke(app, ["frv-sim", "stance", "--frv", "E,rho", "--disc", disc, "--samples", "10",
                                 "--workers", "1", "--out", str(tmp_path / "new.zarr")])  # fmt: skip
    assert result.exit_code == 1 and "--disc must be one whole number of at least 2, or one per --frv parameter " \
        "(E,rho)" in result.stderr, result.output
    assert not (tmp_path / "new.zarr").exists()


def test_the_summary_names_an_alpha_one_lattice_finer_than_the_grid() -> None:
    """frv-sim's summary line says along which parameters α = 1 was interpolated on a
    lattice finer than the grouping grid (the study's ``counts["peak_refine"]``), and
    nothing where it is the grid's."""
    from fuzzygait.cli.simulate import _frv_summary

    counts = {"samples": 100, "occurring_intervals": 7, "possible_intervals": 100, "forward_simulations": 40,
              "possible_intervals_per_parameter": [10, 10], "interval_optimisations": 12, "wall_time": 1.0}  # fmt: skip
    finer = _frv_summary("stance", {**counts, "peak_refine": {"E": 2, "rho": 1}})
    assert "forward simulations 40; α = 1 on E bins / 2; interval optimisations" in finer and "rho bins" not in finer
    assert "α = 1" not in _frv_summary("stance", {**counts, "peak_refine": {"E": 1, "rho": 1}})
    assert "α = 1" not in _frv_summary("stance", counts)
