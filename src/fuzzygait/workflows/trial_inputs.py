"""What a workflow on one trial reads and how it computes the angles: the dynamic trial,
its static trial and subject file and the options of
:func:`~fuzzygait.workflows.angles.run_angles` (:class:`TrialInputs`)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.trial import Trial
from fuzzygait.workflows.angles import DEFAULT_PREPROCESSING, AnglesRun, Preprocessing, run_angles

__all__ = ["TrialInputs"]

_FILE = (str, os.PathLike)


@dataclass(frozen=True)
class TrialInputs:
    """One trial's inputs and the options of its joint-angle run.

    Attributes:
        dynamic: the dynamic trial (a C3D file or a read trial).
        static: the static trial (None: the subject file's calibration, if any).
        subject_file: the subject parameters (.mp/.vsk/.yaml; None: from the trial).
        preprocessing: gap filling and filtering of the markers.
        flat_foot: static calibration with the flat-foot option (None: the file's).
        marker_diameter: mm (finite, > 0), in place of the subject parameters'.
        model: a model version or ``"auto"`` (as for
            :func:`~fuzzygait.workflows.angles.run_angles`).
        knee_ankle_centres: a cluster model's knee/ankle centre rule (None: the default).
    """

    dynamic: str | os.PathLike[str] | Trial
    static: str | os.PathLike[str] | Trial | None = None
    subject_file: str | os.PathLike[str] | None = None
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING
    flat_foot: bool | None = None
    marker_diameter: float | None = None
    model: str = "auto"
    knee_ankle_centres: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.dynamic, _FILE + (Trial,)):
            raise ParameterError(f"dynamic must be a trial file or a Trial; got {self.dynamic!r}")
        if self.static is not None and not isinstance(self.static, _FILE + (Trial,)):
            raise ParameterError(f"static must be a trial file, a Trial or None; got {self.static!r}")
        if self.subject_file is not None and not isinstance(self.subject_file, _FILE):
            raise ParameterError(f"subject_file must be a file or None; got {self.subject_file!r}")
        if not isinstance(self.preprocessing, Preprocessing):
            raise ParameterError(f"preprocessing must be a Preprocessing; got {type(self.preprocessing).__name__}")
        if self.flat_foot is not None and not isinstance(self.flat_foot, bool):
            raise ParameterError(f"flat_foot must be True, False or None; got {self.flat_foot!r}")
        if self.marker_diameter is not None and not (isinstance(self.marker_diameter, int | float)
                                                     and math.isfinite(self.marker_diameter)
                                                     and self.marker_diameter > 0):  # fmt: skip
            raise ParameterError(f"marker_diameter must be a finite number of mm > 0 or None; "
                                 f"got {self.marker_diameter!r}")  # fmt: skip
        self._check_model()
        self._check_knee_ankle_centres()

    def _check_model(self) -> None:
        from fuzzygait.kinematics.versions import MODEL_CHOICES, model_version

        if not isinstance(self.model, str):
            raise ParameterError(f"model must be a model version or 'auto'; got {self.model!r}")
        if self.model != "auto":
            try:
                model_version(self.model)
            except FuzzyGaitError:
                raise ParameterError(f"model must be one of {', '.join(MODEL_CHOICES)}; got {self.model!r}") from None

    def _check_knee_ankle_centres(self) -> None:
        from fuzzygait.kinematics.knee_ankle import KNEE_ANKLE_CENTRES

        if self.knee_ankle_centres is not None and self.knee_ankle_centres not in KNEE_ANKLE_CENTRES:
            raise ParameterError(f"knee_ankle_centres must be one of {', '.join(KNEE_ANKLE_CENTRES)} or None; "
                                 f"got {self.knee_ankle_centres!r}")  # fmt: skip

    def run(self) -> AnglesRun:
        """The joint-angle run (:func:`~fuzzygait.workflows.angles.run_angles`)."""
        return run_angles(self.dynamic, static=self.static, subject_file=self.subject_file,
                          preprocessing=self.preprocessing, flat_foot=self.flat_foot,
                          marker_diameter=self.marker_diameter, model=self.model,
                          knee_ankle_centres=self.knee_ankle_centres)  # fmt: skip
