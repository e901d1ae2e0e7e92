"""Angular resampling (computed order tracking): speed to angle, and alias-free resampling
of a record onto constant angle increments, block by block.

Method (Fyfe & Munck 1997; Brandt 2011, ch. 12; Blough 2003): the shaft angle is the
cumulative trapezoidal integral of the speed; the signal is low-pass filtered in time,
interpolated onto a constant-angle grid finer than needed, low-pass filtered *in the angle
domain* and decimated to ``samples_per_rev``. The two filter stages make the result free of
aliasing at every speed of a run-up, not just at the top speed:

1. a zero-phase 8th-order Butterworth low-pass at ``1.25 * max_order`` times the highest
   shaft frequency (skipped when that exceeds 0.45 ``fs``) removes what cannot be an order of
   interest;
2. the angle grid is oversampled by an integer factor ``L`` chosen so that whatever survives
   step 1 at the *lowest* speed lies below the fine grid's Nyquist order and cannot alias
   into ``[0, samples_per_rev / 2]``; a 24-tap Kaiser-windowed sinc interpolator (compiled,
   :func:`analysis.sinc.interpolate`; error
   < 0.01 dB up to 0.4 ``fs``) evaluates the signal at the instants of the fine angle grid;
3. a Kaiser-window FIR (80 dB stop band, pass band up to ``max_order``, stop band from
   ``samples_per_rev / 2``) removes everything above the final Nyquist order before
   decimation by ``L``.

Orders up to ``max_order`` are therefore reproduced without aliasing; between ``max_order``
and ``samples_per_rev / 2`` the FIR transition band attenuates them.

**Long recordings** are resampled block by block (``block_size`` output samples, and at most
as many samples of the record, per block; default 32768): a first pass integrates the angle
and keeps it every block (checkpoints); each block then recomputes only the stretch of the
record it needs, widened by the support of each step — the half length of the angle-domain
FIR on the fine grid, the 12 samples of the sinc interpolator, and for the zero-phase
Butterworth its settling length (its forward pass restarts exactly from stored states, its
backward pass starts where an error in its initial state has decayed below 1e-17). Blocks
therefore reproduce the whole-record computation to rounding (about 1e-15 relative; an
ill-conditioned low-pass far below ``fs`` amplifies rounding of any start to 1e-12, as it
does in ``sosfiltfilt`` itself). :func:`analysis.orders.order_spectrum`,
:func:`analysis.orders.order_cuts` and :func:`analysis.maps.rpm_order_map` feed each block
straight into their frames and accumulators, so they never hold the angle-domain signal:
beyond their output they need a few MB whatever the record's length.
:func:`resample_to_angle` returns the whole signal.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import scipy.integrate
import scipy.signal

from analysis.cf import cf_dataset, processing_attrs
from analysis.checks import (
    BLOCK_SAMPLES,
    require_block_size,
    require_finite,
    require_finite_blocks,
    require_instance,
    require_monotonic,
    require_positive,
    require_same_length,
    require_size,
    time_or_rate,
)
from analysis.inputs import (
    Reference,
    Signal,
    channel_coords,
    moving_range,
    reference_input,
    signal_input,
)
from analysis.sinc import HALF_TAPS, decimate, interpolate, positions

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "AngleResampler",
    "AngleSignal",
    "Track",
    "Tracking",
    "angle_from_speed",
    "check_sampling",
    "check_speed",
    "default_samples_per_rev",
    "resample_to_angle",
    "tracking",
]

_MAX_OVERSAMPLING = 64
#: Largest number of fine-grid angle samples per time sample of the record (plus
#: :data:`MIN_ANGLE_LIMIT`): a finer angle grid holds no information the record has, so a
#: larger one means a speed, ``fs`` or ``samples_per_rev`` in the wrong units.
MAX_ANGLE_PER_TIME_SAMPLE = 1024
#: Angle samples always admissible, however short the record.
MIN_ANGLE_LIMIT = 1 << 20
_MIN_INTERVAL = 256  # smallest spacing of the time-domain checkpoints [samples]


def angle_from_speed(time: Any, rpm: Any) -> np.ndarray:
    """Shaft angle [rad] from a speed trace by cumulative trapezoidal integration.

    Parameters
    ----------
    time : array_like
        Sample instants [s], strictly increasing.
    rpm : array_like
        Speed [min-1] at ``time`` (same length).

    Returns
    -------
    numpy.ndarray
        Angle [rad], 0 at ``time[0]``.
    """
    t = require_monotonic(time, "time")
    n = require_finite(rpm, "rpm")
    if t.ndim != 1 or n.ndim != 1:
        raise ValueError("time and rpm must be 1-D")
    require_same_length([t, n], ["time", "rpm"])
    return scipy.integrate.cumulative_trapezoid(n * (2.0 * np.pi / 60.0), t, initial=0.0)


@dataclass
class AngleSignal:
    """A signal sampled at constant angle increments.

    Attributes
    ----------
    angle : numpy.ndarray
        Shaft angle of each sample [rad] (uniform, step ``2 pi / samples_per_rev``).
    time : numpy.ndarray
        Instant at which the shaft passes each angle [s].
    values : numpy.ndarray
        Samples, shape ``(..., angle)``.
    samples_per_rev : int
        Samples per revolution.
    max_order : float
        Highest order reproduced without attenuation or aliasing.
    oversampling : int
        Oversampling factor of the intermediate fine angle grid.
    units, name : str
        Units and name of the signal.
    dims : tuple of str
        Names of the leading (channel) dimensions of ``values``.
    coords : dict
        Their coordinates (may be empty).
    reference : str
        The speed reference used (``"rpm"``, ``"angle"`` or a variable name and units).
    notes : tuple of str
        What was done beyond the request (e.g. standstill left out).
    """

    angle: np.ndarray
    time: np.ndarray
    values: np.ndarray
    samples_per_rev: int
    max_order: float
    oversampling: int
    units: str = "1"
    name: str = "x"
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    reference: str = ""
    notes: tuple[str, ...] = ()

    @property
    def revolutions(self) -> np.ndarray:
        """Angle in revolutions."""
        return self.angle / (2.0 * np.pi)

    def to_dataset(self) -> xr.Dataset:
        """:class:`xarray.Dataset` with dimension ``angle`` and auxiliary coordinate ``time``."""
        import xarray as xr

        lead = self.dims or tuple(f"dim_{i}" for i in range(self.values.ndim - 1))
        coords: dict[str, Any] = {
            "angle": ("angle", self.angle, {"units": "rad", "long_name": "shaft angle"}),
            "time": (
                "angle",
                self.time,
                {"units": "s", "long_name": "time at which the shaft reaches the angle"},
            ),
        }
        coords.update(channel_coords(lead, self.coords))
        attrs: dict[str, Any] = {
            "samples_per_rev": int(self.samples_per_rev),
            "max_order": float(self.max_order),
            "oversampling": int(self.oversampling),
        }
        attrs.update(processing_attrs(self.reference, self.notes))
        ds = xr.Dataset(
            {
                self.name: (
                    (*lead, "angle"),
                    self.values,
                    {"units": self.units, "long_name": self.name},
                )
            },
            coords=coords,
            attrs=attrs,
        )
        return cf_dataset(
            ds, title=f"{self.name} resampled to the shaft angle",
            producer="analysis.resample.resample_to_angle",
            inputs={"signal": self.name, "speed_reference": self.reference}
        )


class Samples(Protocol):
    """Values per sample read in slices: an array, or a lazy sequence that computes the
    slices it is asked for (see :mod:`analysis.sync_reference`)."""

    def __len__(self) -> int: ...

    def __getitem__(self, key: slice, /) -> np.ndarray: ...


class Track:
    """Time axis and shaft angle of a record, read block-wise.

    The angle is either given as an array or integrated from the speed by the trapezoidal
    rule exactly as :func:`angle_from_speed` does (same operations in the same order). A
    first pass stores the angle every ``interval`` samples, so that any stretch can later be
    recomputed bit for bit from the checkpoint before it; the same pass checks that the
    angle is finite and strictly increasing and records its smallest and largest step.

    Parameters
    ----------
    n : int
        Number of samples.
    interval : int
        Samples between checkpoints.
    time : numpy.ndarray, optional
        Sample instants [s]; default ``t0 + k / fs``.
    t0, fs : float
        Start time [s] and sample rate [Hz] when ``time`` is not given.
    angle : numpy.ndarray, optional
        Shaft angle [rad] per sample.
    rpm : numpy.ndarray, optional
        Speed [min-1] per sample (used when ``angle`` is not given).
    """

    def __init__(
        self,
        n: int,
        interval: int,
        *,
        time: np.ndarray | None = None,
        t0: float = 0.0,
        fs: float = 1.0,
        angle: Samples | None = None,
        rpm: Samples | None = None,
    ) -> None:
        self.n = n
        self.interval = interval
        self._time = time
        self._t0 = t0
        self._fs = fs
        self._angle = angle
        self._rpm = rpm
        self._checkpoints = np.empty(-(-n // interval))
        self._cache: dict[int, np.ndarray] = {}
        d_min, d_max = np.inf, -np.inf
        th = np.zeros(1)
        for k in range(self._checkpoints.size):
            a = k * interval
            b = min(n, a + interval + 1)
            if angle is None:
                th = self._integrate(a, b, float(th[-1]))
            else:
                th = np.asarray(angle[a:b], dtype=float)
                if not np.all(np.isfinite(th)):
                    i = a + int(np.flatnonzero(~np.isfinite(th))[0])
                    raise ValueError(
                        f"angle: non-finite value (NaN or inf) at sample {i}; only finite "
                        "values are admissible"
                    )
            self._checkpoints[k] = th[0]
            d = np.diff(th)
            if d.size == 0:
                continue
            if np.any(d <= 0):
                i = a + int(np.flatnonzero(d <= 0)[0])
                raise ValueError(
                    f"angle must be strictly increasing (speed > 0); it is not between samples "
                    f"{i} and {i + 1} (t = {self.time(i, i + 1)[0]:.6g} s); trim standstill or "
                    "reversing parts first"
                )
            d_min, d_max = min(d_min, float(d.min())), max(d_max, float(d.max()))
        self.first = float(self._checkpoints[0])
        self.last = float(th[-1])
        self.step_min, self.step_max = d_min, d_max

    def time(self, a: int, b: int) -> np.ndarray:
        """Sample instants ``[a, b)`` [s]."""
        if self._time is not None:
            return np.asarray(self._time[a:b], dtype=float)
        return self._t0 + np.arange(a, b) / self._fs

    def _integrate(self, a: int, b: int, start: Any) -> np.ndarray:
        """Angle of samples ``[a, b)`` given the angle ``start`` of sample ``a``."""
        assert self._rpm is not None
        t = self.time(a, b)
        w = np.asarray(self._rpm[a:b], dtype=float) * (2.0 * np.pi / 60.0)
        inc = np.empty(b - a)
        inc[0] = start
        inc[1:] = np.diff(t) * (w[1:] + w[:-1]) / 2.0
        return np.cumsum(inc, out=inc)

    def _interval(self, k: int) -> np.ndarray:
        """Angle of the samples ``[k iv, (k + 1) iv]`` (``iv`` = interval), integrated from
        checkpoint ``k``; the last two are kept, since blocks progress through the record."""
        hit = self._cache.get(k)
        if hit is None:
            a = k * self.interval
            hit = self._integrate(a, min(self.n, a + self.interval + 1), self._checkpoints[k])
            if len(self._cache) >= 2:
                self._cache.pop(next(iter(self._cache)))
            self._cache[k] = hit
        return hit

    def angle(self, a: int, b: int) -> np.ndarray:
        """Shaft angle of samples ``[a, b)`` [rad].

        Integrated from the checkpoint before ``a``: the same additions in the same order as
        the first pass, so the values equal an integration over the whole record bit for bit.
        """
        if self._angle is not None:
            return np.asarray(self._angle[a:b], dtype=float)
        iv = self.interval
        ka, kb = a // iv, (b - 1) // iv
        if ka == kb:
            return self._interval(ka)[a - ka * iv : b - ka * iv]
        parts = [self._interval(ka)[a - ka * iv : iv]]
        parts += [self._interval(k)[:iv] for k in range(ka + 1, kb)]
        parts.append(self._interval(kb)[: b - kb * iv])
        return np.concatenate(parts)

    def span(self, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
        """Angle and time of the shortest stretch of samples bracketing ``[lo, hi]``.

        Linear interpolation in the stretch therefore equals interpolation in the whole
        record for every angle in ``[lo, hi]``.
        """
        ck = self._checkpoints
        ka = max(0, int(np.searchsorted(ck, lo, side="right")) - 1)
        kb = int(np.searchsorted(ck, hi, side="left"))
        a = ka * self.interval
        b = self.n if kb >= ck.size else min(self.n, kb * self.interval + 1)
        th = self.angle(a, b)
        i0 = max(0, int(np.searchsorted(th, lo, side="right")) - 1)
        i1 = min(th.size, int(np.searchsorted(th, hi, side="left")) + 1)
        return th[i0:i1], self.time(a + i0, a + i1)


def _settling_length(sos: np.ndarray, tol: float = 1e-17) -> int:
    """Samples after which a unit error in any state of the filter ``sos`` is below ``tol``."""
    n_sec = sos.shape[0]
    z = np.zeros((n_sec, 2 * n_sec, 2))  # free responses from each unit state, side by side
    for i in range(2 * n_sec):
        z[i // 2, i, i % 2] = 1.0
    chunk = 4096
    zeros = np.zeros((2 * n_sec, chunk))
    last, start = -1, 0
    while True:  # the responses decay geometrically: stop after a chunk entirely below tol
        y, z = scipy.signal.sosfilt(sos, zeros, axis=-1, zi=z)
        above = np.flatnonzero(np.max(np.abs(y), axis=0) > tol)
        if above.size == 0:
            return last + 2
        last, start = start + int(above[-1]), start + chunk


class _Lowpassed:
    """A record after the zero-phase time-domain low-pass, computed block-wise.

    Equals ``scipy.signal.sosfiltfilt(sos, x)`` (odd extension of ``3 * ntaps`` samples at
    both ends, steady-state initial conditions) without holding the filtered record. The
    forward pass is exact: its state is stored every ``interval`` samples as the record is
    traversed and a stretch is refiltered from the stored state before it. The backward pass
    of a stretch starts :func:`_settling_length` samples after its end, where the error of
    its starting state has decayed below 1e-17 of that state, or at the end of the record,
    where it starts exactly as ``sosfiltfilt`` does.
    """

    def __init__(self, x: np.ndarray, sos: np.ndarray | None, interval: int) -> None:
        self._x = x
        self.n = x.shape[-1]
        self._sos = sos
        self._interval = interval
        if sos is None:
            return
        n_sec = sos.shape[0]
        ntaps = 2 * n_sec + 1 - min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum()))
        self._pad = 3 * ntaps
        if self.n <= self._pad:
            raise ValueError(
                f"needs more than {self._pad} samples for the anti-alias low-pass; the record "
                f"has {self.n}"
            )
        self._zi = scipy.signal.sosfilt_zi(sos).reshape(n_sec, *([1] * (x.ndim - 1)), 2)
        self._settle = _settling_length(sos)
        left = 2.0 * self._float(0, 1) - np.asarray(x[..., self._pad : 0 : -1], dtype=float)
        _, z = scipy.signal.sosfilt(sos, left, axis=-1, zi=self._zi * left[..., :1])
        self._states = [z]  # forward state before sample k * interval

    def _float(self, a: int, b: int) -> np.ndarray:
        return np.asarray(self._x[..., a:b], dtype=float)

    def _forward(self, a: int, e: int) -> tuple[np.ndarray, np.ndarray]:
        """Forward-filtered samples ``[a, e)`` and the state after sample ``e - 1``."""
        assert self._sos is not None
        iv = self._interval
        k = min(a // iv, len(self._states) - 1)
        pos, z = k * iv, self._states[k]
        parts = []
        while pos < e:
            stop = min(e, len(self._states) * iv)
            y, z = scipy.signal.sosfilt(self._sos, self._float(pos, stop), axis=-1, zi=z)
            if stop > a:
                parts.append(y[..., max(0, a - pos) :])
            if stop == len(self._states) * iv and stop < self.n:
                self._states.append(z)
            pos = stop
        return np.concatenate(parts, axis=-1), z

    def get(self, a: int, b: int) -> np.ndarray:
        """Low-passed samples ``[a, b)`` (float64)."""
        if self._sos is None:
            return self._float(a, b)
        e = min(self.n, b + self._settle)
        y, z = self._forward(a, e)
        if e == self.n:  # the end of the record: odd extension as sosfiltfilt
            right = 2.0 * self._float(self.n - 1, self.n) - np.asarray(
                self._x[..., -2 : -(self._pad + 2) : -1], dtype=float
            )
            tail, _ = scipy.signal.sosfilt(self._sos, right, axis=-1, zi=z)
            y = np.concatenate([y, tail], axis=-1)
        back, _ = scipy.signal.sosfilt(self._sos, y[..., ::-1], axis=-1, zi=self._zi * y[..., -1:])
        return back[..., ::-1][..., : b - a]


class AngleResampler:
    """Alias-free resampling of a record onto constant angle increments, block by block.

    See the module docstring for the three steps. :meth:`block` returns any range of output
    samples; it resamples only the stretch of the record that range needs: the fine angle
    grid is extended by the half length of the angle-domain FIR on both sides, the time
    samples by the half length of the sinc interpolator, and the low-pass by its settling
    length (see :class:`_Lowpassed`), so that consecutive blocks reproduce the unchunked
    computation to rounding.

    Parameters
    ----------
    x : numpy.ndarray
        Signal, time along the last axis (checked finite).
    track : Track
        Time axis and angle of ``x``.
    fs : float
        Sample rate [Hz].
    spr : int
        Output samples per revolution (checked).
    max_order : float
        Highest order kept (checked).
    block : int
        Largest number of output samples, and of time samples, handled at once.
    """

    def __init__(
        self, x: np.ndarray, track: Track, fs: float, spr: int, max_order: float, block: int
    ) -> None:
        self.track = track
        self.fs = fs
        self.samples_per_rev = spr
        self.max_order = max_order
        self.lead = x.shape[:-1]
        n_min = track.step_min * (fs / (2.0 * np.pi))  # shaft frequency [Hz]
        n_max = track.step_max * (fs / (2.0 * np.pi))
        # 1) time-domain low-pass
        fc = 1.25 * max_order * n_max
        sos = None
        if fc < 0.45 * fs:
            sos = scipy.signal.butter(8, fc, fs=fs, output="sos")
            f_top = 1.5 * fc  # above this the Butterworth (applied twice) is below -56 dB
        else:
            f_top = 0.5 * fs
        # 2) oversampled angle grid
        o_top = f_top / n_min
        over = max(1, int(np.ceil((o_top + spr / 2.0) / spr)))
        if over > _MAX_OVERSAMPLING:
            raise ValueError(
                f"speed range too wide for alias-free resampling: shaft frequency {n_min:.4g} "
                f"to {n_max:.4g} Hz needs {over}x angular oversampling (max "
                f"{_MAX_OVERSAMPLING}); raise min_rpm (leaves out the slow start or end of the "
                "record) or lower max_order"
            )
        self.signal = _Lowpassed(x, sos, max(_MIN_INTERVAL, block))
        self.oversampling = over
        fine = spr * over
        self.dphi = 2.0 * np.pi / fine
        n_fine = np.floor((track.last - track.first) / self.dphi) + 1.0
        limit = MIN_ANGLE_LIMIT + MAX_ANGLE_PER_TIME_SAMPLE * track.n
        if not n_fine <= limit:  # also catches inf and NaN
            raise ValueError(
                f"rpm/angle, fs, samples_per_rev: {track.n} time samples turning "
                f"{(track.last - track.first) / (2 * np.pi):.6g} revolutions at "
                f"{spr} x {over} (oversampling) samples per revolution need {n_fine:.6g} angle "
                f"samples; admissible: at most {MAX_ANGLE_PER_TIME_SAMPLE} per time sample "
                f"(+ {MIN_ANGLE_LIMIT}); check the units of the speed reference and fs, or "
                "lower samples_per_rev"
            )
        self.n_fine = int(n_fine)
        self.t_first = float(track.time(0, 1)[0])
        # 3) angle-domain anti-alias FIR for the decimation by `over`
        self.fir: np.ndarray | None = None
        if over > 1:
            width = (spr / 2.0 - max_order) / (fine / 2.0)
            if width > 0:
                numtaps, beta = scipy.signal.kaiserord(80.0, width)
                numtaps |= 1
                self.fir = scipy.signal.firwin(
                    numtaps, (max_order + spr / 2.0) / 2.0, window=("kaiser", beta), fs=fine
                )
            else:  # max_order == spr / 2: plain Nyquist cut
                self.fir = scipy.signal.firwin(20 * over + 1, spr / 2.0, fs=fine)
        self.n_out = -(-self.n_fine // over)
        # output samples whose time span is at most `block` samples of the record
        self._piece = max(1, min(block, int(block * spr * track.step_min / (2.0 * np.pi))))

    def angle(self, j0: int, j1: int) -> np.ndarray:
        """Angle of output samples ``[j0, j1)`` [rad]."""
        over = self.oversampling
        return self.track.first + self.dphi * np.arange(j0 * over, j1 * over, over)

    def _fine(self, f0: int, f1: int) -> tuple[np.ndarray, np.ndarray]:
        """Signal and time at the fine-grid angles ``[f0, f1)``."""
        first, dphi = self.track.first, self.dphi
        th, t = self.track.span(first + dphi * float(f0), first + dphi * float(f1 - 1))
        pos, tq = positions(th, t, first, dphi, f0, f1 - f0, self.t_first, self.fs)
        n = self.signal.n
        lo = max(0, int(np.floor(pos[0])) - HALF_TAPS + 1)
        hi = min(n, int(np.floor(pos[-1])) + HALF_TAPS + 1)
        data = self.signal.get(lo, hi)
        out = interpolate(data.reshape(-1, data.shape[-1]), pos, lo, n)
        return out.reshape(*self.lead, f1 - f0), tq

    def block(self, j0: int, j1: int) -> tuple[np.ndarray, np.ndarray]:
        """Output samples ``[j0, j1)`` (shape ``(..., j1 - j0)``) and their instants [s].

        The range is computed in pieces whose time span is at most ``block`` samples of the
        record, so the working memory stays bounded however many time samples a revolution
        holds.
        """
        if j1 - j0 <= self._piece:
            return self._piece_at(j0, j1)
        values = np.empty((*self.lead, j1 - j0))
        times = np.empty(j1 - j0)
        for p0 in range(j0, j1, self._piece):
            p1 = min(j1, p0 + self._piece)
            values[..., p0 - j0 : p1 - j0], times[p0 - j0 : p1 - j0] = self._piece_at(p0, p1)
        return values, times

    def _piece_at(self, j0: int, j1: int) -> tuple[np.ndarray, np.ndarray]:
        over = self.oversampling
        if self.fir is None:
            return self._fine(j0, j1)
        reach = -(-(self.fir.size // 2) // over)  # FIR half length in output samples
        f0 = max(0, j0 - reach) * over
        f1 = min(self.n_fine, (j1 - 1) * over + self.fir.size // 2 + 1)
        fine, tq = self._fine(f0, f1)
        dec = decimate(fine.reshape(-1, fine.shape[-1]), self.fir, over, j0 - f0 // over, j1 - j0)
        return dec.reshape(*self.lead, j1 - j0), tq[j0 * over - f0 :: over][: j1 - j0]


def check_sampling(samples_per_rev: Any, max_order: float | None) -> tuple[int, float]:
    if isinstance(samples_per_rev, bool) or not isinstance(samples_per_rev, int | np.integer):
        raise ValueError(f"samples_per_rev = {samples_per_rev!r} must be an integer >= 4")
    spr = int(samples_per_rev)
    if spr < 4:
        raise ValueError(f"samples_per_rev = {spr} is not admissible: must be >= 4")
    mo = spr / 2.56 if max_order is None else float(max_order)
    if not 0 < mo <= spr / 2:
        raise ValueError(
            f"max_order = {max_order!r} is not admissible: must be in (0, samples_per_rev/2 = "
            f"{spr / 2:g}]"
        )
    return spr, mo


def default_samples_per_rev(fs: float, rpm_max: float) -> tuple[int, float]:
    """Angular sampling matching ``fs`` at the top speed, and its max order ``spr / 2.56``."""
    fs, rpm_max = require_positive(fs, "fs"), require_positive(rpm_max, "rpm_max")
    spr = 2.0 * np.ceil(0.5 * fs / (rpm_max / 60.0))
    if not spr <= 2**62:
        raise ValueError(f"fs / rpm_max = {fs:g} Hz / {rpm_max:g} min-1 give {spr:g} samples per "
                         "revolution; admissible: at most 2**62 (check their units)")
    spr = int(spr)
    return max(spr, 8), max(spr, 8) / 2.56


@dataclass
class Tracking:
    """A record ready for order tracking: moving part, its resampler and what was done.

    Attributes
    ----------
    signal : Signal
        The checked input signal (whole record).
    reference : Reference
        Its speed reference (whole record).
    start, stop : int
        The samples ``[start, stop)`` analysed (standstill at the ends left out).
    resampler : AngleResampler
        Resampler of that part.
    notes : tuple of str
        What was left out, for the result.
    """

    signal: Signal
    reference: Reference
    start: int
    stop: int
    resampler: AngleResampler
    notes: tuple[str, ...]

    @property
    def rpm(self) -> np.ndarray | None:
        """Speed [min-1] of the analysed samples (``None`` for an angle reference)."""
        if self.reference.kind != "rpm":
            return None
        return self.reference.values[self.start : self.stop]

    @property
    def t0(self) -> float:
        """Time of the first analysed sample [s]."""
        return self.signal.t0 + self.start / self.signal.fs

    @property
    def angle(self) -> np.ndarray | None:
        """Angle [rad] of the analysed samples (``None`` for a speed reference)."""
        if self.reference.kind != "angle":
            return None
        return self.reference.values[self.start : self.stop]


def tracking(
    signal: Signal,
    reference: Reference,
    samples_per_rev: int | None,
    max_order: float | None,
    block: int,
    min_rpm: float | None,
    *,
    compact: bool = False,
    max_order_wanted: float | None = None,
) -> Tracking:
    """Leave out standstill at the ends, check the rest and set up its angular resampler.

    ``samples_per_rev`` defaults to ``2 ceil(fs / 2 / f_shaft,max)`` (about ``fs`` at the top
    speed), ``max_order`` to ``samples_per_rev / 2.56``. With ``compact`` and a given
    ``max_order`` (order spectra, maps and cuts, which never show orders above it), the
    default ``samples_per_rev`` is ``2 ceil(1.28 max_order)`` (at least 8), but never more
    than the former: the alias-free order range still ends at ``max_order`` and the
    resampling costs ``samples_per_rev`` per revolution, not ``fs`` per second.
    ``max_order_wanted`` (with neither ``max_order`` nor ``samples_per_rev``) is a default
    ``max_order`` lowered to ``samples_per_rev / 2.56`` of the former sampling where ``fs``
    does not reach it at the top speed.
    """
    require_instance(signal, Signal, "signal")
    require_instance(reference, Reference, "reference")
    fs = signal.fs
    a, b, _, note = moving_range(reference, fs, signal.t0, min_rpm)
    if b - a < 8:
        raise ValueError(
            f"{signal.name}: needs at least 8 samples for angular resampling ({b - a} moving)"
        )
    x = signal.values[..., a:b]
    t0 = signal.t0 + a / fs  # the time axis is taken as uniform: t0 + k / fs
    interval = max(_MIN_INTERVAL, block)
    values = reference.values[a:b]
    if reference.kind == "rpm":
        message = (
            "rpm must be > 0 for order tracking (angle strictly increasing); rpm[{i}] = {value}"
        )
        check_speed(values, b - a, message, offset=a)
        track = Track(b - a, interval, t0=t0, fs=fs, rpm=values)
        rpm_max = float(np.max(values))
    else:
        track = Track(b - a, interval, t0=t0, fs=fs, angle=values)
        rpm_max = track.step_max * fs * 60.0 / (2.0 * np.pi)
    mo: float | None
    if samples_per_rev is None:
        spr, mo_default = default_samples_per_rev(fs, rpm_max)
        if max_order is None and max_order_wanted is not None:
            max_order = min(float(max_order_wanted), mo_default)
        mo = mo_default if max_order is None else max_order
        if compact and max_order is not None and np.isfinite(float(max_order)):
            spr = min(spr, max(8, 2 * int(np.ceil(1.28 * float(max_order)))))
    else:
        spr, mo = samples_per_rev, max_order
    spr, mo = check_sampling(spr, mo)
    resampler = AngleResampler(x, track, fs, spr, mo, block)
    return Tracking(signal, reference, a, b, resampler, (note,) if note else ())


def check_speed(
    rpm: np.ndarray, n: int, message: str | None = None, *, offset: int = 0
) -> np.ndarray:
    """``rpm`` as an array of ``n`` finite values, checked block-wise (no copy).

    With ``message`` (formatted with ``i`` and ``value``; ``i`` counts from ``offset``) every
    value must also be > 0.
    """
    r = np.asarray(rpm)
    if r.ndim != 1 or r.size != n:
        raise ValueError(
            f"sample-count mismatch (x: {n}, rpm: {r.size}); rpm must be 1-D, one value per "
            "sample of x"
        )
    require_finite_blocks(r, "rpm")
    if message is None:
        return r
    for a in range(0, n, BLOCK_SAMPLES):
        bad = np.flatnonzero(r[a : a + BLOCK_SAMPLES] <= 0)
        if bad.size:
            i = a + int(bad[0])
            raise ValueError(message.format(i=i + offset, value=r[i]))
    return r


def resample_to_angle(
    x: Any,
    fs: Any = None,
    angle: Any = None,
    samples_per_rev: int | None = None,
    max_order: float | None = None,
    *,
    rpm: Any = None,
    time: Any = None,
    axis: int | None = None,
    min_rpm: float | None = None,
    units: str | None = None,
    name: str | None = None,
    block_size: int | None = None,
) -> AngleSignal:
    """Resample a time signal onto a constant-angle grid, with anti-alias filtering.

    The whole resampled signal is returned; :func:`analysis.orders.order_spectrum`,
    :func:`analysis.orders.order_cuts` and :func:`analysis.maps.rpm_order_map` use the same
    resampling block by block instead and never hold it.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal, one or several channels (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or give ``time``).
    angle : array_like, optional
        Shaft angle [rad] per sample; non-decreasing. Give ``angle`` or ``rpm``.
    samples_per_rev : int, optional
        Samples per revolution of the output (>= 4); default about ``fs`` at the top speed.
    max_order : float, optional
        Highest order to keep, ``<= samples_per_rev / 2``; default ``samples_per_rev / 2.56``.
    rpm : array_like, optional
        Shaft speed [min-1] per sample, integrated to the angle (trapezoidal rule).
    time : array_like, optional
        Uniform sample instants [s].
    axis : int, optional
        Time axis of a multi-dimensional array (required unless the reference's length
        singles it out).
    min_rpm : float, optional
        Standstill threshold [min-1]: slower samples at the start and end are left out and
        the result says so in ``notes``; default 2 % of the highest speed.
    units, name : str, optional
        Metadata of ``x`` (default from a DataArray, else ``"1"`` and ``"x"``).
    block_size : int, optional
        Output samples resampled per block (default 32768). Only the working memory depends
        on it; the result equals that of a single block to rounding.

    Returns
    -------
    AngleSignal
        Resampled signal, shape ``(*channels, angle)``, starting at the angle of the first
        analysed sample.
    """
    fs, time = time_or_rate(fs, time, "resample_to_angle")
    lengths = tuple(np.shape(r)[0] for r in (rpm, angle) if r is not None and np.ndim(r) == 1)
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name, lengths=lengths)
    ref = reference_input(rpm, angle, sig.n, required=True, signal=sig)
    assert ref is not None
    block = require_block_size(block_size)
    tr = tracking(sig, ref, samples_per_rev, max_order, block, min_rpm)
    res = tr.resampler
    require_size(
        8.0 * res.n_out * (np.prod(sig.lead, dtype=float) + 2),
        f"the resampled signal ({res.n_out} angle samples)", "rpm/angle, fs, samples_per_rev",
    )
    values = np.empty((*sig.lead, res.n_out))
    times = np.empty(res.n_out)
    for j0 in range(0, res.n_out, block):
        j1 = min(res.n_out, j0 + block)
        values[..., j0:j1], times[j0:j1] = res.block(j0, j1)
    return AngleSignal(
        res.angle(0, res.n_out),
        times,
        values,
        res.samples_per_rev,
        res.max_order,
        res.oversampling,
        sig.units,
        sig.name,
        sig.dims,
        sig.coords,
        ref.label,
        tr.notes,
    )
