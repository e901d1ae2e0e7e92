"""Admissible baseline calls of every public function of :mod:`analysis`, for the fuzz suite.

:func:`public_functions` lists every function named in the ``__all__`` of a module of the
package (a re-export counts once, where it is defined). :data:`BASELINES` holds, for each of
them, a call with admissible arguments (``(args, kwargs)``, built lazily and small so that a
call takes milliseconds); :mod:`tests.analysis.test_fuzz_api` replaces one argument at a time
by a hostile value. A function missing here fails the coverage test.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import pkgutil
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

import analysis
from tests.fuzz_guard import lazy_call

FS = 2048.0
N = 4096


def public_functions() -> dict[str, Callable]:
    """``{"module.name": function}`` of every function in a module's ``__all__``."""
    out: dict[str, Callable] = {}
    for info in pkgutil.walk_packages(analysis.__path__, "analysis."):
        mod = importlib.import_module(info.name)
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name)
            if inspect.isfunction(obj) and obj.__module__ == info.name:
                out[f"{info.name}.{name}"] = obj
    return out


# ------------------------------------------------------------------------------------------
# small admissible inputs, built once
# ------------------------------------------------------------------------------------------


@functools.cache
def tmp() -> Path:
    return Path(tempfile.mkdtemp(prefix="gearvib-fuzz-"))


@functools.cache
def run_up() -> dict[str, Any]:
    """A 2 s run-up 600 -> 1500 min-1 with orders 3 and 7 and a little noise."""
    t = np.arange(N) / FS
    rpm = 600.0 + 450.0 * t
    angle = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    rng = np.random.default_rng(1)
    x = np.cos(3 * angle) + 0.5 * np.cos(7 * angle) + 0.1 * rng.standard_normal(N)
    tacho = (np.mod(angle, 2 * np.pi) < 0.5).astype(float)
    return {"t": t, "rpm": rpm, "angle": angle, "x": x, "tacho": tacho}


def x() -> np.ndarray:
    return run_up()["x"].copy()


def rpm() -> np.ndarray:
    return run_up()["rpm"].copy()


def angle() -> np.ndarray:
    return run_up()["angle"].copy()


@functools.cache
def dataset() -> xr.Dataset:
    r = run_up()
    return xr.Dataset(
        {
            "acc": ("time", r["x"], {"units": "m s-2", "long_name": "acceleration"}),
            "speed": ("time", r["rpm"], {"units": "min-1", "long_name": "shaft speed"}),
        },
        coords={"time": ("time", r["t"], {"units": "s", "long_name": "time"})},
        attrs={"title": "fuzz"},
    )


@functools.cache
def objects() -> dict[str, Any]:
    """Result objects the figure and post-processing functions take."""
    from analysis.envelope import envelope_spectrum, squared_envelope
    from analysis.gear_signals import gear_signals
    from analysis.indicators import condition_indicators
    from analysis.instability.theory import instability_candidates
    from analysis.kurtogram import fast_kurtogram, spectral_kurtosis
    from analysis.maps import campbell, overall_level, rpm_frequency_map, rpm_order_map
    from analysis.orders import order_cuts, order_spectrum
    from analysis.spectrum import spectrum
    from analysis.tsa import tsa

    r = run_up()
    o: dict[str, Any] = {}
    o["spectrum"] = spectrum(r["x"], FS, segment_length=512)  # find_peaks: 10 s on 2049 lines
    o["order_spectrum"] = order_spectrum(r["x"], FS, r["rpm"], max_order=10.0)
    o["rpm_order_map"] = rpm_order_map(r["x"], FS, r["rpm"], max_order=10.0, resolution=0.5)
    o["rpm_frequency_map"] = rpm_frequency_map(r["x"], FS, r["rpm"], resolution=8.0)
    with warnings.catch_warnings():  # the bands of 3 and 7 overlap at this resolution
        warnings.simplefilter("ignore")
        o["order_cuts"] = order_cuts(r["x"], FS, r["rpm"], [3.0, 7.0])
    o["overall_level"] = overall_level(r["x"], FS, r["rpm"])
    o["campbell"] = campbell([100.0, 250.0], [1, 3], (600.0, 1500.0))
    o["tsa"] = tsa(r["x"], FS, angle=r["angle"], samples_per_rev=64)
    o["gear_signals"] = gear_signals(o["tsa"], [3])
    o["indicators"] = condition_indicators([o["tsa"], o["tsa"]], [3])
    o["kurtogram"] = fast_kurtogram(r["x"], FS, max_level=3)
    o["spectral_kurtosis"] = spectral_kurtosis(r["x"], FS, segment_length=64)
    o["squared_envelope"] = squared_envelope(r["x"], FS, band=(200.0, 600.0))
    o["envelope_spectrum"] = envelope_spectrum(r["x"], FS, band=(200.0, 600.0))
    o["candidates"] = instability_candidates([100.0, 250.0], mesh_frequency_per_rpm=0.5)
    o["map_ds"] = o["rpm_frequency_map"].to_dataset()
    from analysis.runup_levels import runup_levels

    o["runup_levels"] = runup_levels(r["x"], FS, rpm=r["rpm"], orders=[3.0, 7.0],
                                     natural_frequencies_hz=[100.0], map_resolution=8.0)
    return o


