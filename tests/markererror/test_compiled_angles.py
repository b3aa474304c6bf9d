"""The compiled joint-angle models (issue 40): the chain traced with symbols, its angles and
gradients in C (:mod:`fuzzygait.markererror.row_kernel`).

Independent truth: the numpy chain itself (``compiled=False``: the same code run on
numbers) and autograd's reverse sweep through it, for every angle of every Plug-in Gait
version and with non-zero static offsets (the rotated chord's fixed steps); the central
differences of ``test_exact_gradients.py`` check the compiled gradients too, since those
models now run compiled.  A row the fixed steps do not settle (the rotated chord, the
cluster fits' polar rotation), or a cluster row with a marker missing, is handed back to
the chain.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from fuzzygait.kinematics.versions import MODEL_VERSIONS
from fuzzygait.markererror import row_kernel
from fuzzygait.markererror.angle_model import JointAngleModel, fixed_subject
from fuzzygait.markererror.symbols import NotTraceable, Symbol, expressions, symbol_array
from fuzzygait.workflows.angles import AnglesRun, run_angles
from support import SAMPLE_DATA

FRAMES = np.array([3, 40, 77, 150, 210])
CGM24 = dict(static=SAMPLE_DATA / "cgm24_static.c3d", subject_file=SAMPLE_DATA / "cgm24_subject.toml")


@pytest.fixture(scope="module")
def runs() -> dict[str, AnglesRun]:
    """The synthetic CGM 2.4 walking trial by every model version."""
    return {model: run_angles(SAMPLE_DATA / "cgm24_walking.c3d", model=model, **CGM24) for model in MODEL_VERSIONS}


@pytest.fixture(scope="module")
def offsets_run(angles_run: AnglesRun) -> AnglesRun:
    """Plug-in Gait with the KAD's thigh and shank rotations, tibial torsion and AnkleAbAdd
    on the left side: the rotated chord iterates."""
    subject = angles_run.subject.with_side("L", thigh_rotation=0.12, shank_rotation=-0.09, tibial_torsion=0.3,
                                           ankle_abadd=0.06)  # fmt: skip
    return dataclasses.replace(angles_run, subject=subject)


def model_of(run: AnglesRun, name: str, axis: int = 0, **kwargs: object) -> JointAngleModel:
    reference = run.result.angles[name][FRAMES, axis]
    return JointAngleModel(run.trial, fixed_subject(run.trial, run.subject), run.result.progression, name, axis,
                           FRAMES, model=run.model, clusters=run.clusters, reference=reference,
                           **kwargs)  # type: ignore[arg-type]  # fmt: skip


def assert_same_as_chain(model: JointAngleModel, P: np.ndarray) -> None:
    """Values within 1e-10 deg and gradients within 1e-10 deg/mm of the numpy chain's."""
    chain = dataclasses.replace(model, compiled=False)
    nodes = np.arange(P.shape[0]) % FRAMES.size
    np.testing.assert_allclose(model.evaluate_nodes(P, nodes), chain.evaluate_nodes(P, nodes), rtol=0, atol=1e-10)
    values, gradients = model.evaluate_nodes_gradients(P, nodes)
    chain_values, chain_gradients = chain.evaluate_nodes_gradients(P, nodes)
    np.testing.assert_allclose(values, chain_values, rtol=0, atol=1e-10)
    np.testing.assert_allclose(gradients, chain_gradients, rtol=1e-9, atol=1e-10)


def deviations(model: JointAngleModel, scale: float, rows: int = 20, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).normal(scale=scale, size=(rows, model.n_parameters))


#: Versions the fast selection checks (Plug-in Gait, and the cluster fits with the forefoot);
#: the others compile for 20 s more on a fresh clone and run in the full suite.
FAST_VERSIONS = ("cgm1.0", "cgm2.4")


@pytest.mark.parametrize("version", [v if v in FAST_VERSIONS else pytest.param(v, marks=pytest.mark.slow)
                                     for v in MODEL_VERSIONS])  # fmt: skip
def test_every_angle_compiled_equals_the_chain(runs: dict[str, AnglesRun], version: str) -> None:
    """Every angle and component of every version at deviations of 5 and 40 mm (CGM 2.3/2.4:
    the cluster fits' polar rotation in its fixed Newton steps; cgm2.4: the forefoot)."""
    run = runs[version]
    for name in run.result.angles:
        for axis in range(3):
            model = model_of(run, name, axis)
            assert model.kernel() is not None, f"{version} {name}"
            assert_same_as_chain(model, np.vstack([deviations(model, 5.0), deviations(model, 40.0, seed=1)]))


