"""The Graph Follower algorithm's library: every evaluated parameter vector with its
whole target-output trajectory (and sensitivities, when computed).

Sized for long runs (10⁴ entries × 2000 nodes): arrays grow by doubling, sensitivities
are kept only at the optimisation nodes (the only rows the linearisation reads) and in
float32, the novelty test (Eq. 2.24) uses a k-d tree in the scaled max-norm, and
membership of the entries in an α-level set is cached per set and only computed for new
entries.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # imported where a tree is built: scipy.spatial costs a worker process 0.16 s to import
    from scipy.spatial import cKDTree

#: Entries added since the last k-d tree build that are scanned linearly before the
#: tree is rebuilt.
_TREE_SLACK = 64


class Library:
    """Parameters ``(m, n_p)``, trajectories ``(m, n_time)`` and sensitivities at the
    optimisation nodes ``(m, n_nodes, n_p)`` (float32; None for entries stored without).

    Args:
        n_p: number of parameters.
        n_time: number of time nodes.
        scale: per-parameter scale of the relative novelty distance.
        nodes: the time nodes whose sensitivity rows are kept (default: all).
    """

    def __init__(self, n_p: int, n_time: int, scale: np.ndarray, nodes: np.ndarray | None = None) -> None:
        self.n_p, self.n_time = n_p, n_time
        self.scale = np.asarray(scale, dtype=float)
        self.nodes = np.arange(n_time) if nodes is None else np.asarray(nodes, dtype=int)
        self._row = np.full(n_time, -1)
        self._row[self.nodes] = np.arange(self.nodes.size)
        self._size = 0
        self._p_buf = np.empty((16, n_p))
        self._f_buf = np.empty((16, n_time))
        self._jac: list[np.ndarray | None] = []
        self._tree: cKDTree | None = None
        self._tree_size = 0
        self._membership: dict[object, list[bool]] = {}

    def __len__(self) -> int:
        return self._size

    @property
    def parameters(self) -> np.ndarray:
        """``(m, n_p)`` stored parameters (a view)."""
        return self._p_buf[: self._size]

    @property
    def trajectories(self) -> np.ndarray:
        """``(m, n_time)`` stored trajectories (a view)."""
        return self._f_buf[: self._size]

    def has_sensitivities(self, index: int) -> bool:
        return self._jac[index] is not None

    def gradient(self, index: int, node: int) -> np.ndarray:
        """``df/dp`` of entry ``index`` at time node ``node`` (an optimisation node)."""
        rows = self._jac[index]
        if rows is None or self._row[node] < 0:
            raise KeyError(f"no sensitivities of entry {index} at node {node}")
        return rows[self._row[node]].astype(float)

    def add(self, p: np.ndarray, f: np.ndarray, jac: np.ndarray | None = None) -> int:
        """Store one evaluation (``jac``: ``(n_time, n_p)`` or None); returns its index."""
        if self._size == self._p_buf.shape[0]:  # grow by doubling: amortised O(1) adds
            self._p_buf = np.concatenate([self._p_buf, np.empty_like(self._p_buf)])
            self._f_buf = np.concatenate([self._f_buf, np.empty_like(self._f_buf)])
        self._p_buf[self._size] = p
        self._f_buf[self._size] = f
        self._jac.append(None if jac is None else np.asarray(jac)[self.nodes].astype(np.float32))
        self._size += 1
        return self._size - 1

    # ------------------------------------------------------------------ novelty
    def closest(self, p: np.ndarray) -> tuple[int, float]:
        """Index of the stored parameter closest to ``p`` and that distance, measured as
        the largest relative component difference ``|p_i − p_lib,i| / scale_i``
        (Eq. 2.24)."""
        if not self._size:
            return -1, np.inf
        if self._size - self._tree_size > _TREE_SLACK:
            from scipy.spatial import cKDTree

            self._tree = cKDTree(self.parameters / self.scale)
            self._tree_size = self._size
        best, distance = -1, np.inf
        if self._tree is not None:
            d, i = self._tree.query(p / self.scale, p=np.inf)
            best, distance = int(i), float(d)
        recent = self.parameters[self._tree_size :]
        if recent.size:
            d = np.max(np.abs(recent - p) / self.scale, axis=1)
            k = int(np.argmin(d))
            if d[k] < distance:
                best, distance = self._tree_size + k, float(d[k])
        return best, distance

    def is_novel(self, p: np.ndarray, tolerance: float) -> bool:
        """Whether ``p`` differs from every stored parameter by more than ``tolerance``
        (relative, in at least one component)."""
        return self.closest(p)[1] > tolerance

    # ------------------------------------------------------------------ membership
    def inside(self, key: object, contains: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """Boolean mask of the entries inside a set, cached under ``key``; ``contains``
        maps ``(k, n_p)`` parameters to ``(k,)`` booleans and is called for new entries
        only."""
        known = self._membership.setdefault(key, [])
        if len(known) < self._size:
            known.extend(contains(self.parameters[len(known) :]).tolist())
        return np.asarray(known, dtype=bool)

    def best(self, admissible: np.ndarray, node: int, sense: float) -> int:
        """Index of the admissible entry with the extreme output at ``node``
        (``sense`` +1: largest, −1: smallest)."""
        candidates = np.flatnonzero(admissible)
        values = sense * self._f_buf[candidates, node]
        return int(candidates[np.argmax(values)])