@functools.cache
def files() -> dict[str, Path]:
    """Small valid files of every format the readers take."""
    from analysis.readers import write_csv, write_mat, write_netcdf, write_wav

    d = tmp()
    ds = dataset().isel(time=slice(0, 256))
    out = {"nc": d / "run.nc", "csv": d / "run.csv", "wav": d / "run.wav", "mat": d / "run.mat"}
    write_netcdf(ds, out["nc"])
    write_csv(ds, out["csv"])
    write_wav(ds[["acc"]], out["wav"])
    write_mat(ds, out["mat"])
    frf = d / "frf.csv"
    f = np.linspace(10.0, 500.0, 50)
    frf.write_text("frequency,real,imag\n" + "".join(f"{v},{1.0 / v},{0.1 / v}\n" for v in f))
    out["frf"] = frf
    out["nc3"] = d / "run3.nc"
    ds.to_netcdf(out["nc3"], format="NETCDF3_64BIT")
    return out


def system_at(f_mesh: float) -> tuple:
    om = 2 * np.pi * f_mesh
    return [[1.0]], [[0.05]], lambda t: np.array([[1.0 + 0.2 * np.cos(om * t)]]), 1.0 / f_mesh


def _mathieu_K(t: float) -> np.ndarray:
    return np.array([[1.0 + 0.2 * np.cos(2 * t)]])


def _signal() -> Any:
    from analysis.inputs import signal_input

    return signal_input(x(), FS)


def _reference() -> Any:
    from analysis.inputs import reference_input

    return reference_input(rpm(), None, N, required=True)


def _tracking_args() -> tuple:
    return (_signal(), _reference(), 32, 10.0, 4096, None)


def _catalogue() -> Any:
    from analysis.catalogue import simple_planetary_catalogue

    return simple_planetary_catalogue(21, -83, 31, n_planets=4, speed_rpm=1200.0)


def _ident_args() -> tuple:
    from analysis.identification import mesh_lines
    from analysis.spectrum import find_peaks

    peaks = find_peaks(objects()["spectrum"], max_peaks=5)
    return (np.asarray(peaks.frequency), mesh_lines(100.0)), {"resolution": 1.0}


def _chart() -> Any:
    from analysis.instability.chart import stability_chart

    return stability_chart(system_at, np.linspace(0.3, 0.4, 3), refine=False)


def _peaks_freqs() -> np.ndarray:
    return np.array([100.0, 200.0, 350.0])


def _vk() -> Any:
    from analysis.vold_kalman import order_waveform

    r = run_up()
    return order_waveform(r["x"][:1024], FS, orders=[3.0], bandwidth=5.0, rpm=r["rpm"][:1024])


def _vk_removal() -> Any:
    from analysis.vold_kalman import remove_orders

    r = run_up()
    return remove_orders(r["x"][:1024], FS, orders=[3.0], bandwidth=5.0, rpm=r["rpm"][:1024])


def _planetary() -> Any:
    from analysis.planetary_tsa import planetary_tsa

    return planetary_tsa(
        x(), FS, z_sun=21, z_planet=31, z_ring=83, n_planets=4, angle=angle() / 4.0
    )


def _wav_layout() -> Any:
    from analysis.readers.riff import wav_layout

    return wav_layout(files()["wav"])


def _profile() -> Any:
    from analysis.diagnosis import order_profile

    return order_profile(x(), FS, rpm(), max_order=10.0, revolutions=4)


def _indicators(n: int) -> Any:
    from analysis.indicators import condition_indicators

    return condition_indicators([objects()["tsa"]] * n, [3])


def _mesh(gear: str) -> Any:
    from analysis.catalogue import ToothMesh

    return ToothMesh(f"{gear}-planet", gear, "planet", 21 if gear == "sun" else -83, 31,
                     "carrier")


def _measurement() -> Any:
    from analysis.measurement import load_measurement

    return load_measurement(dataset(), speed="speed")


def _pool() -> Any:
    from concurrent.futures import ThreadPoolExecutor

    return ThreadPoolExecutor(1)


def _chart_rpm() -> Any:
    from analysis.instability.chart import stability_chart

    return stability_chart(system_at, np.linspace(0.3, 0.4, 3), refine=False,
                           mesh_frequency_per_rpm=0.01)


def _band() -> Any:
    from analysis.envelope import choose_band

    return choose_band((200.0, 600.0), FS, x())[0]


def _identify() -> Any:
    from analysis.identification import identify_peaks

    (peaks, lines), kw = _ident_args()
    return identify_peaks(peaks, lines, **kw)


def _floquet() -> Any:
    from analysis.instability.floquet import floquet

    return floquet([[1.0]], [[0.05]], _mathieu_K, np.pi)


def _labels() -> Any:
    from analysis.instability.labels import label_peaks

    return label_peaks(_peaks_freqs(), [100.0, 250.0], resolution_hz=1.0)


def _resonances() -> Any:
    from analysis.instability.resonances import detect_resonances

    return detect_resonances(objects()["map_ds"], natural_frequencies_hz=[100.0, 250.0],
                             mesh_frequency_per_rpm=0.5)


def _family() -> Any:
    from analysis.lines import bearing_families

    return bearing_families(10.0, bpfo=3.1)[0]


def _channel() -> Any:
    from analysis.readers.layout import ChannelData

    return ChannelData("acc", x()[:64], "m s-2")


def _precision() -> Any:
    from analysis.readers.timebase import print_precision

    return print_precision(["0.01", "0.02"])


