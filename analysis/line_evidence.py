"""How much a detected line family says: its chance of a coincidence in the same spectrum.

:func:`analysis.lines.check_lines` finds a family (a fundamental and its harmonics) when lines
stand ``threshold_db`` over their local floor at the expected positions. Whether that is
evidence depends on the spectrum: among the few lines of a noisy envelope spectrum a found
family is unlikely to be chance, among the hundreds of beat lines of a band full of steady
tones (``docs/condition-monitoring.md``) it is likely. This module states that chance, in the
spirit of :mod:`analysis.identification` (a label comes with the fraction of the band its
windows cover, i.e. how often a random peak would get it), turned around: how often would a
family of the same shape, placed at random in this spectrum, be detected?

* The **prominent lines** of the spectrum are its local maxima at least ``threshold_db`` over
  the running median of the power (the same floor and threshold as the check), each with
  its prominence.
* The **strength** ``s`` of a detected family is the weakest prominence among the lines its
  detection rests on: the fundamental and the ``m - 1`` most prominent other harmonics
  (``m`` = ``min_harmonics``); for a family not detected ``s`` is the threshold. Only the
  prominent lines at least ``s`` over their floor count as background, and the lines the
  family itself found are left out: they are what is being judged.
* A search window of half-width ``w`` centred at random in the local band ``c (1 +- lw)``
  around an expected line ``c`` holds a background line with probability ``q = covered
  fraction`` of the band by the union of ``[l - w, l + w]`` over the background lines ``l``
  (:func:`analysis.identification.covered_fraction`).
* The fundamental is searched within ``tol p + spacing`` (``q_1``), the other harmonics,
  once it is found, within ``(h/2 + 1)`` line spacings of ``h f_1`` (``q_h``): the chance
  that a family at a random position is detected with lines at least as strong is
  ``chance = q_1 P(at least m - 1 of the harmonics 2..H found)`` with independent ``q_h`` (a
  Poisson-binomial sum): a p-value of the detection against the spectrum's own lines.

Lines have one cause. A real fault fills the envelope spectrum with more than its own
harmonics: an inner-race fault modulated by the shaft gives the whole lattice
``|h f_1 + k f_r|`` (on the CWRU record ``IR007_0`` the lines at 71.7 Hz = BPFI - 3 f_r and
12 Hz = BPFI - 5 f_r), which other families' windows catch. So the families are judged in
order of strength: the lines at the positions a stronger family reported detected explains (its
harmonics found ``h f_1``, with a sideband spacing ``d`` the lattice ``|h f_1 + k d|`` over
the spectrum) and those of ``known`` families (shaft harmonics, mesh orders) are taken; a
detected family whose detection rests on taken lines is **explained** by that family, not
detected.

A family is reported **detected** when the check detects it on lines of its own and its
chance is at most ``max_chance`` (default 1 %), **possible** when a random family would be
detected as easily as that, **explained** (see above), **not detected** otherwise, and
**outside** when its fundamental lies outside the spectrum (or above the demodulated band).
Rates measured on noise, random tones and the healthy CWRU record are in
``docs/condition-monitoring.md``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.cf import cf_dataset
from analysis.checks import (
    require_finite,
    require_instance,
    require_positive,
    require_real,
    require_real_array,
    require_size,
)
from analysis.envelope_plots import line_evidence_figure
from analysis.identification import covered_fraction
from analysis.lines import (
    FLOOR_FACTOR,
    THRESHOLD_DB,
    TOLERANCE,
    LineCheck,
    LineFamily,
    check_lines,
)

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = [
    "MAX_CHANCE",
    "STATUSES",
    "LineEvidence",
    "claim_tolerance",
    "explained_positions",
    "family_chance",
    "line_evidence",
    "prominent_lines",
    "strength",
]

MAX_CHANCE = 0.01
"""Default largest chance of a coincidence for a detected family to be reported detected."""

STATUSES = ("detected", "possible", "explained", "not detected", "outside")
"""Family statuses (see the module docstring)."""

_MIN_FLOOR_LINES = 10


def _floor_wing(family: LineFamily, tolerance: float, spacing: float) -> int:
    """Floor half-width [lines] of :func:`analysis.lines.check_lines` at the fundamental."""
    half = tolerance * family.fundamental + spacing
    return max(round((FLOOR_FACTOR - 1.0) * half / spacing), _MIN_FLOOR_LINES)


def prominent_lines(axis: Any, power: Any, *, threshold_db: float = THRESHOLD_DB,
                    floor_lines: int = 25) -> tuple[np.ndarray, np.ndarray]:
    """The local maxima at least ``threshold_db`` over the running median, with their
    prominence.

    Parameters
    ----------
    axis, power : array_like
        Uniform axis and power-like values (amplitudes squared) of a spectrum.
    threshold_db : float
        Prominence over the floor [dB].
    floor_lines : int
        Half-width of the running median [lines] (>= 1).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        Positions (axis units) of the prominent lines, increasing (the first line, DC, is
        left out), and their power over the running median [dB].
    """
    from scipy.ndimage import median_filter

    ax = require_finite(axis, "axis")
    pw = require_finite(power, "power")
    if ax.ndim != 1 or pw.shape != ax.shape or ax.size < 3:
        raise ValueError("axis and power must be 1-D of equal length (>= 3 lines)")
    thr = require_real(threshold_db, "threshold_db")
    if not -300.0 <= thr <= 300.0:
        raise ValueError(f"threshold_db = {thr!r} is not admissible (admissible: -300 .. 300 dB)")
    if isinstance(floor_lines, bool) or not isinstance(floor_lines, int | np.integer) \
            or floor_lines < 1:
        raise ValueError(f"floor_lines = {floor_lines!r} is not admissible: an integer >= 1")
    floor = median_filter(pw, size=2 * int(floor_lines) + 1, mode="nearest")
    inner = np.arange(1, ax.size - 1)
    peak = (pw[inner] >= pw[inner - 1]) & (pw[inner] > pw[inner + 1])
    loud = pw[inner] >= floor[inner] * 10.0 ** (thr / 10.0)
    k = inner[peak & loud & (pw[inner] > 0)]
    with np.errstate(divide="ignore"):
        prom = 10.0 * np.log10(pw[k] / floor[k])
    return ax[k], prom


def _at_least(q: np.ndarray, k: int) -> float:
    """P(at least ``k`` successes) among independent Bernoulli trials of probabilities ``q``."""
    if k <= 0:
        return 1.0
    dist = np.zeros(q.size + 1)
    dist[0] = 1.0
    for p in q:
        dist[1:] = dist[1:] * (1.0 - p) + dist[:-1] * p
        dist[0] *= 1.0 - p
    return float(np.clip(dist[k:].sum(), 0.0, 1.0))


def strength(check: LineCheck) -> float:
    """The weakest prominence [dB] among the lines a detection rests on: the fundamental and
    the ``min_harmonics - 1`` most prominent other harmonics (the threshold when the family
    is not detected)."""
    require_instance(check, LineCheck, "check")
    if not check.detected:
        return float(check.threshold_db)
    harm = check.sideband == 0
    first = harm & (check.harmonic == 1)
    others = np.sort(np.nan_to_num(check.prominence_db[harm & ~first], nan=-np.inf))[::-1]
    need = others[:check.min_harmonics - 1]
    return float(min(check.prominence_db[first][0], *need)) if need.size else \
        float(check.prominence_db[first][0])


def family_chance(axis: Any, check: LineCheck, lines: np.ndarray,
                  prominence_db: np.ndarray | None = None, *,
                  local_width: float = 0.1) -> float:
    """Chance that a family shaped like ``check.family`` at a random position is detected
    with lines at least as strong as its own.

    Parameters
    ----------
    axis : array_like
        The spectrum's axis (uniform).
    check : LineCheck
        The family's check in that spectrum.
    lines : numpy.ndarray
        The spectrum's prominent lines (:func:`prominent_lines`, same threshold).
    prominence_db : numpy.ndarray, optional
        Their prominence [dB]; only lines at least :func:`strength` count (default: all).
    local_width : float
        Relative half-width of the band around each expected line (0 < lw < 1).

    Returns
    -------
    float
        ``q_1 P(at least m - 1 of q_2..q_H)`` (module docstring); NaN when the fundamental's
        prominence is NaN (outside the spectrum); 0 only when fewer than ``m - 1`` harmonics
        fit into the spectrum (such a family is never detected).

    Notes
    -----
    Each window probability ``q`` is at least ``half / (f_max - f_min)``: the chance that a
    window of half-width ``half`` catches one line placed at random when the spectrum is
    taken to hold *half a line* of the family's strength outside the family's own. The
    background rate is estimated from the spectrum's own lines; when none (or none near an
    expected line) is as strong as the family's, a count of zero does not prove a rate of
    zero, and half a line (the usual continuity correction of a zero count) keeps the chance
    a small positive number instead of exactly 0. On a clean envelope spectrum (a
    160 Hz family, 0.1 Hz lines, 500 Hz wide, 2 of its harmonics needed) the floor gives a
    chance of the order of 1e-5, far below :data:`MAX_CHANCE`.
    """
    ax = require_real_array(axis, "axis", ndim=1, min_size=3)
    require_instance(check, LineCheck, "check")
    lines = require_real_array(lines, "lines", ndim=1, min_size=0)
    if prominence_db is not None:
        prominence_db = require_real_array(prominence_db, "prominence_db", ndim=1, min_size=0)
        if prominence_db.size != lines.size:
            raise ValueError(f"prominence_db has {prominence_db.size} values for {lines.size} "
                             "lines; give one per line")
    lw = require_real(local_width, "local_width")
    if not 0.0 < lw < 1.0:
        raise ValueError(f"local_width = {local_width!r} is not admissible: 0 < lw < 1")
    spacing = float(ax[1] - ax[0])
    lo_ax, hi_ax = float(ax[1]), float(ax[-1])
    fam = check.family
    first = (check.harmonic == 1) & (check.sideband == 0)
    if not first.any() or not np.isfinite(check.prominence_db[first][0]):
        return float("nan")
    # the lines this family found are what is judged, not the background
    own = check.position[check.found]
    keep = np.ones(lines.size, dtype=bool)
    if prominence_db is not None:
        keep &= np.asarray(prominence_db, dtype=float) >= strength(check) - 1e-9
    for p in own:
        keep &= np.abs(lines - p) > 2.0 * spacing
    bg = lines[keep]

    span = hi_ax - lo_ax

    def q(centre: float, half: float) -> float:
        a, b = max(lo_ax, centre * (1 - lw)), min(hi_ax, centre * (1 + lw))
        if b <= a:
            return 0.0
        # floor: half a background line spread over the whole spectrum (see Notes)
        floor = min(1.0, half / span) if span > 0 else 1.0
        if bg.size == 0:
            return floor
        return max(floor, covered_fraction(bg, np.full(bg.size, half), a, b))

    f1 = float(fam.fundamental)
    q1 = q(f1, check.tolerance * f1 + spacing)
    hs = [h for h in range(2, fam.harmonics + 1) if h * f1 + (0.5 * h + 1) * spacing <= hi_ax]
    qh = np.asarray([q(h * f1, (0.5 * h + 1.0) * spacing) for h in hs], dtype=float)
    need = check.min_harmonics - 1
    if need > qh.size:
        return 0.0  # too few harmonics inside the spectrum: never detected
    return float(q1 * _at_least(qh, need))


def explained_positions(check: LineCheck, top: float) -> np.ndarray:
    """Positions a detected family explains: ``h f_1`` (the harmonics, at multiples of the
    fundamental found) and, with a sideband spacing ``d``, ``|h f_1 + k d|`` up to ``top``
    (the lattice of a fault modulated at ``d``; e.g. BPFO = abs(BPFI - Z f_r) of a ball
    bearing).

    Parameters
    ----------
    check : LineCheck
        A family's check whose fundamental was found.
    top : float
        Highest position [axis units].

    Returns
    -------
    numpy.ndarray
        Sorted positions.
    """
    require_instance(check, LineCheck, "check")
    top = require_positive(require_real(top, "top"), "top")
    first = (check.harmonic == 1) & (check.sideband == 0)
    f1 = float(check.position[first][0])
    h = np.arange(1, check.family.harmonics + 1, dtype=float)
    d = float(check.family.sideband_spacing)
    if d <= 0:
        return h * f1
    count = h.size * (top / d + h[-1] * abs(f1) / d + 3.0)  # float: inf for a tiny spacing
    require_size(24.0 * count, f"{count:.3g} candidate line positions", "top")
    k = np.arange(-int(np.ceil(h[-1] * f1 / d)) - 1, int(np.ceil(top / d)) + 1)
    v = np.abs(h[:, None] * f1 + k[None, :] * d).ravel()
    return np.unique(v[(v > 0) & (v <= top)])


def claim_tolerance(harmonic: Any, spacing: float) -> np.ndarray:
    """Distance [axis units] within which a found line of harmonic ``h`` is taken as a known
    line (or one of a stronger family): ``(h/2 + 1.5)`` line spacings (the fundamental's
    search window grows with ``h`` at exact multiples of the fundamental found).

    Parameters
    ----------
    harmonic : array_like of int
        Harmonic numbers.
    spacing : float
        The spectrum's line spacing [axis units].

    Returns
    -------
    numpy.ndarray
        The tolerances.
    """
    return (0.5 * np.asarray(harmonic, dtype=float) + 1.5) * float(spacing)


def _taken(check: LineCheck, claims: list[tuple[str, np.ndarray]], spacing: float
           ) -> tuple[np.ndarray, list[str]]:
    """Per line of ``check``: found and within ``(h/2 + 1.5)`` line spacings of a position a
    claim explains; and the names of the claims concerned."""
    taken = np.zeros(check.position.size, dtype=bool)
    by: list[str] = []
    tol = claim_tolerance(check.harmonic, spacing)
    for name, pos in claims:
        if pos.size == 0 or name == check.family.name:  # a family does not explain itself
            continue
        near = np.zeros(check.position.size, dtype=bool)
        ok = check.found & np.isfinite(check.position)
        if ok.any():
            k = np.clip(np.searchsorted(pos, check.position[ok]), 1, pos.size - 1) \
                if pos.size > 1 else np.zeros(int(ok.sum()), dtype=int)
            dist = np.minimum(np.abs(pos[k] - check.position[ok]),
                              np.abs(pos[np.maximum(k - 1, 0)] - check.position[ok]))
            near[ok] = dist <= tol[ok]
        new = near & ~taken
        if new.any():
            by.append(name)
        taken |= near
    return taken, by


def _detected_with(check: LineCheck, found: np.ndarray) -> bool:
    harm = check.sideband == 0
    first = bool(np.any(found & harm & (check.harmonic == 1)))
    return first and int(np.sum(found & harm)) >= check.min_harmonics


@dataclass(frozen=True)
class LineEvidence:
    """Families checked in one spectrum, each with its chance of a coincidence.

    Attributes
    ----------
    checks : tuple of LineCheck
        One per family (:func:`analysis.lines.check_lines`).
    chance : numpy.ndarray
        Per family: the chance that a family of its shape at a random position in this
        spectrum is detected (:func:`family_chance`; NaN: outside).
    max_chance : float
        Largest chance for a detected family to be reported ``detected``.
    axis, power : numpy.ndarray
        The spectrum checked (axis units ``axis_units``, power-like values).
    axis_units : str
        ``"Hz"`` or ``"1"`` (orders).
    n_lines : int
        Prominent lines of the spectrum.
    name : str
        What the spectrum is (for titles).
    explained_by : tuple of str
        Per family: the stronger families (or ``known`` ones) whose lines its detection rests
        on (``""`` when none): such a family is ``explained``, not detected.
    """

    checks: tuple[LineCheck, ...]
    chance: np.ndarray
    max_chance: float
    axis: np.ndarray
    power: np.ndarray
    axis_units: str = "Hz"
    n_lines: int = 0
    name: str = "spectrum"
    explained_by: tuple[str, ...] = ()

    def __len__(self) -> int:
        return len(self.checks)

    @property
    def names(self) -> list[str]:
        """Family names."""
        return [c.family.name for c in self.checks]

    @property
    def status(self) -> np.ndarray:
        """Per family: ``detected``, ``possible``, ``not detected`` or ``outside``."""
        out = []
        by = self.explained_by or ("",) * len(self.checks)
        for c, ch, b in zip(self.checks, self.chance, by, strict=True):
            if not np.isfinite(ch):
                out.append("outside")
            elif c.detected and b:
                out.append("explained")
            elif c.detected:
                out.append("detected" if ch <= self.max_chance else "possible")
            else:
                out.append("not detected")
        return np.asarray(out, dtype=object)

    @property
    def detected(self) -> np.ndarray:
        """True for the families reported detected."""
        return self.status == "detected"

    def check(self, name: str) -> LineCheck:
        """The check of family ``name``."""
        for c in self.checks:
            if c.family.name == name:
                return c
        raise ValueError(f"name = {name!r} is not a family checked; admissible: {self.names}")

    def rows(self) -> list[tuple[str, ...]]:
        """One row per family: name, expected fundamental, status, harmonics found,
        prominences of the harmonics [dB], sidebands found, chance."""
        out: list[tuple[str, ...]] = []
        unit = "" if self.axis_units == "1" else " Hz"
        by = self.explained_by or ("",) * len(self.checks)
        for c, ch, st, b in zip(self.checks, self.chance, self.status, by, strict=True):
            harm = c.sideband == 0
            prom = ", ".join("–" if not np.isfinite(v) else f"{v:.1f}"
                             for v in c.prominence_db[harm])
            sb = c.sideband != 0
            sbs = (f"{int(np.sum(c.found & sb))}/{int(np.sum(sb))}" if sb.any() else "–")
            chance = "–" if not np.isfinite(ch) else f"{ch:.2g}"
            st = f"{st} by {b}" if st == "explained" else str(st)
            out.append((c.family.name, f"{c.family.fundamental:.4g}{unit}", st,
                        f"{c.harmonics_found}/{int(np.sum(harm))}", prom, sbs, chance))
        return out

    def __str__(self) -> str:
        head = ("family", "fundamental", "status", "harmonics", "prominence [dB]",
                "sidebands", "chance")
        rows = [head, *self.rows()]
        widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
        return "\n".join("  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True))
                         for r in rows)

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset: one entry per family (dimension ``family``) and line (``line``)."""
        import xarray as xr


        n = len(self.checks)
        k = max((c.expected.size for c in self.checks), default=0)

        def grid(attr: str) -> np.ndarray:
            out = np.full((n, k), np.nan)
            for i, c in enumerate(self.checks):
                v = np.asarray(getattr(c, attr), dtype=float)
                out[i, :v.size] = v
            return out

        u = self.axis_units
        what = "frequency" if u == "Hz" else "order"
        fl = ("family", "line")
        ds = xr.Dataset(
            {"fundamental": ("family", np.asarray([c.family.fundamental for c in self.checks],
                                                   dtype=float),
                             {"units": u, "long_name": f"expected fundamental {what}"}),
             "status": ("family", self.status.astype(str),
                        {"units": "1", "long_name": "detected, possible, not detected or "
                         "outside"}),
             "detected": ("family", self.detected.astype(np.int8),
                          {"units": "1", "long_name": "1: reported detected"}),
             "harmonics_found": ("family", np.asarray([c.harmonics_found for c in self.checks]),
                                 {"units": "1", "long_name": "harmonics found"}),
             "explained_by": ("family", np.asarray(self.explained_by or ("",) * n,
                                                   dtype=object),
                              {"units": "1", "long_name": "families whose lines the "
                               "detection rests on"}),
             "chance": ("family", np.asarray(self.chance, dtype=float),
                        {"units": "1", "long_name": "chance that a family of this shape at a "
                         "random position is detected"}),
             "expected": (fl, grid("expected"), {"units": u, "long_name": f"expected {what}"}),
             "position": (fl, grid("position"), {"units": u, "long_name": f"{what} of the "
                                                 "largest line in the search window"}),
             "prominence": (fl, grid("prominence_db"),
                            {"units": "1", "long_name": "power over the local floor [dB]"}),
             "harmonic": (fl, grid("harmonic"), {"units": "1", "long_name": "harmonic"}),
             "sideband": (fl, grid("sideband"), {"units": "1", "long_name": "sideband index"})},
            coords={"family": ("family", np.asarray(self.names, dtype=object),
                               {"units": "1", "long_name": "line family"}),
                    "line": ("line", np.arange(k), {"units": "1", "long_name": "line index"})},
            attrs={"max_chance": float(self.max_chance), "prominent_lines": int(self.n_lines),
                   "spectrum": self.name,
                   "threshold_db": float(self.checks[0].threshold_db) if n else THRESHOLD_DB,
                   "tolerance": float(self.checks[0].tolerance) if n else TOLERANCE})
        return cf_dataset(ds, title=f"line families in the {self.name}",
                          producer="analysis.line_evidence.line_evidence")

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Spectrum (dB over its median) with every family's harmonics marked, the lines found
        filled (see :func:`analysis.envelope_plots.line_evidence_figure`)."""

        return line_evidence_figure(self, **kwargs)


def line_evidence(axis: Any, power: Any, families: LineFamily | Sequence[LineFamily], *,
                  known: Sequence[LineFamily | tuple[str, Any]] = (),
                  tolerance: float = TOLERANCE, threshold_db: float = THRESHOLD_DB,
                  min_harmonics: int = 2, max_chance: float = MAX_CHANCE,
                  local_width: float = 0.1, axis_units: str = "Hz",
                  name: str = "spectrum") -> LineEvidence:
    """Check every family in a spectrum and state each one's chance of a coincidence.

    Parameters
    ----------
    axis, power : array_like
        Uniform increasing axis (Hz or orders) and power-like values (amplitudes squared),
        e.g. ``es.frequency``, ``es.power()`` of an envelope spectrum up to its band width.
    families : LineFamily or sequence of LineFamily
        Families to check (:func:`analysis.lines.bearing_families`, ...).
    known : sequence of LineFamily or (str, array_like)
        Lines whose cause is known (e.g. the shaft harmonics ``LineFamily("shaft", f_r,
        harmonics=N)``, mesh orders), or ``(name, positions)`` (e.g. the
        :func:`explained_positions` of a family detected in another spectrum): a family
        whose detection rests on them is ``explained`` by them (a family is not explained by
        positions given under its own name). A LineFamily's harmonics (and sidebands) are
        taken at their nominal positions; known lines are not checked themselves.
    tolerance, threshold_db, min_harmonics
        As in :func:`analysis.lines.check_lines`.
    max_chance : float
        Largest chance for a detected family to be reported ``detected`` (0 < p <= 1).
    local_width : float
        Relative half-width of the band around each line for the chance.
    axis_units : str
        ``"Hz"`` or ``"1"``.
    name : str
        What the spectrum is.

    Returns
    -------
    LineEvidence
    """
    fams = [families] if isinstance(families, LineFamily) else list(families)
    if not fams or not all(isinstance(f, LineFamily) for f in fams):
        raise ValueError("families must be LineFamily objects (at least one)")
    mc = require_real(max_chance, "max_chance")
    if not 0.0 < mc <= 1.0:
        raise ValueError(f"max_chance = {max_chance!r} is not admissible: 0 < p <= 1")
    ax = require_finite(axis, "axis")
    pw = require_finite(power, "power")
    checks, chances = [], []
    n_lines = 0
    spacing = float(ax[1] - ax[0]) if ax.size > 1 else 1.0
    cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for fam in fams:
        c = check_lines(ax, pw, fam, tolerance=tolerance, threshold_db=threshold_db,
                        min_harmonics=min_harmonics, axis_units=axis_units)
        wing = _floor_wing(fam, c.tolerance, spacing)
        if wing not in cache:
            cache[wing] = prominent_lines(ax, pw, threshold_db=c.threshold_db,
                                          floor_lines=wing)
        pos, prom = cache[wing]
        n_lines = max(n_lines, int(pos.size))
        checks.append(c)
        chances.append(family_chance(ax, c, pos, prom, local_width=local_width))
    claims: list[tuple[str, np.ndarray]] = []
    for f in known:
        if isinstance(f, LineFamily):
            claims.append((f.name, np.sort(f.lines()[2])))
        elif isinstance(f, tuple) and len(f) == 2 and isinstance(f[0], str):
            claims.append((f[0], np.sort(require_finite(np.ravel(f[1]), f"known {f[0]!r}")
                                         if np.size(f[1]) else np.zeros(0))))
        else:
            raise ValueError("known must be LineFamily objects or (name, positions) pairs")
    top = float(ax[-1])
    by = [""] * len(checks)
    for i in sorted((i for i, c in enumerate(checks) if c.detected),
                    key=lambda i: -strength(checks[i])):
        c = checks[i]
        taken, names = _taken(c, claims, spacing)
        if not _detected_with(c, c.found & ~taken):
            by[i] = ", ".join(names)
        elif chances[i] <= mc:  # a family reported detected explains its lattice
            claims.append((c.family.name, explained_positions(c, top)))
    return LineEvidence(checks=tuple(checks), chance=np.asarray(chances, dtype=float),
                        max_chance=mc, axis=ax, power=pw, axis_units=axis_units,
                        n_lines=n_lines, name=name, explained_by=tuple(by))
