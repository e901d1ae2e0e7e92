"""Floquet analysis of linear periodic systems ``M q'' + C q' + K(t) q = 0``.

The monodromy matrix is computed either exactly, as an ordered product of matrix exponentials
for a piecewise-constant stiffness (:class:`PiecewiseConstant`), or by a fourth-order Magnus
integrator with Richardson extrapolation and step doubling for a smooth stiffness callable.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.checks import (
    require_finite,
    require_mass_matrix,
    require_positive,
    require_square,
)

__all__ = ["FloquetResult", "PiecewiseConstant", "floquet"]

StiffnessCallable = Callable[[float], Any]

_MAX_STEPS = 2**16


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
        ``"exact"`` (matrix-exponential product) or ``"magnus"``.
    n_steps : int
        Number of Magnus steps per period (0 for the exact product).
    error_estimate : float
        Estimated relative error of the monodromy (0 for the exact product).
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
        return ds

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


def _exact_monodromy(m: np.ndarray, c: np.ndarray, k: PiecewiseConstant) -> np.ndarray:
    """Monodromy ``expm(A_m tau_m) ... expm(A_1 tau_1)`` of a piecewise-constant stiffness.

    The product is formed in balanced coordinates, mass-normalised ``p = L^T q``
    (``M = L L^T``) and velocities scaled by ``w = sqrt(max ||L^-1 K_k L^-T||_2)``:
    ``A~ = [[0, w I], [-L^-1 K L^-T / w, -L^-1 C L^-T]]``. This similarity transform leaves the
    multipliers unchanged and brings ``||A~ tau||`` to the order of ``w tau`` (a few units
    instead of ``1e5`` in mixed units), so few squarings are needed and the exponentials are
    accurate to ``1e-14``; the result is transformed back to ``x = [q; q']``. (The Frobenius
    norm stands in for the 2-norm in ``w``: any value of that order balances.)
    """
    n = m.shape[0]
    li = np.linalg.inv(np.linalg.cholesky(m))
    kt = li @ k.matrices @ li.T
    ct = li @ c @ li.T
    norm2 = float(np.max(np.einsum("tij,tij->t", kt, kt))) if n else 0.0
    w = norm2**0.25 if norm2 > 0 else 1.0 / k.period
    a = np.zeros((kt.shape[0], 2 * n, 2 * n))
    a[:, :n, n:] = w * np.eye(n)
    a[:, n:, :n] = -kt / w
    a[:, n:, n:] = -ct
    phit = _ordered_product(_expm_each(a * k.durations[:, None, None]))
    t = np.zeros((2 * n, 2 * n))
    t_inv = np.zeros((2 * n, 2 * n))
    t[:n, :n] = li.T
    t[n:, n:] = w * li.T
    lt = np.linalg.inv(li.T)
    t_inv[:n, :n] = lt
    t_inv[n:, n:] = lt / w
    return t @ phit @ t_inv


def _frob(a: np.ndarray) -> float:
    return float(np.sqrt(np.sum(np.abs(a) ** 2)))


def floquet(
    M: Any,
    C: Any,
    K: StiffnessCallable | PiecewiseConstant,
    period: float,
    *,
    method: str = "auto",
    n_steps: int | None = None,
    rtol: float = 1e-10,
    tol: float = 1e-7,
    periodicity_rtol: float = 1e-8,
) -> FloquetResult:
    """Floquet multipliers of ``M q'' + C q' + K(t) q = 0`` with ``K(t + T) = K(t)``.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix [kg], symmetric positive definite.
    C : array_like, shape (n, n)
        Constant damping (and/or gyroscopic) matrix [N s/m].
    K : callable or PiecewiseConstant
        Stiffness [N/m]: ``K(t) -> (n, n)`` array for a smooth stiffness, or a
        :class:`PiecewiseConstant` description (exact monodromy).
    period : float
        Period ``T`` [s] of ``K``; must be > 0.
    method : {"auto", "exact", "magnus"}
        ``"auto"`` chooses ``"exact"`` for :class:`PiecewiseConstant` and ``"magnus"`` for
        callables. ``"magnus"`` may also be used with a :class:`PiecewiseConstant` (as a check).
    n_steps : int, optional
        Fixed number of Magnus steps per period (no error control). By default the number of
        steps is doubled until the Richardson-extrapolated monodromy meets ``rtol``.
    rtol : float
        Target relative error of the monodromy (Frobenius norm) for the adaptive Magnus scheme.
    tol : float
        Stability tolerance: ``stable`` is ``max|mu| <= 1 + tol``.
    periodicity_rtol : float
        Admissible relative difference ``||K(T) - K(0)|| / ||K(0)||`` for a callable ``K``.

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
    if method not in ("auto", "exact", "magnus"):
        raise ValueError(f"method = {method!r} is not admissible: use 'auto', 'exact' or 'magnus'")
    if n_steps is not None and (int(n_steps) != n_steps or n_steps < 1):
        raise ValueError(f"n_steps = {n_steps!r} is not admissible: must be a positive integer")
    require_positive(rtol, "rtol")
    require_positive(tol, "tol", allow_zero=True)

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
    elif callable(K):
        kfun = K
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

    err = 0.0
    steps = 0
    if use == "exact":
        assert isinstance(K, PiecewiseConstant)
        phi = _exact_monodromy(m, c, K)
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
    expo = np.log(mu.astype(complex)) / T
    return FloquetResult(
        multipliers=mu,
        exponents=expo,
        max_modulus=mmax,
        growth_rate=float(np.log(mmax) / T),
        stable=bool(mmax <= 1.0 + tol),
        monodromy=phi,
        period=T,
        tol=float(tol),
        det_monodromy=float(np.real(np.linalg.det(phi))),
        liouville_expected=float(np.exp(-T * np.trace(minv @ c))),
        log_det_monodromy=float(np.linalg.slogdet(phi)[1]),
        log_liouville_expected=float(-T * np.trace(minv @ c)),
        method=use,
        n_steps=steps,
        error_estimate=float(err),
    )
