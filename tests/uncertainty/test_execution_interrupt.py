"""An interrupted Evaluator leaves nothing: its local pool's workers ignore SIGINT (a
Ctrl-C reaches the whole process group; only the driver decides), an interrupt while
tasks run stops every worker process and removes the evaluator's temporary directory
(Dask's scratch space is inside it), and directories that killed processes left behind
are swept when a new one is made."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest

from fuzzygait.uncertainty.execution import Evaluator
from fuzzygait.uncertainty.execution.evaluator import TMPDIR_PREFIX, remove_stale_tmpdirs

HANG = 120.0  # s: only to stop a hung test


def _busy(marker: str) -> str:
    """A task that says it started (a file) and then runs far longer than the test."""
    Path(marker).write_text(str(os.getpid()))
    deadline = time.monotonic() + HANG
    while time.monotonic() < deadline:
        sum(range(10_000))
    return marker


def _ignored_signals(pid: int) -> int:
    """The process's ignored-signal mask (``SigIgn`` of /proc/<pid>/status)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("SigIgn:"):
            return int(line.split()[1], 16)
    raise AssertionError(f"no SigIgn for {pid}")


def _running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_stale_temporary_directories_are_swept(tmp_path):
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True, check=True).stdout.strip()  # fmt: skip
    dead = tmp_path / f"{TMPDIR_PREFIX}{gone}-abc"
    mine = tmp_path / f"{TMPDIR_PREFIX}{os.getpid()}-def"
    alive = tmp_path / f"{TMPDIR_PREFIX}1-ghi"  # pid 1 always runs
    other = tmp_path / "fuzzygait-parallel-notapid"
    for folder in (dead, mine, alive, other):
        folder.mkdir()
    (dead / "dask").mkdir()
    assert remove_stale_tmpdirs(str(tmp_path)) == [str(dead)]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in (mine, alive, other))


