"""Envelope analysis: the squared envelope spectrum of a band, chosen by the fast kurtogram
or given, in the frequency domain and, after angular resampling, in the order domain.

Method (Randall & Antoni 2011, sec. 3-4): impacts of a local fault excite structural
resonances; band-passing the signal around such a resonance and taking its envelope
demodulates the impacts, whose repetition rate (BPFO, BPFI, ...) and modulations then show
as lines in the spectrum of the envelope even when the raw spectrum shows nothing.

1. **Band.** ``band=(low, high)`` [Hz], or ``None``: the band of largest kurtosis of the fast
   kurtogram (:func:`analysis.kurtogram.fast_kurtogram`). The band is selected in the DFT
   with smooth edges (gain 1/2 at ``low`` and ``high``, :mod:`analysis.bands`), zero phase.
2. **Squared envelope.** ``e(t) = |z(t)|^2 = x_b(t)^2 + H[x_b](t)^2``, ``z`` the analytic
   signal of the band-passed record ``x_b`` (``H``: Hilbert transform), computed at the
   decimated rate ``fs / D`` (``D`` the largest 5-smooth integer with ``fs / D`` at least
   twice the band's support: ``e`` is band-limited to it, so nothing aliases). Its mean is
   removed.
3. **Spectrum.** Welch average of Hann-windowed segments (:func:`analysis.spectrum.spectrum`),
   default segments of a quarter of the record, 50 % overlap (7 averages); or the resolution
   asked for. The **amplitude convention** is the one of :func:`analysis.spectrum.spectrum`,
   default ``"peak"``: a component ``A cos(2 pi f t)`` of the squared envelope reads ``A``
   [signal units squared]. Example: ``x = a (1 + m cos 2 pi f_m t) cos 2 pi f_c t`` gives
   ``e = a^2 (1 + m cos)^2``, a line ``2 m a^2`` at ``f_m`` and ``m^2 a^2 / 2`` at
   ``2 f_m``. The result reports the band, ``D``, the resolution (the window's ENBW) and the
   line spacing actually used.

The **envelope order spectrum** resamples the squared envelope to constant shaft-angle
increments (:mod:`analysis.resample`, from an rpm trace, an angle or a tacho signal) before
its spectrum, so that the lines of a bearing, which are fixed multiples of the shaft speed,
stay sharp when the speed varies (Borghesani et al. 2013). The band stays in Hz: the
resonance does not follow the speed.

References
----------
R. B. Randall, J. Antoni, "Rolling element bearing diagnostics - a tutorial", Mechanical
Systems and Signal Processing 25(2), 485-520, 2011.
P. Borghesani, R. Ricci, S. Chatterton, P. Pennacchi, "A new procedure for using envelope
analysis for rolling element bearing diagnostics in variable operating conditions", MSSP
38(1), 23-35, 2013.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from analysis.bands import Band, envelope_decimation, squared_envelope_samples
from analysis.cf import time_attrs
from analysis.checks import time_or_rate
from analysis.envelope_plots import envelope_spectrum_figure, squared_envelope_figure
from analysis.inputs import Reference, moving_range, one_channel, reference_input, signal_input
from analysis.kurtogram import Kurtogram, fast_kurtogram
from analysis.levels import AMPLITUDES, amplitude_choice, units_of
from analysis.lines import LineCheck, LineFamily, check_lines
from analysis.orders import OrderSpectrum, order_spectrum
from analysis.spectrum import Peaks, Spectrum, find_peaks, spectrum
from analysis.speed import from_tacho
from analysis.windows import WindowSpec, window_info

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = [
    "EnvelopeOrderSpectrum",
    "EnvelopeSpectrum",
    "SquaredEnvelope",
    "envelope_order_spectrum",
    "envelope_spectrum",
    "squared_envelope",
]

_SEGMENTS = 4  # default: segments of a quarter of the record


BandSpec = tuple[float, float] | Band | Kurtogram | None


def _band(band: BandSpec, fs: float, x: np.ndarray, max_level: int | None,
          min_bandwidth: float | None, workers: int | None,
          name: str) -> tuple[Band, Kurtogram | None]:  # fmt: skip
    """The band to demodulate and the kurtogram that chose it (``None`` if given)."""
    kg = None
    if band is None:
        kg = fast_kurtogram(x, fs, max_level=max_level, min_bandwidth=min_bandwidth, name=name,
                            workers=workers)  # fmt: skip
        b = kg.band
    elif isinstance(band, Kurtogram):
        kg, b = band, band.band
    elif isinstance(band, Band):
        b = band
    else:
        if isinstance(band, str) or np.ndim(band) != 1 or np.size(band) != 2:
            raise ValueError(
                f"band = {band!r} is not admissible: (low, high) in Hz, a Band, a Kurtogram "
                "or None (chosen by the fast kurtogram)"
            )
        lo, hi = (float(v) for v in band)  # type: ignore[union-attr]
        b = Band(lo, hi)
    if b.high > 0.5 * fs * (1.0 + 1e-12):
        raise ValueError(
            f"band = ({b.low:g}, {b.high:g}) Hz is not admissible: high must be <= fs/2 = "
            f"{0.5 * fs:g} Hz"
        )
    return b, kg


@dataclass(frozen=True)
class SquaredEnvelope:
    """Squared envelope of a band of a record (see :func:`squared_envelope`).

    Attributes
    ----------
    values : numpy.ndarray
        ``|z|^2`` at the samples ``0, D, 2D, ...`` of the record (mean not removed).
    fs : float
        Its sample rate ``fs_record / D`` [Hz].
    decimation : int
        ``D``.
    t0 : float
        Time of the first sample [s].
    band : Band
        The band.
    units : str
        Units (the record's, squared).
    name : str
        Channel name.
    kurtogram : Kurtogram or None
        The kurtogram that chose the band.
    """

    values: np.ndarray
    fs: float
    decimation: int
    t0: float
    band: Band
    units: str
    name: str = "x"
    kurtogram: Kurtogram | None = None

    @property
    def time(self) -> np.ndarray:
        """Sample times [s]."""
        return self.t0 + np.arange(self.values.size) / self.fs

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset with ``squared_envelope(time)``."""
        import xarray as xr

        return xr.Dataset(
            {
                "squared_envelope": (
                    "time",
                    self.values,
                    {"units": self.units,
                     "long_name": f"squared envelope of {self.name} in {self.band.low:.6g}-"
                                  f"{self.band.high:.6g} Hz"},
                )
            },
            coords={"time": ("time", self.time, time_attrs("time since start of record"))},
            attrs={
                "band_low_hz": self.band.low,
                "band_high_hz": self.band.high,
                "band_transition_hz": self.band.transition,
                "decimation": int(self.decimation),
                "sample_rate_hz": float(self.fs),
            },
        )  # fmt: skip

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.envelope_plots.squared_envelope_figure`)."""
        return squared_envelope_figure(self, **kwargs)


def squared_envelope(
    x: Any,
    fs: float | None = None,
    *,
    band: BandSpec = None,
    max_level: int | None = None,
    min_bandwidth: float | None = None,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    workers: int | None = None,
) -> SquaredEnvelope:
    """Squared envelope ``|z|^2`` of one band of one channel (module docstring, steps 1-2).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One channel (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or ``time``).
    band : (float, float), Band, Kurtogram or None
        The band [Hz]; ``None`` runs :func:`analysis.kurtogram.fast_kurtogram` and takes its
        band of largest kurtosis; a Kurtogram gives its band.
    max_level, min_bandwidth : optional
        Deepest level of that kurtogram and the narrowest band [Hz] it may choose (see
        :func:`analysis.kurtogram.fast_kurtogram`).
    time, axis, units, name, workers
        As in :func:`analysis.spectrum.spectrum`.

    Returns
    -------
    SquaredEnvelope
        At the decimated rate ``fs / D``.
    """
    fs, time = time_or_rate(fs, time, "squared_envelope")
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name)
    v = one_channel(sig, "squared_envelope")
    b, kg = _band(band, sig.fs, v, max_level, min_bandwidth, workers, sig.name)
    d = envelope_decimation(b, sig.fs)
    env = squared_envelope_samples(v, sig.fs, b, d, workers=workers)
    return SquaredEnvelope(env, sig.fs / d, d, sig.t0, b, units_of(sig.units, "power"),
                           sig.name, kg)  # fmt: skip


# --------------------------------------------------------------------- envelope spectrum


@dataclass(frozen=True)
class EnvelopeSpectrum:
    """Squared envelope spectrum (see :func:`envelope_spectrum`).

    Attributes
    ----------
    frequency : numpy.ndarray
        Line frequencies [Hz].
    values : numpy.ndarray
        Spectrum of the squared envelope in ``amplitude``.
    amplitude : str
        Amplitude convention (:mod:`analysis.spectrum`).
    units : str
        Units of ``values``.
    band : Band
        The demodulated band.
    kurtogram : Kurtogram or None
        The kurtogram that chose the band (``None`` when it was given).
    spectrum : Spectrum
        The underlying spectrum of the squared envelope.
    decimation : int
        ``D``: the squared envelope is sampled at ``fs / D``.
    fs : float
        Sample rate of the record [Hz].
    name : str
        Channel name.
    """

    frequency: np.ndarray
    values: np.ndarray
    amplitude: str
    units: str
    band: Band
    kurtogram: Kurtogram | None
    spectrum: Spectrum
    decimation: int
    fs: float
    name: str = "x"

    @property
    def resolution_hz(self) -> float:
        """Resolution bandwidth [Hz] (the window's ENBW)."""
        return self.spectrum.resolution_hz

    @property
    def bin_spacing_hz(self) -> float:
        """Line spacing [Hz]."""
        return self.spectrum.bin_spacing_hz

    @property
    def n_averages(self) -> int:
        """Averaged segments."""
        return self.spectrum.n_averages

    @property
    def envelope_rate(self) -> float:
        """Sample rate of the squared envelope [Hz]."""
        return self.fs / self.decimation

    def power(self) -> np.ndarray:
        """The spectrum as power per line (amplitude squared; for ``"peak"`` halved)."""
        return _power(self.values, self.amplitude)

    def peaks(self, **kwargs: Any) -> Peaks:
        """Peaks (see :func:`analysis.spectrum.find_peaks`)."""
        return find_peaks(self.spectrum, **kwargs)

    def check(self, family: LineFamily, **kwargs: Any) -> LineCheck:
        """Every line of ``family`` checked at its position (:func:`analysis.lines.check_lines`,
        keywords passed on) up to the band's width: above it the squared envelope holds
        little or nothing, and lines there are reported with NaN prominence."""
        keep = self.frequency <= self.band.width
        return check_lines(self.frequency[keep], self.power()[keep], family, axis_units="Hz",
                           **kwargs)  # fmt: skip

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset with ``envelope_spectrum(frequency)``; band, rates and resolution in
        the attributes (and the kurtogram's choice, if any)."""
        ds = self.spectrum.to_dataset().rename({"spectrum": "envelope_spectrum"})
        ds["envelope_spectrum"].attrs["long_name"] = (
            f"{self.amplitude} spectrum of the squared envelope of {self.name} in "
            f"{self.band.low:.6g}-{self.band.high:.6g} Hz"
        )
        ds.attrs.update(_band_attrs(self.band, self.kurtogram, self.decimation, self.fs))
        return ds

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.envelope_plots.envelope_spectrum_figure`)."""
        return envelope_spectrum_figure(self, **kwargs)


def _power(values: np.ndarray, amplitude: str) -> np.ndarray:
    if amplitude in ("power", "density"):
        return values
    return np.square(values)


def _band_attrs(band: Band, kg: Kurtogram | None, decimation: int, fs: float) -> dict:
    attrs: dict[str, Any] = {
        "band_low_hz": band.low,
        "band_high_hz": band.high,
        "band_transition_hz": band.transition,
        "band_source": "fast kurtogram" if kg is not None else "given",
        "decimation": int(decimation),
        "envelope_rate_hz": fs / decimation,
        "record_sample_rate_hz": float(fs),
    }
    if kg is not None:
        attrs.update(kurtogram_level=kg.level, kurtogram_kurtosis=kg.kurtosis_max)
    return attrs


def envelope_spectrum(
    x: Any,
    fs: float | None = None,
    *,
    band: BandSpec = None,
    resolution: float | None = None,
    amplitude: Literal["peak", "rms", "power", "density"] | None = None,
    window: WindowSpec = "hann",
    overlap: float = 0.5,
    max_level: int | None = None,
    min_bandwidth: float | None = None,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    workers: int | None = None,
) -> EnvelopeSpectrum:
    """Squared envelope spectrum of one channel (module docstring).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One channel (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or ``time``).
    band : (float, float), Band, Kurtogram or None
        Band to demodulate [Hz], ``0 <= low < high <= fs/2``; ``None`` (default): the band of
        largest kurtosis of the fast kurtogram; a Kurtogram: its band.
    resolution : float, optional
        Resolution bandwidth [Hz] (the window's ENBW); default segments of a quarter of the
        record (``4 * ENBW_bins / T``: 0.6 Hz for 10 s with the Hann window).
    amplitude : {"peak", "rms", "power", "density"}, default "peak"
        Amplitude convention of the squared envelope's spectrum.
    window : str or tuple, default "hann"
        Segment window.
    overlap : float, default 0.5
        Segment overlap.
    max_level, min_bandwidth : optional
        Deepest level of the kurtogram (``band=None``) and the narrowest band [Hz] it may
        choose: give at least twice the highest line frequency of interest (the squared
        envelope of a band of width ``B`` holds frequencies below ``B`` only).
    time, axis, units, name, workers
        As in :func:`analysis.spectrum.spectrum`.

    Returns
    -------
    EnvelopeSpectrum
        The spectrum with the band (and kurtogram) used, the decimation, the resolution and
        line spacing.

    Notes
    -----
    Memory: a few blocks of the record and the squared envelope at ``fs / D`` (at most half
    the record's samples); time: one FFT of the record and one inverse FFT of the band,
    block by block, then the Welch spectrum of the envelope (:mod:`analysis.bands`).
    """
    amp = amplitude_choice(amplitude, None, "envelope_spectrum", AMPLITUDES, default="peak")
    env = squared_envelope(x, fs, band=band, max_level=max_level, min_bandwidth=min_bandwidth,
                           time=time, axis=axis, units=units, name=name,
                           workers=workers)  # fmt: skip
    e = env.values
    e -= np.mean(e)
    n = e.size
    common = {"window": window, "amplitude": amp, "overlap": overlap, "units": env.units,
              "name": env.name, "workers": workers}  # fmt: skip
    if resolution is None:
        spec = spectrum(e, env.fs, segment_length=max(2, n // _SEGMENTS), **common)
    else:
        spec = spectrum(e, env.fs, resolution=resolution, **common)
    return EnvelopeSpectrum(
        frequency=spec.frequency,
        values=spec.values,
        amplitude=amp,
        units=spec.units,
        band=env.band,
        kurtogram=env.kurtogram,
        spectrum=spec,
        decimation=env.decimation,
        fs=env.fs * env.decimation,
        name=env.name,
    )


# --------------------------------------------------------------- envelope order spectrum


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
        return _power(self.values, self.amplitude)

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
        ds.attrs.update(_band_attrs(self.band, self.kurtogram, self.decimation, self.fs))
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
    b, kg = _band(band, sig.fs, v, max_level, min_bandwidth, workers, sig.name)
    d = envelope_decimation(b, sig.fs)
    e = squared_envelope_samples(v, sig.fs, b, d, workers=workers)
    e -= np.mean(e)
    fs_env = sig.fs / d
    sub = Reference(ref.kind, np.asarray(ref.values[::d], dtype=float), ref.label)
    a0, b0, _, _ = moving_range(sub, fs_env, sig.t0, min_rpm)
    if resolution is None:
        revs = _revolutions(sub, fs_env, a0, b0)
        enbw = window_info(window, 4096).enbw_bins
        resolution = 1.02 * enbw * _SEGMENTS / revs
    part = np.asarray(sub.values[a0:b0], dtype=float)
    if sub.kind == "rpm":
        top_hz = float(part.max()) / 60.0
    else:
        top_hz = float(np.diff(part).max()) * fs_env / (2.0 * np.pi) if part.size > 1 else 0.0
    kwargs = {sub.kind: sub.values}
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
