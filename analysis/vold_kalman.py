"""Vold-Kalman order tracking: the time waveform, amplitude and phase of chosen orders.

:func:`order_waveform` extracts orders with the second-generation Vold-Kalman filter (Vold &
Leuridan 1993; Vold, Mains & Blough 1997), in its least-squares form (Feldbauer & Höldrich
2000; Pan & Lin 2006), for a run-up, a coast-down or any speed profile;
:func:`remove_orders` subtracts them from the signal (MATLAB ``orderwaveform``; rota-order's
``order_waveform`` and ``remove_orders``).

Model. Order ``k`` of shaft ``s_k`` has the carrier phase ``theta_k(t) = o_k phi_{s_k}(t)``
(``phi``: shaft angle [rad], from an rpm trace, an angle trace or a tacho) and the waveform

    x_k(n) = Re(a_k(n) exp(i theta_k(n))) = u_k(n) cos theta_k(n) - v_k(n) sin theta_k(n),

where ``a_k = u_k + i v_k`` is the complex envelope: ``|a_k|`` is the **peak** amplitude in
the signal's units and ``arg a_k`` the phase (no factor 2: a cosine of amplitude A and phase
phi has ``a_k = A exp(i phi)``). The envelopes minimise

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

import dataclasses
import numbers
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.cf import processing_attrs, time_attrs
from analysis.inputs import (
    Signal,
    channel_coords,
    reference_input,
    select_channel,
    signal_input,
)
from analysis.speed import from_angle, from_rpm, from_tacho
from analysis.vold_kalman_plots import order_removal_figure, order_waveform_figure
from analysis.vold_kalman_solver import minimum_working_bytes, plan, solve

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

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
    b = np.asarray(bandwidth, dtype=float)
    return np.sqrt(_HALF_POWER) / (2.0 * np.sin(np.pi * b / (2.0 * fs))) ** p


def weight_to_bandwidth(weight: Any, fs: float, filter_order: int = 1) -> np.ndarray:
    """-3 dB bandwidth [Hz] of the weight ``r`` (inverse of :func:`bandwidth_to_weight`)."""
    p = _difference_order(filter_order)
    r = np.asarray(weight, dtype=float)
    return 2.0 * fs / np.pi * np.arcsin(0.5 * (_HALF_POWER / r**2) ** (1.0 / (2 * p)))


# ---------------------------------------------------------------------------- results


@dataclass(frozen=True, eq=False)
class OrderWaveforms:
    """Orders extracted by the Vold-Kalman filter (MATLAB ``orderwaveform``).

    Attributes
    ----------
    orders : numpy.ndarray
        Tracked orders (cycles per revolution of their shaft).
    shafts : numpy.ndarray
        Speed reference (row of ``rpm``) of each order.
    time : numpy.ndarray
        Sample instants [s].
    rpm : numpy.ndarray
        Speed of each shaft [min-1], shape ``(shaft, time)``.
    angle : numpy.ndarray
        Angle of each shaft [rad], shape ``(shaft, time)``; order ``k``'s carrier phase is
        ``orders[k] * angle[shafts[k]]``.
    envelope : numpy.ndarray
        Complex envelope ``a_k`` (peak amplitude and phase), shape ``(*channels, order,
        time)``.
    waveform : numpy.ndarray
        ``Re(a_k exp(i orders[k] angle[shafts[k]]))``, same shape, units of the signal.
    residual : numpy.ndarray
        Signal minus the sum of the waveforms, shape ``(*channels, time)``.
    bandwidth : numpy.ndarray
        -3 dB bandwidth of each order's filter [Hz] (full width of the half-power band).
    weight : numpy.ndarray
        Weight ``r`` of each order (Feldbauer & Höldrich / Tůma convention).
    filter_order : int
        1 (second difference) or 2 (third difference).
    joint : bool
        Whether the orders were solved in one system.
    fs : float
        Sample rate [Hz].
    units, name : str
        Units and name of the signal.
    dims, coords : tuple, dict
        Names and coordinates of the channel dimensions (empty for one channel).
    reference : str
        Speed reference(s) used.
    notes : tuple of str
        What was done beyond the request.
    """

    orders: np.ndarray
    shafts: np.ndarray
    time: np.ndarray
    rpm: np.ndarray
    angle: np.ndarray
    envelope: np.ndarray
    waveform: np.ndarray
    residual: np.ndarray
    bandwidth: np.ndarray
    weight: np.ndarray
    filter_order: int
    joint: bool
    fs: float
    units: str = "1"
    name: str = "x"
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    reference: str = ""
    notes: tuple[str, ...] = ()

    @property
    def amplitude(self) -> np.ndarray:
        """Peak amplitude ``|a_k|`` (units of the signal); rms is ``amplitude / sqrt(2)``."""
        return np.abs(self.envelope)

    @property
    def phase(self) -> np.ndarray:
        """Phase ``arg a_k`` [rad] relative to the carrier ``orders[k] * angle``."""
        return np.angle(self.envelope)

    @property
    def frequency(self) -> np.ndarray:
        """Instantaneous frequency of each order [Hz], shape ``(order, time)``."""
        return self.orders[:, None] * self.rpm[self.shafts] / 60.0

    def select(self, channel: Any) -> OrderWaveforms:
        """The orders of one channel (a label of the channel coordinate, or an index)."""
        env, dims, coords, label = select_channel(self.envelope, self.dims, self.coords, channel)
        wave, *_ = select_channel(self.waveform, self.dims, self.coords, channel)
        res, *_ = select_channel(self.residual, self.dims, self.coords, channel)
        name = f"{self.name} {label}" if self.name else label
        return dataclasses.replace(
            self, envelope=env, waveform=wave, residual=res, dims=dims, coords=coords, name=name
        )

    def without(self, which: Sequence[int] | None = None) -> np.ndarray:
        """The signal with the orders at positions ``which`` of :attr:`orders` removed (all
        when ``None``): the residual plus the waveforms of the other orders."""
        drop = _positions(which, self.orders.size, "which")
        keep = [k for k in range(self.orders.size) if k not in drop]
        out = self.residual.copy()
        for k in keep:
            out += self.waveform[..., k, :]
        return out

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset: ``waveform``, ``amplitude`` (peak), ``phase`` (degree) along
        ``(*channels, order, time)``, ``residual``, the speeds and angles of the shafts, the
        order frequencies, and ``bandwidth``/``weight`` per order."""
        import xarray as xr

        ch = self.dims
        what = f"of {self.name}" if self.name else ""
        attrs: dict[str, Any] = {
            "Conventions": "CF-1.11",
            "method": "second-generation Vold-Kalman filter (least squares, real data term)",
            "filter_order": int(self.filter_order),
            "difference_order": int(self.filter_order) + 1,
            "joint": int(self.joint),
            "sample_rate": float(self.fs),
            "amplitude": "peak",
            "envelope_convention": (
                "waveform = amplitude * cos(order * shaft_angle[shaft] + phase); no factor 2 "
                "(the analytic envelope of Feldbauer & Hoeldrich is half the amplitude)"
            ),
            "history": "Vold-Kalman order tracking by analysis.vold_kalman",
        }
        attrs.update(processing_attrs(self.reference, self.notes))
        units = self.units
        data = {
            "waveform": (
                (*ch, "order", "time"),
                self.waveform,
                {"units": units, "long_name": f"order waveform {what}".strip()},
            ),
            "amplitude": (
                (*ch, "order", "time"),
                self.amplitude,
                {"units": units, "long_name": f"peak amplitude of the order {what}".strip()},
            ),
            "phase": (
                (*ch, "order", "time"),
                np.degrees(self.phase),
                {
                    "units": "degree",
                    "long_name": "phase of the order relative to order * shaft angle",
                },
            ),
            "residual": (
                (*ch, "time"),
                self.residual,
                {"units": units, "long_name": f"signal minus the tracked orders {what}".strip()},
            ),
            "frequency": (
                ("order", "time"),
                self.frequency,
                {"units": "Hz", "long_name": "instantaneous frequency of the order"},
            ),
            "rpm": (
                ("shaft", "time"),
                self.rpm,
                {"units": "min-1", "long_name": "shaft speed (revolutions per minute)"},
            ),
            "shaft_angle": (
                ("shaft", "time"),
                self.angle,
                {"units": "rad", "long_name": "shaft rotation angle"},
            ),
            "bandwidth": (
                "order",
                self.bandwidth,
                {"units": "Hz", "long_name": "-3 dB bandwidth of the order filter (full width)"},
            ),
            "weight": (
                "order",
                self.weight,
                {"units": "1", "long_name": "weight r of the structural equation"},
            ),
            "order_shaft": (
                "order",
                self.shafts.astype(np.int32),
                {"units": "1", "long_name": "speed reference (shaft index) of the order"},
            ),
        }
        coords = {
            "time": ("time", self.time, time_attrs("time since the start of the record")),
            "order": ("order", self.orders, {"units": "1", "long_name": "tracked order"}),
            "shaft": (
                "shaft",
                np.arange(self.rpm.shape[0], dtype=np.int32),
                {"units": "1", "long_name": "speed reference index"},
            ),
            **channel_coords(self.dims, self.coords),
        }
        return xr.Dataset(data, coords=coords, attrs=attrs)

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.vold_kalman_plots.order_waveform_figure`)."""
        return order_waveform_figure(self, **kwargs)


@dataclass(frozen=True, eq=False)
class OrderRemoval:
    """A signal with chosen orders removed (:func:`remove_orders`).

    Attributes
    ----------
    signal : numpy.ndarray
        The input minus the waveforms of the removed orders, shape ``(*channels, time)``.
    residual : numpy.ndarray
        The input minus the waveforms of every tracked order (removed and kept).
    removed : tuple of int
        Positions in ``extraction.orders`` of the removed orders.
    extraction : OrderWaveforms
        The orders tracked (jointly with those kept, when ``joint``).
    """

    signal: np.ndarray
    residual: np.ndarray
    removed: tuple[int, ...]
    extraction: OrderWaveforms

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset: ``signal`` (orders removed), ``residual``, and the removed orders'
        waveforms and amplitudes."""
        ex = self.extraction
        ds = ex.to_dataset().isel(order=list(self.removed))
        ds = ds.drop_vars(["residual"])
        ch = ex.dims
        ds["signal"] = (
            (*ch, "time"),
            self.signal,
            {"units": ex.units, "long_name": f"{ex.name} with the removed orders subtracted"},
        )
        ds["residual"] = (
            (*ch, "time"),
            self.residual,
            {"units": ex.units, "long_name": f"{ex.name} minus every tracked order"},
        )
        ds.attrs["removed_orders"] = [float(ex.orders[k]) for k in self.removed]
        return ds

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.vold_kalman_plots.order_removal_figure`)."""
        return order_removal_figure(self, **kwargs)


# ---------------------------------------------------------------------------- checks


def _real(value: Any, name: str) -> float:
    """A real number (not a bool, not a string), as float."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} = {value!r} must be a real number, not {type(value).__name__}")
    v = float(value)
    if not np.isfinite(v):
        raise ValueError(f"{name} = {value!r} is not admissible: must be finite")
    return v