@pytest.mark.slow  # starts a local Dask cluster
@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
def test_interrupted_pool_stops_its_workers_and_removes_its_files(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    markers = [str(tmp_path / f"started-{i}") for i in range(2)]

    def interrupt_when_busy() -> None:  # SIGINT once both workers run a task
        deadline = time.monotonic() + HANG
        while time.monotonic() < deadline and not all(os.path.exists(m) for m in markers):
            time.sleep(0.05)
        os.kill(os.getpid(), signal.SIGINT)

    evaluator = Evaluator(workers=2)
    pids = sorted(evaluator.client.run(os.getpid).values())
    assert len(pids) == 2
    cluster = evaluator._resources.cluster
    for pid in pids:
        assert _ignored_signals(pid) & (1 << (signal.SIGINT - 1)), "a worker does not ignore SIGINT"
    assert [p.name.startswith(TMPDIR_PREFIX) for p in scratch.iterdir()] == [True]
    watcher = threading.Thread(target=interrupt_when_busy, daemon=True)
    watcher.start()
    with pytest.raises(KeyboardInterrupt), evaluator:
        evaluator.map(_busy, markers)
    watcher.join(HANG)
    assert sorted(int(Path(m).read_text()) for m in markers) == pids  # both were busy when interrupted
    assert [pid for pid in pids if _running(pid)] == []
    assert list(scratch.iterdir()) == []  # neither the evaluator's directory nor Dask's scratch space
    from distributed.deploy.spec import SpecCluster

    assert cluster not in SpecCluster._instances  # nothing left for distributed to close (again) at exit


class _HalfStarted:
    """A local cluster whose start is cut short: it registers itself for distributed's
    close at exit, as ``SpecCluster.__init__`` does first, and then fails (``error``)."""

    error: type[BaseException] = KeyboardInterrupt
    closed: list[_HalfStarted] = []
    shutdown_on_close = True

    def __init__(self, *args: object, **kwargs: object) -> None:
        from distributed.deploy.spec import SpecCluster

        self.workers: dict[str, object] = {}
        SpecCluster._instances.add(self)  # type: ignore[arg-type]
        raise self.error("cut short while starting")

    def close(self, timeout: float | None = None) -> None:
        _HalfStarted.closed.append(self)


@pytest.mark.parametrize("error", [KeyboardInterrupt, RuntimeError])
def test_a_cluster_cut_short_while_starting_is_released(tmp_path, monkeypatch, error):
    """Interrupted (or failing) while the local cluster starts: the half-started cluster
    is closed by the evaluator and taken off distributed's exit list, whose own close would
    print a traceback (``assert w.status in ...: Status.init``) after the one-line message."""
    distributed = pytest.importorskip("distributed")
    from distributed.deploy.spec import SpecCluster

    from fuzzygait.uncertainty.execution.evaluator import ParallelEvaluationError

    def half_started() -> list[object]:
        return [c for c in SpecCluster._instances if isinstance(c, _HalfStarted)]

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setattr(distributed, "LocalCluster", type("Cut", (_HalfStarted,), {"error": error}))
    _HalfStarted.closed.clear()
    evaluator = Evaluator(workers=2)
    with pytest.raises(KeyboardInterrupt if error is KeyboardInterrupt else ParallelEvaluationError, match="cut short"):
        _ = evaluator.client
    if error is KeyboardInterrupt:  # the evaluator holds it; the interrupt's handler closes the evaluator
        assert len(half_started()) == 1 and not _HalfStarted.closed
    else:  # released at once
        assert len(_HalfStarted.closed) == 1 and not half_started()
    evaluator.close()
    assert len(_HalfStarted.closed) == 1
    assert not half_started()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("method", ["spawn", "fork"])
@pytest.mark.parametrize("main", ["script", "worker", "command", "notebook"])
def test_a_pool_that_cannot_start_from_a_script_says_how_to_guard_it(tmp_path, monkeypatch, main, method):
    """A script that runs its analysis at top level makes every spawned worker run it again,
    and the pool fails to start ("Nanny failed to start"): the one-line error then names the
    script and the ``if __name__ == "__main__":`` guard (or workers=1); the ``fuzzygait``
    command and a notebook (no file) get the plain message, and so does every program whose
    workers are forked (Linux): they import nothing again."""
    import types

    distributed = pytest.importorskip("distributed")
    from fuzzygait.uncertainty.execution import evaluator as evaluator_module
    from fuzzygait.uncertainty.execution.evaluator import ParallelEvaluationError

    monkeypatch.setattr(evaluator_module, "start_method", lambda: method)

    module = types.ModuleType("__main__")
    if main == "script":
        module.__file__, module.__spec__ = str(tmp_path / "gait_analysis.py"), None
    elif main == "worker":  # a spawned worker importing the script: that is __mp_main__, __main__ is spawn's
        monkeypatch.setitem(sys.modules, "__mp_main__", types.ModuleType("__mp_main__"))
    elif main == "command":
        module.__file__ = "/x/fuzzygait/__main__.py"
        module.__spec__ = types.SimpleNamespace(name="fuzzygait.__main__")  # type: ignore[assignment]
    monkeypatch.setitem(sys.modules, "__main__", module)
    if main != "worker":
        monkeypatch.setitem(sys.modules, "__mp_main__", module)  # as multiprocessing sets it in the main process
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setattr(distributed, "LocalCluster", type("Failed", (_HalfStarted,), {"error": RuntimeError}))
    evaluator = Evaluator(workers=2)
    with pytest.raises(ParallelEvaluationError) as caught:
        _ = evaluator.client
    evaluator.close()
    message = str(caught.value)
    assert message.startswith("cannot start a local Dask cluster: cut short while starting")
    if method == "fork":
        assert message == "cannot start a local Dask cluster: cut short while starting"
    elif main == "script":
        assert 'if the script gait_analysis.py starts this run at its top level, put that code under `if __name__ == ' \
               '"__main__":`' in message and "workers=1" in message
    elif main == "worker":
        assert "this is a worker process re-importing the script: put the script's top-level code under `if " \
               '__name__ == "__main__":`' in message
    else:
        assert message == "cannot start a local Dask cluster: cut short while starting"
