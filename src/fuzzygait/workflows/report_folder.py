"""Staged, atomic writing of the report folder: every page and figure goes into a hidden
staging folder beside ``OUT`` and is moved into place when the report is complete (pages
first, ``index.html`` last); on an error (or Ctrl-C) ``OUT`` is left as it was.

The pages and figures are built by :mod:`fuzzygait.viz.report` (which writes nothing);
this module writes them (figures through :func:`fuzzygait.io.figure_files.save_figure_files`).
The folder's layout is described in :mod:`fuzzygait.viz.report`."""

from __future__ import annotations

import dataclasses
import os
import re
import shutil
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.findings import Finding, FindingKind, Severity, of_kind
from fuzzygait.core.options import Option
from fuzzygait.gait.cycles import GaitCycle
from fuzzygait.gait.normative import NormativeData
from fuzzygait.gait.spatiotemporal import TrialParameters
from fuzzygait.io.atomic import replace_path
from fuzzygait.io.figure_files import save_figure_files
from fuzzygait.viz.report.allowable import allowable_summary
from fuzzygait.viz.report.bands import ReportRun, TrialAnalysis, TrialData, TrialEntry, delta_phi_table
from fuzzygait.viz.report.clinical import ClinicalData
from fuzzygait.viz.report.clinical_figures import gait_profile_figure
from fuzzygait.viz.report.clinical_figures import kinetics_figure as stored_kinetics_figure
from fuzzygait.viz.report.figures import DPI, cycle_figure, time_series_figure
from fuzzygait.viz.report.kinetics import (
    KINETIC_ROWS,
    KineticCycles,
    dataset_components,
    grf_figure,
    kinetic_bands,
    kinetics_figure,
    session_kinetics_figure,
)
from fuzzygait.viz.report.kinetics_section import NO_PLATES, KineticsPage
from fuzzygait.viz.report.pages import PageSource, index_page, trial_page
from fuzzygait.viz.report.session import SESSION_DPI, SessionKinetics, session_cycles_figure
from fuzzygait.viz.report.sources import has_source_bands, source_figure

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["ReportItem", "ReportWriter", "kinetics_page", "run_kinetic_cycles", "write_report", "write_session_cycles",
           "write_session_kinetics"]


@dataclass
class ReportItem:
    """One trial of the batch: its analysis, or the one-line error that stopped it.

    Attributes:
        source: the trial's file.
        analysis: its run and marker-error analysis (``analysis.fuzzy`` None: angles
            only, no bands).
        error: the one-line error that stopped it.
        parameters: its spatio-temporal parameters
            (:func:`~fuzzygait.gait.spatiotemporal.spatiotemporal_parameters`); None: the
            writer computes them from the run.
        session: the session (visit) the trial belongs to and its date, for the header
            (e.g. ``"2024-03-05 visit"``); None: the file's modification date is shown.
        warnings: lines shown in a warning box at the top of the page (e.g. a subject
            name that does not match the subject file).
    """

    source: Path
    analysis: TrialAnalysis | None = None
    error: str | None = None
    parameters: TrialParameters | None = None
    session: str | None = None
    warnings: list[str] = field(default_factory=list)


@dataclass
class _AnglesOnly:
    """An analysis without bands (:func:`angles_only`)."""

    run: ReportRun
    fuzzy: None
    delta_phi: pd.DataFrame
    notes: list[Finding]
    result: None = None


def angles_only(analysis: TrialAnalysis) -> TrialAnalysis:
    """``analysis`` as the pages read it: one whose fuzzy dataset is missing or holds no
    angle component (``--uncertainty none``) becomes one with ``fuzzy`` None (no bands,
    no ΔΦ, allowable-error, per-source or assumptions sections)."""
    fuzzy = analysis.fuzzy
    if fuzzy is not None and int(fuzzy.sizes.get("component", 1)) > 0:
        return analysis
    return _AnglesOnly(analysis.run, None, pd.DataFrame(), list(analysis.notes))


def _one_line(text: str) -> str:
    """An error message on one line."""
    lines = [line.strip() for line in str(text).splitlines() if line.strip()]
    return " ".join(lines) if lines else "unknown error"


