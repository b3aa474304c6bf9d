"""The Graph Follower algorithm: strategies, the library-based follower, the batched
direct solver and the entry point :func:`graph_follower`."""

from fuzzygait.uncertainty.gfa.api import alpha_levels, as_parameters, graph_follower
from fuzzygait.uncertainty.gfa.batched import optimisation_nodes
from fuzzygait.uncertainty.gfa.strategies import BatchedDirect, Direct, Linearised, Strategy

__all__ = [
    "BatchedDirect",
    "Direct",
    "Linearised",
    "Strategy",
    "alpha_levels",
    "as_parameters",
    "graph_follower",
    "optimisation_nodes",
]
