"""One trial of the batch report as a self-contained job: what runs on a worker of the
batch's :class:`~fuzzygait.uncertainty.execution.Evaluator`.

:func:`run_trial_job` reads and processes the trial, runs the marker-error analysis the
job's uncertainty mode asks for (:data:`UNCERTAINTY_MODES`), draws its page, writes the
page's data (``<name>_files/data.npz``), its index entry (``<name>_files/entry.json``,
:mod:`~fuzzygait.workflows.report_entries`) and, with ``pdf``, its PDF, all in a staging
folder beside the session's pages, then moves them into place and writes
``<name>_files/job.json`` (the job's key) last.  A trial killed half-way leaves no file
in place and no ``job.json``, so the next run recomputes it; a trial whose ``job.json``
holds the key of an unchanged job is skipped (:func:`finished_outcome`).

It never raises for a bad trial: the outcome carries the one-line error instead.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.core.options import Option
from fuzzygait.gait.cycles import gait_cycles
from fuzzygait.gait.normative import NormativeData
from fuzzygait.gait.spatiotemporal import NAMES, spatiotemporal_parameters
from fuzzygait.io.atomic import replace_path
from fuzzygait.viz.report import TrialEntry
from fuzzygait.workflows.angles import DEFAULT_PREPROCESSING, AnglesRun, Preprocessing, run_angles
from fuzzygait.workflows.marker_uncertainty import (
    DEFAULT_SETTINGS,
    MarkerErrorAnalysis,
    MarkerErrorSettings,
    analyse_run,
)
from fuzzygait.workflows.report_entries import EntryFormatError, read_entry, write_entry
from fuzzygait.workflows.report_folder import ReportItem, ReportWriter, fuzzy_kinetics, run_kinetic_cycles

__all__ = ["UNCERTAINTY_MODES", "TrialJob", "TrialOutcome", "finished_outcome", "mode_settings", "run_trial_job"]

#: ``--uncertainty``: ``none`` the angles only (seconds per trial); ``fast`` the α = 0
#: and 0.5 bands of hip, knee and ankle flexion (no allowable-error refinement, no
#: per-source bands); ``full`` the analysis the settings describe (by default every
#: angle, four α-levels, the allowable marker error and the per-source bands).
UNCERTAINTY_MODES = ("none", "fast", "full")
FAST_ANGLES = tuple(f"{side}{joint}Angles_X" for side in "LR" for joint in ("Hip", "Knee", "Ankle"))
FAST_ALPHAS = (0.0, 0.5, 1.0)


def mode_settings(mode: str, settings: MarkerErrorSettings = DEFAULT_SETTINGS) -> MarkerErrorSettings | None:
    """The marker-error settings of an uncertainty mode (None for ``"none"``): ``fast``
    keeps the error model, sources and method of ``settings``."""
    if mode not in UNCERTAINTY_MODES:
        raise ParameterError(f"{Option.UNCERTAINTY} {mode!r}: choose one of {', '.join(UNCERTAINTY_MODES)}")
    if mode == "none":
        return None
    if mode == "fast":
        return replace(settings, alphas=FAST_ALPHAS, angles=FAST_ANGLES, tolerance=None, allowable_angles=None,
                       per_source=False)  # fmt: skip
    return settings


def angles_only(run: AnglesRun) -> MarkerErrorAnalysis:
    """A run without marker-error analysis in the report's form: no analysed component
    (the page shows the angles and cycles without bands)."""
    frames = np.asarray(run.trial.frames)
    n = frames.size
    fuzzy = xr.Dataset(
        {"hull": (("component", "alpha", "bound", "frame"), np.zeros((0, 1, 2, n))),
         "undetermined": (("component", "alpha", "frame"), np.zeros((0, 1, n), dtype=bool))},
        coords={"component": np.array([], dtype=str), "alpha": [1.0], "bound": ["lower", "upper"], "frame": frames},
        attrs={"trial": Path(run.trial.name).name, "model": run.model},
    )  # fmt: skip
    skipped = Finding(FindingKind.UNCERTAINTY,
                      f"uncertainty: not computed ({Option.UNCERTAINTY} none: the angles only)")  # fmt: skip
    notes = [*run.notes, skipped]
    return MarkerErrorAnalysis(run, fuzzy, pd.DataFrame(), notes)


@dataclass(frozen=True)
class TrialJob:
    """Everything one trial of the batch needs (picklable; paths absolute).

    Attributes:
        source: the walking trial.
        out_dir: the folder of its session's pages.
        name: its page name (``<name>.html``, ``<name>_files/``).
        key: the content hash of its inputs and options (:func:`~fuzzygait.workflows.
            batch_report.job_key`).
        static, subject_file, marker_diameter, flat_foot, preprocessing, model: as for
            :func:`~fuzzygait.workflows.angles.run_angles`.
        settings: the marker-error analysis (None: angles only).
        warnings: shown on the page (e.g. a subject mismatch).
        pdf: also ``<name>.pdf``.
        strict: re-raise errors (``--debug``).
        normative: reference curves for the page
            (:func:`fuzzygait.gait.normative.read_normative`), or None.
        session: the session's name, for the page's header.
    """

    source: Path
    out_dir: Path
    name: str
    key: str
    static: Path | None = None
    subject_file: Path | None = None
    marker_diameter: float | None = None
    flat_foot: bool | None = None
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING
    model: str = "auto"
    settings: MarkerErrorSettings | None = None
    warnings: tuple[str, ...] = ()
    pdf: bool = False
    strict: bool = False
    normative: NormativeData | None = None
    session: str | None = None


@dataclass
class TrialOutcome:
    """What the batch keeps of one trial: its index entry (or one-line error), its
    warnings, the seconds it took (0 when skipped) and whether it was skipped."""

    source: Path
    name: str
    entry: TrialEntry
    warnings: tuple[str, ...] = ()
    seconds: float = 0.0
    skipped: bool = False
    files: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """Whether the trial has a page."""
        return self.entry.ok


def _one_line(text: str) -> str:
    lines = [line.strip() for line in str(text).splitlines() if line.strip()]
    return " ".join(lines) if lines else "unknown error"


def _internal_error(exc: Exception) -> str:
    """The one line of a bug met while reporting a trial."""
    return f"internal error {type(exc).__name__}: {exc} (rerun with {Option.DEBUG} and report it)"


def _failed(job: TrialJob, error: str, start: float) -> TrialOutcome:
    return TrialOutcome(job.source, job.name, TrialEntry(job.source, None, _one_line(error)), job.warnings,
                        time.perf_counter() - start)  # fmt: skip


def _analyse(job: TrialJob) -> MarkerErrorAnalysis:
    run = run_angles(job.source, static=job.static, subject_file=job.subject_file,
                     marker_diameter=job.marker_diameter, flat_foot=job.flat_foot,
                     preprocessing=job.preprocessing, model=job.model)  # fmt: skip
    return angles_only(run) if job.settings is None else analyse_run(run, job.settings)


def page_data(analysis: MarkerErrorAnalysis) -> dict[str, np.ndarray]:
    """The numbers a trial's page is drawn from (``data.npz``): ``angle/<name>``
    (n_frames, 3) deg, ``cycles/<component>`` (n_cycles, n_points) deg per gait-cycle
    percent (the component's side's cycles), ``spatiotemporal/<L|R>`` (n_complete_cycles,
    11) -- each complete cycle's spatio-temporal parameters in
    :data:`~fuzzygait.gait.spatiotemporal.NAMES` order and units (absent without one) --
    ``kinetics/<component>`` (n_cycles, 101) -- the computed kinetics of each cycle whose
    stance was on a force plate (``LKneeMoment_X`` N·m/kg, ``LKneePower_Z`` W/kg over the
    gait cycle, ``LNormalisedGRF_Z`` % body weight over stance;
    :func:`~fuzzygait.workflows.report_folder.run_kinetic_cycles`), with fuzzy kinetics
    ``kinetic_band/<component>`` (alpha, 2, 101) the bands the kinetics figure draws and
    their ``kinetic_alpha`` levels -- and, when analysed,
    ``hull`` (component, alpha, bound, frame) deg with its ``alpha``
    levels and ``component`` names."""
    run = analysis.run
    angles = sorted(run.result.angles.items())
    data: dict[str, np.ndarray] = {f"angle/{n}": np.asarray(v, dtype=float) for n, v in angles}
    table = run.cycle_table()
    for component, rows in table.groupby("angle", sort=True):
        wide = rows.pivot_table(index="cycle", columns="percent", values="value", sort=True)
        data[f"cycles/{component}"] = wide.to_numpy(dtype=float)
    try:
        parameters = spatiotemporal_parameters(run.trial, run.events)
    except FuzzyGaitError:  # no complete cycle: the page says why; nothing to summarise
        parameters = None
    for code, side in (parameters.sides.items() if parameters is not None else ()):
        if side.complete_cycles:
            data[f"spatiotemporal/{code}"] = np.array([[c.values[n] for n in NAMES] for c in side.complete_cycles])
    kinetic = run_kinetic_cycles(run, {side: gait_cycles(run.trial, run.events, side) for side in "LR"},
                                 fuzzy_kinetics(analysis))  # fmt: skip
    for name, stack in (kinetic.cycles.items() if kinetic is not None else ()):
        data[f"kinetics/{name}"] = stack
    if kinetic is not None and kinetic.fuzzy is not None:  # the figure's fuzzy kinetic bands
        data["kinetic_alpha"] = kinetic.fuzzy.alphas
        data.update({f"kinetic_band/{name}": band for name, band in kinetic.fuzzy.bands.items()})
    fuzzy = analysis.fuzzy
    if fuzzy.sizes.get("component", 0):
        hull = fuzzy["hull"].transpose("component", "alpha", "bound", "frame")
        data["hull"] = np.asarray(hull.values, dtype=float)
        data["alpha"] = np.asarray(fuzzy["alpha"].values, dtype=float)
        data["component"] = np.asarray([str(c) for c in fuzzy["component"].values])
    return data


def _move_into_place(staging: Path, job: TrialJob) -> list[str]:
    """Move the staged page, its folder and PDF onto the session's (the old ``job.json``
    removed first, so an interrupted move is recomputed next time)."""
    files = job.out_dir / f"{job.name}_files"
    (files / "job.json").unlink(missing_ok=True)
    moved = []
    for path in sorted(staging.iterdir(), key=lambda p: (p.suffix != "", p.suffix == ".html")):
        replace_path(path, job.out_dir / path.name)
        moved.append(path.name)
    return moved


def _write_json(path: Path, content: dict[str, object]) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        tmp.write_text(json.dumps(content, indent=1), encoding="utf-8")
        os.replace(tmp, path)
    finally:  # interrupted before the rename: no temporary file left
        tmp.unlink(missing_ok=True)


def run_trial_job(job: TrialJob) -> TrialOutcome:
    """Compute and write one trial (see the module docstring); never raises for a bad
    trial (unless ``job.strict``)."""
    start = time.perf_counter()
    try:
        analysis = _analyse(job)
    except FuzzyGaitError as exc:
        if job.strict:
            raise
        return _failed(job, str(exc), start)
    except Exception as exc:  # a bug: listed as failed, the batch goes on
        if job.strict:
            raise
        return _failed(job, _internal_error(exc), start)
    job.out_dir.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{job.name}.", suffix=".tmp", dir=job.out_dir))
    try:
        with ReportWriter(staging / "w", strict=job.strict, normative=job.normative) as writer:
            entry = writer.add(ReportItem(job.source, analysis, session=job.session, warnings=list(job.warnings)))
            writer.finish()
        if not entry.ok:
            return _failed(job, entry.error or "could not draw the report page", start)
        built = staging / "w"
        (built / "index.html").unlink()
        if entry.page != f"{job.name}.html":
            return _failed(job, f"page name {entry.page} is not {job.name}.html (rename the file)", start)
        np.savez_compressed(built / f"{job.name}_files" / "data.npz", **page_data(analysis))  # type: ignore[arg-type]
        write_entry(built / f"{job.name}_files" / "entry.json", entry, job.key)
        if job.pdf:
            from fuzzygait.workflows.pdf import html_to_pdf

            html_to_pdf(built / f"{job.name}.html", built / f"{job.name}.pdf")
        moved = _move_into_place(built, job)
        seconds = time.perf_counter() - start
        _write_json(job.out_dir / f"{job.name}_files" / "job.json",
                    {"key": job.key, "source": str(job.source), "seconds": round(seconds, 3)})  # fmt: skip
    except FuzzyGaitError as exc:
        if job.strict:
            raise
        return _failed(job, str(exc), start)
    except OSError as exc:
        if job.strict:
            raise
        return _failed(job, f"cannot write the page into {job.out_dir} ({exc.strerror or exc})", start)
    except Exception as exc:  # a bug while writing: listed as failed, the batch goes on
        if job.strict:
            raise
        return _failed(job, _internal_error(exc), start)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return TrialOutcome(job.source, job.name, entry, job.warnings, seconds, files=moved)


def finished_outcome(job: TrialJob) -> TrialOutcome | None:
    """The outcome of an earlier run of the same job (same key in ``job.json`` and
    ``entry.json``, every file in place, ``entry.json`` of this schema with every field
    of its type: :func:`~fuzzygait.workflows.report_entries.read_entry`), or None: it must
    be computed.  An ``entry.pkl`` of an earlier version is never opened."""
    files = job.out_dir / f"{job.name}_files"
    try:
        stored = json.loads((files / "job.json").read_text(encoding="utf-8"))
        if not isinstance(stored, dict) or stored.get("key") != job.key:
            return None
        if not (job.out_dir / f"{job.name}.html").is_file() or not (files / "data.npz").is_file():
            return None
        if job.pdf and not (job.out_dir / f"{job.name}.pdf").is_file():
            return None
        entry = read_entry(files / "entry.json", job.key)
    except (OSError, EntryFormatError, ValueError, RecursionError):  # ValueError: job.json not JSON
        return None
    if not entry.ok:
        return None
    entry.source = job.source
    return TrialOutcome(job.source, job.name, entry, job.warnings, 0.0, skipped=True)
