"""CGM 2.3 against pyCGM2's CGM 2.3 output of the shared Qualisys session (issue 14).

Run:  .venv/bin/python benchmarks/cgm2_pycgm2.py      (needs ../shared/data/cgm2)

``Gait - CGM2 3 (pyCGM2 CGM2.3 output).c3d`` holds pyCGM2's inverse-kinematics-fitted
markers (unsuffixed labels), its joint centres (``L/RHJC``, ``L/RKJC``, ``L/RAJC``) and
its angles.  fuzzygait's ``cgm2.3`` runs on those fitted markers *as they are* (no gap
filling, no low-pass filter: they are the positions pyCGM2's own kinematics used) with
the knee/ankle centre rule ``"pycgm2"`` (:mod:`fuzzygait.kinematics.knee_ankle`) and the
subject values of ``session.xml`` (leg length 1000 mm, knee 95, ankle 65, 14 mm
markers).  Two static calibrations:

(A) the session's static trial ``Static - CGM2 1.c3d`` (``static_calibration`` and
    ``calibrate_clusters`` with the rule, what ``workflows.angles.calibrate_static`` runs on
    a trial without gaps; foot flat on: session.xml's "foot normalised to static trial",
    pyCGM2's default);
(B) pyCGM2's own calibrated geometry: its fitted markers at the static trial's frames
    (539-543) as the static trial (the fitted thigh, shank and foot are rigid bodies, so
    any frames give the same cluster geometry), and the foot offsets that pyCGM2's ankle
    angles imply (two constants per side, printed with the evidence that they are
    constants).  (B) tests the definitions; (A) is what a user gets from the files.

Printed: the evidence on the calibration input (fitted cluster geometry against the
static trial's), the knee/ankle centre rules on the fitted markers, and one Markdown
table: per angle component (both sides) and per joint centre, RMS and max of ours minus
pyCGM2's (angles wrapped into (-180, 180] deg; centres: distance, mm) for (A) and (B).

Tibial torsion (issue 36): pyCGM2's CGM 2.3 calibrates a tibial torsion when the static
trial has MED and builds its foot on the ankle axis turned by it
(:mod:`fuzzygait.kinematics.clusters`).  Printed: (B)'s spread of pyCGM2's foot in our
turned uncorrected foot for a few torsions (a constant R_y R_x, SD and third angle 0,
only at the torsion pyCGM2 used), and (A') the session's static trial with its KNM/MED
(rule ``"medial"``): the torsion it calibrates and the ankle / foot-progression
differences from pyCGM2 with the foot on the unturned axis (before issue 36) and on the
turned one (after).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from _setup import ROOT
from scipy.spatial.transform import Rotation

from fuzzygait.core.trial import Trial
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import SubjectParameters, subject_from_processing
from fuzzygait.kinematics import ANGLE_NAMES, CGMResult, compute_lower_body, static_calibration
from fuzzygait.kinematics.angles import ANGLE_TABLE, LEFT_MIRROR, wrap_degrees
from fuzzygait.kinematics.clusters import CLUSTERS, ClusterChain, calibrate_clusters
from fuzzygait.kinematics.joint_centres import chord_joint_centre
from fuzzygait.kinematics.knee_ankle import calibration_chain
from fuzzygait.kinematics.segments import foot_axis_correction, side_sign, turned_uncorrected_foot

SESSION = ROOT.parent / "shared" / "data" / "cgm2" / "qualisys-cgm24-input"
STATIC = SESSION / "Static - CGM2 1.c3d"
RAW = SESSION / "Gait - CGM2 1.c3d"
PYCGM2 = SESSION / "Gait - CGM2 3 (pyCGM2 CGM2.3 output).c3d"
#: session.xml (metres there, mm here).
SUBJECT = {"Bodymass": 70.0, "Height": 1800.0, "LLegLength": 1000.0, "RLegLength": 1000.0,
           "LKneeWidth": 95.0, "RKneeWidth": 95.0, "LAnkleWidth": 65.0, "RAnkleWidth": 65.0,
           "MarkerDiameter": 14.0}  # fmt: skip
#: The static trial's frames (C3D numbering, the walking recording's clock).
STATIC_FRAMES = (539, 543)
RULE = "pycgm2"
CENTRES = ("HJC", "KJC", "AJC")
#: Tibial torsions (deg) tried on pyCGM2's foot, and the outputs the torsion changes.
TRIED_TORSIONS_DEG = (-5.0, -1.0, 0.0, 1.0, 5.0)
FOOT_OUTPUTS = ("LAnkleAngles", "RAnkleAngles", "LFootProgressAngles", "RFootProgressAngles")


@dataclass
class Session:
    static: Trial
    fitted: Trial
    output: Trial
    subject: SubjectParameters


def load() -> Session:
    """The static trial, pyCGM2's fitted markers (the walking trial's marker labels,
    unsuffixed) and its output trial."""
    raw, output = read_c3d(RAW), read_c3d(PYCGM2)
    fitted = output.select_markers([m for m in raw.marker_labels if output.has_marker(m)])
    return Session(read_c3d(STATIC), fitted, output, subject_from_processing(SUBJECT))


def fitted_static(session: Session) -> Trial:
    """pyCGM2's fitted markers at the static trial's frames, as a static trial."""
    first, last = (f - session.fitted.first_frame for f in STATIC_FRAMES)
    fitted = session.fitted
    return Trial(fitted.markers[first : last + 1], list(fitted.marker_labels), fitted.rate,
                 first_frame=STATIC_FRAMES[0], source=Path("pyCGM2 fitted static.c3d"))  # fmt: skip


def distance_table(session: Session) -> list[str]:
    """Per cluster: the largest difference of an inter-marker distance between the static
    trial (mean over its frames) and pyCGM2's fitted markers (which keep every distance
    to float precision), and the fitted distances' spread."""
    lines = ["| side | cluster | max abs(static - fitted) inter-marker distance (mm) | fitted distances' SD (mm) |",
             "|---|---|---|---|"]  # fmt: skip
    for side, (name, markers) in itertools.product("LR", CLUSTERS.items()):
        worst, spread = 0.0, 0.0
        for a, b in itertools.combinations([side + m for m in markers], 2):
            fitted = np.linalg.norm(session.fitted.marker(a) - session.fitted.marker(b), axis=1)
            static = np.linalg.norm(session.static.marker(a) - session.static.marker(b), axis=1).mean()
            worst, spread = max(worst, abs(static - fitted.mean())), max(spread, fitted.std())
        lines.append(f"| {side} | {name} | {worst:.1f} | {spread:.1e} |")
    return lines


