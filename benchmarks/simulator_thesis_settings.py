"""The thesis' own simulator settings (issue 37.4): which runs, and the energy error over time.

Run:  .venv/bin/python benchmarks/simulator_thesis_settings.py                 (about 2 minutes)
      .venv/bin/python benchmarks/simulator_thesis_settings.py --duration 0.5  (quicker)
      .venv/bin/python benchmarks/simulator_thesis_settings.py --diagnosis     (also the diagnosis tables)

Diagnosis (``--diagnosis``, first): (1) the Table 4.3 swing at eta = 1 against the time step,
the scheme, the node count, the damping and the stiffness — when and where the blade folds;
(2) the Table 4.4 stance with the variational integrator without step refinement
(``integrate``, ``SolverSettings(max_halvings=0)``) at dt, dt/2, dt/4: where it stops and its energy error.

Cases, each with the variational integrator (thesis Eq. 4.26) and the energy-momentum
scheme, at eta = 0 (conservative), 1 (Tables 4.3/4.4) and 1e5 Pa s (the swing command
default), dt = 1 ms, 20 blade nodes (the thesis'):

* swing, Table 4.3 blade (E = 59.95e4 Pa, rho = 8550 kg/m³) — folds on the shipped blade;
* swing, the same blade with E = 2e7 Pa (the softest of 6e6 / 2e7 / 6e7 that runs at eta = 1);
* stance, Table 4.4 (E = 59.958e7 Pa, shank 107 kg).

The energy error is the balance ``E(t) + D(t) − E(0)`` (kinetic + gravitational + internal
energy plus the dissipated energy; no external work in either scenario), printed in J at
a few times and as its maximum relative to the largest energy in motion,
``max_t (kinetic + internal)``.  ``substeps`` > 1: :func:`fuzzygait.mechanics.integrator.integrate`
repeated the run with dt/substeps after a step that did not converge (energies are then
evaluated on the 1 ms output grid).
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import os  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.core.errors import SimulationError  # noqa: E402
from fuzzygait.mechanics.integrator import integrate  # noqa: E402
from fuzzygait.mechanics.scenarios import LegSimulator, energy_balance_error  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402
from fuzzygait.mechanics.trajectory import trajectory_energies  # noqa: E402

CASES = (
    ("swing, Table 4.3", "swing", {}),
    ("swing, E = 2e7 Pa", "swing", {"E": 2e7}),
    ("stance, Table 4.4", "stance", {}),
)
ETAS = (0.0, 1.0, 1e5)
SCHEMES = ("variational", "energy-momentum")


def diagnosis(nodes: int) -> None:
    print("### Swing, Table 4.3 blade (E = 59.95e4 Pa, rho = 8550 kg/m³), 2 s: when does it fold?")
    print()
    print("| nodes | dt ms | scheme | eta Pa s | E Pa | outcome |")
    print("|---|---|---|---|---|---|")
    rows = [(nodes, 1e-3, "variational", 1.0, None), (nodes, 5e-4, "variational", 1.0, None),
            (nodes, 2.5e-4, "variational", 1.0, None), (nodes, 1e-3, "energy-momentum", 1.0, None),
            (nodes, 1e-3, "variational", 0.0, None), (2 * nodes, 1e-3, "variational", 1.0, None),
            (4 * nodes, 1e-3, "variational", 1.0, None), (nodes, 1e-3, "variational", 1e4, None),
            (nodes, 1e-3, "variational", 2e4, None), (nodes, 1e-3, "variational", 3e4, None),
            (nodes, 1e-3, "variational", 1.0, 6e6), (nodes, 1e-3, "variational", 1.0, 2e7)]  # fmt: skip
    sims: dict[int, LegSimulator] = {}
    for n, dt, scheme, eta, stiffness in rows:
        sim = sims.get(n) or sims.setdefault(n, LegSimulator("swing", nodes=n))
        p = sim.parameters(eta=eta, **({} if stiffness is None else {"E": stiffness}))
        try:
            ds = sim.run(p, SolverSettings(dt=dt, duration=2.0, scheme=scheme))
            outcome = f"runs the 2 s ({ds.attrs['substeps']} sub-steps per dt)"
        except SimulationError as error:
            outcome = str(error).split(": its")[0]
        e_text = f"{stiffness:g}" if stiffness is not None else "59.95e4"
        print(f"| {n} | {1e3 * dt:g} | {scheme} | {eta:g} | {e_text} | {outcome} |", flush=True)
    print()
    print("### Stance, Table 4.4, variational integrator without step refinement, 2 s")
    print()
    print("| dt ms | outcome | E+D−E0 shortly before J (t s) | max rel energy error | wall s |")
    print("|---|---|---|---|---|")
    sim = LegSimulator("stance", nodes=nodes)
    p = sim.parameters()
    for dt in (1e-3, 5e-4, 2.5e-4):
        n_steps = int(round(2.0 / dt))
        start = time.perf_counter()
        try:
            settings = SolverSettings(dt=dt, n_steps=n_steps, max_halvings=0)
            trajectory = integrate(sim.model, sim.leg.q0, None, p, settings)
            outcome = "runs the 2 s"
        except SimulationError as error:
            outcome = str(error).split(": residual")[0]
            last = int(round(float(outcome.split("t = ")[1].split(" s")[0]) / dt)) - 1
            trajectory = integrate(sim.model, sim.leg.q0, None, p, SolverSettings(dt=dt, n_steps=last, max_halvings=0))
        wall = time.perf_counter() - start
        energies = trajectory_energies(sim.model, trajectory, p)
        balance = energies.total + energies.dissipated
        error = balance - balance[0]
        k = int(np.argmax(np.abs(error)))
        print(f"| {1e3 * dt:g} | {outcome} | {error[k]:+.3g} ({trajectory.times[k]:.3f}) | "
              f"{energy_balance_error(energies):.2g} | {wall:.1f} |", flush=True)  # fmt: skip
    print()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.0, help="simulated time, s (default 2)")
    parser.add_argument("--nodes", type=int, default=20, help="blade nodes (default 20)")
    parser.add_argument("--dt", type=float, default=1e-3, help="time step, s (default 1e-3)")
    parser.add_argument("--diagnosis", action="store_true", help="first the fold and step diagnosis tables")
    args = parser.parse_args()
    if args.diagnosis:
        diagnosis(args.nodes)
    marks = [t for t in (0.25, 0.5, 1.0, 1.5, 2.0) if t <= args.duration + 1e-12]
    one, five, _ = os.getloadavg()
    print(f"## Energy balance at the thesis' settings: {args.nodes} nodes, dt = {args.dt:g} s, "
          f"{args.duration:g} s; load average {one:.2f}, {five:.2f}")  # fmt: skip
    print()
    print("| case | eta Pa s | scheme | outcome | substeps | " + " | ".join(f"E+D−E0 at {t:g} s J" for t in marks)
          + " | max abs J | max rel | wall s |")  # fmt: skip
    print("|---" * (8 + len(marks)) + "|")
    sims: dict[str, LegSimulator] = {}
    for label, scenario, values in CASES:
        sim = sims.get(scenario) or sims.setdefault(scenario, LegSimulator(scenario, nodes=args.nodes))
        for eta in ETAS:
            p = sim.parameters(eta=eta, **values)
            for scheme in SCHEMES:
                try:
                    ds = sim.run(p, SolverSettings(dt=args.dt, duration=args.duration, scheme=scheme))
                except SimulationError as error:
                    reason = str(error).split("; parameters")[0]
                    print(f"| {label} | {eta:g} | {scheme} | {reason} |" + " |" * (4 + len(marks)), flush=True)
                    continue
                t = ds.time.values
                balance = ds.total_energy.values + ds.dissipated_energy.values
                error = balance - balance[0]
                scale = float(np.max(ds.kinetic_energy.values + ds.internal_energy.values))
                at = [error[int(np.argmin(np.abs(t - m)))] for m in marks]
                worst = float(np.max(np.abs(error)))
                wall = ds.attrs["wall_time_s"]
                print(f"| {label} | {eta:g} | {scheme} | ran {t[-1]:g} s | {ds.attrs['substeps']} | "
                      + " | ".join(f"{e:+.2e}" for e in at)
                      + f" | {worst:.2e} | {worst / scale:.1e} | {wall:.1f} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
