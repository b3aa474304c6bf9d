"""The one result schema of every fuzzy analysis (``FuzzyResult``).

A fuzzy result is an :class:`xarray.Dataset` with

* ``hull (alpha, bound, time)``: the lower and upper hull of the output at each
  α-level (ascending; α = 1 is the deterministic run), in the output's units;
* ``deterministic (time)``: the output for the peak values of the fuzzy parameters;
* ``extremiser (alpha, bound, time, parameter)``: the parameter vector that gives each
  hull value;
* attributes ``output`` and ``units`` (what the hull is), ``strategy`` (the algorithm
  and its options as further attributes), ``forward_simulations`` (whole-trajectory
  model evaluations, finite-difference runs included) and ``node_evaluations``
  (single-node evaluations), plus strategy-specific counts.

Analyses of several outputs (the marker-error analysis: one per angle component) stack
such results along a ``component`` dimension. Every result is read the same way through
the ``dataset.fuzzy`` accessor (:mod:`fuzzygait.core.accessor`), and
:func:`fuzzygait.testing.check_result` checks one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr
from numpy.typing import NDArray

import fuzzygait.core.accessor  # noqa: F401 - registers ``dataset.fuzzy`` for every result made here
from fuzzygait.core.errors import ParameterError

BOUNDS = ("lower", "upper")
#: Sign that turns each bound's search into a maximisation.
SENSES = {"lower": -1.0, "upper": 1.0}
RESULT_VARIABLES = ("hull", "deterministic", "extremiser")
REQUIRED_ATTRIBUTES = ("output", "units", "strategy", "forward_simulations", "node_evaluations")


@dataclass(frozen=True)
class HullArrays:
    """The arrays of a fuzzy result: ascending ``alphas``, the output's ``times``, the
    fuzzy ``parameter_names``, ``hull (alpha, bound, time)``, ``deterministic (time)``
    and ``extremiser (alpha, bound, time, parameter)``."""

    alphas: NDArray[np.float64]
    times: NDArray[np.float64]
    parameter_names: Sequence[str]
    hull: NDArray[np.float64]
    deterministic: NDArray[np.float64]
    extremiser: NDArray[np.float64]

    def __post_init__(self) -> None:
        n_alpha, n_time, n_parameter = len(self.alphas), len(self.times), len(self.parameter_names)
        expected = {
            "hull": (n_alpha, len(BOUNDS), n_time),
            "deterministic": (n_time,),
            "extremiser": (n_alpha, len(BOUNDS), n_time, n_parameter),
        }
        for name, shape in expected.items():
            if (got := np.shape(getattr(self, name))) != shape:
                raise ParameterError(f"{name} must have the shape {shape} (alphas {n_alpha}, bounds 2, times "
                                     f"{n_time}, parameters {n_parameter}); got {got}")  # fmt: skip


@dataclass(frozen=True)
class ResultInfo:
    """What a fuzzy result is: its ``output`` and ``units``, the ``strategy`` name and the
    model evaluations it took (``forward_simulations``, ``node_evaluations``)."""

    output: str
    units: str
    strategy: str
    forward_simulations: int
    node_evaluations: int

    def __post_init__(self) -> None:
        for name in ("output", "units", "strategy"):
            if not isinstance(getattr(self, name), str):
                raise ParameterError(f"{name} must be a string; got {getattr(self, name)!r}")
        for name in ("forward_simulations", "node_evaluations"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
                raise ParameterError(f"{name} must be a whole number >= 0; got {value!r}")


def fuzzy_result(arrays: HullArrays, info: ResultInfo, *, attrs: Mapping[str, object] | None = None) -> xr.Dataset:
    """Build a fuzzy result (see the module docstring for the layout) from its arrays,
    what it is and further attributes (``attrs``: strategy options and counts)."""
    units = info.units
    return xr.Dataset(
        {
            "hull": (("alpha", "bound", "time"), arrays.hull, {"units": units}),
            "deterministic": (("time",), arrays.deterministic, {"units": units}),
            "extremiser": (("alpha", "bound", "time", "parameter"), arrays.extremiser),
        },
        coords={"alpha": arrays.alphas, "bound": list(BOUNDS), "time": arrays.times,
                "parameter": list(arrays.parameter_names)},  # fmt: skip
        attrs={
            "output": info.output,
            "units": units,
            "strategy": info.strategy,
            "forward_simulations": int(info.forward_simulations),
            "node_evaluations": int(info.node_evaluations),
            **dict(attrs or {}),
        },
    )


def schema_problems(result: xr.Dataset) -> list[str]:
    """What keeps ``result`` from being a fuzzy result (empty when it is one)."""
    problems = [f"variable {v!r} missing" for v in RESULT_VARIABLES if v not in result.data_vars]
    problems += [f"attribute {a!r} missing" for a in REQUIRED_ATTRIBUTES if a not in result.attrs]
    if "hull" in result.data_vars and result["hull"].dims[-3:] != ("alpha", "bound", "time"):
        problems.append(f"hull has dims {result['hull'].dims}, expected (..., alpha, bound, time)")
    if "bound" in result.coords and [str(b) for b in result["bound"].values] != list(BOUNDS):
        problems.append(f"bound must be {list(BOUNDS)}")
    return problems
