"""The batch report's session pages: one summary page per session (joint angles over the
gait cycle, mean ± SD over every cycle of every trial per side; the session's static
trial and subject file and how they were found; its trials with links, errors and
warnings) and one index across sessions.

The figure draws left and right in the sides' colours *and* line styles (left solid,
right dashed; SD bands hatched differently), so it reads in greyscale too.  Nothing
here writes a file (:mod:`fuzzygait.workflows.report_folder` writes the figure).
"""

from __future__ import annotations

import datetime as _dt
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING
from urllib.parse import quote

import numpy as np

from fuzzygait import __version__
from fuzzygait.core.findings import Finding
from fuzzygait.gait.spatiotemporal import TrialParameters
from fuzzygait.viz.layout import ANGLE_ROWS, PLANES, SIDE_STYLE
from fuzzygait.viz.report.chrome import CSS
from fuzzygait.viz.report.clinical_html import spatiotemporal_table
from fuzzygait.viz.report.grid import SESSION_GRID, place_grid
from fuzzygait.viz.report.markup import escape, html_table

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "SessionKinetics",
    "SessionSummary",
    "SummaryTrial",
    "cross_session_index",
    "cycles_used",
    "session_cycles_figure",
    "session_page",
]

_LINES = {"L": ("-", "////"), "R": ("--", "\\\\\\\\")}
#: Resolution (dots per inch) the session figure is written at (11 in wide -> 1100 px).
SESSION_DPI = 100


@dataclass
class SummaryTrial:
    """One trial row of a session page: its page (href relative to the page shown, None
    when failed), one-line error, cycles per side, warnings, seconds and whether it was
    reused from an earlier run."""

    name: str
    href: str | None
    error: str | None = None
    cycles: dict[str, int] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    seconds: float = 0.0
    skipped: bool = False
    pdf: str | None = None


@dataclass
class SessionSummary:
    """What a session page shows (and the index's row of it)."""

    name: str
    folder: str
    href: str  # the session page, relative to the index
    facts: list[tuple[str, str]]  # (label, text), e.g. ("Static trial", "X.c3d (file name)")
    trials: list[SummaryTrial]
    notes: list[Finding] = field(default_factory=list)
    pdf: str | None = None

    @property
    def n_ok(self) -> int:
        """Trials with a page."""
        return sum(t.error is None for t in self.trials)

    @property
    def warnings(self) -> list[str]:
        """Every trial's warnings, each prefixed with the trial."""
        return [f"{t.name}: {w}" for t in self.trials for w in t.warnings]


def session_cycles_figure(cycles: Mapping[str, np.ndarray], title: str) -> Figure | None:
    """The session's gait-cycle grid (rows pelvis .. foot progression, columns the
    planes): per component mean ± SD over the cycles of ``cycles`` (``"LKneeAngles_X"``
    -> (n_cycles, n_points) deg, every trial's cycles stacked), left and right in one
    panel; None when there is nothing to draw.  Written at :data:`SESSION_DPI` as PNG
    and SVG by :func:`fuzzygait.workflows.report_folder.write_session_cycles`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not any(np.isfinite(v).any() for v in cycles.values()):
        return None
    figure, axes = plt.subplots(len(ANGLE_ROWS), len(PLANES), figsize=(11, 12.6), squeeze=False, sharex=True)
    for r, (base, row_title) in enumerate(ANGLE_ROWS):
        for c, (axis, plane, meaning) in enumerate(PLANES):
            ax = axes[r][c]
            for side, (side_name, colour) in SIDE_STYLE.items():
                values = cycles.get(f"{side}{base}_{axis}")
                if values is None or not np.isfinite(values).any():
                    continue
                with np.errstate(all="ignore"):
                    mean = np.nanmean(values, axis=0)
                    sd = np.nanstd(values, axis=0, ddof=1) if values.shape[0] > 1 else np.zeros_like(mean)
                x = np.linspace(0, 100, mean.size)
                line, hatch = _LINES[side]
                ax.fill_between(x, mean - sd, mean + sd, facecolor=colour, alpha=0.18, hatch=hatch,
                                edgecolor=colour, linewidth=0)  # fmt: skip
                ax.plot(x, mean, line, color=colour, linewidth=1.6,
                        label=f"{side_name} (n = {values.shape[0]})")  # fmt: skip
            if r == 0:
                ax.set_title(plane, fontsize=10)
            if c == 0:
                ax.set_ylabel(f"{row_title} (deg)", fontsize=9)
            if meaning.get(row_title):
                ax.text(0.01, 0.98, f"+ {meaning[row_title]}", transform=ax.transAxes, fontsize=7, va="top",
                        color="0.3")  # fmt: skip
            if r == len(ANGLE_ROWS) - 1:
                ax.set_xlabel("gait cycle (%)", fontsize=9)
            ax.axhline(0, color="0.6", linewidth=0.6)
            ax.tick_params(labelsize=8)
            if (r, c) == (0, 0) and ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=7, loc="lower right", frameon=False)
    figure.suptitle(title, fontsize=11)
    place_grid(figure, 0.97, SESSION_GRID)
    return figure


@dataclass(frozen=True)
class SessionKinetics:
    """The session page's kinetics: the stems (relative to the page) of the moments and
    powers figure and of the ground-reaction figure (None: not written) and per side the
    cycles with their stance on a force plate they average."""

    moments: str | None = None
    grf: str | None = None
    cycles: dict[str, int] = field(default_factory=dict)


def kinetics_section(kinetics: SessionKinetics | None) -> str:
    """The session page's kinetics: mean ± SD moments and powers over every cycle on a
    force plate of the session's trials, and the ground reaction over stance."""
    head = '<h2 id="kinetics">Kinetics: all trials</h2>'
    if kinetics is None or kinetics.moments is None:
        return head + ("<p>No kinetics: no trial of the session has a gait cycle whose stance was on a force "
                       "plate (a trial page says why: no force plates, or no foot on a plate).</p>")  # fmt: skip
    n = kinetics.cycles
    parts = [head, f"<p>Joint moments (N·m per kg body mass; internal moments, positive X extensor at hip and knee, "
             f"plantarflexor at the ankle) and powers (W/kg; positive: generated), mean ± SD over the "
             f"{n.get('L', 0)} left and {n.get('R', 0)} right gait cycles of the session's trials whose stance was "
             "on a force plate, computed from the plates as Plug-in Gait does; left: solid line, right: dashed. "
             "The SD is the stride-to-stride variability, not a measurement uncertainty.</p>"]  # fmt: skip
    figures = [(kinetics.moments, "Joint moments and powers of the session, mean and SD per side", 820),
               (kinetics.grf, "Ground reaction force of the session over stance on the plate, mean and SD per side",
                360)]  # fmt: skip
    for stem, text, height in figures:
        if stem is None:
            continue
        parts.append(f'<figure><a href="{quote(stem)}.svg"><img src="{quote(stem)}.png" width="1100" '
                     f'height="{height}" alt="{escape(text)}"></a><figcaption>{escape(text)} '
                     f'(<a href="{quote(stem)}.svg">SVG</a>).</figcaption></figure>')  # fmt: skip
    return "".join(parts)


