"""Time-varying mesh stiffness models over one mesh cycle.

Every model is a periodic function ``k(s)`` [N/m] of the mesh position ``s`` [mesh cycles],
period 1, with ``s = 0`` the instant a new tooth pair enters contact at the start of the active
path (see :mod:`gearvib.geometry`). Harmonics follow the complex convention::

    k(s) = mean + sum_{l >= 1} 2 Re( c_l exp(i 2 pi l s) ),   c_l = int_0^1 k(s) exp(-i 2 pi l s) ds

Models
------
``ConstantStiffness``, ``RectangularStiffness`` (double/single contact), ``TrapezoidalStiffness``
(tip-relief ramps), ``FourierStiffness``, ``PairSuperposition`` (sum of single-pair curves, the
source paper's method) and its tabulated form ``TabulatedPair`` (CSV export of LVR, KISSsoft, ...).
:func:`iso6336_stiffness` gives the ISO 6336-1 method B single and mean mesh stiffness, and
:func:`stiffness_from_dict` builds a model from a TOML table.
"""

from __future__ import annotations

import abc
import csv
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from gearvib.checks import check_array, check_count, check_real, short
from gearvib.geometry import MeshGeometry
from gearvib.paths import is_file

__all__ = [
    "ConstantStiffness",
    "FourierStiffness",
    "MeshStiffness",
    "PairSuperposition",
    "RectangularStiffness",
    "TabulatedPair",
    "TrapezoidalStiffness",
    "iso6336_stiffness",
    "iso_rectangular",
    "stiffness_from_dict",
]

_N_DENSE = 8192
MAX_STIFFNESS = 1e40
"""Largest stiffness accepted [N/m] (its products with deflections stay finite)."""
MAX_FOURIER = 1_000
"""Most harmonics of a :class:`FourierStiffness`."""
MAX_TABLE = 1 << 16
"""Largest stiffness table (values per mesh cycle, :meth:`MeshStiffness.table`)."""


def _real(name: str, value: Any) -> float:
    return check_real(value, name)


def _stiff(name: str, value: Any, *, allow_zero: bool = False) -> float:
    v = _real(name, value)
    if v > MAX_STIFFNESS:
        raise ValueError(f"stiffness {name} = {v!r} N/m is not admissible (admissible: <= "
                         f"{MAX_STIFFNESS:g})")
    if v < 0.0 or (v == 0.0 and not allow_zero):
        rng = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"stiffness {name} = {v!r} N/m is not admissible (admissible: {rng})")
    return v


def _contact_ratio(value: Any, upper: float | None = None) -> float:
    eps = _real("contact_ratio", value)
    if eps < 1.0 or (upper is not None and eps >= upper):
        rng = ">= 1" if upper is None else f"1 <= eps < {upper:g}"
        raise ValueError(
            f"contact ratio eps_alpha = {eps:.4g} is not admissible (admissible: {rng})"
        )
    return eps


def _lmax(l_max: Any) -> int:
    return check_count(l_max, "l_max", low=0, high=MAX_TABLE)


class MeshStiffness(abc.ABC):
    """Periodic mesh stiffness ``k(s)`` [N/m], period 1 in the mesh position ``s`` [cycles]."""

    @abc.abstractmethod
    def _eval(self, u: np.ndarray) -> np.ndarray:
        """Stiffness at ``u`` in ``[0, 1)``."""

    @property
    @abc.abstractmethod
    def mean(self) -> float:
        """Mean stiffness over one cycle [N/m]."""

    @abc.abstractmethod
    def harmonics(self, l_max: int) -> np.ndarray:
        """Complex coefficients ``c_1 .. c_lmax`` (shape ``(l_max,)``), see module docstring."""

    @abc.abstractmethod
    def to_dict(self) -> dict:
        """Plain dict (TOML table) with ``"model"`` and the parameters."""

    @abc.abstractmethod
    def scaled(self, factor: float) -> MeshStiffness:
        """The same model with every stiffness multiplied by ``factor`` (> 0)."""

    def _breakpoints(self) -> np.ndarray:
        """Positions in ``[0, 1)`` where extrema or jumps can occur (besides a dense grid)."""
        return np.array([0.0])

    def __call__(self, s: Any) -> np.ndarray:
        """Stiffness [N/m] at mesh positions ``s`` [cycles] (any real values, period 1)."""
        x = np.asarray(s, dtype=float)
        u = x - np.floor(x)
        u = np.where(u >= 1.0, 0.0, u)
        return np.asarray(self._eval(u), dtype=float)

    def table(self, n: int = 1024) -> np.ndarray:
        """Values at ``s = i / n``, ``i = 0 .. n-1`` (exact point values, no smoothing)."""
        n = check_count(n, "table size n", low=1, high=MAX_TABLE)
        return self(np.arange(n) / n)

    def _samples(self) -> np.ndarray:
        bp = np.mod(self._breakpoints(), 1.0)
        pts = np.concatenate(
            [np.arange(_N_DENSE) / _N_DENSE, bp, np.mod(bp - 1e-12, 1.0), np.mod(bp + 1e-12, 1.0)]
        )
        return self(pts)

    @property
    def min(self) -> float:
        """Minimum over a cycle [N/m] (exact for piecewise-linear models)."""
        return float(np.min(self._samples()))

    @property
    def max(self) -> float:
        """Maximum over a cycle [N/m] (exact for piecewise-linear models)."""
        return float(np.max(self._samples()))

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={v!r}" for k, v in self.to_dict().items() if k != "model")
        return f"{type(self).__name__}({params})"


