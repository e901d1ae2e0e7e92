"""Identify spectral peaks: ranked candidate explanations with tolerances and coincidence odds.

Every peak of a spectrum (or order spectrum) is compared with *candidate lines*: the kinematic
catalogue at the speed of the spectrum (:mod:`analysis.catalogue`: mesh harmonics, sidebands,
shaft, planet-pass, fault and bearing lines) and the modal/instability theory (natural
frequencies ``f_i``, principal-region frequencies ``2 f_i / n`` and sum-type
``(f_i + f_j) / n``). A candidate explains a peak when the peak lies inside the candidate's
tolerance window

    tol = u_peak + u_line * value,

with ``u_peak`` the uncertainty of the peak position (the spectral resolution, or the measured
-3 dB half-width of a broad peak) and ``u_line`` the relative uncertainty of the line (the speed
uncertainty for order-locked lines, the natural-frequency uncertainty for modal lines).

Because the windows of many candidate lines cover part of the band, a random peak lands in some
window with a probability equal to the covered fraction of the band. That *coincidence
probability* is reported for every match (the fraction of a local band around the peak that the
candidate's family covers), for every peak (all families) and for the whole band, so a label
comes with the odds that it is a coincidence; a peak that nothing explains is reported as
unexplained. Matches are ranked by ``exp(-2 (deviation / tol)^2) / coincidence`` (the
likelihood of the deviation for a true line against that of a chance match).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.cf import cf_dataset
from analysis.checks import require_finite, require_instance, require_int, require_positive

__all__ = [
    "CandidateLines",
    "LineMatch",
    "PeakIdentification",
    "catalogue_lines",
    "covered_fraction",
    "identify_peaks",
    "mesh_lines",
    "modal_lines",
    "peak_half_widths",
    "plot_identification",
    "ratio_expression",
]

MODAL_FAMILIES = ("natural", "principal", "sum")


@dataclass(frozen=True)
class CandidateLines:
    """A set of candidate lines on one axis (Hz or orders).

    Attributes
    ----------
    value : ndarray
        Line positions (Hz, or orders for order spectra).
    family : ndarray of str
        Family of each line (catalogue families, ``"natural"``, ``"principal"``, ``"sum"``).
    expression : ndarray of str
        Display expression, e.g. ``"2 f_mesh"``, ``"f2/2"``, ``"(f2 + f3)/2"``.
    uncertainty : ndarray
        Relative uncertainty of each line value.
    locked : ndarray of str
        ``"order"`` (moves with speed) or ``"frequency"`` (fixed in Hz).
    axis : str
        ``"frequency"`` [Hz] or ``"order"``.
    """

    value: np.ndarray
    family: np.ndarray
    expression: np.ndarray
    uncertainty: np.ndarray
    locked: np.ndarray
    axis: str = "frequency"

    def __len__(self) -> int:
        return int(self.value.size)

    def __add__(self, other: CandidateLines) -> CandidateLines:
        if not isinstance(other, CandidateLines):
            return NotImplemented
        if other.axis != self.axis:
            raise ValueError(f"cannot combine candidate lines on axis {self.axis!r} and "
                             f"{other.axis!r}")

        def joined(field: str) -> np.ndarray:
            return np.concatenate([getattr(self, field), getattr(other, field)])

        return CandidateLines(joined("value"), joined("family"), joined("expression"),
                              joined("uncertainty"), joined("locked"), axis=self.axis)

    @classmethod
    def empty(cls, axis: str = "frequency") -> CandidateLines:
        """No lines."""
        return cls(np.zeros(0), np.zeros(0, object), np.zeros(0, object), np.zeros(0),
                   np.zeros(0, object), axis=axis)

    def tolerance(self, peak_uncertainty: float) -> np.ndarray:
        """Half-width of every line's window for a peak uncertainty (same unit as ``value``)."""
        return float(peak_uncertainty) + self.uncertainty * np.abs(self.value)

    @property
    def families(self) -> list[str]:
        """Distinct families in order of appearance."""
        return list(dict.fromkeys(str(f) for f in self.family))


def _axis(axis: str) -> str:
    if axis not in ("frequency", "order"):
        raise ValueError(f"axis = {axis!r} is not admissible: 'frequency' or 'order'")
    return axis


