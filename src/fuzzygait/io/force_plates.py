"""Force plates of a C3D file: their description (``FORCE_PLATFORM``) and the loads they
measured, at the analog rate, in each plate's own frame.

Conventions (the C3D user guide, as ezc3d and BTK read it; docs/kinetics.md):

* **Plate frame** from ``CORNERS`` (4 corners of the top surface in the laboratory frame,
  corner 1 in the plate's +x+y quadrant, then -x+y, -x-y, +x-y): x along corner 2 -> 1,
  z = x cross (corner 4 -> 1), so z points *into* the plate (down for a floor plate),
  y = z cross x. The surface centre is the mean of the corners.
* **ORIGIN** (types 2, 4, 5): the transducer origin relative to the surface centre in
  plate coordinates, mm. Writers disagree on its direction (AMTI and Vicon store the
  vector surface centre -> transducer origin, whose z is positive, i.e. below the
  surface; others the opposite vector); as ezc3d and BTK do, the vector whose z is
  negative is taken as the opposite one and negated, so :attr:`PlateSetup.depth` always
  points from the surface centre to the transducer origin, into the plate. Type 3
  (Kistler): ORIGIN is (a, b, az0), the sensor offsets and the surface's height; only
  az0's magnitude is used for the depth. Type 1 ignores ORIGIN (its centre of pressure
  is measured on the surface).
* **Channels** (``CHANNEL``, 1-based analog channel numbers): type 1 Fx, Fy, Fz, Px, Py,
  Tz; type 2 Fx, Fy, Fz, Mx, My, Mz about the transducer origin; type 3 (Kistler)
  fx12, fx34, fy14, fy23, fz1, fz2, fz3, fz4; type 4 as type 2 after the 6 x 6
  ``CAL_MATRIX``; type 5 eight raw channels through a 6 x 8 ``CAL_MATRIX`` to type 2's
  six (``CAL_MATRIX[:, :, plate]`` times the channel vector, the matrix in the C3D
  first-index-fastest order, as ezc3d reads it).
* The loads here are the **reaction on the body** (the force and moment of the plate on
  the body), moments about the surface centre, plate frame, forces N, moments N·mm.
  Every writer we have seen (Vicon Nexus and Workstation, QTM through pyCGM2, the
  c3d.org samples) stores the reaction: the normal force is negative in the plate frame
  (pointing out of the plate, up). A plate whose loaded normal force is positive stores
  the action on the plate and is negated (a ground pushes, it never pulls), with a note.
  The centre of pressure and the laboratory frame come in :mod:`fuzzygait.kinetics.plates`.

Units: forces from channels in N (``N``, ``nt``) or kN; moments in N·mm (``Nmm``,
``ntmm``, ``N.mm``) or N·m (``Nm``, ``N.m``: multiplied by 1000 unless the centre of
pressure then leaves the plate -- Vicon Workstation labels N·mm channels ``Nm``);
lengths of ``CORNERS``/``ORIGIN`` in ``POINT:UNITS``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import C3DError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.io.analog import AnalogData, read_analog
from fuzzygait.io.c3d import LENGTH_UNITS_TO_MM
from fuzzygait.io.plate_setup import FORCE_UNITS, MOMENT_UNITS, PlateSetup, factor, plate_setups

Array = NDArray[np.float64]

__all__ = ["ForcePlate", "ForcePlateError", "PlateLoads", "PlateSetup", "read_plate_loads"]


class ForcePlateError(C3DError):
    """The force plates of a file cannot be used (names the file, the plate and why)."""


@dataclass(frozen=True)
class ForcePlate:
    """One plate, laboratory frame, as read and processed (:func:`fuzzygait.kinetics.plates.read_force_plates`).

    Attributes:
        number: 1-based, as in ``FORCE_PLATFORM``.
        kind: ``FORCE_PLATFORM:TYPE`` (1..5).
        corners: ``(4, 3)`` mm, laboratory frame, in the file's order.
        centre: ``(3,)`` mm, centre of the plate's top surface, laboratory frame.
        rate: Hz of the arrays below.
        force: ``(n, 3)`` N, the force of the ground **on the body** (reaction),
            laboratory frame.
        cop: ``(n, 3)`` mm, centre of pressure on the plate surface, laboratory frame;
            NaN without contact.
        free_moment: ``(n, 3)`` N·mm, the moment of the ground on the body about the
            centre of pressure (only its component along the plate normal is non-zero),
            laboratory frame; zero without contact.
        contact: ``(n,)`` bool, the force along the plate normal above the threshold.
        findings: saturation, no load, calibration and unit findings of this plate.
    """

    number: int
    kind: int
    corners: NDArray[np.float64]
    centre: NDArray[np.float64]
    rate: float
    force: NDArray[np.float64]
    cop: NDArray[np.float64]
    free_moment: NDArray[np.float64]
    contact: NDArray[np.bool_]
    findings: tuple[Finding, ...] = ()


@dataclass(frozen=True)
class PlateLoads:
    """What one plate measured, in its own frame, at the analog rate.

    Attributes:
        setup: the plate's description (corners, rotation, depth, channels).
        rate: analog rate, Hz.
        force: ``(n, 3)`` N, force of the plate on the body (reaction), plate frame
            (z into the plate: a load has a negative z).
        moment: ``(n, 3)`` N·mm, moment of the plate on the body about the surface
            centre, plate frame. NaN throughout for an unusable plate.
        findings: what was found reading this plate.
    """

    setup: PlateSetup
    rate: float
    force: NDArray[np.float64]
    moment: NDArray[np.float64]
    findings: tuple[Finding, ...] = field(default=())

    @property
    def usable(self) -> bool:
        """The plate's loads are numbers (not NaN for a missing calibration)."""
        return bool(np.isfinite(self.force).any())


