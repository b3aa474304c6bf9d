"""Crash consistency of FRV studies (issue 17): a study process SIGKILLed just before any
one of its file-system writes — zarr's file writes and deletes, directory renames and
removals, in every write phase (library, intervals, samples, commit record, moving a new
study into place, discarding a killed write's rows) — leaves the study as it was before
the run or as the run would have left it. Opening it discards the killed write's rows;
the next run then completes bit-identical to an uninterrupted run (library, interval
dictionary, every sample's hulls, cuts and bins, the counts), and no temporary file or
folder is left. Never silently different hulls.

The kills are real (``SIGKILL`` of a forked child, at a chosen write, deterministically);
the truth is the same study run without interruption."""

from __future__ import annotations

import multiprocessing
import os
import shutil
import signal
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zarr.storage._local as zarr_local

from fuzzygait.io import atomic
from fuzzygait.uncertainty import FunctionModel
from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy, StudyOptions
from fuzzygait.uncertainty.frv.store import read_meta

TIMES = np.linspace(0.0, 10.0, 21)
SPEC = FRVSpec("p", 1.0, alphas=(0.0, 0.5, 1.0))
SETTINGS = StudyOptions(n_disc=8, seed=1, chunk=64)
FIRST, MORE = 20, 150  # the first batch's grid is extended by the second: every phase writes
VOLATILE = ("wall_time", "last_wall_time", "last_forward_simulations", "last_new_intervals")


def model() -> FunctionModel:
    """f(p, t) = sin(p t) with its sensitivity (the study refines: library slopes too)."""
    return FunctionModel(lambda p: np.sin(p[..., :1] * TIMES), TIMES, lambda p: (TIMES * np.cos(p[0] * TIMES))[:, None])


# ---------------------------------------------------------------- the runs (as frv-sim does them)
def run_once(store: Path, n: int, seed: int = SETTINGS.seed) -> None:
    """Create the study with ``n`` samples, or extend an existing one by ``n``."""
    if store.exists():
        FRVStudy.open(store, model()).add_samples(n)
    else:
        FRVStudy.create(model(), SPEC, n, replace(SETTINGS, seed=seed), store=store)


def overwrite_once(store: Path, n: int) -> None:
    FRVStudy.create(model(), SPEC, n, replace(SETTINGS, seed=11, overwrite=True), store=store)


def snapshot(store: Path) -> dict[str, Any]:
    """Everything a study holds, in a canonical order: the committed samples, the library
    and the dictionary sorted by bin / key, the commit record without wall times."""
    study = FRVStudy.open(store, model())
    lib, table = study.library(), study.intervals()
    order = np.lexsort((table["right"].to_numpy(), table["left"].to_numpy()))
    meta = read_meta(store)
    meta["counts"] = {k: v for k, v in meta["counts"].items() if k not in VOLATILE}
    return {
        "hull": study.hulls()["hull"].to_numpy(), "cut": study.samples()["cut"].to_numpy(),
        "bin": study.samples()["bin"].to_numpy(), "value": lib["value"].to_numpy(), "slope": lib["slope"].to_numpy(),
        "centre": lib["centre"].to_numpy(), "lib_bin": lib["bin"].to_numpy(),
        **{k: table[k].to_numpy()[order] for k in ("left", "right", "lower", "upper")},
        "meta": meta,
    }  # fmt: skip


def same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return a.keys() == b.keys() and all(
        a[k] == b[k] if k == "meta" else (a[k].shape == b[k].shape and np.array_equal(a[k], b[k])) for k in a
    )


# ---------------------------------------------------------------- the kill switch
def _phase(target: str) -> str:
    parts = Path(target).parts
    for group in ("library", "intervals", "samples"):
        if group in parts:
            return group
    return "commit"


