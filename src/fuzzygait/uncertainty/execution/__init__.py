"""Where the engine's work runs: one :class:`Evaluator` (serial, a local Dask process
pool, or a Dask scheduler) for the Graph Follower, the FRV-GFA and the marker-error
analysis alike."""

from fuzzygait.uncertainty.execution.evaluator import (
    EvaluatedModel,
    Evaluator,
    ParallelEvaluationError,
    RecipeBatch,
)
from fuzzygait.uncertainty.execution.workers import WORKER_ENV, ModelRecipe, SharedArray, clear_model_cache

__all__ = [
    "WORKER_ENV",
    "EvaluatedModel",
    "Evaluator",
    "ModelRecipe",
    "ParallelEvaluationError",
    "RecipeBatch",
    "SharedArray",
    "clear_model_cache",
]
