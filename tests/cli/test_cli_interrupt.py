"""SIGINT and SIGTERM of ``uncertainty``, ``report`` and ``frv-sim`` mid-run (issue 17):
no process of the command is left, no temporary file (in the output folder, nor the
evaluator's ``fuzzygait-parallel-*`` folder or Dask's scratch space in the temporary
folder), the result of an earlier run on the same output is still there and unchanged,
exit 130 / 143 and one line on stderr, no traceback.

Each command runs in a subprocess in its own session with its own ``TMPDIR`` and an
environment variable marking its processes; SIGINT goes to the whole process group (as
Ctrl-C in a terminal sends it), SIGTERM to the command alone (as ``kill`` does).  "Mid-run"
is measured, not slept: the signal is sent once the worker processes have spent a few
seconds of CPU time on the work (past their start-up).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from support import SAMPLE_DATA, synthetic_session

psutil = pytest.importorskip("psutil")
pytest.importorskip("distributed")

pytestmark = pytest.mark.slow  # each test runs a command to completion and interrupts it twice

MARK = "FUZZYGAIT_INTERRUPT_TEST"
MODULUS = 59.958e9  # Pa, Table 5.3
#: CPU seconds the workers together must have spent before the signal: well inside the
#: work, about half-way.  The workers are forked copies of the command (Linux), so all of
#: their CPU is the work (spawned ones first spent about 1.5 s each importing).  Measured
#: on a quiet machine, the workers' CPU when the run ends: ``uncertainty`` (the default
#: analysis) 8.9–9.6 s; ``report`` of the two 200-frame trials (``--uncertainty fast``)
#: 6.2–6.7 s, a page written as each worker's trial ends (about 3.2 s each), so 2.5 s is
#: over a second into each worker's trial and short of a page even if one worker had run
#: alone; ``frv-sim`` of 40,000 samples far longer.
BUSY_CPU = {"uncertainty": 4.0, "report": 2.5, "frv-sim": 4.0}
HANG = 240.0  # s: only to stop a hung command, never a measure of speed


class Run:
    """A ``fuzzygait`` command started in its own session, its processes tracked."""

    def __init__(self, args: list[str], tmp: Path) -> None:
        self.token = uuid.uuid4().hex
        self.tmp = tmp
        tmp.mkdir(exist_ok=True)
        env = dict(os.environ, TMPDIR=str(tmp), **{MARK: self.token})
        self.proc = subprocess.Popen([sys.executable, "-m", "fuzzygait", *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)  # fmt: skip
        self.seen: dict[int, psutil.Process] = {}

    def processes(self) -> list[psutil.Process]:
        """The command's live descendants: its children, its process group, and any
        process carrying this run's mark in its environment (zombies are dead)."""
        found: dict[int, psutil.Process] = {}
        try:
            found |= {p.pid: p for p in psutil.Process(self.proc.pid).children(recursive=True)}
        except psutil.NoSuchProcess:
            pass
        for p in psutil.process_iter():
            if p.pid == self.proc.pid:
                continue
            try:
                if os.getpgid(p.pid) == self.proc.pid or p.environ().get(MARK) == self.token:
                    found[p.pid] = p
            except (OSError, psutil.Error):
                continue
        self.seen |= found
        return [p for p in found.values() if _alive(p)]

    def wait_busy(self, cpu_seconds: float) -> None:
        """Wait until two or more worker processes are alive and have spent
        ``cpu_seconds`` of CPU time together."""
        deadline = time.monotonic() + HANG
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                pytest.fail(f"the command ended before it was interrupted: {self.proc.communicate()}")
            workers = [p for p in self.processes() if "resource_tracker" not in " ".join(_cmdline(p))]
            if len(workers) >= 2 and sum(_cpu(p) for p in workers) >= cpu_seconds:
                return
            time.sleep(0.1)
        pytest.fail("the command's workers never got busy")

    def interrupt(self, signum: int) -> tuple[int, str, str]:
        """Send ``signum`` (SIGINT to the process group, as Ctrl-C does; SIGTERM to the
        command); its exit code, stdout and stderr."""
        self.processes()
        if signum == signal.SIGINT:
            os.killpg(self.proc.pid, signum)
        else:
            self.proc.send_signal(signum)
        try:
            stdout, stderr = self.proc.communicate(timeout=HANG)
        except subprocess.TimeoutExpired:
            self.kill()
            pytest.fail("the interrupted command did not end")
        return self.proc.returncode, stdout, stderr

    def left(self) -> list[psutil.Process]:
        """The processes of the run still alive after it ended (given a moment)."""
        deadline = time.monotonic() + 5
        while True:
            alive = [p for p in self.seen.values() if _alive(p)] + self.processes()
            if not alive or time.monotonic() > deadline:
                return alive
            time.sleep(0.1)

    def kill(self) -> None:
        """SIGKILL whatever of the run is still there (the clean-up of a failed test)."""
        for p in self.seen.values():
            try:
                p.kill()
            except psutil.Error:
                pass
        if self.proc.poll() is None:
            self.proc.kill()


