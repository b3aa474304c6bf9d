"""The report pages' fixed sentences: how to read the bands, ΔΦ and "undetermined"
(HTML fragments, made once here)."""

from __future__ import annotations

from fuzzygait.viz.report.clinical_html import footnote

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
    "angle (the magnitude keeps angles that stay negative comparable)." + footnote("delta")
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

CYCLES_ALT = (
    "Grid of joint angles (pelvis, hip, knee, ankle, foot progression; sagittal, frontal, "
    "transverse) over the gait cycle, left and right, with uncertainty bands per alpha-level"
)
