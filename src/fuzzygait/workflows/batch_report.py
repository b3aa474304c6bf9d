"""The clinicians' batch report (``fuzzygait report``): sessions found
(:mod:`~fuzzygait.workflows.session`), every trial a job
(:mod:`~fuzzygait.workflows.trial_job`) run through the project's
:class:`~fuzzygait.uncertainty.execution.Evaluator` (serial, a local Dask pool or a
scheduler), one summary page per session and one index across sessions.

Layout of the report folder::

    OUT/index.html                       the index across sessions
    OUT/<session>/index.html             the session summary (mean ± SD over every cycle)
    OUT/<session>/session_files/cycles.png|svg
    OUT/<session>/<trial>.html           one page per trial (+ <trial>.pdf with ``pdf``)
    OUT/<session>/<trial>_files/         its figures, data.npz (the page's numbers),
                                         entry.json (its index entry), job.json (its key)

Trials given as files (not in a session folder) are written flat into ``OUT`` as before
sessions, with ``OUT/session.html`` their summary (``OUT/index.html`` is the trial index
when there is no session folder).  A failing trial never stops the batch: it is listed
with its one-line error.  Re-running on the same ``OUT`` skips a trial whose
:func:`job_key` (its files' contents, the options, the code) is unchanged (``force``
recomputes); every file appears whole or not at all.  With a remote scheduler, the
workers write the trial pages: ``OUT`` and the inputs must be on a shared file system.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.options import Option
from fuzzygait.gait.spatiotemporal import pooled_parameters
from fuzzygait.io.atomic import atomic_output, remove_path, replace_path
from fuzzygait.uncertainty.execution import Evaluator
from fuzzygait.viz.report import TrialEntry
from fuzzygait.viz.report.pages import index_page
from fuzzygait.viz.report.session import (
    SessionSummary,
    SummaryTrial,
    cross_session_index,
    cycles_used,
    session_page,
)
from fuzzygait.workflows.progress import SILENT, StageProgress
from fuzzygait.workflows.report_entries import ENTRY_SCHEMA, EntryFormatError, read_entry
from fuzzygait.workflows.report_folder import write_session_cycles, write_session_kinetics
from fuzzygait.workflows.report_request import BatchReportRequest
from fuzzygait.workflows.session import Session, find_sessions
from fuzzygait.workflows.trial_job import TrialJob, TrialOutcome, finished_outcome, run_trial_job

__all__ = ["BatchReport", "BatchReportRequest", "job_key", "remove_stale_staging", "write_batch_report"]

_CODE_DIGEST: str | None = None
#: The files of the package that make up the program (not caches or built libraries).
_CODE_SUFFIXES = frozenset({".py", ".toml", ".c", ".json", ".csv", ".txt"})


def code_digest() -> str:
    """SHA-256 of fuzzygait's source and data files (a changed program recomputes every
    trial)."""
    global _CODE_DIGEST
    if _CODE_DIGEST is None:
        root = Path(__file__).resolve().parents[1]
        digest = hashlib.sha256()
        paths = [p for p in root.rglob("*") if p.suffix in _CODE_SUFFIXES and "__pycache__" not in p.parts]
        for path in sorted(paths):
            digest.update(str(path.relative_to(root)).encode())
            digest.update(path.read_bytes())
        _CODE_DIGEST = digest.hexdigest()
    return _CODE_DIGEST


def _file_digest(path: Path | None) -> str:
    if path is None:
        return "-"
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def job_key(job: TrialJob, normative: Path | None = None) -> str:
    """The content hash of a trial job: its trial, static and subject files' (and the
    normative file's) contents, every option (the session named on its page too), the
    code and the version of ``entry.json``; not the paths, nor where or with how many
    workers it runs."""
    settings = None if job.settings is None else replace(job.settings, workers=None)
    options = (job.name, job.marker_diameter, job.flat_foot, job.preprocessing, job.model, settings, job.warnings,
               job.pdf, job.session, ENTRY_SCHEMA)  # fmt: skip
    digest = hashlib.sha256(code_digest().encode())
    for path in (job.source, job.static, job.subject_file, normative):
        digest.update(_file_digest(path).encode())
    digest.update(repr(options).encode())
    return digest.hexdigest()


@dataclass
class BatchReport:
    """The written report: its index, the sessions and every trial's outcome."""

    index: Path
    sessions: list[SessionSummary]
    outcomes: list[TrialOutcome]
    session_pages: list[Path] = field(default_factory=list)

    @property
    def entries(self) -> list[TrialEntry]:
        """The index entry of every trial."""
        return [o.entry for o in self.outcomes]

    @property
    def n_ok(self) -> int:
        """Trials with a page."""
        return sum(o.ok for o in self.outcomes)

    @property
    def n_failed(self) -> int:
        """Trials listed as failed."""
        return len(self.outcomes) - self.n_ok

    @property
    def n_skipped(self) -> int:
        """Trials reused from an earlier run (inputs and options unchanged)."""
        return sum(o.skipped for o in self.outcomes)


