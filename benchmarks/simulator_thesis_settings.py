"""The thesis' own simulator settings (issue 37.4): which runs, and the energy error over time.

Run:  .venv/bin/python benchmarks/simulator_thesis_settings.py                 (about 2 minutes)
      .venv/bin/python benchmarks/simulator_thesis_settings.py --duration 0.5  (quicker)

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

import numpy as np  # noqa: E402

from fuzzygait.core.errors import SimulationError  # noqa: E402
from fuzzygait.mechanics.scenarios import LegSimulator  # noqa: E402

CASES = (
    ("swing, Table 4.3", "swing", {}),
    ("swing, E = 2e7 Pa", "swing", {"E": 2e7}),
    ("stance, Table 4.4", "stance", {}),
)
ETAS = (0.0, 1.0, 1e5)
SCHEMES = ("variational", "energy-momentum")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.0, help="simulated time, s (default 2)")
    parser.add_argument("--nodes", type=int, default=20, help="blade nodes (default 20)")
    parser.add_argument("--dt", type=float, default=1e-3, help="time step, s (default 1e-3)")
    args = parser.parse_args()
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
                    ds = sim.run(p, dt=args.dt, duration=args.duration, scheme=scheme)
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
