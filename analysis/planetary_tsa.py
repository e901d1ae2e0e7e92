"""Planetary gear sets: time-synchronous averages of each planet and of the sun (McFadden 1991).

A transducer on the ring gear (ring fixed, carrier and sun turning) hears a planet's meshes
mainly while that planet passes it. With a carrier reference, McFadden's technique takes a
window of the signal around every pass of a given planet, places it on that planet's tooth
axis at the teeth then in mesh with the ring, and averages the passes: one average per planet
over its own revolution (relative to the carrier); windows placed by the sun teeth then in
mesh with the passing planet give the sun's average. Each carrier revolution brings a planet
past the sensor once, with its ring-mesh count advanced by ``z_ring`` teeth, i.e. by
``z_ring mod z_planet`` planet teeth: after ``z_planet / gcd(z_ring, z_planet)`` passes the
placement cycle closes and, with a window at least ``2 gcd(z_ring, z_planet)`` teeth wide,
every planet tooth has been seen.

Kinematics used (ring fixed; all angles in the carrier's direction of rotation, from the
carrier reference's zero): planet ``p`` sits at carrier angle ``psi_p``; it is at the sensor
(ground angle ``sensor_angle``) when ``theta_c + psi_p = sensor_angle (mod 2 pi)``. Its
ring-mesh count is ``n_p = z_ring (theta_c + psi_p) / 2 pi`` teeth (the mesh phase of planet
``p`` relative to planet 1 is ``z_ring (psi_p - psi_1) / 2 pi``, Parker & Lin 2004), and the
planet tooth in mesh with the ring is ``floor(n_p) mod z_planet``: the planet axis is
``2 pi n_p / z_planet`` (planet rotation relative to the carrier, teeth in the order they
enter the ring mesh; tooth ``k`` spans ``[k, k + 1)`` in the ``tooth`` coordinate; its origin
is the tooth in mesh at ``theta_c + psi_p = 0``, i.e. arbitrary as no planet tooth is
marked). The sun tooth in mesh with planet ``p`` follows ``s_p = z_ring theta_c / 2 pi -
z_sun psi_p / 2 pi`` teeth (the sun turns ``z_ring / z_sun`` times as fast as the carrier
relative to it): the sun axis is ``2 pi s_p / z_sun``, the sun's rotation relative to the
carrier, teeth in the order they enter the meshes; all planets contribute to the sun average,
each through its own window.

Window: a Hann window (default; or a Tukey window with half its width flat, ``alpha = 0.5``)
in carrier angle, centred on the pass, ``window_teeth`` ring tooth pitches wide (default
``k g`` with ``g = gcd(z_ring, z_planet)`` and ``k = max(2, floor(z_ring / (n_planets g)))``:
about the carrier angle between planets, and a width on which the Hann windows of a closed
placement cycle add up to a constant). The average at each angle is the window-weighted mean
``sum(w x) / sum(w)`` of the samples placed there, so a cycle that does not close in the
record still gives a valid average where teeth were seen (where the summed weight reaches 5 %
of its maximum; the others are NaN and ``coverage`` says how much of the gear was seen),
and the number of passes is stated per planet. The noise reduction of a weighted mean is
``1 / sqrt(n_eff)`` with ``n_eff = (sum w)^2 / sum w^2`` (reported as
``effective_averages``, median over the observed angles). McFadden (1991) used a rectangular
window of about one tooth period; McFadden (1994) showed that tapered windows
reduce the errors. A rectangular window is not offered here: the sub-sample placement of the
windows (below) assumes a tapered one.

Assumptions: the ring is fixed and the sensor on it; the planet angles and the sensor angle
are known in the carrier reference's frame; the transfer path from a planet's meshes to the
sensor is significant only while the planet is near the sensor (the window). Since all planets
turn at the same speed relative to the carrier, a neighbour's tooth signature is synchronous on
a planet's axis too (at a fixed tooth offset): it is attenuated by the window and by the
transfer path, not averaged out.

Implementation: the record is resampled onto the carrier angle with ``samples_per_tooth``
samples per ring tooth pitch (alias-free, block by block, :mod:`analysis.resample`); a
resampled sample then falls exactly on the planet and sun axes up to one fractional offset
per planet, so the window-weighted sums are accumulated into integer bins and the constant
fractional offsets are removed at the end by a circular fractional shift of the sums
(:func:`analysis.tsa.fractional_shift`). Working memory: a few resampling blocks plus the
sums (five per gear and channel).

References
----------
P. D. McFadden, "A technique for calculating the time domain averages of the vibration of the
individual planet gears and the sun gear in an epicyclic gearbox", J. Sound Vib. 144(1), 1991,
163-172. P. D. McFadden, "Window functions for the calculation of the time domain averages of
the vibration of the individual planet gears and sun gear in an epicyclic gearbox", J. Vib.
Acoust. 116(2), 1994, 179-187. P. D. Samuel, D. J. Pines, "A review of vibration-based
techniques for helicopter transmission diagnostics", J. Sound Vib. 282, 2005, 475-508.
R. G. Parker, J. Lin, "Mesh phasing relationships in planetary and epicyclic gears", J. Mech.
Des. 126(2), 2004, 365-370.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.cf import cf_dataset
from analysis.checks import require_choice, require_int, require_real
from analysis.cm_plots import planetary_figure
from analysis.inputs import channel_coords
from analysis.tsa import TSA, Synchronous, fractional_shift, synchronous

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = ["PlanetarySeparation", "planetary_tsa"]

_WINDOWS = ("hann", "tukey")
_OBSERVED = 0.05  # an angle is observed where the window weights reach this fraction of the max


@dataclass(frozen=True)
class PlanetarySeparation:
    """Averages of the individual planets and of the sun of a planetary set.

    Attributes
    ----------
    planets : tuple of TSA
        One average per planet, on the planet's axis (``z_planet * samples_per_tooth``
        samples per planet revolution relative to the carrier; ``teeth = z_planet``).
    sun : TSA
        The sun's average (``z_sun * samples_per_tooth`` samples per sun revolution relative
        to the carrier; ``teeth = z_sun``).
    z_sun, z_planet, z_ring : int
        Tooth numbers.
    planet_angles : numpy.ndarray
        Planet positions on the carrier [rad].
    sensor_angle : float
        Sensor position [rad] in the carrier reference's frame.
    window : str
        ``"hann"`` or ``"tukey"`` (``alpha = 0.5``).
    window_teeth : float
        Window width [ring tooth pitches].
    samples_per_tooth : int
        Samples per tooth pitch (on every axis).
    carrier_revolutions : int
        Carrier revolutions analysed.
    passes : numpy.ndarray
        Window centres (planet passes) in the analysed range, per planet.
    planet_cycle : int
        Passes after which a planet's tooth placement repeats,
        ``z_planet / gcd(z_ring, z_planet)``.
    sun_cycle : int
        Passes of one planet after which its sun-tooth placement repeats,
        ``z_sun / gcd(z_ring, z_sun)``.
    notes : tuple of str
        What was assumed or left out.
    """

    planets: tuple[TSA, ...]
    sun: TSA
    z_sun: int
    z_planet: int
    z_ring: int
    planet_angles: np.ndarray
    sensor_angle: float
    window: str
    window_teeth: float
    samples_per_tooth: int
    carrier_revolutions: int
    passes: np.ndarray
    planet_cycle: int
    sun_cycle: int
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def complete_cycles(self) -> np.ndarray:
        """Closed placement cycles per planet: ``passes // planet_cycle``."""
        return np.asarray(self.passes) // self.planet_cycle

    def planet(self, p: int) -> TSA:
        """Average of planet ``p`` (counted from 1, as in the labels)."""
        k = require_int(p, "p", 1)
        if k > len(self.planets):
            raise ValueError(f"p = {p} is not admissible: planets 1 .. {len(self.planets)}")
        return self.planets[k - 1]

    def to_dataset(self) -> xr.Dataset:
        """CF :class:`xarray.Dataset`: ``planet_tsa(planet, *channels, planet_angle)``,
        ``sun_tsa(*channels, sun_angle)``, passes, coverage and noise reduction per planet."""
        import xarray as xr

        first = self.planets[0]
        dims = first.dims
        pl = np.stack([p.values for p in self.planets])
        coords: dict[str, Any] = {
            "planet": ("planet", np.arange(1, len(self.planets) + 1),
                       {"units": "1", "long_name": "planet number"}),
            "planet_angle": ("planet_angle", first.angle,
                             {"units": "rad", "long_name": "planet rotation relative to the "
                              "carrier (teeth in the order they enter the ring mesh)"}),
            "planet_tooth": ("planet_angle", first.angle * self.z_planet / (2 * np.pi),
                             {"units": "1", "long_name": "planet tooth position"}),
            "sun_angle": ("sun_angle", self.sun.angle,
                          {"units": "rad", "long_name": "sun rotation relative to the carrier"}),
            "sun_tooth": ("sun_angle", self.sun.angle * self.z_sun / (2 * np.pi),
                          {"units": "1", "long_name": "sun tooth position"}),
        }  # fmt: skip
        coords.update(channel_coords(dims, first.coords))
        per = {"units": "1"}
        data = {
            "planet_tsa": (("planet", *dims, "planet_angle"), pl,
                           {"units": first.units, "long_name": "time-synchronous average of "
                            "each planet (McFadden 1991)"}),
            "sun_tsa": ((*dims, "sun_angle"), self.sun.values,
                        {"units": first.units, "long_name": "time-synchronous average of the "
                         "sun (windowed at the planet passes)"}),
            "passes": ("planet", np.asarray(self.passes, dtype=np.int64),
                       {**per, "long_name": "planet passes averaged"}),
            "coverage": ("planet", np.array([p.coverage for p in self.planets]),
                         {**per, "long_name": "fraction of the planet's teeth observed"}),
            "effective_averages": ("planet",
                                   np.array([p.effective_averages for p in self.planets]),
                                   {**per, "long_name": "effective number of averages "
                                    "(sum w)^2 / sum w^2, median over the planet angle"}),
        }  # fmt: skip
        attrs: dict[str, Any] = {
            "Conventions": "CF-1.11",
            "z_sun": self.z_sun, "z_planet": self.z_planet, "z_ring": self.z_ring,
            "planet_angles_rad": np.asarray(self.planet_angles, dtype=float),
            "sensor_angle_rad": float(self.sensor_angle),
            "window": self.window, "window_teeth": float(self.window_teeth),
            "samples_per_tooth": int(self.samples_per_tooth),
            "carrier_revolutions": int(self.carrier_revolutions),
            "planet_cycle": int(self.planet_cycle), "sun_cycle": int(self.sun_cycle),
            "sun_coverage": float(self.sun.coverage),
            "sun_effective_averages": float(self.sun.effective_averages),
            "method": "McFadden 1991 windowed averaging, window-weighted mean",
        }  # fmt: skip
        if first.reference:
            attrs["speed_reference"] = first.reference
        if self.notes:
            attrs["comment"] = "; ".join(self.notes)
        return cf_dataset(
            xr.Dataset(data, coords=coords, attrs=attrs),
            title="time-synchronous averages of the planets and the sun (McFadden 1991)",
            producer="analysis.planetary_tsa.planetary_tsa",
        )

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure of the planet and sun averages (see
        :func:`analysis.cm_plots.planetary_figure`)."""
        return planetary_figure(self, **kwargs)


def _window(u: np.ndarray, kind: str) -> np.ndarray:
    """Window of unit width at ``u`` (``|u| < 1/2`` inside)."""
    if kind == "hann":
        return np.cos(np.pi * u) ** 2
    alpha = 0.5
    a = np.abs(u)
    edge = (a - (1.0 - alpha) / 2.0) / alpha  # 0 .. 1/2 across the taper
    return np.where(a <= (1.0 - alpha) / 2.0, 1.0, np.cos(np.pi * edge) ** 2)


def _teeth(value: Any, name: str) -> int:
    return require_int(value, name, 3)


class _Sums:
    """Window-weighted sums on one gear axis: ``sum w x``, ``sum w x^2``, ``sum w``,
    ``sum w^2`` per integer bin."""

    def __init__(self, lead: tuple[int, ...], bins: int) -> None:
        self.bins = bins
        self.wx = np.zeros((*lead, bins))
        self.wxx = np.zeros_like(self.wx)
        self.w = np.zeros(bins)
        self.ww = np.zeros(bins)

    def add(self, b: np.ndarray, w: np.ndarray, x: np.ndarray) -> None:
        n = self.bins
        self.w += np.bincount(b, weights=w, minlength=n)
        self.ww += np.bincount(b, weights=w * w, minlength=n)
        flat = x.reshape(-1, x.shape[-1])
        wx = self.wx.reshape(-1, n)
        wxx = self.wxx.reshape(-1, n)
        for c in range(flat.shape[0]):
            wx[c] += np.bincount(b, weights=w * flat[c], minlength=n)
            wxx[c] += np.bincount(b, weights=w * flat[c] ** 2, minlength=n)

    def shifted(self, shift: float) -> tuple[np.ndarray, ...]:
        return tuple(fractional_shift(a, shift) for a in (self.wx, self.wxx, self.w, self.ww))


def _average(
    parts: list[tuple[np.ndarray, ...]],
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Weighted mean (NaN where unobserved), rms about it, coverage and effective averages."""
    wx = sum(p[0] for p in parts)
    wxx = sum(p[1] for p in parts)
    w = sum(p[2] for p in parts)
    ww = sum(p[3] for p in parts)
    assert isinstance(w, np.ndarray) and isinstance(ww, np.ndarray)
    assert isinstance(wx, np.ndarray) and isinstance(wxx, np.ndarray)
    top = float(np.max(w)) if w.size else 0.0
    seen = w >= _OBSERVED * top if top > 0 else np.zeros(w.shape, dtype=bool)
    mean = np.full(np.shape(wx), np.nan)
    var = np.full(np.shape(wx), np.nan)
    mean[..., seen] = wx[..., seen] / w[seen]
    var[..., seen] = np.maximum(wxx[..., seen] / w[seen] - mean[..., seen] ** 2, 0.0)
    rms = np.sqrt(np.nanmean(var, axis=-1)) if seen.any() else np.full(np.shape(wx)[:-1], np.nan)
    neff = float(np.median(w[seen] ** 2 / ww[seen])) if seen.any() else 0.0
    return mean, rms, float(seen.mean()), neff


