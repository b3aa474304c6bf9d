"""Content sanity of a trial before any model runs on it.

A C3D file can be read without fault and still hold numbers no model should see.  Each
check here either gives a named note (``trial.notes``, shown in the CLI output and on
the report pages) or raises one clear error naming the file; none of them ever changes
a good recording (every trial of ``sample_data`` and ``../shared/data`` passes without a
note, ``tests/mocap/test_sanity.py``).  All are vectorised numpy over the whole marker
array (about a millisecond per trial).

* :func:`check_rate`: the point rate must lie in :data:`RATE_RANGE` Hz.
* :func:`check_units`: body segment lengths (ASIS-ASIS, knee-ankle, ASIS-knee,
  heel-toe) within a factor :data:`SCALE_RANGE` of an adult's; a trial in metres (or
  cm, inches) read as mm is refused, naming the unit it looks like.
* :func:`blank_spikes`: samples beyond any lab (:data:`MAX_COORDINATE` mm) or reached
  by a jump in and a jump out faster than :data:`MAX_SPEED` (a run of at most
  :data:`MAX_SPIKE_FRAMES` frames) are set missing, so gap filling treats them as gaps;
  a marker with more than :data:`MAX_SPIKE_FRACTION` of its samples blanked is refused.
* :func:`missing_throughout`: labelled markers without a single sample (the angle
  workflow names them with the angles left empty; a marker no angle needs is no news).
* :func:`motion_ranges` / :func:`is_motionless`: the pelvis and feet ranges, the measure
  the session discovery's ``motion`` rule uses (:func:`pelvis_range`); a walking trial
  that does not move has no gait events (:mod:`fuzzygait.gait.events`), a static trial
  that moves is refused (:func:`check_static`).
* :func:`~fuzzygait.mocap.marker_placement.moved_markers`: markers that sit elsewhere on
  their segment in the walking trial than in its static trial (moved or relabelled
  between the two), whose static calibration then does not fit the walking trial (a note
  per segment; a check of a static/walking pair, run by the angle workflow;
  :mod:`fuzzygait.mocap.marker_placement`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np

from fuzzygait.core.errors import C3DError, MarkerError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.trial import Trial
from fuzzygait.mocap.gaps import labelled_markers
from fuzzygait.mocap.marker_placement import SEGMENT_MARKERS as SEGMENT_MARKERS  # re-exported: benchmarks use it
from fuzzygait.mocap.marker_placement import median_distance
from fuzzygait.mocap.marker_placement import moved_angles as moved_angles  # re-exported: tests use it
from fuzzygait.mocap.marker_placement import moved_markers as moved_markers  # re-exported: tests, benchmarks, docs
from fuzzygait.mocap.marker_placement import moved_segments as moved_segments  # re-exported: tests use it

#: Plausible point rates (Hz).  Below 1 Hz a gait cycle (about 1 s) would not hold a
#: single sample; 10 kHz is above the fastest optical motion capture (Vicon Vantage
#: 2 kHz at full frame, Qualisys Arqus and Miqus about 10 kHz at reduced resolution).
RATE_RANGE = (1.0, 10_000.0)

#: Body segments (marker pairs) and their typical adult length (mm): inter-ASIS
#: 250 mm, knee-ankle (shank) 400 mm, ASIS-knee (thigh) 450 mm, heel-toe 150 mm.
SEGMENTS: tuple[tuple[str, str, float], ...] = (
    ("LASI", "RASI", 250.0),
    ("LKNE", "LANK", 400.0),
    ("RKNE", "RANK", 400.0),
    ("LASI", "LKNE", 450.0),
    ("RASI", "RKNE", 450.0),
    ("LHEE", "LTOE", 150.0),
    ("RHEE", "RTOE", 150.0),
)
#: Accepted ratio of the measured segment lengths to the typical ones (median over the
#: segments present): a small child is about 0.4, a tall adult 1.3; a unit read wrongly
#: gives 0.001 (metres), 0.1 (centimetres), 0.04 (inches) or 1000 (mm labelled m).
SCALE_RANGE = (0.25, 4.0)
#: The units a wrong scale most likely comes from: (ratio, what the numbers look like).
_UNIT_GUESSES = (
    (1e-3, "metres"),
    (1e-2, "decimetres"),
    (1e-1, "centimetres"),
    (1 / 25.4, "inches"),
    (1e3, "micrometres"),
    (1e6, "nanometres"),
)

#: Largest |coordinate| (mm) of a marker in any lab: 100 m.
MAX_COORDINATE = 1e5
#: Fastest plausible marker speed (mm/s): 50 m/s, about twice the fastest body segment
#: in sport (a kicking foot or a pitching hand, 20-25 m/s).
MAX_SPEED = 50_000.0
#: Measurement noise (mm) allowed on top of MAX_SPEED / rate between two frames.
JUMP_NOISE = 10.0
#: Longest run of frames (a spike) that leaves a marker's path and comes back.
MAX_SPIKE_FRAMES = 3
#: A marker with more than this fraction of its samples implausible is refused.
MAX_SPIKE_FRACTION = 0.05

#: Pelvis and feet ranges (mm) below which a trial is motionless; the session
#: discovery's ``motion`` rule (``STATIC_TRAVEL``).
MOTIONLESS_TRAVEL = 100.0
#: Largest pelvis or foot range (mm) of a static trial; the session discovery's largest
#: pelvis range of a static trial (``STATIC_MARKERS_TRAVEL``).
STATIC_MAX_TRAVEL = 300.0
#: Pelvis markers whose mean is the pelvis centre of the motion measure.
PELVIS_MARKERS = ("LASI", "RASI")
#: Foot markers of the motion measure.
FOOT_MARKERS = ("LHEE", "RHEE", "LTOE", "RTOE")


# --------------------------------------------------------------------------- rate
def check_rate(trial: Trial) -> None:
    """Refuse a point rate outside :data:`RATE_RANGE`.

    Raises:
        C3DError: naming the file and the rate.
    """
    low, high = RATE_RANGE
    if not low <= trial.rate <= high:
        raise C3DError(f"{trial.name}: point rate {trial.rate:g} Hz is implausible (motion capture runs at "
                       f"{low:g} to {high:g} Hz); the file's POINT:RATE is corrupt: fix it in the capture "
                       "software or re-export the trial")  # fmt: skip


# --------------------------------------------------------------------------- units
def segment_lengths(trial: Trial) -> dict[str, float]:
    """Median length (mm) over the frames of each :data:`SEGMENTS` pair present."""
    lengths = {}
    for a, b, _ in SEGMENTS:
        length = median_distance(trial, a, b)
        if length is not None:
            lengths[f"{a}-{b}"] = length
    return lengths


def body_scale(trial: Trial) -> tuple[float, dict[str, float]] | None:
    """``(scale, lengths)``: the median ratio of the segment lengths to the typical
    adult's (:data:`SEGMENTS`) and the lengths (mm); None without any segment."""
    lengths = segment_lengths(trial)
    if not lengths:
        return None
    typical = {f"{a}-{b}": length for a, b, length in SEGMENTS}
    return float(np.median([lengths[k] / typical[k] for k in lengths])), lengths