def _document(title: str, body: str) -> str:
    stamp = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z").strip()
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            f"<meta name=\"generator\" content=\"fuzzygait {escape(__version__)}\">\n"
            f"<title>{escape(title)}</title>\n<style>{CSS}</style>\n</head>\n<body>\n{body}\n"
            f"<footer>Generated by fuzzygait {escape(__version__)} on {escape(stamp)}.</footer>\n"
            "</body>\n</html>\n")  # fmt: skip


def _link(text: str, href: str | None) -> str:
    return f'<a href="{quote(href)}">{escape(text)}</a>' if href else escape(text)


def _trial_rows(trials: Sequence[SummaryTrial], prefix: str = "") -> list[list[tuple[str, bool]]]:
    rows = []
    for t in trials:
        href = prefix + t.href if t.href else None
        status = '<span class="ok">OK</span>' if t.error is None else '<span class="failed">failed</span>'
        cycles = f"{t.cycles.get('L', 0)} / {t.cycles.get('R', 0)}" if t.error is None else "–"
        detail = [f'<span class="mono error">{escape(t.error)}</span>'] if t.error else []
        detail += [f'<span class="warning">warning: {escape(w)}</span>' for w in t.warnings]
        if t.pdf:
            detail.append(_link("PDF", prefix + t.pdf))
        time = "reused" if t.skipped else f"{t.seconds:.1f} s"
        rows.append([(_link(t.name, href), False), (status, False), (cycles, True), (time, True),
                     ("<br>".join(detail) or "–", False)])  # fmt: skip
    return rows


_TRIAL_HEADER = [("Trial", False), ("Status", False), ("Gait cycles<br>L / R", True), ("Time", True),
                 ("Errors / warnings", False)]  # fmt: skip


def cycles_used(cycles: Mapping[str, np.ndarray]) -> dict[str, int]:
    """Per side the most cycles with data of any of its components (what the figure
    averages; cycles a trial excluded for missing data are not among them)."""
    used = {side: 0 for side in SIDE_STYLE}
    for name, values in cycles.items():
        if name[:1] in used:
            used[name[0]] = max(used[name[0]], int(np.isfinite(values).any(axis=1).sum()))
    return used


