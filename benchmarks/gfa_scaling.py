"""Scaling of the Graph Follower algorithm: 1 vs 11 fuzzy parameters (thesis §5.3.1).

Run:  .venv/bin/python benchmarks/gfa_scaling.py

The thesis (Table 5.1) reports that its modified Graph Follower algorithm on the leg
model with a prosthetic foot took 1.05x the run time with 11 fuzzy parameters as with 1
(1000 time nodes; 0.89x for 2000). This script repeats that comparison on a cheap,
smooth model with analytic sensitivities so that it runs in a minute:

    f(p, t) = sum_k A_k exp(-delta c_k t) sin(omega_k t + phi_k),   k = 1..5,
    p = (omega_1..omega_5 [rad/s], A_1..A_5, delta [1/s])           (11 parameters),

every parameter a triangular fuzzy number ±10 % around its deterministic value (as in
the thesis), α-levels 0, 0.5, 1, time 0–2 s with 1000 and 2000 nodes, optimisation at
every 100th node (the thesis' setting) and at every node.

Which comparison is fair?  The thesis keeps the model and changes only which parameters
are fuzzy. We do the same: "1 fuzzy of 11" is the *same* 11-parameter model with one
parameter fuzzy and the other ten crisp (degenerate fuzzy numbers ``triangular(v, v, v)``).
Both runs therefore pay the same price per model evaluation (trajectory + full Jacobian)
and differ only in the α-level sets the engine optimises over. The ratio 11/1 depends on
*which* parameter is the single fuzzy one, so two are shown: omega1 (the dominant
frequency: it shifts the phase, so its extremes are often interior — the reference for
the ratios) and A1 (an amplitude: monotone effect, extremes always at the interval ends).
A third row uses a genuinely 1-parameter model (the other ten values baked in, a 1-column
Jacobian): it shows how much of the difference is the model's own cost rather than the
algorithm's.

Quality is checked against references: for 1 fuzzy parameter a dense grid of 2001
values per α-cut; for 11 a sample of 20,000 uniform random points plus the 2,048
vertices of each α-cut box. Sampling can only miss extremes, so it is a *lower bound*
on the true hull: we report at how many (α, node) pairs the GFA hull contains the
sampled one, the largest shortfall where it does not, and the largest excess (GFA hull
beyond the sample). The single-step variant (``max_iterations=1``, the thesis' step) is
shown for comparison.

Takes about two minutes and ~3.5 GB of memory (the 11-parameter stride-1 runs).
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import itertools  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from fuzzygait.uncertainty import (  # noqa: E402
    Evaluation,
    FuzzyVector,
    Linearised,
    Output,
    graph_follower,
    sufficient_runs,
    triangular,
    triangular_relative,
)

OMEGA = 2 * np.pi * np.array([1.0, 1.7, 2.9, 4.3, 6.1])  # rad/s
AMPLITUDE = np.array([1.0, 0.6, 0.4, 0.25, 0.15])
DELTA = 0.4  # 1/s
PHASE = np.array([0.0, 0.5, 1.0, 1.5, 2.0])  # rad
DECAY = np.array([1.0, 1.2, 1.4, 1.6, 1.8])  # per-oscillator damping multiple
P_DET = np.concatenate([OMEGA, AMPLITUDE, [DELTA]])
NAMES = [f"omega{k + 1}" for k in range(5)] + [f"A{k + 1}" for k in range(5)] + ["delta"]
SPREAD = 0.10  # ±10 %, as in the thesis
ALPHAS = (0.0, 0.5, 1.0)
DURATION = 2.0  # s
REPEATS = 3
N_SAMPLES = 20_000
GRID = 2001


@dataclass
class Oscillators:
    """Sum of five damped oscillators; ``free`` are the indices (into ``P_DET``) of the
    model's parameters, the others are fixed at their deterministic values. A model of the
    engine's protocol with analytic sensitivities."""

    times: np.ndarray
    free: np.ndarray = field(default_factory=lambda: np.arange(P_DET.size))
    seconds: float = 0.0  # time spent inside the model

    output = Output("oscillators", "", "sum of five damped oscillators")
    capabilities = frozenset({"sensitivities"})

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(NAMES[int(i)] for i in self.free)

    def _full(self, p: np.ndarray) -> np.ndarray:
        """``(n, 11)`` full parameter rows from ``(n, n_free)`` free values."""
        full = np.tile(P_DET, (p.shape[0], 1))
        full[:, self.free] = p
        return full

    def evaluate_many(self, p: np.ndarray) -> np.ndarray:
        """``(n, n_time)`` trajectories for ``(n, n_free)`` parameter rows."""
        full = self._full(np.atleast_2d(p))
        omega, amp, delta = full[:, :5, None], full[:, 5:10, None], full[:, 10, None, None]
        t = self.times[None, None, :]
        return np.sum(amp * np.exp(-delta * DECAY[None, :, None] * t) * np.sin(omega * t + PHASE[None, :, None]), axis=1)

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        """The trajectory and, with ``sensitivities``, the analytic Jacobian
        ``(n_time, n_free)`` in the same evaluation."""
        if sensitivities:
            return Evaluation(*self._with_sensitivities(p))
        start = time.perf_counter()
        f = self.evaluate_many(p[None, :])[0]
        self.seconds += time.perf_counter() - start
        return Evaluation(f)

    def _with_sensitivities(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        start = time.perf_counter()
        full = self._full(p[None, :])[0]
        omega, amp, delta = full[:5, None], full[5:10, None], full[10]
        t = self.times[None, :]
        envelope = np.exp(-delta * DECAY[:, None] * t)
        phase = omega * t + PHASE[:, None]
        sin, cos = np.sin(phase), np.cos(phase)
        terms = amp * envelope * sin  # (5, n_time)
        columns = {
            **{k: amp[k] * envelope[k] * cos[k] * self.times for k in range(5)},  # d/d omega_k
            **{5 + k: envelope[k] * sin[k] for k in range(5)},  # d/d A_k
        }
        jac = np.empty((self.times.size, self.free.size))
        for j, index in enumerate(self.free):
            if index == 10:  # d/d delta
                jac[:, j] = -np.sum(DECAY[:, None] * t * terms, axis=0)
            else:
                jac[:, j] = columns[int(index)]
        self.seconds += time.perf_counter() - start
        return terms.sum(axis=0), jac


@dataclass(frozen=True)
class Case:
    """Which parameters are fuzzy (indices into ``P_DET``); ``genuine``: use a model whose
    only parameter is the single fuzzy one instead of 1 fuzzy of 11."""

    label: str
    fuzzy: tuple[int, ...]
    genuine: bool = False

    def model(self, times: np.ndarray) -> Oscillators:
        return Oscillators(times, np.array(self.fuzzy) if self.genuine else np.arange(P_DET.size))

    def params(self) -> FuzzyVector:
        if self.genuine:
            return FuzzyVector([triangular_relative(P_DET[i], SPREAD, NAMES[i]) for i in self.fuzzy])
        return FuzzyVector(
            [
                triangular_relative(v, SPREAD, name) if i in self.fuzzy else triangular(v, v, v, name)
                for i, (v, name) in enumerate(zip(P_DET, NAMES))
            ]
        )


ALL = Case("11 fuzzy", tuple(range(P_DET.size)))
OMEGA1 = Case("1 fuzzy of 11: omega1", (0,))
CASES = [
    ALL,
    OMEGA1,  # the fair reference: same model, the hardest single parameter
    Case("1 fuzzy of 11: A1", (5,)),  # an easy one: monotone effect, extremes at the ends
    Case("1-parameter model: omega1", (0,), genuine=True),  # cheaper model (1-column Jacobian)
]


def run(case: Case, n_time: int, stride: int, max_iterations: int = 4) -> tuple[float, float, xr.Dataset]:
    """Best wall time of ``REPEATS`` runs, the model's share of it, and the result."""
    times = np.linspace(0.0, DURATION, n_time)
    best, model_share, result = np.inf, 0.0, None
    for _ in range(REPEATS):
        model = case.model(times)
        start = time.perf_counter()
        strategy = Linearised(stride=stride, max_iterations=max_iterations)
        result = graph_follower(model, case.params(), alphas=ALPHAS, strategy=strategy)
        wall = time.perf_counter() - start
        if wall < best:
            best, model_share = wall, model.seconds / wall
        del model  # free the library before the next repeat
    return best, model_share, result


def reference_hulls(case: Case, times: np.ndarray, rng: np.random.Generator) -> dict[float, tuple[np.ndarray, np.ndarray]]:
    """Sampled lower/upper hulls per α < 1 (dense grid for 1 fuzzy parameter, random
    points plus box vertices for several)."""
    model = Oscillators(times)
    params = Case(case.label, case.fuzzy).params()  # the same α-cuts, in the 11-parameter model
    out = {}
    for alpha in ALPHAS[:-1]:
        box = params.domain(alpha)
        if len(case.fuzzy) == 1:
            i = case.fuzzy[0]
            points = np.tile(P_DET, (GRID, 1))
            points[:, i] = np.linspace(box.lower[i], box.upper[i], GRID)
        else:
            vertices = np.array(list(itertools.product([0.0, 1.0], repeat=P_DET.size)))
            unit = np.vstack([rng.random((N_SAMPLES, P_DET.size)), vertices])
            points = box.lower + (box.upper - box.lower) * unit
        lower, upper = np.full(times.size, np.inf), np.full(times.size, -np.inf)
        for chunk in np.array_split(points, max(1, points.shape[0] // 500)):
            f = model.evaluate_many(chunk)
            lower, upper = np.minimum(lower, f.min(axis=0)), np.maximum(upper, f.max(axis=0))
        out[alpha] = (lower, upper)
    return out


def quality(result: xr.Dataset, reference: dict[float, tuple[np.ndarray, np.ndarray]], scale: float) -> tuple[float, float, float]:
    """Fraction of (α, node) pairs where the GFA hull contains the reference hull (to
    1e-6 of ``scale``), the largest shortfall and the largest excess (GFA wider), both
    in % of ``scale``."""
    tol = 1e-6 * scale
    contained, shortfall, excess, total = 0, 0.0, 0.0, 0
    for alpha, (ref_lo, ref_hi) in reference.items():
        lo = result["hull"].sel(alpha=alpha, bound="lower").to_numpy()
        hi = result["hull"].sel(alpha=alpha, bound="upper").to_numpy()
        short = np.maximum(lo - ref_lo, ref_hi - hi)  # > 0: the reference reaches further
        contained += int(np.sum(short <= tol))
        total += short.size
        shortfall = max(shortfall, float(short.max()))
        excess = max(excess, float(np.max(np.maximum(ref_lo - lo, hi - ref_hi))))
    return contained / total, 100 * max(shortfall, 0.0) / scale, 100 * max(excess, 0.0) / scale


def main() -> None:
    rng = np.random.default_rng(1)
    print("## Graph Follower scaling: 1 vs 11 fuzzy parameters (linearised mode)")
    print(f"model: 5 damped oscillators, 11 parameters ±{SPREAD:.0%}, α = {ALPHAS}, "
          f"t = 0–{DURATION:g} s; wall time best of {REPEATS}; one core; max_iterations = 4 (default)")  # fmt: skip
    print()
    print("| fuzzy parameters | time nodes | stride | model evaluations | optimisations | library size "
          "| wall s | model share | wall ratio 11/1 | evaluation ratio 11/1 |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|")
    results = {}
    for n_time, stride in [(1000, 100), (2000, 100), (1000, 1), (2000, 1)]:
        rows = {case.label: run(case, n_time, stride) for case in CASES}
        results[n_time, stride] = rows
        w11, _, r11 = rows[ALL.label]
        for case in CASES:
            wall, share, r = rows[case.label]
            single = case is not ALL
            ratio = f"{w11 / wall:.2f}" if single else ""
            evals = f"{r11.attrs['forward_simulations'] / r.attrs['forward_simulations']:.1f}" if single else ""
            print(f"| {case.label} | {n_time} | {stride} | {r.attrs['forward_simulations']} | "
                  f"{r.attrs['optimisations']} | {r.attrs['library_size']} | {wall:.3f} | {share:.0%} | "
                  f"{ratio} | {evals} |")  # fmt: skip

    print()
    print("### run time vs time nodes (thesis Table 5.1 layout: ratio 2000/1000 nodes)")
    print("| fuzzy parameters | stride | wall 1000 | wall 2000 | ratio 2000/1000 |")
    print("|---|---|---|---|---|")
    for stride in (100, 1):
        for case in CASES[:2]:
            w1, w2 = results[1000, stride][case.label][0], results[2000, stride][case.label][0]
            print(f"| {case.label} | {stride} | {w1:.3f} | {w2:.3f} | {w2 / w1:.2f} |")

    print()
    print(f"### hull quality, 2000 nodes (reference: 1 fuzzy: {GRID}-point grid per α-cut; "
          f"11 fuzzy: {N_SAMPLES:,} random points + 2,048 vertices per α-cut box)")  # fmt: skip
    print("| fuzzy parameters | max_iterations | stride | model evaluations | wall s "
          "| (α, node) pairs with GFA ⊇ reference | largest shortfall % | largest excess % |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    times = np.linspace(0.0, DURATION, 2000)
    scale = float(np.max(np.abs(Oscillators(times).evaluate(P_DET).values)))
    for case in CASES[:3]:
        reference = reference_hulls(case, times, rng)
        for max_iterations in (4, 1):
            for stride in (100, 1):
                if max_iterations == 4:
                    wall, _, r = results[2000, stride][case.label]
                else:  # the thesis' single linearised step per node
                    wall, _, r = run(case, 2000, stride, max_iterations=1)
                frac, short, excess = quality(r, reference, scale)
                print(f"| {case.label} | {max_iterations} | {stride} | {r.attrs['forward_simulations']} | "
                      f"{wall:.3f} | {frac:.1%} | {short:.3f} | {excess:.3f} |")  # fmt: skip
    print(f"(percent of the largest deterministic output magnitude, {scale:.3f}. 'shortfall': the sample "
          "reaches beyond the GFA hull; 'excess': the GFA hull reaches beyond the sample, which for 11 "
          "parameters shows how weak random sampling is as a reference — it is only a lower bound)")

    print()
    print("### how many forward runs does the hull need? (2000 nodes)")
    print("The final hulls (α < 1, both bounds) are attained by some distinct parameter sets. How few of them")
    print("keep every hull within 1 % / 0.1 % of its width (the runs that would have sufficed had one known them")
    print("in advance) is a set cover: shown as 'LP lower bound - greedy cover' (`uncertainty.sufficient_runs`).")
    print("| fuzzy parameters | stride | model evaluations | distinct extremisers | sufficient within 1 % "
          "| sufficient within 0.1 % |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    needed = {}
    for case in CASES[:3]:
        for stride in (100, 1):
            r = results[2000, stride][case.label][2]
            model, params = Oscillators(times), Case(case.label, case.fuzzy).params()
            distinct, [(one_lp, one), (tenth_lp, tenth)] = sufficient_runs(
                r, params, lambda p, model=model: model.evaluate(p).values, (0.01, 0.001))
            needed[case.label, stride] = (one_lp, one)
            print(f"| {case.label} | {stride} | {r.attrs['forward_simulations']} | {distinct} | {one_lp}-{one} "
                  f"| {tenth_lp}-{tenth} |")  # fmt: skip

    wall_ratios = [results[k][ALL.label][0] / results[k][OMEGA1.label][0] for k in results]
    eval_ratios = [results[k][ALL.label][2].attrs["forward_simulations"]
                   / results[k][OMEGA1.label][2].attrs["forward_simulations"] for k in results]  # fmt: skip
    per_opt = {k: results[k][ALL.label][2].attrs["forward_simulations"]
               / results[k][ALL.label][2].attrs["optimisations"] for k in results}  # fmt: skip
    share = results[2000, 1][ALL.label][1]
    big = results[2000, 1][ALL.label][2]
    jac_gb = big.attrs["library_size"] * big.sizes["time"] * P_DET.size * 8 / 1e9
    print(f"""
### how the cost scales, and why
* Summary: 11 vs 1 fuzzy parameter (omega1) costs {min(wall_ratios):.1f}-{max(wall_ratios):.1f}x the wall time and
  {min(eval_ratios):.1f}-{max(eval_ratios):.1f}x the model evaluations here. The thesis' 1.05x is NOT matched on this model.
* The model sets the ratio, not the algorithm: even had one known in advance which parameter
  sets to simulate, the 11-parameter hulls need at least {needed[ALL.label, 100][0]} (stride 100) / {needed[ALL.label, 1][0]} (stride 1) runs
  to stay within 1 % of their width (LP lower bound), while omega1 alone needs at most
  {needed[OMEGA1.label, 100][1]} / {needed[OMEGA1.label, 1][1]} and A1 alone {needed['1 fuzzy of 11: A1', 1][1]} (greedy cover; table "how many forward runs does the hull need?"):
  {needed[ALL.label, 100][0] / needed[OMEGA1.label, 100][1]:.0f}x / {needed[ALL.label, 1][0] / needed[OMEGA1.label, 1][1]:.0f}x for 11 vs 1 before any algorithm runs. (The bound counts the parameter
  sets that attain the hulls; each node's optimum is its own vertex or interior point, so a set
  outside them would have to be near-optimal at many nodes at once.) So no method that takes its
  hulls from forward runs can reach the thesis' 1.05x on this model at that accuracy; the
  Graph Follower spends {results[2000, 100][ALL.label][2].attrs['forward_simulations'] / needed[ALL.label, 100][0]:.1f}x the 11-parameter bound at stride 100.
* Per node the linearised α-level optimisation (OP-III) is closed form: the box vertex picked by
  the signs of the node's sensitivities, O(n_p) arithmetic and no optimiser run; the
  sensitivities come with the model run (trajectory + full Jacobian in one evaluation, no
  n_p + 1 finite-difference runs). So the number of fuzzy parameters costs almost nothing per
  node; what remains is (model evaluations) x (cost per evaluation) + library bookkeeping.
* The number of evaluations is the number of distinct extremising parameter sets met along the
  trajectory (each one is simulated once for the whole time span and reused by later nodes and
  α-levels, novelty tolerance Eq. 2.24). With one fuzzy parameter there are few: the two
  interval ends (A1: 5 evaluations in total) plus the moving interior optima of a
  phase-shifting parameter (omega1). With 11, the extremising vertex changes whenever any of
  the 11 sensitivities changes sign, and five frequencies add moving interior optima, so the
  count grows with n_p: {per_opt[2000, 1]:.2f} evaluations per optimisation at stride 1 and
  {per_opt[2000, 100]:.2f} at stride 100 (at most max_iterations = 4; at most 1 with
  max_iterations = 1, the thesis' single step).
* At stride 1 the wall ratio exceeds the evaluation ratio: the library bookkeeping grows with
  the library size m — every candidate's novelty check scans all entries (Library.closest,
  O(m n_p)) and every optimisation tests all entries for α-cut membership — i.e. quadratic in
  m overall; the model is only {share:.0%} of the 11-parameter, 2000-node, stride-1 run. Each
  entry also keeps its full Jacobian (m x nodes x n_p floats: {jac_gb:.1f} GB for that run).
* The thesis' 1.05x is consistent with a run time dominated by a per-optimisation cost that
  does not depend on n_p (fmincon MultiStart with ten starting points at every node, §2.6.3);
  the number of optimisations is the same for 1 and 11 parameters. Here that cost is
  microseconds, so the ratio exposes the evaluation count instead; for an expensive model the
  wall ratio tends to the 'evaluation ratio' column.
* The bound that does match the thesis: the number of forward simulations can never exceed
  1 + optimisations x max_iterations, whatever n_p is (each optimisation simulates at most
  max_iterations new points), and the optimisations are the same for 1 and 11 parameters. With
  the thesis' single step (max_iterations = 1) at stride 100 the 11-parameter run stays within
  that bound (80 evaluations for 84 optimisations, 0.04 s): if every optimisation of the
  1-parameter run needed a new simulation too -- likely for the thesis' non-monotone energy
  target -- both cost the same, i.e. a ratio of ~1. Our 1-parameter runs are cheaper than
  that worst case because the novelty tolerance reuses their few distinct extremisers.
* Quality: with 11 parameters the hull is a hard non-convex problem (products of phase shifts);
  the local linearised search leaves shortfalls against the sampled reference, and stride 100
  is too coarse for this oscillatory output (extremisers change within 100 nodes, unlike the
  thesis' case in Table 2.1). With one parameter and stride 1 the hulls match the dense grid.""")

if __name__ == "__main__":
    main()
