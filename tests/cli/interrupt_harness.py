"""Run a ``fuzzygait`` command in a process group of its own, signal it at a chosen moment,
and see what it leaves: its exit code, stdout and stderr, the processes of its group
still there the moment it has exited, and the files left in its private ``TMPDIR``.

Shared by ``tests/cli/test_cli_interrupt_moments.py`` and
``benchmarks/interrupt_campaign.py`` (which puts this folder on ``sys.path``).

"The processes still in the group" is read from ``/proc`` right after ``waitpid`` of the
command returned, with no grace period: what a ``ps -o pid,pgid,cmd -g PGID`` run by the
shell after the command's prompt returned would list.  Zombies count too (a zombie is a
child the command did not reap).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

#: The one line an interrupted command prints (``fuzzygait.cli.interrupts.interrupt_line``).
LINE = ("fuzzygait: interrupted ({name}); partial output and temporary files removed, results completed "
        "before are kept")  # fmt: skip
#: Seconds after which a command that does not end is killed (a hang, never a measure of speed).
HANG = 240.0


@dataclass
class Outcome:
    """What one run of a command left behind."""

    args: list[str]
    signum: int | None
    target: str | None  # "group" (as Ctrl-C sends it), "command" (as kill PID does), None: no signal
    moment: float | None  # seconds after the start the signal was sent; None: not sent (the command had ended)
    returncode: int
    stdout: str
    stderr: str
    seconds: float
    left: list[tuple[int, str, str]] = field(default_factory=list)  # (pid, state, command line)
    tmp_left: list[str] = field(default_factory=list)
    hung: bool = False

    def problems(self) -> list[str]:
        """Everything wrong with this outcome (empty: a clean ending)."""
        found = []
        if self.hung:
            found.append(f"did not end within {HANG:g} s")
        text = self.stdout + self.stderr
        if "Traceback" in text or "Exception ignored" in text:
            found.append("a traceback")
        lines = [line for line in self.stderr.splitlines() if line.strip()]
        if self.returncode == 0:
            pass  # ended before the signal (or the signal came while it was ending)
        elif self.signum is not None and self.returncode in (128 + self.signum, -self.signum):
            name = signal.Signals(self.signum).name
            if self.returncode < 0 and lines:
                found.append(f"killed by {name} after printing {len(lines)} line(s)")
            elif self.returncode > 0 and lines != [LINE.format(name=name)]:
                found.append(f"{len(lines)} line(s) on stderr, not the one interrupt line")
        else:
            found.append(f"exit code {self.returncode}")
        if self.left:
            found.append(f"{len(self.left)} process(es) left in its group: {self.left}")
        if self.tmp_left:
            found.append(f"left in TMPDIR: {self.tmp_left}")
        return found

    def describe(self) -> str:
        what = "no signal" if self.signum is None else f"{signal.Signals(self.signum).name} to the {self.target}"
        when = "" if self.moment is None else f" at {self.moment:.2f} s"
        return f"{what}{when}: exit {self.returncode} after {self.seconds:.1f} s"


def group_members(pgid: int) -> list[tuple[int, str, str]]:
    """The processes of process group ``pgid`` (pid, state, command line), from ``/proc``."""
    members = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                stat = f.read()
            fields = stat[stat.rindex(")") + 2:].split()
            if int(fields[2]) != pgid:
                continue
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode(errors="replace").strip()
        except (OSError, ValueError, IndexError):
            continue
        members.append((int(entry), fields[0], cmd[:160] or stat[stat.index("(") : stat.rindex(")") + 1]))
    return members


def kill_group(pgid: int) -> None:
    """SIGKILL whatever is left of group ``pgid`` (the clean-up after a failed run)."""
    try:
        os.killpg(pgid, signal.SIGKILL)
    except OSError:
        pass


def run_command(args: list[str], tmp: Path, *, moment: float | None = None, signum: int = signal.SIGINT,
                target: str = "group", env: dict[str, str] | None = None) -> Outcome:  # fmt: skip
    """Run ``fuzzygait *args`` in a new session (its own process group) with ``TMPDIR=tmp``;
    ``moment`` seconds after the start send ``signum`` to its ``target`` ("group": every
    process of the group, as Ctrl-C in a terminal does; "command": the command alone, as
    ``kill PID`` does) unless it has ended.  Returns the :class:`Outcome`."""
    tmp.mkdir(parents=True, exist_ok=True)
    environment = dict(os.environ if env is None else env, TMPDIR=str(tmp))
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        start = time.monotonic()
        proc = subprocess.Popen([sys.executable, "-m", "fuzzygait", *args], stdout=out, stderr=err, text=True,
                                env=environment, start_new_session=True)  # fmt: skip
        sent = None
        hung = False
        try:
            if moment is not None:
                try:
                    proc.wait(max(0.0, moment - (time.monotonic() - start)))
                except subprocess.TimeoutExpired:
                    sent = time.monotonic() - start
                    if target == "group":
                        os.killpg(proc.pid, signum)
                    else:
                        proc.send_signal(signum)
            try:
                proc.wait(HANG)
            except subprocess.TimeoutExpired:
                hung = True
                kill_group(proc.pid)
                proc.wait()
            seconds = time.monotonic() - start
            left = group_members(proc.pid)  # at once: no grace period
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            kill_group(proc.pid)
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    tmp_left = sorted(os.listdir(tmp))
    return Outcome(list(args), signum if sent is not None else None, target if sent is not None else None, sent,
                   proc.returncode, stdout, stderr, seconds, left, tmp_left, hung)  # fmt: skip


# ------------------------------------------------------------------ the commands with workers
#: The repository's sample trials.
SAMPLE = Path(__file__).resolve().parents[2] / "sample_data"
#: The stance study of the FRV commands (6 nodes, 12 grouping points, 0.5 s): seconds a run.
FRV = ["frv-sim", "stance", "--disc", "12", "--duration", "0.5", "--nodes", "6", "--set", "E=59.958e9"]


def session(work: Path, frames: int = 200) -> Path:
    """A session folder in ``work`` (made once): the static trial, the subject file and two
    walking trials of ``frames`` frames cut from the sample walking trial."""
    import dataclasses
    import shutil

    from fuzzygait.io import read_c3d, write_c3d

    folder = work / "session"
    if not folder.exists():
        staging = work / ".session-staging"
        shutil.rmtree(staging, ignore_errors=True)
        staging.mkdir(parents=True)
        shutil.copy(SAMPLE / "static.c3d", staging / "cal01.c3d")
        shutil.copy(SAMPLE / "subject.toml", staging / "Synthetic.toml")
        trial = read_c3d(SAMPLE / "walking.c3d")
        for name, start in (("walk01", 0), ("walk02", 100)):
            t0, t1 = start / trial.rate, (start + frames) / trial.rate
            events = [dataclasses.replace(e, time=e.time - t0) for e in trial.events if t0 <= e.time < t1]
            write_c3d(dataclasses.replace(trial, markers=trial.markers[start:start + frames], outputs={},
                                          output_kinds={}, events=events), staging / f"{name}.c3d")  # fmt: skip
        staging.rename(folder)
    return folder


def study(work: Path) -> Path:
    """An existing 20-sample FRV study in ``work`` (made once, serially) for runs to extend."""
    store = work / "study.zarr"
    if not store.exists():
        done = run_command([*FRV, "--out", str(store), "--samples", "20", "--workers", "1"], work / "tmp-study")
        if done.returncode != 0:
            raise RuntimeError(f"cannot make the FRV study: {done.stderr}")
    return store


def command_args(name: str, work: Path, run: Path, workers: int = 2) -> list[str]:
    """The arguments of a short ``name`` job with ``workers`` workers writing into ``run``
    (its inputs made once in ``work``): ``uncertainty`` of one angle at one α-level,
    ``report`` of a two-trial session (angles only), ``fuzzy-sim`` of the swing with one
    fuzzy parameter, ``frv-sim`` adding 2000 samples to an existing stance study."""
    import shutil

    if name == "uncertainty":
        return ["uncertainty", str(SAMPLE / "walking.c3d"), "--static", str(SAMPLE / "static.c3d"), "--out",
                str(run / "fuzzy.nc"), "--workers", str(workers), "--angles", "LKneeAngles", "--alphas", "0",
                "--no-per-source", "--tolerance", "0"]  # fmt: skip
    if name == "report":
        return ["report", str(session(work)), "--out", str(run / "report"), "--uncertainty", "none", "--workers",
                str(workers)]  # fmt: skip
    if name == "fuzzy-sim":
        return ["fuzzy-sim", "swing", "--fuzzy", "E=10%", "--duration", "0.05", "--nodes", "6", "--stride", "20",
                "--workers", str(workers), "--out", str(run / "fuzzy.nc")]  # fmt: skip
    if name == "frv-sim":
        store = Path(shutil.copytree(study(work), run / "study.zarr"))  # extended by the run
        return [*FRV, "--out", str(store), "--samples", "2000", "--workers", str(workers)]
    raise ValueError(f"no such command with workers: {name}")


#: The commands that start worker processes (``--workers``).
COMMANDS = ("uncertainty", "report", "fuzzy-sim", "frv-sim")


def seeded_fractions(name: str, count: int, seed: int = 37) -> list[float]:
    """``count`` moments for ``name`` as fractions of its duration, one drawn at random
    (seeded by ``seed`` and the command's name) in each of ``count`` equal parts of
    [0.05, 1]."""
    import random
    import zlib

    rng = random.Random(seed * 1_000_003 + zlib.crc32(name.encode()))
    lo, hi = 0.05, 1.0
    return [lo + (hi - lo) * (i + rng.random()) / count for i in range(count)]


# ------------------------------------------------------------------ the checks of the tests
#: A retried run's signal comes this fraction of its duration earlier per retry.
RETRY_EARLIER = 0.05
#: The signals of a test's interrupted runs, in order: Ctrl-C to the group, then SIGTERM to
#: it (as ``timeout`` sends it).
TEST_DELIVERIES = [(signal.SIGINT, "group"), (signal.SIGTERM, "group")]
_REFERENCE: dict[tuple[str, Path], Outcome] = {}


def reference(name: str, work: Path) -> Outcome:
    """``name`` run to completion with two workers (once per ``work`` folder)."""
    if (name, work) not in _REFERENCE:
        run = work / name / "complete"
        run.mkdir(parents=True)
        _REFERENCE[name, work] = run_command(command_args(name, work, run), run / "tmp")
    return _REFERENCE[name, work]


def check_completes_with_an_empty_group(name: str, work: Path) -> None:
    """The complete run exited 0 and left nothing in its process group nor its TMPDIR."""
    done = reference(name, work)
    assert done.returncode == 0, done.stderr
    assert done.problems() == [], (done.describe(), done.problems())


def check_interrupted_cleanly(name: str, work: Path) -> None:
    """Runs signalled at seeded random moments of the complete run's duration: each
    exits 130 / 143 with the one line (or 0, done as the signal came), no traceback, and
    leaves nothing in its process group nor its TMPDIR.  A run that ended before its
    signal was sent (the machine is shared: durations vary) is made again at the same
    fraction of its own, shorter, duration, :data:`RETRY_EARLIER` of it earlier per retry
    (a moment in the last percent of a 3 s run is within one run's jitter of its end: the
    clean-clone suite once saw all three attempts end first)."""
    duration = reference(name, work).seconds
    for i, (fraction, (signum, target)) in enumerate(zip(seeded_fractions(name, len(TEST_DELIVERIES)),
                                                         TEST_DELIVERIES)):  # fmt: skip
        for attempt in range(3):
            run = work / name / f"interrupted-{i}-{attempt}"
            run.mkdir(parents=True)
            moment = fraction * duration * (1.0 - RETRY_EARLIER * attempt)
            outcome = run_command(command_args(name, work, run), run / "tmp", moment=moment, signum=signum,
                                  target=target)  # fmt: skip
            assert outcome.problems() == [], (outcome.describe(), outcome.problems(), outcome.stderr)
            if outcome.moment is not None:
                break
            duration = min(duration, outcome.seconds)
        assert outcome.moment is not None, f"{name} always ended before its signal: {outcome.describe()}"
