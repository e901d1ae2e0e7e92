"""Signals derived from a gear's time-synchronous average: regular, residual, difference.

A TSA spans exactly one revolution, so its DFT line ``k`` *is* order ``k`` of the shaft and
every component is removed exactly by zeroing lines (no filter transition bands). Definitions
(Lebold et al. 2000; Zakrajsek, Townsend & Decker 1993; the same in spirit as MATLAB's
``tsaregular``, ``tsaresidual`` and ``tsadifference``), with ``z`` the mesh order(s) (teeth
of the gear on this shaft), ``H`` mesh harmonics, ``S`` shaft harmonics and ``B`` sideband
orders:

* **regular** -- the regular meshing components: shaft orders ``1 .. S``, mesh orders
  ``h z`` (``h = 1 .. H``) and their sidebands ``h z +- b`` (``b = 1 .. B``; first-order
  sidebands by default);
* **residual** ``r`` -- the TSA without its mean, shaft orders ``1 .. S`` and mesh orders
  ``h z`` (sidebands kept);
* **difference** ``d`` -- the TSA without its mean and the regular components (sidebands
  removed too);
* **envelope** ``e`` -- of the TSA band-passed around the first mesh order (orders
  ``z - W .. z + W``), for NB4: ``|a + j H(a)|`` with ``H`` the Hilbert transform, computed on
  the lines of the band.

Line amplitudes are peak amplitudes, ``2 |X_k| / n`` (``X = rfft(tsa)``, ``n`` samples).

References
----------
M. Lebold, K. McClintic, R. Campbell, C. Byington, K. Maynard, "Review of vibration analysis
methods for gearbox diagnostics and prognostics", Proc. 54th Meeting of the Society for
Machinery Failure Prevention Technology, Virginia Beach, 2000, 623-634.
J. J. Zakrajsek, D. P. Townsend, H. J. Decker, "An analysis of gear fault detection methods as
applied to pitting fatigue failure data", NASA TM-105950, 1993.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.cf import cf_dataset
from analysis.checks import require_int
from analysis.cm_plots import gear_signals_figure
from analysis.fft import irfft, rfft
from analysis.inputs import channel_coords
from analysis.tsa import TSA

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = ["GearSignals", "gear_signals"]


@dataclass(frozen=True)
class GearSignals:
    """Regular, residual, difference and envelope signals of one TSA (module docstring).

    Attributes
    ----------
    angle : numpy.ndarray
        Angle of the shaft (gear) [rad].
    tsa, regular, residual, difference, envelope : numpy.ndarray
        The signals, shape ``(*channels, n)``, in ``units``.
    amplitudes : numpy.ndarray
        Peak amplitude of every order ``0 .. n // 2`` of the TSA, shape ``(*channels,
        n // 2 + 1)``.
    mesh_orders : tuple of int
        Mesh orders (teeth); the first is the one of the sideband level factor and the
        envelope.
    mesh_lines : numpy.ndarray
        Orders of the mesh harmonics ``h z`` used (FM0's denominator).
    regular_orders : numpy.ndarray
        Orders of the regular signal (removed from the difference signal).
    residual_orders : numpy.ndarray
        Orders removed from the residual signal (besides the mean).
    envelope_band : tuple of int
        First and last order of the envelope band.
    harmonics, shaft_harmonics, sidebands : int
        ``H``, ``S`` and ``B`` of the module docstring.
    units, name : str
        Of the signal.
    dims, coords :
        Channel dimensions and their coordinates.
    shaft : str
        What the angle is of (``"shaft"``, ``"planet 1"``, ``"sun"``).
    teeth : int or None
        Teeth of the gear when the TSA is a gear's (planet, sun), else ``None``.
    """

    angle: np.ndarray
    tsa: np.ndarray
    regular: np.ndarray
    residual: np.ndarray
    difference: np.ndarray
    envelope: np.ndarray
    amplitudes: np.ndarray
    mesh_orders: tuple[int, ...]
    mesh_lines: np.ndarray
    regular_orders: np.ndarray
    residual_orders: np.ndarray
    envelope_band: tuple[int, int]
    harmonics: int
    shaft_harmonics: int
    sidebands: int
    units: str = "1"
    name: str = "x"
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    shaft: str = "shaft"
    teeth: int | None = None

    def to_dataset(self) -> xr.Dataset:
        """CF :class:`xarray.Dataset` with the five signals along ``angle`` and the line
        amplitudes along ``order``."""
        import xarray as xr

        lead = self.dims
        long = {
            "tsa": "time-synchronous average",
            "regular": "regular meshing components (shaft and mesh orders, sidebands)",
            "residual": "residual signal (TSA minus shaft and mesh orders)",
            "difference": "difference signal (TSA minus regular components)",
            "envelope": "envelope of the TSA band-passed around the mesh order",
        }
        data = {
            k: ((*lead, "angle"), getattr(self, k), {"units": self.units, "long_name": v})
            for k, v in long.items()
        }
        data["amplitude"] = (
            (*lead, "order"),
            self.amplitudes,
            {"units": self.units, "long_name": "peak amplitude of the TSA's orders"},
        )
        coords: dict[str, Any] = {
            "angle": ("angle", self.angle, {"units": "rad", "long_name": f"{self.shaft} angle"}),
            "order": (
                "order",
                np.arange(self.amplitudes.shape[-1]),
                {"units": "1", "long_name": f"order of the {self.shaft}"},
            ),
        }
        coords.update(channel_coords(lead, self.coords))
        attrs = {
            "Conventions": "CF-1.11",
            "mesh_orders": np.asarray(self.mesh_orders, dtype=np.int64),
            "mesh_harmonics": int(self.harmonics),
            "shaft_harmonics": int(self.shaft_harmonics),
            "sidebands": int(self.sidebands),
            "regular_orders": np.asarray(self.regular_orders, dtype=np.int64),
            "residual_orders": np.asarray(self.residual_orders, dtype=np.int64),
            "envelope_band": np.asarray(self.envelope_band, dtype=np.int64),
            "shaft": self.shaft,
        }
        return cf_dataset(
            xr.Dataset(data, coords=coords, attrs=attrs),
            title=f"regular, residual and difference signals of {self.name} ({self.shaft})",
            producer="analysis.gear_signals.gear_signals",
        )

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure of the signals (see :func:`analysis.cm_plots.gear_signals_figure`)."""
        return gear_signals_figure(self, **kwargs)


def _orders(value: Any) -> tuple[int, ...]:
    items = [value] if np.ndim(value) == 0 else list(np.asarray(value, dtype=object).ravel())
    if not items:
        raise ValueError("mesh_orders: give at least one mesh order (teeth, an integer >= 2)")
    return tuple(require_int(v, "mesh_orders", 2) for v in items)


def _keep(spec: np.ndarray, orders: np.ndarray, n: int) -> np.ndarray:
    """The signal made of the lines ``orders`` of ``spec`` only."""
    part = np.zeros_like(spec)
    part[..., orders] = spec[..., orders]
    return irfft(part, n, axis=-1)


def gear_signals(
    tsa: TSA | Any,
    mesh_orders: Any,
    *,
    harmonics: Any = None,
    shaft_harmonics: Any = 3,
    sidebands: Any = 1,
    envelope_band: Any = None,
) -> GearSignals:
    """Regular, residual, difference and envelope signals of a TSA (module docstring).

    Parameters
    ----------
    tsa : TSA or array_like
        A :class:`analysis.tsa.TSA` (e.g. a planet's from
        :func:`analysis.planetary_tsa.planetary_tsa`), or samples of exactly one revolution
        along the last axis (at least 8).
    mesh_orders : int or sequence of int
        Mesh order(s) of the gear(s) on this shaft: their numbers of teeth.
    harmonics : int, optional
        Mesh harmonics ``H`` (default: all below the TSA's ``max_order``, or below
        ``n / 2`` for an array).
    shaft_harmonics : int, default 3
        Shaft orders ``1 .. S`` counted as regular (0 for none).
    sidebands : int, default 1
        Sideband orders ``B`` around each mesh harmonic counted as regular (first-order
        sidebands by default, the definition of the difference signal).
    envelope_band : int, optional
        Half width ``W`` [orders] of the band around the first mesh order whose envelope is
        taken (NB4); default ``max(1, z // 2 - 1)``: the sidebands up to half-way to the
        neighbouring harmonics.

    Returns
    -------
    GearSignals

    Raises
    ------
    ValueError, TypeError
        Naming the parameter: non-integer or too high mesh orders, negative counts, a TSA
        with unobserved angles (NaN) or non-finite values.
    """
    meta: dict[str, Any]  # the TSA's description, passed on to GearSignals
    if isinstance(tsa, TSA):
        values = np.asarray(tsa.values, dtype=float)
        top = float(tsa.max_order)
        meta = dict(units=tsa.units, name=tsa.name, dims=tsa.dims, coords=tsa.coords,
                    shaft=tsa.shaft, teeth=tsa.teeth)  # fmt: skip
        angle = tsa.angle
    else:
        arr = np.asarray(tsa)
        if arr.dtype.kind not in "iuf":
            raise TypeError(f"tsa must be a TSA or real numbers; got dtype {arr.dtype}")
        values = arr.astype(float)
        if values.ndim == 0:
            raise ValueError("tsa must hold one revolution along its last axis")
        top = values.shape[-1] / 2.0 - 1.0
        dims = ("channel",) if values.ndim == 2 else tuple(
            f"dim_{i}" for i in range(values.ndim - 1)
        )
        meta = dict(units="1", name="x", dims=dims, coords={}, shaft="shaft", teeth=None)
        angle = 2.0 * np.pi * np.arange(values.shape[-1]) / values.shape[-1]
    n = values.shape[-1]
    if n < 8:
        raise ValueError(f"tsa: {n} samples per revolution; at least 8 are needed")
    if not np.all(np.isfinite(values)):
        raise ValueError(
            "tsa holds NaN or inf (a planet or sun average whose placement cycle did not close "
            "leaves unobserved angles NaN): gear signals need a whole revolution"
        )
    nyq = n // 2
    z = _orders(mesh_orders)
    limit = min(top, nyq - 1)
    if max(z) > limit:
        raise ValueError(
            f"mesh_orders = {z} is not admissible: every mesh order must be <= {limit:g} (the "
            "highest order the TSA resolves)"
        )
    if harmonics is None:
        h_max = max(1, int(np.floor(limit / min(z))))
    else:
        h_max = require_int(harmonics, "harmonics", 1)
    s_max = require_int(shaft_harmonics, "shaft_harmonics", 0)
    b_max = require_int(sidebands, "sidebands", 0)
    lines = sorted({h * zz for zz in z for h in range(1, h_max + 1) if h * zz < nyq})
    shaft_lines = [k for k in range(1, s_max + 1) if k < nyq]
    side = {k + s for k in lines for b in range(1, b_max + 1) for s in (-b, b)}
    regular = np.array(sorted({*shaft_lines, *lines, *(k for k in side if 0 < k < nyq)}),
                       dtype=np.int64)  # fmt: skip
    removed = np.array(sorted({*shaft_lines, *lines}), dtype=np.int64)
    w = max(1, z[0] // 2 - 1) if envelope_band is None else require_int(
        envelope_band, "envelope_band", 0
    )
    lo, hi = max(1, z[0] - w), min(nyq - 1, z[0] + w)
    spec = rfft(values, axis=-1)
    amp = np.abs(spec) * (2.0 / n)
    amp[..., 0] /= 2.0
    if n % 2 == 0:
        amp[..., -1] /= 2.0
    mean = values.mean(axis=-1, keepdims=True)
    reg = _keep(spec, regular, n)
    residual = values - mean - _keep(spec, removed, n)
    difference = values - mean - reg
    band = np.zeros_like(spec)
    band[..., lo : hi + 1] = spec[..., lo : hi + 1]
    a = irfft(band, n, axis=-1)
    ha = irfft(-1j * band, n, axis=-1)  # Hilbert transform: -j on the positive orders
    envelope = np.hypot(a, ha)
    return GearSignals(
        angle=angle, tsa=values, regular=reg, residual=residual, difference=difference,
        envelope=envelope, amplitudes=amp, mesh_orders=z, mesh_lines=np.array(lines),
        regular_orders=regular, residual_orders=removed, envelope_band=(lo, hi),
        harmonics=h_max, shaft_harmonics=s_max, sidebands=b_max, **meta,
    )  # fmt: skip
