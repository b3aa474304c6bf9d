"""The Conventional Gait Model versions fuzzygait computes, and which one a trial supports.

=========  ======================================================================
``cgm1.0``  Vicon Plug-in Gait lower body (Davis hip centres, chord-function knee and
            ankle centres with the THI/TIB wands, Plug-in Gait foot); matches Nexus.
``cgm1.1``  as 1.0 with the changes of Leboeuf et al. (2019): one tibia frame for
            knee, ankle and foot (no untwisting by the tibial torsion) and the pelvis
            angles in the order rotation, obliquity, tilt (Baker 2001).
``cgm2.1``  1.1 with Hara et al. (2016) hip centres from leg length.
``cgm2.3``  2.1 with the thigh and shank tracked by least-squares fits of their marker
            clusters (THI, THAP, THAD, KNE; TIB, TIAP, TIAD, ANK) to their static
            positions; static knee/ankle centres from KNM/MED, Plug-in Gait's chord or
            pyCGM2's THAP/TIAP chord (:mod:`fuzzygait.kinematics.knee_ankle`).
``cgm2.4``  2.3 with the CGM 2.4 hindfoot and forefoot (FMH, SMH, VMH;
            ``L/RForeFootAngles``, :mod:`fuzzygait.kinematics.forefoot`).
=========  ======================================================================

With KNM/MED in the static trial both cluster versions calibrate the tibial torsion
(pyCGM2's definition, :mod:`fuzzygait.kinematics.clusters`); ``cgm2.3``'s foot is built on
the ankle axis turned by it (``foot_torsion``), ``cgm2.4``'s hindfoot, as pyCGM2's, is not.

CGM 2.2 and 2.5 (OpenSim inverse kinematics) are out of scope.
"""

from __future__ import annotations

from dataclasses import dataclass

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.trial import Trial

#: Model versions, poorest first.
MODEL_VERSIONS: tuple[str, ...] = ("cgm1.0", "cgm1.1", "cgm2.1", "cgm2.3", "cgm2.4")
#: What ``--model`` accepts.
MODEL_CHOICES: tuple[str, ...] = ("auto", *MODEL_VERSIONS)

#: Per side, the cluster markers CGM 2.3 adds to Plug-in Gait's (dynamic trials).
CLUSTER_MARKERS: tuple[str, ...] = ("THAP", "THAD", "TIAP", "TIAD")
#: Per side, the medial markers of a CGM 2.3 static trial.
MEDIAL_MARKERS: tuple[str, ...] = ("KNM", "MED")
#: Per side, the forefoot markers CGM 2.4 adds.
FOREFOOT_MARKERS: tuple[str, ...] = ("FMH", "SMH", "VMH")


@dataclass(frozen=True)
class ModelVersion:
    """What distinguishes a model version.

    Attributes:
        name: one of :data:`MODEL_VERSIONS`.
        hip: ``"davis"`` (CGM 1.x) or ``"hara"`` (CGM 2.x) hip joint centres.
        clusters: thigh and shank tracked by their marker clusters (CGM 2.3+).
        forefoot: the CGM 2.4 hindfoot/forefoot.
        single_tibia: CGM 1.1+: one tibia frame (the marker-based one) for the knee, the
            ankle and the foot's ankle axis (Plug-in Gait's knee untwists it by the
            tibial torsion).
        pelvis_sequence: ``"TOR"`` (Plug-in Gait) or ``"ROT"`` (CGM 1.1+, Baker 2001).
        foot_torsion: the cluster model's foot takes the ankle axis turned by the tibial
            torsion calibrated with MED, with its static correction (pyCGM2's CGM 2.3;
            :class:`~fuzzygait.kinematics.clusters.ClusterChain`).
    """

    name: str
    hip: str
    clusters: bool
    forefoot: bool
    single_tibia: bool = True
    pelvis_sequence: str = "ROT"
    foot_torsion: bool = False

    @property
    def suffix(self) -> str:
        """pyCGM2's point suffix for this version's outputs, e.g. ``"_CGM_2.4"``."""
        return "_CGM_" + self.name.removeprefix("cgm")


_VERSIONS = {
    "cgm1.0": ModelVersion("cgm1.0", "davis", False, False, single_tibia=False, pelvis_sequence="TOR"),
    "cgm1.1": ModelVersion("cgm1.1", "davis", False, False),
    "cgm2.1": ModelVersion("cgm2.1", "hara", False, False),
    "cgm2.3": ModelVersion("cgm2.3", "hara", True, False, foot_torsion=True),
    "cgm2.4": ModelVersion("cgm2.4", "hara", True, True),
}


def model_version(name: str) -> ModelVersion:
    """The :class:`ModelVersion` called ``name`` (case-insensitive; ``"2.3"`` is
    ``"cgm2.3"``).

    Raises:
        ParameterError: an unknown name or not a string (lists the known ones).
    """
    key = name.strip().lower() if isinstance(name, str) else ""
    key = key if key.startswith("cgm") else "cgm" + key
    if key not in _VERSIONS:
        raise ParameterError(f"unknown model {name!r}; choose one of {', '.join(MODEL_CHOICES)}")
    return _VERSIONS[key]


def _has_all(trial: Trial, names: tuple[str, ...]) -> bool:
    return all(trial.has_marker(side + name) for side in "LR" for name in names)


def supported_version(dynamic: Trial, static: Trial | None = None) -> tuple[ModelVersion, str]:
    """The richest model version the markers support, and why (one phrase, without the
    version's name).

    ``cgm2.4`` needs the clusters and the forefoot markers in the dynamic trial and KNM,
    MED in the static one; ``cgm2.3`` the clusters and the medial static markers;
    otherwise the Plug-in Gait marker set says ``cgm1.0`` (the version that matches
    Nexus: 1.1 and 2.1 use the same markers and differ only in their definitions, so
    they are chosen by name).
    """
    if static is None:
        return _VERSIONS["cgm1.0"], "no static trial, which cluster models need"
    clusters = _has_all(dynamic, CLUSTER_MARKERS) and _has_all(static, CLUSTER_MARKERS)
    medial = _has_all(static, MEDIAL_MARKERS)
    if not (clusters and medial):
        lacking = "thigh/shank clusters (THAP, THAD, TIAP, TIAD)" if not clusters else "static KNM/MED"
        return _VERSIONS["cgm1.0"], f"Plug-in Gait marker set, no {lacking}"
    forefoot = _has_all(dynamic, FOREFOOT_MARKERS) and _has_all(static, FOREFOOT_MARKERS)
    if forefoot:
        return _VERSIONS["cgm2.4"], "CGM 2.4 marker set: clusters, static KNM/MED and FMH/SMH/VMH"
    return _VERSIONS["cgm2.3"], "clusters and static KNM/MED, no FMH/SMH/VMH"


__all__ = [
    "CLUSTER_MARKERS",
    "FOREFOOT_MARKERS",
    "MEDIAL_MARKERS",
    "MODEL_CHOICES",
    "MODEL_VERSIONS",
    "ModelVersion",
    "model_version",
    "supported_version",
]