def check_units(trial: Trial) -> None:
    """Refuse a trial whose body segments are a unit's factor off (metres read as mm).

    Raises:
        C3DError: naming the file, the lengths and the unit the numbers look like.
    """
    found = body_scale(trial)
    if found is None:
        return
    scale, lengths = found
    low, high = SCALE_RANGE
    if low <= scale <= high:
        return
    if scale < 1e-9:
        raise C3DError(f"{trial.name}: the body's markers all sit at one point ({', '.join(lengths)} 0 mm): the file "
                       "holds no usable marker positions; re-export the trial")  # fmt: skip
    ratio, unit = min(_UNIT_GUESSES, key=lambda guess: abs(math.log(guess[0] / max(scale, 1e-300))))
    shown = ", ".join(f"{name} {value:.3g} mm" for name, value in list(lengths.items())[:3])
    if scale < 1:
        factor, looks = f"about {1 / ratio:.4g} times too small", f"{unit} read as millimetres"
    else:
        factor, looks = f"about {ratio:.4g} times too large", f"{unit}, or millimetres read as metres"
    raise C3DError(f"{trial.name}: marker distances are {factor} for a human body ({shown}): the coordinates "
                   f"look like {looks}; set the file's POINT:UNITS to its real unit or re-export the trial "
                   "in mm")  # fmt: skip