def rule_check(session: Session) -> list[str]:
    """Max distance (mm, all frames) from pyCGM2's KJC/AJC of the chord with the joint
    centre (Plug-in Gait) and with THAP/TIAP (the ``"pycgm2"`` rule), on its fitted markers."""
    out, m = session.output, session.fitted.marker
    lines = ["| centre | chord with HJC / KJC (Plug-in Gait) | chord with THAP / TIAP (pycgm2) |", "|---|---|---|"]
    for side in "LR":
        knee, ankle = SUBJECT[side + "KneeWidth"] / 2 + 7.0, SUBJECT[side + "AnkleWidth"] / 2 + 7.0
        rows = {
            "KJC": (chord_joint_centre(m(side + "THI"), out.marker(side + "HJC"), m(side + "KNE"), knee),
                    chord_joint_centre(m(side + "THI"), m(side + "THAP"), m(side + "KNE"), knee)),
            "AJC": (chord_joint_centre(m(side + "TIB"), out.marker(side + "KJC"), m(side + "ANK"), ankle),
                    chord_joint_centre(m(side + "TIB"), m(side + "TIAP"), m(side + "ANK"), ankle)),
        }  # fmt: skip
        for centre, (pig, pycgm2) in rows.items():
            ref = out.marker(side + centre)
            far = [np.linalg.norm(c - ref, axis=1).max() for c in (pig, pycgm2)]
            lines.append(f"| {side}{centre} | {far[0]:.1f} | {far[1]:.1e} |")
    return lines


