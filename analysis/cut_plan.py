"""Which orders a run-up analysis cuts, and at what resolution.

:func:`default_cut_resolution` chooses the order resolution of the cut frames from the
required orders and the revolutions of the record; :func:`cut_order_list` merges required and
optional (named) orders; :func:`select_cut_orders` keeps the optional orders that the
resolution separates from every other (:func:`separation_orders`). Used by
:func:`analysis.runup_levels.runup_levels`, whose module docstring states the rules.

References
----------
A. Brandt, *Noise and Vibration Analysis*, Wiley 2011: ch. 12 (order tracking, order cuts).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from analysis.order_resolution import (
    DEFAULT_ORDER_RESOLUTION,
    RESOLUTIONS_BETWEEN_ORDERS,
    requested_orders,
    smallest_spacing,
)
from analysis.windows import main_lobe_half_width, window_info

__all__ = [
    "CUT_FRAMES",
    "CUT_WINDOW",
    "MIN_CUT_FRAMES",
    "cut_order_list",
    "default_cut_resolution",
    "enbw_and_lobe",
    "select_cut_orders",
    "separation_orders",
]

CUT_WINDOW = "flattop"
"""Window of the order-cut frames (reads a level within 0.01 dB without correction)."""

CUT_FRAMES = 32
"""A default cut frame spans at most ``1 / CUT_FRAMES`` of the revolutions of the record where
the required orders stay separated (speed resolution of a fast run-up)."""

MIN_CUT_FRAMES = 8
"""A default cut frame never spans more than ``1 / MIN_CUT_FRAMES`` of the revolutions."""


def enbw_and_lobe(window: str = CUT_WINDOW) -> tuple[float, float]:
    """ENBW [lines] and main-lobe half width [lines] of ``window``."""
    return float(window_info(window, 4096).enbw_bins), float(main_lobe_half_width(window))


def separation_orders(resolution: float, window: str = CUT_WINDOW) -> float:
    """Smallest distance [orders] of two cut orders whose bands do not reach each other's
    main lobe: ``2 h / ENBW_lines * resolution`` (band half width plus main-lobe half width;
    2.65 resolutions for the flat-top window)."""
    enbw, h = enbw_and_lobe(window)
    return 2.0 * h / enbw * float(resolution)


def default_cut_resolution(required: np.ndarray, revolutions: float, enbw: float) -> float:
    """Default resolution of order cuts [orders]:
    ``max(min(1/4, d/4), min(d/4, ENBW CUT_FRAMES / R), ENBW MIN_CUT_FRAMES / R)``.

    ``d/4`` (``d`` the smallest distance of the required orders and from order 0) is the
    coarsest resolution that still separates them; a frame of ``ENBW / res`` revolutions
    spans at most ``1/CUT_FRAMES`` of the ``R`` revolutions where ``d/4`` allows it (shorter
    frames: a finer speed resolution on a fast run-up), never more than ``1/MIN_CUT_FRAMES``,
    and the resolution is at most 1/4 order finer than needed.

    Parameters
    ----------
    required : ndarray
        The required orders (> 0).
    revolutions : float
        Revolutions of the reference shaft in the record.
    enbw : float
        Equivalent noise bandwidth of the cut window [lines].

    Returns
    -------
    float
        Resolution bandwidth [orders].
    """
    sep = smallest_spacing(required) / RESOLUTIONS_BETWEEN_ORDERS
    r = max(revolutions, 1e-300)
    return max(min(DEFAULT_ORDER_RESOLUTION, sep), min(sep, enbw * CUT_FRAMES / r),
               enbw * MIN_CUT_FRAMES / r)


def cut_order_list(orders: Any, names: Sequence[str] | None,
                   optional: Mapping[str, float] | None
                   ) -> tuple[list[tuple[float, list[str], bool]], list[str]]:
    """Required orders (with names) and optional ones, coinciding orders merged.

    Parameters
    ----------
    orders : array_like
        Required orders (> 0).
    names : sequence of str, optional
        A name per required order (default ``"order 24"``).
    optional : mapping of str to float, optional
        Named optional orders.

    Returns
    -------
    items : list of (float, list of str, bool)
        ``(order, names, required)``: required first, then optional in their order; orders
        within 1e-6 (relative) merged, their names joined.
    notes : list of str
        What was decided (empty: kept for callers that collect notes).
    """
    if optional is not None and not isinstance(optional, Mapping):
        raise TypeError(f"optional_orders must be a mapping of names to orders, got "
                        f"{type(optional).__name__}")
    req = requested_orders(orders)
    if req is None or not req.size:
        raise ValueError("orders (the orders to cut, > 0) are required")
    if names is not None and len(names) != req.size:
        raise ValueError(f"order_names: {len(names)} names for {req.size} orders")
    names = [str(n) for n in names] if names is not None else [f"order {o:g}" for o in req]
    items: list[tuple[float, list[str], bool]] = []

    def add(o: float, n: str, required: bool) -> None:
        for k, (v, ns, r) in enumerate(items):
            if abs(v - o) <= 1e-6 * max(1.0, abs(o)):
                if n not in ns:
                    ns.append(n)
                items[k] = (v, ns, r or required)
                return
        items.append((o, [n], required))

    for o, n in zip(req, names, strict=True):
        add(float(o), n, True)
    if optional:
        for n, o in optional.items():
            v = requested_orders(o, f"optional_orders[{n!r}]")
            assert v is not None
            add(float(v[0]), str(n), False)
    return items, []


def select_cut_orders(items: list[tuple[float, list[str], bool]], reach: float,
                      top_order: float
                      ) -> tuple[list[tuple[float, str, bool]], list[tuple[str, float, str]]]:
    """Required orders, and optional ones that keep ``reach`` from every other kept order.

    Parameters
    ----------
    items : list of (float, list of str, bool)
        From :func:`cut_order_list`.
    reach : float
        Smallest separation [orders] (:func:`separation_orders`), also from order 0.
    top_order : float
        Highest order analysable at the top speed; orders above are dropped.

    Returns
    -------
    kept : list of (float, str, bool)
        ``(order, name, required)`` by increasing order.
    dropped : list of (str, float, str)
        ``(name, order, why)``.
    """
    kept: list[tuple[float, str, bool]] = []
    dropped: list[tuple[str, float, str]] = []
    for o, ns, required in sorted(items, key=lambda it: not it[2]):  # required first
        name = " = ".join(ns)
        if o > top_order:
            dropped.append((name, o, f"above order {top_order:.4g}, the highest analysable at "
                                     "the top speed"))
            continue
        if required:
            kept.append((o, name, True))
            continue
        if o < reach:
            dropped.append((name, o, f"closer than {reach:.3g} orders to order 0"))
            continue
        near = min(kept, key=lambda k: abs(k[0] - o)) if kept else None
        if near is not None and abs(near[0] - o) < reach:
            dropped.append((name, o, f"{abs(near[0] - o):.3g} orders from {near[1]}"))
            continue
        kept.append((o, name, False))
    kept.sort(key=lambda k: k[0])
    return kept, dropped


