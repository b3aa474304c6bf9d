"""The report's HTML: plain HTML5 pages with inline CSS (no JavaScript, no external
resources), one per trial and the index of the batch."""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import quote

import numpy as np

from fuzzygait import __version__
from fuzzygait.kinematics.labels import PLANES, ROW_TITLES, SIDE_NAMES, component_label, parse_component
from fuzzygait.markererror.result import ball_radius
from fuzzygait.markererror.sources import SOURCE_TITLES
from fuzzygait.mocap.gaps import methods_used
from fuzzygait.viz.report.allowable import allowable_section, index_cell, lead_box
from fuzzygait.viz.report.bands import (
    FLEXION,
    DeltaPhiTable,
    Headline,
    ReportRun,
    TrialAnalysis,
    TrialData,
    TrialEntry,
    alpha_text,
    grid_components,
)
from fuzzygait.viz.report.markup import escape as _esc
from fuzzygait.viz.report.markup import html_table as _table
from fuzzygait.viz.report.sources import has_source_bands, sources_section

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["index_page", "trial_page"]


def _fmt(value: float | None, digits: int = 1) -> str:
    """A number with ``digits`` decimals; "–" for a missing or non-finite one."""
    if value is None or not np.isfinite(value):
        return "–"
    return f"{value:.{digits}f}"



def _sources_text(fuzzy: xr.Dataset) -> str:
    """``"measurement,sta"`` attribute -> ``"measurement system, soft-tissue artefact"``."""
    sources = fuzzy.attrs.get("sources", "")
    names = sources.split(",") if isinstance(sources, str) else list(np.atleast_1d(sources))
    return ", ".join(SOURCE_TITLES.get(str(n).strip(), str(n).strip()) for n in names if str(n).strip())


CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, Arial, sans-serif;
       margin: 0 auto; max-width: 1180px; padding: 0 1.2rem 2rem; color: #1d1d1f;
       line-height: 1.45; background: #fff; }