def planetary_tsa(
    x: Any,
    fs: Any = None,
    *,
    z_sun: Any,
    z_planet: Any,
    z_ring: Any,
    n_planets: Any = None,
    planet_angles: Any = None,
    sensor_angle: Any = 0.0,
    tacho: Any = None,
    pulses_per_rev: Any = None,
    pulse_times: Any = None,
    rpm: Any = None,
    angle: Any = None,
    ratio: Any = 1.0,
    window: str = "hann",
    window_teeth: Any = None,
    samples_per_tooth: Any = None,
    revolutions: Any = None,
    max_order: Any = None,
    min_rpm: float | None = None,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    block_size: Any = None,
) -> PlanetarySeparation:
    """Separate the planets and the sun of a planetary set: one average each (McFadden 1991).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal of a transducer on the (fixed) ring gear, one or several channels.
    fs : float, optional
        Sample rate [Hz] (or give ``time``).
    z_sun, z_planet, z_ring : int
        Tooth numbers (>= 3, ``z_ring > z_sun``).
    n_planets : int, optional
        Number of planets (default ``len(planet_angles)``; one of them is required).
    planet_angles : array_like, optional
        Planet positions on the carrier [rad], in the carrier's direction of rotation, from
        the carrier reference's zero (default: equally spaced, ``2 pi p / n_planets``).
    sensor_angle : float, default 0
        Angular position of the sensor [rad] in the same frame (planet ``p`` passes it at
        carrier angle ``sensor_angle - psi_p``).
    tacho, pulses_per_rev, pulse_times, rpm, angle :
        The reference, as for :func:`analysis.tsa.tsa`: of the carrier, or of another shaft
        with ``ratio``.
    ratio : float, default 1
        Carrier speed over the reference speed (e.g. ``z_sun / (z_sun + z_ring)`` for a
        sun-shaft tacho).
    window : {"hann", "tukey"}, default "hann"
        Window around each pass (module docstring).
    window_teeth : float, optional
        Window width [ring tooth pitches] (default: module docstring).
    samples_per_tooth : int, optional
        Samples per tooth pitch (>= 4); default about ``fs`` at the top mesh frequency.
    revolutions : int, optional
        Carrier revolutions to analyse from the first whole one (default: all).
    max_order : float, optional
        Highest carrier order kept by the resampler (default ``z_ring samples_per_tooth /
        2.56``).
    min_rpm, time, axis, units, name, block_size :
        As for :func:`analysis.tsa.tsa`.

    Returns
    -------
    PlanetarySeparation
        Planet and sun averages with passes, coverage and noise reduction.

    Raises
    ------
    ValueError, TypeError
        Naming the parameter: tooth numbers, planet angles, window, too few carrier
        revolutions; and the reference errors of :func:`analysis.tsa.tsa`.
    """
    zs, zp, zr = _teeth(z_sun, "z_sun"), _teeth(z_planet, "z_planet"), _teeth(z_ring, "z_ring")
    if zr <= zs:
        raise ValueError(f"z_ring = {zr} must exceed z_sun = {zs} (internal ring gear)")
    psi = _planet_angles(n_planets, planet_angles)
    theta_s = require_real(sensor_angle, "sensor_angle")
    kind = require_choice(window, _WINDOWS, "window")
    g = math.gcd(zr, zp)
    if window_teeth is None:
        width = float(max(2, zr // (psi.size * g)) * g)
    else:
        width = require_real(window_teeth, "window_teeth")
        if not 0 < width <= zr:
            raise ValueError(
                f"window_teeth = {window_teeth!r} is not admissible: must be in (0, z_ring = "
                f"{zr}] ring tooth pitches"
            )
    spt = None
    if samples_per_tooth is not None:
        spt = require_int(samples_per_tooth, "samples_per_tooth", 4)
    syn = synchronous(
        x, fs, time=time, axis=axis, units=units, name=name, tacho=tacho,
        pulses_per_rev=pulses_per_rev, pulse_times=pulse_times, rpm=rpm, angle=angle,
        ratio=ratio, samples_per_rev=None if spt is None else zr * spt, max_order=max_order,
        min_rpm=min_rpm, block_size=block_size, function="planetary_tsa", multiple=zr,
    )  # fmt: skip
    spt = syn.samples_per_rev // zr
    spr = syn.samples_per_rev
    available = syn.usable // spr
    if available < 1:
        raise ValueError(
            "too few carrier revolutions: the record holds less than one whole carrier "
            f"revolution at {spr} samples/rev after the resampler's edge guards"
        )
    if revolutions is None:
        n_rev = available
    else:
        n_rev = require_int(revolutions, "revolutions", 1)
        if n_rev > available:
            raise ValueError(
                f"revolutions = {n_rev} is not admissible: the record holds {available} whole "
                "carrier revolutions"
            )
    return _separate(syn, zs, zp, zr, psi, theta_s, kind, width, spt, n_rev)


def _planet_angles(n_planets: Any, planet_angles: Any) -> np.ndarray:
    if planet_angles is None:
        if n_planets is None:
            raise ValueError("give n_planets= (equally spaced planets) or planet_angles= (rad)")
        n = require_int(n_planets, "n_planets", 1)
        return 2.0 * np.pi * np.arange(n) / n
    arr = np.asarray(planet_angles)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"planet_angles must be real numbers (rad); got dtype {arr.dtype}")
    if arr.ndim != 1 or arr.size < 1:
        raise ValueError(f"planet_angles must be a 1-D sequence of angles; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("planet_angles: NaN or inf is not admissible")
    if n_planets is not None and require_int(n_planets, "n_planets", 1) != arr.size:
        raise ValueError(
            f"n_planets = {n_planets} but {arr.size} planet_angles were given; they must agree"
        )
    return arr.astype(float)


def _separate(
    syn: Synchronous, zs: int, zp: int, zr: int, psi: np.ndarray, theta_s: float, kind: str,
    width: float, spt: int, n_rev: int,
) -> PlanetarySeparation:  # fmt: skip
    spr = syn.samples_per_rev  # zr * spt: one resampled sample per 1/spt tooth pitch
    lead = syn.signal.lead
    j_start, j_stop = syn.guard, syn.guard + n_rev * spr
    u0 = syn.first_angle(0) * spr / (2.0 * np.pi)  # carrier angle of sample 0 [samples]
    two_pi = 2.0 * np.pi
    half = 0.5 * width * spt  # window half width [samples]
    planet_sums = [_Sums(lead, zp * spt) for _ in psi]
    sun_sums = [_Sums(lead, zs * spt) for _ in psi]
    # constant offsets [samples] of each planet: ring-mesh count, sun-mesh count, window centre
    ring_off = [u0 + zr * spt * p / two_pi for p in psi]
    sun_off = [u0 - zs * spt * p / two_pi for p in psi]
    win_off = [u0 + spr * (p - theta_s) / two_pi for p in psi]
    r_int = [math.floor(c) for c in ring_off]
    s_int = [math.floor(c) for c in sun_off]
    w_int = [math.floor(c) for c in win_off]
    passes = np.zeros(psi.size, dtype=np.int64)
    res = syn.resampler
    step = max(spr, (syn.block // spr) * spr)
    for j0 in range(j_start, j_stop, step):
        j1 = min(j_stop, j0 + step)
        vals, _ = res.block(j0, j1)
        j = np.arange(j0, j1, dtype=np.int64)
        for i in range(psi.size):
            # relative carrier angle of planet i to the sensor, in samples, wrapped to +- spr/2
            rel_int = np.mod(j + w_int[i] + spr // 2, spr) - spr // 2
            rho = rel_int + (win_off[i] - w_int[i])
            rho = np.where(rho >= spr / 2.0, rho - spr, rho)
            inside = np.flatnonzero(np.abs(rho) < half)
            passes[i] += int(np.count_nonzero(rel_int == 0))
            if inside.size == 0:
                continue
            w = _window(rho[inside] / (width * spt), kind)
            xs = vals[..., inside]
            ji = j[inside]
            planet_sums[i].add(np.mod(ji + r_int[i], zp * spt), w, xs)
            sun_sums[i].add(np.mod(ji + s_int[i], zs * spt), w, xs)
    planets = []
    sig = syn.signal
    mo = float(res.max_order)
    notes = list(syn.shaft.notes)
    common: dict[str, Any] = dict(  # the fields every TSA of the separation shares
        samples_per_rev=0, max_order=0.0, start_time=float(res.block(j_start, j_start + 1)[1][0]),
        stop_time=float(res.block(j_stop - 1, j_stop)[1][0]), units=sig.units, name=sig.name,
        dims=sig.dims, coords=sig.coords, reference=syn.shaft.label,
    )  # fmt: skip
    win_note = (
        f"{kind} window {width:g} ring tooth pitches wide around each planet pass "
        f"(ring fixed, sensor at {theta_s:.6g} rad)"
    )
    cycle_p = zp // math.gcd(zr, zp)
    cycle_s = zs // math.gcd(zr, zs)
    for i in range(psi.size):
        parts = [planet_sums[i].shifted(ring_off[i] - r_int[i])]
        mean, rms, cov, neff = _average(parts)
        closed = passes[i] >= cycle_p
        pnote = (
            f"{passes[i]} passes averaged; placement cycle {cycle_p} passes "
            + ("closed" if closed else f"not closed ({passes[i]} < {cycle_p})")
        )
        planets.append(TSA(
            angle=two_pi * np.arange(zp * spt) / (zp * spt), values=mean,
            revolutions=int(passes[i]), effective_averages=neff, nonsynchronous_rms=rms,
            shaft=f"planet {i + 1}", ratio=syn.shaft.ratio * zr / zp, coverage=cov, teeth=zp,
            notes=(*notes, win_note, pnote),
            **{**common, "samples_per_rev": zp * spt, "max_order": mo * zp / zr},
        ))  # fmt: skip
    parts = [sun_sums[i].shifted(sun_off[i] - s_int[i]) for i in range(psi.size)]
    mean, rms, cov, neff = _average(parts)
    sun = TSA(
        angle=two_pi * np.arange(zs * spt) / (zs * spt), values=mean,
        revolutions=int(passes.sum()), effective_averages=neff, nonsynchronous_rms=rms,
        shaft="sun", ratio=syn.shaft.ratio * zr / zs, coverage=cov, teeth=zs,
        notes=(*notes, win_note, f"{int(passes.sum())} planet passes averaged; sun placement "
               f"cycle {cycle_s} passes per planet"),
        **{**common, "samples_per_rev": zs * spt, "max_order": mo * zs / zr},
    )  # fmt: skip
    return PlanetarySeparation(
        planets=tuple(planets), sun=sun, z_sun=zs, z_planet=zp, z_ring=zr, planet_angles=psi,
        sensor_angle=theta_s, window=kind, window_teeth=width, samples_per_tooth=spt,
        carrier_revolutions=n_rev, passes=passes, planet_cycle=cycle_p, sun_cycle=cycle_s,
        notes=(*notes, win_note),
    )  # fmt: skip
