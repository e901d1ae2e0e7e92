"""Band-limited analytic signals of a long record, computed block by block in the frequency
domain: the filter bank under :mod:`analysis.kurtogram` and :mod:`analysis.envelope`.

**Band.** A band ``[low, high]`` [Hz] is selected in the DFT with the gain

    G(f) = nu((f - a) / w + 1/2) * nu((b - f) / w + 1/2)    (f >= 0; 0 for f < 0),

``a = low`` and ``b = high`` the centres of a rising and a falling transition of width
``w = TRANSITION * (high - low)``; ``nu(u) = u^4 (35 - 84 u + 70 u^2 - 20 u^3)`` on
``[0, 1]`` (0 below, 1 above) is the smooth step of Meyer's wavelet (``nu(u) + nu(1 - u) =
1``, three continuous derivatives). The gain is 1/2 at ``low`` and ``high`` (the -6 dB
edges), so adjacent bands sum to 1 (a partition of unity), and its impulse response decays
as ``t^-5``: below 1e-6 of its peak after ``9 / w`` seconds (measured). A transition that
would reach below 0 Hz or above ``fs / 2`` is moved inside (``a = w/2``, ``b = fs/2 - w/2``),
so that the gain is 0 there: an analytic signal whose gain jumps at 0 Hz or at Nyquist has
the Hilbert transform's ``1/t`` tail and could not be cut into blocks.

**Analytic band signal.** Only positive frequencies are kept, doubled: the band signal is
``z(t) = x_b(t) + i H[x_b](t)`` (``x_b`` the band-passed record, ``H`` the Hilbert
transform), so that ``|z|^2`` is the squared envelope of ``x_b`` (a sine of amplitude ``A``
in the pass band gives ``|z|^2 = A^2``). The band's bins are moved to base band (multiplied
by ``exp(-2 pi i f_c t)``, which leaves ``|z|`` unchanged) and inverse-transformed with a
length that decimates ``z`` by an integer factor ``D``: the output is ``z`` at the record's
samples ``0, D, 2D, ...``, exactly (no decimation filter is needed: the band is the filter).

**Blocks.** A record longer than one block is cut into blocks of ``Nb`` samples that overlap
by twice a margin ``m >= 10 / w`` seconds (the impulse response has decayed to 1e-6 there):
each block is transformed, filtered and inverse-transformed, and only its central
``Nb - 2 m`` samples are kept, so the blocks reproduce the whole-record linear filter to
about 1e-6 of the band signal's peak (overlap-save; Oppenheim & Schafer 2010, sec. 8.7).
Outside the record the signal is taken as zero (the record's mean is removed first). The
memory is a few blocks, whatever the length of the record.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from analysis.checks import (
    require_finite_blocks,
    require_instance,
    require_int,
    require_positive,
    require_real,
)
from analysis.fft import RowIfft, next_fast_len, rfft_plan
from analysis.jit import prepare_cache

prepare_cache(__file__)  # before the decorators below: numba resolves its cache folder there

__all__ = [
    "MARGIN_TRANSITIONS",
    "TRANSITION",
    "Band",
    "BlockSpectra",
    "band_moments",
    "envelope_decimation",
    "smooth_step",
    "squared_envelope_samples",
]

#: Transition width of a band as a fraction of its width (each edge).
TRANSITION = 0.25
#: Block margin in units of ``1 / transition width`` (the impulse response is below 1e-6).
MARGIN_TRANSITIONS = 10.0
_MIN_BLOCK = 1 << 18  # samples per block at least (when the record is longer)
_MARGINS_PER_BLOCK = 16  # a block is at least this many margins long


def smooth_step(u: np.ndarray | float) -> np.ndarray:
    """Meyer's smooth step ``nu(u) = u^4 (35 - 84 u + 70 u^2 - 20 u^3)`` on ``[0, 1]``
    (0 below, 1 above); ``nu(u) + nu(1 - u) = 1``."""
    v = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    return v**4 * (35.0 - 84.0 * v + 70.0 * v * v - 20.0 * v**3)


@dataclass(frozen=True)
class Band:
    """A frequency band with smooth edges (module docstring).

    Attributes
    ----------
    low, high : float
        The -6 dB edges [Hz], ``0 <= low < high``.
    transition : float
        Width of each smooth edge [Hz] (default ``TRANSITION * (high - low)``).
    """

    low: float
    high: float
    transition: float = float("nan")

    def __post_init__(self) -> None:
        numbers = (int, float, np.number)
        values = (self.low, self.high, self.transition)
        if any(isinstance(v, bool) or not isinstance(v, numbers) for v in values):
            raise ValueError(
                f"band = ({self.low!r}, {self.high!r}), transition = {self.transition!r}: "
                "not admissible, the edges and the transition must be numbers [Hz]"
            )
        lo, hi = float(self.low), float(self.high)
        if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo < hi):
            raise ValueError(
                f"band = ({self.low!r}, {self.high!r}) Hz is not admissible: needs finite "
                "0 <= low < high"
            )
        object.__setattr__(self, "low", lo)
        object.__setattr__(self, "high", hi)
        tw = float(self.transition)
        if math.isnan(tw):
            tw = TRANSITION * (hi - lo)
        if not (math.isfinite(tw) and 0.0 < tw <= hi - lo):
            raise ValueError(
                f"transition = {self.transition!r} Hz is not admissible: must be in "
                f"(0, {hi - lo:g}] (the band's width)"
            )
        object.__setattr__(self, "transition", tw)

    @property
    def centre(self) -> float:
        """Centre frequency [Hz]."""
        return 0.5 * (self.low + self.high)

    @property
    def width(self) -> float:
        """Width between the -6 dB edges [Hz]."""
        return self.high - self.low

    @property
    def support(self) -> tuple[float, float]:
        """Frequencies [Hz] outside which the gain is 0 (negative frequencies get none)."""
        return self.low - 0.5 * self.transition, self.high + 0.5 * self.transition

    def edges(self, fs: float | None = None) -> tuple[float, float]:
        """Centres ``(a, b)`` [Hz] of the rising and the falling transition: ``low`` and
        ``high``, except that a transition reaching below 0 Hz (or above ``fs / 2``) is moved
        inside, to end there (module docstring)."""
        a, b = self.low, self.high
        half = 0.5 * self.transition
        a = max(a, half)
        if fs is not None:
            b = min(b, 0.5 * float(fs) - half)
        return a, b

    def gain(self, f: np.ndarray | float, fs: float | None = None) -> np.ndarray:
        """Gain ``G(f)`` at frequencies ``f`` [Hz] (0 for ``f < 0``; with ``fs``, the
        transitions clipped at ``fs / 2`` as the filter bank applies them)."""
        f = np.asarray(f, dtype=float)
        a, b = self.edges(fs)
        tw = self.transition
        g = smooth_step((f - a) / tw + 0.5) * smooth_step((b - f) / tw + 0.5)
        return np.where(f >= 0.0, g, 0.0)


# ------------------------------------------------------------------------------- kernels


@numba.njit(cache=True, inline="always")
def _step(u):  # pragma: no cover - compiled
    """Meyer's smooth step on [0, 1] (0 below, 1 above)."""
    if u <= 0.0:
        return 0.0
    if u >= 1.0:
        return 1.0
    return u * u * u * u * (35.0 - 84.0 * u + 70.0 * u * u - 20.0 * u * u * u)


