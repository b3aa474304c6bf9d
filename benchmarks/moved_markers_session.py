"""The shared Qualisys CGM 2.4 session's static and walking trials (issue 15): which
markers moved between them, and what its fuzzy flexion bands become with the one marker
that can be rebuilt, TOE, put back where the static trial has it.

Run:  .venv/bin/python benchmarks/moved_markers_session.py [--workers 2]

Prints

1. per segment (pelvis; each side's thigh, shank and foot markers) the static / walking
   medians of every marker pair's distance and the product's moved-marker notes
   (:func:`fuzzygait.mocap.sanity.moved_markers`);
2. the walking trial with each side's TOE rebuilt from the three foot markers that kept
   their places (HEE, SMH, VMH: the static trial's TOE carried by their least-squares
   rigid motion, :func:`fuzzygait.kinematics.rigid.fit_rigid`; rms residual of that fit),
   its flexion ranges and ankle frontal angle beside the trial as recorded; and that
   trial with TIAD (moved on both shanks) left out, the shank clusters then tracked by
   TIAP, TIB and ANK;
3. the fuzzy flexion bands of the three trials (cgm2.4, Table 3.1 radii, all three sources,
   the default optimiser, α = 0, 0.25, 0.5, 0.75, 1, every 2nd frame as
   ``markererror_table52.py``): ΔΦ (Eq. 5.3) per α-level and the α-levels where a band
   is undetermined somewhere.

Skipped (with a line saying so) when ``../shared/data/cgm2`` is absent.
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import itertools  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402
from _sessions import SESSION, sparse_run  # noqa: E402

from fuzzygait.core.trial import Trial  # noqa: E402
from fuzzygait.io import read_c3d  # noqa: E402
from fuzzygait.kinematics.rigid import fit_rigid  # noqa: E402
from fuzzygait.markererror import analysis as marker_error  # noqa: E402
from fuzzygait.mocap.sanity import SEGMENT_MARKERS, moved_markers  # noqa: E402
from fuzzygait.workflows.angles import AnglesRun, run_angles  # noqa: E402

ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: The foot markers whose distances to each other kept their static values (within
#: 3 mm on both feet) and that rebuild TOE.
KEPT_FOOT = ("HEE", "SMH", "VMH")


def distance_table(static: Trial, walking: Trial) -> None:
    """Static / walking median distance (mm) of every marker pair within a segment."""
    for segment, markers in SEGMENT_MARKERS.items():
        for side in ("",) if segment == "pelvis" else ("L", "R"):
            names = [side + m for m in markers if static.has_marker(side + m) and walking.has_marker(side + m)]
            cells = []
            for a, b in itertools.combinations(names, 2):
                before = np.nanmedian(np.linalg.norm(static.marker(a) - static.marker(b), axis=1))
                now = np.nanmedian(np.linalg.norm(walking.marker(a) - walking.marker(b), axis=1))
                cells.append(f"{a}-{b} {before:.0f}/{now:.0f}")
            print(f"  {side or ''}{segment}: " + "; ".join(cells))


def rebuild_toe(static: Trial, walking: Trial) -> tuple[Trial, dict[str, float]]:
    """``walking`` with each side's TOE replaced by the static trial's TOE carried by the
    rigid motion of :data:`KEPT_FOOT` from the static to each walking frame, and the rms
    fit residual (mm) per side."""
    markers = walking.markers.copy()
    residual = {}
    for side in "LR":
        kept = [side + m for m in KEPT_FOOT]
        local = np.array([np.nanmean(static.marker(m), axis=0) for m in kept])
        observed = np.stack([walking.marker(m) for m in kept], axis=1)
        fit = fit_rigid(local, observed)
        toe = np.nanmean(static.marker(side + "TOE"), axis=0)
        markers[:, walking.marker_labels.index(side + "TOE")] = fit.to_lab(toe)
        fitted = np.stack([fit.to_lab(local[k]) for k in range(len(kept))], axis=1)
        residual[side] = float(np.sqrt(np.nanmean(np.sum((fitted - observed) ** 2, axis=2))))
    return replace(walking, markers=markers), residual


def describe(label: str, run: AnglesRun) -> None:
    parts = []
    for side in "LR":
        for joint in ("Hip", "Knee", "Ankle"):
            flexion = run.result.angles[f"{side}{joint}Angles"][:, 0]
            parts.append(f"{side}{joint} {np.nanmin(flexion):.1f}..{np.nanmax(flexion):.1f}")
        frontal = run.result.angles[f"{side}AnkleAngles"][:, 1]
        parts.append(f"{side}Ankle frontal median {np.nanmedian(frontal):.1f}")
    print(f"  {label}: flexion (deg) " + ", ".join(parts))


def bands(label: str, run: AnglesRun, workers: int) -> None:
    frames = np.arange(0, run.trial.n_frames, 2)
    sparse = sparse_run(run, frames)
    names = [f"{s}{j}Angles" for s in "LR" for j in ("Hip", "Knee", "Ankle")]
    start = time.perf_counter()
    options = marker_error.FuzzyAngleOptions(alphas=ALPHAS, workers=workers)
    fuzzy = marker_error.fuzzy_joint_angles(sparse.trial, sparse.subject, sparse.result, options, names,
                                            clusters=sparse.clusters)  # fmt: skip
    seconds = time.perf_counter() - start
    delta, undetermined = marker_error.relative_envelope_width(fuzzy), marker_error.undetermined_levels(fuzzy)
    print(f"  {label} ({frames.size} frames, {seconds:.0f} s): flexion ΔΦ % at α = 0.75 / 0.5 / 0.25 / 0, "
          "'u' = undetermined somewhere at that level (determined frames' value; "
          "'–': no frame determined)")  # fmt: skip
    for name in names:
        row = name + "_X"
        cells = [("u" if undetermined.loc[row, a] else "")
                 + (f"{delta.loc[row, a]:.0f}" if np.isfinite(delta.loc[row, a]) else "–")
                 for a in (0.75, 0.5, 0.25, 0.0)]  # fmt: skip
        print(f"    {name[:-6]:7s} " + " / ".join(cells))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    if not SESSION.is_dir():
        print(f"skipped: {SESSION} is absent")
        return
    static = read_c3d(SESSION / "Static - CGM2 1.c3d")
    walking = read_c3d(SESSION / "Gait - CGM2 1.c3d")
    print("1. static / walking median distances (mm)")
    distance_table(static, walking)
    print("   notes:")
    for note in moved_markers(static, walking):
        print("   -", note)
    rebuilt, residual = rebuild_toe(static, walking)
    print(f"2. TOE rebuilt from {', '.join(KEPT_FOOT)}: rms fit residual L {residual['L']:.1f} mm, "
          f"R {residual['R']:.1f} mm")  # fmt: skip
    runs = {}
    no_tiad = rebuilt.markers.copy()
    for name in ("LTIAD", "RTIAD"):  # moved on both sides: the shank clusters tracked by the other three
        no_tiad[:, rebuilt.marker_labels.index(name)] = np.nan
    variants = (("as recorded", walking), ("TOE rebuilt", rebuilt),
                ("TOE rebuilt, TIAD left out", replace(rebuilt, markers=no_tiad)))  # fmt: skip
    for label, trial in variants:
        runs[label] = run_angles(trial, static=SESSION / "Static - CGM2 1.c3d", subject_file=SESSION / "session.xml",
                                 model="cgm2.4", flat_foot=True)  # fmt: skip
        describe(label, runs[label])
    print("3. fuzzy flexion bands (cgm2.4)")
    for label, run in runs.items():
        bands(label, run, args.workers)


if __name__ == "__main__":
    main()
