"""The allowable-marker-error table as the report, the demo summary and the terminal show
it: per angle component the largest marker error (mm on its largest ball, % of Table 3.1,
mm per segment) for which the angle stays within the tolerance, and the sentences of the
flexion angles that lead the first screen.

The numbers are those of :func:`fuzzygait.markererror.allowable.allowable_table`, read
from the refined result (``result.allowable``, also after saving and reading it); a
result without the refinement has no table (:func:`allowable_summary` returns None).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from fuzzygait.core.options import Option
from fuzzygait.kinematics.labels import component_label
from fuzzygait.markererror.allowable import SEGMENTS, allowable_table
from fuzzygait.markererror.result import MarkerErrorResult
from fuzzygait.viz.report.bands import component_order
from fuzzygait.viz.report.markup import escape, html_table

__all__ = ["AllowableRow", "AllowableSummary", "allowable_section", "allowable_summary", "index_cell", "lead_box"]

#: What a cell without a number shows.
NO_DATA = "—"
#: The joints whose flexion sentences lead the first screen, in order of preference.
LEAD_JOINTS = ("Knee",)


def _percent(scale: float) -> str:
    """A scale (fraction) as a percentage: 0 decimals, 1 below 10 %, 2 below 1 %."""
    value = 100.0 * scale
    digits = 0 if value >= 10 or value == 0 else 1 if value >= 1 else 2
    return f"{value:.{digits}f}"


@dataclass(frozen=True)
class AllowableRow:
    """One component of the table, its cells as text.

    Attributes:
        component: e.g. ``"LKneeAngles_X"``; ``label``: ``"Left knee, sagittal (+ flexion)"``.
        status: ``"within"`` (bracketed), ``"full table passes"`` (even α = 0 stays within
            the tolerance), ``"smallest fails"`` (even the smallest error tried does not)
            or ``"no data"``.
        mm: the allowable error on the component's largest ball (1 decimal; ``"≥ x"``,
            ``"< x"`` or "—" by status); ``percent``: of Table 3.1 (0 decimals).
        segments: mm per segment of Table 3.1 ("" where the component uses none).
        note: the status in words ("" when bracketed); ``text``: the report's sentence.
    """

    component: str
    label: str
    status: str
    mm: str
    percent: str
    segments: dict[str, str]
    note: str
    text: str


@dataclass(frozen=True)
class AllowableSummary:
    """The table of a trial: ``tolerance`` (± deg), ``source`` (what 100 % is, e.g.
    ``"Table 3.1"``) and the rows in report order."""

    tolerance: float
    source: str
    rows: list[AllowableRow]

    def lead_rows(self) -> list[AllowableRow]:
        """The rows of the left and right knee flexion (else hip, else ankle flexion)."""
        by_name = {row.component: row for row in self.rows}
        for joint in (*LEAD_JOINTS, "Hip", "Ankle"):
            found = [by_name[c] for c in (f"L{joint}Angles_X", f"R{joint}Angles_X") if c in by_name]
            if found:
                return found
        return []

    def lead_sentences(self) -> list[str]:
        """The sentences of :meth:`lead_rows` (what leads the first screen)."""
        return [row.text for row in self.lead_rows()]


def allowable_summary(result: MarkerErrorResult | None) -> AllowableSummary | None:
    """The allowable-error table of a refined result as text cells, None without the
    refinement (or without a result)."""
    if result is None or result.allowable is None:
        return None
    refinement = result.allowable
    table = allowable_table(result)
    source = str(table.attrs.get("source", "Table 3.1"))
    records: dict[str, dict[Any, Any]] = {str(k): v for k, v in table.to_dict(orient="index").items()}
    rows = []
    for component in sorted(records, key=component_order):
        row = records[component]
        sigma = refinement["segment_radius"].sel(component=component).to_numpy().astype(float)
        largest = float(np.nanmax(sigma)) if np.isfinite(sigma).any() else math.nan
        scale, failing = float(row["allowable_scale"]), float(row["failing_scale"])
        segment_sigma = {str(s): float(v) for s, v in zip(refinement["segment"].to_numpy(), sigma, strict=True)}
        if not math.isfinite(scale):
            status, mm, percent, note = "no data", NO_DATA, NO_DATA, "no frame with every marker it needs"
            segments = dict.fromkeys(SEGMENTS, "")
        elif bool(row["full_table_passes"]):
            status, mm, percent, note = "full table passes", f"≥ {largest:.1f}", "≥ 100", f"{source} passes"
            segments = {s: "" if not math.isfinite(v) else f"≥ {v:.1f}"
                        for s in SEGMENTS for v in [segment_sigma.get(s, math.nan)]}  # fmt: skip
        elif bool(row["smallest_fails"]):
            status, note = "smallest fails", "even the smallest error tried fails"
            mm, percent = f"< {failing * largest:.2f}", f"< {_percent(failing)}"
            segments = {s: "" if not math.isfinite(v) else f"< {failing * v:.2f}"
                        for s in SEGMENTS for v in [segment_sigma.get(s, math.nan)]}  # fmt: skip
        else:
            status, mm, percent, note = "within", f"{float(row['allowable_mm']):.1f}", _percent(scale), ""
            segments = {s: "" if not math.isfinite(v := float(row[f"{s}_mm"])) else f"{v:.1f}" for s in SEGMENTS}
        rows.append(AllowableRow(component, str(row["label"]), status, mm, percent, segments, note, str(row["text"])))
    return AllowableSummary(float(table.attrs["tolerance_deg"]), source, rows)


# ============================================================================ HTML
def allowable_section(summary: AllowableSummary | None) -> str:
    """The allowable-marker-error table (rows in report order); a note without one."""
    if summary is None:
        return ("<h2 id=\"allowable\">Allowable marker error</h2><p class=\"small\">Not computed: the analysis "
                f"ran without a tolerance (<span class=\"mono\">{Option.TOLERANCE} 0</span>).</p>")  # fmt: skip
    tau, source = f"±{summary.tolerance:g}°", escape(summary.source)
    header = [("Angle", False), ("Max error (mm)", True), (f"% of {source}", True)]
    header += [(f"{escape(s)} (mm)", True) for s in SEGMENTS]
    rows = []
    for row in summary.rows:
        note = f" <span class=\"small\">({escape(row.note)})</span>" if row.note and row.status != "no data" else ""
        cells = [(f'<span title="{escape(row.component)}">{escape(row.label)}</span>', False),
                 (f"<b>{escape(row.mm)}</b>{note}", True), (escape(row.percent), True)]  # fmt: skip
        cells += [(escape(row.segments.get(s, "")), True) for s in SEGMENTS]
        rows.append(cells)
    return (
        f"<h2 id=\"allowable\">Allowable marker error ({tau})</h2>"
        f"<p>How small the marker errors must be for each angle to be known within {tau}: the largest error "
        f"for which the band stays within {tau} of the measured angle at every frame of the trial, on the "
        f"angle's largest ball (max error), as a fraction of {source} (the same fraction for every marker) "
        "and per segment. “≥”: even the full error passes (larger ones were not tried); “<”: even the "
        "smallest error tried fails; “—”: no frame with every marker the angle needs.</p>"
        + html_table(header, rows)
    )


def _strong_mm(sentence: str) -> str:
    """An allowable-error sentence as HTML with its "within X mm" in bold."""
    return re.sub(r"(within [\d.]+ mm)", r"<b>\1</b>", escape(sentence), count=1)


def index_cell(summary: AllowableSummary | None) -> str:
    """The index cell of the allowable error of knee flexion (else hip/ankle): mm per side."""
    rows = summary.lead_rows() if summary is not None else []
    if summary is None or not rows:
        return "–"
    lines = [f"{escape(r.component[0])} {escape(r.mm)}" + ("" if r.status == "no data" else " mm") for r in rows]
    what = component_label(rows[0].component).split(",")[0].split(" ", 1)[-1]  # "knee"
    return "<br>".join(lines) + f"<br><span class=\"small\">{escape(what)} flexion ±{summary.tolerance:g}°</span>"




def lead_box(summary: AllowableSummary | None) -> str:
    """The box leading the trial page: the knee-flexion sentences (the mm in bold) and a
    link to the table; "" without the refinement."""
    sentences = summary.lead_sentences() if summary is not None else []
    if not sentences:
        return ""
    lines = "".join(f"<p>{_strong_mm(text)}</p>" for text in sentences)
    return f'<div class="lead-box">{lines}<p class="small"><a href="#allowable">Every angle</a></p></div>'
