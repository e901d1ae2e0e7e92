"""Compiled kernels of the angular resampling: band-limited interpolation and FIR decimation.

:func:`interpolate` evaluates a record at fractional sample positions with the 24-tap
Kaiser-windowed sinc of :mod:`analysis.resample` (beta 7, rows normalised to unit DC gain:
amplitude error below 0.01 dB up to 0.4 ``fs``). The kernel's 24 weights are smooth functions
of the fractional position ``f`` in ``[0, 1)``; they are tabulated once as polynomials of
degree 4 on 256 pieces of ``[0, 1)`` (Chebyshev fits, converted to powers of the local
variable; 240 kB), which reproduce the exact kernel to 2e-15, so that a weight costs four
multiply-adds instead of a Bessel series, a sine and a division. The weights of a position
are computed once and applied to every channel. :func:`decimate` is the zero-phase
polyphase FIR that low-passes the fine angle grid and keeps every ``over``-th sample (as
``scipy.signal.resample_poly(x, 1, over, window=fir)``).

The kernels are ``numba.njit(cache=True, error_model="numpy")`` (no zero-division checks;
none can occur), without ``fastmath``; they loop over channels in the outer loop and
accumulate in a fixed order, so each channel's result is the same whether it is processed
alone or with others, bit for bit.
"""

from __future__ import annotations

import functools
import math

import numba
import numpy as np

from analysis.checks import require_int, require_real, require_real_array, require_size
from analysis.jit import prepare_cache

prepare_cache(__file__)  # before the decorators below: numba resolves its cache folder there

__all__ = ["HALF_TAPS", "compile_ahead", "decimate", "interpolate", "kernel_table", "positions"]

#: Half length of the interpolation kernel (taps -11 .. 12 around the position).
HALF_TAPS = 12
_BETA = 7.0
_PIECES = 256
_DEGREE = 4
#: Most pieces and highest degree :func:`kernel_table` accepts.
MAX_PIECES = 1024
MAX_DEGREE = 8
#: Largest magnitude of a position, an index or a count (exact in float64 and int64).
MAX_INDEX = 2**52


def _bounded_int(value: object, name: str, low: int, high: int) -> int:
    """``value`` as an int in ``[low, high]``; a ValueError naming ``name`` otherwise."""
    if type(value) is int and low <= value <= high:  # the per-block calls: no further work
        return value
    v = require_int(value, name, low)
    if v > high:
        raise ValueError(f"{name} = {value!r} is not admissible: an integer in {low} .. {high}")
    return v


def _real(a: object, name: str, ndims: tuple[int, ...]) -> np.ndarray:
    """``a`` as a C-contiguous float64 array of one of ``ndims`` dimensions (no NaN check)."""
    if (type(a) is np.ndarray and a.dtype == np.float64 and a.ndim in ndims
            and a.flags.c_contiguous):
        return a  # the per-block calls: nothing to convert
    arr = require_real_array(a, name, min_size=0, finite=False)
    if arr.ndim not in ndims:
        raise ValueError(f"{name} must have {' or '.join(map(str, ndims))} dimension(s); got "
                         f"shape {arr.shape}")
    return np.ascontiguousarray(arr)


def exact_kernel(frac: np.ndarray) -> np.ndarray:
    """Normalised Kaiser-sinc weights ``(len(frac), 24)`` for taps ``-11 .. 12``."""
    taps = np.arange(-HALF_TAPS + 1, HALF_TAPS + 1)
    tau = np.asarray(frac, dtype=float)[:, None] - taps[None, :]
    z = np.clip(1.0 - (tau / HALF_TAPS) ** 2, 0.0, None)
    h = np.i0(_BETA * np.sqrt(z)) * np.sinc(tau)
    return h / h.sum(axis=1, keepdims=True)


