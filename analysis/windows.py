"""Spectral windows: periodic ("DFT-even") samples and their figures of merit.

The cosine-sum windows are evaluated from their coefficients; their main-lobe half widths
(first null, in bins) are tabulated for the order-band defaults. The equivalent noise
bandwidth (ENBW) of any window is computed from its samples (Heinzel, Rüdiger & Schilling
2002, section 10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "WINDOWS",
    "WindowInfo",
    "WindowSpec",
    "get_window",
    "main_lobe_half_width",
    "parse_window",
    "window_info",
    "window_info_of",
    "window_sums",
]

#: Admissible window names (``"boxcar"`` is an alias of ``"rectangular"``).
WINDOWS = ("rectangular", "boxcar", "hann", "hamming", "blackmanharris", "flattop", "kaiser")

# Cosine-sum coefficients a_k of w[n] = sum_k (-1)^k a_k cos(2 pi k n / L), periodic form.
_COSINE_SUMS: dict[str, tuple[float, ...]] = {
    "rectangular": (1.0,),
    "hann": (0.5, 0.5),
    "hamming": (0.54, 0.46),
    # 4-term Blackman-Harris, -92 dB sidelobes (Harris 1978, table 1)
    "blackmanharris": (0.35875, 0.48829, 0.14128, 0.01168),
    # 5-term flat-top of ISO 18431-2 / D'Antona & Ferrero 2006 (same as MATLAB flattopwin);
    # scalloping loss < 0.01 dB, ENBW 3.77 bins (Heinzel et al. 2002, appendix D)
    "flattop": (0.21557895, 0.41663158, 0.277263158, 0.083578947, 0.006947368),
}
_KAISER_DEFAULT_BETA = 0.5  # MATLAB kaiser() / rpmfreqmap default

WindowSpec = str | tuple[str, float]


@dataclass(frozen=True)
class WindowInfo:
    """Name, parameter and figures of merit of a window of a given length.

    Attributes
    ----------
    name : str
        Canonical window name.
    beta : float or None
        Kaiser shape parameter (``None`` for the other windows).
    length : int
        Number of samples.
    coherent_gain : float
        ``sum(w) / L`` (amplitude gain for a sine on bin).
    enbw_bins : float
        Equivalent noise bandwidth in bins, ``L * sum(w**2) / sum(w)**2``.
    """

    name: str
    beta: float | None
    length: int
    coherent_gain: float
    enbw_bins: float

    def enbw_hz(self, fs: float) -> float:
        """Equivalent noise bandwidth [Hz] at sample rate ``fs`` (independent of zero padding)."""
        return self.enbw_bins * fs / self.length

    @property
    def label(self) -> str:
        """``"kaiser(beta=..)"`` or the plain name."""
        return self.name if self.beta is None else f"{self.name}(beta={self.beta:g})"


def parse_window(window: WindowSpec) -> tuple[str, float | None]:
    """Canonical name and Kaiser beta (``None`` for the others) of a window specification."""
    beta: float | None = None
    if isinstance(window, tuple):
        if len(window) != 2 or not isinstance(window[0], str):
            raise ValueError(
                f"window = {window!r} is not admissible: use a name from {WINDOWS} or "
                "('kaiser', beta)"
            )
        name, beta = window[0].lower(), float(window[1])
        if name != "kaiser":
            raise ValueError(f"window = {window!r}: only 'kaiser' takes a parameter (beta)")
    elif isinstance(window, str):
        name = window.lower()
    else:
        raise ValueError(f"window = {window!r} is not admissible: must be one of {WINDOWS}")
    if name not in WINDOWS:
        raise ValueError(f"window = {window!r} is not admissible: must be one of {WINDOWS}")
    if name == "boxcar":
        name = "rectangular"
    if name == "kaiser":
        beta = _KAISER_DEFAULT_BETA if beta is None else beta
        if not np.isfinite(beta) or beta < 0:
            raise ValueError(f"window kaiser beta = {beta!r} is not admissible: must be >= 0")
    return name, beta


def get_window(window: WindowSpec, n: int) -> np.ndarray:
    """Periodic ("DFT-even") window of length ``n`` for spectral analysis.

    Parameters
    ----------
    window : str or ("kaiser", beta)
        One of :data:`WINDOWS`; ``"kaiser"`` alone uses beta = 0.5 (MATLAB's default).
    n : int
        Length (>= 1).

    Returns
    -------
    numpy.ndarray
        Window samples; the cosine-sum windows have their maximum at index ``n // 2``.
    """
    name, beta = parse_window(window)
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"window length n = {n!r} is not admissible: must be an integer >= 1")
    k = np.arange(n, dtype=float)
    if name == "kaiser":
        assert beta is not None
        r = 2.0 * k / n - 1.0  # periodic: symmetric window of n + 1 points without the last
        return np.i0(beta * np.sqrt(np.clip(1.0 - r * r, 0.0, None))) / np.i0(beta)
    coeffs = _COSINE_SUMS[name]
    w = np.full(n, coeffs[0])
    for j, a in enumerate(coeffs[1:], start=1):
        w += (-1) ** j * a * np.cos(2.0 * np.pi * j * k / n)
    return w


def window_info(window: WindowSpec, n: int) -> WindowInfo:
    """Coherent gain and ENBW of a window of length ``n`` (see :class:`WindowInfo`)."""
    return window_info_of(window, get_window(window, n))


def window_sums(w: np.ndarray) -> tuple[float, float]:
    """``sum(w)`` and ``sum(w**2)`` by numpy's pairwise summation.

    Not ``np.dot``: above 10 000 samples OpenBLAS splits a dot product over its threads,
    which costs milliseconds on a loaded machine and makes the rounding depend on the thread
    count.
    """
    return float(w.sum()), float(np.square(w).sum())


def window_info_of(window: WindowSpec, w: np.ndarray) -> WindowInfo:
    """:class:`WindowInfo` of the samples ``w`` of ``window`` (no second evaluation)."""
    name, beta = parse_window(window)
    n = w.size
    s1, s2 = window_sums(w)
    return WindowInfo(name, beta, int(n), s1 / n, n * s2 / (s1 * s1))



def main_lobe_half_width(window: WindowSpec) -> float:
    """Half width of the main lobe in bins (first null for the cosine sums)."""
    name, beta = parse_window(window)
    table = {"rectangular": 1.0, "hann": 2.0, "hamming": 2.0, "blackmanharris": 4.0, "flattop": 5.0}
    if name == "kaiser":
        assert beta is not None
        return float(np.sqrt(1.0 + (beta / np.pi) ** 2))
    return table[name]

