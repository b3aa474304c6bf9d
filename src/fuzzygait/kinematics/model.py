"""The Conventional Gait Model lower body (Plug-in Gait = CGM 1.0, and the CGM 1.1-2.4
versions of :mod:`fuzzygait.kinematics.versions`): the whole model of a trial.

:func:`compute_lower_body` runs the chain of :mod:`fuzzygait.kinematics.chain` on every
frame at once and returns the ten Plug-in Gait lower-body angle outputs, the joint
centres, the segment frames and Vicon-style virtual markers.  On
``Movement_trial.c3d`` (Vicon Nexus 2, stair descent) every angle component agrees with
Nexus's stored outputs to better than 1e-4 degree.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.options import Option
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics import virtual_markers as vm
from fuzzygait.kinematics.angles import joint_angles
from fuzzygait.kinematics.chain import LowerBodyChain, segment_markers
from fuzzygait.kinematics.clusters import ClusterCalibration, ClusterChain
from fuzzygait.kinematics.kad import StaticKneeChain, knee_method
from fuzzygait.kinematics.progression import progression_frame
from fuzzygait.kinematics.rigid import MIN_MARKERS
from fuzzygait.kinematics.versions import ModelVersion, model_version

#: The Plug-in Gait lower-body angle outputs, in Vicon's names.
ANGLE_NAMES: tuple[str, ...] = (
    "LPelvisAngles", "RPelvisAngles", "LHipAngles", "RHipAngles", "LKneeAngles",
    "RKneeAngles", "LAnkleAngles", "RAnkleAngles", "LFootProgressAngles", "RFootProgressAngles",
)  # fmt: skip
#: The CGM 2.4 forefoot angle outputs (forefoot relative to hindfoot), pyCGM2's names.
FOREFOOT_ANGLE_NAMES: tuple[str, ...] = ("LForeFootAngles", "RForeFootAngles")
#: Every angle output a model version can produce, in output order.
ALL_ANGLE_NAMES: tuple[str, ...] = ANGLE_NAMES + FOREFOOT_ANGLE_NAMES

#: Angle output -> (proximal, distal) segment whose markers it needs.
_ANGLE_SEGMENT = {
    "Pelvis": "pelvis", "Hip": "thigh", "Knee": "tibia", "Ankle": "foot", "FootProgress": "foot",
}  # fmt: skip


@dataclass
class CGMResult:
    """Output of :func:`compute_lower_body`.

    Attributes:
        angles: output name (:data:`ANGLE_NAMES`) -> ``(n_frames, 3)`` degrees; X/Y/Z =
            sagittal/frontal/transverse with Plug-in Gait signs; NaN where an input
            sample is missing.  Angles that cannot be computed at all are absent (see
            ``unavailable``).
        joint_centres: ``"LHJC"``, ``"RHJC"``, ``"LKJC"``, ``"RKJC"``, ``"LAJC"``,
            ``"RAJC"`` -> ``(n_frames, 3)`` mm, lab frame.
        segment_frames: ``"pelvis"``, ``"left_thigh"``, ``"left_tibia"`` (untorsioned),
            ``"left_tibia_torsioned"``, ``"left_foot"`` (Plug-in Gait orientation: z
            along the foot backwards, x dorsal) and the right-side equivalents ->
            ``(n_frames, 3, 3)`` rotations whose columns are the axes in lab coordinates.
        virtual_markers: Vicon-style segment markers (``PELO``..., ``LFEO``..., ``LTIO``...,
            ``LFOO``..., ``LTOO``...) and the joint centres, ``(n_frames, 3)`` mm.
        unavailable: angle name -> why it could not be computed (names the missing
            markers).
        progression: ``(3, 3)`` progression frame (columns forward, left, up in lab
            coordinates) of the pelvis and foot-progression angles.
        notes: findings on the computation (measured parameters, ignored parameters...).
        model: the model version that computed it (``"cgm1.0"``, ``"cgm2.3"``, ...).
    """

    angles: dict[str, np.ndarray] = field(default_factory=dict)
    joint_centres: dict[str, np.ndarray] = field(default_factory=dict)
    segment_frames: dict[str, np.ndarray] = field(default_factory=dict)
    virtual_markers: dict[str, np.ndarray] = field(default_factory=dict)
    unavailable: dict[str, str] = field(default_factory=dict)
    progression: np.ndarray = field(default_factory=lambda: np.full((3, 3), np.nan))
    notes: list[Finding] = field(default_factory=list)
    model: str = "cgm1.0"


def angle_segments(chain: LowerBodyChain, name: str, progression: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (proximal, distal) frames whose relative rotation is the angle ``name``.

    Args:
        chain: the lower-body chain of a trial.
        name: one of :data:`ANGLE_NAMES`.
        progression: ``(3, 3)`` progression frame (pelvis and foot-progression angles).
    """
    side, joint = name[0], name[1:].removesuffix("Angles")
    if joint in ("Pelvis", "PelvisROT"):
        return progression, chain.pelvis()[1]
    if joint == "Hip":
        return chain.pelvis()[1], chain.thigh(side)
    if joint == "Knee":
        return chain.thigh(side), chain.tibia(side)
    if joint == "Ankle":
        return chain.ankle_tibia(side), chain.foot(side)
    if joint == "FootProgress":
        return progression, chain.foot(side)
    if joint == "ForeFoot" and isinstance(chain, ClusterChain):
        return chain.foot(side), chain.forefoot(side)
    raise KeyError(f"unknown angle {name!r}")


