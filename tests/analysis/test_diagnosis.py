"""analysis.diagnosis: order profiles, prominence, scores, family evidence (no simulator)."""

import json

import numpy as np
import pytest

from analysis.diagnosis import (
    Cause,
    Diagnosis,
    OrderProfile,
    deadband_db,
    dynamic_range_db,
    family_evidence,
    family_lines,
    impulse_mismatch_db,
    order_profile,
    phasing_shifts,
    prominence_db,
    shaft_line_mask,
    sideband_ratios,
    signature_score,
    with_noise_floor,
)

FS = 8192.0


def _ramp(duration=20.0, rpm0=600.0, rpm1=900.0):
    t = np.arange(int(duration * FS)) / FS
    rpm = rpm0 + (rpm1 - rpm0) * t / duration
    angle = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    return t, rpm, angle


def test_order_profile_amplitude_of_an_order_line_in_a_run_up():
    # order 10.5 with amplitude 2 (RMS sqrt(2)) and order 37 with 0.5 during a run-up
    _t, rpm, ang = _ramp()
    x = 2.0 * np.sin(10.5 * ang) + 0.5 * np.cos(37 * ang)
    p = order_profile(x, FS, rpm, max_order=60, revolutions=16)
    assert p.order[1] == pytest.approx(1 / 16)
    a = p.amplitude
    i, j = np.argmin(abs(p.order - 10.5)), np.argmin(abs(p.order - 37))
    # Hann window: the line falls on a bin; power summed over the main lobe = RMS^2
    assert np.sqrt(np.sum(a[i - 2:i + 3] ** 2) / 1.5) == pytest.approx(np.sqrt(2), rel=0.02)
    assert np.sqrt(np.sum(a[j - 2:j + 3] ** 2) / 1.5) == pytest.approx(0.5 / np.sqrt(2),
                                                                      rel=0.02)
    assert p.segments >= 3
    assert p.speed_rpm[0] == pytest.approx(600) and p.speed_rpm[2] == pytest.approx(900,
                                                                                    rel=1e-3)


def test_order_profile_refuses_short_records_and_bad_speed():
    _t, rpm, ang = _ramp(duration=0.5)
    with pytest.raises(ValueError, match="at least 16"):
        order_profile(np.sin(3 * ang), FS, rpm, max_order=20)
    with pytest.raises(ValueError, match="> 0"):
        order_profile(np.ones(1000), FS, np.zeros(1000), max_order=20)
    with pytest.raises(ValueError, match="one value per sample"):
        order_profile(np.ones(1000), FS, np.ones(999), max_order=20)


def test_prominence_ignores_a_slow_transfer_function():
    rng = np.random.default_rng(0)
    order = np.arange(4000) / 16
    amp = 1e-3 * (1 + 0.1 * rng.standard_normal(order.size) ** 2)
    amp[(np.arange(order.size) % 57) == 0] = 1e-2  # 20 dB above the floor
    p1 = OrderProfile(order, amp, "1", 16, 4, (1, 1, 1))
    gain = 10 ** (np.sin(order / 40))  # +-20 dB, slow against the floor window
    p2 = OrderProfile(order, amp * gain, "1", 16, 4, (1, 1, 1))
    d = prominence_db(p1) - prominence_db(p2)
    lines = (np.arange(order.size) % 57) == 0
    assert np.max(np.abs(d[lines][3:-3])) < 1.5
    assert prominence_db(p1).max() <= 40.0 and prominence_db(p1).min() >= 0.0


