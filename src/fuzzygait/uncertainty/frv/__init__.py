"""Fuzzy random variables and the FRV Graph Follower algorithm (thesis §2.7, §5.7).

A fuzzy random variable (FRV) is a random variable whose realisations are convex fuzzy
numbers (Eq. 2.25). Propagating one through a model ``f(p) -> (n_time,)`` takes the nested
steps of the FRV-GFA (thesis §2.7.4, "FRV-GFA steps"):

1. **Sample generation** (:func:`generate_samples`, Eqs. 2.26–2.30): ``N_s`` fuzzy-number
   samples of the FRV parameter, each described by ``N_α`` α-cuts.
2. **Grouping** (:class:`Grid`, :func:`group`, Eqs. 2.31–2.32): the sample range is
   discretised into ``N_p-disc`` equidistant points; every α-cut end is mapped to the
   centre of the bin between two neighbouring points. The α-cuts become intervals between
   bin centres, most of which recur across the samples.
3.–4. **Keys and dictionaries**: an interval is keyed by its ``(left bin, right bin)``
   pair; only *occurring* intervals (present in at least one sample) get an entry.
5. **Hulls** (:func:`interval_hulls`): the model is evaluated once per bin centre (the
   library ``f_lib``, one forward simulation each, through an injectable batch
   ``evaluator``). Because every interval end is a bin centre and the GFA's novelty check
   maps optima onto library entries, the α-level optimisation of an interval returns the
   extreme library value over the bins inside it; all occurring intervals are answered
   at once by sparse-table range-max/min queries. A hull is thus always a value the
   model produced: the extrema of the cubic Hermite interpolant between library entries
   (:func:`hermite_segment_extrema`) are not stored, for where the grid does not resolve
   the model they leave the range it can produce (a deformation energy below zero).
6.–7. **Assembly**: each sample's output fuzzy number at every time node is its
   intervals' hulls (α = 1: the library value at the peak bin, or with sensitivities,
   ``refine``, the cubic Hermite interpolant at the sample's own peak kept within its
   cell's two library values), within the bounds the model declares for its output
   (:attr:`~fuzzygait.uncertainty.protocol.Output.bounds`), passed through
   :func:`~fuzzygait.uncertainty.postprocess.repair_nesting` (Fig. 2.11).
8.–9. **Increments and fitting** (:func:`fit_distributions`).

:class:`FRVStudy` runs steps 1–7 into a chunked zarr store, block by block (the
``(n_samples, n_alpha, 2, n_time)`` hull array is never held in memory), and can add
samples later, simulating only new bin centres and computing only new intervals
(the extension the thesis describes as "not yet implemented", §2.7.4).

:class:`FRVStudy` takes one FRV parameter (the Table 5.3 case, with the Hermite
refinement, :mod:`~fuzzygait.uncertainty.frv.single`) or several independent ones
(boxes of per-parameter intervals on tensor grids, :func:`generate_box_samples`,
:func:`occurring_boxes`, :func:`possible_boxes`, :func:`box_extrema`, and with
sensitivities α = 1 at each sample's own peak by :func:`hermite_values` on a lattice,
:mod:`~fuzzygait.uncertainty.frv.multi`); :meth:`FRVStudy.open` opens a store of
either kind. A new study's settings are a :class:`StudyOptions`
(:class:`MultiStudyOptions`: with the grids and the α = 1 lattice of several).
"""

from fuzzygait.uncertainty.frv.evaluation import BatchFunction, serial_evaluator
from fuzzygait.uncertainty.frv.fit import fit_distributions, iter_hull_blocks, stored_samples
from fuzzygait.uncertainty.frv.grouping import (
    EDGE_TOL,
    KEY_BASE,
    KEY_BIAS,
    Grid,
    box_rows,
    group,
    occurring_boxes,
    occurring_intervals,
    possible_boxes,
)
from fuzzygait.uncertainty.frv.hulls import (
    box_extrema,
    hermite_box_extrema,
    hermite_cells,
    hermite_segment_extrema,
    hermite_values,
    interval_hulls,
    range_extrema,
)
from fuzzygait.uncertainty.frv.options import MultiStudyOptions, StudyOptions
from fuzzygait.uncertainty.frv.samples import (
    BLOCK,
    DISTRIBUTIONS,
    SAMPLINGS,
    FRVSpec,
    check_specs,
    generate_box_samples,
    generate_samples,
    sample_increments,
)
from fuzzygait.uncertainty.frv.study import STORE_FORMAT, FRVStudy

__all__ = [
    "BLOCK",
    "DISTRIBUTIONS",
    "EDGE_TOL",
    "KEY_BASE",
    "KEY_BIAS",
    "SAMPLINGS",
    "STORE_FORMAT",
    "BatchFunction",
    "FRVSpec",
    "FRVStudy",
    "Grid",
    "MultiStudyOptions",
    "StudyOptions",
    "box_extrema",
    "box_rows",
    "check_specs",
    "fit_distributions",
    "generate_box_samples",
    "generate_samples",
    "group",
    "hermite_box_extrema",
    "hermite_cells",
    "hermite_segment_extrema",
    "hermite_values",
    "interval_hulls",
    "iter_hull_blocks",
    "occurring_boxes",
    "occurring_intervals",
    "possible_boxes",
    "range_extrema",
    "sample_increments",
    "serial_evaluator",
    "stored_samples",
]
