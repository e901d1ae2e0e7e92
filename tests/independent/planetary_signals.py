"""Planetary-gearbox accelerometer records from the literature's phenomenological model.

An *independent* test set for ``gearvib diagnose``: nothing here uses gearvib's simulator
(its models, kernels, sensors or fault descriptions). The records are built from the
closed-form signal models of the condition-monitoring literature, so that the diagnosis is
checked on signals that its own simulator did not make (issue 30). Only the writing of the
files goes through the project's reader layer (:func:`analysis.readers.layout.build_dataset`,
:func:`analysis.readers.write_netcdf`), so that ``gearvib diagnose`` reads them as it reads any
measurement.

Model (simple planetary set, ring fixed, sun input, carrier output)
-------------------------------------------------------------------
Angles in rad, ``N`` planets at carrier angles ``psi_i``, tooth numbers ``z_s``, ``z_p``,
``z_r`` (``z_r`` the number of ring teeth, > 0 here).

*Kinematics.* The sun angle ``theta_s(t) = 2 pi / 60 * integral n_s(t) dt`` follows the input
speed ``n_s`` [min-1]; the carrier turns at ``theta_c = theta_s z_s / (z_s + z_r)``
(Willis with the ring fixed). Mesh frequency ``f_m = z_r f_c = z_s (f_s - f_c)``.

*Mesh phases* (Parker & Lin 2004; Inalpolat & Kahraman 2009), derived from the tooth
positions: planet ``i`` meshes with the fixed ring at the carrier angle ``theta_c + psi_i``,
which ring teeth pass at ``z_r / 2 pi`` per rad, so its ring-mesh phase is
``Phi_ri = z_r (theta_c + psi_i)``; the sun's teeth pass the same contact at
``z_s (theta_s - theta_c - psi_i)``, so ``Phi_si = z_r theta_c - z_s psi_i`` (with
``z_s (theta_s - theta_c) = z_r theta_c``). The planet-to-planet phase offsets are
``z_r psi_i`` (ring) and ``-z_s psi_i`` (sun) modulo ``2 pi``: in phase when ``z_s / N`` and
``z_r / N`` are integers (``paper-case1``: 33/3, 114/3), sequential otherwise (21/31/83 with
4 planets: sun offsets in quarter mesh cycles).

*Mesh vibration with decaying harmonics.* Per planet and mesh
``v_i(t) = sum_m A_m (1 + a_i(t)) cos(m Phi_i(t) + alpha_m + m b_i(t))``, ``m = 1..M``,
``A_m = A_1 r^(m-1)`` (``r`` = :attr:`RecordSpec.harmonic_decay`), phases ``alpha_m``
drawn once per gearbox; the sun mesh reaches the sensor through the planet and the ring with
the gain :attr:`RecordSpec.sun_mesh_gain`. ``a_i`` is the amplitude modulation (AM) and
``b_i`` the phase (frequency) modulation (FM) of a fault (Feng & Zuo 2012).

*Planet-pass window* (McFadden & Smith 1985): a transducer fixed to the ring at ``theta_t``
hears each planet's meshes weighted by ``w(theta_c + psi_i - theta_t)``, a Hann window
``w(d) = e + (1 - e) cos^2(pi d / W)`` for ``|d| < W / 2`` (else ``e``) or an exponential
window ``w(d) = e + (1 - e) exp(-|d| / W)``, ``d`` wrapped to ``(-pi, pi]``, ``e`` the floor
of the path around the housing (:attr:`RecordSpec.window_floor`). With identical, equally
spaced planets the record then holds only carrier orders divisible by ``N``
(``m z_r + q = 0 mod N``; McFadden & Smith's asymmetric sidebands), which the tests check.

*Faults* (Feng & Zuo 2012, MSSP 34; Lei et al. 2014): a local tooth fault is a pulse
``g(rho) = cos^2(pi rho / L)`` for ``|rho| < L / 2`` in the angle ``rho`` between the damaged
tooth and its mesh partner, over ``L = 1.6`` tooth pitches (the contact ratio): AM
``a = D g``, FM ``b = B g``, and an impulse at each engagement (``rho`` crossing 0) through a
housing resonance ``h(t) = exp(-zeta w_n t) sin(w_d t)`` (a damped second-order system,
:attr:`RecordSpec.resonance_hz`, :attr:`RecordSpec.resonance_damping`), scaled by the
window of the planet where it happens and a random +-10 % per impact
(:attr:`RecordSpec.impact_jitter`).

* sun tooth (sun angle ``delta``): ``rho_i = theta_s + delta - theta_c - psi_i``, on the
  sun mesh of every planet: fault frequency ``f_s - f_c`` per planet, ``N (f_s - f_c)``
  over the set (carrier order ``N z_r / z_s``);
* planet tooth (planet ``j``): ``rho = (z_r / z_p) theta_c + delta`` meets the ring at
  ``rho = 0`` and the sun at ``rho = pi``: ``f_m / z_p`` per flank (order ``z_r / z_p``);
* ring tooth (at ``delta_R``): ``rho_i = theta_c + psi_i - delta_R``, once per planet and
  carrier revolution: ``N f_c`` (order ``N``); the sensor hears it at the fixed window value
  ``w(delta_R - theta_t)``;
* sun eccentricity: ``rho_i = theta_s + phi_e - theta_c - psi_i``, smooth AM
  ``a = E cos rho_i`` and FM ``b = E sin rho_i`` on the sun meshes (half of it on the ring
  meshes through the load sharing) and a once-per-revolution sun line through the sun's
  bearing (not windowed): sidebands at ``f_s - f_c``.

*Healthy imperfections* (scaled by :attr:`RecordSpec.imperfection`, 0 for the ideal set):
planet-to-planet amplitude differences (3 % rms), a 2 % once-per-carrier-revolution load
ripple and weak sun and carrier shaft lines.

*Measurement.* Gaussian white noise at the stated SNR (``10 log10(P_signal / P_noise)``,
10-20 dB in the benchmark); a smooth random speed profile ``n_s(t) = n_0 (1 + u(t))`` with
``max |u| = `` :attr:`RecordSpec.fluctuation` (1 %: three sinusoids of 0.05-0.5 Hz with
random phases, scaled to the bound); a 60-pulse tacho on the input (sun) shaft, a 0-5 V
square wave with edges one sample wide, ``pulses_per_rev`` and ``member`` in its attributes.

References
----------
McFadden, P. D., Smith, J. D. (1985). An explanation for the asymmetry of the modulation
sidebands about the tooth meshing frequency in epicyclic gear vibration. Proc. IMechE C 199,
65-70.

Parker, R. G., Lin, J. (2004). Mesh phasing relationships in planetary and epicyclic gears.
J. Mech. Design 126, 365-370.

Inalpolat, M., Kahraman, A. (2009). A theoretical and experimental investigation of
modulation sidebands of planetary gear sets. J. Sound Vib. 323, 677-696.

Feng, Z., Zuo, M. J. (2012). Vibration signal models for fault diagnosis of planetary
gearboxes. Mech. Syst. Signal Process. 34, 237-252.

Lei, Y., Lin, J., Zuo, M. J., He, Z. (2014). Condition monitoring and fault diagnosis of
planetary gearboxes: a review. Measurement 48, 292-305.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import signal as sps

HERE = Path(__file__).resolve().parent

__all__ = [
    "FAULTS",
    "FOUR_PLANET",
    "GEAR_SETS",
    "PAPER_CASE1",
    "PlanetaryGearSet",
    "RecordSpec",
    "Signals",
    "benchmark_records",
    "generate",
    "mesh_phases",
    "to_dataset",
    "truth",
    "write_record",
]

FAULTS = ("sun_tooth", "planet_tooth", "ring_tooth", "sun_eccentricity")
"""Fault kinds of the generator (``None``: healthy)."""

SEVERITIES = {
    # AM depth D, FM depth B [rad], impulse peak over A_1, eccentricity E
    "clear": {"am": 0.5, "fm": 0.3, "impulse": 1.0, "ecc": 0.25},
    "weak": {"am": 0.2, "fm": 0.1, "impulse": 0.35, "ecc": 0.1},
}
"""Fault sizes of the two severities."""

CONTACT_PITCHES = 1.6
"""Width of a local fault's pulse in tooth pitches (about the contact ratio)."""


