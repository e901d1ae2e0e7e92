"""The sample rate of a printed time column, with the rounding of the print taken into account.

A time column written with 8 decimals at 25.6 kHz (``0.00003906``, ``0.00007812``, ...) is
uniform, but its steps jitter by up to 1e-8 s (2.6e-4 of the 39.0625 µs step) because every
value is rounded to the printed precision. A fixed relative tolerance either refuses such a
column or lets real gaps through. Here the tolerance is derived from the print itself:

* :func:`print_precision` reads tokens of the column as printed and returns the absolute
  unit of the last printed digit of fixed-notation values (``10**-decimals`` for the usual
  number of decimals) and the relative unit of values in exponent notation
  (``10**(1 - significant digits)``);
* :func:`uniform_rate` accepts the column when every step is within the rounding of its two
  ends of the typical (median) step -- a missing sample is named by the step it makes -- and
  every value lies within the rounding bound ``0.5 * (abs_unit + rel_unit * |t|)`` (plus a
  few ulp) of a uniform grid through the first and last value (twice the bound: both ends
  are rounded too); the rate is snapped to the roundest number (1000 Hz, 100 Hz, 10 Hz,
  1 Hz, ... 0.001 Hz steps) whose grid still fits all values.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from analysis.checks import (
    require_instance,
    require_positive,
    require_real,
    require_real_array,
)

__all__ = ["PrintPrecision", "grid_fits", "print_precision", "uniform_rate"]

_TOKEN = re.compile(r"[+-]?(\d*)(?:\.(\d*))?(?:[eE][+-]?\d+)?")
_EPS = np.finfo(np.float64).eps


@dataclass(frozen=True)
class PrintPrecision:
    """Rounding units of printed numbers: ``|printed - true| <= 0.5 * (absolute + relative *
    |value|)``."""

    absolute: float = 0.0
    relative: float = 0.0

    def bound(self, values: np.ndarray) -> np.ndarray:
        """Largest rounding error of each printed value (plus 4 ulp of float64 parsing)."""
        mag = np.abs(values)
        return 0.5 * (self.absolute + self.relative * mag) + 4 * _EPS * mag


def print_precision(tokens: Iterable[str]) -> PrintPrecision:
    """Precision of a column from some of its printed tokens.

    Parameters
    ----------
    tokens : iterable of str
        Printed values (e.g. the first and last thousand of a column); tokens that are not
        plain decimal numbers are ignored.

    Returns
    -------
    PrintPrecision
        ``absolute = 10**-d`` with ``d`` the most frequent number of decimals among
        fixed-notation tokens with a decimal point (``%.8f`` -> 1e-8; ties go to fewer
        decimals; integers such as the ``0`` that ``%g`` prints count only when the column
        holds nothing else, then 1), 0 if there are none; ``relative = 10**(1 - s)`` with
        ``s`` the most significant digits among tokens in exponent notation (``%.6e`` ->
        1e-6), 0 if there are none.
    """
    decimals: Counter[int] = Counter()
    integers = 0
    digits = 0
    for tok in tokens:
        t = tok.strip()
        m = _TOKEN.fullmatch(t)
        if m is None or not (m.group(1) or m.group(2)):
            continue
        whole, frac = m.group(1), m.group(2)
        if "e" in t.lower():
            digits = max(digits, len((whole + (frac or "")).lstrip("0")) or 1)
        elif frac is None and "." not in t:
            integers += 1  # "0" or "2" from %g: exact, says nothing about the precision
        else:
            decimals[len(frac or "")] += 1
    absolute = 0.0
    if decimals:
        top = max(decimals.values())
        absolute = 10.0 ** -min(d for d, k in decimals.items() if k == top)
    elif integers and not digits:
        absolute = 1.0  # a column of integers
    return PrintPrecision(absolute=absolute, relative=10.0 ** (1 - digits) if digits else 0.0)


def _misfit(t: np.ndarray, t0: float, dt: float, allowed: np.ndarray) -> np.ndarray:
    grid = t0 + np.arange(t.size, dtype=np.float64) * dt
    return np.abs(t - grid) > allowed


def uniform_rate(
    time: np.ndarray, precision: PrintPrecision, *, name: str = "time"
) -> tuple[float, float]:
    """Sample rate and start of a uniformly sampled, printed time axis.

    Parameters
    ----------
    time : numpy.ndarray
        Time values [s] as parsed, at least two, finite.
    precision : PrintPrecision
        Rounding of the print (:func:`print_precision`); ``PrintPrecision()`` for exact
        values.
    name : str
        Name for messages.

    Returns
    -------
    rate : float
        Sample rate [Hz], snapped to the roundest multiple of 1000, 100, 10, 1, ... 0.001 Hz
        whose grid fits the printed values (a short column printed coarsely fits several).
    start : float
        The first time value [s].

    Raises
    ------
    ValueError
        Fewer than two values, non-finite values, values that do not increase, or a value off
        the uniform grid by more than the print can explain (naming the sample index, the
        deviation and the allowed bound).
    """
    require_instance(precision, PrintPrecision, "precision")
    t = np.asarray(time, dtype=np.float64)
    if t.size < 2:
        raise ValueError(f"{name}: needs at least two samples to define a sample rate")
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise ValueError(f"{name}: sample index {i} is NaN/inf")
    bound = precision.bound(t)
    step = np.diff(t)
    if np.any(step <= 0):
        i = int(np.flatnonzero(step <= 0)[0])
        hint = ""
        if precision.absolute and precision.absolute >= (t[-1] - t[0]) / (t.size - 1):
            hint = (
                f"; the print resolution ({precision.absolute:g} s) is not finer than the "
                "sample interval: write the time column with more decimals or give fs="
            )
        raise ValueError(
            f"{name} does not increase between sample index {i} and {i + 1}{hint}"
        )
    # a gap or a jump shows as one step off the typical (median) step. Step i is off the true
    # step by at most c_i = bound_i + bound_(i+1) (both ends rounded); the median step is off
    # by at most the upper median of c (at least half the steps lie beyond it otherwise)
    typical = float(np.median(step))
    c = bound[:-1] + bound[1:]
    # the print can only be trusted to half a step: a missing or doubled sample moves a step
    # by a whole one (prints that coarse rarely reach here: their steps repeat or vanish)
    allowed_step = np.minimum(c + float(np.quantile(c, 0.5, method="higher")), 0.5 * typical)
    off = np.abs(step - typical) > allowed_step
    if off.any():
        i = int(np.flatnonzero(off)[0])
        raise ValueError(
            f"{name} is not uniformly sampled: the step from sample index {i} to {i + 1} is "
            f"{step[i]:.9g} s, the typical step {typical:.9g} s (allowed deviation from its "
            f"printed precision {allowed_step[i]:.3g} s); resample or give fs="
        )
    t0 = float(t[0])
    dt = (float(t[-1]) - t0) / (t.size - 1)
    allowed = bound + max(bound[0], bound[-1])
    bad = _misfit(t, t0, dt, allowed)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        dev = float(t[i] - (t0 + i * dt))
        raise ValueError(
            f"{name} is not uniformly sampled: sample index {i} is {dev:.3g} s off the uniform "
            f"grid of step {dt:.9g} s, more than its printed precision explains "
            f"({allowed[i]:.3g} s); resample or give fs="
        )
    rate = 1.0 / dt
    exact = bound + bound[0]
    last = t.size - 1
    for decimals in range(-3, 4):  # coarsest first: 25600 before 25602 when both fit
        snapped = round(rate, decimals)
        if snapped <= 0 or abs(t[-1] - (t0 + last / snapped)) > exact[-1]:
            continue
        if not _misfit(t, t0, 1.0 / snapped, exact).any():
            return float(snapped), t0
    return rate, t0


def grid_fits(time: np.ndarray, rate: float, precision: PrintPrecision) -> bool:
    """Whether ``time`` is the grid ``time[0] + i / rate`` within the printed precision."""
    t = require_real_array(time, "time", ndim=1, min_size=1, max_abs=1e300)
    r = require_positive(require_real(rate, "rate"), "rate")
    require_instance(precision, PrintPrecision, "precision")
    if not t.size / r <= 1e300:
        raise ValueError(f"rate = {rate!r} Hz is not admissible: the grid of {t.size} samples "
                         "would span more than 1e300 s")
    bound = precision.bound(t)
    return not _misfit(t, float(t[0]), 1.0 / rate, bound + max(bound[0], bound[-1])).any()
