"""The engine's one Evaluator (fuzzygait.uncertainty.execution): serial, a local Dask
process pool, or a scheduler address.

Results of N worker processes must be bit-identical to the serial path and to direct
evaluation — for parameter rows, for the Graph Follower (linearised and batched direct),
the FRV-GFA and the marker-error analysis; workers build the leg simulator from the
on-disk compiled library (no recompilation); failures come back as one FuzzyGaitError
naming the row."""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from fuzzygait.core.errors import FuzzyGaitError, ParameterError  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402
from fuzzygait.mechanics.targets import LegModelRecipe  # noqa: E402
from fuzzygait.testing import AnalyticRecipe  # noqa: E402
from fuzzygait.uncertainty import (  # noqa: E402
    BatchedDirect,
    FuzzyVector,
    Linearised,
    graph_follower,
    triangular,
)
from fuzzygait.uncertainty.execution import Evaluator, ParallelEvaluationError, SharedArray  # noqa: E402
from fuzzygait.uncertainty.execution.workers import Slot, evaluate_rows  # noqa: E402
from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy, StudyOptions  # noqa: E402

pytestmark = pytest.mark.slow  # starts Dask clusters

RNG_SEED = 7


@pytest.fixture(scope="module")
def evaluators(cluster):
    """The three kinds of evaluator: serial, a local pool of 2 (started by the Evaluator)
    and the address of an existing LocalCluster."""
    pool, remote = Evaluator(workers=2), Evaluator(scheduler=cluster.scheduler_address)
    yield {"serial": Evaluator(), "pool": pool, "cluster": remote}
    pool.close()
    remote.close()


def parameters(k: int = 20, n_p: int = 3) -> np.ndarray:
    return np.random.default_rng(RNG_SEED).uniform(0.2, 3.0, size=(k, n_p))


def test_rows_bit_identical_to_serial_and_direct(evaluators) -> None:
    recipe = AnalyticRecipe("sin", n_time=101)
    P = parameters()
    model = recipe.build()
    direct = np.array([model.evaluate(p).values for p in P])
    direct_sens = np.array([model.evaluate(p, sensitivities=True).jacobian for p in P])
    for name, evaluator in evaluators.items():
        batch = evaluator.batch(recipe)
        rows = batch(P)
        reversed_rows = batch(P[::-1])  # order follows the input rows
        values, sens = evaluator.batch(recipe, sensitivities=True, chunk=3)(P)
        assert rows.shape == (20, 101), name
        assert np.array_equal(rows, direct) and np.array_equal(reversed_rows, direct[::-1]), name
        assert np.array_equal(values, direct) and np.array_equal(sens, direct_sens), name
        if name != "serial":
            assert len({s["pid"] for s in batch.last_statistics}) == 2, name  # both workers took part


def test_map_keeps_order_and_names_the_failing_item(evaluators) -> None:
    items = list(range(-5, 6))
    for name, evaluator in evaluators.items():
        assert evaluator.map(abs, items) == [abs(i) for i in items], name
        with pytest.raises(ParallelEvaluationError, match=r"item 2 failed: ValueError") as info:
            evaluator.map(_reject_zero, [3, 1, 0, 2, 0])
        assert info.value.row == 2 and "\n" not in str(info.value)


def test_map_reports_progress_as_items_finish(evaluators) -> None:
    """Every evaluator calls ``progress(done, total)`` once per finished item, counting up
    to the total (a pool as the futures complete, not once at the end)."""
    items = list(range(12))
    for name, evaluator in evaluators.items():
        calls: list[tuple[int, int]] = []
        assert evaluator.map(abs, items, progress=lambda d, t: calls.append((d, t))) == items, name
        assert calls == [(i, len(items)) for i in range(1, len(items) + 1)], name


def _reject_zero(x: int) -> int:
    if x == 0:
        raise ValueError("zero is not allowed here")
    return x


def test_local_pool_is_started_once_reused_and_closed(tmp_path) -> None:
    recipe = AnalyticRecipe("poly", n_time=31)
    P = parameters(12, 2)
    direct = np.array([recipe.build().evaluate(p).values for p in P])
    evaluator = Evaluator(workers=2)
    assert evaluator._resources.client is None  # lazy: nothing started yet
    batch = evaluator.batch(recipe, store=tmp_path / "store", chunk=None)
    try:
        first = batch(P)
        client = evaluator.client
        assert len(client.scheduler_info()["workers"]) == 2
        second = batch(P[:5])
        assert evaluator.client is client  # the same cluster serves every call
    finally:
        evaluator.close()
    assert evaluator._resources.client is None and evaluator._resources.cluster is None
    assert np.array_equal(first, direct) and np.array_equal(second, direct[:5])
    # with `store`, the results stay on disk and come back memory-mapped
    assert isinstance(first, np.memmap)
    assert sorted(p.name for p in (tmp_path / "store").iterdir()) == [
        "batch-00001-values.npy", "batch-00002-values.npy"]  # fmt: skip
    assert np.array_equal(np.load(tmp_path / "store" / "batch-00001-values.npy"), direct)


