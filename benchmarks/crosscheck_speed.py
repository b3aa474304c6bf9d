"""Cost of the cross-check with a file's stored angles and of the marker-diameter recovery
in ``fuzzygait angles`` (issue 36: within 10 % of the time without them).

Run:  .venv/bin/python benchmarks/crosscheck_speed.py [--frames 10000] [--repeats 7]

Makes a synthetic walking trial of at least ``--frames`` frames at 100 Hz, stores the
Plug-in Gait angles and virtual markers of a 16 mm run in it as Nexus does (PROCESSING
without MarkerDiameter), writes it to a temporary C3D and times
:func:`fuzzygait.workflows.angles.angles_to_files` (read, content checks, gap filling,
6 Hz low-pass, model, events, the CSV table) on it, alternating in one process:

* **baseline** -- the cross-check (``check_run``) and the diameter recovery
  (``recover_marker_diameter``) replaced by no-ops, i.e. the pipeline as before them;
* **full** -- as shipped: the diameter recovered from the file's outputs, the model once
  more on the file's markers and compared with the stored angles.

Prints the medians and the ratio full / baseline.
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from fuzzygait.io import write_c3d  # noqa: E402
from fuzzygait.kinematics.marker_size import RecoveredDiameter  # noqa: E402
from fuzzygait.synthetic.generate import make_walking_trial  # noqa: E402
from fuzzygait.synthetic.leg_model import SubjectGeometry  # noqa: E402
from fuzzygait.workflows import angles as angles_module  # noqa: E402
from fuzzygait.workflows import subject_resolution  # noqa: E402
from fuzzygait.workflows.angles import AngleOutputs, Preprocessing, angles_to_files, model_output_trial, run_angles  # noqa: E402,E501
from fuzzygait.workflows.trial_inputs import TrialInputs  # noqa: E402


def stored_trial(folder: Path, frames: int) -> Path:
    """The synthetic trial with stored 16 mm Plug-in Gait outputs, as a C3D file."""
    cycles = max(1, int(frames / 110) + 1)
    walking, _ = make_walking_trial(n_cycles=cycles, geometry=SubjectGeometry(marker_diameter=16.0))
    out = model_output_trial(run_angles(walking, preprocessing=Preprocessing(filter=False)))
    out.parameters.pop("MarkerDiameter")
    out.events = out.events[:250]  # a C3D parameter holds at most 255 values per dimension
    path = folder / "long.c3d"
    write_c3d(out, path)
    return path


def timed(path: Path, table: Path) -> float:
    start = time.perf_counter()
    angles_to_files(TrialInputs(path, model="cgm1.0"), AngleOutputs(table=table))
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    check_run, recover = angles_module.check_run, subject_resolution.recover_marker_diameter

    def off() -> None:
        angles_module.check_run = lambda *a, **k: None  # type: ignore[assignment]
        subject_resolution.recover_marker_diameter = lambda *a, **k: RecoveredDiameter(None, {}, reason="off")  # type: ignore[assignment]  # noqa: E501

    def on() -> None:
        angles_module.check_run, subject_resolution.recover_marker_diameter = check_run, recover

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path = stored_trial(folder, args.frames)
        run = run_angles(path)
        print(f"trial: {run.raw.n_frames} frames at {run.raw.rate:g} Hz; {run.diameter.note if run.diameter else ''}")
        print(f"cross-check: {(run.crosscheck.notes() if run.crosscheck else ['none'])[0][:160]}...")
        timed(path, folder / "warm.csv")  # imports and caches
        times: dict[str, list[float]] = {"baseline": [], "full": []}
        for _ in range(args.repeats):
            for name, switch in (("baseline", off), ("full", on)):
                switch()
                times[name].append(timed(path, folder / f"{name}.csv"))
        on()
    base, full = statistics.median(times["baseline"]), statistics.median(times["full"])
    print(f"angles_to_files, median of {args.repeats} alternated runs: baseline {base:.3f} s, "
          f"with recovery + cross-check {full:.3f} s, ratio {full / base:.3f} (target <= 1.10)")


if __name__ == "__main__":
    main()
