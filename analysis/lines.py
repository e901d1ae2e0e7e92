"""Families of expected spectral lines (e.g. bearing fault frequencies with harmonics and
sidebands) and the check of each line at its own position in a spectrum.

A :class:`LineFamily` is a fundamental with harmonics ``h f`` (``h = 1..harmonics``) and,
around each harmonic, sidebands ``h f + s d`` (``s = -sidebands..sidebands``, ``s != 0``) at a
spacing ``d``: the bearing families of :func:`bearing_families` follow Randall & Antoni
(2011, sec. 2): an inner-race fault (BPFI) is amplitude-modulated at the shaft speed as the
fault turns through the load zone (sidebands at the shaft frequency), a rolling-element fault
(BSF, often strongest at ``2 BSF``: the element strikes both races) at the cage speed FTF
(sidebands at FTF), an outer-race fault (BPFO) on a stationary outer ring is not modulated.

:func:`check_lines` measures every line of a family where it is expected, not only among the
loudest peaks: its **prominence** is the largest power within ``+-tol`` of the expected
position over the **local floor**, the median power over ``+-6 tol`` around it without the
search window (at least 10 lines on each side; near DC or the end of the spectrum as many
lines, shifted into the spectrum), in dB. The fundamental is searched within
``p (1 +- tol)`` plus one line spacing (slip, speed uncertainty); once it is found at
``f_1``, the other lines are searched at exact multiples of it, ``h f_1 + s d`` within
``+-(h/2 + 1)`` line spacings (the fundamental's position is known to half a line; a real
family's harmonics follow its actual, slipped fundamental, while chance lines do not).
Without a found fundamental every line gets its own nominal window. A line counts as found
when its prominence reaches ``threshold_db``; a family is *detected* when its fundamental
and at least ``min_harmonics`` of its harmonics (fundamental included) are found. On noise
the median floor is the noise level, and the chance of a false line is that of the largest
of the few lines in the search window exceeding the median by ``threshold_db``; among many
real lines (the beats of steady tones in the demodulated band) it is the chance that one
falls into the window. Measured rates are in ``docs/condition-monitoring.md``.

References
----------
R. B. Randall, J. Antoni, "Rolling element bearing diagnostics - a tutorial", Mechanical
Systems and Signal Processing 25(2), 485-520, 2011.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from analysis.checks import (
    require_finite,
    require_instance,
    require_int,
    require_positive,
    require_real,
)

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "FLOOR_FACTOR",
    "THRESHOLD_DB",
    "TOLERANCE",
    "LineCheck",
    "LineFamily",
    "bearing_families",
    "check_lines",
]

#: Default relative search tolerance of a line (bearings slip 1-2 %; speeds are uncertain).
TOLERANCE = 0.01
#: Default prominence [dB] for a line to count as found.
THRESHOLD_DB = 6.0
#: The floor is taken over ``+-FLOOR_FACTOR`` search half-widths around the line.
FLOOR_FACTOR = 6.0
_MIN_FLOOR_LINES = 10


@dataclass(frozen=True)
class LineFamily:
    """A fundamental with its harmonics and their sidebands.

    Attributes
    ----------
    name : str
        Label, e.g. ``"BPFI"``.
    fundamental : float
        Position of the first harmonic, on the spectrum's axis (Hz, or orders).
    harmonics : int
        Harmonics ``1..harmonics`` (>= 1).
    sideband_spacing : float
        Sideband spacing on the same axis (0: none).
    sidebands : int
        Sidebands on each side of every harmonic (``s = +-1..+-sidebands``).
    """

    name: str
    fundamental: float
    harmonics: int = 3
    sideband_spacing: float = 0.0
    sidebands: int = 0

    def __post_init__(self) -> None:
        require_positive(require_real(self.fundamental, f"family {self.name!r}: fundamental"),
                         f"family {self.name!r}: fundamental")  # fmt: skip
        require_real(self.sideband_spacing, f"family {self.name!r}: sideband_spacing")
        require_int(self.harmonics, f"family {self.name!r}: harmonics", 1)
        require_int(self.sidebands, f"family {self.name!r}: sidebands", 0)
        require_positive(self.sideband_spacing, f"family {self.name!r}: sideband_spacing",
                         allow_zero=True)  # fmt: skip
        if self.sidebands and not self.sideband_spacing > 0:
            raise ValueError(
                f"family {self.name!r}: sidebands = {self.sidebands} need sideband_spacing > 0"
            )

    def lines(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(harmonic, sideband, position)`` of every line with a position > 0, harmonics
        first (sideband 0), in order."""
        h_list, s_list, p_list = [], [], []
        offsets = [0] + [s for k in range(1, self.sidebands + 1) for s in (-k, k)]
        for s in offsets:
            for h in range(1, self.harmonics + 1):
                p = h * self.fundamental + s * self.sideband_spacing
                if p > 0:
                    h_list.append(h)
                    s_list.append(s)
                    p_list.append(p)
        return np.array(h_list), np.array(s_list), np.array(p_list, dtype=float)


