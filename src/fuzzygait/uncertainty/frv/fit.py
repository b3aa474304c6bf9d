"""Reading a stored FRV study back and fitting distributions to its output (thesis
§2.7.4 steps 8–9), streaming over the stored sample chunks."""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import stats

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.frv.method import _blocks
from fuzzygait.uncertainty.frv.samples import DISTRIBUTIONS, sample_increments
from fuzzygait.uncertainty.frv.store import read_group, read_meta
from fuzzygait.uncertainty.frv.study import FRVStudy

#: a study of one or several FRVs, or its store path
StudyOrPath = FRVStudy | str | os.PathLike[str]


def _store_path(store: StudyOrPath) -> Path:
    return store.path if isinstance(store, FRVStudy) else Path(store)


def stored_samples(store: StudyOrPath) -> int:
    """Number of samples in a stored study."""
    return int(read_meta(_store_path(store))["n_samples"])


def iter_hull_blocks(store: StudyOrPath, data: str = "hulls") -> Iterator[np.ndarray]:
    """The stored output block by block (one zarr chunk of samples at a time):
    ``(nb, n_alpha, 2, n_time)`` hulls, or their l_α r_α-increments
    (:func:`sample_increments` per time node) with ``data="increments"``."""
    if data not in ("hulls", "increments"):
        raise ParameterError(f"data must be 'hulls' or 'increments'; got {data!r}")
    path = _store_path(store)
    meta = read_meta(path)
    hull = read_group(path, "samples")["hull"]
    for a, b in _blocks(0, meta["n_samples"], meta["chunk"]):
        block = hull.isel(sample=slice(a, b)).to_numpy()
        yield block if data == "hulls" else np.moveaxis(sample_increments(np.moveaxis(block, 3, 1)), 1, 3)


class _Moments:
    """Running count, mean and sum of squared deviations (Chan et al.'s merge)."""

    def __init__(self) -> None:
        self.n: int = 0
        self.mean: np.ndarray | float = 0.0
        self.m2: np.ndarray | float = 0.0

    def add(self, block: np.ndarray) -> None:
        nb = block.shape[0]
        mean_b = block.mean(axis=0)
        m2_b = ((block - mean_b) ** 2).sum(axis=0)
        n = self.n + nb
        delta = mean_b - self.mean
        self.mean = self.mean + delta * (nb / n)
        self.m2 = self.m2 + m2_b + delta**2 * (self.n * nb / n)
        self.n = n

    @property
    def variance(self) -> np.ndarray | float:
        return self.m2 / self.n


def fit_distributions(store: StudyOrPath, kind: str = "normal", data: str = "hulls",
                      exact_nodes: Sequence[int] = ()) -> xr.Dataset:  # fmt: skip
    """Fit a distribution per ``(alpha, bound, time)`` to the samples' output (step 9),
    streaming over the stored sample chunks.

    Args:
        store: a study or its store path.
        kind: ``"normal"``: ``mean`` and ``std`` (ddof 0 — the exact maximum-likelihood
            estimates, from running sums merged per block). ``"beta"``: each series is
            normalised to [0, 1] by its own min and max (``loc``, ``scale``; first pass —
            the thesis leaves the normalisation open, this is the per-(α, bound, time)
            choice), then method-of-moments ``a = m·c``, ``b = (1−m)·c`` with
            ``c = m(1−m)/v − 1`` (second pass); NaN where a series is constant.
        data: ``"hulls"`` (the α-cut values ``f_{α,l/r}``) or ``"increments"`` (the
            output's l_α r_α-increments; at α = 1 the peak value).
        exact_nodes: with ``kind="beta"``, output time-node indices at which
            ``scipy.stats.beta.fit`` (MLE, ``floc=0, fscale=1``) is also run on the
            normalised values compressed to ``(x(n−1) + ½)/n`` (Smithson & Verkuilen) —
            the min and max map to 0 and 1 exactly, where the likelihood is degenerate.

    Returns:
        Dataset over ``alpha``, ``bound``, ``time`` (``mean``, ``std`` or ``a``, ``b``,
        ``loc``, ``scale``; plus ``a_mle``, ``b_mle`` over ``exact_time``), attributes
        ``kind``, ``data``, ``n_samples``.
    """
    if kind not in DISTRIBUTIONS:
        raise ParameterError(f"kind must be 'normal' or 'beta'; got {kind!r}")
    path = _store_path(store)
    n_samples = read_meta(path)["n_samples"]
    coords = read_group(path, "samples").drop_dims("sample").coords
    dims = ("alpha", "bound", "time")
    attrs = {"kind": kind, "data": data, "n_samples": n_samples}
    if kind == "normal":
        moments = _Moments()
        for block in iter_hull_blocks(path, data):
            moments.add(block)
        return xr.Dataset({"mean": (dims, moments.mean), "std": (dims, np.sqrt(moments.variance))},
                          coords=coords, attrs=attrs)  # fmt: skip
    low: np.ndarray | None = None
    high: np.ndarray | None = None
    for block in iter_hull_blocks(path, data):  # pass 1: normalisation
        b_lo, b_hi = block.min(axis=0), block.max(axis=0)
        low = b_lo if low is None else np.minimum(low, b_lo)
        high = b_hi if high is None else np.maximum(high, b_hi)
    assert low is not None and high is not None  # a stored study has at least one sample
    scale = high - low
    safe = np.where(scale > 0, scale, 1.0)
    moments = _Moments()
    for block in iter_hull_blocks(path, data):  # pass 2: moments of the normalised values
        moments.add((block - low) / safe)
    m, v = moments.mean, moments.variance
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where((scale > 0) & (v > 0), m * (1.0 - m) / v - 1.0, np.nan)
    ds = xr.Dataset({"a": (dims, m * c), "b": (dims, (1.0 - m) * c), "loc": (dims, low), "scale": (dims, scale)},
                    coords=coords, attrs=attrs)  # fmt: skip
    nodes = [int(j) for j in exact_nodes]
    if nodes:
        n_alpha = ds.sizes["alpha"]
        columns = np.concatenate([block[..., nodes] for block in iter_hull_blocks(path, data)])  # (n, n_alpha, 2, k)
        a_mle = np.full((n_alpha, 2, len(nodes)), np.nan)
        b_mle = np.full_like(a_mle, np.nan)
        for index in np.ndindex(a_mle.shape):
            j = nodes[index[2]]
            if scale[index[0], index[1], j] <= 0:
                continue
            x = (columns[:, index[0], index[1], index[2]] - low[index[0], index[1], j]) / scale[index[0], index[1], j]
            x = (x * (x.size - 1) + 0.5) / x.size
            a_mle[index], b_mle[index], _, _ = stats.beta.fit(x, floc=0.0, fscale=1.0)
        ds["a_mle"] = (("alpha", "bound", "exact_time"), a_mle)
        ds["b_mle"] = (("alpha", "bound", "exact_time"), b_mle)
        ds = ds.assign_coords(exact_time=("exact_time", ds["time"].to_numpy()[nodes]), exact_node=("exact_time", nodes))
    return ds