def test_a_cluster_marker_missing_is_fitted_from_the_others(runs: dict[str, AnglesRun]) -> None:
    """CGM 2.4 knee with one thigh cluster marker missing at a frame: the kernel assumes
    every marker seen, so that row goes to the chain, which fits the cluster from the
    others — a finite angle, the chain's."""
    run = runs["cgm2.4"]
    clusters = run.clusters
    assert clusters is not None
    label = clusters.segment("L", "thigh").markers[0]
    markers = run.trial.markers.copy()
    markers[FRAMES[1], run.trial.marker_labels.index(label)] = np.nan
    gapped = dataclasses.replace(run, trial=run.trial.with_markers(markers))
    model = model_of(gapped, "LKneeAngles", 0)
    kernel = model.kernel()
    assert kernel is not None and label in model.markers
    P = deviations(model, 5.0, rows=FRAMES.size)
    _, status = kernel.values(model._rows, np.arange(FRAMES.size), P, model.progression)
    assert status.tolist() == [0, row_kernel.MISSING, 0, 0, 0]
    values = model.evaluate_nodes(P, np.arange(FRAMES.size))
    assert np.isfinite(values).all()
    assert_same_as_chain(model, P)


@pytest.mark.parametrize("name", ["LHipAngles", "LKneeAngles", "LAnkleAngles", "LFootProgressAngles"])
def test_static_offsets_compiled_equal_the_chain(offsets_run: AnglesRun, name: str) -> None:
    """The rotated chord runs a fixed number of steps in C; rows far outside any ball
    (100 mm deviations) that the steps do not settle are handed back to the chain."""
    for axis in range(3):
        model = model_of(offsets_run, name, axis)
        assert model.kernel() is not None
        assert_same_as_chain(model, np.vstack([deviations(model, 5.0, seed=axis), deviations(model, 100.0, 60)]))


def test_unsettled_rows_are_recognised(offsets_run: AnglesRun) -> None:
    """Some 100 mm rows do not settle in the fixed steps (the case the test above covers)."""
    model = model_of(offsets_run, "LKneeAngles")
    kernel = model.kernel()
    assert kernel is not None
    P = deviations(model, 100.0, 60)
    nodes = np.arange(P.shape[0]) % FRAMES.size
    base = np.concatenate([model._base, model._fixed], axis=1).reshape(FRAMES.size, -1)
    angles, status = kernel.values(base, nodes, P, model.progression)
    unsettled = status == row_kernel.UNSETTLED
    assert unsettled.any() and np.isnan(angles[unsettled]).all()
    assert np.all(np.isfinite(model.evaluate_nodes(P, nodes)[unsettled]))  # the chain's numbers there


def test_a_missing_marker_gives_nan_like_the_chain(angles_run: AnglesRun) -> None:
    markers = angles_run.trial.markers.copy()
    markers[FRAMES[2], angles_run.trial.marker_labels.index("LKNE")] = np.nan
    gapped = dataclasses.replace(angles_run, trial=angles_run.trial.with_markers(markers))
    model = model_of(gapped, "LKneeAngles", 1)
    P = deviations(model, 5.0, rows=FRAMES.size)
    values, gradients = model.evaluate_nodes_gradients(P, np.arange(FRAMES.size))
    assert np.isnan(values[2]) and np.isnan(gradients[2]).all()
    kernel = model.kernel()
    assert kernel is not None
    base = np.concatenate([model._base, model._fixed], axis=1).reshape(FRAMES.size, -1)
    _, status = kernel.values(base, np.arange(FRAMES.size), P, model.progression)
    assert status.tolist() == [0, 0, row_kernel.MISSING, 0, 0]
    assert np.isfinite(np.delete(values, 2)).all() and np.isfinite(np.delete(gradients, 2, axis=0)).all()
    assert_same_as_chain(model, P)


def test_no_compiler_means_the_chain(angles_run: AnglesRun, monkeypatch: pytest.MonkeyPatch) -> None:
    """``FUZZYGAIT_NO_COMPILE=1``: no kernel, the chain's numbers."""
    monkeypatch.setenv("FUZZYGAIT_NO_COMPILE", "1")
    monkeypatch.setattr(row_kernel, "_KERNELS", {})
    model = model_of(angles_run, "RHipAngles")
    assert model.kernel() is None and dataclasses.replace(model, compiled=False).kernel() is None
    P = deviations(model, 5.0)
    nodes = np.arange(P.shape[0]) % FRAMES.size
    np.testing.assert_array_equal(model.evaluate_nodes(P, nodes),
                                  dataclasses.replace(model, compiled=False).evaluate_nodes(P, nodes))  # fmt: skip


