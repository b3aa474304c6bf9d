"""The kinetics section of a trial page (HTML): the joint moments and powers fuzzygait
computed from the force plates (Plug-in Gait inverse dynamics, :mod:`fuzzygait.kinetics`)
over the gait cycle, the ground reaction over stance, and per force-plate contact which
foot stood on it or why it was not used; a clear sentence when the trial has no force
plates.  Without computed kinetics, the moments and powers another program stored in the
file (:func:`fuzzygait.viz.report.clinical_html.kinetics_section`) are shown instead."""

from __future__ import annotations

from dataclasses import dataclass, field

from fuzzygait.core.options import Option
from fuzzygait.kinetics.assignment import ContactUse, PlateContact
from fuzzygait.viz.report.clinical import ClinicalData
from fuzzygait.viz.report.clinical_html import kinetics_section as stored_kinetics_section
from fuzzygait.viz.report.kinetics import KineticCycles
from fuzzygait.viz.report.markup import escape as _esc
from fuzzygait.viz.report.markup import html_table as _table

__all__ = ["KineticsPage", "NO_PLATES", "contact_rows", "kinetics_section"]

#: The sentence of a trial without force plates.
NO_PLATES = ("This trial has no force plates, so no joint moments, powers or ground reaction forces can be "
             "computed for it.")  # fmt: skip
HEAD = "<h2 id=\"kinetics\">Kinetics (joint moments, powers and ground reaction)</h2>"


@dataclass(frozen=True)
class KineticsPage:
    """What the kinetics section of a trial page shows.

    Attributes:
        cycles: the computed kinetics cut into the gait cycles; None: not computed
            (``missing`` says why).
        contacts: every force-plate contact and its foot, or why it was not used.
        notes: the kinetics' findings (one line each).
        missing: why there are no kinetics (e.g. :data:`NO_PLATES`), or None.
        first_frame: the C3D frame number of the trial's first frame; ``rate`` frames/s.
        normative: the normative file has kinetic curves (the figures' grey band).
    """

    cycles: KineticCycles | None
    contacts: tuple[PlateContact, ...] = ()
    notes: tuple[str, ...] = field(default_factory=tuple)
    missing: str | None = None
    first_frame: int = 1
    rate: float = 100.0
    normative: bool = False

    def drawn(self) -> bool:
        """Whether the section draws computed kinetics (some cycle stood on a plate)."""
        return self.cycles is not None and self.cycles.any()


def contact_rows(page: KineticsPage) -> list[list[tuple[str, bool]]]:
    """One table row per contact, in time order: plate, foot, C3D frames, duration (s),
    and "used" or why not (HTML cells, right-aligned flags)."""
    rows = []
    for c in sorted(page.contacts, key=lambda c: (c.first, c.plate)):
        foot = c.side or c.foot
        frames = f"{page.first_frame + c.first}–{page.first_frame + c.last}"
        if c.side is not None:
            how = " (as the subject file assigns the plate)" if c.reason is ContactUse.ASSIGNED else ""
            used = f"used for the {c.side.word.lower()} foot{how}"
        else:
            used = f"<span class=\"warning\">{_esc(c.describe())}</span>"
        rows.append([(str(c.plate), True), (foot.word if foot is not None else "–", False), (frames, True),
                     (f"{(c.last - c.first + 1) / page.rate:.2f}" + ("+" if c.cut else ""), True),
                     (used + _esc(c.cut_text()), False)])  # fmt: skip
    return rows


def _contacts_table(page: KineticsPage) -> str:
    if not page.contacts:
        return ("<p>No foot contact on any force plate was found in this trial (contacts are told by the heel, "
                "toe and ankle markers; the kinetics notes below say what was missing).</p>")
    header = [("Plate", True), ("Foot", False), ("C3D frames", True), ("Duration (s)", True), ("Result", False)]
    return ("<h3>Force-plate contacts</h3><p class=\"small\">Each contact goes to the foot whose heel–toe line "
            "the centre of pressure stays within 60 mm of, with the heel and ankle markers over the plate in "
            "mid-stance, unless the subject file assigns the plate; a contact of both feet, of a foot off the "
            "plate's edge or of a foot on two plates at once is not used. Foot: the foot the contact is "
            "about. A duration with + is cut by the start or end of the recording.</p>"
            + _table(header, contact_rows(page)))  # fmt: skip


