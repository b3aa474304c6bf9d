"""The uncertainty engine: fuzzy numbers, α-level optimisation, the Graph Follower
algorithm and the FRV-GFA. It sees only models that follow the protocol of
:mod:`fuzzygait.uncertainty.protocol`, so the MoCap front end and the simulator plug into
the same code."""

from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain
from fuzzygait.uncertainty.fuzzy import FuzzyNumber, from_increments, triangular, triangular_relative
from fuzzygait.uncertainty.gfa import BatchedDirect, Direct, Linearised, graph_follower, optimisation_nodes
from fuzzygait.uncertainty.parameters import FuzzyBalls, FuzzyVector
from fuzzygait.uncertainty.postprocess import combined_envelope, failure_probability, repair_nesting, sufficient_runs
from fuzzygait.uncertainty.protocol import Evaluation, FunctionModel, FuzzyModel, NodeModel, Output, as_model
from fuzzygait.uncertainty.storage import load_result, save_result

__all__ = [
    "BallsDomain",
    "BatchedDirect",
    "BoxDomain",
    "CountedModel",
    "Direct",
    "Evaluation",
    "FunctionModel",
    "FuzzyBalls",
    "FuzzyModel",
    "FuzzyNumber",
    "FuzzyVector",
    "Linearised",
    "NodeModel",
    "Output",
    "as_model",
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

# The FRV-GFA (thesis §2.7, §5.7) is in the subpackage fuzzygait.uncertainty.frv.