def _slug(stem: str) -> str:
    """A file name stem safe in URLs and on every file system."""
    slug = re.sub(r"[^A-Za-z0-9._-]+", "_", stem).strip("._-")
    return slug or "trial"


class ReportWriter:
    """Writes the report trial by trial into a staging folder; :meth:`finish` moves it
    into ``out_dir`` (pages first, index last).  Use as a context manager: on an
    exception the staging folder is removed and ``out_dir`` is left as it was.

    Args:
        out_dir: the report folder (created; existing pages of the same names replaced).
        strict: re-raise errors while drawing a page instead of listing the trial as
            failed (for debugging).
        normative: reference curves (:func:`fuzzygait.gait.normative.read_normative`):
            drawn as grey bands, and the Gait Profile Score / Movement Analysis Profile
            of every trial against them; None: neither.
    """

    def __init__(self, out_dir: str | os.PathLike[str], *, strict: bool = False,
                 normative: NormativeData | None = None) -> None:  # fmt: skip
        self.out_dir = Path(out_dir)
        self.strict = strict
        self.normative = normative
        self.entries: list[TrialEntry] = []
        self._names: set[str] = {"index"}
        self._alphas: set[float] = set()
        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise FuzzyGaitError(f"{self.out_dir}: {Option.OUT} must be a folder, not a file")
        parent = self.out_dir.resolve().parent
        try:
            parent.mkdir(parents=True, exist_ok=True)
            staging = Path(tempfile.mkdtemp(prefix=f".{self.out_dir.name}.", suffix=".tmp", dir=parent))
        except OSError as exc:
            raise FuzzyGaitError(f"{self.out_dir}: cannot create the report folder ({exc.strerror})") from None
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(staging, 0o777 & ~umask)
        self._staging: Path | None = staging

    # -- context manager
    def __enter__(self) -> ReportWriter:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:  # fmt: skip
        self.abort()

    def abort(self) -> None:
        """Remove the staging folder (no-op after :meth:`finish`)."""
        if self._staging is not None:
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None

    # -- trials
    def _unique_name(self, source: Path) -> str:
        """A page name for ``source`` not used yet in this report (case-insensitive)."""
        base = _slug(source.stem)
        name, k = base, 2
        while name.lower() in self._names:
            name, k = f"{base}-{k}", k + 1
        self._names.add(name.lower())
        return name

    def add(self, item: ReportItem) -> TrialEntry:
        """Write the page of one trial (or record its failure); returns its index entry."""
        if self._staging is None:
            raise RuntimeError("the report is already finished")
        source = Path(item.source)
        if item.analysis is None or item.error is not None:
            entry = TrialEntry(source, None, _one_line(item.error or "no analysis result"))
            self.entries.append(entry)
            return entry
        name = self._unique_name(source)
        files = f"{name}_files"
        try:
            entry = self._write_trial(item, item.analysis, source, name, files)
        except Exception as exc:
            if self.strict:
                raise
            shutil.rmtree(self._staging / files, ignore_errors=True)
            (self._staging / f"{name}.html").unlink(missing_ok=True)
            message = str(exc) if isinstance(exc, FuzzyGaitError) else f"{type(exc).__name__}: {exc}"
            entry = TrialEntry(source, None, _one_line(f"could not draw the report page: {message}"))
        finally:
            plt.close("all")
        self.entries.append(entry)
        return entry

    def _write_trial(self, item: ReportItem, analysis: TrialAnalysis, source: Path, name: str,
                     files: str) -> TrialEntry:  # fmt: skip
        """Figures and page of one trial into the staging folder; returns its entry."""
        assert self._staging is not None
        analysis = angles_only(analysis)
        data = TrialData.of(analysis)
        clinical = ClinicalData.of(analysis.run, data.cycles, parameters=item.parameters, normative=self.normative)
        self._alphas.update(float(a) for a in data.alphas)
        folder = self._staging / files
        folder.mkdir()
        title = f"{source.name}: joint angles" + (" with fuzzy α-bands" if len(data.alphas) else "")
        save_figure_files(cycle_figure(data, title + " (mean over gait cycles)", clinical), folder / "cycles", dpi=DPI)
        save_figure_files(time_series_figure(data, title + " (whole trial)", clinical), folder / "time_series",
                          dpi=DPI)  # fmt: skip
        kinetics = kinetics_page(analysis.run, data.cycles, self.normative, fuzzy_kinetics(analysis))
        if kinetics.cycles is not None and kinetics.cycles.any():
            self._kinetic_figures(kinetics.cycles, source, folder)
        elif clinical.has_kinetics():
            figure = stored_kinetics_figure(clinical, f"{source.name}: joint moments and powers stored in the file")
            save_figure_files(figure, folder / "kinetics", dpi=DPI)
        if clinical.profile is not None:
            figure = gait_profile_figure(clinical.profile, f"{source.name}: Movement Analysis Profile")
            save_figure_files(figure, folder / "profile", dpi=DPI)
        fuzzy = analysis.fuzzy
        if fuzzy is not None and has_source_bands(analysis.result):
            figure = source_figure(data, f"{source.name}: flexion with the bands of each error source")
            save_figure_files(figure, folder / "sources", dpi=DPI)
        table = delta_phi_table(analysis, data)
        allowable = allowable_summary(analysis.result)
        gps = clinical.profile.overall if clinical.profile is not None else None
        entry = TrialEntry.of(source, f"{name}.html", data, table, allowable, clinical.model_gaps(analysis.run.gaps),
                              gps)  # fmt: skip
        warnings = list(dict.fromkeys([*item.warnings, *analysis.run.warnings]))  # the run's may repeat the job's
        page = trial_page(analysis, data, entry, table, PageSource(source, files, item.session, warnings),
                          clinical=clinical, kinetics=kinetics)  # fmt: skip
        (self._staging / f"{name}.html").write_text(page, encoding="utf-8")
        return entry

    def _kinetic_figures(self, cycles: KineticCycles, source: Path, folder: Path) -> None:
        """The computed kinetics' figures of a trial (``kinetics``, ``grf``)."""
        title = f"{source.name}: joint moments and powers (Plug-in Gait, from the force plates)"
        save_figure_files(kinetics_figure(cycles, title, self.normative), folder / "kinetics", dpi=DPI)
        grf = grf_figure(cycles.cycles, f"{source.name}: ground reaction force over stance", self.normative)
        if grf is not None:
            save_figure_files(grf, folder / "grf", dpi=DPI)

    # -- the end
    def finish(self) -> Path:
        """Write ``index.html`` and move everything into ``out_dir``; returns the index."""
        if self._staging is None:
            raise RuntimeError("the report is already finished")
        staging = self._staging
        index_html = index_page(self.entries, sorted(self._alphas))
        (staging / "index.html").write_text(index_html, encoding="utf-8")
        try:
            if not self.out_dir.exists():
                os.rename(staging, self.out_dir)
            else:
                entries = sorted(staging.iterdir(), key=lambda p: p.name == "index.html")
                for path in entries:  # index.html last
                    replace_path(path, self.out_dir / path.name)
                staging.rmdir()
        except OSError as exc:
            raise FuzzyGaitError(f"{self.out_dir}: cannot write the report ({exc.strerror or exc})") from None
        self._staging = None
        return self.out_dir / "index.html"


