"""Figures of fuzzy random variables and FRV-GFA results (thesis Figs. 5.14–5.19).

Input side (from an :class:`~fuzzygait.uncertainty.frv.FRVSpec`, no study needed):

* :func:`input_samples_figure` — Fig. 5.14: input samples as fuzzy numbers and the
  histograms of their l_α r_α-increments per α-level with the generating pdf;
* :func:`grouping_figure` — Fig. 5.15: samples before and after grouping;
* :func:`parameter_figures` — both, per parameter of a study of one or several FRVs
  (each from its own sample stream and grid).

Output side (from an :class:`~fuzzygait.uncertainty.frv.FRVStudy` of one FRV parameter
or several, or its store path;
the stored hulls are streamed, never loaded whole):

* :func:`output_distribution_figure` — Figs. 5.16 / 5.17: histogram and fitted pdf of
  the output per α-level at one time node, of the hulls or of their increments;
* :func:`temporal_evolution_figure` — Fig. 5.18: per α-level the mean and 5–95 % band
  of the lower and upper hulls over time, a few samples, and the α = 1 mean;
* :func:`fuzzy_random_output_figure` — Fig. 5.19: the mean output fuzzy number at one
  time node with the standard deviation of the left (right) increments shaded from the
  mean (full colour) to one σ (almost transparent).

All return a :class:`matplotlib.figure.Figure` (no pyplot state; save with
``fig.savefig`` or :func:`fuzzygait.io.figure_files.save_figure`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure
from scipy import stats

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.frv import (
    FRVSpec,
    FRVStudy,
    Grid,
    check_specs,
    fit_distributions,
    generate_samples,
    group,
    iter_hull_blocks,
    sample_increments,
    stored_samples,
)

Store = FRVStudy | str | os.PathLike[str]
SIDES = (("lower", "left", "tab:green"), ("upper", "right", "tab:blue"))


def _membership_lines(cuts: np.ndarray, alphas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Polylines ``(x, y)`` of fuzzy numbers ``(n, n_alpha, 2)`` for one ``ax.plot``:
    up the left flank, down the right one; one column per number."""
    x = np.concatenate([cuts[:, :, 0], cuts[:, ::-1, 1]], axis=1).T
    y = np.concatenate([alphas, alphas[::-1]])
    return x, y


def _axis_label(spec: FRVSpec, unit: str) -> str:
    return f"{spec.name} ({unit})" if unit else spec.name


def input_samples_figure(spec: FRVSpec, seed: int = 0, n_samples: int = 10000, n_show: int = 100,
                         stream: int = 0, unit: str = "") -> Figure:  # fmt: skip
    """Fig. 5.14: ``n_show`` input samples and, per α-level, histograms of the left and
    right increments of ``n_samples`` samples with the generating pdf (α = 1: the peak).
    ``stream``: the parameter's index in a study of several FRVs (its sample stream);
    ``unit``: the parameter's unit for the axis label (e.g. "Pa")."""
    cuts = generate_samples(spec, n_samples, seed, stream=stream)
    alphas = np.asarray(spec.alphas)
    increments = sample_increments(cuts)
    fig = Figure(figsize=(3.0 * alphas.size, 6.5), layout="constrained")
    grid = fig.add_gridspec(2, alphas.size)
    top = fig.add_subplot(grid[0, :])
    x, y = _membership_lines(cuts[:n_show], alphas)
    top.plot(x, y, color="tab:blue", lw=0.6, alpha=0.5)
    top.axvline(spec.deterministic, color="black", lw=1, ls="--", label="p_det")
    title = f"{min(n_show, n_samples)} of {n_samples} samples of the FRV {spec.name}"
    top.set(xlabel=_axis_label(spec, unit), ylabel="α", title=title)
    top.legend(fontsize=8)
    for k, alpha in enumerate(alphas):
        ax = fig.add_subplot(grid[1, k])
        if alpha == 1.0:
            values = increments[:, k, 0]
            ax.hist(values, bins=50, density=True, color="0.7", label="peak")
            xs = np.linspace(values.min(), values.max(), 200)
            ax.plot(xs, spec.peak_distribution().pdf(xs), color="red", lw=1.2, label="N pdf")
        else:
            dist = spec.increment_distribution()
            for b, (_, side, colour) in enumerate(SIDES):
                ax.hist(increments[:, k, b], bins=50, density=True, histtype="step", color=colour, label=f"Δ{side}")
            xs = np.linspace(0.0, increments[:, k].max(), 200)
            ax.plot(xs, dist.pdf(xs), color="red", lw=1.2, label=f"{spec.distribution} pdf")
        ax.set_title(f"α = {alpha:g}", fontsize=9)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=7)
    return fig


