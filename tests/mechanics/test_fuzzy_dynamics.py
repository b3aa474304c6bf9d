"""Fuzzy forward dynamics of the leg (Graph Follower on the simulator, thesis §5.2).

Truths: a dense sampling of the fuzzy parameter's α = 0 interval, the deterministic run
(α = 1, bit for bit) and the nesting of the α-levels.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.fuzzy_dynamics import (
    DEFAULT_STRATEGY,
    LegStudyModel,
    LegTarget,
    dense_reference,
    fuzzy_forward_dynamics,
    parse_fuzzy,
)
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.targets import LegTargetModel
from support import assert_one_line_error, run

DURATION = 0.15


@pytest.fixture(scope="module")
def swing() -> LegSimulator:
    return LegSimulator("swing", nodes=8)


@pytest.fixture(scope="module")
def result(swing):
    base = swing.parameters(eta=1e5)  # the soft Table 4.3 blade needs damping (README)
    target = LegTarget(base=base, settings=SolverSettings(duration=DURATION))
    return fuzzy_forward_dynamics(swing, {"E": 0.1}, target=target, strategy=replace(DEFAULT_STRATEGY, stride=25)), base


@pytest.mark.slow
def test_hulls_match_dense_sampling(swing, result):
    fuzzy, base = result
    settings = SolverSettings(duration=DURATION)
    model = LegTargetModel(swing, "total_deformation_energy", ("E",), base=base, settings=settings)
    e = base[0]
    dense = dense_reference(model, 0.9 * e, 1.1 * e, 21)
    upper = fuzzy["hull"].sel(alpha=0.0, bound="upper").values
    lower = fuzzy["hull"].sel(alpha=0.0, bound="lower").values
    scale = np.max(np.abs(dense))
    # hulls come from library trajectories, so they never leave the dense envelope by more
    # than round-off, and they reach it within a small fraction of the output range
    assert np.all(upper <= dense.max(0) + 1e-12 * scale)
    assert np.all(lower >= dense.min(0) - 1e-12 * scale)
    assert np.max(dense.max(0) - upper) <= 1e-3 * scale
    assert np.max(lower - dense.min(0)) <= 1e-3 * scale
    assert fuzzy.attrs["forward_simulations"] < 21  # fewer simulations than the reference


@pytest.mark.slow
def test_alpha_one_is_the_deterministic_run_bit_for_bit(swing, result):
    fuzzy, base = result
    deterministic = LegTargetModel(swing, "total_deformation_energy", ("E",), base=base,
                                   settings=SolverSettings(duration=DURATION))
    values = deterministic.evaluate(np.array([base[0]])).values
    for bound in ("lower", "upper"):
        assert np.array_equal(fuzzy["hull"].sel(alpha=1.0, bound=bound).values, values)


@pytest.mark.slow
def test_alpha_levels_nest(result):
    fuzzy, _ = result
    hull = fuzzy["hull"]
    assert np.all(hull.sel(alpha=0.0, bound="upper") >= hull.sel(alpha=0.5, bound="upper"))
    assert np.all(hull.sel(alpha=0.0, bound="lower") <= hull.sel(alpha=0.5, bound="lower"))


@pytest.mark.parametrize(
    ("specs", "needle"),
    [(["E"], "NAME=SPREAD"), (["foo=10%"], "foo"), (["E=abc"], "abc"), (["E=150%"], "between 0 and 100"),
     (["E=10%", "E=5%"], "twice"), ([], "at least one")],
)
def test_parse_fuzzy_errors(specs, needle):
    with pytest.raises(ParameterError, match=needle):
        parse_fuzzy(specs)


def test_parse_fuzzy_values():
    assert parse_fuzzy(["E=10%,rho=0.05", "thigh_mass=2.5%"]) == pytest.approx(
        {"E": 0.10, "rho": 0.05, "thigh_mass": 0.025}
    )


@pytest.mark.slow
def test_fuzzy_sim_command(tmp_path):
    out = tmp_path / "swing.zarr"
    result = run("fuzzy-sim", "swing", "--fuzzy", "E=10%", "--set", "eta=1e5", "--nodes", "6",
                 "--duration", "0.05", "--stride", "25", "--out", out, "--plot", tmp_path / "hulls.png")  # fmt: skip
    assert result.returncode == 0, result.stderr
    import xarray as xr

    ds = xr.open_zarr(out).load()
    assert ds["hull"].dims == ("alpha", "bound", "time") and ds.sizes["time"] == 51
    assert ds["hull"].attrs["units"] == "J" and list(ds["parameter_unit"].values) == ["Pa"]
    assert (tmp_path / "hulls.png").stat().st_size > 0
    bad = run("fuzzy-sim", "swing", "--fuzzy", "nu=abc", "--out", tmp_path / "bad.zarr")
    assert_one_line_error(bad, "nu=abc")
    assert not (tmp_path / "bad.zarr").exists()


@pytest.mark.parametrize("fields, said", [
    ({"name": "energy"}, "unknown target 'energy'; choose one of"),
    ({"base": np.ones(3)}, "base: give the 12 finite leg parameters"),
    ({"base": np.full(12, np.nan)}, "base: give the 12 finite leg parameters"),
    ({"settings": {"dt": 1e-3}}, "settings: give a SolverSettings; got dict"),
])  # fmt: skip
def test_a_bad_leg_target_field_is_refused_in_one_line(fields, said) -> None:
    with pytest.raises(ParameterError, match=f"^{said}") as caught:
        LegTarget(**fields)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize("fields, said", [
    ({"target": "energy"}, "unknown target 'energy'; choose one of"),
    ({"base_overrides": [("E", 1.0)]}, "base_overrides: give a mapping NAME -> value"),
    ({"base_overrides": {"Young": 1.0}}, "base_overrides: 'Young' is not a leg parameter"),
    ({"nodes": 1}, "nodes must be a whole number >= 2"),
    ({"nodes": 6.0}, "nodes must be a whole number >= 2"),
    ({"settings": "fast"}, "settings: give a SolverSettings; got str"),
    ({"sensitivities": "yes"}, "sensitivities must be True or False"),
])  # fmt: skip
def test_a_bad_leg_study_model_field_is_refused_in_one_line(fields, said) -> None:
    with pytest.raises(ParameterError, match=f"^{said}") as caught:
        LegStudyModel(**fields)
    assert "\n" not in str(caught.value)


def test_leg_model_defaults_are_the_scenarios() -> None:
    assert LegTarget().name is None and LegTarget().base is None and LegTarget().settings is None
    model = LegStudyModel()
    assert (model.target, dict(model.base_overrides), model.nodes, model.settings, model.sensitivities) == (
        None, {}, 20, None, True)  # fmt: skip
