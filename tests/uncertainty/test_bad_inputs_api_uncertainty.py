"""Bad input to the uncertainty engine's API gets one clear fuzzygait error naming the
offending argument or file, never NaN or an internal error later (audit items 4, 5, 6, 14)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.markererror.result import read_marker_result
from fuzzygait.uncertainty import FuzzyBalls, FuzzyVector, load_result, triangular
from fuzzygait.uncertainty.postprocess import failure_probability
from fuzzygait.uncertainty.storage import load_groups


# ------------------------------------------------------------------ 4: membership of NaN
def test_the_membership_of_nan_is_nan_elementwise() -> None:
    fn = triangular(0.0, 1.0, 2.0)
    mu = fn.membership(np.array([np.nan, 1.0, 0.5, 3.0, np.nan]))
    np.testing.assert_array_equal(mu, [np.nan, 1.0, 0.5, 0.0, np.nan])
    assert np.isnan(fn.membership(np.nan))
    assert fn.membership(1.0) == 1.0


# ------------------------------------------------------------------ 5: FuzzyBalls, FuzzyVector
@pytest.mark.parametrize(
    ("centres", "radii", "names", "needle"),
    [
        ([[0.0, np.nan, 0.0]], [1.0], (), r"ball centres must be finite; ball0 not"),
        ([[0.0, 0.0, 0.0], [0.0, np.inf, 0.0]], [1.0, 1.0], ("A", "B"), r"ball centres must be finite; B not"),
        ([0.0, 0.0, 0.0], [1.0], (), r"centres must be an \(n_balls, block\) array .*got shape \(3,\)"),
        (np.zeros((0, 3)), [], (), r"at least one ball.*got shape \(0, 3\)"),
        (np.zeros((2, 3)), [[1.0, 2.0]], (), r"one radius per ball needed \(shape \(2,\)\): 2 balls, radii of shape "
                                             r"\(1, 2\)"),
        (np.zeros((2, 3)), [1.0, 2.0], ("LKNE",), r"one name per ball needed \(or none\): 2 balls, 1 names \['LKNE'\]"),
    ],
)  # fmt: skip
def test_fuzzy_balls_refuse_impossible_arguments(centres, radii, names, needle) -> None:
    with pytest.raises(ParameterError, match=needle):
        FuzzyBalls(np.asarray(centres, dtype=float), np.asarray(radii, dtype=float), names)


def test_good_fuzzy_balls_are_kept() -> None:
    balls = FuzzyBalls(np.zeros((2, 3)), [1.0, 2.0], ["A", "B"])
    assert balls.names_ == ("A", "B") and balls.dim == 6


def test_a_fuzzy_vector_refuses_plain_numbers_and_repeated_names() -> None:
    k = triangular(0.9, 1.0, 1.1, "k")
    with pytest.raises(ParameterError, match=r"fuzzy parameters must be FuzzyNumber .*got 1: 0\.5"):
        FuzzyVector([k, 0.5])  # type: ignore[list-item]
    with pytest.raises(ParameterError, match=r"fuzzy parameter names must differ; k given more than once"):
        FuzzyVector([k, triangular(1.0, 2.0, 3.0, "k")])
    with pytest.raises(ParameterError, match=r"give the fuzzy parameters as a list"):
        FuzzyVector(k)  # type: ignore[arg-type]
    assert FuzzyVector([k, triangular(1.0, 2.0, 3.0)]).names == ["k", "p1"]


# ------------------------------------------------------------------ 6: failure probability
def _result() -> xr.Dataset:
    hull = np.array([[[0.0], [2.0]], [[1.0], [1.0]]])  # (alpha, bound, time): a triangle 0, 1, 2
    return xr.Dataset({"hull": (("alpha", "bound", "time"), hull), "deterministic": (("time",), [1.0])},
                      coords={"alpha": [0.0, 1.0], "bound": ["lower", "upper"], "time": [0.0]})  # fmt: skip


@pytest.mark.parametrize("limit", [np.nan, np.inf, -np.inf, "1.0"])
def test_failure_probability_refuses_a_limit_that_is_not_a_finite_number(limit) -> None:
    with pytest.raises(ParameterError, match=r"limit must be a finite number"):
        failure_probability(_result(), limit)
    assert float(failure_probability(_result(), 1.0)[0]) == pytest.approx(0.5)


# ------------------------------------------------------------------ 14: not a result file
@pytest.mark.parametrize("read", [load_result, load_groups, read_marker_result])
@pytest.mark.parametrize("kind", ["text.nc", "empty.zarr", "file.zarr"])
def test_a_file_that_is_not_a_result_is_named(tmp_path, read, kind) -> None:
    path = tmp_path / kind
    if kind == "empty.zarr":
        path.mkdir()
    else:
        path.write_text("not a dataset\n")
    with pytest.raises(FuzzyGaitError, match=rf"{kind}: not a fuzzygait result dataset \(a \.nc or \.zarr written by "
                                             r"fuzzygait\)"):  # fmt: skip
        read(path)