def bearing_families(
    shaft: float = 1.0,
    *,
    bpfo: float | None = None,
    bpfi: float | None = None,
    bsf: float | None = None,
    ftf: float | None = None,
    harmonics: int = 3,
    sidebands: int = 1,
) -> list[LineFamily]:
    """The line families of a rolling bearing's defect frequencies.

    Parameters
    ----------
    shaft : float, default 1.0
        Shaft frequency [Hz] (the rotation of the inner ring relative to the outer); 1.0
        gives the families in orders, for envelope order spectra.
    bpfo, bpfi, bsf, ftf : float, optional
        Defect frequencies as orders of the shaft (multiples of ``shaft``), e.g. from the
        bearing's catalogue or :class:`analysis.catalogue.RollingBearing`.
    harmonics : int, default 3
        Harmonics of each family.
    sidebands : int, default 1
        Sidebands of BPFI (at the shaft frequency) and BSF (at FTF, if given).

    Returns
    -------
    list of LineFamily
        In the order BPFO, BPFI, BSF, FTF (those given).
    """
    f = require_positive(shaft, "shaft")
    out = []
    if bpfo is not None:
        out.append(LineFamily("BPFO", require_positive(bpfo, "bpfo") * f, harmonics))
    if bpfi is not None:
        out.append(LineFamily("BPFI", require_positive(bpfi, "bpfi") * f, harmonics, f,
                              sidebands))  # fmt: skip
    if bsf is not None:
        cage = 0.0 if ftf is None else require_positive(ftf, "ftf") * f
        out.append(LineFamily("BSF", require_positive(bsf, "bsf") * f, harmonics, cage,
                              sidebands if cage > 0 else 0))  # fmt: skip
    if ftf is not None:
        out.append(LineFamily("FTF", require_positive(ftf, "ftf") * f, harmonics))
    if not out:
        raise ValueError("give at least one of bpfo, bpfi, bsf, ftf (orders of the shaft)")
    return out


