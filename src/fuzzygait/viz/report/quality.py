"""The data-quality section of a trial page: gait events and cycles, gaps of the markers
the model uses, missing markers and angles not computed, processing notes (HTML)."""

from __future__ import annotations

import numpy as np

from fuzzygait.core.names import angle_names
from fuzzygait.kinematics.labels import SIDE_NAMES
from fuzzygait.mocap.gaps import methods_used
from fuzzygait.viz.report.bands import TrialAnalysis, TrialData, grid_components
from fuzzygait.viz.report.clinical import ClinicalData
from fuzzygait.viz.report.markup import escape as _esc
from fuzzygait.viz.report.markup import html_table as _table

__all__ = ["quality_section"]


def quality_section(analysis: TrialAnalysis, data: TrialData, clinical: ClinicalData) -> str:
    """Gait events, gaps of the markers the model uses, missing markers and angles,
    processing notes."""
    run = analysis.run
    trial = run.trial
    gaps = clinical.model_gaps(run.gaps)
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
    parts.append(f"<p class=\"small\">Only the {len(clinical.markers)} markers the model uses are listed; other "
                 "markers in the file (unlabelled trajectories, markers of other models) do not affect the angles "
                 "and are neither filled nor filtered.</p>")
    if not gaps:
        parts.append("<p>None: every marker was visible in every frame.</p>")
    else:
        filled = sum(g.filled for g in gaps)
        parts.append(
            f"<p>{filled} of {len(gaps)} gaps filled ({_esc(methods_used(gaps)) or 'none'}); frames of gaps "
            "left open have no angle (and no band) for the joints that use the marker.</p>"
        )
        rows = []
        classes = []
        for gap in sorted(gaps, key=lambda g: (g.marker, g.start)):
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
    never = sorted({g.marker for g in gaps if "never visible" in g.reason})
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
        angles = angle_names(no_band)
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