def arm(kill_at: int, events: list[tuple[str, str]] | None = None) -> None:
    """Count this process's file-system writes; SIGKILL it just before write ``kill_at``
    (a file write first leaves a half-written temporary, as a kill inside it would).
    With ``events``, record ``(phase, path)`` of each write instead."""
    count = [0]

    def event(phase: str, target: Any, torn: bytes | None = None) -> None:
        count[0] += 1
        if events is not None:
            events.append((phase, str(target)))
        elif count[0] == kill_at:
            if torn is not None:
                Path(target).parent.mkdir(parents=True, exist_ok=True)
                Path(f"{target}.0123.partial").write_bytes(torn[: len(torn) // 2])
            os.kill(os.getpid(), signal.SIGKILL)

    def wrap(module: Any, name: str, phase: Callable[[Any], str]) -> None:
        original = getattr(module, name)

        def hooked(*args: Any, **kwargs: Any) -> Any:
            event(phase(args[0]), args[0])
            return original(*args, **kwargs)

        setattr(module, name, hooked)

    put = zarr_local._put

    def hooked_put(path: Path, value: Any, exclusive: bool = False) -> int:
        event(_phase(str(path)), path, bytes(value.as_buffer_like()))
        return put(path, value, exclusive=exclusive)

    zarr_local._put = hooked_put
    delete = zarr_local.LocalStore.delete

    async def hooked_delete(self: Any, key: str) -> None:
        event("discard", key)
        await delete(self, key)

    zarr_local.LocalStore.delete = hooked_delete  # type: ignore[method-assign]
    wrap(os, "rename", lambda path: "publish")
    wrap(atomic, "exchange", lambda path: "publish")
    wrap(shutil, "rmtree", lambda path: "discard")


def _child(kill_at: int, action: Callable[[Path, int], None], store: Path, n: int) -> None:
    arm(kill_at)
    action(store, n)


def killed(action: Callable[[Path, int], None], store: Path, n: int, kill_at: int) -> None:
    """Run ``action(store, n)`` in a forked child killed before write ``kill_at``."""
    child = multiprocessing.get_context("fork").Process(target=_child, args=(kill_at, action, store, n))
    child.start()
    child.join(120)
    assert child.exitcode == -signal.SIGKILL, f"write {kill_at} was not reached (exit {child.exitcode})"


def writes(
    action: Callable[[Path, int], None], store: Path, n: int, monkeypatch: pytest.MonkeyPatch
) -> list[tuple[str, str]]:
    """The writes of an uninterrupted ``action`` (run here, on a copy of ``store``)."""
    events: list[tuple[str, str]] = []
    with monkeypatch.context() as patch:
        for module, name in ((zarr_local, "_put"), (zarr_local.LocalStore, "delete"), (os, "rename"),
                             (atomic, "exchange"), (shutil, "rmtree")):  # fmt: skip
            patch.setattr(module, name, getattr(module, name))  # restored afterwards
        arm(0, events)
        action(store, n)
    return events


def moments(events: list[tuple[str, str]], per_phase: int | None) -> list[int]:
    """1-based write indices: every one, or the first, middle and last of each phase."""
    if per_phase is None:
        return list(range(1, len(events) + 1))
    chosen: set[int] = set()
    for phase in {p for p, _ in events}:
        idx = [i + 1 for i, (p, _) in enumerate(events) if p == phase]
        chosen.update(idx[j] for j in np.linspace(0, len(idx) - 1, min(per_phase, len(idx))).round().astype(int))
    return sorted(chosen)


# ---------------------------------------------------------------- the scenarios
class Scenario:
    """A run on a study (``before``: None = no study yet), its uninterrupted truth after
    one run and after the same command once more (what the rerun gives when the killed
    run had finished)."""

    def __init__(self, root: Path, name: str, before: int | None, action: Callable[[Path, int], None],
                 monkeypatch: pytest.MonkeyPatch, killed_at: int = 0) -> None:  # fmt: skip
        self.root, self.name, self.before, self.action = root / name, name, before, action
        self.rerun = overwrite_once if action is overwrite_once else run_once
        self.root.mkdir()
        base = self.root / "base.zarr"
        if before is not None:
            run_once(base, before)
        if killed_at:  # the study as an earlier extension killed before write ``killed_at`` left it
            killed(run_once, base, MORE, killed_at)
        self.truth_before = snapshot(self._copy(base, "before.zarr")) if before is not None else None
        once = self._copy(base, "once.zarr")
        action(once, MORE)
        self.truth_once = snapshot(once)
        self.rerun(once, MORE)
        self.truth_twice = snapshot(once)
        probe = self._copy(base, "probe.zarr")
        self.events = writes(action, probe, MORE, monkeypatch)
        self.base = base

    def _copy(self, base: Path, name: str) -> Path:
        target = self.root / name
        if base.exists():
            shutil.copytree(base, target)
        return target

    def check_kill(self, kill_at: int) -> str:
        """Kill the run before write ``kill_at``, look, run again, compare; returns what
        the kill left ("before" or "after")."""
        work = self.root / f"k{kill_at}"
        work.mkdir()
        store = self._copy(self.base, f"k{kill_at}/s.zarr")
        killed(self.action, store, MORE, kill_at)
        if not store.exists():
            assert self.truth_before is None, "the previous study is gone"
            left = "before"
        else:
            seen = snapshot(store)  # opening discards the killed write's rows
            samples = {k: seen[k] for k in ("hull", "cut", "bin")}
            if self.truth_before is not None and all(
                np.array_equal(v, self.truth_before[k]) for k, v in samples.items()
            ):
                left = "before"
            else:
                assert all(np.array_equal(v, self.truth_once[k]) for k, v in samples.items()), "hulls differ"
                left = "after"
                assert same(seen, self.truth_once)
        self.rerun(store, MORE)
        final, truth = snapshot(store), self.truth_once if left == "before" else self.truth_twice
        assert same(final, truth), (kill_at, [k for k in final if not same({k: final[k]}, {k: truth[k]})])
        assert sorted(p.name for p in work.iterdir()) == ["s.zarr"], "temporaries left beside the study"
        assert not list(store.rglob("*.partial")), "zarr temporaries left in the study"
        return left


_BUILT: dict[str, Scenario] = {}


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("crash")


def scenario(root: Path, name: str) -> Scenario:
    """The scenario ``name``, built once per test module."""
    key = f"{root}:{name}"
    if key not in _BUILT:
        with pytest.MonkeyPatch.context() as patch:
            if name == "repair":  # a second kill while the first one's half-written library rows are discarded
                library = [i + 1 for i, (phase, _) in enumerate(scenario(root, "extend").events) if phase == "library"]
                _BUILT[key] = Scenario(root, name, FIRST, run_once, patch, killed_at=library[len(library) // 2])
            else:
                before = None if name == "create" else FIRST
                _BUILT[key] = Scenario(root, name, before, overwrite_once if name == "overwrite" else run_once, patch)
    return _BUILT[key]


def test_an_extension_killed_in_each_phase_completes_bit_identical(root: Path) -> None:
    extend = scenario(root, "extend")
    assert {p for p, _ in extend.events} == {"library", "intervals", "samples", "commit"}
    # the extension simulates new bins and finds new intervals: it writes the library and the dictionary
    assert extend.truth_once["value"].shape[0] > extend.truth_before["value"].shape[0]
    assert extend.truth_once["left"].shape[0] > extend.truth_before["left"].shape[0]
    assert [extend.check_kill(k) for k in moments(extend.events, 1)] == ["before"] * 4


@pytest.mark.slow
@pytest.mark.parametrize("name", ["create", "extend", "overwrite", "repair"])
def test_killed_at_every_phase(root: Path, name: str) -> None:
    """5 writes of each phase (first, last and evenly between: about 20-25 kills of the
    90-140 writes of each run) of a new study, an extension, an overwrite and the repair
    after a kill."""
    run = scenario(root, name)
    expected = {"library", "intervals", "samples", "commit"}
    assert {p for p, _ in run.events} == expected | {"create": {"publish", "discard"},
                                                     "overwrite": {"publish", "discard"},
                                                     "repair": {"discard"}}.get(name, set())  # fmt: skip
    assert all(sum(p == phase for p, _ in run.events) >= 3 for phase in expected)
    chosen = moments(run.events, 5)
    outcomes = {k: run.check_kill(k) for k in chosen if not (run.root / f"k{k}").exists()}
    # a kill leaves the new study only once it is in place (after the rename / the exchange)
    published = next((i + 1 for i, (p, _) in enumerate(run.events) if p == "publish"), len(run.events) + 1)
    # until the run's first commit record (or the publishing rename) the old study is what a kill leaves; from
    # there on the kill may leave either, and the rerun gives the same numbers in both cases (check_kill)
    first_commit = next(i + 1 for i, (p, _) in enumerate(run.events) if p in ("commit", "publish"))
    assert all(outcomes[k] == "before" for k in outcomes if k <= min(first_commit, published)), outcomes
    assert all(outcomes[k] == "after" for k in outcomes if k > published), outcomes
    assert len(outcomes) >= 3 * len(expected)