def _profile_state(dask_worker=None) -> tuple[bool, int]:  # run on each worker by Client.run
    import dask

    return bool(dask.config.get("distributed.worker.profile.enabled")), len(dask_worker.profile_history)


def test_pool_workers_keep_no_profile_between_tasks(evaluators) -> None:
    """Dask's statistical profiler is off in the local pool's workers: it kept the last
    1,000 one-second stack profiles and grew each worker by about 2 MB per report trial."""
    pool = evaluators["pool"]
    pool.map(_slow_square, list(range(6)))
    states = pool.client.run(_profile_state)
    assert len(states) == 2
    assert all(state == (False, 0) for state in states.values()), states


def _worker_facts(_: int) -> tuple[str, int, bool]:
    """A worker's program (``/proc/self/exe`` and arguments), the most BLAS/OpenMP threads
    of its loaded libraries, and whether it can take the model cache's build lock."""
    import threadpoolctl

    from fuzzygait.uncertainty.execution import workers

    with open("/proc/self/cmdline", "rb") as handle:
        cmdline = handle.read().decode()
    threads = max(info["num_threads"] for info in threadpoolctl.threadpool_info())
    free = workers._BUILD_LOCK.acquire(timeout=5)
    if free:
        workers._BUILD_LOCK.release()
    return cmdline, threads, free


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked on Linux only")
def test_pool_workers_are_forked_with_one_blas_thread_and_free_locks(tmp_path, monkeypatch) -> None:
    """On Linux the local pool's workers are copies of this process (no new interpreter
    importing everything again: issue 40's start-up cost): their command line is this
    process's.  They compute with one BLAS thread even when this process uses more (a
    copy inherits the libraries' thread counts, which WORKER_ENV cannot change once they
    are loaded), and the model cache's lock, held here by another thread at the moment
    of the copy, is free in them."""
    import tempfile

    import threadpoolctl

    from fuzzygait.uncertainty.execution import workers

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    with open("/proc/self/cmdline", "rb") as handle:
        own = handle.read().decode()
    with threadpoolctl.threadpool_limits(limits=2), Evaluator(workers=2) as evaluator:
        assert max(info["num_threads"] for info in threadpoolctl.threadpool_info()) == 2
        with workers._BUILD_LOCK:  # held by this (another) thread while the workers are made
            evaluator.n_workers()
        facts = evaluator.map(_worker_facts, [0, 1, 2, 3])
    assert {cmdline for cmdline, _, _ in facts} == {own}
    assert [threads for _, threads, _ in facts] == [1, 1, 1, 1]
    assert all(free for _, _, free in facts)


def _flushes_in_time(logger_name: str) -> bool:
    """Whether a worker's copy of ``logger_name``'s handler can flush within 10 s."""
    import logging
    import threading

    handler = logging.getLogger(logger_name).handlers[0]
    done = threading.Event()
    threading.Thread(target=lambda: (handler.flush(), done.set()), daemon=True).start()
    return done.wait(10)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked on Linux only")
def test_a_stream_locked_by_a_driver_thread_at_the_copy_is_free_in_the_workers(tmp_path, monkeypatch) -> None:
    """A driver thread blocked inside a write (its pipe full) holds the stream's lock while
    the workers are made, as Dask's event loop logging or a progress bar can at that moment:
    a worker's copy of that logging handler must not wait for that lock for ever (the suite
    once hung so, in a Dask preload's log line through pytest's log file)."""
    import array
    import fcntl
    import logging
    import tempfile
    import termios
    import threading

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    read_end, write_end = os.pipe()
    stream = os.fdopen(write_end, "w")
    logger = logging.getLogger("fuzzygait.test-fork-streams")
    handler = logging.StreamHandler(stream)
    logger.addHandler(handler)
    writer = threading.Thread(target=lambda: (stream.write("x" * (1 << 20)), stream.flush()), daemon=True)
    writer.start()
    try:
        capacity = fcntl.fcntl(read_end, 1032)  # F_GETPIPE_SZ
        held = array.array("i", [0])
        while held[0] < capacity:  # until the pipe is full: the writer is blocked inside its write
            fcntl.ioctl(read_end, termios.FIONREAD, held)
        with Evaluator(workers=2) as evaluator:
            answers = evaluator.map(_flushes_in_time, ["fuzzygait.test-fork-streams"] * 2)
    finally:
        logger.removeHandler(handler)
        os.set_blocking(read_end, False)
        while writer.is_alive():  # let the writer finish
            try:
                os.read(read_end, 1 << 16)
            except BlockingIOError:
                writer.join(0.01)
        stream.close()
        os.close(read_end)
    assert answers == [True, True]


