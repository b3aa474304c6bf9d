"""The joint-angle pipeline shared by the CLI, the batch report and notebooks.

read C3D -> fill gaps -> low-pass -> subject parameters (file, or PROCESSING group) ->
static calibration (optional; or the subject file's cluster calibration) -> a CGM
version's lower body -> gait events -> cycles.  Every file written names the model
version (:class:`AngleOutputs`).
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from fuzzygait import __version__
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.options import Option
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.gait.cycles import mean_sd_table, normalised_angle_table
from fuzzygait.gait.events import SOURCE_FILE, trial_gait_events
from fuzzygait.io import Event, Trial, read_c3d, write_c3d
from fuzzygait.io.tables import write_table
from fuzzygait.kinematics import (
    ALL_ANGLE_NAMES,
    ANGLE_NAMES,
    FOREFOOT_ANGLE_NAMES,
    CGMResult,
    compute_lower_body,
)
from fuzzygait.kinematics.calibration_file import StoredCalibration, read_stored_calibration
from fuzzygait.kinematics.clusters import ClusterCalibration
from fuzzygait.kinematics.marker_names import canonical_labels
from fuzzygait.kinematics.versions import model_version, supported_version
from fuzzygait.mocap.gaps import Gap
from fuzzygait.mocap.sanity import check_trial
from fuzzygait.workflows.crosscheck import CrossCheck, check_run
from fuzzygait.workflows.kinetics import LONGEST_KINETIC_NAME, TrialKinetics, run_kinetics
from fuzzygait.workflows.plate_events import with_plate_events
from fuzzygait.workflows.preprocessing import (  # noqa: F401  (re-exported: the pipeline's options)
    DEFAULT_PREPROCESSING,
    Preprocessing,
    preprocess_file,
)
from fuzzygait.workflows.static_calibration import (  # noqa: F401  (calibrate_static, StaticCalibration: re-exported)
    StaticCalibration,
    calibrate_run,
    calibrate_static,
    stored_calibration,
)
from fuzzygait.workflows.subject_resolution import (  # noqa: F401  (resolve_subject: re-exported)
    MARKER_DIAMETER_RANGE,
    DiameterChoice,
    for_static_calibration,
    inter_asis_notes,
    resolve_subject,
    settle_marker_diameter,
    subject_warnings,
)
from fuzzygait.workflows.uncomputed import mark_empty_angles, refuse_empty

if TYPE_CHECKING:
    from fuzzygait.workflows.trial_inputs import TrialInputs

AXES = ("X", "Y", "Z")
#: Characters of a C3D point label (Vicon's limit, :func:`fuzzygait.io.write_c3d`).
MAX_LABEL = 32


@dataclass
class AnglesRun:
    """Everything one run of the pipeline produced.

    Attributes:
        raw: the trial as read.
        trial: the pre-processed trial the model saw.
        subject: subject parameters used (after static calibration, if any).
        result: model output (angles in degrees, joint centres in mm).
        gaps: gap report of the dynamic trial.
        events: gait events used for the cycles.
        event_source: ``"file"`` or how they were detected.
        notes: data-quality and processing findings for reports (:class:`~fuzzygait.core.findings.Finding`;
            their messages are what the commands print and the pages show).
        warnings: what the user must know before trusting the angles (a stated marker
            diameter that contradicts the file's own outputs, ...); shown on report pages
            and printed by the commands.
        crosscheck: ours against the angles the file already stores (Nexus', pyCGM2's),
            None when it stores none (:mod:`fuzzygait.workflows.crosscheck`).
        diameter: where the marker diameter came from
            (:func:`~fuzzygait.workflows.subject_resolution.settle_marker_diameter`).
        clusters: the static cluster calibration of a cluster model (cgm2.3, cgm2.4; the
            marker-error analysis holds it fixed), else None.
        kinetics: Plug-in Gait kinetics when the trial's file has force plates
            (:func:`fuzzygait.workflows.kinetics.trial_kinetics`), else None; their
            findings are in ``notes``.
    """

    raw: Trial
    trial: Trial
    subject: SubjectParameters
    result: CGMResult
    gaps: list[Gap]
    events: list[Event]
    event_source: str
    notes: list[Finding] = field(default_factory=list)
    clusters: ClusterCalibration | None = None
    warnings: list[str] = field(default_factory=list)
    crosscheck: CrossCheck | None = None
    diameter: DiameterChoice | None = None
    kinetics: TrialKinetics | None = None

    @property
    def model(self) -> str:
        """The model version that computed the angles (``"cgm1.0"``, ``"cgm2.3"``, ...)."""
        return self.result.model

    def angle_names(self) -> list[str]:
        """The angle outputs of the tables: every Plug-in Gait angle, and the CGM 2.4
        forefoot angles when the model computed (or tried) them."""
        forefoot = [n for n in FOREFOOT_ANGLE_NAMES if n in self.result.angles or n in self.result.unavailable]
        return [*ANGLE_NAMES, *forefoot]

    def angle_table(self) -> pd.DataFrame:
        """One row per frame: ``frame``, ``time`` (s), then ``<Angle>_X/Y/Z`` in degrees
        for every angle of :meth:`angle_names` (NaN where it could not be computed);
        ``attrs["model"]`` the model version."""
        columns: dict[str, np.ndarray] = {"frame": self.trial.frames, "time": self.trial.times}
        nan = np.full((self.trial.n_frames, 3), np.nan)
        for name in self.angle_names():
            values = self.result.angles.get(name, nan)
            for k, axis in enumerate(AXES):
                columns[f"{name}_{axis}"] = values[:, k]
        table = pd.DataFrame(columns)
        table.attrs["model"] = self.model
        return table

    def frame_table(self) -> pd.DataFrame:
        """The per-frame table written (``AngleOutputs.table``): :meth:`angle_table` and,
        with kinetics, their columns named as Nexus in Nexus' units (``LAnkleMoment_X``
        N·mm/kg, ``LAnklePower_Z`` W/kg, ``LGroundReactionForce_X`` N/kg,
        ``LNormalisedGRF_X`` % BW; :meth:`TrialKinetics.columns
        <fuzzygait.workflows.kinetics.TrialKinetics.columns>`)."""
        table = self.angle_table()
        if self.kinetics is not None:
            kinetic = pd.DataFrame({name: values for name, (values, _) in self.kinetics.columns().items()})
            table = pd.concat([table, kinetic], axis=1)
            table.attrs["model"] = self.model
        return table

    def units(self) -> dict[str, str]:
        """The unit of every value column of :meth:`frame_table` (angles ``deg``)."""
        units = {f"{name}_{axis}": "deg" for name in self.angle_names() for axis in AXES}
        if self.kinetics is not None:
            units.update({name: unit for name, (_, unit) in self.kinetics.columns().items()})
        return units

    def cycle_table(self) -> pd.DataFrame:
        """Gait-cycle-normalised angles, long format (angle, side, cycle, percent, value)."""
        table = normalised_angle_table(self.result.angles, self.trial, self.events)
        table.attrs["model"] = self.model
        return table

    def cycle_statistics(self) -> pd.DataFrame:
        """Mean and SD over cycles per angle component and percent of the cycle, then the
        kinetics' (:meth:`frame_table`'s names and units) over the cycles whose stance was
        on a force plate, as the pages show them (:meth:`TrialKinetics.cycle_table
        <fuzzygait.workflows.kinetics.TrialKinetics.cycle_table>`; the ground reaction over
        the stance) when the run has them."""
        cycles = self.cycle_table()
        if self.kinetics is not None:
            kinetic = self.kinetics.cycle_table(self.trial, self.events)
            cycles = pd.concat([cycles, kinetic], ignore_index=True) if len(kinetic) else cycles
        table = mean_sd_table(cycles)
        table.attrs["model"] = self.model
        return table


def run_angles(
    dynamic: str | os.PathLike[str] | Trial,
    *,
    static: str | os.PathLike[str] | Trial | None = None,
    subject_file: str | os.PathLike[str] | None = None,
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING,
    flat_foot: bool | None = None,
    marker_diameter: float | None = None,
    model: str = "cgm1.0",
    knee_ankle_centres: str | None = None,
) -> AnglesRun:
    """Run the joint-angle pipeline on one dynamic trial.

    Args:
        dynamic: the walking trial (path or :class:`Trial`).
        static: static calibration trial; without it the static offsets of the subject
            parameters are used as they are, and a cluster model (CGM 2.3+) takes its
            cluster calibration from ``subject_file`` (written by ``fuzzygait calibrate``).
        subject_file: ``.toml`` or ``.vsk``; without it the dynamic trial's PROCESSING
            group.
        preprocessing: gap filling and filter options (the static trial: gap filling
            only, see :func:`~fuzzygait.workflows.static_calibration.calibrate_static`).
        flat_foot: static calibration with the flat-foot option (uses SoleDelta); None:
            the subject file's own setting when it has one (QTM session.xml), else off.
        marker_diameter: mm, in place of the subject parameters' (see :func:`resolve_subject`).
        model: a model version (:data:`fuzzygait.kinematics.versions.MODEL_VERSIONS`) or
            ``"auto"``: the richest the markers support, or without ``static`` the model
            of the subject file's cluster calibration (:func:`choose_model`).  The model
            used and why is the first note.
        knee_ankle_centres: a cluster model's knee/ankle centre rule in the static
            calibration (:mod:`fuzzygait.kinematics.knee_ankle`; None: KNM/MED when the
            static trial has them, else the chord).

    Raises:
        ParameterError: a cluster model with neither ``static`` nor a subject file
            holding a cluster calibration (says what to give).
    """
    raw, relabelled = canonical_labels(dynamic if isinstance(dynamic, Trial) else read_c3d(dynamic))
    checked = check_trial(raw)
    trial, gaps = preprocessing.apply(checked)
    static_trial = None if static is None else static if isinstance(static, Trial) else read_c3d(static)
    static_trial = None if static_trial is None else canonical_labels(static_trial)[0]
    diameter = settle_marker_diameter(resolve_subject(raw, subject_file), marker_diameter, (raw, static_trial))
    warnings = ([diameter.warning] if diameter.warning else []) + subject_warnings(raw, subject_file, static_trial,
                                                                                   diameter.subject)  # fmt: skip
    stored = StoredCalibration()
    if static_trial is None and subject_file is not None:
        stored = read_stored_calibration(subject_file)
    model, why = choose_model(model, raw, static_trial, stored)
    if static_trial is not None:
        calibration = calibrate_run(static_trial, trial, diameter.subject, subject_file,
                                    preprocessing=preprocessing, flat_foot=flat_foot, model=model,
                                    knee_ankle_centres=knee_ankle_centres)  # fmt: skip
    else:
        calibration = stored_calibration(stored, diameter.subject, subject_file, model)
    subject, clusters = calibration.subject, calibration.clusters
    notes = [*trial.notes, *relabelled, Finding(FindingKind.MODEL, f"model {model} ({why})"), diameter.note,
             *calibration.notes]  # fmt: skip
    result = compute_lower_body(trial, subject, model=model, clusters=clusters)
    mark_empty_angles(result, raw)
    refuse_empty(result, raw.name)
    check = check_run(checked, result.angles, raw, subject, diameter.recovered, model=model, clusters=clusters,
                      flat_foot=flat_foot if flat_foot is not None else subject.flat_foot)  # fmt: skip
    if check is not None and calibration.moved:
        check = check.with_cause(f"markers moved between the static trial and this one "
                                 f"({len(calibration.moved)} segments)")  # fmt: skip
    notes += [*result.notes, *(check.notes() if check is not None else [])]
    notes += [Finding(FindingKind.ANGLE_NOT_COMPUTED, f"{name} not computed: {why}", Severity.WARNING)
              for name, why in result.unavailable.items()]  # fmt: skip
    events, source = trial_gait_events(trial)
    if source != "file":
        notes.append(Finding(FindingKind.EVENTS, f"gait events {source}"))
    run = AnglesRun(raw, trial, subject, result, gaps, events, source, notes, clusters, warnings, check, diameter)
    run.kinetics, kinetic_notes = run_kinetics(run, subject_file)
    run.events, run.event_source, event_notes = with_plate_events(run)
    run.notes += kinetic_notes + event_notes
    return run


def choose_model(
    model: str, dynamic: Trial, static: Trial | None, stored: StoredCalibration | None = None
) -> tuple[str, str]:
    """The model version to run on ``dynamic`` and why (a phrase for the notes).

    ``model`` by name; ``"auto"``: with a static trial the richest version the markers
    support (:func:`~fuzzygait.kinematics.versions.supported_version`); without one, the
    version of the subject file's cluster calibration (``stored``) when it holds one,
    else ``cgm1.0``.
    """
    if model != "auto":
        return model_version(model).name, "given by name"
    if static is None and stored is not None and stored.clusters is not None:
        name = stored.model or ("cgm2.4" if stored.has_forefoot() else "cgm2.3")
        where = stored.source.name if stored.source is not None else "the subject file"
        return model_version(name).name, f"the model of the cluster calibration in {where}"
    version, why = supported_version(dynamic, static)
    return version.name, why


def output_suffix(suffix: str, model: str) -> str:
    """The output-name suffix asked for: ``""`` none, ``"model"`` the version's pyCGM2
    suffix (``"_CGM_2.3"``), else ``suffix`` itself (letters, digits, ``_ . -``)."""
    if suffix == "model":
        return model_version(model).suffix
    longest = max(*map(len, ALL_ANGLE_NAMES), LONGEST_KINETIC_NAME)
    if suffix and not (re.fullmatch(r"[A-Za-z0-9_.\-]+", suffix) and len(suffix) <= MAX_LABEL - longest):
        raise FuzzyGaitError(f"{Option.SUFFIX} {suffix!r}: use up to {MAX_LABEL - longest} letters, digits, '_', '.' "
                             "or '-' (e.g. _CGM_2.3; C3D labels hold 32 characters), or 'model'")  # fmt: skip
    return suffix


def model_output_trial(run: AnglesRun, suffix: str = "") -> Trial:
    """The pre-processed trial with the computed angles and virtual markers as model
    outputs, the subject parameters used and the events (for ``--c3d-out``: the trial's
    own, and the detected gait events when it had none).  The markers are the ones the
    model saw, filled and filtered, as Vicon Nexus saves a processed trial: the file's
    outputs are made from its markers (a second run filters them again, as in Nexus; the
    writer marks every changed sample computed, residual 0).  The angle outputs keep
    Vicon's names (``LKneeAngles``) with ``suffix`` appended (:func:`output_suffix`);
    virtual markers and joint centres are not suffixed, except, with a suffix, one the
    input holds too.  With
    kinetics, their outputs as Nexus stores them (:meth:`TrialKinetics.nexus_outputs
    <fuzzygait.workflows.kinetics.TrialKinetics.nexus_outputs>`: ``LAnkleMoment`` N·mm/kg
    in ``POINT:MOMENTS``, ``LAnklePower`` W/kg in ``POWERS``, ``LAnkleForce``,
    ``LGroundReactionForce`` N/kg and ``LNormalisedGRF`` % BW in ``FORCES``), suffixed like
    the angles: with a suffix the input's own (Nexus') outputs are all kept beside ours
    (without, ours replace them: :func:`replaced_outputs`); the outputs of a side not
    computed (all NaN) are not written."""
    out = run.trial.with_markers(run.trial.markers)
    suffix = output_suffix(suffix, run.model)
    for name, values in run.result.angles.items():
        out.outputs[name + suffix] = values
        out.output_kinds[name + suffix] = "angle"
    for name, (values, kind) in (run.kinetics.nexus_outputs(suffix) if run.kinetics is not None else {}).items():
        if np.isfinite(values).any():  # a side not computed replaces nothing of the input's
            out.outputs[name], out.output_kinds[name] = values, kind
    for name, values in run.result.virtual_markers.items():
        if name not in out.marker_labels:
            kept = name + suffix if suffix and name in run.raw.outputs else name
            out.outputs[kept] = values
            out.output_kinds[kept] = "modeled_marker" if name.endswith("JC") else "segment_frame"
    out.parameters.update(run.subject.to_processing())
    out.events = list(run.trial.events) + ([] if run.event_source == SOURCE_FILE else list(run.events))
    return out


def replaced_outputs(run: AnglesRun, trial: Trial) -> list[str]:
    """The input's own model outputs (Nexus' angles, kinetics, virtual markers) that
    ``trial`` (:func:`model_output_trial`) holds with other values: ours replace them."""
    return [name for name, values in run.raw.outputs.items()
            if name in trial.outputs and not np.array_equal(values, trial.outputs[name], equal_nan=True)]  # fmt: skip


def model_parameters(run: AnglesRun, suffix: str = "") -> dict[str, dict[str, str]]:
    """The C3D parameters naming the model of a run's outputs: group ``FUZZYGAIT``,
    ``MODEL`` (``"cgm2.3"``), ``VERSION`` of fuzzygait and, when the angle outputs have
    one, their ``SUFFIX`` (an empty text parameter reads back as no value)."""
    group = {"MODEL": run.model, "VERSION": __version__}
    if output_suffix(suffix, run.model):
        group["SUFFIX"] = output_suffix(suffix, run.model)
    return {"FUZZYGAIT": group}


def table_metadata(run: AnglesRun) -> dict[str, str]:
    """What the angle tables say about themselves: ``model`` and ``fuzzygait`` version."""
    return {"model": run.model, "fuzzygait": __version__}



@dataclass(frozen=True)
class AngleOutputs:
    """Files to write from a run (each optional): the angles per frame (``table``, .csv or
    .parquet), their mean and SD over gait cycles (``cycles``) and the model-output C3D
    (``c3d``, see :func:`model_output_trial`; its angle outputs named with ``suffix``,
    :func:`output_suffix`).

    Each names the model version: the tables in a last constant column ``model`` (and
    ``fuzzygait``, the version; Parquet also in its metadata, :func:`fuzzygait.io.tables.write_table`),
    the C3D in its ``FUZZYGAIT`` parameter group (:func:`model_parameters`).
    """

    table: Path | None = None
    cycles: Path | None = None
    c3d: Path | None = None
    suffix: str = ""

    def __post_init__(self) -> None:
        for name in ("table", "cycles", "c3d"):  # a path given as text
            if isinstance(value := getattr(self, name), (str, os.PathLike)):
                object.__setattr__(self, name, Path(value))

    def write(self, run: AnglesRun) -> list[Path]:
        """Write the files asked for (folders created); returns them in that order."""
        written = []
        metadata = table_metadata(run) | {"units": json.dumps(run.units())}
        for path, make in ((self.table, run.frame_table), (self.cycles, run.cycle_statistics)):
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
                written.append(write_table(make(), path, metadata=metadata, columns=("model",)))
        if self.c3d is not None:
            self.c3d.parent.mkdir(parents=True, exist_ok=True)
            trial = model_output_trial(run, self.suffix)
            # the input's analog channels, force platforms and parameters carried over; a note if not all
            parameters = model_parameters(run, self.suffix)
            run.notes += write_c3d(trial, self.c3d, text_parameters=parameters, source=trial.source)
            if replaced := replaced_outputs(run, trial):
                shown = ", ".join(replaced[:6]) + (f" and {len(replaced) - 6} more" if len(replaced) > 6 else "")
                run.notes.append(Finding(FindingKind.OUTPUT_FILE, f"{self.c3d.name}: ours replace the input's own "
                                         f"{shown} ({Option.SUFFIX} keeps them beside ours)"))  # fmt: skip
            written.append(self.c3d)
        return written


def angles_to_files(trial: TrialInputs, outputs: AngleOutputs) -> tuple[AnglesRun, list[Path]]:
    """The joint-angle run of ``trial`` (:meth:`TrialInputs.run
    <fuzzygait.workflows.trial_inputs.TrialInputs.run>`, :func:`run_angles`) and then
    ``outputs.write``: the run and the files written."""
    run = trial.run()
    return run, outputs.write(run)
