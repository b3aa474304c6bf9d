"""Helpers shared by the test folders: where the sample and reference data live
(skipping when the reference data is absent), the `fuzzygait` command in a subprocess,
and marker-cutting. Imported as ``from support import ...`` (``tests/`` is on the path)."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest

from fuzzygait.uncertainty.protocol import Evaluation, Output

if TYPE_CHECKING:
    from fuzzygait.core.findings import Finding

ROOT = Path(__file__).resolve().parents[1]  # the repository
SAMPLE_DATA = ROOT / "sample_data"
SHARED_DATA = ROOT.parent / "shared" / "data"
VICON = SHARED_DATA / "vicon"
C3D_FORMATS = SHARED_DATA / "c3d-formats"

needs_shared = pytest.mark.skipif(
    not SHARED_DATA.is_dir(),
    reason=f"reference data {SHARED_DATA} is absent (it sits beside the clone in CI)",
)


def shared_file(*parts: str) -> Path:
    """Path of a reference file; skips the calling test when it is absent."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.is_file():
        pytest.skip(f"reference file {path} is absent")
    return path


def run(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """Run the `fuzzygait` command in a subprocess, as a user would."""
    return subprocess.run(
        [sys.executable, "-m", "fuzzygait", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
    )


def run_here(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """Run the `fuzzygait` command in this process, as :func:`run` does in a subprocess
    (the same entry point, exit code, stdout and stderr; ``tests/cli/test_cli.py::
    test_run_here_gives_what_a_subprocess_gives`` compares them) without an interpreter's
    start-up and imports, ~2 s a command: for the checks of arguments and inputs that end
    with one line before any work.  The signal handlers the command installs and its
    one-line warning display are restored afterwards."""
    import contextlib
    import io
    import signal
    import warnings

    from fuzzygait.cli.app import main

    argv = [str(a) for a in args]
    stdout, stderr = io.StringIO(), io.StringIO()
    handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    showwarning = warnings.showwarning
    code = 0
    try:
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            try:
                main(argv)
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else int(exc.code is not None)
    finally:
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
        warnings.showwarning = showwarning
    return subprocess.CompletedProcess(["fuzzygait", *argv], code, stdout.getvalue(), stderr.getvalue())


def assert_one_line_error(result: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert result.returncode != 0
    assert "Traceback" not in result.stderr + result.stdout
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("fuzzygait: error: ")
    for needle in needles:
        assert needle in lines[0]


def cut(markers: np.ndarray, cuts: list[tuple[int, int, int]]) -> np.ndarray:
    """Copy of ``(frames, markers, 3)`` marker data with NaN runs ``(marker, start, length)``."""
    out = markers.copy()
    for m, start, length in cuts:
        out[start : start + length, m] = np.nan
    return out


def nexus_angle_errors(angles: dict[str, np.ndarray], trial, names) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{name: (max |ours - Nexus|, RMS)}`` per component (deg) of the angle outputs
    ``names``, over the frames where Nexus has an output; ours must be finite there."""
    out = {}
    for name in names:
        nexus = np.all(np.isfinite(trial.outputs[name]), axis=1)
        assert nexus.any(), name
        diff = angles[name][nexus] - trial.outputs[name][nexus]
        assert np.isfinite(diff).all(), name
        out[name] = (np.abs(diff).max(axis=0), np.sqrt(np.mean(diff**2, axis=0)))
    return out


def rot_pelvis_truth(truth, side: str) -> np.ndarray:
    """The truth pelvis angles (Plug-in Gait order: tilt, obliquity, rotation) re-decomposed
    in CGM 1.1+'s order (rotation, obliquity, tilt), independently of fuzzygait.kinematics."""
    x, y, z = (np.radians(truth[f"{side}PelvisAngles_{a}"].to_numpy()) for a in "XYZ")
    s = 1.0 if side == "L" else -1.0  # L: (a, b, -c), R: (a, -b, c) of intrinsic Y-X-Z
    from scipy.spatial.transform import Rotation

    rotation = Rotation.from_euler("YXZ", np.stack([x, s * y, -s * z], axis=1))
    c, b, a = rotation.as_euler("ZXY").T
    return np.degrees(np.stack([a, s * b, -s * c], axis=1))


@dataclass
class FakeAnalysis:
    """Stands in for ``fuzzygait.workflows.marker_uncertainty.MarkerErrorAnalysis`` (a run,
    a fuzzy dataset made up by the test, its ΔΦ table, notes, and the whole result: None
    given, the bands ``fuzzy`` alone)."""

    run: Any
    fuzzy: Any
    delta_phi: Any
    notes: list[Finding] = field(default_factory=list)
    result: Any = None

    def __post_init__(self) -> None:
        if self.result is None and self.fuzzy is not None:
            from fuzzygait.markererror.result import MarkerErrorResult

            self.result = MarkerErrorResult(self.fuzzy)


def sparse_angles_run(angles_run: Any, n_frames: int = 6) -> Any:
    """``angles_run`` with every marker NaN outside ``n_frames`` frames spread evenly over
    its trial: the marker-error analysis then only works on those frames (cheap tests)."""
    import dataclasses

    trial = angles_run.trial
    frames = np.linspace(0, trial.n_frames - 1, n_frames).round().astype(int)
    markers = np.full_like(trial.markers, np.nan)
    markers[frames] = trial.markers[frames]
    return dataclasses.replace(angles_run, trial=trial.with_markers(markers))


def sparse_knee_analysis(angles_run: Any, n_frames: int = 6) -> Any:
    """The real marker-error analysis (α = 0, 0.5, ±2.5° allowable error) of the left knee
    on ``n_frames`` frames spread over ``angles_run``'s trial (the other frames' markers NaN)."""
    from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings, analyse_run

    sparse = sparse_angles_run(angles_run, n_frames)
    return analyse_run(sparse, MarkerErrorSettings(alphas=(0.0, 0.5), angles=("LKneeAngles",), workers=1))


class TwoMarkerLine:
    """Analytic marker-error model: the direction of the line from marker A(t) to B(t) in
    the x-y plane (``atan2`` of ``B + p_B − A − p_A``), the deviations of A and B (mm) its 6
    parameters. With balls of radius r the line turns by at most arcsin(2r/d(t)) either
    way (the inner common tangent of the two circles).

    Args:
        n: time nodes on [0, 1] s.
        distance: ``(mean, amplitude)`` of d(t) = mean + amplitude·sin(2πt), mm.
        turn: ``(amplitude, frequency)`` of the direction amplitude·sin(frequency·πt), rad.
        offsets: A(t)'s x, y (as cos(3t)), z slopes, mm.
        degrees: the output in degrees (else rad).
        names: the two markers' names.
    """

    capabilities = frozenset({"nodes"})

    def __init__(self, n: int = 60, distance: tuple[float, float] = (200.0, 100.0),
                 turn: tuple[float, float] = (0.6, 2.6), offsets: tuple[float, float, float] = (50.0, 20.0, 5.0),
                 degrees: bool = False, names: tuple[str, str] = ("A", "B")) -> None:  # fmt: skip
        from fuzzygait.uncertainty import Output

        t = np.linspace(0.0, 1.0, n)
        self.times = t
        self.distance = distance[0] + distance[1] * np.sin(2 * np.pi * t)
        direction = turn[0] * np.sin(turn[1] * np.pi * t)
        self.a = np.stack([offsets[0] * t, offsets[1] * np.cos(3 * t), offsets[2] * t], axis=1)
        self.b = self.a + self.distance[:, None] * np.stack([np.cos(direction), np.sin(direction), 0 * t], axis=1)
        self.degrees = degrees
        self.parameter_names = tuple(f"{m}_{c}" for m in names for c in "xyz")
        self.output = Output("direction", "deg" if degrees else "rad")

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        P = np.asarray(P, dtype=float).reshape(len(nodes), 2, 3)
        v = (self.b[nodes] + P[:, 1]) - (self.a[nodes] + P[:, 0])
        angle = np.arctan2(v[:, 1], v[:, 0])
        return np.degrees(angle) if self.degrees else angle

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Any:
        from fuzzygait.uncertainty import Evaluation

        nodes = np.arange(self.times.size)
        return Evaluation(self.evaluate_nodes(np.tile(np.asarray(p, dtype=float), (nodes.size, 1)), nodes))


def trial_window(source: Path, target: Path, start: int, n: int) -> Path:
    """Frames ``start .. start + n`` of a trial as a new C3D file (events inside kept)."""
    import dataclasses

    from fuzzygait.io import read_c3d, write_c3d

    trial = read_c3d(source)
    t0, t1 = start / trial.rate, (start + n) / trial.rate
    events = [dataclasses.replace(e, time=e.time - t0) for e in trial.events if t0 <= e.time < t1]
    write_c3d(dataclasses.replace(trial, markers=trial.markers[start:start + n], outputs={}, output_kinds={},
                                  events=events), target)  # fmt: skip
    return target


def synthetic_session(folder: Path, frames: int) -> Path:
    """A synthetic session folder as a gait lab stores one: the static trial
    (``cal01.c3d``), two walking trials of ``frames`` frames cut from the bundled walking
    trial at frames 0 and 100 (``walk01.c3d``, ``walk02.c3d``) and the subject file."""
    import shutil

    folder.mkdir()
    shutil.copy(SAMPLE_DATA / "static.c3d", folder / "cal01.c3d")
    shutil.copy(SAMPLE_DATA / "subject.toml", folder / "Synthetic.toml")
    trial_window(SAMPLE_DATA / "walking.c3d", folder / "walk01.c3d", 0, frames)
    trial_window(SAMPLE_DATA / "walking.c3d", folder / "walk02.c3d", 100, frames)
    return folder


def stored_points(path: Path) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, str]]:
    """Per label: coordinates ``(3, frames)`` as stored, residuals, camera masks
    ``(7, frames)`` and description, as ezc3d reads them."""
    import ezc3d

    c = ezc3d.c3d(str(path))
    point = c["parameters"]["POINT"]
    descriptions = list(point["DESCRIPTIONS"]["value"])
    points = np.nan_to_num(c["data"]["points"][:3], nan=0.0)  # ezc3d: NaN where the residual is < 0
    residuals, masks = c["data"]["meta_points"]["residuals"][0], c["data"]["meta_points"]["camera_masks"]
    return {str(label).strip(): (points[:, i], residuals[i], masks[:, i], descriptions[i])
            for i, label in enumerate(point["LABELS"]["value"])}  # fmt: skip


def assert_points_kept(src: Path, out: Path) -> int:
    """Every marker of ``src`` in ``out`` keeps its description; a sample with the same
    coordinates keeps its residual, a changed or filled one has residual 0 (computed); a
    sample that replaces a measured one keeps its cameras, a filled one has none.
    Returns the number of changed samples."""
    from fuzzygait.io import read_c3d

    before, after = stored_points(src), stored_points(out)
    changed = 0
    trial = read_c3d(src)
    for label in (trial.label_prefix + name for name in trial.marker_labels):
        (p_in, r_in, m_in, d_in), (p_out, r_out, m_out, d_out) = before[label], after[label]
        assert d_out.strip() == d_in.strip(), label
        measured, valid = (r_in >= 0) & np.any(p_in != 0.0, axis=0), r_out >= 0
        same = measured & valid & np.all(p_in.astype(np.float32) == p_out.astype(np.float32), axis=0)
        assert np.array_equal(r_out[same], r_in[same]), label
        assert np.all(r_out[valid & ~same] == 0.0), label  # filtered or filled: computed
        assert np.array_equal(m_out[:, measured & valid], m_in[:, measured & valid]), label
        assert not m_out[:, valid & ~measured].any(), label  # a filled sample was seen by no camera
        changed += int(np.count_nonzero(valid & ~same))
    return changed


def write_cut(src: Path, out: Path, first: int = 101, count: int = 200) -> Any:
    """The trial of ``src`` cut to ``count`` frames from C3D frame ``first``, written to
    ``out`` with ``src`` carried over (nothing noted); returns the uncut trial."""
    from dataclasses import replace

    from fuzzygait.io import read_c3d, write_c3d

    trial = read_c3d(src)
    cut = replace(trial, markers=trial.markers[first - 1 : first - 1 + count], first_frame=first)
    assert write_c3d(cut, out, source=src) == []
    return trial


#: The peak of :class:`Bowl` (|PEAK| = 5, outside the balls of radius 2 about 0 the tests take).
PEAK = np.array([3.0, -4.0, 0.0])


class Bowl:
    """``f(p, t) = −|p − PEAK|² + t`` on one 3-vector: over the ball of radius ``r`` about
    0 its maximum is at ``r PEAK/5``, worth ``−(5 − r)² + t``; at ``p = 0``, ``−25 + t``."""

    def __init__(self, limit: float | None = None, n_time: int = 6) -> None:
        self.times = np.arange(n_time) / 100.0
        self.time_step = 0.01
        self.parameter_names = ("m_x", "m_y", "m_z")
        self.output = Output("f", "1")
        self.capabilities = frozenset({"nodes", "node_gradients", "time_step"}
                                      | ({"excursion_limit"} if limit is not None else set()))  # fmt: skip
        if limit is not None:
            self.excursion_limit = limit

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        nodes = np.arange(self.times.size)
        return Evaluation(self.evaluate_nodes(np.tile(p, (nodes.size, 1)), nodes))

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        return -np.sum((P - PEAK) ** 2, axis=1) + nodes

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.evaluate_nodes(P, nodes), -2.0 * (P - PEAK)