def _reals(values: Any, name: str) -> np.ndarray:
    """A number or a sequence of numbers as a 1-D float array (bools and strings refused)."""
    if isinstance(values, str | bytes):
        raise TypeError(f"{name} = {values!r} must be numbers, not a string")
    arr = np.asarray(values, dtype=object) if not isinstance(values, np.ndarray) else values
    if arr.dtype == object or arr.dtype.kind in "bUSV":
        flat = np.ravel(arr) if arr.ndim else [arr.item()]
        return np.array([_real(v, name) for v in flat], dtype=float)
    if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
        raise TypeError(f"{name} must be real numbers; got dtype {arr.dtype}")
    out = np.asarray(arr, dtype=float).ravel()
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{name} = {values!r} is not admissible: must be finite")
    return out


def _per_order(values: np.ndarray, m: int, name: str) -> np.ndarray:
    if values.size == 1:
        return np.full(m, values[0])
    if values.size != m:
        raise ValueError(f"{name}: {values.size} values for {m} orders; give one or one per order")
    return values


def _items(values: Any) -> list[Any]:
    """The elements of a scalar, a sequence or an array, as given (bools stay bools)."""
    if isinstance(values, list | tuple):
        return list(values)
    if np.ndim(values) == 0:
        return [values.item() if isinstance(values, np.ndarray) else values]
    arr = np.asarray(values)
    return [bool(v) for v in arr.ravel()] if arr.dtype == bool else list(arr.ravel())


