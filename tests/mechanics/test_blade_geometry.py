"""Blade geometry, discretisation, rectangular sections and thesis presets."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.geometry import (
    BladeGeometry,
    default_blade,
    read_blade_geometry,
    straight_beam,
)
from fuzzygait.mechanics.presets import (
    REVERSE_ENGINEERED,
    SHANK,
    STANCE,
    SWING,
    THIGH,
    Material,
    material_with,
)
from fuzzygait.mechanics.sections import SHEAR_CORRECTION_RECTANGLE, RectangleSection


def _write_blade(path: Path, rows: list[dict[str, float]], *, face: float = 0.0005,
                 header: str | None = None) -> Path:
    lines = [
        "[blade]" if header is None else header,
        'name = "test blade"',
        'source = "synthetic"',
        f"face_thickness = {face!r}",
        "points = [",
    ]
    for row in rows:
        inner = ", ".join(f"{k} = {v!r}" for k, v in row.items())
        lines.append(f"    {{ {inner} }},")
    lines.append("]")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _arc_rows(radius: float, angle: float, k: int, centre=(0.03, -0.05)):
    phi = np.linspace(0.0, angle, k) - 2.0
    x = centre[0] + radius * np.cos(phi)
    z = centre[1] + radius * np.sin(phi)
    return [
        {"x": float(xi), "z": float(zi), "width": 0.05, "core_thickness": 0.01}
        for xi, zi in zip(x, z)
    ]


def _check_directors(directors: np.ndarray) -> None:
    d1, d2, d3 = directors[:, 0], directors[:, 1], directors[:, 2]
    gram = np.einsum("kij,klj->kil", directors, directors)
    assert np.allclose(gram, np.eye(3), atol=1e-12, rtol=0)
    assert np.allclose(np.cross(d1, d2), d3, atol=1e-12, rtol=0)


# --- discretisation ---------------------------------------------------------------------

def test_circular_arc_discretisation(tmp_path: Path) -> None:
    radius, angle, centre = 0.05, math.radians(120.0), np.array([0.03, 0.0, -0.05])
    path = _write_blade(tmp_path / "arc.toml", _arc_rows(radius, angle, 41))
    mesh = read_blade_geometry(path).discretise(30)
    rel = mesh.positions - centre
    r = np.linalg.norm(rel, axis=1)
    assert np.max(np.abs(r / radius - 1.0)) <= 1e-4
    d3 = mesh.directors[:, 2]
    assert np.max(np.abs(np.einsum("ij,ij->i", d3, rel / r[:, None]))) <= 1e-4
    assert mesh.element_length.sum() == pytest.approx(radius * angle, rel=1e-4)
    assert np.allclose(mesh.element_length, mesh.element_length.mean(), rtol=1e-6)
    assert np.allclose(mesh.positions[:, 1], 0.0)
    _check_directors(mesh.directors)
    assert np.allclose(mesh.directors[:, 0], [0.0, 1.0, 0.0])


def test_default_blade() -> None:
    blade = default_blade()
    assert isinstance(blade, BladeGeometry)
    assert blade.path is not None and blade.path.endswith("variflex_like.toml")
    assert "ASSUMED" in blade.source
    assert blade.face_thickness == pytest.approx(0.0005)
    assert 15 <= len(blade.points) <= 25
    assert blade.arclength[0] == 0.0 and np.all(np.diff(blade.arclength) > 0)
    mesh = blade.discretise(20)
    assert mesh.n_nodes == 20 and mesh.element_length.shape == (19,)
    assert np.allclose(mesh.positions[0], 0.0)
    toe = mesh.positions[-1]
    assert 0.12 <= toe[0] <= 0.25
    assert -0.2 <= mesh.positions[:, 2].min() <= -0.1
    assert np.all(mesh.width > 0) and np.all(mesh.core_thickness > 0)
    assert np.all(mesh.total_thickness() == mesh.core_thickness + 2 * 0.0005)
    assert np.all(blade.total_thickness() > blade.core_thickness)
    # tangent at the attachment points down, at the toe forward
    assert mesh.directors[0, 2, 2] < -0.9 and mesh.directors[-1, 2, 0] > 0.9
    _check_directors(mesh.directors)
    fine = blade.discretise(200)
    assert fine.element_length.sum() == pytest.approx(mesh.element_length.sum(), rel=1e-3)
    assert mesh.element_length.sum() == pytest.approx(blade.arclength[-1], rel=1e-12)


def test_discretise_rejects_too_few_nodes() -> None:
    with pytest.raises(ParameterError, match="n_nodes"):
        default_blade().discretise(1)


def test_straight_beam_exact() -> None:
    mesh = straight_beam(0.5, 0.04, 0.01, 6)
    assert np.array_equal(mesh.positions[:, 0], np.linspace(0.0, 0.5, 6))
    assert np.all(mesh.positions[:, 1:] == 0.0)
    assert np.allclose(mesh.element_length, 0.1, rtol=0, atol=1e-15)
    assert np.allclose(mesh.directors[0], np.eye(3)[[1, 2, 0]])  # d1 = y, d2 = z, d3 = x
    assert mesh.face_thickness == 0.0 and np.all(mesh.total_thickness() == 0.01)
    _check_directors(mesh.directors)
    down = straight_beam(0.3, 0.04, 0.01, 4, direction=(0.0, 0.0, -2.0))
    assert np.allclose(down.positions[-1], [0.0, 0.0, -0.3], atol=1e-15)
    _check_directors(down.directors)
    lateral = straight_beam(0.3, 0.04, 0.01, 3, direction=(0.0, 1.0, 0.0))
    _check_directors(lateral.directors)
    with pytest.raises(ParameterError, match="length"):
        straight_beam(0.0, 0.04, 0.01, 4)


# --- sections ---------------------------------------------------------------------------

# k1 = J / (long · short³), Timoshenko & Goodier's table (printed to 3–4 digits).
@pytest.mark.parametrize("ratio, k1", [(1.0, 0.1406), (2.0, 0.229), (4.0, 0.281), (10.0, 0.312)])
def test_rectangle_torsion_constant(ratio: float, k1: float) -> None:
    short = 0.01
    long = ratio * short
    table = k1 * long * short**3
    j_wide = RectangleSection(long, short).torsion_constant
    j_tall = RectangleSection(short, long).torsion_constant
    assert j_wide == pytest.approx(j_tall, rel=1e-14)
    # within the table's rounding (half a unit in its last digit) and 2e-3 relative
    assert abs(j_wide / (long * short**3) - k1) <= 5e-4
    assert j_wide == pytest.approx(table, rel=2e-3)


def test_rectangle_section_properties() -> None:
    s = RectangleSection(np.array([0.05, 0.06]), np.array([0.01, 0.02]))
    assert np.allclose(s.area, [5e-4, 1.2e-3])
    assert np.allclose(s.second_moment_1, [0.05 * 1e-6 / 12, 0.06 * 8e-6 / 12])
    assert np.allclose(s.second_moment_2, [0.01 * 0.05**3 / 12, 0.02 * 0.06**3 / 12])
    long_thin = RectangleSection(1000.0, 1.0).torsion_constant
    assert long_thin == pytest.approx(1000.0 / 3.0, rel=1e-3)
    assert SHEAR_CORRECTION_RECTANGLE == pytest.approx(5.0 / 6.0)
    with pytest.raises(ParameterError, match="height"):
        RectangleSection(0.05, -0.01)


# --- presets ----------------------------------------------------------------------------

def test_presets() -> None:
    m = REVERSE_ENGINEERED
    assert m.shear_modulus == pytest.approx(m.youngs_modulus / (2 * (1 + m.poisson)))
    assert m.shear_modulus == pytest.approx(23.699e9, rel=1e-4)
    assert SWING.material.shear_modulus == pytest.approx(23.69e4, rel=1e-3)
    assert STANCE.material.shear_modulus == pytest.approx(23.69e7, rel=1e-3)
    assert STANCE.shank_mass == 107.0 and SWING.shank_mass == SHANK.mass
    assert SWING.hip_angle == pytest.approx(-math.pi / 6)  # extension, flexion positive
    assert SWING.knee_angle == pytest.approx(math.pi / 3)
    assert THIGH.inertia[2] < THIGH.inertia[0] and SHANK.length == 0.3753


def test_material_with() -> None:
    soft = material_with(REVERSE_ENGINEERED, youngs_modulus=1e9, damping=0.0)
    assert isinstance(soft, Material) and soft.youngs_modulus == 1e9 and soft.density == 1.71e3
    assert REVERSE_ENGINEERED.youngs_modulus == 59958e6
    for kwargs, name in [
        ({"youngs_modulus": 0.0}, "youngs_modulus"),
        ({"density": -1.0}, "density"),
        ({"poisson": 0.5}, "poisson"),
        ({"poisson": -1.0}, "poisson"),
        ({"damping": -0.1}, "damping"),
        ({"young": 1e9}, "young"),
    ]:
        with pytest.raises(ParameterError, match=name):
            material_with(REVERSE_ENGINEERED, **kwargs)


# --- bad files --------------------------------------------------------------------------

_GOOD = [
    {"x": 0.0, "z": 0.0, "width": 0.05, "core_thickness": 0.01},
    {"x": 0.0, "z": -0.1, "width": 0.05, "core_thickness": 0.01},
    {"x": 0.05, "z": -0.15, "width": 0.05, "core_thickness": 0.01},
    {"x": 0.2, "z": -0.15, "width": 0.05, "core_thickness": 0.01},
]


def _modified(i: int, **changes: float) -> list[dict[str, float]]:
    rows = [dict(r) for r in _GOOD]
    rows[i].update(changes)
    return rows


@pytest.mark.parametrize(
    "case",
    ["missing", "syntax", "no_table", "no_key", "no_point_key", "duplicate", "backwards",
     "zero_width", "negative_thickness", "two_points"],
)
def test_bad_files_name_the_file(tmp_path: Path, case: str) -> None:
    path = tmp_path / f"bad_{case}.toml"
    if case == "missing":
        pass
    elif case == "syntax":
        path.write_text("[blade\nname = 1\n", encoding="utf-8")
    elif case == "no_table":
        _write_blade(path, _GOOD, header="[prosthesis]")
    elif case == "no_key":
        path.write_text('[blade]\nname = "x"\nsource = "y"\npoints = []\n', encoding="utf-8")
    elif case == "no_point_key":
        rows = [dict(r) for r in _GOOD]
        del rows[2]["width"]
        _write_blade(path, rows)
    elif case == "duplicate":
        _write_blade(path, _GOOD[:2] + [dict(_GOOD[1])] + _GOOD[2:])
    elif case == "backwards":
        _write_blade(path, [_GOOD[0], _GOOD[2], _GOOD[1], _GOOD[3]])
    elif case == "zero_width":
        _write_blade(path, _modified(1, width=0.0))
    elif case == "negative_thickness":
        _write_blade(path, _modified(3, core_thickness=-0.001))
    elif case == "two_points":
        _write_blade(path, _GOOD[:2])
    with pytest.raises(ParameterError) as info:
        read_blade_geometry(path)
    message = str(info.value)
    assert path.name in message and "\n" not in message