def angle_from_chain(chain: LowerBodyChain, name: str, progression: np.ndarray) -> np.ndarray:
    """Angle ``name`` (``(n_frames, 3)`` degrees, Plug-in Gait conventions) of ``chain``."""
    proximal, distal = angle_segments(chain, name, progression)
    joint = name[1:].removesuffix("Angles")
    if joint == "Pelvis" and chain.pelvis_sequence == "ROT":
        joint = "PelvisROT"
    return joint_angles(proximal, distal, joint, name[0])


def angle_markers(trial: Trial, name: str, use_medial_markers: bool = False) -> list[str]:
    """The markers the angle ``name`` depends on (its segments and the chain above)."""
    return segment_markers(trial, _ANGLE_SEGMENT[name[1:].removesuffix("Angles")], name[0], use_medial_markers)


def _missing_reason(missing: list[str]) -> str:
    return f"marker{'s' if len(missing) > 1 else ''} {', '.join(missing)} missing"


def model_chain(
    trial: Trial,
    subject: SubjectParameters,
    model: str = "cgm1.0",
    clusters: ClusterCalibration | None = None,
    *,
    use_medial_markers: bool = False,
    static_foot: str | None = None,
) -> LowerBodyChain:
    """The chain of model version ``model`` on ``trial``: Plug-in Gait's with the
    version's hip regression, tibia and pelvis sequence, or for ``cgm2.3``/``cgm2.4``
    the :class:`~fuzzygait.kinematics.clusters.ClusterChain` of the static ``clusters``.

    Raises:
        ParameterError: an unknown model, a cluster model without ``clusters`` or
            ``cgm2.4`` without the forefoot calibration.
    """
    version = model_version(model)
    if not version.clusters:
        return LowerBodyChain(trial, subject, use_medial_markers=use_medial_markers, static_foot=static_foot,
                              hip=version.hip, single_tibia=version.single_tibia,
                              pelvis_sequence=version.pelvis_sequence)  # fmt: skip
    if clusters is None:
        raise ParameterError(
            f"{version.name} tracks the thigh and shank clusters calibrated on a static trial; "
            f"give the static trial ({Option.STATIC}) or its cluster calibration"
        )
    if version.forefoot and not clusters.has_forefoot:
        raise ParameterError(
            f"{version.name} needs the forefoot calibrated on the static trial (FMH, SMH, VMH, TOE); "
            "calibrate with the cgm2.4 model, or use cgm2.3"
        )
    return ClusterChain(trial, subject, clusters, foot_torsion=version.foot_torsion)


