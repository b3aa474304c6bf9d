"""The clinical sections of a trial page as HTML: the plain-words reading guide, the
header facts (subject, session, model, markers, processing), the spatio-temporal table,
the Gait Profile Score / Movement Analysis Profile, the kinetics, and the footnotes that
carry the thesis references."""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Sequence
from pathlib import Path

from fuzzygait.core.findings import Finding, FindingKind, of_kind
from fuzzygait.core.options import Option
from fuzzygait.gait.normative import GPS_VARIABLES
from fuzzygait.gait.spatiotemporal import NAMES, UNITS, TrialParameters
from fuzzygait.io.subject import is_subject_file
from fuzzygait.viz.report.bands import ReportRun
from fuzzygait.viz.report.clinical import ClinicalData
from fuzzygait.viz.report.markup import escape as _esc
from fuzzygait.viz.report.markup import html_table as _table

__all__ = [
    "FOOTNOTES",
    "footnote",
    "footnotes_section",
    "deg_text",
    "gait_profile_section",
    "header_facts",
    "kinetics_section",
    "kv_table",
    "reading_guide",
    "spatiotemporal_section",
    "static_text",
    "subject_section",
    "warnings_box",
]

#: The thesis references, cited by number on the pages (:func:`footnote`).
FOOTNOTES = {
    "bands": "The fuzzy marker-error model and the α-level optimisation follow the thesis, §3.7.3 and §5.5; "
             "the error sizes per segment are its Table 3.1.",
    "delta": "ΔΦ is the relative envelope width of the thesis, Eq. 5.3 (its Table 5.2 lists it for hip, knee "
             "and ankle flexion).",
    "sources": "The bands of each error source alone are those of the thesis' Fig. 5.9.",
    "allowable": "The allowable marker error is that of the thesis, §5.5.2.",
    "gps": "Gait Profile Score and Movement Analysis Profile: R. Baker et al., Gait & Posture 30 (2009) "
           "265–269.",
}  # fmt: skip
_ORDER = list(FOOTNOTES)


def footnote(key: str) -> str:
    """The footnote mark of reference ``key`` (a superscript link to the footnotes)."""
    number = _ORDER.index(key) + 1
    return f'<sup class="fn"><a href="#fn-{key}">{number}</a></sup>'


def footnotes_section() -> str:
    """The footnotes (every page carries all of them, numbered as :func:`footnote`)."""
    items = "".join(f'<li id="fn-{key}">{_esc(text)}</li>' for key, text in FOOTNOTES.items())
    return f'<section class="footnotes small"><h2 id="references">References</h2><ol>{items}</ol></section>'


def reading_guide(has_bands: bool, has_normative: bool, has_kinetics: bool = False) -> str:
    """“How to read this page”, in plain words for clinicians (``has_kinetics``: the page
    shows moments and powers computed from force plates)."""
    lines = ["<b>Lines</b> are the patient's joint angles averaged over the walking cycles of this trial "
             "(left red and solid, right green and dashed); the <b>dotted lines</b> beside them show the "
             "usual stride-to-stride spread (mean ± 1 standard deviation); the <b>vertical lines</b> mark "
             "when the foot leaves the ground (foot off)."]  # fmt: skip
    if has_bands:
        lines.append(
            "<b>Shaded bands</b> (left: filled red; right: green hatching) show how far each curve could be "
            "off because the markers cannot be placed and tracked perfectly. The widest, lightest band assumes "
            "every marker is off by as much as we think possible; the narrower, darker bands assume smaller "
            "errors. A band is the range of possible values, <b>not a confidence interval</b>: it does not say "
            "how likely a value is, and the true curve may lie anywhere inside it."
            + footnote("bands"))  # fmt: skip
        lines.append(
            "<b>“Undetermined”</b> means that with the assumed marker errors the angle could be almost "
            "anything there (a body segment could appear turned the other way), so no band is drawn: read "
            "that part of the curve with great caution. It is not a fault of the recording.")  # fmt: skip
    else:
        lines.append("This report was made without the uncertainty analysis: no bands are shown.")
    if has_normative:
        lines.append(
            "The <b>grey band</b> is the normative range (mean ± 1 standard deviation of the reference "
            "group). The <b>Gait Profile Score</b> (GPS) says, in degrees, how far the patient's curves are "
            "from the normative mean on average; the bars of the Movement Analysis Profile say it for each "
            "joint." + footnote("gps"))  # fmt: skip
    if has_kinetics:
        lines.append(
            "<b>Kinetics</b> (joint moments and powers) need the foot on a force plate: only the walking cycles "
            "whose foot stood on one are shown (thin lines, their mean thick). Moments are per kg body mass "
            "(N·m/kg; positive: the muscles extend the hip and knee, plantarflex the ankle); power is positive "
            "when the joint generates energy, negative when it absorbs it.")  # fmt: skip
    items = "".join(f"<li>{line}</li>" for line in lines)
    return f'<div class="guide"><h2 id="guide">How to read this page</h2><ul>{items}</ul></div>'


