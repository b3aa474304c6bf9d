"""Parameter rows of a model recipe evaluated on an
:class:`~fuzzygait.uncertainty.execution.Evaluator`'s workers (:class:`RecipeBatch`), and
such a batch as a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel`
(:class:`EvaluatedModel`)."""

from __future__ import annotations

import math
import os
import uuid
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.execution.errors import ParallelEvaluationError
from fuzzygait.uncertainty.execution.workers import ModelRecipe, Slot, evaluate_rows, probe
from fuzzygait.uncertainty.protocol import MANY, NODES, SENSITIVITIES, Evaluation, Output

if TYPE_CHECKING:
    from fuzzygait.uncertainty.execution.evaluator import Evaluator


class RecipeBatch:
    """Parameter rows of one recipe's model on an :class:`Evaluator`.

    Args:
        evaluator: where the rows run.
        recipe: a :class:`~fuzzygait.uncertainty.execution.workers.ModelRecipe`.
        sensitivities: return ``(values, sensitivities)`` — ``(k, n_time)`` and
            ``(k, n_time, n_p)``.
        store: directory of the result files. None: a private temporary directory, and
            results are returned as in-memory arrays. A directory: each call's results stay
            there (``batch-NNNNN-values.npy``, ``…-sensitivities.npy``) and are returned as
            read-only memory maps. For a remote cluster it must be on a shared file system.
        chunk: parameter rows per task (None: about four tasks per worker).

    :attr:`last_statistics` lists, per task of the last call, the rows, the worker process
    and host, and the seconds spent building the model (0 when cached) and evaluating;
    :attr:`builds` lists every model build this batch caused (one per process at most).
    """

    def __init__(self, evaluator: Evaluator, recipe: ModelRecipe, *, sensitivities: bool = False,
                 store: str | os.PathLike[str] | None = None, chunk: int | None = 1) -> None:  # fmt: skip
        if not callable(getattr(recipe, "build", None)) or not hasattr(recipe, "key"):
            raise ParameterError("recipe must have build() and a hashable key (see ModelRecipe)")
        try:
            hash(recipe.key)
        except TypeError:
            raise ParameterError(f"the recipe's key must be hashable; got {recipe.key!r}") from None
        if chunk is not None and (int(chunk) != chunk or chunk < 1):
            raise ParameterError(f"chunk must be a positive integer or None; got {chunk}")
        self.evaluator, self.recipe = evaluator, recipe
        self.sensitivities = bool(sensitivities)
        self.store = None if store is None else Path(store)
        self.chunk = None if chunk is None else int(chunk)
        self.last_statistics: list[dict[str, Any]] = []
        self.builds: list[dict[str, Any]] = []
        self._info: dict[str, Any] | None = None
        self._calls = 0

    def _describe(self) -> dict[str, Any]:
        if self._info is None:
            info = self.evaluator.submit_all(probe, [(self.recipe, self.sensitivities)], "probe")[0]
            if "error" in info:
                raise ParallelEvaluationError(f"building the model failed: {info['error']}",
                                              error_type=info["error_type"])  # fmt: skip
            if info["build_seconds"]:
                self.builds.append({key: info[key] for key in ("pid", "host", "build_seconds")})
            if self.sensitivities and not info["sensitivities"]:
                raise ParameterError("the model has no sensitivities; use sensitivities=False")
            self._info = info
        return self._info

    @property
    def times(self) -> np.ndarray:
        """The model's time nodes (a worker builds the model on first access)."""
        return np.asarray(self._describe()["times"])

    @property
    def description(self) -> dict[str, Any]:
        """The model's parameter names, output and capabilities, as a worker reports them."""
        return self._describe()

    def _directory(self) -> Path:
        if self.store is not None:
            self.store.mkdir(parents=True, exist_ok=True)
            return self.store
        return self.evaluator.tmpdir()

    def _blocks(self, k: int) -> list[tuple[int, int]]:
        size = self.chunk if self.chunk is not None else max(1, math.ceil(k / (4 * self.evaluator.n_workers())))
        return [(s, min(s + size, k)) for s in range(0, k, size)]

    def __call__(self, P: np.ndarray) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        P = np.asarray(P, dtype=float)
        if P.ndim != 2:
            raise ParameterError(f"P must be a 2-D array (rows = parameter vectors); got shape {P.shape}")
        if not np.all(np.isfinite(P)):
            bad = int(np.flatnonzero(~np.all(np.isfinite(P), axis=1))[0])
            raise ParameterError(f"parameter row {bad} is not finite: {P[bad].tolist()}")
        k, n_p = P.shape
        n_time = self.times.size
        directory = self._directory()
        self._calls += 1
        stem = f"batch-{self._calls:05d}-{uuid.uuid4().hex[:8]}" if self.store is None else f"batch-{self._calls:05d}"
        values = Slot.allocate(directory / f"{stem}-values.npy", (k, n_time))
        sens = Slot.allocate(directory / f"{stem}-sensitivities.npy", (k, n_time, n_p)) if self.sensitivities else None
        try:
            arguments = [(self.recipe, a, P[a:b], values, sens) for a, b in self._blocks(k)]
            statuses = sorted(self.evaluator.submit_all(evaluate_rows, arguments, "rows"), key=lambda s: s["start"])
            self._raise_first_error(statuses, P)
            out_values = self._read(values, statuses, "values")
            out_sens = self._read(sens, statuses, "sensitivities") if sens is not None else None
        finally:
            if self.store is None:
                for slot in (values, sens):
                    if slot is not None:
                        Path(slot.path).unlink(missing_ok=True)
        self.last_statistics = [
            {key: s[key] for key in ("start", "stop", "pid", "host", "build_seconds", "seconds")} for s in statuses
        ]
        self.builds += [
            {key: s[key] for key in ("pid", "host", "build_seconds")} for s in statuses if s["build_seconds"]
        ]
        return (out_values, out_sens) if out_sens is not None else out_values

    @staticmethod
    def _raise_first_error(statuses: Sequence[dict[str, Any]], P: np.ndarray) -> None:
        failed = [s for s in statuses if "error" in s]
        if not failed:
            return
        first = min(failed, key=lambda s: s["row"])
        row = int(first["row"])
        others = len(failed) - 1
        more = f" ({others} other task(s) failed too)" if others else ""
        raise ParallelEvaluationError(
            f"evaluating parameter row {row} {P[row].tolist()} failed: {first['error']}{more}",
            row=row, parameters=P[row].tolist(), error_type=first["error_type"],
        )  # fmt: skip

    def _read(self, slot: Slot, statuses: Sequence[dict[str, Any]], name: str) -> np.ndarray:
        returned = any(s.get(name) is not None for s in statuses)
        stored = np.load(slot.path, mmap_mode="r+" if returned else "r")
        for s in statuses:
            if s.get(name) is not None:  # a worker that could not see the store
                stored[s["start"]:s["stop"]] = s[name]
        if isinstance(stored, np.memmap) and stored.mode == "r+":
            stored.flush()
        if self.store is not None:
            return np.load(slot.path, mmap_mode="r")
        return np.array(stored)


