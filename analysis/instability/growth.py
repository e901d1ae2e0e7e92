"""Can an instability region grow during a run-up? Time in band × Floquet growth rate.

A parametric instability region is a speed band in which the Floquet growth rate ``sigma`` is
positive: a disturbance grows like ``exp(sigma t)`` while the run stays in the band. A run-up
crosses the band in a time ``tau``, so the disturbance grows at most by

    G = exp(integral of sigma(rpm(t)) dt over the band)      (20 log10 G dB),

which is small when the band is narrow or the run fast (the paper's 1 s run-up crosses a
40 min-1 band in 10 ms). :func:`runup_growth` evaluates this for every unstable region of a
stability chart along a given speed history and says what run would show the region: a slower
run-up or a stepped-speed run that dwells inside the band.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.cf import cf_dataset
from analysis.checks import require_finite, require_instance, require_positive

__all__ = ["GrowthTable", "UnstableBand", "runup_growth", "unstable_bands"]


@dataclass(frozen=True)
class UnstableBand:
    """An unstable speed band with its growth-rate profile.

    Attributes
    ----------
    label : str
        Theory candidate (e.g. ``"2 (f3=f4)/3"``) or ``""``.
    lower_rpm, upper_rpm : float
        Band limits [min-1].
    speeds_rpm, growth_rate : ndarray
        Growth rate [1/s] over speed inside the band (at least the peak value).
    """

    label: str
    lower_rpm: float
    upper_rpm: float
    speeds_rpm: np.ndarray
    growth_rate: np.ndarray

    @property
    def peak_growth_rate(self) -> float:
        """Largest growth rate in the band [1/s]."""
        return float(np.max(self.growth_rate)) if self.growth_rate.size else 0.0

    def rate_at(self, rpm: np.ndarray) -> np.ndarray:
        """Growth rate [1/s] at speeds (0 outside the band; parabolic if only the peak is
        known)."""
        r = np.asarray(rpm, dtype=float)
        inside = (r >= self.lower_rpm) & (r <= self.upper_rpm)
        out = np.zeros_like(r)
        if self.speeds_rpm.size >= 3:
            out[inside] = np.interp(r[inside], self.speeds_rpm, self.growth_rate)
        else:
            mid = 0.5 * (self.lower_rpm + self.upper_rpm)
            half = max(0.5 * (self.upper_rpm - self.lower_rpm), 1e-300)
            out[inside] = self.peak_growth_rate * (1.0 - ((r[inside] - mid) / half) ** 2)
        return np.maximum(out, 0.0)


def unstable_bands(chart: Any) -> list[UnstableBand]:
    """The unstable bands of a :class:`~analysis.instability.StabilityChart` over speed.

    The growth-rate profile inside each band is the chart's grid values plus zeros at the
    refined boundaries.
    """
    factor = getattr(chart, "mesh_frequency_per_rpm", None)
    if not factor:
        raise ValueError("the stability chart has no mesh_frequency_per_rpm: cannot convert its "
                         "regions to speed")
    if getattr(chart, "parameter_values", None) is not None:
        raise ValueError("a two-parameter chart has no single speed profile; use a chart over "
                         "speed")
    f = np.asarray(chart.mesh_frequencies_hz, dtype=float)
    g = np.asarray(chart.growth_rate, dtype=float)
    out = []
    for reg in chart.region_table:
        lo, hi = float(reg["lower"]), float(reg["upper"])
        inside = (f > lo) & (f < hi)
        if inside.any():
            fr = np.concatenate([[lo], f[inside], [hi]])
            gr = np.concatenate([[0.0], np.maximum(g[inside], 0.0), [0.0]])
        else:  # narrower than the grid: only the peak is known (parabolic profile)
            fr = np.zeros(0)
            gr = np.asarray([max(float(reg.get("peak_growth_rate", 0.0)), 0.0)])
        out.append(UnstableBand(str(reg.get("candidate", "")), lo / factor, hi / factor,
                                fr / factor, gr))
    return out


@dataclass(frozen=True)
class GrowthTable:
    """Growth of every unstable band along one run-up (one row per band).

    Attributes
    ----------
    label : ndarray of str
        Theory candidate of the band.
    lower_rpm, upper_rpm : ndarray
        Band limits [min-1].
    time_in_band : ndarray
        Time the run spends inside the band [s].
    peak_growth_rate : ndarray
        Largest Floquet growth rate in the band [1/s].
    exponent : ndarray
        ``integral sigma dt`` along the run (natural log of the amplitude growth).
    growth_db : ndarray
        ``20 log10(e) * exponent`` [dB].
    can_grow : ndarray of bool
        ``growth_db >= threshold_db``.
    needed_time : ndarray
        Time inside the band for ``threshold_db`` of growth at the band's mean growth rate [s].
    advice : ndarray of str
        What shows the band when the run is too fast.
    threshold_db : float
        Growth needed to call a band visible [dB].
    """

    label: np.ndarray
    lower_rpm: np.ndarray
    upper_rpm: np.ndarray
    time_in_band: np.ndarray
    peak_growth_rate: np.ndarray
    exponent: np.ndarray
    growth_db: np.ndarray
    can_grow: np.ndarray
    needed_time: np.ndarray
    advice: np.ndarray
    threshold_db: float

    def __len__(self) -> int:
        return int(self.label.size)

    def row_at(self, rpm: float) -> int | None:
        """Index of the band containing ``rpm`` (None if none)."""
        hit = np.flatnonzero((self.lower_rpm <= rpm) & (rpm <= self.upper_rpm))
        return int(hit[0]) if hit.size else None

    def __str__(self) -> str:
        rows = [f"{'band [min-1]':>17} {'candidate':>16} {'tau [ms]':>9} {'sigma [1/s]':>11} "
                f"{'growth [dB]':>11}  verdict"]
        for i in range(len(self)):
            verdict = "can grow" if self.can_grow[i] else "too fast: " + str(self.advice[i])
            rows.append(f"{self.lower_rpm[i]:8.0f}–{self.upper_rpm[i]:<8.0f} "
                        f"{self.label[i]:>16} {1e3 * self.time_in_band[i]:9.2f} "
                        f"{self.peak_growth_rate[i]:11.3g} {self.growth_db[i]:11.1f}  {verdict}")
        return "\n".join(rows)

    def to_dataset(self):
        """Table as :class:`xarray.Dataset` (dimension ``band``)."""
        import xarray as xr

        def v(x, units, long_name):
            return ("band", x, {"units": units, "long_name": long_name})

        ds = xr.Dataset(
            {
                "candidate": v(self.label.astype(str), "1", "theory candidate of the band"),
                "lower_speed": v(self.lower_rpm, "min-1", "lower band limit"),
                "upper_speed": v(self.upper_rpm, "min-1", "upper band limit"),
                "time_in_band": v(self.time_in_band, "s", "time the run spends in the band"),
                "peak_growth_rate": v(self.peak_growth_rate, "s-1", "largest growth rate"),
                "exponent": v(self.exponent, "1", "integral of the growth rate over time"),
                "growth": v(self.growth_db, "dB", "amplitude growth while crossing the band"),
                "can_grow": v(self.can_grow.astype(np.int8), "1",
                              f"1 if the growth reaches {self.threshold_db:g} dB"),
                "needed_time": v(self.needed_time, "s",
                                 f"time in band for {self.threshold_db:g} dB of growth"),
                "advice": v(self.advice.astype(str), "1", "what run shows the band"),
            },
            coords={"band": ("band", np.arange(len(self)),
                             {"units": "1", "long_name": "band index"})},
            attrs={"threshold_db": self.threshold_db},
        )
        return cf_dataset(
            ds, title="growth of unstable bands along the run-up",
            producer="analysis.instability.runup_growth"
        )


def runup_growth(bands: Any, time: Any, rpm: Any, *, threshold_db: float = 6.0,
                 margin: float = 3.0) -> GrowthTable:
    """Growth of each unstable band along a run-up's speed history.

    Parameters
    ----------
    bands : StabilityChart or sequence of UnstableBand
        Floquet chart over speed (its regions), or bands.
    time : array_like
        Time [s] of the speed history (increasing).
    rpm : array_like
        Speed [min-1] at ``time`` (the chart's speed, usually the input).
    threshold_db : float
        Growth needed for a band to show [dB].
    margin : float
        Safety factor on the needed time in the advice.

    Returns
    -------
    GrowthTable

    Notes
    -----
    The exponent is ``integral sigma(rpm(t)) dt`` evaluated on the speed history refined to at
    least 50 samples per band crossing (linear interpolation of the speed). The advice gives
    the longest run-up duration over the same speed range that still reaches ``threshold_db``
    times ``margin`` in the band (at the same relative ramp), and the dwell time of a
    stepped-speed run at the band centre.
    """
    if hasattr(bands, "region_table"):
        bands = unstable_bands(bands)
    if isinstance(bands, UnstableBand) or not isinstance(bands, list | tuple):
        raise TypeError(f"bands must be a StabilityChart or a sequence of UnstableBand; got "
                        f"{type(bands).__name__}")
    bands = list(bands)
    for k, b in enumerate(bands):
        require_instance(b, UnstableBand, f"bands[{k}]")
    t = require_finite(time, "time").ravel()
    r = np.abs(require_finite(rpm, "rpm").ravel())
    if t.size != r.size or t.size < 2:
        raise ValueError(f"time and rpm need the same length (>= 2); got {t.size} and {r.size}")
    if np.any(np.diff(t) <= 0):
        raise ValueError("time must be strictly increasing")
    thr = require_positive(threshold_db, "threshold_db")
    marg = require_positive(margin, "margin")
    duration = float(t[-1] - t[0])
    rows = []
    for b in bands:
        width = max(b.upper_rpm - b.lower_rpm, 1e-12)
        # refine the history so that every band crossing has >= 50 samples
        slope = np.abs(np.diff(r)) / np.diff(t)
        dt_need = width / 50.0 / max(float(slope.max()), 1e-300)
        n = int(min(max(t.size, np.ceil(duration / max(dt_need, 1e-9))), 5_000_000))
        tt = np.linspace(t[0], t[-1], n) if n > t.size else t
        rr = np.interp(tt, t, r)
        inside = (rr >= b.lower_rpm) & (rr <= b.upper_rpm)
        dt = np.gradient(tt)
        tau = float(dt[inside].sum())
        expo = float((b.rate_at(rr) * dt).sum())
        gdb = 20.0 * np.log10(math.e) * expo
        mean_rate = expo / tau if tau > 0 else (2.0 / 3.0) * b.peak_growth_rate
        need = thr / (20.0 * np.log10(math.e) * mean_rate) if mean_rate > 0 else np.inf
        if gdb >= thr:
            advice = "grows in this run"
        elif not np.isfinite(need):
            advice = "no growth (zero growth rate)"
        elif tau > 0:
            slower = duration * marg * need / tau
            advice = (f"run-up of >= {slower:.3g} s over the same range, or dwell >= "
                      f"{marg * need:.3g} s at {0.5 * (b.lower_rpm + b.upper_rpm):.0f} min-1")
        else:
            advice = (f"the run does not reach this band; dwell >= {marg * need:.3g} s at "
                      f"{0.5 * (b.lower_rpm + b.upper_rpm):.0f} min-1")
        rows.append((b.label, b.lower_rpm, b.upper_rpm, tau, b.peak_growth_rate, expo, gdb,
                     gdb >= thr, need, advice))
    cols: list[Sequence[Any]] = list(zip(*rows, strict=True)) if rows else [[]] * 10
    return GrowthTable(
        label=np.asarray(cols[0], dtype=object), lower_rpm=np.asarray(cols[1], float),
        upper_rpm=np.asarray(cols[2], float), time_in_band=np.asarray(cols[3], float),
        peak_growth_rate=np.asarray(cols[4], float), exponent=np.asarray(cols[5], float),
        growth_db=np.asarray(cols[6], float), can_grow=np.asarray(cols[7], bool),
        needed_time=np.asarray(cols[8], float), advice=np.asarray(cols[9], dtype=object),
        threshold_db=thr)
