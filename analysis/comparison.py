"""Measured against simulated: one reference shaft, common order and rpm grids, matched lines.

:func:`compare_measurements` brings two :class:`analysis.measurement.Measurement` objects -- a
measurement and a simulation's virtual sensor (or any second record) -- onto common ground and
compares them the way an NVH engineer overlays a test and a model:

* **Reference shaft.** Both are order-tracked to their own speed reference (tacho angle when
  there is one); both references must measure the same shaft (the result states both).
* **Grids.** Both rpm-order maps use one order resolution, one angular sampling and one
  highest order (the lower of the two records' alias-free orders at the top common speed), and
  their frames are averaged (power) into one rpm grid over the speed range the two records
  share. The averaged order spectra are taken over that common range only.
* **Channels.** The simulated record's channel is a virtual sensor or, for a run without one,
  a force or transmission-error channel (:func:`simulated_channel_name`); each channel's
  mean (a static load, an offset) is removed before the order analysis.
* **Levels** in dB: *calibrated* (dB re 1 unit) when both channels carry the same physical unit,
  otherwise (or on request) *normalised*: each record's strongest order line (its
  interpolated peak level, at orders of at least twice the order resolution: near-DC content
  is no line) is 0 dB, and the level differences compare the shapes of the spectra. The
  result says which (:attr:`MeasuredSimulatedComparison.level_basis`, ``level_unit``) and
  carries both channels' units; a note states a unit mismatch.
* **Lines.** Peaks of the two order spectra (prominence and range in dB) are matched by order
  within a tolerance (the order resolution): *matched* with the order and level differences,
  *measured only*, *simulated only*. The rpm-order difference map is measured minus simulated.
* **Natural frequencies.** The frequency-locked lines of the measured rpm-frequency map
  (:func:`analysis.runup.map_features`) are set against the model's natural frequencies when
  they are given: nearest mode, offset in per cent, whether the simulation shows the line too.

The result is plain data with :meth:`~MeasuredSimulatedComparison.to_dataset` and
:meth:`~MeasuredSimulatedComparison.plot`; which model parameters explain a frequency offset
needs the model and is worked out in ``gearvib`` (modal strain energy).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr
from scipy.signal import find_peaks as _scipy_peaks

from analysis.cf import cf_dataset
from analysis.checks import require_instance
from analysis.maps import rpm_frequency_map, rpm_order_map
from analysis.measurement import Measurement
from analysis.runup import map_features

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "LINE_TOLERANCE",
    "LineComparison",
    "MeasuredSimulatedComparison",
    "PeakMatch",
    "compare_measurements",
    "simulated_channel_name",
]

LINE_TOLERANCE = 0.10
"""A measured frequency-locked line is 'seen' as a model mode when within 10 % of it."""

_UNCALIBRATED = {"", "1", "v", "mv", "count", "counts"}
_MIN_SPEED_RATIO = 1.3


@dataclass(frozen=True)
class PeakMatch:
    """One line of the order-spectrum comparison.

    Attributes
    ----------
    status : str
        ``"matched"``, ``"measured only"`` or ``"simulated only"``.
    order_measured, order_simulated : float
        Orders of the peaks (NaN where absent).
    level_measured_db, level_simulated_db : float
        Their levels [dB, see ``level_basis``] (NaN where absent; for a one-sided line, the
        other spectrum's level at that order is in ``level_other_db``).
    level_other_db : float
        For a one-sided line: the other record's level at the same order [dB].
    """

    status: str
    order_measured: float
    order_simulated: float
    level_measured_db: float
    level_simulated_db: float
    level_other_db: float = math.nan

    @property
    def order(self) -> float:
        """The order of the line (measured when present)."""
        return self.order_measured if math.isfinite(self.order_measured) else \
            self.order_simulated

    @property
    def order_difference(self) -> float:
        """Measured minus simulated order (NaN unless matched)."""
        return self.order_measured - self.order_simulated

    @property
    def level_difference_db(self) -> float:
        """Measured minus simulated level [dB]; for a one-sided line against the other record's
        level at that order."""
        if self.status == "matched":
            return self.level_measured_db - self.level_simulated_db
        if self.status == "measured only":
            return self.level_measured_db - self.level_other_db
        return self.level_other_db - self.level_simulated_db


@dataclass(frozen=True)
class LineComparison:
    """A frequency-locked line of the measurement against the model's natural frequencies.

    Attributes
    ----------
    frequency_hz : float
        The measured line [Hz].
    mode : str
        Nearest model mode (``""`` when no natural frequencies were given).
    mode_frequency_hz : float
        Its natural frequency [Hz] (NaN without).
    offset : float
        ``frequency_hz / mode_frequency_hz - 1``.
    seen : bool
        Within :data:`LINE_TOLERANCE` of the mode.
    in_simulation : bool
        The simulated map shows a line there too (within 3 %).
    """

    frequency_hz: float
    mode: str
    mode_frequency_hz: float
    offset: float
    seen: bool
    in_simulation: bool


@dataclass(frozen=True)
class MeasuredSimulatedComparison:
    """Result of :func:`compare_measurements` (see the module docstring).

    Attributes
    ----------
    measured_name, simulated_name : str
        Names of the records.
    measured_channel, simulated_channel : str
        Channels compared.
    measured_reference, simulated_reference : str
        Their speed references.
    units : str
        Units of the levels' reference (``"1"`` when normalised).
    level_basis : str
        ``"calibrated: dB re 1 m s-2"`` or ``"normalised: ..."``.
    measured_units, simulated_units : str
        Units of the two channels (they differ for e.g. an accelerometer against a simulated
        force; the levels are normalised then).
    rpm_range : (float, float)
        Common speed range [min-1].
    order : ndarray
        Common order grid.
    order_resolution : float
        Resolution bandwidth of both order analyses [orders].
    rpm : ndarray
        Centres of the common rpm grid [min-1].
    measured_db, simulated_db : ndarray, shape (rpm, order)
        The maps on the common grid [dB] (NaN in rpm bins without a frame).
    measured_spectrum_db, simulated_spectrum_db : ndarray
        Order spectra averaged over the common speed range [dB].
    peaks : tuple of PeakMatch
        Matched, measured-only and simulated-only lines.
    lines : tuple of LineComparison
        Frequency-locked lines of the measurement against the model's modes.
    unseen_modes : tuple of (str, float)
        Model modes in the measured band that no measured line is near.
    match_tolerance : float
        Order tolerance of a match: the order resolution (ENBW), plus 0.2 % of the order
        (the speed references' scale uncertainty).
    notes : tuple of str
        Remarks (what could not be compared, and why).
    """

    measured_name: str
    simulated_name: str
    measured_channel: str
    simulated_channel: str
    measured_reference: str
    simulated_reference: str
    units: str
    level_basis: str
    rpm_range: tuple[float, float]
    order: np.ndarray
    order_resolution: float
    rpm: np.ndarray
    measured_db: np.ndarray
    simulated_db: np.ndarray
    measured_spectrum_db: np.ndarray
    simulated_spectrum_db: np.ndarray
    peaks: tuple[PeakMatch, ...]
    lines: tuple[LineComparison, ...] = ()
    unseen_modes: tuple[tuple[str, float], ...] = ()
    match_tolerance: float = 0.0
    notes: tuple[str, ...] = field(default_factory=tuple)
    measured_units: str = ""
    simulated_units: str = ""

    @property
    def level_unit(self) -> str:
        """The unit of every level: ``"dB re 1 m s-2"``, or ``"dB re the strongest order
        line"`` when normalised."""
        return f"dB re 1 {self.units}" if self.units != "1" else \
            "dB re the strongest order line"

    @property
    def difference_db(self) -> np.ndarray:
        """Measured minus simulated map [dB], shape (rpm, order)."""
        return self.measured_db - self.simulated_db

    def count(self, status: str) -> int:
        """Number of lines with a status (``"matched"``, ``"measured only"``, ...)."""
        return sum(p.status == status for p in self.peaks)

    def summary(self) -> str:
        """One sentence: the lines matched and one-sided, the median level difference."""
        matched = [p for p in self.peaks if p.status == "matched"]
        med = (f"; median level difference of the matched lines "
               f"{np.median([p.level_difference_db for p in matched]):+.1f} dB"
               if matched else "")
        return (f"{self.count('matched')} matched, {self.count('measured only')} measured only, "
                f"{self.count('simulated only')} simulated only (order tolerance ± "
                f"{self.match_tolerance:.3g} + 0.2 %){med}; levels {self.level_basis}")

    def to_dataset(self) -> xr.Dataset:
        """The comparison as a CF Dataset: maps and spectra on the common grids, the lines."""
        unit = "dB"
        p = self.peaks
        ln = self.lines
        ds = xr.Dataset(
            {
                "measured_level": (("rpm", "order"), self.measured_db,
                                   {"units": unit, "long_name": f"measured rpm-order map "
                                    f"({self.level_basis})"}),
                "simulated_level": (("rpm", "order"), self.simulated_db,
                                    {"units": unit, "long_name": f"simulated rpm-order map "
                                     f"({self.level_basis})"}),
                "level_difference": (("rpm", "order"), self.difference_db,
                                     {"units": unit, "long_name": "measured minus simulated "
                                      "level (NaN: both more than the peak range below their "
                                      "maximum, or no frame in the bin)"}),
                "measured_order_spectrum": ("order", self.measured_spectrum_db,
                                            {"units": unit, "long_name": "measured order "
                                             "spectrum over the common speed range "
                                             f"({self.level_basis})"}),
                "simulated_order_spectrum": ("order", self.simulated_spectrum_db,
                                             {"units": unit, "long_name": "simulated order "
                                              "spectrum over the common speed range "
                                              f"({self.level_basis})"}),
                "peak_status": ("peak", np.asarray([x.status for x in p], dtype=str),
                                {"long_name": "matched, measured only or simulated only"}),
                "peak_order_measured": ("peak", np.asarray([x.order_measured for x in p]),
                                        {"units": "1", "long_name": "order of the measured "
                                         "peak"}),
                "peak_order_simulated": ("peak", np.asarray([x.order_simulated for x in p]),
                                         {"units": "1", "long_name": "order of the simulated "
                                          "peak"}),
                "peak_level_measured": ("peak", np.asarray([x.level_measured_db for x in p]),
                                        {"units": unit, "long_name": "measured peak level"}),
                "peak_level_simulated": ("peak", np.asarray([x.level_simulated_db for x in p]),
                                         {"units": unit, "long_name": "simulated peak level"}),
                "peak_level_difference": ("peak", np.asarray([x.level_difference_db
                                                              for x in p]),
                                          {"units": unit, "long_name": "measured minus "
                                           "simulated level (one-sided: against the other "
                                           "record's level at that order)"}),
                "line_frequency": ("line", np.asarray([x.frequency_hz for x in ln]),
                                   {"units": "Hz", "long_name": "frequency-locked line of the "
                                    "measured map"}),
                "line_mode": ("line", np.asarray([x.mode for x in ln], dtype=str),
                              {"long_name": "nearest model mode"}),
                "line_mode_frequency": ("line", np.asarray([x.mode_frequency_hz for x in ln]),
                                        {"units": "Hz", "long_name": "natural frequency of the "
                                         "nearest model mode"}),
                "line_offset": ("line", np.asarray([x.offset for x in ln]),
                                {"units": "1", "long_name": "measured over model frequency "
                                 "minus 1"}),
            },
            coords={"order": ("order", self.order, {"units": "1", "long_name":
                                                     "order of the reference shaft"}),
                    "rpm": ("rpm", self.rpm, {"units": "min-1", "long_name":
                                              "reference speed (bin centre)"})},
            attrs={"Conventions": "CF-1.11", "title": f"{self.measured_name} against "
                   f"{self.simulated_name}", "level_basis": self.level_basis,
                   "level_unit": self.level_unit,
                   "measured_channel": self.measured_channel,
                   "simulated_channel": self.simulated_channel,
                   "measured_units": self.measured_units,
                   "simulated_units": self.simulated_units,
                   "measured_reference": self.measured_reference,
                   "simulated_reference": self.simulated_reference,
                   "rpm_range": np.asarray(self.rpm_range, dtype=float),
                   "order_resolution": float(self.order_resolution),
                   "match_tolerance": float(self.match_tolerance),
                   "summary": self.summary(), "notes": json.dumps(list(self.notes))})
        return cf_dataset(
            ds, title="measured against simulated",
            producer="analysis.comparison.compare_measurements"
        )

    def plot(self, figsize: tuple[float, float] = (8.0, 7.5)) -> Figure:
        """Order spectra of both records (lines marked by status) and the difference map."""
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize, layout="constrained", dpi=100)
        ax, ax2 = fig.subplots(2, 1, height_ratios=(1.0, 1.3))
        ax.plot(self.order, self.measured_spectrum_db, lw=0.8, color="C0",
                label=f"measured ({self.measured_channel}"
                      f"{', ' + self.measured_units if self.measured_units else ''})")
        ax.plot(self.order, self.simulated_spectrum_db, lw=0.8, color="C1",
                label=f"simulated ({self.simulated_channel}"
                      f"{', ' + self.simulated_units if self.simulated_units else ''})")
        styles = {"matched": ("o", "k"), "measured only": ("v", "C0"),
                  "simulated only": ("^", "C1")}
        for status, (mk, col) in styles.items():
            sel = [x for x in self.peaks if x.status == status]
            if not sel:
                continue
            y = [x.level_measured_db if math.isfinite(x.level_measured_db) else
                 x.level_simulated_db for x in sel]
            ax.plot([x.order for x in sel], y, mk, mfc="none", mec=col, ms=7,
                    label=f"{status} ({len(sel)})")
        ax.set_xlim(0, float(self.order[-1]))
        ax.set_xlabel("order of the reference shaft")
        ax.set_ylabel(f"level [{self.level_unit}]")
        ax.set_title(f"order spectra over {self.rpm_range[0]:.0f}–{self.rpm_range[1]:.0f} "
                     f"min⁻¹ (RBW {self.order_resolution:.3g} orders; {self.level_basis})",
                     fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncols=2)
        d = self.difference_db
        finite = d[np.isfinite(d)]
        lim = float(np.clip(np.percentile(np.abs(finite), 98), 6.0, 40.0)) if finite.size \
            else 20.0
        if self.rpm.size > 1:
            mesh = ax2.pcolormesh(self.order, self.rpm, d, shading="nearest", cmap="RdBu_r",
                                  vmin=-lim, vmax=lim, rasterized=True)
            ax2.set_ylabel("reference speed [min⁻¹]")
        else:
            mesh = None
            ax2.plot(self.order, d[0], lw=0.8, color="k")
            ax2.set_ylabel("level difference [dB]")
        if mesh is not None:
            fig.colorbar(mesh, ax=ax2, label="measured − simulated [dB]")
        ax2.set_xlim(0, float(self.order[-1]))
        ax2.set_xlabel("order of the reference shaft")
        ax2.set_title("rpm-order difference map (red: the measurement is louder)", fontsize=8)
        fig.suptitle(f"{self.measured_name} against {self.simulated_name}", fontsize=10)
        return fig


# --------------------------------------------------------------------------- computation


def _db(power: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(np.maximum(power, 1e-300))


def _reference_kw(m: Measurement) -> dict[str, Any]:
    return {"angle": m.angle.values} if m.angle is not None else {"rpm": m.speed_rpm.values}


def _peaks(order: np.ndarray, level: np.ndarray, prominence_db: float, range_db: float,
           min_order: float) -> tuple[np.ndarray, np.ndarray]:
    """Orders and levels of the prominent peaks of a spectrum in dB (quadratic interpolation)."""
    ok = np.isfinite(level)
    if not ok.any():
        return np.zeros(0), np.zeros(0)
    lv = np.where(ok, level, np.nanmin(level[ok]))
    idx, _ = _scipy_peaks(lv, prominence=prominence_db)
    above = ok & (order >= min_order)
    top = float(lv[above].max()) if above.any() else float(lv[ok].max())
    idx = idx[(order[idx] >= min_order) & (lv[idx] >= top - range_db)]
    idx = idx[(idx > 0) & (idx < lv.size - 1)]
    a, b, c = lv[idx - 1], lv[idx], lv[idx + 1]
    den = a - 2 * b + c
    shift = np.where(den != 0, 0.5 * (a - c) / np.where(den != 0, den, 1.0), 0.0)
    step = float(order[1] - order[0]) if order.size > 1 else 0.0
    return order[idx] + shift * step, b - 0.25 * (a - c) * shift


def _match(om: np.ndarray, lm: np.ndarray, os_: np.ndarray, ls: np.ndarray, tol: float,
           order: np.ndarray, spec_m: np.ndarray, spec_s: np.ndarray) -> list[PeakMatch]:
    """Greedy one-to-one matching, closest pairs first."""
    pairs = sorted((abs(a - b), i, j) for i, a in enumerate(om) for j, b in enumerate(os_)
                   if abs(a - b) <= tol + 0.002 * max(a, b))
    used_m: set[int] = set()
    used_s: set[int] = set()
    out: list[PeakMatch] = []
    for _, i, j in pairs:
        if i in used_m or j in used_s:
            continue
        used_m.add(i)
        used_s.add(j)
        out.append(PeakMatch("matched", float(om[i]), float(os_[j]), float(lm[i]),
                             float(ls[j])))
    for i in range(om.size):
        if i not in used_m:
            other = float(np.interp(om[i], order, spec_s))
            out.append(PeakMatch("measured only", float(om[i]), math.nan, float(lm[i]),
                                 math.nan, other))
    for j in range(os_.size):
        if j not in used_s:
            other = float(np.interp(os_[j], order, spec_m))
            out.append(PeakMatch("simulated only", math.nan, float(os_[j]), math.nan,
                                 float(ls[j]), other))
    return sorted(out, key=lambda p: p.order)


def _binned(map_values: np.ndarray, frame_rpm: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Mean power of the frames in each rpm bin (NaN for an empty bin)."""
    out = np.full((edges.size - 1, map_values.shape[-1]), np.nan)
    k = np.clip(np.searchsorted(edges, frame_rpm, side="right") - 1, 0, edges.size - 2)
    inside = (frame_rpm >= edges[0]) & (frame_rpm <= edges[-1])
    for b in range(edges.size - 1):
        sel = inside & (k == b)
        if sel.any():
            out[b] = map_values[sel].mean(axis=0)
    return out


def _line_features(m: Measurement, x: xr.DataArray, resolution_hz: float, fmax: float
                   ) -> np.ndarray | None:
    """Frequency-locked lines of a record's rpm-frequency map (None at constant speed)."""
    rpm = m.speed_rpm.values
    if rpm.max() < _MIN_SPEED_RATIO * max(rpm.min(), 1e-300):
        return None
    res = max(resolution_hz, 1.5 * m.fs * 8 / x.size)
    fmap = rpm_frequency_map(x.values, m.fs, rpm, resolution=res, window="hann", overlap=0.75,
                             amplitude="rms")
    ds = fmap.to_dataset().sel(frequency=slice(0.0, fmax))
    fr = np.asarray(ds["rpm"].values)
    try:
        feats = map_features(ds, frames=fr > 0.02 * float(fr.max()))
    except ValueError:
        return None
    return np.asarray(feats.frequencies, dtype=float)


def simulated_channel_name(simulated: Measurement, name: str | None = None,
                           measured_channel: str | None = None) -> str:
    """The simulated record's channel to compare: ``name``, else the measured channel's name
    when the simulation has it, else its first vibration channel (a virtual sensor, else the
    default force channel, see :func:`analysis.measurement.load_measurement`).

    Raises
    ------
    ValueError
        ``name`` is not a vibration channel of the simulated record (one line naming the
        admissible channels), or the record has none.
    """
    require_instance(simulated, Measurement, "simulated")
    vib = simulated.vibration_channels
    if name is None:
        if measured_channel is not None and measured_channel in vib:
            return measured_channel
        if not vib:
            raise ValueError(f"the simulated record {simulated.name!r} has no vibration, force "
                             f"or transmission-error channel; channels: "
                             f"{list(simulated.signals.data_vars)}")
        return vib[0]
    if name not in vib:
        raise ValueError(f"simulated_channel = {name!r} is not a channel of the simulated "
                         f"record {simulated.name!r}; admissible: {', '.join(vib) or '(none)'}")
    return name


def compare_measurements(
    measured: Measurement,
    simulated: Measurement,
    *,
    channel: str | None = None,
    simulated_channel: str | None = None,
    natural_frequencies_hz: Any = None,
    mode_names: Any = None,
    max_order: float | None = None,
    order_resolution: float = 0.25,
    rpm_bins: int = 30,
    calibrated: bool | None = None,
    prominence_db: float = 6.0,
    peak_range_db: float = 30.0,
    map_resolution_hz: float = 20.0,
) -> MeasuredSimulatedComparison:
    """Compare a measurement with a simulation (or any two records) on common ground.

    Parameters
    ----------
    measured, simulated : Measurement
        The records (:func:`analysis.measurement.load_measurement`); their speed references must
        measure the same shaft.
    channel, simulated_channel : str, optional
        Channels compared (default: the measured one's first vibration channel; for the
        simulation the channel of the same name, else its first: a virtual sensor, else a
        force, see :func:`simulated_channel_name`). The channels' means (a static load, an
        offset) are removed before the order analysis.
    natural_frequencies_hz : array_like, optional
        The model's natural frequencies [Hz] (> 0) for the line comparison (measured lines
        below 0.15 x the lowest of them, near-DC content, are left out).
    mode_names : sequence of str, optional
        Their names (default ``f1, f2, ...``).
    max_order : float, optional
        Highest order compared (default and upper limit: the lower alias-free order of the two
        records at the top common speed).
    order_resolution : float
        Resolution bandwidth of both order analyses [orders], 0.01..10 (default 0.25).
    rpm_bins : int
        Bins of the common rpm grid, 1..500 (fewer when the records have fewer frames).
    calibrated : bool, optional
        Compare absolute levels (dB re 1 unit). Default: when both channels carry the same
        physical unit; False normalises each record to its strongest order line (0 dB) at
        orders of at least twice the order resolution (the near-DC content of a force,
        e.g. its slowly varying static load, is no order line).
    prominence_db, peak_range_db : float
        Peaks of the order spectra: prominence, and range below the strongest [dB].
    map_resolution_hz : float
        Resolution of the rpm-frequency maps whose frequency-locked lines are compared [Hz].

    Returns
    -------
    MeasuredSimulatedComparison

    Raises
    ------
    ValueError
        Parameters out of range (named with the admissible range), speed ranges that do not
        overlap (both stated), calibrated comparison of different units, too few revolutions.
    """
    if not isinstance(measured, Measurement) or not isinstance(simulated, Measurement):
        raise TypeError("measured and simulated must be Measurement objects "
                        "(analysis.measurement.load_measurement)")
    if not (isinstance(order_resolution, int | float) and 0.01 <= order_resolution <= 10):
        raise ValueError(f"order_resolution = {order_resolution!r} is not admissible: "
                         "0.01..10 orders")
    if isinstance(rpm_bins, bool) or not isinstance(rpm_bins, int | np.integer) or not (
            1 <= rpm_bins <= 500):
        raise ValueError(f"rpm_bins = {rpm_bins!r} is not admissible: an integer in 1..500")
    for nm, v, lo_v, hi_v in (("prominence_db", prominence_db, 0.1, 100.0),
                              ("peak_range_db", peak_range_db, 1.0, 300.0),
                              ("map_resolution_hz", map_resolution_hz, 1e-3, 1e6)):
        if not (isinstance(v, int | float) and math.isfinite(v) and lo_v <= v <= hi_v):
            raise ValueError(f"{nm} = {v!r} is not admissible: {lo_v:g}..{hi_v:g}")
    xm = measured.channel(channel)
    xs = simulated.channel(simulated_channel_name(simulated, simulated_channel, str(xm.name)))
    notes: list[str] = []
    um, us = str(xm.attrs.get("units", "1")), str(xs.attrs.get("units", "1"))
    physical = um == us and um.strip().lower() not in _UNCALIBRATED
    if calibrated is None:
        calibrated = physical
        if um != us:
            notes.append(f"the channels measure different quantities (measured "
                         f"{xm.name} in {um!r}, simulated {xs.name} in {us!r}): levels are "
                         "normalised (each record's strongest order line at 0 dB), so the "
                         "level differences compare the shapes of the spectra, not "
                         "absolute levels")
        elif not physical:
            notes.append(f"the channels' unit {um!r} is not a physical one (uncalibrated): "
                         "levels are normalised (each record's strongest order line at 0 dB)")
    elif calibrated and not physical:
        raise ValueError(f"calibrated comparison needs the same physical unit in both records; "
                         f"the measured channel is in {um!r}, the simulated in {us!r}")
    rm, rs = measured.speed_rpm.values, simulated.speed_rpm.values
    lo = max(float(rm.min()), float(rs.min()))
    hi = min(float(rm.max()), float(rs.max()))
    if hi < lo * (1 - 0.02):
        raise ValueError(f"the speed ranges do not overlap: measured {rm.min():.0f}–"
                         f"{rm.max():.0f} min-1, simulated {rs.min():.0f}–{rs.max():.0f} "
                         "min-1; simulate the measured speed range")
    if hi < lo:  # within 2 %: constant speeds that agree
        lo, hi = hi, lo
    if hi < 1.03 * lo:  # a constant speed: the frames within +-3 % of it
        notes.append(f"the common speed range is {lo:.0f}–{hi:.0f} min-1: frames within ± 3 % "
                     "of it are compared")
        lo, hi = lo / 1.03, hi * 1.03
    top = {"measured": float(rm.max()), "simulated": float(rs.max())}
    nyq = min(0.95 * 0.5 * measured.fs * 60.0 / top["measured"],
              0.95 * 0.5 * simulated.fs * 60.0 / top["simulated"])
    if max_order is not None:
        if not (isinstance(max_order, int | float) and 0 < max_order <= 1e5):
            raise ValueError(f"max_order = {max_order!r} is not admissible: 0 < max_order "
                             "<= 1e5")
        if max_order > nyq:
            notes.append(f"max_order {max_order:g} lowered to {nyq:.4g}, the alias-free order "
                         "of the records at their top speed")
        mo = min(float(max_order), nyq)
    else:
        mo = nyq
    if mo <= 2 * order_resolution:
        raise ValueError(f"the alias-free order range (up to {mo:.3g}) is too small for the "
                         f"order resolution {order_resolution:g}")
    spr = 2 * math.ceil(1.28 * mo)
    maps = []
    for m, x, what in ((measured, xm, "measured"), (simulated, xs, "simulated")):
        vals = np.asarray(x.values, dtype=float)
        try:
            om = rpm_order_map(vals - vals.mean(), m.fs, **_reference_kw(m), window="hann",
                               overlap=0.75,
                               amplitude="power", resolution=order_resolution, max_order=mo,
                               samples_per_rev=spr)
        except ValueError as exc:
            raise ValueError(f"{what} record: {exc}") from None
        maps.append(om)
    order = maps[0].order
    keep = order <= mo
    order = order[keep]
    powers = []
    frames = []
    for om in maps:
        vals = np.asarray(om.values, dtype=float)
        if not np.array_equal(om.order[: vals.shape[-1]], maps[0].order[: vals.shape[-1]]):
            vals = np.stack([np.interp(order, om.order, row) for row in vals])
        else:
            vals = vals[:, keep]
        powers.append(vals)
        frames.append(np.asarray(om.rpm, dtype=float))
    # the common range of the frames (a frame's speed is its mean over several revolutions)
    f_lo = max(lo, *(float(f.min()) for f in frames))
    f_hi = min(hi, *(float(f.max()) for f in frames))
    if f_hi > 1.03 * f_lo:
        lo, hi = f_lo, f_hi
    varying = hi >= _MIN_SPEED_RATIO * max(lo, 1e-300)
    inside = [(f >= lo) & (f <= hi) for f in frames]
    for k, (f, what) in enumerate(zip(frames, ("measured", "simulated"), strict=True)):
        if not inside[k].any():  # e.g. a run-up passing quickly through a constant speed
            near = int(np.argmin(np.abs(f - 0.5 * (lo + hi))))
            inside[k] = np.arange(f.size) == near
            notes.append(f"no {what} frame lies in {lo:.0f}–{hi:.0f} min-1: its frame "
                         f"nearest to the middle ({f[near]:.0f} min-1) is used")
    n_common = min(int(x.sum()) for x in inside)
    nb = int(max(1, min(rpm_bins, n_common // 2))) if varying else 1
    edges = np.linspace(lo, hi, nb + 1)
    if nb == 1:
        binned = [pw[x].mean(axis=0)[None, :] for pw, x in zip(powers, inside, strict=True)]
    else:
        binned = [_binned(pw, f, edges) for pw, f in zip(powers, frames, strict=True)]
    spectra = [pw[x].mean(axis=0) for pw, x in zip(powers, inside, strict=True)]
    enbw = float(maps[0].enbw_orders)
    lines_from = order >= 2 * enbw  # the near-DC bins hold no order line
    if not lines_from.any():
        raise ValueError(f"the alias-free order range (up to {mo:.3g}) is too small for the "
                         f"order resolution {order_resolution:g}")
    raw_db = [_db(s) for s in spectra]
    pk = [_peaks(order, s, prominence_db, peak_range_db, min_order=2 * enbw) for s in raw_db]
    if calibrated:
        offsets: tuple[float, ...] = (0.0, 0.0)
        basis = f"calibrated: dB re 1 {um}"
        units = um
    else:  # the strongest line's (interpolated) peak level, else the highest bin
        offsets = tuple(float(lv.max()) if lv.size else float(s[lines_from].max())
                        for (_, lv), s in zip(pk, raw_db, strict=True))
        basis = (f"normalised: each record's strongest order line above order "
                 f"{2 * enbw:.3g} = 0 dB")
        units = "1"
        for (_, lv), what in zip(pk, ("measured", "simulated"), strict=True):
            if not lv.size:
                notes.append(f"the {what} record has no order line above order "
                             f"{2 * enbw:.3g} ({prominence_db:g} dB prominence): its 0 dB is "
                             "its highest level there, not a line")
    pk = [(o, lv - off) for (o, lv), off in zip(pk, offsets, strict=True)]
    spec_db = [s - o for s, o in zip(raw_db, offsets, strict=True)]
    map_db = [_db(b) - o for b, o in zip(binned, offsets, strict=True)]
    # cells where both records are more than peak_range_db below their maximum (above the
    # near-DC bins) are background (noise against round-off): no difference is stated there
    floor = [np.nanmax(d[:, lines_from]) - peak_range_db
             if np.isfinite(d[:, lines_from]).any() else np.inf for d in map_db]
    background = (map_db[0] < floor[0]) & (map_db[1] < floor[1])
    map_db = [np.where(background, np.nan, d) for d in map_db]
    tol = enbw
    peaks = _match(pk[0][0], pk[0][1], pk[1][0], pk[1][1], tol, order, spec_db[0],
                   spec_db[1])
    # frequency-locked lines of the measurement against the model's modes
    fmax = 0.45 * min(measured.fs, simulated.fs)
    lines: list[LineComparison] = []
    unseen: list[tuple[str, float]] = []
    fm = _line_features(measured, xm, map_resolution_hz, fmax)
    if fm is None:
        notes.append("natural-frequency lines not compared: the measured speed does not vary "
                     f"by × {_MIN_SPEED_RATIO:g} (lines and orders cannot be told apart)")
    else:
        fs_lines = _line_features(simulated, xs, map_resolution_hz, fmax)
        fn = (np.asarray(natural_frequencies_hz, dtype=float).ravel()
              if natural_frequencies_hz is not None else np.zeros(0))
        if fn.size and (not np.all(np.isfinite(fn)) or np.any(fn <= 0)):
            raise ValueError("natural_frequencies_hz must be finite and > 0")
        names = (list(mode_names) if mode_names is not None
                 else [f"f{i + 1}" for i in range(fn.size)])
        if len(names) != fn.size:
            raise ValueError(f"mode_names has {len(names)} entries; natural_frequencies_hz "
                             f"has {fn.size}")
        if fn.size:  # near-DC content (drive, rigid-body motion) is no structural line
            fm = fm[fm >= 0.15 * float(fn.min())]
        for f in fm:
            sim = bool(fs_lines is not None and fs_lines.size
                       and np.min(np.abs(fs_lines - f)) <= 0.03 * f)
            if fn.size:
                i = int(np.argmin(np.abs(fn - f)))
                off = float(f / fn[i] - 1.0)
                lines.append(LineComparison(float(f), names[i], float(fn[i]), off,
                                            abs(off) <= LINE_TOLERANCE, sim))
            else:
                lines.append(LineComparison(float(f), "", math.nan, math.nan, False, sim))
        for f, n in zip(fn, names, strict=True):
            if f <= fmax and not any(abs(x.frequency_hz / f - 1) <= LINE_TOLERANCE
                                     for x in lines):
                unseen.append((n, float(f)))
    return MeasuredSimulatedComparison(
        measured_name=measured.name, simulated_name=simulated.name,
        measured_channel=str(xm.name), simulated_channel=str(xs.name),
        measured_reference=measured.reference, simulated_reference=simulated.reference,
        units=units, level_basis=basis, rpm_range=(float(edges[0]), float(edges[-1])),
        order=order, order_resolution=float(maps[0].resolution_orders),
        rpm=0.5 * (edges[1:] + edges[:-1]), measured_db=map_db[0], simulated_db=map_db[1],
        measured_spectrum_db=spec_db[0], simulated_spectrum_db=spec_db[1],
        peaks=tuple(peaks), lines=tuple(lines), unseen_modes=tuple(unseen),
        match_tolerance=float(tol), notes=tuple(notes), measured_units=um, simulated_units=us)
