"""Static calibration to a subject file (``fuzzygait calibrate``).

The static trial is pre-processed and calibrated by the code ``angles --static`` runs
(:func:`fuzzygait.workflows.angles.calibrate_static`), so that a walking trial processed
with the written file gives the same angles as with the static trial itself.
"""

from __future__ import annotations

import os
from pathlib import Path

from fuzzygait import __version__
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.io import Trial, read_c3d
from fuzzygait.io.subject import write_subject
from fuzzygait.io.tomlfile import TomlValue
from fuzzygait.workflows.angles import (
    DEFAULT_PREPROCESSING,
    Preprocessing,
    StaticCalibration,
    calibrate_static,
    resolve_subject,
)

#: Subject file types ``calibrate`` writes.
SUBJECT_SUFFIXES = (".toml", ".vsk")


def check_subject_path(path: Path, option: str) -> None:
    """Refuse an output path that is not ``.toml`` or ``.vsk`` (before any work)."""
    if path.suffix.lower() not in SUBJECT_SUFFIXES:
        raise FuzzyGaitError(f"{path}: {option} must name a .toml or .vsk subject file")


def calibrate_to_file(
    static: str | os.PathLike[str] | Trial,
    out_file: str | os.PathLike[str],
    *,
    subject_file: str | os.PathLike[str] | None = None,
    marker_diameter: float | None = None,
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING,
    flat_foot: bool = False,
) -> StaticCalibration:
    """Calibrate the subject on the static trial and write every parameter to ``out_file``
    (``.toml`` or ``.vsk``, atomically; the method, foot flat and the static trial noted
    in it).  A ``.vsk`` written from a ``.vsk`` subject file is that file with the values
    updated (skeleton and marker set kept, as Nexus' own calibration does); from a TOML
    file or the PROCESSING group it holds the parameters only.

    Args:
        static: the static trial (path or :class:`Trial`).
        out_file: the calibrated subject file.
        subject_file: the subject's measurements (``.toml`` or ``.vsk``); without it the
            static trial's PROCESSING group.
        marker_diameter: mm, in place of the subject's (default: the subject's, else 14).
        preprocessing: gap filling of the static trial (never low-passed, see
            :func:`fuzzygait.workflows.angles.calibrate_static`).
        flat_foot: Plug-in Gait's foot-flat option (uses ``SoleDelta``).
    """
    out_file = Path(out_file)
    check_subject_path(out_file, "--out")
    trial = static if isinstance(static, Trial) else read_c3d(static)
    subject = resolve_subject(trial, subject_file, marker_diameter)
    calibration = calibrate_static(trial, subject, preprocessing=preprocessing, flat_foot=flat_foot)
    source = Path(subject_file).name if subject_file is not None else f"{trial.name} PROCESSING group"
    comments = [
        f"Plug-in Gait subject calibrated by fuzzygait {__version__} (`fuzzygait calibrate`) "
        f"from {Path(trial.name).name}, measurements from {source}.",
        f"Method {calibration.method}, foot flat {'on' if flat_foot else 'off'}, "
        f"{calibration.subject.marker_diameter:g} mm markers.",
        "Vicon PROCESSING names; lengths in mm, angles in rad, mass in kg.",
    ]
    metadata: dict[str, TomlValue] = {"static": Path(trial.name).name, "method": calibration.method,
                                      "flat_foot": flat_foot, "fuzzygait": __version__}  # fmt: skip
    out_file.parent.mkdir(parents=True, exist_ok=True)
    template = subject_file if subject_file is not None and Path(subject_file).suffix.lower() == ".vsk" else None
    write_subject(calibration.subject, out_file, comments=comments, metadata=metadata, vsk_template=template)
    return calibration
