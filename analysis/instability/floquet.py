"""Floquet analysis of linear periodic systems ``M q'' + C q' + K(t) q = 0``.

The monodromy matrix is computed

* exactly, as an ordered product of matrix exponentials, for a piecewise-constant stiffness
  (:class:`PiecewiseConstant`, e.g. a rectangular mesh stiffness);
* as a product of exponentials on sub-steps aligned with the breakpoints of a stiffness that
  is smooth (typically linear) between them (:class:`PiecewiseSmooth`, e.g. a trapezoidal or
  tabulated mesh stiffness): the exponential midpoint rule, sub-steps allotted to the pieces by
  how much ``K`` changes over them and doubled until the largest multiplier converges. Every
  exponential is exact (scaling and squaring), so the step is sized by the variation of the
  stiffness, not by the highest natural frequency;
* by a fourth-order Magnus integrator with Richardson extrapolation and step doubling for a
  smooth stiffness callable (resolves the fastest mode: the reference for small systems).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.cf import cf_dataset
from analysis.checks import (
    require_finite,
    require_mass_matrix,
    require_positive,
    require_square,
)

__all__ = ["FloquetResult", "PiecewiseConstant", "PiecewiseSmooth", "floquet"]

StiffnessCallable = Callable[[float], Any]

_MAX_STEPS = 2**16
_MIDPOINT_START = 2  # sub-steps of the piece with the largest stiffness change, first pass
_MIDPOINT_MAX_SUBSTEPS = 2**17  # sub-steps of one period in the last pass at most (time bound)
_CHUNK = 2048  # exponentials formed at once (memory bound: CHUNK x (2n)^2 x 8 B per array)


@dataclass(frozen=True)
class PiecewiseConstant:
    """Piecewise-constant periodic stiffness matrix.

    Parameters
    ----------
    durations : array_like, shape (m,)
        Duration [s] of each constant piece, in order, starting at ``t = 0``.
    matrices : array_like, shape (m, n, n)
        Stiffness matrix [N/m] held during each piece.

    Notes
    -----
    The period of the description is ``sum(durations)``; :func:`floquet` checks that it equals
    the ``period`` argument. Rectangular gear-mesh stiffness (single/double tooth contact) is the
    typical use: the monodromy is then the exact product of matrix exponentials (the multi-DOF
    form of Meissner's transfer matrix, Meissner 1918; Richards 1983).
    """

    durations: np.ndarray
    matrices: np.ndarray

    def __post_init__(self) -> None:
        d = require_finite(self.durations, "durations")
        if d.ndim != 1:
            raise ValueError(f"durations must be one-dimensional; got shape {d.shape}")
        if np.any(d <= 0):
            raise ValueError("durations must all be > 0 (each piece needs a positive length)")
        k = require_finite(self.matrices, "matrices")
        if k.ndim == 2 and d.size == 1:
            k = k[None]
        if k.ndim != 3 or k.shape[0] != d.size or k.shape[1] != k.shape[2]:
            raise ValueError(
                f"matrices must have shape (m, n, n) with m = len(durations) = {d.size}; "
                f"got {k.shape}"
            )
        object.__setattr__(self, "durations", d)
        object.__setattr__(self, "matrices", k)

    @property
    def period(self) -> float:
        """Total duration [s] of one period."""
        return float(self.durations.sum())

    @property
    def size(self) -> int:
        """Number of degrees of freedom ``n``."""
        return int(self.matrices.shape[1])

    def __call__(self, t: float) -> np.ndarray:
        """Stiffness matrix at time ``t`` [s] (periodic continuation)."""
        tau = float(t) % self.period
        edges = np.cumsum(self.durations)
        idx = min(int(np.searchsorted(edges, tau, side="right")), edges.size - 1)
        return self.matrices[idx]

    def mean(self) -> np.ndarray:
        """Period-mean stiffness matrix [N/m]."""
        return np.tensordot(self.durations, self.matrices, axes=1) / self.period


@dataclass(frozen=True)
class PiecewiseSmooth:
    """Periodic stiffness matrix that is smooth between breakpoints, evaluated in batches.

    Parameters
    ----------
    edges : array_like, shape (m + 1,)
        Breakpoints [s]: ``edges[0] = 0``, ``edges[-1]`` the period, strictly increasing.
        Put an edge wherever ``K`` or its derivative jumps (e.g. every kink of a
        piecewise-linear stiffness table); between edges ``K`` should be smooth.
    evaluate : callable
        ``evaluate(times) -> (k, n, n)`` array: ``K`` at an array of ``k`` times [s] in
        ``[0, period]``.

    Notes
    -----
    :func:`floquet` forms the monodromy as the product of ``expm(A(t_j) h_j)`` over sub-steps
    (exponential midpoint rule, second order). Each piece gets sub-steps in proportion to the
    change of ``K`` over it (a constant piece one: exact); all sub-steps are halved pass by
    pass and two passes are combined by Richardson extrapolation until the largest multiplier
    has converged. With edges at every kink the error expands in even powers of the sub-step,
    whatever the highest natural frequency (each exponential is exact).
    """

    edges: np.ndarray
    evaluate: Callable[[np.ndarray], Any]

    def __post_init__(self) -> None:
        e = require_finite(self.edges, "edges")
        if e.ndim != 1 or e.size < 2:
            raise ValueError(f"edges must be a 1-D array of at least 2 times; got shape {e.shape}")
        if e[0] != 0.0 or np.any(np.diff(e) <= 0):
            raise ValueError("edges must start at 0 and increase strictly (the breakpoints of "
                             "one period)")
        if not callable(self.evaluate):
            raise ValueError("evaluate must be a callable times -> (k, n, n) array")
        object.__setattr__(self, "edges", e)

    @property
    def period(self) -> float:
        """The last edge: the period [s]."""
        return float(self.edges[-1])

    def matrices(self, times: Any) -> np.ndarray:
        """``K`` at ``times`` [s] as a ``(k, n, n)`` array (checked)."""
        t = np.atleast_1d(np.asarray(times, dtype=float))
        k = require_finite(self.evaluate(t), "K(t)")
        if k.ndim != 3 or k.shape[0] != t.size or k.shape[1] != k.shape[2]:
            raise ValueError(f"evaluate(times) must return shape ({t.size}, n, n); got {k.shape}")
        return k

    def __call__(self, t: float) -> np.ndarray:
        """Stiffness matrix at time ``t`` [s] (periodic continuation)."""
        return self.matrices([float(t) % self.period])[0]


@dataclass(frozen=True)
class FloquetResult:
    """Floquet multipliers and derived stability measures of one periodic system.

    Attributes
    ----------
    multipliers : ndarray, shape (2n,)
        Eigenvalues ``mu`` of the monodromy matrix, sorted by decreasing modulus.
    exponents : ndarray, shape (2n,)
        Floquet exponents ``ln(mu)/T`` [1/s] (principal branch of the logarithm).
    max_modulus : float
        ``max |mu|``.
    growth_rate : float
        ``ln(max |mu|)/T`` [1/s]; positive means exponential growth.
    stable : bool
        ``max |mu| <= 1 + tol``.
    monodromy : ndarray, shape (2n, 2n)
        State-transition matrix over one period for the state ``x = [q; q']``.
    period : float
        Period ``T`` [s].
    tol : float
        Tolerance used for ``stable``.
    det_monodromy : float
        ``det(monodromy)`` (real part).
    liouville_expected : float
        ``exp(-T tr(M^-1 C))`` (Liouville's formula).
    log_det_monodromy, log_liouville_expected : float
        ``ln|det(monodromy)|`` and ``-T tr(M^-1 C)``: the same check in logarithms, which
        stays meaningful when a long period (several mesh frequencies) underflows the
        determinant.
    method : str
        ``"exact"`` (matrix-exponential product), ``"midpoint"`` (product of exponentials on
        sub-steps of a :class:`PiecewiseSmooth` stiffness) or ``"magnus"``.
    n_steps : int
        Number of Magnus steps or midpoint sub-steps per period (0 for the exact product).
    error_estimate : float
        Estimated error: relative error of the monodromy (``"magnus"``), error of the largest
        multiplier modulus (``"midpoint"``: a fifteenth of the change between the last two
        Richardson values), 0 for the exact product.
    """

    multipliers: np.ndarray
    exponents: np.ndarray
    max_modulus: float
    growth_rate: float
    stable: bool
    monodromy: np.ndarray
    period: float
    tol: float
    det_monodromy: float
    liouville_expected: float
    method: str
    n_steps: int = 0
    error_estimate: float = 0.0
    log_det_monodromy: float = math.nan
    log_liouville_expected: float = math.nan
    extra: dict = field(default_factory=dict, repr=False)

    @property
    def liouville_error(self) -> float:
        """Relative deviation ``|det(Phi)/exp(-T tr(M^-1 C)) - 1|`` (should be ~rounding).

        Computed from the logarithms when they are known (no underflow on long periods).
        """
        if math.isfinite(self.log_det_monodromy) and math.isfinite(self.log_liouville_expected):
            return float(abs(math.expm1(self.log_det_monodromy - self.log_liouville_expected)))
        return float(abs(self.det_monodromy / self.liouville_expected - 1.0))

    def to_dataset(self):
        """Return the result as an :class:`xarray.Dataset` (CF attributes on every variable)."""
        import xarray as xr

        m = self.multipliers.size
        ds = xr.Dataset(
            {
                "multiplier_real": ("multiplier", self.multipliers.real,
                                    {"units": "1", "long_name": "Floquet multiplier, real part"}),
                "multiplier_imag": ("multiplier", self.multipliers.imag,
                                    {"units": "1",
                                     "long_name": "Floquet multiplier, imaginary part"}),
                "multiplier_modulus": ("multiplier", np.abs(self.multipliers),
                                       {"units": "1", "long_name": "Floquet multiplier modulus"}),
                "exponent_real": ("multiplier", self.exponents.real,
                                  {"units": "s-1",
                                   "long_name": "Floquet exponent, real part (growth rate)"}),
                "exponent_imag": ("multiplier", self.exponents.imag,
                                  {"units": "rad s-1",
                                   "long_name": "Floquet exponent, imaginary part"}),
                "monodromy": (("state_row", "state_col"), self.monodromy,
                              {"units": "1", "long_name": "monodromy matrix (state [q; dq/dt])"}),
                "max_modulus": ((), self.max_modulus,
                                {"units": "1", "long_name": "largest Floquet multiplier modulus"}),
                "growth_rate": ((), self.growth_rate,
                                {"units": "s-1", "long_name": "growth rate ln(max|mu|)/T"}),
                "period": ((), self.period, {"units": "s", "long_name": "period of K(t)"}),
                "liouville_error": ((), self.liouville_error,
                                    {"units": "1",
                                     "long_name": "relative Liouville check |det/expected - 1|"}),
            },
            coords={"multiplier": ("multiplier", np.arange(m),
                                   {"units": "1", "long_name": "multiplier index"})},
            attrs={"stable": int(self.stable), "tol": self.tol, "method": self.method,
                   "n_steps": self.n_steps, "error_estimate": self.error_estimate},
        )
        return cf_dataset(ds, title="Floquet multipliers", producer="analysis.instability.floquet")

    def plot(self, ax=None):
        """Plot the multipliers in the complex plane with the unit circle.

        Delegates to :func:`analysis.instability.plots.plot_floquet`.
        """
        from analysis.instability.plots import plot_floquet

        return plot_floquet(self, ax=ax)


def _state_matrices(minv: np.ndarray, c: np.ndarray, ks: np.ndarray) -> np.ndarray:
    """Batch of state matrices ``[[0, I], [-M^-1 K, -M^-1 C]]`` for stiffness batch ``ks``."""
    n = minv.shape[0]
    out = np.zeros((ks.shape[0], 2 * n, 2 * n))
    out[:, :n, n:] = np.eye(n)
    out[:, n:, :n] = -np.einsum("ij,tjk->tik", minv, ks)
    out[:, n:, n:] = -minv @ c
    return out


def _ordered_product(mats: np.ndarray) -> np.ndarray:
    """Return ``mats[-1] @ ... @ mats[1] @ mats[0]`` by pairwise (tree) reduction."""
    p = mats
    while p.shape[0] > 1:
        if p.shape[0] % 2:
            tail = p[-1:]
            p = np.concatenate([p[1:-1:2] @ p[0:-1:2], tail], axis=0)
        else:
            p = p[1::2] @ p[0::2]
    return p[0]


def _magnus4(a_nodes: np.ndarray, period: float, stride: int) -> np.ndarray:
    """Fourth-order Magnus propagator over one period from state matrices on a node grid.

    ``a_nodes`` holds ``A`` at ``2N + 1`` equispaced times; one step uses the nodes
    ``k, k + stride, k + 2 stride`` (Simpson nodes) so that several step sizes share samples.
    """
    a1 = a_nodes[0:-1:2 * stride]
    a2 = a_nodes[stride::2 * stride]
    a3 = a_nodes[2 * stride::2 * stride]
    h = period / a1.shape[0]
    b0 = (a1 + 4.0 * a2 + a3) / 6.0
    b1 = (a3 - a1) / 12.0
    omega = h * b0 + h * h * (b1 @ b0 - b0 @ b1)
    return _ordered_product(_expm_batch(omega))


def _expm_batch(x: np.ndarray) -> np.ndarray:
    """Matrix exponential of a batch ``(N, m, m)`` by scaling and squaring of a Taylor series.

    The common scaling ``2^-s`` brings every 1-norm below 1/4; the degree-14 Taylor remainder
    is then below ``0.25^15/15! < 1e-21`` relative, i.e. at rounding level.
    """
    norm = float(np.max(np.sum(np.abs(x), axis=-2))) if x.size else 0.0
    s = max(0, int(np.ceil(np.log2(norm / 0.25)))) if norm > 0.25 else 0
    y = x / 2.0**s
    eye = np.broadcast_to(np.eye(x.shape[-1]), x.shape)
    e = eye + y / 14.0
    for k in range(13, 0, -1):
        e = eye + (y @ e) / k
    for _ in range(s):
        e = e @ e
    return e


def _expm_each(x: np.ndarray) -> np.ndarray:
    """Matrix exponential of every matrix of a batch ``(N, m, m)``, each scaled on its own.

    Scaling and squaring of the degree-14 Taylor series as in :func:`_expm_batch`, but every
    matrix gets its own ``2^-s_i`` (1-norm below 1/4) and only its own ``s_i`` squarings, so a
    short piece is not over-squared because a long one shares the batch. Agrees with
    ``scipy.linalg.expm`` to rounding (tested) and is vectorised over the batch (scipy's
    batched ``expm`` loops in Python).
    """
    if x.shape[0] == 0:
        return x.copy()
    norm = np.max(np.sum(np.abs(x), axis=-2), axis=-1)
    s = np.where(norm > 0.25, np.ceil(np.log2(np.maximum(norm, 1e-300) / 0.25)), 0.0)
    s = s.astype(np.int64)
    y = x / np.exp2(s)[:, None, None]
    eye = np.broadcast_to(np.eye(x.shape[-1]), x.shape)
    e = eye + y / 14.0
    for k in range(13, 0, -1):
        e = eye + (y @ e) / k
    for k in range(int(s.max())):
        idx = np.flatnonzero(s > k)
        e[idx] = e[idx] @ e[idx]
    return e


@dataclass(frozen=True)
class _Balanced:
    """Balanced coordinates of ``x' = A(t) x``: mass-normalised ``p = L^T q`` (``M = L L^T``),
    velocities scaled by ``w = sqrt(max ||L^-1 K L^-T||_F)``.

    ``A~ = [[0, w I], [-L^-1 K L^-T / w, -L^-1 C L^-T]]`` is similar to ``A`` (same
    multipliers) and has entries of the order of the highest natural frequency in every block
    (instead of spanning ``1e5`` in mixed units), so scaling and squaring needs few squarings
    and stays accurate to rounding.
    """

    li: np.ndarray
    ct: np.ndarray
    w: float

    @classmethod
    def of(cls, m: np.ndarray, c: np.ndarray, k_sample: np.ndarray, period: float) -> _Balanced:
        li = np.linalg.inv(np.linalg.cholesky(m))
        kt = li @ k_sample @ li.T
        norm2 = float(np.max(np.einsum("tij,tij->t", kt, kt))) if m.shape[0] else 0.0
        w = norm2**0.25 if norm2 > 0 else 1.0 / period
        return cls(li, li @ c @ li.T, w)

    def states(self, ks: np.ndarray) -> np.ndarray:
        """Balanced state matrices of a batch ``(k, n, n)`` of stiffness matrices."""
        n = self.li.shape[0]
        a = np.zeros((ks.shape[0], 2 * n, 2 * n))
        a[:, :n, n:] = self.w * np.eye(n)
        a[:, n:, :n] = -(self.li @ ks @ self.li.T) / self.w
        a[:, n:, n:] = -self.ct
        return a

    def unbalance(self, phit: np.ndarray) -> np.ndarray:
        """The monodromy in ``x = [q; q']`` from the balanced one."""
        n = self.li.shape[0]
        t = np.zeros((2 * n, 2 * n))
        t_inv = np.zeros((2 * n, 2 * n))
        lt = np.linalg.inv(self.li.T)
        t[:n, :n] = self.li.T
        t[n:, n:] = self.w * self.li.T
        t_inv[:n, :n] = lt
        t_inv[n:, n:] = lt / self.w
        return t @ phit @ t_inv


def _exact_monodromy(m: np.ndarray, c: np.ndarray, k: PiecewiseConstant) -> np.ndarray:
    """Monodromy ``expm(A_m tau_m) ... expm(A_1 tau_1)`` of a piecewise-constant stiffness.

    The product is formed in balanced coordinates (:class:`_Balanced`): the similarity
    transform leaves the multipliers unchanged and brings ``||A~ tau||`` to the order of
    ``w tau`` (a few units instead of ``1e5`` in mixed units), so few squarings are needed and
    the exponentials are accurate to ``1e-14``; the result is transformed back to ``x = [q; q']``.
    """
    bal = _Balanced.of(m, c, k.matrices, k.period)
    a = bal.states(k.matrices) * k.durations[:, None, None]
    return bal.unbalance(_ordered_product(_expm_each(a)))


def _midpoint_monodromy(m: np.ndarray, c: np.ndarray, k: PiecewiseSmooth, atol: float,
                        margin: float = 0.0) -> tuple[np.ndarray, int, float]:
    """Product of ``expm(A(t_j) h_j)`` over sub-steps of a :class:`PiecewiseSmooth` stiffness.

    Piece ``i`` gets ``c_i = max(1, ceil(START v_i / max v))`` equal sub-steps in the first
    pass, ``v_i`` the change of ``K`` over it (edge to edge, plus four times the deviation of its
    midpoint from the chord: zero for a linear piece); every further pass halves every
    sub-step (``c_i 2^k``). The exponential midpoint rule is symmetric, so its error expands in
    even powers of the sub-step and two passes give the Richardson value
    ``R_k = Phi_k + (Phi_k - Phi_k-1)/3`` (fourth order). Passes continue until two Richardson
    values differ in ``max|mu|`` by at most ``15 atol`` (the estimate of the last one's error
    is that difference / 15) or by at most ``15 margin |max|mu| - 1|`` (the distance from the
    stability limit then settles the verdict and the growth rate to that relative accuracy),
    or until :data:`_MIDPOINT_MAX_SUBSTEPS` would be exceeded. The exponentials are formed in
    chunks of :data:`_CHUNK`, so memory does not grow with the number of sub-steps.

    Returns
    -------
    (ndarray, int, float)
        Monodromy in ``[q; q']``, sub-steps of the last pass, error estimate of ``max|mu|``.
    """
    edges = k.edges
    n_piece = edges.size - 1
    dur = np.diff(edges)
    mids = 0.5 * (edges[:-1] + edges[1:])
    both = k.matrices(np.concatenate([edges, mids]))
    if both.shape[1] != m.shape[0]:
        raise ValueError(f"K (PiecewiseSmooth) matrices are {both.shape[1:]} but M is "
                         f"{m.shape}; all matrices must have the same size")
    ke, km = both[: n_piece + 1], both[n_piece + 1:]
    chord = ke[1:] - ke[:-1]
    bow = km - 0.5 * (ke[1:] + ke[:-1])
    var = np.sqrt(np.einsum("tij,tij->t", chord, chord)) + 4.0 * np.sqrt(
        np.einsum("tij,tij->t", bow, bow))
    scale = float(var.max())
    bal = _Balanced.of(m, c, ke, k.period)
    size = 2 * m.shape[0]
    base = (np.maximum(1, np.ceil(_MIDPOINT_START * var / scale)).astype(np.int64)
            if scale > 0 else np.ones(n_piece, dtype=np.int64))

    def product(counts: np.ndarray) -> np.ndarray:
        total = int(counts.sum())
        piece = np.repeat(np.arange(n_piece), counts)
        j = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
        h = dur[piece] / counts[piece]
        tm = edges[piece] + (j + 0.5) * h
        p = np.eye(size)
        for a in range(0, total, _CHUNK):
            sl = slice(a, a + _CHUNK)
            x = bal.states(k.matrices(tm[sl])) * h[sl, None, None]
            p = _ordered_product(_expm_each(x)) @ p
        return p

    def top(p: np.ndarray) -> float:
        return float(np.max(np.abs(np.linalg.eigvals(p))))

    counts = base
    phi = product(counts)
    if scale == 0.0:  # every piece constant: the product is exact
        return bal.unbalance(phi), int(counts.sum()), 0.0
    rich, mu, err = phi, math.nan, math.inf
    while 2 * int(counts.sum()) <= _MIDPOINT_MAX_SUBSTEPS:
        counts = 2 * counts
        finer = product(counts)
        rich = finer + (finer - phi) / 3.0
        phi = finer
        mu_new = top(rich)
        if math.isfinite(mu):
            err = abs(mu_new - mu) / 15.0
            if err <= atol or err <= margin * abs(mu_new - 1.0):
                mu = mu_new
                break
        mu = mu_new
    return bal.unbalance(rich), int(counts.sum()), err


#: Largest damping rate over one period, ``T ||M^-1 C||``: a bound on wrong units, not on
#: physics (a strongly damped mode's factor ``exp(-T lambda)`` underflows harmlessly to 0 - a
#: two-stage set at a tenth of its top speed reaches 3.3e3), and largest
#: ``T^2 ||M^-1 K(0)||`` (about ``(omega T)^2``; the same set reaches 6e8; 1e14 is 1.6e6
#: oscillations of the highest mode per period, again a bound on wrong units).
MAX_DAMPING_DECAY = 1e5
MAX_STIFFNESS_PHASE = 1e14


def _check_rates(period: float, minv: np.ndarray, c: np.ndarray, k0: np.ndarray) -> None:
    """Refuse matrices whose scale would overflow the monodromy (checked before it)."""
    with np.errstate(over="ignore", invalid="ignore"):
        decay = period * _frob(minv @ c)
        phase = period * period * _frob(minv @ k0)
    if not decay <= MAX_DAMPING_DECAY:
        raise ValueError(f"M, C: T ||M^-1 C|| = {decay:.3g} per period exceeds "
                         f"{MAX_DAMPING_DECAY:g} (damping rates far beyond any gear set's); "
                         "check the units of M, C and the period")
    if not phase <= MAX_STIFFNESS_PHASE:
        raise ValueError(f"M, K: T^2 ||M^-1 K(0)|| = {phase:.3g} exceeds "
                         f"{MAX_STIFFNESS_PHASE:g} (thousands of oscillations per period); "
                         "check the units of M, K and the period")


def _underflow_silent(func: Callable) -> Callable:
    """Run ``func`` with numpy's underflow warnings off: a tiny entry of M, C or K that
    underflows to zero in a product is no error (overflow is refused up front)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with np.errstate(under="ignore"):
            return func(*args, **kwargs)

    return wrapper


def _frob(a: np.ndarray) -> float:
    """Frobenius norm, scaled by a power of two (exact: the same bits as the plain sum of
    squares, without its overflow for entries above 1e154)."""
    mag = np.abs(a)
    top = float(mag.max()) if mag.size else 0.0
    if top == 0.0 or not math.isfinite(top):
        return top
    e = int(np.frexp(top)[1])
    u = np.ldexp(mag, -e)
    with np.errstate(under="ignore", over="ignore"):
        return float(np.ldexp(np.sqrt(np.sum(u**2)), e))


@_underflow_silent
def floquet(
    M: Any,
    C: Any,
    K: StiffnessCallable | PiecewiseConstant | PiecewiseSmooth,
    period: float,
    *,
    method: str = "auto",
    n_steps: int | None = None,
    rtol: float = 1e-10,
    tol: float = 1e-7,
    periodicity_rtol: float = 1e-8,
    multiplier_atol: float = 1e-8,
    unity_margin: float = 0.0,
) -> FloquetResult:
    """Floquet multipliers of ``M q'' + C q' + K(t) q = 0`` with ``K(t + T) = K(t)``.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix [kg], symmetric positive definite.
    C : array_like, shape (n, n)
        Constant damping (and/or gyroscopic) matrix [N s/m].
    K : callable, PiecewiseConstant or PiecewiseSmooth
        Stiffness [N/m]: ``K(t) -> (n, n)`` array for a smooth stiffness, a
        :class:`PiecewiseConstant` description (exact monodromy) or a :class:`PiecewiseSmooth`
        description (breakpoints and a batch evaluator; product of exponentials).
    period : float
        Period ``T`` [s] of ``K``; must be > 0.
    method : {"auto", "exact", "midpoint", "magnus"}
        ``"auto"`` chooses ``"exact"`` for :class:`PiecewiseConstant`, ``"midpoint"`` for
        :class:`PiecewiseSmooth` and ``"magnus"`` for callables. ``"magnus"`` may also be used
        with the two descriptions (as a check).
    n_steps : int, optional
        Fixed number of Magnus steps per period (no error control). By default the number of
        steps is doubled until the Richardson-extrapolated monodromy meets ``rtol``.
    rtol : float
        Target relative error of the monodromy (Frobenius norm) for the adaptive Magnus scheme.
    tol : float
        Stability tolerance: ``stable`` is ``max|mu| <= 1 + tol``.
    periodicity_rtol : float
        Admissible relative difference ``||K(T) - K(0)|| / ||K(0)||`` for a callable ``K``.
    multiplier_atol : float
        ``"midpoint"``: target error of ``max|mu|`` (sub-steps are halved until two Richardson
        values agree to 15 times this; the estimate is reported as ``error_estimate``).
    unity_margin : float
        ``"midpoint"``: also stop refining once the error estimate is below
        ``unity_margin * |max|mu| - 1|`` (e.g. 0.01: far from the stability limit the
        multiplier is needed to 1 % of its distance from 1 only). 0 (default): off.

    Returns
    -------
    FloquetResult

    Raises
    ------
    ValueError
        Non-positive period, non-symmetric or non-positive-definite ``M``, size mismatch between
        ``M``, ``C`` and ``K``, a ``K`` that is not ``T``-periodic, or an unknown ``method``.

    Notes
    -----
    With the state ``x = [q; q']`` the system is ``x' = A(t) x``,
    ``A = [[0, I], [-M^-1 K(t), -M^-1 C]]``. The monodromy ``Phi = X(T)`` with ``X(0) = I``;
    the multipliers are ``mu = eig(Phi)`` and the system is asymptotically unstable iff
    ``max|mu| > 1`` (Floquet theory; Nayfeh & Mook 1979, ch. 5). Liouville's formula gives
    ``det Phi = exp(-T tr(M^-1 C))``, reported as a built-in check.

    *Exact*: for a piecewise-constant ``K`` with pieces ``(tau_k, K_k)``,
    ``Phi = expm(A_m tau_m) ... expm(A_1 tau_1)``.

    *Midpoint*: for a :class:`PiecewiseSmooth` ``K``, the same product over sub-steps with
    ``A`` at each sub-step's midpoint (exponential midpoint rule: second order, exact for a
    constant piece, every exponential exact however many oscillations of the fastest mode a
    sub-step spans). Sub-steps follow the pieces between the breakpoints, so kinks of ``K``
    never fall inside one, and their number follows the change of ``K`` (see
    :class:`PiecewiseSmooth`); they are halved pass by pass, two passes are combined by
    Richardson extrapolation (fourth order: the rule is symmetric), until ``max|mu|`` has
    converged to ``multiplier_atol``.

    *Magnus*: one step of length ``h`` uses ``A`` at ``t, t + h/2, t + h`` (Simpson nodes),
    ``B0 = (A1 + 4 A2 + A3)/6``, ``B1 = (A3 - A1)/12`` and
    ``Omega = h B0 + h^2 [B1, B0]``, a fourth-order Magnus method (Iserles & Norsett 1999;
    Blanes, Casas, Oteo & Ros 2009). The method is time-symmetric, so its error expands in even
    powers of ``h`` and Richardson extrapolation ``Phi_h + (Phi_h - Phi_2h)/15`` is sixth order.
    The number of steps is doubled until two successive extrapolations agree to ``63 rtol``.
    Products of exponentials of this kind are the approach of Friedmann, Hammond & Woo (1977).
    Near an undamped boundary two multipliers coincide and an error ``delta`` in ``Phi`` moves
    them by about ``sqrt(delta)``; choose ``tol`` accordingly (default 1e-7).
    """
    T = require_positive(period, "period")
    m = require_mass_matrix(M)
    n = m.shape[0]
    c = require_square(C, "C", n)
    minv = np.linalg.solve(m, np.eye(n))
    if method not in ("auto", "exact", "midpoint", "magnus"):
        raise ValueError(f"method = {method!r} is not admissible: use 'auto', 'exact', "
                         "'midpoint' or 'magnus'")
    if n_steps is not None and (int(n_steps) != n_steps or n_steps < 1):
        raise ValueError(f"n_steps = {n_steps!r} is not admissible: must be a positive integer")
    require_positive(rtol, "rtol")
    require_positive(tol, "tol", allow_zero=True)
    require_positive(multiplier_atol, "multiplier_atol")
    require_positive(unity_margin, "unity_margin", allow_zero=True)

    if isinstance(K, PiecewiseConstant):
        if K.size != n:
            raise ValueError(
                f"K (PiecewiseConstant) matrices are ({K.size}, {K.size}) but M is ({n}, {n}); "
                "all matrices must have the same size"
            )
        if abs(K.period - T) > 1e-9 * T:
            raise ValueError(
                f"K is not periodic with period = {T!r} s: its durations sum to {K.period!r} s; "
                "they must sum to the period"
            )
        kfun: StiffnessCallable = K
        use = "exact" if method == "auto" else method
        if use == "midpoint":
            raise ValueError("method = 'midpoint' needs K as a PiecewiseSmooth; a "
                             "PiecewiseConstant is computed exactly ('exact')")
    elif isinstance(K, PiecewiseSmooth):
        if abs(K.period - T) > 1e-9 * T:
            raise ValueError(
                f"K is not periodic with period = {T!r} s: its edges end at {K.period!r} s; "
                "the last edge must be the period"
            )
        kfun = K
        use = "midpoint" if method == "auto" else method
        if use == "exact":
            raise ValueError("method = 'exact' needs K as a PiecewiseConstant; a "
                             "PiecewiseSmooth uses 'midpoint' (or 'magnus')")
        require_square(K(0.0), "K(0)", n)
    elif callable(K):
        kfun = K
        if method == "midpoint":
            raise ValueError("method = 'midpoint' needs K as a PiecewiseSmooth (breakpoints "
                             "and a batch evaluator); for a callable K use 'magnus'")
        if method == "exact":
            raise ValueError(
                "method = 'exact' needs K as a PiecewiseConstant; for a callable K use 'magnus'"
            )
        use = "magnus"
        k0 = require_square(kfun(0.0), "K(0)", n)
        kT = require_square(kfun(T), "K(period)", n)
        scale = max(_frob(k0), _frob(kT), 1e-300)
        if _frob(kT - k0) > periodicity_rtol * scale:
            raise ValueError(
                f"K is not periodic with period = {T!r} s: ||K(period) - K(0)|| / ||K(0)|| = "
                f"{_frob(kT - k0) / scale:.3g} exceeds periodicity_rtol = {periodicity_rtol:g}; "
                "pass the true period of K(t)"
            )
    else:
        raise ValueError("K must be a callable K(t) -> (n, n) array or a PiecewiseConstant")
    _check_rates(T, minv, c, require_square(kfun(0.0), "K(0)", n))

    err = 0.0
    steps = 0
    if use == "exact":
        assert isinstance(K, PiecewiseConstant)
        phi = _exact_monodromy(m, c, K)
    elif use == "midpoint":
        assert isinstance(K, PiecewiseSmooth)
        phi, steps, err = _midpoint_monodromy(m, c, K, float(multiplier_atol),
                                              float(unity_margin))
    else:
        def sample(times: np.ndarray) -> np.ndarray:
            out = np.empty((times.size, n, n))
            for i, t in enumerate(times):
                out[i] = kfun(float(t))
            return require_finite(out, "K(t)")

        if n_steps is not None:
            steps = int(n_steps)
            times = np.linspace(0.0, T, 2 * steps + 1)
            phi = _magnus4(_state_matrices(minv, c, sample(times)), T, 1)
        else:
            # initial resolution from the fastest undamped frequency at a few instants
            w2 = max(
                float(np.max(np.abs(np.linalg.eigvals(minv @ kfun(t))))) for t in
                (0.0, T / 3, 2 * T / 3)
            )
            wmax = np.sqrt(w2) + 0.5 * float(np.max(np.abs(np.linalg.eigvals(minv @ c))))
            steps = 16
            while steps < 4.0 * wmax * T and steps < _MAX_STEPS:
                steps *= 2
            times = np.linspace(0.0, T, 2 * steps + 1)
            ks = sample(times)
            while True:
                a = _state_matrices(minv, c, ks)
                p1, p2, p4 = (_magnus4(a, T, s) for s in (4, 2, 1))
                r1 = p2 + (p2 - p1) / 15.0
                phi = p4 + (p4 - p2) / 15.0
                err = _frob(phi - r1) / 63.0 / max(_frob(phi), 1.0)
                if err <= rtol or steps >= _MAX_STEPS:
                    break
                steps *= 2
                new = np.empty((2 * steps + 1, n, n))
                new[0::2] = ks
                new[1::2] = sample(np.linspace(0.0, T, 2 * steps + 1)[1::2])
                ks = new
    mu = np.linalg.eigvals(phi)
    order = np.argsort(-np.abs(mu), kind="stable")
    mu = mu[order]
    mmax = float(np.abs(mu[0]))
    # a long, strongly damped period can underflow every multiplier to 0: growth rate -inf
    with np.errstate(divide="ignore", invalid="ignore"):
        expo = np.log(mu.astype(complex)) / T
        growth = float(np.log(mmax) / T) if mmax > 0 else -math.inf
        det = float(np.real(np.linalg.det(phi)))
        logdet = float(np.linalg.slogdet(phi)[1])
    return FloquetResult(
        multipliers=mu,
        exponents=expo,
        max_modulus=mmax,
        growth_rate=growth,
        stable=bool(mmax <= 1.0 + tol),
        monodromy=phi,
        period=T,
        tol=float(tol),
        det_monodromy=det,
        liouville_expected=float(np.exp(-T * np.trace(minv @ c))),
        log_det_monodromy=logdet,
        log_liouville_expected=float(-T * np.trace(minv @ c)),
        method=use,
        n_steps=steps,
        error_estimate=float(err),
    )
