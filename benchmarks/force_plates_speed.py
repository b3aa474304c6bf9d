"""Speed of the force-plate reading: file to laboratory-frame plates.

Run:  .venv/bin/python benchmarks/force_plates_speed.py

Writes (with ezc3d, in a temporary folder) a 60 s trial with 4 type-2 plates: 100 Hz
markers, 1000 Hz analog, 24 plate channels plus 8 others, walking-like loads. Times,
best of 5 after a warm-up, on one core (BLAS threads pinned to 1), reading included:

* ``read_force_plates(path)``: every analog sample, unfiltered;
* ``read_force_plates(path, marker_rate=100)``: low-passed (20 Hz) and resampled to the
  marker frames (what a kinetics run reads);
* ezc3d's own extraction, ``ezc3d.c3d(path, extract_forceplat_data=True)``, for scale.

Reported as marker frames per second (6,000 frames per file).
"""

from __future__ import annotations

from _setup import best_of, one_thread

one_thread()

import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

import ezc3d  # noqa: E402
import numpy as np  # noqa: E402

from fuzzygait.kinetics.plates import read_force_plates  # noqa: E402

POINT_RATE, ANALOG_RATE, SECONDS, PLATES, REPEATS = 100.0, 1000.0, 60, 4, 5


def _add_int(c: ezc3d.c3d, name: str, values: np.ndarray) -> None:
    param = ezc3d.ezc3d.Parameter(name, "")
    param.set(ezc3d.ezc3d.VecInt([int(v) for v in values.reshape(-1, order="F")]),
              ezc3d.ezc3d.VecUInt([int(d) for d in values.shape]))  # fmt: skip
    c._storage["parameters"].add_parameter("FORCE_PLATFORM", param)


def write_trial(path: Path) -> int:
    """The benchmark file; returns its marker frames."""
    n_frames = int(SECONDS * POINT_RATE)
    n = n_frames * int(ANALOG_RATE / POINT_RATE)
    t = np.arange(n) / ANALOG_RATE
    channels = []
    for p in range(PLATES):  # a step of 0.6 s every 2.4 s, shifted per plate
        phase = ((t - 0.6 * p) % 2.4) / 0.6
        load = np.where(phase < 1, np.sin(np.pi * np.clip(phase, 0, 1)), 0.0)
        fz = -700 * load + np.random.default_rng(p).normal(0, 1, n)
        channels += [0.2 * fz, 0.05 * fz, fz, -100 * fz, 40 * fz, 3 * fz]
    channels += [np.zeros(n)] * 8
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [POINT_RATE]
    c["parameters"]["ANALOG"]["RATE"]["value"] = [ANALOG_RATE]
    c["parameters"]["POINT"]["LABELS"]["value"] = ["M1"]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = [f"C{i + 1}" for i in range(len(channels))]
    c["parameters"]["ANALOG"]["UNITS"]["value"] = (["N"] * 3 + ["Nmm"] * 3) * PLATES + ["V"] * 8
    c["data"]["points"] = np.ones((4, 1, n_frames))
    c["data"]["analogs"] = np.array(channels)[np.newaxis]
    corners = np.zeros((3, 4, PLATES))
    for p in range(PLATES):
        x0 = 600.0 * p
        corners[:, :, p] = np.array([[x0 + 600, 400, 0], [x0, 400, 0], [x0, 0, 0], [x0 + 600, 0, 0]]).T
    _add_int(c, "USED", np.array([PLATES]))
    _add_int(c, "TYPE", np.full(PLATES, 2))
    _add_int(c, "ZERO", np.array([1, 0]))
    _add_int(c, "CHANNEL", np.arange(1, 6 * PLATES + 1).reshape(PLATES, 6).T)
    c.add_parameter("FORCE_PLATFORM", "CORNERS", corners)
    c.add_parameter("FORCE_PLATFORM", "ORIGIN", np.tile([[0.0], [0.0], [40.0]], (1, PLATES)))
    c.write(str(path))
    return n_frames


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "plates.c3d"
        frames = write_trial(path)
        rows = [
            ("read_force_plates(path) (analog rate, unfiltered)", best_of(lambda: read_force_plates(path), REPEATS)),
            ("read_force_plates(path, marker_rate=100) (20 Hz low-pass, resampled)",
             best_of(lambda: read_force_plates(path, marker_rate=POINT_RATE), REPEATS)),
            ("ezc3d.c3d(path, extract_forceplat_data=True)",
             best_of(lambda: ezc3d.c3d(str(path), extract_forceplat_data=True), 2)),
        ]  # fmt: skip
    print(f"## Force-plate reading ({SECONDS} s, {frames} marker frames, {PLATES} type-2 plates, "
          f"{ANALOG_RATE:g} Hz analog; one core, best of {REPEATS})")  # fmt: skip
    print("| what | seconds | marker frames/s |")
    print("|---|---|---|")
    for what, seconds in rows:
        print(f"| {what} | {seconds:.3f} | {frames / seconds:,.0f} |")


if __name__ == "__main__":
    main()
