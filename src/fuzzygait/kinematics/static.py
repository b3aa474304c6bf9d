"""Plug-in Gait static calibration: foot offsets and (if not given) inter-ASIS distance.

The dynamic foot frame is built from the TOE marker and the ankle joint centre only; the
static trial tells how that "uncorrected" foot is turned relative to the anatomical
foot, whose long axis runs from TOE to HEE (Plug-in Gait "foot flat" off) or from TOE to
HEE brought to the height of TOE + SoleDelta in the laboratory vertical (foot flat on:
the sole is parallel to the floor, apart from a heel raise of ``SoleDelta`` mm) — the
z axis of the chain's heel foot (:meth:`~fuzzygait.kinematics.chain.LowerBodyChain.heel_foot`,
the foot Nexus reports in the static trial itself).  The offsets ``StaticPlantFlex``
and ``StaticRotOff`` (rad) are the angles of that long axis in the uncorrected foot
frame (see :func:`~fuzzygait.kinematics.segments.foot_offsets`), computed per frame and
averaged over the frames where every marker is seen.  This reproduces the values Vicon
Nexus stores in ``L/RStaticPlantFlex`` and ``L/RStaticRotOff`` to better than 1e-6 rad
(Nexus 2 ``Static_trial.c3d``, flat foot off: 8e-9 rad; Nexus 1.4
``PiG_Calibration-FlatFoot-Full.c3d``, flat foot on, 16 mm markers: 4e-8 rad).

The inter-ASIS distance, when the subject file has none, is the distance between the
mean LASI and the mean RASI positions over those frames (inferred from Nexus' stored
``InterAsisDistance``: it reproduces the float32 value of ``PiGKad_Calibration.c3d``
exactly and that of ``PiG_Calibration-FlatFoot-Full.c3d`` within 2.3e-4 mm, where the
mean of the per-frame distances is 5.6e-3 mm off).

With a knee alignment device (``L/RKAX``, ``L/RKD1``, ``L/RKD2``) and optionally medial
malleolus markers (``L/RMED``) in the static trial (:func:`~fuzzygait.kinematics.kad.knee_method`
tells which), the knee and ankle centres come from them and the calibration also gives
``ThighRotation``, ``ShankRotation``, ``AnkleAbAdd`` and, with MED, ``TibialTorsion``
(see :mod:`fuzzygait.kinematics.kad`); the foot offsets then use that chain.

A cluster model (``cgm2.3``, ``cgm2.4``) calibrated with KNM/MED (rule ``"medial"``)
reports its tibial torsion as ``TibialTorsion``: pyCGM2's static angle between the
thigh's and the tibia's flexion axes about the tibia's long axis
(:func:`~fuzzygait.kinematics.clusters.static_tibial_torsion`), which has Plug-in Gait's
meaning and sign (``-s`` × the angle from the knee axis to the ankle axis about
``AJC -> KJC``).  What it does differs: Plug-in Gait's knee angles untwist the tibia by
it and its dynamic foot takes the untwisted axis without correction; CGM 2.x's knee and
ankle keep the marker-based tibia and only CGM 2.3's foot takes the turned axis, with a
static correction (:mod:`fuzzygait.kinematics.clusters`).  The foot offsets are
calibrated on the marker-based tibia's axis in every model, as before.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fuzzygait.core.errors import MarkerError, ParameterError
from fuzzygait.core.options import Option
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.chain import LowerBodyChain, required_markers
from fuzzygait.kinematics.clusters import static_tibial_torsion
from fuzzygait.kinematics.kad import KAD_MARKERS, StaticKneeChain, check_kad, check_medial_malleolus, knee_method
from fuzzygait.kinematics.knee_ankle import RULE_MARKERS, calibration_chain, knee_ankle_rule
from fuzzygait.kinematics.segments import foot_offsets
from fuzzygait.kinematics.vectors import unit
from fuzzygait.kinematics.versions import model_version

#: The offsets (rad) a static calibration computes: ``SideParameters`` field -> Vicon
#: ``PROCESSING`` name (after the side letter).
CALIBRATED_OFFSETS = {
    "thigh_rotation": "ThighRotation",
    "shank_rotation": "ShankRotation",
    "tibial_torsion": "TibialTorsion",
    "ankle_abadd": "AnkleAbAdd",
    "static_plant_flex": "StaticPlantFlex",
    "static_rot_off": "StaticRotOff",
}

#: Largest angle (degrees) between the standing legs (mean AJC -> HJC direction) and lab
#: +Z the foot-flat calibration accepts: a standing subject's legs are within a few
#: degrees of the vertical; a trial exported with another axis up (Y-up lab) or a
#: subject lying down is 90 degrees off.
MAX_LEG_TILT_DEG = 30.0


def check_upright(static: Trial, chain: LowerBodyChain, seen: np.ndarray) -> None:
    """Raise :class:`ParameterError` when the subject does not stand along lab +Z.

    Only the foot-flat option needs it: it levels HEE along the lab vertical, so with
    another axis up its ``StaticPlantFlex``/``StaticRotOff`` are wrong.  A subject turned
    about the vertical (facing 45 degrees between the lab axes, or any direction) is
    *not* refused: every calibrated value is a relative angle or a distance, unchanged by
    such a turn (measured on ``sample_data/static.c3d`` turned by 20, 45, 90, 135 and 180
    degrees: identical to 1e-12 rad); only the static trial's own pelvis and
    foot-progression angles refer to the lab axis nearest to where the pelvis faces, as
    Nexus' do.
    """
    legs = np.mean([unit(chain.hjc(side) - chain.ajc(side))[seen].mean(axis=0) for side in "LR"], axis=0)
    tilt = float(np.degrees(np.arccos(np.clip(unit(legs[None])[0, 2], -1.0, 1.0))))
    if tilt > MAX_LEG_TILT_DEG:
        raise ParameterError(
            f"{static.name}: the subject's legs are {tilt:.0f} deg from the lab's +Z axis, but the foot-flat "
            "option levels the heel along lab Z; export the static trial with Z up (or calibrate without foot flat)"
        )


def calibration_markers(static: Trial, method: str, rule: str) -> list[str]:
    """Every marker the static calibration needs: Plug-in Gait's with HEE, the KAD in place
    of KNE (``method`` ``"KAD"``, ``"KAD+MED"``), MED with the latter, and the markers of
    the knee/ankle centre ``rule`` (:data:`~fuzzygait.kinematics.knee_ankle.RULE_MARKERS`).

    Raises:
        MarkerError: any of them absent from ``static`` (all of them named).
    """
    labels = required_markers(static, use_medial_markers=False) + ["LHEE", "RHEE"]
    if method != "plain":
        labels = [m for m in labels if m[1:] != "KNE"] + [side + m for side in "LR" for m in KAD_MARKERS]
    if method == "KAD+MED":
        labels += ["LMED", "RMED"]
    labels += [side + m for side in "LR" for m in RULE_MARKERS.get(rule, ())]
    missing = [m for m in labels if not static.has_marker(m)]
    if missing:
        raise MarkerError(
            f"{static.name}: static calibration needs marker(s) {', '.join(missing)}; "
            "label them in the static trial"
        )
    return labels


def static_calibration(
    static: Trial,
    subject: SubjectParameters,
    *,
    flat_foot: bool = False,
    model: str = "cgm1.0",
    knee_ankle_centres: str | None = None,
) -> SubjectParameters:
    """Calibrate the foot offsets (and the inter-ASIS distance if unknown) on a static trial.

    Args:
        static: standing trial with the Plug-in Gait lower-body markers (HEE included).
        subject: subject parameters (static offsets in it are ignored).
        flat_foot: Plug-in Gait's "foot flat" option: the sole is taken as parallel to the
            floor (HEE is moved to the height of TOE + ``SoleDelta`` along lab Z).
        model: the model version whose foot is calibrated (:mod:`fuzzygait.kinematics.versions`):
            CGM 1.1+ take the foot's ankle axis from the one (torsioned) tibia, CGM 2.x
            the Hara hip centres and, for ``cgm2.3`` with KNM/MED in the static trial,
            the knee/ankle centres on the medial lines.  The knee alignment device is
            Plug-in Gait's (``cgm1.0``) only.
        knee_ankle_centres: a cluster model's knee/ankle centre rule (``"medial"``,
            ``"chord"``, ``"pycgm2"``; None: medial with KNM/MED, else chord), as its
            cluster calibration's (:mod:`fuzzygait.kinematics.knee_ankle`); the other
            models use the chord.

    Returns:
        A copy of ``subject`` with ``static_plant_flex`` and ``static_rot_off`` (rad) set
        on both sides and, when it was None, ``inter_asis_distance`` = the distance (mm)
        between the mean LASI and RASI positions of the static trial.  With a KAD also
        ``thigh_rotation``, ``shank_rotation`` and ``ankle_abadd`` (0 without MED) and,
        with MED, ``tibial_torsion`` (rad, :mod:`fuzzygait.kinematics.kad`).  A cluster
        model with the ``"medial"`` rule (KNM/MED) also sets ``tibial_torsion`` (rad,
        module docstring); otherwise the subject's is kept.

    Raises:
        MarkerError: a needed marker is absent from the trial (all of them named), an
            incomplete or implausible KAD, or a medial marker on the lateral side.
        ParameterError: implausible subject parameters, no frame with every marker, or
            with ``flat_foot`` a subject not standing along lab +Z (:func:`check_upright`;
            a subject turned about the vertical is calibrated as any other).
    """
    subject.validate()
    version = model_version(model)
    method = knee_method(static)
    rule = knee_ankle_rule(static, knee_ankle_centres)  # an unknown rule first: it lists the known ones
    if not version.clusters and knee_ankle_centres not in (None, "chord"):
        raise ParameterError(
            f"{version.name} places the knee and ankle centres by the chord; "
            f"knee/ankle centres {knee_ankle_centres!r} are a cluster model's (cgm2.3, cgm2.4)"
        )
    rule = rule if version.clusters else "chord"
    if method != "plain" and version.name != "cgm1.0":
        raise ParameterError(
            f"{static.name}: the knee alignment device calibration is Plug-in Gait's; use {Option.MODEL} cgm1.0 "
            f"(not {version.name}) or a static trial with KNM/MED"
        )
    labels = calibration_markers(static, method, rule)
    columns = [static.marker_labels.index(m) for m in labels]
    visible = np.all(np.isfinite(static.markers[:, columns, :]), axis=2)  # (frame, marker)
    seen = np.all(visible, axis=1)
    if not seen.any():
        raise ParameterError(f"{static.name}: no frame shows every calibration marker: {_unseen(labels, visible)}; "
                             "label or gap-fill them in the static trial")  # fmt: skip
    calibrated = subject
    if subject.inter_asis_distance is None:
        iad = float(np.linalg.norm(static.marker("LASI")[seen].mean(0) - static.marker("RASI")[seen].mean(0)))
        calibrated = replace(subject, inter_asis_distance=iad).validate()

    static_foot = "flat" if flat_foot else "heel"
    chain: LowerBodyChain = calibration_chain(static, calibrated, rule, static_foot=static_foot, hip=version.hip,
                                              single_tibia=version.single_tibia)  # fmt: skip
    if method != "plain":
        knee_chain = StaticKneeChain(static, calibrated, static_foot=static_foot)
        for side in "LR":
            check_kad(static, side)
            if knee_chain.medial_malleoli:
                check_medial_malleolus(knee_chain, side, seen)
            calibrated = calibrated.with_side(side, **knee_chain.offsets(side, seen))
        chain = knee_chain
    if flat_foot:
        check_upright(static, chain, seen)
    return with_foot_offsets(calibrated, chain, seen, torsion=version.clusters and rule == "medial")


def _unseen(labels: list[str], visible: np.ndarray) -> str:
    """Which of ``labels`` keep a static trial from a frame showing them all (``visible``:
    ``(frame, marker)`` True where seen): those never seen, else those seen least."""
    counts = visible.sum(axis=0)
    never = [m for m, c in zip(labels, counts, strict=True) if c == 0]
    if never:
        return f"{', '.join(never)} {'is' if len(never) == 1 else 'are'} missing in every frame"
    fewest = sorted((int(c), m) for m, c in zip(labels, counts, strict=True) if c < visible.shape[0])
    return ("every marker is seen somewhere but never all at once; seen least: "
            f"{', '.join(f'{m} in {c} of {visible.shape[0]} frames' for c, m in fewest[:4])}")  # fmt: skip


def with_foot_offsets(
    subject: SubjectParameters, chain: LowerBodyChain, seen: np.ndarray, torsion: bool = False
) -> SubjectParameters:
    """``subject`` with both sides' ``static_plant_flex`` and ``static_rot_off`` (rad) of the
    static ``chain`` (means over the frames ``seen``) and, with ``torsion`` (a cluster
    model calibrated with KNM/MED), ``tibial_torsion`` (rad, module docstring)."""
    for side in "LR":
        if torsion:
            subject = subject.with_side(side, tibial_torsion=static_tibial_torsion(chain, side))
        offsets = foot_offsets(chain.uncorrected_foot(side), chain.heel_foot(side)[:, :, 2], side)
        plantar_flex, rot_off = np.mean(offsets[seen], axis=0)
        subject = subject.with_side(side, static_plant_flex=float(plantar_flex), static_rot_off=float(rot_off))
    return subject.validate()
