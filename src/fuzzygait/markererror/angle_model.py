"""One Plug-in Gait joint-angle component as a model of marker deviations, for the
uncertainty engine (thesis §3.7.3).

The parameters are the deviations ``p = [p_1, …, p_m]`` (mm, lab frame, 3 per marker) of
the markers the angle depends on; the output at frame ``j`` is the angle component
(degrees) computed from ``r_i(t_j) + p_i`` (Eq. 3.1). The same deviation applies at every
frame of a trajectory (so one evaluation is a whole angle curve), and
:meth:`JointAngleModel.evaluate_nodes` evaluates any number of (deviation, frame) pairs
in one vectorised pass of the model.

Subject measures stay fixed: the inter-ASIS distance and the progression frame are
those of the unperturbed trial (the thesis does not propagate the anthropometric
measures, §3.6).

Continuous branch: with ``reference`` (the measured angle component at each frame) the
model returns ``reference + wrap(angle - reference)`` with ``wrap`` into (-180°, 180°]:
the angle on the branch through the measured one, never the ±180° representation, so a
band that passes 180° stays one band.  Where a deviation inside the ball turns the
segment frame so far that this excursion approaches ±180° (the frame can flip) the
hull is not a band any more; :func:`undetermined` marks it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from fuzzygait.core.trial import Trial
from fuzzygait.io.subject import SubjectParameters
from fuzzygait.kinematics.angles import wrap_degrees
from fuzzygait.kinematics.chain import LowerBodyChain
from fuzzygait.kinematics.model import angle_from_chain, angle_markers
from fuzzygait.kinematics.pelvis import inter_asis_distance
from fuzzygait.uncertainty.protocol import NODES, Evaluation, Output

AXES = ("X", "Y", "Z")


def fixed_subject(trial: Trial, subject: SubjectParameters) -> SubjectParameters:
    """``subject`` with the inter-ASIS distance fixed (measured on ``trial`` if unset)."""
    if subject.inter_asis_distance is not None:
        return subject
    return replace(subject, inter_asis_distance=inter_asis_distance(trial.marker("LASI"), trial.marker("RASI")))


@dataclass
class JointAngleModel:
    """Angle component ``name_axis`` as a function of the deviations of ``markers``.

    Attributes:
        trial: the (pre-processed) trial; only frames ``frames`` are used.
        subject: subject parameters with a fixed inter-ASIS distance.
        progression: ``(3, 3)`` progression frame of the unperturbed trial.
        name: Plug-in Gait angle, e.g. ``"LKneeAngles"``.
        axis: 0, 1, 2 for X (sagittal), Y (frontal), Z (transverse).
        frames: sample indices (0-based) of the trial used as time nodes.
        markers: labels whose deviations are the parameters (default: all the angle
            depends on).
        reference: the measured angle component (degrees) at each of ``frames``; given,
            the outputs are on its continuous branch (module docstring).
    """

    trial: Trial
    subject: SubjectParameters
    progression: np.ndarray
    name: str
    axis: int
    frames: np.ndarray
    markers: list[str] = field(default_factory=list)
    use_medial_markers: bool = False
    reference: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not self.markers:
            self.markers = angle_markers(self.trial, self.name, self.use_medial_markers)
        self.frames = np.asarray(self.frames, dtype=int)
        self._base = np.stack([self.trial.marker(m)[self.frames] for m in self.markers], axis=1)
        self.times = self.trial.times[self.frames]

    @property
    def n_parameters(self) -> int:
        return 3 * len(self.markers)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """``<marker>_x``, ``<marker>_y``, ``<marker>_z`` (mm, lab frame) per marker."""
        return tuple(f"{m}_{c}" for m in self.markers for c in "xyz")

    @property
    def output(self) -> Output:
        return Output(f"{self.name}_{AXES[self.axis]}", "deg")

    capabilities = frozenset({NODES})

    def angles_of(self, positions: np.ndarray) -> np.ndarray:
        """All three components (degrees) for marker positions ``(k, n_markers, 3)``."""
        rows = Trial(markers=positions, marker_labels=list(self.markers), rate=self.trial.rate)
        chain = LowerBodyChain(rows, self.subject, use_medial_markers=self.use_medial_markers)
        return angle_from_chain(chain, self.name, self.progression)

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """Angle component at time nodes ``nodes`` (k,) for deviations ``P`` (k, n_p)."""
        positions = self._base[nodes] + np.asarray(P, dtype=float).reshape(len(nodes), -1, 3)
        angle = self.angles_of(positions)[:, self.axis]
        if self.reference is None:
            return angle
        reference = np.asarray(self.reference, dtype=float)[nodes]
        return reference + wrap_degrees(angle - reference)

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        """The angle component over all time nodes with one deviation ``p`` (n_p,); no
        sensitivities (the engine's direct strategies use finite differences)."""
        nodes = np.arange(self.frames.size)
        return Evaluation(self.evaluate_nodes(np.tile(np.asarray(p, dtype=float), (nodes.size, 1)), nodes))


#: Excursion (degrees) of a hull bound from the measured angle beyond which the band is
#: *undetermined*: the segment frame turns more than a quarter turn inside the ball, which
#: for a frame built from two markers and a joint centre means it can flip (the angle
#: then jumps by about 180°; a bound found on the far side of the jump is not an extreme
#: of a continuous band).
UNDETERMINED_DEG = 90.0


def undetermined(lower: np.ndarray, upper: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """Where a band ``[lower, upper]`` around ``measured`` (degrees, broadcasting) is
    undetermined: a bound more than :data:`UNDETERMINED_DEG` from the measured angle."""
    with np.errstate(invalid="ignore"):
        return (np.asarray(upper) - measured > UNDETERMINED_DEG) | (measured - np.asarray(lower) > UNDETERMINED_DEG)


def spherical_to_cartesian(P: np.ndarray) -> np.ndarray:
    """Deviations given per marker as (r, θ, φ) — radius mm, polar and azimuthal angles
    in rad — to Cartesian (x, y, z) mm; any leading shape, last axis 3 per marker."""
    q = np.asarray(P, dtype=float).reshape(*np.shape(P)[:-1], -1, 3)
    r, theta, phi = q[..., 0], q[..., 1], q[..., 2]
    xyz = np.stack([r * np.sin(theta) * np.cos(phi), r * np.sin(theta) * np.sin(phi), r * np.cos(theta)], axis=-1)
    return xyz.reshape(np.shape(P))


@dataclass
class SphericalDeviationModel:
    """The same model with each marker's deviation in spherical coordinates (thesis
    §3.7.2: the α-level sets become boxes, no norm constraint)."""

    cartesian: JointAngleModel

    capabilities = frozenset({NODES})

    @property
    def times(self) -> np.ndarray:
        return self.cartesian.times

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """``<marker>_r`` (mm), ``<marker>_theta``, ``<marker>_phi`` (rad) per marker."""
        return tuple(f"{m}_{c}" for m in self.cartesian.markers for c in ("r", "theta", "phi"))

    @property
    def output(self) -> Output:
        return self.cartesian.output

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        return self.cartesian.evaluate_nodes(spherical_to_cartesian(P), nodes)

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        return self.cartesian.evaluate(spherical_to_cartesian(p))