def _positions(which: Any, m: int, name: str) -> list[int]:
    if which is None:
        return list(range(m))
    items = _items(which)
    out = []
    for v in items:
        if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Integral):
            raise TypeError(f"{name} = {which!r}: positions in orders (integers) are needed")
        if not 0 <= int(v) < m:
            raise ValueError(f"{name} = {which!r}: a position must be in [0, {m})")
        out.append(int(v))
    return sorted(set(out))


def _shaft_list(ref: Any, n: int) -> list[Any]:
    """The references of one or several shafts as a list (one entry per shaft)."""
    if isinstance(ref, list | tuple):
        if not ref:
            raise ValueError("an empty list of speed references was given")
        return list(ref)
    if hasattr(ref, "dims"):  # DataArray: one shaft
        return [ref]
    arr = np.asarray(ref)
    if arr.ndim == 2:
        if arr.shape[1] == n:
            return list(arr)
        if arr.shape[0] == n:
            return list(arr.T)
        raise ValueError(
            f"sample-count mismatch: speed reference of shape {arr.shape} for {n} samples; "
            "give (shafts, samples) or (samples, shafts)"
        )
    return [ref]


def _reference_lengths(ref: Any) -> tuple[int, ...]:
    """Sample counts of a speed reference (they single out the time axis of ``x``): the
    length of a 1-D reference or of the list's entries, the longer side of a 2-D array."""
    if ref is None:
        return ()
    if isinstance(ref, list | tuple):
        return tuple(int(np.shape(r)[-1]) for r in ref if np.ndim(r) == 1)
    shape = np.shape(ref)
    return (int(max(shape)),) if len(shape) in (1, 2) else ()


