"""Build synthetic Plug-in Gait trials with known angles, and the text of their files.

All trials use the lab frame X = walking direction, Y = left, Z = up, positions in mm,
first C3D frame 1, C3D frame ``n`` at ``(n - 1) / rate`` seconds.  Nothing is random in
the clean trials; :func:`make_noisy_gapped` uses a fixed seed.  See
:mod:`fuzzygait.synthetic.leg_model` for frames and sign conventions and
:mod:`fuzzygait.synthetic.gait_curves` for the angle curves.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.core.trial import Event, Trial
from fuzzygait.synthetic.gait_curves import (
    FOOT_OFF_PHASE,
    JOINTS,
    RIGHT_PHASE_SHIFT,
    STRIDE_TIME_S,
    joint_angle_curves,
    limb_phase,
    pelvis_angle_curves,
    pelvis_translation_curves,
)
from fuzzygait.synthetic.leg_model import (
    DYNAMIC_LABELS,
    SIDES,
    STATIC_LABELS,
    Pose,
    SubjectGeometry,
    pose_lower_body,
    static_offsets,
)
from fuzzygait.synthetic.pig_options import (
    PigOptions,
    pose_with_options,
    walking_ankle_angles,
)

#: Mean forward speed of the pelvis, mm/s (1.25 m/s).
WALKING_SPEED_MM_S = 1250.0
#: Mean height of the ASIS midpoint in the walking trial, mm (chosen so that the lowest
#: sole point stays within about +-15 mm of the floor; there is no contact model).
MEAN_PELVIS_HEIGHT_MM = 970.0
#: The walking trial starts this many cycles before the first left Foot Strike ...
LEAD_IN_CYCLES = 0.1
#: ... and ends this many cycles after the last left Foot Strike (so the right side also
#: has ``n_cycles`` complete cycles).
LEAD_OUT_CYCLES = 0.55
#: Subject name stored in the trials and events.
SUBJECT_NAME = "Synthetic"
#: Default standard deviation of the marker noise of the noisy trial, mm.
NOISE_MM = 0.5
#: Default seed of the noisy trial.
NOISE_SEED = 20240611

SEGMENT_ANGLE_NAMES = {"pelvis": "Pelvis", "hip": "Hip", "knee": "Knee", "ankle": "Ankle"}
JOINT_CENTRE_NAMES = ("HJC", "KJC", "AJC")


def angle_columns() -> list[str]:
    """Truth angle column names: ``LPelvisAngles_X`` ... ``RAnkleAngles_Z`` (degrees)."""
    return [
        f"{side}{name}Angles_{axis}"
        for side in SIDES
        for name in SEGMENT_ANGLE_NAMES.values()
        for axis in "XYZ"
    ]


def joint_centre_columns() -> list[str]:
    """Truth joint-centre column names ``LHJC_X`` ... ``RAJC_Z`` (mm)."""
    return [f"{side}{jc}_{axis}" for side in SIDES for jc in JOINT_CENTRE_NAMES for axis in "XYZ"]


# ----------------------------------------------------------------------------- walking
def walking_state(
    times: np.ndarray,
    geometry: SubjectGeometry | None = None,
    first_strike_time: float = LEAD_IN_CYCLES * STRIDE_TIME_S,
    x_offset: float = 0.0,
    options: PigOptions | None = None,
) -> tuple[Pose, dict[tuple[str, str], np.ndarray], np.ndarray]:
    """Exact walker state at arbitrary ``times`` (s).

    The global (left) phase is ``(t - first_strike_time) / STRIDE_TIME_S``.  The pelvis
    moves at :data:`WALKING_SPEED_MM_S` along +X (``x = x_offset + v t``), sways
    laterally and bounces vertically around :data:`MEAN_PELVIS_HEIGHT_MM`.

    With ``options`` the wands, ANK and the ankle angles follow
    :mod:`fuzzygait.synthetic.pig_options` (misplaced wands, tibial torsion).

    Returns:
        ``(pose, angles, phase)`` where ``angles`` maps ``(side, joint)`` (``joint`` in
        pelvis/hip/knee/ankle) to ``(n, 3)`` clinical angles in degrees and ``phase`` is
        the global phase ``(n,)``.
    """
    t = np.atleast_1d(np.asarray(times, dtype=float))
    phase = (t - first_strike_time) / STRIDE_TIME_S
    offsets = static_offsets(geometry)
    if offsets["rotation"] != 0.0:
        raise ParameterError(
            "the walking trial needs TOE in the foot's x-z plane (toe_local y = 0): the "
            "Plug-in Gait ankle Y of the truth assumes a zero static rotation offset"
        )
    angles: dict[tuple[str, str], np.ndarray] = {}
    for side in SIDES:
        angles[(side, "pelvis")] = pelvis_angle_curves(phase, side)
        for joint in JOINTS:
            angles[(side, joint)] = joint_angle_curves(
                limb_phase(phase, side), joint, offsets["plantarflexion"]
            )
    sway = pelvis_translation_curves(phase)
    origin = np.stack(
        [x_offset + WALKING_SPEED_MM_S * t, sway[:, 0], MEAN_PELVIS_HEIGHT_MM + sway[:, 1]],
        axis=-1,
    )
    if options is None:
        return pose_lower_body(origin, angles[("L", "pelvis")], angles, geometry), angles, phase
    g = geometry or SubjectGeometry()
    for side in SIDES:
        angles[(side, "ankle")] = walking_ankle_angles(angles[(side, "ankle")], options, side, g)
    return pose_with_options(origin, angles[("L", "pelvis")], angles, g, options), angles, phase


def gait_events(
    start_time: float, end_time: float, first_strike_time: float, subject: str = SUBJECT_NAME
) -> list[Event]:
    """Foot Strike / Foot Off events of both sides within ``[start_time, end_time]``.

    Left Foot Strike at phase ``k``, left Foot Off at ``k + 0.6``, right Foot Strike at
    ``k + 0.5`` and right Foot Off at ``k + 0.1`` (global phase); times rounded to 1 ns.
    """
    events: list[Event] = []
    k_min = int(np.floor((start_time - first_strike_time) / STRIDE_TIME_S)) - 1
    k_max = int(np.ceil((end_time - first_strike_time) / STRIDE_TIME_S)) + 1
    specs = [
        ("Foot Strike", "Left", 0.0),
        ("Foot Off", "Left", FOOT_OFF_PHASE),
        ("Foot Strike", "Right", RIGHT_PHASE_SHIFT),
        ("Foot Off", "Right", (RIGHT_PHASE_SHIFT + FOOT_OFF_PHASE) % 1.0),
    ]
    for k in range(k_min, k_max + 1):
        for label, context, phase in specs:
            time = round(first_strike_time + (k + phase) * STRIDE_TIME_S, 9)
            if start_time - 1e-9 <= time <= end_time + 1e-9:
                events.append(Event(label=label, context=context, time=time, subject=subject))
    return sorted(events, key=lambda e: (e.time, e.context, e.label))


def make_walking_trial(
    n_cycles: int = 4,
    rate: float = 100.0,
    geometry: SubjectGeometry | None = None,
    options: PigOptions | None = None,
) -> tuple[Trial, pd.DataFrame]:
    """Clean walking trial with exactly known angles.

    The trial starts :data:`LEAD_IN_CYCLES` of a cycle before the first left Foot Strike
    and ends :data:`LEAD_OUT_CYCLES` after the ``n_cycles``-th one, so both sides have
    ``n_cycles`` complete cycles (at 100 Hz and 4 cycles: 512 frames, 5.11 s).  The
    walk is centred on X = 0.  No randomness is involved (hence no seed).

    Returns:
        ``(trial, truth)``: ``trial`` has the markers of
        :data:`~fuzzygait.synthetic.leg_model.DYNAMIC_LABELS`, the events and the subject
        parameters; ``truth`` has columns ``frame`` (1-based), ``time_s``,
        :func:`angle_columns` (degrees) and :func:`joint_centre_columns` (mm).  With
        ``options`` (:class:`~fuzzygait.synthetic.pig_options.PigOptions`) the wands are
        misplaced and the tibia twisted by the known offsets, which the parameters carry.
    """
    if n_cycles < 1:
        raise ParameterError(f"n_cycles must be >= 1; got {n_cycles}")
    if not np.isfinite(rate) or rate <= 0:
        raise ParameterError(f"rate must be a positive number of Hz; got {rate}")
    g = geometry or SubjectGeometry()
    first_strike = LEAD_IN_CYCLES * STRIDE_TIME_S
    duration = (LEAD_IN_CYCLES + n_cycles + LEAD_OUT_CYCLES) * STRIDE_TIME_S
    n_frames = int(np.floor(duration * rate + 1e-9)) + 1
    times = np.arange(n_frames) / rate
    x_offset = -WALKING_SPEED_MM_S * times[-1] / 2.0
    pose, angles, _ = walking_state(times, g, first_strike, x_offset, options)

    markers = np.stack([pose.markers[label] for label in DYNAMIC_LABELS], axis=1)
    events = gait_events(times[0], times[-1], first_strike)
    trial = Trial(
        markers=markers,
        marker_labels=list(DYNAMIC_LABELS),
        rate=float(rate),
        first_frame=1,
        events=events,
        parameters=g.parameters() if options is None else options.parameters(g),
        subject=SUBJECT_NAME,
        notes=[Finding(FindingKind.SYNTHETIC, "synthetic walking trial generated by fuzzygait.synthetic (clean)")],
    )

    columns: dict[str, np.ndarray] = {
        "frame": np.arange(1, n_frames + 1),
        "time_s": np.round(times, 9),
    }
    for side in SIDES:
        for joint, name in SEGMENT_ANGLE_NAMES.items():
            values = angles[(side, joint)]
            for i, axis in enumerate("XYZ"):
                columns[f"{side}{name}Angles_{axis}"] = values[:, i]
    for side in SIDES:
        for jc in JOINT_CENTRE_NAMES:
            values = pose.joint_centres[side + jc]
            for i, axis in enumerate("XYZ"):
                columns[f"{side}{jc}_{axis}"] = values[:, i]
    return trial, pd.DataFrame(columns)


# ----------------------------------------------------------------------------- static
def make_static_trial(
    rate: float = 100.0,
    duration_s: float = 2.0,
    geometry: SubjectGeometry | None = None,
    options: PigOptions | None = None,
) -> Trial:
    """Static standing trial: all joint and pelvis angles 0, pelvis level.

    The ASIS midpoint stands at X = 0, Y = 0 and at the height that puts the soles on the
    floor (:meth:`SubjectGeometry.standing_pelvis_height`, 991.585 mm); both feet point
    along +X.  Includes the medial markers LKNM, RKNM, LMED, RMED.  Every frame is
    identical; no events.  With ``options``
    (:class:`~fuzzygait.synthetic.pig_options.PigOptions`): misplaced wands, twisted
    tibiae, the feet along the torsioned tibiae, the KAD in place of KNE and MED as
    asked, no KNM; the parameters carry zero offsets (an uncalibrated subject).
    """
    if not np.isfinite(rate) or rate <= 0:
        raise ParameterError(f"rate must be a positive number of Hz; got {rate}")
    if not np.isfinite(duration_s) or duration_s <= 0:
        raise ParameterError(f"duration_s must be positive; got {duration_s}")
    g = geometry or SubjectGeometry()
    n = max(int(round(duration_s * rate)), 1)
    origin = np.tile([0.0, 0.0, g.standing_pelvis_height()], (n, 1))
    zeros = np.zeros((n, 3))
    angles = {(side, joint): zeros for side in SIDES for joint in JOINTS}
    labels = list(STATIC_LABELS)
    if options is None:
        pose = pose_lower_body(origin, zeros, angles, g, medial_markers=True)
    else:
        pose = pose_with_options(origin, zeros, angles, g, options, static=True)
        labels = options.static_labels(DYNAMIC_LABELS)
    markers = np.stack([pose.markers[label] for label in labels], axis=1)
    return Trial(
        markers=markers,
        marker_labels=labels,
        rate=float(rate),
        first_frame=1,
        parameters=g.parameters(),
        subject=SUBJECT_NAME,
        notes=[Finding(FindingKind.SYNTHETIC, "synthetic static trial generated by fuzzygait.synthetic")],
    )


# ----------------------------------------------------------------------------- noise/gaps
@dataclass(frozen=True)
class CutGap:
    """A cut stretch of one marker: C3D frames ``start_frame .. start_frame+length-1``."""

    marker: str
    start_frame: int
    length: int


#: Gaps cut by :func:`make_noisy_gapped` (1-based C3D frames of the default 512-frame
#: walking trial): one at the trial start, five interior ones of 1-10 frames and one of
#: 23 frames.
DEFAULT_GAPS: tuple[CutGap, ...] = (
    CutGap("RHEE", 1, 6),
    CutGap("LTHI", 45, 1),
    CutGap("RKNE", 120, 4),
    CutGap("LTOE", 200, 10),
    CutGap("RTIB", 290, 7),
    CutGap("LASI", 350, 2),
    CutGap("LANK", 400, 23),
)


def make_noisy_gapped(
    trial: Trial,
    noise_mm: float = NOISE_MM,
    seed: int = NOISE_SEED,
    gaps: Sequence[CutGap] | None = None,
) -> tuple[Trial, list[CutGap]]:
    """Copy of ``trial`` with Gaussian marker noise and cut gaps.

    Noise is drawn independently per coordinate from ``N(0, noise_mm^2)`` with
    ``numpy.random.default_rng(seed)`` over the whole ``(frames, markers, 3)`` array;
    then the samples of each gap are set to NaN.

    Args:
        trial: clean trial (first frame and labels are used to place the gaps).
        noise_mm: noise standard deviation in mm.
        seed: random seed.
        gaps: gaps to cut (default :data:`DEFAULT_GAPS`).

    Returns:
        ``(noisy_trial, gaps)``.

    Raises:
        ParameterError: a gap names an unknown marker or does not fit in the trial.
    """
    if not np.isfinite(noise_mm) or noise_mm < 0:
        raise ParameterError(f"noise_mm must be >= 0; got {noise_mm}")
    gaps = list(DEFAULT_GAPS if gaps is None else gaps)
    rng = np.random.default_rng(seed)
    markers = trial.markers + rng.normal(0.0, noise_mm, size=trial.markers.shape)
    last = trial.first_frame + trial.n_frames - 1
    for gap in gaps:
        if gap.marker not in trial.marker_labels:
            raise ParameterError(f"gap marker {gap.marker!r} is not in the trial")
        if gap.length < 1 or gap.start_frame < trial.first_frame:
            raise ParameterError(f"gap {gap} does not fit frames {trial.first_frame}..{last}")
        if gap.start_frame + gap.length - 1 > last:
            raise ParameterError(f"gap {gap} does not fit frames {trial.first_frame}..{last}")
        i0 = gap.start_frame - trial.first_frame
        markers[i0 : i0 + gap.length, trial.marker_labels.index(gap.marker), :] = np.nan
    note = Finding(FindingKind.SYNTHETIC, f"Gaussian noise sigma={noise_mm} mm (seed {seed}); {len(gaps)} gaps cut")
    noisy = trial.with_markers(markers, note=note)
    return noisy, gaps


# ----------------------------------------------------------------------------- writers
def subject_toml_text(parameters: dict[str, float], title: str = "Plug-in Gait subject") -> str:
    """TOML text of the subject parameters (flat keys, fixed order, exact floats)."""
    lines = [
        f"# Synthetic {title} (generated by fuzzygait.synthetic; do not edit).",
        "# Vicon PROCESSING parameter names. Units: lengths in mm, angles in rad, mass in kg.",
        "# L/RAsisTrocanterDistance = 0.1288 * LegLength - 48.56 (Plug-in Gait regression).",
        "",
    ]
    lines += [f"{name} = {float(value)!r}" for name, value in parameters.items()]
    return "\n".join(lines) + "\n"


def _csv_text(frame: pd.DataFrame, float_format: str) -> str:
    return frame.to_csv(index=False, float_format=float_format, lineterminator="\n")


def truth_angles_csv_text(truth: pd.DataFrame) -> str:
    """CSV text of ``frame, time_s`` and the truth angles (degrees, 9 decimals)."""
    return _csv_text(truth[["frame", "time_s", *angle_columns()]], "%.9f")


def truth_joint_centres_csv_text(truth: pd.DataFrame) -> str:
    """CSV text of ``frame, time_s`` and the truth joint centres (mm, 6 decimals)."""
    return _csv_text(truth[["frame", "time_s", *joint_centre_columns()]], "%.6f")


def gaps_csv_text(gaps: Sequence[CutGap]) -> str:
    """CSV text ``marker,start_frame,length`` (1-based C3D frames)."""
    rows = ["marker,start_frame,length"] + [f"{g.marker},{g.start_frame},{g.length}" for g in gaps]
    return "\n".join(rows) + "\n"
