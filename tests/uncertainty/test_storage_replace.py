"""``save_result`` over an existing .zarr result (issue 17): the previous result is never
deleted before the new one is complete. A failure at the last step (the swap into
place) leaves it intact; a SIGKILL before any write of the save leaves exactly the old or
exactly the new result, and the next save clears what the killed one left."""

from __future__ import annotations

import multiprocessing
import os
import shutil
import signal
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr
import zarr.storage._local as zarr_local

from fuzzygait.io import atomic
from fuzzygait.uncertainty.storage import load_result, save_result


def result(seed: int) -> xr.Dataset:
    values = np.random.default_rng(seed).normal(size=(3, 40))
    return xr.Dataset({"hull": (("alpha", "time"), values)}, coords={"time": np.arange(40.0)}, attrs={"seed": seed})


def is_result(path: Path, seed: int) -> bool:
    loaded = load_result(path)
    return loaded.attrs["seed"] == seed and np.array_equal(loaded["hull"].values, result(seed)["hull"].values)


def test_a_failed_swap_leaves_the_previous_result(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "r.zarr"
    save_result(result(1), target)

    def broken(new: Path, old: Path) -> bool:
        raise OSError(5, "Input/output error", str(old))

    monkeypatch.setattr(atomic, "exchange", broken)
    with pytest.raises(OSError, match="Input/output"):
        save_result(result(2), target)
    assert is_result(target, 1)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.zarr"]  # the new one's folder removed


def test_without_an_atomic_exchange_the_old_one_is_renamed_aside(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "r.zarr"
    save_result(result(1), target)
    monkeypatch.setattr(atomic, "exchange", lambda new, old: False)  # e.g. a file system without RENAME_EXCHANGE
    save_result(result(2), target)
    assert is_result(target, 2) and sorted(p.name for p in tmp_path.iterdir()) == ["r.zarr"]
    # a process killed between the two renames left the old result aside and nothing in place: put back
    aside = tmp_path / ".r.zarr.old-999999999"
    os.rename(target, aside)
    save_result(result(3), tmp_path / "other.zarr")  # another target: this one is not touched
    assert aside.exists() and not target.exists()
    atomic.tidy_beside(target)
    assert is_result(target, 2) and not aside.exists()


def _save_killed(kill_at: int, target: Path) -> None:
    count = [0]

    def event() -> None:
        count[0] += 1
        if count[0] == kill_at:
            os.kill(os.getpid(), signal.SIGKILL)

    put, exchange, rmtree = zarr_local._put, atomic.exchange, shutil.rmtree

    def hooked_put(path: Path, value: Any, exclusive: bool = False) -> int:
        event()
        return put(path, value, exclusive=exclusive)

    def hooked_exchange(a: Path, b: Path) -> bool:
        event()
        return exchange(a, b)

    def hooked_rmtree(path: Any, *args: Any, **kwargs: Any) -> None:
        event()
        rmtree(path, *args, **kwargs)

    zarr_local._put, atomic.exchange, shutil.rmtree = hooked_put, hooked_exchange, hooked_rmtree
    save_result(result(2), target)
    os._exit(min(count[0], 250))  # the kill was not reached: say how many writes there were


def _run(kill_at: int, target: Path) -> int | None:
    child = multiprocessing.get_context("fork").Process(target=_save_killed, args=(kill_at, target))
    child.start()
    child.join(60)
    return child.exitcode


def test_a_save_killed_at_any_write_leaves_the_old_or_the_new_result(tmp_path: Path) -> None:
    probe = tmp_path / "probe" / "r.zarr"
    probe.parent.mkdir()
    save_result(result(1), probe)
    writes = _run(10**6, probe)
    assert writes is not None and 5 < writes < 250 and is_result(probe, 2)
    # the start, the middle, just before and after the swap (third last), the end
    outcomes = {}
    for kill_at in sorted({1, writes // 2, writes - 3, writes - 2, writes - 1, writes}):
        folder = tmp_path / f"k{kill_at}"
        folder.mkdir()
        target = folder / "r.zarr"
        save_result(result(1), target)
        assert _run(kill_at, target) == -signal.SIGKILL
        outcomes[kill_at] = 2 if is_result(target, 2) else 1
        assert outcomes[kill_at] == 2 or is_result(target, 1)
        save_result(result(3), target)  # the next save clears what the killed one left
        assert is_result(target, 3) and sorted(p.name for p in folder.iterdir()) == ["r.zarr"]
    assert outcomes == {k: 2 if k > writes - 2 else 1 for k in outcomes}
