"""Spectral kurtosis (Antoni 2006) and the fast kurtogram (Antoni 2007).

**Spectral kurtosis** of a signal with short-time Fourier transform ``X(t, f)``::

    K(f) = <|X(t, f)|^4> / <|X(t, f)|^2>^2 - 2,

the average ``<.>`` running over the frames ``t`` (Antoni 2006, its STFT-based estimator).
``K = 0`` for stationary Gaussian noise (complex circular STFT
coefficients), ``-1`` for a constant sine, and large where a band carries transients, which
is what makes it the detector of impulsive (bearing, local gear) faults: it says *where* in
frequency the impulses stand out of the noise. At DC and Nyquist the coefficients are real:
Gaussian noise gives ``K = 1`` there, and the bins within the window's main lobe of them are
biased the same way.

**Fast kurtogram** (Antoni 2007): the kurtosis of the complex band signals of a 1/3-binary
tree of bands covering ``[0, fs/2]``: level ``k`` (``k = 0, 1, 2, ...``) cuts it into
``2^k`` bands of ``fs / 2^(k+1)``, the intermediate level ``k + log2(3) - 1`` (labelled 1.6,
2.6, ...) into ``3 * 2^(k-1)`` bands of ``fs / (3 * 2^k)``. For a band signal ``c(n)``::

    K = <|c(n)|^4> / <|c(n)|^2>^2 - 2,

and the band of largest ``K`` is the one in which the impulses stand out best: the band
for envelope analysis (:mod:`analysis.envelope`). Here the band signals are not made by the
paper's cascade of short quasi-analytic FIR filters but by the smooth-edged bands of
:mod:`analysis.bands` in the DFT of the record (block by block), decimated like the paper's
(a band of width ``B`` sampled at ``2B``): sharper band edges (gain 1/2 at the band
edges, 1 over the central half: ``KURTOGRAM_TRANSITION``), the same tree, ``O(N log N)``
per level. The band-signal samples within ten transition periods of the record's ends are
left out (:func:`analysis.bands.band_moments`): there a band holds the filter's response to
the start and end of the record, which would dominate a band with little energy. The band
of largest ``K`` may be restricted to bands at least ``min_bandwidth`` wide.

**Spread under Gaussian noise.** For ``M`` independent complex Gaussian samples the
estimator has mean ``-2 / (M + 1)`` and variance ``4 / M`` (delta method; the fourth-moment
ratio of ``M`` exponential powers). Correlated samples (overlapping frames, oversampled band
signals) count as ``M_eff = M / (1 + 2 sum_k |rho_k|^4)``, ``rho_k`` the correlation of the
noise samples ``k`` apart; both results report ``M_eff`` and the resulting Gaussian
threshold ``u_(1-p) * 2 / sqrt(M_eff)``.

**Caveats.** (1) Low frequency resolution (wide bands, short STFT windows) dilutes the
impulses in the noise of the whole band: ``K`` of signal plus noise is
``K_s / (1 + rho)^2`` with ``rho`` the noise-to-signal power ratio in the band (Antoni
2006), so a wide band of weak impulses reads low. (2) High resolution (narrow bands, long
windows) lets the impulse responses of successive impacts overlap: the band signal tends to
Gaussian and ``K`` falls again, and its estimate is noisier (fewer independent samples):
the maximum over the many narrow bands of a Gaussian record is a few spreads above 0, not 0.
(3) ``K`` measures impulsiveness, not periodicity: one knock, electrical spikes or a
clipped record give large ``K`` too; the envelope spectrum must then show the fault's lines
(Antoni & Randall 2006).

References
----------
J. Antoni, "The spectral kurtosis: a useful tool for characterising non-stationary
signals", Mechanical Systems and Signal Processing 20(2), 282-307, 2006.
J. Antoni, R. B. Randall, "The spectral kurtosis: application to the vibratory surveillance
and diagnostics of rotating machines", MSSP 20(2), 308-331, 2006.
J. Antoni, "Fast computation of the kurtogram for the detection of transient faults", MSSP
21(1), 108-124, 2007.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.special

from analysis.bands import Band, band_moments, smooth_step
from analysis.checks import require_int, require_real, time_or_rate
from analysis.envelope_plots import kurtogram_figure, spectral_kurtosis_figure
from analysis.fft import rfft_plan
from analysis.inputs import one_channel, signal_input
from analysis.windows import WindowSpec, get_window, window_info_of

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = [
    "KURTOGRAM_TRANSITION",
    "MAX_LEVEL",
    "Kurtogram",
    "SpectralKurtosis",
    "fast_kurtogram",
    "gaussian_threshold",
    "kurtogram_levels",
    "spectral_kurtosis",
]

#: Default deepest level of the fast kurtogram (also limited to ``log2(n) - 8``).
MAX_LEVEL = 8
_TREE_LEVELS = 48  # deepest tree kurtogram_levels lists (2**48 bands: no record is that long)
#: Smooth-edge width of the kurtogram's bands, as a fraction of their width: gain 1/2 at the
#: band edges, 1 over the central half; short impulse responses (a few band periods).
KURTOGRAM_TRANSITION = 0.5
_BLOCK_ROWS = 1 << 17  # windowed samples per batch of STFT frames


def gaussian_threshold(effective_samples: float, probability: float = 0.01) -> float:
    """Kurtosis that stationary Gaussian noise exceeds with ``probability`` (one-sided).

    ``u_(1-p) * 2 / sqrt(M_eff)``: the estimator is asymptotically normal with variance
    ``4 / M_eff`` (module docstring).

    Parameters
    ----------
    effective_samples : float
        ``M_eff`` (> 0).
    probability : float
        False-alarm probability per estimate, in (0, 0.5).
    """
    m = float(effective_samples)
    p = float(probability)
    if not (math.isfinite(m) and m > 0):
        raise ValueError(f"effective_samples = {effective_samples!r} must be finite and > 0")
    if not 0.0 < p < 0.5:
        raise ValueError(f"probability = {probability!r} is not admissible: must be in (0, 0.5)")
    return float(np.sqrt(2.0) * scipy.special.erfcinv(2.0 * p) * 2.0 / np.sqrt(m))


def _effective(m: int, rho4: np.ndarray) -> float:
    """``M / (1 + 2 sum_k (1 - k/M) |rho_k|^4)`` for correlations ``rho_k``, k = 1, 2, ..."""
    k = np.arange(1, rho4.size + 1)
    keep = k < m
    return m / (1.0 + 2.0 * float(np.sum((1.0 - k[keep] / m) * rho4[keep])))


# ------------------------------------------------------------------------ spectral kurtosis


@dataclass(frozen=True)
class SpectralKurtosis:
    """STFT-based spectral kurtosis (see :func:`spectral_kurtosis`).

    Attributes
    ----------
    frequency : numpy.ndarray
        Bin frequencies [Hz].
    kurtosis : numpy.ndarray
        ``K(f)`` (dimensionless).
    n_frames : int
        Frames averaged ``M``.
    effective_frames : float
        ``M_eff``: ``M`` corrected for the overlap of the frames.
    segment_length : int
        Samples per frame.
    overlap : float
        Frame overlap fraction.
    window : str
        Window label.
    resolution_hz : float
        The window's ENBW [Hz].
    fs : float
        Sample rate [Hz].
    name : str
        Channel name.
    """

    frequency: np.ndarray
    kurtosis: np.ndarray
    n_frames: int
    effective_frames: float
    segment_length: int
    overlap: float
    window: str
    resolution_hz: float
    fs: float
    name: str = "x"

    def threshold(self, probability: float = 0.01) -> float:
        """``K`` that stationary Gaussian noise exceeds with ``probability`` in one bin
        (:func:`gaussian_threshold` with ``M_eff`` frames)."""
        return gaussian_threshold(self.effective_frames, probability)

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset with ``spectral_kurtosis(frequency)``."""
        import xarray as xr

        return xr.Dataset(
            {
                "spectral_kurtosis": (
                    "frequency",
                    self.kurtosis,
                    {"units": "1", "long_name": f"spectral kurtosis of {self.name}"},
                )
            },
            coords={
                "frequency": (
                    "frequency", self.frequency, {"units": "Hz", "long_name": "frequency"}
                )
            },
            attrs={
                "n_frames": int(self.n_frames),
                "effective_frames": float(self.effective_frames),
                "segment_length": int(self.segment_length),
                "overlap": float(self.overlap),
                "window": self.window,
                "resolution_hz": float(self.resolution_hz),
                "sample_rate_hz": float(self.fs),
                "gaussian_threshold_1pct": self.threshold(0.01),
            },
        )

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.envelope_plots.spectral_kurtosis_figure`)."""
        return spectral_kurtosis_figure(self, **kwargs)


def spectral_kurtosis(
    x: Any,
    fs: float | None = None,
    *,
    segment_length: int = 256,
    window: WindowSpec = "hann",
    overlap: float = 0.75,
    time: Any = None,
    axis: int | None = None,
    name: str | None = None,
    workers: int | None = None,
) -> SpectralKurtosis:
    """Spectral kurtosis of one channel from its short-time Fourier transform (Antoni 2006).

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One channel (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or ``time``).
    segment_length : int, default 256
        Samples per STFT frame, 4 to ``len(x) // 4``: short enough that a frame holds about
        one impact response, long enough to resolve the resonance (Antoni & Randall 2006).
    window : str or tuple, default "hann"
        STFT window.
    overlap : float, default 0.75
        Frame overlap fraction in ``[0, 1)``.
    time, axis, name, workers
        As in :func:`analysis.spectrum.spectrum`.

    Returns
    -------
    SpectralKurtosis
        ``K(f)`` on the ``segment_length // 2 + 1`` bins, with the frame counts.

    Notes
    -----
    ``K(f) = M S4(f) / S2(f)^2 - 2`` with ``S_n(f) = sum_t |X(t, f)|^n`` over the ``M``
    frames (the mean is removed from ``x`` first). The effective number of frames uses the
    correlation of the frames of white noise, ``rho_k = sum_n w(n) w(n + kR) / sum w^2``
    (hop ``R``; module docstring).
    """
    fs, time = time_or_rate(fs, time, "spectral_kurtosis")
    sig = signal_input(x, fs, time=time, axis=axis, name=name)
    v = one_channel(sig, "spectral_kurtosis")
    n = sig.n
    seg = require_int(segment_length, "segment_length", 4)
    if seg > n // 4:
        raise ValueError(
            f"segment_length = {seg} is not admissible: must be <= len(x) // 4 = {n // 4} "
            "(at least 4 frames)"
        )
    ov = float(overlap)
    if not 0.0 <= ov < 1.0:
        raise ValueError(f"overlap = {overlap!r} is not admissible: must be in [0, 1)")
    step = max(1, round(seg * (1.0 - ov)))
    w = get_window(window, seg)
    info = window_info_of(window, w)
    frames = np.lib.stride_tricks.sliding_window_view(v, seg)[::step]
    m = frames.shape[0]
    mean = float(np.mean(v, dtype=np.float64))
    nbins = seg // 2 + 1
    s2 = np.zeros(nbins)
    s4 = np.zeros(nbins)
    rows = max(1, min(m, _BLOCK_ROWS // seg))
    for r0 in range(0, m, rows):
        r1 = min(m, r0 + rows)
        plan = rfft_plan(r1 - r0, seg, workers=workers)
        np.subtract(frames[r0:r1], mean, out=plan.input)
        plan.input *= w
        spec = plan.execute()
        p = spec.real * spec.real
        p += spec.imag * spec.imag
        s2 += p.sum(axis=0)
        s4 += np.square(p).sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(s2 > 0, m * s4 / np.where(s2 > 0, s2 * s2, 1.0) - 2.0, np.nan)
    lags = np.arange(1, max(1, -(-seg // step)))
    ww = float(np.square(w).sum())
    rho = np.array([float(np.dot(w[: seg - j * step], w[j * step :])) / ww for j in lags])
    return SpectralKurtosis(
        frequency=np.arange(nbins) * (sig.fs / seg),
        kurtosis=k,
        n_frames=int(m),
        effective_frames=_effective(m, rho**4),
        segment_length=seg,
        overlap=ov,
        window=info.label,
        resolution_hz=info.enbw_hz(sig.fs),
        fs=sig.fs,
        name=sig.name,
    )


# ----------------------------------------------------------------------------- kurtogram


def kurtogram_levels(max_level: int) -> list[tuple[float, int]]:
    """Levels of the 1/3-binary tree down to ``max_level``: ``(level, number of bands)``.

    ``[(0, 1), (1, 2), (1.585, 3), (2, 4), (2.585, 6), ..., (max_level, 2**max_level)]``:
    the level is ``log2`` of the number of bands, so a band is ``fs / 2^(level + 1)`` wide.
    """
    top = require_int(max_level, "max_level", 1)
    if top > _TREE_LEVELS:
        raise ValueError(
            f"max_level = {max_level!r} is not admissible: an integer in 1..{_TREE_LEVELS} "
            "(2**max_level bands; a record holds fewer samples than that)"
        )
    rows = [(0.0, 1)]
    for k in range(1, top + 1):
        rows.append((float(k), 2**k))
        if k < top:
            rows.append((math.log2(3 * 2 ** (k - 1)), 3 * 2 ** (k - 1)))
    return rows


@functools.lru_cache(maxsize=4)
def _band_rho4(transition: float) -> np.ndarray:
    """``|rho_k|^4`` of white noise through one band (gain of :class:`analysis.bands.Band`,
    width 1, transition ``transition``) sampled at twice its width, k = 1..64."""
    f = np.linspace(-0.5 - transition / 2, 0.5 + transition / 2, 4097)
    g2 = smooth_step((0.5 + 0.5 * transition - np.abs(f)) / transition) ** 2
    k = np.arange(1, 65)
    rho = (g2[None, :] * np.exp(2j * np.pi * f[None, :] * k[:, None] / 2.0)).sum(axis=1)
    return np.abs(rho / g2.sum()) ** 4


@dataclass(frozen=True)
class Kurtogram:
    """The fast kurtogram (see :func:`fast_kurtogram`).

    Attributes
    ----------
    levels : numpy.ndarray
        Level of each row (``log2`` of its number of bands: 0, 1, 1.585, 2, ...).
    n_bands : numpy.ndarray
        Bands of each row.
    kurtosis : numpy.ndarray
        ``K`` of every band, shape ``(row, max bands)``; NaN beyond a row's bands.
    samples : numpy.ndarray
        Band-signal samples ``M`` averaged per band of each row.
    effective_samples : numpy.ndarray
        ``M_eff`` per row (module docstring).
    fs : float
        Sample rate [Hz].
    n_samples : int
        Samples of the record.
    transition : float
        Smooth-edge width as a fraction of the band width (:mod:`analysis.bands`).
    name : str
        Channel name.
    min_bandwidth : float
        Narrowest band [Hz] the choice (:attr:`best`) may take; 0: any.
    """

    levels: np.ndarray
    n_bands: np.ndarray
    kurtosis: np.ndarray
    samples: np.ndarray
    effective_samples: np.ndarray
    fs: float
    n_samples: int
    transition: float = KURTOGRAM_TRANSITION
    name: str = "x"
    min_bandwidth: float = 0.0

    @property
    def max_level(self) -> int:
        """Deepest (binary) level."""
        return round(float(self.levels[-1]))

    @property
    def best(self) -> tuple[int, int]:
        """``(row, band)`` of the largest kurtosis among the bands at least
        :attr:`min_bandwidth` wide (the first one on ties: the widest band, then the lowest
        frequency)."""
        widths = 0.5 * self.fs / self.n_bands
        k = np.where((widths >= self.min_bandwidth)[:, None], self.kurtosis, np.nan)
        flat = int(np.nanargmax(k))
        return flat // k.shape[1], flat % k.shape[1]

    def band_of(self, row: int, index: int) -> Band:
        """The :class:`analysis.bands.Band` of band ``index`` of row ``row``."""
        width = 0.5 * self.fs / int(self.n_bands[row])
        return Band(index * width, (index + 1) * width, self.transition * width)

    @property
    def band(self) -> Band:
        """The band of largest kurtosis."""
        return self.band_of(*self.best)

    @property
    def level(self) -> float:
        """Level of the band of largest kurtosis."""
        return float(self.levels[self.best[0]])

    @property
    def centre(self) -> float:
        """Centre frequency [Hz] of the band of largest kurtosis."""
        return self.band.centre

    @property
    def bandwidth(self) -> float:
        """Width [Hz] of the band of largest kurtosis."""
        return self.band.width

    @property
    def kurtosis_max(self) -> float:
        """The largest kurtosis."""
        return float(self.kurtosis[self.best])

    def threshold(self, probability: float = 0.01) -> np.ndarray:
        """Per row: ``K`` that stationary Gaussian noise exceeds with ``probability`` in one
        band (:func:`gaussian_threshold`)."""
        return np.array([gaussian_threshold(m, probability) for m in self.effective_samples])

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """The usual kurtogram image: cell centres [Hz] of the finest common grid and
        ``K`` per ``(row, cell)`` (each band's value over its cells)."""
        cells = math.lcm(*(int(b) for b in self.n_bands))
        freq = (np.arange(cells) + 0.5) * (0.5 * self.fs / cells)
        image = np.empty((self.levels.size, cells))
        for r, nb in enumerate(self.n_bands):
            image[r] = np.repeat(self.kurtosis[r, : int(nb)], cells // int(nb))
        return freq, image

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset: ``kurtosis(level, frequency)`` on the common grid, the band table
        (``band_*(band)``) and the chosen band in the attributes."""
        import xarray as xr

        freq, image = self.grid()
        rows = [(r, i) for r, nb in enumerate(self.n_bands) for i in range(int(nb))]
        r_idx = np.array([r for r, _ in rows])
        i_idx = np.array([i for _, i in rows])
        width = 0.5 * self.fs / self.n_bands[r_idx]
        best = self.band
        return xr.Dataset(
            {
                "kurtosis": (
                    ("level", "frequency"),
                    image,
                    {"units": "1", "long_name": f"band kurtosis of {self.name} (fast kurtogram)"},
                ),
                "band_level": (
                    "band", self.levels[r_idx], {"units": "1", "long_name": "level of the band"}
                ),
                "band_centre": (
                    "band", (i_idx + 0.5) * width, {"units": "Hz", "long_name": "band centre"}
                ),
                "band_width": ("band", width, {"units": "Hz", "long_name": "band width"}),
                "band_kurtosis": (
                    "band", self.kurtosis[r_idx, i_idx], {"units": "1", "long_name": "kurtosis"}
                ),
                "gaussian_threshold": (
                    "level",
                    self.threshold(0.01),
                    {"units": "1", "long_name": "kurtosis exceeded by Gaussian noise with "
                     "probability 0.01 in one band"},
                ),
            },
            coords={
                "level": ("level", self.levels, {"units": "1", "long_name": "level (log2 of "
                          "the number of bands)"}),
                "frequency": ("frequency", freq, {"units": "Hz", "long_name": "frequency"}),
                "band": ("band", np.arange(len(rows)), {"units": "1", "long_name": "band index"}),
            },
            attrs={
                "sample_rate_hz": float(self.fs),
                "n_samples": int(self.n_samples),
                "max_level": self.max_level,
                "transition": float(self.transition),
                "best_level": self.level,
                "best_centre_hz": best.centre,
                "best_bandwidth_hz": best.width,
                "best_low_hz": best.low,
                "best_high_hz": best.high,
                "best_kurtosis": self.kurtosis_max,
                "min_bandwidth_hz": float(self.min_bandwidth),
            },
        )  # fmt: skip

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.envelope_plots.kurtogram_figure`)."""
        return kurtogram_figure(self, **kwargs)


def fast_kurtogram(
    x: Any,
    fs: float | None = None,
    *,
    max_level: int | None = None,
    min_bandwidth: float | None = None,
    time: Any = None,
    axis: int | None = None,
    name: str | None = None,
    workers: int | None = None,
) -> Kurtogram:
    """Fast kurtogram of one channel (Antoni 2007): the band kurtosis over a 1/3-binary tree.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One channel (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or ``time``).
    max_level : int, optional
        Deepest level, 1 to ``log2(n) - 8`` (the narrowest bands then keep at least 256
        band samples, less the guards at the record's ends); default ``min(8, log2(n) - 8)``:
        bands down to ``fs / 512``.
    min_bandwidth : float, optional
        Narrowest band [Hz] the choice may take (all bands are computed and shown). The
        squared envelope of a band of width ``B`` carries modulation frequencies below ``B``
        only, so for envelope analysis give at least twice the highest fault frequency (or
        harmonic) of interest. Default: any band, as in Antoni (2007).
    time, axis, name, workers
        As in :func:`analysis.spectrum.spectrum`.

    Returns
    -------
    Kurtogram
        ``K`` of every band of every level, and the band of largest ``K``.

    Notes
    -----
    Cost: one FFT of the record and, per level, inverse FFTs of its decimated band signals
    (``n`` complex samples in all), block by block (:mod:`analysis.bands`): ``O(n log n)``
    per level, memory a few blocks of about 400 000 samples, whatever ``n``.
    """
    fs, time = time_or_rate(fs, time, "fast_kurtogram")
    sig = signal_input(x, fs, time=time, axis=axis, name=name)
    v = one_channel(sig, "fast_kurtogram")
    n = sig.n
    top = math.floor(math.log2(n)) - 8 if n >= 2 else 0
    if top < 1:
        raise ValueError(
            f"x has {n} samples: the fast kurtogram needs at least 512 (level 1 needs "
            "2^9 samples)"
        )
    if max_level is None:
        level = min(MAX_LEVEL, top)
    else:
        level = require_int(max_level, "max_level", 1)
        if level > top:
            raise ValueError(
                f"max_level = {max_level!r} is not admissible for {n} samples: must be <= "
                f"log2(n) - 8 = {top}"
            )
    if not np.any(v != v[0]):
        raise ValueError("x is constant: its kurtosis is undefined")
    rows = kurtogram_levels(level)
    nyq = 0.5 * sig.fs
    min_bw = 0.0
    if min_bandwidth is not None:
        min_bw = require_real(min_bandwidth, "min_bandwidth")
        if not 0.0 <= min_bw <= nyq:
            raise ValueError(
                f"min_bandwidth = {min_bandwidth!r} Hz is not admissible: must be in "
                f"[0, fs/2 = {nyq:g}]"
            )
    tw = KURTOGRAM_TRANSITION
    bands = [
        [Band(i * nyq / nb, (i + 1) * nyq / nb, tw * nyq / nb) for i in range(nb)]
        for _, nb in rows
    ]
    s2, s4, counts = band_moments(v, sig.fs, bands, [nb for _, nb in rows], workers=workers)
    width = max(nb for _, nb in rows)
    kurt = np.full((len(rows), width), np.nan)
    for r, (a2, a4, m) in enumerate(zip(s2, s4, counts, strict=True)):
        safe = np.where(a2 > 0, a2 * a2, 1.0)
        kurt[r, : a2.size] = np.where(a2 > 0, m * a4 / safe - 2.0, np.nan)
    rho4 = _band_rho4(KURTOGRAM_TRANSITION)
    return Kurtogram(
        levels=np.array([lv for lv, _ in rows]),
        n_bands=np.array([nb for _, nb in rows]),
        kurtosis=kurt,
        samples=np.array(counts),
        effective_samples=np.array([_effective(m, rho4) for m in counts]),
        fs=sig.fs,
        n_samples=n,
        transition=KURTOGRAM_TRANSITION,
        name=sig.name,
        min_bandwidth=min_bw,
    )