def catalogue_lines(catalogue: Any, *, speed_rpm: float | None = None, axis: str = "frequency",
                    speed_uncertainty: float = 1e-3, visible_only: bool = True,
                    families: Iterable[str] | None = None) -> CandidateLines:
    """Candidate lines from a :class:`analysis.catalogue.KinematicCatalogue`.

    Parameters
    ----------
    catalogue : KinematicCatalogue
        The kinematic catalogue.
    speed_rpm : float, optional
        Reference speed [min-1] (default: the catalogue's); needed for ``axis="frequency"``.
    axis : {"frequency", "order"}
        Lines in Hz (at the speed) or in orders of the catalogue's reference shaft.
    speed_uncertainty : float
        Relative uncertainty of the speed (frequency axis) or of the order tracking (order
        axis).
    visible_only : bool
        Leave out the lines the planet phasing cancels at the sensor.
    families : iterable of str, optional
        Families to use (default: all).

    Returns
    -------
    CandidateLines
        With several mesh frequencies (stages, stepped planets) an expression that does not
        name its member gets it in brackets: ``"2 f_mesh [stage2.pinion-wheel]"``.
    """
    require_instance(catalogue, "analysis.catalogue.KinematicCatalogue", "catalogue")
    axis = _axis(axis)
    u = require_positive(speed_uncertainty, "speed_uncertainty", allow_zero=True)
    cat = catalogue.select(families=families, visible_only=visible_only)
    if axis == "frequency":
        sp = speed_rpm if speed_rpm is not None else cat.speed_rpm
        if sp is None:
            raise ValueError("speed_rpm is needed for catalogue lines in Hz")
        value = cat.frequency_hz(require_positive(sp, "speed_rpm"))
    else:
        value = cat.order.copy()
    n = len(cat)
    expression = cat.formula.astype(object).copy()
    if len(set(catalogue.member[catalogue.family == "mesh"])) > 1:
        # several mesh frequencies (stages, stepped planets): say whose line it is where the
        # formula does not (f_mesh, sidebands, planet pass, planet faults)
        expression = np.asarray([f if str(m) in str(f) else f"{f} [{m}]"
                                 for f, m in zip(cat.formula, cat.member, strict=True)],
                                dtype=object)
    return CandidateLines(value=value, family=cat.family.astype(object).copy(),
                          expression=expression,
                          uncertainty=np.full(n, u), locked=np.full(n, "order", dtype=object),
                          axis=axis)


def mesh_lines(mesh_frequency: float, harmonics: int = 7, *, axis: str = "frequency",
               uncertainty: float = 1e-3) -> CandidateLines:
    """Mesh harmonics ``m f_mesh`` alone (when no catalogue is at hand).

    Parameters
    ----------
    mesh_frequency : float
        Mesh frequency [Hz] (or mesh order on the order axis).
    harmonics : int
        ``m = 1..harmonics``.
    axis : {"frequency", "order"}
    uncertainty : float
        Relative uncertainty (speed).
    """
    fm = require_positive(mesh_frequency, "mesh_frequency")
    if int(harmonics) != harmonics or harmonics < 1:
        raise ValueError(f"harmonics = {harmonics!r} is not admissible: an integer >= 1")
    m = np.arange(1, int(harmonics) + 1)
    return CandidateLines(value=m * fm, family=np.full(m.size, "mesh", dtype=object),
                          expression=np.asarray(["f_mesh" if k == 1 else f"{k} f_mesh"
                                                 for k in m], dtype=object),
                          uncertainty=np.full(m.size, require_positive(
                              uncertainty, "uncertainty", allow_zero=True)),
                          locked=np.full(m.size, "order", dtype=object), axis=_axis(axis))


def ratio_expression(num: int, den: int, name: str) -> str:
    """``num/den · name`` in the paper's style: ``2 f2``, ``f2``, ``2 f2/3``, ``f2/2``."""
    from math import gcd

    g = gcd(num, den)
    a, b = num // g, den // g
    head = name if a == 1 else f"{a} {name}"
    return head if b == 1 else f"{head}/{b}"


