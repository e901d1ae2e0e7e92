"""Default resolution and order bands of order analysis, and the check of overlapping bands.

The defaults of :func:`analysis.maps.rpm_order_map`, :func:`analysis.orders.order_spectrum`,
:func:`analysis.orders.order_cuts` and :func:`analysis.maps.rpm_frequency_map` are chosen so
that the orders asked for are resolved, not taken from a fixed fraction of the sampling:

* **Order resolution** (resolution bandwidth = the window's ENBW, in orders)::

      res = min(1/4, d_min / 4, max_order / 64)

  where ``d_min`` is the smallest distance between the requested orders and between the
  lowest of them and order 0 (the DC line and slow drifts). A sinusoid's main lobe spans
  ``+-1.33 res`` for the Hann and the flat-top windows alike (``h / ENBW`` = 2 / 1.5 and
  5 / 3.77 lines), so orders four resolution bandwidths apart have main lobes with a gap of
  1.3 ``res`` between them. ``max_order / 64`` keeps at least 64 resolution bandwidths on the
  axis when ``max_order`` is small (a zoom on low orders). A frame spans ``ENBW_lines / res``
  revolutions (15 revolutions for the flat-top window at 1/4 order); it is limited to
  1/16 of the analysed revolutions (:data:`MIN_FRAMES`), which sets a floor to ``res`` on
  short records (the result says so in its ``notes``).
* **Order band of a cut**: the window's main lobe, ``2 h`` lines (``2.67 res``), which holds
  a sinusoid's energy whatever its offset from the lines (:func:`main_lobe_band`).
* **Frequency-map resolution** [Hz]: a quarter of the slowest shaft frequency of the record,
  ``f_shaft,min / 4`` (neighbouring integer orders four resolution bandwidths apart at the
  slowest speed, finer in orders at higher speeds), but not finer than the run-up's sweep
  lets order 1 stay within one resolution bandwidth over a frame, and frames of at most 1/16
  of the moving part of the record (:func:`default_frequency_resolution`).

A cut whose band reaches the main lobe of another requested order or of a named catalogue
line holds both: :func:`check_bands` warns with :class:`OrderBandWarning`, naming both.

References
----------
A. Brandt, *Noise and Vibration Analysis*, Wiley 2011: sec. 9.3 (resolution bandwidth,
ENBW), 10.3 (band levels from spectral lines), ch. 12 (order tracking, order cuts).
G. Heinzel, A. Rüdiger, R. Schilling, *Spectrum and spectral density estimation by the DFT*,
2002: ENBW and main-lobe widths of the Hann and flat-top windows.
The MathWorks documentation of ``rpmordermap`` and ``rpmfreqmap`` for the defaults compared
in ``docs/analysis-spectra-orders.md``.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Mapping
from typing import Any, overload

import numpy as np

from analysis.checks import require_finite, require_positive, require_real

__all__ = [
    "DEFAULT_ORDER_RESOLUTION",
    "MIN_FRAMES",
    "MIN_RESOLUTIONS_ON_AXIS",
    "RESOLUTIONS_BETWEEN_ORDERS",
    "OrderBandWarning",
    "check_bands",
    "choose_order_resolution",
    "default_frequency_resolution",
    "default_order_resolution",
    "main_lobe_band",
    "named_lines",
    "optional_positive",
    "requested_orders",
    "smallest_spacing",
]

DEFAULT_ORDER_RESOLUTION = 0.25
"""Order resolution [orders] (resolution bandwidth) when no requested orders are closer."""

RESOLUTIONS_BETWEEN_ORDERS = 4
"""Resolution bandwidths between the two closest requested orders (and order 0)."""

MIN_RESOLUTIONS_ON_AXIS = 64
"""Resolution bandwidths at least between order 0 and ``max_order``."""

MIN_FRAMES = 16
"""A default frame spans at most this fraction (``1 / MIN_FRAMES``) of the analysed record."""


class OrderBandWarning(UserWarning):
    """An order band holds the main lobe of another requested order or catalogue line."""


@overload
def optional_positive(value: None, name: str, unit: str) -> None: ...


@overload
def optional_positive(value: float, name: str, unit: str) -> float: ...


@overload
def optional_positive(value: Any, name: str, unit: str) -> float | None: ...


def optional_positive(value: Any, name: str, unit: str) -> float | None:
    """``value`` as a float > 0 (``None`` stays ``None``): a finite number, not a bool or a
    string (:class:`TypeError`), > 0 (:class:`ValueError`); the message names ``unit``."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise TypeError(f"{name} = {value!r} must be a number > 0 ({unit})")
    v = float(value)
    if not np.isfinite(v) or v <= 0:
        raise ValueError(f"{name} = {value!r} is not admissible: must be finite and > 0 {unit}")
    return v


