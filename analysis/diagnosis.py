"""Fault-cause evidence: what a measurement shows that a healthy baseline does not explain.

The engine of ``gearvib diagnose`` (the simulation in the loop lives in
:mod:`gearvib.diagnosis`; this module knows nothing of the simulator).

Method (``docs/diagnosis.md``)
------------------------------
1. **Order profile.** A signal is order-tracked on the reference shaft (carrier orders for a
   planetary set) and its amplitude spectrum averaged over segments of ``revolutions``
   reference revolutions (Hann window, 50 % overlap): :func:`order_profile`. Resolution
   ``1 / revolutions`` orders, the same for every record however long it is.
2. **Prominence.** An unknown transfer path (housing modes, sensor position, gain) multiplies
   the spectrum by a function that varies slowly with frequency; the *prominence* of a line,
   its level above the local floor (running median over ``±width`` orders, at most
   ``dynamic_range`` dB below the local maximum), is blind to it: :func:`prominence_db`.
3. **Noise floor.** A simulation is noise-free; before its prominence is taken it gets the
   measurement's dynamic range (:func:`dynamic_range_db`, :func:`with_noise_floor`), so that
   only lines the measurement could show above its noise count.
4. **Difference.** ``D = P(measured) − P(baseline)`` [dB] per order bin: where the measurement
   has lines the healthy baseline lacks, or stronger ones. A candidate cause's *signature*
   is the same difference between a simulation with the fault and one without.
5. **Score.** The cosine similarity of the positive parts of ``D`` (above a deadband of three
   robust standard deviations of ``D``, which removes the noise) and of the signature:
   :func:`signature_score`, in [0, 1], 1 when the measured rises are exactly the simulated
   ones up to a common factor in dB. Level scaling (calibration, severity) changes it
   little; which orders rise decides it.

Further evidence: catalogue families whose lines the rising peaks hit, with the chance of as
many hits by coincidence (:func:`family_evidence`), order-locked vs frequency-locked
behaviour (:func:`order_locking`) and lines near natural frequencies (:func:`near_modes`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr
from scipy import ndimage, signal, stats

from analysis.catalogue import phasing_factor
from analysis.cf import cf_dataset
from analysis.checks import (
    require_instance,
    require_positive,
    require_real,
    require_real_array,
)
from analysis.resample import resample_to_angle

__all__ = [
    "DEFAULT_THRESHOLD",
    "SHAFT_HARMONICS",
    "Cause",
    "Diagnosis",
    "FamilyEvidence",
    "OrderProfile",
    "deadband_db",
    "dynamic_range_db",
    "family_evidence",
    "family_lines",
    "impulse_mismatch_db",
    "near_modes",
    "order_locking",
    "order_profile",
    "phasing_shifts",
    "prominence_db",
    "rising_peaks",
    "shaft_line_mask",
    "sideband_ratios",
    "signature_score",
    "with_noise_floor",
]

DEFAULT_THRESHOLD = 0.4
"""Score above which a cause is reported as likely (see ``docs/diagnosis.md``)."""

DEFAULT_REVOLUTIONS = 16
"""Reference revolutions per averaged segment (resolution 1/16 order)."""


@dataclass(frozen=True)
class OrderProfile:
    """Averaged amplitude spectrum of a signal over orders of a reference shaft.

    Attributes
    ----------
    order : numpy.ndarray
        Orders of the reference shaft (bins ``k / revolutions``).
    amplitude : numpy.ndarray
        RMS amplitude per bin, averaged over the segments (power average) [units].
    units : str
        Units of the signal.
    revolutions : int
        Reference revolutions per segment.
    segments : int
        Number of averaged segments.
    speed_rpm : tuple of float
        Minimum, mean and maximum speed of the reference shaft over the record [min-1].
    name : str
        What the profile is of (e.g. ``"measured"``).
    """

    order: np.ndarray
    amplitude: np.ndarray
    units: str
    revolutions: int
    segments: int
    speed_rpm: tuple[float, float, float]
    name: str = "signal"

    @property
    def level_db(self) -> np.ndarray:
        """Level [dB re 1 unit RMS], floored at 1e-300."""
        return 20.0 * np.log10(np.maximum(self.amplitude, 1e-300))

    def to_dataarray(self) -> xr.DataArray:
        """The amplitude as a DataArray along ``order``."""
        return xr.DataArray(
            self.amplitude, dims=("order",),
            coords={"order": ("order", self.order, {"units": "1",
                                                    "long_name": "order of the reference shaft"})},
            name=self.name,
            attrs={"units": self.units, "long_name": f"RMS order spectrum ({self.name})",
                   "revolutions_per_segment": int(self.revolutions),
                   "segments": int(self.segments),
                   "speed_rpm_min_mean_max": list(self.speed_rpm)})


def _check_positive(value: float, name: str, low: float = 0.0) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= low:
        raise ValueError(f"{name} = {value!r} is not admissible (admissible: finite, > {low:g})")
    return v


def order_profile(x: Any, fs: float, rpm: Any, *, max_order: float,
                  revolutions: int = DEFAULT_REVOLUTIONS, name: str = "signal",
                  units: str = "1", skip_s: float = 0.0) -> OrderProfile:
    """Order-track ``x`` and average its amplitude spectrum over segments.

    Parameters
    ----------
    x : array_like
        Signal samples (1-D, uniform at ``fs``).
    fs : float
        Sample rate [Hz].
    rpm : array_like
        Speed of the reference shaft at every sample [min-1] (> 0).
    max_order : float
        Highest order analysed (limited by ``fs`` at the top speed).
    revolutions : int, optional
        Reference revolutions per segment (resolution ``1/revolutions`` orders).
    name, units : str, optional
        Metadata.
    skip_s : float, optional
        Seconds left out at the start (a simulation's start-up transient).

    Raises
    ------
    ValueError
        Fewer than ``revolutions`` reference revolutions in the record; a bad speed.
    """
    fs = _check_positive(fs, "fs")
    max_order = _check_positive(max_order, "max_order")
    revolutions = int(revolutions)
    if revolutions < 2:
        raise ValueError(f"revolutions = {revolutions} is not admissible (admissible: >= 2)")
    x = np.asarray(x, dtype=float)
    rpm = np.asarray(rpm, dtype=float)
    if x.ndim != 1 or rpm.shape != x.shape:
        raise ValueError(f"signal and speed need one value per sample (signal {x.shape}, speed "
                         f"{rpm.shape})")
    a = round(skip_s * fs)
    x, rpm = x[a:], rpm[a:]
    if x.size < 16:
        raise ValueError(f"{name}: {x.size} samples are too few for an order spectrum")
    if not np.all(np.isfinite(rpm)) or np.min(rpm) <= 0:
        raise ValueError(f"{name}: the reference speed must be finite and > 0 throughout "
                         f"(minimum {np.nanmin(rpm):g} min-1)")
    rpm_max = float(np.max(rpm))
    mo_fs = fs / 2.56 / (rpm_max / 60.0)  # highest order below 0.39 fs at the top speed
    mo = min(max_order, mo_fs)
    spr = int(2 ** math.ceil(math.log2(2.56 * mo)))
    ang = resample_to_angle(x, fs, rpm=rpm, samples_per_rev=spr, max_order=mo, min_rpm=0.0)
    y = ang.values
    nseg = revolutions * spr
    total = y.size / spr
    if y.size < nseg:
        raise ValueError(f"{name}: the record covers {total:.1f} revolutions of the reference "
                         f"shaft; the diagnosis needs at least {revolutions} (a longer record "
                         "or a higher speed)")
    f, p = signal.welch(y, fs=spr, window="hann", nperseg=nseg, noverlap=nseg // 2,
                        detrend=False, scaling="spectrum", average="mean")
    nseg_used = 1 + (y.size - nseg) // (nseg - nseg // 2)
    keep = f <= mo
    return OrderProfile(f[keep], np.sqrt(p[keep]), units, revolutions, nseg_used,
                        (float(np.min(rpm)), float(np.mean(rpm)), rpm_max), name)


def prominence_db(profile: OrderProfile, *, width: float = 6.0,
                  dynamic_range: float = 40.0) -> np.ndarray:
    """Level of every bin above its local floor [dB], in ``[0, dynamic_range]``.

    The floor is the running median of the level over ``±width`` orders, raised to at most
    ``dynamic_range`` dB below the running maximum (so a noise-free simulation has the same
    dynamic range as a measurement). A slowly varying transfer function cancels.
    """
    _profile(profile)
    dr = require_real(dynamic_range, "dynamic_range")
    if dr < 0:
        raise ValueError(f"dynamic_range = {dynamic_range!r} is not admissible: dB >= 0")
    lv = profile.level_db
    n = _window(width, profile.revolutions, profile.order.size)
    med = ndimage.median_filter(lv, size=n, mode="nearest")
    top = ndimage.maximum_filter1d(lv, size=n, mode="nearest")
    floor = np.maximum(med, top - dynamic_range)
    return np.clip(lv - floor, 0.0, dynamic_range)


def _window(width: float, revolutions: int, size: int) -> int:
    """Odd filter length [bins] of ``±width`` orders; a width beyond the profile is refused
    (a filter longer than the profile costs time and says nothing)."""
    w = require_real(width, "width")
    if not 0.0 < w * revolutions <= 2 * size + 2:
        raise ValueError(f"width = {width!r} is not admissible: orders in (0, "
                         f"{(2 * size + 2) / revolutions:g}] (about the profile's span)")
    return max(3, round(2 * w * revolutions) | 1)


def _profile(profile: Any, name: str = "profile") -> None:
    require_instance(profile, OrderProfile, name)


def dynamic_range_db(profile: OrderProfile, *, width: float = 6.0,
                     percentile: float = 20.0) -> np.ndarray:
    """Per bin: the running maximum of the level minus the noise floor [dB] (>= 0).

    The noise floor is the running ``percentile`` of the level over ``±width`` orders: the
    level between the lines (noise of the measuring chain, unmodelled vibration). The result
    says how far below the strongest local line a measurement can see anything.
    """
    _profile(profile)
    q = require_real(percentile, "percentile")
    if not 0.0 < q < 50.0:
        raise ValueError(f"percentile = {percentile!r} is not admissible (admissible: 0 < "
                         "percentile < 50)")
    lv = profile.level_db
    n = _window(width, profile.revolutions, profile.order.size)
    top = ndimage.maximum_filter1d(lv, size=n, mode="nearest")
    floor = ndimage.percentile_filter(lv, q, size=n, mode="nearest")
    return np.maximum(top - floor, 0.0)


def with_noise_floor(profile: OrderProfile, dynamic_range: Any, *,
                     width: float = 6.0) -> OrderProfile:
    """The profile with a noise floor ``dynamic_range`` dB below its running maximum added.

    Powers add: ``A_eff^2 = A^2 + (max_local(A) 10^(-DR/20))^2`` per bin, with the running
    maximum over ``±width`` orders. Given the measurement's :func:`dynamic_range_db`, a
    noise-free simulation shows only what the measurement could show: lines that would lie
    under the measured noise floor do not count as rises (``docs/diagnosis.md``).
    """
    _profile(profile)
    dr = require_real_array(dynamic_range, "dynamic_range", min_size=1, max_abs=1e4)
    try:
        dr = np.broadcast_to(dr, profile.amplitude.shape)
    except ValueError:
        raise ValueError(f"dynamic_range must be one value or one per bin "
                         f"({profile.amplitude.size}); got shape {dr.shape}") from None
    if np.any(dr < 0):
        raise ValueError("dynamic_range must be finite and >= 0 dB in every bin")
    lv = profile.level_db
    top = ndimage.maximum_filter1d(
        lv, size=_window(width, profile.revolutions, profile.order.size), mode="nearest")
    with np.errstate(under="ignore"):
        floor_amp = 10.0 ** ((top - dr) / 20.0)
        amp = np.sqrt(profile.amplitude ** 2 + floor_amp ** 2)
    return OrderProfile(profile.order, amp, profile.units, profile.revolutions,
                        profile.segments, profile.speed_rpm, profile.name)


def deadband_db(diff: np.ndarray, *, k: float = 3.0, minimum: float = 1.0) -> float:
    """``k`` robust standard deviations (1.4826 MAD) of a difference [dB], at least ``minimum``."""
    d = np.asarray(diff, dtype=float)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return minimum
    mad = float(np.median(np.abs(d - np.median(d))))
    return max(minimum, k * 1.4826 * mad)


SHAFT_HARMONICS = 2
"""Harmonics of every turning shaft (1x, 2x) that :func:`shaft_line_mask` leaves out of the
scores."""


def shaft_line_mask(order: Any, shaft_orders: Any, *, harmonics: int = SHAFT_HARMONICS,
                    width: float | None = None) -> np.ndarray:
    """The order bins of the shaft rotation lines: ``h n`` for every shaft order ``n``,
    ``h = 1 .. harmonics``, within ``±width``.

    A line at once or twice a shaft's speed in the fixed frame is what unbalance,
    misalignment or a bent shaft give on any machine: it is no evidence of a gear fault and
    any simulated fault that disturbs the shaft raises it too. A gear's eccentricity or a pin
    error shows as sidebands of the mesh harmonics at the rotation (the lines the fault
    alone explains; Randall 1982, McFadden & Smith 1985), which stay in the score.

    Parameters
    ----------
    order : array_like
        Order bins (uniform, increasing).
    shaft_orders : array_like
        Speeds of the turning shafts in the fixed frame, in orders of the reference shaft
        (absolute values are taken; zeros, a member at rest, are skipped).
    harmonics : int
        Harmonics of each shaft (>= 1).
    width : float, optional
        Half-width [orders]; default 2 bins (the main lobe of the Hann window of
        :func:`order_profile`).

    Returns
    -------
    numpy.ndarray of bool
        True on the bins of a shaft line.

    References
    ----------
    Randall, R. B. (1982). A new method of modeling gear faults. J. Mech. Design 104,
    259-267. McFadden, P. D., Smith, J. D. (1985). An explanation for the asymmetry of the
    modulation sidebands about the tooth meshing frequency in epicyclic gear vibration.
    Proc. IMechE C 199, 65-70.
    """
    o = require_real_array(order, "order", ndim=1, min_size=0, max_abs=1e12)
    sh = np.abs(require_real_array(shaft_orders, "shaft_orders", min_size=0,
                                   max_abs=1e12).ravel())
    if sh.size > 10_000:
        raise ValueError(f"shaft_orders has {sh.size} values; admissible: at most 10000 shafts")
    if isinstance(harmonics, bool) or not isinstance(harmonics, int | np.integer) \
            or not 1 <= harmonics <= 100:
        raise ValueError(f"harmonics = {harmonics!r} is not admissible (admissible: an integer "
                         "1 .. 100)")
    step = float(o[1] - o[0]) if o.size > 1 else 1.0
    w = 2.0 * abs(step) if width is None else require_positive(require_real(width, "width"),
                                                               "width")
    lines = (np.arange(1, int(harmonics) + 1)[:, None] * sh[sh > 0][None, :]).ravel()
    tol = w + 1e-9 * abs(step)
    srt = np.argsort(o, kind="stable")
    os_ = o[srt]
    lo = np.searchsorted(os_, lines - tol, side="left")
    hi = np.searchsorted(os_, lines + tol, side="right")
    count = np.zeros(o.size + 1, dtype=np.int64)
    np.add.at(count, lo, 1)
    np.add.at(count, hi, -1)
    out = np.zeros(o.size, dtype=bool)
    out[srt] = np.cumsum(count)[:-1] > 0
    return out


def signature_score(measured_diff: np.ndarray, signature: np.ndarray, *,
                    deadband: float, signature_deadband: float = 3.0,
                    exclude: Any = None) -> float:
    """Cosine similarity of the measured rises and a candidate's simulated rises, in [0, 1].

    Both are differences of prominence [dB] on the same order bins; only rises above the
    deadbands count. 0 when either has no rise. Bins where ``exclude`` (bool, one per bin;
    e.g. :func:`shaft_line_mask`) is True are left out of both.
    """
    md = require_real_array(measured_diff, "measured_diff", ndim=1, min_size=0, finite=False)
    sg = require_real_array(signature, "signature", ndim=1, min_size=0, finite=False)
    if md.size != sg.size:
        raise ValueError(f"measured_diff and signature have {md.size} and {sg.size} bins; they "
                         "must be on the same order axis")
    a = np.clip(md - require_real(deadband, "deadband"), 0.0, None)
    b = np.clip(sg - require_real(signature_deadband, "signature_deadband"), 0.0, None)
    if exclude is not None:
        ex = np.asarray(exclude)
        if ex.dtype != bool or ex.shape != md.shape:
            raise ValueError(f"exclude must be a bool array of one value per bin ({md.size}); "
                             f"got dtype {ex.dtype}, shape {ex.shape}")
        a = np.where(ex, 0.0, a)
        b = np.where(ex, 0.0, b)
    # cosine similarity is scale-free: both scaled by a power of two (exact, so the same bits)
    # to keep the dot product and the norms finite for any finite input
    with np.errstate(under="ignore", invalid="ignore"):
        a = np.ldexp(a, -np.frexp(max(float(np.max(a, initial=0.0)), 1e-300))[1])
        b = np.ldexp(b, -np.frexp(max(float(np.max(b, initial=0.0)), 1e-300))[1])
        na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
        if na == 0.0 or nb == 0.0:
            return 0.0
        return float(min(1.0, max(0.0, np.dot(a, b) / (na * nb))))


def sideband_ratios(profile: OrderProfile, fundamental: float, mesh_order: float, *,
                    sidebands: int = 10, mesh_harmonics: int = 5,
                    floor_percentile: float = 20.0, width: float = 6.0,
                    with_noise: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Sidebands of a local fault relative to their mesh harmonic, and the noise there.

    A local tooth fault modulates the mesh once per fault period: sidebands
    ``m f_mesh + k f`` (``k = ±1 … ±K``) of every mesh harmonic ``m``. Their amplitude over
    ``k`` is the spectrum of the fault's impulse (its width and shape), and their level
    against the mesh harmonic itself is its depth against the healthy mesh excitation. Both
    travel the same transfer path within a few orders, so the ratio
    ``A(m f_mesh + k f) / A(m f_mesh)`` is blind to the path's gain.

    Parameters
    ----------
    profile : OrderProfile
        Order profile (orders of the reference shaft).
    fundamental : float
        Fault order of the member ``f`` (its tooth meets a mesh once per ``1/f``).
    mesh_order : float
        Mesh order ``f_mesh``.
    sidebands : int
        Largest ``K``; limited to ``f_mesh / (2 f)`` so that the sidebands of neighbouring
        mesh harmonics do not overlap.
    mesh_harmonics : int
        Mesh harmonics used (fewer if the band ends before).
    floor_percentile, width : float
        Noise floor: the running percentile over ``±width`` orders (:func:`dynamic_range_db`).
    with_noise : bool
        Compute the noise floor (False: ``noise`` is empty, the ratios are the same; a noise-free
        simulation needs none, and the running percentile is the costly part).

    Returns
    -------
    ratio, noise : numpy.ndarray
        Per sideband (harmonic-major, ``k = -K … -1, 1 … K``): the amplitude ratio (the
        largest bin within one bin of the line) and the noise floor there over the same mesh
        amplitude. Empty when no mesh harmonic with its sidebands fits into the band.
    """
    _profile(profile)
    f = _check_positive(fundamental, "fundamental")
    fm = _check_positive(mesh_order, "mesh_order")
    order = np.asarray(profile.order, float)
    amp = np.asarray(profile.amplitude, float)
    if order.size < 3:
        return np.empty(0), np.empty(0)
    step = float(order[1] - order[0])
    k_max = min(int(sidebands), int(fm / (2.0 * f)))
    if k_max < 1:
        return np.empty(0), np.empty(0)
    ks = np.concatenate((np.arange(-k_max, 0), np.arange(1, k_max + 1)))
    size = _window(width, profile.revolutions, profile.order.size)
    floor = (ndimage.percentile_filter(amp, float(floor_percentile), size=size, mode="nearest")
             if with_noise else None)

    def index(o: np.ndarray) -> np.ndarray:
        return np.rint((o - order[0]) / step).astype(np.int64)

    def at(o: np.ndarray) -> np.ndarray:  # the largest bin within one bin of each line
        i = index(o)
        return np.maximum(np.maximum(amp[np.maximum(i - 1, 0)], amp[i]),
                          amp[np.minimum(i + 1, amp.size - 1)])

    harm = []
    for m in range(1, int(mesh_harmonics) + 1):
        if m * fm + k_max * f > order[-1] - step:
            break
        harm.append(m)
    centres = np.asarray(harm, dtype=np.int64) * fm
    ref = at(centres)
    centres, ref = centres[ref > 0], ref[ref > 0]
    lines = centres[:, None] + ks[None, :] * f  # harmonic-major
    ratios = (at(lines) / ref[:, None]).ravel()
    noise = (floor[index(lines)] / ref[:, None]).ravel() if floor is not None else np.empty(0)
    return ratios, noise


def impulse_mismatch_db(measured: np.ndarray, noise: np.ndarray,
                        simulated: Sequence[np.ndarray]) -> float:
    """How unlike a simulated fault impulse is to the measured one [dB] (0: alike).

    ``measured`` and ``noise`` are :func:`sideband_ratios` of the measurement, ``simulated``
    those of one simulated fault through each assumed transfer path. The simulated ratios get
    the measured noise (powers add); the mismatch is the mean absolute dB difference after
    removing the median difference (an unknown fault size shifts all sidebands alike), averaged
    over the paths. It compares the shape of the sideband pattern: the width and form of the
    fault's impulse. ``nan`` when there are no sidebands.
    """
    m = np.asarray(measured, float)
    n = np.asarray(noise, float)
    if m.size == 0:
        return float("nan")
    tiny = 1e-30
    out = []
    for sim in simulated:
        s = np.asarray(sim, float)
        if s.shape != m.shape:
            raise ValueError(f"simulated sidebands {s.shape} do not match the measured "
                             f"{m.shape}")
        d = 20.0 * np.log10(np.maximum(m, tiny)) - 10.0 * np.log10(
            np.maximum(s ** 2 + n ** 2, tiny))
        out.append(float(np.mean(np.abs(d - np.median(d)))))
    return float(np.mean(out))


def rising_peaks(order: np.ndarray, diff: np.ndarray, deadband: float) -> np.ndarray:
    """Orders of the local maxima of ``diff`` above ``deadband`` (the measured rises)."""
    o = require_real_array(order, "order", ndim=1, min_size=0)
    d = require_real_array(diff, "diff", ndim=1, min_size=0, finite=False)
    if o.size != d.size:
        raise ValueError(f"order and diff have {o.size} and {d.size} bins; give one diff per "
                         "order bin")
    idx, _ = signal.find_peaks(np.concatenate(([-np.inf], d, [-np.inf])),
                               height=require_real(deadband, "deadband"))
    return o[idx - 1]


def family_lines(fundamental: float, *, mesh_order: float, mesh_harmonics: int,
                 harmonics: int, sidebands: int, max_order: float,
                 shifts: Sequence[Sequence[float]] | None = None) -> np.ndarray:
    """Lines of a fault family: harmonics ``k f`` and sidebands ``m f_mesh ± k f (+ s)``.

    All in orders of the reference shaft, ``0 < order <= max_order``, unique (to 1e-9).
    ``shifts[m - 1]``: the order shifts ``s`` of the sidebands of mesh harmonic ``m`` (the
    planet phasing's, :func:`phasing_shifts`); default ``(0,)`` for every harmonic.
    """
    k = np.arange(1, harmonics + 1) * fundamental
    lines = [k]
    ks = np.arange(1, sidebands + 1) * fundamental
    for m in range(1, mesh_harmonics + 1):
        c = m * mesh_order
        for sh in (shifts[m - 1] if shifts is not None and m <= len(shifts) else (0.0,)):
            lines += [c - ks + sh, c + ks + sh]
    o = np.concatenate(lines)
    o = o[(o > 0) & (o <= max_order)]
    return np.unique(np.round(o, 9))


def phasing_shifts(z_gear: int, planet_angles_rad: Sequence[float], *, pass_order: float,
                   mesh_harmonics: int) -> list[tuple[float, ...]]:
    """Where the planet phasing puts the sidebands of a local fault on a central gear.

    A tooth fault on a central gear (sun or ring) with ``N`` planets meets planet ``n`` at
    the angle ``psi_n``: the fault's modulation of the mesh reaches a sensor on the housing,
    as every planet-phased line does, at ``|m h + q Omega|`` with ``h`` the signed mesh rate
    ``z_gear (n_gear - n_carrier)``, ``Omega = n_carrier - n_sensor`` and the circular index
    ``q`` only where ``|sum_n exp(i (q - m z_gear) psi_n)| > 0``
    (:func:`analysis.catalogue.phasing_factor`; McFadden & Smith 1985, Inalpolat &
    Kahraman 2009). The fault's sidebands ``m f_mesh ± k N |n_gear - n_carrier|`` keep the
    index of their mesh harmonic, so with equally spaced planets and ``m z_gear`` not a
    multiple of ``N`` (sequential phasing) they are all cancelled and the fault's lines stand
    ``q |Omega|`` away from them, with ``q = m z_gear mod N`` (the smallest ``|q|``; both
    signs when two are equally small). In-phase sets (``m z_gear`` a multiple of ``N``)
    and unequally spaced planets (every index passes) keep ``q = 0``.

    Parameters
    ----------
    z_gear : int
        Teeth of the central gear, signed as in the gear-set description (a ring negative).
    planet_angles_rad : sequence of float
        Angles of its planets on their carrier [rad].
    pass_order : float
        ``sign(h) Omega`` in orders of the reference shaft (0: a carrier at rest, no shift).
    mesh_harmonics : int
        Mesh harmonics ``m = 1 .. mesh_harmonics``.

    Returns
    -------
    list of tuple of float
        Per mesh harmonic the order shifts of its fault sidebands (``(0.0,)`` when they are
        not cancelled), for :func:`family_lines`.

    References
    ----------
    McFadden, P. D., Smith, J. D. (1985). Proc. IMechE C 199, 65-70. Inalpolat, M.,
    Kahraman, A. (2009). J. Sound Vib. 323, 677-696.
    """
    if isinstance(z_gear, bool) or not isinstance(z_gear, int | np.integer) \
            or not 0 < abs(int(z_gear)) <= 100_000:
        raise ValueError(f"z_gear = {z_gear!r} is not admissible (a non-zero integer, |z| <= "
                         "100000)")
    psi = require_real_array(planet_angles_rad, "planet_angles_rad", ndim=1, min_size=1,
                             max_abs=1e6)
    if psi.size > 64:
        raise ValueError(f"planet_angles_rad has {psi.size} angles; admissible: 1 .. 64 planets")
    omega = require_real(pass_order, "pass_order")
    if isinstance(mesh_harmonics, bool) or not isinstance(mesh_harmonics, int | np.integer) \
            or not 1 <= mesh_harmonics <= 1000:
        raise ValueError(f"mesh_harmonics = {mesh_harmonics!r} is not admissible (an integer "
                         "1 .. 1000)")
    n = psi.size
    angles = [float(a) for a in psi]
    out: list[tuple[float, ...]] = []
    for m in range(1, int(mesh_harmonics) + 1):
        if omega == 0.0 or phasing_factor(angles, -m * int(z_gear)) > 0.0:
            out.append((0.0,))
            continue
        for r in range(1, n + 1):
            qs = [q for q in (r, -r) if phasing_factor(angles, q - m * int(z_gear)) > 0.0]
            if qs:
                out.append(tuple(float(q * omega) for q in qs))
                break
        else:
            out.append((0.0,))
    return out


@dataclass(frozen=True)
class FamilyEvidence:
    """How a family of kinematic lines explains the measured rises.

    Attributes
    ----------
    family : str
        Family name (``sun_fault``, ``planet_fault``, ...).
    fundamental : float
        Its fundamental order.
    rising : int
        Measured rising peaks in the band.
    hits : int
        Of those, how many fall on a line of the family (within the tolerance).
    coverage : float
        Fraction of the band within the tolerance of a family line.
    chance : float
        Probability of at least ``hits`` hits if the rises fell at random orders (binomial).
    """

    family: str
    fundamental: float
    rising: int
    hits: int
    coverage: float
    chance: float

    def text(self) -> str:
        """One line for a report."""
        return (f"{self.family} (order {self.fundamental:.4g}): {self.hits} of {self.rising} "
                f"rising peaks on its lines (coincidence chance {self.chance:.2g})")


def family_evidence(order: np.ndarray, diff: np.ndarray, deadband: float,
                    families: Mapping[str, tuple[float, np.ndarray]], *,
                    tolerance: float | None = None) -> list[FamilyEvidence]:
    """Which catalogue families the measured rises fall on, with the coincidence chance.

    Parameters
    ----------
    order, diff : numpy.ndarray
        Order bins and the measured prominence difference [dB].
    deadband : float
        Rises below it are noise.
    families : mapping
        ``name -> (fundamental order, line orders)`` (:func:`family_lines`).
    tolerance : float, optional
        Half-width of a hit [orders]; default one bin.
    """
    order = require_real_array(order, "order", ndim=1, min_size=1)
    require_instance(families, Mapping, "families")
    for name, value in families.items():
        if not isinstance(value, tuple | list) or len(value) != 2:
            raise TypeError(f"families[{name!r}] must be (fundamental order, line orders)")
        require_real_array(value[1], f"families[{name!r}] lines", min_size=0)
    if tolerance is not None:
        require_positive(require_real(tolerance, "tolerance"), "tolerance")
    step = float(order[1] - order[0]) if order.size > 1 else 1.0
    tol = step * 1.01 if tolerance is None else float(tolerance)
    lo, hi = float(order[0]), float(order[-1])
    peaks = rising_peaks(order, diff, deadband)
    out = []
    for name, (fund, lines) in families.items():
        lines = np.sort(np.asarray(lines, float))
        if lines.size == 0:
            continue
        # fraction of the band within tol of a line (union of intervals)
        starts, ends = np.maximum(lines - tol, lo), np.minimum(lines + tol, hi)
        covered, cur_s, cur_e = 0.0, starts[0], ends[0]
        for s, e in zip(starts[1:], ends[1:], strict=True):
            if s > cur_e:
                covered += max(0.0, cur_e - cur_s)
                cur_s, cur_e = s, e
            else:
                cur_e = max(cur_e, e)
        covered += max(0.0, cur_e - cur_s)
        cov = min(1.0, covered / max(hi - lo, 1e-12))
        if peaks.size:
            j = np.searchsorted(lines, peaks)
            near = np.full(peaks.size, np.inf)
            for jj in (j - 1, j):
                ok = (jj >= 0) & (jj < lines.size)
                near[ok] = np.minimum(near[ok], np.abs(lines[jj[ok]] - peaks[ok]))
            hits = int(np.sum(near <= tol))
        else:
            hits = 0
        chance = float(stats.binom.sf(hits - 1, peaks.size, cov)) if hits else 1.0
        out.append(FamilyEvidence(name, float(fund), int(peaks.size), hits, cov, chance))
    return out


def order_locking(profile_orders: OrderProfile, x: Any, fs: float, rpm: Any,
                  peak_orders: Sequence[float] | np.ndarray) -> str:
    """Whether the strongest measured rises are order-locked or frequency-locked.

    Compares the prominence of the rising lines in the order spectrum with their prominence
    in the frequency spectrum (same resolution at the mean speed). A line locked to the
    shaft stays sharp in orders and smears in frequency when the speed varies; a line at a
    fixed frequency (a resonance, an electrical line) does the opposite. With the speed
    constant within 3 % the two cannot be told apart and the answer says so.
    """
    _profile(profile_orders, "profile_orders")
    lo, mean, hi = profile_orders.speed_rpm
    spread = (hi - lo) / mean if mean > 0 else 0.0
    if not len(peak_orders):
        return "no rising lines to test for order locking"
    if spread < 0.03:
        return (f"speed constant within {100 * spread:.1f} %: order-locked and frequency-locked "
                "lines cannot be told apart (a run-up would)")
    x = np.asarray(x, float)
    f_ref = mean / 60.0
    nper = int(min(x.size, round(fs * profile_orders.revolutions / f_ref)))
    f, p = signal.welch(x, fs=fs, window="hann", nperseg=nper, noverlap=nper // 2,
                        detrend=False, scaling="spectrum")
    fp = OrderProfile(f / f_ref, np.sqrt(p), profile_orders.units, profile_orders.revolutions,
                      1, profile_orders.speed_rpm)
    po, pf = prominence_db(profile_orders), prominence_db(fp)
    so = float(np.mean(np.interp(peak_orders, profile_orders.order, po)))
    sf = float(np.mean(np.interp(peak_orders, fp.order, pf)))
    verdict = ("order-locked" if so > sf + 3 else "frequency-locked" if sf > so + 3
               else "undecided")
    return (f"{verdict}: the rising lines stand {so:.1f} dB above their floor in the order "
            f"spectrum, {sf:.1f} dB in the frequency spectrum (speed range "
            f"{lo:.0f}-{hi:.0f} min-1)")


def near_modes(orders: Sequence[float] | np.ndarray, reference_hz: float,
               natural_hz: Mapping[str, float], *, rtol: float = 0.05) -> list[str]:
    """Lines (orders at the reference frequency) within ``rtol`` of a natural frequency."""
    require_instance(natural_hz, Mapping, "natural_hz")
    order_values = require_real_array(orders, "orders", min_size=0).ravel()
    reference_hz = require_real(reference_hz, "reference_hz")
    require_real(rtol, "rtol")
    for name, fn in natural_hz.items():
        require_real(fn, f"natural_hz[{name!r}]")
    out = []
    for o in order_values:
        f = float(o) * reference_hz
        for name, fn in natural_hz.items():
            if fn > 0 and abs(f - fn) <= rtol * fn:
                out.append(f"line at order {o:.3f} ({f:.0f} Hz) within {100 * abs(f / fn - 1):.1f}"
                           f" % of natural frequency {name} ({fn:.0f} Hz): its level may be a "
                           "resonance rather than a fault")
    return out


@dataclass(frozen=True)
class Cause:
    """One candidate cause and how well it explains the measurement.

    Attributes
    ----------
    cause : str
        Fault kind as in a gear-set description (``crack``, ``eccentricity``, ...) or
        ``none``.
    member : str
        The member (``sun``, ``planet``, ``planet2``, ``ring``; ``""`` for ``none``).
    score : float
        In [0, 1].
    evidence : tuple of str
        Why.
    variant : str
        The simulated fault that scored best (its description), ``""`` for ``none``.
    verdict : str
        ``"likely"`` (score at or above the threshold), ``"possible"`` (near it, or carried
        by the family evidence), ``"unlikely"``; ``""`` for ``none`` (see
        ``docs/diagnosis.md``).
    """

    cause: str
    member: str
    score: float
    evidence: tuple[str, ...] = ()
    variant: str = ""
    verdict: str = ""

    def to_dict(self) -> dict[str, Any]:
        """``{"cause", "member", "score", "verdict", "evidence"}`` (the JSON of
        ``gearvib diagnose``)."""
        return {"cause": self.cause, "member": self.member, "score": round(self.score, 4),
                "verdict": self.verdict, "evidence": list(self.evidence)}


@dataclass
class Diagnosis:
    """Ranked causes of a measurement and the spectra behind them.

    Attributes
    ----------
    causes : list of Cause
        Best first. ``none`` leads when no cause is likely or possible
        (:mod:`gearvib.diagnosis.verdict`).
    threshold : float
        Score above which a cause is likely.
    order : numpy.ndarray
        Order bins of the reference shaft.
    measured, baseline : OrderProfile
        Profiles of the measurement and the healthy baseline.
    measured_diff : numpy.ndarray
        Prominence difference measured − baseline [dB].
    deadband : float
        Noise deadband of ``measured_diff`` [dB].
    signatures : dict
        ``label -> simulated prominence difference`` [dB] of every candidate variant.
    families : list of FamilyEvidence
    next_steps : list of str
        What to measure next when the evidence is weak.
    notes : list of str
        General evidence (order locking, modes, resolution).
    reference : str
        Reference shaft of the orders.
    attrs : dict
        Provenance (written to the Dataset's attributes).
    line_check : object, optional
        A check of fault lines at their own positions behind causes that were not simulated
        (with ``plot()`` and ``to_dataset()``; gearvib's rolling-bearing check), or None.
    timing : dict
        Wall times [s] and run counts (not written: the same input gives the same output).
    """

    causes: list[Cause]
    threshold: float
    order: np.ndarray
    measured: OrderProfile
    baseline: OrderProfile
    measured_diff: np.ndarray
    deadband: float
    signatures: dict[str, np.ndarray] = field(default_factory=dict)
    families: list[FamilyEvidence] = field(default_factory=list)
    next_steps: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    reference: str = "carrier"
    attrs: dict[str, Any] = field(default_factory=dict)
    line_check: Any = None
    timing: dict[str, float] = field(default_factory=dict)

    @property
    def likely(self) -> list[Cause]:
        """Causes (not ``none``) at or above the threshold."""
        return [c for c in self.causes if c.cause != "none" and c.score >= self.threshold]

    @property
    def possible(self) -> list[Cause]:
        """Causes whose verdict is ``possible`` (below the threshold, but near it or carried
        by their family's lines)."""
        return [c for c in self.causes if c.verdict == "possible"]

    def to_dict(self) -> dict[str, Any]:
        """``{"threshold": ..., "causes": [...]}``, best first."""
        return {"threshold": self.threshold, "causes": [c.to_dict() for c in self.causes]}

    def to_json(self) -> str:
        """:meth:`to_dict` as JSON."""
        return json.dumps(self.to_dict())

    def to_dataset(self) -> xr.Dataset:
        """Profiles, differences, signatures and the ranked causes as a CF Dataset."""
        oc = {"order": ("order", self.order, {"units": "1", "long_name":
                                               f"order of the {self.reference}"})}
        labels = list(self.signatures)
        ds = xr.Dataset(
            {
                "measured_amplitude": ("order", self.measured.amplitude,
                                       {"units": self.measured.units,
                                        "long_name": "RMS order spectrum of the measurement"}),
                "baseline_amplitude": ("order", self.baseline.amplitude,
                                       {"units": self.baseline.units,
                                        "long_name": "RMS order spectrum of the healthy "
                                                     "baseline"}),
                "measured_difference": ("order", self.measured_diff,
                                        {"units": "dB", "long_name": "prominence of the "
                                         "measurement minus prominence of the baseline"}),
                "signature": (("variant", "order"),
                              np.array([self.signatures[k] for k in labels]).reshape(
                                  len(labels), self.order.size),
                              {"units": "dB", "long_name": "simulated prominence difference "
                               "faulty minus healthy"}),
                "score": ("rank", np.array([c.score for c in self.causes], float),
                          {"units": "1", "long_name": "how well the cause explains the "
                           "measured difference (0-1)"}),
            },
            coords={**oc,
                    "variant": ("variant", np.array(labels, dtype=str),
                                {"long_name": "simulated candidate fault"}),
                    "rank": ("rank", np.arange(1, len(self.causes) + 1),
                             {"units": "1", "long_name": "rank of the cause"}),
                    "cause": ("rank", np.array([c.cause for c in self.causes], dtype=str),
                              {"long_name": "fault kind"}),
                    "member": ("rank", np.array([c.member for c in self.causes], dtype=str),
                               {"long_name": "faulty member"}),
                    "verdict": ("rank", np.array([c.verdict for c in self.causes], dtype=str),
                                {"long_name": "verdict: likely, possible or unlikely"})},
            attrs={"title": "gearvib fault-cause diagnosis", "Conventions": "CF-1.11",
                   "threshold": self.threshold, "deadband_db": self.deadband,
                   "reference_shaft": self.reference,
                   "diagnosis_json": self.to_json(),
                   "evidence_json": json.dumps({f"{c.cause}:{c.member}": list(c.evidence)
                                                for c in self.causes}),
                   "next_steps": "; ".join(self.next_steps),
                   "notes": "; ".join(self.notes), **self.attrs})
        return cf_dataset(ds, title="gearvib fault-cause diagnosis", producer="analysis.diagnosis")

    def plot(self, *, top: int = 3, figsize: tuple[float, float] = (9.0, 7.0)):
        """The measured difference against the signatures of the ``top`` causes.

        Returns the matplotlib Figure.
        """
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize, layout="constrained")
        seen: set[str] = set()
        shown = []  # the first cause of each variant
        for c in self.causes:
            if c.cause != "none" and c.variant not in seen:
                seen.add(c.variant)
                shown.append(c)
        shown = shown[:top]
        axes = fig.subplots(1 + len(shown), 1, sharex=True, squeeze=False)[:, 0]
        ax = axes[0]
        ax.plot(self.order, self.measured_diff, lw=0.7, color="k")
        ax.axhline(self.deadband, color="tab:red", lw=0.8, ls="--",
                   label=f"noise deadband {self.deadband:.1f} dB")
        ax.set_ylabel("ΔP [dB]")
        ax.set_title("measured minus healthy baseline (prominence above the local floor)",
                     fontsize=9)
        ax.legend(loc="upper right", fontsize=8)
        for axc, c in zip(axes[1:], shown, strict=True):
            sig = self.signatures.get(c.variant)
            if sig is not None:
                axc.plot(self.order, sig, lw=0.7, color="tab:blue")
            axc.set_ylabel("ΔP [dB]")
            axc.set_title(f"simulated {c.variant}: score {c.score:.2f}"
                          f"{f' ({c.verdict})' if c.verdict else ''}", fontsize=9)
        axes[-1].set_xlabel(f"order of the {self.reference}")
        return fig
