"""`frv-sim` SIGKILLed mid-run, as a user's machine would do it (issue 17): the whole
command's process group is killed at moments picked by watching the study folder — as
soon as a new study's temporary folder appears, at its first, second and third change
seen on disk, and late in the run — during the first run and during an extension.
The next run of the same command either completes with exactly the numbers of an
uninterrupted sequence of runs (every sample's hulls, cuts and bins, the library, the
interval table) or refuses with one line saying what to do; never different hulls.

(The library-level tests in tests/uncertainty/test_frv_study_crash.py kill before each
chosen file write deterministically; these check the command end to end.)"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr
from support import run

from fuzzygait.uncertainty import FunctionModel
from fuzzygait.uncertainty.frv import FRVStudy

MODULUS = 59.958e9  # Pa, Table 5.3
SAMPLES = 150


def args(store: Path) -> list[str]:
    return ["frv-sim", "stance", "--samples", str(SAMPLES), "--disc", "8", "--duration", "0.02", "--nodes", "6",
            "--set", f"E={MODULUS}", "--workers", "1", "--out", str(store)]  # fmt: skip


def snapshot(store: Path) -> dict[str, np.ndarray]:
    with xr.open_zarr(store, group="samples", consolidated=False) as ds:
        times = ds["time"].to_numpy()
    reader = FunctionModel(lambda p: np.zeros(p.shape[:-1] + times.shape), times)  # reading simulates nothing
    study = FRVStudy.open(store, reader)
    lib, table = study.library(), study.intervals()
    order = np.lexsort((table["right"].to_numpy(), table["left"].to_numpy()))
    out = {name: study.samples()[name].to_numpy() for name in ("cut", "bin")}
    out["hull"] = study.hulls()["hull"].to_numpy()
    out |= {f"library_{name}": lib[name].to_numpy() for name in ("bin", "value", "slope")}
    out |= {name: table[name].to_numpy()[order] for name in ("left", "right", "lower", "upper")}
    return out


def same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return a.keys() == b.keys() and all(a[k].shape == b[k].shape and np.array_equal(a[k], b[k]) for k in a)


def state(folder: Path) -> set[tuple[str, int, int]]:
    """Every file under ``folder`` (hidden temporaries included) with its size and mtime.
    A folder renamed or removed while it is walked (the command moving its temporary
    store into place) makes the walk start again."""
    while True:
        found = set()
        try:
            for path in folder.rglob("*"):
                try:
                    info = path.stat()
                except FileNotFoundError:  # removed while we looked
                    continue
                found.add((str(path.relative_to(folder)), info.st_size, info.st_mtime_ns))
        except FileNotFoundError:  # a folder vanished between listing and entering it
            continue
        return found


def killed(store: Path, moment: str) -> bool:
    """Run the command and SIGKILL its process group at ``moment``; False when the run
    ended before the moment came (then it completed)."""
    folder = store.parent
    before = state(folder)
    proc = subprocess.Popen([sys.executable, "-m", "fuzzygait", *args(store)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)  # fmt: skip
    changes, started = 0, time.monotonic()
    try:
        while proc.poll() is None:
            now = state(folder)
            if moment == "temporary" and any(name.startswith(".") for name, _, _ in now - before):
                break
            if moment.startswith("change") and now != before:
                changes += 1
                before = now
                if changes == int(moment[-1]):
                    break
            if moment == "late" and time.monotonic() - started > LATE[store.exists()]:
                break
            time.sleep(0.002)
        else:
            return False
        os.killpg(proc.pid, signal.SIGKILL)
        return True
    finally:
        proc.wait(60)


#: seconds after the start for the "late" kill: most of an uninterrupted run (set below)
LATE: dict[bool, float] = {False: 0.0, True: 0.0}


@pytest.fixture(scope="module")
def truths(tmp_path_factory: pytest.TempPathFactory) -> list[dict[str, np.ndarray]]:
    """Uninterrupted runs 1, 2, 3 of the command (150, 300, 450 samples)."""
    store = tmp_path_factory.mktemp("truth") / "study.zarr"
    out = []
    for k in range(3):
        started = time.monotonic()
        result = run(*args(store))
        assert result.returncode == 0, result.stderr
        LATE[k > 0] = 0.85 * (time.monotonic() - started)
        out.append(snapshot(store))
    assert [t["hull"].shape[0] for t in out] == [SAMPLES, 2 * SAMPLES, 3 * SAMPLES]
    return out


def check_rerun(store: Path, truths: list[dict[str, np.ndarray]]) -> str:
    result = run(*args(store))
    if result.returncode != 0:  # allowed: one line saying what to do
        lines = [line for line in result.stderr.splitlines() if line.strip()]
        assert len(lines) == 1 and lines[0].startswith("fuzzygait: error: "), result.stderr
        assert "Traceback" not in result.stderr
        return "refused"
    now = snapshot(store)
    n = now["hull"].shape[0]
    assert n in (SAMPLES, 2 * SAMPLES, 3 * SAMPLES), n
    assert same(now, truths[n // SAMPLES - 1]), f"hulls differ from the uninterrupted run with {n} samples"
    assert sorted(p.name for p in store.parent.iterdir()) == ["study.zarr"], "temporaries left"
    return f"{n} samples"


@pytest.mark.slow
@pytest.mark.parametrize("moment", ["temporary", "change2", "late"])
def test_first_run_killed(tmp_path: Path, truths: list[dict[str, np.ndarray]], moment: str) -> None:
    store = tmp_path / "study.zarr"
    was_killed = killed(store, moment)
    outcome = check_rerun(store, truths)
    assert outcome != "refused" and (was_killed or outcome == f"{2 * SAMPLES} samples")


@pytest.mark.slow
@pytest.mark.parametrize("moment", ["change1", "change3", "late"])
def test_extension_killed(tmp_path: Path, truths: list[dict[str, np.ndarray]], moment: str) -> None:
    store = tmp_path / "study.zarr"
    result = run(*args(store))
    assert result.returncode == 0, result.stderr
    assert same(snapshot(store), truths[0])
    was_killed = killed(store, moment)
    outcome = check_rerun(store, truths)
    assert outcome in ("refused", f"{2 * SAMPLES} samples", f"{3 * SAMPLES} samples")
    assert was_killed or moment == "late", "the run ended before the chosen moment"
