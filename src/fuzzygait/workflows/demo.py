"""``fuzzygait demo``: the main job on the bundled synthetic sample.

Runs the joint-angle pipeline on ``walking_noisy.c3d`` (noise + gaps) with the static
calibration of ``static.c3d`` and ``subject.toml``, then writes

* ``angles.csv`` -- Plug-in Gait angles per frame (degrees),
* ``cycles.csv`` -- mean and SD over gait cycles,
* ``gait_cycles.png`` -- the gait-report grid,
* ``summary.md`` -- what was done; then how far to trust the knee angles: how small the
  marker errors must be for knee flexion to be known within ±2.5° (the allowable marker
  error), how wide their fuzzy bands are (determined bands first; "undetermined" where a
  segment frame can flip) and which marker error source dominates knee flexion (each
  source alone, thesis Fig. 5.9); then how close the angles are to the known truth
  (one row per angle, X / Y / Z); then the kinetics from the trial's two synthetic force
  plates (:func:`kinetics_lines`: the plates used per side, peak sagittal moments and
  powers over each foot's stance on its plate),
* ``report/index.html`` -- the clinicians' uncertainty report of the knee angles,
* ``session/session.html`` -- the session report of the synthetic Plug-in Gait session
  (``walking.c3d`` and ``walking_noisy.c3d`` with ``static.c3d`` and ``subject.toml``;
  ``report --uncertainty none``: angles, and the kinetics of the cycles whose stance is on
  a plate): the summary over every cycle of both trials, ``session/index.html`` the trial
  index with a page per trial,

and on the synthetic CGM 2.4 session (``cgm24_walking.c3d`` with ``cgm24_static.c3d``,
clean, not low-passed) with the richest model version its markers support
(:func:`~fuzzygait.kinematics.versions.supported_version`, what ``--model auto`` picks):

* ``cgm24_angles.csv`` -- its angles per frame (degrees),
* ``cgm24_accuracy.csv`` -- RMS and max |computed - truth| per angle component against
  ``cgm24_walking_truth_angles.csv`` (degrees; pelvis in CGM 2.x's order, as the truth).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from rich.console import Console

from fuzzygait.core.findings import FindingKind
from fuzzygait.core.names import AngleComponent, Side, angle_names
from fuzzygait.core.options import Option
from fuzzygait.io import read_c3d
from fuzzygait.io.figure_files import save_figure
from fuzzygait.io.tables import write_table
from fuzzygait.kinematics.labels import component_label
from fuzzygait.kinematics.versions import model_version, supported_version
from fuzzygait.mocap.gaps import methods_used
from fuzzygait.viz.figures import gait_cycles_figure
from fuzzygait.viz.report import TrialAnalysis
from fuzzygait.viz.report.allowable import allowable_summary
from fuzzygait.viz.report.bands import TrialData, delta_phi_table, headline
from fuzzygait.viz.report.sources import dominant_sentence
from fuzzygait.workflows.angles import AXES, AngleOutputs, AnglesRun, Preprocessing, run_angles
from fuzzygait.workflows.batch_report import BatchReportRequest, write_batch_report
from fuzzygait.workflows.kinetics import JOINTS as KINETIC_JOINTS
from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings, analyse_run
from fuzzygait.workflows.report_folder import ReportItem, write_report

#: The demo's fuzzy analysis: both knees, three α-levels (fast; the CLI does all angles).
DEMO_FUZZY_ANGLES = ("LKneeAngles", "RKneeAngles")
DEMO_ALPHAS = (0.0, 0.5, 1.0)
#: The allowable marker error for ±2.5° of knee flexion only (fast: the refinement of all
#: six knee components would add ~70 % to the demo's time; the CLI refines every angle).
DEMO_TOLERANCE: float | None = 2.5
DEMO_ALLOWABLE: tuple[str, ...] | None = ("LKneeAngles_X", "RKneeAngles_X")

#: The CGM 2.4 session's files the demo reads.
CGM24_FILES = ("cgm24_walking.c3d", "cgm24_static.c3d", "cgm24_subject.toml",
               "cgm24_walking_truth_angles.csv", "cgm24_walking_truth_joint_centres.csv")  # fmt: skip
SAMPLE_FILES = ("walking_noisy.c3d", "static.c3d", "subject.toml", "walking_truth_angles.csv", *CGM24_FILES)


def _ensure_sample_data(data: Path, progress: Console | None) -> None:
    if all((data / name).is_file() for name in SAMPLE_FILES):
        return
    from fuzzygait.synthetic import write_sample_data

    if progress is not None:
        progress.print(f"sample data not found in {data}; generating it", markup=False)
    data.mkdir(parents=True, exist_ok=True)
    write_sample_data(data)


def truth_comparison(run: AnglesRun, truth: pd.DataFrame, pelvis_sequence: str = "TOR") -> pd.DataFrame:
    """RMS and max |computed - truth| (degrees) of every angle component the run computed
    and ``truth`` has (columns ``<Angle>_X/Y/Z``, rows keyed by ``frame``), on common
    frames, in the truth's column order.

    ``pelvis_sequence`` is the order of the truth's pelvis angles (``"TOR"``: Plug-in
    Gait's, ``"ROT"``: CGM 2.x's); the pelvis is compared only when the model reports it in
    that order.
    """
    at_frames = truth.set_index("frame").reindex(run.trial.frames)
    same_pelvis = model_version(run.result.model).pelvis_sequence == pelvis_sequence
    rows = []
    for column in at_frames.columns:
        component = AngleComponent.maybe(column)  # the truth table's columns: the edge
        if component is None:
            continue
        name = component.angle
        if name not in run.result.angles or (component.joint == "PelvisAngles" and not same_pelvis):
            continue
        diff = run.result.angles[name][:, component.axis.column] - at_frames[column].to_numpy()
        diff = diff[np.isfinite(diff)]
        if diff.size:
            rows.append({"angle": column, "rms_deg": float(np.sqrt(np.mean(diff**2))),
                         "max_deg": float(np.max(np.abs(diff))), "frames": diff.size})  # fmt: skip
    return pd.DataFrame(rows, columns=["angle", "rms_deg", "max_deg", "frames"])


def accuracy_lines(comparison: pd.DataFrame) -> list[str]:
    """The per-component :func:`truth_comparison` as a Markdown table with one row per
    angle (``LHipAngles``) and its X / Y / Z values in one cell each: RMS and max
    |computed - truth| in degrees, 3 decimals; a component the comparison lacks is "–"."""
    lines = ["| angle | RMS X / Y / Z (°) | max X / Y / Z (°) |", "|---|---|---|"]
    by_component = comparison.set_index("angle")
    names = angle_names(str(column) for column in comparison["angle"])

    def cell(name: str, quantity: str) -> str:
        values = (by_component[quantity].get(f"{name}_{axis}") for axis in AXES)
        return " / ".join("–" if value is None else f"{value:.3f}" for value in values)

    lines += [f"| {name} | {cell(name, 'rms_deg')} | {cell(name, 'max_deg')} |" for name in names]
    return lines


def _centre_error(run: AnglesRun, truth: pd.DataFrame) -> tuple[float, list[str]]:
    """Max |computed - truth| (mm) over the joint centres both have, and their names."""
    at_frames = truth.set_index("frame").reindex(run.trial.frames)
    names = [n for n in run.result.joint_centres if all(f"{n}_{a}" in truth.columns for a in "XYZ")]
    errors = [np.nanmax(np.abs(run.result.joint_centres[n] - at_frames[[f"{n}_{a}" for a in "XYZ"]].to_numpy()))
              for n in names]  # fmt: skip
    return (float(max(errors)) if errors else float("nan")), names


def cgm24_session(data: Path, out_dir: Path) -> list[str]:
    """The CGM 2.4 part of the demo: angles and accuracy files; returns the summary lines."""
    walking, static = read_c3d(data / "cgm24_walking.c3d"), read_c3d(data / "cgm24_static.c3d")
    version, why = supported_version(walking, static)  # what model="auto" runs
    run = run_angles(walking, static=static, subject_file=data / "cgm24_subject.toml",
                     preprocessing=Preprocessing(filter=False), model="auto")  # fmt: skip
    AngleOutputs(table=out_dir / "cgm24_angles.csv").write(run)
    truth = pd.read_csv(data / "cgm24_walking_truth_angles.csv")
    accuracy = truth_comparison(run, truth, pelvis_sequence="ROT")
    # 6 significant digits: the errors are ~1e-5 deg (write_table keeps 6 decimals)
    accuracy.assign(model=version.name).to_csv(out_dir / "cgm24_accuracy.csv", index=False, float_format="%.6g")
    centre_mm, centres = _centre_error(run, pd.read_csv(data / "cgm24_walking_truth_joint_centres.csv"))
    angle_of_row = [AngleComponent.parse(label).angle for label in accuracy["angle"]]
    per_angle = accuracy.assign(name=angle_of_row, sq=accuracy["rms_deg"] ** 2).groupby(
        "name", sort=False).agg(rms=("sq", "mean"), max=("max_deg", "max"))  # fmt: skip
    lines = [
        "",
        "## CGM 2.4 session: `cgm24_walking.c3d` with `cgm24_static.c3d`",
        "",
        f"- model (`{Option.MODEL.flag} auto`) {run.result.model}: {why}",
        f"- {walking.n_frames} frames, {walking.n_markers} markers; clean (no noise, not low-passed), so the angles "
        "should equal the truth up to the C3D's float32 markers",
        f"- joint centres {', '.join(centres)}: max {centre_mm:.5f} mm from the truth",
        "",
        f"Computed ({version.name}) against `cgm24_walking_truth_angles.csv` (degrees, over X/Y/Z; per component in "
        "`cgm24_accuracy.csv`):",
        "",
        "| angle | RMS | max |",
        "|---|---|---|",
    ]
    lines += [f"| {name} | {np.sqrt(rms):.5f} | {top:.5f} |" for name, rms, top in per_angle.itertuples()]
    in_truth = angle_names(c for c in truth.columns if AngleComponent.maybe(c) is not None)
    missing = [name for name in in_truth if name not in per_angle.index]
    lines += [f"- truth angles not compared (not computed by {version.name}): {', '.join(missing)}"] if missing else []
    shown = [note for note in run.notes if note.kind not in (FindingKind.MODEL, FindingKind.GAP_FILLING)]
    lines += [""] + [f"- {note.message}" for note in shown]
    return lines


UNDETERMINED_TEXT = (
    '"undetermined": at that α-level the marker errors let the thigh or shank frame flip on some frames '
    "(a bound more than 90° from the measured angle), so the angle is not known there at all; ΔΦ is taken over "
    "the determined frames only."
)


def allowable_lines(analysis: TrialAnalysis) -> list[str]:
    """The summary's allowable-marker-error part: the knee-flexion sentences, then the
    table (mm on the largest ball, % of Table 3.1) -- what leads the report's first screen;
    nothing without the refinement."""
    summary = allowable_summary(analysis.result)
    if summary is None or not summary.rows:
        return []
    tau = f"±{summary.tolerance:g}°"
    flexion = {r.component for r in summary.rows} <= {"LKneeAngles_X", "RKneeAngles_X"}
    which = "knee flexion" if flexion else "the knee angles"
    lines = ["", f"How small the marker errors must be for {which} to be known within {tau} over the whole trial "
             "(the allowable marker error: the largest for which the band stays within the tolerance at every "
             "frame):", ""]
    lines += [f"- {sentence}" for sentence in summary.lead_sentences()]
    lines += ["", f"| angle | allowable error (mm) | % of {summary.source} |", "|---|---|---|"]
    lines += [f"| {row.component} ({row.label.lower()}) | {row.mm} | {row.percent} |"
              + (f" {row.note}" if row.note else "") for row in summary.rows]  # fmt: skip
    return lines


def uncertainty_lines(analysis: TrialAnalysis) -> list[str]:
    """The summary's fuzzy part: the allowable marker error of knee flexion
    (:func:`allowable_lines`), the determined bands (largest flexion ΔΦ), then what is
    undetermined, then the ΔΦ table ("undetermined" where an α-level is undetermined at
    some frame) -- the numbers of the report's first screen -- and, with per-source bands,
    the sentence naming the error source that dominates knee flexion."""
    table = delta_phi_table(analysis, TrialData.of(analysis))
    head = headline(table)
    alphas = table.alphas
    lines = allowable_lines(analysis) + [
        "",
        "How far to trust the knee angles: relative width ΔΦ (Eq. 5.3, %) of their fuzzy bands when every "
        "marker may be off by (1 − α) times its Table 3.1 error (measurement + placement + soft tissue). "
        + UNDETERMINED_TEXT,
        "",
    ]
    if head.largest is not None:
        value, name, alpha = head.largest
        lines.append(f"- determined bands: largest flexion ΔΦ {value:.0f} % at α = {alpha:g} "
                     f"({name}, {component_label(name).lower()})")  # fmt: skip
    else:
        lines.append("- no flexion band is determined at every frame at any α-level")
    if head.alpha is not None and head.undetermined:
        lowest = head.alpha
        text = f"- undetermined at α = {lowest:g}: {len(head.undetermined)} of {head.n_components} components"
        if head.flexion_undetermined:
            where = ", ".join(f"{n} on {table.frames_undetermined(n, lowest)}" for n in head.flexion_undetermined)
            text += f", flexion among them ({where} of {table.n_frames} frames)"
        lines.append(text)
    elif head.alpha is not None:
        lines.append(f"- every band is determined at α = {head.alpha:g}")
    lowest_alpha = min(alphas) if alphas else None
    extra = f" undetermined frames at α = {lowest_alpha:g} |" if lowest_alpha is not None else ""
    lines += ["", "| angle | " + " | ".join(f"α = {a:g}" for a in alphas) + " |" + extra,
              "|---|" + "---|" * (len(alphas) + (1 if extra else 0))]  # fmt: skip
    for name in table.components:
        cells = ["undetermined" if table.is_undetermined(name, a) else f"{table.value(name, a):.0f}" for a in alphas]
        if lowest_alpha is not None:
            count = table.frames_undetermined(name, lowest_alpha)
            cells.append(f"{count} of {table.n_frames}" if count else "none")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    if (sentence := dominant_sentence(analysis.result, "Knee")) is not None:
        lines += ["", f"Which marker error source dominates, each alone (thesis Fig. 5.9): {sentence}"]
    return lines


SYNTHETIC_FORCES_TEXT = (
    "The forces are synthetic: plausible in shape and size, drawn under the generator's feet, not measured "
    '(`sample_data/README.md`, "Force plates"); the moments and powers are what Plug-in Gait computes from them'
)


def kinetics_lines(run: AnglesRun) -> list[str]:
    """The summary's kinetics part: that the forces are synthetic, the plates used per
    side and each contact, then per side the peak (max / min) sagittal (X) ankle, knee and
    hip moments (N·m/kg, + plantarflexor/extensor) and powers (W/kg, + generation) over
    the frames of that foot's stance on its plate; one line without kinetics."""
    kinetics = run.kinetics
    if kinetics is None:
        return ["", "Kinetics: none computed (no force plates in the trial, or see the notes)."]
    lines = ["", f"## Kinetics of `{run.raw.source.name if run.raw.source else 'the trial'}` (Plug-in Gait, "
             "from the force plates)", "", f"- {SYNTHETIC_FORCES_TEXT}", f"- {kinetics.summary()}"]  # fmt: skip
    lines += [f"- {contact.finding(run.trial.first_frame).message}" for contact in kinetics.contacts]
    lines += ["", "Peaks over each foot's stance on its plate, max / min (moment X: + plantarflexor / extensor, "
              "N·m/kg; power: + generation, W/kg):", "",
              "| side | plate | ankle moment | knee moment | hip moment | ankle power | knee power | hip power |",
              "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for side in Side:
        stance = [np.arange(c.first, c.last + 1) for c in kinetics.contacts if c.side is side]
        if not stance:
            lines.append(f"| {side.word.lower()} | none |" + " – |" * 6)
            continue
        data = kinetics.data.sel(side=side.value).isel(frame=np.concatenate(stance))
        series = [data["moment"].sel(joint=j, axis="X").values for j in KINETIC_JOINTS]
        series += [data["power"].sel(joint=j).values for j in KINETIC_JOINTS]
        cells = [f"{np.nanmax(v):.2f} / {np.nanmin(v):.2f}" for v in series]
        plates = ", ".join(map(str, kinetics.plates_used(side)))
        lines.append(f"| {side.word.lower()} | {plates} | " + " | ".join(cells) + " |")
    return lines


def run_demo(data: Path, out_dir: Path, progress: Console | None = None) -> str:
    """Run the demo; returns the summary text (also written to ``summary.md``)."""
    data, out_dir = Path(data), Path(out_dir)
    _ensure_sample_data(data, progress)
    out_dir.mkdir(parents=True, exist_ok=True)
    run = run_angles(
        data / "walking_noisy.c3d", static=data / "static.c3d", subject_file=data / "subject.toml"
    )
    write_table(run.angle_table(), out_dir / "angles.csv")
    stats = run.cycle_statistics()
    write_table(stats, out_dir / "cycles.csv")
    save_figure(gait_cycles_figure(stats, title="Synthetic sample: joint angles (mean ± 1 SD)"),
                out_dir / "gait_cycles.png")  # fmt: skip
    comparison = truth_comparison(run, pd.read_csv(data / "walking_truth_angles.csv"))
    cgm24_lines = cgm24_session(data, out_dir)
    if progress is not None:
        progress.print("fuzzy marker-error analysis of the knee angles and the allowable error of knee flexion "
                       "(about 10 s)...", markup=False)
    settings = MarkerErrorSettings(alphas=DEMO_ALPHAS, angles=DEMO_FUZZY_ANGLES, tolerance=DEMO_TOLERANCE,
                                   allowable_angles=DEMO_ALLOWABLE)  # fmt: skip
    analysis = analyse_run(run, settings)
    index = write_report([ReportItem(data / "walking_noisy.c3d", analysis)], out_dir / "report")
    if progress is not None:
        progress.print("session report of both walking trials (no uncertainty, about 6 s)...", markup=False)
    session = write_batch_report(BatchReportRequest([data / "walking.c3d", data / "walking_noisy.c3d"],
                                                    out_dir / "session", static=data / "static.c3d",
                                                    subject_file=data / "subject.toml", uncertainty="none",
                                                    force=True))  # fmt: skip

    n_cycles = {side: int(stats[stats["angle"].str.startswith(side)]["n_cycles"].max())
                for side in ("L", "R")}  # fmt: skip
    filled = sum(g.filled for g in run.gaps)
    lines = [
        "# fuzzygait demo: synthetic walking trial",
        "",
        f"- input: `{data / 'walking_noisy.c3d'}` ({run.trial.n_frames} frames at {run.trial.rate:g} Hz, "
        f"{run.trial.n_markers} markers), noise 0.5 mm and gaps",
        f"- gaps: {filled} of {len(run.gaps)} filled ({methods_used(run.gaps) or 'none'}; max 10 frames); "
        "low-pass 6 Hz, 4th-order zero-lag Butterworth",
        f"- static offsets from `static.c3d`: plantarflexion L {np.degrees(run.subject.left.static_plant_flex):.3f}°, "
        f"R {np.degrees(run.subject.right.static_plant_flex):.3f}°; rotation L "
        f"{np.degrees(run.subject.left.static_rot_off):.3f}°, R {np.degrees(run.subject.right.static_rot_off):.3f}°",
        f"- gait cycles: left {n_cycles['L']}, right {n_cycles['R']} (events: {run.event_source})",
    ]
    lines += uncertainty_lines(analysis)
    lines += ["", "Computed angles against the known truth of the synthetic trial (degrees):", ""]
    lines += accuracy_lines(comparison)
    lines += kinetics_lines(run)
    lines += ["", f"Uncertainty report (knee angles): `{index}`"]
    lines += ["", "Session report (walking.c3d and walking_noisy.c3d; angles and the kinetics of the cycles on a "
              f"plate, no uncertainty bands): `{session.session_pages[0]}` "
              f"(mean ± SD over all cycles of both trials), trial pages from `{session.index}`"]
    lines += ["", "Notes:"] + [f"- {note.message}" for note in run.notes]
    lines += cgm24_lines
    lines += ["", "Files: `angles.csv`, `cycles.csv`, `gait_cycles.png`, `summary.md`, `report/index.html`, "
              "`session/session.html`, `session/index.html`, "
              "`cgm24_angles.csv`, `cgm24_accuracy.csv`"]
    summary = "\n".join(lines) + "\n"
    (out_dir / "summary.md").write_text(summary, encoding="utf-8")
    return summary
