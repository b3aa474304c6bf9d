"""The ideal planar pendulum: the thesis' introductory Graph Follower case (Fig. 2.5).

``θ'' = −(g / L) sin θ`` with ``θ(0) = θ0``, ``θ'(0) = 0``; the target output is the
angle θ (rad) at the time nodes. The sensitivity ``s = ∂θ/∂L`` (rad/m) follows from the
forward sensitivity equation ``s'' = −(g / L) cos θ · s + (g / L²) sin θ``, integrated
together with the motion, so one evaluation with sensitivities is one simulation.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.protocol import SENSITIVITIES, Evaluation, Output

GRAVITY = 9.81  # m/s²


@dataclass
class Pendulum:
    """Pendulum model for the uncertainty engine; the parameter vector is ``[L]`` (m).

    Attributes:
        times: output time nodes in s (starting at 0).
        theta0: initial angle in rad.
        gravity: m/s².
        rtol: relative tolerance of the integrator.
    """

    times: np.ndarray = field(default_factory=lambda: np.linspace(0.0, 2.0, 201))
    theta0: float = 0.5
    gravity: float = GRAVITY
    rtol: float = 1e-10

    def __post_init__(self) -> None:
        times = np.asarray(self.times, dtype=float) if _numeric(self.times) else np.asarray([np.nan])
        if times.ndim != 1 or times.size == 0 or not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
            raise ParameterError(f"pendulum times must be a non-empty 1-D array of finite, strictly increasing "
                                 f"times in s, e.g. np.linspace(0, 2, 201); got {self.times!r}")  # fmt: skip
        for name, value in (("theta0", self.theta0), ("gravity", self.gravity)):
            if not (_numeric(value) and np.ndim(value) == 0 and np.isfinite(value)):
                raise ParameterError(f"pendulum {name} must be a finite number; got {value!r}")
        if not (_numeric(self.rtol) and np.ndim(self.rtol) == 0 and 0 < self.rtol < 1):
            raise ParameterError(f"pendulum rtol must be a relative tolerance between 0 and 1; got {self.rtol!r}")
        self.times = times

    parameter_names = ("L",)
    output = Output("theta", "rad", "pendulum angle")
    capabilities = frozenset({SENSITIVITIES})

    def _solve(self, p: np.ndarray, sensitivities: bool) -> np.ndarray:
        length = float(np.ravel(p)[0])
        if not np.isfinite(length) or length <= 0:
            raise ParameterError(f"pendulum length must be > 0 m; got {length}")
        k = self.gravity / length

        def rhs(_t: float, y: np.ndarray) -> np.ndarray:
            theta, omega = y[0], y[1]
            out = [omega, -k * np.sin(theta)]
            if sensitivities:
                s, ds = y[2], y[3]
                out += [ds, -k * np.cos(theta) * s + k / length * np.sin(theta)]
            return np.array(out)

        y0 = [self.theta0, 0.0] + ([0.0, 0.0] if sensitivities else [])
        times = np.asarray(self.times, dtype=float)
        if times.size == 1:  # the initial state only (solve_ivp returns nothing for an empty span)
            return np.asarray(y0, dtype=float)[:, None]
        solution = solve_ivp(rhs, (times[0], times[-1]), y0, t_eval=times, method="DOP853",
                             rtol=self.rtol, atol=1e-12)  # fmt: skip
        if not solution.success:
            raise ParameterError(f"pendulum integration failed for L={length} m: {solution.message}")
        return solution.y

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        """θ(t) in rad at the time nodes; with ``sensitivities`` also ∂θ/∂L ``(n_time, 1)``
        in rad/m (integrated together with the motion: one simulation)."""
        y = self._solve(p, sensitivities=sensitivities)
        return Evaluation(y[0], y[2][:, None] if sensitivities else None)


def _numeric(value: object) -> bool:
    """Whether ``value`` is a number or an array of numbers (not a string, a bool or None)."""
    return not isinstance(value, (str, bytes, bool)) and np.asarray(value).dtype.kind in "iuf"
