"""Gait-cycle-normalised fuzzy bands of one angle component (:func:`cycle_bands`): the
mean over the cycles of the measured angle and of each α-level's lower and upper hull,
undetermined points left out (:func:`band_undetermined` tells them), and the hulls of a
component read from the fuzzy marker-error dataset (:func:`component_levels`, through
:mod:`fuzzygait.markererror.result` only).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from fuzzygait.gait.cycles import GaitCycle, normalise_cycles, percent_points
from fuzzygait.markererror.result import angle_components, component_hull, component_undetermined

if TYPE_CHECKING:
    import xarray as xr

#: Samples per normalised gait cycle (0, 1, ..., 100 %).
N_POINTS = 101
#: α-levels closer to 1 than this count as the measured curve.
ALPHA_ONE = 1.0 - 1e-9


def component_levels(
    fuzzy: xr.Dataset, name: str, frames: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(alphas < 1 ascending, hull (n_alpha, 2 [lower, upper], n_frames) deg,
    undetermined (n_alpha, n_frames) bool)`` of one angle component on ``frames``, or
    None when the analysis did not cover it."""
    if name not in angle_components(fuzzy):
        return None
    data = component_hull(fuzzy, name)
    flags = component_undetermined(fuzzy, name)
    if "frame" in data.dims and "frame" in fuzzy.coords:
        data = data.reindex(frame=np.asarray(frames))
        flags = flags.reindex(frame=np.asarray(frames), fill_value=False)
    data = data.sel(bound=["lower", "upper"]).transpose("alpha", "bound", "frame")
    flags = flags.transpose("alpha", "frame")
    alphas = np.asarray(data["alpha"].values, dtype=float)
    keep = alphas < ALPHA_ONE
    if not keep.any():
        return None
    order = np.argsort(alphas[keep])
    values = np.asarray(data.values, dtype=float)[keep][order]
    mask = np.asarray(flags.values, dtype=bool)[keep][order]
    return alphas[keep][order], values, mask


def _quiet_undetermined(signal: np.ndarray, hull: np.ndarray, undetermined: np.ndarray) -> np.ndarray:
    """``hull`` with its undetermined bounds replaced by the measured angle plus the band
    offset interpolated linearly from the determined frames of the same α-level and bound,
    so the cycle splines do not carry the meaningless bounds into the neighbouring
    percentages (those points are marked undetermined anyway)."""
    out = np.array(hull, dtype=float, copy=True)
    frames = np.arange(signal.size)
    for k in range(out.shape[0]):
        bad = undetermined[k]
        if not bad.any():
            continue
        for b in range(out.shape[1]):
            offset = out[k, b] - signal
            good = ~bad & np.isfinite(offset)
            fill = np.interp(frames[bad], frames[good], offset[good]) if good.any() else 0.0
            out[k, b, bad] = signal[bad] + fill
    return out


def _cycle_flags(flags: np.ndarray, cycles: Sequence[GaitCycle], n_points: int) -> np.ndarray:
    """``(n_cycles, n_points, n_alpha)``: a normalised point is flagged when either
    frame around its sample (``start + p/100 (end - start)``) is flagged in ``flags``
    ``(n_frames, n_alpha)``."""
    percent = percent_points(n_points)
    last = flags.shape[0] - 1
    out = np.zeros((len(cycles), percent.size, flags.shape[1]), dtype=bool)
    for c, cycle in enumerate(cycles):
        sample = cycle.start + percent / 100.0 * (cycle.end - cycle.start)
        low = np.clip(np.floor(sample + 1e-9).astype(int), 0, last)
        high = np.clip(np.ceil(sample - 1e-9).astype(int), 0, last)
        out[c] = flags[low] | flags[high]
    return out


def cycle_bands(
    signal: np.ndarray,
    hull: np.ndarray,
    cycles: Sequence[GaitCycle],
    n_points: int = N_POINTS,
    undetermined: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Gait-cycle-normalised mean curve and fuzzy bands of one angle component.

    Args:
        signal: ``(n_frames,)`` measured angle (deg).
        hull: ``(n_alpha, 2, n_frames)`` lower/upper hull per α-level (deg).
        cycles: the side's gait cycles (:func:`gait_cycles`).
        undetermined: ``(n_alpha, n_frames)`` True where the α-level's band is
            undetermined (the segment frame can flip); None: everywhere determined.

    Returns:
        ``(mean (n_points,), band (n_alpha, 2, n_points), n_cycles)``: the mean over
        cycles of the normalised angle and of the normalised lower and upper hulls,
        using at each percentage only the cycles where the angle and all hulls are
        finite; ``n_cycles`` is the largest number of cycles used.  The band is NaN at
        a percentage where the α-level is undetermined in *any* cycle used there (a
        mean with one meaningless bound is meaningless; the mean curve itself is
        unaffected): where the mean curve is finite, a NaN band means "undetermined".
    """
    n_alpha = hull.shape[0]
    if not cycles:
        return np.full(n_points, np.nan), np.full((n_alpha, 2, n_points), np.nan), 0
    signal = np.asarray(signal, dtype=float)
    hull = np.asarray(hull, dtype=float)
    flags = None
    if undetermined is not None and n_alpha and np.any(undetermined):
        flags = np.asarray(undetermined, dtype=bool)
        hull = _quiet_undetermined(signal, hull, flags)
    curve = normalise_cycles(signal, cycles, n_points)  # (c, p)
    hulls = normalise_cycles(np.moveaxis(hull, -1, 0), cycles, n_points)  # (c, p, a, 2)
    valid = np.isfinite(curve) & np.isfinite(hulls).all(axis=(2, 3))  # (c, p)
    count = valid.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(valid, curve, 0.0).sum(axis=0) / count
        band = np.where(valid[:, :, None, None], hulls, 0.0).sum(axis=0) / count[:, None, None]
    mean[count == 0] = np.nan
    band[count == 0] = np.nan
    if flags is not None:
        flagged = (_cycle_flags(flags.T, cycles, n_points) & valid[:, :, None]).any(axis=0)  # (p, a)
        band[flagged] = np.nan
    return mean, np.moveaxis(band, 0, -1), int(count.max())


def band_undetermined(curve: np.ndarray, band: np.ndarray | None) -> np.ndarray | None:
    """``(n_alpha, n_points)`` True where :func:`cycle_bands` left the band out as
    undetermined (curve finite, band NaN); None without a band."""
    if band is None:
        return None
    return np.isfinite(curve)[None, :] & ~np.isfinite(band).all(axis=1)
