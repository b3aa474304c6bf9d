"""The compiled-library cache (core/codegen.py): processes or threads that need the
same library at once compile it once — the others wait on its lock and load the file —
and a library already cached is never recompiled."""

from __future__ import annotations

import shutil
import threading
from pathlib import Path

import casadi as ca
import pytest

from fuzzygait.core import codegen

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler (gcc) on this machine")


def _slow_compiler(tmp_path: Path) -> tuple[Path, Path]:
    """A compiler that logs each call and takes half a second longer than gcc."""
    log = tmp_path / "calls.log"
    script = tmp_path / "cc.sh"
    script.write_text(f'#!/bin/sh\necho call >> "{log}"\nsleep 0.5\nexec gcc "$@"\n', encoding="utf-8")
    script.chmod(0o755)
    return script, log


def test_concurrent_builds_of_one_library_compile_it_once(tmp_path, monkeypatch):
    script, log = _slow_compiler(tmp_path)
    monkeypatch.setenv("CC", str(script))
    monkeypatch.delenv("FUZZYGAIT_NO_COMPILE", raising=False)
    x = ca.SX.sym("x", 3)
    doubled = ca.Function("doubled", [x], [2 * x])
    target = tmp_path / "cache" / "fg_test.so"
    results: list[Path | None] = []
    threads = [threading.Thread(target=lambda: results.append(codegen.build_library(target, [doubled])))
               for _ in range(3)]  # fmt: skip
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert results == [target] * 3
    assert log.read_text(encoding="utf-8").splitlines() == ["call"]  # compiled once, two waited
    assert float(ca.external("doubled", str(target))(ca.DM([1, 2, 3]))[2]) == 6.0
    assert codegen.build_library(target, [doubled]) == target  # cached: not compiled again
    assert log.read_text(encoding="utf-8").splitlines() == ["call"]
    assert sorted(p.name for p in target.parent.iterdir()) == ["fg_test.so", "fg_test.so.lock"]


def test_the_compiler_keeps_its_temporary_files_in_the_build_folder(tmp_path, monkeypatch):
    """A compiler killed mid-build (an interrupted run) must leave nothing in the user's
    TMPDIR: it runs with TMPDIR set to the build's own folder in the cache (``-pipe``
    besides), and a build folder left behind is swept once it is an hour old."""
    script = tmp_path / "cc.sh"
    seen = tmp_path / "tmpdir.txt"
    script.write_text(f'#!/bin/sh\necho "$TMPDIR" > "{seen}"\nexec gcc "$@"\n', encoding="utf-8")
    script.chmod(0o755)
    user_tmp = tmp_path / "user-tmp"
    user_tmp.mkdir()
    monkeypatch.setenv("CC", str(script))
    monkeypatch.setenv("TMPDIR", str(user_tmp))
    monkeypatch.delenv("FUZZYGAIT_NO_COMPILE", raising=False)
    cache = tmp_path / "cache"
    cache.mkdir()
    stale, fresh = cache / "tmpstale", cache / "tmpfresh"
    stale.mkdir()
    fresh.mkdir()
    old = codegen.time.time() - 2 * codegen.STALE_BUILD_SECONDS
    import os

    os.utime(stale, (old, old))
    x = ca.SX.sym("x", 2)
    assert codegen.build_library(cache / "fg_tmp.so", [ca.Function("twice", [x], [2 * x])]) is not None
    compiler_tmp = Path(seen.read_text(encoding="utf-8").strip())
    assert compiler_tmp.parent == cache and compiler_tmp.name.startswith("tmp")
    assert list(user_tmp.iterdir()) == []
    assert not stale.exists() and fresh.exists()