def grouping_figure(spec: FRVSpec, seed: int = 0, n_samples: int = 10000, n_disc: int = 100,
                    n_show: int = 100, grid: Grid | None = None, stream: int = 0,
                    unit: str = "") -> Figure:  # fmt: skip
    """Fig. 5.15: ``n_show`` samples before and after grouping on ``grid`` (default: the
    grid of ``n_samples`` samples with ``n_disc`` points); the grid points are marked.
    ``stream``: the parameter's index in a study of several FRVs (its sample stream);
    ``unit``: the parameter's unit for the axis label."""
    cuts = generate_samples(spec, n_samples, seed, stream=stream)
    grid = grid if grid is not None else Grid.from_samples(cuts, n_disc)
    grid = grid.extended(cuts[:n_show])
    grouped = grid.centres(group(cuts[:n_show], grid))
    alphas = np.asarray(spec.alphas)
    fig = Figure(figsize=(10, 6), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    titles = ("before grouping", f"after grouping ({grid.n_points} points)")
    for ax, data, title in zip(axes, (cuts[:n_show], grouped), titles):
        x, y = _membership_lines(data, alphas)
        ax.plot(x, y, color="tab:blue", lw=0.6, alpha=0.5)
        ax.set(ylabel="α", title=title)
    points = grid.points()
    axes[1].plot(points, np.zeros_like(points), "|", color="black", ms=6)
    axes[1].set_xlabel(_axis_label(spec, unit))
    return fig


def parameter_figures(specs: FRVSpec | Sequence[FRVSpec], seed: int = 0, n_samples: int = 10000,
                      n_disc: int = 100, grids: Sequence[Grid] | None = None,
                      n_show: int = 100, units: Mapping[str, str] | None = None,
                      ) -> dict[str, tuple[Figure, Figure]]:  # fmt: skip
    """Figs. 5.14 and 5.15 for every FRV parameter of a study (one or several), each from
    its own sample stream and on its own grid (``grids``: e.g. a study's ``grids``, or
    ``(study.grid,)``; default: each parameter's grid of ``n_samples`` samples).
    ``units``: unit per parameter name for the axis labels (e.g. the leg's
    ``fuzzygait.mechanics.leg.PARAMETER_UNITS``).

    Returns:
        ``{name: (input_samples_figure, grouping_figure)}`` in parameter order.
    """
    spec_tuple = check_specs(specs)
    if grids is not None and len(grids) != len(spec_tuple):
        raise ParameterError(f"grids: one per parameter ({len(spec_tuple)}); got {len(grids)}")
    units = dict(units or {})
    return {s.name: (input_samples_figure(s, seed, n_samples, n_show, stream=k, unit=units.get(s.name, "")),
                     grouping_figure(s, seed, n_samples, n_disc, n_show, None if grids is None else grids[k],
                                     stream=k, unit=units.get(s.name, "")))
            for k, s in enumerate(spec_tuple)}  # fmt: skip


def _pdf(fit, a: int, b: int, node: int, xs: np.ndarray) -> np.ndarray:
    if fit.attrs["kind"] == "normal":
        mean, std = (float(fit[v].values[a, b, node]) for v in ("mean", "std"))
        return stats.norm(mean, std).pdf(xs) if std > 0 else np.full_like(xs, np.nan)
    pa, pb, loc, scale = (float(fit[v].values[a, b, node]) for v in ("a", "b", "loc", "scale"))
    if not (scale > 0 and np.isfinite(pa) and pa > 0 and pb > 0):
        return np.full_like(xs, np.nan)
    return stats.beta(pa, pb, loc=loc, scale=scale).pdf(xs)


def _column(store: Store, node: int, data: str) -> np.ndarray:
    """All samples' values at one output time node: ``(n, n_alpha, 2)``, streamed."""
    return np.concatenate([block[..., node].copy() for block in iter_hull_blocks(store, data)])  # copies: blocks freed


def output_distribution_figure(store: Store, node: int, data: str = "hulls", kind: str = "normal",
                               bins: int = 40) -> Figure:  # fmt: skip
    """Figs. 5.16 (``data="hulls"``) / 5.17 (``data="increments"``): per α-level the
    histogram of the lower and upper values at output time node ``node`` and the fitted
    pdf (:func:`~fuzzygait.uncertainty.frv.fit_distributions`)."""
    fit = fit_distributions(store, kind, data)
    n_time = fit.sizes["time"]
    if not -n_time <= node < n_time:
        raise ParameterError(f"node must index the {n_time} output time nodes; got {node}")
    node %= n_time
    column = _column(store, node, data)
    alphas = fit["alpha"].values
    fig = Figure(figsize=(3.2 * alphas.size, 3.4), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, alphas.size))
    for a, (ax, alpha) in enumerate(zip(axes, alphas)):
        sides = SIDES[:1] if alpha == 1.0 else SIDES  # α = 1: the two bounds coincide
        for b, (bound, _, colour) in enumerate(sides):
            values = column[:, a, b]
            ax.hist(values, bins=bins, density=True, histtype="stepfilled", alpha=0.35, color=colour,
                    label=bound if alpha < 1 else "peak")  # fmt: skip
            span = values.max() - values.min()
            xs = np.linspace(values.min() - 0.1 * span, values.max() + 0.1 * span, 300)
            ax.plot(xs, _pdf(fit, a, b, node, xs), color=colour, lw=1.3)
        ax.set_title(f"α = {alpha:g}", fontsize=9)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=7)
    what = "output α-cut values" if data == "hulls" else "output increments"
    fig.suptitle(f"{kind} fit to the {what} at t = {float(fit['time'].values[node]):g} (node {node})", fontsize=10)
    return fig


