"""Time integration of a :class:`DiscreteModel` (thesis §4.1.2, Eqs. 4.16–4.29).

Each step of the chosen scheme (:mod:`.schemes`: variational or energy-momentum) is solved by
Newton–Raphson with a sparse LU of the Jacobian, kept across iterations and steps while it
contracts well.  Parameter sensitivities ``S_j = dq_j/dp`` follow by differentiating the
converged step equations:
``J_x [S_{j+1}; dλ_j/dp] = −(∂R/∂q_j S_j + ∂R/∂q_{j−1} S_{j−1} + ∂R/∂p)`` — the same
Jacobian, so one extra back-substitution per step.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.sparse.linalg import splu

from fuzzygait.core.errors import ParameterError, SimulationError
from fuzzygait.mechanics import native
from fuzzygait.mechanics.discrete import DiscreteModel
from fuzzygait.mechanics.schemes import SCHEMES, StepAssembler
from fuzzygait.mechanics.step_functions import group_constants
from fuzzygait.mechanics.trajectory import Trajectory

# Newton keeps its LU factorisation across iterations and steps and refreshes it when an
# update shrinks by less than this factor (linear convergence too slow to be worth it).
REFRESH_CONTRACTION = 0.25
# Largest Newton update of any coordinate per iteration (m for positions, 1 for directors);
# a time step of a few ms never moves a coordinate this far, so larger updates are divergence.
MAX_UPDATE = 0.2
#: Times :func:`integrate` halves the step (repeating the run) after a step that does not converge.
MAX_HALVINGS = 3


ENGINES = ("auto", "compiled", "python")

FOLD_COSINE = 0.0  # adjacent beam cross-sections turned by more than 90° = a folded element


def _check_folding(model: DiscreteModel, q: np.ndarray, t: float, p: np.ndarray) -> None:
    """Raise when a beam element has folded: its two nodes' tangent directors d3 turned by
    more than 90° against each other.  The midpoint element then averages the directors to
    nearly zero and can stretch at almost no energy cost — a discretisation artefact, so the
    run stops instead of returning a physically meaningless motion."""
    for group in model.groups:
        dofs = group.dofs
        cosine = np.einsum("ek,ek->e", q[dofs[:, 9:12]], q[dofs[:, 21:24]])
        worst = int(np.argmin(cosine))
        if cosine[worst] < FOLD_COSINE:
            raise _folded(model, group.name, worst, float(cosine[worst]), t, p)


def _folded(model: DiscreteModel, group: str, element: int, cosine: float, t: float, p: np.ndarray) -> SimulationError:
    angle = float(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))))
    return SimulationError(
        f"{group} element {element} folded at t = {t:.4f} s: its cross-sections turned by "
        f"{angle:.0f}° (> 90°) within one element; parameters {_describe(model.parameter_names, p)}; "
        "use more nodes, a stiffer blade or more damping (eta)"
    )


def _not_converged(model: DiscreteModel, step: int, dt: float, norm: float, iterations: int,
                   p: np.ndarray) -> SimulationError:  # fmt: skip
    return SimulationError(
        f"Newton did not converge at t = {(step + 1) * dt:.4f} s (step {step + 1}, dt = {dt:g} s): "
        f"residual norm {norm:.3g} after {iterations} iterations; parameters {_describe(model.parameter_names, p)}; "
        "try a smaller dt, more damping (eta) or the energy-momentum scheme"
    )


def _integrate_compiled(model: DiscreteModel, q0: np.ndarray, v0: np.ndarray, p: np.ndarray, dt: float,
                        n_steps: int, sensitivities: bool, tolerance: float, constraint_tolerance: float,
                        max_iterations: int, progress: Callable[[int], None] | None,
                        scheme: str) -> Trajectory:  # fmt: skip
    """:func:`integrate` by the compiled loop (:func:`.native.run`)."""
    assert model.stepper is not None
    pair_a = np.concatenate([g.dofs[:, 9] for g in model.groups]) if model.groups else np.zeros(0, dtype=int)
    pair_b = np.concatenate([g.dofs[:, 21] for g in model.groups]) if model.groups else np.zeros(0, dtype=int)
    starts = np.cumsum([0] + [len(g.dofs) for g in model.groups])
    result = native.run(
        model.stepper, n=model.ndof, m=model.nconstraints, p=p, constants=model.constants,
        group_constants=group_constants(model.groups), fold_pairs=(pair_a, pair_b, starts), q0=q0, v0=v0, dt=dt,
        n_steps=n_steps, scheme=scheme, sensitivities=sensitivities, tolerance=tolerance,
        constraint_tolerance=constraint_tolerance, max_iterations=max_iterations, progress=progress,
    )  # fmt: skip
    stopped = result.stopped
    if stopped is not None and stopped.kind == "fold":
        group = int(np.searchsorted(starts, stopped.index, side="right") - 1)
        raise _folded(model, model.groups[group].name, stopped.index - int(starts[group]), stopped.value,
                      (stopped.step + 1) * dt, p)  # fmt: skip
    if stopped is not None:
        raise _not_converged(model, stopped.step, dt, stopped.value, stopped.iterations, p)
    result.timings["pivot_orders"] = float(result.pivot_orders)
    return Trajectory(
        times=np.arange(n_steps + 1) * dt,
        q=result.q,
        multipliers=result.multipliers,
        iterations=result.iterations,
        sensitivities=result.sensitivities,
        timings=result.timings,
        velocities=result.velocities,
        scheme=scheme,
    )


def _describe(parameter_names: Sequence[str], p: np.ndarray) -> str:
    return ", ".join(f"{name}={value:.6g}" for name, value in zip(parameter_names, p))


def integrate(
    model: DiscreteModel,
    q0: np.ndarray,
    p: np.ndarray,
    dt: float,
    n_steps: int,
    *,
    v0: np.ndarray | None = None,
    sensitivities: bool = False,
    tolerance: float = 1e-10,
    constraint_tolerance: float = 1e-11,
    max_iterations: int = 25,
    progress: Callable[[int], None] | None = None,
    scheme: str = "variational",
    engine: str = "auto",
    max_halvings: int = MAX_HALVINGS,
    substeps: int = 1,
) -> Trajectory:
    """Integrate ``n_steps`` steps of size ``dt`` (s) from ``q0`` with velocity ``v0``.

    ``scheme`` "variational" (default): the variational integrator of Eq. 4.26.
    "energy-momentum": the one-step midpoint scheme with the discrete-gradient beam force and
    ``G(q_{j+½})ᵀλ`` (Betsch & Steinmann): energy is conserved exactly without damping and
    the damped balance ``E_0 = E_j + D_j`` holds to the Newton tolerance.  Both give
    sensitivities.

    Newton stops when the last update is ≤ ``tolerance`` (m, unit directors) and the
    constraints hold to ``constraint_tolerance``.  Raises :class:`SimulationError` naming the
    time, the residual norm and the parameter values when a step does not converge.

    ``engine``: "compiled" runs the whole Newton loop in C (:mod:`.native`; the model's
    ``stepper`` library), "python" the loop below over the compiled kernels, "auto" (default)
    the compiled loop where the model has one.  Both solve the same equations with the same
    iteration; trajectories agree to the Newton tolerance.

    Step refinement: when a step does not converge (at dt = 1 ms the midpoint-type
    variational integrator turns unstable for a stiff blade's unresolved high modes — the
    energy grows by orders of magnitude within a few steps before Newton fails, so the
    state there is already wrong), the whole run is repeated with ``dt/2`` sub-steps, up to
    ``max_halvings`` times.  Every accepted step of the repeated run solves the scheme's step
    equations (for the variational integrator the discrete Euler–Lagrange equations with the
    uniform step ``dt/2^r``); the returned trajectory holds the time nodes ``k·dt`` of the
    original grid, its ``iterations`` the Newton iterations summed over each node's sub-steps
    and ``substeps`` = 2^r.  A folded element is not retried (the fold is the blade's
    motion, not the time step's).  ``substeps`` (a power of two, at most 2^max_halvings):
    start with that many sub-steps per ``dt`` (a caller's own acceptance test, e.g.
    :class:`.scenarios.LegSimulator`'s energy balance, asks for more).
    """
    if substeps < 1 or substeps & (substeps - 1) or substeps > 2**max_halvings:
        raise ParameterError(f"substeps must be a power of two ≤ 2^max_halvings; got {substeps}")
    while True:
        try:
            fine = _integrate_uniform(
                model, q0, p, dt / substeps, n_steps * substeps, v0=v0, sensitivities=sensitivities,
                tolerance=tolerance, constraint_tolerance=constraint_tolerance, max_iterations=max_iterations,
                progress=None if progress is None else _coarse_progress(progress, substeps),
                scheme=scheme, engine=engine,
            )  # fmt: skip
        except SimulationError as error:
            if "did not converge" not in str(error) or substeps >= 2**max_halvings:
                if substeps > 1:
                    raise SimulationError(f"{error} (with {substeps} sub-steps per dt = {dt:g} s)") from None
                raise
            substeps *= 2
            continue
        return fine if substeps == 1 else _coarsen(fine, substeps)


def _coarse_progress(progress: Callable[[int], None], substeps: int) -> Callable[[int], None]:
    return lambda done: progress(done // substeps)


def _coarsen(fine: Trajectory, substeps: int) -> Trajectory:
    """The time nodes ``k·dt`` of a run with ``substeps`` uniform sub-steps per ``dt``."""
    r = substeps
    n_steps = (len(fine.times) - 1) // r
    return Trajectory(
        times=fine.times[::r],
        q=fine.q[::r],
        multipliers=fine.multipliers[r - 1 :: r],
        iterations=fine.iterations.reshape(n_steps, r).sum(axis=1),
        sensitivities=None if fine.sensitivities is None else fine.sensitivities[::r],
        timings=fine.timings,
        velocities=None if fine.velocities is None else fine.velocities[::r],
        scheme=fine.scheme,
        substeps=r,
    )


def _integrate_uniform(
    model: DiscreteModel,
    q0: np.ndarray,
    p: np.ndarray,
    dt: float,
    n_steps: int,
    *,
    v0: np.ndarray | None,
    sensitivities: bool,
    tolerance: float,
    constraint_tolerance: float,
    max_iterations: int,
    progress: Callable[[int], None] | None,
    scheme: str,
    engine: str,
) -> Trajectory:
    """:func:`integrate` with one uniform step ``dt`` (no refinement)."""
    import time as _time

    n, m = model.ndof, model.nconstraints
    p = np.asarray(p, dtype=float).ravel()
    if p.size != len(model.parameter_names):
        raise ParameterError(
            f"expected {len(model.parameter_names)} parameters ({', '.join(model.parameter_names)}), got {p.size}"
        )
    if not (np.isfinite(dt) and dt > 0):
        raise ParameterError(f"time step dt must be > 0 s; got {dt}")
    q0 = np.asarray(q0, dtype=float).ravel()
    v0 = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).ravel()
    c = model.constants
    g0 = model.functions["constraints"](q0, c)[0]
    g0 = np.asarray(g0).ravel()
    if g0.size and np.max(np.abs(g0)) > 1e-9:
        worst = int(np.argmax(np.abs(g0)))
        raise ParameterError(
            f"initial configuration violates constraint {model.constraint_labels[worst]} by {g0[worst]:.3g}"
        )
    if scheme not in SCHEMES:
        raise ParameterError(f"scheme must be one of {', '.join(SCHEMES)}; got {scheme!r}")
    if engine not in ENGINES:
        raise ParameterError(f"engine must be one of {', '.join(ENGINES)}; got {engine!r}")
    if engine == "compiled" and model.stepper is None:
        raise ParameterError("no compiled stepper for this model (no C compiler, or FUZZYGAIT_NO_COMPILE set); "
                             "use engine='python'")  # fmt: skip
    if engine != "python" and model.stepper is not None:
        return _integrate_compiled(model, q0, v0, p, dt, n_steps, sensitivities, tolerance, constraint_tolerance,
                                   max_iterations, progress, scheme)  # fmt: skip
    energy_momentum = scheme == "energy-momentum"
    assembler = StepAssembler(model, p, dt, sensitivities, scheme)
    velocities = np.empty((n_steps + 1, n)) if energy_momentum else None
    if velocities is not None:
        velocities[0] = v0
    n_p = p.size
    q = np.empty((n_steps + 1, n))
    lam = np.empty((n_steps, m))
    iterations = np.zeros(n_steps, dtype=int)
    factorisations = 0
    sens = np.zeros((n_steps + 1, n, n_p)) if sensitivities else None
    sens_v = np.zeros((n, n_p))  # dv_j/dp of the energy-momentum scheme (v_0 is given)
    q[0] = q0
    timings = {"evaluation": 0.0, "factorisation": 0.0, "solve": 0.0, "sensitivity": 0.0}
    x = np.concatenate([q0 + dt * v0, np.zeros(m)])
    clock = _time.perf_counter
    lu = None

    def factorise(at: np.ndarray):
        nonlocal factorisations
        t0 = clock()
        jacobian = assembler.jacobian(at)
        t1 = clock()
        timings["evaluation"] += t1 - t0
        try:
            factor = splu(jacobian, permc_spec="COLAMD")
        except RuntimeError:  # singular Jacobian
            factor = None
        timings["factorisation"] += clock() - t1
        factorisations += 1
        return factor

    for j in range(n_steps):
        first = j == 0
        q_cur = q[j]
        q_prev = q[j - 1] if j > 0 else q0
        if not first:
            x[:n] = 2 * q[j] - q[j - 1]
            x[n:] = lam[j - 1]
        t0 = clock()
        assembler.begin_step(q_cur, q_prev, first, velocities[j] if velocities is not None else v0)
        timings["evaluation"] += clock() - t0
        if lu is None or first:
            lu = factorise(x)
        # Newton with a kept factorisation (a chord step while it contracts well).  When an
        # update shrinks by less than REFRESH_CONTRACTION: if the previous update came from a
        # stale factorisation, undo it and refactorise there; otherwise refactorise here
        # (full Newton from then on, as long as needed).
        converged = False
        previous = np.inf
        residual = np.full(n + m, np.nan)
        fresh_here = first  # the factorisation was computed at the current x
        last_dx: np.ndarray | None = None
        last_stale = False
        k = 0
        while k < max_iterations and lu is not None:
            t0 = clock()
            residual = assembler.residual(x)
            timings["evaluation"] += clock() - t0
            finite = bool(np.all(np.isfinite(residual)))
            if finite:
                t0 = clock()
                dx = lu.solve(residual)
                timings["solve"] += clock() - t0
                size = float(np.max(np.abs(dx[:n])))
                finite = np.isfinite(size)
            if not finite or size > REFRESH_CONTRACTION * previous:
                if last_stale and last_dx is not None:
                    x += last_dx  # undo the chord step that went astray
                elif fresh_here or not finite:
                    break  # a fresh Newton step diverged or left the domain
                lu = factorise(x)
                fresh_here, last_dx, last_stale, previous = True, None, False, np.inf
                continue
            if size > MAX_UPDATE:  # damped Newton: never jump further than MAX_UPDATE per iteration
                dx *= MAX_UPDATE / size
            x -= dx
            k += 1
            last_dx, last_stale, fresh_here = dx, not fresh_here, False
            if size <= tolerance * (1.0 + float(np.max(np.abs(x[:n])))) and (
                np.max(np.abs(residual[n:]), initial=0.0) <= constraint_tolerance or size == 0.0
            ):
                converged = True
                break
            previous = size
        if converged:
            g_check = assembler.residual(x)[n:]
            converged = np.max(np.abs(g_check), initial=0.0) <= max(constraint_tolerance, 1e3 * tolerance)
        if not converged:
            with np.errstate(all="ignore"):
                norm = float(np.linalg.norm(residual)) if np.all(np.isfinite(residual)) else float("nan")
            raise _not_converged(model, j, dt, norm, k, p)
        q[j + 1] = x[:n]
        lam[j] = x[n:]
        iterations[j] = k
        _check_folding(model, q[j + 1], (j + 1) * dt, p)
        if velocities is not None:
            velocities[j + 1] = 2.0 * (q[j + 1] - q[j]) / dt - velocities[j]
        if sens is not None:
            t0 = clock()
            exact = factorise(x)  # the Jacobian at the converged step
            if energy_momentum:  # velocity sensitivities dv_j/dp ride along
                s_prev = sens_v
            else:
                s_prev = sens[j - 1] if j > 0 else sens[0]
            rhs = assembler.sensitivity_rhs(x, sens[j], s_prev)
            sens[j + 1] = -exact.solve(np.vstack([rhs, np.zeros((m, n_p))]))[:n]
            if energy_momentum:
                sens_v = 2.0 * (sens[j + 1] - sens[j]) / dt - sens_v
            # the Newton path keeps its own factorisation: trajectories are bit-identical with and without sensitivities
            timings["sensitivity"] += clock() - t0
        if progress is not None:
            progress(j + 1)
    timings["factorisations"] = float(factorisations)
    return Trajectory(
        times=np.arange(n_steps + 1) * dt,
        q=q,
        multipliers=lam,
        iterations=iterations,
        sensitivities=sens,
        timings=timings,
        velocities=velocities,
        scheme=scheme,
    )