def _clusters(f: np.ndarray, rtol: float) -> list[list[int]]:
    order = np.argsort(f, kind="stable")
    out: list[list[int]] = []
    for i in order:
        if out and abs(f[i] - f[out[-1][0]]) <= rtol * f[i]:
            out[-1].append(int(i))
        else:
            out.append([int(i)])
    return out


#: Largest ``n`` of :func:`modal_lines` (regions of order ``n`` are ``O(eps^n)`` narrow).
MAX_N = 100


def modal_lines(natural_frequencies_hz: Any, *, names: Sequence[str] | None = None,
                n_max: int = 4, kinds: Sequence[str] = MODAL_FAMILIES,
                uncertainty: float = 0.01, repeat_rtol: float = 1e-6, axis: str = "frequency",
                speed_rpm: float | None = None, speed_uncertainty: float = 1e-3
                ) -> CandidateLines:
    """Candidate lines of the modal/instability theory.

    Parameters
    ----------
    natural_frequencies_hz : array_like
        Natural frequencies [Hz] (> 0; rigid-body modes removed).
    names : sequence of str, optional
        Mode names (default ``f1, f2, ...``).
    n_max : int
        Largest ``n`` of ``2 f_i / n`` and ``(f_i + f_j) / n``.
    kinds : sequence of str
        Subset of ``("natural", "principal", "sum")``.
    uncertainty : float
        Relative uncertainty of the natural frequencies (model against measurement).
    repeat_rtol : float
        Natural frequencies equal within this relative tolerance are one (degenerate) cluster:
        written ``f3 ≈ f4``, and their sum is ``2 f3``.
    axis : {"frequency", "order"}
        Lines in Hz, or converted to orders at ``speed_rpm`` (then the speed uncertainty adds).
    speed_rpm : float, optional
        Reference speed [min-1] for ``axis="order"``.
    speed_uncertainty : float
        Relative speed uncertainty (order axis only).

    Returns
    -------
    CandidateLines
        Families ``natural`` (``f_i``), ``principal`` (``2 f_i / n`` for ``n != 2``) and
        ``sum`` (``(f_i + f_j) / n``, distinct clusters).

    Notes
    -----
    In the ``n``-th principal instability region the mesh frequency is near ``2 f_i / n`` and
    the response contains ``f_i``; in a sum-type region ``f_mesh ~ (f_i + f_j) / n`` (Nayfeh &
    Mook 1979, ch. 5; the paper's list ``620 Hz ≈ f2/2``, ``1650 Hz ≈ (f2 + f3)/2``). In a
    run-up spectrum a peak at ``2 f_i / n`` is the mesh frequency while the run passes that
    region.
    """
    axis = _axis(axis)
    f = require_finite(natural_frequencies_hz, "natural_frequencies_hz").ravel()
    if f.size == 0 or np.any(f <= 0):
        raise ValueError("natural_frequencies_hz must be > 0 (remove rigid-body modes first)")
    if require_int(n_max, "n_max", 1) > MAX_N:
        raise ValueError(f"n_max = {n_max!r} is not admissible: an integer in 1 .. {MAX_N}")
    kinds = tuple(kinds)
    bad = [k for k in kinds if k not in MODAL_FAMILIES]
    if bad or not kinds:
        raise ValueError(f"kinds = {kinds!r} is not admissible: a subset of {MODAL_FAMILIES}")
    labels = list(names) if names is not None else [f"f{i + 1}" for i in range(f.size)]
    if len(labels) != f.size:
        raise ValueError(f"names has {len(labels)} entries; natural_frequencies_hz has {f.size}")
    u = require_positive(uncertainty, "uncertainty", allow_zero=True)
    cl = _clusters(f, require_positive(repeat_rtol, "repeat_rtol", allow_zero=True))
    rows: list[tuple[float, str, str]] = []
    for c in cl:
        fc = float(f[c].mean())
        if "natural" in kinds:
            rows.append((fc, "natural", " ≈ ".join(labels[i] for i in c)))
        if "principal" in kinds:
            for n in range(1, int(n_max) + 1):
                if n != 2:
                    rows.append((2 * fc / n, "principal",
                                 " ≈ ".join(ratio_expression(2, n, labels[i]) for i in c)))
    if "sum" in kinds:
        for a in range(len(cl)):
            for b in range(a + 1, len(cl)):
                fab = float(f[cl[a]].mean() + f[cl[b]].mean())
                for n in range(1, int(n_max) + 1):
                    exprs = []
                    for i in cl[a]:
                        for j in cl[b]:
                            s = f"{labels[min(i, j)]} + {labels[max(i, j)]}"
                            exprs.append(s if n == 1 else f"({s})/{n}")
                    rows.append((fab / n, "sum", " ≈ ".join(exprs)))
    value = np.asarray([r[0] for r in rows], dtype=float)
    rel = np.full(value.size, u)
    if axis == "order":
        sp = require_positive(speed_rpm, "speed_rpm") if speed_rpm is not None else None
        if sp is None:
            raise ValueError("speed_rpm is needed to place natural frequencies on an order axis")
        value = value * 60.0 / sp
        rel = rel + require_positive(speed_uncertainty, "speed_uncertainty", allow_zero=True)
    return CandidateLines(value=value, family=np.asarray([r[1] for r in rows], dtype=object),
                          expression=np.asarray([r[2] for r in rows], dtype=object),
                          uncertainty=rel, locked=np.full(value.size, "frequency", dtype=object),
                          axis=axis)


