"""Do an FRV study's hulls stay in the range its forward simulations produced? (issue 37.3)

Reads a one-parameter FRV study (``fuzzygait frv-sim ... --out STORE``) and reports, per
stage of the FRV-GFA, how many values leave the range of the simulations they were made
from and how far:

* ``library``: the forward simulations themselves (bin centres);
* ``intervals``: the interval dictionary (α < 1 hulls) against the extreme library values
  over the interval's bins (what the thesis' post-processing takes, §2.7.4);
* ``alpha=1``: each sample's α = 1 value against the values at its interpolation cell's
  two corners (bin centres around the raw peak);
* ``stored``: every stored hull value against the simulations of the bins it was made
  from (its interval's bins and those of every higher α-level's, which nesting repair
  propagates down, and the α = 1 cell);

and the share of stored values below ``--below`` (default −1e-3, for an energy) and
their minimum.

Usage::

    python benchmarks/frv_hull_range.py STORE [--below -1e-3]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from fuzzygait.uncertainty.frv import range_extrema
from fuzzygait.uncertainty.frv.store import read_group, read_meta


def _report(name: str, values: np.ndarray, low: np.ndarray, high: np.ndarray, tol: float) -> None:
    below, above = low - values, values - high
    out = (below > tol) | (above > tol)
    print(f"{name:10s} values {values.size:9d}  outside the simulated range: {out.mean():7.2%}  "
          f"below by up to {max(0.0, float(below.max())):.4g}, above by up to {max(0.0, float(above.max())):.4g}  "
          f"min {values.min():.4g}  max {values.max():.4g}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("store", type=Path)
    parser.add_argument("--below", type=float, default=-1e-3, help="report the share of stored values below this")
    args = parser.parse_args()
    meta = read_meta(args.store)
    lib = read_group(args.store, "library").sortby("bin")
    values = lib["value"].to_numpy()
    first = int(lib["bin"][0])
    spread = float(np.ptp(values))
    tol = 1e-12 * max(spread, 1.0)
    print(f"{args.store}: {meta['n_samples']} samples, {values.shape[0]} simulations, grid {meta['grid']}")
    _report("library", values, values, values, tol)
    table = read_group(args.store, "intervals")
    left, right = table["left"].to_numpy() - first, table["right"].to_numpy() - first
    low, high = range_extrema(values, values, left, right)
    _report("intervals", np.stack([table["lower"], table["upper"]]), np.stack([low, low]), np.stack([high, high]), tol)
    samples = read_group(args.store, "samples")
    hull, bins, cuts = samples["hull"].to_numpy(), samples["bin"].to_numpy() - first, samples["cut"].to_numpy()
    grid = meta["grid"]
    u = (cuts[:, -1, 0] - grid["origin"]) / grid["spacing"] - 0.5 - first
    k = np.clip(np.floor(u).astype(np.int64), 0, values.shape[0] - 2)
    cell_lo, cell_hi = np.minimum(values[k], values[k + 1]), np.maximum(values[k], values[k + 1])
    _report("alpha=1", hull[:, -1, 0], cell_lo, cell_hi, tol)
    # every stored value against the bins it was made from (intervals nested, α = 1 cell)
    lo_bin = np.minimum(np.minimum.accumulate(bins[:, ::-1, 0], axis=1)[:, ::-1], k[:, None])
    hi_bin = np.maximum(np.maximum.accumulate(bins[:, ::-1, 1], axis=1)[:, ::-1], k[:, None] + 1)
    low, high = range_extrema(values, values, lo_bin.ravel(), hi_bin.ravel())
    shape = (*lo_bin.shape, 1, values.shape[1])
    _report("stored", hull, low.reshape(shape), high.reshape(shape), tol)
    n_alpha = hull.shape[1]
    print(f"stored values below {args.below:g}: {np.mean(hull < args.below):.2%} (min {hull.min():.4g}); "
          f"below 0: {np.mean(hull < 0):.2%}; α = 1 below 0: {np.mean(hull[:, -1] < 0):.2%}; "
          f"mean {hull.mean():.4g}")  # fmt: skip
    for a in range(n_alpha):
        print(f"  alpha[{a}]: below {args.below:g} {np.mean(hull[:, a] < args.below):6.2%}  min {hull[:, a].min():.4g}")


if __name__ == "__main__":
    main()
