"""Force plates in the laboratory frame: the ground reaction on the body, its centre of
pressure and free moment, low-passed and resampled to the marker frames.

From each plate's loads (:func:`fuzzygait.io.force_plates.read_plate_loads`: force F and
moment M about the surface centre of the plate on the body, plate frame, z into the
plate, so a load has Fz < 0), at each sample:

* low-pass F and M with the project's zero-lag Butterworth
  (:func:`fuzzygait.mocap.filtering.butterworth_lowpass`, effective order 4) -- before
  the centre of pressure, which is a ratio and must not be filtered across contacts;
* contact: the normal force -Fz above ``threshold_n``;
* centre of pressure on the surface (plate frame): x = -My / Fz, y = Mx / Fz, z = 0;
* free moment about the centre of pressure: Tz = Mz - (x Fy - y Fx), along the normal;
* laboratory frame: ``lab = centre + R @ plate`` (:attr:`PlateSetup.rotation`): the
  reaction on the body R F, its free moment R (0, 0, Tz).

Units: N, mm, N·mm; frames: the C3D's laboratory frame.
"""

from __future__ import annotations

import os

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.io.force_plates import ForcePlate, PlateLoads, read_plate_loads

__all__ = ["DEFAULT_CUTOFF_HZ", "DEFAULT_THRESHOLD_N", "force_plate", "read_force_plates", "resample"]

#: Low-pass cut-off of the plate signals, Hz, when resampled to the marker frames.
DEFAULT_CUTOFF_HZ = 20.0
#: Normal force above which a foot is in contact with a plate, N.
DEFAULT_THRESHOLD_N = 10.0


def _lowpass(data: NDArray[np.float64], rate: float, cutoff_hz: float) -> NDArray[np.float64]:
    from fuzzygait.mocap.filtering import butterworth_lowpass

    return np.asarray(butterworth_lowpass(data, rate, cutoff_hz, order=4, axis=0), dtype=float)


def resample(data: NDArray[np.float64], rate: float, new_rate: float, n: int) -> NDArray[np.float64]:
    """``n`` samples at ``new_rate`` of ``data`` sampled at ``rate`` (first samples
    aligned; linear interpolation, the sample itself where the times coincide)."""
    times = np.arange(data.shape[0]) / rate
    new = np.arange(n) / new_rate
    flat = data.reshape(data.shape[0], -1)
    out = np.empty((n, flat.shape[1]))
    for j in range(flat.shape[1]):
        out[:, j] = np.interp(new, times, flat[:, j])
    return out.reshape((n,) + data.shape[1:])


def force_plate(loads: PlateLoads, *, threshold_n: float = DEFAULT_THRESHOLD_N,
                findings: tuple[Finding, ...] = ()) -> ForcePlate:  # fmt: skip
    """The reaction on the body, centre of pressure and free moment of ``loads`` (plate
    frame, any rate) in the laboratory frame, at the same samples."""
    setup = loads.setup
    force, moment = loads.force, loads.moment
    fz = force[:, 2]
    contact = np.isfinite(fz) & (-fz > threshold_n)
    safe = np.where(contact, fz, 1.0)
    x = np.where(contact, -moment[:, 1] / safe, np.nan)
    y = np.where(contact, moment[:, 0] / safe, np.nan)
    local_cop = np.stack([x, y, np.zeros_like(x)], axis=1)
    tz = np.where(contact, moment[:, 2] - (x * force[:, 1] - y * force[:, 0]), 0.0)
    rotation = setup.rotation
    free = np.zeros_like(force)
    free[:, 2] = tz
    return ForcePlate(
        number=setup.number,
        kind=setup.kind,
        corners=setup.corners,
        centre=setup.centre,
        rate=loads.rate,
        force=force @ rotation.T,
        cop=setup.centre + local_cop @ rotation.T,
        free_moment=free @ rotation.T,
        contact=contact,
        findings=loads.findings + findings,
    )


def read_force_plates(
    path: str | os.PathLike[str],
    *,
    marker_rate: float | None = None,
    cutoff_hz: float | None = DEFAULT_CUTOFF_HZ,
    threshold_n: float = DEFAULT_THRESHOLD_N,
) -> tuple[ForcePlate, ...]:
    """Every force plate of ``path`` in the laboratory frame (:class:`ForcePlate`).

    Args:
        path: a C3D file.
        marker_rate: None: the analog samples, unfiltered. Else the rate, Hz, of the
            marker frames to resample to (the file's point rate for its own n_frames):
            the loads are low-passed at ``cutoff_hz`` at the analog rate, then sampled at
            the frame times, the first frame aligned with the first analog sample.
        cutoff_hz: -3 dB cut-off, Hz, of the low-pass before resampling (None: none).
        threshold_n: normal force, N, above which the plate is in contact.

    Raises:
        ForcePlateError: no plate of the file can be used.
        C3DError: the file cannot be read.
        ParameterError: a bad rate, cut-off or threshold.
    """
    if not threshold_n >= 0:
        raise ParameterError(f"the force-plate threshold must be at least 0 N; got {threshold_n}")
    if marker_rate is not None and not marker_rate > 0:
        raise ParameterError(f"the marker rate must be positive; got {marker_rate}")
    plates = read_plate_loads(path, threshold_n=threshold_n)
    if marker_rate is None or not plates:
        return tuple(force_plate(p, threshold_n=threshold_n) for p in plates)
    rate = plates[0].rate
    n_samples = plates[0].force.shape[0]
    duration = (n_samples - 1) / rate if n_samples else 0.0
    n_frames = int(np.floor(duration * marker_rate + 1e-9)) + 1 if n_samples else 0
    out = []
    for p in plates:
        force, moment, notes = p.force, p.moment, []
        if cutoff_hz is not None and p.usable and n_samples:
            force, moment = _lowpass(force, rate, cutoff_hz), _lowpass(moment, rate, cutoff_hz)
            message = f"force plate {p.setup.number}: low-pass {cutoff_hz:g} Hz (zero-lag Butterworth, order 4)"
            notes.append(Finding(FindingKind.LOW_PASS, message, cutoff_hz=cutoff_hz, order=4))
        resampled = PlateLoads(p.setup, float(marker_rate), resample(force, rate, marker_rate, n_frames),
                               resample(moment, rate, marker_rate, n_frames), p.findings)  # fmt: skip
        out.append(force_plate(resampled, threshold_n=threshold_n, findings=tuple(notes)))
    return tuple(out)
