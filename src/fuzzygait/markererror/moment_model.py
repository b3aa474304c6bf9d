"""Plug-in Gait joint moments and powers of one leg as a model of marker deviations and
centre-of-pressure errors, for the uncertainty engine (issue 39 item 5; the kinetic
counterpart of :class:`~fuzzygait.markererror.angle_model.JointAngleModel`).

Parameters (mm, one ball each, the same deviation at every frame of the trajectory):

* the deviation ``p_i`` (laboratory x, y, z) of every dynamic marker the leg's kinetics
  are computed from — the pelvis and the leg's THI, KNE, TIB, ANK, TOE
  (:func:`~fuzzygait.kinematics.chain.segment_markers` of the foot: the ankle's joint
  centre needs the knee's, the knee's the hip's, and the hip power the pelvis' rotation);
* per loaded plate under the foot, the centre-of-pressure deviation ``d`` in the plate's
  plane: coordinates along the plate's x and y axes and along its normal, the normal one
  without effect — the projections of a 3-D ball of radius ``r`` onto the plane are the
  disc of radius ``r``, so a 3-D ball parameter is the plate-plane disc of the brief.
  The ground's moment about the laboratory origin at frame ``i`` becomes
  ``M_i + d x F_i`` (``F_i`` that plate's share of the foot's load): the force acts at
  ``COP + d``, its magnitude, direction and the free moment unchanged.

Default centre-of-pressure error: :data:`DEFAULT_COP_ERROR_MM` = 10 mm.  Schmiedmayer &
Kastner (2000, J Biomech Eng 122:523-527) report errors of up to ±30 mm for
piezoelectric plates before correction and 5.8 ± 3.7 mm (mean ± SD) left after the
usual single-point-load correction; Middleton et al. (1999, Clin Biomech 14:357-360)
find the single-point errors of a Kistler plate of the same order.  10 mm is that
corrected error's mean plus one standard deviation, as the α = 0 support of a triangular
fuzzy radius (Table 3.1's radii are such maximum deviations).

Fixed (thesis §3.6, as for the angles): the subject parameters with the inter-ASIS
distance of the unperturbed trial, the static offsets, the foot length (mean HEE-TOE
distance minus the marker radius of the unperturbed trial: HEE is no parameter), the
body mass and the segment table, and the force itself.

An evaluation at frame ``j`` runs the chain on the nine frames ``j - 4 … j + 4`` (the
five-point second derivative of the centres of mass and the two-frame differences of the
rotations take them, :mod:`fuzzygait.kinetics.inverse_dynamics`), all shifted by the
row's deviation, and Newton–Euler from the foot up at ``j`` only: at zero deviation the
outputs equal :func:`~fuzzygait.kinetics.plug_in_gait.plug_in_gait_kinetics`'s with
``com_derivative=ComDerivative.FIVE_POINT``.  The measured curve thus uses five-point
differences (local, by design), while the report's kinetics default to Nexus' GCV
smoothing spline through the whole trajectory: on filtered markers they differ by at
most 0.0017 N·m/kg and 0.0010 W/kg (``Movement_trial.c3d``, RMS ≤ 1e-4) and 0.0004
N·m/kg and 0.0010 W/kg on the sample trial; on unfiltered markers by about 0.04 N·m/kg RMS
(``PiGKad_Motion.c3d``, ``docs/kinetics.md``).  Outputs
in N·m/kg (moments: Nexus' X, Y, Z in the distal segment's frame with
:data:`~fuzzygait.kinetics.plug_in_gait.MOMENT_AXES`' signs) or W/kg (powers, Nexus' Z).
Gradients are exact: the model's row — chain and dynamics — compiled to C with CasADi's
reverse-mode gradient (:meth:`LegKineticsModel.kernel`, :mod:`.row_kernel`), else autograd
through the same code on numpy (:func:`~fuzzygait.markererror.angle_model.row_gradients`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import autograd.numpy as anp
import numpy as np
from autograd.tracer import isbox
from numpy.typing import NDArray

from fuzzygait.core.arrays import floats
from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.chain import segment_markers
from fuzzygait.kinematics.model import model_chain
from fuzzygait.kinematics.versions import model_version
from fuzzygait.kinetics.ground import plate_load
from fuzzygait.kinetics.plug_in_gait import JOINTS, MOMENT_AXES, foot_length
from fuzzygait.kinetics.segments import MM
from fuzzygait.markererror.angle_model import AXES, fixed_subject, row_gradients
from fuzzygait.markererror.leg_dynamics import (
    HALF_WINDOW,
    Constants,
    Loads,
    angular_velocities,
    apply_rows,
    leg_segments,
    newton_euler,
    turn_cosines,
)
from fuzzygait.markererror.row_kernel import (
    UNSETTLED,
    CompiledModel,
    RowKernel,
    Shape,
    compile_kernel,
    distinct_rows,
    model_key,
)
from fuzzygait.markererror.undetermined import EXCURSION_LIMIT_DEG
from fuzzygait.uncertainty.protocol import BLOCKS, NODE_GRADIENTS, NODE_LIMITS, NODES, TIME_STEP, Evaluation, Output

Array = NDArray[np.float64]

#: Default centre-of-pressure error ball radius at α = 0, mm (module docstring).
DEFAULT_COP_ERROR_MM = 10.0
#: Kinds of output and their units.
KINDS = {"Moment": "N·m/kg", "Power": "W/kg"}
_OFFSETS = np.arange(-HALF_WINDOW, HALF_WINDOW + 1)
#: The kernel's check outputs: the turn of the 4 segments at the row's frame (:func:`_centre_rotations`).
_TURNS = 4
#: A row whose segment frame turned beyond the limit: its turn's cosine below this.
_COS_LIMIT = float(np.cos(np.radians(EXCURSION_LIMIT_DEG)))


@dataclass(frozen=True)
class PlateShare:
    """One plate's share of a foot's ground load: what its centre-of-pressure error moves.

    Attributes:
        number: the plate's 1-based number.
        force: ``(n_frames, 3)`` N, laboratory frame, at the trial's frames: the plate's
            force on the foot on the frames it is under the foot, zero elsewhere.
        axes: ``(3, 3)`` rows the plate's x, y axes and normal (unit vectors, laboratory
            frame): the centre-of-pressure deviation's coordinates.
    """

    number: int
    force: Array
    axes: Array


def plate_axes(corners: Array) -> Array:
    """``(3, 3)`` rows x, y, z of a plate from its ``(4, 3)`` corners (the C3D rule: x from
    corner 2 to corner 1, z = x × (corner 4 → 1), y = z × x)."""
    corners = np.asarray(corners, dtype=float)
    x = corners[0] - corners[1]
    x = x / np.linalg.norm(x)
    z = np.cross(x, corners[0] - corners[3])
    z = z / np.linalg.norm(z)
    return np.stack([x, np.cross(z, x), z])


def plate_shares(plates: Sequence[object], plate: NDArray[np.int_], rate: float) -> tuple[PlateShare, ...]:
    """Each plate's share of a foot's load whose plate on each frame is ``plate``
    (``(n,)`` 1-based numbers, 0: off the plates; as
    :func:`~fuzzygait.kinetics.assignment.assigned_ground`), for the plates that carry the
    foot on some frame.  ``plates``: :class:`~fuzzygait.io.force_plates.ForcePlate` s at
    the analog rate; ``rate``: the marker rate, Hz."""
    n = len(plate)
    shares = []
    for p in plates:
        on = np.asarray(plate) == p.number  # type: ignore[attr-defined]
        if on.any():
            force = np.where(on[:, None], plate_load(p, n, rate).force, 0.0)  # type: ignore[arg-type]
            shares.append(PlateShare(int(p.number), force, plate_axes(p.corners)))  # type: ignore[attr-defined]
    return tuple(shares)


@dataclass
class LegKineticsModel(CompiledModel):
    """Joint moments or powers of one leg as a function of marker and centre-of-pressure
    deviations (module docstring).

    Node ``b · n_frames + j`` is component ``components[b]`` at trial frame
    ``frames[j]``; the components are :attr:`blocks` independent outputs of the same
    parameters (one pass of the chain gives all of them).

    Attributes:
        trial: the pre-processed trial; ``subject``: its subject parameters (body mass,
            static offsets; the inter-ASIS distance is fixed on the trial).
        side: the leg.
        components: ``(joint, axis)`` pairs: joint ``"Ankle"``, ``"Knee"`` or ``"Hip"``,
            axis 0, 1, 2 = Nexus X, Y, Z (powers: 2 only).
        frames: 0-based trial frames (each with four frames either side).
        ground_force, ground_moment: ``(n_frames, 3)`` the ground's load on the foot at
            the trial's frames, N and N·m about the laboratory origin
            (:class:`~fuzzygait.kinetics.inverse_dynamics.Load` ``force``, ``moment``).
        plates: the plates whose centre of pressure is a parameter (:func:`plate_shares`).
        kind: ``"Moment"`` (N·m/kg) or ``"Power"`` (W/kg).
        markers: the markers whose deviations are parameters (default: all the leg's).
        model: the model version (``"cgm1.0"``, ``"cgm1.1"``, ``"cgm2.1"``).
        compiled: evaluate by the compiled kernel (:meth:`kernel`) where there is one;
            False: always numpy (the same numbers, slower).
    """

    trial: Trial
    subject: SubjectParameters
    side: Side
    components: tuple[tuple[str, int], ...]
    frames: np.ndarray
    ground_force: Array
    ground_moment: Array
    plates: tuple[PlateShare, ...] = ()
    kind: str = "Moment"
    markers: list[str] = field(default_factory=list)
    model: str = "cgm1.0"
    compiled: bool = True

    capabilities = frozenset({NODES, NODE_GRADIENTS, BLOCKS, TIME_STEP, NODE_LIMITS})

    def __post_init__(self) -> None:
        version = model_version(self.model)
        if version.clusters:
            raise ParameterError(f"fuzzy kinetics take the Plug-in Gait chain (cgm1.0-2.1); {version.name} tracks "
                                 "clusters, not supported yet")  # fmt: skip
        if self.kind not in KINDS:
            raise ParameterError(f"kind must be one of {', '.join(KINDS)}; got {self.kind!r}")
        self.components = tuple((str(j), int(a)) for j, a in self.components)
        wrong = [c for c in self.components if c[0] not in JOINTS or c[1] not in (0, 1, 2)
                 or (self.kind == "Power" and c[1] != 2)]  # fmt: skip
        if not self.components or wrong:
            raise ParameterError(f"components must be (joint in {JOINTS}, axis 0-2; powers 2 only); got {wrong}")
        self.subject = fixed_subject(self.trial, self.subject)
        needed = segment_markers(self.trial, "foot", self.side.value, False)
        self.markers = list(self.markers) or list(needed)
        if [m for m in self.markers if m not in needed] or [m for m in needed if not self.trial.has_marker(m)]:
            raise ParameterError(f"the {self.side.word.lower()} leg's kinetics are computed from {', '.join(needed)} "
                                 f"(all needed in the trial); got {', '.join(self.markers)}")  # fmt: skip
        self.fixed_markers = [m for m in needed if m not in self.markers]
        self.frames = np.asarray(self.frames, dtype=int)
        n = self.trial.n_frames
        if self.frames.size == 0 or self.frames.min() < HALF_WINDOW or self.frames.max() >= n - HALF_WINDOW:
            raise ParameterError(f"frames must lie {HALF_WINDOW} frames inside the trial's {n} (the derivatives)")
        self.foot_length = foot_length(self.trial, self.side, self.subject.marker_radius)
        self._positions = np.stack([self.trial.marker(m) for m in self.markers], axis=1)
        self._fixed = np.stack([self.trial.marker(m) for m in self.fixed_markers], axis=1) \
            if self.fixed_markers else np.zeros((n, 0, 3))
        self._force = np.asarray(self.ground_force, dtype=float)
        self._moment = np.asarray(self.ground_moment, dtype=float)
        self._shares = np.stack([s.force for s in self.plates]) if self.plates else np.zeros((0, n, 3))
        self._plane = np.stack([s.axes[:2] for s in self.plates]) if self.plates else np.zeros((0, 2, 3))
        self.times = np.tile(self.trial.times[self.frames], len(self.components))
        #: Sampling period of the trial, s.
        self.time_step = 1.0 / self.trial.rate
        #: Independent outputs: one per component.
        self.blocks = len(self.components)
        #: ``(joint, output, axis)`` signs picking Nexus' X, Y, Z from the distal frame's axes.
        self._picks = np.zeros((3, 3, 3))
        for j, joint in enumerate(JOINTS):
            for c, (axis, sign) in enumerate(MOMENT_AXES[(joint, self.side)]):
                self._picks[j, c, axis] = sign

    @property
    def ball_names(self) -> list[str]:
        """The markers, then ``COP<plate number>`` per plate."""
        return [*self.markers, *(f"COP{s.number}" for s in self.plates)]

    @property
    def n_parameters(self) -> int:
        return 3 * len(self.ball_names)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """``<marker>_x|y|z`` (mm, lab frame), then ``COP<n>_x|y|z`` (mm along the plate's
        x, y and normal)."""
        return tuple(f"{b}_{c}" for b in self.ball_names for c in "xyz")

    @property
    def output(self) -> Output:
        names = ",".join(f"{self.side.value}{j}{self.kind}_{AXES[a]}" for j, a in self.components)
        return Output(names, KINDS[self.kind], f"Plug-in Gait joint {self.kind.lower()}, {self.side.word.lower()} leg")

    def component_labels(self) -> list[str]:
        """``"LKneeMoment_X"`` … per component (Nexus' output and axis)."""
        return [f"{self.side.value}{j}{self.kind}_{AXES[a]}" for j, a in self.components]

    def _chain(self, P: np.ndarray, frames: np.ndarray) -> dict[str, np.ndarray]:
        """Joint centres (m) and frames of the leg at the nine frames around each row's
        frame, the row's deviation applied: each ``(k, 9, 3)`` or ``(k, 9, 3, 3)``."""
        window = frames[:, None] + _OFFSETS[None, :]
        return self._parts(self._positions[window], self._fixed[window], P[:, : 3 * len(self.markers)])

    def _parts(self, positions: np.ndarray, fixed: np.ndarray, deviations: np.ndarray) -> dict[str, np.ndarray]:
        """:meth:`_chain` of the window's positions ``(k, 9, m, 3)`` and ``(k, 9, n_fixed, 3)``
        (mm) and the rows' marker deviations ``(k, 3 m)`` (numbers, traced or symbolic)."""
        k, m = len(positions), len(self.markers)
        positions = positions + anp.reshape(deviations, (k, 1, m, 3))
        if self.fixed_markers:
            positions = anp.concatenate([positions, fixed], axis=2)
        flat = anp.reshape(positions, (k * _OFFSETS.size, -1, 3))
        rows = Trial(markers=flat, marker_labels=[*self.markers, *self.fixed_markers], rate=self.trial.rate)
        chain = model_chain(rows, self.subject, self.model)
        s = self.side.value
        parts = {"HJC": chain.hjc(s) * MM, "KJC": chain.kjc(s) * MM, "AJC": chain.ajc(s) * MM,
                 "thigh": chain.thigh(s), "tibia": chain.tibia(s), "foot": chain.foot(s),
                 "pelvis": chain.pelvis()[1]}  # fmt: skip
        return {key: anp.reshape(v, (k, _OFFSETS.size) + v.shape[1:]) for key, v in parts.items()}

    def outputs(self, P: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """``(k, 3, 3)``: per row (deviations ``P`` (k, n_p), trial frames ``frames`` (k,)),
        joint (ankle, knee, hip) and axis the moment (N·m/kg; Nexus X, Y, Z) or the power
        (W/kg, in Z; X = Y = 0)."""
        return self._outputs_and_rotations(P, frames)[0]

    def _outputs_and_rotations(self, P: np.ndarray, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`outputs` and the rows' segment rotations (:func:`_kinetic_rotations`)."""
        P, frames = floats(P), np.asarray(frames, dtype=int)
        window = frames[:, None] + _OFFSETS[None, :]
        loads = Loads(self._force[frames], self._moment[frames], self._shares[:, frames])
        constants = Constants(self.trial.rate, self.subject.body_mass, self.foot_length * MM, self._plane)
        return self._dynamics(self._positions[window], self._fixed[window], loads, P, constants)

    def _dynamics(self, positions: np.ndarray, fixed: np.ndarray, loads: Loads, P: np.ndarray,
                  constants: Constants) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """:meth:`outputs` from the rows' window positions ``(k, 9, m, 3)``, ``(k, 9,
        n_fixed, 3)`` mm, their loads and deviations ``P`` (numbers, traced or symbolic),
        and the segment rotations the kinetics use (:func:`_kinetic_rotations`)."""
        m = len(self.markers)
        parts = self._parts(positions, fixed, P[:, : 3 * m])
        rate, mass = constants.rate, constants.mass
        shifts = anp.reshape(P[:, 3 * m :], (len(P), len(self.plates), 3))
        moment = loads.moment
        for p in range(len(self.plates)):
            offset = anp.dot(shifts[:, p, :2], constants.plane[p]) * MM
            moment = moment + anp.cross(offset, loads.shares[p])
        rotations = _kinetic_rotations(parts)
        omega = angular_velocities(rotations, rate)  # (k, 4 segments, offsets −2, 0, 2, 3)
        moments = newton_euler(leg_segments(parts, constants.foot_length, mass), rotations, omega, loads.force, moment,
                                rate)  # fmt: skip
        if self.kind == "Power":
            relative = omega[:, :3, 1] - omega[:, 1:, 1]
            power = anp.sum(moments * relative, axis=2) / mass
            zero = anp.zeros_like(power)
            return anp.stack([zero, zero, power], axis=2), rotations
        local = apply_rows(anp.swapaxes(rotations[:, :3, 2], -1, -2), moments)
        return anp.einsum("sca,ksa->ksc", self._picks, local) / mass, rotations

    def _selected(self, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each node's frame index (into :attr:`frames`) and output (``3 joint + axis``)."""
        block, j = np.divmod(np.asarray(nodes, dtype=int), self.frames.size)
        joints = np.array([JOINTS.index(joint) for joint, _ in self.components], dtype=int)
        axes = np.array([axis for _, axis in self.components], dtype=int)
        return j, 3 * joints[block] + axes[block]

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """The components (N·m/kg or W/kg) at nodes ``nodes`` (k,) for deviations ``P``
        (k, n_p): by the compiled kernel where there is one, else numpy."""
        if isbox(P):
            j, selected = self._selected(nodes)
            return self._selected_outputs(P, j, selected)
        return self.evaluate_nodes_limited(P, nodes)[0]

    def evaluate_nodes_limited(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`evaluate_nodes` and, per row, whether it lies beyond the model's limits
        (capability ``"node_limits"``): a segment frame the kinetics use (foot, tibia,
        thigh, pelvis) turned more than :data:`~.undetermined.EXCURSION_LIMIT_DEG` from the
        measured one at the row's frame.  The optimisers stop a bound there; :meth:`frame_turn`
        then flags it undetermined (more than :data:`~.undetermined.UNDETERMINED_DEG` at one
        of the nine frames)."""
        j, selected = self._selected(nodes)
        P = np.asarray(P, dtype=float)
        kernel = self.kernel()
        if kernel is None:
            return self._numpy_rows(P, j, selected)
        out, status = kernel.values(self._kernel_rows(), j, P, self._kernel_shared())
        values, beyond = _split_rows(out, selected)
        redo = status == UNSETTLED
        if redo.any():
            values[redo], beyond[redo] = self._numpy_rows(P[redo], j[redo], selected[redo])
        return values, beyond

    def _selected_outputs(self, P: np.ndarray, j: np.ndarray, selected: np.ndarray) -> np.ndarray:
        """On numpy (numbers or traced): output ``selected[i]`` of :meth:`outputs` at frame
        index ``j[i]`` for row ``i`` of ``P``."""
        pick = np.zeros((len(j), 9))
        pick[np.arange(len(j)), selected] = 1.0
        return anp.sum(anp.reshape(self.outputs(P, self.frames[j]), (len(j), 9)) * pick, axis=1)

    def _numpy_rows(self, P: np.ndarray, j: np.ndarray, selected: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`evaluate_nodes_limited` on numpy (frame indices ``j``, outputs ``selected``)."""
        if len(j) == 0:
            return np.empty(0), np.zeros(0, dtype=bool)
        outputs, rotations = self._outputs_and_rotations(P, self.frames[j])
        cosines = turn_cosines(_centre_rotations(rotations), self._measured_rotations()[j])
        return np.reshape(outputs, (len(j), 9))[np.arange(len(j)), selected], _turned(cosines)

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values and exact gradients (per mm) per row: compiled, else a reverse sweep of
        autograd (:func:`~fuzzygait.markererror.angle_model.row_gradients`)."""
        values, gradients, _ = self.evaluate_nodes_gradients_limited(P, nodes)
        return values, gradients

    def evaluate_nodes_gradients_limited(self, P: np.ndarray,
                                         nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        """:meth:`evaluate_nodes_gradients` and the rows beyond the model's limits
        (:meth:`evaluate_nodes_limited`)."""
        kernel = self.kernel()
        P, nodes = np.asarray(P, dtype=float), np.asarray(nodes, dtype=int)
        j, selected = self._selected(nodes)
        if kernel is None or P.shape[0] == 0:
            values, gradients = row_gradients(self.evaluate_nodes, P, nodes)
            return values, gradients, self._numpy_rows(P, j, selected)[1]
        values, turns, gradients, status = kernel.gradients(self._kernel_rows(), j, P, self._kernel_shared(), selected)
        beyond = _turned(turns)
        redo = status == UNSETTLED
        if redo.any():
            values[redo], gradients[redo] = row_gradients(self.evaluate_nodes, P[redo], nodes[redo])
            beyond[redo] = self._numpy_rows(P[redo], j[redo], selected[redo])[1]
        return values, gradients, beyond

    def _measured_rotations(self) -> np.ndarray:
        """``(n_frames, 4, 3, 3)``: :func:`_centre_rotations` at zero deviation, per frame
        of :attr:`frames`."""
        if "_measured" not in self.__dict__:
            self._measured = _centre_rotations(_kinetic_rotations(self._still_chain(self.frames)))
        return self._measured

    def kernel(self) -> RowKernel | None:
        """The compiled model (:mod:`.row_kernel`), or None where it cannot be had.  Its row:
        ``x`` a frame's window (the markers' and the fixed markers' positions at the nine
        frames, mm; the ground's force N and moment N·m; each plate's share of the force),
        ``p`` the deviations, ``q`` the rate, body mass, foot length and the plates'
        in-plane axes, the segments' measured rotations at the frame; out the 3 × 3 joint
        (ankle, knee, hip) and axis outputs, then the cosines of the 4 segment frames' turns
        (:func:`turn_cosines`) at the frame."""
        return self.held_kernel(lambda: compile_kernel(
            model_key("leg", self.kind, self.side, self.model, self.markers, self.fixed_markers, len(self.plates),
                      self.subject),
            self._row_outputs, Shape(self._kernel_rows().shape[1], self.n_parameters, self._kernel_shared().size, 9,
                                     _TURNS), "a joint-kinetics model"))  # fmt: skip

    def _kernel_rows(self) -> np.ndarray:
        """``(n_frames, n_x)``: the kernel's ``x`` at each of :attr:`frames`."""
        if "_rows" not in self.__dict__:
            window = self.frames[:, None] + _OFFSETS[None, :]
            k = self.frames.size
            shares = np.swapaxes(self._shares[:, self.frames], 0, 1).reshape(k, -1)
            parts = [self._positions[window].reshape(k, -1), self._fixed[window].reshape(k, -1),
                     self._force[self.frames], self._moment[self.frames], shares,
                     self._measured_rotations().reshape(k, -1)]  # fmt: skip
            self._rows = np.ascontiguousarray(np.concatenate(parts, axis=1))
        return self._rows

    def _kernel_shared(self) -> np.ndarray:
        """The kernel's ``q``: rate (Hz), body mass (kg), foot length (m), plate axes."""
        return np.concatenate([[self.trial.rate, self.subject.body_mass, self.foot_length * MM], self._plane.ravel()])

    def _row_outputs(self, x: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """The kernel's row function (:meth:`kernel`): :meth:`_dynamics` of one row."""
        m, n_fixed, n_plates, w = len(self.markers), len(self.fixed_markers), len(self.plates), _OFFSETS.size
        a, b = w * m * 3, w * (m + n_fixed) * 3
        c = b + 6 + 3 * n_plates
        loads = Loads(x[b : b + 3].reshape(1, 3), x[b + 3 : b + 6].reshape(1, 3), x[b + 6 : c].reshape(n_plates, 1, 3))
        constants = Constants(q[0], q[1], q[2], q[3:].reshape(n_plates, 2, 3))
        out, rotations = self._dynamics(x[:a].reshape(1, w, m, 3), x[a:b].reshape(1, w, n_fixed, 3), loads,
                                        p.reshape(1, -1), constants)  # fmt: skip
        centre = _centre_rotations(rotations)
        cosines = turn_cosines(centre, x[c:].reshape(centre.shape))
        return np.concatenate([np.reshape(out, 9), np.reshape(cosines, _TURNS)])

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        """Every node (each component's curve in turn) for one deviation ``p`` (n_p,)."""
        P = np.tile(np.asarray(p, dtype=float), (self.frames.size, 1))
        values = np.asarray(self.outputs(P, self.frames), dtype=float)
        return Evaluation(np.concatenate([values[:, JOINTS.index(j), a] for j, a in self.components]))

    def frame_turn(self, P: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """``(k,)`` degrees: the largest rotation of the pelvis, thigh, tibia or foot frame
        from its measured orientation over the nine frames each row's kinetics use, at the
        row's deviation (more than 90°: a frame can flip inside the ball)."""
        P = np.asarray(P, dtype=float)[:, : 3 * len(self.markers)]  # a centre of pressure turns no frame
        frames = np.asarray(frames, dtype=int)
        turn = np.zeros(len(P))
        moving = np.flatnonzero(np.any(P != 0.0, axis=1))
        if moving.size == 0:
            return turn
        repeats = distinct_rows(frames[moving], P[moving])  # the blocks' shared random starts: once
        first, inverse = (np.arange(moving.size), np.arange(moving.size)) if repeats is None else repeats
        pick = moving[first]
        moved, still = self._chain(P[pick], frames[pick]), self._still_chain(frames[pick])
        segments = ("pelvis", "thigh", "tibia", "foot")
        cosines = np.concatenate([turn_cosines(moved[name], still[name]) for name in segments], axis=1)
        turn[moving] = np.degrees(np.arccos(np.clip(cosines.min(axis=1), -1.0, 1.0)))[inverse]
        return turn

    def _still_chain(self, frames: np.ndarray) -> dict[str, np.ndarray]:
        """:meth:`_chain` at zero deviation at trial frames ``frames`` (k,): looked up in
        the one of :attr:`frames` (computed once) where they are model frames."""
        if "_still" not in self.__dict__:
            self._still = self._chain(np.zeros((self.frames.size, self.n_parameters)), self.frames)
        order = np.argsort(self.frames, kind="stable")
        at = np.minimum(np.searchsorted(self.frames[order], frames), self.frames.size - 1)
        if not np.array_equal(self.frames[order][at], frames):
            return self._chain(np.zeros((len(frames), self.n_parameters)), frames)
        return {name: value[order[at]] for name, value in self._still.items()}


def _kinetic_rotations(parts: dict[str, np.ndarray]) -> np.ndarray:
    """``(k, 4, 5, 3, 3)``: foot, tibia, femur and pelvis at the window's even offsets −4,
    −2, 0, 2, 4 — the rotations whose differences the kinetics take — of
    :meth:`LegKineticsModel._parts`."""
    return anp.stack([parts[name][:, ::2] for name in ("foot", "tibia", "thigh", "pelvis")], axis=1)


def _centre_rotations(rotations: np.ndarray) -> np.ndarray:
    """``(k, 4, 3, 3)``: the row's own frame of :func:`_kinetic_rotations`."""
    return rotations[:, :, 2]


def _split_rows(out: np.ndarray, selected: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A kernel's ``(k, 9 + 4)`` rows: the selected output of each and whether it lies
    beyond the model's limits (a turn's cosine below :data:`_COS_LIMIT`)."""
    return out[np.arange(len(out)), selected], _turned(out[:, 9:])


def _turned(cosines: np.ndarray) -> np.ndarray:
    """``(k,)``: whether a row's ``(k, n)`` turn cosines put it beyond the model's limits."""
    return cosines.min(axis=1) < _COS_LIMIT
