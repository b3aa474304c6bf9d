"""Effective stiffnesses of a three-layer (face/core/face) rectangular beam section.

Thesis §4.3 (Eqs. 4.35–4.42, after [Blo23], [Bîr13], [Mus53]). The prosthesis section is
a rectangle of width ``b`` (axis 1, lateral) and height ``a = c + 2 t_f`` (axis 2,
thickness): a core of thickness ``c`` (E_c, G_c, ρ_c) between two equal faces of
thickness ``t_f`` (E_f, G_f, ρ_f); ``d = c + t_f`` is the distance between the face
mid-planes. Axis 3 is the beam axis. All layers share one Poisson ratio, so
``G = E / (2 (1 + ν))`` in each.

Two homogenisations replace the separable matrices ``diag(Gκ₁A, Gκ₂A, EA)`` and
``diag(EI₁, EI₂, GJ)`` of Eq. 4.35 by ``diag(A₁, A₂, A₃)`` and ``diag(C₁, C₂, C₃)``:

* :data:`standard_stiffness` (Eq. 4.37) sums the layers as independent beams:
  ``C₁ = 2 E_f I_f1 + E_c I_c1`` with the parallel-axis theorem for the faces,
  ``C₂ = 2 E_f I_f2 + E_c I_c2``, ``C₃ = 2 G_f J_f + G_c J_c`` (each layer's own
  Saint-Venant constant, so the layers twist without shear coupling),
  ``A_i = κ (2 G_f A_f + G_c A_c)`` and ``A₃ = 2 E_f A_f + E_c A_c`` (the printed
  "G_f Λ_f" in Eq. 4.37 is a typo for the axial stiffness).
* :data:`coupled_stiffness` (Eqs. 4.38–4.40) replaces C₁, C₃ and A₂ by the [Bîr13]
  expressions; the other entries are the standard ones. Eq. 4.38 for C₁ *is* the
  exact composite bending stiffness ``∫ E x₂² dA``, so it equals the standard C₁.

Torsion of the bonded layers (Eq. 4.39) — derivation of C₍ₙ₎
-------------------------------------------------------------
Eq. 4.41 is garbled in the thesis text, so C₍ₙ₎ is re-derived here (Muskhelishvili's
torsion of composite bars). With twist rate α, the common warping function gives the
stresses ``τ₁₃ = α ∂Ψ/∂x₂``, ``τ₂₃ = −α ∂Ψ/∂x₁`` from a stress function Ψ with

    ∇·((1/G) ∇Ψ) = −2 in the section,  Ψ = 0 on its boundary,

Ψ and (1/G) ∂Ψ/∂x₂ continuous across the bonded interfaces x₂ = ±c/2 (traction and
displacement continuity), and torsional rigidity ``C₃ = 2 ∫ Ψ dA``. Expand along the
width: ``Ψ = Σₙ qₙ gₙ(x₂) cos(mₙ x₁)``, ``mₙ = (2n+1)π/b``,
``qₙ = 4(−1)ⁿ/((2n+1)π)`` (the cosine series of 1 on |x₁| < b/2). In each layer
``gₙ'' − m² gₙ = −2G``, so with s = a/2 − x₂ and the symmetry in x₂

    core:  g = 2G_c/m² + P cosh(m x₂),
    face:  g = (2G_f/m²)(1 − cosh(m s)) + Q sinh(m s)       (g = 0 at s = 0).

The two interface conditions fix P and Q. Integrating over the section,
``∫ cos(mₙx₁) dx₁ = 2(−1)ⁿ/mₙ`` and ``Σ (2n+1)⁻⁴ = π⁴/96`` give the particular parts
``(b³/3)(c G_c + 2 t_f G_f)`` and the homogeneous parts ``−(64 b⁴/π⁵) Σ C₍ₙ₎/(2n+1)⁵``,
i.e. Eq. 4.39, with ``C₍ₙ₎ = −(mₙ³/4) ∫ (gₙ − 2G/mₙ²) dx₂``. Worked out (sympy):

    C₍ₙ₎ = { G_c [G_c cosh(m t_f) T + G_f sinh(m t_f)]
             + 2 G_f (G_c − G_f)(1 − cosh(m t_f)) T }
           / [ G_c cosh(m t_f) + G_f sinh(m t_f) T ],      T = tanh(m c/2), m = mₙ.

That is the bracket printed in Eq. 4.41 over the denominator printed beside it (the
trailing extra term in the thesis text is a duplication). For G_c = G_f = G it reduces
to ``G tanh(m a/2)``, the classical Saint-Venant series of a homogeneous rectangle;
``C₍ₙ₎ → C_∞ = G_f + (G_c − G_f)²/(G_c + G_f)`` as n → ∞.

Numerically, the identity ``(b³/3) S = (64 b⁴/π⁵) Σ S (mₙ/2)/(2n+1)⁵`` (S = c G_c +
2 t_f G_f) turns Eq. 4.39 into a sum of non-negative terms without the cancellation
between the two parts (which is severe for a wide, thin section, b ≫ a)::

    C₃ = (64 b⁴/π⁵) Σₙ [S mₙ/2 − C₍ₙ₎] / (2n+1)⁵.

Terms are summed explicitly until mₙ·min(t_f, c/2) ≥ 14 (at least ``terms`` of them, at
most 20 000), and the rest with C₍ₙ₎ replaced by its limit C_∞ — the difference is then
below e⁻²⁸ — in closed form through the Hurwitz zeta function. The series is evaluated in
overflow-free form (everything divided by cosh(m t_f)).

Transverse shear (Eq. 4.40)
---------------------------
A₂ of [Bîr13] is implemented as printed (with the evident typo p_c = ρ_c)::

    A₂ = κ (12 b/a²) (c G_c + 2 t_f G_f) / (c ρ_c + 2 t_f ρ_f + c (ρ_f − ρ_c) F(πc/(2a)))
         · (ρ_f t_f d²/2 + ρ_f t_f³/6 + ρ_c c³/12),

with F of Eq. 4.42 (:func:`shape_function_F`). For equal densities it equals the
standard ``κ b (c G_c + 2 t_f G_f)``; it could not be checked against [Bîr13] itself.

Inputs ``width``, ``core_thickness`` and ``face_thickness`` may be numpy arrays (one
value per beam element, broadcast against each other); the fields of the returned
:class:`SectionStiffness` are then arrays of the broadcast shape.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import zeta

from fuzzygait.core.errors import ParameterError

__all__ = [
    "Homogenisation",
    "LayerMaterials",
    "SectionStiffness",
    "coupled_stiffness",
    "rectangle_torsion_constant",
    "shape_function_F",
    "standard_stiffness",
]

Value = float | np.ndarray

_DECAY = 14.0  # mₙ·(thinnest layer) at which the remainder uses C₍ₙ₎ → C_∞
_MAX_TERMS = 20_000  # cap on explicitly summed torsion-series terms


# --------------------------------------------------------------------- validation
def _positive(name: str, value: ArrayLike, unit: str) -> np.ndarray:
    """``value`` as a float array, or ParameterError unless finite and > 0."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number > 0 {unit}; got {value!r}") from None
    if arr.size == 0 or not np.all(np.isfinite(arr)) or not np.all(arr > 0):
        bad = arr[~(np.isfinite(arr) & (arr > 0))] if arr.size else arr
        shown = bad.ravel()[0] if bad.size else "an empty array"
        raise ParameterError(f"{name} must be finite and > 0 {unit}; got {shown}")
    return arr