@dataclass(frozen=True)
class PlanetaryGearSet:
    """Tooth numbers and planet positions of a simple planetary set.

    Attributes
    ----------
    name : str
    z_sun, z_planet, z_ring : int
        Tooth numbers (``z_ring`` counted positive).
    planet_angles_deg : tuple of float
        Carrier angles of the planets [deg].
    config : str
        The gear set ``gearvib diagnose --gearset`` is given (preset name or TOML path).
    """

    name: str
    z_sun: int
    z_planet: int
    z_ring: int
    planet_angles_deg: tuple[float, ...]
    config: str

    @property
    def carrier_per_sun(self) -> float:
        """Carrier speed per sun speed, ``z_s / (z_s + z_r)`` (ring fixed)."""
        return self.z_sun / (self.z_sun + self.z_ring)

    @property
    def n_planets(self) -> int:
        return len(self.planet_angles_deg)

    def fault_orders(self) -> dict[str, float]:
        """Characteristic frequencies in carrier orders (Lei et al. 2014, table 1)."""
        n = self.n_planets
        return {"mesh": float(self.z_ring), "sun_tooth": n * self.z_ring / self.z_sun,
                "planet_tooth": self.z_ring / self.z_planet, "ring_tooth": float(n),
                "sun_eccentricity": self.z_ring / self.z_sun}


