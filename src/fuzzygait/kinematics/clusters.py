"""CGM 2.3 thigh and shank tracked by their marker clusters.

Static calibration (:func:`calibrate_clusters`): the static trial's anatomical frames
are built as in :class:`~fuzzygait.kinematics.chain.LowerBodyChain` (Hara hip centres;
the knee/ankle centres by the rule ``knee_ankle_centres`` of
:mod:`fuzzygait.kinematics.knee_ankle`: on the KNE-KNM / ANK-MED lines, Plug-in Gait's
chord, or pyCGM2's chord with THAP/TIAP).  Each tracking marker's position is expressed in its segment's anatomical
frame (thigh: origin KJC; shank: the torsioned tibia, origin AJC) and averaged over the
static frames (CGM 2.x has one tibia frame, the torsioned one, for knee, ankle and
foot).  The anatomical frame *is* the technical frame: a separate marker-built
technical frame would be an intermediate rotation that cancels.

Dynamic trials (:class:`ClusterChain`): per frame, the weighted least-squares rigid fit
(:func:`~fuzzygait.kinematics.rigid.fit_rigid`) of every visible tracking marker of the
segment to its calibrated position gives the anatomical frame and its origin (KJC,
AJC) directly; at least three visible markers are needed, else the frame is NaN.  The
pelvis and the (hind)foot are Plug-in Gait's.  CGM 2.4 adds the forefoot, calibrated and
tracked the same way from TOE, FMH, SMH and VMH (:mod:`fuzzygait.kinematics.forefoot`).

Tibial torsion (static trial with KNM/MED, rule ``"medial"``): as pyCGM2 calibrates it
when the static trial has the medial malleolus (its ``getTibialTorsionOffset``), the
torsion is the static angle between the thigh's and the tibia's flexion axes about the
tibia's long axis (:func:`~fuzzygait.kinematics.segments.flexion_axis_torsion`, mean over
the static frames), stored with the CGM 2.3 foot's static correction
(:func:`~fuzzygait.kinematics.segments.foot_axis_correction`) as the side's
:class:`ShankTorsion`.  CGM 2.3's uncorrected foot is then built on the untorsioned
tibia's y axis and turned about its long axis by that correction (pyCGM2 builds it on
its "proximal shank" and multiplies it by the static ``R_prox^T R_dist``;
:func:`~fuzzygait.kinematics.segments.turned_uncorrected_foot`);
knee and ankle angles keep the torsioned tibia (pyCGM2's CGM 2.x knee and ankle both use
its "Shank").  pyCGM2's CGM 2.4 hindfoot is built on the torsioned tibia's own axis in
the static and in the dynamic trials (its ``_hindFoot_calibrate`` / ``_hindFoot_motion``),
so ``ClusterChain(..., foot_torsion=False)`` (cgm2.4) leaves it as without MED.  Without
MED (rules ``"chord"``, ``"pycgm2"``) there is no :class:`ShankTorsion` and the foot is
today's Plug-in Gait foot on the torsioned tibia's axis.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import autograd.numpy as anp
import numpy as np

from fuzzygait.core.errors import MarkerError
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.chain import LowerBodyChain, _memo
from fuzzygait.kinematics.forefoot import calibrate_forefoot
from fuzzygait.kinematics.knee_ankle import calibration_chain, knee_ankle_rule
from fuzzygait.kinematics.rigid import MIN_MARKERS, RigidFit, fit_rigid
from fuzzygait.kinematics.segments import flexion_axis_torsion, foot_axis_correction, turned_uncorrected_foot
from fuzzygait.kinematics.vectors import to_lab, to_local

#: Tracking markers per segment (after the side letter), CGM 2.3.
CLUSTERS: dict[str, tuple[str, ...]] = {
    "thigh": ("THI", "THAP", "THAD", "KNE"),
    "tibia": ("TIB", "TIAP", "TIAD", "ANK"),
}


@dataclass(frozen=True)
class SegmentCluster:
    """One segment's calibrated cluster.

    Attributes:
        markers: tracking marker labels (with the side letter) seen in the static trial.
        local: ``(m, 3)`` mm, their positions in the segment's anatomical frame.
    """

    markers: tuple[str, ...]
    local: np.ndarray


@dataclass(frozen=True)
class ShankTorsion:
    """One side's tibial torsion as a CGM 2.3+ static trial with MED calibrates it.

    Attributes:
        tibial_torsion: rad, :func:`~fuzzygait.kinematics.segments.flexion_axis_torsion`
            (the subject's ``TibialTorsion``: Nexus' sign, negative = external).
        foot_correction: rad, the CGM 2.3 foot's static correction ``δ``
            (:func:`~fuzzygait.kinematics.segments.foot_axis_correction`).
    """

    tibial_torsion: float
    foot_correction: float


@dataclass(frozen=True)
class ClusterCalibration:
    """A static trial's cluster calibration (everything a dynamic trial needs besides the
    subject parameters).

    Attributes:
        segments: ``(side, "thigh"|"tibia"|"forefoot")`` -> the segment's calibrated
            cluster (``"forefoot"``: CGM 2.4 only; its frame is pyCGM2's forefoot
            anatomical frame, origin vSMH).
        forefoot_joint_centres: side -> the CGM 2.4 forefoot joint centre (FJC), ``(3,)``
            mm in the hindfoot (Plug-in Gait foot) frame, origin AJC (CGM 2.4 only).
        shank_torsions: side -> its :class:`ShankTorsion`, calibrated with KNM/MED only
            (empty otherwise: no torsion, the foot on the torsioned tibia's own axis).
    """

    segments: dict[tuple[str, str], SegmentCluster]
    forefoot_joint_centres: dict[str, np.ndarray] = field(default_factory=dict)
    shank_torsions: dict[str, ShankTorsion] = field(default_factory=dict)

    def segment(self, side: str, name: str) -> SegmentCluster:
        return self.segments[(side, name)]

    @property
    def has_forefoot(self) -> bool:
        """Both CGM 2.4 forefoots are calibrated."""
        return all((side, "forefoot") in self.segments for side in "LR")


def _mean_local(frame: np.ndarray, origin: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Mean over the frames seen of ``points`` in ``frame`` at ``origin`` (``(3,)`` mm)."""
    local = to_local(frame, origin, points)
    seen = np.all(np.isfinite(local), axis=1)
    if not seen.any():
        return np.full(3, np.nan)
    return np.asarray(local[seen].mean(axis=0))


def _finite_mean(values: np.ndarray) -> float:
    finite = np.isfinite(values)
    return float(values[finite].mean()) if finite.any() else float("nan")


def static_tibial_torsion(chain: LowerBodyChain, side: str) -> float:
    """The static trial's tibial torsion (rad): the mean over its frames of
    :func:`~fuzzygait.kinematics.segments.flexion_axis_torsion` of ``chain``'s thigh and
    torsioned tibia (``chain``: the static calibration chain, Hara hips, KNM/MED centres)."""
    return _finite_mean(flexion_axis_torsion(chain.thigh(side), chain.torsioned_tibia(side), side))


def calibrate_shank_torsion(chain: LowerBodyChain, side: str) -> ShankTorsion:
    """One side's :class:`ShankTorsion` on the static trial's ``chain`` (module docstring).

    Raises:
        MarkerError: the side's TOE is not in the static trial, or no frame shows the
            thigh, the tibia and TOE together.
    """
    torsion = static_tibial_torsion(chain, side)
    tibia = chain.torsioned_tibia(side)
    correction = _finite_mean(foot_axis_correction(chain.ajc(side), chain.marker(side + "TOE"), tibia, torsion, side))
    if not (np.isfinite(torsion) and np.isfinite(correction)):
        raise MarkerError(
            f"{chain.trial.name}: no static frame shows the {side} thigh, tibia (KNM/MED) and {side}TOE together; "
            "the tibial torsion needs them"
        )
    return ShankTorsion(torsion, correction)


def calibrate_clusters(
    static: Trial, subject: SubjectParameters, knee_ankle_centres: str | None = None, forefoot: bool = False
) -> ClusterCalibration:
    """Each thigh and shank tracking marker in its segment's anatomical frame of the static
    trial (module docstring).

    Args:
        static: the static trial, mm.
        subject: subject parameters (widths, leg lengths, marker diameter).
        knee_ankle_centres: ``"medial"`` (on the KNE-KNM / ANK-MED lines), ``"chord"``
            (Plug-in Gait's chord with THI/HJC, TIB/KJC) or ``"pycgm2"`` (the chord with
            THI/THAP, TIB/TIAP, as pyCGM2's CGM 2.3); None: medial when the static trial
            has KNM and MED on both sides, else chord
            (:mod:`fuzzygait.kinematics.knee_ankle`).
        forefoot: also calibrate the CGM 2.4 forefoots (:func:`~fuzzygait.kinematics.forefoot.calibrate_forefoot`;
            ``subject`` must then carry this static trial's foot offsets).

    With the ``"medial"`` rule the tibial torsion is calibrated too
    (:func:`calibrate_shank_torsion`, :attr:`ClusterCalibration.shank_torsions`).

    Raises:
        MarkerError: a segment with fewer than three tracking markers in the static trial
            (names the ones missing); with ``forefoot`` a forefoot marker missing; with
            the ``"medial"`` rule a TOE missing.
        ParameterError: an unknown ``knee_ankle_centres``.
    """
    rule = knee_ankle_rule(static, knee_ankle_centres)
    chain = calibration_chain(static, subject, rule, hip="hara", single_tibia=True)
    segments: dict[tuple[str, str], SegmentCluster] = {}
    forefoot_joint_centres: dict[str, np.ndarray] = {}
    torsions = {side: calibrate_shank_torsion(chain, side) for side in "LR"} if rule == "medial" else {}
    for side in "LR":
        frames = {
            "thigh": (chain.thigh(side), chain.kjc(side)),
            "tibia": (chain.torsioned_tibia(side), chain.ajc(side)),
        }
        for name, (frame, origin) in frames.items():
            labels = tuple(side + m for m in CLUSTERS[name] if static.has_marker(side + m))
            if len(labels) < MIN_MARKERS:
                lacking = [side + m for m in CLUSTERS[name] if not static.has_marker(side + m)]
                raise MarkerError(
                    f"{static.name}: the {side} {name} cluster needs {MIN_MARKERS} of "
                    f"{', '.join(side + m for m in CLUSTERS[name])}; {', '.join(lacking)} missing"
                )
            local = np.stack([_mean_local(frame, origin, static.marker(m)) for m in labels])
            segments[(side, name)] = SegmentCluster(labels, local)
        if forefoot:
            labels, local, fjc = calibrate_forefoot(static, side, chain.foot(side), chain.ajc(side),
                                                    subject.marker_diameter)  # fmt: skip
            segments[(side, "forefoot")] = SegmentCluster(labels, local)
            forefoot_joint_centres[side] = fjc
    return ClusterCalibration(segments, forefoot_joint_centres, torsions)


class ClusterChain(LowerBodyChain):
    """A dynamic trial's chain with cluster-tracked thighs and shanks (CGM 2.3).

    Args:
        trial: the dynamic trial, mm.
        subject: subject parameters (static foot offsets included; its ``tibial_torsion``
            is not read: the calibration's :class:`ShankTorsion` is).
        calibration: from :func:`calibrate_clusters` on the session's static trial.
        foot_torsion: build the foot on the ankle axis turned by the calibrated tibial
            torsion (CGM 2.3, :meth:`uncorrected_foot`); False: on the torsioned tibia's
            own axis whatever the calibration (pyCGM2's CGM 2.4 hindfoot).
    """

    def __init__(
        self, trial: Trial, subject: SubjectParameters, calibration: ClusterCalibration, foot_torsion: bool = True
    ):
        super().__init__(trial, subject, hip="hara", single_tibia=True, pelvis_sequence="ROT")
        self.calibration = calibration
        self.foot_torsion = foot_torsion

    def _cluster(self, side: str, name: str) -> tuple[SegmentCluster, list[str]]:
        cluster = self.calibration.segment(side, name)
        return cluster, [m for m in cluster.markers if self.trial.has_marker(m)]

    def missing(self, segment: str, side: str = "L") -> list[str]:
        """Markers of ``segment`` and the chain above it missing from the trial; a thigh or
        shank lacks markers when fewer than three of its calibrated tracking markers are
        in the trial."""
        lacking = super().missing("pelvis")
        if segment == "pelvis":
            return lacking
        for name in CLUSTERS:
            cluster, present = self._cluster(side, name)
            if len(present) < MIN_MARKERS:
                lacking += [m for m in cluster.markers if m not in present]
            if name == segment:
                return lacking
        lacking += [m for m in (side + "TOE",) if not self.trial.has_marker(m)]
        if segment == "forefoot":
            cluster, present = self._cluster(side, "forefoot")
            if len(present) < MIN_MARKERS:
                lacking += [m for m in cluster.markers if m not in present and m not in lacking]
        return lacking

    @_memo
    def fit(self, key: str) -> RigidFit:
        """The least-squares pose of cluster ``key`` = side + segment (``"Lthigh"``)."""
        side, name = key[0], key[1:]
        cluster, present = self._cluster(side, name)
        if len(present) < MIN_MARKERS:
            raise MarkerError(f"{self.trial.name}: the {side} {name} cluster has fewer than {MIN_MARKERS} markers")
        rows = [cluster.markers.index(m) for m in present]
        observed = anp.stack([self.marker(m) for m in present], axis=1)
        return fit_rigid(cluster.local[rows], observed)

    def kjc(self, side: str) -> np.ndarray:
        """Knee joint centre: the thigh cluster's anatomical origin, mm."""
        return self.fit(side + "thigh").origin

    def thigh(self, side: str) -> np.ndarray:
        """Thigh anatomical frame from the thigh cluster fit."""
        return self.fit(side + "thigh").rotation

    def ajc(self, side: str) -> np.ndarray:
        """Ankle joint centre: the shank cluster's anatomical origin, mm."""
        return self.fit(side + "tibia").origin

    def torsioned_tibia(self, side: str) -> np.ndarray:
        """Torsioned tibia (ankle axis) frame from the shank cluster fit."""
        return self.fit(side + "tibia").rotation

    @_memo
    def uncorrected_foot(self, side: str) -> np.ndarray:
        """Foot frame before the static offsets (z from TOE to AJC, x dorsal): with a
        calibrated :class:`ShankTorsion` and ``foot_torsion`` the CGM 2.3 foot on the
        ankle axis turned by the torsion, times the static correction
        (:func:`~fuzzygait.kinematics.segments.turned_uncorrected_foot`); otherwise
        Plug-in Gait's on the torsioned tibia's own y axis."""
        torsion = self.calibration.shank_torsions.get(side) if self.foot_torsion else None
        if torsion is None:
            return LowerBodyChain.uncorrected_foot(self, side)
        return turned_uncorrected_foot(self.ajc(side), self.marker(side + "TOE"), self.torsioned_tibia(side),
                                       torsion.tibial_torsion, torsion.foot_correction, side)  # fmt: skip

    def forefoot(self, side: str) -> np.ndarray:
        """CGM 2.4 forefoot anatomical frame (x dorsal, y left, z posterior) from the
        forefoot cluster fit."""
        return self.fit(side + "forefoot").rotation

    @_memo
    def fjc(self, side: str) -> np.ndarray:
        """CGM 2.4 forefoot joint centre, fixed in the hindfoot (Plug-in Gait foot), mm."""
        return to_lab(self.foot(side), self.ajc(side), self.calibration.forefoot_joint_centres[side])


__all__ = [
    "CLUSTERS",
    "ClusterCalibration",
    "ClusterChain",
    "SegmentCluster",
    "ShankTorsion",
    "calibrate_clusters",
    "calibrate_shank_torsion",
    "static_tibial_torsion",
]
