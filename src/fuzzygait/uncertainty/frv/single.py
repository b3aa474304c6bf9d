"""One FRV parameter (thesis §2.7.4, the Table 5.3 case): the
:class:`~fuzzygait.uncertainty.frv.method.Method` of an
:class:`~fuzzygait.uncertainty.frv.FRVStudy` whose record holds one ``spec``.

The library is contiguous: the model at bin centres ``first … first + m − 1`` (``value``
and, refining, ``slope`` = df/dp); the dictionary holds the occurring intervals, keyed by
their ``(left bin, right bin)`` pair (:func:`~fuzzygait.uncertainty.frv.grouping._encode`),
each one's hulls the extreme library values over its bins. α = 1 is the model at the
sample's own peak by the cubic Hermite interpolant of the library kept within its cell's
two values (``refine``), or the library value at the peak's bin.

Store entries (root): ``spec``, ``grid`` and ``n_disc`` as single entries;
``library``: ``value``, ``slope (bin, time)``, ``centre (bin)``; ``intervals``:
``left``, ``right (interval)``, ``lower``, ``upper (interval, time)``; ``samples``:
``cut``, ``bin (sample, alpha, bound)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.frv.evaluation import _run_evaluator
from fuzzygait.uncertainty.frv.grouping import _decode, _encode, _interval_keys, group
from fuzzygait.uncertainty.frv.hulls import _hermite_rows, interval_hulls
from fuzzygait.uncertainty.frv.method import Method, _blocks
from fuzzygait.uncertainty.frv.samples import generate_samples
from fuzzygait.uncertainty.frv.store import append as _append
from fuzzygait.uncertainty.frv.store import open_group
from fuzzygait.uncertainty.postprocess import repair_nesting

if TYPE_CHECKING:
    from fuzzygait.uncertainty.frv.study import FRVStudy

__all__ = ["OneParameter"]


class OneParameter(Method):
    """Intervals of one FRV parameter over a contiguous library of bin centres, α = 1
    by the bounded Hermite interpolant on the grouping grid (module docstring)."""

    def __init__(self, study: FRVStudy, meta: dict[str, Any]) -> None:
        super().__init__(study, meta)
        self.peak_refine = [1]  # α = 1 is interpolated on the grouping grid
        self.peak_tolerance = None
        nodes = study.nodes.size
        # library: contiguous bins lib_first … lib_first + m − 1
        self._lib_first = 0
        self._lib_values = np.empty((0, nodes))
        self._lib_slopes: np.ndarray | None = None
        # interval dictionary, sorted by key
        self._keys = np.empty(0, dtype=np.int64)
        self._int_lower = np.empty((0, nodes))
        self._int_upper = np.empty((0, nodes))

    @staticmethod
    def listed(value: Any) -> list[Any]:
        return [value]

    @staticmethod
    def recorded(values: Sequence[Any]) -> Any:
        (value,) = values
        return value

    # ------------------------------------------------------------------ samples
    def draw(self, start: int, n: int) -> np.ndarray:
        return generate_samples(self.study.specs[0], n, self.study.seed, start)

    def group(self, cuts: np.ndarray) -> np.ndarray:
        return group(cuts, self.study.grids[0])

    # ------------------------------------------------------------------ library and dictionary
    def library(self) -> xr.Dataset:
        """The library: ``value (bin, time)`` at bin ``centre`` (and ``slope``), sorted."""
        return open_group(self.study.path, "library", self.study.library_rows).sortby("bin")

    def load(self) -> None:
        study = self.study
        if study.library_rows:
            lib = self.library()
            self._lib_first = int(lib["bin"][0])
            self._lib_values = lib["value"].to_numpy()
            self._lib_slopes = lib["slope"].to_numpy() if "slope" in lib else None
        if study.interval_rows:
            table = study.intervals()
            left, right = table["left"].to_numpy(), table["right"].to_numpy()
            keys = _encode(left, right)
            order = np.argsort(keys)
            self._keys = keys[order]
            if study.stored_hulls:
                self._int_lower = table["lower"].to_numpy()[order]
                self._int_upper = table["upper"].to_numpy()[order]
            else:  # an older store: its hulls held the Hermite extrema; new samples use the library's
                self._int_lower, self._int_upper = self._interval_hulls(left[order], right[order])

    def complete(self, start: int, stop: int) -> tuple[int, int]:
        """Pass 2: the samples' bins and occurring intervals; the library is completed
        over their bin range and the new intervals are added."""
        grid = self.study.grids[0]
        keys = np.empty(0, dtype=np.int64)
        bin_lo, bin_hi = grid.last_bin, grid.first_bin
        for a, b in _blocks(start, stop, self.study.chunk):
            bins = self.group(self.draw(a, b - a))
            keys = np.union1d(keys, _interval_keys(bins))
            bin_lo, bin_hi = min(bin_lo, int(bins.min())), max(bin_hi, int(bins.max()))
        simulations = self._extend_library(bin_lo, bin_hi)
        new_keys = np.setdiff1d(keys, self._keys)
        self._add_intervals(new_keys)
        return simulations, int(new_keys.size)

    def _peak_values(self, peaks: np.ndarray) -> np.ndarray:
        """The model at raw ``peaks``: the Hermite interpolant of the library, each value
        within its cell's two library values."""
        assert self._lib_slopes is not None  # only called when refining with a library of slopes
        slopes = self._lib_slopes[..., 0] if self._lib_slopes.ndim == 3 else self._lib_slopes
        grid = self.study.grids[0]
        first = float(grid.centres(self._lib_first))
        return _hermite_rows(self._lib_values, slopes, first, grid.spacing, peaks, bounded=True)

    def _interval_hulls(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper hulls of the intervals of bins ``left … right``: the extreme
        library values over their bins, within the model's declared bounds."""
        lower, upper = interval_hulls(self._lib_values, left - self._lib_first, right - self._lib_first)
        return np.clip(lower, *self.study.bounds), np.clip(upper, *self.study.bounds)

    def _extend_library(self, bin_lo: int, bin_hi: int) -> int:
        """Simulate the bin centres of ``bin_lo … bin_hi`` not yet in the library (one
        evaluator call); returns the number of forward simulations."""
        study = self.study
        m = self._lib_values.shape[0]
        have_lo, have_hi = self._lib_first, self._lib_first + m - 1
        if m:
            bin_lo, bin_hi = min(bin_lo, have_lo), max(bin_hi, have_hi)
            missing = np.concatenate([np.arange(bin_lo, have_lo), np.arange(have_hi + 1, bin_hi + 1)])
        else:
            missing = np.arange(bin_lo, bin_hi + 1)
        if not missing.size:
            return 0
        centres = study.grids[0].centres(missing)
        F, J = _run_evaluator(study.evaluator, centres[:, None], study.n_time)
        if study.refine is None:
            study.refine = J is not None
        if study.refine and J is None:
            raise ParameterError("this study interpolates α = 1 with sensitivities; the evaluator returned none")
        values = F[:, study.nodes]
        slopes = J[:, study.nodes, 0] if study.refine and J is not None else None
        ds = xr.Dataset({"value": (("bin", "time"), values)},
                        coords={"bin": missing, "centre": ("bin", centres), "time": study.times})
        if slopes is not None:
            ds["slope"] = (("bin", "time"), slopes)
        _append(study.path, "library", ds, "bin")
        study.library_rows += int(missing.size)
        # merge into the contiguous in-memory library
        below = missing < have_lo if m else np.ones(missing.size, dtype=bool)
        self._lib_values = np.concatenate([values[below], self._lib_values, values[~below]])
        if slopes is not None:
            old = self._lib_slopes if self._lib_slopes is not None else np.empty((0, study.nodes.size))
            self._lib_slopes = np.concatenate([slopes[below], old, slopes[~below]])
        self._lib_first = bin_lo
        study.counts["forward_simulations"] += int(missing.size)
        study._write_meta()
        return int(missing.size)

    def _add_intervals(self, keys: np.ndarray) -> None:
        """Hulls of new intervals (sorted ``keys``) from the library; store them."""
        if not keys.size:
            return
        study = self.study
        left, right = _decode(keys)
        lower, upper = self._interval_hulls(left, right)
        ds = xr.Dataset({"left": ("interval", left), "right": ("interval", right),
                         "lower": (("interval", "time"), lower), "upper": (("interval", "time"), upper)},
                        coords={"time": study.times})  # fmt: skip
        _append(study.path, "intervals", ds, "interval")
        study.interval_rows += int(keys.size)
        all_keys = np.concatenate([self._keys, keys])
        order = np.argsort(all_keys, kind="stable")
        self._keys = all_keys[order]
        self._int_lower = np.concatenate([self._int_lower, lower])[order]
        self._int_upper = np.concatenate([self._int_upper, upper])[order]
        proper = int(np.count_nonzero(right > left))
        study.counts["occurring_intervals"] = int(self._keys.size)
        study.counts["occurring_proper_intervals"] += proper
        study.counts["interval_optimisations"] += 2 * proper * int(study.nodes.size)
        study._write_meta()

    def assemble(self, bins: np.ndarray, peaks: np.ndarray) -> tuple[np.ndarray, int]:
        """Hulls ``(nb, n_alpha, 2, n_nodes)`` of grouped samples, nesting-repaired.

        α = 1 is the model at the sample's own peak: with sensitivities, the cubic Hermite
        interpolant of the library (values and slopes at the two neighbouring grid points,
        O(spacing⁴)) kept within those two values — so the α = 1 output keeps the peak
        distribution instead of the grid's staircase, and never leaves what the
        simulations produced; without sensitivities, the value at the peak's bin centre.
        Every value lies within the model's declared bounds."""
        nodes = self.study.nodes.size
        idx = np.searchsorted(self._keys, _encode(bins[:, :-1, 0], bins[:, :-1, 1]))
        hull = np.empty((bins.shape[0], bins.shape[1], 2, nodes))
        hull[:, :-1, 0] = self._int_lower[idx]
        hull[:, :-1, 1] = self._int_upper[idx]
        if self.study.refine and self._lib_slopes is not None and self._lib_values.shape[0] >= 2:
            hull[:, -1, :] = self._peak_values(peaks)[:, None, :]
        else:
            hull[:, -1, :] = self._lib_values[bins[:, -1, 0] - self._lib_first][:, None, :]
        hull[:, -1] = np.clip(hull[:, -1], *self.study.bounds)
        repaired = np.moveaxis(repair_nesting(np.moveaxis(hull, 0, 2)), 2, 0)
        return repaired, int(np.count_nonzero(repaired != hull))
