"""One joint-angle component of a CGM version as a model of marker deviations, for the
uncertainty engine (thesis §3.7.3).

The parameters are the deviations ``p = [p_1, …, p_m]`` (mm, lab frame, 3 per marker) of
the markers the angle depends on; the output at frame ``j`` is the angle component
(degrees) computed from ``r_i(t_j) + p_i`` (Eq. 3.1). The same deviation applies at every
frame of a trajectory (so one evaluation is a whole angle curve), and
:meth:`JointAngleModel.evaluate_nodes` evaluates any number of (deviation, frame) pairs
in one vectorised pass of the model; :class:`AngleComponentsModel` stacks the components
of one angle so that pass serves all of them.

Model versions (:mod:`fuzzygait.kinematics.versions`): the angle is computed by the chain
of the version that computed the measured angles — Plug-in Gait's (``cgm1.0``), its
CGM 1.1 / 2.1 variants (tibia, pelvis sequence, Hara hips) or, for ``cgm2.3`` and
``cgm2.4``, the :class:`~fuzzygait.kinematics.clusters.ClusterChain` with the session's
static cluster calibration.  The markers perturbed are the dynamic markers that chain
reads for the angle (:func:`model_angle_markers`); for the cluster models:

=================  ==================================================================
angle              markers (per side; those of the calibrated clusters in the trial)
=================  ==================================================================
Pelvis             LASI, RASI, SACR (or LPSI, RPSI)
Hip                pelvis + thigh cluster THI, THAP, THAD, KNE
Knee               thigh cluster + shank cluster TIB, TIAP, TIAD, ANK (no pelvis: the
                   cluster fits give KJC and AJC directly)
Ankle, FootProg.   shank cluster + TOE (hindfoot: TOE, AJC, the shank's ankle axis and
                   the static offsets; HEE is not used by the dynamic foot)
ForeFoot (2.4)     shank cluster + TOE, FMH, SMH, VMH (forefoot cluster fit; FJC fixed
                   in the hindfoot)
=================  ==================================================================

Fixed (thesis §3.6: the anthropometric measures are not propagated): the subject
parameters with the inter-ASIS distance of the unperturbed trial, the static offsets,
the static cluster calibration (the static-only markers KNM and MED are never
parameters) and the progression frame of the unperturbed trial.

Continuous branch: with ``reference`` (the measured angle component at each frame) the
model returns ``reference + wrap(angle - reference)`` with ``wrap`` into (-180°, 180°]:
the angle on the branch through the measured one, never the ±180° representation, so a
band that passes 180° stays one band.  Where a deviation inside the ball turns the
segment frame so far that this excursion approaches ±180° (the frame can flip) the
hull is not a band any more; :func:`undetermined` marks it.

Evaluation: the model's chain compiled to C where it can be (:meth:`JointAngleModel.kernel`,
:mod:`.row_kernel`: every version), else the chain on numpy with autograd's exact
gradients — the same numbers to rounding (1e-12°).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import autograd.numpy as anp
import numpy as np
from autograd import make_vjp
from autograd.tracer import isbox

from fuzzygait.core.arrays import floats
from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import AXES
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.angles import wrap_degrees
from fuzzygait.kinematics.chain import pelvis_markers
from fuzzygait.kinematics.clusters import ClusterCalibration
from fuzzygait.kinematics.model import ALL_ANGLE_NAMES, angle_from_chain, angle_markers, model_chain
from fuzzygait.kinematics.pelvis import inter_asis_distance
from fuzzygait.kinematics.versions import model_version
from fuzzygait.markererror.row_kernel import (
    MISSING,
    UNSETTLED,
    CompiledModel,
    RowKernel,
    Shape,
    compile_kernel,
    model_key,
)
from fuzzygait.markererror.undetermined import EXCURSION_LIMIT_DEG
from fuzzygait.uncertainty.protocol import (
    BLOCKS,
    EXCURSION_LIMIT,
    NODE_GRADIENTS,
    NODES,
    TIME_STEP,
    Evaluation,
    Output,
)


def model_angle_markers(
    trial: Trial,
    name: str,
    model: str = "cgm1.0",
    clusters: ClusterCalibration | None = None,
    use_medial_markers: bool = False,
) -> list[str]:
    """The dynamic markers the angle ``name`` of model version ``model`` is computed from
    (module docstring): the parameters of its marker-error model.

    Raises:
        ParameterError: an unknown model, a cluster model without ``clusters``, or an angle
            the version does not compute (``ForeFootAngles`` before ``cgm2.4``).
    """
    version = model_version(model)
    side, joint = name[0], name[1:].removesuffix("Angles")
    if joint == "ForeFoot" and not version.forefoot:
        raise ParameterError(f"{name} is a CGM 2.4 output; {version.name} does not compute it")
    if not version.clusters:
        return angle_markers(trial, name, use_medial_markers)
    if clusters is None:
        raise ParameterError(f"the {version.name} markers of {name} are those of the static cluster calibration: "
                             "give it (clusters)")  # fmt: skip
    calibration = clusters

    def tracked(segment: str) -> list[str]:
        return [m for m in calibration.segment(side, segment).markers if trial.has_marker(m)]

    hindfoot = tracked("tibia") + [side + "TOE"]
    needed = {
        "Pelvis": pelvis_markers(trial),
        "Hip": pelvis_markers(trial) + tracked("thigh"),
        "Knee": tracked("thigh") + tracked("tibia"),
        "Ankle": hindfoot,
        "FootProgress": hindfoot,
    }
    if joint == "ForeFoot":
        return hindfoot + [m for m in tracked("forefoot") if m not in hindfoot]
    if joint not in needed:
        raise ParameterError(f"unknown angle {name!r}")
    return needed[joint]


def fixed_subject(trial: Trial, subject: SubjectParameters) -> SubjectParameters:
    """``subject`` with the inter-ASIS distance fixed (measured on ``trial`` if unset)."""
    if subject.inter_asis_distance is not None:
        return subject
    return replace(subject, inter_asis_distance=inter_asis_distance(trial.marker("LASI"), trial.marker("RASI")))


@dataclass
class JointAngleModel(CompiledModel):
    """Angle component ``name_axis`` as a function of the deviations of ``markers``.

    Attributes:
        trial: the (pre-processed) trial; only frames ``frames`` are used.
        subject: subject parameters with a fixed inter-ASIS distance.
        progression: ``(3, 3)`` progression frame of the unperturbed trial.
        name: angle output, e.g. ``"LKneeAngles"`` (``"LForeFootAngles"``: cgm2.4).
        axis: 0, 1, 2 for X (sagittal), Y (frontal), Z (transverse).
        frames: sample indices (0-based) of the trial used as time nodes.
        markers: labels whose deviations are the parameters (default: every marker the
            angle depends on, :func:`model_angle_markers`); the angle's other markers stay
            at their measured positions.  A marker the angle does not depend on (e.g. a
            static-only KNM) is refused.
        reference: the measured angle component (degrees) at each of ``frames``; given,
            the outputs are on its continuous branch (module docstring).
        model: the model version that computed the measured angles (``"cgm1.0"`` …
            ``"cgm2.4"``).
        clusters: the static cluster calibration (``cgm2.3``, ``cgm2.4``), held fixed.
        compiled: evaluate by the compiled kernel where there is one (:mod:`.row_kernel`);
            False: always the numpy chain (the same numbers, slower).
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
    model: str = "cgm1.0"
    clusters: ClusterCalibration | None = None
    compiled: bool = True

    def __post_init__(self) -> None:
        self.model = model_version(self.model).name
        if self.name not in ALL_ANGLE_NAMES:
            raise ParameterError(f"unknown angle {self.name!r}; give one of {', '.join(ALL_ANGLE_NAMES)}")
        if isinstance(self.axis, bool) or not isinstance(self.axis, (int, np.integer)) or not 0 <= self.axis <= 2:
            raise ParameterError(f"axis must be 0, 1 or 2 (X, Y, Z); got {self.axis!r}")
        self._check_frames()
        model_chain(self.trial, self.subject, self.model, self.clusters)  # its errors: no calibration, no forefoot
        needed = model_angle_markers(self.trial, self.name, self.model, self.clusters, self.use_medial_markers)
        if not self.markers:
            self.markers = list(needed)
        unused = [m for m in self.markers if m not in needed]
        if unused:
            raise ParameterError(
                f"{', '.join(unused)}: not a marker {self.name} of {self.model} is computed from (static-only "
                f"markers and the static calibration are fixed); its markers are {', '.join(needed)}"
            )
        self.fixed_markers = [m for m in needed if m not in self.markers]
        self.frames = np.asarray(self.frames, dtype=int)
        self._base = np.stack([self.trial.marker(m)[self.frames] for m in self.markers], axis=1)
        self._fixed = np.stack([self.trial.marker(m)[self.frames] for m in self.fixed_markers], axis=1) \
            if self.fixed_markers else np.zeros((self.frames.size, 0, 3))
        #: Per frame the perturbed then the fixed markers' x, y, z (mm): the compiled rows' base.
        rows = np.concatenate([self._base, self._fixed], axis=1)
        self._rows = np.ascontiguousarray(rows.reshape(len(self.frames), -1))
        self.times = self.trial.times[self.frames]
        #: Sampling period of the trial, s (frames further apart are not neighbours).
        self.time_step = 1.0 / self.trial.rate

    def _check_frames(self) -> None:
        """Refuse :attr:`frames` that are not 0-based sample indices of the trial."""
        frames = np.asarray(self.frames)
        n_frames = self.trial.n_frames
        if frames.ndim == 1 and (frames.dtype.kind in "iu" or (frames.size == 0 and frames.dtype.kind == "f")):
            bad = frames[(frames < 0) | (frames >= n_frames)]
        else:
            bad = frames.ravel() if frames.ndim > 0 else frames.reshape(1)
        if bad.size:
            raise ParameterError(f"frames must be whole 0-based sample indices of {self.trial.name or 'the trial'}, "
                                 f"from 0 to {n_frames - 1} ({n_frames} frames); got {bad[:5].tolist()}"
                                 f"{' …' if bad.size > 5 else ''}")  # fmt: skip

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

    capabilities = frozenset({NODES, NODE_GRADIENTS, TIME_STEP, EXCURSION_LIMIT})

    @property
    def excursion_limit(self) -> float:
        """Degrees from the measured angle beyond which a bound makes the band undetermined
        (:data:`~.undetermined.EXCURSION_LIMIT_DEG`; the optimisers stop a bound there); ``inf`` without
        ``reference`` (no continuous branch to measure it on)."""
        return math.inf if self.reference is None else EXCURSION_LIMIT_DEG

    def angles_of(self, positions: np.ndarray, fixed: np.ndarray | None = None) -> np.ndarray:
        """All three components (degrees) for marker positions ``(k, n_markers, 3)``
        (``fixed``: the positions ``(k, n_fixed, 3)`` of :attr:`fixed_markers`): by the
        chain (:meth:`component_values` takes the compiled kernel where there is one)."""
        if self.fixed_markers and fixed is None:
            raise ParameterError(f"the positions of {', '.join(self.fixed_markers)} are needed too")
        if fixed is None:
            fixed = np.zeros((len(positions), 0, 3))
        return self.chain_angles(positions, fixed, self.progression)

    def chain_angles(self, positions: np.ndarray, fixed: np.ndarray, progression: np.ndarray) -> np.ndarray:
        """The chain of the model version: all three components (degrees) for positions
        ``(k, n_markers, 3)`` and ``(k, n_fixed, 3)`` and the ``(3, 3)`` progression frame
        (numbers, traced or symbolic arrays alike)."""
        if self.fixed_markers:
            positions = anp.concatenate([positions, fixed], axis=1)
        rows = Trial(markers=positions, marker_labels=[*self.markers, *self.fixed_markers], rate=self.trial.rate)
        chain = model_chain(rows, self.subject, self.model, self.clusters, use_medial_markers=self.use_medial_markers)
        return angle_from_chain(chain, self.name, progression)

    def kernel(self) -> RowKernel | None:
        """The compiled model (:func:`~.row_kernel.compile_kernel`, once per process and
        model structure), or None where it cannot be had.  Its row: ``x`` a frame's
        positions (the perturbed markers' x, y, z, then the fixed markers'), ``p`` the
        deviations of the perturbed ones, ``q`` the progression frame; out the three
        components (degrees, on the chain's own branch)."""
        return self.held_kernel(lambda: compile_kernel(
            model_key("angle", self.model, self.name, self.markers, self.fixed_markers, self.use_medial_markers,
                      self.subject, self.clusters),
            self._row_angles, Shape(self._rows.shape[1], 3 * len(self.markers), 9, 3),
            "a joint-angle model"))  # fmt: skip

    def _by_chain(self, status: np.ndarray) -> np.ndarray:
        """The kernel's rows the chain computes: those it did not settle, and for a cluster
        model those with a marker missing (the cluster fit takes the markers it sees; the
        kernel assumes all)."""
        return (status == UNSETTLED) | ((status == MISSING) & (self.clusters is not None))

    def _row_angles(self, x: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """The kernel's row function (:meth:`kernel`)."""
        n = p.size
        positions = (x[:n] + p).reshape(1, -1, 3)
        return self.chain_angles(positions, x[n:].reshape(1, -1, 3), q.reshape(3, 3))[0]

    def measured_angles(self) -> np.ndarray:
        """All three components (degrees) at zero deviation, ``(n_frames, 3)`` on
        :attr:`frames`: the measured angle where the model reproduces it."""
        return self.angles_of(self._base, self._fixed)

    def seen(self) -> np.ndarray:
        """``(n_frames, n_markers)`` True where a perturbed marker is measured (a cluster
        marker may be missing at a frame: its pose is then from the others)."""
        return np.all(np.isfinite(self._base), axis=-1)

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """Angle component at time nodes ``nodes`` (k,) for deviations ``P`` (k, n_p)."""
        nodes = np.asarray(nodes, dtype=int)
        reference = None if self.reference is None else np.asarray(self.reference, dtype=float)[nodes]
        return self.component_values(P, nodes, self.axis, reference)

    def component_values(self, P: np.ndarray, nodes: np.ndarray, axes: int | np.ndarray,
                         reference: np.ndarray | None) -> np.ndarray:  # fmt: skip
        """Component ``axes`` (one for all rows, or ``(k,)`` per row) of the angle (degrees)
        at time nodes ``nodes`` (k,) for deviations ``P`` (k, n_p); with ``reference``
        ``(k,)`` (degrees) on the continuous branch through it.  One pass of the kinematic
        model serves every row, whichever component it asks for."""
        kernel = None if isbox(P) else self.kernel()
        if kernel is not None:
            P, nodes = np.asarray(P, dtype=float), np.asarray(nodes, dtype=int)
            angles, status = kernel.values(self._rows, nodes, P, self.progression)
            redo = self._by_chain(status)
            if redo.any():
                angles[redo] = self._chain_rows(P[redo], nodes[redo])
        else:
            angles = self._chain_rows(P, nodes)
        angle = angles[:, axes] if np.ndim(axes) == 0 else angles[np.arange(len(nodes)), axes]
        return _on_branch(angle, reference)

    def _chain_rows(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """All three components (degrees) by the numpy chain for deviations ``P`` (k, n_p)
        at time nodes ``nodes`` (k,) (numbers or traced)."""
        return self.angles_of(self._base[nodes] + floats(P).reshape(len(nodes), -1, 3), self._fixed[nodes])

    def component_gradients(self, P: np.ndarray, nodes: np.ndarray, axes: int | np.ndarray,
                            reference: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """:meth:`component_values` and the exact gradient of each row's value with
        respect to its own row of ``P``, ``(k, n_p)`` degrees/mm: by the compiled kernel
        where there is one, else one reverse sweep of autograd (:func:`row_gradients`).
        The branch through ``reference`` has the angle's gradient (the wrap is a shift)."""
        P = np.asarray(P, dtype=float)
        nodes = np.asarray(nodes, dtype=int)
        kernel = self.kernel()
        if kernel is None or P.shape[0] == 0:
            return row_gradients(lambda rows, at: self.component_values(rows, at, axes, reference), P, nodes)
        rows = np.arange(len(nodes))
        axes = np.broadcast_to(axes, rows.shape)
        angle, _, gradients, status = kernel.gradients(self._rows, nodes, P, self.progression, axes)
        angle = _on_branch(angle, reference)
        redo = self._by_chain(status)
        if redo.any():
            at = None if reference is None else reference[redo]
            angle[redo], gradients[redo] = row_gradients(
                lambda p, n: self.component_values(p, n, axes[redo], at), P[redo], nodes[redo])  # fmt: skip
        return angle, gradients

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The angle component (degrees) at ``nodes`` (k,) for deviations ``P`` (k, n_p) and
        its exact gradient with respect to each row's deviations, ``(k, n_p)`` degrees/mm
        (:meth:`component_gradients`)."""
        nodes = np.asarray(nodes, dtype=int)
        reference = None if self.reference is None else np.asarray(self.reference, dtype=float)[nodes]
        return self.component_gradients(P, nodes, self.axis, reference)

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        """The angle component over all time nodes with one deviation ``p`` (n_p,); no
        whole-trajectory sensitivities (the batched optimiser takes the per-node exact ones
        of :meth:`evaluate_nodes_gradients`, other strategies finite differences)."""
        nodes = np.arange(self.frames.size)
        return Evaluation(self.evaluate_nodes(np.tile(np.asarray(p, dtype=float), (nodes.size, 1)), nodes))


@dataclass
class AngleComponentsModel:
    """Several components of one angle as one model of the same marker deviations, so the
    α-level optimiser serves them in the same calls (one pass of the kinematic model
    gives all three components of a row).

    Node ``b · n_frames + j`` is component ``axes[b]`` at frame ``angle.frames[j]``, on
    the continuous branch through ``references[b, j]``; :attr:`times` (s) are the frames'
    times once per component.  The components are :attr:`blocks` independent outputs:
    the batched Graph Follower optimises each as it would alone
    (:func:`~fuzzygait.uncertainty.gfa.batched.run_batched`).  The values and gradients
    of a node are those of :class:`JointAngleModel` for that component.

    Attributes:
        angle: the angle's model (its ``axis`` and ``reference`` are not used).
        axes: the components, 0, 1, 2 for X, Y, Z.
        references: ``(len(axes), n_frames)`` the measured components (degrees).
    """

    angle: JointAngleModel
    axes: tuple[int, ...]
    references: np.ndarray

    capabilities = frozenset({NODES, NODE_GRADIENTS, BLOCKS, TIME_STEP, EXCURSION_LIMIT})

    @property
    def excursion_limit(self) -> float:
        """Degrees from the measured component beyond which a bound makes its band
        undetermined (:data:`~.undetermined.EXCURSION_LIMIT_DEG`; the optimisers stop a bound there)."""
        return EXCURSION_LIMIT_DEG

    def __post_init__(self) -> None:
        self.axes = tuple(int(a) for a in self.axes)
        self.references = np.asarray(self.references, dtype=float)
        n_frames = self.angle.frames.size
        if self.references.shape != (len(self.axes), n_frames):
            raise ParameterError(f"references must be (components, frames) = ({len(self.axes)}, {n_frames}); "
                                 f"got {self.references.shape}")  # fmt: skip
        #: The frames' times (s), once per component.
        self.times = np.tile(np.asarray(self.angle.times, dtype=float), len(self.axes))
        #: Sampling period of the trial, s.
        self.time_step = self.angle.time_step
        #: Independent outputs, one per component (:func:`~fuzzygait.uncertainty.gfa.batched.run_batched`).
        self.blocks = len(self.axes)

    @property
    def markers(self) -> list[str]:
        return self.angle.markers

    @property
    def n_parameters(self) -> int:
        return self.angle.n_parameters

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return self.angle.parameter_names

    @property
    def output(self) -> Output:
        return Output(f"{self.angle.name}_{''.join(AXES[a] for a in self.axes)}", "deg")

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """The components (degrees) at nodes ``nodes`` (k,) for deviations ``P`` (k, n_p)."""
        block, frame = np.divmod(np.asarray(nodes, dtype=int), self.angle.frames.size)
        axes = np.asarray(self.axes, dtype=int)[block]
        return self.angle.component_values(P, frame, axes, self.references[block, frame])

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values and exact gradients (degrees/mm) per row
        (:meth:`JointAngleModel.component_gradients`)."""
        block, frame = np.divmod(np.asarray(nodes, dtype=int), self.angle.frames.size)
        axes = np.asarray(self.axes, dtype=int)[block]
        return self.angle.component_gradients(P, frame, axes, self.references[block, frame])

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        """Every node (each component's curve in turn) for one deviation ``p`` (n_p,)."""
        nodes = np.arange(self.times.size)
        return Evaluation(self.evaluate_nodes(np.tile(np.asarray(p, dtype=float), (nodes.size, 1)), nodes))


def _on_branch(angle: np.ndarray, reference: np.ndarray | None) -> np.ndarray:
    """``angle`` (degrees) on the continuous branch through ``reference`` (None: as it is)."""
    return angle if reference is None else reference + wrap_degrees(angle - reference)


def row_gradients(function: Callable[[np.ndarray, np.ndarray], np.ndarray], P: np.ndarray,
                  nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """``function(P, nodes)`` (k,) and the gradient of each row's value with respect to its
    own row of ``P`` (k, n_p), exact, by one reverse sweep through the kinematic model
    (autograd, :mod:`fuzzygait.core.arrays`): every row is computed from its own row of
    ``P`` only, so the gradient of the sum of the values is the rows' gradients.  A row
    whose angle is not defined (a marker missing there) has NaN values and gradients."""
    P = np.asarray(P, dtype=float)
    if P.shape[0] == 0:
        return np.empty(0), np.empty_like(P)
    vjp, values = make_vjp(lambda rows: function(rows, nodes))(P)
    values = np.asarray(values, dtype=float)
    return values, np.asarray(vjp(np.ones_like(values)), dtype=float)