def kernel_table(pieces: int = _PIECES, degree: int = _DEGREE) -> np.ndarray:
    """Polynomial coefficients ``(pieces, degree + 1, 24)`` of the kernel weights.

    On piece ``p`` (``f`` in ``[p / P, (p + 1) / P)``) with ``u = 2 (f P - p) - 1`` in
    ``[-1, 1)``, weight ``k`` is ``sum_d table[p, d, k] u**d``. ``pieces`` lies in
    ``1 .. MAX_PIECES`` and ``degree`` in ``1 .. MAX_DEGREE``.
    """
    pieces = _bounded_int(pieces, "pieces", 1, MAX_PIECES)
    degree = _bounded_int(degree, "degree", 1, MAX_DEGREE)
    nodes = np.cos(np.pi * (np.arange(3 * degree) + 0.5) / (3 * degree))
    # every piece is fitted at the same nodes u: one least-squares operator (Chebyshev basis,
    # then to powers of u) maps a piece's sampled weights to its polynomial coefficients
    cheb_fit = np.linalg.pinv(np.polynomial.chebyshev.chebvander(nodes, degree))
    to_powers = np.zeros((degree + 1, degree + 1))  # column j: T_j(u) in powers of u
    for j in range(degree + 1):
        mono = np.polynomial.chebyshev.cheb2poly(np.eye(degree + 1)[j])
        to_powers[: mono.size, j] = mono
    fit = to_powers @ cheb_fit  # (degree + 1, nodes)
    f = (np.arange(pieces)[:, None] + 0.5 + 0.5 * nodes[None, :]) / pieces
    weights = exact_kernel(f.ravel()).reshape(pieces, nodes.size, 2 * HALF_TAPS)
    return np.ascontiguousarray(np.einsum("dn,pnk->pdk", fit, weights))


@functools.cache
def _default_table() -> np.ndarray:
    # computed on first use, not on import; kept writeable:
    # a read-only array would be another numba signature (a second compilation)
    return kernel_table()


