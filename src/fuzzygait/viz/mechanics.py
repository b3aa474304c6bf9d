"""Figures and Rerun recordings of leg + prosthesis simulations.

Both take the ``xarray.Dataset`` of :meth:`fuzzygait.mechanics.scenarios.LegSimulator.run`
(or one loaded back from ``.nc`` / ``.zarr``): coordinates ``time`` (s) and ``body``
("thigh", "shank", "blade000", ...), variables ``position`` (m), ``directors``, the
energies (J) and ``hip_flexion`` / ``knee_flexion`` (rad).

:func:`energy_figure` draws the energy balance; :func:`log_simulation` logs a simulation
into a Rerun recording stream (rerun-sdk 0.41, through the helpers of
:mod:`fuzzygait.viz.rerun_log`).  Nothing here writes a file:
:mod:`fuzzygait.workflows.rerun_recordings` writes the ``.rrd`` and
:func:`fuzzygait.io.figure_files.save_figure` the figure.

Recording layout (units: **metres** in ``world``, **joules** under ``energy_J``,
**degrees** under ``angles_deg``; one timeline ``time`` in seconds)::

    world                          ViewCoordinates RIGHT_HAND_Z_UP (static; x forward,
                                   z up, y lateral; the hip joint centre at the origin)
    world/leg/thigh                LineStrips3D: hip joint centre -> knee joint centre
    world/leg/shank                LineStrips3D: knee joint centre -> ankle (blade root)
    world/leg/joints               Points3D: hip, knee, ankle, labelled
    world/blade/centreline         LineStrips3D through the blade nodes (beam foot only)
    world/blade/directors/d1|d2|d3 Arrows3D at every blade node: d1 lateral (red),
                                   d2 (green), d3 tangent (blue), drawn
                                   ``director_length`` m long
    energy_J/<kind>                Scalars: kinetic, gravitational, internal, dissipated,
                                   total (= kinetic + gravitational + internal) and
                                   total_plus_dissipated (conserved by an exact integrator)
    energy_drift/relative          Scalars: (total + dissipated − initial) / |initial|
    angles_deg/hip_flexion|knee_flexion   Scalars, degrees, flexion positive

The 3-D entities are logged every ``stride`` time steps (default: every 10 ms); the
series at every step.  Everything is sent column-wise (``send_columns``), so a
2000-step run logs in well under a second.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from fuzzygait.core.errors import ParameterError  # noqa: E402

if TYPE_CHECKING:
    import xarray as xr
    from matplotlib.figure import Figure

    from fuzzygait.mechanics.leg import LegConfiguration

__all__ = [
    "ENERGY_TERMS",
    "SimulationScene",
    "energy_drift",
    "energy_figure",
    "log_simulation",
    "segment_geometry",
    "simulation_blueprint",
    "simulation_scene",
    "simulation_title",
]

#: Energy variables of a simulation: (variable, label, colour).
ENERGY_TERMS: tuple[tuple[str, str, str], ...] = (
    ("kinetic_energy", "kinetic", "tab:blue"),
    ("gravitational_energy", "gravitational", "tab:green"),
    ("internal_energy", "internal (elastic)", "tab:orange"),
    ("dissipated_energy", "dissipated", "tab:red"),
    ("total_energy", "total", "black"),
)
_DEFAULT_STRIDE_S = 0.01
_SEGMENT_COLOURS = {"thigh": (70, 130, 200), "shank": (230, 140, 40)}
_BLADE_COLOUR = (60, 60, 60)
_DIRECTOR_COLOURS = {"d1": (230, 50, 50), "d2": (40, 190, 60), "d3": (50, 110, 240)}
_SERIES_COLOURS = {
    "kinetic": (31, 119, 180), "gravitational": (44, 160, 44), "internal": (255, 127, 14),
    "dissipated": (214, 39, 40), "total": (20, 20, 20), "total_plus_dissipated": (148, 103, 189),
}  # fmt: skip
_SEGMENT_RADIUS_M = 0.012
_BLADE_RADIUS_M = 0.004
_ARROW_RADIUS_M = 0.0015
_JOINT_RADIUS_M = 0.018


# ----------------------------------------------------------------------------- helpers
def _require(ds: xr.Dataset, *names: str) -> None:
    missing = [n for n in names if n not in ds.variables]
    if missing:
        raise ParameterError(
            f"the simulation result lacks {', '.join(missing)} (is it a `fuzzygait simulate` output?)"
        )


def energy_drift(ds: xr.Dataset) -> np.ndarray:
    """Relative energy drift per time step: ``(total + dissipated − initial) / |initial|``
    with ``initial = total(0) + dissipated(0)``; an exact integrator keeps it at 0.  When the
    initial energy is 0 the largest |total| is the reference instead (dimensionless)."""
    _require(ds, "total_energy", "dissipated_energy")
    balance = np.asarray(ds["total_energy"].values, float) + np.asarray(ds["dissipated_energy"].values, float)
    initial = balance[0]
    scale = abs(initial)
    if not scale > 0:
        scale = float(np.nanmax(np.abs(ds["total_energy"].values), initial=0.0)) or 1.0
    return (balance - initial) / scale


def _parameters(ds: xr.Dataset) -> dict[str, float]:
    if "parameter_value" not in ds or "parameter" not in ds.coords:
        return {}
    return {str(k): float(v) for k, v in zip(ds["parameter"].values, ds["parameter_value"].values)}


def simulation_title(ds: xr.Dataset) -> str:
    """``"swing: E = 5.995e+05 Pa, ν = 0.265, ρ = 8550 kg/m³, η = 1 Pa s; 20 nodes, Δt = 1 ms"``."""
    p = _parameters(ds)
    shown = [("E", "E", " Pa"), ("nu", "ν", ""), ("rho", "ρ", " kg/m³"), ("eta", "η", " Pa s")]
    parts = [f"{symbol} = {p[name]:.4g}{unit}" for name, symbol, unit in shown if name in p]
    scenario = str(ds.attrs.get("scenario", "simulation"))
    extra = []
    if "nodes" in ds.attrs and int(ds.attrs["nodes"]) > 0:
        extra.append(f"{int(ds.attrs['nodes'])} nodes")
    if "dt" in ds.attrs:
        extra.append(f"Δt = {1e3 * float(ds.attrs['dt']):g} ms")
    return f"{scenario}: " + ", ".join(parts) + (f"; {', '.join(extra)}" if extra else "")


# ----------------------------------------------------------------------------- figure
def energy_figure(ds: xr.Dataset) -> Figure:
    """The energy balance of a simulation: kinetic, gravitational, internal, dissipated,
    total and total + dissipated over time (J); below, the relative drift of total +
    dissipated from its initial value.  The title names the scenario and parameters."""
    _require(ds, *(name for name, _, _ in ENERGY_TERMS))
    t = np.asarray(ds["time"].values, float)
    fig, (ax, ax_drift) = plt.subplots(
        2, 1, figsize=(9, 6.5), sharex=True, gridspec_kw={"height_ratios": (3, 1.3)}
    )
    for name, label, colour in ENERGY_TERMS:
        ax.plot(t, ds[name].values, color=colour, lw=1.6 if name == "total_energy" else 1.2, label=label)
    balance = ds["total_energy"].values + ds["dissipated_energy"].values
    ax.plot(t, balance, color="tab:purple", lw=1.2, ls="--", label="total + dissipated")
    ax.set_ylabel("energy (J)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=3, loc="best")
    drift = energy_drift(ds)
    ax_drift.plot(t, drift, color="tab:purple", lw=1.2)
    ax_drift.axhline(0.0, color="0.6", lw=0.6)
    ax_drift.set_ylabel("relative drift (−)", fontsize=9)
    ax_drift.ticklabel_format(axis="y", style="sci", scilimits=(-2, 3))
    ax_drift.set_xlabel("time (s)")
    ax_drift.grid(alpha=0.3)
    worst = float(np.nanmax(np.abs(drift))) if drift.size else 0.0
    ax_drift.set_title(f"(total + dissipated − initial) / |initial|, max |drift| = {worst:.3g}", fontsize=9)
    ax_drift.set_xlim(t[0], t[-1] if t[-1] > t[0] else t[0] + 1e-9)
    fig.suptitle(simulation_title(ds), fontsize=10)
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------- geometry
def segment_geometry(
    ds: xr.Dataset, configuration: LegConfiguration | None = None
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Proximal and distal joint centres ``(n_time, 3)`` (m) of the thigh and shank.

    A segment's ``position`` is its centre of mass and its ``d3`` points proximally, so
    proximal = position + c·d3 and distal = position − (L − c)·d3 with the length ``L``
    and centre-of-mass distance ``c`` from ``configuration``; without it from the attributes
    ``thigh_length_m``, ``thigh_com_from_proximal_m``, ... (written by ``fuzzygait simulate``)
    when present, else thesis Table 4.1.
    """
    from fuzzygait.mechanics.presets import SHANK, THIGH

    _require(ds, "position", "directors")
    segments: dict[str, Any] = {"thigh": THIGH, "shank": SHANK}
    if configuration is not None:
        segments = {"thigh": configuration.thigh, "shank": configuration.shank}
    else:  # geometry saved by `fuzzygait simulate` in the attributes
        for name in list(segments):
            keys = (f"{name}_length_m", f"{name}_com_from_proximal_m")
            if all(k in ds.attrs for k in keys):
                segments[name] = _Segment(float(ds.attrs[keys[0]]), float(ds.attrs[keys[1]]))
    bodies = [str(b) for b in ds["body"].values]
    out = {}
    for name, data in segments.items():
        if name not in bodies:
            continue
        centre = ds["position"].sel(body=name).transpose("time", "xyz").values
        d3 = ds["directors"].sel(body=name, director="d3").transpose("time", "xyz").values
        out[name] = (centre + data.com_from_proximal * d3, centre - (data.length - data.com_from_proximal) * d3)
    return out


