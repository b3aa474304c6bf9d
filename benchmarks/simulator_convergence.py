"""Node-count convergence of the blade's maximum deformation energy (thesis Fig. 4.2, Eq. 4.34).

Run:  .venv/bin/python benchmarks/simulator_convergence.py           (about 6 minutes)
      .venv/bin/python benchmarks/simulator_convergence.py --quick   (5, 10, 20, 40 nodes, dt = 1 ms; ~15 s)

The swing scenario (hip extension π/6, knee flexion π/3, released in gravity) with the
stiff reverse-engineered blade of Table 4.2 (E = 59958e6 Pa, rho = 1710 kg/m³, eta = 1)
is simulated for 1 s with n blade nodes, n = 5 … 250 (the thesis used n_max = 250).  The
target is the maximum over the time nodes of the blade's internal (deformation) energy,
V_n = max_j Σ_e W_e(t_j), and its relative error against the finest run (Eq. 4.34)::

    ε_n = |V_n − V_ref| / |V_ref|,   V_ref = V_{n_max}  (same scheme and dt).

One series per integration scheme (``--schemes``: the variational integrator of the thesis,
Eq. 4.26, and the energy-momentum scheme) and time step (``--dt``: 1 ms as in the thesis,
and 0.1 ms, where the time discretisation no longer hides the spatial error).  A short
time-step check at the default 20 nodes shows the temporal error of the same target.
Each node count is its own model structure, so its first run compiles a library (cached
afterwards in ``~/.cache/fuzzygait``); that build time is reported apart from run times.

The figure ``benchmarks/figures/node_convergence.png`` plots ε_n against n on log-log
axes (one line per series, 20 nodes — the thesis' and the simulator's default —
highlighted, a dashed O(n⁻²) guide line through the 20-node point of the last series).
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import argparse  # noqa: E402
import os  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from fuzzygait.core.errors import SimulationError  # noqa: E402
from fuzzygait.mechanics.scenarios import LegSimulator  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402

FIGURE = ROOT / "benchmarks" / "figures" / "node_convergence.png"
STIFF = dict(E=59958e6, rho=1710.0, eta=1.0)  # Table 4.2, reverse-engineered blade
NODES = (5, 10, 15, 20, 30, 40, 60, 80, 120, 250)
QUICK_NODES = (5, 10, 20, 40)
HIGHLIGHT = 20


def run(sim: LegSimulator, p: np.ndarray, scheme: str, dt: float, duration: float):
    """(V_max J, time of the maximum s, integration wall s), or the failure message."""
    kwargs = {} if scheme == "variational" else {"scheme": scheme}
    try:
        ds = sim.run(p, SolverSettings(dt=dt, duration=duration, **kwargs))
    except SimulationError as error:
        return str(error).split(": ")[0]
    energy = ds.internal_energy.values
    k = int(np.argmax(energy))
    return float(energy[k]), float(ds.time.values[k]), float(ds.attrs["wall_time_s"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help=f"nodes {QUICK_NODES} at dt = 1 ms only (reference: 40)")
    parser.add_argument("--nodes", default=None, help="comma-separated node counts; the largest is the reference")
    parser.add_argument("--dt", default=None, help="comma-separated time steps, s (default '1e-3,1e-4'; quick '1e-3')")
    parser.add_argument("--duration", type=float, default=1.0, help="simulated time, s (default 1)")
    parser.add_argument("--schemes", default="variational,energy-momentum", help="comma-separated integration schemes")
    parser.add_argument("--dt-check", default=None, help="comma-separated time steps of the check at "
                        f"{HIGHLIGHT} nodes (default '5e-4,2.5e-4'; quick: none)")
    parser.add_argument("--figure", type=Path, default=FIGURE, help=f"output figure (default {FIGURE.relative_to(ROOT)})")
    args = parser.parse_args()
    nodes = sorted(int(n) for n in args.nodes.split(",")) if args.nodes else list(QUICK_NODES if args.quick else NODES)
    dts = [float(d) for d in (args.dt or ("1e-3" if args.quick else "1e-3,1e-4")).split(",")]
    schemes = args.schemes.split(",")
    checks = [float(d) for d in (args.dt_check if args.dt_check is not None else ("" if args.quick else "5e-4,2.5e-4")).split(",") if d]
    series = [(scheme, dt) for dt in dts for scheme in schemes]
    name = {(s, dt): f"{s}, dt = {1e3 * dt:g} ms" for s, dt in series}

    one, five, _ = os.getloadavg()
    print("## Node-count convergence of the maximum blade deformation energy (Eq. 4.34)")
    print(f"swing, stiff blade (E = {STIFF['E']:g} Pa, rho = {STIFF['rho']:g} kg/m³, eta = {STIFF['eta']:g}), "
          f"{args.duration:g} s simulated; reference n = {nodes[-1]}; load average {one:.2f}, {five:.2f}")
    print()

    build_s: dict[int, float] = {}
    values: dict[tuple, dict[int, tuple | str]] = {key: {} for key in series}
    for n in nodes:
        start = time.perf_counter()
        sim = LegSimulator("swing", nodes=n)
        build_s[n] = time.perf_counter() - start
        p = sim.parameters(**STIFF)
        for key in series:
            result = run(sim, p, *key, args.duration)
            values[key][n] = result
            text = result if isinstance(result, str) else f"V_max = {result[0]:.6e} J at t = {result[1]:.4f} s, integration {result[2]:.2f} s"
            print(f"  n = {n:3d}, {name[key]}: {text}", flush=True)

    errors: dict[tuple, dict[int, float]] = {key: {} for key in series}
    for key in series:
        ref = values[key].get(nodes[-1])
        if isinstance(ref, tuple):
            for n, r in values[key].items():
                if isinstance(r, tuple) and n != nodes[-1]:
                    errors[key][n] = abs(r[0] - ref[0]) / abs(ref[0])

    for dt in dts:
        print()
        print(f"### dt = {1e3 * dt:g} ms")
        print("| nodes | build s |" + "".join(f" {s}: V_max J | t of max s | ε | integration s |" for s in schemes))
        print("|---|---|" + "---|---|---|---|" * len(schemes))
        for n in nodes:
            row = f"| {n}{' (default)' if n == HIGHLIGHT else ''} | {build_s[n]:.2f} |"
            for scheme in schemes:
                r = values[(scheme, dt)][n]
                if isinstance(r, str):
                    row += f" failed: {r} | | | |"
                    continue
                e = errors[(scheme, dt)]
                eps = "reference" if n == nodes[-1] else (f"{e[n]:.2e}" if n in e else "–")
                row += f" {r[0]:.6e} | {r[1]:.4f} | {eps} | {r[2]:.2f} |"
            print(row)
    print("(build: LegSimulator construction — symbolic assembly plus C compilation the first time a node "
          "count is used, a library load afterwards; integration: ds.attrs['wall_time_s'])")
    for key in series:
        e = errors[key]
        pairs = [(a, b) for a, b in zip(nodes, nodes[1:]) if e.get(a, 0) > 0 and e.get(b, 0) > 0]
        if pairs:
            rates = ", ".join(f"{a}→{b}: {np.log(e[a] / e[b]) / np.log(b / a):.1f}" for a, b in pairs)
            print(f"observed order ({name[key]}): {rates}")
        if HIGHLIGHT in e:
            print(f"ε at {HIGHLIGHT} nodes ({name[key]}): {100 * e[HIGHLIGHT]:.2f} %")

    if checks:
        # the temporal error of the same target at the default node count
        print()
        print(f"### Time-step check at {HIGHLIGHT} nodes: V_max against dt")
        print("| dt s |" + "".join(f" {s}: V_max J | integration s |" for s in schemes))
        print("|---|" + "---|---|" * len(schemes))
        sim = LegSimulator("swing", nodes=HIGHLIGHT)
        p = sim.parameters(**STIFF)
        for dt in sorted(set(dts) | set(checks), reverse=True):
            row = f"| {dt:.2e} |"
            for scheme in schemes:
                r = values.get((scheme, dt), {}).get(HIGHLIGHT) or run(sim, p, scheme, dt, args.duration)
                row += f" failed: {r} | |" if isinstance(r, str) else f" {r[0]:.6e} | {r[2]:.2f} |"
            print(row, flush=True)

    # figure
    args.figure.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    markers = ("o", "s", "^", "D", "v", "P")
    anchor = None
    highlighted = False
    for i, key in enumerate(series):
        e = errors[key]
        ns = [n for n in nodes if e.get(n, 0) > 0]
        if not ns:
            continue
        ax.loglog(ns, [e[n] for n in ns], marker=markers[i % len(markers)], linestyle="-" if key[1] == dts[0] else "-.",
                  label=name[key])
        if e.get(HIGHLIGHT, 0) > 0:
            ax.loglog([HIGHLIGHT], [e[HIGHLIGHT]], marker="o", markersize=13, markerfacecolor="none",
                      markeredgecolor="crimson", markeredgewidth=2, linestyle="none",
                      label=None if highlighted else f"{HIGHLIGHT} nodes (default)")
            highlighted = True
            anchor = (HIGHLIGHT, e[HIGHLIGHT])
    if anchor is not None:
        n0, e0 = anchor
        grid = np.array([nodes[0], nodes[-1]], float)
        ax.loglog(grid, e0 * (grid / n0) ** -2.0, "k--", linewidth=1, label="O(n⁻²)")
    ax.set_xlabel("blade nodes n")
    ax.set_ylabel("ε = |V_n − V_ref| / |V_ref|")
    ax.set_title(f"Max. blade deformation energy, swing (stiff blade), {args.duration:g} s, ref. n = {nodes[-1]}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.figure, dpi=150)
    shown = args.figure.relative_to(ROOT) if args.figure.is_relative_to(ROOT) else args.figure
    print(f"figure: {shown}")


if __name__ == "__main__":
    main()
