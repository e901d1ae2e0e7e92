"""Label spectral peaks with natural-frequency combinations and mesh harmonics.

Produces lists in the style used in run-up reports, e.g. ``"300 Hz ≈ f2/4 ≈ f3/6"``,
``"1650 Hz ≈ (f2 + f3)/2"``, ``"3600 Hz ≈ 2 f3 ≈ 2 f4"`` or ``"1280 Hz ≈ 2 f_mesh"``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.checks import require_finite, require_positive
from analysis.instability.theory import _cluster, _positive_frequencies

__all__ = ["PeakLabels", "PeakMatch", "label_peaks"]

_KIND_RANK = {"natural": 0, "mesh": 1, "harmonic": 2, "subharmonic": 3, "sum": 4}


@dataclass(frozen=True)
class PeakMatch:
    """One theory expression matching a peak.

    Attributes
    ----------
    expression : str
        E.g. ``"f2/4"``, ``"2 f3"``, ``"(f2 + f3)/2"``, ``"2 f_mesh"``.
    value_hz : float
        Value of the expression [Hz].
    relative_error : float
        ``|peak - value| / value``.
    kind : str
        ``"natural"`` (f_i), ``"subharmonic"`` (f_i/n), ``"harmonic"`` (n f_i), ``"sum"``
        ((f_i + f_j)/n) or ``"mesh"`` (n f_mesh).
    order : int
        ``n``.
    modes : tuple of int
        Zero-based mode indices involved (empty for mesh harmonics).
    """

    expression: str
    value_hz: float
    relative_error: float
    kind: str
    order: int
    modes: tuple[int, ...]


def _fmt_hz(f: float) -> str:
    return f"{f:.0f} Hz" if abs(f) >= 100 else f"{f:.3g} Hz"


@dataclass(frozen=True)
class PeakLabels:
    """Theory matches for a list of peaks.

    Attributes
    ----------
    peak_frequencies_hz : ndarray
        Peak frequencies [Hz].
    matches : tuple of tuple of PeakMatch
        For every peak, the matching expressions (sorted by order, then kind and modes).
    tolerance : float
        Relative tolerance used.
    """

    peak_frequencies_hz: np.ndarray
    matches: tuple[tuple[PeakMatch, ...], ...]
    tolerance: float

    def __len__(self) -> int:
        return int(self.peak_frequencies_hz.size)

    def label(self, i: int) -> str:
        """Label of peak ``i``, e.g. ``"300 Hz ≈ f2/4 ≈ f3/6"`` (``"... : no match"``)."""
        head = _fmt_hz(float(self.peak_frequencies_hz[i]))
        if not self.matches[i]:
            return f"{head}: no match"
        return " ≈ ".join([head, *(m.expression for m in self.matches[i])])

    @property
    def labels(self) -> list[str]:
        """All labels, one per peak."""
        return [self.label(i) for i in range(len(self))]

    def __str__(self) -> str:
        return "\n".join(self.labels)

    def to_dataset(self):
        """Table as :class:`xarray.Dataset` with dimension ``peak``."""
        import xarray as xr

        best = [min(m, key=lambda x: x.relative_error) if m else None for m in self.matches]

        def v(x, units, long_name):
            return ("peak", x, {"units": units, "long_name": long_name})

        return xr.Dataset(
            {
                "peak_frequency": v(self.peak_frequencies_hz, "Hz", "peak frequency"),
                "label": v(np.asarray(self.labels, dtype=str), "1", "theory label"),
                "n_matches": v(np.asarray([len(m) for m in self.matches]), "1",
                               "number of matching expressions"),
                "best_expression": v(np.asarray([b.expression if b else "" for b in best],
                                                dtype=str), "1", "closest expression"),
                "best_relative_error": v(np.asarray([b.relative_error if b else np.nan
                                                     for b in best]), "1",
                                         "relative error of closest expression"),
            },
            coords={"peak": ("peak", np.arange(len(self)),
                             {"units": "1", "long_name": "peak index"})},
            attrs={"tolerance": self.tolerance},
        )

    def plot(self, frequency_hz: Any = None, amplitude: Any = None, ax=None):
        """Mark labelled peaks (optionally over a spectrum).

        Delegates to :func:`analysis.instability.plots.plot_peak_labels`.
        """
        from analysis.instability.plots import plot_peak_labels

        return plot_peak_labels(self, frequency_hz, amplitude, ax=ax)


def _expressions(f: np.ndarray, names: Sequence[str], f_mesh: float | None, n_max: int,
                 repeat_rtol: float) -> list[tuple[float, str, str, int, tuple[int, ...]]]:
    out = []
    for i, fi in enumerate(f):
        out.append((fi, names[i], "natural", 1, (i,)))
        for n in range(2, n_max + 1):
            out.append((fi / n, f"{names[i]}/{n}", "subharmonic", n, (i,)))
            out.append((fi * n, f"{n} {names[i]}", "harmonic", n, (i,)))
    cluster_of = {}
    for c, members in enumerate(_cluster(f, repeat_rtol)):
        for i in members:
            cluster_of[i] = c
    for i in range(f.size):
        for j in range(i + 1, f.size):
            if cluster_of[i] == cluster_of[j]:
                continue  # (f3 + f4)/n with f3 = f4 is already 2 f3 / n
            for n in range(1, n_max + 1):
                s = f"{names[i]} + {names[j]}"
                out.append(((f[i] + f[j]) / n, s if n == 1 else f"({s})/{n}", "sum", n, (i, j)))
    if f_mesh is not None:
        for n in range(1, n_max + 1):
            out.append((n * f_mesh, "f_mesh" if n == 1 else f"{n} f_mesh", "mesh", n, ()))
    return out


def label_peaks(
    peak_frequencies_hz: Any,
    natural_frequencies_hz: Any,
    *,
    mesh_frequency_hz: float | None = None,
    n_max: int = 6,
    tolerance: float = 0.03,
    names: Sequence[str] | None = None,
    repeat_rtol: float = 1e-6,
) -> PeakLabels:
    """Match spectral peaks to natural-frequency combinations and mesh harmonics.

    Parameters
    ----------
    peak_frequencies_hz : array_like
        Peak frequencies [Hz] (> 0).
    natural_frequencies_hz : array_like
        Natural frequencies [Hz] (> 0).
    mesh_frequency_hz : float, optional
        Mesh frequency [Hz] of the spectrum (constant-speed segment); adds ``n f_mesh``.
    n_max : int
        Largest ``n`` in ``f_i/n``, ``n f_i``, ``(f_i + f_j)/n`` and ``n f_mesh``.
    tolerance : float
        Relative tolerance: a peak ``p`` matches a value ``v`` if ``|p - v| <= tolerance v``.
    names : sequence of str, optional
        Mode names (default ``f1, f2, ...``).
    repeat_rtol : float
        Natural frequencies equal within this relative tolerance are a repeated pair; both are
        listed (``"f3 ≈ f4"``), but their sum is not (it equals ``2 f3``).

    Returns
    -------
    PeakLabels

    Notes
    -----
    The expressions are those of Mathieu-type theory for a parametrically excited system
    (Nayfeh & Mook 1979, ch. 5): in the ``n``-th principal region, ``f_mesh ~ 2 f_i/n``, the
    response contains ``f_i`` and its combinations with mesh harmonics, so peaks appear at
    ``f_i/n``, ``n f_i`` and at sum combinations ``(f_i + f_j)/n``. A label only states
    numerical coincidence within ``tolerance``; several expressions may match one peak.
    """
    p = require_finite(peak_frequencies_hz, "peak_frequencies_hz").ravel()
    if np.any(p <= 0):
        raise ValueError("peak_frequencies_hz must be > 0")
    f = _positive_frequencies(natural_frequencies_hz, "natural_frequencies_hz")
    if int(n_max) != n_max or n_max < 1:
        raise ValueError(f"n_max = {n_max!r} is not admissible: must be an integer >= 1")
    tol = require_positive(tolerance, "tolerance")
    if tol >= 0.5:
        raise ValueError(f"tolerance = {tolerance!r} is not admissible: must be < 0.5 "
                         "(relative)")
    fm = require_positive(mesh_frequency_hz, "mesh_frequency_hz") if mesh_frequency_hz else None
    labels = list(names) if names is not None else [f"f{i + 1}" for i in range(f.size)]
    if len(labels) != f.size:
        raise ValueError(f"names has {len(labels)} entries; natural_frequencies_hz has {f.size}")
    exprs = _expressions(f, labels, fm, int(n_max),
                         require_positive(repeat_rtol, "repeat_rtol", allow_zero=True))
    values = np.asarray([e[0] for e in exprs])
    matches = []
    for pk in p:
        rel = np.abs(pk - values) / values
        hit = [PeakMatch(exprs[k][1], float(values[k]), float(rel[k]), exprs[k][2], exprs[k][3],
                         exprs[k][4]) for k in np.flatnonzero(rel <= tol)]
        hit.sort(key=lambda m: (m.order, _KIND_RANK[m.kind], m.modes))
        matches.append(tuple(hit))
    return PeakLabels(peak_frequencies_hz=p, matches=tuple(matches), tolerance=tol)
