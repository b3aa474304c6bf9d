"""The bundled ``sample_data`` folder: its trials, truth tables and subject file written
by :func:`write_sample_data`, and its README generated from the same values
(:func:`readme_text`), so that the description always matches the files.

Regenerate the folder with ``python -m fuzzygait.synthetic [OUT_DIR]``; the trials and
the text of each file come from :mod:`fuzzygait.synthetic.generate` and, for the CGM 2.4
session, :mod:`fuzzygait.synthetic.cgm24_sample`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from fuzzygait.core.trial import Trial
from fuzzygait.synthetic import cgm24_sample
from fuzzygait.synthetic.force_plates import (
    PlateRecording,
    add_force_plates,
    plate_readme_values,
    sample_walking_plates,
)
from fuzzygait.synthetic.gait_curves import STRIDE_TIME_S
from fuzzygait.synthetic.generate import (
    LEAD_IN_CYCLES,
    MEAN_PELVIS_HEIGHT_MM,
    NOISE_MM,
    NOISE_SEED,
    WALKING_SPEED_MM_S,
    CutGap,
    gaps_csv_text,
    make_noisy_gapped,
    make_static_trial,
    make_walking_trial,
    subject_toml_text,
    truth_angles_csv_text,
    truth_joint_centres_csv_text,
)
from fuzzygait.synthetic.leg_model import SubjectGeometry, static_offsets


def _write_text(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8", newline="\n")
    return path


def write_sample_data(out_dir: Path | str = "sample_data") -> list[Path]:
    """Generate and write the sample-data folder; returns the written paths.

    Files: ``static.c3d``, ``walking.c3d``, ``walking_noisy.c3d``, ``subject.toml``,
    ``walking_truth_angles.csv``, ``walking_truth_joint_centres.csv``,
    ``walking_noisy_gaps.csv``, the CGM 2.4 session's
    :data:`~fuzzygait.synthetic.cgm24_sample.CGM24_SAMPLE_FILES` and ``README.md`` (see
    that README for the contents).
    """
    from fuzzygait.io.c3d import write_c3d  # deferred: keeps the generator importable

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    geometry = SubjectGeometry()
    static = make_static_trial(geometry=geometry)
    walking, truth = make_walking_trial(geometry=geometry)
    noisy, gaps = make_noisy_gapped(walking)

    plates = sample_walking_plates(walking.n_frames, walking.rate, geometry.bodymass, geometry)
    written: list[Path] = []
    for name, trial in (("static.c3d", static), ("walking.c3d", walking),
                        ("walking_noisy.c3d", noisy)):  # fmt: skip
        path = out / name
        write_c3d(trial, path)
        if trial is not static:
            add_force_plates(path, plates)
        written.append(path)
    written.append(_write_text(out / "subject.toml", subject_toml_text(walking.parameters)))
    written.append(_write_text(out / "walking_truth_angles.csv", truth_angles_csv_text(truth)))
    written.append(
        _write_text(out / "walking_truth_joint_centres.csv", truth_joint_centres_csv_text(truth))
    )
    written.append(_write_text(out / "walking_noisy_gaps.csv", gaps_csv_text(gaps)))
    written += cgm24_sample.write_cgm24_sample_data(out)
    written.append(_write_text(out / "README.md", readme_text(geometry, walking, gaps, plates)))
    return written


def readme_text(geometry: SubjectGeometry, walking: Trial, gaps: Sequence[CutGap],
                plates: Sequence[PlateRecording]) -> str:  # fmt: skip
    """The sample-data README (generated so that it always matches the files)."""
    offsets = static_offsets(geometry)
    hjc = geometry.hjc_local("L")
    params = "\n".join(f"| `{k}` | {v!r} |" for k, v in walking.parameters.items())
    gap_rows = "\n".join(f"| {g.marker} | {g.start_frame} | {g.length} |" for g in gaps)
    n_events = {
        (label, ctx): sum(1 for e in walking.events if e.label == label and e.context == ctx)
        for label in ("Foot Strike", "Foot Off")
        for ctx in ("Left", "Right")
    }
    events = ", ".join(f"{n} {ctx} {label}" for (label, ctx), n in n_events.items())
    return _README_TEMPLATE.format(
        n_frames=walking.n_frames,
        duration=walking.times[-1],
        rate=walking.rate,
        stride=STRIDE_TIME_S,
        speed=WALKING_SPEED_MM_S / 1000.0,
        height=MEAN_PELVIS_HEIGHT_MM,
        standing=geometry.standing_pelvis_height(),
        events=events,
        first_strike=LEAD_IN_CYCLES * STRIDE_TIME_S,
        noise=NOISE_MM,
        seed=NOISE_SEED,
        gap_rows=gap_rows,
        params=params,
        hjc_x=hjc[0],
        hjc_y=hjc[1],
        hjc_z=hjc[2],
        thigh=geometry.thigh_length,
        shank=geometry.shank_length,
        toe=geometry.toe_local,
        hee=geometry.hee_local,
        sole=geometry.sole_depth,
        pf_rad=offsets["plantarflexion"],
        pf_deg=np.degrees(offsets["plantarflexion"]),
        rot_rad=offsets["rotation"],
        **plate_readme_values(plates, geometry, walking.rate),
        cgm24_rows=cgm24_sample.readme_rows(cgm24_sample.make_cgm24_walking()[0]),
        cgm24_section=cgm24_sample.readme_section(),
    )


_README_TEMPLATE = """\
# Sample data: synthetic gait trials with known joint angles

