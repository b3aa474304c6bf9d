"""Speed of the leg + prosthesis simulator (thesis §4.2.4, swing and stance, 20 nodes).

Run:  .venv/bin/python benchmarks/simulator_speed.py            (about 1 minute)
      .venv/bin/python benchmarks/simulator_speed.py --quick    (0.5 s runs, ~5 s)

Times ``LegSimulator.run`` for 2 s of simulated time at dt = 1 ms with 20 blade nodes:

* swing (a): the stiff reverse-engineered blade of Table 4.2 (E = 59958e6 Pa, rho = 1710
  kg/m³, eta = 1) in the swing pose;
* swing (b): the thesis' soft swing preset (Table 4.3, E = 59.95e4 Pa, rho = 8550) with
  eta = 1e3 (the shipped eta = 1 does not run 2 s at dt = 1 ms), and with eta = 1e5 in
  case eta = 1e3 fails too;
* stance: the squat preset (Table 4.4, 107 kg shank) with eta = 1e5.

Per run: wall time of the integration alone (``ds.attrs["wall_time_s"]``) and of the
whole ``run`` call (integration + energies + xarray Dataset), Newton iterations per step,
LU factorisations, the integration time split per Newton iteration into evaluation
(residuals and Jacobians assembled from the compiled CasADi element kernels), sparse LU
factorisation and triangular solves (the rest is the Python step loop), time per step,
and the energy balance error max_t |E(t) + D(t) − E(0)| (E = kinetic + gravitational +
internal, D = dissipated) in J and relative to |E(0)| (E(0) is mostly gravitational
energy, whose zero is arbitrary, so the J column is the meaningful one).  Each case is
run with every integration scheme given by ``--schemes`` (the variational integrator of
the thesis, Eq. 4.26, and the energy-momentum scheme).  Best of ``--repeats`` runs.

Also timed: building the model the first time (symbolic assembly, C code generation and
compilation, in a fresh empty cache directory) against loading it from the on-disk cache,
and one run of swing (a) with parameter sensitivities (12 parameters, forward
sensitivities: one extra exact LU and a 12-column back-substitution per step) against the
same run without.

Target (issue): ≤ 4 s wall on one core for 2 s simulated (Exudyn 1.13, C++, needs ≈ 3 s
for a comparable leg with a 19-element 3-D beam at dt = 1 ms).  One core: BLAS threads are
pinned to 1 and SuperLU is single-threaded.
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import argparse  # noqa: E402
import os  # noqa: E402
import shutil  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.core.errors import SimulationError  # noqa: E402
from fuzzygait.mechanics.scenarios import LegSimulator  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402

STIFF = dict(E=59958e6, rho=1710.0, eta=1.0)  # Table 4.2, reverse-engineered blade
TARGET_S = 4.0  # s wall per 2 s simulated (issue)


@dataclass
class Case:
    label: str
    scenario: str
    overrides: dict = field(default_factory=dict)


CASES = [
    Case("swing (a) stiff blade, eta=1", "swing", STIFF),
    Case("swing (b) soft preset, eta=1e3", "swing", dict(eta=1e3)),
    Case("swing (b) soft preset, eta=1e5", "swing", dict(eta=1e5)),
    Case("stance preset, eta=1e5", "stance", dict(eta=1e5)),
]


def git_state() -> str:
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "src"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
        return f"{head}{' + uncommitted changes in src/' if dirty else ''}"
    except OSError:
        return "unknown"


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f}, {five:.2f}, {fifteen:.2f}"


def timed_run(sim: LegSimulator, p: np.ndarray, dt: float, duration: float, repeats: int, **kwargs):
    """Best (smallest integration wall time) of ``repeats`` runs: (dataset, total s), or
    (None, error message) when the run fails."""
    best, best_total = None, np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        try:
            ds = sim.run(p, SolverSettings(dt=dt, duration=duration, scheme=kwargs.get("scheme", "variational")),
                         sensitivities=kwargs.get("sensitivities", False))
        except SimulationError as error:
            return None, str(error)
        total = time.perf_counter() - start
        if best is None or ds.attrs["wall_time_s"] < best.attrs["wall_time_s"]:
            best, best_total = ds, total
    return best, best_total


def summary(ds) -> dict:
    a = ds.attrs
    steps = ds.sizes["step"]
    iterations = int(ds.newton_iterations.sum())
    balance = ds.total_energy.values + ds.dissipated_energy.values
    drift = np.abs(balance - balance[0])
    wall = a["wall_time_s"]
    per_it = lambda key: 1e6 * a.get(key, 0.0) / max(iterations, 1)  # noqa: E731
    other = wall - sum(a.get(k, 0.0) for k in ("time_evaluation_s", "time_factorisation_s", "time_solve_s", "time_sensitivity_s"))
    return dict(
        wall=wall,
        steps=steps,
        it_mean=iterations / steps,
        it_max=int(ds.newton_iterations.max()),
        factorisations=int(a["factorisations"]),
        eval_us=per_it("time_evaluation_s"),
        lu_us=per_it("time_factorisation_s"),
        lu_each_ms=1e3 * a.get("time_factorisation_s", 0.0) / max(a["factorisations"], 1),
        solve_us=per_it("time_solve_s"),
        other_us=1e6 * max(other, 0.0) / max(iterations, 1),
        step_ms=1e3 * wall / steps,
        drift_j=float(drift.max()),
        drift_rel=float(drift.max() / abs(balance[0])),
        sensitivity=a.get("time_sensitivity_s", 0.0),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="0.5 s runs, one repeat, variational only, no compile timing")
    parser.add_argument("--duration", type=float, default=None, help="simulated time per run, s (default 2, quick 0.5)")
    parser.add_argument("--dt", type=float, default=1e-3, help="time step, s (default 1e-3)")
    parser.add_argument("--nodes", type=int, default=20, help="blade nodes (default 20)")
    parser.add_argument("--repeats", type=int, default=None, help="runs per case, best reported (default 3, quick 1)")
    parser.add_argument("--schemes", default=None, help="comma-separated integration schemes "
                        "(default 'variational,energy-momentum', quick 'variational')")
    parser.add_argument("--sensitivity-duration", type=float, default=None, help="simulated time of the sensitivity comparison (default 0.5 s, quick 0.2 s)")
    parser.add_argument("--no-compile-timing", action="store_true", help="skip timing the first build in an empty cache")
    args = parser.parse_args()
    duration = args.duration or (0.5 if args.quick else 2.0)
    repeats = args.repeats or (1 if args.quick else 3)
    schemes = (args.schemes or ("variational" if args.quick else "variational,energy-momentum")).split(",")
    sens_duration = args.sensitivity_duration or (0.2 if args.quick else 0.5)
    compile_timing = not (args.quick or args.no_compile_timing)

    print("## Leg simulator speed (20-node blade, one core)")
    print(f"code: {git_state()}; load average at start (1, 5, 15 min): {load()}; "
          f"dt = {args.dt:g} s, {duration:g} s simulated, best of {repeats}")
    print()

    scratch = None
    if compile_timing:  # a fresh, empty cache directory: the first build generates and compiles C code
        scratch = tempfile.mkdtemp(prefix="fuzzygait-cache-")
        os.environ["FUZZYGAIT_CACHE_DIR"] = scratch
    simulators: dict[str, LegSimulator] = {}
    build_rows = []
    for scenario in dict.fromkeys(c.scenario for c in CASES):
        start = time.perf_counter()
        simulators[scenario] = LegSimulator(scenario, nodes=args.nodes)
        first = time.perf_counter() - start
        start = time.perf_counter()
        LegSimulator(scenario, nodes=args.nodes)
        again = time.perf_counter() - start
        build_rows.append((scenario, first, again, simulators[scenario].model.compiled))
    print("### Building the model (LegSimulator(...))")
    first_header = "compile (first run, empty cache) s" if compile_timing else "first build (existing cache) s"
    print(f"| scenario | {first_header} | load from cache s | compiled |")
    print("|---|---|---|---|")
    for scenario, first, again, compiled in build_rows:
        print(f"| {scenario} | {first:.2f} | {again:.3f} | {bool(compiled)} |")
    print()

    print(f"### Runs: {duration:g} s simulated at dt = {args.dt:g} s")
    print("| case | scheme | integration wall s | run() total s | Newton it/step (max) | LU factorisations "
          "| per iteration µs: eval / LU / solve / other | ms per LU | ms per step | max energy error J | relative to |E(0)| |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    results = {}
    for case in CASES:
        sim = simulators[case.scenario]
        p = sim.parameters(**case.overrides)
        for scheme in schemes:
            kwargs = {} if scheme == "variational" else {"scheme": scheme}
            ds, total = timed_run(sim, p, args.dt, duration, repeats, **kwargs)
            if ds is None:
                reason = total.split(": ")[0]  # "Newton did not converge at t = …" / "… folded at t = …"
                print(f"| {case.label} | {scheme} | failed: {reason} | | | | | | | | |")
                continue
            s = summary(ds)
            results[(case.label, scheme)] = s
            print(f"| {case.label} | {scheme} | {s['wall']:.2f} | {total:.2f} | {s['it_mean']:.2f} ({s['it_max']}) "
                  f"| {s['factorisations']} | {s['eval_us']:.0f} / {s['lu_us']:.0f} / {s['solve_us']:.0f} / {s['other_us']:.0f} "
                  f"| {s['lu_each_ms']:.2f} | {s['step_ms']:.2f} | {s['drift_j']:.2e} | {s['drift_rel']:.1e} |")
    print("(eval: residuals + Jacobian assembly incl. the compiled CasADi kernels; LU: SuperLU "
          "factorisation (COLAMD) of the refreshed Jacobians; solve: triangular solves; other: the "
          "Python step loop. 'per iteration' divides each total by all Newton iterations of the run.)")
    scale = 2.0 / duration
    for (label, scheme), s in results.items():
        if scheme == "variational":
            projected = s["wall"] * scale
            verdict = "met" if projected <= TARGET_S else "NOT met"
            note = "" if scale == 1.0 else f" (projected from {duration:g} s)"
            print(f"target ≤ {TARGET_S:g} s per 2 s simulated, {label}: {projected:.2f} s{note} — {verdict}")
    print()

    # sensitivities: swing (a), variational scheme only
    sim = simulators["swing"]
    p = sim.parameters(**STIFF)
    plain, plain_total = timed_run(sim, p, args.dt, sens_duration, repeats)
    sens, sens_total = timed_run(sim, p, args.dt, sens_duration, repeats, sensitivities=True)
    print(f"### Parameter sensitivities, swing (a), {sens_duration:g} s simulated, 12 parameters")
    print("| run | integration wall s | run() total s | ms per step | Newton it/step | LU factorisations | sensitivity part s |")
    print("|---|---|---|---|---|---|---|")
    if plain is None or sens is None:
        print(f"| failed | {plain_total if plain is None else sens_total} | | | | | |")
    else:
        a, b = summary(plain), summary(sens)
        print(f"| without | {a['wall']:.2f} | {plain_total:.2f} | {a['step_ms']:.2f} | {a['it_mean']:.2f} | {a['factorisations']} | – |")
        print(f"| with dq/dp | {b['wall']:.2f} | {sens_total:.2f} | {b['step_ms']:.2f} | {b['it_mean']:.2f} | {b['factorisations']} | {b['sensitivity']:.2f} |")
        print(f"per-step cost ratio with/without sensitivities: {b['wall'] / a['wall']:.2f} "
              f"(run() total incl. the target-output sensitivities: {sens_total / plain_total:.2f}); "
              "the sensitivity part includes the exact Jacobian's LU at every converged step")
    print()
    print(f"load average at end (1, 5, 15 min): {load()}")
    if scratch is not None:
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
