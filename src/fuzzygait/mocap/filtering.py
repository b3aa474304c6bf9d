"""Zero-lag Butterworth low-pass filtering of marker trajectories.

Order convention (biomechanics, after Winter)
---------------------------------------------
``order`` is the **effective order of the zero-lag filter after both passes**.  A
"4th-order zero-lag Butterworth" is a 2nd-order digital Butterworth run forward and then
backward, so the design order per pass is ``n = order / 2`` and ``order`` must be a
positive even integer.

Cutoff correction
-----------------
A digital (bilinear, pre-warped) Butterworth of order ``n`` and cutoff ``f_w`` has

    |H(f)|^2 = 1 / (1 + (tan(pi f / fs) / tan(pi f_w / fs))^(2n)).

The forward-backward pass applies ``H`` twice with opposite phase, so the combined
amplitude response is ``|H(f)|^2`` (zero phase).  Asking it to be ``1/sqrt(2)``
(-3.01 dB) at the requested ``cutoff`` ``f_c`` gives

    (tan(pi f_c / fs) / tan(pi f_w / fs))^(2n) = sqrt(2) - 1
    tan(pi f_w / fs) = tan(pi f_c / fs) / C,   C = (sqrt(2) - 1)^(1 / (2n)),

(``C = 0.802`` for ``n = 2``, Winter's correction factor), so the per-pass design
cutoff ``f_w`` lies above ``f_c`` and the combined response is exactly -3.01 dB at
``f_c``.  :func:`combined_gain_db` evaluates this combined response analytically.

Implementation
--------------
:func:`scipy.signal.butter` (``output="sos"``) and :func:`scipy.signal.sosfiltfilt` with
odd (point-reflection) padding of ``3 (n + 1)`` samples -- the classic ``filtfilt``
default, 9 samples for a 4th-order zero-lag filter.  A run of valid samples therefore
needs at least ``3 (n + 1) + 1`` samples (10 for 4th order); see :func:`min_run_length`.

Missing data
------------
Each column (each trailing index, e.g. each ``(marker, coordinate)`` pair) is filtered
separately, and within a column each contiguous run of finite samples is filtered on its
own.  NaNs stay NaN and never spread.  Runs shorter than :func:`min_run_length` are left
bit-identical and reported by a single :class:`ShortRunWarning` per call.
"""

from __future__ import annotations

import warnings
from collections import defaultdict
from collections.abc import Sequence

import numpy as np
from scipy import signal

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.core.trial import Trial

#: Combined gain of the zero-lag filter at the cutoff: 20 log10(1/sqrt(2)) dB.
GAIN_AT_CUTOFF_DB = 20.0 * np.log10(np.sqrt(0.5))

#: Columns or markers named at most in one short-run warning.
_MAX_LISTED = 12


class ShortRunWarning(UserWarning):
    """Some runs of valid samples were too short to filter and were left unfiltered."""


def _ordinal(n: int) -> str:
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def _plural(count: int, noun: str) -> str:
    return f"{count} {noun}{'' if count == 1 else 's'}"


def _check_order(order: object) -> int:
    if (
        isinstance(order, bool)
        or not isinstance(order, int | np.integer)
        or order <= 0
        or order % 2
    ):
        raise ParameterError(
            "order is the effective order after the forward and backward passes and must "
            f"be a positive even integer (e.g. 4 = 2nd order run twice); got {order!r}"
        )
    return int(order)


def _check_rate_cutoff(rate: float, cutoff: float) -> tuple[float, float]:
    rate = float(rate)
    if not np.isfinite(rate) or rate <= 0:
        raise ParameterError(f"rate must be a positive sampling rate in Hz; got {rate}")
    cutoff = float(cutoff)
    if not (0.0 < cutoff < rate / 2):
        raise ParameterError(
            f"cutoff must be between 0 and the Nyquist frequency {rate / 2:g} Hz "
            f"(rate {rate:g} Hz); got {cutoff:g} Hz"
        )
    return rate, cutoff


def _tan_ratio(freq: float | np.ndarray, rate: float, cutoff: float, order: int) -> np.ndarray:
    """tan(pi f / fs) / tan(pi f_w / fs) with the corrected per-pass cutoff f_w."""
    n_design = order // 2
    correction = (np.sqrt(2.0) - 1.0) ** (1.0 / (2 * n_design))
    tan_design = np.tan(np.pi * cutoff / rate) / correction
    return np.abs(np.tan(np.pi * np.asarray(freq, dtype=float) / rate)) / tan_design


