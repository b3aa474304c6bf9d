"""Option groups of the commands on the leg + prosthesis model (simulate, fuzzy-sim,
frv-sim): each a dataclass of typer options that :func:`~fuzzygait.cli.options.with_option_groups`
expands in place, so a command declares one parameter per group."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import typer

from fuzzygait.cli.options import SchedulerOption

__all__ = [
    "DEFAULT_FRV", "DEFAULT_FRV_LEG", "DEFAULT_FUZZY_OUTPUTS", "DEFAULT_GFA", "DEFAULT_LEG", "DEFAULT_POOL",
    "FRVLegOptions", "FRVOptions", "FuzzyOutputOptions", "GFAOptions", "LegOptions", "PoolOptions",
]  # fmt: skip

AlphasText = Annotated[str, typer.Option(help="α-levels, comma-separated (1 is always added; at most 20 below 1).")]


@dataclass(frozen=True)
class LegOptions:
    """The leg model and its solver: ``--nodes``, ``--dt``, ``--duration``, ``--set``,
    ``--scheme`` (None: the scenario's value)."""

    nodes: Annotated[
        int | None,
        typer.Option(help="Beam nodes of the prosthesis blade; default: the scenario's (swing 20, stance 40)."),
    ] = None
    dt: Annotated[float | None, typer.Option("--dt", help="Time step (s); default: the scenario's, 0.001.")] = None
    duration: Annotated[
        float | None, typer.Option("--duration", help="Simulated time (s); default: the scenario's, 2.")
    ] = None
    overrides: Annotated[
        list[str] | None,
        typer.Option("--set", metavar="NAME=VALUE,...", help="Fixed parameter values in SI units, comma-separated "
                     "or repeated, e.g. E=6e5,eta=2 (names: E, nu, rho, eta, thigh_mass, thigh_J1..3, "
                     "shank_mass, shank_J1..3); default: the scenario's."),
    ] = None  # fmt: skip
    scheme: Annotated[
        str | None, typer.Option(help="Time integrator: variational (thesis Eq. 4.26) or energy-momentum "
                                 "(exact energy balance, more robust for very flexible and stiff blades); "
                                 "default: the scenario's (swing variational, stance energy-momentum).")
    ] = None  # fmt: skip


@dataclass(frozen=True)
class FRVLegOptions(LegOptions):
    """:class:`LegOptions` with frv-sim's own defaults: 20 blade nodes and the
    energy-momentum scheme whatever the scenario."""

    nodes: Annotated[int, typer.Option(help="Beam nodes of the prosthesis blade.")] = 20
    scheme: Annotated[str, typer.Option(help="energy-momentum (default here) or variational.")] = "energy-momentum"


@dataclass(frozen=True)
class PoolOptions:
    """Where the forward simulations run: ``--workers`` local processes (1: this
    process) or an existing Dask ``--scheduler``; the results do not depend on it."""

    workers: Annotated[int, typer.Option(help="Local worker processes for the forward simulations (1: this "
                                         "process); the results do not depend on it.")] = 2  # fmt: skip
    scheduler: SchedulerOption = None


@dataclass(frozen=True)
class GFAOptions:
    """fuzzy-sim's Graph Follower: ``--target``, ``--alphas``, ``--stride``, ``--novelty``."""

    target: Annotated[
        str | None, typer.Option(help="total_deformation_energy (swing default), max_element_energy (stance "
                                 "default), last_node_x|y|z.")
    ] = None  # fmt: skip
    alphas: AlphasText = "0,0.5,1"
    stride: Annotated[int, typer.Option(help="Optimise every STRIDE-th time node (thesis: 100).")] = 100
    novelty: Annotated[float, typer.Option(help="Novelty tolerance, relative (thesis: 0.01 % = 1e-4).")] = 1e-4


@dataclass(frozen=True)
class FuzzyOutputOptions:
    """fuzzy-sim's files beside the result: ``--rrd``, ``--plot``, ``--parameter-plot``."""

    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also write the hulls as a Rerun recording.")] = None
    plot: Annotated[Path | None, typer.Option("--plot", help="Also plot the hulls (.png, .svg, .pdf).")] = None
    parameter_plot: Annotated[
        Path | None, typer.Option("--parameter-plot", help="Also plot the extremising parameter sets (Fig. 5.6).")
    ] = None


@dataclass(frozen=True)
class FRVOptions:
    """frv-sim's fuzzy random variable(s), sampling and grouping (thesis §2.7):
    ``--frv``, ``--value``, ``--samples`` (``--force`` beyond 10⁶), ``--disc``, ``--alphas``,
    ``--distribution``, ``--seed``, ``--sampling``, ``--target``."""

    parameter: Annotated[str, typer.Option("--frv", help="The fuzzy random leg parameter, or several "
                                           "independent ones comma-separated (E,rho: α-cut boxes on a "
                                           "grid of --disc points per parameter).")] = "E"  # fmt: skip
    value: Annotated[
        float | None, typer.Option("--value", help="Its deterministic value p_det (SI); default: the thesis' "
                                    "study's (stance E: 59.958e9 Pa, Table 5.3), else the scenario's. "
                                    "One --frv parameter only (else --set NAME=VALUE).")
    ] = None  # fmt: skip
    samples: Annotated[int, typer.Option(help="Samples N_s to draw (or to add); more than 10⁶ in one run only "
                                         "with --force.")] = 10000  # fmt: skip
    force: Annotated[bool, typer.Option("--force", help="Draw more than 10⁶ samples in one run.")] = False
    disc: Annotated[str, typer.Option(help="Grouping grid points N_p-disc: one number, or one per --frv "
                                      "parameter (e.g. 60,30 for E,rho).")] = "100"  # fmt: skip
    alphas: AlphasText = "0,0.25,0.5,0.75"
    distribution: Annotated[str, typer.Option(help="normal (with redraw) or beta increments.")] = "normal"
    seed: Annotated[int, typer.Option(help="Seed of the sample streams.")] = 0
    sampling: Annotated[str, typer.Option(help="Peaks: random (the thesis') or lhs (Latin hypercube per "
                                          "block of 1024 samples, §2.7.5).")] = "random"  # fmt: skip
    target: Annotated[str | None, typer.Option(help="Target output (default: per scenario).")] = None


DEFAULT_LEG = LegOptions()
DEFAULT_FRV_LEG = FRVLegOptions()
DEFAULT_POOL = PoolOptions()
DEFAULT_GFA = GFAOptions()
DEFAULT_FUZZY_OUTPUTS = FuzzyOutputOptions()
DEFAULT_FRV = FRVOptions()
