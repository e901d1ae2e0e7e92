"""Time-synchronous averaging (TSA) of a shaft's revolutions, with bounded memory.

The record is resampled to ``samples_per_rev`` samples per revolution of the shaft of interest
by the alias-free angular resampler of :mod:`analysis.resample`, block by block; whole
revolutions are added to a running mean and a running sum of squared deviations per angle
(Chan, Golub & LeVeque's pairwise update), so the angle-domain record is never held: beyond
the input, the working memory is a few blocks of 32768 angle samples whatever the record's
length. The reference (tacho, pulse times, rpm or angle, of this shaft or of another one with
a ``ratio``) is described in :mod:`analysis.sync_reference`.

What the average does (McFadden 1987; Braun 1975): the mean of ``N`` revolutions keeps every
component synchronous with the shaft (integer orders) unchanged, multiplies a component at
order ``k + delta`` (``0 < |delta| < 1``, e.g. another shaft) by the comb response

.. math:: |H(\\delta)| = \\left|\\frac{\\sin(\\pi N \\delta)}{N \\sin(\\pi \\delta)}\\right|,

and divides the rms of noise that is not synchronous (independent from revolution to
revolution) by :math:`\\sqrt{N}`. The result states ``N``, that factor and the rms of the
revolutions about their mean (the non-synchronous part); their ratio estimates the noise
left in the average.

The average is placed on the shaft's angle axis: sample ``i`` is at angle
``2 pi i / samples_per_rev`` from the reference's zero (the first tacho pulse, times the
ratio). The revolutions averaged start at an arbitrary angle of the resampled grid; the mean
is rotated onto that axis by a circular fractional shift (a linear phase on its DFT), exact for
the band-limited averages the resampler delivers (orders below ``samples_per_rev / 2``).

References
----------
P. D. McFadden, "A revised model for the extraction of periodic waveforms by time domain
averaging", Mechanical Systems and Signal Processing 1(1), 1987, 83-95.
S. Braun, "The extraction of periodic waveforms by time domain averaging", Acustica 32, 1975.
T. F. Chan, G. H. Golub, R. J. LeVeque, "Algorithms for computing the sample variance",
The American Statistician 37(3), 1983.
MATLAB ``tsa`` (Signal Processing Toolbox): ``tsa(x, fs, tp, NumRotations=...)``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.cf import cf_dataset, processing_attrs
from analysis.checks import (
    require_block_size,
    require_int,
    require_real,
    require_real_array,
    time_or_rate,
)
from analysis.cm_plots import tsa_figure
from analysis.fft import irfft, rfft
from analysis.inputs import Signal, channel_coords, select_channel, signal_input
from analysis.resample import AngleResampler, check_sampling, default_samples_per_rev
from analysis.sinc import HALF_TAPS
from analysis.sync_reference import ShaftAngle, shaft_angle

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = ["TSA", "comb_response", "fractional_shift", "tsa", "tsa_windows"]


@dataclass(frozen=True)
class TSA:
    """A time-synchronous average: one revolution of a shaft (or a gear), on its angle axis.

    Attributes
    ----------
    angle : numpy.ndarray
        Angle of the shaft (gear) [rad], ``2 pi i / samples_per_rev``.
    values : numpy.ndarray
        The average, shape ``(*channels, samples_per_rev)``, in ``units``. Angles never
        observed (a planet TSA whose placement cycle did not close) are NaN.
    revolutions : int
        Revolutions averaged (of the reference shaft for a planet or sun average: each is one
        pass of the planet under the sensor).
    effective_averages : float
        Number of equally weighted averages with the same noise reduction: ``revolutions`` for
        a plain TSA, :math:`(\\sum w)^2 / \\sum w^2` (median over the angle) for a windowed
        average.
    samples_per_rev : int
        Samples per revolution.
    max_order : float
        Highest order reproduced without attenuation by the resampler's anti-alias filter.
    nonsynchronous_rms : numpy.ndarray
        Rms of the revolutions about their mean, per channel (``(*channels,)``): the part of
        the signal that is not synchronous with the shaft (noise, other shafts), before
        averaging. NaN for windowed averages.
    start_time, stop_time : float
        First and last instant of the revolutions averaged [s].
    shaft : str
        What turns once per ``angle`` revolution (``"shaft"``, ``"planet 1"``, ``"sun"``).
    ratio : float
        Speed of that shaft over the speed of the reference shaft.
    units, name : str
        Units and name of the signal.
    dims : tuple of str
        Names of the channel dimensions of ``values``.
    coords : dict
        Their coordinates (may be empty).
    reference : str
        The reference used.
    notes : tuple of str
        What was done beyond the request (samples left out, window used ...).
    coverage : float
        Fraction of the angle axis observed (1 for a plain TSA).
    teeth : int or None
        Teeth of the gear when the average is of a gear (planet, sun), else ``None``.
    """

    angle: np.ndarray
    values: np.ndarray
    revolutions: int
    effective_averages: float
    samples_per_rev: int
    max_order: float
    nonsynchronous_rms: np.ndarray
    start_time: float
    stop_time: float
    shaft: str = "shaft"
    ratio: float = 1.0
    units: str = "1"
    name: str = "x"
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    reference: str = ""
    notes: tuple[str, ...] = ()
    coverage: float = 1.0
    teeth: int | None = None

    @property
    def noise_reduction(self) -> float:
        """Amplitude factor applied to non-synchronous noise: ``1 / sqrt(effective_averages)``."""
        return float(1.0 / np.sqrt(self.effective_averages))

    @property
    def noise_reduction_db(self) -> float:
        """The same in dB: ``-10 log10(effective_averages)``."""
        return float(-10.0 * np.log10(self.effective_averages))

    @property
    def residual_noise_rms(self) -> np.ndarray:
        """Estimated rms of the noise left in the average: ``nonsynchronous_rms`` times
        :attr:`noise_reduction` (per channel)."""
        return np.asarray(self.nonsynchronous_rms) * self.noise_reduction

    @property
    def rpm(self) -> float:
        """Mean speed of the shaft over the revolutions averaged [min-1] (NaN for a gear
        average whose ``revolutions`` are of the reference)."""
        if self.shaft != "shaft" or not self.stop_time > self.start_time:
            return float("nan")
        return float(60.0 * self.revolutions / (self.stop_time - self.start_time))

    def select(self, channel: Any) -> TSA:
        """The average of one channel (a label of the channel coordinate, or an index)."""
        values, dims, coords, label = select_channel(self.values, self.dims, self.coords, channel)
        i = _channel_index(self.values.shape[:-1], self.dims, self.coords, channel)
        rms = np.asarray(self.nonsynchronous_rms)[i] if np.ndim(self.nonsynchronous_rms) else (
            self.nonsynchronous_rms
        )
        name = f"{self.name} {label}" if self.name else label
        return dataclasses.replace(
            self, values=values, dims=dims, coords=coords, name=name,
            nonsynchronous_rms=np.asarray(rms),
        )  # fmt: skip

    def to_dataset(self) -> xr.Dataset:
        """CF :class:`xarray.Dataset`: ``tsa(*channels, angle)`` and ``nonsynchronous_rms``;
        the averaging figures (revolutions, noise reduction ...) in attributes."""
        import xarray as xr

        coords: dict[str, Any] = {
            "angle": (
                "angle",
                self.angle,
                {"units": "rad", "long_name": f"angle of the {self.shaft} (0 = reference zero)"},
            )
        }
        if self.teeth:
            coords["tooth"] = (
                "angle",
                self.angle * self.teeth / (2.0 * np.pi),
                {"units": "1", "long_name": "tooth position (tooth k spans [k, k + 1))"},
            )
        coords.update(channel_coords(self.dims, self.coords))
        attrs: dict[str, Any] = {
            "Conventions": "CF-1.11",
            "revolutions": int(self.revolutions),
            "effective_averages": float(self.effective_averages),
            "noise_reduction": self.noise_reduction,
            "noise_reduction_db": self.noise_reduction_db,
            "samples_per_rev": int(self.samples_per_rev),
            "max_order": float(self.max_order),
            "start_time_s": float(self.start_time),
            "stop_time_s": float(self.stop_time),
            "shaft": self.shaft,
            "ratio": float(self.ratio),
            "coverage": float(self.coverage),
        }
        if self.teeth:
            attrs["teeth"] = int(self.teeth)
        attrs.update(processing_attrs(self.reference, self.notes))
        ds = xr.Dataset(
            {
                "tsa": (
                    (*self.dims, "angle"),
                    self.values,
                    {
                        "units": self.units,
                        "long_name": f"time-synchronous average of {self.name} ({self.shaft})",
                    },
                ),
                "nonsynchronous_rms": (
                    self.dims,
                    np.asarray(self.nonsynchronous_rms, dtype=float),
                    {
                        "units": self.units,
                        "long_name": "rms of the revolutions about their average (before "
                        "averaging)",
                    },
                ),
            },
            coords=coords,
            attrs=attrs,
        )
        return cf_dataset(
            ds,
            title=f"time-synchronous average of {self.name} ({self.shaft})",
            producer="analysis.tsa.tsa",
        )

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure of the average (see :func:`analysis.cm_plots.tsa_figure`)."""
        return tsa_figure(self, **kwargs)


