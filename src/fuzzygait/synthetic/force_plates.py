"""Synthetic force plates: the analog channels of two type-2 plates under a synthetic
walker's feet, added to a C3D file as Vicon Nexus writes them.

The loads are **synthetic and plausible, not measured**: no contact or muscle model
produces them, they are shaped like a normal adult walking trial's (Perry & Burnfield,
*Gait Analysis*, ch. "Kinetics") and placed under the generator's feet:

* vertical force: a double hump over each foot's stance (peaks 1.14 body weights at 24 %
  and 76 % of stance, 0.71 at mid-stance), its area chosen so that both
  feet's vertical impulse over a stride is the body weight times the stride time (the
  mean vertical force of a stride equals the weight);
* anterior-posterior force: braking in the first half of stance, propulsion in the
  second, ``0.2 sin(2 pi s)`` body weights (``s`` the stance fraction; zero net impulse);
* medio-lateral force: ``0.05 sin(pi s)`` body weights towards the midline;
* centre of pressure: on the horizontal line from the heel marker to the toe marker of
  the stance foot at each sample, from 5 % to 95 % of the way (heel to toe) as stance
  goes on, on the plate surface (z = 0);
* free moment about the vertical: ``3 sin(2 pi s)`` N·m, turning the foot inwards early
  in stance (left foot: -z), outwards late.

The plates (:class:`SyntheticPlate`) lie in the floor (surface z = 0), 600 mm along the
walking direction (laboratory X) by 400 mm, their axes x = lab X, y = -lab Y, z = -lab Z
(into the floor), the transducer origin 41 mm below the surface centre (``ORIGIN`` (0, 0,
41), as Vicon writes its plates).  Channels: ``FORCE_PLATFORM:TYPE`` 2 (Fx, Fy, Fz, Mx,
My, Mz about the transducer origin, plate frame, the reaction on the body: Fz < 0), 1000
Hz, ``ANALOG:SCALE`` 1, ``OFFSET`` 0, ``GEN_SCALE`` 1, ``UNITS`` N and Nmm, labels
``Force.Fx1`` ... ``Moment.Mz2`` (Vicon Nexus' layout: the values are stored in physical
units).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError
from fuzzygait.synthetic.gait_curves import FOOT_OFF_PHASE, RIGHT_PHASE_SHIFT, STRIDE_TIME_S
from fuzzygait.synthetic.generate import LEAD_IN_CYCLES, WALKING_SPEED_MM_S, walking_state
from fuzzygait.synthetic.leg_model import SubjectGeometry

Array = NDArray[np.float64]

#: Analog samples per marker frame (1000 Hz at the trials' 100 Hz).
SAMPLES_PER_FRAME = 10
#: Standard gravity used to turn the body mass into a weight, m/s².
G = 9.81
#: Plate size along its x (laboratory X) and y axes, mm.
PLATE_SIZE_MM = (600.0, 400.0)
#: ``FORCE_PLATFORM:ORIGIN`` of every plate: the transducer origin relative to the
#: surface centre, plate frame (z into the plate), mm.
PLATE_ORIGIN_MM = (0.0, 0.0, 41.0)
#: Plate axes (columns) in the laboratory frame: x = X, y = -Y, z = -Z.
PLATE_AXES = np.diag([1.0, -1.0, -1.0])
#: Shape coefficients of the vertical force over stance, body weights:
#: ``A sin(pi s) + B sin(3 pi s)`` (area 2A/pi + 2B/(3 pi) = stride / (2 stance)).
VERTICAL_B = 0.45
VERTICAL_A = (STRIDE_TIME_S / (2.0 * FOOT_OFF_PHASE * STRIDE_TIME_S) - 2.0 * VERTICAL_B / (3.0 * np.pi)) * np.pi / 2.0
#: Peak anterior-posterior and medio-lateral force, body weights; peak free moment, N·mm.
AP_PEAK = 0.2
ML_PEAK = 0.05
FREE_MOMENT_PEAK_NMM = 3000.0
#: The centre of pressure runs from this fraction of the heel-toe line to the other.
COP_FROM_TO = (0.05, 0.95)
#: The stances the sample trial puts on plates: (side, global phase of the foot strike):
#: the second left stance on plate 1, the right one after it on plate 2.
SAMPLE_STANCES: tuple[tuple[str, float], ...] = (("L", 1.0), ("R", 1.0 + RIGHT_PHASE_SHIFT))


@dataclass(frozen=True)
class SyntheticPlate:
    """A type-2 floor plate: its surface centre (mm, laboratory frame, z = 0), size and
    transducer origin (:data:`PLATE_SIZE_MM`, :data:`PLATE_ORIGIN_MM`), axes
    :data:`PLATE_AXES`."""

    centre: tuple[float, float, float]
    size: tuple[float, float] = PLATE_SIZE_MM
    origin: tuple[float, float, float] = PLATE_ORIGIN_MM

    def corners(self) -> Array:
        """``(4, 3)`` mm, laboratory frame: the +x+y, -x+y, -x-y, +x-y corners of the
        surface in plate axes (the C3D order)."""
        w, h = self.size[0] / 2.0, self.size[1] / 2.0
        local = np.array([[w, h, 0.0], [-w, h, 0.0], [-w, -h, 0.0], [w, -h, 0.0]])
        return np.asarray(self.centre) + local @ PLATE_AXES.T

    def channels(self, force: Array, cop: Array, free_moment: Array) -> Array:
        """``(n, 6)`` type-2 channels Fx, Fy, Fz (N), Mx, My, Mz (N·mm) about the
        transducer origin, plate frame, from the reaction ``force`` on the body ``(n, 3)``
        N, the centre of pressure ``cop`` ``(n, 3)`` mm and the free moment about the
        vertical ``free_moment`` ``(n,)`` N·mm, all laboratory frame (0 where unloaded)."""
        force_p = force @ PLATE_AXES  # lab -> plate components
        cop_p = np.where(np.isfinite(cop), cop - np.asarray(self.centre), 0.0) @ PLATE_AXES
        free_p = np.column_stack([np.zeros((len(force), 2)), free_moment]) @ PLATE_AXES
        about_centre = np.cross(cop_p, force_p) + free_p
        about_origin = about_centre - np.cross(np.asarray(self.origin), force_p)
        return np.column_stack([force_p, about_origin])


def stance_loads(s: Array, body_mass: float, side: str) -> tuple[Array, Array]:
    """Reaction force on the foot ``(n, 3)`` N (laboratory frame) and free moment about
    the vertical ``(n,)`` N·mm at stance fractions ``s`` (0 outside ``[0, 1]``)."""
    inside = (s >= 0.0) & (s <= 1.0)
    weight = body_mass * G
    medial = -1.0 if side == "L" else 1.0
    force = np.column_stack([
        -AP_PEAK * np.sin(2 * np.pi * s),
        medial * ML_PEAK * np.sin(np.pi * s),
        VERTICAL_A * np.sin(np.pi * s) + VERTICAL_B * np.sin(3 * np.pi * s),
    ]) * weight  # fmt: skip
    free = medial * FREE_MOMENT_PEAK_NMM * np.sin(2 * np.pi * s)
    return np.where(inside[:, None], force, 0.0), np.where(inside, free, 0.0)


def stance_cop(s: Array, heel: Array, toe: Array) -> Array:
    """``(n, 3)`` mm: the centre of pressure on the floor (z = 0) along the horizontal
    heel-to-toe line of the foot's markers ``heel``, ``toe`` ``(n, 3)`` mm (laboratory
    frame) at stance fractions ``s`` (NaN outside ``[0, 1]``)."""
    a, b = COP_FROM_TO
    u = (a + (b - a) * np.clip(s, 0.0, 1.0))[:, None]
    cop = heel + u * (toe - heel)
    cop[:, 2] = 0.0
    cop[(s < 0.0) | (s > 1.0)] = np.nan
    return cop


@dataclass(frozen=True)
class PlateRecording:
    """One plate and its analog channels ``(n, 6)`` (Fx, Fy, Fz N; Mx, My, Mz N·mm)."""

    plate: SyntheticPlate
    channels: Array


def walking_plates(
    n_frames: int,
    rate: float,
    foot_markers: Callable[[Array, str], tuple[Array, Array]],
    first_strike_time: float,
    body_mass: float,
    stances: Sequence[tuple[str, float]] = SAMPLE_STANCES,
) -> list[PlateRecording]:
    """One plate per stance of ``stances`` (side, global phase of its foot strike), under
    that foot, with its loads at :data:`SAMPLES_PER_FRAME` samples a frame.

    Args:
        n_frames, rate: the marker trial's frames and rate (Hz); the first analog sample
            is at the first frame's time (0 s).
        foot_markers: ``(times s, side) -> (HEE, TOE)`` positions ``(n, 3)`` mm of that
            foot at those times (the generator's exact walker).
        first_strike_time: s, time of the global phase 0.
        body_mass: kg.

    The plate's centre is put, rounded to the mm, at the middle of the stance's centre of
    pressure (the middle of its X range, its mean Y).
    """
    if not np.isfinite(body_mass) or body_mass <= 0:
        raise ParameterError(f"body mass must be positive for the synthetic plates; got {body_mass} kg")
    times = np.arange(n_frames * SAMPLES_PER_FRAME) / (rate * SAMPLES_PER_FRAME)
    out = []
    for side, strike in stances:
        s = ((times - first_strike_time) / STRIDE_TIME_S - strike) / FOOT_OFF_PHASE
        heel, toe = foot_markers(times, side)
        force, free = stance_loads(s, body_mass, side)
        cop = stance_cop(s, heel, toe)
        loaded = np.isfinite(cop[:, 0])
        centre_x = 0.5 * (cop[loaded, 0].min() + cop[loaded, 0].max())
        plate = SyntheticPlate((float(np.round(centre_x)), float(np.round(cop[loaded, 1].mean())), 0.0))
        out.append(PlateRecording(plate, plate.channels(force, cop, free)))
    return out


def _add_int(c: object, group: str, name: str, value: object) -> None:
    """Add an integer parameter as the C3D's integer type (ezc3d's ``add_parameter``
    stores Python integers as floats; Vicon writes these as integers)."""
    import ezc3d

    array = np.asarray(value, dtype=int)
    param = ezc3d.ezc3d.Parameter(name, "")
    param.set(ezc3d.ezc3d.VecInt([int(v) for v in array.reshape(-1, order="F")]),
              ezc3d.ezc3d.VecUInt([int(d) for d in array.shape]))  # fmt: skip
    c._storage["parameters"].add_parameter(group, param)  # type: ignore[attr-defined]


def add_force_plates(path: Path | str, recordings: Sequence[PlateRecording]) -> Path:
    """Add the plates' analog channels and ``FORCE_PLATFORM`` group to the C3D file at
    ``path`` (rewritten in place with ezc3d; its points, events and other parameters as
    read).  Channels in Vicon Nexus' layout (module docstring); the analog rate is
    :data:`SAMPLES_PER_FRAME` times the point rate."""
    import ezc3d

    c = ezc3d.c3d(str(path))
    n_frames = c["data"]["points"].shape[2]
    rate = float(np.asarray(c["parameters"]["POINT"]["RATE"]["value"]).ravel()[0])
    for rec in recordings:
        if rec.channels.shape != (n_frames * SAMPLES_PER_FRAME, 6):
            raise ParameterError(f"plate channels of shape {rec.channels.shape}; the file needs "
                                 f"({n_frames * SAMPLES_PER_FRAME}, 6)")  # fmt: skip
    names = ("Force.Fx", "Force.Fy", "Force.Fz", "Moment.Mx", "Moment.My", "Moment.Mz")
    labels = [f"{name}{i}" for i in range(1, len(recordings) + 1) for name in names]
    n = len(labels)
    c["parameters"]["ANALOG"]["RATE"]["value"] = [rate * SAMPLES_PER_FRAME]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = labels
    c["parameters"]["ANALOG"]["DESCRIPTIONS"]["value"] = [f"Synthetic force plate [{i}]" for i in
                                                          range(1, len(recordings) + 1) for _ in names]  # fmt: skip
    c["parameters"]["ANALOG"]["SCALE"]["value"] = [1.0] * n
    c["parameters"]["ANALOG"]["OFFSET"]["value"] = [0] * n
    c["parameters"]["ANALOG"]["GEN_SCALE"]["value"] = [1.0]
    c["parameters"]["ANALOG"]["UNITS"]["value"] = ["N", "N", "N", "Nmm", "Nmm", "Nmm"] * len(recordings)
    c["data"]["analogs"] = np.concatenate([rec.channels.T for rec in recordings])[np.newaxis]
    _add_int(c, "FORCE_PLATFORM", "USED", [len(recordings)])
    _add_int(c, "FORCE_PLATFORM", "TYPE", [2] * len(recordings))
    _add_int(c, "FORCE_PLATFORM", "ZERO", [1, 0])
    c.add_parameter("FORCE_PLATFORM", "CORNERS", np.stack([r.plate.corners().T for r in recordings], axis=2))
    c.add_parameter("FORCE_PLATFORM", "ORIGIN", np.stack([np.asarray(r.plate.origin) for r in recordings], axis=1))
    _add_int(c, "FORCE_PLATFORM", "CHANNEL", np.arange(1, n + 1).reshape(len(recordings), 6).T)
    c.write(str(path))
    return Path(path)


def sample_walking_plates(n_frames: int, rate: float, body_mass: float,
                          geometry: SubjectGeometry | None = None) -> list[PlateRecording]:  # fmt: skip
    """The two plates of the sample walking trial (:func:`~fuzzygait.synthetic.generate.
    make_walking_trial` with ``n_frames`` at ``rate`` Hz): the stances of
    :data:`SAMPLE_STANCES` under the exact walker's feet."""
    x_offset = -WALKING_SPEED_MM_S * (n_frames - 1) / rate / 2.0
    first_strike = LEAD_IN_CYCLES * STRIDE_TIME_S

    def feet(times: Array, side: str) -> tuple[Array, Array]:
        pose, _, _ = walking_state(times, geometry, first_strike, x_offset)
        return pose.markers[side + "HEE"], pose.markers[side + "TOE"]

    return walking_plates(n_frames, rate, feet, first_strike, body_mass)