def remove_stale_staging(folder: Path) -> list[str]:
    """Remove what a killed or interrupted batch left in a report folder: its hidden
    staging folders and temporary files (``.<name>.*.tmp``, ``.*.tmp-<pid>``, the PDF
    printer's ``.<name>.print.html`` / ``.<name>.chromium``, and in a trial's
    ``<name>_files`` folder its ``.job.json.tmp-<pid>``), and a page folder set aside
    while being replaced (``.<name>.old-<pid>``: put back when the new one is missing,
    else removed).  One batch per report folder at a time: a concurrent batch's staging
    would be removed too."""
    removed: list[str] = []
    if not folder.is_dir():
        return removed
    for path in folder.iterdir():
        name = path.name
        if name.startswith(".") and (".tmp" in name or name.endswith((".print.html", ".chromium"))):
            remove_path(path)
            removed.append(name)
        elif name.startswith(".") and (aside := re.fullmatch(r"\.(.+)\.old-\d+", name)):
            target = folder / aside.group(1)
            if target.exists():
                remove_path(path)
            else:
                os.rename(path, target)
            removed.append(name)
        elif name.endswith("_files") and path.is_dir():
            for tmp in path.glob(".*.tmp-*"):
                remove_path(tmp)
                removed.append(f"{name}/{tmp.name}")
    return removed


def _page_name(path: Path) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", path.stem).strip("._-") or "trial"


def _jobs(sessions: Sequence[Session], out_dir: Path, template: TrialJob,
          normative: Path | None) -> tuple[list[list[TrialJob]], list[TrialOutcome]]:  # fmt: skip
    """Per session its jobs, and the outcomes of trials failing before they start
    (duplicate page names)."""
    per_session, early = [], []
    for session in sessions:
        folder = (out_dir / session.output) if session.output else out_dir
        names: set[str] = {"index", "session"}
        jobs = []
        for trial in session.trials:
            name = _page_name(trial.path)
            job = replace(template, source=trial.path.resolve(), out_dir=folder.resolve(), name=name,
                          static=trial.static.resolve() if trial.static else None,
                          subject_file=trial.subject_file.resolve() if trial.subject_file else None,
                          warnings=trial.warnings,
                          session=session.name if session.folder is not None else None)  # fmt: skip
            if name.lower() in names:
                early.append(TrialOutcome(trial.path, name, TrialEntry(trial.path, None, f"{trial.path}: its page name "
                             f"{name}.html is taken by another trial of the session; rename the file")))  # fmt: skip
                continue
            names.add(name.lower())
            jobs.append(replace(job, key=job_key(job, normative)))
        per_session.append(jobs)
    return per_session, early


def _run(jobs: list[TrialJob], workers: int, scheduler: str | None, trials: StageProgress) -> list[TrialOutcome]:
    """Run the jobs: in this process (one worker, or a single trial: its analysis then uses
    the settings' workers), else one trial per worker with a serial analysis inside."""
    trials.stage("trials", len(jobs))
    if not jobs:
        return []
    if scheduler is None and (workers == 1 or len(jobs) == 1):
        outcomes = []
        for done, job in enumerate(jobs, 1):
            outcomes.append(run_trial_job(job))
            trials.update(done, len(jobs))
        return outcomes
    serial = [replace(j, settings=None if j.settings is None else replace(j.settings, workers=1)) for j in jobs]
    with Evaluator(workers=workers, scheduler=scheduler) as evaluator:
        return evaluator.map(run_trial_job, serial, progress=lambda done, total: trials.update(done, total))


def _stacked_cycles(outcomes: Sequence[TrialOutcome], folder: Path) -> dict[str, np.ndarray]:
    """Every gait cycle of the session's trials per component, from their ``data.npz``."""
    stacks = _stacked(outcomes, folder, "cycles/")
    width = {k: max(a.shape[1] for a in v) for k, v in stacks.items()}
    return {k: np.vstack([a for a in v if a.shape[1] == width[k]]) for k, v in stacks.items()}


