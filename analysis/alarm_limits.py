"""Alarm limits of condition indicators, learned from healthy records.

A condition-monitoring system trends indicators over many records and raises an alarm when
one leaves the band it had while the machine was known to be healthy. Here the limit of each
indicator (and channel) is ``mean + k std`` of the healthy records (``std`` with ``ddof =
1``), and with ``sides="both"`` also ``mean - k std``. For Gaussian indicator values and
limits known exactly, ``k = 3`` gives a one-sided false-alarm probability of 0.13 % per
indicator and record; limits estimated from few healthy records, indicators that are not
Gaussian (FM4, NA4 are skewed) and the number of indicators watched raise it: the rate
measured on healthy records is stated in ``docs/condition-monitoring.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.cf import cf_dataset
from analysis.checks import require_choice, require_instance, require_real
from analysis.cm_plots import trend_figure

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = ["AlarmLimits", "learn_limits"]


@dataclass(frozen=True)
class AlarmLimits:
    """Alarm limits per indicator (and channel), learned from healthy records.

    Attributes
    ----------
    lower, upper : xarray.Dataset
        Limits, one variable per indicator (channel dimensions kept); ``lower`` is ``-inf``
        for one-sided limits.
    mean, std : xarray.Dataset
        Mean and standard deviation (ddof 1) of the healthy records.
    k : float
        Width of the band in standard deviations.
    sides : str
        ``"upper"`` or ``"both"``.
    healthy_records : int
        Number of healthy records learned from.
    """

    lower: xr.Dataset
    upper: xr.Dataset
    mean: xr.Dataset
    std: xr.Dataset
    k: float
    sides: str
    healthy_records: int

    @property
    def indicators(self) -> tuple[str, ...]:
        """Indicator names."""
        return tuple(str(v) for v in self.upper.data_vars)

    def exceeded(self, indicators: xr.Dataset) -> xr.Dataset:
        """Boolean Dataset: which indicator values lie outside the limits."""
        missing = [k for k in self.indicators if k not in indicators.data_vars]
        if missing:
            raise ValueError(f"indicators: variables {missing} are missing")
        sel = indicators[list(self.indicators)]
        return (sel > self.upper) | (sel < self.lower)

    def alarms(self, indicators: xr.Dataset) -> xr.DataArray:
        """Per record: whether any indicator of any channel is outside its limits."""
        ex = self.exceeded(indicators).to_array("indicator")
        other = [d for d in ex.dims if d != "record"]
        return ex.any(dim=other)

    def to_dataset(self) -> xr.Dataset:
        """Limits as one Dataset: ``<indicator>_upper``, ``<indicator>_lower``,
        ``<indicator>_mean``, ``<indicator>_std``."""
        import xarray as xr

        parts = []
        for what, ds in (("upper", self.upper), ("lower", self.lower), ("mean", self.mean),
                         ("std", self.std)):  # fmt: skip
            renamed = ds.rename({k: f"{k}_{what}" for k in ds.data_vars})
            for k in renamed.data_vars:
                renamed[k].attrs["long_name"] = f"{what} of {str(k)[: -len(what) - 1]}"
            parts.append(renamed)
        out = xr.merge(parts)
        out.attrs.update(k=float(self.k), sides=self.sides,
                         healthy_records=int(self.healthy_records),
                         method="mean +- k std (ddof 1) of the healthy records")  # fmt: skip
        return cf_dataset(
            out,
            title="alarm limits of condition indicators",
            producer="analysis.alarm_limits.learn_limits",
        )

    def plot(self, indicators: xr.Dataset, **kwargs: Any) -> matplotlib.figure.Figure:
        """Trend figure of ``indicators`` with these limits (see
        :func:`analysis.cm_plots.trend_figure`)."""
        return trend_figure(indicators, limits=self, **kwargs)


def learn_limits(
    indicators: xr.Dataset,
    healthy: Any = None,
    *,
    k: Any = 3.0,
    sides: str = "upper",
    variables: Any = None,
) -> AlarmLimits:
    """Alarm limits ``mean +- k std`` of each indicator over the healthy records.

    Parameters
    ----------
    indicators : xarray.Dataset
        From :func:`analysis.indicators.condition_indicators` (dimension ``record``).
    healthy : int, slice or array_like of bool or int, optional
        The healthy records: the first ``healthy`` records (int), a slice, a boolean mask or
        indices along ``record``; default all records.
    k : float, default 3
        Band width in standard deviations (> 0).
    sides : {"upper", "both"}, default "upper"
        One-sided (damage raises every indicator of :mod:`analysis.indicators`) or two-sided.
    variables : sequence of str, optional
        Indicators to watch (default: every data variable).

    Returns
    -------
    AlarmLimits

    Raises
    ------
    ValueError, TypeError
        Naming the parameter: fewer than 3 healthy records, ``k`` not a positive number,
        unknown variables or ``sides``.
    """
    import xarray

    require_instance(indicators, xarray.Dataset, "indicators")
    if "record" not in indicators.dims:
        raise ValueError("indicators needs a 'record' dimension (condition_indicators output)")
    kk = require_real(k, "k")
    if kk <= 0:
        raise ValueError(f"k = {k!r} is not admissible: must be > 0 (standard deviations)")
    side = require_choice(sides, ("upper", "both"), "sides")
    names = list(indicators.data_vars) if variables is None else list(variables)
    unknown = [v for v in names if v not in indicators.data_vars]
    if unknown:
        raise ValueError(f"variables: {unknown} are not in the indicators")
    n = indicators.sizes["record"]
    if healthy is None:
        sel = indicators[names]
    elif isinstance(healthy, bool):
        raise TypeError("healthy must be a count, a slice, a mask or indices; not a bool")
    elif isinstance(healthy, int | np.integer):
        if not 3 <= healthy <= n:
            raise ValueError(f"healthy = {healthy} is not admissible: 3 .. {n} records")
        sel = indicators[names].isel(record=slice(0, int(healthy)))
    else:
        sel = indicators[names].isel(record=healthy)
    m = sel.sizes["record"]
    if m < 3:
        raise ValueError(f"healthy: {m} record(s) selected; at least 3 are needed to learn limits")
    mean = sel.mean("record")
    std = sel.std("record", ddof=1)
    upper = mean + kk * std
    lower = mean - kk * std if side == "both" else mean * 0 - np.inf
    for ds in (mean, std, upper, lower):
        for v in ds.data_vars:
            ds[v].attrs = dict(indicators[v].attrs)
    return AlarmLimits(lower, upper, mean, std, kk, side, int(m))
