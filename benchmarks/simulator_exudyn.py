"""Our simulator against Exudyn (C++ multibody code) on three shared models: speed and agreement.

Run:  .venv/bin/python benchmarks/simulator_exudyn.py            (about 30 s for (a) + (b), (c) ≈ 25 s more)
      .venv/bin/python benchmarks/simulator_exudyn.py --quick    (one repeat, no dt/10 references)
      .venv/bin/python benchmarks/simulator_exudyn.py --case swing --quick   (one case alone: beam, pendulum,
                                                                             swing or all, the default)

Exudyn is an optional, benchmark-only dependency (``pip install -e '.[benchmark]'``); the
script exits with a message when it cannot be imported.  Both codes run in this process,
one after the other, on one core (BLAS threads 1, Exudyn ``parallel.numberOfThreads = 1``),
for the same simulated time with the same fixed step; best of ``--repeats`` runs.

(a) Straight clamped beam — ``build_cantilever`` against Exudyn's
    ``ObjectBeamGeometricallyExact`` (3-D shear-deformable two-node beam, SE(3)
    interpolation, rigid-body nodes with Euler parameters ``NodeRigidBodyEP``).  Same
    length 0.35 m, rectangle 55 mm (width, along y) × 10 mm (thickness, along z), material of
    Table 4.2 (E = 59958e6 Pa, ν = 0.265, ρ = 1710 kg/m³), κ = 5/6, Saint-Venant torsion
    constant, 20 nodes / 19 elements, node 0 clamped, a −50 N tip force along z switched on
    at t = 0 (no gravity), 1 s at dt = 1 ms.  The sudden load makes the beam vibrate about
    its static deflection (first bending mode ≈ 77 Hz, ≈ 13 steps per period).  Exudyn's
    beam takes no material damping here (a row with ``sectionData.dampingMatrix`` set as
    ours shows that the installed version ignores it for this element); its generalized-α with spectral
    radius 0.9 damps the unresolved axial/shear/torsion modes numerically.  Our variational
    integrator is not dissipative and diverges with eta = 1 (shown), so it runs with
    Kelvin–Voigt eta = 1e5 Pa s, which damps those high modes and the first bending mode
    by a damping ratio of only ≈ 4e-4; the energy-momentum scheme runs with eta = 1.
    Agreement is judged on quantities that do not depend on the accumulated phase error of
    77 vibrations: the mean tip deflection over the run (≈ the static deflection; also
    compared with Timoshenko's), the vibration frequency (zero crossings of the deflection
    about its mean) and the deflection history during the first 0.1 s.

(b) Rigid double pendulum — ``LegSimulator("swing", foot="none")`` against two Exudyn
    ``ObjectRigidBody`` s (Euler-parameter nodes) with the thigh and shank of Table 4.1, a
    spherical hip (``ObjectJointSpherical``) and a revolute knee about the lateral axis
    (``ObjectJointRevoluteZ``), released at rest from hip −π/6 (extension) and knee π/3
    flexion in gravity (9.81 m/s²), 1 s at dt = 1 ms.  Agreement: hip and knee flexion
    angles at t = 1 s, and (unless ``--quick``) each code's error against its own run at
    dt = 0.1 ms.

(c) The swing scenario — ``LegSimulator("swing")`` (20 blade nodes, the packaged
    Vari-Flex-like blade, homogeneous section) with the stiff blade of Table 4.2
    (``REVERSE_ENGINEERED``: E = 59958e6 Pa, ν = 0.265, ρ = 1710 kg/m³, as the "swing, stiff
    blade" rows of RESULTS.md) and eta = 1 Pa s (the damping of ``SWING`` and of Table 4.2;
    not the eta = 1e5 of ``COMMAND_DEFAULTS["swing"]``, which the commands need for the soft
    Table 4.3 blade), released at rest from hip −π/6 and knee π/3 in gravity (9.81 m/s²),
    2 s at dt = 1 ms; our model is built (compiled library loaded from the cache) before the
    clock starts, and the time is that of the integration alone (``wall_time_s``).  The
    Exudyn leg: thigh and shank as in (b); the blade as 19 ``ObjectBeamGeometricallyExact``
    elements between 20 ``NodeRigidBodyEP`` nodes at our model's reference configuration
    (positions and directors of ``LegSimulator.leg.q0``: node axes x = d3, the tangent of the
    curved centreline, y = d1, lateral/width, z = d2, thickness), node 0 held to the shank's
    distal end by an ``ObjectJointGeneric`` on all six axes whose shank marker carries node
    0's frame in the shank's axes (our rigid ankle, Eq. 4.7).  Each element takes our
    model's own element constants (``add_beam``: L, A, I_1, I_2, J, κ — they vary along the
    blade with its tabulated width and core thickness): stiffness diag(EA, κGA, κGA, GJ,
    EI_1, EI_2) (axial, shear y/z, torsion, bending about d1 — the soft sagittal one — and
    about d2), mass per length ρA, section inertia ρ·diag(I_1 + I_2, I_1, I_2) (our Euler
    tensor ρ·diag(I_2, I_1, 0) on d1, d2, d3 as an inertia tensor); gravity as nodal forces
    ρAL·g/2 at both ends of each element, which is our gravity energy exactly.
    Curved reference in Exudyn 1.13.6: the element's documentation says nothing about it
    (the element is marked "under construction" and has no curvature parameter; the
    stored public source of earlier versions used a fixed straight reference, h0 = [L, 0, 0,
    0, 0, 0], with a note that the pre-deformed reference was still to come), but the installed
    version takes the nodes' reference coordinates and rotations as the stress-free state:
    its strains come from the SE(3) relative motion of node 1 to node 0, and a single
    pre-curved element (nodes on an arc, frames along the tangents, or even frames not
    along the chord) stays at rest unloaded and turns by ML/EI under a tip moment M, as a
    straight one does (checked with one-element models while writing this case); ``length``
    only scales the strains and the mass.  So, like ours (reference strains Γ_ref, K_ref
    subtracted), the chain is stress free at t = 0; the toe's elastic deflection in the
    shank-fixed attachment frame (tens of µm in both codes) shows it — a straight reference
    would spring the blade open.  Mass: both consistent linear-element masses (the installed
    element's mass matrix has the blocks ρAL/3, ρAL/6 for the translations and the same 2:1
    pattern for the section inertia, checked as above; ours interpolates the directors,
    Exudyn the angular velocities — the same at the reference, different at higher order).
    What still differs from ours: Exudyn's element interpolates on SE(3) (strains from the
    relative motion of the node frames) where ours uses averaged directors at the midpoint
    (Eqs. 4.31–4.32; both tend to the same continuum strains, they differ at higher order in
    the rotation across an element); rotations by Euler parameters (7 coordinates + 1
    constraint per node) against our directors; no material damping (the damping matrix is
    ignored, see (a)) where ours has Kelvin–Voigt eta = 1 Pa s (negligible against
    E = 6e10 Pa); and its generalized-α (ρ∞ = 0.9) damps
    the blade's unresolved modes numerically where our schemes do not.  With its default
    Newton tolerances Exudyn stops at t ≈ 0.48 s: Newton stalls at a relative error of
    ≈ 1.5e-8 against the 1e-8 tolerance (apparently a round-off floor of the stiff blade's
    forces: 50 iterations or full Newton stop at the same time), so a second run with
    ``newton.relativeTolerance = 1e-7`` runs the 2 s and is the reference.  Agreement on
    quantities that do not depend on accumulated phase error of the blade's vibration: hip
    and knee flexion and the toe (last blade node) position at t = 0.1, 0.5, 1 and 2 s
    (the slow pendulum motion; tolerances 1e-3 rad and 1 mm), and the mean and standard
    deviation over the run of the toe's elastic deflection.

What each solver does per step (both: fixed step, sparse direct LU, modified Newton):

* ours — variational integrator (midpoint discrete Lagrangian, Eq. 4.26; index-3
  constraints, director coordinates: 12 per body + 6 orthonormality constraints) or the
  energy-momentum scheme; Newton on (q_{j+1}, λ_j), SuperLU (COLAMD) factorisation kept
  across iterations and steps, refreshed when an update shrinks by less than 4×; converged
  when the update is ≤ 1e-10·(1 + |q|∞) and the constraints hold to 1e-11; residuals and
  Jacobians from compiled CasADi kernels, the step loop in Python.
* Exudyn 1.13 — ``SolveDynamic`` with generalized-α (index 3, spectral radius 0.9,
  ``adaptiveStep`` off), Euler-parameter nodes (7 coordinates + 1 constraint per body),
  modified Newton (its default: Jacobian kept while the contraction is < 0.5, relative
  residual tolerance 1e-8, absolute 1e-10), Eigen sparse LU (``EigenSparse``), all in
  C++; tip position / rotation matrices recorded every step by internal sensors, no files.
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import contextlib  # noqa: E402
import io  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.core.errors import SimulationError  # noqa: E402
from fuzzygait.mechanics.cantilever import build_cantilever  # noqa: E402
from fuzzygait.mechanics.leg import segment_frame  # noqa: E402
from fuzzygait.mechanics.presets import REVERSE_ENGINEERED, SHANK, SWING, THIGH  # noqa: E402
from fuzzygait.mechanics.scenarios import LegSimulator  # noqa: E402
from fuzzygait.mechanics.sections import SHEAR_CORRECTION_RECTANGLE, rectangle_torsion_constant  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402

try:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import exudyn as exu
        import exudyn.itemInterface as eii
        from exudyn.rigidBodyUtilities import RotationMatrix2EulerParameters, eulerParameters0
except ImportError as _error:  # optional dependency
    exu = None
    _IMPORT_ERROR = _error

LENGTH, WIDTH, THICKNESS, NODES = 0.35, 0.055, 0.010, 20  # m, m, m, nodes
TIP_FORCE = -50.0  # N along z
E, NU, RHO = REVERSE_ENGINEERED.youngs_modulus, REVERSE_ENGINEERED.poisson, REVERSE_ENGINEERED.density
GRAVITY = 9.81
DT, DURATION = 1e-3, 1.0
# agreement tolerances
TOL_MEAN = 5e-3  # relative, mean tip deflection
TOL_FREQUENCY = 1e-2  # relative, vibration frequency
TOL_HISTORY = 2e-2  # RMS difference over the first 0.1 s / peak deflection
TOL_ANGLE = 1e-3  # rad, hip and knee angle at the end (b) / at the sample times (c)
# (c) the swing scenario with the stiff blade
SWING_ETA = REVERSE_ENGINEERED.damping  # = SWING.material.damping = 1 (Tables 4.2/4.3); not COMMAND_DEFAULTS' 1e5
SWING_DURATION = SWING.duration  # 2 s at SWING.dt = 1 ms
SWING_TIMES = (0.1, 0.5, 1.0, 2.0)  # s, sample times of the agreement figures
TOL_TOE = 1e-3  # m, toe position at the sample times (≈ TOL_ANGLE × the 0.9 m leg)
SWING_RELATIVE_TOLERANCE = 1e-7  # Exudyn's Newton stalls at ≈ 1.5e-8 > its default 1e-8 at t ≈ 0.48 s
ANKLE_ARM = [0.0, 0.0, -(SHANK.length - SHANK.com_from_proximal)]  # shank body axes (d1, d2, d3)


# -- Exudyn models ----------------------------------------------------------------------------
def exudyn_settings(dt: float, duration: float, sparse: bool = True):
    s = exu.SimulationSettings()
    s.timeIntegration.numberOfSteps = int(round(duration / dt))
    s.timeIntegration.endTime = duration
    s.timeIntegration.generalizedAlpha.spectralRadius = 0.9
    s.timeIntegration.adaptiveStep = False
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.writePeriod = dt
    s.parallel.numberOfThreads = 1
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse if sparse else exu.LinearSolverType.EXUdense
    return s


def exudyn_solve(mbs, settings) -> tuple[float, dict | str]:
    """Wall time of SolveDynamic and the Newton statistics (or the error)."""
    start = time.perf_counter()
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):  # no failure banner
            warnings.simplefilter("ignore")
            mbs.SolveDynamic(settings)
    except Exception as error:  # noqa: BLE001 — exudyn raises its own SolverError / RuntimeError
        it = mbs.sys["dynamicSolver"].it if "dynamicSolver" in mbs.sys else None
        where = f" at t = {it.currentTime:.3f} s" if it is not None else ""
        return time.perf_counter() - start, f"{type(error).__name__}{where}"
    wall = time.perf_counter() - start
    it = mbs.sys["dynamicSolver"].it
    return wall, dict(iterations=it.newtonStepsCount / it.numberOfSteps, jacobians=it.newtonJacobiCount)


def exudyn_cantilever(nodes: int, lie_group: bool = False, eta: float = 0.0):
    """Clamped straight beam of ``ObjectBeamGeometricallyExact`` elements; returns (mbs, tip sensor).
    ``eta`` (Pa s): sectional damping matrix of the same Kelvin–Voigt form as ours (0: none)."""
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    shear = E / (2 * (1 + NU))
    kappa = SHEAR_CORRECTION_RECTANGLE
    area = WIDTH * THICKNESS
    i_y = WIDTH * THICKNESS**3 / 12  # ∫ z² dA: bending about the width axis y (soft, tip moves along z)
    i_z = THICKNESS * WIDTH**3 / 12
    torsion = float(rectangle_torsion_constant(np.array(WIDTH), np.array(THICKNESS)))
    section = exu.BeamSection()
    # local x = beam axis; order: axial, shear y, shear z, torsion, bending y, bending z
    section.stiffnessMatrix = np.diag([E * area, kappa * shear * area, kappa * shear * area, shear * torsion,
                                       E * i_y, E * i_z])
    section.dampingMatrix = eta * np.diag([area, kappa * area, kappa * area, torsion, i_y, i_z])
    section.massPerLength = RHO * area
    section.inertia = RHO * np.diag([i_y + i_z, i_y, i_z])
    element = LENGTH / (nodes - 1)
    if lie_group:
        node_type, rotation = eii.NodeRigidBodyRotVecLG, [0.0, 0.0, 0.0]
    else:
        node_type, rotation = eii.NodeRigidBodyEP, list(eulerParameters0)
    node_ids = [mbs.AddNode(node_type(referenceCoordinates=[element * k, 0.0, 0.0] + rotation)) for k in range(nodes)]
    for a, b in zip(node_ids, node_ids[1:]):
        mbs.AddObject(eii.ObjectBeamGeometricallyExact(nodeNumbers=[a, b], length=element, sectionData=section))
    ground = mbs.AddObject(eii.ObjectGround())
    clamp_ground = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    clamp_node = mbs.AddMarker(eii.MarkerNodeRigid(nodeNumber=node_ids[0]))
    mbs.AddObject(eii.ObjectJointGeneric(markerNumbers=[clamp_ground, clamp_node], constrainedAxes=[1] * 6))
    tip = mbs.AddMarker(eii.MarkerNodeRigid(nodeNumber=node_ids[-1]))
    mbs.AddLoad(eii.LoadForceVector(markerNumber=tip, loadVector=[0.0, 0.0, TIP_FORCE]))
    sensor = mbs.AddSensor(eii.SensorNode(nodeNumber=node_ids[-1], storeInternal=True,
                                          outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    return sc, mbs, sensor


def exudyn_leg(blade: tuple[LegSimulator, np.ndarray] | None = None):
    """Thigh + shank (Table 4.1): spherical hip at the origin, revolute knee about the lateral axis;
    with ``blade = (sim, p)`` also our swing model's blade (see (c) in the module docstring).
    Returns (system container, mbs, [thigh, shank] rotation sensors, and with the blade the
    shank's position sensor and the toe's, else None, None)."""
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    hip_angle, knee_angle = SWING.hip_angle, SWING.knee_angle
    u_thigh = np.array([np.sin(hip_angle), 0.0, -np.cos(hip_angle)])
    shank_angle = hip_angle - knee_angle
    u_shank = np.array([np.sin(shank_angle), 0.0, -np.cos(shank_angle)])
    knee = THIGH.length * u_thigh
    masses = {"thigh": (THIGH.mass, THIGH.inertia), "shank": (SHANK.mass, SHANK.inertia)}
    if blade is not None:  # the parameter vector's segment data (the same values as Table 4.1)
        sim, p = blade
        value = dict(zip(sim.parameter_names, p))
        masses = {name: (value[f"{name}_mass"], tuple(value[f"{name}_J{i}"] for i in (1, 2, 3))) for name in masses}
    ground = mbs.AddObject(eii.ObjectGround())
    bodies, nodes, sensors = [], [], []
    for segment, direction, proximal in ((THIGH, u_thigh, np.zeros(3)), (SHANK, u_shank, knee)):
        # body axes = our directors: x = d1 (lateral, the knee axis), z = d3 (long axis, proximal)
        rotation = segment_frame(direction).T
        centre = proximal + segment.com_from_proximal * direction
        node = mbs.AddNode(eii.NodeRigidBodyEP(
            referenceCoordinates=list(centre) + list(RotationMatrix2EulerParameters(rotation))))
        mass, (j1, j2, j3) = masses[segment.name]
        body = mbs.AddObject(eii.ObjectRigidBody(nodeNumber=node, mass=mass, inertia=[j1, j2, j3, 0.0, 0.0, 0.0]))
        mass_marker = mbs.AddMarker(eii.MarkerBodyMass(bodyNumber=body))
        mbs.AddLoad(eii.LoadMassProportional(markerNumber=mass_marker, loadVector=[0.0, 0.0, -GRAVITY]))
        bodies.append(body)
        nodes.append(node)
        sensors.append(mbs.AddSensor(eii.SensorNode(nodeNumber=node, storeInternal=True,
                                                    outputVariableType=exu.OutputVariableType.RotationMatrix)))
    thigh, shank = bodies
    hip_ground = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    hip_thigh = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=thigh, localPosition=[0.0, 0.0, THIGH.com_from_proximal]))
    mbs.AddObject(eii.ObjectJointSpherical(markerNumbers=[hip_ground, hip_thigh]))
    joint_axes = np.column_stack([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])  # joint z = body x (lateral)
    knee_thigh = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=thigh, localHT=exu.HT(
        rotation=joint_axes, translation=[0.0, 0.0, -(THIGH.length - THIGH.com_from_proximal)])))
    knee_shank = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=shank, localHT=exu.HT(
        rotation=joint_axes, translation=[0.0, 0.0, SHANK.com_from_proximal])))
    mbs.AddObject(eii.ObjectJointRevoluteZ(markerNumbers=[knee_thigh, knee_shank]))
    shank_position = toe = None
    if blade is not None:
        shank_position = mbs.AddSensor(eii.SensorNode(nodeNumber=nodes[1], storeInternal=True,
                                                      outputVariableType=exu.OutputVariableType.Position))
        toe = exudyn_blade(mbs, *blade, shank, segment_frame(u_shank).T)
    mbs.Assemble()
    return sc, mbs, sensors, shank_position, toe


def exudyn_blade(mbs, sim: LegSimulator, p: np.ndarray, shank: int, shank_rotation: np.ndarray) -> int:
    """Our blade as ``ObjectBeamGeometricallyExact`` elements between ``NodeRigidBodyEP`` nodes at
    our model's reference (curved) configuration, node 0 rigidly joined to the shank's distal
    end; returns the toe position sensor."""
    value = dict(zip(sim.parameter_names, p))
    modulus, rho = value["E"], value["rho"]
    shear = modulus / (2 * (1 + value["nu"]))
    (group,) = sim.leg.builder.element_groups
    # per element, as our model has them (add_beam): L, A, I_1 (about d1), I_2 (about d2), J, κ
    lengths, area, i_1, i_2, torsion, kappa = group.constants[:, :6].T
    names = list(sim.leg.builder.body_names)
    q0 = sim.leg.q0.reshape(len(names), 12)
    node_ids = []
    for name in sim.leg.blade_bodies:
        position, d1, d2, d3 = q0[names.index(name)].reshape(4, 3)
        rotation = np.column_stack([d3, d1, d2])  # Exudyn's beam axis x = our d3, y = d1 (width), z = d2 (thickness)
        node_ids.append(mbs.AddNode(eii.NodeRigidBodyEP(
            referenceCoordinates=list(position) + list(RotationMatrix2EulerParameters(rotation)))))
    weights = np.zeros(len(node_ids))
    for e, (a, b) in enumerate(zip(node_ids, node_ids[1:])):
        section = exu.BeamSection()
        # order: axial, shear y, shear z, torsion, bending about y (= d1, the soft sagittal bending), bending about z
        section.stiffnessMatrix = np.diag([modulus * area[e], kappa[e] * shear * area[e], kappa[e] * shear * area[e],
                                           shear * torsion[e], modulus * i_1[e], modulus * i_2[e]])
        section.massPerLength = rho * area[e]
        section.inertia = rho * np.diag([i_1[e] + i_2[e], i_1[e], i_2[e]])
        mbs.AddObject(eii.ObjectBeamGeometricallyExact(nodeNumbers=[a, b], length=lengths[e], sectionData=section))
        weights[e : e + 2] += 0.5 * rho * area[e] * lengths[e] * GRAVITY  # = our gravity energy ρAL g (z_a + z_b)/2
    for node, weight in zip(node_ids, weights):  # the element takes no body markers (MarkerBodyMass)
        marker = mbs.AddMarker(eii.MarkerNodePosition(nodeNumber=node))
        mbs.AddLoad(eii.LoadForceVector(markerNumber=marker, loadVector=[0.0, 0.0, -weight]))
    _, d1, d2, d3 = q0[names.index(sim.leg.blade_bodies[0])].reshape(4, 3)
    relative = shank_rotation.T @ np.column_stack([d3, d1, d2])  # node 0's frame in the shank's body axes
    ankle = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=shank,
                                              localHT=exu.HT(rotation=relative, translation=ANKLE_ARM)))
    attachment = mbs.AddMarker(eii.MarkerNodeRigid(nodeNumber=node_ids[0]))
    mbs.AddObject(eii.ObjectJointGeneric(markerNumbers=[ankle, attachment], constrainedAxes=[1] * 6))
    return mbs.AddSensor(eii.SensorNode(nodeNumber=node_ids[-1], storeInternal=True,
                                        outputVariableType=exu.OutputVariableType.Position))


def exudyn_pendulum():
    """Thigh + shank (Table 4.1): spherical hip at the origin, revolute knee about the lateral axis."""
    sc, mbs, sensors, _, _ = exudyn_leg()
    return sc, mbs, sensors


def exudyn_angles(mbs, sensors) -> tuple[np.ndarray, np.ndarray]:
    """Hip and knee flexion (rad) from the stored rotation matrices, as LegSimulator defines them."""
    sagittal = []
    for sensor in sensors:
        data = mbs.GetSensorStoredData(sensor)
        rotation = data[:, 1:10].reshape(-1, 3, 3)
        distal = -rotation[:, :, 2]  # −d3
        sagittal.append(np.arctan2(distal[:, 0], -distal[:, 2]))
    hip, shank = sagittal
    return hip, np.unwrap(hip - shank)


# -- comparisons ------------------------------------------------------------------------------
def frequency(t: np.ndarray, z: np.ndarray) -> float:
    """Vibration frequency (Hz) from the interpolated zero crossings of z − mean(z)."""
    y = z - z.mean()
    k = np.nonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)[0]
    crossings = t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])
    return (len(crossings) - 1) / (2.0 * (crossings[-1] - crossings[0]))


def best(fn, repeats: int):
    """Run ``fn`` (returns (wall, payload)) ``repeats`` times; the fastest, or the first failure."""
    chosen = None
    for _ in range(repeats):
        wall, payload = fn()
        if isinstance(payload, str):
            return wall, payload
        if chosen is None or wall < chosen[0]:
            chosen = (wall, payload)
    return chosen


def cantilever_case(repeats: int, schemes: list[str]) -> None:
    print(f"### (a) Clamped beam, {NODES} nodes, tip force {TIP_FORCE:g} N, {DURATION:g} s at dt = {DT:g} s")
    n_steps = int(round(DURATION / DT))
    ours = build_cantilever(LENGTH, WIDTH, THICKNESS, NODES, (0.0, 0.0, TIP_FORCE))
    histories: dict[str, np.ndarray] = {}
    rows = []

    def run_ours(eta: float, scheme: str):
        def fn():
            kwargs = {} if scheme == "variational" else {"scheme": scheme}
            start = time.perf_counter()
            try:
                trajectory = ours.run(np.array([E, NU, RHO, eta]), DT, n_steps, **kwargs)
            except SimulationError as error:
                return time.perf_counter() - start, str(error).split(": ")[0]
            wall = time.perf_counter() - start
            return wall, dict(tip=ours.tip_position(trajectory)[:, 2], iterations=float(trajectory.iterations.mean()),
                              jacobians=int(trajectory.timings.get("factorisations", 0)))
        return fn

    variants = [("variational", 1.0), ("variational", 1e5)] + [(s, 1.0) for s in schemes if s != "variational"]
    for scheme, eta in variants:
        label = f"ours, {scheme}, eta = {eta:g}"
        wall, payload = best(run_ours(eta, scheme), 1 if (scheme, eta) == ("variational", 1.0) else repeats)
        rows.append((label, wall, payload))
        if not isinstance(payload, str):
            histories[label] = payload["tip"]

    def run_exudyn(lie_group: bool, eta: float = 0.0):
        def fn():
            _, mbs, sensor = exudyn_cantilever(NODES, lie_group, eta)
            wall, stats = exudyn_solve(mbs, exudyn_settings(DT, DURATION))
            if isinstance(stats, str):
                return wall, stats
            return wall, dict(stats, tip=mbs.GetSensorStoredData(sensor)[:, 3])
        return fn

    start = time.perf_counter()
    exudyn_cantilever(NODES)
    exudyn_build = time.perf_counter() - start
    wall, payload = best(run_exudyn(False), repeats)
    reference_label = "Exudyn, GeometricallyExact beam, EP nodes"
    rows.append((reference_label, wall, payload))
    exudyn_wall = wall if not isinstance(payload, str) else np.nan
    if not isinstance(payload, str):
        histories[reference_label] = payload["tip"]
    wall, payload = best(run_exudyn(False, 1e5), 1)
    rows.append(("Exudyn, same with sectionData.dampingMatrix = eta·diag(A, κA, κA, J, I_y, I_z), eta = 1e5",
                 wall, payload))
    wall, payload = best(run_exudyn(True), 1)
    rows.append(("Exudyn, same with Lie-group nodes (RotVecLG)", wall, payload))

    timoshenko = ours.timoshenko_tip_deflection(TIP_FORCE, E, NU)
    t = np.arange(n_steps + 1) * DT
    early = t <= 0.1 + 1e-12
    print("| solver | integration wall s | ratio to Exudyn | Newton it/step | Jacobians / LU | mean tip deflection mm "
          "| vs Timoshenko | frequency Hz | RMS diff. first 0.1 s / peak | tip at 1 s mm |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    reference = histories.get(reference_label)
    checks = []
    for label, wall, payload in rows:
        if isinstance(payload, str):
            print(f"| {label} | failed after {wall:.2f} s: {payload} | | | | | | | | |")
            continue
        z = payload["tip"]
        mean = z.mean()
        f = frequency(t, z)
        if reference is not None and label != reference_label:
            history = np.sqrt(np.mean((z[early] - reference[early]) ** 2)) / np.abs(reference[early]).max()
            history_text = f"{history:.1e}"
            if label.startswith("ours"):
                checks.append((label, abs(mean / reference.mean() - 1), abs(f / frequency(t, reference) - 1), history))
        else:
            history_text = "reference" if label == reference_label else "–"
        print(f"| {label} | {wall:.2f} | {wall / exudyn_wall:.2f} | {payload['iterations']:.2f} "
              f"| {payload['jacobians']} | {1e3 * mean:.4f} | {100 * (mean / timoshenko - 1):+.2f} % | {f:.2f} "
              f"| {history_text} | {1e3 * z[-1]:.3f} |")
    print(f"(Timoshenko static tip deflection {1e3 * timoshenko:.4f} mm; the mean over the run of an undamped "
          f"vibration about the static state equals it. Exudyn model build + Assemble: {exudyn_build:.3f} s.)")
    for label, d_mean, d_freq, history in checks:
        ok = d_mean <= TOL_MEAN and d_freq <= TOL_FREQUENCY and history <= TOL_HISTORY
        print(f"agreement {label} vs Exudyn: mean {100 * d_mean:.3f} % (tol {100 * TOL_MEAN:g} %), frequency "
              f"{100 * d_freq:.3f} % (tol {100 * TOL_FREQUENCY:g} %), history {100 * history:.2f} % (tol "
              f"{100 * TOL_HISTORY:g} %) — {'agree' if ok else 'DO NOT agree'}")
    print()


def pendulum_case(repeats: int, schemes: list[str], references: bool) -> None:
    print(f"### (b) Rigid double pendulum (thigh + shank), {DURATION:g} s at dt = {DT:g} s")
    sim = LegSimulator("swing", foot="none")
    p = sim.parameters()

    def run_ours(scheme: str, dt: float):
        def fn():
            kwargs = {} if scheme == "variational" else {"scheme": scheme}
            start = time.perf_counter()
            try:
                ds = sim.run(p, SolverSettings(dt=dt, duration=DURATION, **kwargs))
            except SimulationError as error:
                return time.perf_counter() - start, str(error).split(": ")[0]
            total = time.perf_counter() - start
            return ds.attrs["wall_time_s"], dict(total=total, hip=float(ds.hip_flexion[-1]),
                                                 knee=float(ds.knee_flexion[-1]),
                                                 iterations=float(ds.newton_iterations.mean()),
                                                 jacobians=int(ds.attrs["factorisations"]))
        return fn

    def run_exudyn(dt: float, sparse: bool):
        def fn():
            _, mbs, sensors = exudyn_pendulum()
            wall, stats = exudyn_solve(mbs, exudyn_settings(dt, DURATION, sparse))
            if isinstance(stats, str):
                return wall, stats
            hip, knee = exudyn_angles(mbs, sensors)
            return wall, dict(stats, total=wall, hip=float(hip[-1]), knee=float(knee[-1]))
        return fn

    rows = [(f"ours, {scheme}", scheme, best(run_ours(scheme, DT), repeats)) for scheme in schemes]
    rows.append(("Exudyn, EigenSparse LU", "exudyn", best(run_exudyn(DT, True), repeats)))
    rows.append(("Exudyn, dense LU", "exudyn-dense", best(run_exudyn(DT, False), repeats)))
    fine = {}
    if references:
        for scheme in schemes:
            fine[scheme] = best(run_ours(scheme, DT / 10), 1)[1]
        fine["exudyn"] = fine["exudyn-dense"] = best(run_exudyn(DT / 10, True), 1)[1]
    exudyn_wall = rows[-2][2][0]
    exudyn_end = rows[-2][2][1]
    print("| solver | integration wall s | run() total s | ratio to Exudyn (sparse) | Newton it/step | Jacobians / LU "
          "| hip at 1 s rad | knee at 1 s rad | Δ to Exudyn hip / knee rad | error vs own dt/10 hip / knee rad |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    checks = []
    for label, key, (wall, r) in rows:
        if isinstance(r, str):
            print(f"| {label} | failed: {r} | | | | | | | | |")
            continue
        if key == "exudyn":
            delta = "reference"
        else:
            delta = f"{r['hip'] - exudyn_end['hip']:+.1e} / {r['knee'] - exudyn_end['knee']:+.1e}"
        if key.startswith("ours") or key in schemes:
            checks.append((label, max(abs(r["hip"] - exudyn_end["hip"]), abs(r["knee"] - exudyn_end["knee"]))))
        own = fine.get(key)
        own_text = f"{r['hip'] - own['hip']:+.1e} / {r['knee'] - own['knee']:+.1e}" if isinstance(own, dict) else "–"
        print(f"| {label} | {wall:.3f} | {r['total']:.3f} | {wall / exudyn_wall:.1f} | {r['iterations']:.2f} "
              f"| {r['jacobians']} | {r['hip']:.6f} | {r['knee']:.6f} | {delta} | {own_text} |")
    if isinstance(fine.get("exudyn"), dict) and any(isinstance(fine.get(s), dict) for s in schemes):
        s0 = next(s for s in schemes if isinstance(fine.get(s), dict))
        print(f"(dt/10 references: ours ({s0}) hip {fine[s0]['hip']:.7f}, knee {fine[s0]['knee']:.7f}; Exudyn hip "
              f"{fine['exudyn']['hip']:.7f}, knee {fine['exudyn']['knee']:.7f} rad)")
    for label, worst in checks:
        print(f"agreement {label} vs Exudyn at t = {DURATION:g} s: max |Δ angle| = {worst:.1e} rad "
              f"(tol {TOL_ANGLE:g} rad) — {'agree' if worst <= TOL_ANGLE else 'DO NOT agree'}")
    print()


def toe_deflection(shank_position: np.ndarray, shank_rotation: np.ndarray, toe: np.ndarray,
                   reference: np.ndarray) -> np.ndarray:
    """(n, 3) elastic toe displacement in the blade's attachment frame (x fwd, y lat, z up) from the
    shank's centre, its rotation (n, 3, 3; columns d1, d2, d3) and the toe's inertial position."""
    ankle = shank_position + shank_rotation @ np.asarray(ANKLE_ARM)
    attachment = np.stack([-shank_rotation[:, :, 1], shank_rotation[:, :, 0], shank_rotation[:, :, 2]], axis=2)
    return np.einsum("nji,nj->ni", attachment, toe - ankle) - reference


def swing_case(repeats: int, schemes: list[str]) -> None:
    sim = LegSimulator("swing")  # 20 blade nodes, the packaged blade, homogeneous section
    p = sim.parameters(E=E, nu=NU, rho=RHO, eta=SWING_ETA)
    dt, n_nodes = SWING.dt, sim.configuration.nodes
    print(f"### (c) Swing scenario, stiff blade (E = {E / 1e6:g}e6 Pa, rho = {RHO:g} kg/m³, eta = {SWING_ETA:g} Pa s), "
          f"{n_nodes} blade nodes, {SWING_DURATION:g} s at dt = {dt:g} s")
    reference_toe = np.asarray(sim.leg.mesh.positions[-1])
    samples = np.rint(np.asarray(SWING_TIMES) / dt).astype(int)

    def run_ours(scheme: str):
        def fn():
            kwargs = {} if scheme == "variational" else {"scheme": scheme}
            start = time.perf_counter()
            try:
                ds = sim.run(p, SolverSettings(dt=dt, duration=SWING_DURATION, **kwargs))
            except SimulationError as error:
                return time.perf_counter() - start, str(error).split(": ")[0]
            total = time.perf_counter() - start
            shank = list(ds.body.values).index("shank")
            rotation = np.swapaxes(ds.directors.values[:, shank], 1, 2)  # columns d1, d2, d3
            toe = ds.last_node_position.values
            return ds.attrs["wall_time_s"], dict(
                total=total, hip=ds.hip_flexion.values, knee=ds.knee_flexion.values, toe=toe,
                deflection=toe_deflection(ds.position.values[:, shank], rotation, toe, reference_toe),
                iterations=float(ds.newton_iterations.mean()), jacobians=int(ds.attrs["factorisations"]))
        return fn

    def run_exudyn(relative_tolerance: float | None):
        def fn():
            _, mbs, sensors, shank_position, toe_sensor = exudyn_leg((sim, p))
            settings = exudyn_settings(dt, SWING_DURATION)
            if relative_tolerance is not None:
                settings.timeIntegration.newton.relativeTolerance = relative_tolerance
            wall, stats = exudyn_solve(mbs, settings)
            if isinstance(stats, str):
                return wall, stats
            hip, knee = exudyn_angles(mbs, sensors)
            rotation = mbs.GetSensorStoredData(sensors[1])[:, 1:10].reshape(-1, 3, 3)
            toe = mbs.GetSensorStoredData(toe_sensor)[:, 1:4]
            return wall, dict(stats, total=wall, hip=hip, knee=knee, toe=toe, deflection=toe_deflection(
                mbs.GetSensorStoredData(shank_position)[:, 1:4], rotation, toe, reference_toe))
        return fn

    rows = [(f"ours, {scheme}", best(run_ours(scheme), repeats)) for scheme in schemes]
    start = time.perf_counter()
    exudyn_leg((sim, p))
    exudyn_build = time.perf_counter() - start
    exudyn_rows = [
        ("Exudyn, thigh/shank + GeometricallyExact blade, EP nodes, Newton defaults (relative tol. 1e-8)", None),
        (f"Exudyn, same with newton.relativeTolerance = {SWING_RELATIVE_TOLERANCE:g}", SWING_RELATIVE_TOLERANCE),
    ]
    for label, tolerance in exudyn_rows:  # a failing run stops after its first try
        rows.append((label, best(run_exudyn(tolerance), repeats)))
    # the reference: the first Exudyn run that reached the end
    reference_label, (exudyn_wall, exudyn_run) = next(
        ((label, result) for label, result in rows[len(schemes):] if not isinstance(result[1], str)), rows[-1])
    exudyn_ok = not isinstance(exudyn_run, str)
    print("| solver | integration wall s | run() total s | ratio to Exudyn | Newton it/step | Jacobians / LU "
          "| toe elastic deflection x / z mm: mean over run (std) |")
    print("|---|---|---|---|---|---|---|")
    for label, (wall, r) in rows:
        if isinstance(r, str):
            print(f"| {label} | failed after {wall:.2f} s: {r} | | | | | |")
            continue
        ratio = f"{wall / exudyn_wall:.2f}" if exudyn_ok else "–"
        mean, std = 1e3 * r["deflection"].mean(axis=0), 1e3 * r["deflection"].std(axis=0)
        print(f"| {label} | {wall:.2f} | {r['total']:.2f} | {ratio} | {r['iterations']:.2f} | {r['jacobians']} "
              f"| {mean[0]:+.4f} ({std[0]:.4f}) / {mean[2]:+.4f} ({std[2]:.4f}) |")
    print()
    print("| t s | solver | hip rad | knee rad | toe x / z mm | toe deflection x / z mm "
          "| Δ to Exudyn hip / knee rad | Δ to Exudyn toe x / z mm |")
    print("|---|---|---|---|---|---|---|---|")
    worst: dict[str, list[float]] = {}
    for t, k in zip(SWING_TIMES, samples):
        for label, (_, r) in rows:
            if isinstance(r, str) or k >= len(r["hip"]):
                continue
            toe, deflection = 1e3 * r["toe"][k], 1e3 * r["deflection"][k]
            if exudyn_ok and label != reference_label:
                d_angle = (r["hip"][k] - exudyn_run["hip"][k], r["knee"][k] - exudyn_run["knee"][k])
                d_toe = r["toe"][k] - exudyn_run["toe"][k]
                angles_text = f"{d_angle[0]:+.1e} / {d_angle[1]:+.1e}"
                toe_text = f"{1e3 * d_toe[0]:+.3f} / {1e3 * d_toe[2]:+.3f}"
                entry = worst.setdefault(label, [0.0, 0.0])
                entry[0] = max(entry[0], *map(abs, d_angle))
                entry[1] = max(entry[1], float(np.linalg.norm(d_toe)))
            else:
                angles_text = toe_text = "reference" if label == reference_label else "–"
            print(f"| {t:g} | {label} | {r['hip'][k]:.6f} | {r['knee'][k]:.6f} | {toe[0]:.2f} / {toe[2]:.2f} "
                  f"| {deflection[0]:+.4f} / {deflection[2]:+.4f} | {angles_text} | {toe_text} |")
    blade_mass = float((RHO * sim.leg.builder.element_groups[0].constants[:, :2].prod(axis=1)).sum())
    print(f"(Blade {blade_mass * 1e3:.1f} g in both models; toe deflection = toe in the shank-fixed attachment frame "
          f"minus its reference, our blade's toe at {1e3 * reference_toe[0]:.1f} / {1e3 * reference_toe[2]:.1f} mm. "
          f"Exudyn model build + Assemble: {exudyn_build:.3f} s.)")
    for label, (angle, toe) in worst.items():
        ok = angle <= TOL_ANGLE and toe <= TOL_TOE
        print(f"agreement {label} vs Exudyn at t = {', '.join(f'{t:g}' for t in SWING_TIMES)} s: max |Δ angle| = "
              f"{angle:.1e} rad (tol {TOL_ANGLE:g}), max |Δ toe| = {1e3 * toe:.3f} mm (tol {1e3 * TOL_TOE:g} mm) — "
              f"{'agree' if ok else 'DO NOT agree'}")
    print()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one repeat, no dt/10 reference runs")
    parser.add_argument("--repeats", type=int, default=None,
                        help="runs per solver, fastest reported (default 3, quick 1)")
    parser.add_argument("--schemes", default="variational,energy-momentum", help="our integration schemes")
    parser.add_argument("--case", choices=("beam", "pendulum", "swing", "all"), default="all",
                        help="run one case alone: (a) beam, (b) pendulum, (c) swing (default all)")
    args = parser.parse_args()
    if exu is None:
        print(f"Exudyn is not importable ({_IMPORT_ERROR}); it is an optional benchmark dependency: "
              "pip install -e '.[benchmark]'. Skipping.")
        sys.exit(0)
    repeats = args.repeats or (1 if args.quick else 3)
    schemes = args.schemes.split(",")
    one, five, _ = os.getloadavg()
    print(f"## Simulator vs Exudyn {exu.__version__} (same process, one core; best of {repeats}; "
          f"load average {one:.2f}, {five:.2f})")
    print()
    if args.case in ("beam", "all"):
        cantilever_case(repeats, schemes)
    if args.case in ("pendulum", "all"):
        pendulum_case(repeats, schemes, references=not args.quick)
    if args.case in ("swing", "all"):
        swing_case(repeats, schemes)
    one, five, _ = os.getloadavg()
    print(f"load average at end: {one:.2f}, {five:.2f}")


if __name__ == "__main__":
    main()