def requested_orders(orders: Any, name: str = "orders") -> np.ndarray | None:
    """``orders`` as a checked 1-D array of finite orders > 0 (``None`` stays ``None``)."""
    if orders is None:
        return None
    if isinstance(orders, str | bytes | bool):
        raise TypeError(f"{name} = {orders!r} must be a number or a list of orders > 0")
    arr = np.asarray(orders)
    if arr.dtype == bool or not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
        raise TypeError(f"{name} = {orders!r} must be a number or a list of orders > 0")
    ords = np.atleast_1d(require_finite(arr, name))
    if ords.ndim != 1 or np.any(ords <= 0):
        raise ValueError(f"{name} must be a 1-D list of orders > 0 (got {orders!r})")
    return ords


def smallest_spacing(orders: np.ndarray) -> float:
    """Smallest distance between distinct requested orders and from the lowest to order 0."""
    u = np.unique(np.concatenate(([0.0], np.asarray(orders, dtype=float))))
    return float(np.min(np.diff(u)))


def default_order_resolution(orders: np.ndarray | None, max_order: float | None) -> float:
    """``min(1/4, d_min / 4, max_order / 64)`` [orders] (see the module docstring)."""
    orders = requested_orders(orders, "orders")
    max_order = optional_positive(max_order, "max_order", "orders")
    res = DEFAULT_ORDER_RESOLUTION
    if orders is not None and orders.size:
        res = min(res, smallest_spacing(orders) / RESOLUTIONS_BETWEEN_ORDERS)
    if max_order is not None:
        res = min(res, float(max_order) / MIN_RESOLUTIONS_ON_AXIS)
    return res


def choose_order_resolution(
    resolution: float | None,
    orders: np.ndarray | None,
    max_order: float | None,
    revolutions: float,
    enbw_lines: float,
) -> tuple[float, str]:
    """The resolution to use [orders] and a note when the record limited the default.

    A given ``resolution`` is used as it is. The default (:func:`default_order_resolution`)
    is coarsened where a frame of ``enbw_lines / res`` revolutions would exceed
    ``revolutions / MIN_FRAMES``.
    """
    if resolution is not None:
        return optional_positive(resolution, "resolution", "orders"), ""
    res = default_order_resolution(orders, max_order)
    revolutions = require_positive(require_real(revolutions, "revolutions"), "revolutions",
                                   allow_zero=True)
    enbw_lines = require_positive(require_real(enbw_lines, "enbw_lines"), "enbw_lines")
    floor = enbw_lines * MIN_FRAMES / max(revolutions, 1e-300)
    if not np.isfinite(floor):
        raise ValueError(f"enbw_lines = {enbw_lines:g} over revolutions = {revolutions:g} give "
                         "no finite resolution; check them")
    if res >= floor:
        return res, ""
    note = (
        f"order resolution {floor:.3g} orders instead of {res:.3g}: the record holds "
        f"{revolutions:.4g} revolutions, and a default frame spans at most 1/{MIN_FRAMES} of "
        "them (give resolution= to override)"
    )
    return floor, note


def default_frequency_resolution(
    shaft_hz_min: float,
    shaft_hz_max: float,
    duration_s: float,
    enbw_lines: float,
    orders: np.ndarray | None = None,
) -> float:
    """Default resolution bandwidth [Hz] of an rpm-frequency map.

    ``max(f_min / 4, sqrt(ENBW_lines * (f_max - f_min) / duration),
    ENBW_lines * MIN_FRAMES / duration)`` with ``f_min``, ``f_max`` the slowest and fastest
    shaft frequency of the moving part of the record and ``duration`` its length:

    * a quarter order at the slowest speed separates neighbouring integer orders by four
      resolution bandwidths everywhere (:func:`default_order_resolution` of ``orders`` at
      that speed for order cuts read from frequency frames);
    * no finer than the mean sweep allows: over a frame of ``T = ENBW_lines / res`` seconds
      the shaft frequency moves by ``T (f_max - f_min) / duration``; the square root is the
      resolution at which this equals ``res`` (order 1 moves by one resolution bandwidth per
      frame; order ``k`` by ``k`` of them: a fixed-frequency map blurs high orders of a fast
      run-up, an order map does not);
    * frames of at most ``1 / MIN_FRAMES`` of the record.
    """
    shaft_hz_min, shaft_hz_max, duration_s, enbw_lines = (
        require_positive(require_real(v, k), k, allow_zero=True) for k, v in (
            ("shaft_hz_min", shaft_hz_min), ("shaft_hz_max", shaft_hz_max),
            ("duration_s", duration_s), ("enbw_lines", enbw_lines)))
    with np.errstate(over="ignore"):
        res = _finite_resolution(shaft_hz_min, shaft_hz_max, duration_s, enbw_lines, orders)
    return res


