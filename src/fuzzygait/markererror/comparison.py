"""The comparison methods of thesis Fig. 5.11: fixed marker deviations and random
(Monte Carlo) marker deviations, against which the fuzzy envelopes of
:func:`fuzzygait.markererror.analysis.fuzzy_joint_angles` are judged (§5.5).

All three methods use the same spherical error model (Eq. 3.1): marker ``i`` may lie
anywhere in the ball of radius ``Σ_i`` (mm) around its measured position.

* :func:`fixed_deviation_curves` (Fig. 5.11 a): the angle with no deviation, with every
  marker displaced by ``+Σ_i`` and with every marker displaced by ``−Σ_i``. The thesis
  does not say in which direction "the largest positive/negative deviation" points; here
  it is the lab-frame unit diagonal ``(1, 1, 1)/√3`` — the one direction in which every
  coordinate of every marker moves by the same positive (negative) amount,
  ``Σ_i/√3`` mm, and the deviation still lies on the ball's surface (``‖p_i‖ = Σ_i``).
  Note that any common direction makes this close to a rigid translation of all
  markers (exactly one where the radii are equal), which joint angles do not see: only
  the differences between the radii (e.g. 32 mm thigh vs 20 mm ankle) move the curves.
  That is the thesis' point about Fig. 5.11 (a) — fixed errors do not depict what
  marker errors can do to an angle.
* :func:`monte_carlo_envelope` (Fig. 5.11 b): uniform random deviations inside the
  balls; the lowest and highest angle met per frame. Random sampling can only find
  values the true range contains, so its envelope is an inner bound of the true range —
  as is the Graph Follower's (a local optimiser), which should nevertheless reach
  further than any affordable sample.
* :func:`deviation_norms` (Fig. 5.12): the norms of the extremising marker deviations
  stored in the fuzzy-angle Dataset.

The models are :class:`~fuzzygait.markererror.angle_model.JointAngleModel` or anything
with ``times``, ``evaluate(p)`` and ``evaluate_nodes(P, nodes)`` whose parameters are
3 lab-frame coordinates (mm) per marker.
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from numbers import Integral

import numpy as np
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.markererror.result import angle_components, component_deviation
from fuzzygait.uncertainty.protocol import NodeModel

#: The fixed-deviation direction of Fig. 5.11 (a): the unit diagonal of the lab frame.
DIAGONAL = np.ones(3) / np.sqrt(3.0)

#: Rows (deviation, frame pairs) per ``evaluate_nodes`` call at most: a Plug-in Gait
#: row needs about 1 kB of temporaries (measured: +53 MB peak for the 9-marker ankle
#: model), so this bounds the extra memory to some 50 MB.
DEFAULT_CHUNK_ROWS = 50_000


def _radii(model: NodeModel, radii: Sequence[float] | np.ndarray) -> np.ndarray:
    """Validated per-marker radii (mm) matching the model's parameter vector."""
    r = np.asarray(radii, dtype=float).ravel()
    n_p = _n_parameters(model)
    if n_p % 3 or r.size != n_p // 3:
        raise ParameterError(f"one radius per marker needed: the model has {n_p} parameters, got {r.size} radii")
    if np.any(r < 0) or not np.all(np.isfinite(r)):
        raise ParameterError(f"radii must be finite and >= 0 mm; got {r.tolist()}")
    return r


def _n_parameters(model: NodeModel) -> int:
    n_p = getattr(model, "n_parameters", None)
    if n_p is None:
        markers = getattr(model, "markers", None)
        if markers is None:
            raise ParameterError("the model must say its size: `n_parameters` or `markers`")
        n_p = 3 * len(markers)
    return int(n_p)


def fixed_deviation_curves(model: NodeModel, radii: Sequence[float] | np.ndarray) -> dict[str, np.ndarray]:
    """The angle curve without deviation and with the largest positive and negative
    fixed deviations (Fig. 5.11 a).

    Every marker ``i`` is displaced by ``±Σ_i · (1, 1, 1)/√3`` (mm, lab frame) at every
    frame — see the module docstring for why the diagonal.

    Args:
        model: a joint-angle model (``evaluate(p)``, 3 parameters per marker).
        radii: ``Σ_i`` per marker in mm, in the model's marker order.

    Returns:
        ``{"none": …, "positive": …, "negative": …}``, each ``(n_time,)`` in the
        model's output unit (degrees for joint angles).
    """
    r = _radii(model, radii)
    shift = (r[:, None] * DIAGONAL[None, :]).ravel()
    return {
        "none": np.asarray(model.evaluate(np.zeros_like(shift)).values, dtype=float),
        "positive": np.asarray(model.evaluate(shift).values, dtype=float),
        "negative": np.asarray(model.evaluate(-shift).values, dtype=float),
    }