Everything in this folder is generated by code (`fuzzygait.synthetic`); nothing is
measured or copied. Regenerate it (byte-identical) with

    python -m fuzzygait.synthetic sample_data

Synthetic subject "Synthetic": a Plug-in Gait / CGM 1.0 lower-body session (`static`,
`walking*`, `subject.toml`) and a CGM 2.4 session of the same person (`cgm24_*`, see
"CGM 2.4 session" below).

## Files

| file | content |
|---|---|
| `static.c3d` | standing trial, {rate:g} Hz, 2 s, every frame identical; all joint and pelvis angles 0, pelvis \
level, feet parallel along +X, soles on the floor (ASIS midpoint at X=Y=0, Z={standing:.3f} mm). Markers: LASI RASI \
LPSI RPSI LTHI LKNE LTIB LANK LHEE LTOE RTHI RKNE RTIB RANK RHEE RTOE + medial LKNM RKNM LMED RMED. No events. |
| `walking.c3d` | clean walking trial, {rate:g} Hz, {n_frames} frames (0 .. {duration:.2f} s), 4 complete gait cycles \
per side, the 16 dynamic markers. Events: {events}. Two force plates ({analog_rate:g} Hz; see "Force plates" \
below). |
| `walking_noisy.c3d` | `walking.c3d` + Gaussian noise (sigma = {noise} mm per coordinate, seed {seed}) + the gaps of \
`walking_noisy_gaps.csv`; same events and force plates (no noise on the plates). |
| `subject.toml` | subject parameters (Vicon `PROCESSING` names; mm, rad, kg), also stored in every C3D. |
| `walking_truth_angles.csv` | exact joint angles of `walking.c3d`: `frame` (1-based C3D frame), `time_s`, \
`LPelvisAngles_X/Y/Z`, `LHipAngles_*`, `LKneeAngles_*`, `LAnkleAngles_*`, then the same for R; degrees; X = sagittal, \
Y = frontal, Z = transverse. |
| `walking_truth_joint_centres.csv` | exact joint centres of `walking.c3d`: `frame`, `time_s`, `LHJC_X/Y/Z`, \
`LKJC_*`, `LAJC_*`, `RHJC_*`, `RKJC_*`, `RAJC_*`, mm, lab frame. |
| `walking_noisy_gaps.csv` | the gaps cut in `walking_noisy.c3d`: `marker`, `start_frame` (1-based C3D frame), \
`length` (frames). |
{cgm24_rows}
The C3D files store float32, so markers read back differ from the exact values by up to
~2e-4 mm; the CSVs carry 9 (angles) and 6 (positions) decimals.

## Conventions