def _out(arr: np.ndarray) -> Value:
    """0-d arrays back to float, other arrays unchanged."""
    return float(arr) if arr.ndim == 0 else arr


# --------------------------------------------------------------------- data types
@dataclass(frozen=True)
class LayerMaterials:
    """Face and core materials of the three-layer section.

    Attributes:
        face_modulus: Young's modulus E_f of each face in Pa.
        core_modulus: Young's modulus E_c of the core in Pa.
        poisson: Poisson ratio ν common to all layers, in (−1, 0.5).
        face_density: density ρ_f of the faces in kg/m³.
        core_density: density ρ_c of the core in kg/m³.
    """

    face_modulus: float
    core_modulus: float
    poisson: float
    face_density: float
    core_density: float

    def __post_init__(self) -> None:
        for name in ("face_modulus", "core_modulus"):
            _positive(name, getattr(self, name), "Pa")
        for name in ("face_density", "core_density"):
            _positive(name, getattr(self, name), "kg/m^3")
        nu = self.poisson
        if not isinstance(nu, int | float) or not math.isfinite(nu) or not -1.0 < nu < 0.5:
            raise ParameterError(f"poisson must be in the open interval (-1, 0.5); got {nu!r}")

    @property
    def face_shear_modulus(self) -> float:
        """G_f = E_f / (2 (1 + ν)) in Pa."""
        return self.face_modulus / (2.0 * (1.0 + self.poisson))

    @property
    def core_shear_modulus(self) -> float:
        """G_c = E_c / (2 (1 + ν)) in Pa."""
        return self.core_modulus / (2.0 * (1.0 + self.poisson))


