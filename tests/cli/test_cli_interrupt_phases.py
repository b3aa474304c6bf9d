"""Issue 37, the pieces one by one: a signal at each moment of a command's life (start-up,
working, releasing a pool, ending) gives the one line or nothing, never a traceback; a
pool's workers are born with SIGINT and SIGTERM blocked and, cut short while starting,
leave no process; the resource tracker and orphaned descendants do not outlive the
command.

The processes that must be the ``fuzzygait`` command itself run a script named
``fuzzygait`` (what :func:`fuzzygait.cli.interrupts.is_the_command` recognises: the
console script), each in a process group of its own.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from interrupt_harness import LINE, group_members

from fuzzygait.cli.interrupts import Interrupted, InterruptGuard, is_the_command
from fuzzygait.uncertainty.execution import teardown

pytestmark = pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
HANG = 120.0  # s: only to stop a hung test


def _spin() -> None:
    """Bytecodes for a pending signal's handler to run between."""
    for _ in range(10_000):
        pass


def _signal_mask(pid: int, field: str = "SigBlk") -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(f"{field}:"):
            return int(line.split()[1], 16)
    raise AssertionError(f"no {field} for {pid}")


def _bits(*signums: int) -> int:
    return sum(1 << (s - 1) for s in signums)


def test_this_test_process_is_not_the_command():
    assert not is_the_command()  # so importing fuzzygait.cli here installed nothing


def test_an_interrupt_is_held_while_a_pool_is_released():
    """The first signal while an evaluator releases its cluster does not cut the release
    short: it is raised, as the command's Interrupted, when the release is done."""
    done = []
    with pytest.raises(Interrupted) as raised, InterruptGuard(grace_seconds=HANG) as guard:
        with teardown.interrupts_held():
            os.kill(os.getpid(), signal.SIGTERM)
            _spin()
            done.append("released")  # reached: the signal was held
        _spin()
    assert done == ["released"]
    assert raised.value.signum == signal.SIGTERM == guard.signum


def test_a_signal_inside_a_finalizer_is_raised_after_it(capsys):
    """A signal while Python runs a ``weakref.finalize`` callback (whose exception cannot
    propagate: it was printed, "Exception ignored in: <finalize object ...>", and lost; seen
    in the campaign) is raised once the callback is done, and nothing is printed."""
    import weakref

    class Thing:
        pass

    def callback() -> None:
        os.kill(os.getpid(), signal.SIGINT)
        _spin()
        ran.append(True)  # not reached: the handler raised inside the callback

    ran: list[bool] = []
    with pytest.raises(Interrupted), InterruptGuard(grace_seconds=HANG):
        thing = Thing()
        weakref.finalize(thing, callback)
        del thing  # the callback runs now, the signal arrives inside it
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:  # the signal is delivered again: raised here
            time.sleep(0.01)
    assert ran == []
    assert "Exception ignored" not in capsys.readouterr().err


def test_a_signal_while_the_command_ends_raises_nothing():
    """After the work (``ending``): no Interrupted, no KeyboardInterrupt; only the hard
    stop is armed (cancelled here: it would end this test process)."""
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        with InterruptGuard(grace_seconds=HANG, ending=True):
            pass
        ending = signal.getsignal(signal.SIGINT)
        assert ending is signal.getsignal(signal.SIGTERM) and callable(ending)
        os.kill(os.getpid(), signal.SIGINT)
        _spin()
        os.kill(os.getpid(), signal.SIGTERM)
        _spin()
        timer = ending.timer  # type: ignore[union-attr]
        assert timer is not None and timer.is_alive()
        timer.cancel()
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


@pytest.mark.parametrize("inside_user_errors", [True, False])
def test_an_error_after_a_signal_is_reported_as_the_interrupt(inside_user_errors):
    """A C extension imported as the signal comes turns the KeyboardInterrupt into
    ``ImportError: initialization failed`` (scipy's, seen in the campaign): the command
    still prints the interrupt's one line, no error line and no traceback, exit 130."""
    import typer
    from typer.testing import CliRunner

    from fuzzygait.cli.app import Commands, user_errors

    app = typer.Typer(cls=Commands)

    @app.callback()
    def _main() -> None:
        pass

    @app.command()
    def load() -> None:
        def extension_init() -> None:  # what pybind11 does with an error raised while a module initialises
            try:
                os.kill(os.getpid(), signal.SIGINT)
                _spin()
            except KeyboardInterrupt:
                raise ImportError("initialization failed") from None

        if inside_user_errors:
            with user_errors():
                extension_init()
        else:
            extension_init()

    result = CliRunner().invoke(app, ["load"])
    assert result.exit_code == 130, (result.output, result.exception)
    assert result.stderr.splitlines() == [LINE.format(name="SIGINT")]