def _slow_square(x: int) -> int:
    import time

    time.sleep(0.05)  # several of the profiler's 10 ms samples, had it been on
    return x * x


def test_shared_array_inputs_are_memory_mapped_by_the_workers(evaluators, tmp_path) -> None:
    offset = np.linspace(-1.0, 1.0, 41) ** 3
    shared = SharedArray.create(offset, tmp_path / "offset.npy")
    recipe = AnalyticRecipe("sin", n_time=41, offset=shared)
    P = parameters(6, 2)
    par = evaluators["cluster"].batch(recipe)(P)
    plain = AnalyticRecipe("sin", n_time=41).build()
    assert np.array_equal(par, np.array([plain.evaluate(p).values + offset for p in P]))
    assert isinstance(shared.load(), np.memmap)


def test_leg_model_in_parallel_is_bit_identical_and_not_recompiled(evaluators) -> None:
    from fuzzygait.core.codegen import cache_dir
    from fuzzygait.markererror.row_kernel import ROW_LIBRARY_PREFIX
    from fuzzygait.mechanics.scenarios import LegSimulator

    # the driver builds the simulator once: this populates the on-disk cache if needed
    base = tuple(LegSimulator("swing", nodes=6).parameters(eta=1e5))
    libraries = {p: p.stat().st_mtime_ns for p in cache_dir().glob("fg_*.so")}
    recipe = LegModelRecipe("swing", "total_deformation_energy", ("E",), base=base, nodes=6,
                            settings=SolverSettings(duration=0.05))
    P = np.array([[4.0e5], [5.0e5], [6.0e5], [7.0e5]])

    batch = evaluators["cluster"].batch(recipe, sensitivities=True)
    values, sens = batch(P)
    serial_values, serial_sens = evaluators["serial"].batch(recipe, sensitivities=True)(P)
    direct = recipe.build().evaluate(P[2]).values

    assert values.shape == (4, 51) and sens.shape == (4, 51, 1)
    assert np.array_equal(values, serial_values) and np.array_equal(sens, serial_sens)
    assert np.array_equal(values[2], direct)
    assert not np.array_equal(values[0], values[3])
    # no worker recompiled: the libraries untouched and no simulator library added (the other
    # test process may compile marker-error row kernels into the same cache meanwhile)
    after = {p: p.stat().st_mtime_ns for p in cache_dir().glob("fg_*.so")}
    assert {p: after.get(p) for p in libraries} == libraries
    assert not [p for p in set(after) - set(libraries) if not p.name.startswith(ROW_LIBRARY_PREFIX)]
    assert 1 <= len(batch.builds) <= 2 and len({b["pid"] for b in batch.builds}) == len(batch.builds), batch.builds


def test_failing_row_is_one_error_naming_the_row(evaluators, capfd) -> None:
    recipe = AnalyticRecipe("sin", n_time=11, fail_above=2.0)
    P = np.full((10, 2), 1.0)
    P[7, 0] = 2.5
    P[9, 0] = 3.0  # a later failure: the first failing row is the one reported
    for evaluator in (evaluators["serial"], evaluators["cluster"]):
        with pytest.raises(FuzzyGaitError) as info:
            evaluator.batch(recipe)(P)
        err = info.value
        assert isinstance(err, ParallelEvaluationError)
        assert err.row == 7 and err.parameters == [2.5, 1.0] and err.error_type == "ParameterError"
        message = str(err)
        assert "row 7" in message and "ParameterError" in message and "exceeds fail_above" in message
        assert "\n" not in message and err.__cause__ is None and err.__context__ is None
    assert "Traceback" not in capfd.readouterr().err


def test_unreachable_scheduler_is_one_clear_error() -> None:
    evaluator = Evaluator(scheduler="tcp://127.0.0.1:9", connect_timeout=1.0)
    with pytest.raises(FuzzyGaitError, match=r"cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'") as info:
        evaluator.batch(AnalyticRecipe())(parameters(2, 1))
    assert "\n" not in str(info.value)
    evaluator.close()


# ------------------------------------------------------------------ engines on the evaluators
PARAMS = FuzzyVector([triangular(0.8, 1.0, 1.3, "a"), triangular(1.5, 2.0, 2.2, "b")])