@dataclass(frozen=True)
class _Segment:
    length: float
    com_from_proximal: float


def _blade_bodies(ds: xr.Dataset) -> list[str]:
    return [str(b) for b in ds["body"].values if str(b).startswith("blade")]


def _default_stride(times: np.ndarray) -> int:
    if times.size < 2:
        return 1
    dt = float(np.median(np.diff(times)))
    return max(1, int(round(_DEFAULT_STRIDE_S / dt))) if dt > 0 else 1


# ----------------------------------------------------------------------------- rerun
def _log_strips(rec: Any, rr: Any, entity: str, index: list[Any], strips: np.ndarray,
                colour: tuple[int, int, int], radius: float) -> None:  # fmt: skip
    """One line strip per row: ``strips`` is ``(n_rows, n_points, 3)``."""
    from fuzzygait.viz.rerun_log import _send_instances

    rec.log(entity, rr.LineStrips3D.from_fields(colors=[colour], radii=[radius]), static=True, strict=True)
    valid = np.all(np.isfinite(strips), axis=(1, 2))[:, None]
    _send_instances(rec, entity, index, rr.LineStrips3D.columns, {"strips": strips[:, None]}, valid)


def _blueprint(rrb: Any, has_blade: bool) -> Any:
    plots = rrb.Vertical(
        rrb.TimeSeriesView(origin="/energy_J", name="Energies (J)"),
        rrb.TimeSeriesView(origin="/energy_drift", name="Relative energy drift (−)"),
        rrb.TimeSeriesView(origin="/angles_deg", name="Joint flexion (deg)"),
    )
    world = rrb.Spatial3DView(origin="/world", name="Leg" + (" and blade" if has_blade else "") + " (m)")
    return rrb.Blueprint(rrb.Horizontal(world, plots, column_shares=[3, 2]), rrb.TimePanel(timeline="time"))