@numba.njit(cache=True, inline="always")
def _sum4(prod, n):  # pragma: no cover - compiled
    # sum of prod[:n] (n a multiple of 4) as four partial sums over k = 4 m + q in increasing m,
    # then (a0 + a1) + (a2 + a3): a fixed order with no serial chain of additions (inlined in
    # the caller's loop by numba)
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    a3 = 0.0
    for kk in range(n // 4):
        k = 4 * kk
        a0 += prod[k]
        a1 += prod[k + 1]
        a2 += prod[k + 2]
        a3 += prod[k + 3]
    return (a0 + a1) + (a2 + a3)


@numba.njit(cache=True, error_model="numpy")  # no zero-division checks (none can occur)
def _interpolate(x, start, n_total, pos, table, out):  # pragma: no cover - compiled
    n_ch = x.shape[0]
    pieces = table.shape[0]
    n_taps = table.shape[2]
    w = np.empty(n_taps)
    prod = np.empty(n_taps)
    for i in range(pos.size):
        ib = int(pos[i])
        if pos[i] < ib:  # floor for negative positions
            ib -= 1
        frac = pos[i] - ib
        p = int(frac * pieces)
        if p >= pieces:
            p = pieces - 1
        u = 2.0 * (frac * pieces - p) - 1.0
        tp = table[p]
        c0 = tp[0]
        c1 = tp[1]
        c2 = tp[2]
        c3 = tp[3]
        c4 = tp[4]
        first = ib - HALF_TAPS + 1
        inside = first >= 0 and first + n_taps <= n_total
        if inside and n_ch == 1:  # one channel: weights and products in one pass
            seg = x[0, first - start : first - start + n_taps]
            for k in range(n_taps):
                prod[k] = ((((c4[k] * u + c3[k]) * u + c2[k]) * u + c1[k]) * u + c0[k]) * seg[k]
            out[0, i] = _sum4(prod, n_taps)
            continue
        for k in range(n_taps):  # Horner, degree 4 (the table's), vectorised over the taps
            w[k] = (((c4[k] * u + c3[k]) * u + c2[k]) * u + c1[k]) * u + c0[k]
        if inside:  # products in one vectorised pass, then the four partial sums
            o = first - start
            for c in range(n_ch):
                seg = x[c, o : o + n_taps]
                for k in range(n_taps):
                    prod[k] = w[k] * seg[k]
                out[c, i] = _sum4(prod, n_taps)
        else:  # near the ends of the record: samples beyond them equal the end samples
            for c in range(n_ch):
                for k in range(n_taps):
                    j = first + k
                    if j < 0:
                        j = 0
                    elif j > n_total - 1:
                        j = n_total - 1
                    prod[k] = w[k] * x[c, j - start]
                out[c, i] = _sum4(prod, n_taps)


def interpolate(
    x: np.ndarray, pos: np.ndarray, start: int = 0, n_total: int | None = None
) -> np.ndarray:
    """Band-limited interpolation of ``x`` (channels, samples) at fractional positions ``pos``.

    ``x`` holds the samples ``start, start + 1, ...`` of a record of ``n_total`` samples
    (default: ``x`` is the whole record) and must cover every sample the kernel reaches
    (``floor(pos) - 11 .. floor(pos) + 12``, clipped to the record); samples beyond the ends of
    the record are taken equal to the end samples.

    The positions are checked before the compiled kernel runs (it has no bounds checks):
    finite, at most :data:`MAX_INDEX` in magnitude, and every sample they reach inside ``x``
    (a :class:`ValueError` otherwise).

    Returns
    -------
    numpy.ndarray
        Shape ``(channels, len(pos))``, float64.
    """
    xa = _real(x, "x", (1, 2))
    if xa.shape[-1] < 1:
        raise ValueError("x holds no samples")
    x2 = xa.reshape(-1, xa.shape[-1])
    start = _bounded_int(start, "start", 0, MAX_INDEX)
    n = start + x2.shape[1] if n_total is None else _bounded_int(n_total, "n_total", 1,
                                                                  MAX_INDEX)
    if start + x2.shape[1] > n:
        raise ValueError(f"x holds samples {start} .. {start + x2.shape[1] - 1}, beyond the "
                         f"record of n_total = {n} samples")
    p = _real(pos, "pos", (0, 1)).reshape(-1)
    if p.size:
        lo, hi = float(p.min()), float(p.max())
        if not (lo >= -MAX_INDEX and hi <= MAX_INDEX):  # also NaN
            raise ValueError(f"pos must be finite positions within +-{MAX_INDEX:g} samples; "
                             f"got {lo:.6g} .. {hi:.6g}")
        first = max(0, min(n - 1, int(np.floor(lo)) - HALF_TAPS + 1))
        last = min(n - 1, max(0, int(np.floor(hi)) + HALF_TAPS))
        if first < start or last >= start + x2.shape[1]:
            raise ValueError(f"pos = {lo:.6g} .. {hi:.6g} reaches samples {first} .. {last}; "
                             f"x holds {start} .. {start + x2.shape[1] - 1} only")
    out = np.empty((x2.shape[0], p.size))
    _interpolate(x2, start, n, p, _default_table(), out)
    return out


@numba.njit(cache=True, error_model="numpy")  # no zero-division checks (none can occur)
def _positions(th, t, first, dphi, f0, t_first, fs, pos, tq):  # pragma: no cover - compiled
    # tq[i] = numpy.interp(first + dphi * (f0 + i), th, t), the same operations in the same
    # order, found by one forward sweep (the angles increase); pos = (tq - t_first) * fs
    m = th.size
    j = 0
    for i in range(pos.size):
        phi = first + dphi * float(f0 + i)
        if phi >= th[m - 1]:
            v = t[m - 1]
        elif phi < th[0]:
            v = t[0]
        else:
            while th[j + 1] <= phi:
                j += 1
            slope = (t[j + 1] - t[j]) / (th[j + 1] - th[j])
            v = slope * (phi - th[j]) + t[j]
        tq[i] = v
        pos[i] = (v - t_first) * fs


def positions(
    th: np.ndarray, t: np.ndarray, first: float, dphi: float, f0: int, count: int,
    t_first: float, fs: float,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Instants and fractional sample positions of the angles ``first + dphi * (f0 + i)``.

    ``th`` (increasing) and ``t`` are the angle and time of the samples around them; the
    instants are their linear interpolation (as :func:`numpy.interp`), the positions
    ``(instant - t_first) * fs``.

    Returns
    -------
    pos, tq : numpy.ndarray
        Positions [samples] and instants [s], ``count`` each.
    """
    tha, ta = _real(th, "th", (1,)), _real(t, "t", (1,))
    if tha.size < 1 or ta.size != tha.size:
        raise ValueError(f"th and t must be non-empty and of equal length; got {tha.size} and "
                         f"{ta.size}")
    count = _bounded_int(count, "count", 0, MAX_INDEX)
    f0 = _bounded_int(f0, "f0", -MAX_INDEX, MAX_INDEX)
    first, dphi, t_first, fs = (v if type(v) is float and math.isfinite(v) else require_real(v, k)
                                for k, v in (("first", first), ("dphi", dphi),
                                             ("t_first", t_first), ("fs", fs)))
    require_size(16.0 * count, f"{count} positions and instants", "count")
    pos = np.empty(count)
    tq = np.empty(count)
    _positions(tha, ta, first, dphi, f0, t_first, fs, pos, tq)
    return pos, tq


@numba.njit(cache=True, error_model="numpy")  # no zero-division checks (none can occur)
def _decimate(fine, fir, over, first, out):  # pragma: no cover - compiled
    # Output j is sum_k fir[k] fine[(first + j) over + half - k]. With half - k = q over + r
    # (0 <= r < over) that is sum_k fir[k] s_r[first + j + q], s_r[m] = fine[m over + r]: the
    # fine samples are split into `over` contiguous phase streams once, and every tap adds a
    # contiguous, vectorisable multiple of one stream to a chunk of outputs (taps in a fixed
    # order, so the result does not depend on the chunking or on the other channels).
    n_ch = fine.shape[0]
    n_fine = fine.shape[1]
    n_taps = fir.size
    n_out = out.shape[1]
    half = (n_taps - 1) // 2
    q_min = (half - (n_taps - 1)) // over
    q_max = half // over
    length = n_out + q_max - q_min
    streams = np.empty((over, length))
    chunk = 1024
    acc = np.empty(chunk)
    for c in range(n_ch):
        base = first + q_min
        for r in range(over):  # s_r[m] = fine[(base + m) over + r], zero beyond the ends
            m_lo = max(0, -base)
            m_hi = min(length, (n_fine - 1 - r) // over - base + 1)
            streams[r, :] = 0.0
            if m_hi > m_lo:
                g0 = (base + m_lo) * over + r
                for m in range(m_hi - m_lo):  # a loop, not a slice assignment: numba
                    # would compile its shape-mismatch message (~5 s at the first run)
                    streams[r, m_lo + m] = fine[c, g0 + m * over]
        for j0 in range(0, n_out, chunk):
            j1 = min(n_out, j0 + chunk)
            n = j1 - j0
            for j in range(n):
                acc[j] = 0.0
            a = acc[:n]
            for k in range(n_taps):
                d = half - k
                q = d // over
                r = d - q * over
                off = j0 + q - q_min
                seg = streams[r, off : off + n]  # slices: no index checks, vectorised
                f = fir[k]
                for j in range(n):
                    a[j] += f * seg[j]
            for j in range(n):
                out[c, j0 + j] = acc[j]


def decimate(fine: np.ndarray, fir: np.ndarray, over: int, first: int, count: int) -> np.ndarray:
    """Zero-phase FIR low-pass and decimation by ``over`` of ``fine`` (channels, samples).

    Output sample ``j`` is ``sum_k fir[k] fine[(first + j) over + (len(fir) - 1) / 2 - k]``,
    with zeros beyond the ends of ``fine`` (``len(fir)`` odd): samples ``first .. first +
    count - 1`` of ``scipy.signal.resample_poly(fine, 1, over, window=fir)``.
    """
    fa = _real(fine, "fine", (1, 2))
    f2 = fa.reshape(-1, fa.shape[-1])
    taps = _real(fir, "fir", (1,))
    if taps.size % 2 == 0:
        raise ValueError(f"fir must have an odd number of taps (zero phase); got {taps.size}")
    over = _bounded_int(over, "over", 1, MAX_INDEX)
    first = _bounded_int(first, "first", -MAX_INDEX, MAX_INDEX)
    count = _bounded_int(count, "count", 0, MAX_INDEX)
    length = count + taps.size // over + 2  # the phase streams of one channel
    require_size(8.0 * (f2.shape[0] * count + over * length), f"the output ({count} samples) "
                 f"and {over} phase streams", "count, over")
    out = np.empty((f2.shape[0], count))
    _decimate(f2, taps, over, first, out)
    return out


def compile_ahead() -> None:
    """Compile this module's kernels now, for the argument types :func:`interpolate`,
    :func:`positions` and :func:`decimate` pass (every array C-contiguous float64, integers
    int64), or load them from numba's cache: a second process can prepare the cache while
    the first one works."""
    f8, i8 = numba.float64, numba.int64
    a1, a2, a3 = (numba.types.Array(f8, d, "C") for d in (1, 2, 3))
    _interpolate.compile((a2, i8, i8, a1, a3, a2))
    _positions.compile((a1, a1, f8, f8, i8, f8, f8, a1, a1))
    _decimate.compile((a2, a1, i8, i8, a2))