def _as_the_command(tmp_path: Path, body: str, **popen: object) -> subprocess.Popen[str]:
    """Run ``body`` as a script named ``fuzzygait`` (the console script's name) in a new
    session."""
    script = tmp_path / "fuzzygait"
    script.write_text(textwrap.dedent(body))
    return subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True, **popen)  # type: ignore[call-overload]  # fmt: skip


def test_a_signal_during_start_up_gives_the_one_line(tmp_path):
    """While the command's modules load (before any work): the one line, exit 130."""
    proc = _as_the_command(tmp_path, """
        import os, signal, time
        import fuzzygait.cli  # its first import makes this process the command
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(30)
        print("not interrupted")
        """)
    out, err = proc.communicate(timeout=HANG)
    assert proc.returncode == 130, (out, err)
    assert err.splitlines() == [LINE.format(name="SIGINT")] and out == ""


def test_a_signal_in_an_exit_handler_prints_nothing(tmp_path):
    """The work is done and the exit code decided: a signal while Python runs its exit
    handlers neither prints a traceback nor changes the exit code."""
    proc = _as_the_command(tmp_path, """
        import atexit, os, signal, sys
        from fuzzygait.cli import main
        atexit.register(lambda: (os.kill(os.getpid(), signal.SIGINT), os.kill(os.getpid(), signal.SIGTERM),
                                 sum(range(100_000))))
        main(["--version"])
        """)
    out, err = proc.communicate(timeout=HANG)
    assert (proc.returncode, err) == (0, ""), (out, err)
    assert out.startswith("fuzzygait ")


def test_no_orphan_outlives_the_command(tmp_path):
    """A process whose parent ended without it (a compiler a killed worker had started)
    is adopted by the command and killed at its exit: its process group is empty."""
    pid_file = tmp_path / "orphan.pid"
    proc = _as_the_command(tmp_path, f"""
        import subprocess
        from fuzzygait.cli import main
        subprocess.run(["sh", "-c", "sleep 60 & echo $! > {pid_file}"], check=True)  # sh ends: sleep is orphaned
        main(["--version"])
        """)
    out, err = proc.communicate(timeout=HANG)
    left = group_members(proc.pid)
    orphan = int(pid_file.read_text())
    if any(pid == orphan for pid, _, _ in left):
        os.kill(orphan, signal.SIGKILL)
    assert (proc.returncode, err) == (0, ""), (out, err)
    assert left == []


def test_the_resource_tracker_is_stopped_at_exit(tmp_path):
    """multiprocessing's resource tracker (started by any pool) ends before the command
    does, not just after it: nothing of the command is in its group once it has exited."""
    proc = _as_the_command(tmp_path, """
        from multiprocessing import resource_tracker
        import multiprocessing
        from fuzzygait.cli import main
        lock = multiprocessing.get_context("spawn").Lock()  # a semaphore: the tracker starts
        print(resource_tracker._resource_tracker._pid, flush=True)
        main(["--version"])
        """)
    out, err = proc.communicate(timeout=HANG)
    left = group_members(proc.pid)
    assert (proc.returncode, err) == (0, ""), (out, err)
    assert int(out.splitlines()[0]) > 0
    assert left == []


@pytest.mark.slow  # starts local Dask clusters
def test_pool_checks_in_a_fresh_interpreter():
    """The checks of a pool's workers (``isolated_pool_checks.py``: born with SIGINT and
    SIGTERM blocked, none left after an interrupt while they start, each pool's own
    token) run in a fresh interpreter: they look for this process's pool workers, and the
    pools other test files keep open in the same process would be among them."""
    checks = Path(__file__).with_name("isolated_pool_checks.py")
    result = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider", str(checks)],
                            capture_output=True, text=True, timeout=600, cwd=Path(__file__).resolve().parents[2])
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-2000:]
    assert "3 passed" in result.stdout.splitlines()[-1]
