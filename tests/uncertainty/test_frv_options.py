"""StudyOptions / MultiStudyOptions: each bad field refused in one line naming it."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty import FunctionModel
from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy, Grid, MultiStudyOptions, StudyOptions

TIMES = np.linspace(0.0, 1.0, 5)


@pytest.mark.parametrize("field, value, said", [
    ("n_disc", 1, "n_disc must be a whole number >= 2"),
    ("n_disc", 2.5, "n_disc must be a whole number >= 2"),
    ("n_disc", (8, 1), "n_disc must be a whole number >= 2"),
    ("n_disc", (), "n_disc must be a whole number >= 2 or one per parameter"),
    ("n_disc", True, "n_disc must be a whole number >= 2 or one per parameter"),
    ("seed", -1, "seed must be a whole number >= 0"),
    ("seed", 1.0, "seed must be a whole number >= 0"),
    ("time_stride", 0, "time_stride must be a whole number >= 1"),
    ("chunk", 0, "chunk must be a whole number >= 1"),
    ("refine", "yes", "refine must be True, False or None"),
    ("overwrite", 1, "overwrite must be True or False"),
    ("record", [("a", 1)], "record must be a mapping"),
])  # fmt: skip
def test_each_bad_study_option_is_refused_in_one_line(field, value, said) -> None:
    for cls in (StudyOptions, MultiStudyOptions):
        with pytest.raises(ParameterError, match=f"^{said}") as caught:
            cls(**{field: value})
        assert "\n" not in str(caught.value)


@pytest.mark.parametrize("field, value, said", [
    ("grids", Grid.from_range(0.0, 1.0, 4), "grids: give one Grid per parameter"),
    ("grids", [1.0, 2.0], "grids: give one Grid per parameter"),
    ("peak_refine", 3, "peak_refine: .*each of 1, 2, 4, 8"),
    ("peak_refine", (1, 16), "peak_refine: .*each of 1, 2, 4, 8"),
    ("peak_refine", True, "peak_refine: .*each of 1, 2, 4, 8"),
    ("peak_tolerance", 1.5, "peak_tolerance must lie between 0 and 1"),
    ("peak_tolerance", float("nan"), "peak_tolerance must lie between 0 and 1"),
    ("peak_tolerance", "0.1", "peak_tolerance must lie between 0 and 1"),
])  # fmt: skip
def test_each_bad_multi_option_is_refused_in_one_line(field, value, said) -> None:
    with pytest.raises(ParameterError, match=f"^{said}") as caught:
        MultiStudyOptions(**{field: value})
    assert "\n" not in str(caught.value)


def test_options_are_normalised_and_frozen() -> None:
    options = MultiStudyOptions(n_disc=[np.int64(6), 7], seed=np.int64(3), refine=np.bool_(True),
                                peak_refine=[2, 1])  # fmt: skip
    assert options.n_disc == (6, 7) and type(options.seed) is int and options.refine is True
    assert options.peak_refine == (2, 1) and options.discs(2, 30) == [6, 7]
    assert StudyOptions().discs(1, 100) == [100] and StudyOptions(n_disc=5).discs(3, 30) == [5, 5, 5]
    with pytest.raises(ParameterError, match=r"n_disc: give one number or one per parameter \(3\)"):
        options.discs(3, 30)
    with pytest.raises(AttributeError):
        options.seed = 4  # type: ignore[misc]
    plain = StudyOptions(n_disc=9, seed=2, chunk=32, overwrite=True, record={"a": 1})
    widened = MultiStudyOptions.of(plain)
    assert (widened.n_disc, widened.seed, widened.chunk, widened.overwrite, widened.record) == (9, 2, 32, True, {"a": 1})
    assert widened.peak_refine is None and MultiStudyOptions.of(None) == MultiStudyOptions()
    assert StudyOptions(record=None).record == {}


def test_create_refuses_other_options_and_wrong_disc_counts(tmp_path) -> None:
    model = FunctionModel(lambda p: p[..., :1] * TIMES, TIMES)
    with pytest.raises(ParameterError, match="options: give a StudyOptions"):
        FRVStudy.create(model, FRVSpec("p", 1.0), 10, {"n_disc": 8}, store=tmp_path / "a.zarr")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"n_disc: give one number or one per parameter \(1\)"):
        FRVStudy.create(model, FRVSpec("p", 1.0), 10, StudyOptions(n_disc=(8, 9)), store=tmp_path / "b.zarr")
    specs = [FRVSpec("p", 1.0), FRVSpec("q", 2.0)]
    two = FunctionModel(lambda p: (p[..., :1] + p[..., 1:2]) * TIMES, TIMES)
    with pytest.raises(ParameterError, match=r"n_disc: give one number or one per parameter \(2\)"):
        FRVStudy.create(two, specs, 10, StudyOptions(n_disc=(8, 9, 10)), store=tmp_path / "c.zarr")
    with pytest.raises(ParameterError, match=r"grids: give one Grid per parameter \(2\)"):
        FRVStudy.create(two, specs, 10, MultiStudyOptions(grids=[Grid.from_range(0.0, 1.0, 4)]),
                        store=tmp_path / "d.zarr")  # fmt: skip
    assert not any(tmp_path.iterdir())