def covered_fraction(centres: np.ndarray, half_widths: np.ndarray, lo: float, hi: float
                     ) -> float:
    """Fraction of ``[lo, hi]`` covered by the union of ``[c - w, c + w]``."""
    if hi <= lo:
        return 0.0
    c = np.asarray(centres, dtype=float)
    w = np.broadcast_to(np.asarray(half_widths, dtype=float), c.shape)
    a = np.clip(c - w, lo, hi)
    b = np.clip(c + w, lo, hi)
    keep = b > a
    if not keep.any():
        return 0.0
    order = np.argsort(a[keep])
    a, b = a[keep][order], b[keep][order]
    total, cur_a, cur_b = 0.0, a[0], b[0]
    for x, y in zip(a[1:], b[1:], strict=True):
        if x > cur_b:
            total += cur_b - cur_a
            cur_a, cur_b = x, y
        else:
            cur_b = max(cur_b, y)
    total += cur_b - cur_a
    return float(total / (hi - lo))


class _Union:
    """Union of intervals ``[c - w, c + w]`` with fast covered length over any ``[a, b]``."""

    def __init__(self, centres: np.ndarray, half_widths: np.ndarray) -> None:
        c = np.asarray(centres, dtype=float)
        w = np.broadcast_to(np.asarray(half_widths, dtype=float), c.shape)
        order = np.argsort(c - w)
        lo, hi = (c - w)[order], (c + w)[order]
        starts: list[float] = []
        ends: list[float] = []
        for x, y in zip(lo, hi, strict=True):
            if starts and x <= ends[-1]:
                ends[-1] = max(ends[-1], y)
            else:
                starts.append(x)
                ends.append(y)
        self.lo = np.asarray(starts)
        self.hi = np.asarray(ends)
        self.cum = np.concatenate([[0.0], np.cumsum(self.hi - self.lo)])

    def _upto(self, x: float) -> float:
        k = int(np.searchsorted(self.lo, x, side="right"))  # intervals starting <= x
        if k == 0:
            return 0.0
        return float(self.cum[k - 1] + min(x, self.hi[k - 1]) - self.lo[k - 1])

    def fraction(self, a: float, b: float) -> float:
        """Covered fraction of ``[a, b]``."""
        if b <= a or self.lo.size == 0:
            return 0.0
        return (self._upto(b) - self._upto(a)) / (b - a)