def plate_readme_values(recordings: Sequence[PlateRecording], geometry: SubjectGeometry,
                        rate: float) -> dict[str, object]:  # fmt: skip
    """The values the sample-data README states about the plates of a trial at ``rate``
    Hz (its template's fields)."""
    s = np.linspace(0.0, 1.0, 100001)
    vertical = VERTICAL_A * np.sin(np.pi * s) + VERTICAL_B * np.sin(3 * np.pi * s)
    rows = ["| plate | centre X, Y (mm) | X range (mm) | Y range (mm) | foot | frames loaded (> 10 N) |",
            "|---|---|---|---|---|---|"]
    for number, (rec, (side, _)) in enumerate(zip(recordings, SAMPLE_STANCES, strict=True), start=1):
        corners = rec.plate.corners()
        loaded = np.flatnonzero(-rec.channels[:, 2] > 10.0)
        frames = f"{loaded[0] // SAMPLES_PER_FRAME + 1}-{loaded[-1] // SAMPLES_PER_FRAME + 1}"
        rows.append(f"| {number} | {rec.plate.centre[0]:g}, {rec.plate.centre[1]:g} | {corners[:, 0].min():g} .. "
                    f"{corners[:, 0].max():g} | {corners[:, 1].min():g} .. {corners[:, 1].max():g} | "
                    f"{'left' if side == 'L' else 'right'} | {frames} |")  # fmt: skip
    return {
        "plate_rows": "\n".join(rows), "plate_x": PLATE_SIZE_MM[0], "plate_y": PLATE_SIZE_MM[1],
        "origin_z": PLATE_ORIGIN_MM[2], "analog_rate": rate * SAMPLES_PER_FRAME, "per_frame": SAMPLES_PER_FRAME,
        "bodymass": geometry.bodymass, "vert_a": VERTICAL_A, "vert_b": VERTICAL_B, "vert_peak": vertical.max(),
        "vert_valley": vertical[len(s) // 2], "ap": AP_PEAK, "ml": ML_PEAK, "free": FREE_MOMENT_PEAK_NMM / 1000.0,
        "cop_a": COP_FROM_TO[0], "cop_b": COP_FROM_TO[1],
    }  # fmt: skip