def _frames_from_angles(proximal: np.ndarray, angles: np.ndarray, joint: str, side: str) -> np.ndarray:
    """The distal frames whose angles relative to ``proximal`` are ``angles`` (the inverse
    of :func:`fuzzygait.kinematics.angles.joint_angles` for a Y-X-Z joint)."""
    order, table_signs, offsets = ANGLE_TABLE[joint]
    signs = np.asarray(table_signs) * (LEFT_MIRROR if side == "L" else 1.0)
    components = np.empty_like(angles)
    components[:, list(order)] = (angles - np.asarray(offsets)) / signs
    return proximal @ Rotation.from_euler("YXZ", components, degrees=True).as_matrix()


def pycgm2_foot_offsets(session: Session, subject: SubjectParameters) -> tuple[SubjectParameters, list[str]]:
    """The static foot offsets pyCGM2's ankle angles imply: its foot (our torsioned tibia
    turned by its ankle angles) expressed in our uncorrected foot is one rotation
    ``R_y(-StaticPlantFlex) R_x(-s StaticRotOff)`` on every frame (Plug-in Gait's foot
    offsets); returns ``subject`` with them and the evidence (per side: the two offsets,
    their SD over the frames and the third Y-X-Z angle, which must be 0)."""
    lines = ["| side | StaticPlantFlex (deg) | StaticRotOff (deg) | SD over frames (deg) | third angle (deg) |",
             "|---|---|---|---|---|"]  # fmt: skip
    calibration = calibrate_clusters(fitted_static(session), subject, RULE)
    tracked = ClusterChain(session.fitted, subject, calibration)
    for side in "LR":
        foot = _frames_from_angles(tracked.ankle_tibia(side), session.output.outputs[side + "AnkleAngles"],
                                   "Ankle", side)  # fmt: skip
        relative = np.einsum("nji,njk->nik", tracked.uncorrected_foot(side), foot)
        yxz = Rotation.from_matrix(relative).as_euler("YXZ", degrees=True)
        plant_flex, rot_off = -yxz[:, 0].mean(), -side_sign(side) * yxz[:, 1].mean()
        subject = subject.with_side(side, static_plant_flex=float(np.radians(plant_flex)),
                                    static_rot_off=float(np.radians(rot_off)))  # fmt: skip
        lines.append(f"| {side} | {plant_flex:.3f} | {rot_off:.3f} | {yxz[:, :2].std(axis=0).max():.1e} "
                     f"| {np.abs(yxz[:, 2]).max():.1e} |")  # fmt: skip
    return subject, lines


def run_a(session: Session) -> tuple[CGMResult, SubjectParameters]:
    """(A): calibrated on the session's static trial; the result and the calibrated subject."""
    calibrated = static_calibration(session.static, session.subject, model="cgm2.3", knee_ankle_centres=RULE,
                                    flat_foot=True)  # fmt: skip
    clusters = calibrate_clusters(session.static, calibrated, RULE)
    return compute_lower_body(session.fitted, calibrated, model="cgm2.3", clusters=clusters), calibrated


def offsets_line(label: str, subject: SubjectParameters) -> str:
    """The foot offsets of ``subject`` in degrees, one line."""
    values = [f"{side} {np.degrees(p.static_plant_flex):.2f} / {np.degrees(p.static_rot_off):.2f}"
              for side, p in (("L", subject.left), ("R", subject.right))]  # fmt: skip
    return f"{label} StaticPlantFlex / StaticRotOff (deg): {', '.join(values)}"