def peak_half_widths(frequency: Any, level_db: Any, peaks: Any, *, drop_db: float = 3.0
                     ) -> np.ndarray:
    """Half-width of each peak at ``drop_db`` below its maximum (same unit as ``frequency``).

    Parameters
    ----------
    frequency : array_like
        Equally spaced axis of the spectrum.
    level_db : array_like
        Spectrum in dB.
    peaks : array_like
        Peak positions on the same axis.
    drop_db : float
        Level drop defining the width (3 dB: half power).

    Returns
    -------
    ndarray
        Half of the width between the crossings of ``max - drop_db`` on both sides (linear
        interpolation between bins).
    """
    x = require_finite(frequency, "frequency").ravel()
    y = require_finite(level_db, "level_db").ravel()
    if x.size != y.size or x.size < 3:
        raise ValueError("frequency and level_db need the same length (>= 3)")
    d = require_positive(drop_db, "drop_db")
    out = []
    for p in np.atleast_1d(np.asarray(peaks, dtype=float)):
        k = int(np.clip(np.searchsorted(x, p), 1, x.size - 1))
        k = k if y[k] >= y[k - 1] else k - 1
        top = y[k] - d
        i = k
        while i > 0 and y[i - 1] > top:
            i -= 1
        left = x[i] if i == 0 else np.interp(top, [y[i - 1], y[i]], [x[i - 1], x[i]])
        j = k
        while j < x.size - 1 and y[j + 1] > top:
            j += 1
        right = x[j] if j == x.size - 1 else np.interp(top, [y[j + 1], y[j]],
                                                        [x[j + 1], x[j]])
        out.append(0.5 * (right - left))
    return np.asarray(out, dtype=float)


@dataclass(frozen=True)
class LineMatch:
    """One candidate explanation of a peak.

    Attributes
    ----------
    expression : str
        E.g. ``"2 f_mesh"``, ``"f2/2"``, ``"f_mesh + f_pp"``.
    family : str
        Family of the line.
    value : float
        Line position (Hz or orders).
    deviation : float
        ``peak - value``.
    tolerance : float
        Half-width of the line's window.
    coincidence : float
        Fraction of the local band around the peak covered by this family's windows: the
        chance that a random peak there matches the family.
    score : float
        Ranking score ``exp(-2 (deviation/tolerance)^2) / coincidence``.
    """

    expression: str
    family: str
    value: float
    deviation: float
    tolerance: float
    coincidence: float
    score: float

    @property
    def value_hz(self) -> float:
        """Alias of :attr:`value` (Hz on a frequency axis)."""
        return self.value

    @property
    def relative_error(self) -> float:
        """``|deviation| / value``."""
        return abs(self.deviation) / abs(self.value) if self.value else np.inf


