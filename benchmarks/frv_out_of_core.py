"""The FRV-GFA output never has to fit in memory (thesis §2.7.4, Eq. 2.34).

The thesis' example of the storage problem: 100 000 samples × 2 000 time nodes × 5
α-levels × 2 hulls. That is 2·10⁹ values; Eq. 2.34 divides their *number* by 1024³ and
reports 1.86 GB, but as float64 (8 bytes each, as the text says) they take 16 GB
(14.9 GiB) — more than the RAM of most desktop computers.

:class:`~fuzzygait.uncertainty.frv.FRVStudy` writes the hulls block by block (``chunk``
samples at a time) into a zarr store on disk, and
:func:`~fuzzygait.uncertainty.frv.fit_distributions` streams them back block by block.
This script runs that at the thesis' size with a cheap analytic model (so the model is
not what is measured): a damped oscillator whose frequency grows with √E and whose
energy falls with 1/E, with exact sensitivities (so the Hermite refinement runs too),
2 001 time nodes over 2 s, E a fuzzy random variable about 59.958e9 Pa (Table 5.3,
N(1, 1) increments, 5 α-levels), N_p-disc = 100, chunk 256.

Measured per phase (create = steps 1–7 with the store writes; fit = a normal fit per
(α, bound, time) over all samples; reading one time node of all samples):

* peak resident memory: the process' high-water mark (``VmHWM``), reset before each
  phase through ``/proc/self/clear_refs`` where Linux allows it (otherwise only the
  cumulative ``resource.getrusage`` ``ru_maxrss`` is meaningful), and the resident set
  before the phase, so the phase's own growth is visible;
* with ``--tracemalloc``: the peak of memory allocated through Python and NumPy during
  the phase (slower; the allocation tracer costs time);
* wall time; the store's size on disk (the zarr default compressor) against the
  uncompressed array.

Usage::

    python benchmarks/frv_out_of_core.py [--samples 100000] [--time-nodes 2001]
        [--disc 100] [--chunk 256] [--store DIR] [--keep] [--tracemalloc]

Without ``--store`` the study goes into a temporary directory (on the same file system
as ``$TMPDIR``; it needs ≈ the printed disk size) that is removed at the end.
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import os  # noqa: E402
import resource  # noqa: E402
import shutil  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.uncertainty import FunctionModel  # noqa: E402
from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy, StudyOptions, fit_distributions, iter_hull_blocks  # noqa: E402

MODULUS = 59.958e9  # Pa, Table 5.3
ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)
GIB = 1024**3
MIB = 1024**2


# ------------------------------------------------------------------------------ model
def oscillator(n_time: int, duration: float = 2.0, frequency: float = 5.0, decay: float = 0.5) -> FunctionModel:
    """``f(t; E) = (E0/E)·(1 − cos ω t)/2·exp(−decay·t)``, ``ω = 2π·frequency·√(E/E0)``:
    the energy of a loaded spring-like blade, with its exact ``df/dE``."""
    times = np.linspace(0.0, duration, n_time)
    damping = np.exp(-decay * times)

    def parts(p: np.ndarray) -> tuple[float, np.ndarray, float, float]:
        e = float(np.asarray(p, dtype=float).ravel()[0])
        omega = 2.0 * np.pi * frequency * np.sqrt(e / MODULUS)
        return e, omega * times, MODULUS / e, omega

    def function(p: np.ndarray) -> np.ndarray:
        _, phase, g, _ = parts(p)
        return g * 0.5 * (1.0 - np.cos(phase)) * damping

    def jacobian(p: np.ndarray) -> np.ndarray:
        e, phase, g, omega = parts(p)
        dg = -g / e
        dphase = times * omega / (2.0 * e)  # d(ω t)/dE
        df = (dg * 0.5 * (1.0 - np.cos(phase)) + g * 0.5 * np.sin(phase) * dphase) * damping
        return df[:, None]

    return FunctionModel(function, times, jacobian)


# ------------------------------------------------------------------------------ memory
def _status_kib(field: str) -> int | None:
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def _reset_peak() -> bool:
    """Reset the kernel's resident high-water mark (Linux ≥ 4.0); False if not allowed."""
    try:
        with open("/proc/self/clear_refs", "w") as refs:
            refs.write("5")
        return True
    except OSError:
        return False


def _ru_maxrss_bytes() -> int:
    value = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return value if sys.platform == "darwin" else value * 1024  # KiB on Linux


@contextmanager
def phase(name: str, rows: list[dict], trace: bool):
    """Time a phase and record its memory: resident before, peak during."""
    reset = _reset_peak()
    rss_before = (_status_kib("VmRSS") or 0) * 1024
    if trace:
        tracemalloc.start()
    start = time.perf_counter()
    row: dict = {"phase": name}
    try:
        yield row
    finally:
        row["seconds"] = time.perf_counter() - start
        if trace:
            row["traced_peak"] = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
        hwm = _status_kib("VmHWM")
        row["rss_before"] = rss_before
        row["peak_rss"] = hwm * 1024 if (reset and hwm is not None) else None
        row["ru_maxrss"] = _ru_maxrss_bytes()
        rows.append(row)


