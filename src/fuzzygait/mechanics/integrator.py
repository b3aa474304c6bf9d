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
from time import perf_counter as clock

import numpy as np
from scipy.sparse.linalg import splu

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics import native
from fuzzygait.mechanics.discrete import DiscreteModel
from fuzzygait.mechanics.schemes import StepAssembler
from fuzzygait.mechanics.solver import (
    ENGINES,
    MAX_HALVINGS,
    SCHEMES,
    BladeFolded,
    NewtonNotConverged,
    SolverError,
    SolverSettings,
)
from fuzzygait.mechanics.step_functions import group_constants
from fuzzygait.mechanics.trajectory import Trajectory

__all__ = ["ENGINES", "MAX_HALVINGS", "SCHEMES", "SolverSettings", "integrate"]

# Newton keeps its LU factorisation across iterations and steps and refreshes it when an
# update shrinks by less than this factor (linear convergence too slow to be worth it).
REFRESH_CONTRACTION = 0.25
# Largest Newton update of any coordinate per iteration (m for positions, 1 for directors);
# a time step of a few ms never moves a coordinate this far, so larger updates are divergence.
MAX_UPDATE = 0.2

FOLD_COSINE = 0.0  # adjacent beam cross-sections turned by more than 90° = a folded element


def _check_folding(model: DiscreteModel, q: np.ndarray, step: int, t: float, p: np.ndarray) -> None:
    """Raise :class:`BladeFolded` when a beam element has folded at ``step`` (time ``t``): its
    two nodes' tangent directors d3 turned by more than 90° against each other.  The
    midpoint element then averages the directors to nearly zero and can stretch at almost no
    energy cost — a discretisation artefact, so the run stops instead of returning a
    physically meaningless motion."""
    for group in model.groups:
        dofs = group.dofs
        cosine = np.einsum("ek,ek->e", q[dofs[:, 9:12]], q[dofs[:, 21:24]])
        worst = int(np.argmin(cosine))
        if cosine[worst] < FOLD_COSINE:
            raise _folded(model, (group.name, worst), float(cosine[worst]), step, t, p)


def _folded(model: DiscreteModel, where: tuple[str, int], cosine: float, step: int, t: float,
            p: np.ndarray) -> BladeFolded:  # fmt: skip
    group, element = where
    angle = float(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))))
    return BladeFolded(
        f"{group} element {element} folded at t = {t:.4f} s: its cross-sections turned by "
        f"{angle:.0f}° (> 90°) within one element; parameters {_describe(model.parameter_names, p)}; "
        "use more nodes, a stiffer blade or more damping (eta)",
        step=step, time=t, group=group, element=element, angle=angle,
    )  # fmt: skip


def _not_converged(model: DiscreteModel, step: int, dt: float, norm: float, iterations: int,
                   p: np.ndarray) -> NewtonNotConverged:  # fmt: skip
    """``step``: the 0-based index of the step that failed."""
    t = (step + 1) * dt
    return NewtonNotConverged(
        f"Newton did not converge at t = {t:.4f} s (step {step + 1}, dt = {dt:g} s): "
        f"residual norm {norm:.3g} after {iterations} iterations; parameters {_describe(model.parameter_names, p)}; "
        "try a smaller dt, more damping (eta) or the energy-momentum scheme",
        step=step + 1, time=t, residual=norm, iterations=iterations,
    )  # fmt: skip


def _integrate_compiled(model: DiscreteModel, q0: np.ndarray, v0: np.ndarray, p: np.ndarray,
                        settings: SolverSettings, sensitivities: bool,
                        progress: Callable[[int], None] | None) -> Trajectory:  # fmt: skip
    """:func:`integrate` by the compiled loop (:func:`.native.run`), one uniform step."""
    assert model.stepper is not None
    pair_a = np.concatenate([g.dofs[:, 9] for g in model.groups]) if model.groups else np.zeros(0, dtype=int)
    pair_b = np.concatenate([g.dofs[:, 21] for g in model.groups]) if model.groups else np.zeros(0, dtype=int)
    starts = np.cumsum([0] + [len(g.dofs) for g in model.groups])
    problem = native.NativeProblem(
        n=model.ndof, m=model.nconstraints, p=p, constants=model.constants,
        group_constants=group_constants(model.groups), fold_pairs=(pair_a, pair_b, starts),
    )  # fmt: skip
    result = native.run(model.stepper, problem, q0, v0, settings, sensitivities=sensitivities, progress=progress)
    dt, n_steps = settings.dt, settings.steps
    stopped = result.stopped
    if stopped is not None and stopped.kind == "fold":
        group = int(np.searchsorted(starts, stopped.index, side="right") - 1)
        raise _folded(model, (model.groups[group].name, stopped.index - int(starts[group])), stopped.value,
                      stopped.step + 1, (stopped.step + 1) * dt, p)  # fmt: skip
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
        scheme=settings.scheme,
    )


