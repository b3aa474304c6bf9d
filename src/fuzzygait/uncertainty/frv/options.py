"""What an FRV-GFA study is made with, besides its model, parameters and sample count:
:class:`StudyOptions` and :class:`MultiStudyOptions` (several parameters, or the
several-parameter layout of one) for :meth:`FRVStudy.create
<fuzzygait.uncertainty.frv.FRVStudy.create>`, each field checked when it is made
(one :class:`~fuzzygait.core.errors.ParameterError` naming the first bad field)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.frv.grouping import Grid
from fuzzygait.uncertainty.frv.samples import _whole

__all__ = ["PEAK_FACTORS", "PEAK_TOLERANCE", "MultiStudyOptions", "StudyOptions"]

#: Default largest α = 1 interpolation error, as a fraction of the output's spread.
PEAK_TOLERANCE = 0.01
#: The α = 1 lattice refinement factors a parameter can have (divisors of RESOLUTION).
PEAK_FACTORS = (1, 2, 4, 8)


@dataclass(frozen=True)
class StudyOptions:
    """The settings of a new FRV study.

    Attributes:
        n_disc: ``N_p-disc`` grid points over the first batch's range (≥ 2; for a study
            of several parameters one number for all or one per parameter); None: the
            study's default (100 for one parameter, 30 per parameter for several).
        seed: seed of the sample streams (parameter ``k`` is stream ``k``).
        time_stride: keep every ``time_stride``-th time node (and the last).
        refine: α = 1 by the Hermite interpolant of the library values and
            sensitivities at each sample's own peak; None: when the evaluator returns
            sensitivities.
        chunk: samples per zarr chunk and per processing block.
        overwrite: replace an existing store (it stays intact until the new one is
            complete).
        record: what the study is made with, JSON-compatible (stored as the store's
            ``options`` attribute, e.g. for the caller to refuse extending it with other
            ones); None: none.
    """

    n_disc: int | Sequence[int] | None = None
    seed: int = 0
    time_stride: int = 1
    refine: bool | None = None
    chunk: int = 256
    overwrite: bool = False
    record: Mapping[str, Any] | None = field(default_factory=dict)

    def __post_init__(self) -> None:
        n_disc = self.n_disc
        if n_disc is not None:
            if isinstance(n_disc, (int, np.integer)) and not isinstance(n_disc, bool):
                n_disc = _whole(n_disc, "n_disc", 2)
            elif isinstance(n_disc, Sequence) and not isinstance(n_disc, str) and len(n_disc) > 0:
                n_disc = tuple(_whole(n, "n_disc", 2) for n in n_disc)
            else:
                raise ParameterError(f"n_disc must be a whole number >= 2 or one per parameter; got {n_disc!r}")
        object.__setattr__(self, "n_disc", n_disc)
        object.__setattr__(self, "seed", _whole(self.seed, "seed"))
        object.__setattr__(self, "time_stride", _whole(self.time_stride, "time_stride", 1))
        object.__setattr__(self, "chunk", _whole(self.chunk, "chunk", 1))
        if self.refine is not None and not isinstance(self.refine, (bool, np.bool_)):
            raise ParameterError(f"refine must be True, False or None (when the evaluator returns sensitivities); "
                                 f"got {self.refine!r}")  # fmt: skip
        object.__setattr__(self, "refine", None if self.refine is None else bool(self.refine))
        if not isinstance(self.overwrite, (bool, np.bool_)):
            raise ParameterError(f"overwrite must be True or False; got {self.overwrite!r}")
        if not isinstance(self.record, Mapping | None):
            raise ParameterError(f"record must be a mapping (what the study is made with); got {self.record!r}")
        object.__setattr__(self, "record", dict(self.record or {}))

    def discs(self, n_params: int, default: int) -> list[int]:
        """``n_disc`` per parameter (``default`` when not given)."""
        n_disc = default if self.n_disc is None else self.n_disc
        discs = [n_disc] * n_params if isinstance(n_disc, int) else list(n_disc)
        if len(discs) != n_params:
            raise ParameterError(f"n_disc: give one number or one per parameter ({n_params}); got {discs}")
        return discs


@dataclass(frozen=True)
class MultiStudyOptions(StudyOptions):
    """:class:`StudyOptions` of a study of several FRV parameters (given for one, the
    study is made the several-parameter way: boxes, α = 1 lattice), and:

    Attributes:
        grids: the grids to group on (one :class:`~fuzzygait.uncertainty.frv.Grid` per
            parameter) instead of the first batch's ranges, e.g. another study's, to
            compare two studies bin by bin.
        peak_refine: the α = 1 lattice per parameter (one factor for all or one each,
            from :data:`~fuzzygait.uncertainty.frv.peaks.PEAK_FACTORS`: 1 = the grouping
            grid, 2 = half its spacing, ...); None: chosen on the first batch.
        peak_tolerance: the largest α = 1 interpolation error, as a fraction of the
            output's spread, when the lattice is chosen (default 1 %).
    """

    grids: Sequence[Grid] | None = None
    peak_refine: int | Sequence[int] | None = None
    peak_tolerance: float = PEAK_TOLERANCE

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.grids is not None:
            if isinstance(self.grids, Grid) or not isinstance(self.grids, Sequence) or not all(
                    isinstance(g, Grid) for g in self.grids):  # fmt: skip
                raise ParameterError("grids: give one Grid per parameter")
            object.__setattr__(self, "grids", tuple(self.grids))
        if self.peak_refine is not None:
            factors = [self.peak_refine] if isinstance(self.peak_refine, (int, np.integer)) else self.peak_refine
            if isinstance(factors, str) or not isinstance(factors, Sequence) or not all(
                    not isinstance(f, bool) and f in PEAK_FACTORS for f in factors):  # fmt: skip
                raise ParameterError(f"peak_refine: give one factor or one per parameter, each of "
                                     f"{', '.join(map(str, PEAK_FACTORS))}; got {self.peak_refine!r}")  # fmt: skip
            if not isinstance(self.peak_refine, (int, np.integer)):
                object.__setattr__(self, "peak_refine", tuple(self.peak_refine))
        tolerance = self.peak_tolerance
        if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float, np.floating, np.integer)) or not (
                math.isfinite(tolerance) and 0.0 < tolerance < 1.0):  # fmt: skip
            raise ParameterError(f"peak_tolerance must lie between 0 and 1 (a fraction of the output's spread); "
                                 f"got {tolerance}")  # fmt: skip

    @classmethod
    def of(cls, options: StudyOptions | None) -> MultiStudyOptions:
        """``options`` as :class:`MultiStudyOptions` (the extra fields at their defaults)."""
        if options is None:
            return cls()
        if isinstance(options, cls):
            return options
        return cls(**{f.name: getattr(options, f.name) for f in fields(StudyOptions)})
