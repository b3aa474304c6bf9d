"""FRV-GFA on the stance scenario with the Table 5.3 settings (thesis §5.7).

Young's modulus as a fuzzy random variable (Eqs. 2.28–2.30, N(1, 1) increments with
redraw), N_s samples grouped on N_p-disc = 100 grid points, target maximum element energy
(Eq. 5.2), 2 s at dt = 1 ms, energy-momentum scheme (the variational scheme does not
converge for this stiff, heavily loaded case at dt = 1 ms), forward simulations in
parallel on an ``Evaluator`` (a local Dask process pool).  Reports occurring vs possible
intervals (Eq. 2.32), forward simulations, optimisations and wall time; then adds N_s more samples to the stored study;
then checks the α = 1 output distribution against a Monte Carlo run of the deterministic
model on a random subset of the same (ungrouped) peak samples (two-sample KS test).

Usage::

    python benchmarks/frv_stance.py [--samples 10000] [--workers 2] [--duration 2]
        [--mc 200] [--store results/frv_stance.zarr]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from fuzzygait.mechanics.scenarios import LegSimulator  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402
from fuzzygait.mechanics.targets import LegModelRecipe, LegTargetModel  # noqa: E402
from fuzzygait.uncertainty.execution import Evaluator  # noqa: E402
from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy, StudyOptions, fit_distributions, generate_samples  # noqa: E402

FIGURES = Path(__file__).parent / "figures"
MODULUS = 59.958e9  # Pa, Table 5.3
ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--disc", type=int, default=100)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--duration", type=float, default=2.0)
    parser.add_argument("--mc", type=int, default=200, help="Monte Carlo runs for the KS check")
    parser.add_argument("--store", type=Path, default=Path("results/frv_stance.zarr"))
    parser.add_argument("--figures", action="store_true", help="write the Fig. 5.14–5.19 analogues")
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}")

    sim = LegSimulator("stance")
    base = sim.parameters(E=MODULUS)
    scheme = "energy-momentum"
    settings = SolverSettings(duration=args.duration, scheme=scheme)
    model = LegTargetModel(sim, "max_element_energy", ("E",), base=base, settings=settings)
    recipe = LegModelRecipe("stance", "max_element_energy", ("E",), tuple(float(v) for v in base), settings=settings)
    spec = FRVSpec("E", MODULUS, alphas=ALPHAS)
    args.store.parent.mkdir(parents=True, exist_ok=True)
    with Evaluator(workers=args.workers) as pool:
        evaluator = pool.batch(recipe, sensitivities=True)
        start = time.perf_counter()
        study = FRVStudy.create(model, spec, args.samples,
                                StudyOptions(n_disc=args.disc, seed=0, overwrite=True),
                                store=args.store, evaluator=evaluator)  # fmt: skip
        first = time.perf_counter() - start
        counts = dict(study.counts)
        print(f"\nFRV-GFA, stance, E ~ FRV about {MODULUS:g} Pa, {args.samples} samples, N_p-disc = {args.disc}, "
              f"{len(ALPHAS)} α-levels, {args.duration:g} s at 1 ms ({scheme}), {args.workers} workers")  # fmt: skip
        for key in sorted(counts):
            print(f"   {key}: {counts[key]}")
        print(f"   wall time: {first:.1f} s")
        start = time.perf_counter()
        study.add_samples(args.samples)
        added = time.perf_counter() - start
        after = dict(study.counts)
        print(f"\nadding {args.samples} samples: {added:.1f} s = {100 * added / first:.1f} % of the first run; "
              f"new forward simulations {after.get('forward_simulations', 0) - counts.get('forward_simulations', 0)}, "
              f"new intervals {after.get('occurring_intervals', 0) - counts.get('occurring_intervals', 0)}")  # fmt: skip

    # α = 1 output distribution vs Monte Carlo of the deterministic model on the raw peaks
    peaks = generate_samples(spec, args.samples, seed=0)[:, -1, 0]
    rng = np.random.default_rng(1)
    subset = np.sort(rng.choice(args.samples, size=min(args.mc, args.samples), replace=False))
    with Evaluator(workers=args.workers) as pool:
        evaluator = pool.batch(recipe)
        start = time.perf_counter()
        monte_carlo = np.asarray(evaluator(peaks[subset, None]))
        mc_wall = time.perf_counter() - start
    hulls = study.hulls()["hull"]
    times = hulls["time"].values
    print(f"\nα = 1 distribution vs Monte Carlo at the raw peaks ({subset.size} runs, {mc_wall:.1f} s):")
    for t in (0.25, 0.5, 1.0, 1.5, args.duration):
        node = int(np.argmin(np.abs(times - t)))
        frv = hulls.isel(time=node).sel(alpha=1.0, bound="upper").values[: args.samples]
        mc_node = int(np.argmin(np.abs(model.times - times[node])))
        result = stats.ks_2samp(frv, monte_carlo[:, mc_node])
        print(f"   t = {times[node]:.3f} s: KS statistic {result.statistic:.4f}, p = {result.pvalue:.3f}")

    fit = fit_distributions(args.store, kind="normal", data="hulls")
    print(f"\nnormal fits per (α, bound, time): {dict(fit.sizes)}")
    if args.figures:
        from fuzzygait.io.figure_files import save_figure
        from fuzzygait.viz.frv import (
            fuzzy_random_output_figure,
            grouping_figure,
            input_samples_figure,
            output_distribution_figure,
            temporal_evolution_figure,
        )

        FIGURES.mkdir(exist_ok=True)
        node = int(np.argmin(np.abs(times - 1.0)))
        save_figure(input_samples_figure(spec, n_samples=args.samples), FIGURES / "frv_5_14_input_samples.png")
        save_figure(grouping_figure(spec, n_samples=args.samples, n_disc=args.disc), FIGURES / "frv_5_15_grouping.png")
        save_figure(output_distribution_figure(args.store, node), FIGURES / "frv_5_16_output_hulls.png")
        save_figure(output_distribution_figure(args.store, node, data="increments"),
                     FIGURES / "frv_5_17_output_increments.png")  # fmt: skip
        save_figure(temporal_evolution_figure(args.store), FIGURES / "frv_5_18_temporal.png")
        save_figure(fuzzy_random_output_figure(args.store, node), FIGURES / "frv_5_19_output_frv.png")
        print(f"figures in {FIGURES}")


if __name__ == "__main__":
    main()