#: The note of a run with the knee and ankle centres at the medial/lateral midpoints.
MEDIAL_NOTE = "knee and ankle joint centres at the medial/lateral marker midpoints (CGM 2.x style)"


def compute_lower_body(
    trial: Trial,
    subject: SubjectParameters,
    *,
    use_medial_markers: bool | None = None,
    static_foot: str | None = None,
    model: str = "cgm1.0",
    clusters: ClusterCalibration | None = None,
) -> CGMResult:
    """Run the Plug-in Gait lower-body model on every frame of ``trial``.

    Markers: LASI, RASI and SACR (or LPSI + RPSI); per side THI, KNE, TIB, ANK, TOE (HEE
    only for the foot virtual markers).  Missing markers do not raise: the angles that
    need them go to :attr:`CGMResult.unavailable` and everything else is computed.
    Frames where a marker is NaN give NaN outputs (no gap filling here).

    Args:
        trial: markers in mm.
        subject: subject parameters (lengths mm, angles rad) including the static offsets
            (see :func:`~fuzzygait.kinematics.static.static_calibration`).  When
            ``inter_asis_distance`` is None it is measured on this trial.
        use_medial_markers: True to place KJC / AJC at the KNE-KNM / ANK-MED midpoints
            (CGM 2.x style; Plug-in Gait ignores medial markers).  None or False: the
            Plug-in Gait chord construction.
        static_foot: None for a dynamic trial (the foot from the static offsets).  For
            the outputs Nexus stores in a *static* trial, ``"heel"`` (foot flat off) or
            ``"flat"`` (foot flat on): the foot is then built from HEE and TOE, HEE
            levelled to TOE + ``SoleDelta`` for ``"flat"`` (see
            :mod:`fuzzygait.kinematics.chain`); the static offsets are not used.  A
            static trial with a knee alignment device then uses the KAD (and MED)
            knee and ankle centres of :mod:`fuzzygait.kinematics.kad` and exports the
            virtual ``L/RKNE``.
        model: the model version (:mod:`fuzzygait.kinematics.versions`): ``"cgm1.0"``
            (Plug-in Gait), ``"cgm1.1"``, ``"cgm2.1"`` (Hara hip centres), ``"cgm2.3"``
            (thigh and shank tracked by their clusters; needs ``clusters``) or
            ``"cgm2.4"`` (also the forefoot: ``L/RForeFootAngles`` and ``L/RFJC``; needs
            ``clusters`` calibrated with ``forefoot=True``).
        clusters: the static trial's :func:`~fuzzygait.kinematics.clusters.calibrate_clusters`
            (``cgm2.3``, ``cgm2.4``).

    Raises:
        ParameterError: implausible subject parameters (names them), an unknown model,
            a cluster model without ``clusters`` or ``cgm2.4`` without the forefoot
            calibration.
    """
    subject.validate()
    version = model_version(model)
    medial = bool(use_medial_markers)
    chain = model_chain(trial, subject, version.name, clusters, use_medial_markers=medial, static_foot=static_foot)
    if static_foot is not None and knee_method(trial) != "plain" and version.name == "cgm1.0":
        chain = StaticKneeChain(trial, subject, static_foot=static_foot)
    result = CGMResult(model=version.name)
    if medial:
        result.notes.append(Finding(FindingKind.KINEMATICS, MEDIAL_NOTE))

    missing_pelvis = chain.missing("pelvis")
    if missing_pelvis:
        for name in ANGLE_NAMES:
            result.unavailable[name] = _missing_reason(missing_pelvis)
        return result
    if subject.inter_asis_distance is None:
        measured = f"InterAsisDistance measured on this trial: {chain.inter_asis_distance():.2f} mm"
        result.notes.append(Finding(FindingKind.SUBJECT, measured))

    origin, pelvis = chain.pelvis()
    hjc = {side: chain.hjc(side) for side in "LR"}
    result.segment_frames["pelvis"] = pelvis
    result.virtual_markers.update(vm.pelvis_markers(hjc["L"], hjc["R"], pelvis))
    try:
        result.progression = progression_frame(0.5 * (hjc["L"] + hjc["R"]), pelvis[:, :, 0])
    except FuzzyGaitError as exc:
        result.notes.append(Finding(FindingKind.KINEMATICS, f"no progression frame ({exc}); pelvis and foot "
                                    "progression angles are NaN", Severity.WARNING))  # fmt: skip

    for side in "LR":
        _add_side(chain, side, result, hjc[side], version, subject, trial, static_foot)

    result.virtual_markers.update(result.joint_centres)
    result.angles = {name: result.angles[name] for name in ALL_ANGLE_NAMES if name in result.angles}
    return result