def test_signature_score_bounds_and_scaling():
    rng = np.random.default_rng(1)
    sig = np.zeros(2000)
    sig[rng.choice(2000, 60, replace=False)] = 20.0
    noise = rng.normal(0, 1.0, 2000)
    dead = deadband_db(noise)
    assert 2.0 < dead < 4.5  # 3 robust sigma of unit noise
    # the measured rises are the simulated ones at half the level, plus noise
    meas = 0.5 * sig + noise
    s = signature_score(meas, sig, deadband=deadband_db(meas))
    assert s > 0.8
    # noise alone, or rises elsewhere, explain nothing
    assert signature_score(noise, sig, deadband=dead) < 0.1
    other = np.roll(sig, 7) + noise
    assert signature_score(other, sig, deadband=deadband_db(other)) < 0.2
    assert signature_score(np.zeros(10), np.ones(10), deadband=1.0) == 0.0


def test_shaft_lines_alone_do_not_make_an_eccentricity():
    """A healthy gearbox with strong 1x lines (unbalance of the sun, 4.95 carrier orders, and
    of the carrier) against a simulated sun eccentricity that raises those lines and its mesh
    sidebands ``m f_mesh +- f_rel``: counted, the shaft lines alone score it above the 0.4
    threshold; left out (``shaft_line_mask``), they do not. A real eccentricity (the mesh
    sidebands, with or without the 1x line) keeps its score."""
    order = np.arange(0, 420, 1 / 16)
    rng = np.random.default_rng(5)
    mesh, f_rel, sun, carrier = 83.0, 83.0 / 21.0, 104.0 / 21.0, 1.0

    def lines(at, db, base):
        d = base.copy()
        for o, v in at:
            d[np.argmin(np.abs(order - o))] += v
        return d

    sidebands = [(m * mesh + k * f_rel, 12.0) for m in (1, 2, 3, 4) for k in (-1, 1)]
    shaft = [(sun, 25.0), (carrier, 22.0)]
    noise = rng.normal(0.0, 1.0, order.size)
    healthy = lines(shaft, None, noise)
    sig = lines(shaft + sidebands, None, np.zeros(order.size))
    dead = deadband_db(healthy)
    mask = shaft_line_mask(order, [sun, carrier, 0.0, -1.68])
    # the mask: 1x and 2x of each turning shaft, +-2 bins; nothing else
    want = np.zeros(order.size, bool)
    for c in (sun, 2 * sun, carrier, 2 * carrier, 1.68, 3.36):
        want |= np.abs(order - c) <= 2 / 16 + 1e-12
    np.testing.assert_array_equal(mask, want)
    assert not mask[np.argmin(np.abs(order - (mesh + f_rel)))]
    assert mask[np.argmin(np.abs(order - 2 * sun))] and mask[np.argmin(np.abs(order - 3.36))]
    assert signature_score(healthy, sig, deadband=dead) > 0.4  # the false alarm of before
    assert signature_score(healthy, sig, deadband=dead, exclude=mask) < 0.1
    faulty = lines(sidebands, None, healthy)
    for meas in (faulty, lines(sidebands, None, noise)):
        d = deadband_db(meas)
        assert signature_score(meas, sig, deadband=d, exclude=mask) > 0.9
    with pytest.raises(ValueError, match="exclude must be a bool array"):
        signature_score(healthy, sig, deadband=dead, exclude=mask[1:])
    with pytest.raises(ValueError, match="harmonics = 0 is not admissible"):
        shaft_line_mask(order, [sun], harmonics=0)