@dataclass(frozen=True)
class PeakIdentification:
    """Candidate explanations of a list of peaks.

    Attributes
    ----------
    peaks : ndarray
        Peak positions (Hz or orders).
    matches : tuple of tuple of LineMatch
        For every peak the matching candidates, best first (empty: unexplained).
    coincidence : ndarray
        Per peak: fraction of the local band covered by all candidate windows.
    peak_uncertainty : ndarray
        Per peak: the uncertainty of its position used in the windows.
    coverage : dict
        Fraction of the whole band covered, per family and ``"all"``: the rate at which
        random peaks get a label.
    band : (float, float)
        The band.
    axis : str
        ``"frequency"`` or ``"order"``.
    local_width : float
        Relative half-width of the local band used for :attr:`coincidence`.
    """

    peaks: np.ndarray
    matches: tuple[tuple[LineMatch, ...], ...]
    coincidence: np.ndarray
    peak_uncertainty: np.ndarray
    coverage: dict = field(default_factory=dict)
    band: tuple[float, float] = (0.0, 0.0)
    axis: str = "frequency"
    local_width: float = 0.1
    max_coincidence: float = 0.5

    def __len__(self) -> int:
        return int(self.peaks.size)

    @property
    def status(self) -> np.ndarray:
        """Per peak: ``"explained"`` (best candidate's family covers at most
        :attr:`max_coincidence` of the local band), ``"ambiguous"`` (candidates within
        tolerance, but a random peak would match as easily) or ``"unexplained"``."""
        out = []
        for ms in self.matches:
            if not ms:
                out.append("unexplained")
            elif ms[0].coincidence <= self.max_coincidence:
                out.append("explained")
            else:
                out.append("ambiguous")
        return np.asarray(out, dtype=object)

    @property
    def peak_frequencies_hz(self) -> np.ndarray:
        """Alias of :attr:`peaks` (Hz on a frequency axis)."""
        return self.peaks

    @property
    def explained(self) -> np.ndarray:
        """True for peaks whose best candidate is not likely a coincidence (see :attr:`status`).
        """
        return self.status == "explained"

    @property
    def matched(self) -> np.ndarray:
        """True for peaks with at least one candidate within tolerance (explained or ambiguous).
        """
        return np.asarray([bool(m) for m in self.matches], dtype=bool)

    @property
    def unexplained_fraction(self) -> float:
        """Fraction of the peaks that nothing explains."""
        return float(np.mean(self.status == "unexplained")) if len(self) else 0.0

    def _head(self, i: int) -> str:
        p = float(self.peaks[i])
        if self.axis == "order":
            return f"order {p:.4g}"
        return f"{p:.0f} Hz" if abs(p) >= 100 else f"{p:.3g} Hz"

    def label(self, i: int, *, max_matches: int = 3) -> str:
        """Paper-style label of peak ``i``: ``"620 Hz ≈ f2/2 ≈ f_mesh − f_pp"``.

        Up to ``max_matches`` best candidates; ``"...: unexplained"`` if none;
        ``"...: ambiguous (...)"`` when the windows cover so much of the band around the peak
        that a random peak would match as easily.
        """
        ms = self.matches[i]
        if not ms:
            return f"{self._head(i)}: unexplained"
        text = " ≈ ".join([self._head(i), *(m.expression for m in ms[:max_matches])])
        if ms[0].coincidence > self.max_coincidence:
            cands = ", ".join(m.expression for m in ms[:max_matches])
            return (f"{self._head(i)}: ambiguous ({cands} within ± {ms[0].tolerance:.3g}; "
                    "chance match "
                    f"{100 * ms[0].coincidence:.0f} %)")
        return text

    @property
    def labels(self) -> list[str]:
        """All labels."""
        return [self.label(i) for i in range(len(self))]

    def __str__(self) -> str:
        rows = []
        for i in range(len(self)):
            rows.append(self.label(i))
            for m in self.matches[i]:
                rows.append(f"    {m.family:14} {m.expression:32} dev {m.deviation:+.4g} "
                            f"(tol ±{m.tolerance:.3g}), chance match {100 * m.coincidence:.1f} %")
        rows.append(f"band {self.band[0]:.4g}–{self.band[1]:.4g}: candidate windows cover "
                    f"{100 * self.coverage.get('all', 0.0):.1f} % (random peaks get a label at "
                    "this rate)")
        return "\n".join(rows)

    def to_dataset(self, *, max_matches: int = 3):
        """Table as :class:`xarray.Dataset` (dimensions ``peak`` and ``rank``)."""
        import xarray as xr

        unit = "Hz" if self.axis == "frequency" else "1"
        k = max(1, int(max_matches))
        n = len(self)

        def grid(attr, fill, dtype):
            out = np.full((n, k), fill, dtype=dtype)
            for i, ms in enumerate(self.matches):
                for r, m in enumerate(ms[:k]):
                    out[i, r] = getattr(m, attr)
            return out

        def v(x, units, long_name, dims=("peak",)):
            return (dims, x, {"units": units, "long_name": long_name})

        pr = ("peak", "rank")
        ds = xr.Dataset(
            {
                "peak_position": v(self.peaks, unit, f"peak {self.axis}"),
                "label": v(np.asarray(self.labels, dtype=str), "1", "identification label"),
                "status": v(self.status.astype(str), "1",
                            "explained, ambiguous (likely coincidence) or unexplained"),
                "explained": v(self.explained.astype(np.int8), "1",
                               "1 if the best candidate is not likely a coincidence"),
                "n_matches": v(np.asarray([len(m) for m in self.matches]), "1",
                               "number of candidates within tolerance"),
                "coincidence": v(self.coincidence, "1", "fraction of the local band covered by "
                                 "all candidate windows"),
                "peak_uncertainty": v(self.peak_uncertainty, unit, "uncertainty of the peak "
                                      "position"),
                "expression": v(grid("expression", "", object).astype(str), "1",
                                "candidate expression", pr),
                "family": v(grid("family", "", object).astype(str), "1", "candidate family", pr),
                "deviation": v(grid("deviation", np.nan, float), unit,
                               "peak minus candidate", pr),
                "tolerance": v(grid("tolerance", np.nan, float), unit,
                               "half-width of the candidate window", pr),
                "match_coincidence": v(grid("coincidence", np.nan, float), "1",
                                       "chance that a random peak matches this family", pr),
            },
            coords={"peak": ("peak", np.arange(n), {"units": "1", "long_name": "peak index"}),
                    "rank": ("rank", np.arange(k), {"units": "1",
                                                    "long_name": "rank of the candidate"})},
            attrs={"axis": self.axis, "band_low": float(self.band[0]),
                   "band_high": float(self.band[1]), "local_width": self.local_width,
                   "max_coincidence": self.max_coincidence,
                   **{f"coverage_{k2}": float(v2) for k2, v2 in self.coverage.items()}},
        )
        return cf_dataset(
            ds, title="identified peaks",
            producer="analysis.identification.identify_peaks"
        )

    def plot(self, frequency: Any = None, amplitude: Any = None, ax: Any = None,
             max_matches: int = 2):
        """Mark the peaks over an optional spectrum (delegates to :func:`plot_identification`)."""
        return plot_identification(self, frequency, amplitude, ax=ax, max_matches=max_matches)


