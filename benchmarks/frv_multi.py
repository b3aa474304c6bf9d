"""FRV-GFA with two fuzzy random parameters (issue 18, Deliver 4): Young's modulus E and the
density ρ of the blade, independent FRVs (Eqs. 2.28–2.30, N(1, 1) increments), stance
scenario (Table 4.4 with the Table 5.3 p_det of E), target maximum element energy (Eq. 5.2),
energy-momentum scheme, N_s samples grouped on N_p-disc points per parameter; the library
with sensitivities, so α = 1 is the Hermite interpolant at each sample's own peak.

Reports: occurring boxes against the possible ones (the product over the parameters of
Eq. 2.32's interval counts), forward simulations (grid points inside an occurring box and
the peaks' Hermite cells on the α = 1 lattice, chosen by the study unless
``--peak-refine`` gives it), wall time and the part of it spent simulating; the cost of
adding N_s more samples as a fraction of the first run; the α = 1 output distribution
against a Monte Carlo of the deterministic model at a random subset of the same
(ungrouped) peak samples (two-sample KS test at five times); and whether a smaller
study is bit-identical on 1 and 2 workers.

Usage::

    python benchmarks/frv_multi.py [--samples 10000] [--disc 30] [--duration 1] [--mc 400]
        [--workers 2] [--store results/frv_multi.zarr] [--peak-refine auto]
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from fuzzygait.mechanics.scenarios import LegSimulator  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402
from fuzzygait.mechanics.targets import LegModelRecipe, LegTargetModel  # noqa: E402
from fuzzygait.uncertainty.execution import Evaluator  # noqa: E402
from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy, MultiStudyOptions, generate_box_samples  # noqa: E402

MODULUS = 59.958e9  # Pa, Table 5.3
ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)
SCHEME = "energy-momentum"
TARGET = "max_element_energy"


def build(duration: float):
    sim = LegSimulator("stance")
    base = sim.parameters(E=MODULUS)
    names = ("E", "rho")
    settings = SolverSettings(duration=duration, scheme=SCHEME)
    model = LegTargetModel(sim, TARGET, names, base=base, settings=settings)
    recipe = LegModelRecipe("stance", TARGET, names, tuple(float(v) for v in base), settings=settings)
    density = float(base[list(sim.parameter_names).index("rho")])
    specs = [FRVSpec("E", MODULUS, alphas=ALPHAS), FRVSpec("rho", density, alphas=ALPHAS)]
    return model, recipe, specs


class Timed:
    """An evaluator that adds up the wall time of its calls (the forward simulations)."""

    def __init__(self, inner):
        self.inner, self.seconds, self.rows = inner, 0.0, 0

    def __call__(self, P):
        start = time.perf_counter()
        try:
            return self.inner(P)
        finally:
            self.seconds += time.perf_counter() - start
            self.rows += len(P)


def study(model, recipe, specs, n, disc, workers, store, timed=None, peak_refine=None):
    with Evaluator(workers=workers) as pool:
        evaluator = pool.batch(recipe, sensitivities=True)  # Hermite refinement (α = 1 at the raw peak)
        if timed is not None:
            timed.inner = evaluator
            evaluator = timed
        start = time.perf_counter()
        result = FRVStudy.create(model, specs, n,
                                 MultiStudyOptions(n_disc=disc, seed=0, overwrite=True, peak_refine=peak_refine),
                                 store=store, evaluator=evaluator)  # fmt: skip
        return result, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--disc", default="30", help="grid points: one number, or E,rho (e.g. 59,30)")
    parser.add_argument("--duration", type=float, default=1.0)
    parser.add_argument("--mc", type=int, default=400, help="Monte Carlo runs for the KS check, per subset")
    parser.add_argument("--mc-seeds", default="1,2,3", help="seeds of the random Monte Carlo subsets")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--check-samples", type=int, default=500, help="samples of the 1-vs-2-worker study")
    parser.add_argument("--check-disc", type=int, default=8)
    parser.add_argument("--check-duration", type=float, default=0.3, help="simulated time of that study (s)")
    parser.add_argument("--store", type=Path, default=Path("results/frv_multi.zarr"))
    parser.add_argument("--peak-refine", default="auto",
                        help="the α = 1 lattice: auto (chosen by the study) or factors, e.g. 1 (the grid) or 2,1")
    args = parser.parse_args()
    peak_refine = None if args.peak_refine == "auto" else [int(v) for v in args.peak_refine.split(",")]
    peak_refine = peak_refine[0] if peak_refine is not None and len(peak_refine) == 1 else peak_refine
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    model, recipe, specs = build(args.duration)
    disc = [int(n) for n in args.disc.split(",")]
    disc = disc[0] if len(disc) == 1 else disc
    args.store.parent.mkdir(parents=True, exist_ok=True)

    first_timer = Timed(None)
    first, first_wall = study(model, recipe, specs, args.samples, disc, args.workers, args.store, first_timer,
                              peak_refine)  # fmt: skip
    counts = dict(first.counts)
    print(f"\nFRV-GFA, stance, E and rho independent FRVs about {MODULUS:g} Pa / {specs[1].deterministic:g} kg/m³, "
          f"{args.samples} samples, N_p-disc = {args.disc} (E,rho), {len(ALPHAS)} α-levels, {args.duration:g} s at "
          f"1 ms ({SCHEME}), {args.workers} workers")  # fmt: skip
    for key in ("occurring_intervals", "possible_intervals", "possible_intervals_per_parameter",
                "forward_simulations", "interval_optimisations", "worst_case_optimisations"):  # fmt: skip
        print(f"   {key}: {counts.get(key)}")
    checks = "; ".join(f"{c['parameter']} x{c['factor']}: {100 * c['error']:.2f} %"
                       for c in counts.get("peak_checks", []))  # fmt: skip
    print(f"   α = 1 lattice (factors E, rho): {first.peak_refine} ({args.peak_refine}); checks: {checks}")
    print(f"   wall time: {first_wall:.1f} s, of which forward simulations {first_timer.seconds:.1f} s "
          f"({first_timer.rows} rows, with sensitivities)")  # fmt: skip

    with Evaluator(workers=args.workers) as pool:
        added_timer = Timed(pool.batch(recipe, sensitivities=True))
        reopened = FRVStudy.open(args.store, model, evaluator=added_timer)
        start = time.perf_counter()
        reopened.add_samples(args.samples)
        added = time.perf_counter() - start
    after = dict(reopened.counts)
    print(f"\nadding {args.samples} samples: {added:.1f} s = {100 * added / first_wall:.1f} % of the first run; "
          f"new forward simulations {after['forward_simulations'] - counts['forward_simulations']}, "
          f"new boxes {after['occurring_intervals'] - counts['occurring_intervals']}; forward simulations "
          f"{added_timer.seconds:.1f} s, the rest {added - added_timer.seconds:.1f} s")  # fmt: skip

    # α = 1 outputs vs Monte Carlo of the deterministic model at the raw peaks of the first N_s samples
    peaks = generate_box_samples(specs, args.samples, seed=0)[:, :, -1, 0]  # (n, 2): E, rho
    hulls = reopened.hulls()["hull"]
    times = hulls["time"].values
    nodes = [int(np.argmin(np.abs(times - f * args.duration))) for f in (0.2, 0.4, 0.6, 0.8, 1.0)]
    alpha_one = hulls.sel(alpha=1.0, bound="upper").values[: args.samples][:, nodes]
    model_nodes = [int(np.argmin(np.abs(model.times - times[n]))) for n in nodes]
    for mc_seed in (int(v) for v in args.mc_seeds.split(",")):
        rng = np.random.default_rng(mc_seed)
        subset = np.sort(rng.choice(args.samples, size=min(args.mc, args.samples), replace=False))
        with Evaluator(workers=args.workers) as pool:
            start = time.perf_counter()
            monte_carlo = np.asarray(pool.batch(recipe)(peaks[subset]))[:, model_nodes]
            mc_wall = time.perf_counter() - start
        print(f"\nα = 1 outputs (first {args.samples} samples) vs Monte Carlo at {subset.size} of their raw peaks "
              f"(subset seed {mc_seed}, {mc_wall:.1f} s):")  # fmt: skip
        error = np.median(np.abs(alpha_one[subset] - monte_carlo), axis=0) / np.median(np.abs(monte_carlo), axis=0)
        for k, node in enumerate(nodes):
            result = stats.ks_2samp(alpha_one[:, k], monte_carlo[:, k])
            print(f"   t = {times[node]:.3f} s: KS statistic {result.statistic:.4f}, p = {result.pvalue:.3f}; "
                  f"median |α=1 − model| at the same peaks {100 * error[k]:.2f} % of the median output")  # fmt: skip

    folder = Path(tempfile.mkdtemp())
    try:
        check_model, check_recipe, _ = build(args.check_duration)
        runs = [study(check_model, check_recipe, specs, args.check_samples, args.check_disc, w, folder / f"w{w}.zarr")
                for w in (1, 2)]  # fmt: skip
        same = all(
            np.array_equal(runs[0][0].hulls()[name].values, runs[1][0].hulls()[name].values, equal_nan=True)
            for name in runs[0][0].hulls().data_vars
        )
        print(f"\n{args.check_samples} samples, N_p-disc = {args.check_disc}, {args.check_duration:g} s, α = 1 lattice "
              f"{runs[0][0].peak_refine} / {runs[1][0].peak_refine}: 1 worker {runs[0][1]:.1f} s, "
              f"2 workers {runs[1][1]:.1f} s; hulls bit-identical: {same}")  # fmt: skip
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