@pytest.mark.parametrize("gear", ["ring", "sun"])
def test_the_phasing_moves_a_central_gear_faults_sidebands(gear):
    """Four planets at 90 deg, z_s = 21, z_r = 83 (sequential phasing), ring fixed, a sensor
    on the housing with a Hann window over the planets' angle: the spectrum (21 carrier
    revolutions, exact bins) of a tooth fault on the ring or the sun, written here from the
    mesh phases (each planet's mesh modulated by a pulse when it meets the damaged tooth). The
    catalogue's sidebands ``m f_mesh +- k f`` are cancelled (nothing there), the lines stand
    at the positions ``phasing_shifts`` moves them to; for 3 in-phase planets nothing moves."""
    revs, spr = 21, 2048
    th = 2 * np.pi * np.arange(revs * spr) / spr  # carrier angle
    psi = np.radians([0.0, 90.0, 180.0, 270.0])
    zs, zr = 21, 83

    def pulse(x, width):
        x = np.angle(np.exp(1j * x))
        return np.where(np.abs(x) < width / 2, np.cos(np.pi * x / width) ** 2, 0.0)

    y = np.zeros(th.size)
    for p in psi:
        d = np.angle(np.exp(1j * (th + p)))  # the planet's angle from the sensor
        w = 0.05 + 0.95 * pulse(d, np.radians(120.0))  # Hann window, 120 deg
        if gear == "ring":  # the planet passes the damaged ring tooth at carrier angle 1.0
            y += w * (1 + 0.5 * pulse(th + p - 1.0, 1.6 * 2 * np.pi / zr)) * np.cos(zr * (th + p))
        else:  # the sun turns at 83/21 relative to the carrier
            phi = th * zr / zs
            y += w * (1 + 0.5 * pulse(phi - p - 1.0, 1.6 * 2 * np.pi / zs)) * np.cos(
                zs * (phi - p))
    amp = np.abs(np.fft.rfft(y)) / y.size

    def at(o):
        return amp[np.rint(np.asarray(o) * revs).astype(int)]

    f = 4.0 if gear == "ring" else 4 * zr / zs  # N |n_gear - n_carrier|
    z = -zr if gear == "ring" else zs
    shifts = phasing_shifts(z, psi, pass_order=1.0, mesh_harmonics=2)
    assert shifts == [(1.0,), (2.0, -2.0)]
    nominal = family_lines(f, mesh_order=83.0, mesh_harmonics=2, harmonics=0, sidebands=4,
                           max_order=200.0)
    moved = family_lines(f, mesh_order=83.0, mesh_harmonics=2, harmonics=0, sidebands=4,
                         max_order=200.0, shifts=shifts)
    big = amp.max()
    assert np.all(at(nominal) < 1e-9 * big)  # cancelled by the phasing
    assert np.all(at(moved) > 1e-6 * big)  # the fault's lines, all of them
    if gear == "ring":  # the whole record repeats every quarter revolution
        assert np.all(np.abs(moved / 4 - np.rint(moved / 4)) < 1e-9)
    in_phase = phasing_shifts(-114, np.radians([0.0, 120.0, 240.0]), pass_order=1.0,
                              mesh_harmonics=3)
    assert in_phase == [(0.0,)] * 3
    assert phasing_shifts(z, psi, pass_order=0.0, mesh_harmonics=1) == [(0.0,)]
    with pytest.raises(ValueError, match="z_gear = 0 is not admissible"):
        phasing_shifts(0, psi, pass_order=1.0, mesh_harmonics=1)


def test_family_evidence_chance_on_random_peaks():
    """False-positive rate: random rises hit a family by chance at the stated rate."""
    order = np.arange(1, 6000) / 16
    lines = family_lines(2.85, mesh_order=114, mesh_harmonics=3, harmonics=6, sidebands=3,
                         max_order=order[-1])
    assert np.all(lines > 0) and lines.size == 6 + 3 * 6
    rng = np.random.default_rng(2)
    small = 0
    trials = 200
    for _ in range(trials):
        d = np.zeros(order.size)
        d[rng.choice(order.size, 40, replace=False)] = 10.0
        ev = family_evidence(order, d, 3.0, {"planet_fault": (2.85, lines)})[0]
        small += ev.chance < 0.01
    assert small / trials <= 0.03  # at most the nominal 1 % (+ discreteness)
    # rises on the family's lines: tiny chance
    d = np.zeros(order.size)
    for o in lines:
        d[np.argmin(abs(order - o))] = 10.0
    ev = family_evidence(order, d, 3.0, {"planet_fault": (2.85, lines)})[0]
    assert ev.hits == lines.size and ev.chance < 1e-20