def plot_identification(ident: PeakIdentification, frequency: Any = None, amplitude: Any = None,
                        ax: Any = None, *, max_matches: int = 2):
    """Peaks marked with their best candidates (explained: red; unexplained "?" and ambiguous
    "~": grey).

    Parameters
    ----------
    ident : PeakIdentification
    frequency, amplitude : array_like, optional
        A spectrum to draw underneath (same axis as the peaks).
    ax : matplotlib Axes, optional
    max_matches : int
        Candidates written per peak.

    Returns
    -------
    matplotlib.figure.Figure
    """
    require_instance(ident, PeakIdentification, "ident")
    if ax is not None and (not hasattr(ax, "figure") or not hasattr(ax, "plot")):
        raise TypeError(f"ax must be matplotlib Axes; got {type(ax).__name__}")
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(8, 4.5), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    top = 1.0
    if frequency is not None and amplitude is not None:
        ax.plot(frequency, amplitude, color="C0", lw=0.8)
        lo, hi = float(np.min(amplitude)), float(np.max(amplitude))
        ax.set_ylim(lo, hi + 0.6 * (hi - lo))  # the upper part holds the labels
        top = hi + 0.58 * (hi - lo)
        ax.set_ylabel("amplitude")
    status = ident.status
    for i, p in enumerate(ident.peaks):
        ok = status[i] == "explained"
        ax.axvline(p, color="C3" if ok else "0.6", lw=0.6, alpha=0.7)
        text = (" ≈ ".join(m.expression for m in ident.matches[i][:max_matches]) if ok
                else "?" if status[i] == "unexplained" else "~")
        ax.annotate(text, (p, top), rotation=90, fontsize=6, va="top", ha="right",
                    color="k" if ok else "0.4")
    ax.set_xlabel("frequency [Hz]" if ident.axis == "frequency" else "order")
    ax.set_title(f"Peak identification: {int(ident.explained.sum())} of {len(ident)} explained "
                 "('?' unexplained, '~' ambiguous); a random peak is matched at "
                 f"{100 * ident.coverage.get('all', 0.0):.0f} %", fontsize=9)
    return fig