def _add_side(chain: LowerBodyChain, side: str, result: CGMResult, hjc: np.ndarray, version: ModelVersion,
              subject: SubjectParameters, trial: Trial, static_foot: str | None) -> None:  # fmt: skip
    """One side's outputs (``side`` ``"L"`` or ``"R"``) into ``result``: its pelvis angles,
    then as far as its markers allow the thigh (hip angles), the tibia (knee angles) and
    the foot (:func:`_add_foot`); ``hjc`` is the side's hip joint centre (mm)."""
    long = "left" if side == "L" else "right"
    result.joint_centres[side + "HJC"] = hjc
    result.angles[side + "PelvisAngles"] = angle_from_chain(chain, side + "PelvisAngles", result.progression)
    for name, segment in _ANGLE_SEGMENT.items():
        missing = chain.missing(segment, side)
        if missing and segment != "pelvis":
            result.unavailable[side + name + "Angles"] = _missing_reason(missing)
    if chain.missing("thigh", side):
        return
    if isinstance(chain, ClusterChain):
        tracked = ("thigh", "tibia") + (("forefoot",) if version.forefoot else ())
        result.notes += cluster_tracking_notes(chain, side, tracked)
    kjc, thigh = chain.kjc(side), chain.thigh(side)
    result.joint_centres[side + "KJC"] = kjc
    result.segment_frames[long + "_thigh"] = thigh
    result.virtual_markers.update(vm.thigh_markers(side, hjc, kjc, thigh))
    if isinstance(chain, StaticKneeChain):  # Nexus exports the KAD's virtual knee marker
        result.virtual_markers[side + "KNE"] = chain.marker(side + "KNE")
    result.angles[side + "HipAngles"] = angle_from_chain(chain, side + "HipAngles", result.progression)
    if chain.missing("tibia", side):
        return
    ajc, tibia = chain.ajc(side), chain.tibia(side)
    result.joint_centres[side + "AJC"] = ajc
    result.segment_frames[long + "_tibia"] = tibia
    result.segment_frames[long + "_tibia_torsioned"] = chain.torsioned_tibia(side)
    knee_width = subject.side(side).knee_width
    result.virtual_markers.update(vm.tibia_markers(side, kjc, ajc, tibia, knee_width))
    result.angles[side + "KneeAngles"] = angle_from_chain(chain, side + "KneeAngles", result.progression)
    _add_foot(chain, side, result, ajc, version, subject, trial, static_foot)