def _diagnosis():
    order = np.arange(100) / 16
    prof = OrderProfile(order, np.ones(100), "m s-2", 16, 3, (1.0, 2.0, 3.0), "measured")
    causes = [Cause("crack", "sun", 0.7, ("a", "b"), "crack sun 50 %", "likely"),
              Cause("pin_error", "planet", 0.1, ("c",), "pin_error planet 30 um", "unlikely")]
    return Diagnosis(causes, 0.4, order, prof, prof, np.zeros(100), 2.0,
                     {"crack sun 50 %": np.ones(100), "pin_error planet 30 um": np.zeros(100)})


def test_result_json_dataset_and_plot():
    d = _diagnosis()
    js = json.loads(d.to_json())
    assert list(js) == ["threshold", "causes"]
    assert [list(c) for c in js["causes"]] == [["cause", "member", "score", "verdict",
                                                "evidence"]] * 2
    assert js["causes"][0] == {"cause": "crack", "member": "sun", "score": 0.7,
                               "verdict": "likely", "evidence": ["a", "b"]}
    assert [c.cause for c in d.likely] == ["crack"]
    assert d.possible == []
    ds = d.to_dataset()
    for v in ds.variables:
        assert "long_name" in ds[v].attrs or v in ("cause", "member", "variant"), v
    assert ds["signature"].dims == ("variant", "order")
    assert ds["score"].attrs["units"] == "1"
    fig = d.plot()
    assert len(fig.axes) == 3


def test_noise_floor_of_a_measurement_carried_over_to_a_noise_free_simulation():
    # constant speed: lines at every integer order (amplitude 1) and a weak line at 20.5
    # (30 dB down); the "measurement" adds white noise that buries the weak line
    _t, rpm, ang = _ramp(duration=20.0, rpm0=900.0, rpm1=900.0)
    clean = np.sum([np.sin(k * ang) for k in range(1, 41)], axis=0) + 0.03 * np.sin(20.5 * ang)
    noise = 2.0 * np.random.default_rng(3).standard_normal(clean.size)
    sim = order_profile(clean, FS, rpm, max_order=45, revolutions=16)
    meas = order_profile(clean + noise, FS, rpm, max_order=45, revolutions=16)
    only_noise = order_profile(noise, FS, rpm, max_order=45, revolutions=16)
    dr = dynamic_range_db(meas)
    # independent: line level minus the 20th percentile of the noise-only profile's level
    i = np.argmin(abs(meas.order - 20.0))
    line_db = float(np.max(sim.level_db[i - 2:i + 3]))
    noise_db = float(np.percentile(only_noise.level_db, 20))
    assert dr[i] == pytest.approx(line_db - noise_db, abs=1.5)
    eff = with_noise_floor(sim, dr)
    # powers add, the floor DR dB below the running maximum over +-6 orders (193 bins)
    k = i + 5
    top = np.max(sim.level_db[k - 96:k + 97])
    assert eff.amplitude[k] ** 2 == pytest.approx(sim.amplitude[k] ** 2
                                                  + 10 ** ((top - dr[k]) / 10), rel=1e-9)
    # the floor level matches the measured one within 2 dB between the lines
    between = (np.abs(meas.order - np.round(meas.order)) > 0.2) & (meas.order > 8) & (
        meas.order < 37)
    assert np.median(eff.level_db[between]) == pytest.approx(
        np.median(meas.level_db[between]), abs=2.0)
    # the weak line stands out of the noise-free simulation, not out of the measurement nor
    # out of the simulation with the measurement's floor
    j = np.argmin(abs(meas.order - 20.5))
    assert prominence_db(sim)[j] > 8.0
    assert prominence_db(meas)[j] < 3.0
    assert prominence_db(eff)[j] < 3.0
    with pytest.raises(ValueError, match="dynamic_range"):
        with_noise_floor(sim, -1.0)
    with pytest.raises(ValueError, match="percentile"):
        dynamic_range_db(meas, percentile=60.0)