def identify_peaks(
    peaks: Any,
    lines: CandidateLines | Sequence[CandidateLines],
    *,
    resolution: float,
    peak_widths: Any = None,
    resolution_factor: float = 0.5,
    band: tuple[float, float] | None = None,
    local_width: float = 0.1,
    max_coincidence: float = 0.5,
) -> PeakIdentification:
    """Rank the candidate explanations of every peak.

    Parameters
    ----------
    peaks : array_like
        Peak positions (Hz, or orders for an order spectrum) (> 0).
    lines : CandidateLines or sequence of CandidateLines
        Candidates (:func:`catalogue_lines`, :func:`modal_lines`, :func:`mesh_lines`).
    resolution : float
        Resolution of the spectrum (bin spacing or ENBW, same unit as ``peaks``).
    peak_widths : array_like, optional
        Half-width of each peak (e.g. :func:`peak_half_widths` at -3 dB); a broad peak's
        position is uncertain by this much. The uncertainty used is the larger of it and
        ``resolution_factor * resolution``.
    resolution_factor : float
        Peak-position uncertainty in units of ``resolution`` (default 0.5).
    band : (float, float), optional
        Band for the coverage (default: from 0.5 x the lowest to 1.5 x the highest peak).
    local_width : float
        Relative half-width of the local band for the per-peak coincidence (default 0.1: the
        band from 0.9 p to 1.1 p).
    max_coincidence : float
        A peak whose best candidate's family covers more than this fraction of the local band
        is *ambiguous*, not explained (a random peak would match as easily).

    Returns
    -------
    PeakIdentification
    """
    p = np.asarray(peaks, dtype=float).ravel()
    if p.size:  # no peaks at all is a valid (empty) result
        p = require_finite(p, "peaks")
    if np.any(p <= 0):
        raise ValueError("peaks must be > 0")
    if isinstance(lines, CandidateLines):
        lines = [lines]
    lines = list(lines)
    if not lines or not all(isinstance(x, CandidateLines) for x in lines):
        raise ValueError("lines must be CandidateLines (catalogue_lines, modal_lines, ...)")
    allc = lines[0]
    for x in lines[1:]:
        allc = allc + x
    res = require_positive(resolution, "resolution")
    rf = require_positive(resolution_factor, "resolution_factor")
    lw = require_positive(local_width, "local_width")
    mc = require_positive(max_coincidence, "max_coincidence")
    if lw >= 1:
        raise ValueError(f"local_width = {local_width!r} is not admissible: < 1 (relative)")
    u_peak = np.full(p.size, rf * res)
    if peak_widths is not None:
        w = require_finite(peak_widths, "peak_widths").ravel()
        if w.size != p.size:
            raise ValueError(f"peak_widths has {w.size} entries; peaks has {p.size}")
        u_peak = np.maximum(u_peak, np.abs(w))
    if band is None:
        lo, hi = (0.5 * float(p.min()), 1.5 * float(p.max())) if p.size else (0.0, 1.0)
    else:
        lo, hi = (float(b) for b in band)
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
            raise ValueError(f"band = {band!r} is not admissible: 0 <= low < high")
    fams = allc.families
    typical = float(np.median(u_peak)) if p.size else rf * res
    tol_typ = allc.tolerance(typical)
    coverage = {f: covered_fraction(allc.value[allc.family == f], tol_typ[allc.family == f],
                                    lo, hi) for f in fams}
    coverage["all"] = covered_fraction(allc.value, tol_typ, lo, hi)
    cache: dict[float, tuple[np.ndarray, _Union, dict[str, _Union]]] = {}

    def unions(u: float) -> tuple[np.ndarray, _Union, dict[str, _Union]]:
        if u not in cache:
            tol = allc.tolerance(u)
            cache[u] = (tol, _Union(allc.value, tol),
                        {f: _Union(allc.value[allc.family == f], tol[allc.family == f])
                         for f in fams})
        return cache[u]

    matches, coinc = [], np.zeros(p.size)
    for i, pk in enumerate(p):
        tol, u_all, u_fam = unions(float(u_peak[i]))
        a, b = max(lo, pk * (1 - lw)), min(hi, pk * (1 + lw))
        if b <= a:
            a, b = pk * (1 - lw), pk * (1 + lw)
        coinc[i] = u_all.fraction(a, b)
        dev = pk - allc.value
        hit = np.flatnonzero(np.abs(dev) <= tol)
        found = []
        for k in hit:
            f = str(allc.family[k])
            c = max(u_fam[f].fraction(a, b), 1e-12)
            score = float(np.exp(-2.0 * (dev[k] / tol[k]) ** 2) / c)
            found.append(LineMatch(str(allc.expression[k]), f, float(allc.value[k]),
                                   float(dev[k]), float(tol[k]), float(c), score))
        found.sort(key=lambda m: (-m.score, abs(m.deviation)))
        matches.append(tuple(found))
    return PeakIdentification(peaks=p, matches=tuple(matches), coincidence=coinc,
                              peak_uncertainty=u_peak, coverage=coverage, band=(lo, hi),
                              axis=allc.axis, local_width=lw, max_coincidence=mc)
