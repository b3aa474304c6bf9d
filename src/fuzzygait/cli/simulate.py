"""Commands on the leg + prosthesis model: simulate, fuzzy-sim, frv-sim."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from fuzzygait.cli.app import StageBars, app, out, progress_bars, user_errors
from fuzzygait.cli.leg_options import (
    DEFAULT_FRV,
    DEFAULT_FRV_LEG,
    DEFAULT_FUZZY_OUTPUTS,
    DEFAULT_GFA,
    DEFAULT_LEG,
    DEFAULT_POOL,
    FRVLegOptions,
    FRVOptions,
    FuzzyOutputOptions,
    GFAOptions,
    LegOptions,
    PoolOptions,
)
from fuzzygait.cli.options import estimated_stages, parse_alphas, parse_disc, parse_overrides, with_option_groups
from fuzzygait.core.errors import FuzzyGaitError

if TYPE_CHECKING:
    import xarray as xr

@app.command(short_help="Simulate the leg with the prosthesis blade.")
@with_option_groups
def simulate(
    scenario: Annotated[str, typer.Argument(metavar="SCENARIO", help="swing or stance (thesis Tables 4.3 / 4.4).")],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Simulation results, .nc or .zarr.")],
    leg: LegOptions = DEFAULT_LEG,
    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also write a Rerun recording (.rrd).")] = None,
    plot: Annotated[
        Path | None, typer.Option("--plot", help="Also plot the energies over time (.png, .svg or .pdf).")
    ] = None,
    sensitivities: Annotated[
        bool, typer.Option("--sensitivities", help="Also integrate dq/dp and the target sensitivities "
                           "(about twice the cost of a plain run).")
    ] = False,
) -> None:
    """Simulate the leg with the prosthesis blade (swing or stance scenario) and save
    positions, directors, joint angles and energies over time.

    The thesis' Table 4.3/4.4 values, except where they do not run on the shipped blade
    (swing: --set eta=1e5; stance: --scheme energy-momentum; printed as a note). A step
    that does not converge, or a run whose energy balance is off by more than 0.5 %, is
    repeated with 2, 4 or 8 sub-steps per --dt. Nothing is written when the simulation
    fails; the error names the options that fix it.
    """
    from fuzzygait.workflows.outputs import check_output_suffixes

    with user_errors():
        check_output_suffixes(out_file, rrd, {"--plot": plot})
        from fuzzygait.mechanics.presets import thesis_setting_note
        from fuzzygait.workflows.fuzzy_dynamics import (
            SimulationOutputs,
            check_scenario,
            command_setup,
            simulate_leg,
            simulation_timing,
        )

        check_scenario(scenario)
        if leg.nodes is not None and leg.nodes < 2:
            raise FuzzyGaitError(f"--nodes must be at least 2; got {leg.nodes}")
        step, span = simulation_timing(scenario, leg.dt, leg.duration)
        values = parse_overrides(leg.overrides or [])
        setup, note = command_setup(scenario, leg.nodes, step, span, values, leg.scheme)
        if note:
            out.print(f"note: {note}", markup=False)
        thesis_note = thesis_setting_note(scenario, setup.values)
        if thesis_note:
            out.print(f"note: {thesis_note}", markup=False)
        with progress_bars() as bars:
            ds, written = simulate_leg(
                setup, SimulationOutputs(out_file, plot=plot, rrd=rrd),
                sensitivities=sensitivities, progress=StageBars(bars),
            )  # fmt: skip
    _print_simulation_summary(ds)
    _print_written(written)


@app.command("fuzzy-sim", short_help="Fuzzy forward dynamics: Graph Follower hulls.")
@with_option_groups
def fuzzy_sim(
    scenario: Annotated[str, typer.Argument(metavar="SCENARIO", help="swing or stance (thesis Tables 4.3 / 4.4).")],
    fuzzy: Annotated[
        list[str], typer.Option("--fuzzy", metavar="NAME=SPREAD,...",
                                help="Triangular fuzzy parameters as ± relative spreads, e.g. E=10% (repeatable).")
    ],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Fuzzy result, .zarr or .nc.")],
    gfa: GFAOptions = DEFAULT_GFA,
    leg: LegOptions = DEFAULT_LEG,
    outputs: FuzzyOutputOptions = DEFAULT_FUZZY_OUTPUTS,
    pool: PoolOptions = DEFAULT_POOL,
) -> None:
    """Fuzzy forward dynamics: hulls of a target output for triangular fuzzy parameters
    (Graph Follower algorithm, linearised with the simulator's sensitivities).

    Before it starts, one line estimates the work: at most how many forward simulations
    (the novelty check skips most) and how long one takes (its first steps timed)."""
    from fuzzygait.workflows.outputs import check_output_suffixes

    with user_errors():
        plots = {"--plot": outputs.plot, "--parameter-plot": outputs.parameter_plot}
        check_output_suffixes(out_file, outputs.rrd, plots)
        from fuzzygait.mechanics.fuzzy_dynamics import parse_fuzzy
        from fuzzygait.workflows.fuzzy_dynamics import (
            FuzzySimOutputs,
            FuzzySimRequest,
            check_scenario,
            command_setup,
            command_strategy,
            fuzzy_simulation,
        )

        check_scenario(scenario)
        spreads = parse_fuzzy(fuzzy)
        levels = parse_alphas(gfa.alphas)
        setup, note = command_setup(scenario, leg.nodes, leg.dt, leg.duration, parse_overrides(leg.overrides or []),
                                    leg.scheme)  # fmt: skip
        if note:
            out.print(f"note: {note}", markup=False)
        request = FuzzySimRequest(spreads, gfa.target, levels, command_strategy(gfa.stride, gfa.novelty))
        files = FuzzySimOutputs(out_file, plot=outputs.plot, parameter_plot=outputs.parameter_plot, rrd=outputs.rrd)
        with progress_bars() as bars:
            result, written = fuzzy_simulation(setup, request, files, workers=pool.workers, scheduler=pool.scheduler,
                                               progress=estimated_stages(bars))  # fmt: skip
    out.print(_fuzzy_summary(scenario, spreads, result.attrs), markup=False)
    _print_written(written)


#: frv-sim's parameters that a study records, by the name of the recorded option
_RECORDED = {"parameter": "frv", "value": "value", "disc": "disc", "alphas": "alphas", "distribution": "distribution",
             "seed": "seed", "sampling": "sampling", "target": "target", "overrides": "set", "nodes": "nodes",
             "dt": "dt", "duration": "duration", "scheme": "scheme"}  # fmt: skip


@app.command("frv-sim", short_help="FRV-GFA: a leg parameter as a fuzzy random variable.")
@with_option_groups
def frv_sim(
    ctx: typer.Context,
    scenario: Annotated[str, typer.Argument(metavar="SCENARIO", help="stance (thesis §5.7) or swing.")],
    out_store: Annotated[Path, typer.Option("--out", "-o", help="FRV study, a .zarr directory; an existing "
                                            "study is extended with --samples more samples, with the options it "
                                            "was made with (an option given must match them).")],
    frv: FRVOptions = DEFAULT_FRV,
    leg: FRVLegOptions = DEFAULT_FRV_LEG,
    pool: PoolOptions = DEFAULT_POOL,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Start a new study even if --out exists (the "
                                            "old one is replaced once the new one is complete).")] = False,
) -> None:
    """FRV-GFA (thesis §2.7, §5.7): a leg parameter (or several independent ones) as a
    fuzzy random variable, grouped samples, Graph Follower hulls on the occurring
    intervals (boxes) only, output samples and their counts in a chunked zarr store.

    Every write commits atomically: a run that fails or is killed leaves the study as it
    was (a new one: nothing); run the command again to complete it. Before it starts, one
    line estimates the work: the forward simulations (exactly, for a new study of one
    parameter) and how long one takes (its first steps timed).
    """

    from fuzzygait.workflows.frv_leg import FRVRequest, check_frv_parameter, run_frv_leg
    from fuzzygait.workflows.fuzzy_dynamics import LegSetup, check_scenario, solver_settings
    from fuzzygait.workflows.work_estimate import check_frv_samples

    with user_errors():
        check_scenario(scenario)
        check_frv_samples(frv.samples, frv.force)
        if out_store.suffix.lower() != ".zarr":
            raise FuzzyGaitError(f"{out_store}: --out must be a .zarr directory")
        check_frv_parameter(frv.parameter)
        values = parse_overrides(leg.overrides or [])
        levels = parse_alphas(frv.alphas)
        grid_points = parse_disc(frv.disc, frv.parameter)
        given = {"scenario"} | {k for name, k in _RECORDED.items() if _given(ctx, name)}
        request = FRVRequest(frv.parameter, frv.value, frv.samples, grid_points, levels, frv.distribution, frv.seed,
                             frv.sampling, frv.target)  # fmt: skip
        with progress_bars() as bars:
            study = run_frv_leg(
                LegSetup(scenario, leg.nodes, values, solver_settings(scenario, leg.dt, leg.duration, leg.scheme)),
                request, out_store, workers=pool.workers, scheduler=pool.scheduler, overwrite=overwrite, given=given,
                progress=estimated_stages(bars),
            )  # fmt: skip
    out.print(_frv_summary(scenario, study.counts), markup=False)
    _print_written([out_store])


def _given(ctx: typer.Context, name: str) -> bool:
    """Whether the user gave parameter ``name`` (typer bundles its own click: compare by name)."""
    source = ctx.get_parameter_source(name)
    return source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP")


def _print_written(paths: Sequence[Path]) -> None:
    out.print("wrote " + ", ".join(str(p) for p in paths), markup=False)


def _fuzzy_summary(scenario: str, spreads: Mapping[str, float], attrs: Mapping[str, Any]) -> str:
    """The target, the fuzzy parameters, the engine's counts and the wall time."""
    fuzzy = ", ".join(f"{n} ±{100 * s:g} %" for n, s in spreads.items())
    return (
        f"{scenario}: {attrs['target']} with fuzzy {fuzzy}; "
        f"{attrs['forward_simulations']} forward simulations, {attrs['optimisations']} optimisations, "
        f"wall time {attrs['wall_time_s']:.1f} s"
    )


def _frv_summary(scenario: str, counts: Mapping[str, Any]) -> str:
    """Samples, occurring and possible intervals (boxes, with several FRVs: possible =
    the product over the parameters), the engine's counts and the wall time."""
    per = counts.get("possible_intervals_per_parameter")
    kind = "intervals" if per is None else "boxes"
    product = "" if per is None else " (" + " × ".join(str(n) for n in per) + ")"
    finer = {name: factor for name, factor in (counts.get("peak_refine") or {}).items() if factor > 1}
    lattice = "".join(f"; α = 1 on {name} bins / {factor}" for name, factor in finer.items())
    return (
        f"{scenario}: {counts.get('samples')} samples; occurring {kind} {counts.get('occurring_intervals')} of "
        f"{counts.get('possible_intervals')}{product} possible; "
        f"forward simulations {counts.get('forward_simulations')}{lattice}; "
        f"interval optimisations {counts.get('interval_optimisations')}; wall time {counts.get('wall_time', 0):.1f} s"
    )


def _print_simulation_summary(ds: xr.Dataset) -> None:
    """Steps, wall time, Newton iterations, peak internal energy and energy drift."""
    import numpy as np

    from fuzzygait.viz.mechanics import energy_drift

    attrs = ds.attrs
    iterations = np.asarray(ds["newton_iterations"].values)
    n_steps = iterations.size
    per_step = f"{iterations.mean():.2f} mean, {iterations.max()} max" if n_steps else "none"
    nodes = int(attrs.get("nodes", 0))
    out.print(
        f"{attrs.get('scenario')}: {n_steps} steps of {float(attrs['dt']):g} s to t = {float(attrs['duration']):g} s"
        + (f", {nodes} blade nodes" if nodes else "")
        + (f", {attrs['scheme']} scheme" if "scheme" in attrs else "")
        + (f" ({int(attrs['substeps'])} sub-steps each: a step at dt did not converge or the energy balance was off)"
           if int(attrs.get("substeps", 1)) > 1 else "")
        + f"; wall time {float(attrs.get('wall_time_s', np.nan)):.2f} s"
        + ("" if int(attrs.get("compiled", 0)) else " (not compiled)"),
        markup=False,
    )
    out.print(f"  Newton iterations per step: {per_step}", markup=False)
    out.print(f"  max internal energy: {float(ds['internal_energy'].max()):.4g} J", markup=False)
    drift = float(np.nanmax(np.abs(energy_drift(ds))))
    out.print(f"  energy drift max |total + dissipated − initial| / |initial|: {drift:.3g}", markup=False)
