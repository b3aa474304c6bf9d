"""The clinical figures of a trial page: kinetics stored in the file (joint moments and
powers over the gait cycle, mean ± SD per side) and the Movement Analysis Profile (GVS
bars per variable and side, GPS beside them); written as PNG and SVG by
:mod:`fuzzygait.workflows.report_folder` (nothing here writes a file)."""

from __future__ import annotations

import numpy as np
from matplotlib.artist import Artist
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from fuzzygait.gait.cycles import percent_points
from fuzzygait.gait.normative import GPS_VARIABLES, GaitProfile
from fuzzygait.viz.layout import SIDE_STYLE
from fuzzygait.viz.report.clinical import KINETIC_JOINTS, N_POINTS, ClinicalData
from fuzzygait.viz.report.figures import SIDE_LINE, _add_legend, _right_hatch, foot_off_lines
from fuzzygait.viz.report.grid import KINETICS_GRID

__all__ = ["gait_profile_figure", "kinetics_figure"]

#: Columns of the kinetics grid: (kind, axis, title, meaning of positive values).
KINETIC_COLUMNS = (
    ("moment", "X", "Moment, sagittal", "+ extensor"),
    ("moment", "Y", "Moment, frontal", "Plug-in Gait sign"),
    ("moment", "Z", "Moment, transverse", "Plug-in Gait sign"),
    ("power", "Z", "Power", "+ generated, − absorbed"),
)
#: The sagittal sign where a joint names it otherwise (internal moments; checked on the
#: reference files: hip flexor moment negative in late stance, knee extensor positive in
#: early stance, ankle plantarflexor positive at push-off).
SAGITTAL_MEANING = {"Ankle": "+ plantarflexor"}


def kinetics_figure(clinical: ClinicalData, title: str) -> Figure:
    """Hip, knee and ankle (rows) moments in three planes and power (columns) over the
    gait cycle: per side the mean (left solid, right dashed) and ± 1 SD over the cycles
    with force-plate data (filled for the left, hatched for the right), foot-off lines;
    units on every axis."""
    import matplotlib.pyplot as plt

    x = percent_points(N_POINTS)
    fig, axes = plt.subplots(len(KINETIC_JOINTS), len(KINETIC_COLUMNS), figsize=(11.0, 7.6), sharex=True,
                             squeeze=False)  # fmt: skip
    fig.suptitle(title, fontsize=13)
    counts: dict[str, int] = {}
    for r, joint in enumerate(KINETIC_JOINTS):
        for c, (kind, axis, column, meaning) in enumerate(KINETIC_COLUMNS):
            ax = axes[r, c]
            ax.axhline(0.0, color="0.6", lw=0.6)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=8)
            foot_off_lines(ax, clinical)
            unit = ""
            for side, (_, colour) in SIDE_STYLE.items():
                curve = clinical.kinetics.get((joint, kind, side, axis))
                if curve is None:
                    continue
                unit = curve.unit
                counts[side] = max(counts.get(side, 0), curve.cycles)
                low, high = curve.mean - curve.sd, curve.mean + curve.sd
                if side == "R":
                    ax.fill_between(x, low, high, facecolor="none", edgecolor=colour, hatch=_right_hatch(3), lw=0)
                else:
                    ax.fill_between(x, low, high, color=colour, alpha=0.2, lw=0)
                ax.plot(x, curve.mean, color=colour, lw=1.4, ls=SIDE_LINE[side])
            if not unit:
                ax.text(0.5, 0.5, "not in the file", transform=ax.transAxes, ha="center", va="center",
                        fontsize=8, color="0.45")  # fmt: skip
            if kind == "moment" and axis == "X":
                meaning = SAGITTAL_MEANING.get(joint, meaning)
            ax.set_ylabel(f"{joint} ({unit or '–'})\n{meaning}", fontsize=7.5)
            if r == 0:
                ax.set_title(column, fontsize=10.5)
            if r == len(KINETIC_JOINTS) - 1:
                ax.set_xlabel("gait cycle (%)", fontsize=8)
            ax.set_xlim(0, 100)
    handles: list[Artist] = []
    for side, (name, colour) in SIDE_STYLE.items():
        n = counts.get(side, 0)
        if not n:  # no cycle of this side struck a force plate
            continue
        label = f"{name} mean of {n} cycle{'s' if n != 1 else ''} with force-plate data"
        handles.append(Line2D([], [], color=colour, lw=1.4, ls=SIDE_LINE[side], label=label))
        face = {"facecolor": "white", "hatch": _right_hatch(3)} if side == "R" else {"facecolor": colour, "alpha": 0.2}
        handles.append(Patch(edgecolor=colour, lw=0.5, label=f"{name} ± 1 SD over cycles", **face))
    handles.append(Line2D([], [], color="0.2", lw=1.0, label="foot off (vertical, per side)"))
    return _add_legend(fig, handles, ncol=3, margins=KINETICS_GRID)


def gait_profile_figure(profile: GaitProfile, title: str) -> Figure:
    """The Movement Analysis Profile: per variable the GVS of each side (left filled,
    right hatched, in the sides' colours) and the GPS per side and overall, in degrees."""
    import matplotlib.pyplot as plt

    names = [name for _, _, name in GPS_VARIABLES] + ["GPS"]
    values = {side: [profile.gvs[side][n] for n in names[:-1]] + [profile.gps[side]] for side in "LR"}
    fig, ax = plt.subplots(figsize=(11.0, 4.4))
    fig.suptitle(title, fontsize=13)
    x = np.arange(len(names), dtype=float)
    width = 0.36
    for k, (side, (side_name, colour)) in enumerate(SIDE_STYLE.items()):
        heights = np.nan_to_num(np.asarray(values[side], dtype=float), nan=0.0)
        hatched = side == "R"
        bars = ax.bar(x + (k - 0.5) * width, heights, width, edgecolor=colour, lw=1.0, label=side_name,
                      facecolor="white" if hatched else colour, hatch=_right_hatch(3) if hatched else None)  # fmt: skip
        for bar, value in zip(bars, values[side], strict=True):
            text = "n/a" if not np.isfinite(value) else f"{value:.1f}"
            ax.annotate(text, (bar.get_x() + bar.get_width() / 2, bar.get_height()), xytext=(0, 2),
                        textcoords="offset points", ha="center", va="bottom", fontsize=7.5)  # fmt: skip
    ax.axvline(len(names) - 1.5, color="0.5", lw=0.8, ls=":")
    overall = "n/a" if not np.isfinite(profile.overall) else f"{profile.overall:.1f}°"
    ax.text(0.99, 0.95, f"overall GPS {overall}", transform=ax.transAxes, ha="right", va="top", fontsize=9)
    ax.set_xticks(x, names, rotation=25, ha="right", fontsize=8.5)
    ax.set_ylabel("RMS difference from the\nnormative mean (deg)", fontsize=8.5)
    ax.grid(axis="y", alpha=0.3)
    ax.set_ylim(0.0, max(1.0, 1.15 * float(np.nanmax([*values["L"], *values["R"], 0.0]))))
    ax.legend(fontsize=8.5, loc="upper left", frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    return fig

