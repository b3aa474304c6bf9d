"""The simulator's solver settings and its typed failures.

:class:`SolverSettings` is everything the time integration (:func:`.integrator.integrate`)
is run with — time step, simulated time, scheme, Newton tolerances and limits, step
refinement and engine — as one frozen, picklable value.  The scenario presets give theirs
(:attr:`.presets.ScenarioPreset.solver`); a caller derives variations with
:meth:`SolverSettings.derive`.

A failed run raises a :class:`SolverError` (a :class:`~fuzzygait.core.errors.SimulationError`):
:class:`NewtonNotConverged` or :class:`BladeFolded`, with the step, time and residual (or
fold) as fields, so callers decide by type, not by message text.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass
from typing import Any

from fuzzygait.core.errors import ParameterError, SimulationError

#: Time stepping schemes (:mod:`.schemes`).
SCHEMES = ("variational", "energy-momentum")
#: Newton loops: "auto" (the compiled one where the model has it), "compiled", "python".
ENGINES = ("auto", "compiled", "python")
#: Times :func:`.integrator.integrate` halves the step by default after a step that does not converge.
MAX_HALVINGS = 3
#: Simulated time (s) when neither ``duration`` nor ``n_steps`` is given: the thesis' scenarios' 2 s.
DEFAULT_DURATION = 2.0


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ParameterError(f"solver setting {name} must be a number; got {value!r}")
    return float(value)


def _count(name: str, value: object, least: int, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least:
        raise ParameterError(f"solver setting {name} must be an integer ≥ {least} ({what}); got {value!r}")
    return int(value)


@dataclass(frozen=True)
class SolverSettings:
    """How a simulation is integrated in time (thesis §4.1.2).

    Attributes:
        dt: time step Δt (s), > 0.
        duration: simulated time T (s), ≥ ``dt``; the run takes ``round(duration / dt)``
            steps.  Give it or ``n_steps``, not both; neither: :data:`DEFAULT_DURATION`.
        n_steps: number of steps of size ``dt`` (instead of ``duration``).
        scheme: "variational" (Eq. 4.26) or "energy-momentum" (:data:`SCHEMES`).
        tolerance: Newton stops when its last update is at most this (m for positions,
            1 for unit directors; relative to 1 + the largest coordinate).
        constraint_tolerance: ... and the constraints hold to this (m, or 1 for directors).
        max_iterations: Newton iterations per step at most.
        max_halvings: times the whole run is repeated with half the step after a step
            that does not converge (0: never).
        substeps: sub-steps per ``dt`` to start with (a power of two ≤ 2^max_halvings).
        engine: the Newton loop, one of :data:`ENGINES`.

    Raises:
        ParameterError: an impossible value, naming the field and what to give.
    """

    dt: float = 1e-3
    duration: float | None = None
    n_steps: int | None = None
    scheme: str = "variational"
    tolerance: float = 1e-10
    constraint_tolerance: float = 1e-11
    max_iterations: int = 25
    max_halvings: int = MAX_HALVINGS
    substeps: int = 1
    engine: str = "auto"

    def __post_init__(self) -> None:
        dt = _number("dt", self.dt)
        if not (math.isfinite(dt) and dt > 0):
            raise ParameterError(f"solver setting dt must be a time step > 0 s; got {dt}")
        object.__setattr__(self, "dt", dt)
        if self.duration is not None and self.n_steps is not None:
            raise ParameterError(f"solver settings: give duration ({self.duration} s) or n_steps ({self.n_steps}), "
                                 "not both")  # fmt: skip
        if self.n_steps is not None:
            object.__setattr__(self, "n_steps", _count("n_steps", self.n_steps, 1, "time steps to take"))
        else:
            duration = DEFAULT_DURATION if self.duration is None else _number("duration", self.duration)
            if not (math.isfinite(duration) and duration >= dt):
                raise ParameterError(f"solver setting duration must be ≥ dt ({dt} s); got {duration}: give the "
                                     "simulated time in seconds")  # fmt: skip
            object.__setattr__(self, "duration", duration)
        self._check_choices()
        for name in ("tolerance", "constraint_tolerance"):
            value = _number(name, getattr(self, name))
            if not (math.isfinite(value) and value > 0):
                raise ParameterError(f"solver setting {name} must be > 0; got {value}: give a small positive "
                                     "tolerance such as 1e-10")  # fmt: skip
            object.__setattr__(self, name, value)
        object.__setattr__(self, "max_iterations", _count("max_iterations", self.max_iterations, 1,
                                                          "Newton iterations per step"))  # fmt: skip
        object.__setattr__(self, "max_halvings", _count("max_halvings", self.max_halvings, 0,
                                                        "step halvings after a failed step"))  # fmt: skip
        substeps = self.substeps
        if (isinstance(substeps, bool) or not isinstance(substeps, numbers.Integral) or substeps < 1
                or substeps & (substeps - 1) or substeps > 2**self.max_halvings):  # fmt: skip
            raise ParameterError(f"substeps must be a power of two ≤ 2^max_halvings; got {substeps}")
        object.__setattr__(self, "substeps", int(substeps))

    def _check_choices(self) -> None:
        if self.scheme not in SCHEMES:
            raise ParameterError(f"scheme must be one of {', '.join(SCHEMES)}; got {self.scheme!r}")
        if self.engine not in ENGINES:
            raise ParameterError(f"engine must be one of {', '.join(ENGINES)}; got {self.engine!r}")

    @property
    def steps(self) -> int:
        """Number of time steps of size :attr:`dt`: ``n_steps``, else ``round(duration / dt)``."""
        if self.n_steps is not None:
            return self.n_steps
        assert self.duration is not None
        return int(round(self.duration / self.dt))

    def derive(self, **changes: Any) -> SolverSettings:
        """A copy with ``changes`` (``dataclasses.replace``, validated again); giving
        ``n_steps`` drops the ``duration`` and giving ``duration`` drops the ``n_steps``
        unless both are given."""
        if "n_steps" in changes and "duration" not in changes:
            changes["duration"] = None
        elif "duration" in changes and "n_steps" not in changes:
            changes["n_steps"] = None
        return dataclasses.replace(self, **changes)


class SolverError(SimulationError):
    """A simulation stopped at a time step: ``step`` (1-based, on the grid of the run that
    failed, i.e. of its sub-steps) ending at ``time`` (s)."""

    def __init__(self, message: str, *, step: int, time: float) -> None:
        super().__init__(message)
        self.step = step
        self.time = time

    def _fields(self) -> dict[str, Any]:
        return {"step": self.step, "time": self.time}

    def __reduce__(self) -> tuple[Any, ...]:  # picklable to and from worker processes
        return (_rebuild, (type(self), str(self), self._fields()))

    def with_suffix(self, text: str) -> SolverError:
        """The same error (type and fields) with ``text`` appended to its message."""
        return type(self)(f"{self}{text}", **self._fields())


def _rebuild(cls: type[SolverError], message: str, fields: dict[str, Any]) -> SolverError:
    return cls(message, **fields)


class NewtonNotConverged(SolverError):
    """Newton did not converge within ``max_iterations`` (``iterations`` taken) at a step;
    ``residual``: the norm of the last residual (NaN when not finite)."""

    def __init__(self, message: str, *, step: int, time: float, residual: float, iterations: int) -> None:
        super().__init__(message, step=step, time=time)
        self.residual = residual
        self.iterations = iterations

    def _fields(self) -> dict[str, Any]:
        return {**super()._fields(), "residual": self.residual, "iterations": self.iterations}


class BladeFolded(SolverError):
    """A beam element folded: element ``element`` of group ``group``, its cross-sections
    turned by ``angle`` degrees (> 90°) against each other."""

    def __init__(self, message: str, *, step: int, time: float, group: str, element: int, angle: float) -> None:
        super().__init__(message, step=step, time=time)
        self.group = group
        self.element = element
        self.angle = angle

    def _fields(self) -> dict[str, Any]:
        return {**super()._fields(), "group": self.group, "element": self.element, "angle": self.angle}
