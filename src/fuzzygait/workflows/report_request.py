"""What the clinicians' batch report is asked for (:class:`BatchReportRequest`): its
inputs, its report folder, the joint-angle options shared by every trial, the
marker-error analysis and how the trials run.  Checked when made: an impossible value,
or a static trial, subject file or normative file that is not there, is refused in one
line naming it, before any trial is read."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.options import Option
from fuzzygait.core.paths import check_c3d_input, check_subject_input
from fuzzygait.workflows.angles import DEFAULT_PREPROCESSING, Preprocessing
from fuzzygait.workflows.marker_uncertainty import DEFAULT_SETTINGS, MarkerErrorSettings
from fuzzygait.workflows.trial_job import mode_settings

__all__ = ["BatchReportRequest"]


@dataclass(frozen=True)
class BatchReportRequest:
    """One batch report (:func:`~fuzzygait.workflows.batch_report.write_batch_report`).

    Attributes:
        inputs: session folders (or folders of session folders) and walking-trial C3D
            files (at least one; kept as a tuple).
        out_dir: the report folder (created; an existing file is refused when the report
            is written).
        static: the static trial of the files given directly; in session folders it
            overrides the one found (None: found, or none).
        subject_file: the subject file (.toml, .vsk, .mp, session.xml), as ``static``.
        marker_diameter: marker diameter in mm (finite, > 0) in place of the subject
            parameters' (None: theirs), the same for every trial.
        flat_foot: static calibration with the flat-foot option (None: the subject
            file's own setting, else off), as for
            :func:`~fuzzygait.workflows.angles.run_angles`.
        preprocessing: gap filling and low-pass filter of every trial.
        settings: the marker-error analysis of ``uncertainty="full"`` (``"fast"`` keeps
            its error model, sources and method).
        uncertainty: ``"none"`` the angles only, ``"fast"`` the α = 0 and 0.5 bands of
            hip, knee and ankle flexion, ``"full"`` the analysis of ``settings``
            (:func:`~fuzzygait.workflows.trial_job.mode_settings`).
        model: a model version or ``"auto"`` (as for
            :func:`~fuzzygait.workflows.angles.run_angles`).
        pdf: also a PDF (A4) of every trial page and session page.
        workers: processes for the trials (≥ 1; a local Dask pool, 1: in this process).
        scheduler: address of a running Dask scheduler (``tcp://host:8786``) instead of
            the local pool (None: local).
        force: recompute trials whose inputs and options are unchanged since the last run
            on ``out_dir`` (they are reused otherwise).
        normative: reference curves for the pages (a normative CSV: mean and SD per % of
            the gait cycle), or None.
        strict: re-raise a trial's error instead of listing it as failed (debugging).
    """

    inputs: Sequence[Path]
    out_dir: Path
    static: Path | None = None
    subject_file: Path | None = None
    marker_diameter: float | None = None
    flat_foot: bool | None = None
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING
    settings: MarkerErrorSettings = DEFAULT_SETTINGS
    uncertainty: str = "full"
    model: str = "auto"
    pdf: bool = False
    workers: int = 1
    scheduler: str | None = None
    force: bool = False
    normative: Path | None = None
    strict: bool = False

    def __post_init__(self) -> None:
        if isinstance(self.inputs, str | os.PathLike) or not self.inputs:
            raise ParameterError(f"inputs must be a non-empty list of session folders or C3D files; "
                                 f"got {self.inputs!r}")  # fmt: skip
        object.__setattr__(self, "inputs", tuple(Path(p) for p in self.inputs))
        object.__setattr__(self, "out_dir", Path(self.out_dir))
        for name in ("static", "subject_file", "normative"):
            if (value := getattr(self, name)) is not None:
                object.__setattr__(self, name, Path(value))
        if self.static is not None:
            check_c3d_input(self.static)
        if self.subject_file is not None:
            check_subject_input(self.subject_file)
        if self.normative is not None and not self.normative.is_file():
            raise ParameterError(f"{self.normative}: no such normative file; check the path ({Option.NORMATIVE})")
        diameter = self.marker_diameter
        if diameter is not None and not (isinstance(diameter, int | float) and not isinstance(diameter, bool)
                                         and math.isfinite(diameter) and diameter > 0):  # fmt: skip
            raise ParameterError(f"marker_diameter must be a finite number of mm > 0 or None; got {diameter!r}")
        if isinstance(self.workers, bool) or not isinstance(self.workers, int) or self.workers < 1:
            raise ParameterError(f"workers must be a whole number ≥ 1; got {self.workers!r}")
        if not isinstance(self.preprocessing, Preprocessing):
            raise ParameterError(f"preprocessing must be a Preprocessing; got {type(self.preprocessing).__name__}")
        if not isinstance(self.settings, MarkerErrorSettings):
            raise ParameterError(f"settings must be MarkerErrorSettings; got {type(self.settings).__name__}")
        self.analysis()  # a bad uncertainty mode: one line naming the choices
        self._check_model()

    def _check_model(self) -> None:
        from fuzzygait.kinematics.versions import MODEL_CHOICES, model_version

        try:
            if not isinstance(self.model, str):
                raise ParameterError(self.model)
            if self.model != "auto":
                model_version(self.model)  # also "2.3", "CGM2.3"
        except ParameterError:
            raise ParameterError(f"model must be one of {', '.join(MODEL_CHOICES)}; got {self.model!r}") from None

    def analysis(self) -> MarkerErrorSettings | None:
        """The marker-error analysis of every trial (None: angles only,
        ``uncertainty="none"``)."""
        return mode_settings(self.uncertainty, self.settings)