def uniform_ball_deviations(rng: np.random.Generator, n: int, radii: np.ndarray,
                            length_rng: np.random.Generator | None = None) -> np.ndarray:  # fmt: skip
    """``n`` deviation vectors ``(n, 3·n_markers)`` (mm), marker ``i``'s part uniform in
    the ball of radius ``radii[i]``: direction uniform on the sphere (normalised normal
    draws from ``rng``), length ``Σ_i·U^{1/3}`` (``U`` uniform from ``length_rng``, default
    ``rng``). With two generators, drawing ``n`` then ``m`` samples gives the same values
    as drawing ``n + m`` at once, so results do not depend on the chunk size."""
    direction = rng.standard_normal((n, radii.size, 3))
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    uniform = (rng if length_rng is None else length_rng).random((n, radii.size))
    length = radii[None, :] * uniform ** (1.0 / 3.0)
    return (direction * length[..., None]).reshape(n, -1)


def _node_indices(model: NodeModel, frames: Sequence[int] | np.ndarray | None) -> np.ndarray:
    n_time = int(np.asarray(model.times).size)
    if frames is None:
        return np.arange(n_time)
    nodes = np.asarray(frames, dtype=int).ravel()
    if nodes.size == 0 or nodes.min() < 0 or nodes.max() >= n_time:
        raise ParameterError(f"frames must be node indices 0..{n_time - 1} of the model")
    return nodes


def _generators(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """Independent streams for the directions and the lengths of the deviations."""
    return tuple(np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))  # type: ignore[return-value]