@pytest.mark.parametrize(
    "strategy",
    [BatchedDirect(stride=5, starts=3, screen=16, iterations=8), Linearised(stride=4),
     Linearised(stride=4, tracks="side-by-side")],
    ids=["batched-direct", "linearised", "linearised-side-by-side"],
)
def test_graph_follower_bit_identical_on_every_evaluator(evaluators, strategy) -> None:
    recipe = AnalyticRecipe("sin", n_time=21, t_end=2.0)
    if isinstance(strategy, Linearised):  # the model itself, in this process (one row after another)
        direct = graph_follower(recipe.build(), PARAMS, (0.0, 0.5), strategy=strategy)
    else:  # node evaluations need the evaluated model's "nodes"
        direct = graph_follower(evaluators["serial"].model(recipe), PARAMS, (0.0, 0.5), strategy=strategy)
    for name, evaluator in evaluators.items():
        result = graph_follower(evaluator.model(recipe, sensitivities=True), PARAMS, (0.0, 0.5), strategy=strategy)
        assert np.array_equal(result.hull.values, direct.hull.values), name
        assert np.array_equal(result.extremiser.values, direct.extremiser.values), name
        for key in ("forward_simulations", "node_evaluations"):
            assert result.attrs[key] == direct.attrs[key], (name, key)


def test_frv_study_bit_identical_on_every_evaluator(evaluators, tmp_path) -> None:
    recipe = AnalyticRecipe("sin", n_time=41, t_end=4.0)
    spec = FRVSpec("p", 1.0, alphas=(0.0, 0.5, 1.0))
    model = recipe.build()
    reference = FRVStudy.create(model, spec, 300, StudyOptions(n_disc=12, seed=2, chunk=64),
                                store=tmp_path / "ref.zarr")
    expected = reference.hulls()["hull"].to_numpy()
    for name, evaluator in evaluators.items():
        batch = evaluator.batch(recipe, sensitivities=True)
        study = FRVStudy.create(model, spec, 300, StudyOptions(n_disc=12, seed=2, chunk=64),
                                store=tmp_path / f"{name}.zarr", evaluator=batch)  # fmt: skip
        assert np.array_equal(study.hulls()["hull"].to_numpy(), expected), name


def test_marker_error_analysis_bit_identical_on_every_evaluator(evaluators, angles_run) -> None:
    from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles

    trial = angles_run.trial
    frames = np.linspace(0, trial.n_frames - 1, 4).round().astype(int)
    markers = np.full_like(trial.markers, np.nan)
    markers[frames] = trial.markers[frames]
    sparse = trial.with_markers(markers)
    options = FuzzyAngleOptions(alphas=(0.0, 0.5), starts=2, iterations=6)
    results = {
        name: fuzzy_joint_angles(sparse, angles_run.subject, angles_run.result, options, angles=["LKneeAngles"],
                                 evaluator=evaluator)  # fmt: skip
        for name, evaluator in evaluators.items()
    }
    serial = results.pop("serial")
    assert np.isfinite(serial["hull"].sel(alpha=0.0).isel(frame=frames).values).all()
    for name, result in results.items():
        assert np.array_equal(result["hull"].values, serial["hull"].values, equal_nan=True), name
        assert np.array_equal(result["deviation"].values, serial["deviation"].values, equal_nan=True), name


# ------------------------------------------------------------------ details
def test_rows_come_back_with_the_status_when_the_store_is_not_visible(tmp_path) -> None:
    recipe = AnalyticRecipe("sin", n_time=5)
    P = parameters(3, 1)
    missing = Slot(str(tmp_path / "elsewhere.npy"), 128, (5,))
    status = evaluate_rows(recipe, 4, P, missing, None)
    assert status["start"] == 4 and status["stop"] == 7
    assert np.array_equal(status["values"], np.array([recipe.build().evaluate(p).values for p in P]))


def test_bad_arguments() -> None:
    batch = Evaluator().batch(AnalyticRecipe())
    with pytest.raises(ParameterError, match="2-D"):
        batch(np.ones(3))
    with pytest.raises(ParameterError, match="row 1 is not finite"):
        batch(np.array([[1.0], [np.nan]]))
    with pytest.raises(ParameterError, match="workers"):
        Evaluator(workers=0)
    with pytest.raises(ParameterError, match="recipe"):
        Evaluator().batch(object())  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="unknown analytic model"):
        AnalyticRecipe("cos")
    assert Evaluator().batch(AnalyticRecipe(n_time=4))(np.empty((0, 2))).shape == (0, 4)
