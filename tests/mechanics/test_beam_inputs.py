"""The inputs of ``add_beam`` (mechanics/beam.py): the parameter names and the given stiffness.

Truth: the position of each name in the builder's parameter vector, the beam's translational
mass ρ A L (a straight two-element beam of known section), and the ParameterError contract
(one line that names the offending value).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.assembly import SystemBuilder, director_configuration
from fuzzygait.mechanics.beam import BeamParameterNames, BeamSection, GivenStiffness, add_beam
from fuzzygait.mechanics.cantilever import build_clamped_beam
from fuzzygait.mechanics.homogenisation import LayerMaterials, standard_stiffness
from fuzzygait.mechanics.leg import LegConfiguration

LENGTH, WIDTH, THICKNESS = 0.4, 0.05, 0.01  # m: two elements of 0.2 m
AREA = WIDTH * THICKNESS
SECTION = BeamSection(np.array(AREA), np.array(WIDTH * THICKNESS**3 / 12), np.array(THICKNESS * WIDTH**3 / 12),
                      np.array(1e-9))  # fmt: skip
DEFAULT_NAMES = BeamParameterNames()  # E, nu, rho, eta


def straight_beam(parameters: tuple[str, ...], names: BeamParameterNames = DEFAULT_NAMES,
                  lengths: np.ndarray | None = None, given: GivenStiffness | None = None) -> SystemBuilder:  # fmt: skip
    """Three nodes along +x (reference frame = inertial frame) with the section :data:`SECTION`."""
    bodies = ["n0", "n1", "n2"]
    builder = SystemBuilder(bodies, parameters, gravity=9.81)
    reference = np.array([director_configuration(np.array([x, 0.0, 0.0]), np.eye(3)[[1, 2, 0]])
                          for x in (0.0, LENGTH / 2, LENGTH)])  # fmt: skip
    element_length = np.full(2, LENGTH / 2) if lengths is None else lengths
    add_beam(builder, "beam", [builder.body(b) for b in bodies], reference, element_length, SECTION, names, given)
    return builder


def translational_mass(builder: SystemBuilder, p: np.ndarray) -> float:
    """Sum of the x-position rows and columns of the mass matrix: the beam's mass (kg)."""
    mass = ca.Function("mass", [builder.p, builder.c], [builder.mass])(p, builder.constant_values).full()
    x_rows = [builder.body(name).offset for name in ("n0", "n1", "n2")]
    return float(mass[np.ix_(x_rows, x_rows)].sum())


def one_line(error: pytest.ExceptionInfo) -> str:
    message = str(error.value)
    assert "\n" not in message
    return message


def test_default_names_find_the_parameters_in_any_order():
    builder = straight_beam(("eta", "rho", "nu", "E"))
    (group,) = builder.element_groups
    assert tuple(group.parameter_indices) == (3, 2, 0)  # the kernels' pe = (E, ν, η)
    p = np.array([1.0, 1500.0, 0.3, 2e9])
    assert translational_mass(builder, p) == pytest.approx(1500.0 * AREA * LENGTH, rel=1e-12)


def test_other_names_pick_their_parameters():
    names = BeamParameterNames(modulus="E_b", poisson="nu_b", density="rho_b", damping="eta_b")
    builder = straight_beam(("rho", "rho_b", "E_b", "eta_b", "nu_b", "E"), names)
    (group,) = builder.element_groups
    assert tuple(group.parameter_indices) == (2, 4, 3)
    p = np.array([1000.0, 2500.0, 2e9, 1.0, 0.3, 7e9])
    assert translational_mass(builder, p) == pytest.approx(2500.0 * AREA * LENGTH, rel=1e-12)  # rho_b, not rho


def test_a_name_missing_from_the_model_is_named():
    with pytest.raises(ParameterError) as error:
        straight_beam(("E", "nu", "rho", "eta"), BeamParameterNames(density="rho_blade"))
    message = one_line(error)
    assert "density" in message and "'rho_blade'" in message and "E, nu, rho, eta" in message


@pytest.mark.parametrize("lengths", [np.array([0.2, 0.0]), np.array([0.2, np.nan]), np.array([0.2, 0.1, 0.1])])
def test_impossible_element_lengths(lengths):
    with pytest.raises(ParameterError) as error:
        straight_beam(("E", "nu", "rho", "eta"), lengths=lengths)
    assert "element length" in one_line(error)


def blade_stiffness():
    mesh = LegConfiguration(hip_angle=0.0, knee_angle=0.0).blade.discretise(3)
    layers = LayerMaterials(60e9, 3e9, 0.3, 1700.0, 1700.0)
    return mesh, standard_stiffness(layers, mesh.width, mesh.core_thickness, mesh.face_thickness)


@pytest.mark.parametrize("modulus", [None, 0.0, -1e9, np.nan, np.inf])
def test_given_stiffness_needs_a_reference_modulus(modulus):
    mesh, stiffness = blade_stiffness()
    with pytest.raises(ParameterError) as error:
        GivenStiffness.optional(stiffness, modulus)
    assert "reference_modulus > 0 Pa" in one_line(error) and str(modulus) in str(error.value)
    if modulus is not None:
        with pytest.raises(ParameterError):
            GivenStiffness(stiffness, modulus)
    with pytest.raises(ParameterError):  # the same error through the clamped-beam model
        build_clamped_beam(mesh, (0.0, 0.0, -1.0), compile=False, stiffness=stiffness, reference_modulus=modulus)


def test_given_stiffness_constants_per_element():
    mesh, stiffness = blade_stiffness()
    assert GivenStiffness.optional(None, None) is None  # the homogeneous law
    given = GivenStiffness.optional(stiffness, 60e9)
    assert given is not None
    values = given.values(2)
    assert values.shape == (2, 7)
    assert np.array_equal(values[:, 2], np.broadcast_to(stiffness.axial, 2))
    assert np.array_equal(values[:, 3], np.broadcast_to(stiffness.bending_1, 2))
    assert np.all(values[:, 6] == 60e9)
    builder = straight_beam(("E", "nu", "rho", "eta"), given=given)
    (group,) = builder.element_groups
    assert group.kernel_name.endswith(":given") and group.constants.shape == (2, 19)
    assert np.array_equal(group.constants[:, 12:], values)