def test_the_library_is_compiled_once(angles_run: AnglesRun, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A second process (here: an emptied memo) loads the cached library, compiling nothing."""
    monkeypatch.setenv("FUZZYGAIT_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(row_kernel, "_KERNELS", {})
    model = model_of(angles_run, "LAnkleAngles", 2)
    first = model.kernel()
    assert first is not None and len(list(tmp_path.glob("fg_rows_*.so"))) == 1
    monkeypatch.setattr(row_kernel, "_KERNELS", {})

    def refuse(*_: object, **__: object) -> None:
        raise AssertionError("compiled again")

    monkeypatch.setattr(row_kernel, "build_library", refuse)
    again = model_of(angles_run, "LAnkleAngles", 2).kernel()
    assert again is not None and again is not first
    P = deviations(model, 5.0, rows=FRAMES.size)
    base, nodes = np.concatenate([model._base, model._fixed], axis=1).reshape(FRAMES.size, -1), np.arange(FRAMES.size)
    np.testing.assert_array_equal(again.values(base, nodes, P, model.progression)[0],
                                  first.values(base, nodes, P, model.progression)[0])  # fmt: skip


# ---------------------------------------------------------------------------- symbols
def evaluate(expression: Symbol, x: ca.SX, value: float) -> float:
    return float(ca.Function("f", [x], [expressions([expression])])(value))


def test_symbols_refuse_decisions() -> None:
    a = symbol_array(ca.SX.sym("x", 2), (2,))
    for decide in (lambda: bool(a[0]), lambda: a[0] > 1.0, lambda: a[0] == a[1], lambda: float(a[0]),
                   lambda: np.any(a > 0.0)):  # fmt: skip
        with pytest.raises(NotTraceable):
            decide()


@pytest.mark.parametrize("value", [-725.5, -180.0, -0.25, 0.0, 179.75, 180.0, 540.25])
def test_symbolic_modulo_and_wrap_are_numpys(value: float) -> None:
    x = ca.SX.sym("x")
    s = Symbol(x)
    assert evaluate(s % 360.0, x, value) == pytest.approx(np.mod(value, 360.0), abs=1e-12)
    assert evaluate(180.0 - (180.0 - s) % 360.0, x, value) == pytest.approx(180.0 - np.mod(180.0 - value, 360.0),
                                                                            abs=1e-12)  # fmt: skip


@pytest.mark.parametrize("value", [-1.5, -1.0, -0.3, 0.999, 1.0 + 1e-12, 2.0])
def test_symbolic_capped_arcsin(value: float) -> None:
    x = ca.SX.sym("x")
    assert evaluate(Symbol(x).capped_arcsin(), x, value) == pytest.approx(np.arcsin(np.clip(value, -1, 1)), abs=1e-15)
    assert np.isnan(evaluate(Symbol(x).capped_arcsin(), x, np.nan))
    assert evaluate(Symbol(x).undefined_above(1.0), x, min(value, 1.0)) == 0.0
    assert np.isnan(evaluate(Symbol(x).undefined_above(1.0), x, 1.5))


def test_a_model_with_its_kernel_pickles(angles_run: AnglesRun) -> None:
    """Sent to a worker after use: the loaded library stays behind, the worker loads its own."""
    import pickle

    model = model_of(angles_run, "RKneeAngles", 1)
    assert model.kernel() is not None
    copy = pickle.loads(pickle.dumps(model))
    P = deviations(model, 5.0)
    nodes = np.arange(P.shape[0]) % FRAMES.size
    np.testing.assert_array_equal(copy.evaluate_nodes(P, nodes), model.evaluate_nodes(P, nodes))
    assert copy.kernel() is not None


def test_a_cache_that_cannot_be_written_means_numpy_with_a_warning(angles_run: AnglesRun, tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    """``FUZZYGAIT_CACHE_DIR`` pointing into a file: one warning naming the folder and what to
    do, the chain's numbers."""
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder", encoding="utf-8")
    monkeypatch.setenv("FUZZYGAIT_CACHE_DIR", str(blocker / "cache"))
    monkeypatch.setattr(row_kernel, "_KERNELS", {})
    model = model_of(angles_run, "LHipAngles", 1)
    with pytest.warns(UserWarning, match="FUZZYGAIT_CACHE_DIR to a writable folder"):
        assert model.kernel() is None
    P = deviations(model, 5.0)
    nodes = np.arange(P.shape[0]) % FRAMES.size
    np.testing.assert_array_equal(model.evaluate_nodes(P, nodes),
                                  dataclasses.replace(model, compiled=False).evaluate_nodes(P, nodes))  # fmt: skip
