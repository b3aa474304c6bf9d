"""Clinicians' batch report: one HTML page per trial plus an ``index.html``.

Layout of the output folder::

    OUT/index.html                     every trial: status, key numbers, error line
    OUT/<trial>.html                   one page per successful trial
    OUT/<trial>_files/cycles.png|svg   angles over the gait cycle with fuzzy α-bands
    OUT/<trial>_files/time_series.png|svg   the whole trial with its α-bands
    OUT/<trial>_files/sources.png|svg  flexion with the α = 0 band of each error source
                                       (with per-source bands only)

The pages are plain HTML5 with inline CSS: no JavaScript, no external resources; the
figures are referenced by relative paths, so the folder can be zipped, mailed or opened
from a USB stick.

Gait-cycle bands
----------------
The fuzzy analysis gives, for every α-level, a lower and an upper hull of each angle at
every frame.  Each hull is time-normalised with the *same* gait cycles as the angle
(:func:`fuzzygait.gait.cycles.normalise_cycles`), and the band drawn is the **mean
over cycles** of the normalised lower hulls and of the normalised upper hulls, around
the mean over cycles of the measured angle.  Because the mean is linear and every
cycle's hulls enclose every angle curve the marker errors allow, this band encloses
every *mean* curve the marker errors allow: it is the uncertainty of the curve that is
drawn, and it keeps the α-levels nested.  Min/max over cycles would mix the stride-to-
stride variability (the SD of the classic report) into the measurement uncertainty.  At
each percentage only cycles where the angle and every hull are available are used.

Undetermined bands
------------------
Where an α-level's band is undetermined (the marker errors let a segment frame flip, a
bound more than 90° from the measured angle; ``undetermined`` in the dataset) the band
is not drawn: a hatched strip in the side's colour along the top of the panel marks
those points, the y-limits come from the curves and the determined bands only.  A
cycle point is undetermined when it is in *any* cycle used there (a mean with one
meaningless bound is meaningless).  ΔΦ cells read "undetermined" where an α-level is
undetermined at some frame; the key numbers (trial page, index) are of the bands
determined at every frame, with the number of components undetermined at the smallest
α beside them (a determined band is at most 180° wide).

Atomicity
---------
Everything is written into a hidden staging folder beside ``OUT`` and moved into place
when the report is complete: pages first, ``index.html`` last.  On an error (or Ctrl-C)
the staging folder is removed and ``OUT`` is untouched.  Pages of trials from earlier
runs that are not part of this batch stay in ``OUT`` but are not linked.

Allowable marker error
----------------------
A result refined by :func:`fuzzygait.markererror.allowable.allowable_errors` (what
``uncertainty`` / ``report`` compute for ``--tolerance``, default ±2.5°) leads the trial
page with the sentences of left and right knee flexion ("known within ±2.5° if every
marker stays within 2.3 mm of where it was measured ..."), followed by the table of every
angle (largest error mm, % of Table 3.1, mm per segment); the index shows knee flexion's.

Error sources
-------------
A result with per-source bands (:func:`fuzzygait.markererror.per_source.per_source_bands`,
``--per-source``, the default) gets a section after the ΔΦ table (thesis Fig. 5.9): per
joint (hip, knee, ankle) and side the measured flexion over the gait cycle with the α = 0
band of each error source alone and of all together (opaque fills drawn widest first, so
each ring shows its source's colour; undetermined bands hatched as above), and the table
of the widest α = 0 band per source with the source that dominates (a source whose band
is undetermined somewhere counts as dominating).

Modules: :mod:`~fuzzygait.viz.report.normalised_bands` (the cycle bands),
:mod:`~fuzzygait.viz.report.bands` (the numbers: ΔΦ table, summary numbers),
:mod:`~fuzzygait.viz.report.allowable` (the allowable-error table and its HTML),
:mod:`~fuzzygait.viz.report.figures`, :mod:`~fuzzygait.viz.report.sources` (the
per-source figure, table and sentence) and :mod:`~fuzzygait.viz.report.pages` (HTML
and CSS, :mod:`~fuzzygait.viz.report.markup` its building blocks).  They build figures
and page text only; the folder is written by :mod:`fuzzygait.workflows.report_folder`
(staged, atomic writing: ``ReportWriter``, ``write_report``) and the entries a re-run
reuses by :mod:`fuzzygait.workflows.report_entries`.
"""

from fuzzygait.kinematics.labels import component_label
from fuzzygait.viz.report.bands import TrialAnalysis, TrialEntry
from fuzzygait.viz.report.normalised_bands import cycle_bands

# The figures (matplotlib, half a second to import) are imported where they are drawn,
# from fuzzygait.viz.report.figures: the terminal's tables (``fuzzygait uncertainty``)
# read the page data of this package without drawing anything.
__all__ = [
    "TrialAnalysis",
    "TrialEntry",
    "component_label",
    "cycle_bands",
]
