"""Plug-in Gait options (KAD, KAD + medial malleolus, foot flat) against Vicon Nexus (issue 13).

Run:  .venv/bin/python benchmarks/pig_options_agreement.py

For each static/walking pair of ``../shared/data/pig-options`` (and ``vicon/
Static_trial.c3d`` + ``Test.vsk`` / ``Movement_trial.c3d``, the plain model) prints one
Markdown table:

* every value our static calibration computes minus the one in the walking trial's
  ``PROCESSING`` group (what Nexus calibrated and applied): offsets in rad, the
  inter-ASIS and ASIS-trochanter distances in mm.  The pig-options static trials are
  calibrated from their subject measurements alone (every offset zeroed, no inter-ASIS
  distance);
* per angle and side, the max and RMS error (degrees, worst of the three components,
  frames where Nexus has an output) of (a) the walking trial with its own
  ``PROCESSING`` parameters, (b) the walking trial with our calibration, (c) the static
  trial's own outputs (``compute_lower_body(static_foot=...)``).

The FlatFoot session (Nexus 1.4) used 16 mm markers, which Nexus keeps in the pipeline
and not in the C3D: it is passed as ``marker_diameter=16`` for all three columns.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from _setup import VICON

from fuzzygait.io import read_c3d
from fuzzygait.io.subject import SubjectParameters, read_vsk, subject_from_processing
from fuzzygait.kinematics import compute_lower_body, static_calibration
from fuzzygait.kinematics.static import CALIBRATED_OFFSETS

PIG_OPTIONS = VICON.parent / "pig-options"

JOINTS = ("Pelvis", "Hip", "Knee", "Ankle", "FootProgress")


@dataclass
class Session:
    name: str
    static: str
    motion: str
    flat_foot: bool = False
    marker_diameter: float | None = None
    vsk: str | None = None


SESSIONS = (
    Session("KAD", "pig-options/PiGKad_Calibration.c3d", "pig-options/PiGKad_Motion.c3d"),
    Session("KAD+Med", "pig-options/PiGKadMed_Calibration.c3d", "pig-options/PiGKadMed_Motion.c3d"),
    Session("FlatFoot (16 mm)", "pig-options/PiG_Calibration-FlatFoot-Full.c3d",
            "pig-options/PiG_Motion-FlatFoot-Full.c3d", flat_foot=True, marker_diameter=16.0),
    Session("plain (Movement_trial)", "vicon/Static_trial.c3d", "vicon/Movement_trial.c3d", vsk="vicon/Test.vsk"),
)  # fmt: skip


def _diameter(subject: SubjectParameters, session: Session) -> SubjectParameters:
    if session.marker_diameter is None:
        return subject
    return replace(subject, marker_diameter=session.marker_diameter)


def _uncalibrated(static, session: Session) -> SubjectParameters:
    """The subject before the static calibration: Test.vsk, or the static trial's
    measurements with every offset zeroed and no inter-ASIS distance."""
    if session.vsk is not None:
        return read_vsk(VICON.parent / session.vsk)
    subject = replace(subject_from_processing(static.parameters), inter_asis_distance=None)
    for side in "LR":
        subject = subject.with_side(side, **{field: 0.0 for field in CALIBRATED_OFFSETS})
    return _diameter(subject, session)


def _errors(angles: dict[str, np.ndarray], trial, name: str) -> tuple[float, float]:
    """(max, RMS) in degrees of the worst component of ``name`` against Nexus."""
    nexus = np.all(np.isfinite(trial.outputs[name]), axis=1)
    diff = angles[name][nexus] - trial.outputs[name][nexus]
    if not np.isfinite(diff).all():
        return float("nan"), float("nan")
    return float(np.abs(diff).max()), float(np.sqrt(np.mean(diff**2, axis=0)).max())


def session_rows(session: Session) -> list[str]:
    static = read_c3d(VICON.parent / session.static)
    motion = read_c3d(VICON.parent / session.motion)
    calibrated = static_calibration(static, _uncalibrated(static, session), flat_foot=session.flat_foot)
    reference = motion.parameters
    rows = []
    for side in "LR":
        params = calibrated.side(side)
        for field, vicon in CALIBRATED_OFFSETS.items():
            difference = getattr(params, field) - reference[side + vicon]
            rows.append(f"| {session.name} | {side}{vicon} (rad) | {difference:.1e} |||||")
        nexus_asis = reference[side + "AsisTrocanterDistance"]
        asis = f"{params.asis_trochanter - nexus_asis:.1e}" if nexus_asis > 0 else "(Nexus stores 0: the regression)"
        rows.append(f"| {session.name} | {side}AsisTrocanterDistance (mm) | {asis} |||||")
    iad = (calibrated.inter_asis_distance or np.nan) - reference["InterAsisDistance"]
    rows.append(f"| {session.name} | InterAsisDistance (mm) | {iad:.1e} |||||")

    columns = {
        "processing": (motion, compute_lower_body(motion, _diameter(subject_from_processing(reference), session))),
        "calibrated": (motion, compute_lower_body(motion, calibrated)),
        "static": (static, compute_lower_body(static, calibrated, static_foot="flat" if session.flat_foot else "heel")),
    }
    for joint in JOINTS:
        for side in "LR":
            name = f"{side}{joint}Angles"
            cells = " | ".join("{:.1e} | {:.1e}".format(*_errors(result.angles, trial, name))
                               for trial, result in columns.values())  # fmt: skip
            rows.append(f"| {session.name} | {name} (deg) | {cells} |")
    return rows


def main() -> None:
    if not PIG_OPTIONS.is_dir() or not VICON.is_dir():
        print(f"skipped: {PIG_OPTIONS} or {VICON} is absent (the Nexus sessions are shared next to the repository)")
        return
    print("| session | quantity | ours − Nexus / (a) max | (a) RMS | (b) max | (b) RMS | (c) max | (c) RMS |")
    print("|---|---|---|---|---|---|---|---|")
    for session in SESSIONS:
        for row in session_rows(session):
            print(row)
    print()
    print("(a) walking trial, its own PROCESSING; (b) walking trial, our calibration of the static trial;")
    print("(c) the static trial's own outputs; angles: worst of the three components. FlatFoot: 16 mm markers")
    print("(marker_diameter=16; Nexus does not store the diameter in the C3D).")


if __name__ == "__main__":
    main()
