"""The uncertainty engine: fuzzy numbers, α-level optimisation and the Graph Follower
algorithm. It sees only a model ``f(p) -> trajectory`` (see
:mod:`fuzzygait.uncertainty.model`), so the MoCap front end and the simulator plug into
the same code."""

from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain
from fuzzygait.uncertainty.fuzzy import FuzzyNumber, from_increments, triangular, triangular_relative
from fuzzygait.uncertainty.gfa import graph_follower, optimisation_nodes
from fuzzygait.uncertainty.model import CountedModel, FunctionModel, Model
from fuzzygait.uncertainty.parameters import FuzzyBalls, FuzzyVector
from fuzzygait.uncertainty.postprocess import combined_envelope, failure_probability, repair_nesting, sufficient_runs
from fuzzygait.uncertainty.storage import load_result, save_result

__all__ = [
    "BallsDomain",
    "BoxDomain",
    "CountedModel",
    "FunctionModel",
    "FuzzyBalls",
    "FuzzyNumber",
    "FuzzyVector",
    "Model",
    "combined_envelope",
    "failure_probability",
    "from_increments",
    "graph_follower",
    "load_result",
    "optimisation_nodes",
    "repair_nesting",
    "save_result",
    "sufficient_runs",
    "triangular",
    "triangular_relative",
]

# Fuzzy random variables and the FRV Graph Follower algorithm (thesis §2.7, §5.7)
from fuzzygait.uncertainty.frv import (  # noqa: E402
    FRVSpec,
    FRVStudy,
    Grid,
    fit_distributions,
    generate_samples,
    group,
    interval_hulls,
    occurring_intervals,
    serial_evaluator,
)

__all__ += [
    "FRVSpec",
    "FRVStudy",
    "Grid",
    "fit_distributions",
    "generate_samples",
    "group",
    "interval_hulls",
    "occurring_intervals",
    "serial_evaluator",
]
