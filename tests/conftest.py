"""Fixtures shared by every test folder: the sample trials, the Vicon movement trial, the
angles run of the sample trial and a Dask cluster. Helpers are in ``support.py``."""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

# Small linear-algebra calls (scipy's optimisers, 3x3 frames) only lose time to BLAS
# threads on the 2-core CI machine; set before numpy is first imported.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pandas as pd  # noqa: E402

if TYPE_CHECKING:
    from distributed import LocalCluster

    from fuzzygait.core.trial import Trial
    from fuzzygait.workflows.angles import AnglesRun

from support import SAMPLE_DATA, shared_file  # noqa: E402


# --------------------------------------------------------------------------- fixtures
# Module scope: each test module gets its own copy (all are cheap to make), so a test
# that changed one could not reach into another module.
@pytest.fixture(scope="module")
def walking() -> Trial:
    """sample_data/walking.c3d as read (the synthetic walking trial)."""
    from fuzzygait.io import read_c3d

    return read_c3d(SAMPLE_DATA / "walking.c3d")


@pytest.fixture(scope="module")
def truth() -> pd.DataFrame:
    """The true joint angles of walking.c3d (sample_data/walking_truth_angles.csv, deg)."""
    return pd.read_csv(SAMPLE_DATA / "walking_truth_angles.csv")


@pytest.fixture(scope="module")
def movement() -> Trial:
    """The Vicon Movement_trial.c3d of the reference data (skips when absent)."""
    from fuzzygait.io import read_c3d

    return read_c3d(shared_file("vicon", "Movement_trial.c3d"))


@pytest.fixture(scope="module")
def angles_run() -> AnglesRun:
    """The angles pipeline on walking.c3d, calibrated on static.c3d with subject.toml."""
    from fuzzygait.workflows.angles import run_angles

    return run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d",
                      subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip


def _hear_sigint() -> None:
    """Let this test process (and the fresh interpreters some tests start, which load this
    file too) raise KeyboardInterrupt on SIGINT however it was started: a shell starts a
    background job (``cmd &`` without job control) with SIGINT ignored, Python keeps an
    ignored SIGINT ignored, and the interrupt tests then waited in vain for their own
    SIGINT ("DID NOT RAISE KeyboardInterrupt")."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


_hear_sigint()


@pytest.fixture(scope="module")
def cluster() -> Iterator[LocalCluster]:
    """A 2-process Dask LocalCluster shared by the tests of a module (≈1.5 s to start)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, silence_logs=logging.ERROR,
        dashboard_address=None, scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
    ) as c:  # fmt: skip
        yield c


@pytest.fixture(autouse=True)
def _library_option_names(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every test starts with messages naming options as the library does (``static=``);
    a command run in this process switches to ``--static`` (fuzzygait.core.options), and
    this keeps that from reaching the tests after it."""
    from fuzzygait.core.options import STYLE_VARIABLE

    monkeypatch.delenv(STYLE_VARIABLE, raising=False)


@pytest.fixture(autouse=True)
def _signals_left_as_found() -> Iterator[None]:
    """Each test starts with this process's SIGINT/SIGTERM handlers and its main thread's
    signal mask as the session had them: what a test (a notebook kernel, an interrupted
    command run in-process) changes is put back after it."""
    import signal
    import threading

    watched = (signal.SIGINT, signal.SIGTERM)
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handlers = {s: signal.getsignal(s) for s in watched}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    yield
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    for s, handler in handlers.items():
        signal.signal(s, handler)
