"""FRV sample generation (thesis §2.7.1–2.7.2, Eqs. 2.20, 2.26–2.30): the fuzzy random
parameter :class:`FRVSpec` and its fuzzy-number samples, each ``N_α`` α-cuts ``[left,
right]`` in the parameter's units."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy import stats

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.fuzzy import _as_levels

#: Samples per random stream: sample ``i`` is drawn from ``default_rng([seed, i // BLOCK])``
#: so it is the same whatever blocks the samples are requested in.
BLOCK = 1024
DISTRIBUTIONS = ("normal", "beta")
#: How the peaks are drawn: independently, or Latin-hypercube stratified per block (§2.7.5).
SAMPLINGS = ("random", "lhs")


@dataclass(frozen=True)
class FRVSpec:
    """A fuzzy random parameter (thesis §2.7.1, Table 5.3).

    Attributes:
        name: parameter name.
        deterministic: ``p_det``, the deterministic value (non-zero: it sets the scale).
        relative_scale: the 0.1 of Eqs. 2.28–2.29; increments scale with
            ``relative_scale·|p_det|``.
        alphas: increasing α-levels, the last one 1 (at least two levels).
        distribution: ``"normal"`` (thesis §2.7.2, increments redrawn while ≤ 0) or
            ``"beta"`` (§5.7.2: beta-distributed increments, normal peak).
        mean, std: the normal distribution ``N(mean, std)`` of the peak draw (both
            distributions) and of the increments (``"normal"``); the thesis uses N(1, 1).
        beta_a, beta_b: shape parameters of the increments' beta distribution.
        sampling: ``"random"`` (independent peak draws, the thesis') or ``"lhs"``
            (Latin-hypercube peaks, thesis §2.7.5: within every block of :data:`BLOCK`
            samples each of ``BLOCK`` equal-probability strata of the peak distribution
            holds exactly one peak; with several FRVs each parameter's strata are
            permuted independently, so every full block is a Latin hypercube).
    """

    name: str
    deterministic: float
    relative_scale: float = 0.1
    alphas: tuple[float, ...] = (0.0, 0.5, 1.0)
    distribution: str = "normal"
    mean: float = 1.0
    std: float = 1.0
    beta_a: float = 2.0
    beta_b: float = 2.0
    sampling: str = "random"

    def __post_init__(self) -> None:
        label = f"FRV {self.name!r}"
        levels = _as_levels(self.alphas)
        if levels[-1] != 1.0 or levels.size < 2:
            raise ParameterError(f"{label}: alphas must end with 1 and have a level below it; got {levels.tolist()}")
        object.__setattr__(self, "alphas", tuple(float(a) for a in levels))
        names = ("deterministic", "relative_scale", "mean", "std", "beta_a", "beta_b")
        values = {k: float(getattr(self, k)) for k in names}
        if not all(math.isfinite(v) for v in values.values()):
            raise ParameterError(f"{label}: parameters must be finite; got {values}")
        if values["deterministic"] == 0.0:
            raise ParameterError(
                f"{label}: deterministic value must be non-zero (it sets the increments' scale, Eq. 2.28)"
            )
        if values["relative_scale"] <= 0 or values["std"] <= 0:
            raise ParameterError(
                f"{label}: relative_scale and std must be > 0; got {values['relative_scale']}, {values['std']}"
            )
        if self.distribution not in DISTRIBUTIONS:
            raise ParameterError(f"{label}: distribution must be 'normal' or 'beta'; got {self.distribution!r}")
        if self.sampling not in SAMPLINGS:
            raise ParameterError(f"{label}: sampling must be 'random' or 'lhs'; got {self.sampling!r}")
        if values["beta_a"] <= 0 or values["beta_b"] <= 0:
            raise ParameterError(f"{label}: beta_a and beta_b must be > 0")
        if self.distribution == "normal" and values["mean"] / values["std"] < -3.0:
            raise ParameterError(
                f"{label}: increments N({values['mean']}, {values['std']}) are positive in under 0.2 % of draws; "
                "the redraw (Eq. 2.21) would hardly terminate — use mean/std >= -3"
            )
        for key, value in values.items():
            object.__setattr__(self, key, value)

    @property
    def scale(self) -> float:
        """``relative_scale·|p_det|``: the Δp of one unit of the drawn value (Eq. 2.28)."""
        return self.relative_scale * abs(self.deterministic)

    @property
    def n_alpha_divisor(self) -> int:
        """``N_α`` of Eq. 2.29: the number of α-levels below 1 (= increments per side)."""
        return len(self.alphas) - 1

    @property
    def increment_scale(self) -> float:
        """``relative_scale·|p_det|/N_α`` (Eq. 2.29)."""
        return self.scale / self.n_alpha_divisor

    def peak_distribution(self) -> Any:
        """The peak's distribution ``N(p_det + mean·s, (std·s)²)``, ``s`` = :attr:`scale`."""
        return stats.norm(self.deterministic + self.mean * self.scale, self.std * self.scale)

    def increment_distribution(self) -> Any:
        """The distribution of every increment ``Δp_{l/r, α<1}``: the normal truncated to
        positive values (what redrawing yields) or the scaled beta."""
        c = self.increment_scale
        if self.distribution == "beta":
            return stats.beta(self.beta_a, self.beta_b, loc=0.0, scale=c)
        return stats.truncnorm(-self.mean / self.std, np.inf, loc=self.mean * c, scale=self.std * c)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["alphas"] = list(self.alphas)
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> FRVSpec:
        return cls(**{**data, "alphas": tuple(data["alphas"])})


def _whole(value: object, name: str, minimum: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) < minimum:
        raise ParameterError(f"{name} must be a whole number >= {minimum}; got {value!r}")
    return int(value)


def _stream_seed(seed: int, block: int, stream: int) -> list[int]:
    """The entropy of block ``block`` of parameter stream ``stream``: ``[seed, block]`` for
    stream 0 (the one-parameter stream, unchanged), ``[seed, block, stream]`` otherwise."""
    return [seed, block] if stream == 0 else [seed, block, stream]


def _sample_block(spec: FRVSpec, seed: int, block: int, stream: int = 0) -> np.ndarray:
    """The ``BLOCK`` samples of block ``block`` (see :func:`generate_samples`)."""
    rng = np.random.default_rng(_stream_seed(seed, block, stream))
    if spec.sampling == "lhs":  # one peak per equal-probability stratum of N(mean, std)
        u = rng.uniform(size=BLOCK)
        u[u == 0.0] = 0.5  # inside the stratum: ppf stays finite
        z = stats.norm.ppf((rng.permutation(BLOCK) + u) / BLOCK)
        peak = spec.deterministic + (spec.mean + spec.std * z) * spec.scale
    else:
        peak = spec.deterministic + rng.normal(spec.mean, spec.std, BLOCK) * spec.scale  # Eq. 2.28
    shape = (BLOCK, spec.n_alpha_divisor, 2)
    if spec.distribution == "beta":
        drawn = rng.beta(spec.beta_a, spec.beta_b, shape)
    else:
        drawn = rng.normal(spec.mean, spec.std, shape)
        while True:  # redraw non-positive increments (convexity, Eq. 2.21); terminates (mean/std >= -3)
            bad = drawn <= 0.0
            count = int(np.count_nonzero(bad))
            if not count:
                break
            drawn[bad] = rng.normal(spec.mean, spec.std, count)
    delta = drawn * spec.increment_scale  # Eq. 2.29; delta[:, 0] is the step below α = 1
    n_alpha = len(spec.alphas)
    cuts = np.empty((BLOCK, n_alpha, 2))
    cuts[:, -1, :] = peak[:, None]
    for step, k in enumerate(range(n_alpha - 2, -1, -1)):  # Eq. 2.30, from α = 1 downwards
        cuts[:, k, 0] = cuts[:, k + 1, 0] - delta[:, step, 0]
        cuts[:, k, 1] = cuts[:, k + 1, 1] + delta[:, step, 1]
    return cuts


def generate_samples(spec: FRVSpec, n: int, seed: int = 0, start: int = 0, stream: int = 0) -> np.ndarray:
    """Samples ``start … start+n−1`` of the FRV (thesis Eqs. 2.26–2.30).

    Each sample is a fuzzy number built from its peak downwards:

    * peak (Eq. 2.28, implemented as printed): ``p_peak = p_det + X·s`` with
      ``X ~ N(mean, std)`` and ``s = relative_scale·|p_det|``. With the thesis' N(1, 1)
      the peak is *shifted* by one ``s`` on average: ``p_peak ~ N(p_det + mean·s, (std·s)²)``.
      With ``spec.sampling == "lhs"`` the same distribution, Latin-hypercube stratified
      per block: ``X = mean + std·Φ⁻¹((π_i + U_i)/BLOCK)``, ``π`` a random permutation of
      the block's ``0 … BLOCK−1``, ``U_i ~ U(0, 1)``.
      (``|p_det|`` makes the scale a magnitude; the thesis' ``p_det`` is positive.)
    * increments (Eq. 2.29): ``Δ = X·s/N_α`` for every α-level below 1 and each side, with
      ``N_α`` the number of α-levels *below 1* (the number of increments per side), so
      the expected α = 0 half-width ``E[X]·s`` does not depend on how many α-levels are
      used — the purpose the thesis gives for the division. ``"normal"``: ``X ~ N(mean,
      std)`` redrawn while ``X ≤ 0`` (the truncation of §2.7.2); ``"beta"``:
      ``X ~ Beta(a, b)`` in [0, 1], no redraw needed (§5.7.2).
    * α-cuts (Eq. 2.30): ``p_{l,k−1} = p_{l,k} − Δ_l``, ``p_{r,k−1} = p_{r,k} + Δ_r``.

    Sample ``i`` is a function of ``(spec, seed, i)`` only: it is taken from block
    ``i // BLOCK`` generated with ``np.random.default_rng([seed, i // BLOCK])``, so two
    calls ``(start=0, n=a)`` and ``(start=a, n=b)`` give the samples of one call ``n=a+b``.
    ``stream`` numbers independent streams of one seed (the parameter index of a study of
    several FRVs, :func:`generate_box_samples`): stream ``k > 0`` seeds its blocks with
    ``[seed, i // BLOCK, k]``; stream 0 is the one-parameter stream above.

    Returns:
        ``(n, n_alpha, 2)``: per sample and α-level (in ``spec.alphas`` order) the α-cut
        ``[left, right]``; the α = 1 cut is ``[peak, peak]``.
    """
    n, start, seed = _whole(n, "n"), _whole(start, "start"), _whole(seed, "seed")
    stream = _whole(stream, "stream")
    out = np.empty((n, len(spec.alphas), 2))
    stop = start + n
    for block in range(start // BLOCK, (stop - 1) // BLOCK + 1 if n else start // BLOCK):
        first = block * BLOCK
        a, b = max(start, first), min(stop, first + BLOCK)
        out[a - start : b - start] = _sample_block(spec, seed, block, stream)[a - first : b - first]
    return out


def check_specs(specs: FRVSpec | Sequence[FRVSpec]) -> tuple[FRVSpec, ...]:
    """The FRV parameters of a study as a tuple: at least one, distinct names, one set of
    α-levels (a sample's α-cut is a box, one interval per parameter at each level)."""
    out = (specs,) if isinstance(specs, FRVSpec) else tuple(specs)
    if not out or not all(isinstance(s, FRVSpec) for s in out):
        raise ParameterError(f"give one FRVSpec per FRV parameter; got {specs!r}")
    names = [s.name for s in out]
    if len(set(names)) != len(names):
        raise ParameterError(f"FRV parameters must have distinct names; got {names}")
    if any(s.alphas != out[0].alphas for s in out):
        raise ParameterError(f"all FRV parameters need the same α-levels; got {[list(s.alphas) for s in out]}")
    return out


def generate_box_samples(specs: Sequence[FRVSpec], n: int, seed: int = 0, start: int = 0) -> np.ndarray:
    """Samples ``start … start+n−1`` of independent FRVs (one :func:`generate_samples`
    stream per parameter: parameter ``k`` is stream ``k``, so parameter 0 draws exactly
    the samples of a one-parameter study with the same seed).

    Returns:
        ``(n, n_params, n_alpha, 2)``: per sample, parameter and α-level the α-cut
        ``[left, right]`` in that parameter's units; at each α the sample's α-cut is the
        box of its ``n_params`` intervals.
    """
    specs = check_specs(specs)
    return np.stack([generate_samples(s, n, seed, start, stream=k) for k, s in enumerate(specs)], axis=1)


def sample_increments(samples: np.ndarray) -> np.ndarray:
    """The l_α r_α-increments of fuzzy-number samples (Eq. 2.20).

    Args:
        samples: ``(..., n_alpha, 2)`` α-cuts ``[left, right]``, α increasing.

    Returns:
        ``(..., n_alpha, 2)``: for α_k < 1 ``left(α_{k+1}) − left(α_k)`` and
        ``right(α_k) − right(α_{k+1})`` (both ≥ 0 for a convex number); at α = 1 the peak
        (the α = 1 left end, both bounds) — the ``Δp_{α=1}`` entry of Eq. 2.26.
    """
    samples = np.asarray(samples, dtype=float)
    out = np.empty_like(samples)
    out[..., :-1, 0] = samples[..., 1:, 0] - samples[..., :-1, 0]
    out[..., :-1, 1] = samples[..., :-1, 1] - samples[..., 1:, 1]
    out[..., -1, :] = samples[..., -1, 0, None]
    return out
