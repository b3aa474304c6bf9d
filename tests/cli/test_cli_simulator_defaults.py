"""The simulator commands' defaults: where the thesis' Table 4.3/4.4 values do not run on
the shipped blade, the command takes the nearest that do, says so in a note, and a run
that stops names the options that fix it; the variational stance runs on sub-steps."""

from __future__ import annotations

from pathlib import Path

import pytest
from support import assert_one_line_error, run, run_here

from fuzzygait.mechanics.presets import COMMAND_DEFAULTS, STANCE, SWING
from fuzzygait.workflows.fuzzy_dynamics import command_setup


def test_command_defaults_leave_the_library_presets_and_the_users_values_alone() -> None:
    assert SWING.material.damping == 1.0 and STANCE.material.damping == 1.0  # the tables' values
    setup, note = command_setup("swing", 20, None, None, {}, None)
    assert setup.values == {"eta": 1e5} and setup.scheme == "variational"
    assert note is not None and note.startswith("swing runs with values= eta=100000 by default (Table 4.3's eta = 1 folds")
    setup, note = command_setup("swing", 20, None, None, {"eta": 2.0, "E": 7e5}, None)
    assert setup.values == {"eta": 2.0, "E": 7e5} and note is None
    setup, note = command_setup("stance", 20, None, None, {}, None)
    assert setup.values == {} and setup.scheme == "energy-momentum" and "scheme= energy-momentum" in (note or "")
    assert command_setup("stance", 20, None, None, {}, "variational") == (
        command_setup("stance", 20, None, None, {}, "variational")[0], None)
    assert set(COMMAND_DEFAULTS) == {"swing", "stance"}


def test_simulate_prints_the_default_it_takes(tmp_path: Path) -> None:
    result = run("simulate", "swing", "--duration", "0.01", "--nodes", "6", "--out", tmp_path / "s.nc")
    assert result.returncode == 0, result.stderr
    assert "note: swing runs with --set eta=100000 by default" in result.stdout
    assert "variational scheme" in result.stdout


@pytest.mark.slow
def test_the_thesis_swing_folds_and_the_error_names_the_fixes(tmp_path: Path) -> None:
    result = run_here("simulate", "swing", "--set", "eta=1", "--duration", "0.3", "--out", tmp_path / "s.nc")
    assert_one_line_error(result, "folded at t = 0.27", "on the command line: --set eta=100000 or --nodes 40")
    assert not list(tmp_path.iterdir())


@pytest.mark.slow
def test_the_thesis_stance_with_the_variational_scheme_runs_on_sub_steps(tmp_path: Path) -> None:
    """At dt = 1 ms the variational scheme is unstable on the stance blade (its energy grows
    before Newton fails at t = 0.719 s); the integrator repeats the run on sub-steps of dt
    and says so (``benchmarks/simulator_thesis_settings.py``)."""
    result = run_here("simulate", "stance", "--scheme", "variational", "--duration", "0.75", "--out", tmp_path / "s.nc")
    assert result.returncode == 0, result.stderr
    assert "variational scheme (4 sub-steps each: a step at dt did not converge" in result.stdout
    drift = float(result.stdout.split("energy drift max |total + dissipated − initial| / |initial|: ")[1].split()[0])
    assert drift < 1e-4
    assert (tmp_path / "s.nc").is_file()
