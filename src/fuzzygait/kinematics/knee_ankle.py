"""Where the static calibration of a cluster model (CGM 2.3+) puts the knee and ankle
centres: one rule per ``knee_ankle_centres`` value.

``"medial"``
    On the KNE->KNM line at ``KneeWidth / 2 + marker radius`` from KNE, and on the
    ANK->MED line at ``AnkleWidth / 2 + marker radius`` from ANK (Leboeuf et al. 2019:
    the medial epicondyle and malleolus markers of the CGM 2.x static trial).
``"chord"``
    Plug-in Gait's chord function (:mod:`fuzzygait.kinematics.joint_centres`): KJC in
    the plane of THI, HJC and KNE, AJC in the plane of TIB, KJC and ANK, each at
    width / 2 + marker radius from the lateral marker and at a right angle between the
    lateral marker and the *proximal joint centre*.
``"pycgm2"``
    What pyCGM2's CGM 2.3 output of the shared Qualisys session holds
    (``../shared/data/cgm2``, ``benchmarks/cgm2_pycgm2.py``): the same chord function, but
    the proximal point is the thigh's (shank's) proximal cluster marker THAP (TIAP), not
    the hip (knee) centre — KJC = chord(THI, THAP, KNE), AJC = chord(TIB, TIAP, ANK);
    KNM and MED are not used even when the static trial has them.  Measured: on all 272
    frames of its IK-fitted markers this reproduces pyCGM2's ``L/RKJC`` and ``L/RAJC``
    to 1e-4 mm, the chord with HJC (KJC) is 23-43 mm (6-12 mm) away.  Read as a
    definition: pyCGM2 places the centres with the three points of each segment's
    technical frame — for CGM 1 (KNE, HJC, THI) and (ANK, KJC, TIB), the Plug-in Gait
    chord; for CGM 2.3 (KNE, THAP, THI) and (ANK, TIAP, TIB), whose second point is a
    skin marker.  The wand offsets (``ThighRotation``, ``ShankRotation``, ``AnkleAbAdd``)
    act as in the Plug-in Gait chord, with THAP/TIAP in the proximal centre's place (a
    CGM 2.x calibration has none: the knee alignment device is Plug-in Gait's).

``None`` (the default) is ``"medial"`` when the static trial has KNM and MED on both
sides, else ``"chord"``.  The rule matters only in the static trial: the cluster
calibration stores the tracking markers in the anatomical frames whose origins are these
centres (:mod:`fuzzygait.kinematics.clusters`), and the foot offsets are calibrated on
the same chain (:func:`fuzzygait.kinematics.static.static_calibration`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.chain import LowerBodyChain, _memo
from fuzzygait.kinematics.joint_centres import abducted_joint_centre, rotated_chord_joint_centre
from fuzzygait.kinematics.segments import side_sign

#: ``knee_ankle_centres`` values (module docstring); None picks medial or chord.
KNEE_ANKLE_CENTRES: tuple[str, ...] = ("medial", "chord", "pycgm2")
#: Per segment, the proximal cluster marker the ``"pycgm2"`` chord uses in place of the
#: proximal joint centre.
PROXIMAL_CLUSTER_MARKER = {"thigh": "THAP", "tibia": "TIAP"}
#: Per rule, the markers (after the side letter) it needs beyond Plug-in Gait's.
RULE_MARKERS: dict[str, tuple[str, ...]] = {"medial": ("KNM", "MED"), "chord": (), "pycgm2": ("THAP", "TIAP")}
#: Per rule, how a calibration names it.
RULE_NAMES = {"medial": "KNM/MED", "chord": "chord", "pycgm2": "pyCGM2 THAP/TIAP chord"}


def knee_ankle_rule(static: Trial, knee_ankle_centres: str | None) -> str:
    """The rule ``knee_ankle_centres`` names, ``None`` resolved on ``static``.

    Raises:
        ParameterError: an unknown rule (lists the known ones).
    """
    if knee_ankle_centres is None:
        medial = all(static.has_marker(side + m) for side in "LR" for m in ("KNM", "MED"))
        return "medial" if medial else "chord"
    if knee_ankle_centres not in KNEE_ANKLE_CENTRES:
        raise ParameterError(
            f"unknown knee/ankle centre rule {knee_ankle_centres!r}; choose one of {', '.join(KNEE_ANKLE_CENTRES)}"
        )
    return knee_ankle_centres


class ClusterChordChain(LowerBodyChain):
    """A static trial's chain with the ``"pycgm2"`` knee and ankle centres (module
    docstring); everything else is :class:`LowerBodyChain`'s."""

    @_memo
    def kjc(self, side: str) -> np.ndarray:
        """chord(THI, THAP, KNE) at ``KneeWidth / 2 + marker radius`` from KNE, mm."""
        params = self.subject.side(side)
        thi, thap, kne = (self.marker(side + m) for m in ("THI", PROXIMAL_CLUSTER_MARKER["thigh"], "KNE"))
        rotation = side_sign(side) * params.thigh_rotation
        return rotated_chord_joint_centre(thi, thap, kne, self._offset(params.knee_width), rotation)

    @_memo
    def ajc(self, side: str) -> np.ndarray:
        """chord(TIB, TIAP, ANK) at ``AnkleWidth / 2 + marker radius`` from ANK, mm."""
        params = self.subject.side(side)
        tib, tiap, ank = (self.marker(side + m) for m in ("TIB", PROXIMAL_CLUSTER_MARKER["tibia"], "ANK"))
        rotation = side_sign(side) * params.shank_rotation
        centre = rotated_chord_joint_centre(tib, tiap, ank, self._offset(params.ankle_width), rotation)
        return abducted_joint_centre(centre, tiap, ank, params.ankle_abadd)


def calibration_chain(static: Trial, subject: SubjectParameters, rule: str, **options: Any) -> LowerBodyChain:
    """The static trial's chain whose knee/ankle centres follow ``rule`` (one of
    :data:`KNEE_ANKLE_CENTRES`); ``options`` go to :class:`LowerBodyChain`."""
    if rule == "pycgm2":
        return ClusterChordChain(static, subject, **options)
    return LowerBodyChain(static, subject, use_medial_markers=rule == "medial", **options)


__all__ = [
    "KNEE_ANKLE_CENTRES",
    "PROXIMAL_CLUSTER_MARKER",
    "RULE_MARKERS",
    "RULE_NAMES",
    "ClusterChordChain",
    "calibration_chain",
    "knee_ankle_rule",
]
