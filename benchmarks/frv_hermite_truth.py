"""How good is the cubic Hermite refinement of an FRV leg study? (issue 37.3)

Rebuilds the model of a one-parameter leg FRV study (``fuzzygait frv-sim``, from the
options it records) and, for each chosen grid cell ``k`` of the study, the cell
``[c_k, c_k + h/q]`` (``h`` the study's spacing, ``q`` = ``--divisor``: 1 is the study's own
cell, 5 that of a grid five times finer): simulates its two ends with sensitivities and
``--points`` equally spaced parameters inside it without, and compares per time node

* the cell's minimum and maximum: ``nodes`` (the two ends' simulations: the thesis'
  hull, the extreme simulated values), ``hermite`` (the extrema of the cubic Hermite
  interpolant of the ends' values and sensitivities) against ``dense`` (the ends and the
  points inside: the reference);
* the value at the points inside (α = 1 at a raw peak): the cubic Hermite interpolant,
  the same clipped to its two ends' values, the monotone (Fritsch–Carlson) cubic, and
  the straight line, against the simulations there;

as absolute errors in per cent of the output's spread over the study's library, and how
far the simulations inside leave the ends' range (the model itself, not an interpolant).

Usage::

    python benchmarks/frv_hermite_truth.py STORE [--cells 0,9] [--divisor 1] [--points 7] [--workers 2]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from fuzzygait.mechanics.fuzzy_dynamics import _recipe_of
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.targets import LegTargetModel
from fuzzygait.uncertainty.execution import Evaluator
from fuzzygait.uncertainty.frv import hermite_segment_extrema
from fuzzygait.uncertainty.frv.hulls import _hermite_rows
from fuzzygait.uncertainty.frv.store import read_group, read_meta
from fuzzygait.uncertainty.gfa import optimisation_nodes


def _model(options: dict) -> LegTargetModel:
    simulator = LegSimulator(options["scenario"], nodes=options["nodes"])
    base = simulator.parameters(**options["set"])
    settings = SolverSettings(dt=options["dt"], duration=options["duration"], scheme=options["scheme"])
    return LegTargetModel(simulator, options["target"], (options["frv"],), base=base, settings=settings)


def _stats(name: str, estimate: np.ndarray, reference: np.ndarray, scale: float) -> None:
    error = np.abs(estimate - reference) / scale
    print(f"  {name:24s} |error| / spread: median {np.median(error):7.2%}  95 % {np.quantile(error, 0.95):7.2%}  "
          f"max {error.max():7.2%}")  # fmt: skip


def _monotone(values: np.ndarray, slopes: np.ndarray, spacing: float, s: np.ndarray) -> np.ndarray:
    """Fritsch–Carlson: the slopes limited per cell (sign of the secant, α² + β² ≤ 9)."""
    delta = values[1] - values[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = spacing * slopes[0] / delta, spacing * slopes[1] / delta
    a, b = np.where(delta != 0, np.maximum(a, 0.0), 0.0), np.where(delta != 0, np.maximum(b, 0.0), 0.0)
    tau = np.minimum(1.0, 3.0 / np.sqrt(np.maximum(a * a + b * b, 1e-300)))
    m = np.stack([a * tau * delta, b * tau * delta]) / spacing
    return _hermite_rows(values, m, 0.0, spacing, s * spacing)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("store", type=Path)
    parser.add_argument("--cells", default="0,9", help="grid cells of the study, comma-separated")
    parser.add_argument("--divisor", type=int, default=1, help="cell width h / divisor")
    parser.add_argument("--points", type=int, default=7, help="simulations inside each cell")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    meta = read_meta(args.store)
    lib = read_group(args.store, "library").sortby("bin")
    centres, width = lib["centre"].to_numpy(), float(meta["grid"]["spacing"]) / args.divisor
    scale = float(np.ptp(lib["value"].to_numpy()))
    cells = [int(c) for c in args.cells.split(",")]
    s = np.arange(1, args.points + 1) / (args.points + 1)
    ends = np.concatenate([[centres[c], centres[c] + width] for c in cells])[:, None]
    inside = np.concatenate([centres[c] + s * width for c in cells])[:, None]
    model = _model(meta["options"])
    nodes = optimisation_nodes(int(meta["n_time"]), int(meta["time_stride"]))
    with Evaluator(workers=args.workers) as pool:
        F, J = pool.batch(_recipe_of(model), sensitivities=True)(ends)
        G = np.asarray(pool.batch(_recipe_of(model), sensitivities=False)(inside))
    F, J = np.asarray(F)[:, nodes].reshape(len(cells), 2, -1), np.asarray(J)[:, nodes, 0].reshape(len(cells), 2, -1)
    G = G[:, nodes].reshape(len(cells), s.size, -1)
    print(f"{args.store}: cells {cells} of width h/{args.divisor} = {width:.4g}, {s.size} simulations inside each; "
          f"output spread {scale:.4g}")  # fmt: skip
    for j, c in enumerate(cells):
        values, slopes, sims = F[j], J[j], G[j]
        dense = np.concatenate([values, sims])
        ref_lo, ref_hi = dense.min(axis=0), dense.max(axis=0)
        node_lo, node_hi = values.min(axis=0), values.max(axis=0)
        h_lo, h_hi = hermite_segment_extrema(values, slopes, width)
        print(f"cell {c}: simulations inside below the ends' range by up to {(node_lo - ref_lo).max() / scale:.1%}, "
              f"above by up to {(ref_hi - node_hi).max() / scale:.1%} of the spread; Hermite minimum below 0 at "
              f"{int(np.count_nonzero(h_lo[0] < 0))} of {values.shape[1]} nodes (down to {h_lo.min():.4g})")
        _stats("min, nodes", node_lo, ref_lo, scale)
        _stats("min, hermite", h_lo[0], ref_lo, scale)
        _stats("min, hermite >= 0", np.maximum(h_lo[0], 0.0), ref_lo, scale)
        _stats("max, nodes", node_hi, ref_hi, scale)
        _stats("max, hermite", h_hi[0], ref_hi, scale)
        cubic = _hermite_rows(values, slopes, 0.0, width, s * width)
        _stats("inside, hermite", cubic, sims, scale)
        _stats("inside, hermite clipped", np.clip(cubic, node_lo, node_hi), sims, scale)
        _stats("inside, monotone cubic", _monotone(values, slopes, width, s), sims, scale)
        _stats("inside, linear", (1 - s)[:, None] * values[0] + s[:, None] * values[1], sims, scale)


if __name__ == "__main__":
    main()