class ConstantStiffness(MeshStiffness):
    """Constant mesh stiffness ``k`` [N/m] (> 0)."""

    def __init__(self, k: float) -> None:
        self.k = _stiff("k", k)

    def _eval(self, u: np.ndarray) -> np.ndarray:
        return np.full_like(u, self.k, dtype=float)

    @property
    def mean(self) -> float:
        return self.k

    @property
    def min(self) -> float:
        return self.k

    @property
    def max(self) -> float:
        return self.k

    def harmonics(self, l_max: int) -> np.ndarray:
        return np.zeros(_lmax(l_max), dtype=complex)

    def to_dict(self) -> dict:
        return {"model": "constant", "k": self.k}

    def scaled(self, factor: float) -> ConstantStiffness:
        return ConstantStiffness(self.k * _positive_factor(factor))


def _positive_factor(factor: Any) -> float:
    f = _real("factor", factor)
    if f <= 0.0:
        raise ValueError(f"scale factor = {f!r} is not admissible (admissible: > 0)")
    return f


class RectangularStiffness(MeshStiffness):
    """Rectangular wave: ``k_max`` for ``s in [0, eps-1)`` (two pairs), else ``k_min``.

    Parameters
    ----------
    k_min, k_max : float
        Single- and double-contact stiffness [N/m], ``0 < k_min <= k_max``.
    contact_ratio : float
        ``1 <= eps_alpha < 2`` (use :class:`PairSuperposition` for ``eps >= 2``).

    Notes
    -----
    With ``d = eps - 1`` and ``dk = k_max - k_min`` (physics.md 3.2, 4.3)::

        mean = k_min + d dk,   c_l = dk (1 - exp(-i 2 pi l d)) / (i 2 pi l),
        |c_l| = dk |sin(pi l d)| / (pi l)
    """

    def __init__(self, k_min: float, k_max: float, contact_ratio: float) -> None:
        self.k_min = _stiff("k_min", k_min)
        self.k_max = _stiff("k_max", k_max)
        if self.k_max < self.k_min:
            raise ValueError(
                f"stiffness k_max = {self.k_max!r} N/m is below k_min = {self.k_min!r} N/m "
                "(admissible: k_max >= k_min)"
            )
        self.contact_ratio = _contact_ratio(contact_ratio, upper=2.0)

    @property
    def double_contact(self) -> float:
        """Double-contact fraction ``d = eps - 1`` of the cycle."""
        return self.contact_ratio - 1.0

    def _eval(self, u: np.ndarray) -> np.ndarray:
        return np.where(u < self.double_contact, self.k_max, self.k_min)

    def _breakpoints(self) -> np.ndarray:
        return np.array([0.0, self.double_contact])

    @property
    def mean(self) -> float:
        return self.k_min + self.double_contact * (self.k_max - self.k_min)

    @property
    def min(self) -> float:
        return self.k_min if self.double_contact < 1.0 else self.k_max

    @property
    def max(self) -> float:
        return self.k_max if self.double_contact > 0.0 else self.k_min

    def harmonics(self, l_max: int) -> np.ndarray:
        ll = np.arange(1, _lmax(l_max) + 1)
        w = 2j * np.pi * ll
        return (self.k_max - self.k_min) * (1.0 - np.exp(-w * self.double_contact)) / w

    def to_dict(self) -> dict:
        return {
            "model": "rectangular",
            "k_min": self.k_min,
            "k_max": self.k_max,
            "contact_ratio": self.contact_ratio,
        }

    def scaled(self, factor: float) -> RectangularStiffness:
        f = _positive_factor(factor)
        return RectangularStiffness(self.k_min * f, self.k_max * f, self.contact_ratio)


class TrapezoidalStiffness(RectangularStiffness):
    """Rectangular wave with linear ramps of width ``ramp`` [cycles] centred on the transitions.

    Parameters
    ----------
    k_min, k_max, contact_ratio
        As :class:`RectangularStiffness`.
    ramp : float
        Ramp width ``rho`` [cycles], ``0 <= rho <= min(eps - 1, 2 - eps)``.

    Notes
    -----
    The trapezoid is the rectangular pulse convolved with a box of width ``rho``, so
    ``c_l = c_l^rect sinc(l rho)``, ``sinc(x) = sin(pi x)/(pi x)``, and the mean is unchanged
    (physics.md 3.2). At ``s = 0`` the stiffness is half-way between ``k_min`` and ``k_max``.
    """

    def __init__(self, k_min: float, k_max: float, contact_ratio: float, ramp: float) -> None:
        super().__init__(k_min, k_max, contact_ratio)
        rho = _real("ramp", ramp)
        d = self.double_contact
        top = min(d, 1.0 - d)
        if not 0.0 <= rho <= top + 1e-12:
            raise ValueError(
                f"ramp = {rho!r} cycles is not admissible for contact ratio "
                f"{self.contact_ratio:.4g} (admissible: 0 <= ramp <= min(eps-1, 2-eps) = {top:.4g})"
            )
        self.ramp = min(rho, top)

    def _eval(self, u: np.ndarray) -> np.ndarray:
        rho, d = self.ramp, self.double_contact
        if rho == 0.0:
            return super()._eval(u)
        a, b = u - 0.5 * rho, u + 0.5 * rho
        overlap = np.zeros_like(u)
        for j in (-1.0, 0.0, 1.0):
            overlap += np.clip(np.minimum(b, d + j) - np.maximum(a, j), 0.0, None)
        return self.k_min + (self.k_max - self.k_min) * overlap / rho

    def _breakpoints(self) -> np.ndarray:
        h = 0.5 * self.ramp
        d = self.double_contact
        return np.array([-h, h, d - h, d + h])

    def harmonics(self, l_max: int) -> np.ndarray:
        ll = np.arange(1, _lmax(l_max) + 1)
        return super().harmonics(l_max) * np.sinc(ll * self.ramp)

    def to_dict(self) -> dict:
        d = super().to_dict()
        d["model"] = "trapezoidal"
        d["ramp"] = self.ramp
        return d

    def scaled(self, factor: float) -> TrapezoidalStiffness:
        f = _positive_factor(factor)
        return TrapezoidalStiffness(self.k_min * f, self.k_max * f, self.contact_ratio, self.ramp)


