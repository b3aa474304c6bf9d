"""The marker-error result as three datasets (issue 38 item 2): the bands at the root, the
allowable-error refinement and the per-source bands as groups with plain names; a file of
layout version 1 (one flat dataset with ``refined_*``/``allowable_*``/``source_*``
variables, written here by hand with the names of that layout) reads back as the same
result, number for number; a newer version is refused in one line; ``check_result`` checks
every part and names the part that breaks the schema. The error sources of the bands (and
the kinetics) are the coordinate ``error_source``, kept by .nc and .zarr even for one
source; a file that names them in the old comma-joined attribute ``sources`` reads as the
new layout; no string attribute of any part is a comma-joined list.

Speed: the sample trial cut to 6 frames, left knee, α = 0 and 0.5 (as test_per_source).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.markererror.allowable import AllowableRequest, allowable_errors, allowable_table
from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles
from fuzzygait.markererror.per_source import PerSourceRequest, per_source_bands, widest_source_bands
from fuzzygait.markererror.result import (
    MarkerErrorResult,
    error_sources,
    read_marker_result,
    save_marker_result,
    with_error_sources,
)
from fuzzygait.testing import ModelCheckError, check_result
from fuzzygait.uncertainty.storage import load_groups, load_result, save_groups, save_result
from fuzzygait.workflows.angles import AnglesRun
from support import sparse_angles_run

KNEE = "LKneeAngles_X"
ALL_SOURCES = ("measurement", "placement", "sta")
#: A list joined by commas without spaces ("measurement,sta", "0,0.5"), not prose ("a, b").
COMMA_LIST = re.compile(r"[^\s,]+,[^\s,]+")


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
    flat = result.bands.drop_vars("error_source")
    flat.attrs["sources"] = "measurement,placement,sta"
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
    assert list(groups) == ["/", "/allowable", "/sources"] and groups["/"].attrs["layout_version"] == 3
    assert set(groups["/allowable"].data_vars) >= {"alpha", "hull", "undetermined", "scale", "status"}
    assert groups["/sources"]["hull"].dims == ("source", "component", "alpha", "bound", "frame")
    assert groups["/sources"]["alpha"].to_numpy().tolist() == [0.0, 1.0]  # a coordinate, not "0,1"
    for dataset in groups.values():
        assert not any(str(v).startswith(("refined_", "allowable_", "source_")) for v in dataset.variables)
        assert not any(isinstance(v, str) and "," in v for v in dataset.attrs.values())
    assert groups["/"]["error_source"].dims == ("error_source",) and "sources" not in groups["/"].attrs
    assert groups["/"]["error_source"].to_numpy().tolist() == list(ALL_SOURCES)
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
    future.attrs["layout_version"] = 4
    path = save_result(future, tmp_path / "future.nc")
    with pytest.raises(FuzzyGaitError, match=r"layout version 4.*update fuzzygait") as error:
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


def _kinetics_like(bands: xr.Dataset) -> xr.Dataset:
    """A stand-in kinetics group (the bands with a ``units`` coordinate), for the storage
    of its error sources only."""
    return bands.assign_coords(units=("component", ["N·m/kg"] * bands.sizes["component"]))


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_error_sources_are_a_coordinate_in_both_formats(result: MarkerErrorResult, tmp_path: Path,
                                                        suffix: str) -> None:  # fmt: skip
    assert error_sources(result.bands) == ALL_SOURCES
    one = with_error_sources(result.bands.drop_vars("error_source"), ["sta"])  # one name: no scalar in netCDF
    saved = MarkerErrorResult(one, result.allowable, result.sources, _kinetics_like(one))
    again = read_marker_result(save_marker_result(saved, tmp_path / f"one{suffix}"))
    assert again.kinetics is not None
    for part in (again.bands, again.kinetics):
        assert part["error_source"].dims == ("error_source",) and error_sources(part) == ("sta",)
    xr.testing.assert_identical(again.bands, one)
    plain = load_result(save_result(result.bands, tmp_path / f"plain{suffix}"))  # a plain reader keeps it too
    assert plain["error_source"].to_numpy().tolist() == list(ALL_SOURCES)


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_old_sources_attribute_reads_as_the_coordinate(result: MarkerErrorResult, tmp_path: Path,
                                                       suffix: str) -> None:  # fmt: skip
    """A version-2 file written before the coordinate (the attribute on the bands and the
    kinetics) reads as one written now."""
    kinetics = _kinetics_like(result.bands)
    new = MarkerErrorResult(result.bands, result.allowable, result.sources, kinetics)
    old_bands = result.bands.drop_vars("error_source").assign_attrs(sources="measurement,placement,sta",
                                                                    layout_version=2)  # fmt: skip
    old_kinetics = kinetics.drop_vars("error_source").assign_attrs(sources="measurement,placement,sta")
    assert error_sources(old_bands) == ALL_SOURCES  # read straight from a dataset of an old file
    path = save_groups({"/": old_bands, "/allowable": result.allowable, "/sources": result.sources,
                        "/kinetics": old_kinetics}, tmp_path / f"old{suffix}")  # fmt: skip
    old = read_marker_result(path)
    for part in ("bands", "allowable", "sources", "kinetics"):
        xr.testing.assert_identical(getattr(old, part), getattr(new, part))
    assert "sources" not in old.bands.attrs and check_result(old)["values"] == check_result(new)["values"]


def test_old_sources_attribute_naming_no_source_is_one_line(result: MarkerErrorResult) -> None:
    old = result.bands.drop_vars("error_source").assign_attrs(sources="measurement,gps")
    with pytest.raises(ParameterError, match=r"attribute 'sources' = 'measurement,gps'.*unknown") as error:
        error_sources(old)
    assert "\n" not in str(error.value)
    assert error_sources(result.bands.drop_vars("error_source")) == ()  # names none


def test_no_attribute_is_a_comma_joined_list(result: MarkerErrorResult, tmp_path: Path) -> None:
    saved = MarkerErrorResult(result.bands, result.allowable, result.sources, _kinetics_like(result.bands))
    for name, dataset in load_groups(save_marker_result(saved, tmp_path / "fuzzy.nc")).items():
        for owner, attrs in [(name, dataset.attrs), *((f"{name} {v}", dataset[v].attrs) for v in dataset.variables)]:
            lists = {k: v for k, v in attrs.items() if isinstance(v, str) and COMMA_LIST.search(v)}
            assert not lists, f"{owner}: {lists}"
    assert COMMA_LIST.search("measurement,placement,sta") and not COMMA_LIST.search("lower, upper")