def _sample_chunks(model: NodeModel, radii: np.ndarray, nodes: np.ndarray, n_samples: int,
                   seed: int, per_frame: bool,
                   chunk_rows: int) -> Iterator[tuple[int, np.ndarray]]:  # fmt: skip
    """Yield ``(samples in this chunk, values (samples, len(nodes)))`` until
    ``n_samples`` samples per node have been evaluated (the same values whatever
    ``chunk_rows``)."""
    rng, length_rng = _generators(seed)
    per_chunk = max(1, chunk_rows // nodes.size)
    done = 0
    while done < n_samples:
        m = min(per_chunk, n_samples - done)
        if per_frame:  # an independent deviation for every (sample, node)
            P = uniform_ball_deviations(rng, m * nodes.size, radii, length_rng)
        else:  # one deviation per sample, the same at every node (a whole curve)
            P = np.repeat(uniform_ball_deviations(rng, m, radii, length_rng), nodes.size, axis=0)
        values = np.asarray(model.evaluate_nodes(P, np.tile(nodes, m)), dtype=float)
        yield m, values.reshape(m, nodes.size)
        done += m


def monte_carlo_envelope(
    model: NodeModel,
    radii: Sequence[float] | np.ndarray,
    n_samples: int,
    seed: int = 0,
    frames: Sequence[int] | np.ndarray | None = None,
    per_frame: bool = True,
    *,
    chunk_rows: int = DEFAULT_CHUNK_ROWS,
) -> tuple[np.ndarray, np.ndarray]:
    """Envelope of the angle under uniform random marker deviations (Fig. 5.11 b).

    Args:
        model: a joint-angle model with ``evaluate_nodes(P, nodes)``.
        radii: ball radius ``Σ_i`` per marker in mm, in the model's marker order (for an
            α-level, pass ``(1 − α)·Σ_i``).
        n_samples: random deviations per frame.
        seed: seed of the random generator (the result is reproducible).
        frames: node indices (0-based positions in ``model.times``) to sample; default
            all.
        per_frame: ``True``: an independent deviation at every frame (random noise);
            ``False``: one deviation per sample kept over all frames (a whole perturbed
            curve, like the Graph Follower's library trajectories).
        chunk_rows: (deviation, frame) rows per vectorised model call at most; bounds
            the memory (about 1 kB per row for Plug-in Gait).

    Returns:
        ``(lower, upper)``: min and max over the samples per frame, each
        ``(len(frames),)`` in the model's unit (degrees).
    """
    lower, upper, _ = _envelope(model, radii, n_samples, seed, frames, per_frame, chunk_rows, None)
    return lower, upper


def monte_carlo_timed(
    model: NodeModel,
    radii: Sequence[float] | np.ndarray,
    seconds: float,
    seed: int = 0,
    frames: Sequence[int] | np.ndarray | None = None,
    per_frame: bool = True,
    *,
    chunk_rows: int = DEFAULT_CHUNK_ROWS,
) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`monte_carlo_envelope` with as many samples as fit in ``seconds`` of wall
    time (checked after every chunk of ``chunk_rows`` rows, so it may overrun by one
    chunk). Returns ``(lower, upper, samples per frame)``."""
    return _envelope(model, radii, np.iinfo(np.int64).max, seed, frames, per_frame, chunk_rows, seconds)


def _require_count(name: str, value: int) -> None:
    """Refuse a count argument ``name`` that is not a whole number >= 1."""
    if isinstance(value, bool) or not isinstance(value, Integral) or value < 1:
        raise ParameterError(f"{name} must be a whole number >= 1; got {value!r}")


def _envelope(model: NodeModel, radii: Sequence[float] | np.ndarray, n_samples: int, seed: int,
              frames: Sequence[int] | np.ndarray | None, per_frame: bool, chunk_rows: int,
              seconds: float | None) -> tuple[np.ndarray, np.ndarray, int]:  # fmt: skip
    _require_count("n_samples", n_samples)
    _require_count("chunk_rows", chunk_rows)
    r = _radii(model, radii)
    nodes = _node_indices(model, frames)
    lower, upper = np.full(nodes.size, np.inf), np.full(nodes.size, -np.inf)
    start, total = time.perf_counter(), 0
    for m, values in _sample_chunks(model, r, nodes, n_samples, seed, per_frame, chunk_rows):
        np.minimum(lower, values.min(axis=0), out=lower)
        np.maximum(upper, values.max(axis=0), out=upper)
        total += m
        if seconds is not None and time.perf_counter() - start >= seconds:
            break
    return lower, upper, total


def random_deviation_curves(
    model: NodeModel,
    radii: Sequence[float] | np.ndarray,
    n_curves: int,
    seed: int = 0,
    per_frame: bool = True,
) -> np.ndarray:
    """``n_curves`` angle curves ``(n_curves, n_time)`` under uniform random marker
    deviations inside the balls (mm): fresh deviations at every frame (``per_frame``,
    noisy curves as in Fig. 5.11 b) or one deviation per curve.

    Raises:
        ParameterError: ``n_curves`` < 1, or radii not one finite value >= 0 per marker.
    """
    _require_count("n_curves", n_curves)
    r = _radii(model, radii)
    nodes = _node_indices(model, None)
    chunks = _sample_chunks(model, r, nodes, n_curves, seed, per_frame, DEFAULT_CHUNK_ROWS)
    return np.concatenate([values for _, values in chunks])


def deviation_norms(fuzzy: xr.Dataset, name: str, markers: Sequence[str] | None = None) -> xr.DataArray:
    """Norms (mm) of the marker deviations that produce the hull of angle component
    ``name`` (e.g. ``"LKneeAngles_X"``), dims ``(alpha, bound, frame, marker)``
    (Fig. 5.12). Only the markers the angle uses (or ``markers``) are kept; α = 1 is
    dropped (its deviation is zero).

    Raises:
        ParameterError: ``name`` is not an angle component of ``fuzzy``, or a requested
            marker is not used by that angle.
    """
    components = angle_components(fuzzy)
    found = component_deviation(fuzzy, name) if name in components else None
    if found is None:
        raise ParameterError(f"no deviations for {name!r} in the result; it holds {components}")
    norms = found
    used = [str(m) for m in norms["marker"].to_numpy() if bool(norms.sel(marker=m).notnull().any())]
    if markers is not None:
        unknown = [m for m in markers if m not in used]
        if unknown:
            raise ParameterError(f"{name} does not depend on markers {unknown}; it uses {', '.join(used)}")
        used = list(markers)
    norms = norms.sel(marker=used, alpha=norms["alpha"] < 1.0)
    norms.attrs["units"] = "mm"
    return norms

