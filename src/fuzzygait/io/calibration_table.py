"""The ``[calibration]`` table of a calibrated subject file, as plain data.

``fuzzygait calibrate`` writes what it calibrated besides the subject parameters into
the ``[calibration]`` table of a TOML subject file: the model version, the static trial,
the method and, for the cluster models (CGM 2.3+), the cluster calibration as sub-tables
(their meaning: :mod:`fuzzygait.kinematics.calibration_file`).  A Vicon ``.vsk`` has no
place for it: ``CAL.vsk`` gets a sidecar ``CAL.clusters.toml`` beside it holding only that
table, found by name when ``CAL.vsk`` is read.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.atomic import atomic_output
from fuzzygait.io.tomlfile import TomlData, load_toml, toml_text

#: What a ``.vsk``'s sidecar adds to its name (``CAL.vsk`` -> ``CAL.clusters.toml``).
SIDECAR_SUFFIX = ".clusters.toml"


def sidecar_path(vsk: str | os.PathLike[str]) -> Path:
    """The sidecar of a ``.vsk`` subject file: ``CAL.vsk`` -> ``CAL.clusters.toml``."""
    vsk = Path(vsk)
    return vsk.with_name(vsk.stem + SIDECAR_SUFFIX)


def read_calibration_table(subject_file: str | os.PathLike[str]) -> tuple[dict[str, Any], Path | None]:
    """The ``[calibration]`` table of a subject file and the file it is in: a TOML file's
    own, a ``.vsk``'s sidecar's (:func:`sidecar_path`) when there is one; ``({}, None)``
    when there is none (a plain subject file, or one written before fuzzygait 0.1's
    calibration tables: nothing but subject parameters).

    Raises:
        ParameterError: unreadable TOML, or a ``calibration`` entry that is not a table.
    """
    path = Path(subject_file)
    if path.suffix.lower() == ".vsk":
        path = sidecar_path(path)
        if not path.is_file():
            return {}, None
    elif path.suffix.lower() != ".toml":
        return {}, None
    table = load_toml(path, "subject file").get("calibration", {})
    if not isinstance(table, dict):
        raise ParameterError(f"{path}: 'calibration' must be a table ([calibration]); "
                             "rewrite the file with fuzzygait calibrate")
    return table, path


def write_calibration_sidecar(
    vsk: str | os.PathLike[str], table: Mapping[str, TomlData], comments: Sequence[str] = ()
) -> Path:
    """Write ``table`` as the ``[calibration]`` of ``vsk``'s sidecar, atomically; returns
    the sidecar's path."""
    path = sidecar_path(vsk)
    text = toml_text({"calibration": table}, comments)
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path
