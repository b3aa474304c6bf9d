"""Rerun ``.rrd`` files of a gait trial, a leg simulation and a fuzzy simulation's hulls.

Each writer checks its inputs first, then opens a recording stream that saves atomically
(:func:`fuzzygait.io.rerun_files.recording_file`) and lets :mod:`fuzzygait.viz` log the
contents into it (:func:`~fuzzygait.viz.rerun_log.log_trial`,
:func:`~fuzzygait.viz.mechanics.log_simulation`,
:func:`~fuzzygait.viz.fuzzy_dynamics.log_fuzzy_hulls`; entity layouts, units and
blueprints are described there).  Nothing is left at the path when anything fails.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.rerun_files import recording_file

if TYPE_CHECKING:
    import xarray as xr

    from fuzzygait.core.trial import Trial
    from fuzzygait.kinematics.model import CGMResult
    from fuzzygait.mechanics.leg import LegConfiguration

__all__ = ["write_fuzzy_recording", "write_recording", "write_simulation_recording"]


def _rrd_path(path: str | os.PathLike[str]) -> Path:
    """``path`` as a :class:`Path`; a :class:`ParameterError` unless it ends in ``.rrd``."""
    path = Path(path)
    if path.suffix.lower() != ".rrd":
        raise ParameterError(f"{path}: a Rerun recording must end in .rrd")
    return path


def write_recording(
    path: str | os.PathLike[str],
    trial: Trial,
    result: CGMResult,
    fuzzy: xr.Dataset | None = None,
    *,
    alphas_to_show: Iterable[float] | None = None,
    recording_name: str = "fuzzygait",
    kinetics: xr.Dataset | None = None,
) -> Path:
    """Write ``trial``, its model ``result`` and optional fuzzy envelopes as a Rerun ``.rrd``.

    The entity layout, units, timelines and blueprint are described in
    :mod:`fuzzygait.viz.rerun_log`.  The file is written atomically: a temporary file
    beside ``path`` is renamed onto it once complete; nothing is left behind on error.

    Args:
        path: the ``.rrd`` file to write (its folder must exist).
        trial: the (pre-processed) trial the model ran on; markers in mm.
        result: :func:`~fuzzygait.kinematics.compute_lower_body` output for ``trial``.
        fuzzy: fuzzy joint-angle result (:mod:`fuzzygait.markererror.analysis`); adds the
            alpha-cut envelope series and the marker balls.
        alphas_to_show: alpha levels of ``fuzzy`` whose envelopes are logged; None for
            every level below 1 (ignored without ``fuzzy``).
        recording_name: Rerun application id the recording is filed under (the viewer
            keeps one default blueprint per application id); the recording itself is
            named after the trial.
        kinetics: the trial's kinetics (:attr:`AnglesRun.kinetics
            <fuzzygait.workflows.angles.AnglesRun.kinetics>` ``.data``): the ground reaction
            arrows at the plates' centres of pressure (1 mm per N), the moments and powers
            as series and their tab.

    Returns:
        ``path``.

    Raises:
        ParameterError: ``path`` does not end in ``.rrd``, the result does not belong to
            the trial, or ``fuzzy`` lacks a dimension / holds no requested alpha level.
        FuzzyGaitError: the file cannot be written (names ``path``), Rerun logging is
            disabled (``RERUN=off``) or rerun-sdk is not installed.
    """
    from fuzzygait.viz.rerun_log import check_recording, log_trial, trial_blueprint

    path = _rrd_path(path)
    check_recording(trial, result, fuzzy, alphas_to_show)  # before touching the disk
    if kinetics is not None and kinetics.sizes["frame"] != trial.n_frames:
        raise ParameterError(f"the kinetics have {kinetics.sizes['frame']} frames; the trial has {trial.n_frames}")
    blueprint = lambda rrb: trial_blueprint(rrb, result, kinetics is not None)  # noqa: E731
    with recording_file(path, recording_name, trial.name, blueprint) as (rec, rr):
        log_trial(rec, rr, trial, result, fuzzy, alphas_to_show=alphas_to_show, kinetics=kinetics)
    return path


def write_simulation_recording(
    ds: xr.Dataset,
    path: str | os.PathLike[str],
    *,
    configuration: LegConfiguration | None = None,
    stride: int | None = None,
    director_length: float | None = None,
    recording_name: str = "fuzzygait-mechanics",
) -> Path:
    """Write a simulation as a Rerun ``.rrd`` (layout and units:
    :mod:`fuzzygait.viz.mechanics`).

    Args:
        ds: result of :meth:`LegSimulator.run <fuzzygait.mechanics.scenarios.LegSimulator.run>`.
        path: the ``.rrd`` file (its folder must exist); written atomically.
        configuration: the simulator's leg configuration (``sim.configuration``) for the
            segment lengths; default: thesis Table 4.1.
        stride: log the 3-D entities every ``stride`` time steps (default: every 10 ms).
        director_length: drawn length of the blade director arrows (m); default 40 % of
            the mean node spacing.
        recording_name: Rerun application id.

    Returns:
        ``path``.

    Raises:
        ParameterError: a bad ``path`` suffix or ``stride``, or ``ds`` is not a simulation.
        FuzzyGaitError: the file cannot be written, Rerun is disabled or not installed.
    """
    from fuzzygait.viz.mechanics import log_simulation, simulation_blueprint, simulation_scene

    path = _rrd_path(path)
    scene = simulation_scene(ds, configuration=configuration, stride=stride, director_length=director_length)
    with recording_file(path, recording_name, scene.title, lambda rrb: simulation_blueprint(rrb, scene)) as (rec, rr):
        log_simulation(rec, rr, scene)
    return path


def write_fuzzy_recording(result: xr.Dataset, path: str | os.PathLike[str],
                          recording_name: str = "fuzzygait-fuzzy-dynamics") -> Path:  # fmt: skip
    """Write the hulls of a fuzzy simulation as Rerun time series (rerun-sdk 0.41;
    entities: :func:`~fuzzygait.viz.fuzzy_dynamics.log_fuzzy_hulls`) to the ``.rrd``
    ``path``, atomically; returns ``path``."""
    from fuzzygait.viz.fuzzy_dynamics import fuzzy_title, log_fuzzy_hulls

    path = _rrd_path(path)
    with recording_file(path, recording_name, fuzzy_title(result)) as (rec, rr):
        log_fuzzy_hulls(rec, rr, result)
    return path