class FourierStiffness(MeshStiffness):
    """Truncated Fourier series ``k(s) = mean + sum_l a_l cos(2 pi l s) + b_l sin(2 pi l s)``.

    Parameters
    ----------
    mean : float
        Mean stiffness [N/m] (> 0).
    cos, sin : sequence of float
        Coefficients ``a_1, a_2, ...`` and ``b_1, b_2, ...`` [N/m].

    Raises
    ------
    ValueError
        If the series becomes negative anywhere in the cycle.

    Notes
    -----
    ``c_l = (a_l - i b_l) / 2``. ``min``/``max`` are found on an 8192-point grid refined by
    a bounded scalar minimisation.
    """

    def __init__(self, mean: float, cos: ArrayLike = (), sin: ArrayLike = ()) -> None:
        self._mean = _stiff("mean", mean)
        a = self._coeffs("cos", cos)
        b = self._coeffs("sin", sin)
        n = max(a.size, b.size)
        self.cos = np.pad(a, (0, n - a.size))
        self.sin = np.pad(b, (0, n - b.size))
        lo = self._extreme(-1.0)
        if lo < 0.0:
            raise ValueError(
                f"Fourier stiffness becomes negative: min k(s) = {lo:.4g} N/m "
                "(admissible: k(s) >= 0 for all s; reduce the cos/sin coefficients)"
            )

    @staticmethod
    def _coeffs(name: str, values: ArrayLike) -> np.ndarray:
        arr = check_array(values, name, min_size=0, max_abs=MAX_STIFFNESS).ravel()
        if arr.size > MAX_FOURIER:
            raise ValueError(f"{name}: {arr.size} coefficients (admissible: at most "
                             f"{MAX_FOURIER})")
        return arr

    def _eval(self, u: np.ndarray) -> np.ndarray:
        out = np.full(np.shape(u), self._mean, dtype=float)
        for l_, (a, b) in enumerate(zip(self.cos, self.sin, strict=True), start=1):
            ph = 2.0 * np.pi * l_ * u
            out = out + a * np.cos(ph) + b * np.sin(ph)
        return out

    def _extreme(self, sign: float) -> float:
        from scipy.optimize import minimize_scalar

        grid = np.arange(_N_DENSE) / _N_DENSE
        vals = sign * self._eval(grid)
        i = int(np.argmax(vals))
        h = 1.0 / _N_DENSE
        res = minimize_scalar(
            lambda x: -sign * float(self._eval(np.array([x]))[0]),
            bounds=(grid[i] - h, grid[i] + h),
            method="bounded",
            options={"xatol": 1e-12},
        )
        return float(max(vals[i], -res.fun) * sign)

    @property
    def mean(self) -> float:
        return self._mean

    @property
    def min(self) -> float:
        return self._extreme(-1.0)

    @property
    def max(self) -> float:
        return self._extreme(1.0)

    def harmonics(self, l_max: int) -> np.ndarray:
        n = _lmax(l_max)
        c = np.zeros(n, dtype=complex)
        m = min(n, self.cos.size)
        c[:m] = 0.5 * (self.cos[:m] - 1j * self.sin[:m])
        return c

    def to_dict(self) -> dict:
        return {
            "model": "fourier",
            "mean": self._mean,
            "cos": [float(v) for v in self.cos],
            "sin": [float(v) for v in self.sin],
        }

    def scaled(self, factor: float) -> FourierStiffness:
        f = _positive_factor(factor)
        return FourierStiffness(self._mean * f, self.cos * f, self.sin * f)


