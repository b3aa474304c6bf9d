"""Figures of fuzzy forward dynamics results (thesis Figs. 5.2, 5.4 and 5.6).

Both take the Dataset of :func:`fuzzygait.mechanics.fuzzy_dynamics.fuzzy_forward_dynamics`
(``hull (alpha, bound, time)``, ``deterministic (time)``, ``extremiser (alpha, bound,
time, parameter)``; attributes ``fuzzy_parameters``, ``fuzzy_spreads``, ``target``,
``target_units``).  :func:`log_fuzzy_hulls` logs the hulls into a Rerun recording
stream; nothing here writes a file (:mod:`fuzzygait.workflows.rerun_recordings`,
:func:`fuzzygait.io.figure_files.save_figure`).
"""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402


def _title(result: xr.Dataset) -> str:
    attrs = result.attrs
    spreads = zip(attrs.get("fuzzy_parameters", []), attrs.get("fuzzy_spreads", []))
    fuzzy = ", ".join(f"{n} ±{100 * s:g} %" for n, s in spreads)
    return f"{attrs.get('scenario', '')}: {attrs.get('target', 'target')} with fuzzy {fuzzy}"


def hull_figure(result: xr.Dataset) -> Figure:
    """Target output hulls of every α-level over time with the deterministic run (Fig. 5.2)."""
    fig, ax = plt.subplots(figsize=(9, 4.5), layout="constrained")
    t = result["time"].values
    alphas = sorted(float(a) for a in result["alpha"].values if a < 1)
    cmap = plt.get_cmap("Blues")
    for k, alpha in enumerate(alphas):
        lower = result["hull"].sel(alpha=alpha, bound="lower").values
        upper = result["hull"].sel(alpha=alpha, bound="upper").values
        ax.fill_between(t, lower, upper, color=cmap(0.35 + 0.5 * k / max(len(alphas), 1)), alpha=0.8,
                        label=f"α = {alpha:g}", linewidth=0)  # fmt: skip
    ax.plot(t, result["deterministic"].values, color="black", lw=1.2, label="deterministic (α = 1)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"{result.attrs.get('target', 'target')} ({result.attrs.get('target_units', '')})")
    ax.set_title(_title(result), fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def extremiser_figure(result: xr.Dataset, alpha: float = 0.0) -> Figure:
    """Which parameter values produce the hulls (Fig. 5.6 analogue): for every fuzzy
    parameter, the position of the extremising value inside its α-cut (−1 = left end,
    +1 = right end) over time, upper and lower hull."""
    names = list(result.attrs.get("fuzzy_parameters", result["parameter"].values))
    spreads = np.asarray(result.attrs.get("fuzzy_spreads", [np.nan] * len(names)), float)
    base = dict(zip(result.attrs.get("base_parameter_names", []), result.attrs.get("base_parameters", [])))
    t = result["time"].values
    fig, axes = plt.subplots(2, 1, figsize=(10, 1.2 + 0.35 * len(names) * 2), sharex=True, layout="constrained")
    for ax, bound in zip(axes, ("upper", "lower")):
        values = result["extremiser"].sel(alpha=alpha, bound=bound).values  # (time, parameter)
        centre = np.array([base.get(n, np.nan) for n in names])
        half = (1 - alpha) * spreads * np.abs(centre)
        with np.errstate(invalid="ignore", divide="ignore"):
            position = (values - centre) / np.where(half > 0, half, np.nan)
        image = ax.imshow(position.T, aspect="auto", cmap="coolwarm", vmin=-1, vmax=1, interpolation="nearest",
                          extent=(t[0], t[-1], len(names) - 0.5, -0.5))  # fmt: skip
        ax.set_yticks(range(len(names)), names, fontsize=8)
        ax.set_title(f"{bound} hull, α = {alpha:g}: extremising parameter within its α-cut", fontsize=9)
    axes[-1].set_xlabel("time (s)")
    fig.colorbar(image, ax=axes, label="position in α-cut", shrink=0.8)
    fig.suptitle(_title(result), fontsize=10)
    return fig


def fuzzy_title(result: xr.Dataset) -> str:
    """``"<scenario>: <target> with fuzzy E ±5 %, ..."``: the figures' title and the
    recording's name."""
    return _title(result)


def log_fuzzy_hulls(rec: Any, rr: Any, result: xr.Dataset) -> None:
    """Log the hulls into the Rerun recording stream ``rec`` (``rr``: the ``rerun``
    module; rerun-sdk 0.41) as time series ``<target>/alpha_<α>/lower|upper`` and
    ``<target>/deterministic`` on the timeline ``time`` (s), in the target's unit.
    Writes no file (the stream's sink does: :func:`fuzzygait.io.rerun_files.recording_file`)."""
    from fuzzygait.viz.rerun_log import _log_series

    target = f"{result.attrs.get('target', 'target')}_{result.attrs.get('target_units', '')}".rstrip("_")
    cmap = plt.get_cmap("Blues")
    times = [rr.TimeColumn("time", duration=np.asarray(result["time"].values, float))]
    for alpha in sorted(float(a) for a in result["alpha"].values if a < 1):
        red, green, blue = (int(255 * c) for c in cmap(0.4 + 0.5 * alpha)[:3])
        colour = (red, green, blue)
        for bound in ("lower", "upper"):
            values = result["hull"].sel(alpha=alpha, bound=bound).values
            _log_series(rec, rr, f"{target}/alpha_{alpha:g}/{bound}", times, values,
                        f"α = {alpha:g} {bound}", colour, 1.5)  # fmt: skip
    _log_series(rec, rr, f"{target}/deterministic", times, result["deterministic"].values,
                "deterministic", (0, 0, 0), 2.0)  # fmt: skip
