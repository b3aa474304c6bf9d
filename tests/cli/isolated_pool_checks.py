"""Checks of a local pool's worker processes, run by
``test_cli_interrupt_phases.py::test_pool_checks_in_a_fresh_interpreter`` in a fresh
interpreter (this file is not collected by the suite itself: its name does not start
with ``test_``)."""

from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest
from test_cli_interrupt_phases import HANG, _bits, _signal_mask

from fuzzygait.uncertainty.execution import teardown


def _token_children(token: str) -> list[int]:
    return [p.pid for p in teardown._marked_children(token)]


@pytest.mark.slow  # starts local Dask clusters
def test_pool_workers_are_born_deaf_to_sigint_and_sigterm(tmp_path, monkeypatch):
    """A pool's workers, and the processes they start, have SIGINT and SIGTERM blocked
    from their first instruction (a Ctrl-C during their start-up printed a traceback);
    this process has neither blocked; after the close no worker is left."""
    pytest.importorskip("distributed")
    import tempfile

    from fuzzygait.uncertainty.execution import Evaluator

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    with Evaluator(workers=2) as evaluator:
        pids = sorted(set(evaluator.map(_own_pid, [0, 1, 2, 3])))
        token = evaluator._resources.token
        assert token and sorted(_token_children(token)) == sorted(evaluator.client.run(os.getpid).values())
        for pid in pids:
            assert _signal_mask(pid) & _bits(signal.SIGINT, signal.SIGTERM) == _bits(signal.SIGINT, signal.SIGTERM)
        grandchild = evaluator.map(_child_mask, [0])[0]
        assert grandchild & _bits(signal.SIGINT, signal.SIGTERM) == _bits(signal.SIGINT, signal.SIGTERM)
    assert _signal_mask(os.getpid()) & _bits(signal.SIGINT, signal.SIGTERM) == 0
    assert [pid for pid in pids if Path(f"/proc/{pid}").exists()] == []
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow  # starts local Dask clusters
def test_a_second_pool_marks_its_workers_with_its_own_token(tmp_path, monkeypatch):
    """Dask's nanny copies the token into this process's environment, and reads it back
    from there before its setting: the token of a process's first pool marked the
    workers of every later one, which a release then could not find by their token. The
    environment is cleared, and each pool's workers carry that pool's token."""
    pytest.importorskip("distributed")
    import tempfile

    from fuzzygait.uncertainty.execution import Evaluator

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    tokens = []
    for _ in range(2):
        with Evaluator(workers=2) as evaluator:
            pids = evaluator.client.run(os.getpid).values()
            tokens.append(evaluator._resources.token)
            assert sorted(_token_children(tokens[-1])) == sorted(pids)
            assert teardown.POOL_VARIABLE not in os.environ
        assert teardown.POOL_VARIABLE not in os.environ
    assert tokens[0] != tokens[1]


def _own_pid(_: int) -> int:
    return os.getpid()


def _child_mask(_: int) -> int:
    """The blocked signals of a process a worker starts."""
    text = subprocess.run(["cat", "/proc/self/status"], capture_output=True, text=True, check=True).stdout
    return int(next(line for line in text.splitlines() if line.startswith("SigBlk:")).split()[1], 16)


@pytest.mark.slow  # starts a local Dask cluster
def test_a_pool_interrupted_while_its_workers_start_leaves_no_process(tmp_path, monkeypatch):
    """Interrupted while the nannies start their workers (the cluster has no running
    worker yet, and distributed's close of a cluster still starting closes nothing): the
    release still finds the workers, being started ones included, and kills them; none
    is left, so the interpreter's exit does not wait for one for ever."""
    pytest.importorskip("distributed")
    import tempfile

    from fuzzygait.uncertainty.execution import Evaluator

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    seen: set[int] = set()
    me = os.getpid()

    def interrupt_when_a_worker_starts() -> None:
        deadline = time.monotonic() + HANG
        while time.monotonic() < deadline:
            workers = teardown._marked_children(None)
            if workers:
                seen.update(p.pid for p in workers)
                os.kill(me, signal.SIGINT)
                return
            time.sleep(0.01)

    # the interrupt must land while the workers start; on a loaded machine the start can
    # win the race (the cluster is up before the watcher acts): then that attempt is not
    # this case, its cluster is closed normally and the scenario is made again
    interrupted = False
    for _attempt in range(3):
        seen.clear()
        evaluator = Evaluator(workers=2)
        watcher = threading.Thread(target=interrupt_when_a_worker_starts, daemon=True)
        watcher.start()
        try:
            with evaluator:
                _ = evaluator.client
        except KeyboardInterrupt:
            interrupted = True
        try:
            watcher.join(HANG)
            time.sleep(0.1)  # a signal sent late is handled here, not in the next attempt
        except KeyboardInterrupt:  # it came after the cluster had started: not this case
            pass
        if interrupted:
            break
    assert interrupted, "in 3 attempts the interrupt never landed while the workers started"
    assert seen, "no worker was seen starting"
    assert [pid for pid in seen if Path(f"/proc/{pid}").exists()] == []
    assert teardown._marked_children(None) == []
    assert list(tmp_path.iterdir()) == []
