"""Every kind of file the toolkit writes passes the IOOS compliance-checker at CF-1.11 with no
message at any priority (errors, warnings, recommendations) and no exception inside the
checker, carries its provenance, and opens sensibly in plain xarray (issue 25).

Files: a run of ``gearvib simulate`` (sensors, tacho, a fault; the writer without xarray), a
measurement written by :func:`analysis.readers.write_netcdf`, ``sweep.nc``, ``diagnosis.nc``,
``comparison.nc``, and ``to_dataset().to_netcdf()`` of every public result object.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from tests.analysis.test_cf import cf_messages

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")  # the checker's own
pytest.importorskip("compliance_checker")
pytest.importorskip("cf_xarray")

FS = 4096.0


@pytest.fixture(scope="module")
def runup():
    """A 3 s run-up 600 -> 2400 min-1: two channels with order 7 and a 60-pulse tacho."""
    from analysis.readers import ChannelData, build_dataset

    t = np.arange(int(3 * FS)) / FS
    rpm = 600.0 + 600.0 * t
    theta = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    rng = np.random.default_rng(3)
    x = np.sin(7 * theta) + 0.3 * np.sin(2 * np.pi * 700 * t) + 0.01 * rng.normal(size=t.size)
    tacho = np.where((60 * theta / (2 * np.pi)) % 1.0 < 0.5, 5.0, 0.0)
    ds = build_dataset([ChannelData("ring x", x, "m s-2"), ChannelData("ring y", 0.5 * x, "m s-2"),
                        ChannelData("tacho", tacho, "V", attrs={"pulses_per_rev": 60})], FS,
                       source_format="test", attrs={"title": "test run-up"})
    channels = xr.concat([ds["ring_x"], ds["ring_y"]], dim="channel").assign_coords(
        channel=["ring x", "ring y"]).assign_coords(rpm=("time", rpm, {"units": "min-1"}))
    return {"t": t, "rpm": rpm, "theta": theta, "x": x, "ds": ds, "channels": channels}


def _spectrum(r):
    from analysis.spectrum import spectrum

    return spectrum(r["channels"], resolution=4.0)


def _order_map(r):
    from analysis.maps import rpm_order_map

    return rpm_order_map(r["channels"], rpm=r["rpm"])


def _freq_map(r):
    from analysis.maps import rpm_frequency_map

    return rpm_frequency_map(r["x"], FS, rpm=r["rpm"], resolution=4.0, amplitude="rms")


def _identification(r):
    from analysis.identification import identify_peaks, mesh_lines
    from analysis.spectrum import spectrum

    s = spectrum(r["x"], FS, resolution=2.0)
    return identify_peaks(s.peaks().frequency, mesh_lines(700.0), resolution=s.resolution_hz)


def _resonances(r):
    from analysis.instability import detect_resonances

    return detect_resonances(_freq_map(r).to_dataset(), natural_frequencies_hz=[700.0, 1500.0],
                             mesh_frequency_per_rpm=7 / 60, orders=range(1, 3))


def _growth(r):
    from analysis.instability import UnstableBand, runup_growth

    band = UnstableBand("x", 2084.0, 2122.0, np.array([2084.0, 2103.0, 2122.0]),
                        np.array([0.0, 51.7, 0.0]))
    return runup_growth([band], np.linspace(0.0, 1.0, 11), np.linspace(0.0, 4000.0, 11))


def _chart(r):
    from analysis.instability import stability_chart

    def one_dof(f_mesh, eps):
        om = 2 * np.pi * f_mesh
        return [[1.0]], [[0.0]], lambda t: np.array([[1.0 + eps * np.cos(om * t)]]), 1 / f_mesh

    return stability_chart(one_dof, np.linspace(0.1, 0.4, 7), parameter_values=[0.2, 0.4],
                           refine=False, parameter_name="relative stiffness variation")


def _floquet(r):
    from analysis.instability import floquet

    return floquet([[1.0]], [[0.0]], lambda t: np.array([[1.0 - 2.0 * np.cos(2.0 * t)]]), np.pi)


def _candidates(r):
    from analysis.instability import instability_candidates

    return instability_candidates([1000.0, 1250.0, 1800.0], mesh_frequency_per_rpm=0.5)


def _widths(r):
    from analysis.instability import first_order_widths

    w = np.array([100.0, 170.0])
    return first_order_widths(np.eye(2), np.diag(2 * 0.002 * w), np.diag(w**2),
                              0.1 * np.array([[[0.8, 0.6], [0.6, 0.5]]]) * w.mean() ** 2,
                              mesh_frequency_per_rpm=0.5)


def _records():
    from tests.analysis.test_comparison import record

    return record({10: 1.0, 20: 0.5}, line_hz=700.0, seed=1), record({10: 2.0, 45: 0.3}, seed=2)


def _comparison(r):
    from analysis.comparison import compare_measurements

    measured, simulated = _records()
    return compare_measurements(measured, simulated, natural_frequencies_hz=[690.0],
                                mode_names=["f2"], max_order=60)


def _measurement(r):
    from analysis.measurement import load_measurement

    return load_measurement(r["ds"])


RESULTS: dict[str, Callable] = {
    "Spectrum": _spectrum,
    "Peaks": lambda r: _spectrum(r).select("ring x").peaks(),
    "OrderSpectrum": lambda r: __import__("analysis.orders", fromlist=["x"]).order_spectrum(
        r["channels"], rpm=r["rpm"]),
    "OrderCut": lambda r: __import__("analysis.orders", fromlist=["x"]).order_cuts(
        r["channels"], orders=[7, 14], rpm=r["rpm"], scale="dB"),
    "RpmOrderMap": _order_map,
    "RpmFrequencyMap": _freq_map,
    "OverallLevel": lambda r: __import__("analysis.maps", fromlist=["x"]).overall_level(
        r["x"], FS, rpm=r["rpm"], scale="dB"),
    "Campbell": lambda r: __import__("analysis.maps", fromlist=["x"]).campbell(
        [700.0, 1500.0], [7, 14], (0.0, 3000.0)),
    "MapFeatures": lambda r: __import__("analysis.runup", fromlist=["x"]).map_features(
        _freq_map(r).to_dataset()),
    "SpeedReference": lambda r: __import__("analysis.speed", fromlist=["x"]).from_tacho(
        r["ds"]["tacho"].values, FS, pulses_per_rev=60),
    "AngleSignal": lambda r: __import__("analysis.resample", fromlist=["x"]).resample_to_angle(
        r["x"], FS, rpm=r["rpm"]),
    "PeakIdentification": _identification,
    "Diagnosis": lambda r: __import__("tests.analysis.test_diagnosis",
                                      fromlist=["x"])._diagnosis(),
    "Resonances": _resonances,
    "GrowthTable": _growth,
    "StabilityChart": _chart,
    "FloquetResult": _floquet,
    "Candidates": _candidates,
    "FirstOrderWidths": _widths,
    "KinematicCatalogue": lambda r: __import__(
        "analysis.catalogue", fromlist=["x"]).simple_planetary_catalogue(
        33, -114, 40, n_planets=3, speed_rpm=1500.0, speeds_rpm=np.linspace(0, 4000, 5)),
    "MeasuredSimulatedComparison": _comparison,
    "Measurement": _measurement,
    "ModalResult": lambda r: __import__("gearvib.modal", fromlist=["x"]).modal_analysis(
        __import__("gearvib.assembly", fromlist=["x"]).assemble(
            __import__("gearvib.config", fromlist=["x"]).load_gearset("paper-case1"))),
}


def _assert_clean(path: Path, tmp_path: Path) -> xr.Dataset:
    """No checker message; provenance; the plain reopening (labels as string indexes)."""
    assert cf_messages(path, tmp_path) == []
    with xr.open_dataset(path) as plain:
        ds = plain.load()
    assert ds.attrs["Conventions"] == "CF-1.11"
    for key in ("title", "history"):
        assert str(ds.attrs.get(key, "")).strip(), key
    assert ds.attrs.get("gearvib_version")  # a measurement keeps the source of its data
    assert "gearvib" in f"{ds.attrs.get('source', '')} {ds.attrs['history']}"
    return ds


@pytest.mark.parametrize("kind", list(RESULTS))
def test_result_datasets_pass_the_checker(kind, runup, tmp_path):
    result = RESULTS[kind](runup)
    ds = result.to_dataset()
    assert ds.attrs["history"] and ds.attrs["gearvib_version"]
    path = tmp_path / f"{kind}.nc"
    ds.to_netcdf(path)  # what a user does
    back = _assert_clean(path, tmp_path)
    if "time" in ds.dims:
        assert back.cf.axes["T"] == ["time"]
    for name in ds.dims:  # labels: a plain open selects them by name
        if name in ds.coords and ds[name].dtype.kind == "U" and ds.sizes[name]:
            label = str(ds[name].values[-1])
            assert back.sel({name: label})[name].values == label


def test_a_simulated_run_passes_the_checker(tmp_path):
    """``gearvib simulate``: sensors, a tacho and a fault, written without xarray."""
    from gearvib.assembly import assemble
    from gearvib.config import load_gearset
    from gearvib.faults import Crack
    from gearvib.io import read_run, write_netcdf
    from gearvib.sensors import HousingMode, HousingSensor, Tacho
    from gearvib.simulate import SpeedRamp, simulate

    model = assemble(load_gearset("paper-case1")).with_sensors([
        HousingSensor("acc1", 30.0, housing_modes=(HousingMode(3000.0, 0.05, 1.0),)),
        HousingSensor("acc2", 120.0, housing_modes=(HousingMode(4000.0, 0.05, 1.0),)),
        Tacho("tacho", pulses_per_rev=60)]).with_faults(
        [Crack("sun", 3, severity=0.2)])
    res = simulate(model, SpeedRamp(600, 1800, 1.0, input_torque=60.0), duration=0.05,
                   progress=False)
    path = write_netcdf(res.to_plain_dataset(), tmp_path / "run.nc")
    plain = _assert_clean(path, tmp_path)
    # the lines of docs/faults-sensors.md and docs/files.md work on a plain open
    acc = plain.sensor_acceleration.sel(sensor="acc1")
    assert acc.dims == ("time",) and np.issubdtype(plain["time"].dtype, np.datetime64)
    assert plain.normal_force.sel(mesh="sun-planet1", flank="left").dims == ("time",)
    assert plain.cf.axes["T"] == ["time"]
    assert acc.gearvib.spectrum().fs == pytest.approx(res.to_dataset().attrs["fs_out"])
    np.testing.assert_array_equal(acc.values, read_run(path).sensor_acceleration.sel(
        sensor="acc1").values)


def test_a_measurement_file_passes_the_checker(runup, tmp_path):
    from analysis.readers import write_netcdf

    _assert_clean(write_netcdf(runup["ds"], tmp_path / "measured.nc"), tmp_path)


def test_sweep_file_passes_the_checker(tmp_path):
    import cf_xarray  # noqa: F401

    from gearvib.sweep import run_sweep
    from tests.gearvib.test_sweep import _sweep

    res = run_sweep(_sweep(), tmp_path / "sw", workers=1, progress=False, report=True)
    plain = _assert_clean(res.path, tmp_path)
    assert plain["meshes_sun_damping_ratio"].attrs["gearvib_parameter_path"] == \
        "meshes.sun.damping_ratio"
    assert plain.sel(mesh="sun-planet1").dynamic_factor.dims == ("case",)
    assert (tmp_path / "sw" / "sweep.html").is_file()  # the report reads the new names


def test_diagnosis_file_passes_the_checker(tmp_path):
    from gearvib.io import write_netcdf
    from tests.analysis.test_diagnosis import _diagnosis

    d = _diagnosis()
    path = write_netcdf(d.to_dataset(), tmp_path / "diagnosis.nc")  # as write_diagnosis_report
    plain = _assert_clean(path, tmp_path)
    assert plain.signature.sel(variant="crack sun 50 %").dims == ("order",)


def test_comparison_file_passes_the_checker(tmp_path):
    from gearvib.report.measured_compare import SimulationComparison, build_comparison_report

    measured, simulated = _records()
    cmp = SimulationComparison(result=_comparison(None), measured=measured, simulated=simulated,
                               gearset_name="paper-case1")
    build_comparison_report(cmp, tmp_path / "cmp")  # writes comparison.nc with to_netcdf
    _assert_clean(tmp_path / "cmp" / "comparison.nc", tmp_path)