PAPER_CASE1 = PlanetaryGearSet("paper-case1", 33, 40, 114, (0.0, 120.0, 240.0), "paper-case1")
"""``gearvib/presets/paper-case1.toml``: z_s = 33, z_p = 40, z_r = -114, 3 planets."""

FOUR_PLANET = PlanetaryGearSet("four-planet-21-31-83", 21, 31, 83, (0.0, 90.0, 180.0, 270.0),
                               str(HERE / "four-planet-21-31-83.toml"))
"""A 4-planet 21/31/83 set (``tests/independent/four-planet-21-31-83.toml``)."""

GEAR_SETS = {g.name: g for g in (PAPER_CASE1, FOUR_PLANET)}


def mesh_phases(gs: PlanetaryGearSet) -> tuple[np.ndarray, np.ndarray]:
    """Phase offsets of every planet's sun and ring mesh [rad, in [0, 2 pi)].

    From the tooth positions (module docstring): ring ``z_r psi_i``, sun ``-z_s psi_i``.
    """
    psi = np.radians(np.asarray(gs.planet_angles_deg, float))
    return (np.mod(-gs.z_sun * psi, 2 * np.pi), np.mod(gs.z_ring * psi, 2 * np.pi))


@dataclass(frozen=True)
class RecordSpec:
    """One record of the independent set.

    Attributes
    ----------
    gear_set : PlanetaryGearSet
    fault : str or None
        One of :data:`FAULTS`, or None (healthy).
    severity : str
        ``"clear"`` or ``"weak"`` (:data:`SEVERITIES`).
    speed_rpm : float
        Mean input (sun) speed [min-1].
    duration : float
        Record length [s].
    fs : float
        Sample rate [Hz].
    snr_db : float
        Signal-to-noise ratio of the accelerometer channel [dB].
    fluctuation : float
        Bound of the relative speed fluctuation (0.01: +-1 %).
    sensor_deg : float
        Transducer position on the ring [deg, carrier-angle frame].
    window : str
        ``"hann"`` or ``"exponential"``.
    window_deg : float
        Hann: full width; exponential: decay angle [deg].
    window_floor : float
        Weight of a planet far from the transducer (path around the housing).
    resonance_hz, resonance_damping : float
        Housing resonance the fault impacts ring (natural frequency, damping ratio).
    planet : int
        Faulty planet (0-based) of a planet fault.
    harmonics : int
        Mesh harmonics ``M``.
    harmonic_decay : float
        ``A_(m+1) / A_m``.
    sun_mesh_gain : float
        Sun-mesh vibration at the sensor relative to the ring mesh's.
    imperfection : float
        Scale of the healthy imperfections (0: ideal set).
    impacts : bool
        Whether a local fault's impacts ring the housing resonance.
    impact_jitter : float
        Random relative spread of the impact sizes (uniform, +-).
    seed : int
        Seeds the gearbox (phases, imperfections, fault position), the speed profile, the
        impacts and the noise.
    """

    gear_set: PlanetaryGearSet
    fault: str | None = None
    severity: str = "clear"
    speed_rpm: float = 1500.0
    duration: float = 10.0
    fs: float = 20_000.0
    snr_db: float = 15.0
    fluctuation: float = 0.01
    sensor_deg: float = 200.0
    window: str = "hann"
    window_deg: float = 120.0
    window_floor: float = 0.05
    resonance_hz: float = 3000.0
    resonance_damping: float = 0.05
    planet: int = 0
    harmonics: int = 6
    harmonic_decay: float = 0.6
    sun_mesh_gain: float = 0.5
    imperfection: float = 1.0
    impacts: bool = True
    impact_jitter: float = 0.1
    seed: int = 0

    def __post_init__(self) -> None:
        if self.fault is not None and self.fault not in FAULTS:
            raise ValueError(f"fault = {self.fault!r} is not admissible (admissible: None, "
                             f"{', '.join(FAULTS)})")
        if self.severity not in SEVERITIES:
            raise ValueError(f"severity = {self.severity!r} is not admissible (admissible: "
                             f"{', '.join(SEVERITIES)})")
        if self.window not in ("hann", "exponential"):
            raise ValueError(f"window = {self.window!r} is not admissible (admissible: 'hann', "
                             "'exponential')")
        for name in ("speed_rpm", "duration", "fs", "window_deg", "resonance_hz"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} = {v!r} is not admissible (admissible: finite, > 0)")
        if not 0 <= self.fluctuation < 0.2:
            raise ValueError(f"fluctuation = {self.fluctuation!r} is not admissible "
                             "(admissible: 0 <= fluctuation < 0.2)")
        if not 0 <= self.planet < self.gear_set.n_planets:
            raise ValueError(f"planet = {self.planet!r} is not admissible (admissible: 0.."
                             f"{self.gear_set.n_planets - 1})")
        if self.resonance_hz >= self.fs / 2:
            raise ValueError(f"resonance_hz = {self.resonance_hz!r} is not admissible "
                             f"(admissible: < fs / 2 = {self.fs / 2:g})")

    @property
    def name(self) -> str:
        what = "healthy" if self.fault is None else f"{self.fault}-{self.severity}"
        return f"{self.gear_set.name}_{what}_{self.speed_rpm:.0f}rpm_s{self.seed}"