class PairSuperposition(MeshStiffness):
    """Mesh stiffness as the sum of single-tooth-pair curves (the source paper's method).

    Parameters
    ----------
    single_pair : callable
        ``single_pair(u)`` [N/m], vectorised, the stiffness of one tooth pair at the position
        ``u`` [base pitches] along the active path, ``0 <= u <= eps``; taken as zero outside
        ``[0, eps)``. Must be finite and non-negative.
    contact_ratio : float
        ``eps_alpha >= 1`` (any value; ``eps >= 2`` gives two or three pairs in contact).
    breakpoints : sequence of float, optional
        Positions ``u`` where ``single_pair`` has kinks or jumps (improves quadrature and
        min/max).

    Notes
    -----
    ``k(s) = sum_j f(s + j)`` over ``j = 0 .. ceil(eps)``: the pair that entered at ``s = 0``
    is at ``u = s``, the one before at ``u = s + 1``, ... Because the periodic sum unfolds,
    ``mean = int_0^eps f(u) du`` and ``c_l = int_0^eps f(u) exp(-i 2 pi l u) du``
    (evaluated by adaptive QUADPACK quadrature, :func:`scipy.integrate.quad`, split at the
    breakpoints). A constant ``f = k`` with ``1 <= eps < 2`` is the rectangular model with
    ``k_min = k``, ``k_max = 2 k``.
    """

    def __init__(
        self,
        single_pair: Callable[[np.ndarray], np.ndarray],
        contact_ratio: float,
        breakpoints: Sequence[float] | np.ndarray | None = None,
    ) -> None:
        if not callable(single_pair):
            raise TypeError(f"single_pair = {short(single_pair)} must be callable")
        self.contact_ratio = _contact_ratio(contact_ratio)
        self.single_pair = single_pair
        bp = [] if breakpoints is None else [float(b) for b in check_array(
            breakpoints, "breakpoints", ndim=1, min_size=0, max_abs=1e6)]
        if len(bp) > MAX_TABLE:
            raise ValueError(f"breakpoints: {len(bp)} values (admissible: at most {MAX_TABLE})")
        eps = self.contact_ratio
        self._bp_u = np.unique(np.clip(np.array([0.0, eps, *bp]), 0.0, eps))
        probe = np.concatenate([np.linspace(0.0, eps, 1001, endpoint=False), self._bp_u[:-1]])
        vals = np.asarray(single_pair(probe), dtype=float)
        if vals.shape != probe.shape:
            raise ValueError("single_pair must be vectorised: return one value per position")
        if not np.all(np.isfinite(vals)):
            raise ValueError("single-pair stiffness contains NaN or inf (admissible: finite, >= 0)")
        if np.any(vals < 0.0):
            raise ValueError(
                f"single-pair stiffness is negative ({vals.min():.4g} N/m; admissible: >= 0)"
            )

    def pair(self, u: Any) -> np.ndarray:
        """Single-pair stiffness [N/m] at path positions ``u`` [base pitches], 0 outside."""
        x = np.asarray(u, dtype=float)
        inside = (x >= 0.0) & (x < self.contact_ratio)
        xc = np.where(inside, x, 0.0)
        return np.where(inside, np.asarray(self.single_pair(xc), dtype=float), 0.0)

    def _eval(self, u: np.ndarray) -> np.ndarray:
        n = math.ceil(self.contact_ratio)
        # n + 1 >= 1 terms (never the start 0); a numpy scalar for a 0-d u (__call__ converts)
        return sum(self.pair(u + j) for j in range(n + 1))  # type: ignore[return-value]

    def _breakpoints(self) -> np.ndarray:
        return np.mod(self._bp_u, 1.0)

    def _segments(self) -> list[tuple[float, float]]:
        b = self._bp_u
        return [(float(b[i]), float(b[i + 1])) for i in range(b.size - 1) if b[i + 1] > b[i]]

    def _f_scalar(self, x: float) -> float:
        return float(np.asarray(self.single_pair(np.array([x])), dtype=float)[0])

    @property
    def mean(self) -> float:
        from scipy.integrate import quad  # on use, not on import

        return float(
            sum(quad(self._f_scalar, a, b, limit=200, epsabs=0.0)[0] for a, b in self._segments())
        )

    def harmonics(self, l_max: int) -> np.ndarray:
        from scipy.integrate import quad

        n = _lmax(l_max)
        out = np.zeros(n, dtype=complex)
        for i in range(n):
            w = 2.0 * np.pi * (i + 1)
            re = im = 0.0
            for a, b in self._segments():
                re += quad(self._f_scalar, a, b, weight="cos", wvar=w, limit=200)[0]
                im -= quad(self._f_scalar, a, b, weight="sin", wvar=w, limit=200)[0]
            out[i] = re + 1j * im
        return out

    def to_dict(self, n: int = 257) -> dict:
        """Tabulated form (``model = "pairs"``) sampled at ``n`` points along the path."""
        u = np.linspace(0.0, self.contact_ratio, n)
        k = np.asarray(self.single_pair(u), dtype=float)
        return {
            "model": "pairs",
            "contact_ratio": self.contact_ratio,
            "position": [float(v) for v in u],
            "stiffness": [float(v) for v in k],
            "position_unit": "base_pitch",
            "stiffness_unit": "N/m",
            "source": f"sampled from {getattr(self.single_pair, '__name__', 'callable')}",
        }

    def scaled(self, factor: float) -> PairSuperposition:
        f = _positive_factor(factor)
        g = self.single_pair
        return PairSuperposition(
            lambda u: f * np.asarray(g(u), dtype=float), self.contact_ratio, self._bp_u
        )


_POSITION_UNITS = ("path_fraction", "base_pitch")
_STIFFNESS_UNITS = ("N/m", "N/(mm um)", "N/(mm µm)")
CSV_MAX_BYTES = 16 * 2**20
"""Largest stiffness CSV file read [bytes]."""
CSV_MAX_ROWS = 100_000
"""Most data rows of a stiffness CSV file."""


