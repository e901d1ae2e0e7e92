"""Results of Vold-Kalman order tracking (:mod:`analysis.vold_kalman`): the tracked orders
and a signal with orders removed, with their CF datasets and figures."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.cf import processing_attrs, time_attrs
from analysis.inputs import channel_coords, select_channel
from analysis.vold_kalman_checks import positions
from analysis.vold_kalman_plots import order_removal_figure, order_waveform_figure

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = ["OrderRemoval", "OrderWaveforms"]


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
        drop = positions(which, self.orders.size, "which")
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
