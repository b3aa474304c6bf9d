"""Angles a run could not compute: each named with its reason, and a run that computed
none at all refused in one line (never an angle table of NaN)."""

from __future__ import annotations

import numpy as np

from fuzzygait.core.errors import MarkerError
from fuzzygait.core.options import Option
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics import CGMResult
from fuzzygait.kinematics.marker_names import required_markers
from fuzzygait.kinematics.versions import model_version
from fuzzygait.mocap.sanity import missing_throughout


def mark_empty_angles(result: CGMResult, raw: Trial) -> None:
    """Add every angle NaN in every frame to ``result.unavailable`` (so that it is not
    counted as computed), saying why: the markers of ``raw`` missing in every frame
    (:func:`fuzzygait.mocap.sanity.missing_throughout`), when there are any."""
    empty = [name for name, values in result.angles.items()
             if name not in result.unavailable and not np.isfinite(values).any()]  # fmt: skip
    if not empty:
        return
    missing = missing_throughout(raw)
    why = "no frame could be computed" + (f" (marker{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
                                          "missing in every frame)" if missing else "")  # fmt: skip
    for name in empty:
        result.unavailable[name] = why


def refuse_empty(result: CGMResult, trial_name: str) -> None:
    """One line when ``result`` has no angle with a value in any frame: what is missing
    (the reasons of :attr:`CGMResult.unavailable`, each once) and what the model version
    needs -- an angle table of NaN is never written."""
    if any(name not in result.unavailable for name in result.angles) or not result.unavailable:
        return
    reasons = list(dict.fromkeys(result.unavailable.values()))
    version = model_version(result.model)
    raise MarkerError(f"{trial_name}: no joint angle can be computed by {result.model}: {'; '.join(reasons)}; "
                      f"{result.model} needs {required_markers(version.clusters, version.forefoot)}; label them in "
                      f"the capture software (the sacrum may also be VSAC) or give another model with {Option.MODEL}")