def session_page(summary: SessionSummary, figure: str | None, index_href: str | None,
                 used: Mapping[str, int] | None = None, parameters: TrialParameters | None = None,
                 kinetics: SessionKinetics | None = None) -> str:  # fmt: skip
    """The HTML of a session page; ``figure`` the stem of its cycle figure (relative),
    ``index_href`` the index across sessions (None: there is none), ``used`` the cycles
    per side the figure averages (:func:`cycles_used`), ``parameters`` the complete cycles
    of all trials (:func:`~fuzzygait.gait.spatiotemporal.pooled_parameters`), ``kinetics``
    its kinetics figures (:func:`kinetics_section`)."""
    facts = "".join(f'<tr><th scope="row">{escape(k)}</th><td>{escape(v)}</td></tr>' for k, v in summary.facts)
    nav = f'<nav><a href="{quote(index_href)}">← All sessions (index)</a></nav>' if index_href else ""
    n_cycles = {s: sum(t.cycles.get(s, 0) for t in summary.trials if t.error is None) for s in SIDE_STYLE}
    used = dict(used) if used is not None else n_cycles
    if figure:
        fig = (f'<figure><a href="{quote(figure)}.svg"><img src="{quote(figure)}.png" width="1100" height="1260" '
               f'alt="Joint angles of the session, mean and SD per side"></a><figcaption>Joint angles over the gait '
               f"cycle, mean ± SD over the {used['L']} left and {used['R']} right cycles with data of the session's "
               f"trials (of {n_cycles['L']} and {n_cycles['R']}: a trial page says which cycles it left out for "
               "missing data); left: solid line, right: dashed. The SD is the stride-to-stride variability, not a "
               "measurement uncertainty.</figcaption></figure>")  # fmt: skip
    else:
        fig = "<p>No gait cycles to summarise (no trial with a page has complete cycles).</p>"
    warnings = "".join(f"<li class=\"warning\">{escape(w)}</li>" for w in summary.warnings)
    if parameters is not None and any(s.complete_cycles for s in parameters.sides.values()):
        spatiotemporal = ("<p>Mean ± SD over every complete gait cycle of the session's trials, computed as on the "
                          "trial pages (as Vicon Nexus does, from the events and the toe markers).</p>"
                          + spatiotemporal_table(parameters))  # fmt: skip
    else:
        spatiotemporal = "<p>No complete gait cycle in the session's trials.</p>"
    notes = "".join(f"<li>{escape(n.message)}</li>" for n in summary.notes)
    pdf = f" · {_link('PDF of this page', summary.pdf)}" if summary.pdf else ""
    body = f"""
{nav}
<header>
<h1>Session {escape(summary.name)}: summary</h1>
<p class="lead">{len(summary.trials)} walking trial{'s' if len(summary.trials) != 1 else ''},
<span class="ok">{summary.n_ok} OK</span>{pdf}</p>
</header>
<main>
<h2 id="session">Session</h2>
<table class="kv"><tbody>{facts}</tbody></table>
{f'<h2 id="warnings">Warnings</h2><ul>{warnings}</ul>' if warnings else ''}
<h2 id="spatiotemporal">Spatio-temporal parameters: all trials</h2>
{spatiotemporal}
<h2 id="cycles">Gait cycle: all trials</h2>
{fig}
{kinetics_section(kinetics)}
<h2 id="trials">Trials</h2>
<div class="index-table">{html_table(_TRIAL_HEADER, _trial_rows(summary.trials))}</div>
{f'<h2 id="notes">Notes</h2><ul class="small">{notes}</ul>' if notes else ''}
</main>"""
    return _document(f"fuzzygait report – session {summary.name}", body)


def cross_session_index(sessions: Sequence[SessionSummary], failed_inputs: Sequence[str] = ()) -> str:
    """The index across sessions: per session its summary page, its static trial and
    subject file, then its trials (links, one-line errors, warnings)."""
    n_trials = sum(len(s.trials) for s in sessions)
    n_ok = sum(s.n_ok for s in sessions)
    rows = []
    for s in sessions:
        warn = len(s.warnings)
        rows.append([(_link(s.name, s.href), False), (escape(s.folder), False), (f"{s.n_ok} / {len(s.trials)}", True),
                     (f'<span class="warning">{warn}</span>' if warn else "0", True),
                     ("<br>".join(escape(f"{k}: {v}") for k, v in s.facts[:2]), False)])  # fmt: skip
    header = [("Session", False), ("Folder", False), ("Trials OK", True), ("Warnings", True),
              ("Static trial / subject file", False)]  # fmt: skip
    parts = []
    for s in sessions:
        prefix = s.href.rsplit("/", 1)[0] + "/" if "/" in s.href else ""
        table = html_table(_TRIAL_HEADER, _trial_rows(s.trials, prefix))
        parts.append(f'<h3 id="{escape(s.name)}">{_link(s.name, s.href)}</h3><div class="index-table">{table}</div>')
    failed = "".join(f'<li class="mono error">{escape(line)}</li>' for line in failed_inputs)
    n_failed = f', <span class="failed">{n_trials - n_ok} failed</span>' if n_trials - n_ok else ""
    body = f"""
<header>
<h1>Gait report: all sessions</h1>
<p class="lead">{len(sessions)} session{'s' if len(sessions) != 1 else ''}, {n_trials} trials:
<span class="ok">{n_ok} OK</span>{n_failed}</p>
</header>
<main>
<h2 id="sessions">Sessions</h2>
<div class="index-table">{html_table(header, rows)}</div>
{f'<ul>{failed}</ul>' if failed else ''}
<h2 id="trials">Trials per session</h2>
{''.join(parts)}
</main>"""
    return _document("fuzzygait report – all sessions", body)