@dataclass(frozen=True)
class Signals:
    """A generated record.

    Attributes
    ----------
    time : numpy.ndarray
        [s].
    acceleration : numpy.ndarray
        Accelerometer channel with noise [m s-2].
    clean : numpy.ndarray
        The same without noise.
    tacho : numpy.ndarray
        60-pulse tacho on the sun shaft [V].
    speed_rpm : numpy.ndarray
        Sun speed [min-1].
    carrier_angle : numpy.ndarray
        ``theta_c`` [rad].
    impacts : numpy.ndarray
        Times of the fault impacts [s] (empty without a local fault).
    """

    time: np.ndarray
    acceleration: np.ndarray
    clean: np.ndarray
    tacho: np.ndarray
    speed_rpm: np.ndarray
    carrier_angle: np.ndarray
    impacts: np.ndarray


PULSES_PER_REV = 60


def _wrap(x: np.ndarray) -> np.ndarray:
    return np.mod(x + np.pi, 2 * np.pi) - np.pi


def _window(spec: RecordSpec, d: np.ndarray) -> np.ndarray:
    d = np.abs(_wrap(d))
    w = math.radians(spec.window_deg)
    if spec.window == "hann":
        core = np.where(d < w / 2, np.cos(np.pi * d / w) ** 2, 0.0)
    else:
        core = np.exp(-d / w)
    return spec.window_floor + (1.0 - spec.window_floor) * core


def _pulse(rho: np.ndarray, width: float) -> np.ndarray:
    r = _wrap(rho)
    return np.where(np.abs(r) < width / 2, np.cos(np.pi * r / width) ** 2, 0.0)


