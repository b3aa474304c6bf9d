"""Synthetic force-plate C3D files with known loads, written with ezc3d.

Every plate carries a known reaction force F, centre of pressure (x, y) and free moment
Tz in its own frame (x, y on the surface, z into the plate), chosen as integers so that
each channel value -- and each stored number, the channel divided by a power-of-two
``SCALE * GEN_SCALE`` -- is exact in the file's float32: the loads read back must equal
the truth to rounding (1e-9 relative), not to float32 precision.

The plates lie in the laboratory frame turned about the vertical by an angle whose cosine
and sine are 3/5 and 4/5 (or a right angle), so the corners are integers too; the
expected laboratory values use the rotation written here, not the reader's corner rule.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import ezc3d
import numpy as np

POINT_RATE = 100.0
ANALOG_RATE = 1000.0
PER_FRAME = 10
N_FRAMES = 20
N = N_FRAMES * PER_FRAME  # analog samples


def yaw(cos: float, sin: float) -> np.ndarray:
    """Plate axes (columns) in the laboratory frame: x = (cos, sin, 0), z down."""
    return np.array([[cos, sin, 0.0], [sin, -cos, 0.0], [0.0, 0.0, -1.0]])


@dataclass
class Truth:
    """Known loads of one plate, plate frame: reaction force (N), COP (mm), free moment
    about the normal (N·mm); ``contact`` False where there is no load."""

    force: np.ndarray
    cop: np.ndarray
    tz: np.ndarray

    @property
    def contact(self) -> np.ndarray:
        return -self.force[:, 2] > 10.0

    def moment_centre(self) -> np.ndarray:
        """Moment about the surface centre: COP x F + (0, 0, Tz)."""
        p = np.column_stack([self.cop, np.zeros(len(self.cop))])
        m = np.cross(p, self.force)
        m[:, 2] += self.tz
        return m


def truth(seed: int, n: int = N, unloaded: slice | None = slice(0, 30)) -> Truth:
    """Integer loads: |Fx|, |Fy| <= 150 N, Fz in [-900, -40] N, COP within +-200 mm,
    Tz within +-4000 N·mm; no load in the ``unloaded`` samples."""
    rng = np.random.default_rng(seed)
    force = np.column_stack([rng.integers(-150, 151, n), rng.integers(-150, 151, n), rng.integers(-900, -39, n)])
    cop = rng.integers(-200, 201, (n, 2)).astype(float)
    tz = rng.integers(-4000, 4001, n).astype(float)
    force = force.astype(float)
    if unloaded is not None:
        force[unloaded] = 0.0
        cop[unloaded] = 0.0
        tz[unloaded] = 0.0
    return Truth(force, cop, tz)


@dataclass
class Plate:
    """One plate of a synthetic file: its type, placement, origin and channel values."""

    kind: int
    rotation: np.ndarray  # plate axes (columns) in the laboratory frame
    centre: np.ndarray  # mm, laboratory frame
    size: tuple[float, float]  # mm along the plate's x and y
    origin: np.ndarray  # ORIGIN as written, mm
    channels: np.ndarray  # (N, k) channel values in physical units
    calibration: np.ndarray | None = None  # (6, k) for types 4 and 5
    units: list[str] = field(default_factory=list)
    scales: list[float] = field(default_factory=list)  # SCALE per channel (power of two)

    def corners(self) -> np.ndarray:
        """(4, 3): +x+y, -x+y, -x-y, +x-y corners of the surface, laboratory frame."""
        w, h = self.size[0] / 2, self.size[1] / 2
        local = np.array([[w, h, 0.0], [-w, h, 0.0], [-w, -h, 0.0], [w, -h, 0.0]])
        return self.centre + local @ self.rotation.T


def type2_channels(t: Truth, depth: np.ndarray) -> np.ndarray:
    """Fx, Fy, Fz, Mx, My, Mz about the transducer origin at ``depth`` below the centre."""
    m_origin = t.moment_centre() - np.cross(depth, t.force)
    return np.column_stack([t.force, m_origin])


def type1_channels(t: Truth) -> np.ndarray:
    """Fx, Fy, Fz, Px, Py, Tz."""
    return np.column_stack([t.force, t.cop, t.tz])


def type3_channels(t: Truth, a: float, b: float, az0: float) -> np.ndarray:
    """Kistler fx12, fx34, fy14, fy23, fz1..fz4 (N) whose sums and moments about the
    sensor plane's centre (|az0| below the surface) give the truth."""
    m = t.moment_centre() - np.cross(np.array([0.0, 0.0, abs(az0)]), t.force)
    s, big_a, big_b = t.force[:, 2], m[:, 0] / b, m[:, 1] / a
    fz = np.column_stack([(s + big_a - big_b) / 4, (s + big_a + big_b) / 4, (s - big_a + big_b) / 4,
                          (s - big_a - big_b) / 4])  # fmt: skip
    dx = m[:, 2] / b  # fx34 - fx12, with fy14 = fy23
    fx = np.column_stack([(t.force[:, 0] - dx) / 2, (t.force[:, 0] + dx) / 2])
    fy = np.column_stack([t.force[:, 1] / 2, t.force[:, 1] / 2])
    return np.column_stack([fx, fy, fz])


