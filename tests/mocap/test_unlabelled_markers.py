"""Unlabelled trajectories (Vicon's ``*127``) are neither gap-filled, filtered nor
reported by the pre-processing; the markers asked for are (``markers=``)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from support import needs_shared, shared_file

from fuzzygait.core.trial import Trial
from fuzzygait.mocap import ShortRunWarning, fill_trial_gaps, filter_trial, is_unlabelled, labelled_markers
from fuzzygait.workflows.angles import Preprocessing


def _trial() -> Trial:
    t = np.arange(200) / 100.0
    base = np.stack([np.sin(t), np.cos(t), t], axis=1) * 100.0
    markers = np.stack([base, base + 50.0, base - 50.0], axis=1)
    markers[50:55, 0] = np.nan  # a gap in a labelled marker
    markers[:, 2] = np.nan
    markers[100:104, 2] = base[100:104] - 50.0  # a short fragment of an unlabelled one
    markers[120:126, 2] = base[120:126] - 50.0
    return Trial(markers=markers, marker_labels=["LASI", "RASI", "*127"], rate=100.0)


def test_unlabelled_labels() -> None:
    assert is_unlabelled("*127") and is_unlabelled("C_12") and is_unlabelled("Unlabeled 3")
    assert not is_unlabelled("LASI") and not is_unlabelled("*LASI") and not is_unlabelled("C7")
    assert labelled_markers(["LASI", "*1", "RASI", "*22"]) == ["LASI", "RASI"]


def test_only_the_markers_asked_for_are_filled_and_filtered() -> None:
    trial = _trial()
    filled, gaps = fill_trial_gaps(trial, markers=["LASI", "RASI"])
    assert [g.marker for g in gaps] == ["LASI"] and gaps[0].filled
    assert np.array_equal(filled.markers[:, 2], trial.markers[:, 2], equal_nan=True)  # untouched
    with warnings.catch_warnings():
        warnings.simplefilter("error", ShortRunWarning)  # the *127 fragments would warn
        out = filter_trial(filled, markers=["LASI", "RASI"])
    assert np.array_equal(out.markers[:, 2], trial.markers[:, 2], equal_nan=True)
    assert not np.array_equal(out.markers[:, 1], filled.markers[:, 1])
    assert out.notes[-1].message.endswith("(2 of 3 markers)")
    with pytest.warns(ShortRunWarning, match=r"\*127"):  # every marker, as before
        filter_trial(filled)


def test_preprocessing_skips_unlabelled_markers() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", ShortRunWarning)
        _, gaps = Preprocessing().apply(_trial())
    assert [g.marker for g in gaps] == ["LASI"]


@needs_shared
def test_movement_trial_reports_no_unlabelled_gaps() -> None:
    from fuzzygait.io import read_c3d

    raw = read_c3d(shared_file("vicon", "Movement_trial.c3d"))
    assert sum(map(is_unlabelled, raw.marker_labels)) > 30
    with warnings.catch_warnings():
        warnings.simplefilter("error", ShortRunWarning)
        _, gaps = Preprocessing().apply(raw)
    assert not [g for g in gaps if is_unlabelled(g.marker)]