def write_report(items: Iterable[ReportItem], out_dir: str | os.PathLike[str], *,
                 normative: NormativeData | None = None) -> Path:  # fmt: skip
    """Write the batch report: one page per trial and ``index.html``.

    Args:
        items: the trials, in index order; may be a generator (each analysis is drawn
            and can be freed before the next one is computed).  An item with an
            ``error`` (or no analysis) is listed as failed with that one-line error.
        out_dir: report folder; created, or updated in place (same-named pages are
            replaced).  Nothing is changed in it if writing fails.

    Returns:
        Path of ``index.html``.  A trial whose page cannot be drawn is listed as failed
        with the reason; the other trials are still written.  ``normative``: see
        :class:`ReportWriter`.
    """
    with ReportWriter(out_dir, normative=normative) as writer:
        for item in items:
            writer.add(item)
        return writer.finish()


def write_session_cycles(cycles: Mapping[str, np.ndarray], stem: Path, title: str) -> bool:
    """The session's gait-cycle figure
    (:func:`~fuzzygait.viz.report.session.session_cycles_figure`) as ``stem.png`` and
    ``stem.svg`` (into a staging folder: not atomic itself); False when there is nothing
    to draw (no file written)."""
    figure = session_cycles_figure(cycles, title)
    if figure is None:
        return False
    save_figure_files(figure, stem, dpi=SESSION_DPI)
    return True