def _references(
    sig: Signal,
    rpm: Any,
    angle: Any,
    tacho: Any,
    pulses_per_rev: Any,
    missing_teeth: Any,
    time: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, str]:
    """Angles and speeds ``(shaft, time)`` of the speed references, and their description."""
    given = [k for k, v in (("rpm", rpm), ("angle", angle), ("tacho", tacho)) if v is not None]
    if len(given) > 1:
        raise ValueError(f"give one speed reference (rpm=, angle= or tacho=), not {given}")
    n = sig.n
    angles, speeds, labels = [], [], []
    if tacho is not None:
        for v in pulses_per_rev if isinstance(pulses_per_rev, list | tuple) else [pulses_per_rev]:
            if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Integral):
                raise TypeError(f"pulses_per_rev = {pulses_per_rev!r} must be integers >= 1")
        pulses = _shaft_list(tacho, n)
        ppr = list(pulses_per_rev) if isinstance(pulses_per_rev, list | tuple) else None
        for i, p in enumerate(pulses):
            arr = np.asarray(p)
            if arr.ndim != 1 or arr.size != n:
                raise ValueError(
                    f"sample-count mismatch (x: {n}, tacho[{i}]: {arr.size}); a tacho must be "
                    "1-D, sampled with x"
                )
            if not np.issubdtype(arr.dtype, np.number) or arr.dtype == bool:
                raise TypeError(f"tacho[{i}] must be real numbers; got dtype {arr.dtype}")
            per = ppr[i] if ppr is not None else pulses_per_rev
            ref = from_tacho(
                arr, sig.fs, per, missing_teeth=missing_teeth, output_time=time - time[0]
            )
            angles.append(ref.angle)
            speeds.append(ref.rpm)
            labels.append(f"tacho {i} ({per} pulses/rev)")
        return np.array(angles), np.array(speeds), ", ".join(labels)
    kind = "rpm" if rpm is not None else ("angle" if angle is not None else None)
    items = _shaft_list(rpm if rpm is not None else angle, n) if kind else [None]
    for i, item in enumerate(items):
        ref = reference_input(
            item if kind == "rpm" else None,
            item if kind == "angle" else None,
            n,
            required=True,
            signal=sig if kind is None else None,
        )
        values = np.asarray(ref.values, dtype=float)
        label = ref.label if len(items) == 1 else f"{ref.label} (shaft {i})"
        if ref.kind == "rpm":
            if float(values.min()) < 0.0:
                j = int(np.argmin(values))
                raise ValueError(
                    f"rpm must be >= 0 (rotation in one direction); rpm[{j}] = {values[j]:.6g}"
                    f"{'' if len(items) == 1 else f' of shaft {i}'}. Negate a reference of "
                    "reverse rotation"
                )
            sr = from_rpm(time, values)
        else:
            sr = from_angle(time, values)
        angles.append(sr.angle)
        speeds.append(sr.rpm)
        labels.append(label)
    return np.array(angles), np.array(speeds), ", ".join(labels)