def _log_leg(rec: Any, rr: Any, segments: dict[str, tuple[np.ndarray, np.ndarray]], rows: np.ndarray,
             sampled: list[Any]) -> None:  # fmt: skip
    """The thigh and shank as strips and the hip, knee and ankle as labelled points (m),
    at the sampled ``rows``."""
    from fuzzygait.viz.rerun_log import _send_instances

    joints: list[np.ndarray] = []
    labels: list[str] = []
    for name, (proximal, distal) in segments.items():
        strips = np.stack([proximal[rows], distal[rows]], axis=1)
        _log_strips(rec, rr, f"world/leg/{name}", sampled, strips, _SEGMENT_COLOURS[name],
                    _SEGMENT_RADIUS_M)  # fmt: skip
        if not joints:
            joints.append(proximal[rows])
            labels.append("hip")
        joints.append(distal[rows])
        labels.append({"thigh": "knee", "shank": "ankle"}[name])
    if joints:
        points = np.stack(joints, axis=1)
        rec.log("world/leg/joints", rr.Points3D.from_fields(radii=[_JOINT_RADIUS_M], colors=[(90, 90, 90)]),
                static=True, strict=True)  # fmt: skip
        names = np.broadcast_to(np.array(labels, dtype=object), points.shape[:2])
        _send_instances(rec, "world/leg/joints", sampled, rr.Points3D.columns,
                        {"positions": points, "labels": names}, np.all(np.isfinite(points), axis=2))  # fmt: skip