def _channel_index(
    lead: tuple[int, ...], dims: tuple[str, ...], coords: dict[str, np.ndarray], key: Any
) -> int:
    labels = coords.get(dims[0]) if dims else None
    if labels is not None and not isinstance(key, int | np.integer):
        return int(np.flatnonzero(np.asarray(labels) == key)[0])
    return int(key) % lead[0]


def comb_response(delta: Any, revolutions: int) -> np.ndarray:
    """Amplitude response of an average of ``revolutions`` revolutions to a component
    ``delta`` orders away from the nearest integer order: ``|sin(pi N d) / (N sin(pi d))|``
    (1 at integer orders; McFadden 1987, eq. 4; Braun 1975).

    Parameters
    ----------
    delta : array_like
        Order offsets (any real; the response has period 1).
    revolutions : int
        Revolutions averaged ``N``.

    Returns
    -------
    numpy.ndarray
        The response, in ``[0, 1]``.
    """
    n = require_int(revolutions, "revolutions", 1)
    d = np.asarray(delta, dtype=float)
    s = np.sin(np.pi * d)
    with np.errstate(invalid="ignore", divide="ignore"):
        h = np.abs(np.sin(np.pi * n * d) / (n * s))
    return np.where(np.abs(s) < 1e-12, 1.0, h)


