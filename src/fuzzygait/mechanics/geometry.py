"""Centreline geometry of a prosthetic blade and its discretisation into beam nodes.

The blade is a precurved (predeformed) beam (thesis Section 4.2.1).  Its geometry is
read from a TOML file tabulating, in arclength order, centreline points together with
the cross-section width ``b`` and core thickness ``c`` (thesis Section 4.3: total
thickness ``a = c + 2 t_f`` with a constant face-layer thickness ``t_f``).

Frame (the *attachment frame*): origin at the attachment point (the ankle/pyramid
adapter at the distal end of the shank), x forward (walking direction), y lateral
(left), z up.  The blade lies in the x–z plane.  All lengths are in metres.

File format::

    [blade]
    name = "..."
    source = "where every number comes from"
    face_thickness = 0.0005          # t_f (m)
    points = [
        { x = 0.0, z = 0.0, width = 0.050, core_thickness = 0.014 },  # attachment
        ...                                                          # ... to the toe
    ]

The packaged default (:func:`default_blade`) is an *assumed*, documented Vari-Flex-like
shape, not a measurement; see the ``source`` text in ``mechanics/data/variflex_like.toml``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from importlib import resources
from numbers import Real
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.tomlfile import load_toml

#: Packaged default blade, relative to the ``fuzzygait.mechanics`` package.
DEFAULT_BLADE_RESOURCE = "data/variflex_like.toml"

_KIND = "blade geometry file"
_LATERAL = np.array([0.0, 1.0, 0.0])
# Gauss–Legendre rule for the arclength integrals of the centreline spline.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_SUBDIVISIONS = 16  # quadrature sub-intervals per spline interval


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def _directors_from_tangents(tangents: np.ndarray) -> np.ndarray:
    """Director triads ``(n, 3, 3)`` (``[k, i]`` = d_{i+1}) for unit tangents d3 ⟂ y."""
    n = len(tangents)
    d1 = np.broadcast_to(_LATERAL, (n, 3))
    d2 = np.cross(tangents, d1)
    return np.stack([d1, d2, tangents], axis=1)


@dataclass(frozen=True, eq=False)
class BladeMesh:
    """A beam discretised into ``n`` nodes and ``n - 1`` two-node elements.

    Attributes:
        positions: ``(n, 3)`` node positions (m) in the attachment frame; node 0 is the
            attachment point, node ``n - 1`` the toe.
        directors: ``(n, 3, 3)`` reference director triads, ``directors[k, i]`` is
            ``d_{i+1}`` of node ``k`` in the attachment frame: ``d3`` the unit tangent
            towards the toe, ``d1`` the lateral axis (cross-section width direction),
            ``d2 = d3 × d1`` (thickness direction); right-handed, ``d1 × d2 = d3``.
        element_length: ``(n - 1,)`` reference arclength of each element (m).
        width: ``(n - 1,)`` cross-section width ``b`` (along d1) at element mid-arclength (m).
        core_thickness: ``(n - 1,)`` core thickness ``c`` (along d2) at element
            mid-arclength (m).
        face_thickness: face-layer thickness ``t_f`` (m); 0 for a homogeneous beam.
    """

    positions: np.ndarray
    directors: np.ndarray
    element_length: np.ndarray
    width: np.ndarray
    core_thickness: np.ndarray
    face_thickness: float

    def __post_init__(self) -> None:
        for name in ("positions", "directors", "element_length", "width", "core_thickness"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))
        n = len(self.positions)
        if n < 2 or self.positions.shape != (n, 3):
            raise ParameterError(
                "BladeMesh: positions must have shape (n, 3) with n >= 2; "
                f"got {self.positions.shape}"
            )
        if self.directors.shape != (n, 3, 3):
            raise ParameterError(
                f"BladeMesh: directors must have shape ({n}, 3, 3); got {self.directors.shape}"
            )
        for name in ("element_length", "width", "core_thickness"):
            value = getattr(self, name)
            if value.shape != (n - 1,):
                raise ParameterError(
                    f"BladeMesh: {name} must have shape ({n - 1},) (one per element); "
                    f"got {value.shape}"
                )
            if not np.all(np.isfinite(value)) or np.any(value <= 0):
                raise ParameterError(f"BladeMesh: {name} must be finite and > 0 m")
        t_f = float(self.face_thickness)
        if not math.isfinite(t_f) or t_f < 0:
            raise ParameterError(f"BladeMesh: face_thickness must be >= 0 m; got {t_f}")
        object.__setattr__(self, "face_thickness", t_f)
        gram = np.einsum("kij,klj->kil", self.directors, self.directors)
        if not np.allclose(gram, np.eye(3), atol=1e-9):
            raise ParameterError("BladeMesh: directors must be orthonormal at every node")

    @property
    def n_nodes(self) -> int:
        """Number of nodes ``n``."""
        return len(self.positions)

    @property
    def length(self) -> float:
        """Total reference arclength (m)."""
        return float(self.element_length.sum())

    def total_thickness(self) -> np.ndarray:
        """``(n - 1,)`` total cross-section height ``a = c + 2 t_f`` per element (m)."""
        return self.core_thickness + 2.0 * self.face_thickness


class _Centreline:
    """Cubic spline ``r(t)`` through the points against cumulative chord length ``t``,
    with its true arclength ``S(t)`` by Gauss–Legendre quadrature and the inverse."""

    def __init__(self, points: np.ndarray) -> None:
        chords = np.linalg.norm(np.diff(points, axis=0), axis=1)
        self.t_knots = np.concatenate([[0.0], np.cumsum(chords)])
        self.spline = CubicSpline(self.t_knots, points, axis=0)
        # fine grid of parameter values with the cumulative arclength at each
        frac = np.arange(_SUBDIVISIONS) / _SUBDIVISIONS
        starts = self.t_knots[:-1, None] + chords[:, None] * frac[None, :]
        self.t_grid = np.concatenate([starts.ravel(), self.t_knots[-1:]])
        pieces = self._integral(self.t_grid[:-1], self.t_grid[1:])
        self.s_grid = np.concatenate([[0.0], np.cumsum(pieces)])
        self.length = float(self.s_grid[-1])

    def speed(self, t: np.ndarray) -> np.ndarray:
        return np.linalg.norm(self.spline(t, 1), axis=-1)

    def _integral(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        half = 0.5 * (b - a)
        nodes = 0.5 * (a + b)[:, None] + half[:, None] * _GL_X[None, :]
        return half * (self.speed(nodes) * _GL_W[None, :]).sum(axis=1)

    def arclength(self, t: np.ndarray) -> np.ndarray:
        """``S(t)``, arclength from the first point (m)."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.t_knots[-1])
        idx = np.clip(np.searchsorted(self.t_grid, t, side="right") - 1, 0, len(self.t_grid) - 2)
        return self.s_grid[idx] + self._integral(self.t_grid[idx], t)

    def parameter_at(self, s: np.ndarray) -> np.ndarray:
        """Parameter ``t`` with ``S(t) = s`` (Newton from a piecewise-linear guess)."""
        s = np.asarray(s, dtype=float)
        t = np.interp(s, self.s_grid, self.t_grid)
        for _ in range(8):
            step = (self.arclength(t) - s) / self.speed(t)
            t = np.clip(t - step, 0.0, self.t_knots[-1])
            if np.max(np.abs(step), initial=0.0) < 1e-15 * max(self.t_knots[-1], 1.0):
                break
        return t


