"""Zero-lag Butterworth low-pass: phase, gain, NaN handling, argument checks.

Gains and phases are measured by a least-squares fit of ``a sin + b cos + c`` to the
middle half of a long filtered sine, away from the edge transients.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import signal

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import FindingKind
from fuzzygait.core.trial import Trial
from fuzzygait.mocap import (
    ShortRunWarning,
    butterworth_lowpass,
    combined_gain_db,
    filter_trial,
    min_run_length,
)

RATE_CUTOFF = [(100.0, 6.0), (120.0, 6.0), (50.0, 6.0), (200.0, 10.0)]


def sine(rate: float, freq: float, seconds: float = 40.0, phase: float = 0.3) -> np.ndarray:
    t = np.arange(int(seconds * rate)) / rate
    return np.sin(2 * np.pi * freq * t + phase)


def fit_sine(y: np.ndarray, rate: float, freq: float) -> tuple[float, float]:
    """Amplitude and phase (rad) of ``freq`` in the middle half of ``y``."""
    t = np.arange(len(y)) / rate
    mid = slice(len(y) // 4, 3 * len(y) // 4)
    w = 2 * np.pi * freq * t[mid]
    basis = np.column_stack([np.sin(w), np.cos(w), np.ones_like(w)])
    (a, b, _), *_ = np.linalg.lstsq(basis, y[mid], rcond=None)
    return float(np.hypot(a, b)), float(np.arctan2(b, a))


def expected_gain_db(freq: float, rate: float, cutoff: float, n_design: int) -> float:
    """Two passes of an order-n digital Butterworth, corrected to -3.01 dB at cutoff."""
    correction = (np.sqrt(2) - 1) ** (1 / (2 * n_design))
    ratio = np.tan(np.pi * freq / rate) / (np.tan(np.pi * cutoff / rate) / correction)
    return float(-20 * np.log10(1 + ratio ** (2 * n_design)))


def test_zero_phase_in_passband():
    rate, freq = 100.0, 1.0
    x = sine(rate, freq, seconds=60, phase=0.3)
    amplitude, phase = fit_sine(butterworth_lowpass(x, rate, cutoff=6.0), rate, freq)
    print(f"1 Hz sine: phase shift {phase - 0.3:.2e} rad, gain {20 * np.log10(amplitude):.4f} dB")
    assert abs(phase - 0.3) < 1e-3
    assert fit_sine(x, rate, freq)[1] == pytest.approx(0.3, abs=1e-12)  # the fit is exact


def test_symmetric_pulse_stays_symmetric_about_its_centre():
    rate, centre = 100.0, 500
    t = (np.arange(1001) - centre) / rate
    pulse = 50.0 * np.exp(-0.5 * (t / 0.05) ** 2)  # mm, sigma 50 ms
    out = butterworth_lowpass(pulse, rate, cutoff=6.0)
    np.testing.assert_allclose(out[centre::-1], out[centre:], rtol=0, atol=1e-9 * pulse.max())
    centroid = np.sum(np.arange(len(out)) * out) / np.sum(out)
    assert centroid == pytest.approx(centre, abs=1e-6)
    assert int(np.argmax(out)) == centre
    assert out.max() < pulse.max()  # it did filter


@pytest.mark.parametrize(("rate", "cutoff"), RATE_CUTOFF)
def test_gain_is_minus_3_01_db_at_cutoff(rate, cutoff):
    amplitude, _ = fit_sine(butterworth_lowpass(sine(rate, cutoff), rate, cutoff), rate, cutoff)
    gain = 20 * np.log10(amplitude)
    print(f"{rate:g} Hz / {cutoff:g} Hz: gain at cutoff {gain:.6f} dB")
    assert gain == pytest.approx(-3.0103, abs=0.1)
    assert float(combined_gain_db(cutoff, rate, cutoff)) == pytest.approx(-3.0103, abs=1e-4)


@pytest.mark.parametrize(("rate", "cutoff"), RATE_CUTOFF)
def test_measured_gain_matches_analytic_response(rate, cutoff):
    for factor in (0.1, 0.5, 1.5, 2.0, 3.0):
        freq = factor * cutoff
        if freq >= rate / 2:
            continue
        amplitude, _ = fit_sine(butterworth_lowpass(sine(rate, freq), rate, cutoff), rate, freq)
        measured = 20 * np.log10(amplitude)
        analytic = float(combined_gain_db(freq, rate, cutoff))
        independent = expected_gain_db(freq, rate, cutoff, n_design=2)
        print(f"{rate:g}/{cutoff:g} Hz at {freq:g} Hz: {measured:.3f} dB "
              f"(analytic {analytic:.3f} dB)")
        assert measured == pytest.approx(analytic, abs=0.1)
        assert analytic == pytest.approx(independent, abs=1e-9)


def test_default_is_second_order_run_twice():
    """At twice the cutoff, 2 x 2nd order and 2 x 4th order differ by > 10 dB."""
    rate, cutoff = 100.0, 6.0
    amplitude, _ = fit_sine(butterworth_lowpass(sine(rate, 12.0), rate, cutoff), rate, 12.0)
    measured = 20 * np.log10(amplitude)
    as_documented = expected_gain_db(12.0, rate, cutoff, n_design=2)  # -18.8 dB
    if_4th_per_pass = expected_gain_db(12.0, rate, cutoff, n_design=4)  # -35.6 dB
    assert measured == pytest.approx(as_documented, abs=0.1)
    assert abs(as_documented - if_4th_per_pass) > 10
    # order=8 is the 4th-order-per-pass filter
    amplitude8, _ = fit_sine(butterworth_lowpass(sine(rate, 12.0), rate, cutoff, order=8),
                             rate, 12.0)
    assert 20 * np.log10(amplitude8) == pytest.approx(if_4th_per_pass, abs=0.1)


def test_matches_documented_scipy_recipe():
    """butter(2, corrected cutoff) + sosfiltfilt with odd padding of 9 samples."""
    rate, cutoff = 100.0, 6.0
    x = np.random.default_rng(3).normal(size=500).cumsum()
    winter = (np.sqrt(2) - 1) ** 0.25
    assert winter == pytest.approx(0.802, abs=5e-4)  # Winter's factor for 2 passes
    f_design = rate / np.pi * np.arctan(np.tan(np.pi * cutoff / rate) / winter)
    sos = signal.butter(2, f_design, output="sos", fs=rate)
    expected = signal.sosfiltfilt(sos, x, padtype="odd", padlen=9)
    np.testing.assert_allclose(butterworth_lowpass(x, rate, cutoff), expected, atol=1e-9)
    assert min_run_length(4) == 10


def test_nans_never_spread_and_runs_are_filtered_alone():
    rate = 100.0
    x = 80 * sine(rate, 1.3, seconds=8) + np.random.default_rng(0).normal(0, 2, 800)
    runs = [(0, 150), (153, 400), (420, 421 + 60), (500, 800)]
    x_nan = np.full_like(x, np.nan)
    for start, stop in runs:
        x_nan[start:stop] = x[start:stop]
    out = butterworth_lowpass(x_nan, rate)
    assert np.array_equal(np.isnan(out), np.isnan(x_nan))
    for start, stop in runs:
        alone = butterworth_lowpass(x[start:stop], rate)
        np.testing.assert_allclose(out[start:stop], alone, rtol=0, atol=1e-12)
        assert not np.allclose(out[start:stop], x[start:stop])  # filtered


def test_short_run_is_untouched_and_warned():
    rate = 100.0
    x = sine(rate, 1.0, seconds=3)
    short = min_run_length(4) - 1
    x[100:102] = np.nan
    x[102 + short : 110 + short] = np.nan  # run of `short` samples at 102
    message = "1 run of valid samples shorter than 10 samples left unfiltered in the signal"
    with pytest.warns(ShortRunWarning, match=message) as record:
        out = butterworth_lowpass(x, rate)
    assert len(record) == 1 and record[0].filename == __file__  # points at the caller
    assert np.array_equal(out[102 : 102 + short], x[102 : 102 + short])
    assert not np.allclose(out[:100], x[:100], atol=1e-6, rtol=0)
    # one more sample and the run is filtered, without a warning
    x[102 + short] = 0.5
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = butterworth_lowpass(x, rate)
    assert not np.array_equal(out[102 : 103 + short], x[102 : 103 + short])


def test_short_run_warning_from_filter_trial_names_markers():
    rate = 100.0
    markers = np.repeat(sine(rate, 1.0, seconds=3)[:, None, None], 3, axis=2) * [[[1, 2, 3]]]
    markers = np.concatenate([markers, markers], axis=1)
    markers[50:60, 1] = np.nan
    markers[63:70, 1] = np.nan  # 3-sample run of RTOE
    trial = Trial(markers=markers, marker_labels=["LTOE", "RTOE"], rate=rate)
    with pytest.warns(ShortRunWarning, match=r"1 run .* in RTOE \(1\)$") as record:
        filtered = filter_trial(trial)
    assert len(record) == 1
    assert np.array_equal(filtered.markers[60:63, 1], markers[60:63, 1])
    assert np.array_equal(np.isnan(filtered.markers), np.isnan(markers))
    assert filtered.notes[-1].message == "Butterworth low-pass 6 Hz, 4th order zero-lag"
    assert filtered.notes[-1].kind is FindingKind.LOW_PASS
    assert (filtered.notes[-1].cutoff_hz, filtered.notes[-1].order) == (6.0, 4)
    assert trial.notes == [] and np.array_equal(trial.markers, markers, equal_nan=True)
    np.testing.assert_array_equal(filtered.markers[:, 0], butterworth_lowpass(markers[:, 0], rate))


@pytest.mark.parametrize("cutoff", [50.0, 60.0, 0.0, -1.0, float("nan")])
def test_bad_cutoff_raises(cutoff):
    with pytest.raises(ParameterError, match=r"cutoff.*Nyquist frequency 50 Hz \(rate 100 Hz\)"):
        butterworth_lowpass(np.zeros(100), 100.0, cutoff=cutoff)


@pytest.mark.parametrize("order", [3, 1, 0, -2, 4.0, True])
def test_bad_order_raises(order):
    with pytest.raises(ParameterError, match="order"):
        butterworth_lowpass(np.zeros(100), 100.0, order=order)


@pytest.mark.parametrize("rate", [0.0, -100.0, float("inf")])
def test_bad_rate_raises(rate):
    with pytest.raises(ParameterError, match="rate"):
        butterworth_lowpass(np.zeros(100), rate)


def test_shapes_agree_columnwise():
    rng = np.random.default_rng(5)
    data = rng.normal(size=(300, 4, 3)).cumsum(axis=0)
    data[40:45, 2] = np.nan
    data[100:103, 1, 0] = np.nan
    full = butterworth_lowpass(data, 120.0)
    flat = butterworth_lowpass(data.reshape(300, 12), 120.0).reshape(300, 4, 3)
    np.testing.assert_array_equal(full, flat)
    for m in range(4):
        for c in range(3):
            np.testing.assert_allclose(
                full[:, m, c], butterworth_lowpass(data[:, m, c], 120.0), rtol=0, atol=1e-12
            )
    np.testing.assert_allclose(
        butterworth_lowpass(data.transpose(1, 2, 0), 120.0, axis=-1).transpose(2, 0, 1),
        full, rtol=0, atol=1e-12,
    )
    assert full.shape == data.shape and np.array_equal(np.isnan(full), np.isnan(data))


def test_empty_and_all_nan_inputs():
    assert butterworth_lowpass(np.zeros((0, 4, 3)), 100.0).shape == (0, 4, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = butterworth_lowpass(np.full((50, 2), np.nan), 100.0)
    assert np.all(np.isnan(out))


def test_input_not_mutated():
    x = sine(100.0, 2.0, seconds=2)
    x[50] = np.nan
    before = x.copy()
    butterworth_lowpass(x, 100.0)
    assert np.array_equal(x, before, equal_nan=True)
