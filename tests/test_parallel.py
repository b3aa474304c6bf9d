"""Parallel and distributed evaluation through Dask (fuzzygait.uncertainty.parallel).

Results of N worker processes must be bit-identical to the serial path and to direct
evaluation; workers build the leg simulator from the on-disk compiled library (no
recompilation); failures come back as one FuzzyGaitError naming the row."""

from __future__ import annotations

import logging
import time

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from fuzzygait.core.errors import FuzzyGaitError, ParameterError  # noqa: E402
from fuzzygait.uncertainty import FuzzyVector, graph_follower, triangular  # noqa: E402
from fuzzygait.uncertainty.parallel import (  # noqa: E402
    AnalyticRecipe,
    BatchEvaluator,
    LegModelRecipe,
    ParallelEvaluationError,
    ParallelModel,
    SharedArray,
    _evaluate_rows,
    _Slot,
    parallel_map,
)

RNG_SEED = 7


@pytest.fixture(scope="module")
def cluster():
    """A 2-process Dask cluster shared by the tests of this module (≈1.5 s to start)."""
    with distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, silence_logs=logging.ERROR,
        dashboard_address=None, scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
    ) as c:
        yield c


def parameters(k: int = 20, n_p: int = 3) -> np.ndarray:
    return np.random.default_rng(RNG_SEED).uniform(0.2, 3.0, size=(k, n_p))


def test_two_workers_bit_identical_to_serial_and_direct(cluster) -> None:
    recipe = AnalyticRecipe("sin", n_time=101)
    P = parameters()
    model = recipe.build()
    direct = np.array([model.evaluate(p) for p in P])
    direct_sens = np.array([model.evaluate_with_sensitivities(p)[1] for p in P])

    serial = parallel_map(recipe, P, workers=1)
    with BatchEvaluator(recipe, scheduler=cluster.scheduler_address) as evaluate:
        par = evaluate(P)
        pids = {s["pid"] for s in evaluate.last_statistics}
        reversed_rows = evaluate(P[::-1])  # order follows the input rows
    with BatchEvaluator(recipe, scheduler=cluster.scheduler_address, sensitivities=True, chunk=3) as evaluate:
        values, sens = evaluate(P)

    assert par.shape == (20, 101)
    assert np.array_equal(par, serial) and np.array_equal(par, direct)
    assert np.array_equal(reversed_rows, direct[::-1])
    assert np.array_equal(values, direct) and np.array_equal(sens, direct_sens)
    assert sens.shape == (20, 101, 3)
    assert len(pids) == 2  # both workers took part


def test_default_local_cluster_is_started_once_reused_and_closed(tmp_path) -> None:
    recipe = AnalyticRecipe("poly", n_time=31)
    P = parameters(12, 2)
    direct = np.array([recipe.build().evaluate(p) for p in P])
    evaluate = BatchEvaluator(recipe, workers=2, store=tmp_path / "store", chunk=None)
    assert evaluate._resources.client is None  # lazy: nothing started yet
    try:
        first = evaluate(P)
        client = evaluate.client
        assert len(client.scheduler_info()["workers"]) == 2
        second = evaluate(P[:5])
        assert evaluate.client is client  # the same cluster serves every call
    finally:
        evaluate.close()
    assert evaluate._resources.client is None and evaluate._resources.cluster is None
    assert np.array_equal(first, direct) and np.array_equal(second, direct[:5])
    # with `store`, the results stay on disk and come back memory-mapped
    assert isinstance(first, np.memmap)
    assert sorted(p.name for p in (tmp_path / "store").iterdir()) == [
        "batch-00001-values.npy", "batch-00002-values.npy"]  # fmt: skip
    assert np.array_equal(np.load(tmp_path / "store" / "batch-00001-values.npy"), direct)


def test_shared_array_inputs_are_memory_mapped_by_the_workers(cluster, tmp_path) -> None:
    offset = np.linspace(-1.0, 1.0, 41) ** 3
    shared = SharedArray.create(offset, tmp_path / "offset.npy")
    recipe = AnalyticRecipe("sin", n_time=41, offset=shared)
    P = parameters(6, 2)
    par = parallel_map(recipe, P, scheduler=cluster.scheduler_address)
    plain = AnalyticRecipe("sin", n_time=41).build()
    assert np.array_equal(par, np.array([plain.evaluate(p) + offset for p in P]))
    assert isinstance(shared.load(), np.memmap)