def _pulse_sidebands(duty, depth, mesh, fault, k_max, harmonic=1):
    """Analytic sidebands of cos(m M θ) (1 + a p(θ)), p a rectangular pulse train of period
    1/f and duty d: a d |sinc(k d)| over the mesh line 1 + a d."""
    k = np.concatenate((np.arange(-k_max, 0), np.arange(1, k_max + 1)))
    return depth * duty * np.abs(np.sinc(k * duty)) / (1 + depth * duty)


def _pulse_signal(duty, depth, mesh=40.0, fault=2.5, gain=1.0):
    _t, rpm, ang = _ramp(duration=12.0)
    phase = np.mod(fault * ang / (2 * np.pi), 1.0)
    return gain * np.cos(mesh * ang) * (1 + depth * (phase < duty)), rpm


def test_sideband_ratios_against_the_fourier_series_of_a_pulse():
    # a mesh line modulated by a rectangular pulse once per fault period: the sidebands over
    # the mesh line are the pulse's Fourier coefficients, whatever the gain of the path
    for duty, depth in ((0.1, 0.5), (0.35, 0.2)):
        x, rpm = _pulse_signal(duty, depth, gain=37.0)
        p = order_profile(x, FS, rpm, max_order=100, revolutions=16)
        r, n = sideband_ratios(p, 2.5, 40.0, mesh_harmonics=1)
        # exact: line M + k f of a real signal gets c_k and the image c_(k + 2M/f), with the
        # pulse's coefficients c_n = d sinc(n d) exp(-i pi n d)
        k = np.concatenate((np.arange(-8, 0), np.arange(1, 9)))

        def c(n, duty=duty):
            return duty * np.sinc(n * duty) * np.exp(-1j * np.pi * n * duty)

        exact = depth * np.abs(c(k) + c(k + 32)) / np.abs(1 + depth * c(0) + depth * c(32))
        assert r.shape == exact.shape == n.shape == (16,)
        big = exact > 0.01 * exact.max()  # the sinc's zeros only show the window's leakage
        np.testing.assert_allclose(r[big], exact[big], rtol=0.03)
        assert np.all(n < 1e-3)  # no noise
        # without the noise floor (simulated profiles): the same ratios, bit for bit
        r2, n2 = sideband_ratios(p, 2.5, 40.0, mesh_harmonics=1, with_noise=False)
        assert np.array_equal(r, r2) and n2.size == 0
    with pytest.raises(ValueError, match="fundamental"):
        sideband_ratios(p, 0.0, 40.0)
    # a fault order above half the mesh order has no sidebands of its own
    assert sideband_ratios(p, 30.0, 40.0)[0].size == 0


def test_impulse_mismatch_tells_pulse_widths_apart_not_sizes():
    narrow = _pulse_sidebands(0.1, 0.3, 40.0, 2.5, 8)
    narrow_deep = _pulse_sidebands(0.1, 0.9, 40.0, 2.5, 8)  # same width, another size
    wide = _pulse_sidebands(0.4, 0.3, 40.0, 2.5, 8)
    quiet = np.full_like(narrow, 1e-6)
    same = impulse_mismatch_db(narrow, quiet, [narrow_deep, 2 * narrow_deep])
    other = impulse_mismatch_db(narrow, quiet, [wide, 2 * wide])
    assert same < 0.1 < 3.0 < other
    # where the noise buries every sideband there is nothing to tell apart
    loud = np.full_like(narrow, 10.0)
    assert impulse_mismatch_db(loud, loud, [narrow]) == pytest.approx(
        impulse_mismatch_db(loud, loud, [wide]), abs=0.05)
    assert np.isnan(impulse_mismatch_db(np.empty(0), np.empty(0), [np.empty(0)]))
    with pytest.raises(ValueError, match="do not match"):
        impulse_mismatch_db(narrow, quiet, [narrow[:-1]])
