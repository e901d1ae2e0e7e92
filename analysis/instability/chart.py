"""Stability charts: Floquet multipliers over a mesh-frequency grid (and a second parameter).

A one-parameter chart (mesh frequency) gives the unstable intervals with refined boundaries;
a two-parameter chart is an Ince-Strutt diagram (e.g. mesh frequency against stiffness
variation or damping).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize

from analysis.checks import require_finite, require_monotonic, require_positive
from analysis.instability.floquet import floquet
from analysis.instability.theory import Candidates

__all__ = ["StabilityChart", "stability_chart"]

SystemAt = Callable[..., tuple[Any, Any, Any, float]]


@dataclass(frozen=True)
class StabilityChart:
    """Floquet stability over a grid of mesh frequencies (and optionally a parameter).

    Attributes
    ----------
    mesh_frequencies_hz : ndarray, shape (nf,)
        Mesh-frequency grid [Hz].
    parameter_values : ndarray or None, shape (np,)
        Second parameter grid, or None for a one-parameter chart.
    max_modulus : ndarray, shape (nf,) or (np, nf)
        ``max|mu|`` at each grid point.
    growth_rate : ndarray, same shape
        ``ln(max|mu|)/T`` [1/s].
    tol : float
        Stability tolerance (unstable iff ``max|mu| > 1 + tol``).
    mesh_frequency_per_rpm : float or None
        Mesh frequency per input speed [Hz/min-1].
    region_table : list of dict
        Unstable intervals (see :meth:`regions`).
    mesh_frequency_names : tuple of str
        Systems with several mesh frequencies (two-stage, Wolfrom): the name of each; the grid
        ``mesh_frequencies_hz`` is the first one (the reference). Empty for one frequency.
    mesh_frequency_ratios : tuple of float
        Each mesh frequency divided by the reference (kinematic ratios).
    method : str
        How the system with several mesh frequencies was made periodic (see the caller).
    """

    mesh_frequencies_hz: np.ndarray
    parameter_values: np.ndarray | None
    max_modulus: np.ndarray
    growth_rate: np.ndarray
    tol: float
    mesh_frequency_per_rpm: float | None = None
    region_table: list[dict] = field(default_factory=list)
    parameter_name: str = "parameter"
    parameter_units: str = "1"
    mesh_frequency_names: tuple[str, ...] = ()
    mesh_frequency_ratios: tuple[float, ...] = ()
    method: str = ""

    @property
    def unstable(self) -> np.ndarray:
        """Boolean mask ``max|mu| > 1 + tol``."""
        return self.max_modulus > 1.0 + self.tol

    def regions(self):
        """Table of unstable intervals as :class:`xarray.Dataset` (dimension ``region``).

        Variables: ``lower``, ``upper``, ``width``, ``centre`` [Hz] of the mesh frequency
        (boundaries refined by root finding unless the interval touches the grid end, flagged by
        ``lower_open``/``upper_open``), ``lower_speed``/``upper_speed`` [min-1] (NaN without a
        speed factor), ``peak_growth_rate`` [1/s], ``peak_max_modulus``, ``candidate`` (label of
        the nearest allowed theory candidate by centre, "" if none given; with several mesh
        frequencies the label names the one it belongs to, ``"2 f3/4 [stage 2]"``),
        ``candidate_f_mesh`` [Hz] (its centre on the grid's mesh frequency), and ``parameter``
        for two-parameter charts. With several mesh frequencies, ``group_lower`` and
        ``group_upper`` (dimensions ``region``, ``mesh_frequency_group``) give the boundaries
        in every mesh frequency [Hz].
        """
        import xarray as xr

        t = self.region_table
        factor = self.mesh_frequency_per_rpm

        def col(key, dtype=float):
            return np.asarray([r[key] for r in t], dtype=dtype)

        def v(x, units, long_name):
            return ("region", x, {"units": units, "long_name": long_name})

        lower, upper = col("lower"), col("upper")
        speed = (lambda x: x / factor) if factor else (lambda x: np.full_like(x, np.nan))
        data = {
            "lower": v(lower, "Hz", "lower boundary of unstable interval (mesh frequency)"),
            "upper": v(upper, "Hz", "upper boundary of unstable interval (mesh frequency)"),
            "width": v(upper - lower, "Hz", "width of unstable interval (mesh frequency)"),
            "centre": v(0.5 * (lower + upper), "Hz", "centre of unstable interval"),
            "lower_speed": v(speed(lower), "min-1", "lower boundary input speed"),
            "upper_speed": v(speed(upper), "min-1", "upper boundary input speed"),
            "lower_open": v(col("lower_open", np.int8), "1",
                            "1 if the interval reaches the lower grid end"),
            "upper_open": v(col("upper_open", np.int8), "1",
                            "1 if the interval reaches the upper grid end"),
            "peak_growth_rate": v(col("peak_growth_rate"), "s-1", "largest growth rate on grid"),
            "peak_max_modulus": v(col("peak_max_modulus"), "1", "largest max|mu| on grid"),
            "candidate": v(col("candidate", object).astype(str), "1",
                           "nearest theory candidate (by centre)"),
            "candidate_f_mesh": v(col("candidate_f_mesh"), "Hz", "centre of that candidate"),
        }
        if self.parameter_values is not None:
            data["parameter"] = v(col("parameter"), self.parameter_units, self.parameter_name)
        coords: dict[str, Any] = {"region": ("region", np.arange(len(t)),
                                             {"units": "1", "long_name": "region index"})}
        if len(self.mesh_frequency_names) > 1:
            ratios = np.asarray(self.mesh_frequency_ratios, dtype=float)
            dims = ("region", "mesh_frequency_group")
            data["group_lower"] = (dims, np.outer(lower, ratios).reshape(len(t), ratios.size),
                                   {"units": "Hz", "long_name": "lower boundary in each mesh "
                                                                "frequency"})
            data["group_upper"] = (dims, np.outer(upper, ratios).reshape(len(t), ratios.size),
                                   {"units": "Hz", "long_name": "upper boundary in each mesh "
                                                                "frequency"})
            coords["mesh_frequency_group"] = ("mesh_frequency_group",
                                              np.array(self.mesh_frequency_names, dtype=str),
                                              {"long_name": "mesh frequency (stage, toothing)"})
        return xr.Dataset(data, coords=coords, attrs={"method": self.method})

    def to_dataset(self):
        """Grid results as :class:`xarray.Dataset` (CF attributes on every variable)."""
        import xarray as xr

        coords: dict[str, Any] = {
            "f_mesh": ("f_mesh", self.mesh_frequencies_hz,
                       {"units": "Hz", "long_name": "mesh frequency"})}
        dims: tuple[str, ...] = ("f_mesh",)
        if self.parameter_values is not None:
            coords["parameter"] = ("parameter", self.parameter_values,
                                   {"units": self.parameter_units,
                                    "long_name": self.parameter_name})
            dims = ("parameter", "f_mesh")
        if self.mesh_frequency_per_rpm:
            coords["speed"] = ("f_mesh", self.mesh_frequencies_hz / self.mesh_frequency_per_rpm,
                               {"units": "min-1", "long_name": "input speed"})
        if len(self.mesh_frequency_names) > 1:
            ratios = np.asarray(self.mesh_frequency_ratios, dtype=float)
            coords["mesh_frequency_group"] = ("mesh_frequency_group",
                                              np.array(self.mesh_frequency_names, dtype=str),
                                              {"long_name": "mesh frequency (stage, toothing)"})
            coords["group_f_mesh"] = (("mesh_frequency_group", "f_mesh"),
                                      np.outer(ratios, self.mesh_frequencies_hz),
                                      {"units": "Hz", "long_name": "every mesh frequency on "
                                                                  "the grid"})
        return xr.Dataset(
            {
                "max_modulus": (dims, self.max_modulus,
                                {"units": "1", "long_name": "largest Floquet multiplier modulus"}),
                "growth_rate": (dims, self.growth_rate,
                                {"units": "s-1", "long_name": "growth rate ln(max|mu|)/T"}),
                "unstable": (dims, self.unstable.astype(np.int8),
                             {"units": "1", "long_name": "1 where max|mu| > 1 + tol"}),
            },
            coords=coords,
            attrs={"tol": self.tol, "method": self.method},
        )

    def plot(self, ax=None):
        """Growth rate over mesh frequency, or an Ince-Strutt chart for two parameters.

        Delegates to :func:`analysis.instability.plots.plot_chart`.
        """
        from analysis.instability.plots import plot_chart

        return plot_chart(self, ax=ax)


def _call(system_at: SystemAt, f: float, p: Any) -> tuple:
    out = system_at(f) if p is None else system_at(f, p)
    try:
        M, C, K, T = out
    except (TypeError, ValueError):
        raise ValueError("system_at must return a tuple (M, C, K, period)") from None
    return M, C, K, T


def stability_chart(
    system_at: SystemAt,
    mesh_frequencies_hz: Any,
    *,
    parameter_values: Sequence[float] | None = None,
    mesh_frequency_per_rpm: float | None = None,
    candidates: Candidates | None = None,
    refine: bool = True,
    tol: float = 1e-7,
    xtol_rel: float = 1e-11,
    parameter_name: str = "parameter",
    parameter_units: str = "1",
    floquet_options: dict | None = None,
    mesh_frequency_names: Sequence[str] = (),
    mesh_frequency_ratios: Sequence[float] = (),
    method: str = "",
) -> StabilityChart:
    """Evaluate Floquet stability over a mesh-frequency grid.

    Parameters
    ----------
    system_at : callable
        ``system_at(f_mesh)`` (or ``system_at(f_mesh, param)`` with ``parameter_values``)
        returning ``(M, C, K, period)`` as accepted by
        :func:`analysis.instability.floquet.floquet` (``K`` callable or ``PiecewiseConstant``).
    mesh_frequencies_hz : array_like, shape (nf,)
        Strictly increasing mesh-frequency grid [Hz].
    parameter_values : sequence of float, optional
        Second parameter (Ince-Strutt chart).
    mesh_frequency_per_rpm : float, optional
        Mesh frequency per input speed [Hz/min-1] (speeds in the region table).
    candidates : Candidates, optional
        Theory candidates; each region is attributed to the nearest allowed candidate centre.
    refine : bool
        Refine every interior boundary by root finding on ``max|mu| - 1 - tol``.
    tol : float
        Stability tolerance.
    xtol_rel : float
        Relative tolerance of the refined boundaries.
    parameter_name, parameter_units : str
        Metadata of the second parameter.
    floquet_options : dict, optional
        Extra keyword arguments for :func:`floquet` (``method``, ``n_steps``, ``rtol``).
    mesh_frequency_names, mesh_frequency_ratios : sequence
        For a system with several mesh frequencies: their names and their ratios to the grid's
        (reference) mesh frequency, first entry the reference (ratio 1). The region table then
        gives every region in every mesh frequency, and regions are attributed to candidates
        by speed (needs ``mesh_frequency_per_rpm``).
    method : str
        Description of how ``system_at`` makes the system periodic (stored).

    Returns
    -------
    StabilityChart

    Notes
    -----
    Unstable intervals narrower than the grid spacing can be missed: regions of order ``n``
    are ``O(eps^n)`` wide, so build the grid from first-order widths
    (:func:`analysis.instability.theory.first_order_widths`) rather than a fixed step. Boundary
    refinement uses Brent's method between the last stable and the first unstable grid point
    (the function has a square-root onset at undamped boundaries, which Brent's bracketing
    handles). The widths reported are in mesh frequency; an interval at ``f`` corresponds to
    input speed ``f / mesh_frequency_per_rpm``.
    """
    f = require_monotonic(mesh_frequencies_hz, "mesh_frequencies_hz")
    if f.ndim != 1 or f.size < 2:
        raise ValueError("mesh_frequencies_hz must be one-dimensional with at least 2 points")
    if np.any(f <= 0):
        raise ValueError("mesh_frequencies_hz must be > 0")
    params = None
    if parameter_values is not None:
        params = require_finite(parameter_values, "parameter_values")
        if params.ndim != 1:
            raise ValueError("parameter_values must be one-dimensional")
    factor = (require_positive(mesh_frequency_per_rpm, "mesh_frequency_per_rpm")
              if mesh_frequency_per_rpm is not None else None)
    require_positive(tol, "tol", allow_zero=True)
    opts = dict(floquet_options or {})
    opts["tol"] = tol
    names = tuple(str(x) for x in mesh_frequency_names)
    ratios = tuple(float(x) for x in mesh_frequency_ratios)
    if len(names) != len(ratios):
        raise ValueError(f"mesh_frequency_names has {len(names)} entries, "
                         f"mesh_frequency_ratios {len(ratios)}; give one ratio per name")
    if ratios and not (ratios[0] == 1.0 and all(r > 0 for r in ratios)):
        raise ValueError("mesh_frequency_ratios must be > 0 and start with 1 (the reference)")

    def evaluate(fm: float, p: Any) -> tuple[float, float]:
        M, C, K, T = _call(system_at, fm, p)
        r = floquet(M, C, K, T, **opts)
        return r.max_modulus, r.growth_rate

    rows = [None] if params is None else list(params)
    mm = np.empty((len(rows), f.size))
    gr = np.empty_like(mm)
    for a, p in enumerate(rows):
        for b, fm in enumerate(f):
            mm[a, b], gr[a, b] = evaluate(float(fm), p)

    table: list[dict] = []
    for a, p in enumerate(rows):
        uns = mm[a] > 1.0 + tol
        edges = np.flatnonzero(np.diff(uns.astype(np.int8)))
        starts = [0] if uns[0] else []
        starts += [int(e) + 1 for e in edges if not uns[e]]
        for s in starts:
            e = s
            while e + 1 < f.size and uns[e + 1]:
                e += 1

            def g(x: float, p=p) -> float:
                return evaluate(x, p)[0] - 1.0 - tol

            lower_open, upper_open = s == 0, e == f.size - 1
            if lower_open:
                lower = f[0]
            elif refine:
                lower = scipy.optimize.brentq(g, f[s - 1], f[s], xtol=xtol_rel * f[s])
            else:
                lower = 0.5 * (f[s - 1] + f[s])
            if upper_open:
                upper = f[-1]
            elif refine:
                upper = scipy.optimize.brentq(g, f[e], f[e + 1], xtol=xtol_rel * f[e + 1])
            else:
                upper = 0.5 * (f[e] + f[e + 1])
            k = s + int(np.argmax(gr[a, s:e + 1]))
            centre = 0.5 * (lower + upper)
            lab, cf = "", np.nan
            if candidates is not None:
                by_speed = factor is not None and bool(np.isfinite(candidates.rpm).any())
                idx = (candidates.nearest_speed(centre / factor) if by_speed
                       else candidates.nearest(centre))
                if idx is not None:
                    lab = candidates.full_label(idx)
                    cf = (float(candidates.rpm[idx]) * factor if by_speed
                          else float(candidates.f_mesh_hz[idx]))
            table.append({
                "lower": float(lower), "upper": float(upper), "lower_open": lower_open,
                "upper_open": upper_open, "peak_growth_rate": float(gr[a, k]),
                "peak_max_modulus": float(mm[a, k]), "candidate": lab, "candidate_f_mesh": cf,
                "parameter": np.nan if p is None else float(p),
            })
    squeeze = params is None
    return StabilityChart(
        mesh_frequencies_hz=f, parameter_values=params,
        max_modulus=mm[0] if squeeze else mm, growth_rate=gr[0] if squeeze else gr,
        tol=float(tol), mesh_frequency_per_rpm=factor, region_table=table,
        parameter_name=parameter_name, parameter_units=parameter_units,
        mesh_frequency_names=names, mesh_frequency_ratios=ratios, method=str(method),
    )