#: A calibration with cross-talk whose inverse is exact: unit lower-triangular integers
#: times a power-of-two diagonal (outputs = CAL @ channels).
CAL = np.array([[1, 0, 0, 0, 0, 0], [1, 1, 0, 0, 0, 0], [0, 2, 1, 0, 0, 0], [0, 0, 3, 1, 0, 0], [4, 0, 0, 1, 1, 0],
                [0, 0, 0, 2, 0, 1]], dtype=float) @ np.diag([256.0, 256.0, 512.0, 4096.0, 4096.0, 2048.0])  # fmt: skip


def _add(c: ezc3d.c3d, group: str, name: str, value: object) -> None:
    """Add a parameter, integers as the C3D's integer type (ezc3d's ``add_parameter``
    stores Python integers as floats)."""
    array = np.asarray(value)
    if not np.issubdtype(array.dtype, np.integer):
        c.add_parameter(group, name, array.astype(float) if array.ndim else float(array))
        return
    param = ezc3d.ezc3d.Parameter(name, "")
    param.set(ezc3d.ezc3d.VecInt([int(v) for v in array.reshape(-1, order="F")]),
              ezc3d.ezc3d.VecUInt([int(d) for d in array.shape]))
    c._storage["parameters"].add_parameter(group, param)


def write(path: Path, plates: list[Plate], *, gen_scale: float = 0.5, zero: tuple[int, int] = (1, 0),
          bits: int | None = None, extra: dict[str, dict[str, object]] | None = None) -> Path:  # fmt: skip
    """Write ``plates`` (channels numbered in order, two spare channels first) to ``path``."""
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [POINT_RATE]
    c["parameters"]["ANALOG"]["RATE"]["value"] = [ANALOG_RATE]
    c["parameters"]["POINT"]["LABELS"]["value"] = ["M1"]
    c["data"]["points"] = np.ones((4, 1, N_FRAMES))
    columns = [np.zeros(N), np.arange(N, dtype=float)]  # spare channels
    labels, units, scales, channel_numbers = ["spare1", "spare2"], ["V", "V"], [1.0, 1.0], []
    for i, plate in enumerate(plates, start=1):
        k = plate.channels.shape[1]
        channel_numbers.append(list(range(len(columns) + 1, len(columns) + k + 1)))
        columns += list(plate.channels.T)
        labels += [f"P{i}C{j + 1}" for j in range(k)]
        units += plate.units or (["N"] * 3 + ["Nmm"] * 3 if k == 6 else ["N"] * k)
        scales += plate.scales or [0.25, 0.5, 2.0, 4.0, 8.0, 16.0, 0.5, 1.0][:k]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = labels
    c["parameters"]["ANALOG"]["SCALE"]["value"] = scales
    c["parameters"]["ANALOG"]["OFFSET"]["value"] = [0] * len(labels)
    c["parameters"]["ANALOG"]["GEN_SCALE"]["value"] = [gen_scale]
    c["parameters"]["ANALOG"]["UNITS"]["value"] = units
    if bits is not None:
        c["parameters"]["ANALOG"]["BITS"]["value"] = [bits]
    c["data"]["analogs"] = np.array(columns)[np.newaxis]
    width = max(p.channels.shape[1] for p in plates)
    channel = np.zeros((width, len(plates)), dtype=int)
    for j, numbers in enumerate(channel_numbers):
        channel[: len(numbers), j] = numbers
    _add(c, "FORCE_PLATFORM", "USED", [len(plates)])
    _add(c, "FORCE_PLATFORM", "TYPE", [p.kind for p in plates])
    _add(c, "FORCE_PLATFORM", "ZERO", list(zero))
    _add(c, "FORCE_PLATFORM", "CORNERS", np.stack([p.corners().T for p in plates], axis=2))
    _add(c, "FORCE_PLATFORM", "ORIGIN", np.stack([p.origin for p in plates], axis=1))
    _add(c, "FORCE_PLATFORM", "CHANNEL", channel)
    if any(p.calibration is not None for p in plates):
        cal = np.zeros((6, width, len(plates)))
        for j, p in enumerate(plates):
            if p.calibration is not None:
                cal[:, : p.calibration.shape[1], j] = p.calibration
        _add(c, "FORCE_PLATFORM", "CAL_MATRIX", cal)
    for group, params in (extra or {}).items():
        for name, value in params.items():
            _add(c, group, name, value)
    c.write(str(path))
    return path


def expected_lab(plate: Plate, t: Truth) -> dict[str, np.ndarray]:
    """The laboratory-frame values a reader must give (the rotation written here)."""
    r = plate.rotation
    cop = plate.centre + np.column_stack([t.cop, np.zeros(len(t.cop))]) @ r.T
    cop[~t.contact] = np.nan
    free = np.zeros_like(t.force)
    free[:, 2] = np.where(t.contact, t.tz, 0.0)
    return {"force": t.force @ r.T, "cop": cop, "free_moment": free @ r.T, "contact": t.contact}