def fractional_shift(values: np.ndarray, shift: float) -> np.ndarray:
    """Circular shift of periodic samples by ``shift`` samples (any real), along the last axis.

    ``out[i] = f(i - shift)`` for the trigonometric interpolant ``f`` of ``values``: a
    linear phase ``exp(-2 pi j k shift / n)`` on the DFT, exact for a signal band-limited
    below ``n / 2``; the Nyquist line of an even ``n`` is kept real (scaled by
    ``cos(pi shift)``).
    """
    values = require_real_array(values, "values", min_size=1)
    if values.ndim == 0:
        raise ValueError("values must be an array along the angle (last axis); got a scalar")
    shift = require_real(shift, "shift")
    n = values.shape[-1]
    k = np.arange(n // 2 + 1)
    spec = rfft(values, axis=-1)
    nyquist = spec[..., -1].real.copy()
    spec *= np.exp(-2j * np.pi * k * shift / n)
    if n % 2 == 0:
        spec[..., -1] = nyquist * np.cos(np.pi * shift)
    return irfft(spec, n, axis=-1)


# ----------------------------------------------------------------------------------------------
# set-up shared with the planetary separation
# ----------------------------------------------------------------------------------------------


@dataclass
class Synchronous:
    """A record ready for averaging: its resampler onto the shaft angle and the usable range.

    Attributes
    ----------
    signal : Signal
        The checked signal.
    shaft : ShaftAngle
        Angle reference of the shaft of interest.
    resampler : AngleResampler
        Resampler of ``signal`` samples ``[shaft.start, shaft.stop)``.
    guard : int
        Angle samples left out at each end of the resampled record (the anti-alias FIR and
        the interpolator reach beyond the record there).
    block : int
        Angle samples resampled per block.
    """

    signal: Signal
    shaft: ShaftAngle
    resampler: AngleResampler
    guard: int
    block: int

    @property
    def samples_per_rev(self) -> int:
        return int(self.resampler.samples_per_rev)

    @property
    def usable(self) -> int:
        """Angle samples between the guards."""
        return max(0, self.resampler.n_out - 2 * self.guard)

    def first_angle(self, j: int) -> float:
        """Angle [rad] of resampled sample ``j``."""
        return float(self.resampler.angle(j, j + 1)[0])


def synchronous(
    x: Any, fs: Any, *, time: Any, axis: int | None, units: str | None, name: str | None,
    tacho: Any, pulses_per_rev: Any, pulse_times: Any, rpm: Any, angle: Any, ratio: Any,
    samples_per_rev: Any, max_order: Any, min_rpm: float | None, block_size: Any,
    function: str, multiple: int = 1,
) -> Synchronous:  # fmt: skip
    """Check the inputs and set up the angular resampling (shared by the averages).

    The default ``samples_per_rev`` (about ``fs`` at the top speed) is rounded up to a
    multiple of ``multiple`` (and is at least ``4 * multiple``).
    """
    fs, time = time_or_rate(fs, time, function)
    if fs is not None:
        require_real(fs, "fs")
    lengths = tuple(
        np.shape(r)[0] for r in (rpm, angle, tacho) if r is not None and np.ndim(r) == 1
    )
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name, lengths=lengths)
    block = require_block_size(block_size)
    ref_rpm, ref_angle = rpm, angle
    if all(v is None for v in (tacho, pulse_times, rpm, angle)) and sig.reference is not None:
        ref_rpm = sig.reference.values if sig.reference.kind == "rpm" else None
        ref_angle = sig.reference.values if sig.reference.kind == "angle" else None
    shaft = shaft_angle(
        sig, tacho=tacho, pulses_per_rev=pulses_per_rev, pulse_times=pulse_times,
        rpm=ref_rpm, angle=ref_angle, ratio=ratio, min_rpm=min_rpm, block=block,
    )  # fmt: skip
    if samples_per_rev is None:
        spr, _ = default_samples_per_rev(sig.fs, shaft.rpm_max)
        # about fs at the lowest speed when that costs at most 25 % more samples: the
        # resampler then needs no oversampling (half the interpolation work, no FIR)
        rpm_min = shaft.track.step_min * sig.fs * 60.0 / (2.0 * np.pi)
        low, _ = default_samples_per_rev(sig.fs, rpm_min)
        if low <= 1.25 * spr:
            spr = low
        spr = max(4, -(-spr // multiple)) * multiple
        mo = max_order
    else:
        spr, mo = samples_per_rev, max_order
    if mo is not None and (isinstance(mo, bool | str) or not isinstance(mo, int | float)):
        raise TypeError(f"max_order = {mo!r} must be a real number (orders)")
    spr, mo = check_sampling(spr, mo)
    if spr > 1 << 22:
        raise ValueError(f"samples_per_rev = {spr} is not admissible: at most {1 << 22}")
    xs = sig.values[..., shaft.start : shaft.stop]
    res = AngleResampler(xs, shaft.track, sig.fs, spr, mo, block)
    fir_reach = 0 if res.fir is None else -(-(res.fir.size // 2) // res.oversampling)
    # the interpolator reaches HALF_TAPS time samples: at the top speed that many angle samples
    per_time_sample = spr * shaft.track.step_max / (2.0 * np.pi)
    guard = fir_reach + int(np.ceil(HALF_TAPS * per_time_sample)) + 1
    return Synchronous(sig, shaft, res, guard, block)


def _revolution_sums(
    syn: Synchronous, groups: list[tuple[int, int]]
) -> Iterator[tuple[np.ndarray, np.ndarray, float, float]]:
    """Mean and sum of squared deviations per angle of each group ``[r0, r1)`` of revolutions
    (counted from the first whole revolution after the guard), with its first and last
    instant; revolutions are resampled and added block by block."""
    spr = syn.samples_per_rev
    res = syn.resampler
    per_block = max(1, syn.block // spr)
    for r0, r1 in groups:
        count = 0
        mean = np.zeros((*syn.signal.lead, spr))
        m2 = np.zeros_like(mean)
        t_first = t_last = float("nan")
        for a in range(r0, r1, per_block):
            b = min(r1, a + per_block)
            j0 = syn.guard + a * spr
            vals, times = res.block(j0, syn.guard + b * spr + (1 if b == r1 else 0))
            if b == r1:
                t_last = float(times[-1])
                vals = vals[..., :-1]
            if a == r0:
                t_first = float(times[0])
            revs = vals.reshape(*syn.signal.lead, b - a, spr)
            bm = revs.mean(axis=-2)
            bm2 = ((revs - bm[..., None, :]) ** 2).sum(axis=-2)
            nb = b - a
            delta = bm - mean
            total = count + nb
            mean += delta * (nb / total)
            m2 += bm2 + delta**2 * (count * nb / total)
            count = total
        yield mean, m2, t_first, t_last


def _checked_revolutions(value: Any, name: str, available: int, spr: int) -> int:
    if available < 2:
        raise ValueError(
            f"too few revolutions: the record holds {available} whole revolution(s) of the shaft "
            f"at {spr} samples/rev after the resampler's edge guards; a synchronous average "
            "needs at least 2"
        )
    if value is None:
        return available
    n = require_int(value, name, 2)
    if n > available:
        raise ValueError(
            f"{name} = {n} is not admissible: the record holds {available} whole revolutions "
            "of the shaft"
        )
    return n


def _result(
    syn: Synchronous, mean: np.ndarray, m2: np.ndarray, count: int, j_first: int,
    t_first: float, t_last: float,
) -> TSA:  # fmt: skip
    spr = syn.samples_per_rev
    phase = syn.first_angle(j_first) % (2.0 * np.pi)
    values = fractional_shift(mean, phase * spr / (2.0 * np.pi))
    rms = np.sqrt(m2.mean(axis=-1) / max(count - 1, 1))
    sig = syn.signal
    angle = 2.0 * np.pi * np.arange(spr) / spr
    return TSA(
        angle=angle, values=values, revolutions=int(count), effective_averages=float(count),
        samples_per_rev=spr, max_order=float(syn.resampler.max_order), nonsynchronous_rms=rms,
        start_time=t_first, stop_time=t_last, shaft="shaft", ratio=syn.shaft.ratio,
        units=sig.units, name=sig.name, dims=sig.dims, coords=sig.coords,
        reference=syn.shaft.label, notes=syn.shaft.notes,
    )  # fmt: skip


_PARAMS_DOC = """
    x : array_like or xarray.DataArray
        Signal, one or several channels (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or give ``time``).
    tacho : array_like, optional
        Tacho pulse train, one value per sample of ``x``.
    pulses_per_rev : int, optional
        Pulses per revolution of the reference shaft (default 1).
    pulse_times : array_like, optional
        Pulse instants [s] on the time axis of ``x`` (MATLAB's ``tp``).
    rpm : array_like, optional
        Reference speed [min-1] per sample.
    angle : array_like, optional
        Reference angle [rad] per sample.
    ratio : float, default 1
        Speed of the shaft to average over the speed of the reference shaft.
    samples_per_rev : int, optional
        Samples per revolution of the average; default about ``fs`` at the lowest speed of
        the record when that is at most 25 % more than at the top speed (the resampler then
        needs no oversampling), else about ``fs`` at the top speed
        (:func:`analysis.resample.default_samples_per_rev`).
    max_order : float, optional
        Highest order kept by the resampler (default ``samples_per_rev / 2.56``).
    min_rpm : float, optional
        Standstill threshold of an rpm/angle reference (default 2 % of its top speed).
    time : array_like, optional
        Uniform sample instants [s].
    axis : int, optional
        Time axis of a multi-dimensional array.
    units, name : str, optional
        Metadata of ``x``.
    block_size : int, optional
        Angle samples resampled per block (default 32768): sets the working memory only."""


def tsa(
    x: Any,
    fs: Any = None,
    *,
    tacho: Any = None,
    pulses_per_rev: Any = None,
    pulse_times: Any = None,
    rpm: Any = None,
    angle: Any = None,
    ratio: Any = 1.0,
    samples_per_rev: Any = None,
    max_order: Any = None,
    revolutions: Any = None,
    min_rpm: float | None = None,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    block_size: Any = None,
) -> TSA:
    """Time-synchronous average of a shaft's revolutions (MATLAB ``tsa``), bounded memory.

    Parameters
    ----------{params}
    revolutions : int, optional
        Revolutions to average, from the first whole revolution of the record (default: all
        whole revolutions; at least 2).

    Returns
    -------
    TSA
        The average on the shaft's angle axis, the revolutions averaged, the noise reduction
        ``1 / sqrt(revolutions)`` and the rms of the non-synchronous part.

    Raises
    ------
    ValueError, TypeError
        Naming the parameter: no or several references, wrong sizes, NaN/inf, bool or string
        numbers, fewer than 2 whole revolutions, more ``revolutions`` than the record holds.

    Notes
    -----
    Average of revolutions :math:`x_r(\\theta_i)`, :math:`\\theta_i = 2\\pi i / n`:
    :math:`\\bar x(\\theta_i) = \\frac{1}{N} \\sum_{r=1}^{N} x_r(\\theta_i)`. Resampling,
    comb response and noise reduction: module docstring. Working memory: the blocks of the
    resampler (``block_size`` angle samples per channel) and two revolutions per channel.

    References
    ----------
    McFadden 1987, MSSP 1(1); Braun 1975, Acustica 32 (module docstring).
    """
    syn = synchronous(
        x, fs, time=time, axis=axis, units=units, name=name, tacho=tacho,
        pulses_per_rev=pulses_per_rev, pulse_times=pulse_times, rpm=rpm, angle=angle,
        ratio=ratio, samples_per_rev=samples_per_rev, max_order=max_order, min_rpm=min_rpm,
        block_size=block_size, function="tsa",
    )  # fmt: skip
    spr = syn.samples_per_rev
    n = _checked_revolutions(revolutions, "revolutions", syn.usable // spr, spr)
    mean, m2, t0, t1 = next(_revolution_sums(syn, [(0, n)]))
    return _result(syn, mean, m2, n, syn.guard, t0, t1)


def tsa_windows(
    x: Any,
    fs: Any = None,
    *,
    revolutions: Any,
    windows: Any = None,
    tacho: Any = None,
    pulses_per_rev: Any = None,
    pulse_times: Any = None,
    rpm: Any = None,
    angle: Any = None,
    ratio: Any = 1.0,
    samples_per_rev: Any = None,
    max_order: Any = None,
    min_rpm: float | None = None,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    block_size: Any = None,
) -> tuple[TSA, ...]:
    """Time-synchronous averages of consecutive groups of revolutions (a trend over time).

    One pass over the record: the averages of revolutions ``[0, K)``, ``[K, 2K)``, ... with
    ``K = revolutions``, each a :class:`TSA` with its own start and stop time; feed them to
    :func:`analysis.indicators.condition_indicators` for indicators over time windows.

    Parameters
    ----------{params}
    revolutions : int
        Revolutions per average (>= 2).
    windows : int, optional
        Number of averages (default: as many as the record holds).

    Returns
    -------
    tuple of TSA
        The averages, in time order.
    """
    syn = synchronous(
        x, fs, time=time, axis=axis, units=units, name=name, tacho=tacho,
        pulses_per_rev=pulses_per_rev, pulse_times=pulse_times, rpm=rpm, angle=angle,
        ratio=ratio, samples_per_rev=samples_per_rev, max_order=max_order, min_rpm=min_rpm,
        block_size=block_size, function="tsa_windows",
    )  # fmt: skip
    spr = syn.samples_per_rev
    available = syn.usable // spr
    k = _checked_revolutions(revolutions, "revolutions", available, spr)
    count = available // k
    if windows is not None:
        w = require_int(windows, "windows", 1)
        if w > count:
            raise ValueError(
                f"windows = {w} is not admissible: the record holds {count} windows of {k} "
                "revolutions"
            )
        count = w
    groups = [(i * k, (i + 1) * k) for i in range(count)]
    out = []
    for (r0, _), (mean, m2, t0, t1) in zip(groups, _revolution_sums(syn, groups), strict=True):
        out.append(_result(syn, mean, m2, k, syn.guard + r0 * spr, t0, t1))
    return tuple(out)


tsa.__doc__ = (tsa.__doc__ or "").replace("{params}", _PARAMS_DOC)
tsa_windows.__doc__ = (tsa_windows.__doc__ or "").replace("{params}", _PARAMS_DOC)
