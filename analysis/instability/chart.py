"""Stability charts: Floquet multipliers over a mesh-frequency grid (and a second parameter).

A one-parameter chart (mesh frequency) gives the unstable intervals with refined boundaries;
a two-parameter chart is an Ince-Strutt diagram (e.g. mesh frequency against stiffness
variation or damping).

Every unstable interval is attributed to the theory candidate whose frequency relation holds
there (:func:`attribute_region`): its centre ``2 f_i/n`` or ``(f_i + f_j)/n`` must lie inside
the interval widened by a small relative tolerance, and -- when the mode shapes are given --
its modes must carry the growing Floquet solution. An interval no candidate explains stays
*unattributed* (label ``""``); the nearest candidate is never taken as such.

Grid points and boundary refinements are independent Floquet evaluations. They run on any
:class:`concurrent.futures.Executor` (``executor=``: a process pool, a Dask cluster; gearvib
passes the executors its sweeps use) or, with ``workers > 1`` and no executor, on a forked
process pool of the call (the system callable is then not pickled), in chunks of
:func:`chart_chunk`, when the first evaluation shows that the chart takes long enough to pay
for it. The results do not depend on the executor or the number of workers.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize

from analysis.cf import cf_dataset
from analysis.checks import (
    require_finite,
    require_instance,
    require_monotonic,
    require_positive,
    require_real,
    shown,
)
from analysis.instability.floquet import floquet
from analysis.instability.theory import Candidates
from analysis.threads import one_blas_thread

__all__ = ["ATTRIBUTION_RTOL", "StabilityChart", "attribute_region", "chart_chunk",
           "stability_chart", "terminate_pool"]

SystemAt = Callable[..., tuple[Any, Any, Any, float]]

ATTRIBUTION_RTOL = 0.01
"""Relative tolerance by which a candidate centre may lie outside an unstable interval: the
centres ``2 f_i/n``, ``(f_i + f_j)/n`` come from the mean-stiffness modes, and the regions of a
strongly varying stiffness sit up to about 0.6 % away from them (the paper's case 2: the sum
region (f2 + f3)/2 at 3550-3565 min-1, its centre at 3586 min-1)."""

MODE_SHARE_MIN = 0.3
"""Smallest share of the growing Floquet solution's modal energy that a candidate's modes
must carry together to explain an interval (when mode shapes are given)."""

CLUSTER_SHARE_MIN = 0.03
"""... and each of its two modes (clusters of repeated modes) of a sum-type candidate."""

SHARE_TIE = 0.05
"""Candidates whose modes carry within this share of the best one are ranked by order n."""

_PARALLEL_MIN_S = 3.0  # a chart expected to take less runs in this process


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
    candidates : Candidates or None
        The theory candidates the intervals were attributed to (each region's
        ``candidate_index`` is a row of this table, -1 when unattributed).
    notes : tuple of str
        Remarks (e.g. evaluations whose error estimate exceeds the requested accuracy).
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
    candidates: Candidates | None = None
    notes: tuple[str, ...] = ()

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
        the theory candidate whose relation holds in the interval, see
        :func:`attribute_region`; "" when none does or none were given; with several mesh
        frequencies the label names the one it belongs to, ``"2 f3/4 [stage 2]"``),
        ``candidate_f_mesh`` [Hz] (its centre on the grid's mesh frequency), ``evidence``
        (why, or the modes that carry the growing solution) and ``parameter`` for
        two-parameter charts. With several mesh frequencies, ``group_lower`` and
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
                           "theory candidate whose relation holds in the interval"),
            "candidate_f_mesh": v(col("candidate_f_mesh"), "Hz", "centre of that candidate"),
            "evidence": v(np.asarray([r.get("evidence", "") for r in t], dtype=object)
                          .astype(str), "1", "why the candidate holds (or none does)"),
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
        ds = xr.Dataset(
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
        return cf_dataset(
            ds, title="parametric stability chart",
            producer="analysis.instability.stability_chart"
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


# ------------------------------------------------------------------------- parallel map

_INSTALLED: SystemAt | None = None  # the system of this chart's own forked pool (initializer)


def _install(system_at: SystemAt) -> None:
    """Initializer of the chart's own pool: the system arrives by fork (never pickled), and
    Ctrl-C is the parent's to handle (it cancels the pool)."""
    global _INSTALLED
    _INSTALLED = system_at
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def default_workers() -> int:
    """Cores this process may use (``os.sched_getaffinity``, else ``os.cpu_count``)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def terminate_pool(pool: Executor) -> None:
    """Cancel the queued work of a process pool and end its worker processes now.

    ``ProcessPoolExecutor.shutdown`` waits for the calls that are running (a chunk of a chart
    may take seconds), and a parent that exits meanwhile leaves its workers blocked for ever.
    Python 3.14's ``terminate_workers`` is used where it exists; before, the pool's worker
    processes (its ``_processes`` table, stable since Python 3.3) are terminated.
    """
    require_instance(pool, Executor, "pool")
    stop = getattr(pool, "terminate_workers", None)
    if callable(stop):
        stop()
        return
    procs = list((getattr(pool, "_processes", None) or {}).values())  # shutdown clears it
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        if proc.is_alive():
            proc.terminate()
    for proc in procs:
        proc.join(timeout=1.0)
    for proc in procs:  # a worker that did not end on SIGTERM within a second (a loaded host)
        if proc.is_alive():
            proc.kill()
            proc.join(timeout=2.0)


def _one_thread() -> Any:
    """One BLAS/OpenMP thread (:func:`analysis.threads.one_blas_thread`) while a chunk is
    evaluated, wherever it runs: no oversubscription by workers, and the same arithmetic in
    this process and in any worker."""
    return one_blas_thread()


def _evaluate_point(system_at: SystemAt, f: float, p: Any, opts: dict) -> tuple:
    M, C, K, T = _call(system_at, f, p)
    r = floquet(M, C, K, T, **opts)
    return r.max_modulus, r.growth_rate, r.error_estimate


def _boundary(system_at: SystemAt, lo_f: float, hi_f: float, p: Any, opts: dict,
              xtol_rel: float) -> float:
    tol = float(opts["tol"])
    return float(scipy.optimize.brentq(
        lambda x: _evaluate_point(system_at, x, p, opts)[0] - 1.0 - tol, lo_f, hi_f,
        xtol=xtol_rel * hi_f))


def chart_chunk(system_at: SystemAt | None, kind: str, items: Sequence[tuple], opts: dict,
                xtol_rel: float) -> list:
    """Evaluate a chunk of a chart (the task every executor runs; importable by workers).

    ``kind = "grid"``: ``items`` are ``(f_mesh, parameter)``, the result per item is
    ``(max|mu|, growth rate, error estimate)``; ``kind = "boundary"``: ``items`` are
    ``(f_low, f_high, parameter)`` brackets, the result the refined boundary [Hz].
    ``system_at = None`` takes the system the chart's own pool installed in this worker.
    """
    sa = _INSTALLED if system_at is None else system_at
    if sa is None:
        raise RuntimeError("chart_chunk: no system given and none installed in this process")
    with _one_thread():  # entering the limit costs ~10 ms: once per chunk
        return _evaluate_items(sa, kind, items, opts, xtol_rel)


def _evaluate_items(system_at: SystemAt, kind: str, items: Sequence[tuple], opts: dict,
                    xtol_rel: float) -> list:
    if kind == "grid":
        return [_evaluate_point(system_at, float(f), p, opts) for f, p in items]
    return [_boundary(system_at, float(lo), float(hi), p, opts, xtol_rel)
            for lo, hi, p in items]


def _chunks(n: int, parts: int) -> list[range]:
    size = max(1, -(-n // max(1, parts)))
    return [range(i, min(n, i + size)) for i in range(0, n, size)]


def _map_chart(kind: str, items: Sequence[tuple], *, system_at: SystemAt, opts: dict,
               xtol_rel: float, executor: Executor | None, own_pool: bool, workers: int,
               bar: Any) -> list:
    """Results of :func:`chart_chunk` over ``items`` in their order.

    ``executor`` None: in this process, one item per chunk (the progress bar moves with each).
    Otherwise the items are cut into about four chunks per worker and submitted; the system
    travels with each chunk (pickled), except to the chart's own forked pool
    (``own_pool``), whose workers hold it already. The result of an item does not depend on
    the chunk it is in, so the chart is the same for any executor and worker count.
    """
    if not items:
        return []
    if executor is None:
        out = []
        with _one_thread():
            for it in items:
                out.extend(_evaluate_items(system_at, kind, [it], opts, xtol_rel))
                bar.update(1)
        return out
    sent = None if own_pool else system_at
    futures: dict[Future, range] = {}
    try:
        for r in _chunks(len(items), 4 * workers):
            fut = executor.submit(chart_chunk, sent, kind, [items[i] for i in r], opts,
                                  xtol_rel)
            futures[fut] = r
        results: list[Any] = [None] * len(items)
        for fut in as_completed(futures):
            r = futures[fut]
            for i, v in zip(r, fut.result(), strict=True):
                results[i] = v
            bar.update(len(r))
        return results
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise


class _NoBar:
    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass

    def set_description(self, text: str) -> None:
        pass


def _progress_bar(progress: bool | None, total: int, desc: str) -> Any:
    if progress is False:
        return _NoBar()
    try:
        from tqdm.auto import tqdm
    except ImportError:  # pragma: no cover - tqdm is a required dependency
        return _NoBar()
    return tqdm(total=total, desc=desc, unit="speed", leave=False,
                disable=None if progress is None else not progress)


# ------------------------------------------------------------------------- attribution


def _by_speed(candidates: Candidates, factor: float | None) -> bool:
    """Compare candidates by speed (``rpm x factor``): needed when they belong to named mesh
    frequencies (their ``f_mesh_hz`` are then in different units), used whenever possible."""
    named = candidates.mesh_frequency is not None and any(
        str(x) for x in candidates.mesh_frequency)
    usable = bool(factor) and bool(np.all(np.isfinite(candidates.rpm)))
    if named and not usable:
        raise ValueError("candidates of named mesh frequencies need factor (reference mesh "
                         "frequency per speed) and speeds to be compared with the interval")
    return usable


def _mode_shares(result: Any, mass: np.ndarray, shapes: np.ndarray,
                 freqs_hz: np.ndarray) -> np.ndarray:
    """Share of each mode in the energy of the growing Floquet solution at ``t = 0``.

    ``x = [q; q']`` is the eigenvector of the largest multiplier; with mass-normalised shapes
    ``phi_i`` the modal coordinates are ``eta_i = phi_i^T M q`` and the energy of mode ``i`` is
    ``|eta_i'|^2 + omega_i^2 |eta_i|^2``.
    """
    w, v = np.linalg.eig(result.monodromy)
    x = v[:, int(np.argmax(np.abs(w)))]
    n = mass.shape[0]
    eta = shapes.T @ (mass @ x[:n])
    etad = shapes.T @ (mass @ x[n:])
    om = 2.0 * np.pi * np.asarray(freqs_hz, dtype=float)
    e = np.abs(etad) ** 2 + (om * np.abs(eta)) ** 2
    total = float(e.sum())
    return e / total if total > 0 else np.zeros_like(e)


def attribute_region(lower_hz: float, upper_hz: float, candidates: Candidates, *,
                     factor: float | None = None, rtol: float = ATTRIBUTION_RTOL,
                     shares: np.ndarray | None = None, names: Sequence[str] | None = None,
                     min_share: float = MODE_SHARE_MIN) -> tuple[int | None, str]:
    """The theory candidate whose frequency relation holds in an unstable interval.

    Parameters
    ----------
    lower_hz, upper_hz : float
        The interval in the grid's (reference) mesh frequency [Hz].
    candidates : Candidates
        Allowed rows are considered (suppressed ones never explain a region).
    factor : float, optional
        Reference mesh frequency per speed [Hz per min^-1]. Needed when the rows belong to
        several mesh frequencies (their centres are compared by speed, ``rpm x factor``).
    rtol : float
        A candidate holds when its centre lies in ``[lower (1 - rtol), upper (1 + rtol)]``.
    shares : ndarray, optional
        Share of every mode (indices of ``candidates.natural_frequencies_hz``) in the growing
        Floquet solution (see ``mode_shapes`` of :func:`stability_chart`). When given, a
        candidate must also have its modes carry at least ``min_share`` of it.
    names : sequence of str, optional
        Mode names for the evidence text (default ``f1, f2, ...``).
    min_share : float
        See ``shares``.

    Returns
    -------
    (int or None, str)
        Row index of the candidate, or None; and the evidence text. With ``shares``, the
        candidates whose modes carry at least ``min_share`` of the growing solution together
        (and each of a sum's two modes at least :data:`CLUSTER_SHARE_MIN`) qualify; among those
        within :data:`SHARE_TIE` of the largest share the lowest order ``n`` wins (a region of
        order ``n`` is ``O(eps^n)`` wide), then the nearest centre. Without ``shares``: the
        lowest order, then the nearest centre.
    """
    require_instance(candidates, Candidates, "candidates")
    lo, hi = require_real(lower_hz, "lower_hz"), require_real(upper_hz, "upper_hz")
    if not 0.0 <= require_real(rtol, "rtol") < 1.0:
        raise ValueError(f"rtol = {shown(rtol)} is not admissible: 0 <= rtol < 1 (relative)")
    require_real(min_share, "min_share")
    if factor is not None:
        require_positive(require_real(factor, "factor"), "factor")
    n_modes = candidates.natural_frequencies_hz.size
    if shares is not None:
        sh = np.asarray(shares)
        if (sh.dtype.kind not in "iuf" or sh.ndim != 1 or sh.size not in (0, n_modes)
                or not np.all(np.isfinite(sh))):
            raise ValueError(f"shares must be a 1-D array of {n_modes} finite real numbers (one "
                             "per natural frequency)")
        shares = sh.astype(float)
    if names is not None and (isinstance(names, str) or len(list(names)) != n_modes):
        raise ValueError(f"names must be a sequence of {n_modes} mode names")
    if not len(candidates):
        return None, "no theory candidates in range"
    several = _by_speed(candidates, factor)
    centre = (candidates.rpm * factor if several else candidates.f_mesh_hz).astype(float)
    holds = (candidates.allowed.astype(bool) & np.isfinite(centre)
             & (centre >= lo * (1.0 - rtol)) & (centre <= hi * (1.0 + rtol)))
    labels = list(names) if names is not None else [
        f"f{i + 1}" for i in range(candidates.natural_frequencies_hz.size)]
    dominant = ""
    if shares is not None and shares.size:
        order = np.argsort(shares)[::-1]
        parts = []
        for i in order[:3]:
            if shares[i] >= 0.05:
                parts.append(f"{labels[i]} {100 * shares[i]:.0f} %")
        dominant = "growing solution: " + ", ".join(parts) if parts else ""
    freqs = candidates.natural_frequencies_hz

    def cluster(j: int) -> np.ndarray:
        return np.flatnonzero(np.abs(freqs - freqs[j]) <= 1e-6 * freqs[j])

    scored: list[tuple[float, int]] = []
    for i in np.flatnonzero(holds):
        share = 1.0
        if shares is not None and shares.size:
            mode_parts = [float(shares[cluster(int(j))].sum())
                          for j in {int(candidates.mode_i[i]), int(candidates.mode_j[i])}]
            share = float(sum(mode_parts))
            if share < min_share or min(mode_parts) < CLUSTER_SHARE_MIN:
                continue
        scored.append((share, int(i)))
    best: tuple[tuple, int] | None = None
    if scored:
        top = max(sc for sc, _ in scored)
        for sc, i in scored:
            if sc < top - SHARE_TIE:
                continue
            key = (int(candidates.n[i]), abs(centre[i] - 0.5 * (lo + hi)))
            if best is None or key < best[0]:
                best = (key, i)
    if best is None:
        why = (f"no allowed candidate within the interval ± {100 * rtol:g} %"
               if not holds.any() else
               f"no allowed candidate within ± {100 * rtol:g} % whose modes carry the growing "
               "solution")
        return None, "; ".join(x for x in (why, dominant) if x)
    i = best[1]
    where = (f"centre {candidates.rpm[i]:.0f} min-1" if several else
             f"centre {centre[i]:.1f} Hz")
    inside = lo <= centre[i] <= hi
    text = (f"{candidates.full_label(i)}: {where} "
            + ("inside the interval" if inside else
               f"{100 * min(abs(centre[i] - lo), abs(centre[i] - hi)) / centre[i]:.2f} % "
               "outside it"))
    return i, "; ".join(x for x in (text, dominant) if x)


# ------------------------------------------------------------------------- the chart


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
    mode_shapes: Any = None,
    mode_names: Sequence[str] | None = None,
    attribution_rtol: float = ATTRIBUTION_RTOL,
    workers: int | None = 1,
    executor: Executor | None = None,
    progress: bool | None = False,
) -> StabilityChart:
    """Evaluate Floquet stability over a mesh-frequency grid.

    Parameters
    ----------
    system_at : callable
        ``system_at(f_mesh)`` (or ``system_at(f_mesh, param)`` with ``parameter_values``)
        returning ``(M, C, K, period)`` as accepted by
        :func:`analysis.instability.floquet.floquet` (``K`` callable, ``PiecewiseConstant``
        or ``PiecewiseSmooth``).
    mesh_frequencies_hz : array_like, shape (nf,)
        Strictly increasing mesh-frequency grid [Hz].
    parameter_values : sequence of float, optional
        Second parameter (Ince-Strutt chart).
    mesh_frequency_per_rpm : float, optional
        Mesh frequency per input speed [Hz/min-1] (speeds in the region table).
    candidates : Candidates, optional
        Theory candidates; each region is attributed to the candidate whose relation holds in
        it (:func:`attribute_region`), else left unattributed.
    refine : bool
        Refine every interior boundary by root finding on ``max|mu| - 1 - tol``.
    tol : float
        Stability tolerance.
    xtol_rel : float
        Relative tolerance of the refined boundaries.
    parameter_name, parameter_units : str
        Metadata of the second parameter.
    floquet_options : dict, optional
        Extra keyword arguments for :func:`floquet` (``method``, ``n_steps``, ``rtol``,
        ``multiplier_atol``, ``unity_margin``).
    mesh_frequency_names, mesh_frequency_ratios : sequence
        For a system with several mesh frequencies: their names and their ratios to the grid's
        (reference) mesh frequency, first entry the reference (ratio 1). The region table then
        gives every region in every mesh frequency, and candidates are compared by speed
        (needs ``mesh_frequency_per_rpm``).
    method : str
        Description of how ``system_at`` makes the system periodic (stored).
    mode_shapes : array_like, shape (n_dof, n_modes), optional
        Mass-normalised mode shapes of the mean system, one column per natural frequency of
        ``candidates`` (same order). The growing Floquet solution at each region's peak is
        decomposed into them, and a candidate explains the region only if its modes carry at
        least :data:`MODE_SHARE_MIN` of that solution's energy.
    mode_names : sequence of str, optional
        Names of those modes (evidence text).
    attribution_rtol : float
        See :func:`attribute_region`.
    workers : int or None
        Processes for the grid and the boundary refinements (None: the cores available to
        this process): a forked process pool of this call (where ``fork`` is available) when
        no ``executor`` is given, else the number of workers of ``executor`` (sizes the
        chunks: about four per worker).
    executor : concurrent.futures.Executor, optional
        Where the evaluations run when the chart is worth it: e.g. the local pool or Dask
        cluster of :func:`gearvib.execution.executor_for`, or
        ``dask.distributed.Client(address).get_executor()``. ``system_at`` is then pickled
        with every chunk (cloudpickle on Dask), so it must be picklable for a process pool.
        Not shut down here.

        Parallel work (own pool or ``executor``) starts only when the first evaluation
        predicts a chart of more than a few seconds. Every evaluation runs with one
        BLAS/OpenMP thread (threadpoolctl), here and in the workers, so the results are
        identical for any executor and number of workers.
    progress : bool or None
        Progress bar (tqdm) over the evaluations; None shows it on a terminal only.

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
    require_positive(attribution_rtol, "attribution_rtol", allow_zero=True)
    opts = dict(floquet_options or {})
    opts["tol"] = tol
    names = tuple(str(x) for x in mesh_frequency_names)
    ratios = tuple(float(x) for x in mesh_frequency_ratios)
    if len(names) != len(ratios):
        raise ValueError(f"mesh_frequency_names has {len(names)} entries, "
                         f"mesh_frequency_ratios {len(ratios)}; give one ratio per name")
    if ratios and not (ratios[0] == 1.0 and all(r > 0 for r in ratios)):
        raise ValueError("mesh_frequency_ratios must be > 0 and start with 1 (the reference)")
    shapes = None
    if mode_shapes is not None:
        shapes = require_finite(mode_shapes, "mode_shapes")
        if candidates is None or shapes.ndim != 2 or \
                shapes.shape[1] != candidates.natural_frequencies_hz.size:
            raise ValueError("mode_shapes must be (n_dof, n_modes) with one column per natural "
                             "frequency of candidates (and candidates given)")
    n_workers = default_workers() if workers is None else workers
    if isinstance(n_workers, bool) or not isinstance(n_workers, int | np.integer) \
            or n_workers < 1:
        raise ValueError(f"workers = {shown(workers)} is not admissible: an integer >= 1 or "
                         "None")
    n_workers = int(n_workers)
    if executor is not None and not isinstance(executor, Executor):
        raise ValueError(f"executor = {shown(executor)} is not admissible: a "
                         "concurrent.futures.Executor or None")

    rows = [None] if params is None else list(params)
    items = [(float(fm), p) for p in rows for fm in f]
    bar = _progress_bar(progress, len(items), "Floquet chart")
    pool: Executor | None = None
    own_pool = False
    run = {"system_at": system_at, "opts": opts, "xtol_rel": xtol_rel, "bar": bar,
           "workers": n_workers, "own_pool": False, "executor": None}
    try:
        # the first evaluation (the lowest mesh frequency: the longest period) tells whether
        # parallel work pays
        t0 = time.perf_counter()
        first = _map_chart("grid", items[:1], **run)
        expected = (time.perf_counter() - t0) * len(items)
        if len(items) > 1 and expected > _PARALLEL_MIN_S:
            if executor is not None:
                pool = executor
            elif n_workers > 1 and "fork" in multiprocessing.get_all_start_methods():
                pool = ProcessPoolExecutor(min(n_workers, len(items) - 1),
                                           mp_context=multiprocessing.get_context("fork"),
                                           initializer=_install, initargs=(system_at,))
                own_pool = True
        run.update(executor=pool, own_pool=own_pool)
        values = [*first, *_map_chart("grid", items[1:], **run)]
        mm = np.array([v[0] for v in values]).reshape(len(rows), f.size)
        gr = np.array([v[1] for v in values]).reshape(len(rows), f.size)
        err = np.array([v[2] for v in values]).reshape(len(rows), f.size)

        # intervals and the boundary brackets to refine
        spans: list[tuple[int, int, int]] = []
        for a in range(len(rows)):
            uns = mm[a] > 1.0 + tol
            edges = np.flatnonzero(np.diff(uns.astype(np.int8)))
            starts = [0] if uns[0] else []
            starts += [int(e) + 1 for e in edges if not uns[e]]
            for s_ in starts:
                e_ = s_
                while e_ + 1 < f.size and uns[e_ + 1]:
                    e_ += 1
                spans.append((a, s_, e_))
        brackets: list[tuple[float, float, Any]] = []
        for a, s_, e_ in spans:
            if refine and s_ > 0:
                brackets.append((float(f[s_ - 1]), float(f[s_]), rows[a]))
            if refine and e_ < f.size - 1:
                brackets.append((float(f[e_]), float(f[e_ + 1]), rows[a]))

        if brackets:
            bar.total = len(items) + len(brackets)
            bar.set_description("Floquet boundaries")
        roots = dict(zip(brackets, _map_chart("boundary", brackets, **run), strict=True))
    except BaseException:
        if own_pool and pool is not None:  # return at once, nothing left running
            terminate_pool(pool)
            own_pool = False
        raise
    finally:
        if own_pool and pool is not None:
            pool.shutdown(wait=True)
        bar.close()

    table: list[dict] = []
    for a, s_, e_ in spans:
        p = rows[a]
        lower_open, upper_open = s_ == 0, e_ == f.size - 1
        if lower_open:
            lower = f[0]
        elif refine:
            lower = roots[(float(f[s_ - 1]), float(f[s_]), p)]
        else:
            lower = 0.5 * (f[s_ - 1] + f[s_])
        if upper_open:
            upper = f[-1]
        elif refine:
            upper = roots[(float(f[e_]), float(f[e_ + 1]), p)]
        else:
            upper = 0.5 * (f[e_] + f[e_ + 1])
        k = s_ + int(np.argmax(gr[a, s_:e_ + 1]))
        lab, cf, idx, why = "", np.nan, -1, ""
        if candidates is not None:
            shares = None
            if shapes is not None:
                M, C, K, T = _call(system_at, float(f[k]), p)
                shares = _mode_shares(floquet(M, C, K, T, **opts), np.asarray(M, float),
                                      shapes, candidates.natural_frequencies_hz)
            hit, why = attribute_region(float(lower), float(upper), candidates, factor=factor,
                                        rtol=attribution_rtol, shares=shares,
                                        names=mode_names)
            if hit is None and (lower_open or upper_open):
                why += ("; the interval reaches the end of the analysed range, so its "
                        "candidate may lie beyond it")
            if hit is not None:
                idx = hit
                lab = candidates.full_label(hit)
                cf = (float(candidates.rpm[hit]) * factor
                      if _by_speed(candidates, factor) and factor is not None
                      else float(candidates.f_mesh_hz[hit]))
        table.append({
            "lower": float(lower), "upper": float(upper), "lower_open": lower_open,
            "upper_open": upper_open, "peak_growth_rate": float(gr[a, k]),
            "peak_max_modulus": float(mm[a, k]), "candidate": lab, "candidate_f_mesh": cf,
            "candidate_index": idx, "evidence": why,
            "parameter": np.nan if p is None else float(p),
        })
    notes = []
    atol = float(opts.get("multiplier_atol", 0.0) or 0.0)
    if atol and np.isfinite(err).any() and float(np.nanmax(err)) > 10 * atol:
        notes.append(f"largest estimated error of max|mu| {float(np.nanmax(err)):.2g} "
                     f"(requested {atol:g}): the sub-step limit was reached")
    squeeze = params is None
    return StabilityChart(
        mesh_frequencies_hz=f, parameter_values=params,
        max_modulus=mm[0] if squeeze else mm, growth_rate=gr[0] if squeeze else gr,
        tol=float(tol), mesh_frequency_per_rpm=factor, region_table=table,
        parameter_name=parameter_name, parameter_units=parameter_units,
        mesh_frequency_names=names, mesh_frequency_ratios=ratios, method=str(method),
        candidates=candidates, notes=tuple(notes),
    )