* Lab frame: X = walking direction, Y = left, Z = up; mm. C3D frame n is at (n-1)/rate s.
* Segment frames (both sides): pelvis, thigh, shank: x anterior, y left, z proximal;
  foot: x anterior along the foot (HEE->TOE), y left, z dorsal. Origins: ASIS midpoint,
  HJC, KJC, AJC. At ankle angle 0 the foot frame equals the shank frame.
* Joint angles: `R_distal = R_proximal * R_y(fs*X) * R_x(as*Y) * R_z(rs*Z)` (intrinsic
  Y-X-Z, Grood-Suntay order: flexion about the proximal y, rotation about the distal z,
  adduction about the floating axis) for the pelvis, hip and knee. The ankle uses Vicon
  Plug-in Gait's Y-Z-X sequence in these frames: `R_foot = R_shank * R_y(fs*X) *
  R_z(rs*Z) * R_x(as*Y)` (foot rotation about the floating axis, Y last about the
  foot's long axis). The pelvis angles are the pelvis relative to the lab (=
  progression) frame. The signs reproduce what Vicon Nexus reports (checked against
  Nexus output with `fuzzygait.kinematics`).

| joint | fs | as L / R | rs L / R | + X | + Y | + Z |
|---|---|---|---|---|---|---|
| Pelvis | +1 | +1 / -1 | -1 / +1 | anterior tilt (ASIS below PSIS) | own side up | own ASIS forward |
| Hip | -1 | -1 / +1 | -1 / +1 | flexion (knee anterior) | adduction (knee medial) | internal rotation (lateral knee \
marker turns anterior) |
| Knee | +1 | -1 / +1 | -1 / +1 | flexion (ankle posterior) | varus (ankle medial) | internal rotation |
| Ankle | -1 | +1 / -1 | -1 / +1 | dorsiflexion (toe up) | Plug-in Gait "inversion" (see below) | internal rotation \
(toe medial) |

  Ankle Y: Vicon labels it inversion/adduction, but as Nexus computes it a positive
  value turns the foot about its long axis so that the lateral border rises (the sole
  faces laterally) on both sides. It is not a free curve here: Plug-in Gait's foot has
  only TOE and the ankle joint centre, its roll follows the tibia's flexion axis, so the
  Y it reports is `atan2(-sin(b0) sin(beta), cos(b0))` with `sin(b0) = sin(Z) /
  cos(beta)` and `beta` the static plantarflexion offset (cross-talk of the ankle
  rotation; `fuzzygait.synthetic.gait_curves.plug_in_gait_ankle_y`). The feet are posed
  accordingly, so the truth is exactly what Plug-in Gait reports.

* Gait timing: stride {stride} s; left Foot Strike at phase 0 (first at {first_strike:.2f} s),
  Foot Off at phase 0.6; the right side runs half a cycle later. Angle curves are
  Fourier series (<= 6 harmonics) of phase, see `fuzzygait/synthetic/gait_curves.py`.
* Pelvis: ASIS midpoint moves at {speed} m/s along +X (walk centred on X = 0), sways
  +-20 mm laterally once per stride and +-15 mm vertically twice per stride around
  Z = {height:g} mm; pelvis tilt 5 +- 1.5 deg, obliquity and rotation about +-4 deg.
  There is no foot-contact model: the lowest sole point stays within about +-15 mm of
  the floor and the stance foot slides a little.

## Geometry (exact; the Plug-in Gait reconstruction should find it)

* Hip joint centres at Plug-in Gait's Davis regression location in the pelvis frame:
  ({hjc_x:.6f}, +-{hjc_y:.6f}, {hjc_z:.6f}) mm.
* PSIS {{LPSI,RPSI}} 160 mm behind the ASIS, +-45 mm lateral, in the pelvis x-y plane
  (so SACR = their midpoint gives Plug-in Gait's pelvis x axis exactly).
* Thigh length (HJC-KJC) {thigh:g} mm, shank length (KJC-AJC) {shank:g} mm.
  KNE = KJC +- (KneeWidth/2 + MarkerDiameter/2) along the thigh y axis, ANK = AJC +-
  (AnkleWidth/2 + MarkerDiameter/2) along the shank y axis (lateral), so the chord
  constructions are exact. THI: mid-thigh, 75 mm lateral, in the thigh y-z plane
  (ThighRotation 0); TIB: mid-shank, 65 mm lateral, in the shank y-z plane
  (ShankRotation 0, TibialTorsion 0). Static KNM / MED are the medial mirror images.
* Foot (x, y, z relative to the AJC in the foot frame): TOE {toe} mm, HEE {hee} mm; the
  sole is {sole:g} mm below the AJC (TOE and HEE are 30 mm above the floor when
  standing). HEE->TOE is parallel to the foot x axis.
* Expected Plug-in Gait static offsets:
  static plantarflexion offset = angle between AJC->TOE and the foot x axis =
  **{pf_rad:.6f} rad ({pf_deg:.4f} deg)** (TOE below the AJC's x line);
  static rotation offset = **{rot_rad:.6f} rad** (TOE and HEE in the foot x-z plane).
  (`fuzzygait.synthetic.static_offsets()`.) Like trials calibrated in Nexus, every C3D
  file and `subject.toml` carry them as `L/RStaticPlantFlex` and `L/RStaticRotOff`.

## Force plates (in `walking.c3d` and `walking_noisy.c3d`)

The forces are **synthetic: plausible in shape and size, not measured**, and not the
result of any contact or muscle model (the walker has none; its stance foot slides a
little). They are drawn under the generator's feet so that the kinetics pipeline has
something realistic to work on (`fuzzygait.synthetic.force_plates`):

{plate_rows}

* Two floor plates, {plate_x:g} mm along X by {plate_y:g} mm, surface at Z = 0,
  `FORCE_PLATFORM:TYPE` 2 (Fx, Fy, Fz in N; Mx, My, Mz in N·mm about the transducer origin,
  `ORIGIN` = (0, 0, {origin_z:g}) mm below the surface centre), plate axes x = +X, y = -Y,
  z = -Z (down); the reaction on the body is stored (Fz < 0). Analog channels as Vicon Nexus
  writes them: {analog_rate:g} Hz ({per_frame} samples a marker frame, the first on frame 1),
  `ANALOG:SCALE` 1, `OFFSET` 0, `GEN_SCALE` 1, `UNITS` N / Nmm, labels `Force.Fx1` ...
  `Moment.Mz2`.
* Plate 1 carries the whole left stance starting at the second left Foot Strike, plate 2
  the right stance after it; each plate's centre is the middle of that stance's centre of
  pressure (rounded to the mm). No other foot touches a plate.
* Loads over a stance (s = 0 at Foot Strike, 1 at Foot Off), W = body weight
  ({bodymass:g} kg x 9.81 m/s²): vertical `W ({vert_a:.4f} sin(pi s) + {vert_b:g} sin(3 pi s))` (two
  peaks of {vert_peak:.2f} W, {vert_valley:.2f} W at mid-stance; over a stride both feet's vertical
  impulse is W x stride time); anterior-posterior `-{ap:g} W sin(2 pi s)` (braking, then
  propulsion); medio-lateral `{ml:g} W sin(pi s)` towards the midline; free moment about
  the vertical `{free:g} N·m sin(2 pi s)` (toe in, then out); centre of pressure on the
  horizontal heel-marker-to-toe-marker line of the stance foot at each sample, from
  {cop_a:.0%} to {cop_b:.0%} of the way as stance goes on.
* The joint moments and powers computed from them (`fuzzygait angles` or `fuzzygait demo`)
  are therefore plausible, not a real subject's: the loads and the generator's joint
  angles are not dynamically consistent (e.g. knee power absorption near Foot Off is larger
  than in normal gait). The kinetics pipeline itself is checked against closed-form truth in
  `tests/synthetic/test_kinetics_truth.py`.

{cgm24_section}
## Gaps in `walking_noisy.c3d`

| marker | start frame | length |
|---|---|---|
{gap_rows}

## Subject parameters

| name | value |
|---|---|
{params}
"""