@dataclass(frozen=True, eq=False)
class BladeGeometry:
    """Tabulated centreline of a precurved blade with its cross-section dimensions.

    Attributes:
        name: display name.
        source: where the numbers come from (measurement, assumption, ...).
        path: the file it was read from, or ``None``.
        points: ``(k, 3)`` centreline points (m) in the attachment frame, ordered by
            arclength from the attachment to the toe, ``y = 0``.
        width: ``(k,)`` cross-section width ``b`` (m, lateral) at each point.
        core_thickness: ``(k,)`` core thickness ``c`` (m) at each point.
        face_thickness: face-layer thickness ``t_f`` (m), constant along the blade.
        arclength: ``(k,)`` cumulative arclength (m) of the points along the centreline
            spline used by :meth:`discretise` (computed; first entry 0).
    """

    name: str
    source: str
    path: str | None
    points: np.ndarray
    width: np.ndarray
    core_thickness: np.ndarray
    face_thickness: float
    arclength: np.ndarray = field(init=False, repr=False)
    _curve: _Centreline = field(init=False, repr=False)

    def __post_init__(self) -> None:
        where = self.path if self.path is not None else f"blade {self.name!r}"
        points = np.array(self.points, dtype=float)
        if points.ndim != 2 or points.shape[1] != 3:
            raise ParameterError(f"{where}: points must have shape (k, 3); got {points.shape}")
        k = len(points)
        if k < 3:
            raise ParameterError(
                f"{where}: at least 3 centreline points are needed for a curved blade; got {k}"
            )
        if not np.all(np.isfinite(points)):
            raise ParameterError(f"{where}: centreline points must be finite numbers")
        if np.any(points[:, 1] != 0.0):
            raise ParameterError(
                f"{where}: the blade must lie in the x-z plane of the attachment frame (y = 0)"
            )
        for name in ("width", "core_thickness"):
            value = np.array(getattr(self, name), dtype=float)
            if value.shape != (k,):
                raise ParameterError(
                    f"{where}: {name} needs one value per point ({k}); got {value.shape}"
                )
            bad = np.flatnonzero(~np.isfinite(value) | (value <= 0))
            if bad.size:
                i = int(bad[0])
                raise ParameterError(
                    f"{where}: point {i} has {name} = {value[i]} m; it must be > 0 m"
                )
            object.__setattr__(self, name, _readonly(value))
        t_f = float(self.face_thickness)
        if not math.isfinite(t_f) or t_f < 0:
            raise ParameterError(
                f"{where}: face_thickness must be >= 0 m; got {self.face_thickness}"
            )
        object.__setattr__(self, "face_thickness", t_f)
        chords = np.diff(points, axis=0)
        lengths = np.linalg.norm(chords, axis=1)
        scale = max(float(lengths.sum()), 1e-300)
        dup = np.flatnonzero(lengths <= 1e-9 * scale)
        if dup.size:
            i = int(dup[0])
            raise ParameterError(
                f"{where}: points {i} and {i + 1} coincide; remove the duplicate point"
            )
        back = np.flatnonzero(np.einsum("ij,ij->i", chords[:-1], chords[1:]) <= 0)
        if back.size:
            i = int(back[0]) + 1
            raise ParameterError(
                f"{where}: the centreline turns back at point {i}; "
                "order the points by arclength from the attachment to the toe"
            )
        object.__setattr__(self, "points", _readonly(points))
        curve = _Centreline(points)
        object.__setattr__(self, "_curve", curve)
        object.__setattr__(self, "arclength", _readonly(curve.arclength(curve.t_knots)))

    @property
    def length(self) -> float:
        """Total arclength of the centreline spline (m)."""
        return self._curve.length

    def total_thickness(self) -> np.ndarray:
        """``(k,)`` total cross-section height ``a = c + 2 t_f`` at each point (m)."""
        return self.core_thickness + 2.0 * self.face_thickness

    def discretise(self, n_nodes: int) -> BladeMesh:
        """Nodes equally spaced in arclength along a cubic spline of the centreline.

        The centreline is interpolated by a C² cubic spline through the points against
        cumulative chord length.  Node 0 is the attachment point and node
        ``n_nodes - 1`` the toe; tangents (d3) come from the spline derivative; element
        lengths are arclengths along the spline (they sum to its length); width and core
        thickness are interpolated linearly in arclength at element mid-arclength.

        Raises:
            ParameterError: ``n_nodes`` is not an integer >= 2.
        """
        if isinstance(n_nodes, bool) or not isinstance(n_nodes, (int, np.integer)) or n_nodes < 2:
            raise ParameterError(
                f"n_nodes must be an integer >= 2 (attachment and toe nodes); got {n_nodes!r}"
            )
        curve = self._curve
        s_nodes = np.linspace(0.0, curve.length, int(n_nodes))
        t_nodes = curve.parameter_at(s_nodes)
        t_nodes[0], t_nodes[-1] = 0.0, curve.t_knots[-1]
        positions = curve.spline(t_nodes)
        positions[0], positions[-1] = self.points[0], self.points[-1]
        tangents = curve.spline(t_nodes, 1)
        tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
        s_actual = curve.arclength(t_nodes)
        element_length = np.diff(s_actual)
        s_mid = 0.5 * (s_actual[:-1] + s_actual[1:])
        return BladeMesh(
            positions=positions,
            directors=_directors_from_tangents(tangents),
            element_length=element_length,
            width=np.interp(s_mid, self.arclength, self.width),
            core_thickness=np.interp(s_mid, self.arclength, self.core_thickness),
            face_thickness=self.face_thickness,
        )


