"""The marker diameter a Plug-in Gait run used, recovered from its own outputs.

Vicon Nexus keeps the marker diameter as a setting of the Plug-in Gait pipeline
operation: no C3D file states it, yet it moves every joint centre (the hip centre by the
marker radius ``r`` through the Davis regression, the knee and ankle centres by ``r``
along their axes).  A file that carries Nexus' outputs holds the evidence:

* the pelvis frame's orientation as segment-axis markers (``PELO`` origin, drawn at the
  hip-centre midpoint, ``PELA`` anterior, ``PELL`` left, ``PELP`` proximal); the
  regression's origin is the midpoint of the ``LASI`` and ``RASI`` markers, and
* the hip joint centres, as ``L/RHJC`` or as the femur's proximal axis marker
  ``L/RFEP`` (the femur runs from the knee centre to the hip centre and its axis
  markers are drawn at the femur's length, so ``FEP`` *is* the hip centre).

In the pelvis frame the Davis hip centre (:func:`~fuzzygait.kinematics.joint_centres.davis_hjc_local`)
is, with ``C = 0.115 L̄ - 15.3`` (``L̄`` the mean leg length, mm), ``θ = 0.5``,
``β = 0.314`` rad and ``X`` the side's ASIS-trochanter distance::

    x = -(X + r) cos β + C cos θ sin β
    z = -(X + r) sin β - C cos θ cos β

so ``X + r`` enters linearly and each of ``x`` and ``z`` gives ``r`` on its own::

    r_x = (C cos θ sin β - x) / cos β - X
    r_z = -(z + C cos θ cos β) / sin β - X

Two independent estimates per side, four per trial.  They agree when the subject's leg
lengths and ASIS-trochanter distances are those Nexus used (the file's ``PROCESSING``
values): within 1e-3 mm on every Nexus file of the reference data (14 and 16 mm
markers).  When they disagree the other parameters differ from Nexus' and the radius
cannot be told apart from them: no value is recovered and the reason is given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.joint_centres import DAVIS_BETA, DAVIS_THETA

#: The four estimates (both sides, x and z) must agree within this (mm) to be trusted.
AGREEMENT_MM = 0.05
#: A recovered diameter is rounded to this (mm): the estimates' agreement on the
#: reference files is 1e-3 mm, so the second decimal is still meaningful.
ROUND_MM = 0.01
#: A stated diameter that differs from the file's own by more than this (mm) is warned of.
CONTRADICTION_MM = 0.5

#: Pelvis segment-axis markers Nexus exports: origin, anterior, lateral (left), proximal.
PELVIS_AXES = ("PELO", "PELA", "PELL", "PELP")
#: Names under which a file may carry the hip joint centres, in order of preference.
HIP_CENTRE_NAMES = {"L": ("LHJC", "LFEP"), "R": ("RHJC", "RFEP")}


@dataclass(frozen=True)
class RecoveredDiameter:
    """A marker diameter recovered from a trial's stored Plug-in Gait outputs.

    Attributes:
        diameter: mm, rounded to :data:`ROUND_MM` (None: not recovered, see ``reason``).
        estimates: the estimates of the diameter (mm, unrounded): ``(side, axis)`` ->
            value, ``axis`` ``"x"`` or ``"z"`` of the pelvis frame.
        hip_markers: the hip-centre outputs used (``("LFEP", "RFEP")``).
        frames: how many frames had the pelvis frame and a hip centre.
        reason: why nothing was recovered ("" when recovered).
    """

    diameter: float | None
    estimates: dict[tuple[str, str], float]
    hip_markers: tuple[str, ...] = ()
    frames: int = 0
    reason: str = ""

    @property
    def spread(self) -> float:
        """Largest minus smallest estimate, mm (0 without estimates)."""
        values = list(self.estimates.values())
        return float(max(values) - min(values)) if values else 0.0

    def describe(self, where: str = "the file") -> str:
        """``"recovered from T.c3d's Plug-in Gait hip joint centres (LFEP, RFEP) in its
        pelvis frame (4 estimates within 0.001 mm)"``."""
        spread = f"within {self.spread:.3f} mm" if self.spread >= 1e-3 else "within < 0.001 mm"
        return (f"recovered from {where}'s Plug-in Gait hip joint centres ({', '.join(self.hip_markers)}) in its "
                f"pelvis frame ({len(self.estimates)} estimates {spread})")


