"""Spectral windows: periodic ("DFT-even") samples and their figures of merit.

Every window name of :func:`scipy.signal.get_window` is accepted, with its parameters as a
tuple (``("tukey", 0.25)``, ``("chebwin", 100)``, ``("gaussian", std)``, ``("dpss", NW)``),
and windows are always periodic (``fftbins=True``), the right form for spectral analysis.
The five windows order analysis uses most -- rectangular, Hann, Hamming, 4-term
Blackman-Harris and the ISO 18431-2 flat-top (the same as MATLAB ``flattopwin``) -- are
evaluated from their cosine-sum coefficients here (they agree with scipy to 1e-12), and
``"kaiser"`` alone means beta = 0.5, MATLAB's default. The equivalent noise bandwidth (ENBW)
and coherent gain of any window are computed from its samples (Heinzel, Rüdiger & Schilling
2002, section 10); the main-lobe half width, which sets the default order-band width, is
tabulated for the cosine sums and the Kaiser window and found numerically (first minimum of
the window's transform) for the others.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.signal

from analysis.checks import require_real_array

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

#: Window names evaluated here; any other :func:`scipy.signal.get_window` name is accepted too.
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
# scipy's aliases of the windows evaluated here
_ALIASES = {
    "boxcar": "rectangular", "box": "rectangular", "ones": "rectangular", "rect": "rectangular",
    "han": "hann", "hamm": "hamming", "ham": "hamming", "blackharr": "blackmanharris",
    "bkh": "blackmanharris", "flat": "flattop", "flt": "flattop", "ksr": "kaiser",
}  # fmt: skip
# main-lobe half widths [bins] (first null) of the cosine sums
_MAIN_LOBE = {
    "rectangular": 1.0, "hann": 2.0, "hamming": 2.0, "blackmanharris": 4.0, "flattop": 5.0
}  # fmt: skip
_KAISER_DEFAULT_BETA = 0.5  # MATLAB kaiser() / rpmfreqmap default
_HELP = (
    "a window name or a (name, parameter, ...) tuple as accepted by scipy.signal.get_window, "
    "e.g. 'hann', 'flattop', ('kaiser', 6.0), ('tukey', 0.25)"
)

WindowSpec = str | tuple[Any, ...]


@dataclass(frozen=True)
class WindowInfo:
    """Name, parameters and figures of merit of a window of a given length.

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
    params : tuple
        Parameters of the window other than Kaiser's beta (empty for most).
    """

    name: str
    beta: float | None
    length: int
    coherent_gain: float
    enbw_bins: float
    params: tuple[Any, ...] = ()

    def enbw_hz(self, fs: float) -> float:
        """Equivalent noise bandwidth [Hz] at sample rate ``fs`` (independent of zero padding)."""
        return self.enbw_bins * fs / self.length

    @property
    def label(self) -> str:
        """``"kaiser(beta=..)"``, ``"tukey(0.25)"`` or the plain name."""
        if self.beta is not None:
            return f"{self.name}(beta={self.beta:g})"
        if self.params:
            return f"{self.name}({', '.join(_fmt(p) for p in self.params)})"
        return self.name

    @property
    def spec(self) -> WindowSpec:
        """Window specification that gives this window again."""
        if self.beta is not None:
            return (self.name, self.beta)
        return (self.name, *self.params) if self.params else self.name


def _fmt(p: Any) -> str:
    if isinstance(p, tuple):
        return "[" + ", ".join(_fmt(v) for v in p) + "]"
    return f"{p:g}" if isinstance(p, float) else str(p)


def _describe(window: Any) -> str:
    """Short description of an inadmissible window (never prints an array's contents)."""
    if isinstance(window, np.ndarray):
        return f"an array of shape {window.shape}"
    if isinstance(window, str | int | float | bool) or window is None:
        return repr(window)
    if isinstance(window, tuple) and len(window) <= 4 and all(
        isinstance(v, str | int | float) for v in window
    ):
        return repr(window)
    return f"a {type(window).__name__}"


def _param(value: Any, window: Any) -> Any:
    """A window parameter as a float, or a tuple of floats (``general_cosine`` weights)."""
    if isinstance(value, bool):
        raise ValueError(f"window = {_describe(window)} is not admissible: use {_HELP}")
    if isinstance(value, int | float | np.integer | np.floating):
        v = float(value)
        if not np.isfinite(v):
            raise ValueError(f"window parameter {v!r} is not admissible: must be finite")
        return v
    if isinstance(value, list | tuple | np.ndarray):
        arr = np.asarray(value, dtype=float) if np.asarray(value).dtype.kind in "iuf" else None
        if arr is not None and arr.ndim == 1 and 0 < arr.size <= 16 and np.all(np.isfinite(arr)):
            return tuple(float(v) for v in arr)
    raise ValueError(f"window = {_describe(window)} is not admissible: use {_HELP}")


def parse_window(window: WindowSpec) -> tuple[str, float | None]:
    """Canonical name and Kaiser beta (``None`` for the others) of a window specification.

    Raises a short :class:`ValueError` (naming ``window`` and what is admissible) for anything
    :func:`scipy.signal.get_window` would not accept.
    """
    name, beta, _ = _parse(window)
    return name, beta


def _parse(window: Any) -> tuple[str, float | None, tuple[Any, ...]]:
    if isinstance(window, tuple) and window and isinstance(window[0], str):
        name, params = window[0].lower(), tuple(_param(p, window) for p in window[1:])
    elif isinstance(window, str):
        name, params = window.lower(), ()
    else:
        raise ValueError(f"window = {_describe(window)} is not admissible: use {_HELP}")
    name = _ALIASES.get(name, name)
    if name == "kaiser":
        if len(params) > 1 or (params and isinstance(params[0], tuple)):
            raise ValueError(f"window = {_describe(window)}: kaiser takes one parameter (beta)")
        beta = params[0] if params else _KAISER_DEFAULT_BETA
        if beta < 0:
            raise ValueError(f"window kaiser beta = {beta!r} is not admissible: must be >= 0")
        return name, beta, ()
    if name in _COSINE_SUMS:
        if params:
            raise ValueError(
                f"window = {_describe(window)}: {name!r} takes no parameter (('kaiser', beta) "
                "and scipy's parametrised windows do)"
            )
        return name, None, ()
    spec = (name, *(list(p) if isinstance(p, tuple) else p for p in params)) if params else name
    try:
        scipy.signal.get_window(spec, 16, fftbins=True)
    except (ValueError, TypeError) as exc:
        text = str(exc)
        reason = "it needs parameters: pass a tuple" if "must have parameters" in text else (
            "unknown name" if "Invalid window name" in text or "Unknown window" in text
            else "scipy.signal.get_window refuses it"
        )
        raise ValueError(
            f"window = {_describe(window)} is not admissible ({reason}): use {_HELP}"
        ) from None
    return name, None, params


def get_window(window: WindowSpec, n: int) -> np.ndarray:
    """Periodic ("DFT-even") window of length ``n`` for spectral analysis.

    Parameters
    ----------
    window : str or tuple
        Any name or ``(name, parameters...)`` tuple of :func:`scipy.signal.get_window`
        (``"rectangular"`` is an alias of ``"boxcar"``); ``"kaiser"`` alone uses beta = 0.5
        (MATLAB's default).
    n : int
        Length (>= 1).

    Returns
    -------
    numpy.ndarray
        Window samples; the cosine-sum windows have their maximum at index ``n // 2``.
    """
    name, beta, params = _parse(window)
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"window length n = {n!r} is not admissible: must be an integer >= 1")
    k = np.arange(n, dtype=float)
    if name == "kaiser":
        assert beta is not None
        r = 2.0 * k / n - 1.0  # periodic: symmetric window of n + 1 points without the last
        return np.i0(beta * np.sqrt(np.clip(1.0 - r * r, 0.0, None))) / np.i0(beta)
    if name not in _COSINE_SUMS:
        spec = (name, *(list(p) if isinstance(p, tuple) else p for p in params)) if params else name
        return np.asarray(scipy.signal.get_window(spec, int(n), fftbins=True), dtype=float)
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
    count. ``w`` must be 1-D, finite and at most 1e100 in magnitude (its squares would
    overflow); squares of tiny samples underflow to zero silently.
    """
    w = require_real_array(w, "w", ndim=1, min_size=1, max_abs=1e100)
    with np.errstate(under="ignore"):
        return float(w.sum()), float(np.square(w).sum())


def window_info_of(window: WindowSpec, w: np.ndarray) -> WindowInfo:
    """:class:`WindowInfo` of the samples ``w`` of ``window`` (no second evaluation)."""
    name, beta, params = _parse(window)
    s1, s2 = window_sums(w)  # checks w
    w = np.asarray(w, dtype=float)
    n = w.size
    if not s1 > 0:
        raise ValueError(f"window = {_describe(window)}: its samples sum to {s1:g} (must be > 0)")
    if not 1e-100 < s1 < 1e100:  # ENBW is scale-free: computed on w / max|w| (no underflow)
        peak = float(np.max(np.abs(w)))
        u1, u2 = window_sums(w / peak)
        return WindowInfo(name, beta, int(n), s1 / n, n * u2 / (u1 * u1), params)
    return WindowInfo(name, beta, int(n), s1 / n, n * s2 / (s1 * s1), params)



def main_lobe_half_width(window: WindowSpec) -> float:
    """Half width of the main lobe in bins (first null of the window's transform).

    Tabulated for the cosine sums, ``sqrt(1 + (beta / pi)^2)`` for Kaiser; for any other
    window the first local minimum of ``|W|`` on a 64-times zero-padded transform of 1024
    samples (to 1/64 bin).
    """
    name, beta, _ = _parse(window)
    if name == "kaiser":
        assert beta is not None
        return float(np.sqrt(1.0 + (beta / np.pi) ** 2))
    if name in _MAIN_LOBE:
        return _MAIN_LOBE[name]
    n, pad = 1024, 64
    mag = np.abs(np.fft.rfft(get_window(window, n), n * pad))
    rising = np.flatnonzero(np.diff(mag) > 0)
    first_min = int(rising[0]) if rising.size else mag.size - 1
    return first_min / pad
