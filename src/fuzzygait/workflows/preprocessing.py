"""Pre-processing of a trial's markers before a model sees them (:class:`Preprocessing`):
gaps filled, then a zero-lag low-pass; and ``fuzzygait preprocess`` (:func:`preprocess_file`:
a C3D file in, the same file cleaned out)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from fuzzygait.io import Trial, read_c3d, write_c3d
from fuzzygait.mocap import fill_trial_gaps, filter_trial, labelled_markers
from fuzzygait.mocap.gaps import Gap, Method
from fuzzygait.mocap.sanity import check_trial

__all__ = ["DEFAULT_PREPROCESSING", "Preprocessing", "preprocess_file"]


@dataclass(frozen=True)
class Preprocessing:
    """Pre-processing options: gaps up to ``max_gap`` frames filled by ``fill_method``
    (``"auto"``, ``"spline"`` or ``"pattern"``, see :func:`fuzzygait.mocap.gaps.fill_gaps`),
    then a zero-lag Butterworth low-pass at ``cutoff`` Hz unless ``filter`` is False.

    With ``labelled_only`` (the default of the model pipelines) unlabelled trajectories
    (Vicon's ``*127``, :func:`fuzzygait.mocap.gaps.is_unlabelled`) are neither filled nor
    filtered nor reported: no model reads them, and their many short fragments only filled
    the gap report and the filter's short-run warnings; ``fuzzygait preprocess`` (a file
    in, the same file cleaned out) treats every trajectory."""

    max_gap: int = 10
    cutoff: float = 6.0
    filter: bool = True
    fill_method: Method = "auto"
    labelled_only: bool = True

    def apply(self, trial: Trial) -> tuple[Trial, list[Gap]]:
        """The pre-processed trial and its gap report."""
        labelled = labelled_markers(trial.marker_labels) if self.labelled_only else list(trial.marker_labels)
        markers = None if len(labelled) == trial.n_markers else labelled
        filled, gaps = fill_trial_gaps(trial, max_gap=self.max_gap, method=self.fill_method, markers=markers)
        return (filter_trial(filled, cutoff=self.cutoff, markers=markers) if self.filter else filled), gaps


#: The default pre-processing (gaps up to 10 frames, auto method; 6 Hz low-pass).
DEFAULT_PREPROCESSING = Preprocessing()


def preprocess_file(
    input_file: str | os.PathLike[str], out_file: str | os.PathLike[str], preprocessing: Preprocessing = Preprocessing()
) -> tuple[Trial, list[Gap]]:
    """Read a C3D file, pre-process it and write the result to ``out_file`` (its folder
    created); returns the trial as read after the content checks
    (:func:`fuzzygait.mocap.sanity.check_trial`: implausible samples of the labelled
    markers blanked, each noted in its ``notes``) and the gap report. The written file
    carries the input's analog channels, force platforms, events and parameters over
    (:func:`fuzzygait.io.write_c3d`); what could not be is one more note.

    Raises:
        C3DError, MarkerError: an absurd rate, a unit mismatch, a marker with too many
            implausible samples (nothing written)."""
    raw = check_trial(read_c3d(input_file))
    cleaned, gaps = preprocessing.apply(raw)
    Path(out_file).parent.mkdir(parents=True, exist_ok=True)
    raw.notes.extend(write_c3d(cleaned, out_file, source=input_file))
    return raw, gaps