def design_cutoff(rate: float, cutoff: float, order: int = 4) -> float:
    """Per-pass design cutoff in Hz giving a combined -3.01 dB at ``cutoff`` (Hz).

    ``order`` is the effective (two-pass) order; see the module docstring.
    """
    order = _check_order(order)
    rate, cutoff = _check_rate_cutoff(rate, cutoff)
    n_design = order // 2
    correction = (np.sqrt(2.0) - 1.0) ** (1.0 / (2 * n_design))
    return float(rate / np.pi * np.arctan(np.tan(np.pi * cutoff / rate) / correction))


def combined_gain_db(
    freq: float | np.ndarray, rate: float, cutoff: float, order: int = 4
) -> float | np.ndarray:
    """Analytic gain in dB of the two-pass filter of :func:`butterworth_lowpass`.

    Args:
        freq: frequency or frequencies in Hz.
        rate: sampling rate in Hz.
        cutoff: requested cutoff in Hz (the gain there is -3.01 dB).
        order: effective order after both passes (positive, even).

    Returns:
        ``20 log10 |H(f)|^2`` in dB, the same shape as ``freq`` (``0`` at 0 Hz).
    """
    order = _check_order(order)
    rate, cutoff = _check_rate_cutoff(rate, cutoff)
    ratio = _tan_ratio(freq, rate, cutoff, order)
    return -20.0 * np.log10(1.0 + ratio ** (2 * (order // 2)))


def min_run_length(order: int = 4) -> int:
    """Fewest consecutive valid samples that get filtered: ``3 (order/2 + 1) + 1``."""
    return 3 * (_check_order(order) // 2 + 1) + 1


def _lowpass_columns(
    data: np.ndarray, rate: float, cutoff: float, order: int
) -> tuple[np.ndarray, np.ndarray]:
    """Filter each column of a 2-D ``(time, columns)`` array by valid runs.

    Returns the filtered copy and the number of too-short runs per column.
    """
    sos = signal.butter(
        order // 2, design_cutoff(rate, cutoff, order), btype="low", output="sos", fs=rate
    )
    padlen = min_run_length(order) - 1
    out = data.copy()
    short = np.zeros(data.shape[1], dtype=int)
    valid = np.isfinite(data)
    # Columns with the same missing pattern are filtered together, run by run.
    columns_by_pattern: dict[bytes, list[int]] = defaultdict(list)
    for column in range(data.shape[1]):
        columns_by_pattern[np.packbits(valid[:, column]).tobytes()].append(column)
    for columns in columns_by_pattern.values():
        pattern = np.concatenate(([0], valid[:, columns[0]].astype(np.int8), [0]))
        edges = np.diff(pattern)
        for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
            if stop - start > padlen:
                block = data[start:stop, columns]
                out[start:stop, columns] = signal.sosfiltfilt(
                    sos, block, axis=0, padtype="odd", padlen=padlen
                )
            else:
                short[columns] += 1
    return out, short


def _lowpass(
    data: np.ndarray, rate: float, cutoff: float, order: int, axis: int
) -> tuple[np.ndarray, np.ndarray]:
    """Validated filtering along ``axis``; also returns short-run counts per column
    (shape: ``data.shape`` without ``axis``)."""
    order = _check_order(order)
    rate, cutoff = _check_rate_cutoff(rate, cutoff)
    data = np.asarray(data, dtype=float)
    if data.ndim == 0:
        raise ParameterError("data must have a time axis; got a scalar")
    try:
        moved = np.moveaxis(data, axis, 0)
    except np.exceptions.AxisError:
        raise ParameterError(
            f"axis {axis} does not exist for data of shape {data.shape}; pass the time axis"
        ) from None
    trailing = moved.shape[1:]
    columns = moved.reshape(moved.shape[0], int(np.prod(trailing)))
    filtered, short = _lowpass_columns(columns, rate, cutoff, order)
    return np.moveaxis(filtered.reshape(moved.shape), 0, axis), short.reshape(trailing)


def _warn_short_runs(where: dict[str, int], order: int, stacklevel: int) -> None:
    if not where:
        return
    items = [f"{name} ({count})" for name, count in where.items()]
    if len(items) > _MAX_LISTED:
        items = [*items[:_MAX_LISTED], f"and {len(items) - _MAX_LISTED} more"]
    listing = ", ".join(items)
    warnings.warn(
        ShortRunWarning(
            f"Butterworth low-pass: {_plural(sum(where.values()), 'run')} of valid samples "
            f"shorter than {min_run_length(order)} samples left unfiltered in {listing}"
        ),
        stacklevel=stacklevel + 1,
    )


def butterworth_lowpass(
    data: np.ndarray, rate: float, cutoff: float = 6.0, order: int = 4, axis: int = 0
) -> np.ndarray:
    """Zero-lag (forward-backward) Butterworth low-pass.

    ``order`` is the **effective order after both passes** (Winter's convention): the
    default 4 is a 2nd-order Butterworth run forward and backward.  The per-pass cutoff is
    corrected so that the combined gain is exactly -3.01 dB (amplitude 1/sqrt(2)) at
    ``cutoff``; padding is odd reflection of ``3 (order/2 + 1)`` samples.  See the module
    docstring for the derivation.

    Each column is filtered separately, one contiguous run of finite samples at a time;
    NaNs stay NaN.  Runs shorter than :func:`min_run_length` samples are returned
    unchanged and reported in one :class:`ShortRunWarning` naming the column indices.

    Args:
        data: samples along ``axis`` (time), any other shape, e.g. ``(frames, markers, 3)``
            in mm; the output has the same unit.
        rate: sampling rate in Hz.
        cutoff: -3 dB frequency of the combined filter in Hz, ``0 < cutoff < rate / 2``.
        order: effective zero-lag order, a positive even integer.
        axis: time axis of ``data``.

    Returns:
        The filtered copy, same shape as ``data``.

    Raises:
        ParameterError: for a bad ``rate``, ``cutoff``, ``order`` or ``axis``.
    """
    out, short = _lowpass(data, rate, cutoff, order, axis)
    if short.ndim == 0:
        where = {"the signal": int(short)} if short else {}
    else:
        where = {
            f"column {index[0] if short.ndim == 1 else index}": int(short[index])
            for index in map(tuple, np.argwhere(short).tolist())
        }
    _warn_short_runs(where, order, stacklevel=2)
    return out


def filter_trial(trial: Trial, cutoff: float = 6.0, order: int = 4, markers: Sequence[str] | None = None) -> Trial:
    """:func:`butterworth_lowpass` applied to a trial's markers (a new trial).

    The :attr:`~fuzzygait.core.findings.FindingKind.LOW_PASS` finding added (``cutoff_hz``,
    ``order``) reads e.g. ``"Butterworth low-pass 6 Hz, 4th order zero-lag"``.  Too
    short runs are reported in one :class:`ShortRunWarning` naming the markers.

    Args:
        trial: the trial (not modified); its ``rate`` (Hz) is used.
        cutoff: -3 dB frequency of the combined filter in Hz.
        order: effective zero-lag order, a positive even integer.
        markers: filter (and warn about) only these markers; the others are kept as they
            are.  None: every marker.  Labels the trial does not hold are ignored.
    """
    if markers is None:
        columns = list(range(trial.n_markers))
    else:
        wanted = set(markers)
        columns = [k for k, label in enumerate(trial.marker_labels) if label in wanted]
    out = np.array(trial.markers, dtype=float)
    filtered, short = _lowpass(trial.markers[:, columns, :], trial.rate, cutoff, order, axis=0)
    out[:, columns, :] = filtered
    per_marker = short.max(axis=1) if short.size else np.zeros(0, dtype=int)  # x, y, z share their gaps
    where = {
        trial.marker_labels[columns[m]]: int(per_marker[m]) for m in np.flatnonzero(per_marker)
    }
    _warn_short_runs(where, order, stacklevel=2)
    message = f"Butterworth low-pass {cutoff:g} Hz, {_ordinal(order)} order zero-lag"
    if markers is not None:
        message += f" ({len(columns)} of {trial.n_markers} markers)"
    note = Finding(FindingKind.LOW_PASS, message, cutoff_hz=float(cutoff), order=int(order))
    return trial.with_markers(out, note=note)