def speed_profile(spec: RecordSpec, t: np.ndarray, rng: np.random.Generator
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Sun speed [min-1] and angle [rad] at ``t``: ``n_0 (1 + u(t))``, ``max |u|`` the bound.

    ``u`` is a sum of three sinusoids (0.05-0.5 Hz, random amplitudes and phases), scaled so
    that its largest excursion over the record is ``fluctuation``; the angle is its exact
    integral.
    """
    f = rng.uniform(0.05, 0.5, 3)
    c = rng.uniform(0.5, 1.0, 3)
    ph = rng.uniform(0, 2 * np.pi, 3)
    u = np.sum(c[:, None] * np.sin(2 * np.pi * f[:, None] * t + ph[:, None]), axis=0)
    scale = spec.fluctuation / max(float(np.max(np.abs(u))), 1e-12)
    # integral of c sin(2 pi f t + ph) dt = c (cos(ph) - cos(2 pi f t + ph)) / (2 pi f)
    iu = np.sum((c / (2 * np.pi * f))[:, None]
                * (np.cos(ph)[:, None] - np.cos(2 * np.pi * f[:, None] * t + ph[:, None])),
                axis=0)
    w0 = spec.speed_rpm * 2 * np.pi / 60.0
    return spec.speed_rpm * (1.0 + scale * u), w0 * (t + scale * iu)


def _resonator(spec: RecordSpec) -> tuple[np.ndarray, np.ndarray]:
    """Impulse-invariant discretisation of ``h(t) = exp(-zeta w_n t) sin(w_d t)`` (peak ~1)."""
    wn = 2 * np.pi * spec.resonance_hz
    z = spec.resonance_damping
    wd = wn * math.sqrt(1 - z * z)
    r = math.exp(-z * wn / spec.fs)
    return (np.array([0.0, r * math.sin(wd / spec.fs)]),
            np.array([1.0, -2 * r * math.cos(wd / spec.fs), r * r]))


def _crossings(rho: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Times where the wrapped angle ``rho`` passes 0 upwards (linear interpolation)."""
    r = _wrap(rho)
    k = np.nonzero((r[:-1] < 0) & (r[1:] >= 0) & (r[1:] - r[:-1] < np.pi))[0]
    frac = -r[k] / (r[k + 1] - r[k])
    return t[k] + frac * (t[k + 1] - t[k])


def generate(spec: RecordSpec) -> Signals:
    """The accelerometer and tacho record of ``spec`` (formulas: module docstring)."""
    gs = spec.gear_set
    rng_box = np.random.default_rng([spec.seed, 1])  # the gearbox: phases, imperfections
    rng_speed = np.random.default_rng([spec.seed, 2])
    rng_fault = np.random.default_rng([spec.seed, 3])
    rng_noise = np.random.default_rng([spec.seed, 4])
    n = round(spec.duration * spec.fs)
    t = np.arange(n) / spec.fs
    rpm, th_s = speed_profile(spec, t, rng_speed)
    th_c = th_s * gs.carrier_per_sun
    psi = np.radians(np.asarray(gs.planet_angles_deg, float))
    th_t = math.radians(spec.sensor_deg)
    zs, zp, zr, npl = gs.z_sun, gs.z_planet, gs.z_ring, gs.n_planets
    sev = SEVERITIES[spec.severity]
    m = np.arange(1, spec.harmonics + 1)
    amp = spec.harmonic_decay ** (m - 1)  # A_1 = 1 m s-2
    alpha_r = rng_box.uniform(0, 2 * np.pi, m.size)
    alpha_s = rng_box.uniform(0, 2 * np.pi, m.size)
    gain = 1.0 + spec.imperfection * 0.03 * rng_box.standard_normal(npl)
    ripple_phase = rng_box.uniform(0, 2 * np.pi)
    delta = rng_fault.uniform(0, 2 * np.pi)  # where the damaged tooth / eccentricity is
    y = np.zeros(n)
    impulses = np.zeros(n + 2)
    impact_times = []

    def mesh(phase: np.ndarray, a: np.ndarray, b: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        out = np.zeros(n)
        for k in range(m.size):
            out += amp[k] * np.cos(m[k] * (phase + b) + alpha[k])
        return (1.0 + a) * out

    def add_impacts(rho: np.ndarray, weight: np.ndarray, size: float) -> None:
        tk = _crossings(rho, t)
        if tk.size == 0:
            return
        jitter = 1 + spec.impact_jitter * rng_fault.uniform(-1, 1, tk.size)
        wk = np.interp(tk, t, weight) * size * jitter * spec.impacts
        pos = tk * spec.fs
        i0 = np.floor(pos).astype(int)
        fr = pos - i0
        np.add.at(impulses, i0, wk * (1 - fr))
        np.add.at(impulses, i0 + 1, wk * fr)
        impact_times.extend(tk.tolist())

    width_s = CONTACT_PITCHES * 2 * np.pi / zs
    width_p = CONTACT_PITCHES * 2 * np.pi / zp
    width_r = CONTACT_PITCHES * 2 * np.pi / zr
    ripple = 1.0 + spec.imperfection * 0.02 * np.cos(th_c + ripple_phase)
    for i in range(npl):
        w_i = _window(spec, th_c + psi[i] - th_t)
        ring_phase = zr * (th_c + psi[i])
        sun_phase = zr * th_c - zs * psi[i]
        a_r = np.zeros(n)
        b_r = np.zeros(n)
        a_s = np.zeros(n)
        b_s = np.zeros(n)
        if spec.fault == "sun_tooth":
            rho = th_s + delta - th_c - psi[i]
            g = _pulse(rho, width_s)
            a_s, b_s = sev["am"] * g, sev["fm"] * g
            add_impacts(rho, w_i, sev["impulse"])
        elif spec.fault == "ring_tooth":
            rho = th_c + psi[i] - delta
            g = _pulse(rho, width_r)
            a_r, b_r = sev["am"] * g, sev["fm"] * g
            add_impacts(rho, w_i, sev["impulse"])
        elif spec.fault == "planet_tooth" and i == spec.planet:
            rho = (zr / zp) * th_c + delta
            g_r = _pulse(rho, width_p)
            g_s = _pulse(rho - np.pi, width_p)
            a_r, b_r = sev["am"] * g_r, sev["fm"] * g_r
            a_s, b_s = sev["am"] * g_s, sev["fm"] * g_s
            add_impacts(rho, w_i, sev["impulse"])
            add_impacts(rho - np.pi, w_i, 0.5 * sev["impulse"])  # sun side, farther from the ring
        elif spec.fault == "sun_eccentricity":
            rho = th_s + delta - th_c - psi[i]
            a_s = sev["ecc"] * np.cos(rho)
            b_s = sev["ecc"] * np.sin(rho)
            a_r, b_r = 0.5 * a_s, 0.5 * b_s
        v = mesh(ring_phase, a_r, b_r, alpha_r) + spec.sun_mesh_gain * mesh(
            sun_phase, a_s, b_s, alpha_s)
        y += gain[i] * ripple * w_i * v
    # shaft lines through the bearings (not windowed)
    y += spec.imperfection * 0.02 * (np.cos(th_s + 0.3) + 0.5 * np.cos(th_c + 1.1))
    if spec.fault == "sun_eccentricity":
        y += sev["ecc"] * 0.2 * np.cos(th_s + delta)
    if impact_times and spec.impacts:
        b, a = _resonator(spec)
        ring = sps.lfilter(b, a, impulses)[:n]
        peak = np.max(np.abs(sps.lfilter(b, a, np.r_[1.0, np.zeros(int(spec.fs / 100))])))
        y += ring / peak
    p_sig = float(np.mean(y ** 2))
    sigma = math.sqrt(p_sig / 10 ** (spec.snr_db / 10.0))
    noisy = y + sigma * rng_noise.standard_normal(n)
    tacho = np.where(np.mod(th_s * PULSES_PER_REV / (2 * np.pi), 1.0) < 0.5, 5.0, 0.0)
    return Signals(t, noisy, y, tacho, rpm, th_c, np.sort(np.asarray(impact_times)))


def to_dataset(spec: RecordSpec, sig: Signals | None = None) -> xr.Dataset:
    """The record in the common measurement layout (channels ``acc`` and ``tacho``)."""
    from analysis.readers.layout import ChannelData, build_dataset

    sig = generate(spec) if sig is None else sig
    what = "healthy" if spec.fault is None else f"{spec.fault} ({spec.severity})"
    chans = [ChannelData("acc", sig.acceleration, "m s-2", "housing acceleration",
                         {"comment": f"independent phenomenological record: {what}, SNR "
                                     f"{spec.snr_db:g} dB"}),
             ChannelData("tacho", sig.tacho, "V", "tacho, 60 pulses per sun revolution",
                         {"pulses_per_rev": PULSES_PER_REV, "member": "sun"})]
    return build_dataset(chans, spec.fs, source_format="generated",
                         attrs={"title": f"independent planetary record {spec.name}",
                                "gear_set": spec.gear_set.name,
                                "fault": spec.fault or "none", "severity": spec.severity})


def write_record(spec: RecordSpec, path: str | Path) -> Path:
    """Write the record as netCDF (:func:`analysis.readers.write_netcdf`)."""
    from analysis.readers import write_netcdf

    return write_netcdf(to_dataset(spec), path)


def truth(spec: RecordSpec) -> tuple[str, str]:
    """``(kind, member)`` the diagnosis should name: kind ``local`` (crack, pitting or broken
    tooth: the generator's tooth fault is none of them in particular) or ``eccentricity``;
    member ``sun``, ``planet`` (equally spaced planets are one member) or ``ring``;
    ``("none", "")`` for a healthy record."""
    return {None: ("none", ""), "sun_tooth": ("local", "sun"),
            "planet_tooth": ("local", "planet"), "ring_tooth": ("local", "ring"),
            "sun_eccentricity": ("eccentricity", "sun")}[spec.fault]


def benchmark_records(quick: bool = False, *, master: int = 30, healthy: int = 3,
                      first_seed: int = 100) -> list[RecordSpec]:
    """The independent set: per gear set every fault clear and weak, and 3 healthy records.

    Paper-case1 at 1500 min-1 and the 4-planet set at 1200 min-1 (one operating point each,
    so the candidate library of the diagnosis serves all records of a set); sensor position,
    window, housing resonance, SNR (clear 15-20 dB, weak 10-15 dB), speed profile and noise
    drawn per record from its seed. ``quick``: 3 records (a clear sun tooth fault, a clear
    ring fault of the 4-planet set, a healthy record). ``master`` seeds the draws, ``healthy``
    healthy records per set, record seeds from ``first_seed + 1`` on (the benchmark's set is
    the default; ``benchmarks/bench_impact_alarms.py`` draws others).
    """
    rng = np.random.default_rng(master)
    out = []
    seed = first_seed
    for gs, rpm in ((PAPER_CASE1, 1500.0), (FOUR_PLANET, 1200.0)):
        plan = [(f, s) for f in FAULTS for s in ("clear", "weak")] + [(None, "clear")] * healthy
        for fault, sev in plan:
            seed += 1
            window = ("hann", "exponential")[int(rng.integers(2))]
            out.append(RecordSpec(
                gs, fault, sev, speed_rpm=rpm, seed=seed,
                snr_db=float(rng.uniform(15, 20) if sev == "clear" else rng.uniform(10, 15)),
                sensor_deg=float(rng.uniform(0, 360)), window=window,
                window_deg=float(rng.uniform(90, 150) if window == "hann"
                                 else rng.uniform(30, 70)),
                resonance_hz=float(rng.uniform(2500, 4000)),
                resonance_damping=float(rng.uniform(0.03, 0.08)),
                planet=int(rng.integers(gs.n_planets))))
    if quick:
        pick = [("paper-case1", "sun_tooth", "clear"), ("four-planet-21-31-83", "ring_tooth",
                                                        "clear"), ("paper-case1", None, "clear")]
        out = [next(r for r in out if (r.gear_set.name, r.fault, r.severity) == p)
               for p in pick]
    return out


def with_changes(spec: RecordSpec, **kw) -> RecordSpec:
    """``spec`` with some fields replaced (a convenience for the tests)."""
    return replace(spec, **kw)
