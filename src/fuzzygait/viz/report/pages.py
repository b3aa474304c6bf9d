"""The report's HTML: plain HTML5 pages with inline CSS (no JavaScript, no external
resources), one per trial and the index of the batch."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import quote

import numpy as np

from fuzzygait.core.names import is_flexion
from fuzzygait.kinematics.labels import PLANES, ROW_TITLES, component_label, parse_component
from fuzzygait.markererror.result import MarkerErrorResult, ball_radius, error_sources
from fuzzygait.markererror.sources import SOURCE_TITLES
from fuzzygait.mocap.marker_placement import moved_angles
from fuzzygait.viz.report.allowable import allowable_section, index_cell, lead_box
from fuzzygait.viz.report.bands import (
    DeltaPhiTable,
    Headline,
    ReportRun,
    TrialAnalysis,
    TrialData,
    TrialEntry,
    alpha_text,
)
from fuzzygait.viz.report.chrome import model_title, page_document, page_footer
from fuzzygait.viz.report.clinical import ClinicalData
from fuzzygait.viz.report.clinical_html import (
    deg_text,
    footnote,
    footnotes_section,
    gait_profile_section,
    header_facts,
    kv_table,
    reading_guide,
    spatiotemporal_section,
    static_text,
    subject_section,
    warnings_box,
)
from fuzzygait.viz.report.kinetics_section import KineticsPage, kinetics_section
from fuzzygait.viz.report.markup import escape as _esc
from fuzzygait.viz.report.markup import html_table as _table
from fuzzygait.viz.report.quality import quality_section
from fuzzygait.viz.report.sources import has_source_bands, sources_section
from fuzzygait.viz.report.wording import (
    ALPHA_SENTENCE,
    CYCLES_ALT,
    DELTA_PHI_SENTENCE,
    UNDETERMINED,
    UNDETERMINED_SENTENCE,
)

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["PageSource", "index_page", "trial_page"]


def _fmt(value: float | None, digits: int = 1) -> str:
    """A number with ``digits`` decimals; "–" for a missing or non-finite one."""
    if value is None or not np.isfinite(value):
        return "–"
    return f"{value:.{digits}f}"



def _sources_text(fuzzy: xr.Dataset) -> str:
    """The bands' error sources as words: ``("measurement", "sta")`` -> ``"measurement
    system, soft-tissue artefact"`` ("" when the bands name none)."""
    return ", ".join(SOURCE_TITLES.get(name, name) for name in error_sources(fuzzy))




def _assumptions_section(analysis: TrialAnalysis) -> str:
    """The assumed marker errors: α = 0 ball radius per marker."""
    fuzzy = analysis.fuzzy
    assert fuzzy is not None, "the assumed marker errors need a fuzzy analysis"
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
        plane = "flexion" if is_flexion(name) else dict((a, p) for a, p, _ in PLANES).get(axis, axis)
        groups.setdefault(f"{row} {plane}", []).append(side)
    nbsp = ",\u00a0"  # the sides stay together
    return ", ".join(f"{what} ({nbsp.join(sides)})" if sides else what for what, sides in groups.items())


def headline_lines(head: Headline) -> list[str]:
    """The key numbers of a trial as HTML lines, determined bands first."""
    lines = []
    if head.largest is not None:
        value, name, alpha = head.largest
        what = "hip/knee/ankle flexion" if is_flexion(name) else "the analysed angles"
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


@dataclass(frozen=True)
class PageSource:
    """Where a trial page's trial comes from: its file (``source``; the page's title), its
    figures' folder beside the page (``files``, relative), its session's name (None: the
    files were given directly) and the warnings shown at the top."""

    source: Path
    files: str
    session: str | None = None
    warnings: Sequence[str] = ()