def _stacked_parameters(outcomes: Sequence[TrialOutcome], folder: Path) -> dict[str, np.ndarray]:
    """Every complete gait cycle's spatio-temporal parameters per side, from the trials'
    ``data.npz`` (pages written before these were stored contribute none)."""
    return {code: np.vstack(rows) for code, rows in _stacked(outcomes, folder, "spatiotemporal/").items()}


def _stacked(outcomes: Sequence[TrialOutcome], folder: Path, prefix: str) -> dict[str, list[np.ndarray]]:
    """The page-data arrays under ``prefix`` of every successful trial, per key (the
    prefix removed), in trial order."""
    stacks: dict[str, list[np.ndarray]] = {}
    for outcome in (o for o in outcomes if o.ok):
        for key, array in load_page_data(folder, outcome.name).items():
            if key.startswith(prefix):
                stacks.setdefault(key.removeprefix(prefix), []).append(array)
    return stacks


def _facts(session: Session) -> list[tuple[str, str]]:
    statics = "; ".join(f"{s.path.name} (found by {s.rule}: {s.detail})" for s in session.statics) or "none found"
    used = sorted({t.static.name for t in session.trials if t.static is not None})
    subjects = sorted({t.subject_file.name for t in session.trials if t.subject_file is not None})
    given = ", ".join(used) or f"none ({Option.STATIC})"
    facts = [("Static trial", statics if session.folder is not None else given),
             ("Subject file", ", ".join(subjects) or "none: the trials' PROCESSING groups")]  # fmt: skip
    facts.append(("Folder", str(session.folder) if session.folder is not None else "files given directly"))
    names = sorted({t.subject for t in session.trials if t.subject})
    if names:
        facts.append(("Subject (C3D)", ", ".join(names)))
    return facts


def _write_session(session: Session, outcomes: Sequence[TrialOutcome], out_dir: Path, flat: bool,
                   index_href: str | None, pdf: bool) -> tuple[SessionSummary, Path]:  # fmt: skip
    """The session's summary page (atomic: figure folder, then page)."""
    folder = (out_dir / session.output) if session.output else out_dir
    folder.mkdir(parents=True, exist_ok=True)
    page_name = "session.html" if flat else "index.html"
    href_prefix = f"{session.output}/" if session.output else ""
    trials = [SummaryTrial(o.source.name, f"{o.name}.html" if o.ok else None, o.entry.error, dict(o.entry.cycles),
                           tuple(dict.fromkeys((*o.warnings, *o.entry.data_warnings))), o.seconds, o.skipped,
                           f"{o.name}.pdf" if pdf and o.ok else None)
              for o in outcomes]  # fmt: skip
    summary = SessionSummary(session.name, str(session.folder or "files given directly"), href_prefix + page_name,
                             _facts(session), trials, list(session.notes),
                             (page_name.removesuffix(".html") + ".pdf") if pdf else None)  # fmt: skip
    staging = Path(tempfile.mkdtemp(prefix=".session.", suffix=".tmp", dir=folder))
    try:
        figures = staging / "session_files"
        figures.mkdir()
        title = f"Session {session.name}: joint angles, mean ± SD over all gait cycles"
        cycles = _stacked_cycles(outcomes, folder)
        drawn = write_session_cycles(cycles, figures / "cycles", title)
        parameters = pooled_parameters(session.name, _stacked_parameters(outcomes, folder), "the trials' events")
        kinetic = {k: np.vstack(v) for k, v in _stacked(outcomes, folder, "kinetics/").items()}
        kinetics = write_session_kinetics(kinetic, figures, f"Session {session.name}")
        html = session_page(summary, "session_files/cycles" if drawn else None, index_href, cycles_used(cycles),
                            parameters, kinetics)  # fmt: skip
        (staging / page_name).write_text(html, encoding="utf-8")
        if pdf:
            from fuzzygait.workflows.pdf import html_to_pdf

            html_to_pdf(staging / page_name, staging / page_name.replace(".html", ".pdf"))
        for path in sorted(staging.iterdir(), key=lambda p: p.suffix == ".html"):  # the page last
            replace_path(path, folder / path.name)  # the old one goes only once the new one is in place
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return summary, folder / page_name


def _clean_up(out: Path, sessions: Sequence[Session], created: bool) -> None:
    """After a batch stopped early (an interrupt, an unreachable scheduler): remove the
    staging its trials left (a worker stopped mid-trial cannot), and a report folder
    this batch created that is left empty; the pages finished before are kept."""
    for session in sessions:
        folder = (out / session.output) if session.output else out
        remove_stale_staging(folder)
        if created and folder != out and folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()
    if created and out.is_dir() and not any(out.iterdir()):
        out.rmdir()  # no empty report folder left behind


