"""The Graph Follower algorithm's library: every evaluated parameter vector with its
whole target-output trajectory (and sensitivities, when computed)."""

from __future__ import annotations

import numpy as np


class Library:
    """Growing arrays of parameters ``(m, n_p)``, trajectories ``(m, n_time)`` and
    optional sensitivities ``(m, n_time, n_p)``."""

    def __init__(self, n_p: int, n_time: int, scale: np.ndarray) -> None:
        self.n_p, self.n_time = n_p, n_time
        self.scale = np.asarray(scale, dtype=float)
        self._size = 0
        self._p_buf = np.empty((16, n_p))
        self._f_buf = np.empty((16, n_time))
        self._jac: list[np.ndarray | None] = []

    def __len__(self) -> int:
        return self._size

    @property
    def _p(self) -> np.ndarray:
        return self._p_buf[: self._size]

    @property
    def _f(self) -> np.ndarray:
        return self._f_buf[: self._size]

    @property
    def parameters(self) -> np.ndarray:
        """``(m, n_p)`` stored parameters (a view)."""
        return self._p

    @property
    def trajectories(self) -> np.ndarray:
        """``(m, n_time)`` stored trajectories (a view)."""
        return self._f

    def sensitivities(self, index: int) -> np.ndarray | None:
        return self._jac[index]

    def add(self, p: np.ndarray, f: np.ndarray, jac: np.ndarray | None = None) -> int:
        """Store one evaluation; returns its index."""
        if self._size == self._p_buf.shape[0]:  # grow by doubling: amortised O(1) adds
            self._p_buf = np.concatenate([self._p_buf, np.empty_like(self._p_buf)])
            self._f_buf = np.concatenate([self._f_buf, np.empty_like(self._f_buf)])
        self._p_buf[self._size] = p
        self._f_buf[self._size] = f
        self._jac.append(None if jac is None else np.asarray(jac, dtype=float))
        self._size += 1
        return self._size - 1

    def closest(self, p: np.ndarray) -> tuple[int, float]:
        """Index of the stored parameter closest to ``p`` and that distance, measured as
        the largest relative component difference ``|p_i − p_lib,i| / scale_i``
        (Eq. 2.24)."""
        if not len(self):
            return -1, np.inf
        distance = np.max(np.abs(self._p - p) / self.scale, axis=1)
        index = int(np.argmin(distance))
        return index, float(distance[index])

    def is_novel(self, p: np.ndarray, tolerance: float) -> bool:
        """Whether ``p`` differs from every stored parameter by more than ``tolerance``
        (relative, in at least one component)."""
        return self.closest(p)[1] > tolerance

    def best(self, admissible: np.ndarray, node: int, sense: float) -> int:
        """Index of the admissible entry with the extreme output at ``node``
        (``sense`` +1: largest, −1: smallest)."""
        candidates = np.flatnonzero(admissible)
        values = sense * self._f[candidates, node]
        return int(candidates[np.argmax(values)])
