"""Detect and classify amplitude rises in an rpm-frequency (run-up) map.

Each detected spot is classified as a forced resonance (a mesh-order ray crossing a natural
frequency), a parametric instability (mesh frequency in a principal or sum-type region with
response at the natural frequency of a participating mode), or unclassified.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.ndimage

from analysis.checks import require_finite, require_positive
from analysis.instability.theory import Candidates, _positive_frequencies, instability_candidates

__all__ = ["Resonances", "detect_resonances"]

FORCED = "forced resonance"
UNCLASSIFIED = "unclassified"


@dataclass(frozen=True)
class Resonances:
    """Table of detected spots (one row each), sorted by time.

    Attributes
    ----------
    time : ndarray
        Time [s] of the spot.
    rpm : ndarray
        Input speed [min-1].
    frequency : ndarray
        Response frequency [Hz].
    f_mesh : ndarray
        Mesh frequency [Hz] at that speed.
    order : ndarray of int
        Mesh order of the ray the spot lies on (0: not on a ray within tolerance).
    mechanism : ndarray of str
        ``"forced resonance"``, ``"parametric instability (principal, n=3)"``,
        ``"parametric instability (sum, n=2)"`` or ``"unclassified"``.
    mode : ndarray of str
        Natural-frequency label the response is attributed to ("" if none).
    strength_db : ndarray
        Rise above the background [dB] (ray median for spots on a ray, median over time at the
        frequency otherwise).
    note : ndarray of str
        Remarks, e.g. coincidence with an even-order principal region.
    """

    time: np.ndarray
    rpm: np.ndarray
    frequency: np.ndarray
    f_mesh: np.ndarray
    order: np.ndarray
    mechanism: np.ndarray
    mode: np.ndarray
    strength_db: np.ndarray
    note: np.ndarray
    mesh_frequency_per_rpm: float = 1.0

    def __len__(self) -> int:
        return int(self.time.size)

    def to_dataset(self):
        """Table as :class:`xarray.Dataset` with dimension ``resonance``."""
        import xarray as xr

        def v(x, units, long_name):
            return ("resonance", x, {"units": units, "long_name": long_name})

        return xr.Dataset(
            {
                "speed": v(self.rpm, "min-1", "input speed"),
                "time": v(self.time, "s", "time"),
                "frequency": v(self.frequency, "Hz", "response frequency"),
                "f_mesh": v(self.f_mesh, "Hz", "mesh frequency"),
                "order": v(self.order, "1", "mesh order of the ray (0: none)"),
                "mechanism": v(self.mechanism.astype(str), "1", "classified mechanism"),
                "mode": v(self.mode.astype(str), "1", "natural frequency of the response"),
                "strength_db": v(self.strength_db, "dB", "rise above background"),
                "note": v(self.note.astype(str), "1", "remarks"),
            },
            coords={"resonance": ("resonance", np.arange(len(self)),
                                  {"units": "1", "long_name": "resonance index"})},
            attrs={"mesh_frequency_per_rpm": self.mesh_frequency_per_rpm},
        )

    def __str__(self) -> str:
        lines = [f"{'speed [rpm]':>11} {'f [Hz]':>8} {'order':>5} {'dB':>6}  mechanism (mode)"]
        for r in range(len(self)):
            mode = f" ({self.mode[r]})" if self.mode[r] else ""
            lines.append(f"{self.rpm[r]:11.1f} {self.frequency[r]:8.1f} {self.order[r]:5d} "
                         f"{self.strength_db[r]:6.1f}  {self.mechanism[r]}{mode}")
        return "\n".join(lines)

    def plot(self, map_ds=None, ax=None):
        """Spots over the rpm-frequency map (delegates to ``plots.plot_resonances``)."""
        from analysis.instability.plots import plot_resonances

        return plot_resonances(self, map_ds, ax=ax)


def _check_map(map_ds: Any, variable: str) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                     np.ndarray]:
    if not hasattr(map_ds, "data_vars"):
        raise ValueError("map_ds must be an xarray.Dataset with amplitude(time, frequency)")
    if variable not in map_ds.data_vars:
        raise ValueError(f"map_ds has no data variable {variable!r} (expected "
                         f"{variable}(time, frequency))")
    da = map_ds[variable]
    if set(da.dims) != {"time", "frequency"}:
        raise ValueError(f"map_ds[{variable!r}] must have dims ('time', 'frequency'); "
                         f"got {da.dims}")
    da = da.transpose("time", "frequency")
    for c in ("time", "frequency", "rpm"):
        if c not in map_ds.coords:
            raise ValueError(f"map_ds needs coordinate {c!r} (time [s], frequency [Hz], "
                             "rpm(time) [min-1])")
    if map_ds["rpm"].dims != ("time",):
        raise ValueError(f"map_ds coordinate 'rpm' must have dim ('time',); got "
                         f"{map_ds['rpm'].dims}")
    t = require_finite(map_ds["time"].values, "time")
    f = require_finite(map_ds["frequency"].values, "frequency")
    rpm = require_finite(map_ds["rpm"].values, "rpm")
    a = require_finite(da.values, variable)
    if np.any(a < 0):
        raise ValueError(f"{variable} must be a linear (non-negative) amplitude")
    if f.size < 3 or t.size < 3:
        raise ValueError("map_ds needs at least 3 times and 3 frequencies")
    if np.any(np.diff(f) <= 0):
        raise ValueError("frequency must be strictly increasing")
    return t, f, rpm, a


def detect_resonances(
    map_ds: Any,
    *,
    natural_frequencies_hz: Any,
    mesh_frequency_per_rpm: float,
    orders: Iterable[int] = range(1, 8),
    candidates: Candidates | None = None,
    threshold_db: float = 6.0,
    tolerance: float = 0.03,
    n_max: int = 4,
    neighbourhood: tuple[int, int] = (5, 5),
    names: Sequence[str] | None = None,
    variable: str = "amplitude",
) -> Resonances:
    """Detect amplitude rises in an rpm-frequency map and classify their mechanism.

    Parameters
    ----------
    map_ds : xarray.Dataset
        Data variable ``amplitude(time, frequency)`` (linear units), coordinates ``time`` [s],
        ``frequency`` [Hz] and auxiliary coordinate ``rpm(time)`` [min-1].
    natural_frequencies_hz : array_like
        Natural frequencies [Hz] (> 0).
    mesh_frequency_per_rpm : float
        Mesh frequency per input speed [Hz/min-1] (``f_mesh = factor * rpm``).
    orders : iterable of int
        Mesh orders whose rays ``f = order * f_mesh`` are considered.
    candidates : Candidates, optional
        Theory candidates (e.g. with mesh-phasing rules applied); by default principal and sum
        candidates up to ``n_max`` from the natural frequencies. A spot matching only
        suppressed candidates stays unclassified, with a note.
    threshold_db : float
        Minimum rise above the background [dB].
    tolerance : float
        Relative tolerance for "on a ray", "at a natural frequency" and "in a region".
    n_max : int
        Largest region order for the default candidates.
    neighbourhood : (int, int)
        Size (time bins, frequency bins) of the local-maximum window.
    names : sequence of str, optional
        Natural-frequency names (default ``f1, f2, ...``).
    variable : str
        Name of the amplitude variable.

    Returns
    -------
    Resonances

    Notes
    -----
    Background: the median over time at each frequency (robust against the short passage of a
    ray). Spots are local maxima of ``20 log10(amplitude / background)`` within
    ``neighbourhood``. A spot on an order ray is compared with the median amplitude *along that
    ray*, so constant order content does not count as a rise. Classification:

    * on ray ``o`` (``|f - o f_mesh| <= tolerance f`` + one frequency bin) and at a natural
      frequency ``f_i``: forced resonance (the even-order principal region ``n = 2 o``
      coincides with it and is mentioned in ``note``);
    * at ``f_i`` with ``f_mesh`` within ``tolerance`` of a principal (``2 f_i/n``) or sum
      (``(f_i + f_j)/n``) centre containing mode ``i``: parametric instability
      (Nayfeh & Mook 1979, ch. 5; Lin & Parker 2002);
    * otherwise unclassified.

    Spots at zero frequency or zero speed (where all rays meet) are ignored.
    """
    t, f, rpm, a = _check_map(map_ds, variable)
    fn = _positive_frequencies(natural_frequencies_hz, "natural_frequencies_hz")
    factor = require_positive(mesh_frequency_per_rpm, "mesh_frequency_per_rpm")
    orders = [int(o) for o in orders]
    if not orders or any(o < 1 for o in orders):
        raise ValueError(f"orders = {orders!r} is not admissible: need positive integers")
    thr = require_positive(threshold_db, "threshold_db", allow_zero=True)
    tol = require_positive(tolerance, "tolerance")
    labels = list(names) if names is not None else [f"f{i + 1}" for i in range(fn.size)]
    if len(labels) != fn.size:
        raise ValueError(f"names has {len(labels)} entries; natural_frequencies_hz has "
                         f"{fn.size}")
    if candidates is None:
        candidates = instability_candidates(fn, n_max=n_max, mode_labels=labels)
    cand_f = candidates.natural_frequencies_hz
    if cand_f.size == 0:
        cand_f = fn
    nb = tuple(int(x) for x in neighbourhood)
    if len(nb) != 2 or min(nb) < 1:
        raise ValueError(f"neighbourhood = {neighbourhood!r} is not admissible: two integers >= 1")

    tiny = 1e-12 * max(float(a.max()), 1e-300)
    bg = np.maximum(np.median(a, axis=0), tiny)
    level = 20.0 * np.log10(np.maximum(a, tiny) / bg[None, :])
    peaks = (level == scipy.ndimage.maximum_filter(level, size=nb, mode="nearest")) & (
        level >= thr)
    lab, nlab = scipy.ndimage.label(peaks)
    fmesh = factor * rpm
    df = float(np.median(np.diff(f)))

    ray_median = {}
    for o in orders:
        idx = np.clip(np.searchsorted(f, o * fmesh), 0, f.size - 1)
        inside = (o * fmesh >= f[0]) & (o * fmesh <= f[-1])
        ray_median[o] = (max(float(np.median(a[np.flatnonzero(inside), idx[inside]])), tiny)
                         if inside.any() else tiny)

    rows = []
    for comp in range(1, nlab + 1):
        ii, jj = np.nonzero(lab == comp)
        k = int(np.argmax(level[ii, jj]))
        it, jf = int(ii[k]), int(jj[k])
        fr, fm = float(f[jf]), float(fmesh[it])
        if fr <= 0 or fm <= 0:
            continue  # static (DC) content and standstill, where all rays meet
        strength = float(level[it, jf])
        on = [o for o in orders if abs(fr - o * fm) <= tol * fr + df]
        order = min(on, key=lambda o: abs(fr - o * fm)) if on else 0
        if order:
            strength = 20.0 * np.log10(max(float(a[it, jf]), tiny) / ray_median[order])
            if strength < thr:
                continue  # ordinary order content, no rise along the ray
        near = np.flatnonzero(np.abs(fr - fn) <= tol * fn)
        mode = "=".join(labels[i] for i in near)
        mech, note = UNCLASSIFIED, ""
        if order and near.size:
            mech = FORCED
            if 2 * order <= n_max:
                note = f"coincides with principal region n={2 * order} of {mode}"
        elif near.size:
            best, best_err = None, np.inf
            suppressed = []
            for r in range(len(candidates)):
                if candidates.kind[r] not in ("principal", "sum"):
                    continue
                members = {float(cand_f[candidates.mode_i[r]]), float(cand_f[candidates.mode_j[r]])}
                if not any(abs(fr - x) <= tol * x for x in members):
                    continue
                err = abs(fm - candidates.f_mesh_hz[r]) / candidates.f_mesh_hz[r]
                if err > tol:
                    continue
                if not candidates.allowed[r]:
                    suppressed.append(str(candidates.label[r]))
                elif err < best_err:
                    best, best_err = r, err
            if best is not None:
                mech = (f"parametric instability ({candidates.kind[best]}, "
                        f"n={candidates.n[best]})")
                note = f"f_mesh ≈ {candidates.label[best]}"
            elif suppressed:
                note = "matches only suppressed candidates: " + ", ".join(suppressed)
        rows.append((float(t[it]), float(rpm[it]), fr, fm, order, mech, mode, strength, note))
    rows.sort(key=lambda r: r[0])
    cols = list(zip(*rows, strict=True)) if rows else [[]] * 9
    return Resonances(
        time=np.asarray(cols[0], float), rpm=np.asarray(cols[1], float),
        frequency=np.asarray(cols[2], float), f_mesh=np.asarray(cols[3], float),
        order=np.asarray(cols[4], int), mechanism=np.asarray(cols[5], object),
        mode=np.asarray(cols[6], object), strength_db=np.asarray(cols[7], float),
        note=np.asarray(cols[8], object), mesh_frequency_per_rpm=factor,
    )