def _log_blade(rec: Any, rr: Any, sampled: list[Any], nodes: np.ndarray, frames: np.ndarray,
               director_length: float) -> None:  # fmt: skip
    """The blade's centreline (m) and its directors as arrows of ``director_length`` (m)."""
    from fuzzygait.viz.rerun_log import _send_instances

    _log_strips(rec, rr, "world/blade/centreline", sampled, nodes, _BLADE_COLOUR, _BLADE_RADIUS_M)
    ok = np.all(np.isfinite(nodes), axis=2) & np.all(np.isfinite(frames), axis=(2, 3))
    for k, director in enumerate(("d1", "d2", "d3")):
        entity = f"world/blade/directors/{director}"
        rec.log(entity, rr.Arrows3D.from_fields(radii=[_ARROW_RADIUS_M],
                colors=[_DIRECTOR_COLOURS[director]]), static=True, strict=True)  # fmt: skip
        _send_instances(rec, entity, sampled, rr.Arrows3D.columns,
                        {"origins": nodes, "vectors": director_length * frames[:, :, k]}, ok)  # fmt: skip


def _log_energies(rec: Any, rr: Any, ds: xr.Dataset, all_steps: list[Any]) -> None:
    """The energies (J), the energy balance, its relative drift and the hip and knee
    flexion (deg) as time series over every step."""
    from fuzzygait.viz.rerun_log import _log_series

    series = {
        "kinetic": ds.get("kinetic_energy"), "gravitational": ds.get("gravitational_energy"),
        "internal": ds.get("internal_energy"), "dissipated": ds["dissipated_energy"],
        "total": ds["total_energy"],
    }  # fmt: skip
    for key, values in series.items():
        if values is not None:
            _log_series(rec, rr, f"energy_J/{key}", all_steps, values.values, f"{key} (J)",
                        _SERIES_COLOURS[key], 1.5)  # fmt: skip
    balance = ds["total_energy"].values + ds["dissipated_energy"].values
    _log_series(rec, rr, "energy_J/total_plus_dissipated", all_steps, balance,
                "total + dissipated (J)", _SERIES_COLOURS["total_plus_dissipated"], 1.5)  # fmt: skip
    _log_series(rec, rr, "energy_drift/relative", all_steps, energy_drift(ds),
                "(total + dissipated − initial) / |initial|", (148, 103, 189), 1.5)  # fmt: skip
    for key, colour in (("hip_flexion", (70, 130, 200)), ("knee_flexion", (230, 140, 40))):
        if key in ds:
            _log_series(rec, rr, f"angles_deg/{key}", all_steps, np.degrees(ds[key].values),
                        f"{key.replace('_', ' ')} (deg)", colour, 1.5)  # fmt: skip


