"""Static calibration to a subject file (``fuzzygait calibrate``).

The static trial is pre-processed and calibrated by the code ``angles --static`` runs
(:func:`fuzzygait.workflows.angles.calibrate_static`), so that a walking trial processed
with the written file gives the same angles as with the static trial itself.  For a
cluster model (CGM 2.3+) the file also holds the cluster calibration
(:mod:`fuzzygait.kinematics.calibration_file`): in a TOML file its ``[calibration]``
table, beside a ``.vsk`` (which has no place for it) a sidecar ``CAL.clusters.toml``
(:mod:`fuzzygait.io.calibration_table`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from fuzzygait import __version__
from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding
from fuzzygait.core.options import Option
from fuzzygait.core.paths import check_subject_path
from fuzzygait.io import Trial, read_c3d
from fuzzygait.io.calibration_table import sidecar_path, write_calibration_sidecar
from fuzzygait.io.subject import write_subject
from fuzzygait.io.tomlfile import TomlData
from fuzzygait.kinematics.calibration_file import cluster_table
from fuzzygait.kinematics.marker_names import canonical_labels
from fuzzygait.kinematics.versions import CLUSTER_MARKERS, FOREFOOT_MARKERS, MEDIAL_MARKERS, model_version
from fuzzygait.workflows.angles import (
    DEFAULT_PREPROCESSING,
    Preprocessing,
    StaticCalibration,
    calibrate_static,
)
from fuzzygait.workflows.subject_resolution import (
    for_static_calibration,
    inter_asis_notes,
    resolve_subject,
    settle_marker_diameter,
    subject_warnings,
)


def _has_all(trial: Trial, names: tuple[str, ...]) -> bool:
    return all(trial.has_marker(side + name) for side in "LR" for name in names)


def calibration_model(static: Trial, model: str = "auto") -> tuple[str, str]:
    """The model version to calibrate for, and why.

    ``model`` by name; ``"auto"`` looks at the static trial alone (the walking trials are
    not known yet): thigh/shank clusters (THAP, THAD, TIAP, TIAD) with the medial KNM and
    MED on both sides -- the CGM 2.3 static marker set -- calibrate the cluster model
    (``cgm2.4`` when FMH/SMH/VMH are there too and 2.4 is implemented); otherwise
    Plug-in Gait (``cgm1.0``, whose offsets ``cgm1.1`` and ``cgm2.1`` read as they are).
    """
    if model != "auto":
        return model_version(model).name, "given by name"
    if not (_has_all(static, CLUSTER_MARKERS) and _has_all(static, MEDIAL_MARKERS)):
        return "cgm1.0", "static trial without thigh/shank clusters and KNM/MED"
    if _has_all(static, FOREFOOT_MARKERS) and _implemented("cgm2.4"):
        return "cgm2.4", "static trial with clusters, KNM/MED and FMH/SMH/VMH"
    return "cgm2.3", "static trial with thigh/shank clusters and KNM/MED"


def _implemented(name: str) -> bool:
    try:
        model_version(name)
    except ParameterError:
        return False
    return True


@dataclass(frozen=True)
class CalibrationFile:
    """What :func:`calibrate_to_file` did: the calibration, its model and why, the
    files written (and a stale sidecar removed, if any), the notes on the subject
    parameters (marker diameter, inter-ASIS distance) and warnings (a stated marker
    diameter that contradicts the static trial's own outputs)."""

    calibration: StaticCalibration
    model: str
    why: str
    files: list[Path] = field(default_factory=list)
    removed: list[Path] = field(default_factory=list)
    notes: list[Finding] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def _file_comments(calibration: StaticCalibration, name: str, static_name: str,
                   subject_file: str | os.PathLike[str] | None, trial_name: str) -> list[str]:  # fmt: skip
    """The comments heading a calibrated subject file: who calibrated it how, from what."""
    source = Path(subject_file).name if subject_file is not None else f"{trial_name} PROCESSING group"
    title = "Plug-in Gait" if name == "cgm1.0" else name.upper().replace("CGM", "CGM ")
    return [
        f"{title} subject calibrated by fuzzygait {__version__} (`fuzzygait calibrate {Option.MODEL.flag} {name}`) "
        f"from {static_name}, measurements from {source}.",
        f"Method {calibration.method}, foot flat {'on' if calibration.flat_foot else 'off'}, "
        f"{calibration.subject.marker_diameter:g} mm markers.",
        "Vicon PROCESSING names; lengths in mm, angles in rad, mass in kg.",
        *(f"Static trial note: {note.message}" for note in calibration.notes),
    ]


def calibrate_to_file(
    static: str | os.PathLike[str] | Trial,
    out_file: str | os.PathLike[str],
    *,
    subject_file: str | os.PathLike[str] | None = None,
    marker_diameter: float | None = None,
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING,
    flat_foot: bool | None = None,
    model: str = "auto",
    knee_ankle_centres: str | None = None,
) -> CalibrationFile:
    """Calibrate the subject on the static trial and write every parameter to ``out_file``
    (``.toml`` or ``.vsk``, atomically; the model, method, foot flat and the static trial
    noted in it).  A ``.vsk`` written from a ``.vsk`` subject file is that file with the
    values updated (skeleton and marker set kept, as Nexus' own calibration does); from a
    TOML file or the PROCESSING group it holds the parameters only.

    A cluster model's calibration goes into the TOML file's ``[calibration]`` table, or
    for a ``.vsk`` into the sidecar ``<name>.clusters.toml`` beside it (written first);
    a Plug-in Gait ``.vsk`` removes a sidecar of that name left by an earlier cluster
    calibration to the same file (it no longer belongs to it).

    Args:
        static: the static trial (path or :class:`Trial`).
        out_file: the calibrated subject file.
        subject_file: the subject's measurements (``.toml`` or ``.vsk``); without it the
            static trial's PROCESSING group.
        marker_diameter: mm, in place of the subject's (default: the subject's, else 14).
        preprocessing: gap filling of the static trial (never low-passed, see
            :func:`fuzzygait.workflows.angles.calibrate_static`).
        flat_foot: Plug-in Gait's foot-flat option (uses ``SoleDelta``); None: the
            subject file's own setting when it has one (QTM session.xml), else off.
        model: the model version to calibrate for, or ``"auto"`` (:func:`calibration_model`).
        knee_ankle_centres: a cluster model's knee/ankle centre rule
            (:mod:`fuzzygait.kinematics.knee_ankle`; None: KNM/MED when the static trial
            has them, else the chord).
    """
    out_file = Path(out_file)
    check_subject_path(out_file)
    trial, relabelled = canonical_labels(static if isinstance(static, Trial) else read_c3d(static))
    diameter = settle_marker_diameter(resolve_subject(trial, subject_file), marker_diameter, (trial,))
    to_calibrate = for_static_calibration(diameter.subject, subject_file)
    name, why = calibration_model(trial, model)
    calibration = calibrate_static(trial, to_calibrate, preprocessing=preprocessing, flat_foot=flat_foot, model=name,
                                   knee_ankle_centres=knee_ankle_centres)  # fmt: skip
    notes = [*relabelled, diameter.note,
             *inter_asis_notes(diameter.subject, to_calibrate, calibration.subject, trial.name)]  # fmt: skip
    static_name = Path(trial.name).name
    comments = _file_comments(calibration, name, static_name, subject_file, trial.name)
    metadata: dict[str, TomlData] = {"model": name, "static": static_name, "method": calibration.method,
                                     "flat_foot": calibration.flat_foot, "fuzzygait": __version__}  # fmt: skip
    clusters = cluster_table(calibration.clusters) if calibration.clusters is not None else None
    if clusters is not None:
        comments.append("[calibration.clusters.*]: each tracking marker's mean static position (mm) in its "
                        "segment's anatomical frame (= technical frame; origins KJC, AJC, vSMH), "
                        "forefoot_joint_centres in the hindfoot frame (origin AJC).")  # fmt: skip
    out_file.parent.mkdir(parents=True, exist_ok=True)
    template = subject_file if subject_file is not None and Path(subject_file).suffix.lower() == ".vsk" else None
    files, removed = [], []
    if out_file.suffix.lower() == ".vsk":
        sidecar = sidecar_path(out_file)
        if clusters is not None:
            files.append(write_calibration_sidecar(out_file, {**metadata, "subject_file": out_file.name, **clusters},
                                                   comments[:1] + comments[-1:]))  # fmt: skip
            metadata["clusters"] = sidecar.name
        elif sidecar.is_file():
            sidecar.unlink()
            removed.append(sidecar)
    elif clusters is not None:
        metadata.update(clusters)
    files.insert(0, write_subject(calibration.subject, out_file, comments=comments, metadata=metadata,
                                  vsk_template=template))  # fmt: skip
    warnings = ([diameter.warning] if diameter.warning else []) + subject_warnings(trial, subject_file, trial,
                                                                                   diameter.subject)  # fmt: skip
    return CalibrationFile(calibration, name, why, files, removed, notes, warnings)
