"""Fuzzy forward dynamics of the leg + prosthesis (thesis §5.2–5.3): accuracy and cost.

1. Swing, fuzzy Young's modulus (triangular ±10 %), target total deformation energy,
   α = 0, 0.5, 1, stride 100, novelty 0.01 %: Graph Follower hulls vs a dense-sampling
   reference (41 forward runs on the α = 0 interval); counts and wall times; α = 1 vs the
   deterministic run.
2. Swing, the 11 fuzzy parameters of §5.3 (E, ν, ρ, thigh and shank mass and inertias),
   ±10 % each: wall time and forward simulations; Fig. 5.6 analogue.
4. The layered blade alone (§5.4): clamped, tip-loaded, fuzzy face and core moduli and face
   thickness; hulls of the toe height and of the deformation energy (Figs. 5.7/5.8).
3. Stance, fuzzy E ±10 % about the Table 5.3 modulus, target maximum element energy
   (energy-momentum scheme: the variational scheme does not converge at dt = 1 ms here).

Usage::

    python benchmarks/fuzzy_dynamics.py [--quick] [--workers 2] [--cases 1,2,3]

``--quick`` simulates 0.5 s instead of 2 s.  The soft Table 4.3 blade runs with
η = 10⁵ Pa s (see README: without it the shipped blade folds).  Figures go to
``benchmarks/figures/``.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from fuzzygait.io.figure_files import save_figure  # noqa: E402
from fuzzygait.mechanics.fuzzy_dynamics import (  # noqa: E402
    ELEVEN_PARAMETERS,
    LegTarget,
    dense_reference,
    fuzzy_forward_dynamics,
)
from fuzzygait.mechanics.leg import LEG_PARAMETERS  # noqa: E402
from fuzzygait.mechanics.scenarios import LegSimulator  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402
from fuzzygait.mechanics.targets import LegTargetModel  # noqa: E402
from fuzzygait.uncertainty import FuzzyVector, sufficient_runs, triangular_relative  # noqa: E402
from fuzzygait.viz.fuzzy_dynamics import extremiser_figure, hull_figure  # noqa: E402

FIGURES = Path(__file__).parent / "figures"
SWING_DAMPING = 1e5  # Pa s
# Table 5.3 (the §5.7 stance study); the Table 4.4 value 59.958e7 Pa folds the shipped blade
# under the 107 kg shank once E drops ~5 % (README)
STANCE_MODULUS = 59.958e9  # Pa


def _evaluator(model: LegTargetModel, scenario: str, workers: int):
    """A local pool of ``workers`` processes and a batch function of ``model`` on it
    (``(None, None)`` for one worker: the dense reference then runs in this process)."""
    if workers <= 1:
        return None, None
    from fuzzygait.mechanics.targets import LegModelRecipe
    from fuzzygait.uncertainty.execution import Evaluator

    recipe = LegModelRecipe(scenario, model.target, tuple(model.names), tuple(float(v) for v in model.base),
                            nodes=20, settings=model.settings)  # fmt: skip
    pool = Evaluator(workers=workers)
    return pool, pool.batch(recipe)


def swing_one_parameter(duration: float, workers: int) -> None:
    sim = LegSimulator("swing")
    base = sim.parameters(eta=SWING_DAMPING)
    target = LegTarget(base=base, settings=SolverSettings(duration=duration))
    result = fuzzy_forward_dynamics(sim, {"E": 0.1}, target=target)
    e = base[0]
    model = LegTargetModel(sim, "total_deformation_energy", ("E",), base=base,
                           settings=SolverSettings(duration=duration))
    pool, evaluator = _evaluator(model, "swing", workers)
    start = time.perf_counter()
    dense = dense_reference(model, 0.9 * e, 1.1 * e, 41, evaluator=evaluator)
    dense_wall = time.perf_counter() - start
    upper = result["hull"].sel(alpha=0.0, bound="upper").values
    lower = result["hull"].sel(alpha=0.0, bound="lower").values
    scale = float(np.max(np.abs(dense)))
    deterministic = model.evaluate(np.array([e])).values
    exact = np.array_equal(result["hull"].sel(alpha=1.0, bound="upper").values, deterministic)
    print(f"\n1. swing, fuzzy E ±10 %, {duration:g} s, {result.sizes['time']} time nodes, stride 100")
    print(f"   GFA: {result.attrs['wall_time_s']:.1f} s wall, "
          f"{result.attrs['forward_simulations']} forward simulations "
          f"(with sensitivities), {result.attrs['optimisations']} optimisations")  # fmt: skip
    print(f"   dense reference: 41 forward simulations, {dense_wall:.1f} s wall ({max(workers, 1)} worker(s))")
    print(f"   max |hull − dense| α = 0: upper {np.max(np.abs(upper - dense.max(0))):.3e} J, "
          f"lower {np.max(np.abs(lower - dense.min(0))):.3e} J (max target {scale:.3e} J; "
          f"{100 * max(np.max(np.abs(upper - dense.max(0))), np.max(np.abs(lower - dense.min(0)))) / scale:.3f} %)")  # fmt: skip
    print(f"   GFA hull narrower than dense by at most {max(np.max(dense.max(0) - upper), np.max(lower - dense.min(0))):.3e} J; "
          f"wider by at most {max(np.max(upper - dense.max(0)), np.max(dense.min(0) - lower)):.3e} J")  # fmt: skip
    print(f"   α = 1 hull equals the deterministic run bit for bit: {exact}")
    FIGURES.mkdir(exist_ok=True)
    save_figure(hull_figure(result), FIGURES / "fuzzy_swing_E.png")
    if pool is not None:
        pool.close()


def swing_eleven_parameters(duration: float) -> None:
    sim = LegSimulator("swing")
    base = sim.parameters(eta=SWING_DAMPING)
    target = LegTarget(base=base, settings=SolverSettings(duration=duration))
    result = fuzzy_forward_dynamics(sim, {n: 0.1 for n in ELEVEN_PARAMETERS}, target=target)
    one = fuzzy_forward_dynamics(sim, {"E": 0.1}, target=target)
    print(f"\n2. swing, 11 fuzzy parameters ±10 %, {duration:g} s")
    for label, r in (("11 parameters", result), ("1 parameter", one)):
        print(f"   {label}: {r.attrs['wall_time_s']:.1f} s wall, {r.attrs['forward_simulations']} forward simulations, "
              f"{r.attrs['optimisations']} optimisations, library {r.attrs['library_size']}")  # fmt: skip
    print(f"   ratio 11/1: wall {result.attrs['wall_time_s'] / one.attrs['wall_time_s']:.2f}×, "
          f"simulations {result.attrs['forward_simulations'] / one.attrs['forward_simulations']:.2f}×")  # fmt: skip
    # How many of those simulations do the hulls need? Re-simulate the distinct extremisers
    # (no sensitivities) and find the fewest that keep the hulls within 1 % / 0.1 % of their width.
    for label, r in (("11 parameters", result), ("1 parameter", one)):
        names = r.attrs["fuzzy_parameters"]
        model = LegTargetModel(sim, r.attrs["target"], names, base=base, settings=SolverSettings(duration=duration))
        params = FuzzyVector([triangular_relative(model.base[LEG_PARAMETERS.index(n)], 0.1, n) for n in names])
        def trajectory(p: np.ndarray, model: LegTargetModel = model) -> np.ndarray:
            return model.evaluate(p).values

        distinct, [(lp1, greedy1), (lp01, greedy01)] = sufficient_runs(r, params, trajectory, (0.01, 0.001))
        print(f"   {label}: the hulls are attained by {distinct} distinct parameter sets; {lp1}-{greedy1} of them keep "
              f"every hull within 1 % of its width, {lp01}-{greedy01} within 0.1 % (LP lower bound - greedy cover)")  # fmt: skip
    save_figure(extremiser_figure(result), FIGURES / "fuzzy_swing_11_parameter_sets.png")
    save_figure(hull_figure(result), FIGURES / "fuzzy_swing_11.png")


def stance_one_parameter(duration: float) -> None:
    sim = LegSimulator("stance")
    base = sim.parameters(E=STANCE_MODULUS)
    result = fuzzy_forward_dynamics(sim, {"E": 0.1}, target=LegTarget(
        base=base, settings=SolverSettings(duration=duration, scheme="energy-momentum")))
    print(f"\n3. stance, fuzzy E ±10 % about {STANCE_MODULUS:g} Pa (Table 5.3), max element energy, "
          f"{duration:g} s (energy-momentum)")
    print(f"   GFA: {result.attrs['wall_time_s']:.1f} s wall, "
          f"{result.attrs['forward_simulations']} forward simulations, "
          f"{result.attrs['optimisations']} optimisations")  # fmt: skip
    save_figure(hull_figure(result), FIGURES / "fuzzy_stance_E.png")


def layered_blade(duration: float) -> None:
    from fuzzygait.mechanics.layered_blade import LayeredBladeModel
    from fuzzygait.uncertainty import Linearised, graph_follower

    print(f"\n4. layered blade (coupled homogenisation), clamped, 500 N on the toe, {min(duration, 0.3):g} s; "
          "fuzzy face modulus, core modulus, face thickness ±10 % (finite-difference linearisation)")  # fmt: skip
    for target, name in (("toe_z", "fuzzy_layers_toe_z.png"), ("total_deformation_energy", "fuzzy_layers_energy.png")):
        model = LayeredBladeModel(target=target, duration=min(duration, 0.3))
        numbers = [triangular_relative(v, 0.1, n) for v, n in zip(model.base, model.names)]
        start = time.perf_counter()
        result = graph_follower(model, FuzzyVector(numbers), (0.0, 0.5, 1.0), strategy=Linearised(stride=30))
        wall = time.perf_counter() - start
        result.attrs.update(scenario="layered blade", target=target, target_units="m" if target == "toe_z" else "J",
                            fuzzy_parameters=list(model.names), fuzzy_spreads=[0.1] * 3)  # fmt: skip
        end = result["hull"].isel(time=-1)
        print(f"   {target}: {wall:.1f} s wall, {result.attrs['forward_simulations']} forward simulations; at "
              f"t = {model.times[-1]:g} s α = 0 hull [{float(end.sel(alpha=0.0, bound='lower')):.5g}, "
              f"{float(end.sel(alpha=0.0, bound='upper')):.5g}], deterministic {float(result['deterministic'][-1]):.5g}")  # fmt: skip
        save_figure(hull_figure(result), FIGURES / name)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="0.5 s instead of 2 s")
    parser.add_argument("--workers", type=int, default=1, help="processes for the dense reference")
    parser.add_argument("--cases", default="1,2,3,4")
    args = parser.parse_args()
    duration = 0.5 if args.quick else 2.0
    cases = {c.strip() for c in args.cases.split(",")}
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    if "1" in cases:
        swing_one_parameter(duration, args.workers)
    if "2" in cases:
        swing_eleven_parameters(duration)
    if "3" in cases:
        stance_one_parameter(duration)
    if "4" in cases:
        layered_blade(duration)


if __name__ == "__main__":
    main()
