"""Three-layer section homogenisation (thesis §4.3) against independent truth.

* the Saint-Venant torsion constant of a rectangle against the classical table
  (Timoshenko & Goodier, Roark: J = k₁ · long · short³);
* the coupled torsional rigidity of genuinely layered sections against a finite-volume
  solution of the Prandtl problem ∇·((1/G)∇Ψ) = −2, Ψ = 0 on the boundary, C₃ = 2∫Ψ dA,
  on a 200 × 200 grid with the layer interfaces on cell faces (and its Richardson
  extrapolation from a 100 × 100 grid) — the check of the re-derived C₍ₙ₎ of Eq. 4.41;
* bending stiffnesses, axial stiffness, mass and rotary inertia against quadrature of
  ∫E x² dA, ∫ρ x² dA over the layers;
* the homogeneous limit (face material = core material) against E b a³/12, E b a, G J.

Measured deviations are printed (run with ``-s``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sparse
from scipy.integrate import quad
from scipy.sparse.linalg import spsolve

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.homogenisation import (
    LayerMaterials,
    SectionStiffness,
    coupled_stiffness,
    rectangle_torsion_constant,
    shape_function_F,
    standard_stiffness,
)

NU = 0.265


def materials(face_modulus: float, core_modulus: float, face_density: float = 1500.0,
              core_density: float = 1500.0) -> LayerMaterials:  # fmt: skip
    return LayerMaterials(face_modulus, core_modulus, NU, face_density, core_density)


def shear(modulus: float) -> float:
    return modulus / (2 * (1 + NU))


# ------------------------------------------------------------ independent solvers
def prandtl_torsion_fv(width: float, core: float, face: float, g_core: float, g_face: float,
                       cells: int) -> float:  # fmt: skip
    """Torsional rigidity 2∫Ψ dA of the face/core/face rectangle by cell-centred finite
    volumes for ∇·((1/G)∇Ψ) = −2, Ψ = 0 on the boundary; ``cells`` cells across the width
    and across the height, the layer interfaces on cell faces (harmonic coupling)."""
    n_face = max(2, round(cells * face / (core + 2 * face)))
    n_core = cells - 2 * n_face
    h1 = width / cells
    h2 = np.concatenate([np.full(n_face, face / n_face), np.full(n_core, core / n_core),
                         np.full(n_face, face / n_face)])  # fmt: skip
    k2 = 1.0 / np.concatenate([np.full(n_face, g_face), np.full(n_core, g_core),
                               np.full(n_face, g_face)])  # fmt: skip
    n2 = h2.size
    index = np.arange(cells * n2).reshape(cells, n2)
    diag = np.zeros((cells, n2))
    rows, cols, vals = [], [], []

    def couple(a: np.ndarray, b: np.ndarray, conductance: np.ndarray) -> None:
        rows.extend([a.ravel(), b.ravel()])
        cols.extend([b.ravel(), a.ravel()])
        vals.extend([-conductance.ravel(), -conductance.ravel()])

    t1 = np.broadcast_to(h2 * k2 / h1, (cells - 1, n2))  # along the width, within a layer
    couple(index[:-1], index[1:], t1)
    diag[:-1] += t1
    diag[1:] += t1
    diag[[0, -1]] += h2 * k2 / (h1 / 2)  # Ψ = 0 at x₁ = ±b/2
    t2 = np.broadcast_to(h1 / (h2[:-1] / (2 * k2[:-1]) + h2[1:] / (2 * k2[1:])), (cells, n2 - 1))
    couple(index[:, :-1], index[:, 1:], t2)
    diag[:, :-1] += t2
    diag[:, 1:] += t2
    diag[:, 0] += h1 * 2 * k2[0] / h2[0]  # Ψ = 0 at x₂ = ±a/2
    diag[:, -1] += h1 * 2 * k2[-1] / h2[-1]
    rows.append(index.ravel())
    cols.append(index.ravel())
    vals.append(diag.ravel())
    size = cells * n2
    matrix = sparse.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(size, size)
    )
    area = (h1 * h2)[None, :].repeat(cells, axis=0).ravel()
    psi = spsolve(matrix, 2.0 * area)
    return float(2.0 * psi @ area)


def layer_integral(weight_face: float, weight_core: float, core: float, face: float,
                   power: int) -> float:  # fmt: skip
    """∫ w(x₂) x₂^power dx₂ over the height, by adaptive quadrature split at interfaces."""
    half_a, half_c = core / 2 + face, core / 2

    def integrand(x: float) -> float:
        return (weight_core if abs(x) < half_c else weight_face) * x**power

    value, _ = quad(integrand, -half_a, half_a, points=[-half_c, half_c], epsabs=0, epsrel=1e-12)
    return value


# ------------------------------------------------------------ torsion constant
# k₁ of J = k₁ · long · short³ (Timoshenko & Goodier, Theory of Elasticity, §109;
# Roark table 10.7), given to 3 decimals (square: 4), so held to half a unit of the
# last digit.
TABLE_K1 = [(1.0, 0.1406, 5e-5), (1.5, 0.196, 5e-4), (2.0, 0.229, 5e-4),
            (2.5, 0.249, 5e-4), (3.0, 0.263, 5e-4), (4.0, 0.281, 5e-4),
            (5.0, 0.291, 5e-4), (10.0, 0.312, 5e-4)]  # fmt: skip


@pytest.mark.parametrize(("ratio", "k1", "tolerance"), TABLE_K1)
def test_rectangle_torsion_constant_matches_classical_table(ratio: float, k1: float,
                                                            tolerance: float) -> None:  # fmt: skip
    short = 0.003
    for width, height in [(ratio * short, short), (short, ratio * short)]:
        k = rectangle_torsion_constant(width, height) / (ratio * short * short**3)
        assert abs(k - k1) <= tolerance, (ratio, k)
        assert abs(k / k1 - 1) < 3.6e-3  # 1e-3 relative where the table gives 4 digits


def test_rectangle_torsion_constant_thin_strip_and_square_limit() -> None:
    # a thin strip: J → long·short³/3 (1 − 0.630 short/long), the first correction exact
    # in the limit: 1 − (192/π⁵) Σ (2n+1)⁻⁵ · short/long = 1 − 0.6302 short/long
    for ratio in (1e3, 1e6):
        k = rectangle_torsion_constant(ratio, 1.0) / ratio
        expected = (1 - 192 / math.pi**5 * 1.0045237627724553 / ratio) / 3
        assert k == pytest.approx(expected, rel=1e-9)
    # the square: J = 0.1406 a⁴ (2.2492 (a/2)⁴, Timoshenko & Goodier)
    assert rectangle_torsion_constant(2.0, 2.0) == pytest.approx(2.2492, rel=1e-4)


def test_rectangle_torsion_constant_against_finite_volumes() -> None:
    for width, height in [(1.0, 1.0), (0.04, 0.004)]:
        fv = prandtl_torsion_fv(width, height / 2, height / 4, 1.0, 1.0, 200)
        series = rectangle_torsion_constant(width, height)
        print(f"homogeneous {width}x{height}: FV/series - 1 = {fv / series - 1:.2e}")
        assert fv / series - 1 == pytest.approx(0, abs=1e-3)


# ------------------------------------------------------------ coupled torsion
LAYERED = [
    # width, core, face, E_core, E_face  (m, m, m, Pa, Pa)
    (0.040, 0.002, 0.0005, 2e9, 60e9),  # prosthesis-like: stiff faces, wide thin section
    (0.040, 0.002, 0.0005, 60e9, 2e9),  # soft faces
    (0.010, 0.006, 0.002, 1e9, 10e9),  # thick faces, b/a = 1
    (0.010, 0.006, 0.002, 10e9, 1e9),
    (0.005, 0.005, 0.0025, 1e9, 4e9),  # narrow: b/a = 0.5
]


@pytest.mark.parametrize(("width", "core", "face", "e_core", "e_face"), LAYERED)
def test_coupled_torsion_matches_finite_volume_prandtl_solution(
    width: float, core: float, face: float, e_core: float, e_face: float
) -> None:
    stiffness = coupled_stiffness(materials(e_face, e_core), width, core, face)
    g_core, g_face = shear(e_core), shear(e_face)
    coarse = prandtl_torsion_fv(width, core, face, g_core, g_face, 100)
    fine = prandtl_torsion_fv(width, core, face, g_core, g_face, 200)
    richardson = (4 * fine - coarse) / 3  # second-order scheme
    deviation = fine / stiffness.torsion - 1
    deviation_extrapolated = richardson / stiffness.torsion - 1
    print(f"C3 b={width} c={core} tf={face} Ec/Ef={e_core / e_face:g}: FV(200)/series - 1 = "
          f"{deviation:.2e}, Richardson/series - 1 = {deviation_extrapolated:.2e}")  # fmt: skip
    assert abs(deviation) < 1e-2
    assert abs(deviation_extrapolated) < 1e-4
    # bonded layers are stiffer than the same layers twisting independently (Eq. 4.37)
    standard = standard_stiffness(materials(e_face, e_core), width, core, face)
    assert stiffness.torsion > standard.torsion


def test_coupled_torsion_converges_with_terms() -> None:
    mat = materials(60e9, 2e9)
    values = [coupled_stiffness(mat, 0.04, 0.002, 0.0005, terms=n).torsion for n in (1, 50, 5000)]
    assert values[0] == pytest.approx(values[2], rel=1e-12)
    assert values[1] == pytest.approx(values[2], rel=1e-12)


# ------------------------------------------------------------ homogeneous limit
@pytest.mark.parametrize(("width", "core", "face"), [(0.04, 0.002, 0.0005), (0.01, 0.01, 0.001),
                                                      (0.003, 0.004, 0.002)])  # fmt: skip
def test_homogeneous_limit(width: float, core: float, face: float) -> None:
    e, rho = 6e9, 1200.0
    g = shear(e)
    a = core + 2 * face
    mat = LayerMaterials(e, e, NU, rho, rho)
    std = standard_stiffness(mat, width, core, face)
    coup = coupled_stiffness(mat, width, core, face)
    for s in (std, coup):
        assert s.bending_1 == pytest.approx(e * width * a**3 / 12, rel=1e-12)
        assert s.bending_2 == pytest.approx(e * a * width**3 / 12, rel=1e-12)
        assert s.axial == pytest.approx(e * width * a, rel=1e-12)
        assert s.shear_1 == pytest.approx(5 / 6 * g * width * a, rel=1e-12)
        assert s.shear_2 == pytest.approx(5 / 6 * g * width * a, rel=1e-12)
        assert s.mass_per_length == pytest.approx(rho * width * a, rel=1e-12)
        assert s.rotary_1 == pytest.approx(rho * width * a**3 / 12, rel=1e-12)
        assert s.rotary_2 == pytest.approx(rho * a * width**3 / 12, rel=1e-12)
    assert coup.torsion == pytest.approx(g * rectangle_torsion_constant(width, a), rel=1e-12)
    k1 = rectangle_torsion_constant(width, a) / (max(width, a) * min(width, a) ** 3)
    assert 0.1405 < k1 < 1 / 3


# ------------------------------------------------------------ bending, mass, inertia
@pytest.mark.parametrize(("width", "core", "face", "e_core", "e_face", "rho_core", "rho_face"), [
    (0.04, 0.002, 0.0005, 2e9, 60e9, 300.0, 1600.0),
    (0.02, 0.010, 0.001, 30e9, 5e9, 2000.0, 900.0),
])  # fmt: skip
def test_bending_and_inertia_against_quadrature(width: float, core: float, face: float,
                                                e_core: float, e_face: float, rho_core: float,
                                                rho_face: float) -> None:  # fmt: skip
    mat = materials(e_face, e_core, rho_face, rho_core)
    std = standard_stiffness(mat, width, core, face)
    coup = coupled_stiffness(mat, width, core, face)
    ei1 = width * layer_integral(e_face, e_core, core, face, 2)  # ∫E x₂² dA
    ei2 = width**3 / 12 * layer_integral(e_face, e_core, core, face, 0)  # ∫E x₁² dA
    ea = width * layer_integral(e_face, e_core, core, face, 0)
    mass = width * layer_integral(rho_face, rho_core, core, face, 0)
    rot1 = width * layer_integral(rho_face, rho_core, core, face, 2)
    rot2 = width**3 / 12 * layer_integral(rho_face, rho_core, core, face, 0)
    for s in (std, coup):
        assert s.bending_1 == pytest.approx(ei1, rel=1e-10)
        assert s.bending_2 == pytest.approx(ei2, rel=1e-10)
        assert s.axial == pytest.approx(ea, rel=1e-10)
        assert s.mass_per_length == pytest.approx(mass, rel=1e-10)
        assert s.rotary_1 == pytest.approx(rot1, rel=1e-10)
        assert s.rotary_2 == pytest.approx(rot2, rel=1e-10)
    gs = width * layer_integral(shear(e_face), shear(e_core), core, face, 0)
    assert std.shear_1 == pytest.approx(5 / 6 * gs, rel=1e-10)
    assert std.shear_2 == pytest.approx(5 / 6 * gs, rel=1e-10)
    assert coup.shear_1 == pytest.approx(5 / 6 * gs, rel=1e-10)


def test_coupled_shear_2_equal_densities_and_by_hand() -> None:
    width, core, face, kappa = 0.04, 0.002, 0.0005, math.pi**2 / 12
    # equal densities: Eq. 4.40 collapses to κ ∫G dA
    mat = materials(60e9, 2e9, 1400.0, 1400.0)
    s = coupled_stiffness(mat, width, core, face, shear_factor=kappa)
    gs = width * (core * shear(2e9) + 2 * face * shear(60e9))
    assert s.shear_2 == pytest.approx(kappa * gs, rel=1e-12)
    # different densities: Eq. 4.40 evaluated by hand with math
    rf, rc = 1600.0, 400.0
    s = coupled_stiffness(materials(60e9, 2e9, rf, rc), width, core, face, shear_factor=kappa)
    a, d, x = core + 2 * face, core + face, math.pi * core / (2 * (core + 2 * face))
    f = math.cos(x) / x * math.log((1 + math.sin(x)) / math.cos(x))
    expected = (kappa * 12 * width / a**2 * (core * shear(2e9) + 2 * face * shear(60e9))
                / (core * rc + 2 * face * rf + core * (rf - rc) * f)
                * (rf * face * d**2 / 2 + rf * face**3 / 6 + rc * core**3 / 12))  # fmt: skip
    assert s.shear_2 == pytest.approx(expected, rel=1e-12)


# ------------------------------------------------------------ vectorisation
def test_arrays_per_element_match_scalars() -> None:
    mat = materials(60e9, 2e9, 1600.0, 400.0)
    widths = np.linspace(0.03, 0.05, 7)
    cores = np.linspace(0.001, 0.006, 7)
    for func in (standard_stiffness, coupled_stiffness):
        batch = func(mat, widths, cores, 0.0005)
        assert isinstance(batch.torsion, np.ndarray) and batch.torsion.shape == (7,)
        for i in range(7):
            one = func(mat, float(widths[i]), float(cores[i]), 0.0005)
            assert isinstance(one.torsion, float)
            for name in SectionStiffness.__dataclass_fields__:
                assert getattr(batch, name)[i] == pytest.approx(getattr(one, name), rel=1e-13)


# ------------------------------------------------------------ F(x), Eq. 4.42
def test_shape_function_F() -> None:
    assert shape_function_F(0.0) == 1.0
    assert shape_function_F(1e-8) == pytest.approx(1.0, abs=1e-14)
    assert shape_function_F(1e-3) == pytest.approx(1 - 1e-6 / 3, abs=1e-14)  # 1 − x²/3
    x = math.pi / 4  # cos x / x · ln((1 + sin x)/cos x) = (√2/2)(4/π) ln(1 + √2)
    expected = math.sqrt(2) / 2 * 4 / math.pi * math.log(1 + math.sqrt(2))
    assert shape_function_F(x) == pytest.approx(expected, rel=1e-14)
    x = 1.2
    direct = math.cos(x) / x * math.log((1 + math.sin(x)) / math.cos(x))
    assert shape_function_F(x) == pytest.approx(direct, rel=1e-13)
    values = shape_function_F(np.array([-0.5, 0.0, 0.5]))
    assert values[0] == values[2] and values[1] == 1.0
    assert np.all(np.diff(shape_function_F(np.linspace(0, 1.5, 50))) < 0)
    with pytest.raises(ParameterError, match="pi/2"):
        shape_function_F(math.pi / 2)


# ------------------------------------------------------------ bad input
MAT = dict(face_modulus=60e9, core_modulus=2e9, poisson=0.3, face_density=1600.0,
           core_density=400.0)  # fmt: skip


@pytest.mark.parametrize(("field", "value", "words"), [
    ("face_modulus", 0.0, "> 0"), ("core_modulus", -1e9, "> 0"), ("face_modulus", math.nan, "> 0"),
    ("face_density", 0.0, "> 0"), ("core_density", -5.0, "> 0"),
    ("poisson", 0.5, "(-1, 0.5)"), ("poisson", -1.0, "(-1, 0.5)"), ("poisson", 0.7, "(-1, 0.5)"),
])  # fmt: skip
def test_bad_materials(field: str, value: float, words: str) -> None:
    with pytest.raises(ParameterError) as info:
        LayerMaterials(**{**MAT, field: value})
    message = str(info.value)
    assert field in message and words in message and "\n" not in message


@pytest.mark.parametrize(("kwargs", "name", "words"), [
    (dict(width=0.0), "width", "> 0"),
    (dict(core_thickness=-0.001), "core_thickness", "> 0"),
    (dict(face_thickness=0.0), "face_thickness", "> 0"),
    (dict(width=np.array([0.04, -0.01])), "width", "> 0"),
    (dict(shear_factor=0.0), "shear_factor", "(0, 1]"),
    (dict(terms=0), "terms", ">= 1"),
])  # fmt: skip
def test_bad_geometry(kwargs: dict, name: str, words: str) -> None:
    args = dict(width=0.04, core_thickness=0.002, face_thickness=0.0005) | kwargs
    for func in (standard_stiffness, coupled_stiffness):
        with pytest.raises(ParameterError) as info:
            func(LayerMaterials(**MAT), **args)
        message = str(info.value)
        assert name in message and words in message and "\n" not in message
    with pytest.raises(ParameterError, match="height"):
        rectangle_torsion_constant(0.01, 0.0)