# --------------------------------------------------------------------------- spikes
def _spike_mask(position: np.ndarray, jump: float) -> np.ndarray:
    """``(n_frames,)`` True at the samples of ``position`` (``(n, 3)`` mm) off the
    marker's path.

    The visible samples are cut into *pieces* at every jump larger than ``jump`` mm and
    at every gap.  A piece next to a jump is off the path when it is short: at most
    :data:`MAX_SPIKE_FRAMES` frames and shorter than the marker's longest piece (so that
    in a trial of a few frames the majority stays).  A jump between two long pieces (a
    label swap held for a while) blanks nothing."""
    n = position.shape[0]
    finite = np.isfinite(position).all(axis=1)
    steps = np.linalg.norm(np.diff(position, axis=0), axis=1)
    jumped = np.zeros(n + 1, dtype=bool)
    jumped[1:n][steps > jump] = True  # jumped[i]: a jump between samples i-1 and i
    cut = jumped.copy()
    cut[0] = cut[n] = True
    cut[np.flatnonzero(np.diff(np.concatenate([[0], finite.astype(np.int8), [0]])) != 0)] = True
    starts = np.flatnonzero(cut[:-1])
    stops = np.concatenate([starts[1:], [n]])
    visible = finite[starts]
    lengths = np.where(visible, stops - starts, 0)
    short = min(MAX_SPIKE_FRAMES, int(lengths.max()) - 1)
    spiky = visible & (lengths <= short) & (jumped[starts] | jumped[stops])
    mask = np.zeros(n, dtype=bool)
    for start, stop in zip(starts[spiky], stops[spiky], strict=True):
        mask[start:stop] = True
    return mask


def find_spikes(trial: Trial, markers: Sequence[str] | None = None) -> dict[str, np.ndarray]:
    """Implausible samples per marker: ``{label: sample indices}`` (markers without any
    left out).  A sample is implausible beyond :data:`MAX_COORDINATE` mm or in a spike
    (:data:`MAX_SPEED`, :data:`MAX_SPIKE_FRAMES`).  ``markers``: the labels to check
    (default: the labelled ones)."""
    labels = labelled_markers(trial.marker_labels) if markers is None else list(markers)
    columns = [trial.marker_labels.index(label) for label in labels]
    data = trial.markers[:, columns, :]
    with np.errstate(invalid="ignore", over="ignore"):
        far = (np.abs(data) > MAX_COORDINATE).any(axis=2)
        data = np.where(far[:, :, None], np.nan, data)
        jump = MAX_SPEED / trial.rate + JUMP_NOISE
        steps = np.linalg.norm(np.diff(data, axis=0), axis=2)
        jumpy = (steps > jump).any(axis=0)
    found = {}
    for k in np.flatnonzero(far.any(axis=0) | jumpy):
        mask = far[:, k].copy()
        if jumpy[k]:
            with np.errstate(invalid="ignore", over="ignore"):
                mask |= _spike_mask(data[:, k, :], jump)
        if mask.any():
            found[labels[k]] = np.flatnonzero(mask)
    return found


def _frames_text(trial: Trial, samples: np.ndarray) -> str:
    frames = trial.first_frame + samples
    shown = ", ".join(str(f) for f in frames[:5])
    more = f" and {frames.size - 5} more" if frames.size > 5 else ""
    return f"frame{'s' if frames.size > 1 else ''} {shown}{more}"


def blank_spikes(trial: Trial) -> Trial:
    """The trial with the implausible samples of :func:`find_spikes` set missing (NaN:
    gap filling then treats them as gaps) and one note per marker; ``trial`` itself when
    there are none.

    Raises:
        MarkerError: a marker with more than :data:`MAX_SPIKE_FRACTION` of its visible
            samples implausible (names the marker and the file).
    """
    spikes = find_spikes(trial)
    if not spikes:
        return trial
    markers = trial.markers.copy()
    notes: list[Finding] = []
    for label, samples in spikes.items():
        column = trial.marker_labels.index(label)
        visible = int((~np.isnan(trial.markers[:, column, :]).any(axis=1)).sum())  # samples with a value
        if samples.size > MAX_SPIKE_FRACTION * max(visible, 1):
            raise MarkerError(f"{trial.name}: marker {label} has {samples.size} implausible samples of {visible} "
                              f"(beyond {MAX_COORDINATE:g} mm or jumps faster than {MAX_SPEED / 1000:g} m/s; "
                              f"{_frames_text(trial, samples)}): check its labelling in the capture software "
                              "or delete the trajectory")  # fmt: skip
        markers[samples, column, :] = np.nan
        notes.append(Finding(
            FindingKind.SPIKES,
            f"{label}: {samples.size} implausible sample{'s' if samples.size > 1 else ''} blanked "
            f"({_frames_text(trial, samples)}: beyond {MAX_COORDINATE:g} mm or a jump faster than "
            f"{MAX_SPEED / 1000:g} m/s); filled like a gap where short enough",
            Severity.WARNING,
            marker=label,
        ))
    out = trial.with_markers(markers)
    out.notes.extend(notes)
    return out