def _figures(page: KineticsPage, figs: str) -> str:
    cycles = page.cycles
    assert cycles is not None
    if not cycles.any():
        return ("<p><b>No gait cycle of this trial had its stance on a force plate</b>, so no moment or power "
                "curve is drawn (a cycle counts when its foot is on a used plate at 20, 30 and 40 % of the "
                "cycle).</p>")  # fmt: skip
    counts = ", ".join(f"{'left' if s == 'L' else 'right'} {cycles.counted.get(s, 0)} of {cycles.total.get(s, 0)}"
                       for s in ("L", "R"))  # fmt: skip
    grey = "; grey: normative mean ± 1 SD" if page.normative else ""
    return (f"<p>Cycles with their stance on a force plate: {counts}. Thin lines: each such cycle; thick: their "
            f"mean (left red and solid, right green and dashed); vertical lines: mean foot off{grey}.</p>"
            f"<figure><a href=\"{figs}/kinetics.svg\"><img src=\"{figs}/kinetics.png\" width=\"1100\" "
            "height=\"820\" alt=\"Hip, knee and ankle moments (N·m/kg) in three planes and powers (W/kg) over "
            "the gait cycle, left and right\"></a><figcaption>Joint moments (N·m per kg body mass; internal "
            "moments) and powers (W per kg; positive: generated, negative: absorbed) over the gait cycle "
            f"(<a href=\"{figs}/kinetics.svg\">SVG</a>).</figcaption></figure>"
            f"<figure><a href=\"{figs}/grf.svg\"><img src=\"{figs}/grf.png\" width=\"1100\" height=\"360\" "
            "alt=\"Ground reaction force in % body weight over stance, left and right\"></a><figcaption>Ground "
            "reaction force (% body weight) over stance as the plate measured it: 0 % the first, 100 % the "
            "last frame the foot loads the plate (above 1 % body weight) "
            f"(<a href=\"{figs}/grf.svg\">SVG</a>).</figcaption></figure>")  # fmt: skip


def _uncertainty(page: KineticsPage) -> str:
    """The sentence on the moments' uncertainty bands (drawn or not)."""
    fuzzy = page.cycles.fuzzy if page.cycles is not None else None
    if fuzzy is None or not fuzzy.bands:
        return (" No uncertainty band is drawn for them (the marker-error analysis did not include the kinetics; "
                f"{Option.KINETICS} adds them).")  # fmt: skip
    levels = ", ".join(f"{a:g}" for a in fuzzy.alphas)
    return (f" The shaded bands (α = {levels}) around the sagittal moments and the powers are their fuzzy "
            "uncertainty: how far they can move when every marker moves within its Table 3.1 error ball and the "
            f"centre of pressure within {fuzzy.cop_error_mm:g} mm on the plate (the widest band: the full errors). "
            "Hatched strips along the top of a panel mark where a band is undetermined (a segment's frame can "
            "flip within the errors): no band is drawn there. Frontal and transverse moments carry no band "
            "(not analysed).")  # fmt: skip


def _delta_phi(page: KineticsPage) -> str:
    """The fuzzy kinetics' ΔΦ table (nothing without them)."""
    fuzzy = page.cycles.fuzzy if page.cycles is not None else None
    if fuzzy is None or not fuzzy.delta_phi:
        return ""
    levels = [a for a in fuzzy.alphas[::-1]]
    header = [("Moment or power", False), ("Units", False)] + [(f"α = {a:g}", True) for a in levels]
    rows = [[(_esc(label), False), (_esc(units), False)]
            + [(f"<i>{c}</i>" if c == "undetermined" else c, True) for c in cells]
            for label, units, cells in fuzzy.delta_phi]  # fmt: skip
    return ("<h3>Relative band width ΔΦ of the moments and powers (%)</h3><p class=\"small\">As for the angles: "
            "the widest α-band anywhere in the analysed frames relative to the largest measured |value|, over the "
            "frames where the band is determined; “undetermined”: some frame's band is.</p>"
            + _table(header, rows))  # fmt: skip


def _allowable(page: KineticsPage) -> str:
    """The moments' allowable-error sentences (nothing without fuzzy kinetics)."""
    fuzzy = page.cycles.fuzzy if page.cycles is not None else None
    if fuzzy is None or not fuzzy.allowable:
        return ""
    items = "".join(f"<li>{_esc(text)}</li>" for text in fuzzy.allowable)
    return ("<h3>How small the errors must be (allowable error of the sagittal moments)</h3><p class=\"small\">"
            "The largest errors, among the α-levels analysed, for which each moment stays within the tolerance "
            "of the measured value on every analysed frame (markers: the largest error ball; centre of "
            f"pressure: its ball).</p><ul>{items}</ul>")  # fmt: skip


def kinetics_section(page: KineticsPage | None, clinical: ClinicalData, figs: str) -> str:
    """The kinetics section: computed kinetics (``page``), else the trial's reason for
    none and the kinetics stored in the file, if any."""
    if page is None or page.cycles is None:
        reason = f"<p><b>{_esc(page.missing)}</b></p>" if page is not None and page.missing else ""
        if clinical.has_kinetics():
            return stored_kinetics_section(clinical, figs).replace("</h2>", "</h2>" + reason, 1)
        return HEAD + (reason or "<p>No kinetics: they were not computed for this trial.</p>")
    notes = "".join(f"<li>{_esc(n)}</li>" for n in page.notes)
    return (HEAD + "<p>Computed by fuzzygait from the force plates as Plug-in Gait does (inverse dynamics from "
            "the foot up, Dempster's segment parameters as Vicon tabulates them): moments in "
            "N·m per kg body mass — positive X is an internal extensor moment at hip and knee and a "
            "plantarflexor moment at the ankle — powers in W/kg, the ground reaction in % body weight."
            + _uncertainty(page) + "</p>" + _figures(page, figs) + _delta_phi(page) + _allowable(page)
            + _contacts_table(page)
            + (f"<h3>Kinetics notes</h3><ul class=\"notes small\">{notes}</ul>" if notes else ""))  # fmt: skip