def temporal_evolution_figure(store: Store, max_nodes: int = 200, n_show: int = 10,
                              quantiles: tuple[float, float] = (0.05, 0.95),
                              max_band_samples: int = 20000) -> Figure:  # fmt: skip
    """Fig. 5.18: per α-level (one panel each) the mean and the ``quantiles`` band of the
    lower and upper hulls over time (at most ``max_nodes`` time nodes, evenly picked),
    ``n_show`` samples' hulls, and the mean α = 1 output in every panel.  The mean uses
    every sample (streamed); the quantile band at most ``max_band_samples`` evenly spaced
    samples, so memory stays bounded for 10⁵ samples."""
    fit = fit_distributions(store, "normal", "hulls")
    n_time = fit.sizes["time"]
    select = np.unique(np.linspace(0, n_time - 1, min(max_nodes, n_time)).round().astype(int))
    n_samples = stored_samples(store)
    step = max(1, -(-n_samples // max_band_samples))  # every step-th sample for the band
    parts, start = [], 0
    for block in iter_hull_blocks(store):
        rows = np.arange(start, start + block.shape[0])
        parts.append(block[(rows % step) == 0][..., select].copy())
        start += block.shape[0]
    values = np.concatenate(parts)  # (≤ max_band_samples, n_alpha, 2, k)
    fit = fit.isel(time=select)
    t = fit["time"].values
    alphas = fit["alpha"].values
    fig = Figure(figsize=(10, 2.4 * alphas.size), layout="constrained")
    axes = np.atleast_1d(fig.subplots(alphas.size, 1, sharex=True))
    low_q, high_q = np.quantile(values, quantiles, axis=0)
    peak_mean = fit["mean"].values[-1, 0]
    for a, (ax, alpha) in enumerate(zip(axes, alphas)):
        for b, (bound, _, colour) in enumerate(SIDES):
            ax.fill_between(t, low_q[a, b], high_q[a, b], color=colour, alpha=0.2, lw=0)
            band = f"{quantiles[0]:.0%}–{quantiles[1]:.0%}"
            ax.plot(t, fit["mean"].values[a, b], color=colour, lw=1.2, label=f"{bound}: mean, {band}")
            ax.plot(t, values[:n_show, a, b].T, color=colour, lw=0.4, alpha=0.5)
        ax.plot(t, peak_mean, color="navy", lw=1.0, ls="--", label="mean at α = 1")
        ax.set_ylabel(f"α = {alpha:g}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("time")
    fig.suptitle(f"Temporal evolution of the output FRV ({n_samples} samples"
                 + (f"; band from every {step}-th)" if step > 1 else ")"), fontsize=10)  # fmt: skip
    return fig


def fuzzy_random_output_figure(store: Store, node: int, layers: int = 12) -> Figure:
    """Fig. 5.19: the output FRV at one time node. Red: the mean fuzzy number (mean
    α-cut ends). Left panel: the standard deviation of the left increments (green),
    right panel: of the right increments (blue), shaded around the mean α-cut ends from
    full colour at σ = 0 to almost transparent at one σ (``layers`` shades)."""
    means = fit_distributions(store, "normal", "hulls")
    spread = fit_distributions(store, "normal", "increments")
    n_time = means.sizes["time"]
    if not -n_time <= node < n_time:
        raise ParameterError(f"node must index the {n_time} output time nodes; got {node}")
    node %= n_time
    alphas = means["alpha"].values
    mean = means["mean"].values[..., node]  # (n_alpha, 2)
    sigma = spread["std"].values[..., node]
    line_x = np.concatenate([mean[:, 0], mean[::-1, 1]])
    line_y = np.concatenate([alphas, alphas[::-1]])
    fig = Figure(figsize=(10, 3.8), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    for b, (ax, (_, side, colour)) in enumerate(zip(axes, SIDES)):
        for s in np.linspace(1.0, 0.0, layers, endpoint=False):
            ax.fill_betweenx(alphas, mean[:, b] - s * sigma[:, b], mean[:, b] + s * sigma[:, b], color=colour,
                             alpha=1.0 / layers, lw=0)  # fmt: skip
        ax.plot(line_x, line_y, color="red", lw=1.5, label="mean μ")
        ax.set(xlabel=f"output at t = {float(means['time'].values[node]):g}", title=f"σ of the {side} increments")
        ax.legend(fontsize=8)
    axes[0].set_ylabel("α")
    return fig