def _finite_resolution(shaft_hz_min: float, shaft_hz_max: float, duration_s: float,
                       enbw_lines: float, orders: Any) -> float:
    res = default_order_resolution(orders, None) * shaft_hz_min
    duration = max(duration_s, 1e-300)
    sweep = np.sqrt(enbw_lines * max(shaft_hz_max - shaft_hz_min, 0.0) / duration)
    floor = enbw_lines * MIN_FRAMES / duration
    out = float(max(res, sweep, floor))
    if not np.isfinite(out):
        raise ValueError(f"shaft_hz_min .. shaft_hz_max = {shaft_hz_min:g} .. {shaft_hz_max:g} "
                         f"Hz over {duration_s:g} s give no finite resolution; check the units")
    return out


def main_lobe_band(half_width_lines: float, spacing: float) -> float:
    """Default order band: the main lobe, ``2 h`` lines of ``spacing`` (orders or Hz)."""
    return 2.0 * half_width_lines * spacing


def named_lines(lines: Any) -> list[tuple[str, float]]:
    """Catalogue lines as ``(name, order)`` pairs from a mapping ``{name: order}`` or an
    iterable of ``(name, order)`` pairs; orders finite and > 0."""
    if lines is None:
        return []
    items: Iterable[Any] = lines.items() if isinstance(lines, Mapping) else lines
    if isinstance(items, str | bytes):
        raise TypeError("lines must be a mapping {name: order} or (name, order) pairs")
    out: list[tuple[str, float]] = []
    for item in items:
        try:
            name, order = item
        except (TypeError, ValueError):
            raise TypeError(
                f"lines: {item!r} is not a (name, order) pair; give a mapping {{name: order}} "
                "or (name, order) pairs"
            ) from None
        if isinstance(order, bool) or not isinstance(order, int | float | np.integer | np.floating):
            raise TypeError(f"lines: the order of {name!r} must be a number (got {order!r})")
        value = float(order)
        if not np.isfinite(value) or value <= 0:
            raise ValueError(f"lines: the order of {name!r} must be finite and > 0 (got {order!r})")
        out.append((str(name), value))
    return out


def _same(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-9 * max(1.0, abs(a), abs(b))


def check_bands(
    orders: np.ndarray,
    half_band: float,
    main_lobe: float,
    lines: list[tuple[str, float]],
    *,
    what: str,
    stacklevel: int = 3,
) -> list[str]:
    """Warn when the band of a requested order reaches another order's main lobe.

    Parameters
    ----------
    orders : numpy.ndarray
        Requested orders.
    half_band : float
        Half width of the bands [orders] (the widest over the record, for bands fixed in Hz).
    main_lobe : float
        Half width of a sinusoid's main lobe [orders] (likewise the widest).
    lines : list of (str, float)
        Named catalogue lines; a line at a requested order names it.
    what : str
        How the bands were set, for the message (e.g. ``"bandwidth 0.67 orders"``).
    stacklevel : int
        Passed to :func:`warnings.warn`.

    Returns
    -------
    list of str
        One text per conflict (empty if none); a :class:`OrderBandWarning` lists them all.
    """
    def label(o: float) -> str:
        names = [n for n, v in lines if _same(v, o)]
        return f"order {o:g}" + (f" ({', '.join(names)})" if names else "")

    reach = half_band + main_lobe
    uniq = np.unique(orders)
    others = [(label(float(o)), float(o)) for o in uniq]
    others += [(f"line '{n}' at order {v:g}", v) for n, v in lines
               if not any(_same(v, float(o)) for o in uniq)]  # fmt: skip
    found = []
    for k in uniq:
        k = float(k)
        for text, v in others:
            if not _same(v, k) and abs(v - k) < reach:
                found.append(
                    f"the band of {label(k)} ({k - half_band:.4g} to {k + half_band:.4g}) "
                    f"reaches {text} (main lobe +-{main_lobe:.3g})"
                )
    if found:
        warnings.warn(
            f"order cuts ({what}): " + "; ".join(found) + ". The cut holds both; give a finer "
            "resolution= (orders four resolutions apart are separated) or a narrower band",
            OrderBandWarning,
            stacklevel=stacklevel,
        )
    return found
