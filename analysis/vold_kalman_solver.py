"""Banded least-squares solver of the Vold-Kalman filter (Givens rotations, square-root form).

The envelopes of :mod:`analysis.vold_kalman` minimise a sum of squares ``||A z - b||^2`` whose
matrix ``A`` stacks one *data row* per sample and one *structural row* per unknown and sample
(see that module). With the unknowns interleaved sample by sample, ``z = [u_0(0), v_0(0), ...,
u_{m-1}(0), v_{m-1}(0), u_0(1), ...]`` (``q = 2m`` real unknowns per sample), every row of
``A`` spans at most ``w = p q + 1`` consecutive columns, and so does every row of the
triangular factor ``R`` of ``A = Q R``.

:func:`solve` computes ``R`` and ``Q^T b`` row by row, rotating each row of ``A`` into ``R``
with Givens rotations in the order of its first column (sequential banded QR, Lawson & Hanson
1974, ch. 27), then solves ``R z = Q^T b`` by back substitution. It never forms the normal
equations ``A^T A z = A^T b``: their matrix holds ``1 + 6 r^2`` on its diagonal (second
difference), in which the data term 1 is lost to rounding once ``r^2`` reaches ``1e15``, i.e.
for a few Hz of bandwidth at 25.6 kHz. The factor ``R`` has the square root of their
condition number.

Memory. One pass stores ``R`` for the whole record: ``q n w`` floats plus ``q n`` per
right-hand side. When that exceeds the caller's budget, the record is cut into blocks: the
first pass keeps only the rows of ``R`` that are still being modified at each block start
(``p q`` rows, a *checkpoint*), the second pass recomputes each block's rows of ``R`` from its
checkpoint, last block first, and back-substitutes it. The arithmetic is the same in both
passes, so the blocked result equals the one-pass result bit for bit, for twice the
rotations.

References
----------
Lawson, C. L., & Hanson, R. J. (1974). *Solving Least Squares Problems*, ch. 27 (sequential
processing of banded least-squares problems). Prentice-Hall.
Golub, G. H., & Van Loan, C. F. (2013). *Matrix Computations*, 4th ed., 5.1.8-5.1.9 (Givens
rotations) and 5.3.7 (normal equations vs QR). Johns Hopkins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from analysis.checks import require_int, require_real_array, require_size
from analysis.jit import prepare_cache

prepare_cache(__file__)  # before the decorators below: numba resolves its cache folder there

__all__ = ["SolvePlan", "difference_coefficients", "minimum_working_bytes", "plan", "solve"]

_FLOAT = 8  # bytes per float64


#: Highest difference order the solver takes (the filter uses 2 or 3).
MAX_DIFFERENCE_ORDER = 8


def _order(p: object) -> int:
    v = require_int(p, "p", 1)
    if v > MAX_DIFFERENCE_ORDER:
        raise ValueError(f"p = {p!r} is not admissible: a difference order in 1 .. "
                         f"{MAX_DIFFERENCE_ORDER}")
    return v


def _counts(**values: object) -> list[int]:
    """Integers >= 1 (sample, order and signal counts), checked in the order given."""
    return [require_int(v, k, 1) for k, v in values.items()]


def difference_coefficients(p: int) -> np.ndarray:
    """Coefficients of the ``p``-th forward difference, ``(-1)^(p-i) C(p, i)``, i = 0..p
    (``p`` in 1 .. :data:`MAX_DIFFERENCE_ORDER`)."""
    p = _order(p)
    return np.array([(-1) ** (p - i) * math.comb(p, i) for i in range(p + 1)], dtype=float)


@dataclass(frozen=True)
class SolvePlan:
    """How :func:`solve` will run: block length and the memory it allocates.

    Attributes
    ----------
    block : int
        Samples per block (``n`` for one pass).
    n_blocks : int
        Number of blocks (1: one pass, no recomputation).
    working_bytes : int
        Bytes of the band of ``R``, the rotated right-hand sides and the checkpoints.
    """

    block: int
    n_blocks: int
    working_bytes: int


def _working_bytes(n: int, block: int, q: int, w: int, nrhs: int) -> int:
    rows = q * min(block, n) + (w - 1)
    n_blocks = -(-n // block)
    checkpoints = n_blocks * (w - 1) * (w + nrhs) if n_blocks > 1 else 0
    return (rows * (w + nrhs) + checkpoints) * _FLOAT


def minimum_working_bytes(n: int, m: int, p: int, nrhs: int) -> int:
    """Working memory [bytes] of the smallest blocks :func:`plan` uses (``64 p`` samples)."""
    n, m, nrhs = _counts(n=n, m=m, nrhs=nrhs)
    p = _order(p)
    q = 2 * m
    return _working_bytes(n, min(n, 64 * p), q, p * q + 1, nrhs)


def plan(n: int, m: int, p: int, nrhs: int, budget: float) -> SolvePlan | None:
    """Block length for ``n`` samples, ``m`` orders, difference order ``p`` and ``nrhs``
    right-hand sides within ``budget`` bytes of working memory; ``None`` if even blocks of
    ``64 p`` samples do not fit."""
    n, m, nrhs = _counts(n=n, m=m, nrhs=nrhs)
    p = _order(p)
    if isinstance(budget, bool | np.bool_) or not isinstance(budget, int | float | np.number):
        raise TypeError(f"budget must be a number of bytes; got {type(budget).__name__}")
    if np.isnan(budget):
        raise ValueError("budget = nan is not admissible: a number of bytes")
    q = 2 * m
    w = p * q + 1
    if _working_bytes(n, n, q, w, nrhs) <= budget:
        return SolvePlan(n, 1, _working_bytes(n, n, q, w, nrhs))
    smallest = 64 * p
    if n <= smallest or _working_bytes(n, smallest, q, w, nrhs) > budget:
        return None
    lo, hi = smallest, n  # largest block that fits: bisection on a monotone size
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if _working_bytes(n, mid, q, w, nrhs) <= budget:
            lo = mid
        else:
            hi = mid
    return SolvePlan(lo, -(-n // lo), _working_bytes(n, lo, q, w, nrhs))


@numba.njit(cache=True, error_model="numpy")  # no zero-division checks: rho > 0 when used
def _rotate_in(rb, rhs, buf, rr, j, stop, base, w, nrhs):  # pragma: no cover - compiled
    """Rotate the row ``buf[0:w]`` (first column ``j``) and its right-hand side ``rr`` into
    the rows of ``R`` held in ``rb[J - base]`` until it lands in an empty row or vanishes.

    ``buf`` has ``2 w`` places: the row slides along it (offset ``o``) instead of being
    shifted after every rotation.
    """
    o = 0
    while j < stop:
        a = buf[o]
        if a != 0.0:
            jr = j - base
            d = rb[jr, 0]
            if d == 0.0:  # empty row of R: the row becomes it (diagonal made positive)
                sg = 1.0 if a > 0.0 else -1.0
                for i in range(w):
                    rb[jr, i] = sg * buf[o + i]
                for c in range(nrhs):
                    rhs[jr, c] = sg * rr[c]
                return
            rho = math.sqrt(d * d + a * a)
            cs = d / rho
            sn = a / rho
            rb[jr, 0] = rho
            for i in range(1, w):
                ri = rb[jr, i]
                xi = buf[o + i]
                rb[jr, i] = cs * ri + sn * xi
                buf[o + i] = cs * xi - sn * ri
            for c in range(nrhs):
                ri = rhs[jr, c]
                xi = rr[c]
                rhs[jr, c] = cs * ri + sn * xi
                rr[c] = cs * xi - sn * ri
        else:
            empty = True
            for i in range(1, w):
                if buf[o + i] != 0.0:
                    empty = False
                    break
            if empty:
                return
        o += 1
        if o == w:
            for i in range(w):
                buf[i] = buf[w + i]
                buf[w + i] = 0.0
            o = 0
        j += 1


@numba.njit(cache=True, error_model="numpy")
def _forward(angle, orders, shafts, x, rows, coef, s0, s1, rb, rhs, base):  # pragma: no cover
    """Rotate the data and structural rows of samples ``s0 .. s1-1`` into ``R``.

    ``rb``/``rhs`` hold the rows ``base ..`` of ``R`` and of the rotated right-hand sides.
    """
    m = orders.size
    n = angle.shape[1]
    nrhs = x.shape[0]
    p = coef.size - 1
    q = 2 * m
    w = p * q + 1
    stop = q * n
    buf = np.zeros(2 * w)
    rr = np.zeros(nrhs)
    for s in range(s0, s1):
        for i in range(2 * w):
            buf[i] = 0.0
        for k in range(m):
            th = orders[k] * angle[shafts[k], s]
            buf[2 * k] = math.cos(th)
            buf[2 * k + 1] = -math.sin(th)
        for c in range(nrhs):
            rr[c] = x[c, s]
        _rotate_in(rb, rhs, buf, rr, s * q, stop, base, w, nrhs)
        if s + p < n:
            for jj in range(q):
                for i in range(2 * w):
                    buf[i] = 0.0
                for a in range(p + 1):
                    buf[a * q] = rows[jj // 2] * coef[a]
                for c in range(nrhs):
                    rr[c] = 0.0
                _rotate_in(rb, rhs, buf, rr, s * q + jj, stop, base, w, nrhs)


@numba.njit(cache=True, error_model="numpy")
def _back(rb, rhs, base, j0, j1, n_unknowns, out, s0):  # pragma: no cover - compiled
    """Back substitution of the rows ``j0 .. j1-1`` (the solution of the rows from ``j1`` on
    is already in ``rhs``); envelopes ``u + i v`` of their samples into ``out[c, k, s]``.

    Returns the smallest diagonal element of ``R`` met (0 for a singular system).
    """
    w = rb.shape[1]
    nrhs = rhs.shape[1]
    m = out.shape[1]
    q = 2 * m
    smallest = np.inf
    for j in range(j1 - 1, j0 - 1, -1):
        jr = j - base
        d = rb[jr, 0]
        smallest = min(smallest, d)
        top = min(w, n_unknowns - j)
        for c in range(nrhs):
            acc = rhs[jr, c]
            for i in range(1, top):
                acc -= rb[jr, i] * rhs[jr + i, c]
            rhs[jr, c] = acc / d
    for c in range(nrhs):
        for j in range(j0, j1, 2):
            s = j // q
            k = (j - s * q) // 2
            out[c, k, s] = complex(rhs[j - base, c], rhs[j + 1 - base, c])
    return smallest


def solve(
    angle: np.ndarray,
    orders: np.ndarray,
    shafts: np.ndarray,
    x: np.ndarray,
    rows: np.ndarray,
    p: int,
    block: int,
) -> tuple[np.ndarray, float]:
    """Envelopes ``a_k = u_k + i v_k`` minimising the stacked least-squares problem.

    Parameters
    ----------
    angle : ndarray, shape (n_shafts, n)
        Shaft angles [rad].
    orders : ndarray, shape (m,)
        Order of each envelope; its carrier is ``orders[k] * angle[shafts[k]]``.
    shafts : ndarray of int64, shape (m,)
        Shaft (row of ``angle``) of each order.
    x : ndarray, shape (nrhs, n)
        Signals (one right-hand side each; they share the factorisation).
    rows : ndarray, shape (m,)
        Weight of the structural rows of order ``k`` (applied to ``u_k`` and ``v_k`` alike).
    p : int
        Difference order of the structural equation.
    block : int
        Samples per block (``>= n``: one pass).

    Returns
    -------
    envelopes : ndarray, complex, shape (nrhs, m, n)
        ``u + i v`` for every signal, order and sample.
    smallest_pivot : float
        Smallest diagonal element of ``R`` (0 or tiny: the system is singular).
    """
    angle = np.ascontiguousarray(require_real_array(angle, "angle", ndim=2))
    x = np.ascontiguousarray(require_real_array(x, "x", ndim=2))
    orders = np.ascontiguousarray(require_real_array(orders, "orders", ndim=1))
    rows = np.ascontiguousarray(require_real_array(rows, "rows", ndim=1))
    sh = np.asarray(shafts)
    if sh.dtype.kind not in "iu" or sh.ndim != 1:
        raise TypeError(f"shafts must be a 1-D array of integers; got dtype {sh.dtype}, shape "
                        f"{sh.shape}")
    m = orders.size
    nrhs, n = x.shape
    if angle.shape[1] != n or rows.size != m or sh.size != m:
        raise ValueError(f"shapes disagree: angle {angle.shape}, x {x.shape} (same number of "
                         f"samples), orders {orders.shape}, shafts {sh.shape}, rows "
                         f"{rows.shape} (one per order)")
    if sh.size and not (sh.min() >= 0 and sh.max() < angle.shape[0]):
        raise ValueError(f"shafts must index the rows of angle (0 .. {angle.shape[0] - 1})")
    shafts = np.ascontiguousarray(sh, dtype=np.int64)
    p = _order(p)
    block = require_int(block, "block", 1)
    q = 2 * m
    w = p * q + 1
    total = q * n
    coef = difference_coefficients(p)
    block = min(block, n)
    cap = q * block + (w - 1)
    require_size(16.0 * nrhs * m * n + 8.0 * cap * (w + nrhs), f"the envelopes ({nrhs} x {m} "
                 f"x {n} complex) and the band of R", "x, orders, block")
    out = np.empty((nrhs, m, n), dtype=complex)
    rb = np.zeros((cap, w))
    rhs = np.zeros((cap, nrhs))
    if block >= n:
        _forward(angle, orders, shafts, x, rows, coef, 0, n, rb, rhs, 0)
        return out, float(_back(rb, rhs, 0, 0, total, total, out, 0))
    starts = list(range(0, n, block))
    states = []
    for s0 in starts:  # first pass: the checkpoint at every block start
        s1 = min(n, s0 + block)
        states.append((rb[: w - 1].copy(), rhs[: w - 1].copy()))
        _forward(angle, orders, shafts, x, rows, coef, s0, s1, rb, rhs, q * s0)
        k = q * (s1 - s0)
        rb[: w - 1] = rb[k : k + w - 1]
        rhs[: w - 1] = rhs[k : k + w - 1]
        rb[w - 1 :] = 0.0
        rhs[w - 1 :] = 0.0
    carry = np.zeros((w - 1, nrhs))
    smallest = np.inf
    for s0, (r_state, b_state) in zip(reversed(starts), reversed(states), strict=True):
        s1 = min(n, s0 + block)  # second pass, last block first: recompute, back-substitute
        rb[:] = 0.0
        rhs[:] = 0.0
        rb[: w - 1] = r_state
        rhs[: w - 1] = b_state
        _forward(angle, orders, shafts, x, rows, coef, s0, s1, rb, rhs, q * s0)
        k = q * (s1 - s0)
        rhs[k : k + w - 1] = carry  # solution of the next block's first rows
        low = _back(rb, rhs, q * s0, q * s0, q * s1, total, out, s0)
        smallest = min(smallest, float(low))
        carry = rhs[: w - 1].copy()
    return out, smallest