def fuzzy_kinetics(analysis: TrialAnalysis) -> xr.Dataset | None:
    """The analysis' fuzzy kinetics (the kinetics group of its marker-error result), or None."""
    result = getattr(analysis, "result", None)
    return getattr(result, "kinetics", None)


def run_kinetic_cycles(run: ReportRun, cycles: Mapping[str, list[GaitCycle]],
                       fuzzy: xr.Dataset | None = None) -> KineticCycles | None:  # fmt: skip
    """The run's computed kinetics (``AnglesRun.kinetics``) cut into ``cycles`` (per
    side), with the α-bands of ``fuzzy`` (fuzzy kinetics, :func:`fuzzy_kinetics`) over
    the same cycles; None when it has none."""
    kinetics = getattr(run, "kinetics", None)  # the report's ReportRun protocol does not require it
    if kinetics is None:
        return None
    components = dataset_components(kinetics.data)
    out = KineticCycles.of(components, cycles)
    if fuzzy is None:
        return out
    frames = np.asarray(kinetics.data["frame"].to_numpy())
    return dataclasses.replace(out, fuzzy=kinetic_bands(fuzzy, components, cycles, frames))


def kinetics_page(run: ReportRun, cycles: Mapping[str, list[GaitCycle]], normative: NormativeData | None = None,
                  fuzzy: xr.Dataset | None = None) -> KineticsPage:  # fmt: skip
    """What the trial page's kinetics section shows: the computed kinetics, their contacts
    and notes; without them, why (the run's kinetics warning, else :data:`NO_PLATES` when
    the pipeline noted a file without force plates)."""
    kinetics = getattr(run, "kinetics", None)
    if kinetics is None:
        notes = of_kind(run.notes, FindingKind.KINETICS)
        warned = [n.message for n in notes if n.severity is Severity.WARNING]
        reason = warned[0] if warned else (NO_PLATES if notes else None)
        return KineticsPage(None, missing=reason)
    has_norm = normative is not None and any(normative.curve(f"L{j}Moment_X") is not None for j in KINETIC_ROWS)
    return KineticsPage(run_kinetic_cycles(run, cycles, fuzzy), tuple(kinetics.contacts),
                        tuple(dict.fromkeys(f.message for f in kinetics.findings if f.kind is not
                                            FindingKind.FORCE_PLATE_ASSIGNMENT)),
                        None, run.trial.first_frame, run.trial.rate, has_norm)  # fmt: skip


def write_session_kinetics(cycles: Mapping[str, np.ndarray], folder: Path, title: str,
                           normative: NormativeData | None = None) -> SessionKinetics:  # fmt: skip
    """The session's kinetics figures, mean ± SD over every counted cycle of its trials
    (``cycles``: sided component -> ``(n, 101)`` stacked, as ``data.npz`` holds them):
    ``kinetics`` and ``grf`` as PNG and SVG into ``folder`` (the page's
    ``session_files``; into a staging folder: not atomic itself)."""
    moments = grf = None
    figure = session_kinetics_figure(cycles, f"{title}: joint moments and powers, mean ± SD", normative)
    if figure is not None:
        save_figure_files(figure, folder / "kinetics", dpi=SESSION_DPI)
        moments = f"{folder.name}/kinetics"
    stance = grf_figure(cycles, f"{title}: ground reaction over stance, mean ± SD", normative, spread="sd")
    if stance is not None:
        save_figure_files(stance, folder / "grf", dpi=SESSION_DPI)
        grf = f"{folder.name}/grf"
    counted = {side: max((len(cycles.get(f"{side}{j}Moment_X", ())) for j in KINETIC_ROWS), default=0)
               for side in ("L", "R")}  # fmt: skip
    return SessionKinetics(moments, grf, counted)
