"""Gear condition indicators from time-synchronous averages, and their history.

Definitions (``x`` = TSA, ``d`` = difference, ``r`` = residual, ``e`` = envelope signal of
:func:`analysis.gear_signals.gear_signals`, ``N`` samples, bars = means over the revolution;
Lebold et al. 2000, who collect them with their preprocessing; Zakrajsek, Townsend & Decker
1993 for NA4/NB4; Stewart 1977 for FM0/FM4; Martin 1989 for M6A/M8A):

* ``rms`` = :math:`\\sqrt{\\overline{x^2}}`; ``peak`` = :math:`\\max |x|`;
  ``crest_factor`` = peak / rms; ``kurtosis`` = :math:`N \\sum (x - \\bar x)^4 /
  [\\sum (x - \\bar x)^2]^2` (3 for Gaussian samples, 1.5 for a sine).
* ``fm0`` = :math:`(\\max x - \\min x) / \\sum_h A_h`, ``A_h`` the peak amplitudes of the mesh
  harmonics (all mesh orders and harmonics of the gear signals).
* ``fm4`` = :math:`N \\sum (d - \\bar d)^4 / [\\sum (d - \\bar d)^2]^2` (3 for a Gaussian
  difference signal, larger with a local fault);
  ``m6a`` = :math:`N^2 \\sum (d - \\bar d)^6 / [\\sum (d - \\bar d)^2]^3` (15 Gaussian);
  ``m8a`` = :math:`N^3 \\sum (d - \\bar d)^8 / [\\sum (d - \\bar d)^2]^4` (105 Gaussian).
* ``na4`` of record ``M`` of a history = :math:`N \\sum_i (r_{iM} - \\bar r_M)^4 /
  \\{\\frac{1}{M} \\sum_{j=1}^{M} \\sum_i (r_{ij} - \\bar r_j)^2\\}^2`: the residual's fourth
  moment over the squared *run-to-date* mean variance of the residuals of records ``1 .. M``
  (:class:`RunToDate`); about 3 while the gear is healthy, it keeps rising as damage spreads
  because the variance is averaged over the history. ``nb4``: the same on the envelope ``e``.
  For a single record (``M = 1``) they equal the kurtosis of ``r`` and ``e``.
* ``energy_ratio`` = rms(d) / rms(regular).
* ``sideband_level_factor`` = :math:`(A_{z-1} + A_{z+1}) / \\sigma_x`: the first-order
  sidebands of the first mesh order over the standard deviation of the TSA.

:func:`condition_indicators` computes all of them for a sequence of records (or of time
windows of one record, :func:`analysis.tsa.tsa_windows`) in time order, carrying the NA4/NB4
history, as a CF Dataset with one variable per indicator along ``record``; alarm limits
learned from healthy records are in :mod:`analysis.alarm_limits`.

References
----------
M. Lebold et al., "Review of vibration analysis methods for gearbox diagnostics and
prognostics", Proc. 54th MFPT, 2000, 623-634. J. J. Zakrajsek, D. P. Townsend, H. J. Decker,
"An analysis of gear fault detection methods as applied to pitting fatigue failure data",
NASA TM-105950, 1993. R. M. Stewart, "Some useful data analysis techniques for gearbox
diagnostics", Univ. Southampton ISVR report MHM/R/10/77, 1977. H. R. Martin, "Statistical
moment analysis as a means of surface damage detection", Proc. 7th IMAC, 1989.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.cf import cf_dataset, time_attrs
from analysis.checks import require_instance, require_real_array
from analysis.gear_signals import GearSignals, gear_signals
from analysis.inputs import channel_coords
from analysis.tsa import TSA

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "INDICATORS",
    "RunToDate",
    "condition_indicators",
    "crest_factor",
    "energy_ratio",
    "fm0",
    "fm4",
    "gear_indicators",
    "kurtosis",
    "m6a",
    "m8a",
    "na4",
    "normalized_moment",
    "peak",
    "rms",
    "sideband_level_factor",
]

#: Indicator names, their long names and whether they carry the signal's units.
INDICATORS: dict[str, tuple[str, bool]] = {
    "rms": ("rms of the TSA", True),
    "peak": ("peak (largest absolute value) of the TSA", True),
    "crest_factor": ("crest factor of the TSA (peak / rms)", False),
    "kurtosis": ("kurtosis of the TSA", False),
    "fm0": ("FM0: peak-to-peak of the TSA / sum of the mesh harmonic amplitudes", False),
    "fm4": ("FM4: normalised 4th moment of the difference signal", False),
    "m6a": ("M6A: normalised 6th moment of the difference signal", False),
    "m8a": ("M8A: normalised 8th moment of the difference signal", False),
    "na4": ("NA4: residual 4th moment / squared run-to-date residual variance", False),
    "nb4": ("NB4: envelope 4th moment / squared run-to-date envelope variance", False),
    "energy_ratio": ("energy ratio: rms(difference) / rms(regular)", False),
    "sideband_level_factor": (
        "sideband level factor: first-order sidebands of the mesh order / std of the TSA",
        False,
    ),
}


def _values(x: Any, name: str) -> np.ndarray:
    arr = np.asarray(x)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be real numbers; got dtype {arr.dtype}")
    if arr.ndim == 0 or arr.shape[-1] < 2:
        raise ValueError(f"{name} needs at least 2 samples along its last axis")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} holds NaN or inf; only finite values are admissible")
    return arr.astype(float)


#: Rows whose largest magnitude lies in ``[2**-32, 2**32]`` are used as they are (the 16th
#: power of such samples, summed, stays within float64); others are scaled by a power of two.
_SAFE_EXPONENT = 32


def _pow2(v: np.ndarray, top: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(u, e)`` with ``v = u 2**e`` per row: ``e = 0`` (``u`` is ``v``, the plain formulas'
    bits) for a row whose ``max|v|`` lies in ``[2**-32, 2**32]``, else ``max|u|`` in
    [0.5, 1), so that powers of ``u`` neither overflow nor lose the row to underflow (a zero
    row stays zero). The scaling by a power of two is exact. ``top``: ``max|v|`` per row,
    if known."""
    if top is None:
        top = np.max(np.abs(v), axis=-1)
    _, e = np.frexp(np.where(top > 0.0, top, 1.0))
    e = np.where(np.abs(e) <= _SAFE_EXPONENT, 0, e)
    if not np.any(e):
        return v, e
    return np.ldexp(v, -e[..., None]), e