def _describe(parameter_names: Sequence[str], p: np.ndarray) -> str:
    return ", ".join(f"{name}={value:.6g}" for name, value in zip(parameter_names, p))


def integrate(
    model: DiscreteModel,
    q0: np.ndarray,
    v0: np.ndarray | None,
    p: np.ndarray,
    settings: SolverSettings,
    *,
    sensitivities: bool = False,
    progress: Callable[[int], None] | None = None,
) -> Trajectory:
    """Integrate ``settings.steps`` steps of size ``settings.dt`` (s) from ``q0`` with
    velocity ``v0`` (None: at rest) for the parameter vector ``p``.

    ``settings.scheme`` "variational": the variational integrator of Eq. 4.26.
    "energy-momentum": the one-step midpoint scheme with the discrete-gradient beam force and
    ``G(q_{j+½})ᵀλ`` (Betsch & Steinmann): energy is conserved exactly without damping and
    the damped balance ``E_0 = E_j + D_j`` holds to the Newton tolerance.  Both give
    sensitivities (``sensitivities=True``: ``dq/dp`` in the trajectory).

    Newton stops when the last update is ≤ ``settings.tolerance`` (m, unit directors) and the
    constraints hold to ``settings.constraint_tolerance``.  Raises :class:`NewtonNotConverged`
    (a :class:`~fuzzygait.core.errors.SimulationError`) naming the time, the residual norm
    and the parameter values when a step does not converge, :class:`BladeFolded` when a beam
    element folds.

    ``settings.engine``: "compiled" runs the whole Newton loop in C (:mod:`.native`; the
    model's ``stepper`` library), "python" the loop below over the compiled kernels, "auto"
    the compiled loop where the model has one.  Both solve the same equations with the same
    iteration; trajectories agree to the Newton tolerance.

    Step refinement: when a step does not converge (at dt = 1 ms the midpoint-type
    variational integrator turns unstable for a stiff blade's unresolved high modes — the
    energy grows by orders of magnitude within a few steps before Newton fails, so the
    state there is already wrong), the whole run is repeated with ``dt/2`` sub-steps, up to
    ``settings.max_halvings`` times.  Every accepted step of the repeated run solves the
    scheme's step equations (for the variational integrator the discrete Euler–Lagrange
    equations with the uniform step ``dt/2^r``); the returned trajectory holds the time
    nodes ``k·dt`` of the original grid, its ``iterations`` the Newton iterations summed over
    each node's sub-steps and ``substeps`` = 2^r.  A folded element is not retried (the fold
    is the blade's motion, not the time step's).  ``settings.substeps``: start with that many
    sub-steps per ``dt`` (a caller's own acceptance test, e.g.
    :class:`.scenarios.LegSimulator`'s energy balance, asks for more).
    """
    dt, n_steps, substeps = settings.dt, settings.steps, settings.substeps
    while True:
        fine = settings.derive(dt=dt / substeps, n_steps=n_steps * substeps, substeps=1)
        try:
            trajectory = _integrate_uniform(model, q0, v0, p, fine, sensitivities,
                                            None if progress is None else _coarse_progress(progress, substeps))
        except SolverError as error:
            if isinstance(error, NewtonNotConverged) and substeps < 2**settings.max_halvings:
                substeps *= 2
                continue
            if substeps > 1:
                raise error.with_suffix(f" (with {substeps} sub-steps per dt = {dt:g} s)") from None
            raise
        return trajectory if substeps == 1 else _coarsen(trajectory, substeps)


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