def _units(units: list[str], table: dict[str, float]) -> Array:
    """Factors of ``units`` in ``table``, 1 for an unknown or missing unit."""
    return np.array([factor(u, table) or 1.0 for u in units])


def _kistler(setup: PlateSetup, ch: Array) -> tuple[Array, Array]:
    """Force (N) and moment about the sensor plane's centre (N·mm) of a Kistler (type 3)
    plate from fx12, fx34, fy14, fy23, fz1..fz4 (N) and the sensor offsets a, b (mm)."""
    a, b = setup.sensor_offsets
    force = np.stack([ch[:, 0] + ch[:, 1], ch[:, 2] + ch[:, 3], ch[:, 4:8].sum(axis=1)], axis=1)
    moment = np.stack([
        b * (ch[:, 4] + ch[:, 5] - ch[:, 6] - ch[:, 7]),
        a * (-ch[:, 4] + ch[:, 5] + ch[:, 6] - ch[:, 7]),
        b * (-ch[:, 0] + ch[:, 1]) + a * (ch[:, 2] - ch[:, 3]),
    ], axis=1)  # fmt: skip
    return force, moment


def _loads(setup: PlateSetup, ch: Array, units: list[str], moment_factor: float | None = None) -> tuple[Array, Array]:
    """Force (N) and moment about the surface centre (N·mm), plate frame, with the sign
    the channels give, from the plate's channels ``ch`` ``(n, k)`` in ``units``;
    ``moment_factor``: to N·mm for moment channels, overriding their units."""
    if setup.kind == 1:
        force = ch[:, :3] * _units(units[:3], FORCE_UNITS)
        cop = np.zeros_like(force)
        cop[:, :2] = ch[:, 3:5] * np.array([LENGTH_UNITS_TO_MM.get(u.strip().lower(), 1.0) for u in units[3:5]])
        moment = np.cross(cop, force)
        moment[:, 2] += ch[:, 5] * _units(units[5:6], MOMENT_UNITS)[0]
        return force, moment
    if setup.kind == 3:
        force, moment = _kistler(setup, ch)
    elif setup.calibration is not None:  # types 4 and 5: outputs in N and N·mm
        data = ch @ setup.calibration.T
        force, moment = data[:, :3], data[:, 3:6]
    else:
        force = ch[:, :3] * _units(units[:3], FORCE_UNITS)
        moment = ch[:, 3:6] * (_units(units[3:6], MOMENT_UNITS) if moment_factor is None else moment_factor)
    # moment about the surface centre: M_c = M_o + (o - c) x F, o - c = depth
    return force, moment + np.cross(setup.depth, force)


def _on_plate(setup: PlateSetup, force: Array, moment: Array, loaded: NDArray[np.bool_]) -> float:
    """Fraction of the ``loaded`` samples whose centre of pressure lies on the plate
    (within 5 % of its half sizes)."""
    half = setup.half_size() * 1.05
    fz = force[loaded, 2]
    x, y = -moment[loaded, 1] / fz, moment[loaded, 0] / fz
    return float(np.mean((np.abs(x) <= half[0]) & (np.abs(y) <= half[1])))


