"""The pieces of a clean ending, in-process and fast: usage errors as one line (exit 1,
``--help`` untouched), warnings held while a command works (printed when it succeeds,
left out and counted when it fails), SIGINT/SIGTERM raising one ``Interrupted`` whose
exit code is 128 + signal, and the report folder's clean-up of an interrupted batch."""

from __future__ import annotations

import os
import signal
import sys
import warnings

import pytest
import typer
from typer.testing import CliRunner

from fuzzygait.cli import app
from fuzzygait.cli.app import user_errors
from fuzzygait.cli.interrupts import Interrupted, InterruptGuard, exit_code, interrupt_line
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.workflows.batch_report import remove_stale_staging

runner = CliRunner()


def _line(*args: str) -> str:
    """The one stderr line of a usage error (exit 1, nothing on stdout)."""
    result = runner.invoke(app, list(args))
    assert result.exit_code == 1, (result.exit_code, result.output)
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert result.stdout == ""
    assert lines[0].startswith("fuzzygait: error: ")
    return lines[0]


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["uncertainty", "--foo"], "fuzzygait: error: uncertainty: no such option --foo (did you mean --flat-foot "
         "or --out?); see 'fuzzygait uncertainty --help'"),
        (["uncertainty"], "fuzzygait: error: uncertainty: missing argument DYNAMIC.c3d; see "
         "'fuzzygait uncertainty --help'"),
        (["uncertainty", "x.c3d"], "fuzzygait: error: uncertainty: missing option --out / -o; see "
         "'fuzzygait uncertainty --help'"),
        (["uncertainty", "x.c3d", "--out", "x.nc", "--workers", "two"], "fuzzygait: error: uncertainty: invalid "
         "value 'two' for --workers: input should be a valid integer, unable to parse string as an integer; see "
         "'fuzzygait uncertainty --help'"),
        (["uncertainty", "x.c3d", "--out"], "fuzzygait: error: uncertainty: option '--out' requires an argument; "
         "see 'fuzzygait uncertainty --help'"),
        (["uncertanty"], "fuzzygait: error: no such command 'uncertanty' (did you mean 'uncertainty'?); see "
         "'fuzzygait --help'"),
        (["info"], "fuzzygait: error: info: missing argument FILES; see 'fuzzygait info --help'"),
        (["report", "s", "--out", "r", "--pdf=yes"], "fuzzygait: error: report: option '--pdf' does not take a "
         "value; see 'fuzzygait report --help'"),
    ],
)  # fmt: skip
def test_usage_errors_are_one_line_naming_the_option(args, expected):
    assert _line(*args) == expected


def test_usage_error_escapes_control_characters():
    line = _line("angles", "--modl\x1b[31m", "x.c3d")
    assert "\x1b" not in line and "\\x1b[31m" in line


def test_help_is_untouched():
    result = runner.invoke(app, ["uncertainty", "--help"])
    assert result.exit_code == 0
    assert "Usage: fuzzygait uncertainty" in result.stdout and "--workers" in result.stdout
    bare = runner.invoke(app, [])  # no command: the help, as --help prints it
    assert bare.exit_code == 0
    assert bare.stdout == runner.invoke(app, ["--help"]).stdout


def test_warnings_are_held_until_the_work_ends(capsys):
    warnings.simplefilter("always")
    app_module = sys.modules["fuzzygait.cli.app"]  # (the package's `app` is the typer app)
    previous = warnings.showwarning
    warnings.showwarning = app_module._show_warning  # as the command's callback sets it
    try:
        with user_errors():
            warnings.warn("marker LTOE: 3 frames blanked", stacklevel=1)
            assert capsys.readouterr().err == ""  # held while the work runs
        assert capsys.readouterr().err == "fuzzygait: warning: marker LTOE: 3 frames blanked\n"
        with pytest.raises(typer.Exit) as failed, user_errors():
            warnings.warn("marker LTOE: 3 frames blanked", stacklevel=1)
            warnings.warn("marker RTOE: 1 frame blanked", stacklevel=1)
            raise FuzzyGaitError("walk.c3d: no foot strikes")
        assert failed.value.exit_code == 1
        assert capsys.readouterr().err == ("fuzzygait: error: walk.c3d: no foot strikes (2 warnings left out; "
                                           "--debug shows them)\n")  # fmt: skip
    finally:
        warnings.showwarning = previous


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_raises_interrupted_once(signum):
    with InterruptGuard(grace_seconds=60) as guard:
        with pytest.raises(Interrupted) as raised:
            os.kill(os.getpid(), signum)
            for _ in range(1000):  # the handler runs between bytecodes
                pass
        assert raised.value.signum == signum == guard.signum
        os.kill(os.getpid(), signum)  # during the clean-up: ignored
        for _ in range(1000):
            pass
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # the handlers are restored
    assert exit_code(signum) == {signal.SIGINT: 130, signal.SIGTERM: 143}[signum]
    assert interrupt_line(signum).startswith(f"fuzzygait: interrupted ({signal.Signals(signum).name}); ")


def test_interrupted_report_folder_is_cleaned(tmp_path):
    """What a batch stopped mid-trial leaves: staging folders, a job.json's temporary file
    and a page folder set aside while its replacement was moving in."""
    (tmp_path / ".walk01.abc.tmp").mkdir()
    (tmp_path / ".walk01.abc.tmp" / "walk01.html").write_text("half")
    files = tmp_path / "walk02_files"
    files.mkdir()
    (files / "data.npz").write_bytes(b"new")
    (files / ".job.json.tmp-123").write_text("{")
    aside = tmp_path / ".walk03_files.old-123"  # the move was cut between its two renames
    aside.mkdir()
    (aside / "data.npz").write_bytes(b"old")
    (tmp_path / ".walk02_files.old-124").mkdir()  # its replacement is in place: only removed
    (tmp_path / "walk02.html").write_text("page")
    removed = remove_stale_staging(tmp_path)
    assert sorted(removed) == [".walk01.abc.tmp", ".walk02_files.old-124", ".walk03_files.old-123",
                               "walk02_files/.job.json.tmp-123"]  # fmt: skip
    assert sorted(p.name for p in tmp_path.iterdir()) == ["walk02.html", "walk02_files", "walk03_files"]
    assert (tmp_path / "walk03_files" / "data.npz").read_bytes() == b"old"  # the previous page folder is back
    assert [p.name for p in files.iterdir()] == ["data.npz"]
