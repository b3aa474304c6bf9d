"""fuzzygait.io.atomic: outputs appear complete or not at all, and what a killed writer
leaves is cleared by the next write (issue 17: "a .nc temp from a killed save stays")."""

from __future__ import annotations

import multiprocessing
import os
import signal
from pathlib import Path

import pytest

from fuzzygait.io import atomic
from fuzzygait.io.atomic import atomic_output, replace_path


def _killed_inside(path: Path) -> None:
    with atomic_output(path) as tmp:
        tmp.write_text("half")
        os.kill(os.getpid(), signal.SIGKILL)


def test_a_file_write_killed_midway_leaves_the_old_file_and_the_next_write_clears_the_temporary(
    tmp_path: Path,
) -> None:
    target = tmp_path / "result.nc"
    target.write_text("old")
    child = multiprocessing.get_context("fork").Process(target=_killed_inside, args=(target,))
    child.start()
    child.join(30)
    assert child.exitcode == -signal.SIGKILL
    left = sorted(p.name for p in tmp_path.iterdir())
    assert target.read_text() == "old" and len(left) == 2
    assert left[0].startswith(".result.nc.tmp-") and left[0].endswith(".nc")  # the writer's pid inside
    with atomic_output(target) as tmp:
        tmp.write_text("new")
    assert target.read_text() == "new" and [p.name for p in tmp_path.iterdir()] == ["result.nc"]


def test_a_running_writers_temporary_is_kept(tmp_path: Path) -> None:
    target = tmp_path / "t.csv"
    with atomic_output(target) as first:
        first.write_text("a")
        with atomic_output(target) as second:  # this process is alive: its temporary stays
            assert first.exists()
            second.write_text("b")
    assert target.read_text() == "a" and [p.name for p in tmp_path.iterdir()] == ["t.csv"]


def test_a_failed_write_leaves_nothing(tmp_path: Path) -> None:
    target = tmp_path / "t.csv"
    with pytest.raises(RuntimeError), atomic_output(target) as tmp:
        tmp.write_text("x")
        raise RuntimeError("writer failed")
    assert not list(tmp_path.iterdir())


def _folder(path: Path, text: str) -> Path:
    path.mkdir()
    (path / "page.html").write_text(text)
    return path


@pytest.mark.parametrize("exchange", [True, False], ids=["renameat2-exchange", "rename-aside"])
def test_replacing_a_folder_never_deletes_the_old_one_first(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, exchange: bool
) -> None:
    if not exchange:
        monkeypatch.setattr(atomic, "exchange", lambda a, b: False)  # a file system without RENAME_EXCHANGE
    target = _folder(tmp_path / "trial_files", "old")
    seen: list[str] = []
    rmtree = atomic.shutil.rmtree

    def watched_rmtree(path: Path, *args: object, **kwargs: object) -> None:
        seen.append((target / "page.html").read_text())  # what the target holds when something is deleted
        rmtree(path, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(atomic.shutil, "rmtree", watched_rmtree)
    replace_path(_folder(tmp_path / ".new", "new"), target)
    assert (target / "page.html").read_text() == "new" and seen == ["new"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["trial_files"]


def test_a_folder_set_aside_by_a_killed_replace_is_put_back(tmp_path: Path) -> None:
    """Killed between the two renames of the fallback: the old folder is back next time."""
    target = tmp_path / "trial_files"
    dead = multiprocessing.get_context("fork").Process(target=os._exit, args=(0,))
    dead.start()
    dead.join()
    _folder(tmp_path / f".trial_files.old-{dead.pid}", "old")
    atomic.tidy_beside(target)
    assert (target / "page.html").read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["trial_files"]