nav { padding: .7rem 0; border-bottom: 1px solid #ddd; margin-bottom: .6rem; font-size: .95rem; }
a { color: #0b57b0; }
h1 { font-size: 1.6rem; margin: .6rem 0 .2rem; word-break: break-all; }
h2 { font-size: 1.2rem; margin: 1.8rem 0 .5rem; border-bottom: 2px solid #e4e4e4; padding-bottom: .2rem; }
h3 { font-size: 1rem; margin: 1rem 0 .3rem; }
p.lead { color: #555; margin-top: 0; }
table { border-collapse: collapse; margin: .4rem 0 1rem; font-size: .92rem; }
th, td { border: 1px solid #d5d5d5; padding: .25rem .55rem; text-align: left; vertical-align: top; }
thead th { background: #f2f4f7; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.kv th { background: #f7f7f7; font-weight: 600; white-space: nowrap; }
.cols { display: flex; flex-wrap: wrap; gap: 0 2.5rem; align-items: flex-start; }
.lead-box { background: #eef6ee; border: 1px solid #bcd9bf; border-radius: 6px; padding: .6rem 1rem;
            margin: .6rem 0; font-size: 1.05rem; }
.lead-box p { margin: .25rem 0; }
.index-table table { font-size: .86rem; }
.index-table th, .index-table td { padding: .25rem .4rem; }
.box { background: #f5f8fc; border: 1px solid #cfdcec; border-radius: 6px; padding: .7rem 1rem; margin: .8rem 0; }
.ok { color: #17692e; font-weight: 700; }
.failed { color: #b3261e; font-weight: 700; }
tr.failed-row td { background: #fff4f3; }
code, .mono { font-family: ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; font-size: .88em; }
span.error { display: inline-block; max-width: 24rem; overflow-wrap: anywhere; color: #7a1c16; font-size: .85em; }
figure { margin: .6rem 0 1rem; }
figure img { max-width: 100%; height: auto; border: 1px solid #e2e2e2; }
figcaption { font-size: .9rem; color: #444; margin-top: .3rem; }
.small { font-size: .85rem; color: #555; }
.undet { color: #6b4a00; font-style: italic; }
span.wrap { display: inline-block; max-width: 11rem; white-space: normal; }
.nowrap { white-space: nowrap; }
ul.notes li { margin: .15rem 0; }
footer { margin-top: 2.5rem; border-top: 1px solid #ddd; padding-top: .6rem; font-size: .85rem; color: #666; }
"""

ALPHA_SENTENCE = (
    "Each shaded band shows how far the joint angle could be off if every marker were "
    "displaced by up to (1 − α) times its assumed maximum error: the lightest, widest "
    "band (α = 0) is the worst case with all error sources at their maximum, darker "
    "bands (higher α) assume smaller errors, and the line (α = 1) is the angle as "
    "measured."
)
DELTA_PHI_SENTENCE = (
    "ΔΦ<sub>α</sub> = max<sub>t</sub>(Φ<sup>u</sup><sub>α</sub>(t) − "
    "Φ<sup>l</sup><sub>α</sub>(t)) / max<sub>t</sub> |Φ(t)| × 100 %: the widest the "
    "α-band gets anywhere in the trial, relative to the largest measured magnitude of the "
    "angle (thesis Eq. 5.3 and Table 5.2; the magnitude keeps angles that stay negative "
    "comparable)."
)

UNDETERMINED_SENTENCE = (
    "“Undetermined” means that at that α-level the assumed marker errors let a segment's "
    "coordinate frame flip (a bound lies more than 90° from the measured angle), so the "
    "angle is not known there at all: such bands are not drawn (a hatched strip along the "
    "top of the panel marks where), and ΔΦ and band widths are taken over the determined "
    "frames only."
)
#: What the report writes for an undetermined number.
UNDETERMINED = "undetermined"

_CYCLES_ALT = (
    "Grid of joint angles (pelvis, hip, knee, ankle, foot progression; sagittal, frontal, "
    "transverse) over the gait cycle, left and right, with uncertainty bands per alpha-level"
)


def _page(title: str, body: str) -> str:
    """A complete HTML5 document with the report's CSS."""
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        "<meta name=\"generator\" content=\"fuzzygait " + _esc(__version__) + "\">\n"
        f"<title>{_esc(title)}</title>\n<style>{CSS}</style>\n</head>\n<body>\n{body}\n"
        "</body>\n</html>\n"
    )


def model_title(model: str) -> str:
    """A model version as the report names it: ``"cgm1.0"`` -> ``"CGM 1.0 (Plug-in
    Gait)"``, ``"cgm2.3"`` -> ``"CGM 2.3"``."""
    title = "CGM " + model.removeprefix("cgm")
    return title + " (Plug-in Gait)" if model == "cgm1.0" else title


def _footer(model: str = "cgm1.0") -> str:
    """The footer: version and time of the report, what the numbers are."""
    stamp = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z").strip()
    return (
        f"<footer>Generated by fuzzygait {_esc(__version__)} on {_esc(stamp)}. "
        f"Angles: {_esc(model_title(model))} lower body; uncertainty: fuzzy marker-position errors "
        "propagated with the Graph Follower algorithm (α-level optimisation).</footer>"
    )


def _kv_table(rows: Sequence[tuple[str, str]], caption: str | None = None) -> str:
    """A two-column table of (label, html) rows."""
    cap = f"<caption class=\"small\">{_esc(caption)}</caption>" if caption else ""
    body = "".join(f"<tr><th scope=\"row\">{_esc(k)}</th><td>{v}</td></tr>" for k, v in rows)
    return f"<table class=\"kv\">{cap}<tbody>{body}</tbody></table>"


def _deg(rad: float) -> str:
    """Radians as degrees with two decimals (never "-0.00")."""
    text = f"{math.degrees(rad):.2f}"
    return "0.00" if text == "-0.00" else text


def _static_text(run: ReportRun) -> str:
    """Where the static offsets come from (a sentence)."""
    static = [n for n in run.notes if n.startswith("static offsets")]
    if static:
        return static[0][0].upper() + static[0][1:] + "."
    return "No static trial given: the static offsets are used as stored in the subject parameters."


def _subject_section(run: ReportRun) -> str:
    """The subject parameters used, per side and general."""
    subject = run.subject
    rows = [
        ("Leg length", "mm", "leg_length", lambda v: f"{v:.1f}"),
        ("Knee width", "mm", "knee_width", lambda v: f"{v:.1f}"),
        ("Ankle width", "mm", "ankle_width", lambda v: f"{v:.1f}"),
        ("ASIS–trochanter distance", "mm", "asis_trochanter", lambda v: f"{v:.1f}"),
        ("Tibial torsion", "deg", "tibial_torsion", _deg),
        ("Thigh rotation offset", "deg", "thigh_rotation", _deg),
        ("Shank rotation offset", "deg", "shank_rotation", _deg),
        ("Ankle ab/adduction offset", "deg", "ankle_abadd", _deg),
        ("Sole delta", "mm", "sole_delta", lambda v: f"{v:.1f}"),
        ("<b>Static plantarflexion offset</b>", "deg", "static_plant_flex", _deg),
        ("<b>Static rotation offset</b>", "deg", "static_rot_off", _deg),
    ]
    side_rows = [
        [(label, False), (unit, False), (_esc(fmt(getattr(subject.left, attr))), True),
         (_esc(fmt(getattr(subject.right, attr))), True)]
        for label, unit, attr, fmt in rows
    ]  # fmt: skip
    sides = _table([("Parameter", False), ("Unit", False), ("Left", True), ("Right", True)], side_rows)
    general = [
        ("Body mass", f"{subject.body_mass:g} kg" if subject.body_mass else "not given"),
        ("Height", f"{subject.height:g} mm" if subject.height else "not given"),
        ("Marker diameter", f"{subject.marker_diameter:g} mm"),
        ("Inter-ASIS distance", f"{subject.inter_asis_distance:g} mm"
         if subject.inter_asis_distance else "measured from the markers"),
        ("Source", _esc(subject.source or "trial file")),
    ]  # fmt: skip
    return (
        "<h2 id=\"subject\">Subject parameters used</h2>"
        f"<p class=\"small\">{_esc(_static_text(run))}</p>"
        f"<div class=\"cols\">{sides}{_kv_table(general)}</div>"
    )


def _quality_section(analysis: TrialAnalysis, data: TrialData) -> str:
    """Gait events, gaps, missing markers and angles, processing notes."""
    run = analysis.run
    trial = run.trial
    parts = ["<h2 id=\"quality\">Data quality</h2>"]
    # events and cycles
    counts = []
    for side, side_name in SIDE_NAMES.items():
        strikes = sum(1 for e in run.events if e.context == side_name and e.label == "Foot Strike")
        offs = sum(1 for e in run.events if e.context == side_name and e.label == "Foot Off")
        counts.append([(side_name, False), (str(strikes), True), (str(offs), True),
                       (str(len(data.cycles[side])), True)])  # fmt: skip
    source = "read from the file" if run.event_source == "file" else run.event_source
    parts.append(f"<h3>Gait events</h3><p>Events {_esc(source)}.</p>")
    parts.append(_table([("Side", False), ("Foot strikes", True), ("Foot offs", True),
                         ("Gait cycles", True)], counts))  # fmt: skip
    # gaps
    parts.append("<h3>Gaps in the marker trajectories</h3>")
    if not run.gaps:
        parts.append("<p>None: every marker was visible in every frame.</p>")
    else:
        filled = sum(g.filled for g in run.gaps)
        parts.append(
            f"<p>{filled} of {len(run.gaps)} gaps filled ({_esc(methods_used(run.gaps)) or 'none'}); frames of gaps "
            "left open have no angle (and no band) for the joints that use the marker.</p>"
        )
        rows = []
        classes = []
        for gap in sorted(run.gaps, key=lambda g: (g.marker, g.start)):
            first = trial.first_frame + gap.start
            status = f"filled by {gap.method}" if gap.filled else f"not filled: {gap.reason}"
            span = f"{first}–{first + gap.length - 1}" if gap.length > 1 else f"{first}"
            rows.append([(_esc(gap.marker), False), (span, True),
                         (str(gap.length), True), (_esc(status), False)])  # fmt: skip
            classes.append("" if gap.filled else "failed-row")
        parts.append(_table([("Marker", False), ("C3D frames", True), ("Frames", True),
                             ("Result", False)], rows, row_classes=classes))  # fmt: skip
    # missing markers / angles not computed
    parts.append("<h3>Missing markers and angles not computed</h3>")
    never = sorted({g.marker for g in run.gaps if "never visible" in g.reason})
    missing = []
    if never:
        missing.append(f"Markers never visible: {_esc(', '.join(never))}.")
    missing += [f"{_esc(name)} not computed: {_esc(why)}" for name, why in run.result.unavailable.items()]
    for name, values in run.result.angles.items():
        if name in run.result.unavailable:
            continue
        empty = int((~np.isfinite(np.asarray(values, dtype=float)).all(axis=1)).sum())
        if 0 < empty < trial.n_frames:
            missing.append(f"{_esc(name)}: no value on {empty} of {trial.n_frames} frames "
                           "(a marker it needs is missing there).")  # fmt: skip
    no_band = [n for n in grid_components() if data.angle(n) is not None and data.hull(n) is None]
    if no_band:
        angles = list(dict.fromkeys(n.rsplit("_", 1)[0] for n in no_band))
        missing.append("No uncertainty band (not analysed): " + _esc(", ".join(angles)) + ".")
    if missing:
        parts.append("<ul class=\"notes\">" + "".join(f"<li>{m}</li>" for m in missing) + "</ul>")
    else:
        parts.append("<p>None: every marker was recorded and every angle computed on every frame.</p>")
    # notes
    notes = list(dict.fromkeys([*run.notes, *analysis.notes]))
    if notes:
        parts.append("<h3>Processing notes</h3><ul class=\"notes\">"
                     + "".join(f"<li>{_esc(n)}</li>" for n in notes) + "</ul>")  # fmt: skip
    return "".join(parts)


def _assumptions_section(analysis: TrialAnalysis) -> str:
    """The assumed marker errors: α = 0 ball radius per marker."""
    fuzzy = analysis.fuzzy
    sources = _sources_text(fuzzy)
    parts = ["<h2 id=\"assumptions\">Assumed marker errors</h2>",
             "<p>The true position of every marker is taken to lie within a ball around "
             "its measured position; at α = 0 the ball has the radius below (the sum of the "
             f"selected error sources: {_esc(sources or 'see notes')}), at level α the radius "
             "is (1 − α) times that.</p>"]  # fmt: skip
    radius = ball_radius(fuzzy)
    if radius is not None:
        rows = [[(_esc(m), False), (_fmt(float(r), 1), True)]
                for m, r in zip(radius["marker"].values, radius.values, strict=True)]  # fmt: skip
        half = (len(rows) + 1) // 2
        tables = [_table([("Marker", False), ("Radius at α = 0 (mm)", True)], chunk)
                  for chunk in (rows[:half], rows[half:]) if chunk]  # fmt: skip
        parts.append(f"<div class=\"cols\">{''.join(tables)}</div>")
    return "".join(parts)


def _delta_phi_section(table: DeltaPhiTable, data: TrialData) -> str:
    """The ΔΦ table (rows in report order, α columns descending) with its explanation;
    "undetermined" where the α-level is undetermined at some frame."""
    alphas = table.alphas
    lowest = min(alphas) if alphas else None
    header = [("Angle", False)] + [(f"α = {alpha_text(a)}", True) for a in alphas]
    header += [("Reference<br>max |Φ| (deg)", True)]
    if lowest is not None:
        header += [(f"Widest determined<br>band α = {alpha_text(lowest)} (deg)", True),
                   (f"Undetermined<br>frames α = {alpha_text(lowest)}", True)]  # fmt: skip
    rows = []
    for name in table.components:
        cells = [(f"{_esc(component_label(name))} <span class=\"small mono\">{_esc(name)}</span>", False)]
        for alpha in alphas:
            if table.is_undetermined(name, alpha):
                cells.append((f"<span class=\"undet\">{UNDETERMINED}</span>", True))
            else:
                cells.append((_fmt(table.value(name, alpha), 0), True))
        cells += [(_fmt(float(table.peak[name]), 1), True)]
        if lowest is not None:
            count = table.frames_undetermined(name, lowest)
            if count and not np.isfinite(table.widest_band(name, lowest)):  # no determined frame
                cells.append((f"<span class=\"undet\">{UNDETERMINED}</span>", True))
            else:
                cells.append((_fmt(table.widest_band(name, lowest), 1), True))
            cells.append((f"{count} of {table.n_frames}" if count else "none", True))
        rows.append(cells)
    return (
        "<h2 id=\"delta-phi\">Relative envelope width ΔΦ (%)</h2>"
        f"<p>{DELTA_PHI_SENTENCE} Values are large for angles whose largest value is "
        "small or near zero (e.g. frontal and transverse planes); read them together with "
        "the band width in degrees. “–”: not available.</p>"
        f"<p>{UNDETERMINED_SENTENCE}</p>"
        + _table(header, rows)
    )


def _names(components: Sequence[str]) -> str:
    """Angle components as a short list, sides grouped: ``"knee flexion (L, R), ankle
    frontal (L)"`` (sagittal hip/knee/ankle: "flexion", else the plane)."""
    groups: dict[str, list[str]] = {}
    for name in components:
        parsed = parse_component(name)
        if parsed is None:
            groups.setdefault(name, [])
            continue
        side, base, axis = parsed
        row = ROW_TITLES.get(base, base).lower()
        plane = "flexion" if FLEXION.fullmatch(name) else dict((a, p) for a, p, _ in PLANES).get(axis, axis)
        groups.setdefault(f"{row} {plane}", []).append(side)
    nbsp = ",\u00a0"  # the sides stay together
    return ", ".join(f"{what} ({nbsp.join(sides)})" if sides else what for what, sides in groups.items())


def headline_lines(head: Headline) -> list[str]:
    """The key numbers of a trial as HTML lines, determined bands first."""
    lines = []
    if head.largest is not None:
        value, name, alpha = head.largest
        what = "hip/knee/ankle flexion" if FLEXION.fullmatch(name) else "the analysed angles"
        lines.append(f"Largest ΔΦ of {what} (determined bands): <b>{_fmt(value, 0)} %</b> at "
                     f"α = {alpha_text(alpha)} – {_esc(component_label(name))}")  # fmt: skip
    elif head.n_components:
        lines.append("Largest ΔΦ: <b>undetermined</b> – no flexion band is determined at any α-level")
    if head.alpha is not None and head.n_components:
        lowest = alpha_text(head.alpha)
        if head.undetermined:
            text = (f"Undetermined at α = {lowest}: <b>{len(head.undetermined)} of {head.n_components}</b> "
                    "angle components (a segment frame can flip; hatched in the figures)")  # fmt: skip
            if head.flexion_undetermined:
                text += f", among them {_esc(_names(head.flexion_undetermined))}"
            lines.append(text)
        else:
            lines.append(f"Every band is determined at α = {lowest} ({head.n_components} angle components).")
    if head.widest is not None:
        value, name, alpha = head.widest
        lines.append(f"Widest determined band: <b>{_fmt(value, 1)}°</b> at α = {alpha_text(alpha)} "
                     f"– {_esc(component_label(name))}")  # fmt: skip
    return lines


def trial_page(analysis: TrialAnalysis, data: TrialData, entry: TrialEntry,
                table: DeltaPhiTable, files: str, source: Path) -> str:  # fmt: skip
    """The page of one trial: the allowable marker error first, figures, ΔΦ table, the
    flexion bands per error source (with per-source bands), data quality, assumptions,
    subject."""
    run = analysis.run
    trial = run.trial
    last = trial.first_frame + trial.n_frames - 1
    n_cycles = data.n_cycles()
    facts = [
        ("File", f"<span class=\"mono\">{_esc(source)}</span>"),
        ("Subject", _esc(trial.subject or run.raw.subject or "not named in the file")),
        ("Frames", f"{trial.n_frames} (C3D frames {trial.first_frame}–{last})"),
        ("Sampling rate", f"{trial.rate:g} Hz"),
        ("Duration", f"{trial.n_frames / trial.rate:.2f} s"),
        ("Gait cycles", f"left {n_cycles['L']}, right {n_cycles['R']}"),
        ("Static offsets",
         f"plantarflexion L {_deg(run.subject.left.static_plant_flex)}°, "
         f"R {_deg(run.subject.right.static_plant_flex)}°; "
         f"rotation L {_deg(run.subject.left.static_rot_off)}°, R {_deg(run.subject.right.static_rot_off)}°"
         f"<br><span class=\"small\">{_esc(_static_text(run))} "
         "<a href=\"#subject\">All subject parameters</a></span>"),
        ("α-levels", ", ".join(alpha_text(a) for a in data.alphas) + ", 1 (measured)"),
    ]  # fmt: skip
    if _sources_text(analysis.fuzzy):
        facts.append(("Error sources", _esc(_sources_text(analysis.fuzzy))))
    key = headline_lines(entry.headline)
    filled = sum(g.filled for g in run.gaps)
    key.append(f"Gaps: {filled} filled, {len(run.gaps) - filled} left open; "
               f"{len(run.result.unavailable)} angle(s) not computed.")  # fmt: skip
    figs = quote(files)
    sources_link = ' <a href="#sources">Error sources</a> ·' if has_source_bands(analysis.fuzzy) else ""
    body = f"""
<nav><a href="index.html">← All trials (index)</a> · <a href="#allowable">Allowable error</a> ·
<a href="#cycles">Gait cycle</a> ·
<a href="#delta-phi">ΔΦ table</a> ·{sources_link} <a href="#time-series">Whole trial</a> ·
<a href="#quality">Data quality</a> · <a href="#subject">Subject</a></nav>
<header>
<h1>{_esc(source.name)}</h1>
<p class="lead">Joint angles by {_esc(model_title(run.result.model))} with their uncertainty from
marker position errors</p>
</header>
<main>
{lead_box(entry.allowable)}<div class="cols">{_kv_table(facts)}<div class="box">{'<br>'.join(key)}</div></div>
{allowable_section(entry.allowable)}
<h2 id="cycles">Joint angles over the gait cycle</h2>
<p>{ALPHA_SENTENCE} Left side red, right side green; all angles in degrees, positive
direction as labelled on each axis.</p>
<p class="small">How the bands are normalised: each α-level's lower and upper bound is
cut into the same gait cycles (foot strike to next foot strike of that side) and
time-normalised like the angle; the band shown is the mean over cycles of the lower and of
the upper bounds, around the mean angle curve. It is therefore the uncertainty of the
mean curve drawn; the stride-to-stride variability is not included. A note such as
“L: 3 of 4 cycles” means some cycles had missing data there.</p>
<figure>
<a href="{figs}/cycles.svg"><img src="{figs}/cycles.png" width="1100" height="1260"
alt="{_CYCLES_ALT}"></a>
<figcaption>Mean over gait cycles with α-bands; hatched strips along the top of a panel:
undetermined there (no band drawn). Click for the scalable version
(<a href="{figs}/cycles.svg">SVG</a>, <a href="{figs}/cycles.png">PNG</a>).</figcaption>
</figure>
{_delta_phi_section(table, data)}
{sources_section(analysis.fuzzy, figs)}
<h2 id="time-series">Whole trial</h2>
<p>The same angles over the whole recording (not normalised), with the α-bands frame by
frame. Dotted vertical lines mark foot strikes (red left, green right).</p>
<figure>
<a href="{figs}/time_series.svg"><img src="{figs}/time_series.png" width="1100" height="1260"
alt="Grid of joint angles over time for the whole trial with uncertainty bands per alpha-level"></a>
<figcaption>Joint angles over time with α-bands
(<a href="{figs}/time_series.svg">SVG</a>, <a href="{figs}/time_series.png">PNG</a>).</figcaption>
</figure>
{_quality_section(analysis, data)}
{_assumptions_section(analysis)}
{_subject_section(run)}
<p><a href="index.html">← Back to all trials</a></p>
</main>
{_footer(run.result.model)}"""
    return _page(f"{source.name} – fuzzygait report", body)


def _index_numbers(head: Headline) -> tuple[str, str, str]:
    """The index cells of a trial: largest determined flexion ΔΦ, undetermined components
    at the smallest α, widest determined band."""
    dphi = widest = "–"
    if head.largest is not None:
        value, name, alpha = head.largest
        dphi = (f"{_fmt(value, 0)} % at α = {alpha_text(alpha)}<br>"
                f"<span class=\"small wrap\">{_esc(component_label(name))}</span>")  # fmt: skip
    elif head.n_components:
        dphi = f"<span class=\"undet\">{UNDETERMINED}</span>"
    if head.widest is not None:
        value, name, alpha = head.widest
        widest = (f"{_fmt(value, 1)}° at α = {alpha_text(alpha)}<br>"
                  f"<span class=\"small wrap\">{_esc(component_label(name))}</span>")  # fmt: skip
    undet = "–"
    if head.n_components:
        undet = f"{len(head.undetermined)} of {head.n_components}"
        if head.flexion_undetermined:
            undet += f"<br><span class=\"small wrap\">incl. {_esc(_names(head.flexion_undetermined))}</span>"
    return dphi, undet, widest


def index_page(entries: Sequence[TrialEntry], alphas: Sequence[float]) -> str:
    """The index of the batch: every trial with status, key numbers or its error."""
    n_ok = sum(e.ok for e in entries)
    n_failed = len(entries) - n_ok
    rows, classes = [], []
    for i, e in enumerate(entries, 1):
        if e.ok:
            name = f"<a href=\"{quote(e.page or '')}\">{_esc(e.source.name)}</a>"
            status = "<span class=\"ok\">OK</span>"
            frames = f"{e.n_frames} @ {e.rate:g} Hz" if e.n_frames is not None and e.rate else "–"
            cycles = f"{e.cycles.get('L', 0)} / {e.cycles.get('R', 0)}"
            dphi, undet, widest = _index_numbers(e.headline)
            gaps = f"{e.gaps_filled} filled" + (f", {e.gaps_left} open" if e.gaps_left else "")
            detail = (f"<a class=\"nowrap\" href=\"{quote(e.page or '')}\">report page</a><br>"
                      f"<span class=\"small nowrap\">gaps: {_esc(gaps)}</span>")  # fmt: skip
            rows.append([(str(i), True), (name, False), (status, False), (frames, True),
                         (cycles, True), (index_cell(e.allowable), True), (dphi, True), (undet, True),
                         (widest, True), (detail, False)])  # fmt: skip
            classes.append("")
        else:
            rows.append([(str(i), True), (_esc(e.source.name), False),
                         ("<span class=\"failed\">failed</span>", False), ("–", True), ("–", True),
                         ("–", True), ("–", True), ("–", True), ("–", True),
                         (f'<span class="mono error">{_esc(e.error)}</span>', False)])  # fmt: skip
            classes.append("failed-row")
    lowest = alpha_text(min(alphas)) if alphas else "0"
    header = [("#", True), ("Trial", False), ("Status", False), ("Frames", True),
              ("Gait cycles<br>L / R", True), ("Allowable<br>error", True),
              ("Largest ΔΦ, flexion<br>(determined bands)", True),
              (f"Undetermined<br>at α = {lowest}", True), ("Widest<br>determined band", True),
              ("Details / error", False)]  # fmt: skip
    table = _table(header, rows, row_classes=classes)
    failed_text = f', <span class="failed">{n_failed} failed</span>' if n_failed else ""
    sources = "".join(f"<li><span class=\"mono\">{_esc(e.source)}</span></li>" for e in entries)
    body = f"""
<header>
<h1>Gait report: joint angles and their uncertainty</h1>
<p class="lead">{len(entries)} trial{'s' if len(entries) != 1 else ''}:
<span class="ok">{n_ok} OK</span>{failed_text}</p>
</header>
<main>
<div class="box">
<p>Each trial page shows the joint angles (by the model version named in its header) over the gait cycle and over the
whole trial, with shaded bands for the uncertainty caused by marker position errors
(measurement system, marker placement, soft-tissue artefact). {ALPHA_SENTENCE}</p>
<p>{DELTA_PHI_SENTENCE} Of the bands that are determined at every frame, the index
shows the largest ΔΦ among hip, knee and ankle flexion (as in the thesis' Table 5.2) and
the widest band in degrees among all angles, each at the smallest α-level where there is
one, and how many angle components are undetermined at the smallest α.</p>
<p>{UNDETERMINED_SENTENCE}</p>
<p>Allowable marker error: the largest marker error (mm; % of the assumed errors) for which the angle is
known within the tolerance over the whole trial — the index shows knee flexion, each trial page every
angle.</p>
</div>
<h2>Trials</h2>
<div class="index-table">{table}</div>
<h2>Input files</h2>
<ol class="small">{sources}</ol>
</main>
{_footer()}"""
    return _page("fuzzygait report – all trials", body)