def _solve_args() -> A:
    from analysis.vold_kalman_solver import difference_coefficients

    n = 256
    th = np.linspace(0.0, 40.0, n)
    return (th[None, :], np.array([3.0]), np.array([0]), np.ones((1, n)), np.full(1, 100.0),
            difference_coefficients(1), 64), {}


# ------------------------------------------------------------------------------------------
# one admissible call per function: name -> () -> (args, kwargs)
# ------------------------------------------------------------------------------------------

A = tuple[tuple, dict]


def _impact_families() -> list[Any]:
    from analysis.diagnosis_impacts import ImpactFamily

    return [ImpactFamily("f", 1.3)]


@functools.cache
def _impact() -> Any:
    from analysis.diagnosis_impacts import impact_check

    return impact_check(x(), FS, rpm(), mesh_orders=[7.0], families=_impact_families())


_c = lazy_call  # a baseline whose callable arguments are built when it is


def _o(key: str) -> Callable[[], Any]:
    return lambda: objects()[key]


def _f(key: str) -> Callable[[], Any]:
    return lambda: files()[key]


def _literal(value: Any) -> Callable[[], Any]:
    """A callable argument passed as is (``_c`` evaluates callables)."""
    return lambda: value


@functools.cache
def _evidence_parts() -> dict[str, Any]:
    """A line family, its check and its line evidence in the fuzz envelope spectrum."""
    from analysis.line_evidence import line_evidence
    from analysis.lines import bearing_families

    es = objects()["envelope_spectrum"]
    family = bearing_families(10.0, bpfo=3.5848, bpfi=5.4152)[1]
    power = np.square(es.values)
    return {"axis": es.frequency, "power": power, "family": family,
            "check": es.check(family),
            "evidence": line_evidence(es.frequency, power, family)}


def _e(key: str) -> Callable[[], Any]:
    return lambda: _evidence_parts()[key]


def _measured_signals() -> xr.Dataset:
    r = run_up()
    return xr.Dataset({"acc": ("time", r["x"], {"units": "m s-2", "long_name": "acc"})},
                      coords={"time": ("time", r["t"], {"units": "s", "long_name": "time"})})


def _scalar_file_dataset() -> xr.Dataset:
    ds = _measured_signals()
    ds["X105RPM"] = ((), 1797.0)
    return ds