def _result_bytes(nch: int, m: int, n: int, shafts: int) -> int:
    """Bytes of the result arrays (envelopes, waveforms, residual, angles and speeds, time),
    of the float copy of the input and of the temporaries of the speed references and of
    the waveforms (about six arrays of ``n``)."""
    return 8 * n * (nch * m * 3 + nch * 2 + shafts * 2 + m + 7)


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
    budget = _real(max_memory, "max_memory")
    if budget <= 0:
        raise ValueError(f"max_memory = {max_memory!r} is not admissible: must be > 0 bytes")
    order_values = _reals(orders, "orders")
    m = order_values.size
    if m == 0:
        raise ValueError("orders: give at least one order")
    if np.any(order_values <= 0):
        raise ValueError(f"orders = {orders!r} is not admissible: every order must be > 0")
    ref_len = _reference_lengths(rpm if rpm is not None else angle if angle is not None else tacho)
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name, lengths=tuple(ref_len))
    n = sig.n
    fs_v = sig.fs
    bw = _per_order(_reals(bandwidth, "bandwidth"), m, "bandwidth")
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
    n_shafts = len(_shaft_list(given, n)) if given is not None else 1
    if shafts is None:
        shaft_idx = np.zeros(m, dtype=np.int64)
    else:
        shaft_idx = np.array(_positions_of_shafts(shafts, m, n_shafts), dtype=np.int64)
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
    need = _result_bytes(nch, m, n, n_shafts)  # checked before any array of n is made
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
    angles, speeds, reference = _references(
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


def _positions_of_shafts(shafts: Any, m: int, n_shafts: int) -> list[int]:
    items = [shafts] * m if np.ndim(shafts) == 0 else _items(shafts)
    if len(items) != m:
        raise ValueError(f"shafts: {len(items)} values for {m} orders; give one per order")
    out = []
    for v in items:
        if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Integral):
            raise TypeError(f"shafts = {shafts!r}: integers (speed reference indices) needed")
        if not 0 <= int(v) < n_shafts:
            raise ValueError(
                f"shafts = {shafts!r}: an index must be in [0, {n_shafts}) ({n_shafts} speed "
                "reference(s) given)"
            )
        out.append(int(v))
    return out


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
    drop = _positions(remove, ex.orders.size, "remove")
    return OrderRemoval(ex.without(drop), ex.residual, tuple(drop), ex)