@numba.njit(cache=True, error_model="numpy")  # no zero-division checks (none can occur)
def _fill_rows(X, out, k_lo, k_hi, k_shift, rise, fall, tw, scale):  # pragma: no cover
    """Row ``i`` of ``out``: bins ``k_lo[i]..k_hi[i]`` of ``X`` times the band gain times
    ``scale``, at index ``(k - k_shift[i]) mod L``; every other element 0.

    The gain is ``nu((k - rise)/tw + 1/2) nu((fall - k)/tw + 1/2)``; ``rise``, ``fall``
    (transition centres) and ``tw`` (transition width) are in bins.
    """
    rows, length = out.shape
    for i in range(rows):
        first = (k_lo[i] - k_shift[i]) % length
        used = k_hi[i] - k_lo[i] + 1
        for m in range(used, length):  # the indices not written below
            out[i, (first + m) % length] = 0.0
        inv = 1.0 / tw[i]
        j = first
        for k in range(k_lo[i], k_hi[i] + 1):
            u1 = (k - rise[i]) * inv + 0.5
            u2 = (fall[i] - k) * inv + 0.5
            if u1 >= 1.0 and u2 >= 1.0:
                out[i, j] = X[k] * scale
            else:
                out[i, j] = X[k] * (_step(u1) * _step(u2) * scale)
            j += 1
            if j == length:
                j = 0