BASELINES: dict[str, Callable[[], A]] = {
    # line_evidence, measurement_options (entries added with those modules)
    "analysis.envelope_plots.line_evidence_figure": _c(_e("evidence")),
    "analysis.line_evidence.claim_tolerance": _c(lambda: np.arange(1, 4), 10.0),
    "analysis.line_evidence.explained_positions": _c(_e("check"), 100.0),
    "analysis.line_evidence.family_chance": _c(_e("axis"), _e("check"),
                                               lambda: np.array([50.0, 54.2, 108.3])),
    "analysis.line_evidence.line_evidence": _c(_e("axis"), _e("power"), _e("family")),
    "analysis.line_evidence.prominent_lines": _c(_e("axis"), _e("power")),
    "analysis.line_evidence.strength": _c(_e("check")),
    "analysis.measurement_options.apply_calibration": _c(_measured_signals,
                                                         {"acc": 9.81}, {"acc": "m s-2"}),
    "analysis.measurement_options.check_fs": _c(FS),
    "analysis.measurement_options.check_rate": _c(_measured_signals, FS, "fuzz"),
    "analysis.measurement_options.reader_options": _c(".wav", None, FS, None),
    "analysis.measurement_options.scalar_speed": _c(_scalar_file_dataset, "X105RPM", 1e5),
    "analysis.measurement_options.scalar_variables": _c(_scalar_file_dataset),
    # alarm_limits
    "analysis.alarm_limits.learn_limits": _c(lambda: _indicators(3)),
    # bands
    "analysis.bands.band_moments": _c(x, FS, lambda: [[_band()]], lambda: [1]),
    "analysis.bands.envelope_decimation": _c(_band, FS),
    "analysis.bands.smooth_step": _c(lambda: np.linspace(-1, 2, 7)),
    "analysis.bands.squared_envelope_samples": _c(x, FS, _band, 2),
    # catalogue
    "analysis.catalogue.kinematic_catalogue": _c(
        lambda: {"sun": 1.0, "carrier": 0.2, "ring": 0.0, "planet": -0.4},
        lambda: [_mesh("sun"), _mesh("ring")], reference="sun", fixed="ring",
        speed_rpm=1200.0),
    "analysis.catalogue.phasing_factor": _c(lambda: np.linspace(0, 2 * np.pi, 4,
                                                                endpoint=False), 3),
    "analysis.catalogue.simple_planetary_catalogue": _c(21, -83, 31, n_planets=4,
                                                        speed_rpm=1200.0),
    "analysis.catalogue.simple_planetary_speeds": _c(21, -83, 31),
    # cf
    "analysis.cf.cf_dataset": _c(dataset, title="fuzz", producer="tests"),
    "analysis.cf.clean_attr_value": _c(3.0),
    "analysis.cf.elapsed_seconds": _c(lambda: np.arange(10.0)),
    "analysis.cf.is_elapsed_seconds": _c("s"),
    "analysis.cf.label_encoding": _c("sensor"),
    "analysis.cf.labels_from_cf": _c(dataset),
    "analysis.cf.labels_to_cf": _c(dataset),
    "analysis.cf.processing_attrs": _c("rpm", ("note",)),
    "analysis.cf.provenance_attrs": _c("tests"),
    "analysis.cf.time_attrs": _c("time"),
    "analysis.cf.toolkit_version": _c(),
    # checks
    "analysis.checks.renamed": _c(1.0, None, "new", "old", "f"),
    "analysis.checks.require_block_size": _c(1024),
    "analysis.checks.require_choice": _c("a", ("a", "b"), "choice"),
    "analysis.checks.require_colormap": _c("viridis"),
    "analysis.checks.require_instance": _c(2.0, float, "v"),
    "analysis.checks.require_real_array": _c(x, "x"),
    "analysis.checks.require_finite": _c(x, "x"),
    "analysis.checks.require_finite_blocks": _c(x, "x"),
    "analysis.checks.require_int": _c(3, "n", 1),
    "analysis.checks.require_mass_matrix": _c(lambda: np.eye(2)),
    "analysis.checks.require_monotonic": _c(lambda: np.arange(5.0), "t"),
    "analysis.checks.require_positive": _c(2.0, "v"),
    "analysis.checks.require_real": _c(2.0, "v"),
    "analysis.checks.require_same_length": _c(lambda: [np.ones(3), np.ones(3)],
                                              lambda: ["a", "b"]),
    "analysis.checks.require_size": _c(1024.0, "a test", "n"),
    "analysis.checks.require_square": _c(lambda: np.eye(2), "K"),
    "analysis.checks.sample_rate": _c(lambda: np.arange(10) / FS),
    "analysis.checks.shown": _c(3.0),
    "analysis.checks.time_or_rate": _c(FS, None, "f"),
    "analysis.checks.uniform_rate": _c(lambda: np.arange(10) / FS),
    # cm_plots
    "analysis.cm_plots.gear_signals_figure": _c(_o("gear_signals")),
    "analysis.cm_plots.planetary_figure": _c(_planetary),
    "analysis.cm_plots.trend_figure": _c(_o("indicators")),
    "analysis.cm_plots.tsa_figure": _c(_o("tsa")),
    # comparison
    "analysis.comparison.compare_measurements": _c(_measurement, _measurement, channel="acc",
                                                   simulated_channel="acc"),
    "analysis.comparison.simulated_channel_name": _c(_measurement, "acc"),
    # diagnosis
    "analysis.diagnosis.deadband_db": _c(lambda: np.linspace(-3, 3, 50)),
    "analysis.diagnosis.dynamic_range_db": _c(lambda: _profile()),
    "analysis.diagnosis.family_evidence": _c(
        lambda: np.linspace(0.1, 10, 100), lambda: np.zeros(100), 3.0,
        lambda: {"gear": (3.0, np.array([3.0, 6.0]))}),
    "analysis.diagnosis.family_lines": _c(1.0, mesh_order=3.0, mesh_harmonics=2,
                                          harmonics=2, sidebands=1, max_order=10.0),
    "analysis.diagnosis.impulse_mismatch_db": _c(lambda: np.ones(4), lambda: np.ones(4),
                                                 lambda: [np.full(4, 2.0)]),
    "analysis.diagnosis.near_modes": _c(lambda: np.array([3.0]), 20.0,
                                        lambda: {"mode 1": 60.0}),
    "analysis.diagnosis.order_locking": _c(_profile, x, FS, rpm,
                                           lambda: np.array([3.0])),
    "analysis.diagnosis.order_profile": _c(x, FS, rpm, max_order=10.0, revolutions=4),
    "analysis.diagnosis.phasing_shifts": _c(-83, lambda: np.radians([0.0, 90.0, 180.0, 270.0]),
                                            pass_order=1.0, mesh_harmonics=3),
    "analysis.diagnosis.prominence_db": _c(lambda: _profile()),
    "analysis.diagnosis.shaft_line_mask": _c(lambda: np.linspace(0.0, 10.0, 161),
                                             lambda: np.array([1.0, 4.95])),
    "analysis.diagnosis.rising_peaks": _c(lambda: np.linspace(0.1, 10, 100),
                                          lambda: np.sin(np.linspace(0, 20, 100)), 0.5),
    "analysis.diagnosis.sideband_ratios": _c(lambda: _profile(), 1.0, 3.0),
    "analysis.diagnosis.signature_score": _c(lambda: np.ones(10), lambda: np.ones(10),
                                             deadband=1.0),
    "analysis.diagnosis.with_noise_floor": _c(lambda: _profile(), 40.0),
    # diagnosis_impacts, diagnosis_impact_plots
    "analysis.diagnosis_impacts.impact_check": _c(x, FS, rpm, mesh_orders=[7.0],
                                                  families=_impact_families),
    "analysis.diagnosis_impact_plots.impact_figure": _c(_impact),
    # envelope
    "analysis.envelope.band_attributes": _c(lambda: _band(), None, 2, FS),
    "analysis.envelope.choose_band": _c(lambda: (200.0, 600.0), FS, x),
    "analysis.envelope.envelope_spectrum": _c(x, FS, band=(200.0, 600.0)),
    "analysis.envelope.line_power": _c(lambda: np.ones(8), "rms"),
    "analysis.envelope.squared_envelope": _c(x, FS, band=(200.0, 600.0)),
    "analysis.envelope_orders.envelope_order_spectrum": _c(x, FS, rpm, band=(200.0, 600.0),
                                                           max_order=10.0),
    "analysis.envelope_plots.envelope_spectrum_figure": _c(_o("envelope_spectrum")),
    "analysis.envelope_plots.kurtogram_figure": _c(_o("kurtogram")),
    "analysis.envelope_plots.spectral_kurtosis_figure": _c(_o("spectral_kurtosis")),
    "analysis.envelope_plots.squared_envelope_figure": _c(_o("squared_envelope")),
    # fft
    "analysis.fft.backend": _c(),
    "analysis.fft.empty_aligned": _c(lambda: (4, 8)),
    "analysis.fft.get_workers": _c(),
    "analysis.fft.irfft": _c(lambda: np.ones(5, dtype=complex), 8),
    "analysis.fft.next_fast_len": _c(1000),
    "analysis.fft.rfft": _c(lambda: np.ones(8)),
    "analysis.fft.rfft_plan": _c(2, 8),
    "analysis.fft.set_planner_effort": _c("FFTW_ESTIMATE"),
    "analysis.fft.set_workers": _c(1),
    # frames
    "analysis.frames.frame_coords": _c(lambda: np.arange(4.0), lambda: np.full(4, 600.0)),
    "analysis.frames.frame_layout": _c(1000, 100, 0.5),
    "analysis.frames.frame_ranges": _c(10, 100, 50, 4096),
    "analysis.frames.frequency_plan": _c(x, FS, rpm, resolution=8.0),
    "analysis.frames.order_plan": _c(x, FS, rpm, max_order=10.0, resolution=0.5),
    "analysis.frames.stft_into": _c(lambda: np.ones(256), lambda: np.hanning(64), 32,
                                    lambda: np.empty((7, 33)), "rms", "linear"),
    "analysis.frames.values_at": _c(lambda: np.array([0.5, 1.5]), lambda: np.arange(4.0)),
    "analysis.frames.window_length": _c("hann", FS, 8.0, N, "resolution"),
    # gear_signals
    "analysis.gear_signals.gear_signals": _c(_o("tsa"), lambda: [3]),
    # identification
    "analysis.identification.catalogue_lines": _c(_catalogue),
    "analysis.identification.covered_fraction": _c(lambda: np.array([1.0, 3.0]),
                                                   lambda: np.array([0.1, 0.1]), 0.0, 5.0),
    "analysis.identification.identify_peaks": lambda: _ident_args(),
    "analysis.identification.mesh_lines": _c(100.0),
    "analysis.identification.modal_lines": _c(lambda: [100.0, 250.0]),
    "analysis.identification.peak_half_widths": _c(
        lambda: np.linspace(0, 100, 101), lambda: -np.abs(np.linspace(-50, 50, 101)),
        lambda: np.array([50])),
    "analysis.identification.plot_identification": lambda: (
        (_identify(),), {}),
    "analysis.identification.ratio_expression": _c(3, 7, "f"),
    # indicators
    "analysis.indicators.condition_indicators": _c(lambda: [objects()["tsa"]] * 2,
                                                   lambda: [3]),
    "analysis.indicators.crest_factor": _c(x),
    "analysis.indicators.energy_ratio": _c(x, x),
    "analysis.indicators.fm0": _c(x, lambda: np.array([1.0, 0.5])),
    "analysis.indicators.fm4": _c(x),
    "analysis.indicators.gear_indicators": _c(_o("gear_signals")),
    "analysis.indicators.kurtosis": _c(x),
    "analysis.indicators.m6a": _c(x),
    "analysis.indicators.m8a": _c(x),
    "analysis.indicators.na4": _c(x, 1.0),
    "analysis.indicators.normalized_moment": _c(x, 4),
    "analysis.indicators.peak": _c(x),
    "analysis.indicators.rms": _c(x),
    "analysis.indicators.sideband_level_factor": _c(1.0, 1.0, x),
    # inputs
    "analysis.inputs.channel_coords": _c(("channel",), lambda: {"channel": np.arange(2)}),
    "analysis.inputs.dataset_reference": _c(dataset, "speed", None),
    "analysis.inputs.dataset_variable": _c(dataset, "acc"),
    "analysis.inputs.find_reference": _c(dataset),
    "analysis.inputs.moving_range": _c(_reference, FS, 0.0, None),
    "analysis.inputs.one_channel": _c(_signal, "f"),
    "analysis.inputs.reference_input": _c(rpm, None, N, required=True),
    "analysis.inputs.select_channel": _c(lambda: np.ones((2, 5)), ("channel",),
                                         lambda: {"channel": np.arange(2)}, 1),
    "analysis.inputs.signal_input": _c(x, FS),
    # instability
    "analysis.instability.chart.attribute_region": _c(190.0, 210.0, _o("candidates")),
    "analysis.instability.chart.chart_chunk": _c(_literal(lambda f, p: system_at(f)), "grid",
                                                 lambda: [(0.3, 0.0)], lambda: {}, 1e-11),
    "analysis.instability.chart.stability_chart": _c(_literal(system_at),
                                                     lambda: np.linspace(0.3, 0.4, 3),
                                                     refine=False),
    "analysis.instability.chart.terminate_pool": _c(_pool),
    "analysis.instability.floquet.floquet": _c(lambda: [[1.0]], lambda: [[0.05]],
                                               _literal(_mathieu_K), np.pi),
    "analysis.instability.growth.runup_growth": _c(
        _chart_rpm, lambda: np.linspace(0, 2, 50),
        lambda: np.linspace(600, 1500, 50)),
    "analysis.instability.growth.unstable_bands": _c(_chart_rpm),
    "analysis.instability.labels.label_peaks": _c(_peaks_freqs, lambda: [100.0, 250.0],
                                                  resolution_hz=1.0),
    "analysis.instability.labels.theory_lines": _c(_o("candidates")),
    "analysis.instability.plots.plot_candidates": _c(_o("candidates")),
    "analysis.instability.plots.plot_chart": _c(_chart),
    "analysis.instability.plots.plot_floquet": _c(lambda: _floquet()),
    "analysis.instability.plots.plot_peak_labels": _c(lambda: _labels()),
    "analysis.instability.plots.plot_resonances": _c(lambda: _resonances()),
    "analysis.instability.resonances.detect_resonances": _c(
        _o("map_ds"), natural_frequencies_hz=[100.0, 250.0], mesh_frequency_per_rpm=0.5),
    "analysis.instability.resonances.merge_mesh_frequencies": _c(
        lambda: [("mesh", _resonances())], rpm_tolerance=10.0, frequency_tolerance=5.0),
    "analysis.instability.theory.first_order_widths": _c(
        lambda: np.eye(2), lambda: np.zeros((2, 2)), lambda: np.diag([1.0, 4.0]),
        lambda: [0.1 * np.ones((2, 2))]),
    "analysis.instability.theory.instability_candidates": _c(lambda: [100.0, 250.0]),
    "analysis.instability.theory.natural_frequencies": _c(lambda: [100.0, 250.0]),
    "analysis.instability.theory.rectangular_wave_harmonics": _c(1.0, 1.5, 1.6, 0.0, 5),
    "analysis.instability.theory.rectangular_wave_pieces": _c(1.0, 1.5, 1.6, 0.0, 1.0),
    # jit
    "analysis.jit.cache_candidates": _c(),
    "analysis.jit.prepare_cache": _c(lambda: str(tmp() / "module.py")),
    "analysis.jit.private_folder": _c(lambda: tmp() / "private"),
    # kurtogram
    "analysis.kurtogram.fast_kurtogram": _c(x, FS, max_level=3),
    "analysis.kurtogram.gaussian_threshold": _c(1000.0),
    "analysis.kurtogram.kurtogram_levels": _c(3),
    "analysis.kurtogram.spectral_kurtosis": _c(x, FS, segment_length=64),
    # levels
    "analysis.levels.amplitude_choice": _c("rms", None, "f", lambda: ("rms", "peak")),
    "analysis.levels.line_factors": _c(5, 8),
    "analysis.levels.power_of": _c(lambda: np.ones(5), "rms", "linear", 8),
    "analysis.levels.to_db": _c(lambda: np.ones(5), "power"),
    "analysis.levels.units_of": _c("m s-2", "rms"),
    # lines
    "analysis.lines.bearing_families": _c(10.0, bpfo=3.1),
    "analysis.lines.check_lines": _c(lambda: np.linspace(0, 100, 201),
                                     lambda: np.ones(201), lambda: _family()),
    # maps
    "analysis.maps.campbell": _c(lambda: [100.0, 250.0], lambda: [1, 3], (600.0, 1500.0)),
    "analysis.maps.overall_level": _c(x, FS, rpm),
    "analysis.maps.overall_level_from_map": _c(_o("rpm_frequency_map")),
    "analysis.maps.rpm_frequency_map": _c(x, FS, rpm, resolution=8.0),
    "analysis.maps.rpm_frequency_map_ds": _c(dataset, "acc", "speed", resolution=8.0),
    "analysis.maps.rpm_order_map": _c(x, FS, rpm, max_order=10.0, resolution=0.5),
    "analysis.maps.rpm_order_map_ds": _c(dataset, "acc", "speed", max_order=10.0,
                                         resolution=0.5),
    # measurement
    "analysis.measurement.load_measurement": _c(_f("nc"), speed="speed"),
    "analysis.measurement.reference_channel": _c(dataset),
    "analysis.measurement.tacho_reference": _c(
        lambda: dataset().assign(tacho=("time", run_up()["tacho"], {"units": "V",
                                                                    "long_name": "tacho"})),
        "tacho", 1, lambda: run_up()["t"]),
    # order_resolution
    "analysis.order_resolution.check_bands": _c(lambda: np.array([3.0, 7.0]), 0.2, 0.5,
                                                lambda: [], what="orders"),
    "analysis.order_resolution.choose_order_resolution": _c(None, lambda: np.array([3.0]),
                                                            10.0, 30.0, 3.8),
    "analysis.order_resolution.default_frequency_resolution": _c(10.0, 25.0, 2.0, 1.5),
    "analysis.order_resolution.default_order_resolution": _c(lambda: np.array([3.0, 7.0]),
                                                             10.0),
    "analysis.order_resolution.main_lobe_band": _c(2.0, 0.25),
    "analysis.order_resolution.named_lines": _c(lambda: {"mesh": 3.0}),
    "analysis.order_resolution.optional_positive": _c(1.0, "v", "Hz"),
    "analysis.order_resolution.requested_orders": _c(lambda: [3.0, 7.0]),
    "analysis.order_resolution.smallest_spacing": _c(lambda: np.array([3.0, 7.0])),
    # orders
    "analysis.orders.order_cuts": _c(x, FS, rpm, lambda: [3.0, 7.0]),
    "analysis.orders.order_cuts_from_map": _c(_o("rpm_order_map"), lambda: [3.0, 7.0]),
    "analysis.orders.order_spectrum": _c(x, FS, rpm, max_order=10.0),
    # planetary_tsa
    "analysis.planetary_tsa.planetary_tsa": _c(x, FS, z_sun=21, z_planet=31, z_ring=83,
                                               n_planets=4, angle=lambda: angle() / 4.0),
    # plots
    "analysis.plots.campbell_figure": _c(_o("campbell")),
    "analysis.plots.order_cuts_figure": _c(_o("order_cuts")),
    "analysis.plots.order_spectrum_figure": _c(_o("order_spectrum")),
    "analysis.plots.overall_level_figure": _c(_o("overall_level")),
    "analysis.plots.rpm_frequency_map_figure": _c(_o("rpm_frequency_map")),
    "analysis.plots.rpm_order_map_figure": _c(_o("rpm_order_map")),
    "analysis.plots.spectrum_figure": _c(_o("spectrum")),
    # readers
    "analysis.readers.read": _c(_f("nc")),
    "analysis.readers.cdf3.check_cdf3": _c(_f("nc3")),
    "analysis.readers.cdf3.is_cdf3": _c(_f("nc")),
    "analysis.readers.csv.read_csv": _c(_f("csv"), time_column="time"),
    "analysis.readers.csv.write_csv": _c(dataset, lambda: tmp() / "out.csv"),
    "analysis.readers.frf.read_frf": _c(_f("frf")),
    "analysis.readers.frf.read_frf_csv": _c(_f("frf")),
    "analysis.readers.frf.read_frf_uff": _c(lambda: tmp() / "missing.uff"),
    "analysis.readers.integrity.available_memory": _c(),
    "analysis.readers.integrity.describe": _c(lambda: ValueError("bad")),
    "analysis.readers.integrity.file_size": _c(_f("nc")),
    "analysis.readers.integrity.format_bytes": _c(1536),
    "analysis.readers.integrity.memory_budget": _c(),
    "analysis.readers.integrity.reading": _c(_f("nc"), "netCDF"),
    "analysis.readers.integrity.require_in_file": _c(10, 100, _f("nc"), "a block",
                                                     format_name="netCDF"),
    "analysis.readers.integrity.require_memory": _c(1024, _f("nc"), "a block"),
    "analysis.readers.layout.build_dataset": _c(lambda: [_channel()], FS,
                                                source_format="test"),
    "analysis.readers.layout.clean_attrs": _c(lambda: {"a": True, "b": {"c": 1}}),
    "analysis.readers.layout.sanitize_names": _c(lambda: ["a b", "time", "1x"]),
    "analysis.readers.layout.to_udunits": _c("m/s^2"),
    "analysis.readers.layout.validate_dataset": _c(dataset),
    "analysis.readers.mat.read_mat": _c(_f("mat")),
    "analysis.readers.mat.write_mat": _c(dataset, lambda: tmp() / "out.mat"),
    "analysis.readers.mat73.is_mat73": _c(_f("mat")),
    "analysis.readers.mat73.load_mat73": _c(lambda: tmp() / "missing.mat"),
    "analysis.readers.matcheck.check_mat": _c(_f("mat")),
    "analysis.readers.ncimage.file_image": _c(_f("nc")),
    "analysis.readers.ncimage.load_image": _c(_f("nc")),
    "analysis.readers.ncimage.open_image": _c(_f("nc")),
    "analysis.readers.netcdf.read_netcdf": _c(_f("nc")),
    "analysis.readers.netcdf.write_netcdf": _c(dataset, lambda: tmp() / "out.nc"),
    "analysis.readers.riff.read_samples": _c(_f("wav"), _wav_layout),
    "analysis.readers.riff.wav_layout": _c(_f("wav")),
    "analysis.readers.tdms.read_tdms": _c(lambda: tmp() / "missing.tdms"),
    "analysis.readers.texttable.table_lines": _c("a,b\n1,2\n"),
    "analysis.readers.timebase.grid_fits": _c(lambda: np.arange(10) / 100.0, 100.0,
                                              _precision),
    "analysis.readers.timebase.print_precision": _c(lambda: ["0.01", "0.02"]),
    "analysis.readers.timebase.uniform_rate": _c(lambda: np.arange(10) / 100.0, _precision),
    "analysis.readers.uff.read_uff": _c(lambda: tmp() / "missing.uff"),
    "analysis.readers.wav.read_wav": _c(_f("wav")),
    "analysis.readers.wav.write_wav": _c(lambda: dataset()[["acc"]], lambda: tmp() / "o.wav"),
    # resample
    "analysis.resample.angle_from_speed": _c(lambda: run_up()["t"], rpm),
    "analysis.resample.check_sampling": _c(32, 10.0),
    "analysis.resample.check_speed": _c(rpm, N),
    "analysis.resample.default_samples_per_rev": _c(FS, 1500.0),
    "analysis.resample.resample_to_angle": _c(x, FS, samples_per_rev=32, rpm=rpm),
    "analysis.resample.tracking": lambda: (_tracking_args(), {}),
    # runup
    "analysis.cut_plan.cut_order_list": _c(lambda: [3.0, 7.0], None, lambda: {"a": 5.0}),
    "analysis.cut_plan.default_cut_resolution": _c(lambda: np.array([3.0, 7.0]), 30.0, 3.77),
    "analysis.cut_plan.enbw_and_lobe": _c("flattop"),
    "analysis.cut_plan.select_cut_orders": _c(lambda: [(3.0, ["a"], True), (5.0, ["b"], False)],
                                              1.0, 20.0),
    "analysis.cut_plan.separation_orders": _c(0.25),
    "analysis.cut_resonances.cut_resonances": _c(lambda: objects()["runup_levels"].cuts,
                                                 lambda: ["a", "b"]),
    "analysis.runup_level_plots.campbell_levels_figure": _c(_o("runup_levels")),
    "analysis.runup_level_plots.order_cuts_levels_figure": _c(_o("runup_levels")),
    "analysis.runup_level_plots.waterfall_figure": _c(_o("runup_levels")),
    "analysis.runup_levels.finest_order_resolution": _c(30.0),
    "analysis.runup_levels.runup_levels": _c(x, FS, rpm, lambda: [3.0, 7.0],
                                             map_resolution=8.0),
    "analysis.waterfall.level_reference": _c("N"),
    "analysis.waterfall.waterfall_from_map": _c(_o("rpm_frequency_map")),
    "analysis.runup.map_features": _c(_o("map_ds")),
    "analysis.runup.map_levels": _c(_o("map_ds")),
    # sinc
    "analysis.sinc.compile_ahead": _c(),
    "analysis.sinc.decimate": _c(lambda: np.ones((1, 64)), lambda: np.ones(9) / 9, 2, 4, 10),
    "analysis.sinc.interpolate": _c(lambda: np.ones((1, 64)), lambda: np.linspace(12, 50, 20)),
    "analysis.sinc.kernel_table": _c(),
    "analysis.sinc.positions": _c(lambda: np.linspace(0, 10, 64), lambda: np.arange(64) / FS,
                                  0.0, 0.1, 0, 50, 0.0, FS),
    # spectrum
    "analysis.spectrum.find_peaks": _c(_o("spectrum")),
    "analysis.spectrum.spectrum": _c(x, FS),
    # speed
    "analysis.speed.from_angle": _c(lambda: run_up()["t"], angle),
    "analysis.speed.from_rpm": _c(lambda: run_up()["t"], rpm),
    "analysis.speed.from_tacho": _c(lambda: run_up()["tacho"], FS),
    "analysis.sync_reference.shaft_angle": _c(lambda: _signal(), rpm=rpm),
    "analysis.threads.one_blas_thread": _c(),
    # tsa
    "analysis.tsa.comb_response": _c(lambda: np.linspace(0, 1, 5), 10),
    "analysis.tsa.fractional_shift": _c(lambda: np.sin(np.linspace(0, 6, 64)), 0.3),
    "analysis.tsa.tsa": _c(x, FS, angle=angle, samples_per_rev=64),
    "analysis.tsa.tsa_windows": _c(x, FS, revolutions=10, angle=angle, samples_per_rev=64),
    # vold-kalman
    "analysis.vold_kalman.bandwidth_to_weight": _c(5.0, FS),
    "analysis.vold_kalman.order_waveform": _c(lambda: x()[:1024], FS, orders=[3.0],
                                              bandwidth=5.0, rpm=lambda: rpm()[:1024]),
    "analysis.vold_kalman.remove_orders": _c(lambda: x()[:1024], FS, orders=[3.0],
                                             bandwidth=5.0, rpm=lambda: rpm()[:1024]),
    "analysis.vold_kalman.weight_to_bandwidth": _c(1e6, FS),
    "analysis.vold_kalman_checks.elements": _c(lambda: [1.0, 2.0]),
    "analysis.vold_kalman_checks.per_order": _c(lambda: np.array([5.0]), 2, "bandwidth"),
    "analysis.vold_kalman_checks.positions": _c(lambda: [0], 2, "remove"),
    "analysis.vold_kalman_checks.real_number": _c(1.0, "v"),
    "analysis.vold_kalman_checks.real_numbers": _c(lambda: [1.0, 2.0], "v"),
    "analysis.vold_kalman_checks.reference_lengths": _c(rpm),
    "analysis.vold_kalman_checks.result_bytes": _c(1, 2, 1024, 1),
    "analysis.vold_kalman_checks.shaft_list": _c(rpm, N),
    "analysis.vold_kalman_checks.shaft_positions": _c(lambda: [0, 0], 2, 1),
    "analysis.vold_kalman_checks.speed_references": _c(lambda: _signal(), rpm, None, None, 1,
                                                       0, lambda: run_up()["t"]),
    "analysis.vold_kalman_plots.order_removal_figure": _c(_vk_removal),
    "analysis.vold_kalman_plots.order_waveform_figure": _c(_vk),
    "analysis.vold_kalman_solver.difference_coefficients": _c(2),
    "analysis.vold_kalman_solver.minimum_working_bytes": _c(1024, 2, 1, 1),
    "analysis.vold_kalman_solver.plan": _c(1024, 2, 1, 1, 1e9),
    "analysis.vold_kalman_solver.solve": lambda: _solve_args(),
    # windows
    "analysis.windows.get_window": _c("hann", 64),
    "analysis.windows.main_lobe_half_width": _c("hann"),
    "analysis.windows.parse_window": _c(lambda: ("kaiser", 8.6)),
    "analysis.windows.window_info": _c("hann", 64),
    "analysis.windows.window_info_of": _c("hann", lambda: np.hanning(64)),
    "analysis.windows.window_sums": _c(lambda: np.hanning(64)),
}