class TabulatedPair(PairSuperposition):
    """Tabulated single-pair stiffness curve, linearly interpolated, superposed over pairs.

    Parameters
    ----------
    position : sequence of float
        Path positions [base pitches], strictly increasing, within ``[0, eps]``.
    stiffness : sequence of float
        Single-pair stiffness [N/m] at those positions (finite, >= 0).
    contact_ratio : float
        ``eps_alpha >= 1``.
    source : str, optional
        Provenance (e.g. the CSV path).

    Notes
    -----
    Outside the tabulated range the pair is out of contact (zero). Mean and harmonics are
    exact integrals of the piecewise-linear curve: on a segment ``[u0, u0 + h]`` with values
    ``k0, k1``: ``int (k0 + (k1-k0) t/h) e^{-iwt} dt = k0 I0 + (k1-k0)/h I1``,
    ``I0 = (1 - e^{-iwh})/(iw)``, ``I1 = (I0 - h e^{-iwh})/(iw)``, times ``e^{-iw u0}``.
    """

    def __init__(
        self,
        position: ArrayLike,
        stiffness: ArrayLike,
        contact_ratio: float,
        source: str | None = None,
    ) -> None:
        eps = _contact_ratio(contact_ratio)
        u = check_array(position, "position", min_size=0).ravel()
        k = check_array(stiffness, "stiffness", min_size=0, max_abs=MAX_STIFFNESS).ravel()
        if u.size > MAX_TABLE:
            raise ValueError(f"position: {u.size} values (admissible: at most {MAX_TABLE})")
        if u.size != k.size or u.size < 2:
            raise ValueError(
                f"position ({u.size}) and stiffness ({k.size}) must have the same length >= 2"
            )
        if not np.all(np.isfinite(u)):
            raise ValueError("position contains NaN or inf (admissible: finite)")
        if np.any(np.diff(u) <= 0.0):
            i = int(np.argmax(np.diff(u) <= 0.0))
            raise ValueError(
                f"position is not strictly increasing at row {i + 1}: "
                f"{float(u[i])!r} -> {float(u[i + 1])!r}"
            )
        tol = 1e-6 * eps
        if u[0] < -tol or u[-1] > eps + tol:
            raise ValueError(
                f"position range [{u[0]:.6g}, {u[-1]:.6g}] base pitches is not admissible "
                f"(admissible: within [0, eps_alpha] = [0, {eps:.6g}])"
            )
        if not np.all(np.isfinite(k)):
            raise ValueError("stiffness contains NaN or inf (admissible: finite, >= 0)")
        if np.any(k < 0.0):
            i = int(np.argmax(k < 0.0))
            raise ValueError(
                f"stiffness at row {i + 1} is {float(k[i])!r} N/m (admissible: >= 0 N/m)"
            )
        self.position = np.clip(u, 0.0, eps)
        self.stiffness = k
        self.source = source
        pos, stf = self.position, self.stiffness

        def curve(x: np.ndarray) -> np.ndarray:
            return np.interp(x, pos, stf, left=0.0, right=0.0)

        super().__init__(curve, eps, breakpoints=pos)

    def _segments_lin(self):
        u, k = self.position, self.stiffness
        return u[:-1], np.diff(u), k[:-1], k[1:]

    @property
    def mean(self) -> float:
        _, h, k0, k1 = self._segments_lin()
        return float(np.sum(0.5 * h * (k0 + k1)))

    def harmonics(self, l_max: int) -> np.ndarray:
        n = _lmax(l_max)
        u0, h, k0, k1 = self._segments_lin()
        out = np.zeros(n, dtype=complex)
        for i in range(n):
            w = 2.0 * np.pi * (i + 1)
            e = np.exp(-1j * w * h)
            i0 = (1.0 - e) / (1j * w)
            i1 = (i0 - h * e) / (1j * w)
            out[i] = np.sum(np.exp(-1j * w * u0) * (k0 * i0 + (k1 - k0) / h * i1))
        return out

    def to_dict(self, n: int = 257) -> dict:
        """The table as it is (``n``, the sampling of :meth:`PairSuperposition.to_dict`, does
        not apply)."""
        d: dict[str, Any] = {
            "model": "pairs",
            "contact_ratio": self.contact_ratio,
            "position": [float(v) for v in self.position],
            "stiffness": [float(v) for v in self.stiffness],
            "position_unit": "base_pitch",
            "stiffness_unit": "N/m",
        }
        if self.source is not None:
            d["source"] = self.source
        return d

    def scaled(self, factor: float) -> TabulatedPair:
        f = _positive_factor(factor)
        return TabulatedPair(self.position, self.stiffness * f, self.contact_ratio, self.source)

    @classmethod
    def from_arrays(
        cls,
        position: ArrayLike,
        stiffness: ArrayLike,
        contact_ratio: float,
        *,
        position_unit: str = "path_fraction",
        stiffness_unit: str = "N/m",
        face_width: float | None = None,
        source: str | None = None,
    ) -> TabulatedPair:
        """Build from arrays in the units of a tooth-contact program (see :meth:`from_csv`)."""
        eps = _contact_ratio(contact_ratio)
        if position_unit not in _POSITION_UNITS:
            raise ValueError(
                f"position_unit = {position_unit!r} is not admissible "
                f"(admissible: {', '.join(_POSITION_UNITS)})"
            )
        if stiffness_unit not in _STIFFNESS_UNITS:
            raise ValueError(
                f"stiffness_unit = {stiffness_unit!r} is not admissible "
                f"(admissible: {', '.join(_STIFFNESS_UNITS[:2])})"
            )
        u = np.asarray(position, dtype=float)
        k = np.asarray(stiffness, dtype=float)
        if position_unit == "path_fraction":
            if u.size and (np.nanmin(u) < -1e-9 or np.nanmax(u) > 1.0 + 1e-9):
                raise ValueError(
                    f"path_fraction positions span [{np.nanmin(u):.6g}, {np.nanmax(u):.6g}] "
                    "(admissible: within [0, 1])"
                )
            u = u * eps
        if stiffness_unit != "N/m":
            if face_width is None:
                raise ValueError(
                    f"face_width [m] is required to convert stiffness_unit = {stiffness_unit!r}"
                )
            b = _real("face_width", face_width)
            if b <= 0.0:
                raise ValueError(f"face_width = {b!r} m is not admissible (admissible: > 0)")
            # c [N/(mm um)] * b [mm] = N/um = 1e6 N/m
            k = k * (b * 1e3) * 1e6
        return cls(u, k, eps, source=source)

    @classmethod
    def from_csv(
        cls,
        path: str | Path,
        contact_ratio: float,
        position_column: int = 0,
        stiffness_column: int = 1,
        position_unit: str = "path_fraction",
        stiffness_unit: str = "N/m",
        face_width: float | None = None,
    ) -> TabulatedPair:
        """Read a single-pair stiffness curve exported by a tooth-contact program.

        Parameters
        ----------
        path : str or Path
            Text file; delimiter ``,``, ``;`` (then ``,`` may be the decimal mark), tab or
            blanks. Leading header lines and lines starting with ``#`` are skipped.
        contact_ratio : float
            ``eps_alpha`` of the mesh (>= 1).
        position_column, stiffness_column : int
            Zero-based column indices.
        position_unit : {"path_fraction", "base_pitch"}
            Position as fraction ``[0, 1]`` of the active path, or in base pitches.
        stiffness_unit : {"N/m", "N/(mm um)"}
            Stiffness per pair; ``N/(mm um)`` is per unit face width and needs ``face_width``.
        face_width : float, optional
            Face width [m] for ``N/(mm um)``.

        Raises
        ------
        ValueError
            Missing file or column, non-numeric data line, fewer than 2 rows, non-monotonic
            positions, negative or NaN stiffness, unknown unit.
        """
        p = Path(path)
        if not is_file(p):
            raise ValueError(f"stiffness CSV file {str(p)!r} does not exist")
        for name, c in (
            ("position_column", position_column),
            ("stiffness_column", stiffness_column),
        ):
            if isinstance(c, bool) or not isinstance(c, int | np.integer) or not 0 <= c < 1000:
                raise ValueError(f"{name} = {c!r} is not admissible (admissible: integer "
                                 "0..999)")
        rows: list[tuple[float, float]] = []
        need = max(position_column, stiffness_column) + 1
        try:
            size = p.stat().st_size
            if size > CSV_MAX_BYTES:
                raise ValueError(f"stiffness CSV file {str(p)!r} has {size} bytes (admissible: "
                                 f"<= {CSV_MAX_BYTES}; a single-pair curve has a few hundred "
                                 "rows)")
            with p.open(newline="", encoding="utf-8-sig") as fh:
                lines = fh.read(CSV_MAX_BYTES + 1).splitlines()
        except UnicodeDecodeError as exc:
            raise ValueError(f"stiffness CSV file {str(p)!r} is not a UTF-8 text file (byte "
                             f"{exc.start} cannot be decoded)") from None
        except OSError as exc:
            raise ValueError(f"stiffness CSV file {str(p)!r} cannot be read "
                             f"({exc.strerror or type(exc).__name__})") from None
        # errors name the file, the line and the column, never the file's content (the TOML
        # may point to any file)
        for lineno, raw in enumerate(lines, start=1):
            line = raw.strip()
            if not line or line.startswith("#"):
                continue
            if ";" in line:
                fields = [f.strip().replace(",", ".") for f in line.split(";")]
            elif "," in line:
                try:
                    fields = [f.strip() for f in next(csv.reader([line]))]
                except csv.Error:
                    fields = [line]
            else:
                fields = line.split()
            bad = None
            values = []
            for col in (position_column, stiffness_column):
                if col >= len(fields) or not _isnum(fields[col]):
                    bad = col
                    break
                values.append(float(fields[col]))
            if bad is not None:
                if not rows and not any(_isnum(f) for f in fields):
                    continue  # header line(s) before the data
                raise ValueError(
                    f"stiffness CSV file {str(p)!r}, line {lineno}, column {bad + 1}: "
                    + ("missing" if bad >= len(fields) else "not a number")
                    + f" (need {need} numeric columns; position column {position_column + 1}, "
                    f"stiffness column {stiffness_column + 1}, counted from 1)"
                )
            rows.append((values[0], values[1]))
            if len(rows) > CSV_MAX_ROWS:
                raise ValueError(f"stiffness CSV file {str(p)!r} has more than {CSV_MAX_ROWS} "
                                 "rows (admissible: a single-pair curve)")
        if len(rows) < 2:
            raise ValueError(
                f"{p.name}: found {len(rows)} numeric rows with {need} columns "
                "(admissible: >= 2 rows)"
            )
        arr = np.array(rows)
        return cls.from_arrays(
            arr[:, 0],
            arr[:, 1],
            contact_ratio,
            position_unit=position_unit,
            stiffness_unit=stiffness_unit,
            face_width=face_width,
            source=str(p),
        )