def _moment_units(
    setup: PlateSetup, ch: Array, units: list[str], threshold_n: float
) -> tuple[float | None, list[Finding]]:
    """None (the moment channels' own units), or 1.0 with a note for channels labelled
    N·m whose values are N·mm (Vicon Workstation): with N·m the centre of pressure lies
    off the plate in most loaded samples, with N·mm on it."""
    labels = units[3:6]
    if setup.kind != 2 or not all(factor(u, MOMENT_UNITS) == 1000.0 for u in labels):
        return None, []
    force, as_labelled = _loads(setup, ch, units)
    normal = np.abs(force[:, 2])
    loaded = normal > max(threshold_n, 0.2 * float(np.nanmax(normal, initial=0.0)))
    if not loaded.any():
        return None, []
    _, as_nmm = _loads(setup, ch, units, moment_factor=1.0)
    if _on_plate(setup, force, as_labelled, loaded) < 0.5 <= _on_plate(setup, force, as_nmm, loaded):
        return 1.0, [Finding(
            FindingKind.FORCE_PLATE_UNITS,
            f"force plate {setup.number}: ANALOG:UNITS says {labels[0]} for the moment channels but the values are "
            "N·mm (in N·m the centre of pressure would lie off the plate); read as N·mm",
            Severity.WARNING,
        )]  # fmt: skip
    return None, []


def _zero(
    setup: PlateSetup, ch: Array, units: list[str], n_frames: int, threshold_n: float
) -> tuple[Array, list[Finding]]:
    """Channels less their mean over the ``FORCE_PLATFORM:ZERO`` frames (marker frames,
    1-based from the file's first; none when the range is empty). Not when the normal
    force varies by more than ``threshold_n`` in those frames (a load, not an offset)."""
    first, last = max(setup.zero[0], 1), setup.zero[1]
    if last < first or not n_frames:
        return ch, []
    per_frame = ch.shape[0] / n_frames
    start, stop = int(round((first - 1) * per_frame)), int(round(min(last, n_frames) * per_frame))
    if stop <= start:
        return ch, []
    window = ch[start:stop]
    fz = _loads(setup, window, units)[0][:, 2]
    if float(np.ptp(fz)) > threshold_n:
        return ch, [Finding(FindingKind.FORCE_PLATE,
                            f"force plate {setup.number}: offsets not removed: the plate is loaded in the "
                            f"FORCE_PLATFORM:ZERO frames {first}-{last} (normal force varies by {np.ptp(fz):.0f} N)",
                            Severity.WARNING)]  # fmt: skip
    note = Finding(FindingKind.FORCE_PLATE, f"force plate {setup.number}: channel offsets removed (their mean over "
                                            f"frames {first}-{last}, FORCE_PLATFORM:ZERO)")  # fmt: skip
    return ch - window.mean(axis=0), [note]


def read_plate_loads(
    path: str | os.PathLike[str], *, zero_baseline: bool = True, threshold_n: float = 10.0
) -> tuple[PlateLoads, ...]:
    """The loads every plate of ``path`` measured, in its own frame, at the analog rate.

    Args:
        path: a C3D file.
        zero_baseline: subtract each channel's mean over the ``FORCE_PLATFORM:ZERO``
            frames (the C3D rule; off to compare with readers that ignore ``ZERO``).
        threshold_n: normal force, N, above which a plate counts as loaded (for the
            "no load" finding and the unit check).

    Returns:
        One :class:`PlateLoads` per plate of ``FORCE_PLATFORM:USED`` (none when the file
        has no force plates). A plate that cannot be used (no calibration, a scale of
        0, channels beyond the analog block) has NaN loads and a WARNING finding.

    Raises:
        ForcePlateError: ``FORCE_PLATFORM`` is unreadable, or no plate is usable.
        C3DError: the file cannot be read.
    """
    analog = read_analog(path)
    setups, problems = plate_setups(analog, LENGTH_UNITS_TO_MM)
    read_notes = tuple(Finding(FindingKind.FILE_FORMAT, note) for note in analog.notes)  # the reader used
    out = []
    for setup in setups:
        plate = _plate(analog, setup, problems.get(setup.number), zero_baseline, threshold_n)
        out.append(replace(plate, findings=read_notes + plate.findings) if read_notes else plate)
    if out and not any(p.usable for p in out):
        reasons = "; ".join(f.message for p in out for f in p.findings if f.kind is FindingKind.FORCE_PLATE_CALIBRATION)
        raise ForcePlateError(f"{Path(path)}: no force plate can be used ({reasons})")
    return tuple(out)