def _add_foot(chain: LowerBodyChain, side: str, result: CGMResult, ajc: np.ndarray, version: ModelVersion,
              subject: SubjectParameters, trial: Trial, static_foot: str | None) -> None:  # fmt: skip
    """The foot of one side: ankle and foot progression angles, the CGM 2.4 forefoot and
    the foot's virtual markers (``ajc``: the side's ankle joint centre, mm)."""
    long = "left" if side == "L" else "right"
    if chain.missing("foot", side):
        return
    if static_foot is not None and not trial.has_marker(side + "HEE"):
        for name in ("AnkleAngles", "FootProgressAngles"):
            result.unavailable[side + name] = _missing_reason([side + "HEE"]) + " (static-trial foot)"
        return
    foot = chain.foot(side)
    result.segment_frames[long + "_foot"] = foot
    for name in ("AnkleAngles", "FootProgressAngles"):
        result.angles[side + name] = angle_from_chain(chain, side + name, result.progression)
    if version.forefoot and isinstance(chain, ClusterChain):
        _add_forefoot(chain, side, result)
    if trial.has_marker(side + "HEE"):
        hee, toe = trial.marker(side + "HEE"), trial.marker(side + "TOE")
        length = vm.foot_bone_length(hee, toe, subject.marker_radius)
        result.virtual_markers.update(vm.foot_markers(side, ajc, foot, length))
    else:
        result.notes.append(Finding(FindingKind.KINEMATICS, f"no {side}HEE marker: {side}FO*/{side}TO* virtual "
                                    "markers not produced", Severity.WARNING, side=long,
                                    marker=side + "HEE"))  # fmt: skip


def _frame_ranges(mask: np.ndarray, first_frame: int) -> str:
    """``"51-120, 300"``: the C3D frame numbers where ``mask`` is True, as ranges."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    ranges = [(first_frame + a, first_frame + b - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in ranges)


def cluster_tracking_notes(chain: ClusterChain, side: str, segments: tuple[str, ...]) -> list[Finding]:
    """Per cluster segment of ``side``, the C3D frames where a calibrated tracking marker is
    not seen (the pose from the others) and where fewer than three are (no pose, NaN)."""
    notes: list[Finding] = []
    long = "left" if side == "L" else "right"
    for name in segments:
        cluster = chain.calibration.segment(side, name)
        present = [m for m in cluster.markers if chain.trial.has_marker(m)]
        if len(present) < MIN_MARKERS:
            continue
        fit = chain.fit(side + name)
        seen = np.zeros((chain.trial.n_frames, len(cluster.markers)), dtype=bool)
        seen[:, [cluster.markers.index(m) for m in present]] = fit.visible
        too_few = seen.sum(axis=1) < MIN_MARKERS
        for k, marker in enumerate(cluster.markers):
            hidden = ~seen[:, k] & ~too_few
            if marker in present and hidden.any():
                frames = _frame_ranges(hidden, chain.trial.first_frame)
                notes.append(Finding(FindingKind.KINEMATICS, f"{long} {name}: {marker} not seen in frames {frames}; "
                                     "tracked by the other markers there", side=long, segment=f"{long} {name}",
                                     marker=marker))  # fmt: skip
        if too_few.any():
            frames = _frame_ranges(too_few, chain.trial.first_frame)
            notes.append(Finding(FindingKind.KINEMATICS, f"{long} {name}: fewer than {MIN_MARKERS} markers seen in "
                                 f"frames {frames}; no pose there (NaN)", Severity.WARNING, side=long,
                                 segment=f"{long} {name}"))  # fmt: skip
    return notes


def _add_forefoot(chain: ClusterChain, side: str, result: CGMResult) -> None:
    """The CGM 2.4 forefoot of ``side``: ``ForeFootAngles``, the FJC and the forefoot
    frame, or why not (the forefoot markers missing)."""
    name = side + "ForeFootAngles"
    missing = chain.missing("forefoot", side)
    if missing:
        result.unavailable[name] = _missing_reason(missing)
        return
    result.joint_centres[side + "FJC"] = chain.fjc(side)
    result.segment_frames[("left" if side == "L" else "right") + "_forefoot"] = chain.forefoot(side)
    result.angles[name] = angle_from_chain(chain, name, result.progression)