@numba.njit(cache=True)
def _moments(z, j0, j1, s2, s4):  # pragma: no cover - compiled
    """Add ``sum |z[i, j]|^2`` and ``sum |z[i, j]|^4`` over ``j0 <= j < j1`` to ``s2[i]``,
    ``s4[i]``."""
    for i in range(z.shape[0]):
        a2 = 0.0
        a4 = 0.0
        for j in range(j0, j1):
            v = z[i, j]
            p = v.real * v.real + v.imag * v.imag
            a2 += p
            a4 += p * p
        s2[i] += a2
        s4[i] += a4


@numba.njit(cache=True)
def _power(z, j0, out, o0, count):  # pragma: no cover - compiled
    """``out[o0 + j] = |z[j0 + j]|^2`` for ``0 <= j < count``."""
    for j in range(count):
        v = z[j0 + j]
        out[o0 + j] = v.real * v.real + v.imag * v.imag


# -------------------------------------------------------------------------------- blocks


def _smooth_below(n: int) -> int:
    """Largest 5-smooth integer (factors 2, 3, 5) <= ``n`` (``n >= 1``)."""
    best = 1
    p2 = 1
    while p2 <= n:
        p3 = p2
        while p3 <= n:
            p5 = p3
            while p5 <= n:
                best = max(best, p5)
                p5 *= 5
            p3 *= 3
        p2 *= 2
    return best


