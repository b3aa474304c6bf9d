"""CGM 2.3 cluster tracking against CGM 1.0 under 1 mm marker noise (issue 14 acceptance).

Run:  .venv/bin/python benchmarks/cgm2_noise.py [--seeds 10] [--sigma 1.0]

The synthetic CGM 2.4 session of ``fuzzygait.synthetic.cgm24`` (the one in
``sample_data/cgm24_*``, generated in memory, float64): the **clean** static trial
calibrates; the walking trial gets i.i.d. Gaussian noise of ``sigma`` mm **per
coordinate** (3-D RMS ``sqrt(3) sigma``) on every marker in every frame
(``numpy.random.default_rng(seed)``, seeds 0 .. n-1, one draw of the whole
``(frames, markers, 3)`` array, as ``make_noisy_gapped``).  ``cgm1.0`` and ``cgm2.3`` run
on the *same* noisy trial (both sides), without and with the default 6 Hz low-pass.

The default session's true hip centres are Hara's, so ``cgm1.0`` (Davis hips) has a model
bias on it that is no noise effect.  Hence, per angle component:

* noise effect = noisy output - clean output of the *same* model (RMS over frames and
  seeds): what the marker noise does through each model's tracking;
* bias = clean output - truth (RMS over frames);
* for a fair total error of ``cgm1.0`` against the truth, the same noise on the same
  session with Davis hip centres (``hjc="davis"``, where ``cgm1.0`` is exact when clean).

The pelvis truth is in each model's order (``cgm1.0`` tilt-obliquity-rotation, ``cgm2.3``
rotation-obliquity-tilt).  Angle differences are wrapped into (-180, 180].
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from fuzzygait.core.trial import Trial  # noqa: E402
from fuzzygait.synthetic.cgm24 import make_cgm24_static, make_cgm24_walking  # noqa: E402
from fuzzygait.synthetic.cgm24_sample import rot_pelvis_angles  # noqa: E402
from fuzzygait.synthetic.generate import make_noisy_gapped  # noqa: E402
from fuzzygait.workflows.angles import Preprocessing, run_angles  # noqa: E402

ANGLES = ("Pelvis", "Hip", "Knee", "Ankle", "FootProgress")
COMPONENTS = [f"{side}{name}Angles_{axis}" for side in "LR" for name in ANGLES for axis in "XYZ"]
FILTERS = {"unfiltered": Preprocessing(filter=False), "6 Hz": Preprocessing()}


def truth_table(truth: pd.DataFrame, model: str) -> dict[str, np.ndarray]:
    """Truth per component in ``model``'s pelvis order."""
    out = {c: truth[c].to_numpy() for c in COMPONENTS}
    if model != "cgm1.0":
        for side in "LR":
            rot = rot_pelvis_angles(truth[[f"{side}PelvisAngles_{a}" for a in "XYZ"]].to_numpy(), side)
            for k, axis in enumerate("XYZ"):
                out[f"{side}PelvisAngles_{axis}"] = rot[:, k]
    return out


def angles(walking: Trial, static: Trial, model: str, preprocessing: Preprocessing) -> dict[str, np.ndarray]:
    result = run_angles(walking, static=static, preprocessing=preprocessing, model=model).result
    return {c: result.angles[c[:-2]][:, "XYZ".index(c[-1])] for c in COMPONENTS}


def wrapped(d: np.ndarray) -> np.ndarray:
    return (d + 180.0) % 360.0 - 180.0


