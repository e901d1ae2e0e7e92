"""Virtual housing sensors and the tacho: windows, housing response, planet phasing.

References: analytic window coefficients and steady-state modal responses, a UFF 58 / CSV FRF
equal to the modal one, McFadden & Smith's phasing rule (``analysis.catalogue``), and the
analysis tools reading the channels like measured ones.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import xarray as xr

from analysis.catalogue import phasing_factor
from analysis.spectrum import spectrum
from analysis.speed import from_tacho
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config, load_gearset
from gearvib.io import read_run, write_netcdf
from gearvib.sensors import (
    HousingMode,
    HousingSensor,
    MeasuredFrf,
    Tacho,
    housing_response,
    path_force,
    tacho_signal,
    window_weight,
)
from gearvib.simulate import SpeedRamp, simulate
from tests.gearvib.preset_drive import input_coupling

FS = 20000.0
MODES = (HousingMode(800.0, 0.03, 2.0), HousingMode(2500.0, 0.05, -1.0))


def test_window_definitions() -> None:
    w = math.radians(60.0)
    d = np.array([0.0, w / 2, w, 1.2 * w, -w / 2, 2 * math.pi + w / 2])
    np.testing.assert_allclose(window_weight("hann", 60.0, d), [1, 0.5, 0, 0, 0.5, 0.5],
                               atol=1e-15)
    np.testing.assert_allclose(window_weight("rectangular", 60.0, d), [1, 1, 1, 0, 1, 1])
    np.testing.assert_allclose(window_weight("exponential", 60.0, d),
                               np.exp(-np.abs([0, w / 2, w, 1.2 * w, w / 2, w / 2]) / w))


def modal_sensor(modes=MODES) -> HousingSensor:
    return HousingSensor("s", 0.0, housing_modes=modes)


def test_housing_response_is_the_modal_steady_state() -> None:
    """Sines switched on at t = 0 reach the steady state A |H(f)| sin(w t + arg H(f)) of the
    modal accelerance H = sum g (-w^2) / (w_k^2 - w^2 + 2 i z w_k w); a constant force gives
    no acceleration."""
    t = np.arange(8000) / FS
    freqs, amps = (300.0, 1100.0, 2600.0), (5.0, 2.0, 1.0)
    p = 40.0 + sum(a * np.sin(2 * np.pi * f * t) for f, a in zip(freqs, amps, strict=True))
    acc = housing_response(p, FS, modal_sensor())
    ref = np.zeros_like(t)
    for f, a in zip(freqs, amps, strict=True):
        h = sum(m.accelerance(np.array([f]))[0] for m in MODES)
        ref += a * abs(h) * np.sin(2 * np.pi * f * t + np.angle(h))
    tail = t > 0.3  # transients (z w_k >= 150 s^-1) decayed
    np.testing.assert_allclose(acc[tail], ref[tail], atol=2e-3 * np.abs(ref).max())
    assert np.abs(housing_response(np.full(500, 7.0), FS, modal_sensor())).max() < 1e-12


def test_measured_frf_files_give_the_modal_response(tmp_path) -> None:
    """The modal accelerance written to a UFF 58 file (and as mobility to a CSV file) and read
    back as a measured FRF gives the same acceleration (1 Hz frequency resolution)."""
    import pyuff

    f = np.arange(0.0, 10001.0, 1.0)
    h = sum(m.accelerance(f) for m in MODES)
    uff = tmp_path / "housing.uff"
    pyuff.UFF(str(uff)).write_sets(pyuff.prepare_58(
        func_type=4, ordinate_spec_data_type=12, orddenom_spec_data_type=13,
        abscissa_spec_data_type=18, x=f, data=h, ordinate_axis_units_lab="m/s2",
        orddenom_axis_units_lab="N", abscissa_axis_units_lab="Hz", id1="housing FRF",
        rsp_node=1, rsp_dir=1, ref_node=2, ref_dir=1), mode="overwrite")
    mob = h[1:] / (2j * np.pi * f[1:])
    csv = tmp_path / "housing.csv"
    csv.write_text("f [Hz]; |Y| ; phase [deg]\n" + "".join(
        f"{fi:.1f};{abs(v):.12e};{np.degrees(np.angle(v)):.12f}\n".replace(".", ",")
        for fi, v in zip(f[1:], mob, strict=True)))
    t = np.arange(6000) / FS
    p = np.random.default_rng(2).standard_normal(t.size) * 10.0
    ref = housing_response(p, FS, modal_sensor())
    for frf in (MeasuredFrf.read(uff),
                MeasuredFrf.read(csv, quantity="mobility", columns="magnitude_phase")):
        acc = housing_response(p, FS, HousingSensor("s", 0.0, frf=frf))
        assert np.abs(acc - ref).max() < 2e-3 * np.abs(ref).max()


def test_tacho_pulses_and_speed_reference() -> None:
    """The area-sampled pulse train gives analysis.speed.from_tacho the shaft speed."""
    t = np.arange(20000) / FS
    rpm = 900.0 + 600.0 * t  # a ramp
    angle = np.cumsum(rpm / 60 * 2 * np.pi / FS) - rpm[0] / 60 * 2 * np.pi / FS
    v = tacho_signal(angle, Tacho(pulses_per_rev=30, duty=0.4, level_v=5.0))
    assert v.max() == 5.0 and v.min() == 0.0
    rising = np.flatnonzero((v[1:] >= 2.5) & (v[:-1] < 2.5))
    assert rising.size == int(angle[-1] * 30 / (2 * np.pi))
    ref = from_tacho(v, FS, pulses_per_rev=30)
    # every edge where the shaft passes k/30 of a revolution, to rounding
    exact = np.interp(ref.pulse_angles + 2 * np.pi / 30, angle, t)  # the first edge: k = 1
    np.testing.assert_allclose(ref.pulse_times, exact, atol=1e-9)
    inner = (t > 0.05) & (t < 0.95)
    got = np.interp(t[inner], ref.time, ref.rpm)
    np.testing.assert_allclose(got, rpm[inner], rtol=1e-4)


# ---- McFadden & Smith: planet phasing -------------------------------------------------------


def carrier_order_spectrum(result, values: np.ndarray, n_rev: int) -> dict[int, float]:
    """Amplitude of every carrier order of the last ``n_rev`` carrier revolutions (the run's
    carrier period is an integer number of samples)."""
    theta_c = result.rotation[result.members.index("carrier")]
    rate = (theta_c[-1] - theta_c[0]) / (theta_c.size - 1)  # mean [rad per sample]
    n = round(n_rev * 2 * np.pi / rate)
    x = values[-n:]
    spec = np.abs(np.fft.rfft(x)) * 2 / n
    return {k // n_rev: spec[k] for k in range(0, spec.size, n_rev)}


def constant_run(model, rpm: float, duration: float):
    """A constant-speed run of a paper set through its drive, a spring-damper on the sun (the
    paper presets' [simulation]): near 1500 min^-1 the paper set's rotational modes are
    parametrically unstable (2 f2/4) without the drive's damping."""
    return simulate(model, SpeedRamp(rpm, rpm, 1.0, input_torque=60.0,
                                     coupling=input_coupling(model)),
                    duration=duration, fs_out=FS, progress=False)


def paper_sensor() -> HousingSensor:
    return HousingSensor("top", 30.0, window="hann", width_deg=90.0,
                         housing_modes=(HousingMode(3000.0, 0.05, 1.0),))


@pytest.mark.parametrize("preset", ["paper-case1", "paper-case2"])
def test_housing_sensor_passes_only_the_phased_carrier_orders(preset) -> None:
    """Equally spaced identical planets (paper-case1): the housing signal has components only
    at carrier orders divisible by N = 3 (McFadden & Smith 1985). With paper-case2's spacing
    the other orders appear, as the catalogue's phasing factor says."""
    model = assemble(load_gearset(preset)).with_sensors([paper_sensor()])
    f_c = FS / 3600  # carrier period: 3600 samples
    rpm = f_c * 147 / 33 * 60
    res = constant_run(model, rpm, 0.15 + 2 * 3600 / FS)
    spec = carrier_order_spectrum(res, res.sensor_acceleration[0], 2)
    top = max(spec.values())
    angles = np.radians([p["angle_deg"] for p in model.meta["planets"]])
    for m in (1, 2):  # carrier orders around the first two mesh harmonics (114, 228)
        near = range(114 * m - 6, 114 * m + 7)
        passed = [o for o in near if o % 3 == 0]
        others = [o for o in near if o % 3]
        assert all(phasing_factor(angles, o) == (1.0 if o % 3 == 0 else 0.0) for o in near) \
            or preset == "paper-case2"
        if preset == "paper-case1":
            assert min(spec[o] for o in passed[1:-1]) > 1e-4 * top  # measured 9e-4 .. 2e-2
            assert max(spec[o] for o in others) < 1e-6 * top  # measured 3e-8 (-151 dB)
        else:
            # the strongest non-multiple of 3 is one the phasing factor passes well
            best = max(others, key=lambda o: spec[o])
            assert spec[best] > 1e-3 * top  # measured 1.8e-2 (order 115), 5.6e-2 (229)
            assert phasing_factor(angles, best) > 0.5


def four_planet_model():
    cfg, base = load_config("paper-case1")
    cfg = copy.deepcopy(cfg)
    geo = cfg["geometry"]
    geo.update(z_sun=21, z_ring=-63, z_planet=21)
    geo.pop("planet_angles_deg", None)
    geo["n_planets"] = 4
    return assemble(gearset_from_dict(cfg, base=base))


def window_coefficient(shape, width_deg: float, q: int) -> float:
    """|W_q| = |(1/2 pi) int w(d) exp(-i q d) dd| of the analytic window (fine quadrature)."""
    d = np.linspace(-np.pi, np.pi, 400001)
    wdt = math.radians(width_deg)
    w = {"hann": np.where(np.abs(d) <= wdt, 0.5 * (1 + np.cos(np.pi * d / wdt)), 0.0),
         "exponential": np.exp(-np.abs(d) / wdt)}[shape]
    return abs(np.trapezoid(w * np.exp(-1j * q * d), d)) / (2 * np.pi)


@pytest.mark.parametrize("shape,width", [("hann", 60.0), ("exponential", 40.0)])
def test_sideband_asymmetry_follows_the_window(shape, width) -> None:
    """Four equally spaced planets, z_s = 21, z_r = 63: around the mesh order 63 only the
    carrier orders 64, 60, 68, 56 (q = +1, -3, +5, -7) survive, and their levels stand as the
    window's Fourier coefficients |W_1| : |W_3| : |W_5| : |W_7| - an asymmetric pattern."""
    model = four_planet_model().with_sensors([HousingSensor(
        "s", 0.0, window=shape, width_deg=width, housing_modes=(HousingMode(3000.0, 0.05, 1.0),))])
    sensor = model.sensors[0]
    f_c = FS / 5000  # 4 Hz: no mesh harmonic near a natural frequency (832, 947, 1384 Hz)
    rpm = f_c * 4 * 60
    res = constant_run(model, rpm, 0.2 + 5000 / FS)
    assert not res.flank_contact_changes.any()
    p = path_force(res, model, sensor)
    spec = carrier_order_spectrum(res, p, 1)
    survivors = {64: 1, 60: -3, 68: 5, 56: -7}
    assert max(spec[o] for o in range(50, 76) if o % 4) < 1e-6 * spec[64]
    ref = {o: window_coefficient(shape, width, q) for o, q in survivors.items()}
    for o in (60, 68, 56):
        assert spec[o] / spec[64] == pytest.approx(ref[o] / ref[64], rel=0.02)
    assert spec[60] != pytest.approx(spec[68], rel=0.1)  # asymmetric about the mesh order
    # the housing accelerance multiplies every order by |H(f)|
    acc = carrier_order_spectrum(res, res.sensor_acceleration[0], 1)
    h = np.abs(sensor.accelerance(np.array([60.0, 64.0, 68.0]) * f_c))
    assert acc[60] / acc[64] == pytest.approx(spec[60] / spec[64] * h[0] / h[1], rel=5e-3)
    assert acc[68] / acc[64] == pytest.approx(spec[68] / spec[64] * h[2] / h[1], rel=5e-3)


# ---- the run dataset --------------------------------------------------------------------------


def test_sensor_channels_in_the_dataset_and_analysis_tools(tmp_path) -> None:
    """sensor_acceleration(sensor, time) [m s-2] and tacho(time) [V] with CF attributes,
    written and read back, analysed like measured channels."""
    model = assemble(load_gearset("paper-case1")).with_sensors([
        paper_sensor(), HousingSensor("side", 120.0, window="exponential", width_deg=30.0,
                                      housing_modes=MODES),
        Tacho("tacho", pulses_per_rev=60)])
    res = simulate(model, SpeedRamp(600, 1800, 0.3, input_torque=60.0,
                                    coupling=input_coupling(model)), progress=False)
    ds = read_run(write_netcdf(res.to_dataset(), tmp_path / "run.nc"))
    acc = ds["sensor_acceleration"]
    assert acc.dims == ("sensor", "time") and list(ds["sensor"].values) == ["top", "side"]
    assert acc.attrs["units"] == "m s-2" and acc.attrs["gearvib_quantity"] == "virtual_sensor"
    assert ds["sensor_angle"].attrs["units"] == "degree"
    assert ds["tacho"].attrs["pulses_per_rev"] == 60 and ds["tacho"].attrs["units"] == "V"
    np.testing.assert_array_equal(acc.values, res.sensor_acceleration)
    s = spectrum(acc.sel(sensor="top"), window="hann", segment_length=4096)
    peak = float(s.frequency[int(np.argmax(np.asarray(s.values)))])
    assert 0 < peak < FS / 2
    # the tacho follows the simulated sun shaft: its pulses where the sun has turned by
    # k / 60 revolutions, its mean speed over 20 ms windows that of the shaft
    ref = from_tacho(ds["tacho"].values, float(ds.attrs["fs_out"]), pulses_per_rev=60)
    theta = ds["rotation"].sel(member="sun").values
    t = ds.time.values
    k0 = np.ceil(theta[0] * 60 / (2 * np.pi) - 1e-12)
    k0 += 1 if (theta[0] * 60 / (2 * np.pi)) % 1.0 < 0.5 else 0  # the first edge after t = 0
    exact = np.interp(2 * np.pi * (k0 + np.arange(ref.pulse_times.size)) / 60, theta, t)
    np.testing.assert_allclose(ref.pulse_times, exact, atol=1e-9)
    grid = np.arange(0.02, 0.28, 0.02)
    mean_tacho = np.diff(np.interp(grid, ref.time, ref.angle)) / 0.02 * 60 / (2 * np.pi)
    mean_sun = np.diff(np.interp(grid, t, theta)) / 0.02 * 60 / (2 * np.pi)
    np.testing.assert_allclose(mean_tacho, mean_sun, rtol=5e-4)  # PCHIP between pulses
    assert isinstance(ds, xr.Dataset)


def test_sensor_at_the_output_rate_matches_a_finer_output() -> None:
    """Computed after the integration from the stored forces: with the same internal step and
    twice the output rate the acceleration agrees in the analysed band (< 0.3 fs_out)."""
    model = assemble(load_gearset("paper-case1")).with_sensors([paper_sensor()])
    cond = SpeedRamp(1500, 1500, 1.0, input_torque=60.0, coupling=input_coupling(model))
    dt = 1.0 / (8 * 20000)
    a = simulate(model, cond, duration=0.2, dt=dt, fs_out=20000, progress=False)
    b = simulate(model, cond, duration=0.2, dt=dt, fs_out=40000, progress=False)
    n = 2048  # the same 0.1024 s of both records, spectra on the same frequency grid
    fa = np.fft.rfft(a.sensor_acceleration[0, -n - 1:-1]) / n
    fb = np.fft.rfft(b.sensor_acceleration[0, -2 * n - 1:-1])[: fa.size] / (2 * n)
    band = np.arange(fa.size) < 0.3 * 2 * fa.size / 2  # below 0.3 fs_out = 6 kHz
    assert np.abs(fa[band] - fb[band]).max() < 2e-3 * np.abs(fa[band]).max()


def test_bearing_path_adds_the_projected_radial_force() -> None:
    """A bearing path adds the member's radial bearing force (components in the carrier frame)
    projected on the sensor's direction, times its gain, to the windowed mesh forces."""
    from gearvib.faults import Eccentricity

    # an eccentric sun: the equally spaced planets no longer cancel the ring's radial force
    model = assemble(load_gearset("paper-case1-elastic")).with_faults(
        [Eccentricity("sun", 20e-6)])
    plain = HousingSensor("p", 75.0, housing_modes=MODES)
    with_path = HousingSensor("b", 75.0, housing_modes=MODES, bearings=(("ring", 0.7),))
    model = model.with_sensors([plain, with_path])
    res = simulate(model, SpeedRamp(900, 900, 1.0, input_torque=60.0), duration=0.05,
                   progress=False)
    p0 = path_force(res, model, model.sensors[0])
    p1 = path_force(res, model, model.sensors[1])
    fx = res.bearing_force[res.bearing_names.index("ring.x")]
    fy = res.bearing_force[res.bearing_names.index("ring.y")]
    theta_c = res.rotation[res.members.index("carrier")]
    rel = math.radians(75.0) - theta_c
    np.testing.assert_allclose(p1 - p0, 0.7 * (fx * np.cos(rel) + fy * np.sin(rel)),
                               rtol=1e-12, atol=1e-9)
    assert np.abs(fx).max() > 1.0
