"""The marker-error result as three datasets (issue 38 item 2): the bands at the root, the
allowable-error refinement and the per-source bands as groups with plain names; a file of
layout version 1 (one flat dataset with ``refined_*``/``allowable_*``/``source_*``
variables, written here by hand with the names of that layout) reads back as the same
result, number for number; a newer version is refused in one line; ``check_result`` checks
every part and names the part that breaks the schema.

Speed: the sample trial cut to 6 frames, left knee, α = 0 and 0.5 (as test_per_source).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.markererror.allowable import AllowableRequest, allowable_errors, allowable_table
from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles
from fuzzygait.markererror.per_source import PerSourceRequest, per_source_bands, widest_source_bands
from fuzzygait.markererror.result import MarkerErrorResult, read_marker_result, save_marker_result
from fuzzygait.testing import ModelCheckError, check_result
from fuzzygait.uncertainty.storage import load_groups, load_result, save_result
from fuzzygait.workflows.angles import AnglesRun
from support import sparse_angles_run

KNEE = "LKneeAngles_X"


@pytest.fixture(scope="module")
def result(angles_run: AnglesRun) -> MarkerErrorResult:
    run = sparse_angles_run(angles_run, 6)
    options = FuzzyAngleOptions(alphas=(0.0, 0.5), workers=1)
    plain = fuzzy_joint_angles(run.trial, run.subject, run.result, options, ["LKneeAngles"])
    _, refined = allowable_errors(run.trial, run.subject, run.result, AllowableRequest(options, angles=[KNEE]),
                                  fuzzy=plain)  # fmt: skip
    sources = per_source_bands(run.trial, run.subject, run.result, refined.bands, PerSourceRequest(options))
    return MarkerErrorResult(refined.bands, refined.allowable, sources)


def _flat(result: MarkerErrorResult) -> xr.Dataset:
    """``result`` in layout version 1, as fuzzygait wrote it before issue 38 (names typed out)."""
    assert result.allowable is not None and result.sources is not None
    flat = result.bands.copy()
    levels, sources = result.allowable, result.sources
    for new, old in {"alpha": "refined_alpha", "hull": "refined_hull", "undetermined": "refined_undetermined",
                     "deviation": "refined_deviation"}.items():  # fmt: skip
        flat[old] = levels[new]
    for name in ("scale", "mm", "failing_scale", "excursion", "evaluations", "status"):
        flat[f"allowable_{name}"] = levels[name]
    flat["allowable_alpha"] = 1.0 - levels["scale"]
    flat["segment_radius"] = levels["segment_radius"]
    renamed = sources.rename({"component": "source_component", "alpha": "source_alpha"})
    for name in ("hull", "undetermined", "ball_radius"):
        flat[f"source_{name}"] = renamed[name]
    flat.attrs.update({"tolerance_deg": levels.attrs["tolerance_deg"],
                       "allowable_resolution_mm": levels.attrs["resolution_mm"],
                       "allowable_source": levels.attrs["source"], "allowable_seconds": levels.attrs["seconds"],
                       "allowable_runs": levels.attrs["runs"],
                       "allowable_node_evaluations": levels.attrs["node_evaluations"],
                       "source_seconds": sources.attrs["seconds"], "source_runs": sources.attrs["runs"],
                       "source_forward_simulations": sources.attrs["forward_simulations"],
                       "source_node_evaluations": sources.attrs["node_evaluations"],
                       "source_nesting_excess_deg": sources.attrs["nesting_excess_deg"],
                       "source_alphas": ",".join(f"{a:g}" for a in sources["alpha"].to_numpy())})  # fmt: skip
    return flat


def test_groups_with_plain_names(result: MarkerErrorResult, tmp_path: Path) -> None:
    path = save_marker_result(result, tmp_path / "fuzzy.nc")
    groups = load_groups(path)
    assert list(groups) == ["/", "/allowable", "/sources"] and groups["/"].attrs["layout_version"] == 2
    assert set(groups["/allowable"].data_vars) >= {"alpha", "hull", "undetermined", "scale", "status"}
    assert groups["/sources"]["hull"].dims == ("source", "component", "alpha", "bound", "frame")
    assert groups["/sources"]["alpha"].to_numpy().tolist() == [0.0, 1.0]  # a coordinate, not "0,1"
    for dataset in groups.values():
        assert not any(str(v).startswith(("refined_", "allowable_", "source_")) for v in dataset.variables)
        assert not any(isinstance(v, str) and "," in v and k != "sources" for k, v in dataset.attrs.items())
    xr.testing.assert_identical(load_result(path), groups["/"])  # a plain reader gets the bands


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_version_1_file_reads_as_the_same_result(result: MarkerErrorResult, tmp_path: Path, suffix: str) -> None:
    old = read_marker_result(save_result(_flat(result), tmp_path / f"old{suffix}"))
    new = read_marker_result(save_marker_result(result, tmp_path / f"new{suffix}"))
    for part in ("bands", "allowable", "sources"):
        xr.testing.assert_identical(getattr(old, part), getattr(new, part))
    assert allowable_table(old).equals(allowable_table(result))
    assert widest_source_bands(old).widths.equals(widest_source_bands(result).widths)
    np.testing.assert_array_equal(old.bands["hull"], result.bands["hull"])


def test_newer_version_refused_in_one_line(result: MarkerErrorResult, tmp_path: Path) -> None:
    future = result.bands.copy()
    future.attrs["layout_version"] = 3
    path = save_result(future, tmp_path / "future.nc")
    with pytest.raises(FuzzyGaitError, match=r"layout version 3.*update fuzzygait") as error:
        read_marker_result(path)
    assert "\n" not in str(error.value)


def test_check_result_checks_every_part(result: MarkerErrorResult) -> None:
    figures = check_result(result)
    assert list(result.parts()) == ["/", "/sources", f"/allowable/{KNEE}"]
    assert figures["values"] == sum(np.isfinite(p["hull"].to_numpy()).sum() for p in result.parts().values())
    assert result.sources is not None
    broken = result.sources.copy(deep=True)
    broken["hull"].loc[{"source": "sta", "alpha": 1.0, "bound": "upper"}] += 1.0  # α = 1 no longer one value
    with pytest.raises(ModelCheckError, match=r"^/sources: α = 1 not a single value"):
        check_result(MarkerErrorResult(result.bands, result.allowable, broken))