def trial_page(analysis: TrialAnalysis, data: TrialData, entry: TrialEntry, table: DeltaPhiTable, page: PageSource,
               *, clinical: ClinicalData | None = None, kinetics: KineticsPage | None = None) -> str:  # fmt: skip
    """The page of one trial: how to read it, the header (subject, session, model, markers,
    processing), spatio-temporal parameters, the kinematics grid, GPS/MAP, kinetics
    (``kinetics``: computed from the force plates; None: those stored in the file), the
    allowable marker error, ΔΦ table, per-source bands, whole trial, data quality (the
    model's markers), assumptions, subject, references.  Without a fuzzy analysis
    (``analysis.fuzzy`` None) the uncertainty sections are left out."""
    source, files, session, warnings = page.source, page.files, page.session, page.warnings
    run = analysis.run
    fuzzy = analysis.fuzzy
    if clinical is None:
        clinical = ClinicalData.of(run, data.cycles)
    facts = _trial_facts(run, source, clinical, session, data)
    key = _key_lines(entry, clinical, run)
    figs = quote(files)
    nav = _page_nav(fuzzy, analysis.result)
    uncertainty = ""
    if fuzzy is not None:
        uncertainty = (allowable_section(entry.allowable) + _delta_phi_section(table, data)
                       + sources_section(analysis.result, figs))  # fmt: skip
    bands_text = "<p>No uncertainty bands: the trial was reported without the marker-error analysis.</p>"
    if len(data.alphas):
        bands_text = f"<p>{ALPHA_SENTENCE}{footnote('bands')}</p>"
    height = int(round(1260 * ((len(clinical.rows) or 5) + 0.6) / 5.6))
    lead = " with their uncertainty from marker position errors" if fuzzy is not None else ""
    grey = "; grey: normative mean ± 1 SD" if clinical.normative is not None else ""
    cycles_caption = frame_bands = ""
    if len(data.alphas):
        cycles_caption = " with α-bands; hatched strips along the top of a panel: undetermined there (no band drawn)"
        frame_bands = ", with the α-bands frame by frame"
    assumptions = _assumptions_section(analysis) if fuzzy is not None else ""
    body = f"""
<nav><a href="index.html">← All trials (index)</a> · {nav}</nav>
<header>
<h1>{_esc(source.name)}</h1>
<p class="lead">Joint angles by {_esc(model_title(run.result.model))}{lead}</p>
</header>
<main>
{warnings_box(list(warnings))}{lead_box(entry.allowable)}<div class="cols">{kv_table(facts)}
<div class="box">{'<br>'.join(key)}</div></div>
{reading_guide(bool(len(data.alphas)), clinical.normative is not None, kinetics is not None and kinetics.drawn())}
{spatiotemporal_section(clinical)}
<h2 id="cycles">Kinematics over the gait cycle</h2>
{bands_text}
<p>Left side red (solid line, filled bands), right side green (dashed line, hatched bands); all angles in degrees,
positive direction as labelled on each axis; vertical lines: foot off of each side; dotted lines: mean ± 1 SD over
the cycles (stride-to-stride variability){grey}.</p>
<p class="small">How the bands are normalised: each α-level's lower and upper bound is
cut into the same gait cycles (foot strike to next foot strike of that side) and
time-normalised like the angle; the band shown is the mean over cycles of the lower and of
the upper bounds, around the mean angle curve. It is therefore the uncertainty of the
mean curve drawn; the stride-to-stride variability is not included. A note such as
“L: 3 of 4 cycles” means some cycles had missing data there.</p>
<figure>
<a href="{figs}/cycles.svg"><img src="{figs}/cycles.png" width="1100" height="{height}"
alt="{CYCLES_ALT}"></a>
<figcaption>Mean over gait cycles{cycles_caption}.
Click for the scalable version (<a href="{figs}/cycles.svg">SVG</a>, <a href="{figs}/cycles.png">PNG</a>).</figcaption>
</figure>
{gait_profile_section(clinical, figs)}
{kinetics_section(kinetics, clinical, figs)}
{uncertainty}
<h2 id="time-series">Whole trial</h2>
<p>The same angles over the whole recording (not normalised){frame_bands}.
Dotted vertical lines mark foot strikes (red left, green right).</p>
<figure>
<a href="{figs}/time_series.svg"><img src="{figs}/time_series.png" width="1100" height="{height}"
alt="Grid of joint angles over time for the whole trial"></a>
<figcaption>Joint angles over time
(<a href="{figs}/time_series.svg">SVG</a>, <a href="{figs}/time_series.png">PNG</a>).</figcaption>
</figure>
{quality_section(analysis, data, clinical)}
{assumptions}
{subject_section(run)}
{footnotes_section()}
<p><a href="index.html">← Back to all trials</a></p>
</main>
{page_footer(run.result.model)}"""
    return page_document(f"{source.name} – fuzzygait report", body)


def _trial_facts(run: ReportRun, source: Path, clinical: ClinicalData, session: str | None,
                 data: TrialData) -> list[tuple[str, str]]:  # fmt: skip
    """The header table of a trial page: subject, session, model, file, frames, cycles,
    static offsets (degrees), α-levels and error sources (HTML)."""
    trial, fuzzy = run.trial, data.fuzzy
    last = trial.first_frame + trial.n_frames - 1
    n_cycles = data.n_cycles()
    facts = header_facts(run, source, clinical, session) + [
        ("File", f"<span class=\"mono\">{_esc(source)}</span>"),
        ("Frames", f"{trial.n_frames} (C3D frames {trial.first_frame}–{last}) at {trial.rate:g} Hz, "
                   f"{trial.n_frames / trial.rate:.2f} s"),
        ("Gait cycles", f"left {n_cycles['L']}, right {n_cycles['R']}"),
        ("Static offsets",
         f"plantarflexion L {deg_text(run.subject.left.static_plant_flex)}°, "
         f"R {deg_text(run.subject.right.static_plant_flex)}°; "
         f"rotation L {deg_text(run.subject.left.static_rot_off)}°, R {deg_text(run.subject.right.static_rot_off)}°"
         f"<br><span class=\"small\">{_esc(static_text(run))} "
         "<a href=\"#subject\">All subject parameters</a></span>"),
    ]  # fmt: skip
    if len(data.alphas):
        facts.append(("α-levels", ", ".join(alpha_text(a) for a in data.alphas) + ", 1 (measured)"))
    if fuzzy is not None and _sources_text(fuzzy):
        facts.append(("Error sources", _esc(_sources_text(fuzzy))))
    return facts