class EvaluatedModel:
    """A :class:`RecipeBatch` as a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel`:
    every forward simulation runs on the evaluator's workers. Offers ``evaluate``,
    ``evaluate_many(P)`` and ``evaluate_nodes(P, nodes)`` (the batched direct strategy
    then evaluates each iteration's points in parallel; duplicate rows are simulated
    once)."""

    def __init__(self, batch: RecipeBatch) -> None:
        self.batch = batch
        info = batch.description
        self.times = np.asarray(info["times"], dtype=float)
        self.parameter_names: tuple[str, ...] = tuple(info["parameter_names"])
        self.output = Output(*info["output"])
        self.capabilities = frozenset({NODES, MANY} | ({SENSITIVITIES} if batch.sensitivities else set()))

    def evaluate_many(self, P: np.ndarray) -> np.ndarray:
        out = self.batch(np.atleast_2d(np.asarray(P, dtype=float)))
        return out[0] if isinstance(out, tuple) else out

    def evaluate_many_with_sensitivities(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rows of ``P`` in parallel with their sensitivities: ``(k, n_time)``, ``(k, n_time, n_p)``."""
        out = self.batch(np.atleast_2d(np.asarray(P, dtype=float)))
        if not isinstance(out, tuple):
            raise ParameterError("this model was made without sensitivities (Evaluator.model(..., sensitivities=True))")
        return np.asarray(out[0]), np.asarray(out[1])

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        out = self.batch(np.asarray(p, dtype=float).reshape(1, -1))
        if isinstance(out, tuple):
            return Evaluation(out[0][0], out[1][0] if sensitivities else None)
        return Evaluation(out[0])

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        P = np.atleast_2d(np.asarray(P, dtype=float))
        unique, inverse = np.unique(P, axis=0, return_inverse=True)
        trajectories = self.evaluate_many(unique)
        return trajectories[inverse.ravel(), np.asarray(nodes, dtype=int).ravel()]
