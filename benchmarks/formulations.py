"""Cartesian vs spherical marker deviations (thesis §3.7.2) with a quasi-Newton optimiser.

Run:  OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/formulations.py   (about 5 min)

The thesis found that the norm-constrained Cartesian deviations and the box-constrained
spherical ones give the same envelopes (with fmincon multistart). Here the engine's
per-node scipy multistart is used (``Direct``: SLSQP on the balls, L-BFGS-B on the
spherical box; the model is wrapped without the ``"nodes"`` capability, so it is solved
node by node on whole trajectories), on 8 frames of the synthetic trial, hip flexion, α = 0 and 0.5, 10 starts.
The batched Cartesian solver (``BatchedDirect``, the default of ``fuzzygait uncertainty``) is compared too.
"""

from __future__ import annotations

import time

import numpy as np

from fuzzygait.markererror.angle_model import JointAngleModel, fixed_subject
from fuzzygait.markererror.spherical import SphericalDeviationModel
from fuzzygait.markererror.sources import ErrorModel
from fuzzygait.workflows.angles import run_angles
from fuzzygait.uncertainty import (
    BatchedDirect,
    Direct,
    Evaluation,
    FuzzyBalls,
    FuzzyNumber,
    FuzzyVector,
    graph_follower,
)


class WholeTrajectoryModel:
    """Declares no ``"nodes"`` capability (so no ``evaluate_nodes``): the engine solves
    each node with scipy's multistart on whole trajectories."""

    capabilities = frozenset[str]()

    def __init__(self, model: object) -> None:
        self.model, self.times = model, model.times
        self.parameter_names, self.output = model.parameter_names, model.output

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        return self.model.evaluate(p)


def spherical_parameters(radii: np.ndarray) -> FuzzyVector:
    numbers = []
    for radius in radii:
        numbers += [
            FuzzyNumber(np.array([0.0, 1.0]), np.array([0.0, 0.0]), np.array([radius, 0.0])),
            FuzzyNumber(np.array([0.0, 1.0]), np.array([0.0, 0.0]), np.array([np.pi, np.pi])),
            FuzzyNumber(np.array([0.0, 1.0]), np.array([-np.pi, -np.pi]), np.array([np.pi, np.pi])),
        ]
    return FuzzyVector(numbers)


def main() -> None:
    run = run_angles("sample_data/walking.c3d", static="sample_data/static.c3d", subject_file="sample_data/subject.toml")
    frames = np.linspace(0, run.trial.n_frames - 1, 8).round().astype(int)
    subject = fixed_subject(run.trial, run.subject)
    model = JointAngleModel(run.trial, subject, run.result.progression, "LHipAngles", 0, frames)
    radii = np.array([ErrorModel().radius(m) for m in model.markers])
    cartesian = FuzzyBalls(np.zeros((len(model.markers), 3)), radii, tuple(model.markers))
    runs = {}
    for name, fuzzy_model, params, strategy in (
        ("Cartesian, SLSQP multistart", WholeTrajectoryModel(model), cartesian, Direct(starts=10)),
        ("spherical, L-BFGS-B multistart", WholeTrajectoryModel(SphericalDeviationModel(model)),
         spherical_parameters(radii), Direct(starts=10)),
        ("Cartesian, batched (default)", model, cartesian, BatchedDirect(starts=6, iterations=50)),
    ):  # fmt: skip
        start = time.perf_counter()
        result = graph_follower(fuzzy_model, params, (0.0, 0.5), strategy=strategy)
        runs[name] = (result["hull"].sel(alpha=[0.0, 0.5]).to_numpy(), time.perf_counter() - start)
    reference, _ = runs["Cartesian, SLSQP multistart"]
    width = reference[:, 1] - reference[:, 0]
    print("## LHipAngles_X, 8 frames, α = 0 and 0.5: difference to Cartesian SLSQP, % of the hull width")
    print("| formulation / optimiser | wall s | max % | mean % |")
    print("|---|---|---|---|")
    for name, (hull, seconds) in runs.items():
        relative = np.abs(hull - reference).max(axis=1) / width
        print(f"| {name} | {seconds:.1f} | {100 * relative.max():.2f} | {100 * relative.mean():.2f} |")


if __name__ == "__main__":
    main()