# --------------------------------------------------------------------------- missing
def missing_throughout(trial: Trial) -> list[str]:
    """Labelled markers that have no visible sample in any frame."""
    labels = labelled_markers(trial.marker_labels)
    columns = [trial.marker_labels.index(label) for label in labels]
    seen = np.isfinite(trial.markers[:, columns, :]).all(axis=2).any(axis=0)
    return [label for label, ok in zip(labels, seen, strict=True) if not ok]


# --------------------------------------------------------------------------- motion
def _range(points: np.ndarray) -> float | None:
    """Diagonal (mm) of the bounding box of ``(n, 3)`` points over their visible samples."""
    ok = np.isfinite(points).all(axis=1)
    if not ok.any():
        return None
    with np.errstate(over="ignore"):
        return float(np.linalg.norm(points[ok].max(axis=0) - points[ok].min(axis=0)))


def pelvis_range(trial: Trial) -> float | None:
    """Range (mm, diagonal of the bounding box) of the ASIS midpoint over the trial (the
    mean of the ASIS markers present); None without a visible ASIS marker."""
    present = [m for m in PELVIS_MARKERS if trial.has_marker(m)]
    if not present:
        return None
    with warnings.catch_warnings(), np.errstate(invalid="ignore", over="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)  # nanmean of an all-NaN frame
        mid = np.nanmean([trial.marker(m) for m in present], axis=0)
    return _range(mid)


def motion_ranges(trial: Trial) -> dict[str, float]:
    """Range (mm) over the trial of the pelvis (:func:`pelvis_range`, key ``"pelvis"``)
    and of each foot marker (:data:`FOOT_MARKERS`) present and visible."""
    ranges = {}
    pelvis = pelvis_range(trial)
    if pelvis is not None:
        ranges["pelvis"] = pelvis
    for label in FOOT_MARKERS:
        if trial.has_marker(label):
            value = _range(trial.marker(label))
            if value is not None:
                ranges[label] = value
    return ranges


def _ranges_text(ranges: dict[str, float]) -> str:
    return ", ".join(f"{name} {value:.0f} mm" for name, value in ranges.items())


def motionless(trial: Trial) -> str | None:
    """Why ``trial`` is motionless, or None when it moves (or cannot be told: no pelvis
    marker).  Motionless: the pelvis and every foot marker stay within
    :data:`MOTIONLESS_TRAVEL` mm (the feet too, so that walking on a treadmill, whose
    pelvis hardly travels, still counts as moving).  A trial of a single frame has no
    motion to tell events from."""
    if trial.n_frames < 2:
        frames = f"{trial.n_frames} frame{'' if trial.n_frames == 1 else 's'}"
        return f"the trial has {frames}: no motion to tell events from"
    ranges = motion_ranges(trial)
    if "pelvis" not in ranges or max(ranges.values()) >= MOTIONLESS_TRAVEL:
        return None
    return (f"the trial is motionless (ranges over the trial: {_ranges_text(ranges)}; all below "
            f"{MOTIONLESS_TRAVEL:g} mm): a static trial?")  # fmt: skip


def check_static(trial: Trial) -> None:
    """Refuse a static (standing) trial whose pelvis or feet move more than
    :data:`STATIC_MAX_TRAVEL` mm: the calibration averages its frames.

    Raises:
        C3DError: naming the file and the ranges.
    """
    ranges = motion_ranges(trial)
    moving = {k: v for k, v in ranges.items() if v > STATIC_MAX_TRAVEL}
    if moving:
        raise C3DError(f"{trial.name}: given as the static trial but it moves ({_ranges_text(moving)} over the "
                       f"trial; a standing trial stays within {STATIC_MAX_TRAVEL:g} mm): give the standing "
                       "calibration trial as the static trial")  # fmt: skip


# --------------------------------------------------------------------------- all
def check_trial(trial: Trial, *, static: bool = False) -> Trial:
    """The checks of this module a trial goes through before a model sees it, in order:
    rate, units, spikes (blanked, a note each) and for a ``static`` trial its motion.
    Returns the trial to use (``trial`` itself when nothing was changed).  Markers
    missing throughout are reported with the angles they leave empty
    (:func:`missing_throughout`, by the angle workflow).

    Raises:
        C3DError, MarkerError: one line naming the file and what to do.
    """
    check_rate(trial)
    check_units(trial)
    out = blank_spikes(trial)
    if static:
        check_static(out)
    return out
