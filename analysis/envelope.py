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

The **envelope order spectrum** (:mod:`analysis.envelope_orders`) resamples the squared
envelope to constant shaft-angle increments before its spectrum, so that the lines of a
bearing stay sharp when the speed varies.

References
----------
R. B. Randall, J. Antoni, "Rolling element bearing diagnostics - a tutorial", Mechanical
Systems and Signal Processing 25(2), 485-520, 2011.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from analysis.bands import Band, envelope_decimation, squared_envelope_samples
from analysis.cf import time_attrs
from analysis.checks import (
    require_choice,
    require_instance,
    require_int,
    require_positive,
    require_real,
    require_real_array,
    shown,
    time_or_rate,
)
from analysis.envelope_plots import envelope_spectrum_figure, squared_envelope_figure
from analysis.inputs import one_channel, signal_input
from analysis.kurtogram import Kurtogram, fast_kurtogram
from analysis.levels import AMPLITUDES, amplitude_choice, units_of
from analysis.lines import LineCheck, LineFamily, check_lines
from analysis.spectrum import Peaks, Spectrum, find_peaks, spectrum
from analysis.windows import WindowSpec

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = [
    "SEGMENTS",
    "BandSpec",
    "EnvelopeSpectrum",
    "SquaredEnvelope",
    "band_attributes",
    "choose_band",
    "envelope_spectrum",
    "line_power",
    "squared_envelope",
]

#: Default number of segment lengths in the record (Hann, 50 % overlap: 7 averages).
SEGMENTS = 4


BandSpec = tuple[float, float] | Band | Kurtogram | None


def choose_band(band: BandSpec, fs: float, x: np.ndarray, *, max_level: int | None = None,
                min_bandwidth: float | None = None, workers: int | None = None,
                name: str = "x") -> tuple[Band, Kurtogram | None]:  # fmt: skip
    """The band to demodulate and the kurtogram that chose it (``None`` if given).

    Parameters
    ----------
    band : (float, float), Band, Kurtogram or None
        As in :func:`envelope_spectrum`.
    fs : float
        Sample rate [Hz].
    x : numpy.ndarray
        The record (one channel), for the kurtogram.
    max_level, min_bandwidth, workers, name
        Passed to :func:`analysis.kurtogram.fast_kurtogram` when ``band`` is ``None``.

    Returns
    -------
    tuple
        ``(Band, Kurtogram or None)``.
    """
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
                f"band = {shown(band)} is not admissible: (low, high) in Hz, a Band, a Kurtogram "
                "or None (chosen by the fast kurtogram)"
            )
        lo, hi = band
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
    b, kg = choose_band(band, sig.fs, v, max_level=max_level, min_bandwidth=min_bandwidth,
                        workers=workers, name=sig.name)
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
        """The spectrum as a power-like value per line (amplitudes squared)."""
        return line_power(self.values, self.amplitude)

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
        ds.attrs.update(band_attributes(self.band, self.kurtogram, self.decimation, self.fs))
        return ds

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.envelope_plots.envelope_spectrum_figure`)."""
        return envelope_spectrum_figure(self, **kwargs)


def line_power(values: np.ndarray, amplitude: str) -> np.ndarray:
    """Power-like values of spectral lines in ``amplitude`` (amplitudes squared, power and
    density as they are): what :func:`analysis.lines.check_lines` compares.

    Amplitudes above 1e150 are refused (their squares would overflow float64).
    """
    require_choice(amplitude, AMPLITUDES, "amplitude")
    if amplitude in ("power", "density"):
        return values
    v = require_real_array(values, "values", min_size=0, max_abs=1e150)
    with np.errstate(under="ignore"):
        return np.square(v)


def band_attributes(band: Band, kg: Kurtogram | None, decimation: int, fs: float) -> dict:
    """Dataset attributes that say which band was demodulated, how it was chosen and at
    which rate the squared envelope was sampled."""
    require_instance(band, Band, "band")
    if kg is not None:
        require_instance(kg, Kurtogram, "kg")
    decimation = require_int(decimation, "decimation", 1)
    fs = require_positive(require_real(fs, "fs"), "fs")
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
    if resolution is not None:
        resolution = require_real(resolution, "resolution")
    env = squared_envelope(x, fs, band=band, max_level=max_level, min_bandwidth=min_bandwidth,
                           time=time, axis=axis, units=units, name=name,
                           workers=workers)  # fmt: skip
    e = env.values
    e -= np.mean(e)
    n = e.size
    common: dict[str, Any] = {"window": window, "amplitude": amp, "overlap": overlap,
                              "units": env.units, "name": env.name, "workers": workers}
    if resolution is None:
        spec = spectrum(e, env.fs, segment_length=max(2, n // SEGMENTS), **common)
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