@dataclass(frozen=True)
class SectionStiffness:
    """Effective section properties (Eq. 4.36) plus the inertia per unit length.

    Fields are floats, or arrays when the geometry was given per element.

    Attributes:
        shear_1: shear stiffness A₁ (shear along axis 1, the width) in N.
        shear_2: shear stiffness A₂ (shear along axis 2, the thickness) in N.
        axial: axial stiffness A₃ in N.
        bending_1: bending stiffness C₁ about axis 1 (∫E x₂² dA) in N m².
        bending_2: bending stiffness C₂ about axis 2 (∫E x₁² dA) in N m².
        torsion: torsional rigidity C₃ in N m².
        mass_per_length: ∫ρ dA in kg/m.
        rotary_1: rotary inertia per length about axis 1, ∫ρ x₂² dA, in kg m.
        rotary_2: rotary inertia per length about axis 2, ∫ρ x₁² dA, in kg m.
    """

    shear_1: Value
    shear_2: Value
    axial: Value
    bending_1: Value
    bending_2: Value
    torsion: Value
    mass_per_length: Value
    rotary_1: Value
    rotary_2: Value


# --------------------------------------------------------------------- series
def _check_terms(terms: int) -> int:
    if isinstance(terms, bool) or not isinstance(terms, int | np.integer) or terms < 1:
        raise ParameterError(f"terms must be an integer >= 1; got {terms!r}")
    return int(terms)


def _odd_power_tail(power: float, terms: int) -> float:
    """Σ_{n ≥ terms} (2n+1)^(−power), via the Hurwitz zeta function."""
    return float(2.0**-power * zeta(power, terms + 0.5))


def _sech(x: np.ndarray) -> np.ndarray:
    """1/cosh(x) for x ≥ 0 without overflow."""
    e = np.exp(-x)
    return 2.0 * e / (1.0 + e * e)


def _composite_torsion(
    width: np.ndarray, core: np.ndarray, face: np.ndarray, g_core: float, g_face: float, terms: int
) -> np.ndarray:
    """Eq. 4.39 with the derived C₍ₙ₎, summed in the cancellation-free form (N m²)."""
    b, c, t = np.broadcast_arrays(width, core, face)
    # Sum explicitly until exp(−2 mₙ·(thinnest layer)) < 1e-12, so that the closed-form
    # remainder (C₍ₙ₎ → C_∞) is exact to rounding; at least ``terms`` terms.
    thinnest = np.where(t > 0, np.minimum(t, c / 2.0), c / 2.0)
    needed = np.max(np.ceil((_DECAY * b / (np.pi * thinnest) - 1.0) / 2.0))
    terms = int(min(max(terms, needed), _MAX_TERMS))
    b, c, t = b[..., None], c[..., None], t[..., None]
    odd = 2.0 * np.arange(terms, dtype=float) + 1.0
    m = odd * np.pi / b
    tanh_core = np.tanh(m * c / 2.0)
    tanh_face = np.tanh(m * t)
    sech_face = _sech(m * t)
    # C₍ₙ₎ with numerator and denominator divided by cosh(m t_f)
    numerator = g_core * (g_core * tanh_core + g_face * tanh_face) + 2.0 * g_face * (
        g_core - g_face
    ) * (sech_face - 1.0) * tanh_core
    c_n = numerator / (g_core + g_face * tanh_face * tanh_core)
    s = c * g_core + 2.0 * t * g_face
    head = np.sum((s * m / 2.0 - c_n) / odd**5, axis=-1)
    c_inf = g_face + (g_core - g_face) ** 2 / (g_core + g_face)
    b, s = b[..., 0], s[..., 0]
    tail = s * np.pi / (2.0 * b) * _odd_power_tail(4.0, terms) - c_inf * _odd_power_tail(5.0, terms)
    return 64.0 * b**4 / np.pi**5 * (head + tail)


