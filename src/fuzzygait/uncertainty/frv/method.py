"""What an FRV study does differently for one FRV parameter and for several: the internal
strategy an :class:`~fuzzygait.uncertainty.frv.FRVStudy` holds (composition, one per
study, chosen from its commit record).

* :class:`~fuzzygait.uncertainty.frv.single.OneParameter` (thesis Table 5.3): a
  dictionary of occurring intervals over a contiguous library of bin centres, α = 1 by
  the bounded cubic Hermite interpolant on the grouping grid;
* :class:`~fuzzygait.uncertainty.frv.multi.SeveralParameters`: boxes of per-parameter
  intervals over a library of grid points, α = 1 on the peak lattice
  (:mod:`fuzzygait.uncertainty.frv.peaks`).

The study keeps what both share (the commit record's settings, counts, row counts,
grids, the evaluator, the sample loop and the store); the strategy keeps its own
in-memory library and dictionary, draws and groups the samples in its layout, completes
the library and dictionary for new samples and assembles their hulls.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from fuzzygait.uncertainty.frv.grouping import Grid
from fuzzygait.uncertainty.frv.samples import BLOCK, FRVSpec, generate_box_samples

if TYPE_CHECKING:
    from fuzzygait.uncertainty.frv.options import StudyOptions
    from fuzzygait.uncertainty.frv.study import FRVStudy


def _blocks(start: int, stop: int, chunk: int) -> Iterator[tuple[int, int]]:
    """Sample ranges aligned to multiples of ``chunk`` (so appends fill zarr chunks)."""
    a = start
    while a < stop:
        b = min(stop, (a // chunk + 1) * chunk)
        yield a, b
        a = b


def sample_ranges(specs: Sequence[FRVSpec], seed: int, start: int, n: int) -> np.ndarray:
    """``(n_params, 2)``: per parameter the smallest and largest α-cut end of samples
    ``start … start+n−1`` (pass 1), :data:`~fuzzygait.uncertainty.frv.samples.BLOCK`
    samples at a time (parameter ``k`` is stream ``k``, as the study draws them)."""
    out = np.array([[np.inf, -np.inf]] * len(specs))
    for a, b in _blocks(start, start + n, BLOCK):
        ends = generate_box_samples(specs, b - a, seed, a)[:, :, 0, :]
        out[:, 0] = np.minimum(out[:, 0], ends[:, :, 0].min(axis=0))
        out[:, 1] = np.maximum(out[:, 1], ends[:, :, 1].max(axis=0))
    return out


class Method:
    """The part of an FRV study that depends on how many FRV parameters it has.

    Attributes:
        study: the study this strategy works for (its grids, counts, rows, evaluator).
        axes: the cut and bin dimensions between ``sample`` and ``alpha`` in the store
            (``()`` for one parameter, ``("parameter",)`` for several).
        default_disc: ``N_p-disc`` per parameter when the options give none.
        peak_refine: the α = 1 lattice per parameter (1: the grouping grid; None: not
            yet chosen).
        peak_tolerance: the largest α = 1 interpolation error, as a fraction of the
            output's spread, when the lattice is chosen (None: no lattice to choose).
    """

    axes: tuple[str, ...] = ()
    default_disc: int = 100
    peak_refine: list[int] | None
    peak_tolerance: float | None

    def __init__(self, study: FRVStudy, meta: dict[str, Any]) -> None:
        self.study = study

    # ------------------------------------------------------------------ the record
    @staticmethod
    def listed(value: Any) -> list[Any]:
        """A per-parameter record entry as a list (a one-parameter record holds the entry)."""
        raise NotImplementedError

    @staticmethod
    def recorded(values: Sequence[Any]) -> Any:
        """Per-parameter ``values`` as the record holds them."""
        raise NotImplementedError

    @classmethod
    def settings(cls, options: StudyOptions, n_params: int) -> tuple[dict[str, Any], Sequence[Grid] | None]:
        """The record's method settings (after ``refine`` and ``hulls``) from a new
        study's ``options``, and the grids they give (None: from the first batch).

        Raises:
            ParameterError: an option does not fit ``n_params`` parameters.
        """
        return {}, None

    def commit_entries(self) -> dict[str, Any]:
        """The method's entries of a commit (after ``refine``); the counts it adds are
        updated in the study's counts."""
        return {}

    # ------------------------------------------------------------------ samples
    def draw(self, start: int, n: int) -> np.ndarray:
        """Samples ``start … start+n−1``: α-cuts ``(n, *axes, n_alpha, 2)``."""
        raise NotImplementedError

    def group(self, cuts: np.ndarray) -> np.ndarray:
        """The bins of ``cuts`` on the study's grids (same shape)."""
        raise NotImplementedError

    def parameter_coords(self) -> dict[str, Any]:
        """The coordinates of :attr:`axes` for the first write of the samples."""
        return {}

    # ------------------------------------------------------------------ library and dictionary
    def load(self) -> None:
        """Read the committed library and dictionary of an opened store into memory."""
        raise NotImplementedError

    def complete(self, start: int, stop: int) -> tuple[int, int]:
        """Pass 2 for samples ``start … stop−1``: find their occurring intervals (boxes),
        simulate what the library lacks for them, add the new dictionary entries.
        Returns ``(forward simulations, new entries)``."""
        raise NotImplementedError

    def assemble(self, bins: np.ndarray, peaks: np.ndarray) -> tuple[np.ndarray, int]:
        """Hulls ``(nb, n_alpha, 2, n_nodes)`` of grouped samples ``bins`` with raw peaks
        ``peaks`` (``bins[..., -1, 0]``'s values), nesting-repaired, and the number of
        values the repair changed."""
        raise NotImplementedError

    def library(self) -> xr.Dataset:
        """The stored library (committed rows)."""
        raise NotImplementedError