def _scaled(v: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_pow2`, refusing a row of zeros (its scale-free indicators are 0/0)."""
    top = np.max(np.abs(v), axis=-1)
    if np.any(top == 0.0):
        raise ValueError(f"{name} is zero throughout (a row of zeros): the indicator is "
                         "undefined")
    return _pow2(v, top)


def _finite(result: np.ndarray, what: str) -> np.ndarray:
    """``result``; raise if an element overflowed (or is undefined)."""
    if not np.all(np.isfinite(result)):
        raise ValueError(f"{what} is not representable in float64 (overflow or 0/0); check "
                         "the scaling of the inputs")
    return result


def _central(v: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Scaled central values ``c`` (``(v - mean) = c 2**e``) and their mean square; raise
    for a constant row (its normalised moments are 0/0)."""
    u, _ = _scaled(v, name)
    c = u - u.mean(axis=-1, keepdims=True)
    with np.errstate(under="ignore"):
        m2 = np.mean(c * c, axis=-1)
    if np.any(m2 == 0.0):
        raise ValueError(f"{name} is constant along its last axis (zero variance): the "
                         "normalised moment is undefined")
    return c, m2


def rms(x: Any) -> np.ndarray:
    """Root mean square along the last axis, :math:`\\sqrt{\\overline{x^2}}`."""
    u, e = _pow2(_values(x, "x"))
    with np.errstate(under="ignore"):
        return np.ldexp(np.sqrt(np.mean(u * u, axis=-1)), e)


def peak(x: Any) -> np.ndarray:
    """Largest absolute value along the last axis."""
    return np.max(np.abs(_values(x, "x")), axis=-1)


def crest_factor(x: Any) -> np.ndarray:
    """Peak / rms along the last axis."""
    u, _ = _scaled(_values(x, "x"), "x")
    with np.errstate(under="ignore"):
        return np.max(np.abs(u), axis=-1) / np.sqrt(np.mean(u * u, axis=-1))


#: Highest order of :func:`normalized_moment` (its powers stay within float64).
MAX_MOMENT_ORDER = 16


def normalized_moment(x: Any, order: int) -> np.ndarray:
    """:math:`N^{k/2 - 1} \\sum (x - \\bar x)^k / [\\sum (x - \\bar x)^2]^{k/2}` along the
    last axis (``k = order``, even, 2 .. :data:`MAX_MOMENT_ORDER`): the k-th central moment
    over the variance to the power ``k / 2``; for Gaussian samples ``(k - 1)!!`` (3, 15, 105
    for k = 4, 6, 8). Scale-free: computed on the samples scaled by a power of two (exact),
    so samples of any finite magnitude give a finite result; a constant row is refused."""
    if isinstance(order, bool) or not isinstance(order, int | np.integer) or not (
        2 <= order <= MAX_MOMENT_ORDER
    ) or (order % 2):
        raise ValueError(f"order = {order!r} is not admissible: an even integer in 2 .. "
                         f"{MAX_MOMENT_ORDER}")
    c, m2 = _central(_values(x, "x"), "x")
    with np.errstate(under="ignore"):
        return np.mean(c**order, axis=-1) / m2 ** (order // 2)


def kurtosis(x: Any) -> np.ndarray:
    """Kurtosis :math:`N \\sum (x - \\bar x)^4 / [\\sum (x - \\bar x)^2]^2` (3 Gaussian)."""
    return normalized_moment(x, 4)


def fm4(d: Any) -> np.ndarray:
    """FM4 of a difference signal ``d``: its kurtosis (Stewart 1977)."""
    return normalized_moment(d, 4)


def m6a(d: Any) -> np.ndarray:
    """M6A of a difference signal: normalised 6th moment (Martin 1989; 15 Gaussian)."""
    return normalized_moment(d, 6)


def m8a(d: Any) -> np.ndarray:
    """M8A of a difference signal: normalised 8th moment (Martin 1989; 105 Gaussian)."""
    return normalized_moment(d, 8)


def fm0(x: Any, mesh_amplitudes: Any) -> np.ndarray:
    """FM0 = peak-to-peak of the TSA ``x`` / sum of the mesh harmonic amplitudes.

    Parameters
    ----------
    x : array_like
        The TSA (last axis: one revolution).
    mesh_amplitudes : array_like
        Peak amplitudes of the mesh harmonics (finite, >= 0, not all zero), shape
        ``(*channels, harmonics)``.
    """
    v = _values(x, "x")
    a = require_real_array(mesh_amplitudes, "mesh_amplitudes")
    if a.ndim == 0 or np.any(a < 0):
        raise ValueError("mesh_amplitudes must be an array of amplitudes >= 0 (last axis: the "
                         "harmonics)")
    total = np.sum(a, axis=-1)
    if np.any(total == 0.0):
        raise ValueError("mesh_amplitudes are all zero: FM0 is undefined")
    with np.errstate(over="ignore", under="ignore"):
        return _finite((np.max(v, axis=-1) - np.min(v, axis=-1)) / total, "FM0")


def energy_ratio(d: Any, regular: Any) -> np.ndarray:
    """Energy ratio rms(d) / rms(regular) along the last axis."""
    den = rms(regular)
    if np.any(den == 0.0):
        raise ValueError("regular is zero throughout: the energy ratio is undefined")
    with np.errstate(over="ignore", under="ignore"):
        return _finite(rms(d) / den, "the energy ratio")


def sideband_level_factor(lower: Any, upper: Any, x: Any) -> np.ndarray:
    """(A_{z-1} + A_{z+1}) / std(x): first-order sideband amplitudes over the TSA's std."""
    v = _values(x, "x")
    return (np.asarray(lower, dtype=float) + np.asarray(upper, dtype=float)) / np.std(
        v, axis=-1
    )


#: Range of the run-to-date mean variance :func:`na4` accepts (its square stays finite).
MEAN_VARIANCE_RANGE = (1e-150, 1e150)


def na4(r: Any, mean_variance: Any) -> np.ndarray:
    """NA4 of a residual ``r`` given the run-to-date mean variance of the residuals.

    :math:`N \\sum (r - \\bar r)^4 / (N \\bar v)^2 = \\overline{(r - \\bar r)^4} / \\bar v^2`
    with :math:`\\bar v = \\frac{1}{M} \\sum_j \\frac{1}{N} \\sum_i (r_{ij} - \\bar r_j)^2`
    (records of ``N`` samples). :class:`RunToDate` keeps :math:`\\bar v`, which must lie in
    :data:`MEAN_VARIANCE_RANGE`.
    """
    v = _values(r, "r")
    mv = require_real_array(mean_variance, "mean_variance")
    lo, hi = MEAN_VARIANCE_RANGE
    if np.any(mv < lo) or np.any(mv > hi):
        raise ValueError(f"mean_variance must lie in [{lo:g}, {hi:g}] (a variance of the "
                         "residuals; 0 for constant records)")
    u, e = _pow2(v)
    c = u - u.mean(axis=-1, keepdims=True)
    with np.errstate(over="ignore", under="ignore"):
        m4 = np.ldexp(np.mean(c**4, axis=-1), 4 * e)
        return _finite(m4 / mv**2, "NA4")


class RunToDate:
    """Run-to-date mean variance of a sequence of records (the NA4 and NB4 normalisation).

    ``add(r)`` takes record ``M`` (channels along the leading axes, samples along the last)
    and returns its NA4 with the mean variance of records ``1 .. M``; use one instance per
    indicator and gear, and feed records in time order.

    Parameters
    ----------
    freeze_after : int, optional
        Stop updating the mean variance after this many records (a healthy baseline: the
        NA4* idea of Decker et al. 1994 without its extra scaling); default never.

    Attributes
    ----------
    records : int
        Records added so far.
    mean_variance : numpy.ndarray or None
        Current mean variance per channel.
    """

    def __init__(self, freeze_after: int | None = None) -> None:
        if freeze_after is not None and (
            isinstance(freeze_after, bool) or not isinstance(freeze_after, int | np.integer)
            or freeze_after < 1
        ):  # fmt: skip
            raise ValueError(f"freeze_after = {freeze_after!r} must be an integer >= 1")
        self.freeze_after = freeze_after
        self.records = 0
        self._sum: np.ndarray | None = None
        self._used = 0

    @property
    def mean_variance(self) -> np.ndarray | None:
        return None if self._sum is None else self._sum / self._used

    def add(self, r: Any) -> np.ndarray:
        """Add record ``r`` and return its NA4 (per channel)."""
        v = _values(r, "r")
        u, e = _pow2(v)
        with np.errstate(over="ignore", under="ignore"):
            var = _finite(np.ldexp(np.var(u, axis=-1), 2 * e), "the variance of r")
        if self._sum is not None and self._sum.shape != var.shape:
            raise ValueError(
                f"r has channels {var.shape}; the history has {self._sum.shape}: one history "
                "per gear and channel set"
            )
        if self.freeze_after is None or self._used < self.freeze_after:
            self._sum = var.copy() if self._sum is None else self._sum + var
            self._used += 1
        self.records += 1
        return na4(v, self.mean_variance)


def gear_indicators(
    signals: GearSignals,
    *,
    na4_history: RunToDate | None = None,
    nb4_history: RunToDate | None = None,
) -> dict[str, np.ndarray]:
    """All indicators of one record (module docstring), per channel.

    Parameters
    ----------
    signals : GearSignals
        From :func:`analysis.gear_signals.gear_signals`.
    na4_history, nb4_history : RunToDate, optional
        Histories of the residual and envelope variances; each record is added to them (time
        order). Without them NA4 and NB4 are those of a single record.

    Returns
    -------
    dict of str to numpy.ndarray
        One entry per name of :data:`INDICATORS`, shape ``(*channels,)``.
    """
    if not isinstance(signals, GearSignals):
        raise TypeError(f"signals must be GearSignals; got {type(signals).__name__}")
    for name, history in (("na4_history", na4_history), ("nb4_history", nb4_history)):
        if history is not None:
            require_instance(history, RunToDate, name)
    x, d, r = signals.tsa, signals.difference, signals.residual
    amp = signals.amplitudes
    z = signals.mesh_orders[0]
    nyq = amp.shape[-1] - 1
    out = {
        "rms": rms(x),
        "peak": peak(x),
        "crest_factor": crest_factor(x),
        "kurtosis": kurtosis(x),
        "fm0": fm0(x, amp[..., signals.mesh_lines]),
        "fm4": fm4(d),
        "m6a": m6a(d),
        "m8a": m8a(d),
        "na4": (na4_history if na4_history is not None else RunToDate()).add(r),
        "nb4": (nb4_history if nb4_history is not None else RunToDate()).add(
            signals.envelope
        ),
        "energy_ratio": energy_ratio(d, signals.regular),
        "sideband_level_factor": sideband_level_factor(
            amp[..., z - 1], amp[..., min(z + 1, nyq)], x
        ),
    }
    return {k: np.asarray(v, dtype=float) for k, v in out.items()}


def condition_indicators(
    records: Sequence[TSA | GearSignals],
    mesh_orders: Any = None,
    *,
    harmonics: Any = None,
    shaft_harmonics: Any = 3,
    sidebands: Any = 1,
    envelope_band: Any = None,
    labels: Sequence[Any] | None = None,
) -> xr.Dataset:
    """Condition indicators of a sequence of records (or time windows), in time order.

    Parameters
    ----------
    records : sequence of TSA or GearSignals
        The averages (e.g. one :func:`analysis.tsa.tsa` per measurement, or the windows of
        :func:`analysis.tsa.tsa_windows`), in time order; TSAs are turned into gear signals
        with the parameters below. All with the same channels.
    mesh_orders, harmonics, shaft_harmonics, sidebands, envelope_band :
        As for :func:`analysis.gear_signals.gear_signals` (``mesh_orders`` required for TSA
        records).
    labels : sequence, optional
        A label per record (e.g. file names or dates), stored as coordinate
        ``record_label``.

    Returns
    -------
    xarray.Dataset
        One variable per indicator (:data:`INDICATORS`) along ``record`` (and the channel
        dimensions), with ``units`` and ``long_name``; coordinate ``time`` = start of each
        record's average [s] when known (TSA records). NA4 and NB4 use the run-to-date
        variance of the records so far.
    """
    import xarray as xr

    recs = list(records)
    if not recs:
        raise ValueError("records: give at least one TSA or GearSignals")
    if labels is not None and len(labels) != len(recs):
        raise ValueError(f"labels: {len(labels)} given for {len(recs)} records")
    hist_r, hist_e = RunToDate(), RunToDate()
    rows: list[dict[str, np.ndarray]] = []
    times = []
    first: GearSignals | None = None
    for i, rec in enumerate(recs):
        if isinstance(rec, TSA):
            if mesh_orders is None:
                raise ValueError("mesh_orders is required for TSA records (teeth of the gear)")
            sig = gear_signals(
                rec, mesh_orders, harmonics=harmonics, shaft_harmonics=shaft_harmonics,
                sidebands=sidebands, envelope_band=envelope_band,
            )  # fmt: skip
            times.append(rec.start_time)
        elif isinstance(rec, GearSignals):
            sig = rec
            times.append(np.nan)
        else:
            raise TypeError(f"records[{i}] is a {type(rec).__name__}; TSA or GearSignals needed")
        if first is None:
            first = sig
        elif sig.tsa.shape[:-1] != first.tsa.shape[:-1]:
            raise ValueError(
                f"records[{i}] has channels {sig.tsa.shape[:-1]}, records[0] has "
                f"{first.tsa.shape[:-1]}"
            )
        rows.append(gear_indicators(sig, na4_history=hist_r, nb4_history=hist_e))
    assert first is not None
    dims = ("record", *first.dims)
    data = {}
    for key, (long, with_units) in INDICATORS.items():
        data[key] = (
            dims,
            np.stack([row[key] for row in rows]),
            {"units": first.units if with_units else "1", "long_name": long},
        )
    coords: dict[str, Any] = {
        "record": ("record", np.arange(len(recs)), {"units": "1", "long_name": "record number"}),
        "time": ("record", np.asarray(times, dtype=float),
                 time_attrs("start of the record's average (seconds since the start of its "
                            "record)")),
    }  # fmt: skip
    if labels is not None:
        coords["record_label"] = ("record", np.asarray([str(v) for v in labels]),
                                  {"long_name": "record label"})  # fmt: skip
    coords.update(channel_coords(first.dims, first.coords))
    attrs = {
        "Conventions": "CF-1.11",
        "mesh_orders": np.asarray(first.mesh_orders, dtype=np.int64),
        "mesh_harmonics": int(first.harmonics),
        "shaft_harmonics": int(first.shaft_harmonics),
        "sidebands": int(first.sidebands),
        "envelope_band": np.asarray(first.envelope_band, dtype=np.int64),
        "shaft": first.shaft,
        "comment": "NA4/NB4 normalised by the run-to-date mean variance of records 0 .. k",
    }
    return cf_dataset(
        xr.Dataset(data, coords=coords, attrs=attrs),
        title="gear condition indicators",
        producer="analysis.indicators.condition_indicators",
    )