def _plate(
    analog: AnalogData, setup: PlateSetup, problem: str | None, zero_baseline: bool, threshold_n: float
) -> PlateLoads:
    n = analog.values.shape[0]
    if problem is not None:
        bad = Finding(FindingKind.FORCE_PLATE_CALIBRATION, f"force plate {setup.number}: {problem}; not used",
                      Severity.WARNING)  # fmt: skip
        nan = np.full((n, 3), np.nan)
        return PlateLoads(setup, analog.rate, nan, nan.copy(), (bad,))
    findings: list[Finding] = list(_saturation(analog, setup))
    ch = analog.values[:, list(setup.channels)]
    units = [analog.units[c] for c in setup.channels]
    if zero_baseline:
        ch, notes = _zero(setup, ch, units, analog.n_frames, threshold_n)
        findings += notes
    moment_factor, notes = _moment_units(setup, ch, units, threshold_n)
    findings += notes
    force, moment = _loads(setup, ch, units, moment_factor)
    return PlateLoads(setup, analog.rate, *_reaction(setup, force, moment, threshold_n, findings))


def _reaction(
    setup: PlateSetup, force: Array, moment: Array, threshold_n: float, findings: list[Finding]
) -> tuple[Array, Array, tuple[Finding, ...]]:
    """The loads as the reaction on the body (negated when the channels give the action
    on the plate) and the notes on the normal force."""
    normal = np.abs(force[:, 2])
    if not normal.size:
        return force, moment, tuple(findings)
    peak = int(np.argmax(normal))
    if force[peak, 2] > threshold_n:  # the action on the plate: the reaction is its opposite
        force, moment = -force, -moment
        findings.append(Finding(FindingKind.FORCE_PLATE,
                                f"force plate {setup.number}: its channels give the force on the plate (the normal "
                                "force points into it); negated to the reaction on the body"))  # fmt: skip
    if normal.min() > threshold_n:
        findings.append(Finding(FindingKind.FORCE_PLATE,
                                f"force plate {setup.number}: the normal force never falls below {threshold_n:g} N "
                                f"(least {normal.min():.0f} N): an offset not removed? Contact is found throughout",
                                Severity.WARNING))  # fmt: skip
    if not np.any(normal > threshold_n):
        findings.append(Finding(FindingKind.FORCE_PLATE_UNLOADED,
                                f"force plate {setup.number} carries no load (normal force below {threshold_n:g} N "
                                "throughout)"))  # fmt: skip
    return force, moment, tuple(findings)


def _saturation(analog: AnalogData, setup: PlateSetup) -> list[Finding]:
    """Channels of the plate that reach the converter's limit (:attr:`AnalogData.count_range`)."""
    if analog.count_range is None or not analog.values.size:
        return []
    low, high = analog.count_range
    counts = analog.counts[:, list(setup.channels)]
    finite = np.isfinite(counts)
    with np.errstate(invalid="ignore"):
        # a channel whose stored numbers leave the range is not counts of this converter
        # (Vicon's float files in N with BITS 12): not checked
        inside = (np.nanmin(counts, axis=0) >= low - 0.5) & (np.nanmax(counts, axis=0) <= high + 0.5)
        counts_of_adc = finite.all(axis=0) & inside
    at_limit = finite & counts_of_adc & ((counts <= low + 0.5) | (counts >= high - 0.5))
    out = []
    for j in np.flatnonzero(at_limit.any(axis=0)):
        samples = np.flatnonzero(at_limit[:, j])
        channel = setup.channels[j]
        label = analog.labels[channel] or f"channel {channel + 1}"
        out.append(Finding(
            FindingKind.FORCE_PLATE_SATURATED,
            f"force plate {setup.number}: {label} is at the converter's limit in {samples.size} samples (from "
            f"{samples[0] / analog.rate:.3f} s to {samples[-1] / analog.rate:.3f} s); its forces there are wrong",
            Severity.WARNING,
        ))  # fmt: skip
    return out