def _session_text(source: Path, session: str | None) -> str:
    if session:
        return _esc(session)
    try:
        stamp = _dt.datetime.fromtimestamp(source.stat().st_mtime).strftime("%Y-%m-%d")
    except OSError:
        return "not known"
    return f"{stamp} <span class=\"small\">(the file's date; the C3D file stores none)</span>"


def _gap_settings(finding: Finding) -> str:
    """The settings of a gap-filling finding (``max_gap`` 10 frames, ``method`` auto ->
    ``"gaps of up to 10 frames filled (method auto)"``; its message's counts include
    markers the model does not use, the data-quality section counts the model's)."""
    if finding.max_gap is None or finding.method is None:
        return finding.message
    if finding.max_gap == 0:
        return "gap filling: off (max_gap 0)"
    return f"gaps of up to {finding.max_gap} frames filled (method {finding.method}); what was filled: Data quality"


def _processing_text(run: ReportRun) -> str:
    """Gap filling and filter settings, from the trial's gap-filling and low-pass findings."""
    gap = of_kind(run.trial.notes, FindingKind.GAP_FILLING)
    low = of_kind(run.trial.notes, FindingKind.LOW_PASS)
    parts = [_gap_settings(gap[-1]) if gap else "gap filling: not applied"]
    parts.append(low[-1].message if low else "no low-pass filter")
    return "<br>".join(_esc(p) for p in parts)


def header_facts(run: ReportRun, source: Path, clinical: ClinicalData, session: str | None) -> list[tuple[str, str]]:
    """The header rows: subject, session date, model version, marker set, processing."""
    markers = clinical.markers
    listing = ", ".join(markers)
    return [
        ("Subject", _subject_text(run)),
        ("Session", _session_text(source, session)),
        ("Model", _esc(_model_name(run.result.model))),
        ("Marker set", f"{len(markers)} markers used by the model: <span class=\"small mono\">{_esc(listing)}</span>"),
        ("Gaps and filter", _processing_text(run)),
    ]


def _subject_text(run: ReportRun) -> str:
    """The subject's name as the C3D file gives it, else where its parameters came from."""
    name = run.trial.subject or run.raw.subject
    if name:
        return _esc(name)
    source = Path(run.subject.source)
    origin = f" (parameters from {source.name})" if is_subject_file(source) else ""
    return _esc(f"not named in the C3D file{origin}")


def _model_name(model: str) -> str:
    title = "CGM " + model.removeprefix("cgm")
    return title + " (Plug-in Gait)" if model == "cgm1.0" else title


def _number(value: float, unit: str) -> str:
    """A parameter value as shown: 0.1 steps/min and %, 1 ms, 1 mm, 0.01 m/s."""
    if not math.isfinite(value):
        return "–"
    digits = 1 if unit in ("steps/min", "%") else 3 if unit in ("s", "m") else 2
    return f"{value:.{digits}f}"