def _size(path: Path) -> tuple[int, int]:
    """Bytes on disk (allocated blocks where known) and number of files under ``path``."""
    total, files = 0, 0
    for root, _, names in os.walk(path):
        for name in names:
            st = os.stat(os.path.join(root, name))
            total += getattr(st, "st_blocks", 0) * 512 or st.st_size
            files += 1
    return total, files


def _fmt(n: float | None) -> str:
    if n is None:
        return "n/a"
    return f"{n / GIB:.2f} GiB" if n >= GIB else f"{n / MIB:.0f} MiB"


# ------------------------------------------------------------------------------ main
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000, help="N_s (default 100000)")
    parser.add_argument("--time-nodes", type=int, default=2001, help="time nodes (default 2001: 2 s at 1 ms)")
    parser.add_argument("--disc", type=int, default=100, help="N_p-disc (default 100)")
    parser.add_argument("--chunk", type=int, default=256, help="samples per block and zarr chunk (default 256)")
    parser.add_argument("--store", type=Path, default=None, help="zarr directory (default: a temporary one)")
    parser.add_argument("--keep", action="store_true", help="keep the store")
    parser.add_argument("--tracemalloc", action="store_true", help="also trace Python/NumPy allocations (slower)")
    args = parser.parse_args()

    n_alpha, n_time = len(ALPHAS), args.time_nodes
    values = args.samples * n_alpha * 2 * n_time
    full_bytes = 8 * values
    block_bytes = 8 * min(args.chunk, args.samples) * n_alpha * 2 * n_time
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    print(f"hull array: {args.samples} samples × {n_time} time nodes × {n_alpha} α-levels × 2 hulls "
          f"= {values:.3g} values")  # fmt: skip
    print(f"   as float64: {full_bytes / 1e9:.2f} GB = {_fmt(full_bytes)}; Eq. 2.34 as printed (values / 1024³) "
          f"gives {values / GIB:.2f} — it leaves out the 8 bytes per value")
    print(f"   one block of {args.chunk} samples: {_fmt(block_bytes)}")

    model = oscillator(n_time)
    spec = FRVSpec("E", MODULUS, alphas=ALPHAS)
    tmp = None
    if args.store is None:
        tmp = Path(tempfile.mkdtemp(prefix="fuzzygait-frv-ooc-"))
        store = tmp / "study.zarr"
    else:
        store = args.store
        store.parent.mkdir(parents=True, exist_ok=True)
    rows: list[dict] = []
    baseline = (_status_kib("VmRSS") or 0) * 1024
    try:
        with phase("create", rows, args.tracemalloc) as row:
            study = FRVStudy.create(model, spec, args.samples,
                                    StudyOptions(n_disc=args.disc, seed=0, chunk=args.chunk, overwrite=True),
                                    store=store)  # fmt: skip
        counts = study.counts
        row["note"] = (f"{counts['forward_simulations']} forward simulations, {counts['occurring_intervals']} "
                       f"occurring of {counts['possible_intervals']} possible intervals")  # fmt: skip
        disk, files = _size(store)
        hull_disk, _ = _size(store / "samples" / "hull")

        with phase("fit_distributions (normal, hulls)", rows, args.tracemalloc) as row:
            fit = fit_distributions(store, kind="normal", data="hulls")
        row["note"] = f"mean/std over {dict(fit.sizes)}"

        node = n_time // 2
        with phase(f"one time node of all samples (node {node})", rows, args.tracemalloc) as row:
            # copy: a view of the block would keep the whole block (all time nodes) alive
            column = np.concatenate([block[..., node].copy() for block in iter_hull_blocks(store)])
        row["note"] = f"{column.shape} read block by block"
        check = float(np.abs(column.mean(axis=0) - fit["mean"].values[..., node]).max())
    finally:
        if tmp is not None and not args.keep:
            shutil.rmtree(tmp, ignore_errors=True)

    print(f"\nstore: {store}{'' if args.keep or tmp is None else ' (removed)'}")
    print(f"   on disk: {_fmt(disk)} in {files} files (hulls {_fmt(hull_disk)}; "
          f"{full_bytes / max(hull_disk, 1):.1f}× smaller than the float64 array)")
    print(f"resident memory after imports and model: {_fmt(baseline)}")
    print(f"\n{'phase':<42} {'wall':>8} {'RSS before':>11} {'peak RSS':>10} {'ru_maxrss':>10}"
          + (f" {'traced peak':>12}" if args.tracemalloc else ""))
    for r in rows:
        print(f"{r['phase']:<42} {r['seconds']:>7.1f}s {_fmt(r['rss_before']):>11} {_fmt(r['peak_rss']):>10} "
              f"{_fmt(r['ru_maxrss']):>10}" + (f" {_fmt(r['traced_peak']):>12}" if args.tracemalloc else ""))
        if r.get("note"):
            print(f"   {r['note']}")
    peak = max((r["peak_rss"] or r["ru_maxrss"]) for r in rows)
    print(f"\nlargest peak RSS {_fmt(peak)} = {100 * peak / full_bytes:.1f} % of the {_fmt(full_bytes)} hull array")
    print(f"streamed column mean vs fit_distributions mean at node {node}: max |difference| {check:.2e}")


if __name__ == "__main__":
    main()
