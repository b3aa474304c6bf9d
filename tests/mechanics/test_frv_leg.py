"""FRV-GFA on the leg model: 1 worker and 2 workers give bit-identical hulls; the
``frv-sim`` command writes and extends a study."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fuzzygait.mechanics.fuzzy_dynamics import LegStudyModel, leg_frv_study
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.uncertainty.frv import FRVSpec, StudyOptions
from support import assert_one_line_error, run

distributed = pytest.importorskip("distributed")

pytestmark = pytest.mark.slow  # leg simulations on a Dask cluster and through the CLI

MODULUS = 59.958e9  # Pa, Table 5.3
SETTINGS = SolverSettings(duration=0.03, scheme="energy-momentum")  # the study's default scheme
SMALL = dict(leg=LegStudyModel(base_overrides={"E": MODULUS}, nodes=6, settings=SETTINGS), study=StudyOptions(n_disc=8))


def test_one_and_two_workers_give_bit_identical_hulls(tmp_path, cluster):
    spec = FRVSpec("E", MODULUS, alphas=(0.0, 0.5, 1.0))
    serial = leg_frv_study("stance", spec, 150, tmp_path / "one.zarr", workers=1, **SMALL)
    parallel = leg_frv_study("stance", spec, 150, tmp_path / "two.zarr", scheduler=cluster.scheduler_address,
                             **SMALL)  # fmt: skip
    a = serial.hulls()["hull"].values
    b = parallel.hulls()["hull"].values
    assert a.shape == b.shape and np.isfinite(a).all()
    assert np.array_equal(a, b)
    assert serial.counts["forward_simulations"] == parallel.counts["forward_simulations"]


def test_frv_sim_command_creates_and_extends(tmp_path):
    store = tmp_path / "study.zarr"
    args = ("frv-sim", "stance", "--samples", "100", "--disc", "6", "--duration", "0.02", "--nodes", "6",
            "--set", f"E={MODULUS}", "--workers", "1", "--out", store)  # fmt: skip
    first = run(*args)
    assert first.returncode == 0, first.stderr
    assert "100 samples" in first.stdout and "occurring intervals" in first.stdout
    second = run(*args)
    assert second.returncode == 0, second.stderr
    assert "200 samples" in second.stdout
    bad = run("frv-sim", "stance", "--frv", "foo", "--out", tmp_path / "bad.zarr")
    assert_one_line_error(bad, "foo")
    assert not (tmp_path / "bad.zarr").exists()


def test_two_frvs_one_and_two_workers_bit_identical_and_the_command(tmp_path, cluster):
    """``E`` and ``rho`` as independent FRVs: the box study on 1 worker and on 2 workers
    is bit-identical; ``frv-sim --frv E,rho`` writes and extends such a study."""
    alphas = (0.0, 0.5, 1.0)
    specs = [FRVSpec("E", MODULUS, alphas=alphas), FRVSpec("rho", 8550.0, alphas=alphas)]
    small = dict(leg=replace(SMALL["leg"], settings=SETTINGS.derive(duration=0.02)), study=StudyOptions(n_disc=4))
    serial = leg_frv_study("stance", specs, 40, tmp_path / "one.zarr", workers=1, **small)
    parallel = leg_frv_study("stance", specs, 40, tmp_path / "two.zarr", scheduler=cluster.scheduler_address, **small)
    assert serial.several and serial.counts["possible_intervals"] == 6 * 6
    a, b = serial.hulls()["hull"].values, parallel.hulls()["hull"].values
    assert a.shape == (40, 3, 2, a.shape[-1]) and np.isfinite(a).all() and np.array_equal(a, b)
    assert 0 < serial.counts["forward_simulations"] == parallel.counts["forward_simulations"]
    assert serial.peak_refine == parallel.peak_refine and serial.counts["peak_checks"] == parallel.counts["peak_checks"]
    on_grid = (serial.library()["offset"].values == 0).all(axis=1)  # the rest: the α = 1 lattice between them
    assert 0 < int(on_grid.sum()) <= 9  # at most the 3 × 3 grid points
    store = tmp_path / "study.zarr"
    args = ("frv-sim", "stance", "--frv", "E,rho", "--samples", "30", "--disc", "4", "--duration", "0.02",
            "--nodes", "6", "--set", f"E={MODULUS}", "--workers", "1", "--out", store)  # fmt: skip
    first = run(*args)
    assert first.returncode == 0, first.stderr
    assert "30 samples" in first.stdout and "occurring boxes" in first.stdout and "(6 × 6) possible" in first.stdout
    second = run(*args)
    assert second.returncode == 0, second.stderr
    assert "60 samples" in second.stdout
