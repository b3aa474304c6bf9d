"""``fuzzygait simulate`` end to end (subprocess), with its .nc, .rrd and energy plot."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from support import assert_one_line_error, run, run_here

xr = pytest.importorskip("xarray")

DURATION, DT, NODES = 0.05, 0.001, 6
SHORT = ("swing", "--duration", str(DURATION), "--nodes", str(NODES))


@pytest.fixture(scope="module")
def short_run(tmp_path_factory) -> tuple[subprocess.CompletedProcess[str], Path]:
    folder = tmp_path_factory.mktemp("simulate")
    result = run("simulate", *SHORT, "--set", "E=7e5, eta=2", "--out", folder / "swing.nc",
                 "--rrd", folder / "swing.rrd", "--plot", folder / "energies.png")  # fmt: skip
    return result, folder


def test_simulate_writes_dataset(short_run) -> None:
    result, folder = short_run
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stdout + result.stderr
    for needle in ("wall time", "Newton iterations per step", "max internal energy", "energy drift"):
        assert needle in result.stdout
    with xr.open_dataset(folder / "swing.nc", engine="h5netcdf") as ds:
        ds = ds.load()
    n = int(round(DURATION / DT)) + 1
    assert ds.sizes["time"] == n and ds["total_energy"].shape == (n,)
    np.testing.assert_allclose(ds["time"].values[[0, -1]], [0.0, DURATION], atol=1e-12)
    parts = ds["kinetic_energy"] + ds["gravitational_energy"] + ds["internal_energy"]
    np.testing.assert_allclose(ds["total_energy"].values, parts.values, rtol=1e-12, atol=1e-12)
    assert ds.attrs["scenario"] == "swing" and int(ds.attrs["nodes"]) == NODES
    assert ds["newton_iterations"].sizes["step"] == n - 1
    # every variable states its unit (one string, CF), every dimension has its coordinate
    assert all(isinstance(ds[v].attrs.get("units"), str) for v in ds.data_vars if v != "parameter_value"), [
        v for v in ds.data_vars if not isinstance(ds[v].attrs.get("units"), str)]
    assert ds["parameter_unit"].sel(parameter="E") == "Pa" and set(ds.dims) <= set(ds.coords)
    assert list(ds["step"].values[[0, -1]]) == [1, n - 1]
    assert float(ds["parameter_value"].sel(parameter="E")) == 7e5  # --set applied
    assert float(ds["parameter_value"].sel(parameter="eta")) == 2.0
    assert "blade005" in ds["body"].values
    assert sorted(p.name for p in folder.iterdir()) == ["energies.png", "swing.nc", "swing.rrd"]


def test_simulate_writes_recording(short_run) -> None:
    rr = pytest.importorskip("rerun")
    pa = pytest.importorskip("pyarrow")
    result, folder = short_run
    assert result.returncode == 0, result.stderr
    reader = rr.chunk.RrdReader(folder / "swing.rrd")
    paths = set(reader.store().schema().entity_paths())
    expected = {"/world/leg/thigh", "/world/leg/shank", "/world/blade/centreline", "/energy_J/total",
                "/energy_J/kinetic", "/energy_drift/relative"}  # fmt: skip
    expected |= {f"/world/blade/directors/d{k}" for k in (1, 2, 3)}
    assert expected <= paths, sorted(expected - paths)

    def rows(entity: str) -> pa.Table:
        stream = reader.stream().filter(content=entity, is_static=False)
        tables = [pa.Table.from_batches([c.to_record_batch()]) for c in stream.to_chunks()]
        return pa.concat_tables(tables, promote_options="default").sort_by("time")

    blade = rows("/world/blade/centreline")  # every 10 ms: t = 0, 0.01, ..., 0.05
    assert blade.num_rows == 6
    strip = np.array(blade.column("LineStrips3D:strips").to_pylist()[0][0])
    assert strip.shape == (NODES, 3)
    arrows = rows("/world/blade/directors/d1")
    assert len(arrows.column("Arrows3D:vectors").to_pylist()[-1]) == NODES
    with xr.open_dataset(folder / "swing.nc", engine="h5netcdf") as ds:
        np.testing.assert_allclose(strip, ds["position"].isel(time=0).values[2:], atol=1e-6)
        total = rows("/energy_J/total")
        np.testing.assert_allclose(total.column("time").cast(pa.int64()).to_numpy() / 1e9, ds["time"].values,
                                   atol=1e-9)  # fmt: skip
        values = np.array([r[0] for r in total.column("Scalars:scalars").to_pylist()])
        np.testing.assert_allclose(values, ds["total_energy"].values, rtol=1e-12)


def test_simulate_writes_plot(short_run) -> None:
    _, folder = short_run
    assert (folder / "energies.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (("--set", "foo=1"), "foo"),
        (("--set", "E=abc"), "E='abc'"),
        (("--dt", "-1"), "--dt"),
        (("--set", "nu=0.7"), "nu"),
        (("--scheme", "euler"), "--scheme"),
    ],
)
def test_simulate_bad_arguments_are_one_line(tmp_path: Path, args: tuple[str, ...], needle: str) -> None:
    out = tmp_path / "x.nc"
    assert_one_line_error(run_here("simulate", *SHORT, *args, "--out", out, "--plot", tmp_path / "e.png"), needle)
    assert not list(tmp_path.iterdir())


def test_simulate_non_convergence_writes_nothing(tmp_path: Path) -> None:
    """A far too large step for the soft blade: Newton fails at dt, the run is repeated on
    sub-steps, where the blade folds; one line naming the parameters, no output file."""
    result = run_here("simulate", "swing", "--nodes", str(NODES), "--set", "E=1000,eta=1", "--dt", "0.05", "--duration", "0.5",
                 "--out", tmp_path / "x.nc", "--rrd", tmp_path / "x.rrd")  # fmt: skip
    assert_one_line_error(result, "E=1000", "sub-steps per dt = 0.05 s")
    assert "folded at t =" in result.stderr or "Newton did not converge" in result.stderr
    assert not list(tmp_path.iterdir())


@pytest.mark.slow
def test_simulate_all_outputs_or_none(tmp_path: Path) -> None:
    """The .nc is removed again when a later output (here the recording) cannot be written."""
    env = {**os.environ, "RERUN": "off"}
    result = subprocess.run(
        [sys.executable, "-m", "fuzzygait", "simulate", "swing", "--duration", "0.01", "--nodes", str(NODES),
         "--out", tmp_path / "x.nc", "--rrd", tmp_path / "x.rrd"],
        capture_output=True, text=True, timeout=300, env=env,
    )  # fmt: skip
    assert_one_line_error(result, "x.rrd", "disabled")
    assert not list(tmp_path.iterdir())


def _synthetic_run(n: int = 11) -> xr.Dataset:
    """A stand-in simulation result (energies only) for the figure."""
    t = np.linspace(0.0, 0.1, n)
    kinetic = 5.0 * t
    return xr.Dataset(
        {
            "kinetic_energy": ("time", kinetic),
            "gravitational_energy": ("time", -20.0 - 5.0 * t),
            "internal_energy": ("time", 0.01 * t),
            "dissipated_energy": ("time", 0.001 * t),
            "total_energy": ("time", -20.0 + 0.01 * t),
            "parameter_value": ("parameter", [6e5, 0.265, 8550.0, 1.0]),
        },
        coords={"time": t, "parameter": ["E", "nu", "rho", "eta"]},
        attrs={"scenario": "swing", "nodes": 6, "dt": 0.01},
    )


def test_energy_figure_panels() -> None:
    from fuzzygait.viz.mechanics import energy_drift, energy_figure

    ds = _synthetic_run()
    drift = energy_drift(ds)
    np.testing.assert_allclose(drift, 0.011 * ds["time"].values / 20.0)
    fig = energy_figure(ds)
    energy_axes, drift_axes = fig.axes
    labels = [line.get_label() for line in energy_axes.get_lines()]
    assert labels == ["kinetic", "gravitational", "internal (elastic)", "dissipated", "total", "total + dissipated"]
    np.testing.assert_allclose(drift_axes.get_lines()[0].get_ydata(), drift)
    assert "swing" in fig.get_suptitle() and "E = 6e+05 Pa" in fig.get_suptitle()
    import matplotlib.pyplot as plt

    plt.close(fig)