def spatiotemporal_section(clinical: ClinicalData) -> str:
    """The spatio-temporal table of a trial page (mean ± SD over the complete cycles)."""
    head = "<h2 id=\"spatiotemporal\">Spatio-temporal parameters</h2>"
    params = clinical.parameters
    if params is None:
        return head + f"<p class=\"small\">Not available: {_esc(clinical.parameters_error or 'no gait cycle')}</p>"
    notes = "".join(f"<li>{_esc(n.message)}</li>" for n in params.notes)
    return (head + "<p>Computed from the gait events and the toe markers as Vicon Nexus does, over the complete "
            "gait cycles of each side (a cycle with both feet's events in order). Percentages are of the gait "
            "cycle; “Opposite Foot Off/Contact” are the other foot's events.</p>" + spatiotemporal_table(params)
            + (f"<ul class=\"notes small\">{notes}</ul>" if notes else ""))  # fmt: skip


def spatiotemporal_table(params: TrialParameters) -> str:
    """Parameter, unit, then mean ± SD over each side's complete cycles (HTML table)."""
    rows = []
    for name in NAMES:
        unit = UNITS[name]
        cells = [(_esc(name), False), (_esc(unit), False)]
        for code in "LR":
            side = params.sides[code]
            mean, sd = side.mean()[name], side.sd()[name]
            text = _number(mean, unit)
            if math.isfinite(sd):
                text += f" ± {_number(sd, unit)}"
            cells.append((text, True))
        rows.append(cells)
    counts = [len(params.sides[c].complete_cycles) for c in "LR"]
    header = [("Parameter", False), ("Unit", False), (f"Left (mean ± SD, {counts[0]} cycles)", True),
              (f"Right (mean ± SD, {counts[1]} cycles)", True)]  # fmt: skip
    return _table(header, rows)


def gait_profile_section(clinical: ClinicalData, figs: str) -> str:
    """The Gait Profile Score and the Movement Analysis Profile (with normative data)."""
    head = "<h2 id=\"gps\">Gait Profile Score and Movement Analysis Profile</h2>"
    profile = clinical.profile
    if profile is None:
        return (head + "<p class=\"small\">Not computed: no normative data were given (<span class=\"mono\">"
                f"{Option.NORMATIVE} NORM.csv</span>).</p>")  # fmt: skip

    def deg(value: float) -> str:
        return f"{value:.1f}" if math.isfinite(value) else "–"

    rows = [[(_esc(name), False), (deg(profile.gvs["L"][name]), True), (deg(profile.gvs["R"][name]), True)]
            for _, _, name in GPS_VARIABLES]  # fmt: skip
    rows.append([("<b>GPS</b>", False), (f"<b>{deg(profile.gps['L'])}</b>", True),
                 (f"<b>{deg(profile.gps['R'])}</b>", True)])  # fmt: skip
    table = _table([("Variable", False), ("Left (deg)", True), ("Right (deg)", True)], rows)
    overall = f"<b>{deg(profile.overall)}°</b>" if math.isfinite(profile.overall) else (
        "<b>not available</b> (it needs every variable of both sides; a side without a gait cycle or a "
        "missing curve leaves it out — the side scores below are what there is)")  # fmt: skip
    return (
        head + f"<p>Overall GPS: {overall} against the normative data "
        f"<span class=\"mono\">{_esc(profile.normative)}</span>. Each number is the typical difference (root "
        "mean square over the gait cycle, every 2 %) between the patient's mean curve and the normative mean; "
        "0 means the same curve. A side's GPS combines its nine variables; the overall GPS combines both "
        "sides, counting the pelvis once." + footnote("gps") + "</p>"
        + f"<div class=\"cols\">{table}<figure><img src=\"{figs}/profile.png\" width=\"1100\" height=\"440\" "
        "alt=\"Movement Analysis Profile: bars of the gait variable scores per variable and side\">"
        f"<figcaption>Movement Analysis Profile (<a href=\"{figs}/profile.svg\">SVG</a>).</figcaption>"
        "</figure></div>"
    )