def _output(trial: Trial, name: str) -> np.ndarray | None:
    values = trial.outputs.get(name)
    if values is None and trial.has_marker(name):
        values = trial.marker(name)
    return None if values is None else np.asarray(values, dtype=float)


def _pelvis_frames(trial: Trial) -> tuple[np.ndarray, np.ndarray] | None:
    """The Davis regression's origin ``(n, 3)``, the ASIS midpoint of the trial's
    ``LASI``/``RASI`` markers (Nexus draws ``PELO`` at the hip-centre midpoint instead),
    and the rotation ``(n, 3, 3)`` of the stored pelvis frame (columns x anterior, y
    left, z up); None without the ASIS markers or the four axis markers."""
    points = [p for p in (_output(trial, name) for name in PELVIS_AXES) if p is not None]
    if len(points) < len(PELVIS_AXES) or not (trial.has_marker("LASI") and trial.has_marker("RASI")):
        return None
    origin, anterior, lateral, proximal = points
    asis_midpoint = 0.5 * (trial.marker("LASI") + trial.marker("RASI"))
    axes = []
    for tip in (anterior, lateral, proximal):
        v = tip - origin
        with np.errstate(invalid="ignore", divide="ignore"):
            axes.append(v / np.linalg.norm(v, axis=1, keepdims=True))
    return asis_midpoint, np.stack(axes, axis=2)


def recover_marker_diameter(trial: Trial, subject: SubjectParameters) -> RecoveredDiameter:
    """The marker diameter of the Plug-in Gait run whose outputs ``trial`` carries.

    Args:
        trial: a trial with Nexus' pelvis axis markers and hip centres (see the module
            docstring); markers and outputs in mm, lab frame.
        subject: the subject parameters the run is to use (leg lengths, ASIS-trochanter
            distances: given, else Plug-in Gait's regression from the leg length).

    Returns:
        The recovered diameter, or one with ``diameter`` None and the reason (no stored
        outputs, no frame with all of them, or estimates that disagree: the subject's
        leg lengths or ASIS-trochanter distances are not the ones the file was made with).
    """
    pelvis = _pelvis_frames(trial)
    hips = {side: next(((n, v) for n in names if (v := _output(trial, n)) is not None), None)
            for side, names in HIP_CENTRE_NAMES.items()}  # fmt: skip
    if pelvis is None or not any(hips.values()):
        return RecoveredDiameter(None, {}, reason="the file holds no Plug-in Gait pelvis frame and hip joint centres")
    origin, rotation = pelvis
    c = 0.115 * (subject.left.leg_length + subject.right.leg_length) / 2.0 - 15.3
    estimates: dict[tuple[str, str], float] = {}
    used: list[str] = []
    frames = 0
    for side, found in hips.items():
        if found is None:
            continue
        name, centre = found
        local = np.einsum("nji,nj->ni", rotation, centre - origin)
        valid = np.all(np.isfinite(local), axis=1)
        if not valid.any():
            continue
        x, z = float(np.median(local[valid, 0])), float(np.median(local[valid, 2]))
        trochanter = subject.side(side).asis_trochanter
        radius_x = (c * np.cos(DAVIS_THETA) * np.sin(DAVIS_BETA) - x) / np.cos(DAVIS_BETA) - trochanter
        radius_z = -(z + c * np.cos(DAVIS_THETA) * np.cos(DAVIS_BETA)) / np.sin(DAVIS_BETA) - trochanter
        estimates[(side, "x")], estimates[(side, "z")] = 2.0 * float(radius_x), 2.0 * float(radius_z)
        used.append(name)
        frames = max(frames, int(valid.sum()))
    if not estimates:
        return RecoveredDiameter(None, {}, reason="the file's pelvis frame and hip joint centres are empty")
    result = RecoveredDiameter(None, estimates, tuple(used), frames)
    if result.spread > AGREEMENT_MM:
        listed = ", ".join(f"{side} {axis} {value:.2f} mm" for (side, axis), value in estimates.items())
        reason = (f"the file's hip joint centres give inconsistent diameters ({listed}): the subject's leg "
                  "lengths or ASIS-trochanter distances differ from those the file was processed with")
        return RecoveredDiameter(None, estimates, tuple(used), frames, reason)
    mean = float(np.mean(list(estimates.values())))
    return RecoveredDiameter(round(mean / ROUND_MM) * ROUND_MM, estimates, tuple(used), frames)