def write_batch_report(request: BatchReportRequest, *, trials: StageProgress = SILENT,
                       on_failure: Callable[[Path, str], None] | None = None) -> BatchReport:  # fmt: skip
    """Find the sessions of ``request.inputs``, report every trial and write the session
    pages and the index into ``request.out_dir`` (see the module docstring and
    :class:`~fuzzygait.workflows.report_request.BatchReportRequest`).

    Args:
        request: what to report and how.
        trials: progress over the trials computed.
        on_failure: called as ``on_failure(path, error)`` for every failed trial.

    Raises:
        FuzzyGaitError: ``out_dir`` is a file or cannot be created, an input is missing
            or holds no C3D file (nothing written).
    """
    out = request.out_dir
    if out.exists() and not out.is_dir():
        raise FuzzyGaitError(f"{out}: {Option.OUT} must be a folder, not a file")
    sessions = find_sessions(request.inputs, request.static, request.subject_file)
    template = _template(request)
    created = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise FuzzyGaitError(f"{out}: cannot create the report folder ({exc.strerror})") from None
    for session in sessions:
        remove_stale_staging((out / session.output) if session.output else out)
    per_session, early = _jobs(sessions, out, template, request.normative)
    jobs = [job for session_jobs in per_session for job in session_jobs]
    reused = {job.key: finished_outcome(job) for job in jobs} if not request.force else {}
    todo = [job for job in jobs if reused.get(job.key) is None]
    try:
        computed = dict(zip([j.key for j in todo], _run(todo, request.workers, request.scheduler, trials), strict=True))
    except BaseException:  # interrupted, or the pool failed: its processes are gone by now
        _clean_up(out, sessions, created)
        raise
    by_source: dict[Path, TrialOutcome] = {o.source: o for o in early}
    for job in jobs:
        outcome = reused.get(job.key) or computed[job.key]
        by_source[job.source] = outcome
        if not outcome.ok and on_failure is not None:
            on_failure(job.source, outcome.entry.error or "")
    return _write_pages(sessions, by_source, out, template)


def _template(request: BatchReportRequest) -> TrialJob:
    """The job every trial's is made from: the request's options (paths left empty)."""
    extra: dict[str, Any] = {}
    if request.normative is not None:
        from fuzzygait.gait.normative import read_normative

        extra["normative"] = read_normative(request.normative)
    return TrialJob(Path(), Path(), "", "", marker_diameter=request.marker_diameter, flat_foot=request.flat_foot,
                    preprocessing=request.preprocessing, model=request.model, settings=request.analysis(),
                    pdf=request.pdf, strict=request.strict, **extra)  # fmt: skip


def _write_pages(sessions: Sequence[Session], by_source: dict[Path, TrialOutcome], out: Path,
                 template: TrialJob) -> BatchReport:  # fmt: skip
    """Every session's summary page, then the index (the trial index when every trial was
    given as a file, else the index across sessions)."""
    flat_only = all(s.folder is None for s in sessions)
    summaries, pages, outcomes = [], [], []
    for session in sessions:
        found = [by_source.get(t.path.resolve()) or by_source[t.path] for t in session.trials]
        outcomes += found
        summary, page = _write_session(session, found, out, session.folder is None, None if flat_only else
                                       ("../index.html" if session.output else "index.html"), template.pdf)  # fmt: skip
        summaries.append(summary)
        pages.append(page)
    index = out / "index.html"
    if flat_only:
        alphas = [] if template.settings is None else [a for a in template.settings.alphas if a < 1]
        html = index_page([o.entry for o in outcomes], sorted(alphas))
    else:
        html = cross_session_index(summaries)
    with atomic_output(index) as tmp:
        tmp.write_text(html, encoding="utf-8")
    return BatchReport(index, summaries, outcomes, pages)


def load_page_data(folder: Path, name: str) -> dict[str, np.ndarray]:
    """The numbers of a written trial page (``<name>_files/data.npz``), for checks."""
    with np.load(folder / f"{name}_files" / "data.npz", allow_pickle=False) as data:
        return {key: np.asarray(data[key]) for key in data.files}


def load_entry(folder: Path, name: str) -> TrialEntry:
    """The index entry of a written trial page (``<name>_files/entry.json``).

    Raises:
        FuzzyGaitError: it is missing or not an entry of this version.
    """
    path = folder / f"{name}_files" / "entry.json"
    try:
        return read_entry(path)
    except (OSError, EntryFormatError) as exc:
        raise FuzzyGaitError(f"{path}: not a report entry of this version ({exc})") from None
