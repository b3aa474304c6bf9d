"""The marker-error model with each marker's deviation in spherical coordinates (thesis
§3.7.2): the α-level sets become boxes, no norm constraint.  The Cartesian model
(:mod:`.angle_model`) evaluates; autograd differentiates through the coordinate change and
the kinematic chain (traced positions take the chain, not the compiled kernel)."""

from __future__ import annotations

from dataclasses import dataclass

import autograd.numpy as anp
import numpy as np

from fuzzygait.core.arrays import floats
from fuzzygait.markererror.angle_model import AngleComponentsModel, JointAngleModel, row_gradients
from fuzzygait.uncertainty.protocol import BLOCKS, Evaluation, Output, declared_blocks


def spherical_to_cartesian(P: np.ndarray) -> np.ndarray:
    """Deviations given per marker as (r, θ, φ) — radius mm, polar and azimuthal angles
    in rad — to Cartesian (x, y, z) mm; any leading shape, last axis 3 per marker."""
    P = floats(P)
    q = P.reshape(*P.shape[:-1], -1, 3)
    r, theta, phi = q[..., 0], q[..., 1], q[..., 2]
    xyz = anp.stack([r * anp.sin(theta) * anp.cos(phi), r * anp.sin(theta) * anp.sin(phi), r * anp.cos(theta)],
                    axis=-1)  # fmt: skip
    return xyz.reshape(P.shape)


@dataclass
class SphericalDeviationModel:
    """The same model with each marker's deviation in spherical coordinates (thesis
    §3.7.2: the α-level sets become boxes, no norm constraint)."""

    cartesian: JointAngleModel | AngleComponentsModel

    @property
    def capabilities(self) -> frozenset[str]:
        """The Cartesian model's (nodes and their gradients, its time step) and its blocks
        (1 for a single component)."""
        return frozenset(self.cartesian.capabilities) | {BLOCKS}

    @property
    def times(self) -> np.ndarray:
        return self.cartesian.times

    @property
    def excursion_limit(self) -> float:
        """The Cartesian model's (degrees)."""
        return self.cartesian.excursion_limit

    @property
    def time_step(self) -> float:
        return self.cartesian.time_step

    @property
    def blocks(self) -> int:
        """Independent outputs (the components of :class:`AngleComponentsModel`)."""
        return declared_blocks(self.cartesian)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """``<marker>_r`` (mm), ``<marker>_theta``, ``<marker>_phi`` (rad) per marker."""
        return tuple(f"{m}_{c}" for m in self.cartesian.markers for c in ("r", "theta", "phi"))

    @property
    def output(self) -> Output:
        return self.cartesian.output

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        return self.cartesian.evaluate_nodes(spherical_to_cartesian(P), nodes)

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values and exact gradients with respect to (r mm, θ, φ rad) per marker."""
        return row_gradients(self.evaluate_nodes, P, nodes)

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        return self.cartesian.evaluate(spherical_to_cartesian(p))