@dataclass(frozen=True)
class LineCheck:
    """Every line of a family checked in a spectrum (see :func:`check_lines`).

    Attributes
    ----------
    family : LineFamily
        The family.
    harmonic, sideband : numpy.ndarray
        Indices of each line.
    expected : numpy.ndarray
        Expected positions (axis units).
    position : numpy.ndarray
        Position of the largest line within the search window.
    prominence_db : numpy.ndarray
        Its power over the local floor [dB]; NaN where the window leaves the spectrum.
    found : numpy.ndarray of bool
        ``prominence_db >= threshold_db``.
    threshold_db, tolerance : float
        Criterion used.
    min_harmonics : int
        Harmonics needed for :attr:`detected`.
    axis_units : str
        ``"Hz"`` or ``"1"`` (orders).
    anchored : bool
        The fundamental was found, and the other lines were searched at exact multiples of
        its position (``h f_1 + s d``, ``+-(h/2 + 1)`` line spacings).
    """

    family: LineFamily
    harmonic: np.ndarray
    sideband: np.ndarray
    expected: np.ndarray
    position: np.ndarray
    prominence_db: np.ndarray
    found: np.ndarray
    threshold_db: float
    tolerance: float
    min_harmonics: int
    axis_units: str = "Hz"
    anchored: bool = False

    @property
    def harmonics_found(self) -> int:
        """Harmonics (sideband 0) found."""
        return int(np.sum(self.found & (self.sideband == 0)))

    @property
    def detected(self) -> bool:
        """The fundamental found and at least :attr:`min_harmonics` harmonics in all."""
        first = bool(np.any(self.found & (self.sideband == 0) & (self.harmonic == 1)))
        return first and self.harmonics_found >= self.min_harmonics

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset with one entry per line (dimension ``line``)."""
        import xarray as xr

        u = self.axis_units
        what = "frequency" if u == "Hz" else "order"
        return xr.Dataset(
            {
                "expected": ("line", self.expected, {"units": u, "long_name": f"expected {what}"}),
                "position": ("line", self.position,
                             {"units": u, "long_name": f"{what} of the largest line in the "
                              "search window"}),
                "prominence": ("line", self.prominence_db,
                               {"units": "dB", "long_name": "power over the local floor"}),
                "found": ("line", self.found.astype(np.int8),
                          {"units": "1", "long_name": "prominence >= threshold (1: found)"}),
                "harmonic": ("line", self.harmonic, {"units": "1", "long_name": "harmonic"}),
                "sideband": ("line", self.sideband, {"units": "1", "long_name": "sideband index"}),
            },
            coords={"line": ("line", np.arange(self.expected.size),
                             {"units": "1", "long_name": "line index"})},
            attrs={
                "family": self.family.name,
                "fundamental": float(self.family.fundamental),
                "threshold_db": float(self.threshold_db),
                "tolerance": float(self.tolerance),
                "min_harmonics": int(self.min_harmonics),
                "harmonics_found": self.harmonics_found,
                "detected": int(self.detected),
                "anchored": int(self.anchored),
            },
        )  # fmt: skip


def check_lines(
    axis: np.ndarray,
    power: np.ndarray,
    family: LineFamily,
    *,
    tolerance: float = TOLERANCE,
    threshold_db: float = THRESHOLD_DB,
    min_harmonics: int = 2,
    axis_units: str = "Hz",
) -> LineCheck:
    """Check every line of ``family`` at its expected position in a spectrum.

    Parameters
    ----------
    axis : numpy.ndarray
        Uniform, increasing frequency (or order) axis of the spectrum.
    power : numpy.ndarray
        Power-like values on ``axis`` (amplitudes squared), same length.
    family : LineFamily
        Lines to check.
    tolerance : float, default 0.01
        Relative search half-width: the window is ``p (1 +- tolerance)`` widened by one line
        spacing (so that it always holds the nearest lines).
    threshold_db : float, default 6
        Prominence [dB] for a line to count as found.
    min_harmonics : int, default 2
        Harmonics found (the fundamental among them) for the family to count as detected.
    axis_units : str
        ``"Hz"`` or ``"1"`` (orders), for the result.

    Returns
    -------
    LineCheck
        Per line: position and prominence (NaN when the floor window leaves the spectrum).
    """
    require_instance(family, LineFamily, "family")
    ax = require_finite(axis, "axis")
    pw = require_finite(power, "power")
    if ax.ndim != 1 or pw.shape != ax.shape or ax.size < 2 * _MIN_FLOOR_LINES + 3:
        raise ValueError("axis and power must be 1-D of equal length (>= 23 lines)")
    tol = require_real(tolerance, "tolerance")
    if not 0.0 < tol < 0.5:
        raise ValueError(f"tolerance = {tolerance!r} is not admissible: must be in (0, 0.5)")
    thr = require_real(threshold_db, "threshold_db")
    require_int(min_harmonics, "min_harmonics", 1)
    spacing = float(ax[1] - ax[0])
    h, s, p = family.lines()
    position = np.full(p.size, np.nan)
    prom = np.full(p.size, np.nan)
    centres = p.copy()
    halves = tol * p + spacing
    hits = np.flatnonzero((h == 1) & (s == 0))
    first = int(hits[0]) if hits.size else -1
    anchor = None
    if first >= 0:
        position[first], prom[first] = _measure(ax, pw, p[first], halves[first], p[first],
                                                halves[first], spacing)  # fmt: skip
        if prom[first] >= thr:
            anchor = float(position[first])
    if anchor is not None:  # the other lines at exact multiples of the fundamental found
        centres = h * anchor + s * family.sideband_spacing
        halves = (0.5 * h + 1.0) * spacing
    for i in range(p.size):
        if i == first:
            continue
        position[i], prom[i] = _measure(ax, pw, centres[i], halves[i], p[i],
                                        tol * p[i] + spacing, spacing)  # fmt: skip
    found = np.nan_to_num(prom, nan=-np.inf) >= thr
    return LineCheck(
        family=family,
        harmonic=h,
        sideband=s,
        expected=p,
        position=position,
        prominence_db=prom,
        found=found,
        threshold_db=thr,
        tolerance=tol,
        min_harmonics=int(min_harmonics),
        axis_units=axis_units,
        anchored=anchor is not None,
    )


def _measure(
    ax: np.ndarray,
    pw: np.ndarray,
    centre: float,
    half: float,
    nominal: float,
    nominal_half: float,
    spacing: float,
) -> tuple[float, float]:
    """Position and prominence [dB] of the largest line within ``centre +- half``.

    The floor is the median of the lines within ``max(5 nominal_half, 10 lines)`` on either
    side of the search and the nominal window (shifted into the spectrum near DC or its end;
    DC excluded). NaN when the search window leaves the spectrum or the floor has fewer
    than ``2 * _MIN_FLOOR_LINES`` lines.
    """
    lo = int(np.searchsorted(ax, centre - half, side="left"))
    hi = int(np.searchsorted(ax, centre + half, side="right"))
    if centre - half < ax[1] or centre + half > ax[-1] or hi <= lo:
        return np.nan, np.nan
    # excluded: both windows; the floor: ``wing`` on either side of them
    n_lo = int(np.searchsorted(ax, nominal - nominal_half, side="left"))
    n_hi = int(np.searchsorted(ax, nominal + nominal_half, side="right"))
    ex_lo, ex_hi = min(lo, n_lo), max(hi, n_hi)
    wing = max(round((FLOOR_FACTOR - 1.0) * nominal_half / spacing), _MIN_FLOOR_LINES)
    f_lo, f_hi = ex_lo - wing, ex_hi + wing
    if f_lo < 1:  # near DC: as many lines, shifted up
        f_lo, f_hi = 1, min(ax.size, f_hi + 1 - f_lo)
    elif f_hi > ax.size:  # near the end: shifted down
        f_lo, f_hi = max(1, f_lo - (f_hi - ax.size)), ax.size
    floor_lines = np.concatenate((pw[f_lo:max(f_lo, ex_lo)], pw[min(f_hi, ex_hi):f_hi]))
    if floor_lines.size < 2 * _MIN_FLOOR_LINES:
        return np.nan, np.nan
    floor = float(np.median(floor_lines))
    k = lo + int(np.argmax(pw[lo:hi]))
    top = float(pw[k])
    if top <= 0:
        return float(ax[k]), 0.0
    if floor <= 0:
        return float(ax[k]), np.inf
    return float(ax[k]), 10.0 * math.log10(top / floor)
