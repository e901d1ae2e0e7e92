"""Envelope order spectrum: the squared envelope of a band (given, or chosen by the fast
kurtogram) resampled to constant shaft-angle increments, then its order spectrum.

The band stays in Hz (the resonance that the impacts excite does not follow the speed);
the squared envelope (:mod:`analysis.envelope`) is computed at its decimated rate ``fs / D``
and resampled with the computed order tracking of :mod:`analysis.resample` through
:func:`analysis.orders.order_spectrum`, from an rpm trace, an angle, or a tacho signal
(:func:`analysis.speed.from_tacho`); the reference is taken at the same samples ``0, D,
2D, ...``. Lines that are fixed multiples of the shaft speed (bearing defect orders) stay
sharp when the speed varies (Borghesani et al. 2013), whereas the envelope spectrum in Hz
smears them over the speed range.

References
----------
P. Borghesani, R. Ricci, S. Chatterton, P. Pennacchi, "A new procedure for using envelope
analysis for rolling element bearing diagnostics in variable operating conditions",
Mechanical Systems and Signal Processing 38(1), 23-35, 2013.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from analysis.bands import Band, envelope_decimation, squared_envelope_samples
from analysis.checks import require_real, time_or_rate
from analysis.envelope import SEGMENTS, BandSpec, band_attributes, choose_band, line_power
from analysis.envelope_plots import envelope_spectrum_figure
from analysis.inputs import Reference, moving_range, one_channel, reference_input, signal_input
from analysis.kurtogram import Kurtogram
from analysis.levels import AMPLITUDES, amplitude_choice, units_of
from analysis.lines import LineCheck, LineFamily, check_lines
from analysis.orders import OrderSpectrum, order_spectrum
from analysis.speed import from_tacho
from analysis.windows import WindowSpec, window_info

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = ["EnvelopeOrderSpectrum", "envelope_order_spectrum"]


@dataclass(frozen=True)
class EnvelopeOrderSpectrum:
    """Squared envelope order spectrum (see :func:`envelope_order_spectrum`).

    Attributes
    ----------
    order : numpy.ndarray
        Orders (cycles per shaft revolution).
    values : numpy.ndarray
        Order spectrum of the squared envelope in ``amplitude``.
    amplitude : str
        Amplitude convention.
    units : str
        Units of ``values``.
    band : Band
        The demodulated band [Hz].
    kurtogram : Kurtogram or None
        The kurtogram that chose the band.
    order_spectrum : OrderSpectrum
        The underlying order spectrum of the squared envelope.
    decimation : int
        ``D``: the squared envelope is resampled from ``fs / D``.
    fs : float
        Sample rate of the record [Hz].
    name : str
        Channel name.
    order_limit : float
        The band's width in orders at the highest speed: the squared envelope holds little
        above it.
    """

    order: np.ndarray
    values: np.ndarray
    amplitude: str
    units: str
    band: Band
    kurtogram: Kurtogram | None
    order_spectrum: OrderSpectrum
    decimation: int
    fs: float
    name: str = "x"
    order_limit: float = float("inf")

    @property
    def resolution_orders(self) -> float:
        """Resolution bandwidth [orders] (the window's ENBW)."""
        return self.order_spectrum.resolution_orders

    @property
    def bin_spacing_orders(self) -> float:
        """Line spacing [orders]."""
        return self.order_spectrum.bin_spacing_orders

    def power(self) -> np.ndarray:
        """The spectrum as power per line (amplitude squared)."""
        return line_power(self.values, self.amplitude)

    def check(self, family: LineFamily, **kwargs: Any) -> LineCheck:
        """Every line of ``family`` (in orders) checked at its position, up to
        :attr:`order_limit` (as :meth:`EnvelopeSpectrum.check`)."""
        keep = self.order <= self.order_limit
        return check_lines(self.order[keep], self.power()[keep], family, axis_units="1",
                           **kwargs)  # fmt: skip

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset with ``envelope_order_spectrum(order)``; band and resolution in the
        attributes."""
        ds = self.order_spectrum.to_dataset().rename({"order_spectrum": "envelope_order_spectrum"})
        ds["envelope_order_spectrum"].attrs["long_name"] = (
            f"{self.amplitude} order spectrum of the squared envelope of {self.name} in "
            f"{self.band.low:.6g}-{self.band.high:.6g} Hz"
        )
        ds.attrs.update(band_attributes(self.band, self.kurtogram, self.decimation, self.fs))
        return ds

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.envelope_plots.envelope_spectrum_figure`)."""
        return envelope_spectrum_figure(self, **kwargs)


def _revolutions(ref: Reference, fs: float, a: int, b: int) -> float:
    """Shaft revolutions between samples ``a`` and ``b - 1``."""
    v = np.asarray(ref.values[a:b], dtype=float)
    if ref.kind == "angle":
        return float(v[-1] - v[0]) / (2.0 * np.pi)
    return float(np.sum(0.5 * (v[1:] + v[:-1]))) / (60.0 * fs)


def envelope_order_spectrum(
    x: Any,
    fs: float | None = None,
    rpm: Any = None,
    *,
    angle: Any = None,
    tacho: Any = None,
    pulses_per_rev: int = 1,
    band: BandSpec = None,
    resolution: float | None = None,
    amplitude: Literal["peak", "rms", "power", "density"] | None = None,
    window: WindowSpec = "hann",
    overlap: float = 0.5,
    samples_per_rev: int | None = None,
    max_order: float | None = None,
    min_rpm: float | None = None,
    max_level: int | None = None,
    min_bandwidth: float | None = None,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    workers: int | None = None,
) -> EnvelopeOrderSpectrum:
    """Squared envelope order spectrum of one channel measured at varying speed.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One channel (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or ``time``).
    rpm : array_like, optional
        Shaft speed [min-1] per sample.
    angle : array_like, optional
        Shaft angle [rad] per sample.
    tacho : array_like, optional
        Tacho pulse signal per sample, processed by :func:`analysis.speed.from_tacho` with
        ``pulses_per_rev``. Give exactly one of ``rpm``, ``angle``, ``tacho`` (or a DataArray
        carrying a reference).
    pulses_per_rev : int, default 1
        Pulses per revolution of ``tacho``.
    band : (float, float), Band, Kurtogram or None
        Band to demodulate [Hz] (as in :func:`envelope_spectrum`).
    resolution : float, optional
        Resolution bandwidth [orders]; default segments of a quarter of the revolutions.
    amplitude, window, overlap
        As in :func:`envelope_spectrum`.
    samples_per_rev, max_order, min_rpm
        Angular resampling of the squared envelope (:func:`analysis.orders.order_spectrum`).
    max_level, min_bandwidth : optional
        As in :func:`envelope_spectrum` (``min_bandwidth`` in Hz).
    time, axis, units, name, workers
        As in :func:`analysis.spectrum.spectrum`.

    Returns
    -------
    EnvelopeOrderSpectrum
        Order spectrum of the squared envelope, with the band and resolution used.
    """
    amp = amplitude_choice(amplitude, None, "envelope_order_spectrum", AMPLITUDES,
                           default="peak")  # fmt: skip
    fs, time = time_or_rate(fs, time, "envelope_order_spectrum")
    if resolution is not None:
        resolution = require_real(resolution, "resolution")
    given = [k for k, v in (("rpm", rpm), ("angle", angle), ("tacho", tacho)) if v is not None]
    if len(given) > 1:
        raise ValueError(f"give one speed reference: rpm=, angle= or tacho=; got {given}")
    refs = (rpm, angle, tacho)
    lengths = tuple(np.shape(r)[0] for r in refs if r is not None and np.ndim(r) == 1)
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name, lengths=lengths)
    v = one_channel(sig, "envelope_order_spectrum")
    if tacho is not None:
        t = np.asarray(tacho)
        if t.ndim != 1 or t.size != sig.n:
            raise ValueError(
                f"sample-count mismatch (x: {sig.n}, tacho: {t.size}); tacho must be 1-D, one "
                "value per sample of x"
            )
        angle = from_tacho(t, sig.fs, pulses_per_rev).angle
    ref = reference_input(rpm, angle, sig.n, required=True, signal=sig)
    assert ref is not None
    b, kg = choose_band(band, sig.fs, v, max_level=max_level, min_bandwidth=min_bandwidth,
                        workers=workers, name=sig.name)
    d = envelope_decimation(b, sig.fs)
    e = squared_envelope_samples(v, sig.fs, b, d, workers=workers)
    e -= np.mean(e)
    fs_env = sig.fs / d
    sub = Reference(ref.kind, np.asarray(ref.values[::d], dtype=float), ref.label)
    a0, b0, _, _ = moving_range(sub, fs_env, sig.t0, min_rpm)
    if resolution is None:
        revs = _revolutions(sub, fs_env, a0, b0)
        enbw = window_info(window, 4096).enbw_bins
        resolution = 1.02 * enbw * SEGMENTS / revs
    part = np.asarray(sub.values[a0:b0], dtype=float)
    if sub.kind == "rpm":
        top_hz = float(part.max()) / 60.0
    else:
        top_hz = float(np.diff(part).max()) * fs_env / (2.0 * np.pi) if part.size > 1 else 0.0
    kwargs: dict[str, Any] = {sub.kind: sub.values}  # rpm= or angle=
    os_ = order_spectrum(
        e, fs_env, resolution=resolution, window=window, amplitude=amp, overlap=overlap,
        samples_per_rev=samples_per_rev, max_order=max_order, min_rpm=min_rpm,
        units=units_of(sig.units, "power"), name=sig.name, **kwargs,
    )  # fmt: skip
    os_ = dataclasses.replace(os_, reference=ref.label if tacho is None else "tacho")
    return EnvelopeOrderSpectrum(
        order=os_.order,
        values=os_.values,
        amplitude=amp,
        units=os_.units,
        band=b,
        kurtogram=kg,
        order_spectrum=os_,
        decimation=d,
        fs=sig.fs,
        name=sig.name,
        order_limit=b.width / top_hz if top_hz > 0 else float("inf"),
    )