def rms(d: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(d))))


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    info = Path("/proc/cpuinfo")
    if info.is_file():
        lines = info.read_text().splitlines()
        names = [line.split(":", 1)[1].strip() for line in lines if line.startswith("model name")]
        cpu = names[0] if names else cpu
    return f"{cpu}, Python {platform.python_version()}, one thread"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--sigma", type=float, default=1.0, help="noise SD per coordinate, mm")
    args = parser.parse_args()
    t0 = time.perf_counter()
    sessions = {}
    for hjc in ("hara", "davis"):
        walking, truth = make_cgm24_walking(hjc=hjc)
        sessions[hjc] = (make_cgm24_static(hjc=hjc), walking, truth)
    runs = [("cgm1.0", "hara"), ("cgm2.3", "hara"), ("cgm1.0", "davis")]

    tables = {}
    for fname, pre in FILTERS.items():
        clean = {(m, h): angles(sessions[h][1], sessions[h][0], m, pre) for m, h in runs}
        truths = {(m, h): truth_table(sessions[h][2], m) for m, h in runs}
        noise = {(key, c): [] for key in runs for c in COMPONENTS}  # per seed: noisy - clean
        total = {(key, c): [] for key in runs for c in COMPONENTS}  # per seed: noisy - truth
        for seed in range(args.seeds):
            for m, h in runs:
                static, walking, _ = sessions[h]
                noisy, _ = make_noisy_gapped(walking, noise_mm=args.sigma, seed=seed, gaps=[])
                out = angles(noisy, static, m, pre)
                for c in COMPONENTS:
                    noise[((m, h), c)].append(wrapped(out[c] - clean[(m, h)][c]))
                    total[((m, h), c)].append(wrapped(out[c] - truths[(m, h)][c]))
        rows = []
        for c in COMPONENTS:
            n10 = noise[(("cgm1.0", "hara"), c)]
            n23 = noise[(("cgm2.3", "hara"), c)]
            per_seed = [rms(b) / rms(a) for a, b in zip(n10, n23, strict=True)]
            rows.append({
                "component": c,
                "cgm1.0 noise": rms(np.concatenate(n10)),
                "cgm2.3 noise": rms(np.concatenate(n23)),
                "2.3/1.0": rms(np.concatenate(n23)) / rms(np.concatenate(n10)),
                "ratio range (seeds)": f"{min(per_seed):.2f}-{max(per_seed):.2f}",
                "cgm1.0 total, Davis session": rms(np.concatenate(total[(("cgm1.0", "davis"), c)])),
                "cgm2.3 total": rms(np.concatenate(total[(("cgm2.3", "hara"), c)])),
                "cgm1.0 bias, Hara session": rms(wrapped(clean[("cgm1.0", "hara")][c] - truths[("cgm1.0", "hara")][c])),
                "cgm2.3 bias": rms(wrapped(clean[("cgm2.3", "hara")][c] - truths[("cgm2.3", "hara")][c])),
            })  # fmt: skip
        tables[fname] = pd.DataFrame(rows)

    n = sessions["hara"][1].n_frames
    print(f"# CGM 2.3 clusters vs CGM 1.0, noise {args.sigma:g} mm SD per coordinate "
          f"({np.sqrt(3) * args.sigma:.2f} mm 3-D RMS), {args.seeds} seeds x {n} frames; RMS in degrees")  # fmt: skip
    print(f"# machine: {machine()}; {time.perf_counter() - t0:.1f} s")
    for fname, table in tables.items():
        print(f"\n## {fname}\n")
        cols = list(table.columns)
        print("| " + " | ".join(cols) + " |")
        print("|" + "---|" * len(cols))
        for row in table.itertuples(index=False):
            cells = [f"{v:.3g}" if isinstance(v, float) and k != "2.3/1.0" else f"{v:.2f}" if isinstance(v, float)
                     else str(v) for k, v in zip(cols, row, strict=True)]  # fmt: skip
            print("| " + " | ".join(cells) + " |")
        wins = int((table["2.3/1.0"] < 1.0).sum())
        print(f"\ncgm2.3's noise effect smaller in {wins} of {len(table)} components; ratio median "
              f"{table['2.3/1.0'].median():.2f}, min {table['2.3/1.0'].min():.2f} "
              f"({table.loc[table['2.3/1.0'].idxmin(), 'component']}), max {table['2.3/1.0'].max():.2f} "
              f"({table.loc[table['2.3/1.0'].idxmax(), 'component']})")  # fmt: skip


if __name__ == "__main__":
    main()