def rectangle_torsion_constant(width: ArrayLike, height: ArrayLike, terms: int = 50) -> Value:
    """Saint-Venant torsion constant J (m⁴) of a homogeneous ``width × height`` rectangle.

    With s = the shorter and l = the longer side,
    ``J = (64 s⁴/π⁵) Σₙ [xₙ − tanh xₙ]/(2n+1)⁵``, ``xₙ = (2n+1)π l/(2s)``, which is the
    classical ``(l s³/3)[1 − (192 s/(π⁵ l)) Σ tanh(xₙ)/(2n+1)⁵]`` without its
    cancellation; the terms are summed until tanh xₙ = 1 to rounding (at least ``terms``)
    and the rest in closed form.

    Args:
        width, height: side lengths in m (> 0; arrays broadcast).
        terms: minimum number of explicitly summed series terms.
    """
    w = _positive("width", width, "m")
    h = _positive("height", height, "m")
    terms = _check_terms(terms)
    short, long_ = np.minimum(w, h), np.maximum(w, h)
    return _out(_composite_torsion(short, long_, np.zeros_like(short), 1.0, 1.0, terms))


def shape_function_F(x: ArrayLike) -> Value:
    """F of Eq. 4.42: ``F(x) = cos(x)/x · ln((1 + sin x)/cos x)``, F(0) = 1 (dimensionless).

    Defined (even, continuous) for |x| < π/2; evaluated as ``cos(x) artanh(sin x)/x``,
    which equals the printed form there and is accurate near 0 (F = 1 − x²/3 + O(x⁶)).
    Eq. 4.40 uses x = πc/(2a) ∈ (0, π/2).
    """
    arr = np.asarray(x, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(np.abs(arr) >= np.pi / 2):
        raise ParameterError(f"shape_function_F needs |x| < pi/2; got {x!r}")
    safe = np.where(arr == 0.0, 1.0, arr)
    value = np.where(arr == 0.0, 1.0, np.cos(safe) * np.arctanh(np.sin(safe)) / safe)
    return _out(value)


# --------------------------------------------------------------------- sections
def _geometry(
    materials: LayerMaterials,
    width: ArrayLike,
    core_thickness: ArrayLike,
    face_thickness: ArrayLike,
    shear_factor: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if not isinstance(materials, LayerMaterials):
        raise ParameterError(f"materials must be a LayerMaterials; got {type(materials).__name__}")
    b = _positive("width", width, "m")
    c = _positive("core_thickness", core_thickness, "m")
    t = _positive("face_thickness", face_thickness, "m")
    k = shear_factor
    if not isinstance(k, int | float) or not math.isfinite(k) or not 0.0 < k <= 1.0:
        raise ParameterError(f"shear_factor must be in (0, 1]; got {k!r}")
    try:
        b, c, t = np.broadcast_arrays(b, c, t)
    except ValueError:
        raise ParameterError(
            f"width, core_thickness and face_thickness must broadcast together; got shapes "
            f"{np.shape(b)}, {np.shape(c)}, {np.shape(t)}"
        ) from None
    return b, c, t


def _standard(
    mat: LayerMaterials, b: np.ndarray, c: np.ndarray, t: np.ndarray, kappa: float, terms: int
) -> SectionStiffness:
    ef, ec = mat.face_modulus, mat.core_modulus
    gf, gc = mat.face_shear_modulus, mat.core_shear_modulus
    rf, rc = mat.face_density, mat.core_density
    d = c + t
    area_f, area_c = b * t, b * c
    i1_f = b * t**3 / 12.0 + area_f * (d / 2.0) ** 2  # one face, parallel-axis theorem
    i1_c = b * c**3 / 12.0
    i2_f, i2_c = t * b**3 / 12.0, c * b**3 / 12.0
    j_f = _composite_torsion(np.minimum(b, t), np.maximum(b, t), 0.0 * t, 1.0, 1.0, terms)
    j_c = _composite_torsion(np.minimum(b, c), np.maximum(b, c), 0.0 * c, 1.0, 1.0, terms)
    shear = kappa * (2.0 * gf * area_f + gc * area_c)
    return SectionStiffness(
        shear_1=_out(shear),
        shear_2=_out(shear.copy()),
        axial=_out(2.0 * ef * area_f + ec * area_c),
        bending_1=_out(2.0 * ef * i1_f + ec * i1_c),
        bending_2=_out(2.0 * ef * i2_f + ec * i2_c),
        torsion=_out(2.0 * gf * j_f + gc * j_c),
        mass_per_length=_out(2.0 * rf * area_f + rc * area_c),
        rotary_1=_out(2.0 * rf * i1_f + rc * i1_c),
        rotary_2=_out(2.0 * rf * i2_f + rc * i2_c),
    )


def _coupled(
    mat: LayerMaterials, b: np.ndarray, c: np.ndarray, t: np.ndarray, kappa: float, terms: int
) -> SectionStiffness:
    std = _standard(mat, b, c, t, kappa, terms)
    ef, ec = mat.face_modulus, mat.core_modulus
    gf, gc = mat.face_shear_modulus, mat.core_shear_modulus
    rf, rc = mat.face_density, mat.core_density
    a, d = c + 2.0 * t, c + t
    bending_1 = ef * b * t * d**2 / 2.0 + ef * b * t**3 / 6.0 + ec * b * c**3 / 12.0
    torsion = _composite_torsion(b, c, t, gc, gf, terms)
    s = c * gc + 2.0 * t * gf
    f = shape_function_F(np.pi * c / (2.0 * a))
    effective_density = c * rc + 2.0 * t * rf + c * (rf - rc) * f
    rotary = rf * t * d**2 / 2.0 + rf * t**3 / 6.0 + rc * c**3 / 12.0
    shear_2 = kappa * 12.0 * b / a**2 * s / effective_density * rotary
    return SectionStiffness(
        shear_1=std.shear_1,
        shear_2=_out(shear_2),
        axial=std.axial,
        bending_1=_out(bending_1),
        bending_2=std.bending_2,
        torsion=_out(torsion),
        mass_per_length=std.mass_per_length,
        rotary_1=std.rotary_1,
        rotary_2=std.rotary_2,
    )


#: ``(materials, b, c, t_f, κ, terms) -> SectionStiffness`` on validated, broadcast geometry
_Kernel = Callable[[LayerMaterials, np.ndarray, np.ndarray, np.ndarray, float, int], SectionStiffness]


@dataclass(frozen=True)
class Homogenisation:
    """One homogenisation of the three-layer section, called with the materials and the
    geometry (see :meth:`__call__`); :data:`standard_stiffness` and :data:`coupled_stiffness`
    are the two of the module docstring.

    Attributes:
        name: ``"standard"`` or ``"coupled"``.
    """

    name: str
    _kernel: _Kernel = field(repr=False)

    def __call__(
        self,
        materials: LayerMaterials,
        width: ArrayLike,
        core_thickness: ArrayLike,
        face_thickness: ArrayLike,
        shear_factor: float = 5.0 / 6.0,
        terms: int = 50,
    ) -> SectionStiffness:
        """The section stiffnesses of this homogenisation.

        Args:
            materials: face and core materials.
            width: section width b in m (scalar or one value per element).
            core_thickness: core thickness c in m (scalar or array).
            face_thickness: thickness t_f of each face in m (scalar or array).
            shear_factor: shear correction factor κ (same for both shear directions).
            terms: minimum number of explicitly summed terms of the torsion series; more
                are used automatically for layers thin compared with the width, and the
                remainder is added in closed form (see the module docstring).
        """
        b, c, t = _geometry(materials, width, core_thickness, face_thickness, shear_factor)
        return self._kernel(materials, b, c, t, shear_factor, _check_terms(terms))


#: Standard homogenisation, Eq. 4.37: the layers summed as independent beams.
#: C₃ = 2 G_f J(b, t_f) + G_c J(b, c) neglects the shear coupling of the bonded layers
#: and so underestimates the torsional rigidity.
standard_stiffness = Homogenisation("standard", _standard)

#: Coupled homogenisation, Eqs. 4.38–4.40 ([Bîr13], [Mus53]): C₁ (Eq. 4.38, the exact
#: composite bending stiffness), C₃ (Eq. 4.39 with the derived C₍ₙ₎, see the module
#: docstring) and A₂ (Eq. 4.40); A₁, A₃, C₂ and the inertia terms as in
#: :data:`standard_stiffness`.
coupled_stiffness = Homogenisation("coupled", _coupled)