def _number(value: Any, where: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ParameterError(f"{where}: {key} must be a number in metres; got {value!r}")
    return float(value)


def read_blade_geometry(path: str | os.PathLike[str]) -> BladeGeometry:
    """The blade geometry in the TOML file at ``path`` (format: see the module docstring).

    Raises:
        ParameterError: missing file, invalid TOML, a missing or malformed key, fewer
            than 3 points, duplicate or back-turning points, or a non-positive width or
            thickness; the message names the file.
    """
    where = os.fspath(path)
    doc = load_toml(path, _KIND)
    blade = doc.get("blade")
    if not isinstance(blade, dict):
        raise ParameterError(f"{where}: missing table [blade]; see fuzzygait.mechanics.geometry")
    for key in ("name", "source", "face_thickness", "points"):
        if key not in blade:
            raise ParameterError(f"{where}: missing key 'blade.{key}'; add it to the [blade] table")
    for key in ("name", "source"):
        if not isinstance(blade[key], str):
            raise ParameterError(f"{where}: blade.{key} must be a string")
    face = _number(blade["face_thickness"], where, "blade.face_thickness")
    rows = blade["points"]
    if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
        raise ParameterError(
            f"{where}: blade.points must be an array of tables {{x, z, width, core_thickness}}"
        )
    columns: dict[str, list[float]] = {"x": [], "z": [], "width": [], "core_thickness": []}
    for i, row in enumerate(rows):
        for key, column in columns.items():
            if key not in row:
                raise ParameterError(f"{where}: missing key 'blade.points[{i}].{key}'; add it")
            column.append(_number(row[key], where, f"blade.points[{i}].{key}"))
    x = np.array(columns["x"])
    points = np.column_stack([x, np.zeros_like(x), np.array(columns["z"])]).reshape(-1, 3)
    return BladeGeometry(
        name=blade["name"],
        source=blade["source"],
        path=where,
        points=points,
        width=np.array(columns["width"]),
        core_thickness=np.array(columns["core_thickness"]),
        face_thickness=face,
    )


def default_blade() -> BladeGeometry:
    """The packaged Vari-Flex-like blade (assumed geometry, see its ``source`` text)."""
    resource = resources.files("fuzzygait.mechanics").joinpath(DEFAULT_BLADE_RESOURCE)
    with resources.as_file(resource) as path:
        return read_blade_geometry(path)


def straight_beam(
    length: float,
    width: float,
    thickness: float,
    n_nodes: int,
    direction: tuple[float, float, float] | np.ndarray = (1.0, 0.0, 0.0),
) -> BladeMesh:
    """A straight prismatic beam from the origin along ``direction`` (for cantilever tests).

    Args:
        length: total length (m).
        width: cross-section width ``b`` along d1 (m).
        thickness: cross-section height ``a`` along d2 (m), stored as the core thickness
            with ``face_thickness = 0``.
        n_nodes: number of nodes (>= 2), equally spaced.
        direction: beam axis d3 in the attachment frame (normalised here).

    The lateral director d1 is the y axis projected perpendicular to d3 (the z axis when
    d3 is parallel to y), and ``d2 = d3 × d1``, so ``d1 × d2 = d3``; for d3 = x this gives
    d1 = y, d2 = z.
    """
    for name, value in (("length", length), ("width", width), ("thickness", thickness)):
        bad_type = isinstance(value, bool) or not isinstance(value, Real)
        if bad_type or not math.isfinite(value) or value <= 0:
            raise ParameterError(f"straight_beam: {name} must be a number > 0 m; got {value!r}")
    if isinstance(n_nodes, bool) or not isinstance(n_nodes, (int, np.integer)) or n_nodes < 2:
        raise ParameterError(f"straight_beam: n_nodes must be an integer >= 2; got {n_nodes!r}")
    d3 = np.asarray(direction, dtype=float)
    norm = float(np.linalg.norm(d3)) if d3.shape == (3,) else 0.0
    if not math.isfinite(norm) or norm == 0.0:
        raise ParameterError(
            f"straight_beam: direction must be a non-zero 3-vector; got {direction!r}"
        )
    d3 = d3 / norm
    d1 = _LATERAL - (_LATERAL @ d3) * d3
    if np.linalg.norm(d1) < 1e-8:
        d1 = np.array([0.0, 0.0, 1.0]) - d3[2] * d3
    d1 /= np.linalg.norm(d1)
    d2 = np.cross(d3, d1)
    n = int(n_nodes)
    s = np.linspace(0.0, float(length), n)
    ne = n - 1
    return BladeMesh(
        positions=s[:, None] * d3[None, :],
        directors=np.broadcast_to(np.stack([d1, d2, d3]), (n, 3, 3)).copy(),
        element_length=np.diff(s),
        width=np.full(ne, float(width)),
        core_thickness=np.full(ne, float(thickness)),
        face_thickness=0.0,
    )