def _key_lines(entry: TrialEntry, clinical: ClinicalData, run: ReportRun) -> list[str]:
    """The key-numbers box: moved markers first, the GPS, the headline and the gaps (HTML lines)."""
    key = headline_lines(entry.headline)
    if entry.gps is not None:
        gps = f"<b>{_fmt(entry.gps, 1)}°</b>" if np.isfinite(entry.gps) else "not available for both sides"
        key.insert(0, f"Gait Profile Score: {gps} (<a href=\"#gps\">per joint</a>)")
    moved = entry.moved
    if moved:  # first: it says how far to trust the numbers below
        key.insert(0, f"<b>Markers moved</b> between the static trial and this one ({', '.join(moved)}): the "
                      f"static calibration does not fit them, so the {moved_angles(moved)} are unreliable "
                      "(<a href=\"#quality\">Data quality</a>).")  # fmt: skip
    gaps = clinical.model_gaps(run.gaps)
    filled = sum(g.filled for g in gaps)
    key.append(f"Gaps in the model's markers: {filled} filled, {len(gaps) - filled} left open; "
               f"{len(run.result.unavailable)} angle(s) not computed.")  # fmt: skip
    kinetics = getattr(run, "kinetics", None)  # computed from the force plates (AnglesRun.kinetics)
    if kinetics is not None:
        summary = str(kinetics.summary())
        key.append(f"{_esc(summary[:1].upper() + summary[1:])} (<a href=\"#kinetics\">Kinetics</a>).")
    return key


def _page_nav(fuzzy: xr.Dataset | None, result: MarkerErrorResult | None) -> str:
    """The links along the top of a trial page (its uncertainty sections only with an analysis)."""
    links = [("guide", "How to read"), ("spatiotemporal", "Spatio-temporal"), ("cycles", "Kinematics"),
             ("gps", "GPS"), ("kinetics", "Kinetics")]  # fmt: skip
    if fuzzy is not None:
        links += [("allowable", "Allowable error"), ("delta-phi", "ΔΦ table")]
        if has_source_bands(result):
            links.append(("sources", "Error sources"))
    links += [("time-series", "Whole trial"), ("quality", "Data quality"), ("subject", "Subject")]
    nav = " · ".join(f'<a href="#{k}">{_esc(t)}</a>' for k, t in links)
    return nav


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
    with_gps = any(e.gps is not None for e in entries)
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
            detail += "".join(f'<br><span class="warning">warning: {_esc(w)}</span>' for w in e.data_warnings)
            gps = [(_fmt(e.gps, 1) + ("°" if e.gps is not None else ""), True)] if with_gps else []
            rows.append([(str(i), True), (name, False), (status, False), (frames, True),
                         (cycles, True), *gps, (index_cell(e.allowable), True), (dphi, True), (undet, True),
                         (widest, True), (detail, False)])  # fmt: skip
            classes.append("")
        else:
            rows.append([(str(i), True), (_esc(e.source.name), False),
                         ("<span class=\"failed\">failed</span>", False), ("–", True), ("–", True),
                         *([("–", True)] if with_gps else []),
                         ("–", True), ("–", True), ("–", True), ("–", True),
                         (f'<span class="mono error">{_esc(e.error)}</span>', False)])  # fmt: skip
            classes.append("failed-row")
    lowest = alpha_text(min(alphas)) if alphas else "0"
    header = [("#", True), ("Trial", False), ("Status", False), ("Frames", True),
              ("Gait cycles<br>L / R", True), *([("GPS", True)] if with_gps else []), ("Allowable<br>error", True),
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
shows the largest ΔΦ among hip, knee and ankle flexion and
the widest band in degrees among all angles, each at the smallest α-level where there is
one, and how many angle components are undetermined at the smallest α.</p>
<p>{UNDETERMINED_SENTENCE} The bands are ranges of possible values, not confidence intervals: they do not say
how likely a value is.</p>
<p>GPS: the Gait Profile Score (deg), how far the trial's joint angles are from the normative mean on average
(only with normative data).{footnote("gps")}</p>
<p>Allowable marker error: the largest marker error (mm; % of the assumed errors) for which the angle is
known within the tolerance over the whole trial — the index shows knee flexion, each trial page every
angle.</p>
</div>
<h2>Trials</h2>
<div class="index-table">{table}</div>
<h2>Input files</h2>
<ol class="small">{sources}</ol>
{footnotes_section()}
</main>
{page_footer()}"""
    return page_document("fuzzygait report – all trials", body)