def _isnum(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


# --- ISO 6336-1 method B --------------------------------------------------------------------
_ISO_C = (0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188, 0.00529, 0.00182)


def iso6336_stiffness(
    mesh: MeshGeometry,
    *,
    C_M: float = 0.8,
    C_R: float = 1.0,
    basic_rack_dedendum: float = 1.25,
    low_contact_factor: float = 0.9,
) -> dict:
    """Single and mean mesh stiffness by ISO 6336-1:2006 method B.

    Parameters
    ----------
    mesh : MeshGeometry
        The gear pair (spur or helical, external or internal).
    C_M : float
        Theoretical correction factor (0.8 for solid disc gears).
    C_R : float
        Gear blank factor (1 for solid discs; 0 < C_R <= 1).
    basic_rack_dedendum : float
        ``h_fP / m_n`` of the basic rack for ``C_B``.
    low_contact_factor : float
        Factor applied to ``c_gamma_alpha`` when ``eps_alpha < 1.2`` (ISO: "up to 10 % lower";
        default 0.9, use 1.0 to disable).

    Returns
    -------
    dict
        ``q_prime`` [mm um/N], ``c_prime_th``, ``c_prime``, ``c_gamma_alpha``,
        ``c_gamma_beta`` [N/(mm um)], ``C_B``, ``z_n1``, ``z_n2``, ``x1``, ``x2`` (pinion 1,
        wheel 2), ``pinion`` ("gear1"/"gear2"), ``face_width`` [m], ``contact_ratio``,
        ``single_pair_stiffness`` = c' b and ``mean_mesh_stiffness`` = c_gamma_alpha b [N/m],
        ``in_validity_range`` (bool: x1 >= x2 and -0.5 <= x1 + x2 <= 2).

    Notes
    -----
    ISO 6336-1:2006 sec. 9 (method B), physics.md 3.2::

        q' = C1 + C2/z_n1 + C3/z_n2 + C4 x1 + C5 x1/z_n1 + C6 x2 + C7 x2/z_n2 + C8 x1² + C9 x2²
        z_n = z / cos³(beta);  internal gear: z_n2 -> inf (C3, C7 terms vanish)
        c'_th = 1/q',  c' = c'_th C_M C_R C_B cos(beta)
        C_B = [1 + 0.5 (1.2 - h_fP/m_n)] [1 - 0.02 (20° - alpha_n)]
        c_gamma_alpha = c' (0.75 eps_alpha + 0.25)   (eps_alpha >= 1.2),  c_gamma_beta = 0.85 c_ga
        k_mean [N/m] = c_gamma_alpha [N/(mm um)] * b [mm] * 1e6

    Subscript 1 is the pinion: the external gear of an internal pair, otherwise the gear with
    fewer teeth. Valid for steel/steel pairs, ``F_t K_A / b >= 100 N/mm`` (no load
    correction applied) and solid gear blanks unless ``C_R`` is set.
    """
    if not isinstance(mesh, MeshGeometry):
        raise TypeError(f"mesh must be a MeshGeometry; got {type(mesh).__name__}")
    for name, v in (("C_M", C_M), ("C_R", C_R)):
        if not 0.0 < _real(name, v) <= 1.0:
            raise ValueError(f"{name} = {v!r} is not admissible (admissible: 0 < {name} <= 1)")
    hfp = _real("basic_rack_dedendum", basic_rack_dedendum)
    if not 0.0 < hfp <= 10.0:
        raise ValueError(f"basic_rack_dedendum = {hfp!r} is not admissible (admissible: > 0, "
                         "<= 10)")
    lcf = _real("low_contact_factor", low_contact_factor)
    if not 0.9 <= lcf <= 1.0:
        raise ValueError(f"low_contact_factor = {lcf!r} is not admissible (admissible: 0.9 .. 1.0)")
    g1, g2 = mesh.gear1, mesh.gear2
    if g1.internal or (not g2.internal and abs(g2.z) < abs(g1.z)):
        pin, whl, pinion = g2, g1, "gear2"
    else:
        pin, whl, pinion = g1, g2, "gear1"
    beta = abs(pin.helix_angle)
    cb3 = math.cos(beta) ** 3
    zn1 = pin.z / cb3
    zn2 = math.inf if whl.internal else whl.z / cb3
    x1, x2 = pin.profile_shift, whl.profile_shift
    c1, c2, c3, c4, c5, c6, c7, c8, c9 = _ISO_C
    inv2 = 0.0 if math.isinf(zn2) else 1.0 / zn2
    q = (
        c1
        + c2 / zn1
        + c3 * inv2
        + c4 * x1
        + c5 * x1 / zn1
        + c6 * x2
        + c7 * x2 * inv2
        + c8 * x1**2
        + c9 * x2**2
    )
    c_th = 1.0 / q
    alpha_n_deg = math.degrees(pin.pressure_angle)
    C_B = (1.0 + 0.5 * (1.2 - hfp)) * (1.0 - 0.02 * (20.0 - alpha_n_deg))
    c_p = c_th * C_M * C_R * C_B * math.cos(beta)
    eps = mesh.contact_ratio
    c_ga = c_p * (0.75 * eps + 0.25)
    if eps < 1.2:
        c_ga *= lcf
    b = mesh.face_width
    to_n_per_m = b * 1e3 * 1e6  # N/(mm um) * mm -> N/um -> N/m
    return {
        "q_prime": q,
        "c_prime_th": c_th,
        "c_prime": c_p,
        "c_gamma_alpha": c_ga,
        "c_gamma_beta": 0.85 * c_ga,
        "C_B": C_B,
        "C_M": float(C_M),
        "C_R": float(C_R),
        "z_n1": zn1,
        "z_n2": zn2,
        "x1": x1,
        "x2": x2,
        "pinion": pinion,
        "face_width": b,
        "contact_ratio": eps,
        "single_pair_stiffness": c_p * to_n_per_m,
        "mean_mesh_stiffness": c_ga * to_n_per_m,
        "in_validity_range": bool(x1 >= x2 and -0.5 <= x1 + x2 <= 2.0),
    }


def iso_rectangular(mesh: MeshGeometry, **iso_kwargs: Any) -> RectangularStiffness:
    """Rectangular model consistent with ISO 6336-1 method B.

    ``k_min = c' b`` (one pair) and ``k_max = 1.75 c' b``, so that the mean
    ``k_min + (eps - 1)(k_max - k_min) = c' b (0.75 eps + 0.25) = c_gamma_alpha b`` reproduces
    the ISO mean mesh stiffness exactly (the ISO formula *is* a rectangular wave whose second
    pair adds 75 % of c'). For ``eps < 1.2`` both levels carry the ISO reduction factor.
    Spur-gear approximation: the overlap ratio of helical gears is ignored, and
    ``1 <= eps_alpha < 2`` is required.
    """
    iso = iso6336_stiffness(mesh, **iso_kwargs)
    red = iso["c_gamma_alpha"] / (iso["c_prime"] * (0.75 * iso["contact_ratio"] + 0.25))
    k1 = iso["single_pair_stiffness"] * red
    return RectangularStiffness(k1, 1.75 * k1, mesh.contact_ratio)


# --- TOML tables ----------------------------------------------------------------------------
_KEYS: dict[str, tuple[set[str], set[str]]] = {
    # model: (required keys, optional keys)
    "constant": ({"k"}, set()),
    "rectangular": ({"k_min", "k_max"}, {"contact_ratio"}),
    "trapezoidal": ({"k_min", "k_max", "ramp"}, {"contact_ratio"}),
    "fourier": ({"mean"}, {"cos", "sin"}),
    "iso6336": (set(), {"C_M", "C_R", "basic_rack_dedendum", "low_contact_factor"}),
    "iso6336-rectangular": (set(), {"C_M", "C_R", "basic_rack_dedendum", "low_contact_factor"}),
    "csv": (
        {"path"},
        {
            "contact_ratio",
            "position_column",
            "stiffness_column",
            "position_unit",
            "stiffness_unit",
            "face_width",
        },
    ),
    "pairs": (
        {"position", "stiffness"},
        {"contact_ratio", "position_unit", "stiffness_unit", "face_width", "source"},
    ),
}


def stiffness_from_dict(
    d: dict, mesh: MeshGeometry | None = None, base_dir: str | Path | None = None
) -> MeshStiffness:
    """Build a stiffness model from a TOML table.

    Parameters
    ----------
    d : dict
        Table with ``model`` and its parameters, e.g. ``{model = "rectangular", k_min = 2.67e7,
        k_max = 4.33e7, contact_ratio = 1.6}``. Models and keys:

        * ``constant``: ``k``
        * ``rectangular``: ``k_min``, ``k_max``, [``contact_ratio``]
        * ``trapezoidal``: ``k_min``, ``k_max``, ``ramp``, [``contact_ratio``]
        * ``fourier``: ``mean``, [``cos``], [``sin``]
        * ``iso6336``: constant ISO 6336-1 mean (needs ``mesh``); [``C_M``, ``C_R``,
          ``basic_rack_dedendum``, ``low_contact_factor``]
        * ``iso6336-rectangular``: :func:`iso_rectangular` (needs ``mesh``), same options
        * ``csv``: ``path``, [``contact_ratio``, ``position_column``, ``stiffness_column``,
          ``position_unit``, ``stiffness_unit``, ``face_width``] (see
          :meth:`TabulatedPair.from_csv`; ``face_width`` defaults to the mesh's)
        * ``pairs``: ``position``, ``stiffness``, [``contact_ratio``, ``position_unit``
          (default ``"base_pitch"``), ``stiffness_unit``, ``face_width``, ``source``]

        ``contact_ratio`` may be omitted when ``mesh`` is given (``mesh.contact_ratio``).
    mesh : MeshGeometry, optional
        Geometry of the mesh.
    base_dir : str or Path, optional
        Directory against which a relative CSV ``path`` is resolved.

    Raises
    ------
    ValueError
        Unknown model or key (naming the admissible ones), a missing key, or an invalid value.
    """
    if not isinstance(d, dict):
        raise ValueError(f"stiffness table must be a dict, got {type(d).__name__}")
    if mesh is not None and not isinstance(mesh, MeshGeometry):
        raise TypeError(f"mesh must be a MeshGeometry; got {type(mesh).__name__}")
    if base_dir is not None and not isinstance(base_dir, str | Path):
        raise TypeError(f"base_dir must be a path; got {type(base_dir).__name__}")
    model = d.get("model")
    if not isinstance(model, str) or model not in _KEYS:
        raise ValueError(
            f"stiffness model {short(model)} is unknown (admissible: {', '.join(sorted(_KEYS))})"
        )
    req, opt = _KEYS[model]
    keys = set(d) - {"model"}
    unknown = sorted(keys - req - opt)
    if unknown:
        raise ValueError(
            f"unknown key {short(unknown[0])} for stiffness model {model!r} "
            f"(admissible keys: {', '.join(sorted(req | opt))})"
        )
    missing = sorted(req - keys)
    if missing:
        raise ValueError(f"stiffness model {model!r} needs key {missing[0]!r}")

    def eps() -> float:
        if "contact_ratio" in d:
            return d["contact_ratio"]
        if mesh is None:
            raise ValueError(f"stiffness model {model!r}: give contact_ratio or the mesh geometry")
        return mesh.contact_ratio

    def need_mesh() -> MeshGeometry:
        if mesh is None:
            raise ValueError(f"stiffness model {model!r} needs the mesh geometry")
        return mesh

    if model == "constant":
        return ConstantStiffness(d["k"])
    if model == "rectangular":
        return RectangularStiffness(d["k_min"], d["k_max"], eps())
    if model == "trapezoidal":
        return TrapezoidalStiffness(d["k_min"], d["k_max"], eps(), d["ramp"])
    if model == "fourier":
        return FourierStiffness(d["mean"], d.get("cos", ()), d.get("sin", ()))
    iso_kw = {k: d[k] for k in keys if k in _KEYS["iso6336"][1]}
    if model == "iso6336":
        return ConstantStiffness(iso6336_stiffness(need_mesh(), **iso_kw)["mean_mesh_stiffness"])
    if model == "iso6336-rectangular":
        return iso_rectangular(need_mesh(), **iso_kw)
    fw = d.get("face_width", mesh.face_width if mesh is not None else None)
    if model == "csv":
        path = Path(d["path"])
        if base_dir is not None and not path.is_absolute():
            path = Path(base_dir) / path
        return TabulatedPair.from_csv(
            path,
            eps(),
            position_column=d.get("position_column", 0),
            stiffness_column=d.get("stiffness_column", 1),
            position_unit=d.get("position_unit", "path_fraction"),
            stiffness_unit=d.get("stiffness_unit", "N/m"),
            face_width=fw,
        )
    # pairs
    return TabulatedPair.from_arrays(
        d["position"],
        d["stiffness"],
        eps(),
        position_unit=d.get("position_unit", "base_pitch"),
        stiffness_unit=d.get("stiffness_unit", "N/m"),
        face_width=fw,
        source=d.get("source"),
    )