def run_b(session: Session, subject: SubjectParameters) -> CGMResult:
    """(B): pyCGM2's fitted geometry and its implied foot offsets."""
    calibration = calibrate_clusters(fitted_static(session), subject, RULE)
    return compute_lower_body(session.fitted, subject, model="cgm2.3", clusters=calibration)


def angle_errors(result: CGMResult, output: Trial, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(RMS, max) per component X, Y, Z of ours minus pyCGM2's, degrees."""
    diff = np.abs(wrap_degrees(result.angles[name] - output.outputs[name]))
    return np.sqrt(np.mean(diff**2, axis=0)), diff.max(axis=0)


def centre_errors(result: CGMResult, output: Trial, name: str) -> tuple[float, float]:
    """(RMS, max) distance of our joint centre ``name`` from pyCGM2's, mm."""
    distance = np.linalg.norm(result.joint_centres[name] - output.marker(name), axis=1)
    return float(np.sqrt(np.mean(distance**2))), float(distance.max())


def comparison_table(a: CGMResult, b: CGMResult, output: Trial) -> list[str]:
    lines = ["| output | component | (A) RMS | (A) max | (B) RMS | (B) max |", "|---|---|---|---|---|---|"]
    for name in ANGLE_NAMES:
        (a_rms, a_max), (b_rms, b_max) = angle_errors(a, output, name), angle_errors(b, output, name)
        for k, axis in enumerate("XYZ"):
            values = " | ".join(f"{v:.2g}" for v in (a_rms[k], a_max[k], b_rms[k], b_max[k]))
            lines.append(f"| {name} (deg) | {axis} | {values} |")
    for side, centre in itertools.product("LR", CENTRES):
        name = side + centre
        (a_rms, a_max), (b_rms, b_max) = centre_errors(a, output, name), centre_errors(b, output, name)
        lines.append(f"| {name} (mm) | distance | {a_rms:.2g} | {a_max:.2g} | {b_rms:.2g} | {b_max:.2g} |")
    return lines


def right_foot_progression(result: CGMResult, output: Trial) -> float:
    """Max over frames and components (deg) of pyCGM2's RFootProgressAngles minus
    ``(X + 180, -180 - Y, Z + 180)`` of ours: the same angles on the other Cardan
    solution with the left side's frontal/transverse signs."""
    x, y, z = result.angles["RFootProgressAngles"].T
    mirrored = np.stack([x + 180.0, -180.0 - y, z + 180.0], axis=1)
    return float(np.abs(wrap_degrees(output.outputs["RFootProgressAngles"] - mirrored)).max())


def torsion_spread(session: Session, subject: SubjectParameters) -> list[str]:
    """(B) per side and tried torsion: pyCGM2's foot (as in :func:`pycgm2_foot_offsets`)
    in our CGM 2.3 uncorrected foot turned by that torsion with its static correction on
    pyCGM2's fitted static: the largest SD of its Y, X angles over the frames and its
    largest third angle (deg), both 0 for the torsion pyCGM2's foot was built with."""
    lines = ["| side | torsion (deg) | SD of R_y, R_x over frames (deg) | max third angle (deg) |", "|---|---|---|---|"]
    static = fitted_static(session)
    tracked = ClusterChain(session.fitted, subject, calibrate_clusters(static, subject, RULE))
    chain = calibration_chain(static, subject, RULE, hip="hara", single_tibia=True)
    for side in "LR":
        foot = _frames_from_angles(tracked.ankle_tibia(side), session.output.outputs[side + "AnkleAngles"],
                                   "Ankle", side)  # fmt: skip
        for degrees in TRIED_TORSIONS_DEG:
            torsion = float(np.radians(degrees))
            per_frame = foot_axis_correction(chain.ajc(side), static.marker(side + "TOE"), chain.torsioned_tibia(side),
                                             torsion, side)  # fmt: skip
            correction = float(np.nanmean(per_frame))
            turned = turned_uncorrected_foot(tracked.ajc(side), session.fitted.marker(side + "TOE"),
                                             tracked.torsioned_tibia(side), torsion, correction, side)  # fmt: skip
            yxz = Rotation.from_matrix(np.einsum("nji,njk->nik", turned, foot)).as_euler("YXZ", degrees=True)
            lines.append(f"| {side} | {degrees:+.0f} | {yxz[:, :2].std(axis=0).max():.2g} "
                         f"| {np.abs(yxz[:, 2]).max():.2g} |")  # fmt: skip
    return lines


def medial_run(session: Session) -> list[str]:
    """(A'): the session's static trial with its KNM/MED (rule ``"medial"``): the
    calibrated TibialTorsion and, per foot output, RMS / max (deg, over the components) of
    ours minus pyCGM2's with the foot on the unturned axis (the calibration without its
    torsion: before issue 36) and on the turned one (after)."""
    calibrated = static_calibration(session.static, session.subject, model="cgm2.3", knee_ankle_centres="medial",
                                    flat_foot=True)  # fmt: skip
    clusters = calibrate_clusters(session.static, calibrated, "medial")
    unturned = replace(clusters, shank_torsions={})
    before = compute_lower_body(session.fitted, calibrated, model="cgm2.3", clusters=unturned)
    after = compute_lower_body(session.fitted, calibrated, model="cgm2.3", clusters=clusters)
    torsions = ", ".join(f"{side} {np.degrees(calibrated.side(side).tibial_torsion):.2f}" for side in "LR")
    lines = [f"(A') TibialTorsion of the session's static trial (deg): {torsions}", "",
             "| output | before: RMS / max (deg) | after: RMS / max (deg) | after minus before, max (deg) |",
             "|---|---|---|---|"]  # fmt: skip
    for name in FOOT_OUTPUTS:
        (b_rms, b_max), (a_rms, a_max) = (angle_errors(run, session.output, name) for run in (before, after))
        change = np.abs(wrap_degrees(after.angles[name] - before.angles[name])).max()
        lines.append(f"| {name} | {b_rms.max():.3g} / {b_max.max():.3g} | {a_rms.max():.3g} / {a_max.max():.3g} "
                     f"| {change:.3g} |")  # fmt: skip
    return lines


def main() -> None:
    session = load()
    print("## Calibration input: the static trial against pyCGM2's fitted clusters\n")
    print("\n".join(distance_table(session)))
    print("\n## pyCGM2's knee/ankle centres on its fitted markers (max distance, mm, 272 frames)\n")
    print("\n".join(rule_check(session)))
    subject_b, evidence = pycgm2_foot_offsets(session, session.subject)
    print("\n## (B) foot offsets implied by pyCGM2's ankle angles\n")
    print("\n".join(evidence))
    (a, subject_a), b = run_a(session), run_b(session, subject_b)
    print("\n" + offsets_line("(A) the static trial's", subject_a))
    print(offsets_line("(B) pyCGM2's implied", subject_b))
    print("\n## cgm2.3 minus pyCGM2 (A: static trial; B: pyCGM2's fitted geometry)\n")
    print("\n".join(comparison_table(a, b, session.output)))
    mirrored = [f"{right_foot_progression(r, session.output):.2g} deg" for r in (a, b)]
    print(
        f"\nRFootProgressAngles, pyCGM2 minus (X+180, -180-Y, Z+180) of ours, max: (A) {mirrored[0]}, (B) {mirrored[1]}"
    )
    print(f"\n## Tibial torsion: the static trial has MED: {all(session.static.has_marker(s + 'MED') for s in 'LR')}; "
          "(B) pyCGM2's foot in our CGM 2.3 foot turned by a torsion\n")  # fmt: skip
    print("\n".join(torsion_spread(session, subject_b)))
    print()
    print("\n".join(medial_run(session)))


if __name__ == "__main__":
    main()