def _integrate_uniform(model: DiscreteModel, q0: np.ndarray, v0: np.ndarray | None, p: np.ndarray,
                       settings: SolverSettings, sensitivities: bool,
                       progress: Callable[[int], None] | None) -> Trajectory:  # fmt: skip
    """:func:`integrate` with one uniform step ``settings.dt`` (no refinement)."""
    p, q0, v0_ = _checked_inputs(model, q0, v0, p, settings.engine)
    if settings.engine != "python" and model.stepper is not None:
        return _integrate_compiled(model, q0, v0_, p, settings, sensitivities, progress)
    return _PythonLoop(model, p, settings, sensitivities).run(q0, v0_, progress)


def _checked_inputs(model: DiscreteModel, q0: np.ndarray, v0: np.ndarray | None, p: np.ndarray,
                    engine: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """``p``, ``q0`` and ``v0`` as flat float arrays (v0 None: zeros), or a ParameterError
    for a parameter vector of the wrong size, an initial configuration off its constraints
    or the compiled engine asked for where there is none."""
    p = np.asarray(p, dtype=float).ravel()
    if p.size != len(model.parameter_names):
        raise ParameterError(
            f"expected {len(model.parameter_names)} parameters ({', '.join(model.parameter_names)}), got {p.size}"
        )
    q0 = np.asarray(q0, dtype=float).ravel()
    v0 = np.zeros(model.ndof) if v0 is None else np.asarray(v0, dtype=float).ravel()
    g0 = model.functions["constraints"](q0, model.constants)[0]
    g0 = np.asarray(g0).ravel()
    if g0.size and np.max(np.abs(g0)) > 1e-9:
        worst = int(np.argmax(np.abs(g0)))
        raise ParameterError(
            f"initial configuration violates constraint {model.constraint_labels[worst]} by {g0[worst]:.3g}"
        )
    if engine == "compiled" and model.stepper is None:
        raise ParameterError("no compiled stepper for this model (no C compiler, or FUZZYGAIT_NO_COMPILE set); "
                             "use engine='python'")  # fmt: skip
    return p, q0, v0


class _PythonLoop:
    """The Newton loop of :func:`integrate` in Python over the model's kernels: one run of
    uniform steps ``settings.dt``, its sparse LU kept across iterations and steps."""

    def __init__(self, model: DiscreteModel, p: np.ndarray, settings: SolverSettings, sensitivities: bool) -> None:
        self.model, self.p, self.settings = model, p, settings
        self.assembler = StepAssembler(model, p, settings.dt, sensitivities, settings.scheme)
        self.sensitivities = sensitivities
        self.energy_momentum = settings.scheme == "energy-momentum"
        self.timings = {"evaluation": 0.0, "factorisation": 0.0, "solve": 0.0, "sensitivity": 0.0}
        self.factorisations = 0
        self.lu = None

    def factorise(self, at: np.ndarray):
        """The LU of the step Jacobian at ``at`` (None: singular)."""
        t0 = clock()
        jacobian = self.assembler.jacobian(at)
        t1 = clock()
        self.timings["evaluation"] += t1 - t0
        try:
            factor = splu(jacobian, permc_spec="COLAMD")
        except RuntimeError:  # singular Jacobian
            factor = None
        self.timings["factorisation"] += clock() - t1
        self.factorisations += 1
        return factor

    def run(self, q0: np.ndarray, v0: np.ndarray, progress: Callable[[int], None] | None) -> Trajectory:
        model, p, dt, n_steps = self.model, self.p, self.settings.dt, self.settings.steps
        n, m = model.ndof, model.nconstraints
        velocities = np.empty((n_steps + 1, n)) if self.energy_momentum else None
        if velocities is not None:
            velocities[0] = v0
        q = np.empty((n_steps + 1, n))
        lam = np.empty((n_steps, m))
        iterations = np.zeros(n_steps, dtype=int)
        sens = np.zeros((n_steps + 1, n, p.size)) if self.sensitivities else None
        sens_v = np.zeros((n, p.size))  # dv_j/dp of the energy-momentum scheme (v_0 is given)
        q[0] = q0
        x = np.concatenate([q0 + dt * v0, np.zeros(m)])
        for j in range(n_steps):
            first = j == 0
            if not first:
                x[:n] = 2 * q[j] - q[j - 1]
                x[n:] = lam[j - 1]
            t0 = clock()
            self.assembler.begin_step(q[j], q[j - 1] if j > 0 else q0, first,
                                      velocities[j] if velocities is not None else v0)  # fmt: skip
            self.timings["evaluation"] += clock() - t0
            if self.lu is None or first:
                self.lu = self.factorise(x)
            iterations[j] = self.newton(x, j, first)
            q[j + 1] = x[:n]
            lam[j] = x[n:]
            _check_folding(model, q[j + 1], j + 1, (j + 1) * dt, p)
            if velocities is not None:
                velocities[j + 1] = 2.0 * (q[j + 1] - q[j]) / dt - velocities[j]
            if sens is not None:
                sens_v = self.sensitivity_step(x, sens, sens_v, j)
            if progress is not None:
                progress(j + 1)
        self.timings["factorisations"] = float(self.factorisations)
        return Trajectory(times=np.arange(n_steps + 1) * dt, q=q, multipliers=lam, iterations=iterations,
                          sensitivities=sens, timings=self.timings, velocities=velocities,
                          scheme=self.settings.scheme)  # fmt: skip

    def newton(self, x: np.ndarray, j: int, first: bool) -> int:
        """Solve step ``j`` for ``x`` (updated in place) and return the iterations taken, or
        raise :class:`NewtonNotConverged`.

        Newton with a kept factorisation (a chord step while it contracts well).  When an
        update shrinks by less than REFRESH_CONTRACTION: if the previous update came from a
        stale factorisation, undo it and refactorise there; otherwise refactorise here
        (full Newton from then on, as long as needed)."""
        n, m = self.model.ndof, self.model.nconstraints
        tolerance, constraint_tolerance = self.settings.tolerance, self.settings.constraint_tolerance
        converged = False
        previous = np.inf
        residual = np.full(n + m, np.nan)
        fresh_here = first  # the factorisation was computed at the current x
        last_dx: np.ndarray | None = None
        last_stale = False
        k = 0
        while k < self.settings.max_iterations and self.lu is not None:
            t0 = clock()
            residual = self.assembler.residual(x)
            self.timings["evaluation"] += clock() - t0
            finite = bool(np.all(np.isfinite(residual)))
            if finite:
                t0 = clock()
                dx = self.lu.solve(residual)
                self.timings["solve"] += clock() - t0
                size = float(np.max(np.abs(dx[:n])))
                finite = np.isfinite(size)
            if not finite or size > REFRESH_CONTRACTION * previous:
                if last_stale and last_dx is not None:
                    x += last_dx  # undo the chord step that went astray
                elif fresh_here or not finite:
                    break  # a fresh Newton step diverged or left the domain
                self.lu = self.factorise(x)
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
            g_check = self.assembler.residual(x)[n:]
            converged = np.max(np.abs(g_check), initial=0.0) <= max(constraint_tolerance, 1e3 * tolerance)
        if not converged:
            with np.errstate(all="ignore"):
                norm = float(np.linalg.norm(residual)) if np.all(np.isfinite(residual)) else float("nan")
            raise _not_converged(self.model, j, self.settings.dt, norm, k, self.p)
        return k

    def sensitivity_step(self, x: np.ndarray, sens: np.ndarray, sens_v: np.ndarray, j: int) -> np.ndarray:
        """``sens[j + 1] = dq_{j+1}/dp`` from the converged step ``x``; returns the velocity
        sensitivities ``dv_{j+1}/dp`` of the energy-momentum scheme (else ``sens_v`` as given)."""
        n, m, dt = self.model.ndof, self.model.nconstraints, self.settings.dt
        t0 = clock()
        exact = self.factorise(x)  # the Jacobian at the converged step
        if self.energy_momentum:  # velocity sensitivities dv_j/dp ride along
            s_prev = sens_v
        else:
            s_prev = sens[j - 1] if j > 0 else sens[0]
        rhs = self.assembler.sensitivity_rhs(x, sens[j], s_prev)
        sens[j + 1] = -exact.solve(np.vstack([rhs, np.zeros((m, self.p.size))]))[:n]
        if self.energy_momentum:
            sens_v = 2.0 * (sens[j + 1] - sens[j]) / dt - sens_v
        # the Newton path keeps its own factorisation: trajectories are bit-identical with and without sensitivities
        self.timings["sensitivity"] += clock() - t0
        return sens_v