@dataclass(frozen=True)
class SimulationScene:
    """What a simulation's recording shows, checked and sampled (:func:`simulation_scene`):
    the ``times`` of every step (s), the sampled ``rows`` of the 3-D entities, the thigh
    and shank joint centres (m, :func:`segment_geometry`), the blade's sampled ``nodes``
    ``(n_rows, n_nodes, 3)`` (m) and director ``frames`` ``(n_rows, n_nodes, 3, 3)`` (None
    without a blade), the arrows' ``director_length`` (m) and the recording's ``title``."""

    ds: xr.Dataset
    times: np.ndarray
    rows: np.ndarray
    segments: dict[str, tuple[np.ndarray, np.ndarray]]
    nodes: np.ndarray | None
    frames: np.ndarray | None
    director_length: float
    title: str

    @property
    def has_blade(self) -> bool:
        """Whether the simulation has a blade (beam foot)."""
        return self.nodes is not None


def simulation_scene(
    ds: xr.Dataset,
    *,
    configuration: LegConfiguration | None = None,
    stride: int | None = None,
    director_length: float | None = None,
) -> SimulationScene:
    """The checked contents of a simulation's recording (layout and units in the module
    docstring), before anything is written.

    Args:
        ds: result of :meth:`LegSimulator.run <fuzzygait.mechanics.scenarios.LegSimulator.run>`.
        configuration: the simulator's leg configuration (``sim.configuration``) for the
            segment lengths; default: thesis Table 4.1.
        stride: log the 3-D entities every ``stride`` time steps (default: every 10 ms).
        director_length: drawn length of the blade director arrows (m); default 40 % of
            the mean node spacing.

    Raises:
        ParameterError: a bad ``stride``, or ``ds`` is not a simulation.
    """
    _require(ds, "position", "directors", "total_energy", "dissipated_energy")
    times = np.asarray(ds["time"].values, dtype=float)
    if stride is None:
        stride = _default_stride(times)
    if isinstance(stride, bool) or int(stride) != stride or stride < 1:
        raise ParameterError(f"stride must be a whole number of time steps ≥ 1; got {stride!r}")
    stride = int(stride)
    rows = np.arange(0, times.size, stride)
    if rows[-1] != times.size - 1:
        rows = np.append(rows, times.size - 1)  # always show the final state
    segments = segment_geometry(ds, configuration)
    blade = _blade_bodies(ds)
    nodes = frames = None
    if blade:
        nodes = ds["position"].sel(body=blade).transpose("time", "body", "xyz").values[rows]
        frames = ds["directors"].sel(body=blade).transpose("time", "body", "director", "xyz").values[rows]
        if director_length is None:
            spacing = np.linalg.norm(np.diff(nodes[0], axis=0), axis=1)
            director_length = 0.4 * float(np.mean(spacing)) if spacing.size else 0.02
    return SimulationScene(ds, times, rows, segments, nodes, frames, float(director_length or 0.0),
                           simulation_title(ds))  # fmt: skip


def simulation_blueprint(rrb: Any, scene: SimulationScene) -> Any:
    """The default blueprint of a simulation's recording (``rrb``: ``rerun.blueprint``):
    the leg (and blade) in 3-D beside the energies, the drift and the joint flexion."""
    return _blueprint(rrb, scene.has_blade)


def log_simulation(rec: Any, rr: Any, scene: SimulationScene) -> None:
    """Log a simulation's ``scene`` (:func:`simulation_scene`) into the Rerun recording
    stream ``rec`` (``rr``: the ``rerun`` module; layout and units in the module
    docstring); writes no file (the stream's sink does:
    :func:`fuzzygait.io.rerun_files.recording_file`)."""
    all_steps = [rr.TimeColumn("time", duration=scene.times)]
    sampled = [rr.TimeColumn("time", duration=scene.times[scene.rows])]
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True, strict=True)
    _log_leg(rec, rr, scene.segments, scene.rows, sampled)
    if scene.nodes is not None and scene.frames is not None:
        _log_blade(rec, rr, sampled, scene.nodes, scene.frames, scene.director_length)
    _log_energies(rec, rr, scene.ds, all_steps)