def kinetics_section(clinical: ClinicalData, figs: str) -> str:
    """Joint moments and powers stored in the file, over the gait cycle."""
    head = "<h2 id=\"kinetics\">Kinetics (joint moments and powers)</h2>"
    if not clinical.has_kinetics():
        return head + ("<p class=\"small\">None in the file: it holds no moments or powers from force-plate "
                       "data for a whole gait cycle.</p>")  # fmt: skip
    units = sorted({c.unit for c in clinical.kinetics.values()})
    per_kg = all(u.endswith("/kg") for u in units)
    unit_text = ("moments in N·m per kg body mass, powers in W per kg (Plug-in Gait divides by the body mass; "
                 "the file labels them Nmm and W)") if per_kg else ("in " + ", ".join(units))  # fmt: skip
    return (
        head + "<p>As computed by the program that wrote the file (e.g. Vicon Nexus) and stored there — "
        f"fuzzygait does not recompute them: {_esc(unit_text)}. Only cycles in which the foot struck a force "
        "plate are averaged; no uncertainty band is given for them.</p>"
        f"<figure><img src=\"{figs}/kinetics.png\" width=\"1100\" height=\"760\" alt=\"Joint moments and powers "
        "of hip, knee and ankle over the gait cycle, left and right\"><figcaption>Mean ± 1 SD over the cycles "
        f"with force-plate data (<a href=\"{figs}/kinetics.svg\">SVG</a>).</figcaption></figure>"
    )


def warnings_box(warnings: list[str]) -> str:
    """A box of warnings at the top of the page ("" without any)."""
    if not warnings:
        return ""
    items = "".join(f"<li>{_esc(w)}</li>" for w in warnings)
    return f'<div class="warn"><b>Warning</b><ul>{items}</ul></div>'


def kv_table(rows: Sequence[tuple[str, str]], caption: str | None = None) -> str:
    """A two-column table of (label, html) rows."""
    cap = f"<caption class=\"small\">{_esc(caption)}</caption>" if caption else ""
    body = "".join(f"<tr><th scope=\"row\">{_esc(k)}</th><td>{v}</td></tr>" for k, v in rows)
    return f"<table class=\"kv\">{cap}<tbody>{body}</tbody></table>"


def deg_text(rad: float) -> str:
    """Radians as degrees with two decimals (never "-0.00")."""
    text = f"{math.degrees(rad):.2f}"
    return "0.00" if text == "-0.00" else text


def static_text(run: ReportRun) -> str:
    """Where the static offsets come from (a sentence)."""
    static = of_kind(run.notes, FindingKind.STATIC_CALIBRATION)
    if static:
        text = static[0].message
        return text[0].upper() + text[1:] + "."
    return "No static trial given: the static offsets are used as stored in the subject parameters."


def subject_section(run: ReportRun) -> str:
    """The subject parameters used, per side and general."""
    subject = run.subject
    rows = [
        ("Leg length", "mm", "leg_length", lambda v: f"{v:.1f}"),
        ("Knee width", "mm", "knee_width", lambda v: f"{v:.1f}"),
        ("Ankle width", "mm", "ankle_width", lambda v: f"{v:.1f}"),
        ("ASIS–trochanter distance", "mm", "asis_trochanter", lambda v: f"{v:.1f}"),
        ("Tibial torsion", "deg", "tibial_torsion", deg_text),
        ("Thigh rotation offset", "deg", "thigh_rotation", deg_text),
        ("Shank rotation offset", "deg", "shank_rotation", deg_text),
        ("Ankle ab/adduction offset", "deg", "ankle_abadd", deg_text),
        ("Sole delta", "mm", "sole_delta", lambda v: f"{v:.1f}"),
        ("<b>Static plantarflexion offset</b>", "deg", "static_plant_flex", deg_text),
        ("<b>Static rotation offset</b>", "deg", "static_rot_off", deg_text),
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
        f"<p class=\"small\">{_esc(static_text(run))}</p>"
        f"<div class=\"cols\">{sides}{kv_table(general)}</div>"
    )