class BlockSpectra:
    """The record in overlapping blocks, each transformed once (overlap-save).

    Parameters
    ----------
    x : numpy.ndarray
        The record, 1-D (any real dtype; its mean is removed, in float64).
    unit : int
        Block length, margin and hop are multiples of ``unit`` (the decimation factors used).
    margin : int
        Samples at least on each side of a block's kept part.
    workers : int, optional
        FFT threads.

    Attributes
    ----------
    n, block, margin, hop, n_blocks : int
        Record length, block length ``Nb``, margin ``m``, hop ``Nb - 2 m`` and number of blocks.
    """

    def __init__(
        self, x: np.ndarray, *, unit: int, margin: int, workers: int | None = None
    ) -> None:
        self.x = x
        self.n = int(x.shape[-1])
        self.unit = int(unit)
        self.margin = self.unit * max(1, -(-int(margin) // self.unit))
        single = self.n + 2 * self.margin
        target = max(_MIN_BLOCK, _MARGINS_PER_BLOCK * self.margin)
        if single <= target:  # one block holds the record with its margins
            q = next_fast_len(-(-single // self.unit))
        else:
            q = 1 << max(0, math.ceil(math.log2(target / self.unit)))
        self.block = self.unit * q
        self.hop = self.block - 2 * self.margin
        self.n_blocks = -(-self.n // self.hop)
        self.workers = workers
        self.mean = float(np.mean(x, dtype=np.float64))

    def __iter__(self) -> Iterator[tuple[np.ndarray, int, int]]:
        """Yield ``(X, first, keep)``: the rfft ``X`` of block ``b`` (the plan's own output
        buffer, valid until the next block) and its kept part, ``keep`` samples from the
        global sample ``first = b * hop`` (local sample ``margin``)."""
        plan = rfft_plan(1, self.block, workers=self.workers)
        buf = plan.input[0]
        for b in range(self.n_blocks):
            start = b * self.hop - self.margin
            a, e = max(0, start), min(self.n, start + self.block)
            buf[: a - start] = 0.0
            np.subtract(self.x[a:e], self.mean, out=buf[a - start : e - start])
            buf[e - start :] = 0.0
            yield plan.execute()[0], b * self.hop, min(self.hop, self.n - b * self.hop)


#: Largest sample magnitude :func:`band_moments` takes (``|z|^4`` summed stays finite).
MAX_MOMENT_SAMPLE = 1e70
#: Largest sample magnitude :func:`squared_envelope_samples` takes.
MAX_ENVELOPE_SAMPLE = 1e140


def _record(x: Any, fs: Any, bound: float) -> float:
    """Check the record ``x`` (1-D, real, finite, ``|x| <= bound``) and return ``fs``."""
    require_instance(x, np.ndarray, "x")
    if x.dtype.kind not in "iuf":
        raise TypeError(f"x must hold real numbers; got dtype {x.dtype}")
    if x.ndim != 1 or x.size < 2:
        raise ValueError(f"x must be a 1-D record of at least 2 samples; got shape {x.shape}")
    require_finite_blocks(x, "x", bound)
    return require_positive(require_real(fs, "fs"), "fs")


def _decimation(d: Any, n: int, name: str) -> int:
    v = require_int(d, name, 1)
    if v > n:
        raise ValueError(f"{name} = {d!r} is not admissible: 1 .. {n} (the record's length)")
    return v


def _check_ringing(margin: int, n: int, fs: float, band: Band) -> None:
    """Refuse a band whose filter rings longer than the record (checked before the blocks,
    whose size follows from it, are allocated)."""
    if margin > n:
        raise ValueError(
            f"band = ({band.low:.6g}, {band.high:.6g}) Hz is too narrow for a record of "
            f"{n / fs:.6g} s: its filter rings for {margin / fs:.6g} s "
            f"({MARGIN_TRANSITIONS:g} / transition of {band.transition:.6g} Hz); widen the "
            "band or give a longer record"
        )


def _band_bins(band: Band, nb: int, fs: float) -> tuple[int, int, int, float, float, float]:
    """First and last DFT bin of ``band``'s support, the bin moved to 0 Hz (the centre), and
    the rising and falling transition centres and the transition width, in bins of an
    ``nb``-point transform."""
    scale = nb / fs
    lo, hi = band.support
    a, b = band.edges(fs)
    k_lo = max(0, math.ceil(lo * scale))
    k_hi = min(nb // 2, math.floor(hi * scale))
    return k_lo, k_hi, round(band.centre * scale), a * scale, b * scale, band.transition * scale


def band_moments(
    x: np.ndarray,
    fs: float,
    levels: Sequence[Sequence[Band]],
    decimations: Sequence[int],
    *,
    workers: int | None = None,
) -> tuple[list[np.ndarray], list[np.ndarray], list[int]]:
    """Sums of ``|z|^2`` and ``|z|^4`` of the analytic signal of every band of every level.

    The samples within ``MARGIN_TRANSITIONS / w`` of either end of the record (``w`` the
    band's transition width) are left out: there the band signal holds the filter's response
    to the start and the end of the record, a transient that would dominate a band with
    little energy (e.g. above an anti-alias filter: 50-60 dB down in the CWRU records).

    Parameters
    ----------
    x : numpy.ndarray
        The record, 1-D.
    fs : float
        Sample rate [Hz].
    levels : sequence of sequences of Band
        The bands of each level.
    decimations : sequence of int
        Decimation of each level's band signals (each band's support must be narrower than
        ``fs / D``).
    workers : int, optional
        FFT threads.

    Returns
    -------
    s2, s4 : list of numpy.ndarray
        Per level, per band: ``sum |z|^2`` and ``sum |z|^4`` over the band signal's samples.
    counts : list of int
        Per level, the number of samples summed.

    Raises
    ------
    ValueError
        A level keeps no sample between its end guards.
    """
    fs = _record(x, fs, MAX_MOMENT_SAMPLE)
    if not isinstance(levels, Sequence) or not isinstance(decimations, Sequence) or not levels \
            or len(levels) != len(decimations):
        raise ValueError("levels and decimations must be sequences of equal, non-zero length "
                         "(one decimation per level)")
    decimations = [_decimation(d, x.size, f"decimations[{k}]") for k, d in enumerate(decimations)]
    for k, bands in enumerate(levels):
        if not isinstance(bands, Sequence) or not bands:
            raise ValueError(f"levels[{k}] must be a non-empty sequence of Band")
        for j, b in enumerate(bands):
            require_instance(b, Band, f"levels[{k}][{j}]")
    unit = math.lcm(*decimations)
    if unit > x.size:
        raise ValueError(f"decimations {decimations}: their least common multiple {unit} "
                         f"exceeds the record's {x.size} samples")
    narrowest = min((b for bands in levels for b in bands), key=lambda b: b.transition)
    margin = math.ceil(MARGIN_TRANSITIONS * fs / narrowest.transition)
    _check_ringing(margin, x.shape[-1], fs, narrowest)
    blocks = BlockSpectra(x, unit=unit, margin=margin, workers=workers)
    nb = blocks.block
    ifft = RowIfft(nb, workers=workers)
    tables = []
    guards = []
    for bands, d in zip(levels, decimations, strict=True):
        rows = len(bands)
        length = nb // d
        tw = min(b.transition for b in bands)
        guards.append(math.ceil(MARGIN_TRANSITIONS * fs / tw / d))
        cols = [_band_bins(b, nb, fs) for b in bands]
        k_lo, k_hi, shift = (np.array([c[m] for c in cols], dtype=np.int64) for m in range(3))
        rise, fall, width = (np.array([c[m] for c in cols]) for m in range(3, 6))
        if np.any(k_hi - k_lo + 1 > length):
            raise ValueError("a band is wider than its decimated rate (internal error)")
        tables.append((rows, d, k_lo, k_hi, shift, rise, fall, width))
        assert length * d == nb
    s2 = [np.zeros(len(bands)) for bands in levels]
    s4 = [np.zeros(len(bands)) for bands in levels]
    counts = [0 for _ in levels]
    scale = 2.0 / nb
    for X, first, keep in blocks:
        for li, (rows, d, k_lo, k_hi, shift, rise, fall, width) in enumerate(tables):
            total = -(-blocks.n // d)
            g0 = first // d  # global index of the block's first kept output sample
            g1 = g0 + -(-keep // d)
            a, e = max(g0, guards[li]), min(g1, total - guards[li])
            if e <= a:
                continue
            view = ifft.rows(rows)
            _fill_rows(X, view, k_lo, k_hi, shift, rise, fall, width, scale)
            z = ifft.execute(rows)
            j0 = blocks.margin // d - g0
            _moments(z, j0 + a, j0 + e, s2[li], s4[li])
            counts[li] += e - a
    if min(counts) < 1:
        raise ValueError("the record is too short for its narrowest bands (no sample between "
                         "the guards at its ends)")
    return s2, s4, counts


def envelope_decimation(band: Band, fs: float) -> int:
    """Largest 5-smooth decimation ``D`` whose rate ``fs / D`` carries the squared envelope
    of ``band`` without aliasing (``fs / D >= 2 * support width``); the band must start
    below the Nyquist frequency ``fs / 2``."""
    require_instance(band, Band, "band")
    fs = require_positive(require_real(fs, "fs"), "fs")
    if not band.support[0] < 0.5 * fs:
        raise ValueError(f"band = ({band.low:g}, {band.high:g}) Hz is not admissible for fs = "
                         f"{fs:g} Hz: it must start below fs / 2")
    lo, hi = band.support
    width = min(hi, 0.5 * fs) - max(lo, 0.0)
    return _smooth_below(max(1, math.floor(fs / (2.0 * width))))


def squared_envelope_samples(
    x: np.ndarray, fs: float, band: Band, decimation: int, *, workers: int | None = None
) -> np.ndarray:
    """Squared envelope ``|z|^2`` of ``band`` at the record's samples ``0, D, 2D, ...``.

    Parameters
    ----------
    x : numpy.ndarray
        The record, 1-D.
    fs : float
        Sample rate [Hz].
    band : Band
        The band.
    decimation : int
        ``D`` (see :func:`envelope_decimation`).
    workers : int, optional
        FFT threads.

    Returns
    -------
    numpy.ndarray
        ``ceil(n / D)`` samples, in the squared units of ``x``.
    """
    fs = _record(x, fs, MAX_ENVELOPE_SAMPLE)
    require_instance(band, Band, "band")
    d = _decimation(decimation, x.size, "decimation")
    margin = math.ceil(MARGIN_TRANSITIONS * fs / band.transition)
    _check_ringing(margin, x.shape[-1], fs, band)
    blocks = BlockSpectra(x, unit=d, margin=margin, workers=workers)
    nb = blocks.block
    length = nb // d
    k_lo, k_hi, shift, rise, fall, width = _band_bins(band, nb, fs)
    if k_hi < k_lo:
        raise ValueError(
            f"band ({band.low:g}, {band.high:g}) Hz holds no frequency line of the record "
            f"(lines every {fs / nb:.4g} Hz up to {fs / 2:g} Hz)"
        )
    if k_hi - k_lo + 1 > length:
        raise ValueError("the band is wider than the decimated rate (internal error)")
    ifft = RowIfft(length, workers=workers)
    out = np.empty(-(-blocks.n // d))
    args = (np.array([k_lo]), np.array([k_hi]), np.array([shift]), np.array([rise]),
            np.array([fall]), np.array([width]))  # fmt: skip
    for X, first, keep in blocks:
        view = ifft.rows(1)
        _fill_rows(X, view, *args, 2.0 / nb)
        z = ifft.execute(1)[0]
        count = -(-keep // d)
        _power(z, blocks.margin // d, out, first // d, count)
    return out