def test_leg_model_in_parallel_is_bit_identical_and_not_recompiled(cluster) -> None:
    from fuzzygait.mechanics.codegen import cache_dir
    from fuzzygait.mechanics.scenarios import LegSimulator

    # the driver builds the simulator once: this populates the on-disk cache if needed
    base = tuple(LegSimulator("swing", nodes=6).parameters(eta=1e5))
    libraries = {p: p.stat().st_mtime_ns for p in cache_dir().glob("fg_*.so")}
    recipe = LegModelRecipe("swing", "total_deformation_energy", ("E",), base=base, nodes=6, duration=0.05)
    P = np.array([[4.0e5], [5.0e5], [6.0e5], [7.0e5]])

    tic = time.perf_counter()
    with BatchEvaluator(recipe, scheduler=cluster.scheduler_address, sensitivities=True) as evaluate:
        values, sens = evaluate(P)
        builds = evaluate.builds
    parallel_seconds = time.perf_counter() - tic
    serial_values, serial_sens = parallel_map(recipe, P, workers=1, sensitivities=True)
    direct = recipe.build().evaluate(P[2])

    assert values.shape == (4, 51) and sens.shape == (4, 51, 1)
    assert np.array_equal(values, serial_values) and np.array_equal(sens, serial_sens)
    assert np.array_equal(values[2], direct)
    assert not np.array_equal(values[0], values[3])
    # no worker recompiled: same libraries, untouched, and each worker's build was a load
    assert {p: p.stat().st_mtime_ns for p in cache_dir().glob("fg_*.so")} == libraries
    assert 1 <= len(builds) <= 2 and len({b["pid"] for b in builds}) == len(builds), builds  # once per worker
    assert max(b["build_seconds"] for b in builds) < 2.0, builds
    print(f"\nleg, 4 runs on 2 workers: {parallel_seconds:.2f} s; worker builds "
          f"{[round(b['build_seconds'], 2) for b in builds]} s")  # fmt: skip


def test_failing_row_is_one_error_naming_the_row(cluster, capfd) -> None:
    recipe = AnalyticRecipe("sin", n_time=11, fail_above=2.0)
    P = np.full((10, 2), 1.0)
    P[7, 0] = 2.5
    P[9, 0] = 3.0  # a later failure: the first failing row is the one reported
    for options in ({"workers": 1}, {"scheduler": cluster.scheduler_address}):
        with pytest.raises(FuzzyGaitError) as info:
            parallel_map(recipe, P, **options)
        err = info.value
        assert isinstance(err, ParallelEvaluationError)
        assert err.row == 7 and err.parameters == [2.5, 1.0] and err.error_type == "ParameterError"
        message = str(err)
        assert "row 7" in message and "ParameterError" in message and "exceeds fail_above" in message
        assert "\n" not in message and err.__cause__ is None and err.__context__ is None
    assert "Traceback" not in capfd.readouterr().err


def test_unreachable_scheduler_is_one_clear_error() -> None:
    evaluate = BatchEvaluator(AnalyticRecipe(), scheduler="tcp://127.0.0.1:9", connect_timeout=1.0)
    with pytest.raises(FuzzyGaitError, match=r"cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'") as info:
        evaluate(parameters(2, 1))
    assert "\n" not in str(info.value)
    evaluate.close()


def test_graph_follower_direct_mode_through_the_pool(cluster) -> None:
    params = FuzzyVector([triangular(0.8, 1.0, 1.3, "a"), triangular(1.5, 2.0, 2.2, "b")])
    options = {"mode": "direct", "stride": 5, "starts": 3, "screen": 16, "batch_iterations": 8}
    recipe = AnalyticRecipe("sin", n_time=21, t_end=2.0)
    serial = graph_follower(ParallelModel(BatchEvaluator(recipe, workers=1)), params, (0.0, 0.5), **options)
    with BatchEvaluator(recipe, scheduler=cluster.scheduler_address, chunk=None) as evaluate:
        par = graph_follower(ParallelModel(evaluate), params, (0.0, 0.5), **options)
    assert np.array_equal(par.hull.values, serial.hull.values)
    assert par.attrs["node_evaluations"] == serial.attrs["node_evaluations"]


def test_rows_come_back_with_the_status_when_the_store_is_not_visible(tmp_path) -> None:
    recipe = AnalyticRecipe("sin", n_time=5)
    P = parameters(3, 1)
    missing = _Slot(str(tmp_path / "elsewhere.npy"), 128, (5,))
    status = _evaluate_rows(recipe, 4, P, missing, None)
    assert status["start"] == 4 and status["stop"] == 7
    assert np.array_equal(status["values"], np.array([recipe.build().evaluate(p) for p in P]))


def test_bad_arguments() -> None:
    with pytest.raises(ParameterError, match="2-D"):
        parallel_map(AnalyticRecipe(), np.ones(3), workers=1)
    with pytest.raises(ParameterError, match="row 1 is not finite"):
        parallel_map(AnalyticRecipe(), np.array([[1.0], [np.nan]]), workers=1)
    with pytest.raises(ParameterError, match="workers"):
        BatchEvaluator(AnalyticRecipe(), workers=0)
    with pytest.raises(ParameterError, match="recipe"):
        BatchEvaluator(object())  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="unknown analytic model"):
        AnalyticRecipe("cos")
    assert parallel_map(AnalyticRecipe(n_time=4), np.empty((0, 2)), workers=1).shape == (0, 4)
