"""Vold-Kalman order tracking: the time waveform, amplitude and phase of chosen orders.

:func:`order_waveform` extracts orders with the second-generation Vold-Kalman filter (Vold &
Leuridan 1993; Vold, Mains & Blough 1997), in its least-squares form (Feldbauer & Höldrich
2000; Pan & Lin 2006), for a run-up, a coast-down or any speed profile;
:func:`remove_orders` subtracts them from the signal (MATLAB ``orderwaveform``; rota-order's
``order_waveform`` and ``remove_orders``).

Model. Order ``k`` of shaft ``s_k`` has the carrier phase ``theta_k(t) = o_k phi_{s_k}(t)``
(``phi``: shaft angle [rad], from an rpm trace, an angle trace or a tacho) and the waveform::

    x_k(n) = Re(a_k(n) exp(i theta_k(n))) = u_k(n) cos theta_k(n) - v_k(n) sin theta_k(n),

where ``a_k = u_k + i v_k`` is the complex envelope: ``|a_k|`` is the **peak** amplitude in
the signal's units and ``arg a_k`` the phase (no factor 2: a cosine of amplitude A and phase
phi has ``a_k = A exp(i phi)``). The envelopes minimise::

    J = sum_n (x(n) - sum_k x_k(n))^2 + sum_k (r_k^2 / 2) sum_n |nabla^p a_k(n)|^2

with ``nabla^p`` the p-th forward difference (``p = filter_order + 1``: the *structural
equation* of the filter says that the envelope is locally a polynomial of degree ``p - 1``).
The data term is the *real* signal: each order is modelled with its negative-frequency
mirror (the conjugate pair of Vold, Mains & Blough), so that a stationary component is
reproduced exactly to the record ends and an order close to 0 Hz is not biased by its own
image.

Weight and bandwidth. Feldbauer & Höldrich and Tůma write the filter for the analytic
envelope ``c_k = a_k / 2`` with the data term ``|x - sum c_k e^{i theta_k}|^2`` and weight
``r^2 |nabla^p c_k|^2``; for a tone at ``Delta f`` from the carrier of a single order the
envelope is then multiplied by

    H(Delta f) = 1 / (1 + r^2 (2 sin(pi Delta f / fs))^(2p)).

The real data term above averages to ``|X - a|^2 / 2`` per sample (the ``2 theta`` part
oscillates out), so the weight ``r^2 / 2`` on ``|nabla^p a|^2`` gives the same ``H``: the
``r`` reported is the published one. The bandwidth ``B`` [Hz] is the full width of the
half-power band, ``|H(+-B/2)|^2 = 1/2``:

    r = sqrt(sqrt(2) - 1) / (2 sin(pi B / (2 fs)))^p,

which for ``B << fs`` is ``(1.604 fs / (2 pi B))^2`` for ``filter_order=1`` and
``(1.727 fs / (2 pi B))^3`` for ``filter_order=2``: Tůma's (2005) and Feldbauer & Höldrich's
constants 1.58 and 1.70 are these, rounded (they give a band 1.5 % wider). Measured with
stepped sines: the requested width within 0.1 % (``tests/analysis/test_vold_kalman.py``).

Joint solution. With ``joint=True`` all orders are unknowns of one least-squares problem,
which attributes the signal to the orders jointly: two orders that cross in frequency are
separated by the smoothness of their envelopes. ``joint=False`` solves each order alone, which
is cheaper, but an order passing within about a bandwidth leaks into it (beats).

Numerics and memory: :mod:`analysis.vold_kalman_solver` (Givens QR of the banded stacked
matrix; memory linear in the record, or bounded by checkpoints when ``max_memory`` asks).
Results: :mod:`analysis.vold_kalman_results`; input checks and speed references:
:mod:`analysis.vold_kalman_checks`; figures: :mod:`analysis.vold_kalman_plots`.

References
----------
Vold, H., & Leuridan, J. (1993). High resolution order tracking at extreme slew rates, using
Kalman tracking filters. SAE Technical Paper 931288.
Vold, H., Mains, M., & Blough, J. (1997). Theoretical foundations for high performance order
tracking with the Vold-Kalman tracking filter. SAE Technical Paper 972007.
Feldbauer, C., & Höldrich, R. (2000). Realization of a Vold-Kalman tracking filter - a least
squares problem. Proc. COST G-6 Conference on Digital Audio Effects (DAFx-00), Verona.
Tůma, J. (2005). Setting the passband width in the Vold-Kalman order tracking filter. Proc.
12th International Congress on Sound and Vibration (ICSV12), Lisbon.
Pan, M.-C., & Lin, Y.-F. (2006). Further exploration of Vold-Kalman-filtering order tracking
with shaft-speed information - I: Theoretical part, numerical implementation and parameter
investigations. Mechanical Systems and Signal Processing 20(5), 1134-1154.
Blough, J. R. (2007). Understanding the Kalman/Vold-Kalman order tracking filters'
formulation and behavior. SAE Technical Paper 2007-01-2221 (07NVC-254).
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

from analysis.checks import require_positive, require_real, require_real_array
from analysis.inputs import signal_input
from analysis.vold_kalman_checks import (
    per_order,
    positions,
    real_number,
    real_numbers,
    reference_lengths,
    result_bytes,
    shaft_list,
    shaft_positions,
    speed_references,
)
from analysis.vold_kalman_results import OrderRemoval, OrderWaveforms
from analysis.vold_kalman_solver import minimum_working_bytes, plan, solve

__all__ = [
    "DEFAULT_MAX_MEMORY",
    "MAX_BANDWIDTH_FRACTION",
    "MAX_WEIGHT",
    "OrderRemoval",
    "OrderWaveforms",
    "bandwidth_to_weight",
    "order_waveform",
    "remove_orders",
    "weight_to_bandwidth",
]

#: Default bound [bytes] on the memory one call allocates (result and solver arrays).
DEFAULT_MAX_MEMORY = 2 * 1024**3
#: Widest admissible bandwidth, as a fraction of the sample rate.
MAX_BANDWIDTH_FRACTION = 0.1
#: Largest admissible weight r: rounding errors then stay below about 1e-4 of the amplitude.
MAX_WEIGHT = 1e12
_HALF_POWER = np.sqrt(2.0) - 1.0
_WEIGHT_LIMIT = 1e150  # the largest weight weight_to_bandwidth takes (its square is finite)
_SINGULAR = 1e-6  # pivot of R below which the envelopes are not determined (measured >= 4)


# ------------------------------------------------------------------------- bandwidth <-> r


def _difference_order(filter_order: Any) -> int:
    if isinstance(filter_order, bool) or not isinstance(filter_order, numbers.Integral):
        raise TypeError(f"filter_order = {filter_order!r} must be the integer 1 or 2")
    if filter_order not in (1, 2):
        raise ValueError(
            f"filter_order = {filter_order!r} is not admissible: 1 (2 poles, second "
            "difference) or 2 (3 poles, third difference)"
        )
    return int(filter_order) + 1


def bandwidth_to_weight(bandwidth: Any, fs: float, filter_order: int = 1) -> np.ndarray:
    """Weight ``r`` of the structural equation for a -3 dB bandwidth.

    Parameters
    ----------
    bandwidth : float or array_like
        Full width [Hz] of the half-power band around the tracked order.
    fs : float
        Sample rate [Hz].
    filter_order : {1, 2}
        1: second difference (2 poles, -40 dB/decade); 2: third difference (3 poles).

    Returns
    -------
    numpy.ndarray
        ``r = sqrt(sqrt(2) - 1) / (2 sin(pi B / (2 fs)))^p`` with ``p = filter_order + 1``.

    Notes
    -----
    The single-order filter multiplies the envelope of a tone ``Delta f`` from the carrier
    by ``H = 1 / (1 + r^2 (2 sin(pi Delta f / fs))^(2p))``, the frequency response of
    ``(I + r^2 D^T D)^-1`` on an infinite record (``D``: p-th difference); ``|H|^2 = 1/2``
    at ``Delta f = B/2`` gives ``r``. For ``B << fs``: ``r = (1.604 fs / (2 pi B))^2``
    (order 1) and ``(1.727 fs / (2 pi B))^3`` (order 2); Tůma (2005) gives 1.58 and 1.70.
    """
    p = _difference_order(filter_order)
    f = require_positive(require_real(fs, "fs"), "fs")
    b = require_real_array(bandwidth, "bandwidth", min_size=0)
    if b.size and (b.min() <= 0.0 or b.max() > f):
        raise ValueError(f"bandwidth must lie in (0, fs] = (0, {f:g}] Hz; got {b.min():g} .. "
                         f"{b.max():g} Hz")
    with np.errstate(all="ignore"):
        r = np.sqrt(_HALF_POWER) / (2.0 * np.sin(np.pi * b / (2.0 * f))) ** p
    if not np.all(np.isfinite(r)):
        raise ValueError(f"bandwidth = {b.min():g} Hz is too narrow for fs = {f:g} Hz: its "
                         "weight overflows float64")
    return r


def weight_to_bandwidth(weight: Any, fs: float, filter_order: int = 1) -> np.ndarray:
    """-3 dB bandwidth [Hz] of the weight ``r`` (inverse of :func:`bandwidth_to_weight`).

    Parameters
    ----------
    weight : float or array_like
        Weight ``r`` of the structural equation (Feldbauer & Höldrich / Tůma convention).
    fs : float
        Sample rate [Hz].
    filter_order : {1, 2}
        As in :func:`bandwidth_to_weight`.

    Returns
    -------
    numpy.ndarray
        ``B = (2 fs / pi) arcsin(((sqrt(2) - 1) / r^2)^(1 / (2p)) / 2)`` [Hz].
    """
    p = _difference_order(filter_order)
    f = require_positive(require_real(fs, "fs"), "fs")
    r = require_real_array(weight, "weight", min_size=0)
    r_min = np.sqrt(_HALF_POWER) / 2.0**p  # the bandwidth fs
    if r.size and (r.min() < r_min or r.max() > _WEIGHT_LIMIT):
        raise ValueError(f"weight must lie in [{r_min:.6g}, {_WEIGHT_LIMIT:g}] (bandwidths "
                         f"fs .. near 0); got {r.min():g} .. {r.max():g}")
    with np.errstate(under="ignore"):
        arg = np.minimum(0.5 * (_HALF_POWER / r**2) ** (1.0 / (2 * p)), 1.0)
    return 2.0 * f / np.pi * np.arcsin(arg)


# ---------------------------------------------------------------------------- extraction


def order_waveform(
    x: Any,
    fs: Any = None,
    *,
    orders: Any,
    bandwidth: Any,
    rpm: Any = None,
    angle: Any = None,
    tacho: Any = None,
    shafts: Any = None,
    filter_order: int = 1,
    joint: bool = True,
    time: Any = None,
    axis: int | None = None,
    pulses_per_rev: Any = 1,
    missing_teeth: int = 0,
    max_memory: float = DEFAULT_MAX_MEMORY,
    units: str | None = None,
    name: str | None = None,
) -> OrderWaveforms:
    """Waveform, amplitude and phase of orders by the Vold-Kalman filter.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal, time along the last axis (or ``axis``); a DataArray brings its time
        coordinate and may carry the speed reference as a coordinate. Several channels share
        one factorisation.
    fs : float, optional
        Sample rate [Hz] (or ``time``).
    orders : float or sequence of float
        Orders to track (cycles per revolution of their shaft), > 0.
    bandwidth : float or sequence of float
        -3 dB bandwidth [Hz] of each order's filter: the full width of the half-power band
        around the order (MATLAB's ``Bandwidth``; rota-order's ``bandwidth`` is half of it).
        It sets how fast the envelope may change (10-90 % rise time ``0.72 / B`` s with
        ``filter_order=1``, ``0.77 / B`` with 2) and how far another order must be to be
        rejected (-17.6 dB at ``B`` from the order, -31 dB at ``1.5 B`` with
        ``filter_order=1``; -29 and -50 dB with 2). Admissible: ``0 < B <= 0.1 fs``, and
        wide enough for ``r <= 1e12`` (:data:`MAX_WEIGHT`).
    rpm, angle, tacho : array_like, optional
        Speed reference, exactly one, sampled with ``x``: speed [min-1], angle [rad] or tacho
        pulse train (:func:`analysis.speed.from_tacho` with ``pulses_per_rev`` and
        ``missing_teeth``). Several shafts: a list of such arrays or a 2-D array (one row or
        column per shaft), with ``shafts`` mapping each order to one of them (MATLAB's
        ``rpmrefidx``).
    shafts : int or sequence of int, optional
        Speed reference of each order (default 0 for all).
    filter_order : {1, 2}
        1: second difference, 2 poles (default, as MATLAB); 2: third difference, 3 poles
        (steeper band edges, slower envelope response).
    joint : bool
        Solve all orders in one system (default; separates crossing orders), or each alone.
    time : array_like, optional
        Uniform time axis [s] instead of ``fs``.
    axis : int, optional
        Time axis of a multi-dimensional array.
    pulses_per_rev, missing_teeth : int
        Tacho wheel (``tacho=`` only); ``pulses_per_rev`` may be a list, one per tacho.
    max_memory : float
        Bound [bytes] on the memory the call allocates (result and solver); default 2 GiB.
        A system larger than its share is solved in blocks (same result, twice the
        rotations); one whose result alone does not fit is refused.
    units, name : str, optional
        Units and name of the signal (default from a DataArray, else ``"1"``/``"x"``).

    Returns
    -------
    OrderWaveforms
        Envelopes (peak amplitude and phase), waveforms, residual and the parameters used.

    Raises
    ------
    ValueError
        Inadmissible values (naming the parameter and the admissible range): an order at or
        above the Nyquist frequency at the highest speed, a bandwidth <= 0, above 0.1 fs or
        too narrow for the numerics, unequal lengths, NaN or inf, a negative speed, the same
        order of the same shaft twice, a system larger than ``max_memory``.
    TypeError
        A bool or a string where a number is needed.

    Notes
    -----
    The envelopes minimise ``sum_n (x - sum_k Re(a_k e^{i theta_k}))^2 + sum_k (r_k^2/2)
    sum_n |nabla^p a_k|^2`` (module docstring), solved by Givens rotations of the banded
    stacked matrix (:mod:`analysis.vold_kalman_solver`): ``O(n (2 m + 1) (2 m p + 1)^2)``
    operations for ``m`` joint orders and ``16 m n (2 m p + 1 + c)`` bytes of working
    memory in one pass (``c`` channels), plus the result, ``8 n (3 m c + 2 c + ...)``.
    The carrier phase is ``orders[k] * angle``, the angle counted from 0 at the first
    sample (from ``rpm``) or as given (``angle``), or from the first tacho pulse.

    References
    ----------
    See the module docstring (Vold & Leuridan 1993; Vold, Mains & Blough 1997; Feldbauer &
    Höldrich 2000; Tůma 2005; Pan & Lin 2006).
    """
    if isinstance(fs, bool | np.bool_) or (fs is not None and isinstance(fs, str)):
        raise TypeError(f"fs = {fs!r} must be a number (Hz)")
    if isinstance(joint, np.bool_):
        joint = bool(joint)
    if not isinstance(joint, bool):
        raise TypeError(f"joint = {joint!r} must be True or False")
    p = _difference_order(filter_order)
    budget = real_number(max_memory, "max_memory")
    if budget <= 0:
        raise ValueError(f"max_memory = {max_memory!r} is not admissible: must be > 0 bytes")
    order_values = real_numbers(orders, "orders")
    m = order_values.size
    if m == 0:
        raise ValueError("orders: give at least one order")
    if np.any(order_values <= 0):
        raise ValueError(f"orders = {orders!r} is not admissible: every order must be > 0")
    ref_len = reference_lengths(rpm if rpm is not None else angle if angle is not None else tacho)
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name, lengths=tuple(ref_len))
    n = sig.n
    fs_v = sig.fs
    bw = per_order(real_numbers(bandwidth, "bandwidth"), m, "bandwidth")
    top = MAX_BANDWIDTH_FRACTION * fs_v
    for b in bw:
        if not 0.0 < b <= top:
            raise ValueError(
                f"bandwidth = {b:g} Hz is not admissible: must be > 0 and <= "
                f"{MAX_BANDWIDTH_FRACTION:g} fs = {top:g} Hz"
            )
    weight = bandwidth_to_weight(bw, fs_v, filter_order)
    if np.any(weight > MAX_WEIGHT):
        k = int(np.argmax(weight))
        narrowest = float(weight_to_bandwidth(MAX_WEIGHT, fs_v, filter_order))
        raise ValueError(
            f"bandwidth = {bw[k]:g} Hz is too narrow for fs = {fs_v:g} Hz with filter_order="
            f"{filter_order}: its weight r = {weight[k]:.3g} exceeds {MAX_WEIGHT:g}, beyond "
            f"which rounding errors exceed 1e-4 of the amplitude; the narrowest admissible is "
            f"{narrowest:.3g} Hz (decimate the signal first, or use filter_order=1)"
        )
    given = next((v for v in (rpm, angle, tacho) if v is not None), None)
    n_shafts = len(shaft_list(given, n)) if given is not None else 1
    if shafts is None:
        shaft_idx = np.zeros(m, dtype=np.int64)
    else:
        shaft_idx = np.array(shaft_positions(shafts, m, n_shafts), dtype=np.int64)
    seen: dict[tuple[float, int], int] = {}
    for k in range(m):
        key = (float(order_values[k]), int(shaft_idx[k]))
        if key in seen:
            raise ValueError(
                f"orders: order {key[0]:g} of shaft {key[1]} is given twice (positions "
                f"{seen[key]} and {k}); each order can be tracked once"
            )
        seen[key] = k
    if n < max(16, 2 * m * p + 1):
        raise ValueError(
            f"x has {n} samples; {m} order(s) with filter_order={filter_order} need at least "
            f"{max(16, 2 * m * p + 1)}"
        )
    lead = sig.lead
    nch = int(np.prod(lead)) if lead else 1
    need = result_bytes(nch, m, n, n_shafts)  # checked before any array of n is made
    solve_m = m if joint else 1
    work = plan(n, solve_m, p, nch, budget - need)
    if work is None:
        least = minimum_working_bytes(n, solve_m, p, nch)
        raise ValueError(
            f"max_memory = {budget:.4g} bytes is too small: the result of {m} order(s) x "
            f"{nch} channel(s) x {n} samples needs {need:.4g} bytes and the solver at least "
            f"{least:.4g} more; raise max_memory or analyse a shorter record"
        )
    t = sig.time if sig.time is not None else sig.t0 + np.arange(n) / fs_v
    angles, speeds, reference = speed_references(
        sig, rpm, angle, tacho, pulses_per_rev, missing_teeth, t
    )
    top_rpm = speeds.max(axis=1)
    if not np.all(top_rpm > 0):
        i = int(np.flatnonzero(~(top_rpm > 0))[0])
        raise ValueError(f"speed reference {i}: the shaft does not turn (highest speed 0 min-1)")
    nyq = 0.5 * fs_v
    for k in range(m):
        f_top = order_values[k] * top_rpm[shaft_idx[k]] / 60.0
        if f_top + 0.5 * bw[k] >= nyq:
            raise ValueError(
                f"orders: order {order_values[k]:g} reaches {f_top:.6g} Hz at the highest speed "
                f"({top_rpm[shaft_idx[k]]:.6g} min-1); with half its bandwidth it must stay "
                f"below the Nyquist frequency fs/2 = {nyq:.6g} Hz (admissible orders < "
                f"{(nyq - 0.5 * bw[k]) * 60.0 / top_rpm[shaft_idx[k]]:.6g})"
            )
    freq = order_values[:, None] * speeds[shaft_idx] / 60.0
    for k in range(m):
        for j in range(k):
            if np.max(np.abs(freq[k] - freq[j])) <= 1e-9 * np.max(freq[k]):
                raise ValueError(
                    f"orders: order {order_values[j]:g} of shaft {shaft_idx[j]} and order "
                    f"{order_values[k]:g} of shaft {shaft_idx[k]} have the same frequency over "
                    "the whole record; the data cannot tell them apart: track it once"
                )
    notes = []
    if work.n_blocks > 1:
        notes.append(
            f"solved in {work.n_blocks} blocks of {work.block} samples within max_memory "
            f"(checkpointed: same result, twice the rotations)"
        )
    for k in range(m):
        low = freq[k] < 0.5 * bw[k]
        if low.any():
            notes.append(
                f"order {order_values[k]:g} is below half its bandwidth ({0.5 * bw[k]:.3g} Hz) "
                f"for {low.mean():.1%} of the record: the order and its mirror image overlap "
                "there, its envelope is set more by smoothness than by the data"
            )
    xs = np.asarray(sig.values, dtype=float).reshape(nch, n)
    rows = weight / np.sqrt(2.0)
    env = np.empty((nch, m, n), dtype=complex)
    groups = [list(range(m))] if joint else [[k] for k in range(m)]
    for g in groups:
        e, pivot = solve(angles, order_values[g], shaft_idx[g], xs, rows[g], p, work.block)
        if not (pivot > _SINGULAR and np.all(np.isfinite(e))):
            raise ValueError(
                f"orders {order_values[g].tolist()}: the envelopes are not determined by the "
                "data (the carriers coincide over the whole record, or a shaft stands still); "
                "track such orders once"
            )
        env[:, g, :] = e
    wave = np.empty((nch, m, n))
    resid = xs.copy()
    for k in range(m):
        th = order_values[k] * angles[shaft_idx[k]]
        wave[:, k, :] = env[:, k, :].real * np.cos(th) - env[:, k, :].imag * np.sin(th)
        resid -= wave[:, k, :]
    return OrderWaveforms(
        orders=order_values,
        shafts=shaft_idx,
        time=np.asarray(t, dtype=float),
        rpm=speeds,
        angle=angles,
        envelope=env.reshape(*lead, m, n),
        waveform=wave.reshape(*lead, m, n),
        residual=resid.reshape(*lead, n),
        bandwidth=bw,
        weight=weight,
        filter_order=int(filter_order),
        joint=joint,
        fs=fs_v,
        units=sig.units,
        name=sig.name,
        dims=sig.dims,
        coords=sig.coords,
        reference=reference,
        notes=tuple(notes),
    )


def remove_orders(
    x: Any,
    fs: Any = None,
    *,
    orders: Any,
    remove: Any = None,
    **kwargs: Any,
) -> OrderRemoval:
    """The signal with chosen orders removed, and the residual.

    Parameters
    ----------
    x, fs
        Signal and sample rate (as :func:`order_waveform`).
    orders : float or sequence of float
        Orders tracked (jointly by default), removed and kept alike: track a kept order that
        crosses a removed one so that the joint solution separates them.
    remove : int or sequence of int, optional
        Positions in ``orders`` of the orders to remove (default: all).
    **kwargs
        Everything else of :func:`order_waveform` (``bandwidth`` is required; ``rpm``,
        ``angle`` or ``tacho``, ``shafts``, ``filter_order``, ``joint``, ...).

    Returns
    -------
    OrderRemoval
        ``signal = x - sum(removed waveforms)``; ``residual = x - sum(all tracked
        waveforms)``; the extraction.
    """
    ex = order_waveform(x, fs, orders=orders, **kwargs)
    drop = positions(remove, ex.orders.size, "remove")
    return OrderRemoval(ex.without(drop), ex.residual, tuple(drop), ex)