def _alive(p: psutil.Process) -> bool:
    try:
        return p.is_running() and p.status() != psutil.STATUS_ZOMBIE
    except psutil.Error:
        return False


def _cmdline(p: psutil.Process) -> list[str]:
    try:
        return p.cmdline()
    except psutil.Error:
        return []


def _cpu(p: psutil.Process) -> float:
    try:
        times = p.cpu_times()
    except psutil.Error:
        return 0.0
    return times.user + times.system


def _digests(folder: Path) -> dict[str, str]:
    """SHA-256 of every file under ``folder`` by relative path."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}  # fmt: skip


def _hidden(folder: Path, allowed: tuple[str, ...] = ()) -> list[str]:
    """Hidden files and folders under ``folder`` (temporary files of the writers), except
    those named in ``allowed`` (zarr's own metadata files)."""
    return [str(p.relative_to(folder)) for p in folder.rglob(".*") if p.name not in allowed]


def _interrupted_cleanly(args: list[str], tmp: Path, signum: int, cpu: float, out: Path,
                         allowed: tuple[str, ...] = ()) -> None:  # fmt: skip
    """Start ``args``, interrupt it mid-run with ``signum`` and check everything the
    acceptance asks for but the earlier result (checked by the caller)."""
    run = Run(args, tmp)
    try:
        run.wait_busy(cpu)
        code, stdout, stderr = run.interrupt(signum)
        left = run.left()
    finally:
        run.kill()
    name = signal.Signals(signum).name
    assert code == 128 + signum, (code, stderr)
    assert "Traceback" not in stdout + stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert lines == [f"fuzzygait: interrupted ({name}); partial output and temporary files removed, results "
                     "completed before are kept"], stderr  # fmt: skip
    assert not left, [(p.pid, _cmdline(p)) for p in left]
    assert len(run.seen) >= 2  # the workers were seen, so "none left" means something
    assert sorted(os.listdir(tmp)) == []  # no fuzzygait-parallel-*, no dask-scratch-space
    assert _hidden(out.parent, allowed) == []


def _complete(args: list[str], tmp: Path) -> None:
    tmp.mkdir(exist_ok=True)
    result = subprocess.run([sys.executable, "-m", "fuzzygait", *args], capture_output=True, text=True,
                            timeout=HANG, env=dict(os.environ, TMPDIR=str(tmp)))  # fmt: skip
    assert result.returncode == 0, result.stderr


def _earlier_run(factory: pytest.TempPathFactory, name: str, args: list[str]) -> Path:
    """Run ``args`` (which write under ``{out}``) to completion once per module in a folder
    of its own and return that folder; each test copies it (:func:`_copy_of`)."""
    folder = factory.mktemp(name)
    _complete([a.replace("{out}", str(folder / "out")) for a in args], folder / "tmp")
    shutil.rmtree(folder / "tmp")
    return folder / "out"


def _copy_of(earlier: Path, tmp_path: Path) -> Path:
    """A copy of an earlier run's output folder for one test to interrupt a run over."""
    return Path(shutil.copytree(earlier, tmp_path / "out"))


UNCERTAINTY = ["uncertainty", str(SAMPLE_DATA / "walking.c3d"), "--static", str(SAMPLE_DATA / "static.c3d")]


@pytest.fixture(scope="module")
def earlier_uncertainty(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The output folder of a completed (short) ``uncertainty`` run: ``fuzzy.nc``."""
    return _earlier_run(tmp_path_factory, "uncertainty", [*UNCERTAINTY, "--out", "{out}/fuzzy.nc", "--workers", "1",
                        "--angles", "LKneeAngles", "--alphas", "0", "--no-per-source", "--tolerance", "0"])  # fmt: skip


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_uncertainty_interrupted(tmp_path, signum, earlier_uncertainty):
    import xarray as xr

    out = _copy_of(earlier_uncertainty, tmp_path) / "fuzzy.nc"
    with xr.open_dataset(out) as ds:
        before = ds.load()
    digest = hashlib.sha256(out.read_bytes()).hexdigest()
    _interrupted_cleanly([*UNCERTAINTY, "--out", str(out), "--workers", "2"], tmp_path / "tmp", signum,
                         BUSY_CPU["uncertainty"], out)  # fmt: skip
    assert hashlib.sha256(out.read_bytes()).hexdigest() == digest
    with xr.open_dataset(out) as ds:
        xr.testing.assert_identical(ds.load(), before)
    assert sorted(p.name for p in out.parent.iterdir()) == ["fuzzy.nc"]


@pytest.fixture(scope="module")
def visit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A synthetic session folder of two 200-frame walking trials."""
    return synthetic_session(tmp_path_factory.mktemp("session") / "visit", 200)


@pytest.fixture(scope="module")
def earlier_report(tmp_path_factory: pytest.TempPathFactory, visit: Path) -> Path:
    """The output folder of a completed angles-only ``report`` of :func:`visit`."""
    return _earlier_run(tmp_path_factory, "report", ["report", str(visit), "--out", "{out}", "--uncertainty", "none",
                                                     "--workers", "1"])  # fmt: skip


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_report_interrupted(tmp_path, signum, visit, earlier_report):
    from fuzzygait.workflows.batch_report import load_page_data

    out = _copy_of(earlier_report, tmp_path)
    before = _digests(out)
    pages = {name: load_page_data(out / "visit", name) for name in ("walk01", "walk02")}
    args = ["report", str(visit), "--out", str(out), "--uncertainty", "fast", "--workers", "2"]
    _interrupted_cleanly(args, tmp_path / "tmp", signum, BUSY_CPU["report"], out / "index.html")
    assert _digests(out) == before  # every page of the first run as it was (none finished in between)
    for name, data in pages.items():
        again = load_page_data(out / "visit", name)
        assert again.keys() == data.keys()
        assert all(np.array_equal(again[k], data[k]) for k in data)


#: 6 nodes: the model structure of the other frv-sim command tests, whose compiled library it shares
STUDY = ["frv-sim", "stance", "--disc", "12", "--duration", "2.0", "--nodes", "6", "--set", f"E={MODULUS}"]


@pytest.fixture(scope="module")
def earlier_study(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The output folder of a completed 20-sample ``frv-sim`` study: ``study.zarr``."""
    return _earlier_run(tmp_path_factory, "study", [*STUDY, "--out", "{out}/study.zarr", "--samples", "20",
                                                    "--workers", "1"])  # fmt: skip


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_frv_sim_interrupted(tmp_path, signum, earlier_study):
    import xarray as xr

    store = _copy_of(earlier_study, tmp_path) / "study.zarr"

    def first_hulls() -> np.ndarray:
        with xr.open_zarr(store, group="samples", consolidated=False) as ds:
            return np.asarray(ds["hull"][:20].values)

    before = first_hulls()
    assert before.shape[0] == 20 and np.isfinite(before).all()
    zarr_metadata = (".zattrs", ".zgroup", ".zarray", ".zmetadata")
    _interrupted_cleanly([*STUDY, "--out", str(store), "--samples", "40000", "--workers", "2"], tmp_path / "tmp",
                         signum, BUSY_CPU["frv-sim"], store, allowed=zarr_metadata)  # fmt: skip
    assert np.array_equal(first_hulls(), before)  # the first run's samples untouched


def test_interrupt_helpers_find_the_workers(tmp_path):
    """The checks above can fail: while the command runs, its workers are found by the
    same helper that later finds none, and a worker killed from outside is not alive."""
    out = tmp_path / "fuzzy.nc"
    run = Run(["uncertainty", str(SAMPLE_DATA / "walking.c3d"), "--static", str(SAMPLE_DATA / "static.c3d"),
               "--workers", "2", "--out", str(out)], tmp_path / "tmp")  # fmt: skip
    try:
        run.wait_busy(4.0)
        workers = [p for p in run.processes() if "resource_tracker" not in " ".join(_cmdline(p))]
        assert len(workers) >= 2
        assert any(path.name.startswith("fuzzygait-parallel-") for path in (tmp_path / "tmp").iterdir())
    finally:
        run.kill()
        run.proc.communicate(timeout=HANG)
    assert run.left() == []

