"""Levels over a run-up, the NVH deliverables of one channel: order cuts, overall level,
waterfall, Campbell diagram and the resonances of the order cuts.

:func:`runup_levels` computes, once, what an NVH suite (Simcenter Testlab, ArtemiS SUITE)
shows first for a run-up or coast-down:

* **order cuts** of chosen orders in dB over rpm (:func:`analysis.orders.order_cuts`:
  angle-domain frames, flat-top window, proportional band = the main lobe), with named
  optional orders (catalogue lines: fault orders, sidebands) added only where the resolution
  separates them from every other cut;
* the **overall level** over rpm (sum of the lines of the rpm-frequency map,
  :func:`analysis.maps.overall_level_from_map`);
* a **waterfall**: spectra of the rpm-frequency map at evenly spaced speeds
  (:class:`Waterfall`);
* the **Campbell** data: the cut orders as rays, natural frequencies and critical speeds
  (:func:`analysis.maps.campbell`);
* the **resonances of the cuts** (:class:`CutPeaks`): local maxima of each cut that rise at
  least ``min_rise_db`` above their surroundings (the peak's prominence), with speed,
  frequency, level, -3 dB width and the natural frequency the order crosses there.

The result (:class:`RunupLevels`) has ``.to_dataset()`` (CF) and ``.plot(kind)``
(:mod:`analysis.runup_level_plots`).

**Resolution.** A cut is right only where its band holds one order (see
``docs/analysis-spectra-orders.md``). The resolution bandwidth is ``order_resolution`` when
given, else ``max(min(1/4, d/4), min(d/4, ENBW_lines * 32 / R), ENBW_lines * 8 / R)``
orders, ``d`` the smallest distance between the required orders (and from order 0), ``R``
the revolutions of the record: 1/4 order (or ``d/4``, four resolutions between the closest
orders, as :func:`analysis.order_resolution.default_order_resolution`) on a long record;
on a short or fast run-up frames of at most 1/32 of the revolutions as long as the required
orders stay ``d/4`` apart (a frame of a fast run-up spans a wide speed range: shorter frames
resolve a resonance crossed quickly), and never more than 1/8 of them. Two cuts are separated
when their orders are at least ``2 h / ENBW_lines`` resolutions apart (``h`` the main-lobe
half width in lines: 2.65 resolutions for the flat-top window), where neither band reaches
the other's main lobe.

References
----------
A. Brandt, *Noise and Vibration Analysis*, Wiley 2011: ch. 12 (order tracking, order cuts,
overall level from spectral lines, waterfall and Campbell plots).
HEAD acoustics, *Order analysis in ArtemiS SUITE* (application note); Siemens Simcenter
Testlab documentation of order sections and the Campbell diagram: the deliverables, not code.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis import runup_level_plots as rp
from analysis.cf import cf_dataset
from analysis.checks import require_finite, uniform_rate
from analysis.cut_plan import (
    CUT_FRAMES,
    CUT_WINDOW,
    MIN_CUT_FRAMES,
    cut_order_list,
    default_cut_resolution,
    enbw_and_lobe,
    select_cut_orders,
    separation_orders,
)
from analysis.cut_resonances import CutPeaks, cut_resonances
from analysis.maps import (
    Campbell,
    OverallLevel,
    RpmFrequencyMap,
    campbell,
    overall_level_from_map,
    rpm_frequency_map,
)
from analysis.order_resolution import (
    OrderBandWarning,
    default_order_resolution,
    optional_positive,
)
from analysis.orders import OrderCut, order_cuts
from analysis.waterfall import Waterfall, level_reference, waterfall_from_map

if TYPE_CHECKING:
    import xarray as xr
    from matplotlib.figure import Figure

__all__ = [  # CUT_* and separation_orders: from analysis.cut_plan
    "CUT_FRAMES",
    "CUT_WINDOW",
    "MIN_CUT_FRAMES",
    "MIN_GIVEN_FRAMES",
    "CutPeaks",
    "RunupLevels",
    "Waterfall",
    "finest_order_resolution",
    "runup_levels",
    "separation_orders",
]

MIN_GIVEN_FRAMES = 4
"""A given ``order_resolution`` must leave at least this many independent frames."""

_STANDSTILL = 0.02  # samples below 2 % of the top speed are standstill (as order_cuts)


def finest_order_resolution(revolutions: float) -> float:
    """Finest ``order_resolution`` [orders] a record of ``revolutions`` admits:
    ``ENBW_lines * MIN_GIVEN_FRAMES / revolutions`` (frames of ``ENBW / resolution``
    revolutions, at least :data:`MIN_GIVEN_FRAMES` of them; flat-top window).

    Parameters
    ----------
    revolutions : float
        Revolutions of the reference shaft while it turns.

    Returns
    -------
    float
    """
    enbw, _ = enbw_and_lobe()
    return enbw * MIN_GIVEN_FRAMES / max(float(revolutions), 1e-300)


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class RunupLevels:
    """Order cuts, overall level, waterfall, Campbell data and cut resonances of one channel.

    Attributes
    ----------
    name, units : str
        Signal name and units (levels are dB re 1 ``units``).
    cuts : OrderCut
        rms order cuts in dB, one row per cut order (:attr:`order_names`).
    order_names : tuple of str
        Name of every cut (names of coinciding orders joined by ``" = "``).
    required : tuple of bool
        Per cut: one of the ``orders`` asked for (True) or an optional order (False).
    overall : OverallLevel
        Overall rms level in dB over the frames of the rpm-frequency map.
    waterfall : Waterfall
        Spectra of the map at evenly spaced speeds.
    campbell : Campbell
        The cut orders as rays with the natural frequencies and critical speeds.
    natural_names : tuple of str
        Names of the natural frequencies.
    peaks : CutPeaks
        Resonances of the cuts, strongest level first (empty at constant speed).
    resolution : float
        Resolution bandwidth of the cut frames [orders].
    revolutions : float
        Revolutions of the reference shaft while it turns (above 2 % of the top speed).
    speed_range : (float, float)
        Lowest and highest frame speed of the cuts [min-1].
    varying_speed : bool
        The speed range spans at least ``min_speed_ratio``: levels are shown over rpm and
        cut maxima are resonances; otherwise over time, without resonances.
    dropped : tuple of (str, float, str)
        Optional orders not cut: name, order, why (``"0.673 orders from 1× mesh"``,
        ``"closer than 9.6 orders to order 0"``, ``"above order 150, ..."``).
    notes : tuple of str
        What else the computation decided (band overlaps of required orders, resolution).
    min_rise_db : float
        Prominence a cut maximum needs to count as a resonance [dB].
    dynamic_range_db : float
        Cut maxima more than this below the highest cut level are not resonances [dB].
    natural_tolerance : float
        Relative tolerance of the natural-frequency match of a resonance.
    min_speed_ratio : float
        Highest over lowest frame speed from which on the record counts as a run-up.
    """

    name: str
    units: str
    cuts: OrderCut
    order_names: tuple[str, ...]
    required: tuple[bool, ...]
    overall: OverallLevel
    waterfall: Waterfall
    campbell: Campbell
    natural_names: tuple[str, ...]
    peaks: CutPeaks
    resolution: float
    revolutions: float
    speed_range: tuple[float, float]
    varying_speed: bool
    dropped: tuple[tuple[str, float, str], ...] = ()
    notes: tuple[str, ...] = ()
    min_rise_db: float = 6.0
    dynamic_range_db: float = 40.0
    natural_tolerance: float = 0.05
    min_speed_ratio: float = 1.3

    @property
    def orders(self) -> np.ndarray:
        """The cut orders."""
        return self.cuts.orders

    @property
    def separation(self) -> float:
        """Smallest distance [orders] of two separated cuts at :attr:`resolution`
        (:func:`separation_orders`)."""
        return separation_orders(self.resolution, CUT_WINDOW)

    @property
    def level_reference(self) -> str:
        """Reference of the dB levels, e.g. ``"1 N"`` (``"1"`` for a dimensionless signal)."""
        return level_reference(self.units)

    def order_statistics(self) -> list[tuple[float, str, float, float, float]]:
        """Per cut: ``(order, name, max level [dB], speed of the max [min-1], median [dB])``
        over the frames where the band lies inside the analysed range (NaN if none)."""
        out = []
        for i, o in enumerate(self.cuts.orders):
            row = np.asarray(self.cuts.values[i], dtype=float)
            ok = np.isfinite(row)
            if not ok.any():
                out.append((float(o), self.order_names[i], np.nan, np.nan, np.nan))
                continue
            j = int(np.flatnonzero(ok)[np.argmax(row[ok])])
            out.append((float(o), self.order_names[i], float(row[j]), float(self.cuts.rpm[j]),
                        float(np.median(row[ok]))))
        return out

    def overall_maximum(self) -> tuple[float, float]:
        """Highest overall level [dB] and its speed [min-1]."""
        v = np.asarray(self.overall.values, dtype=float)
        j = int(np.nanargmax(v))
        return float(v[j]), float(self.overall.rpm[j])

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset: ``cut_level(order, time)``, ``overall_level(map_time)``,
        ``waterfall_level(trace, frequency)``, ``critical_rpm(order, mode)`` and the cut
        resonances along ``resonance``; settings in the attributes."""
        import xarray as xr

        ref = self.level_reference
        c, p, w = self.cuts, self.peaks, self.waterfall
        ds = xr.Dataset(
            {
                "cut_level": (("order", "time"), np.asarray(c.values, dtype=float),
                              {"units": "1", "long_name": f"rms level in the order band "
                               f"(dB re {ref})"}),
                "overall_level": ("map_time", np.asarray(self.overall.values, dtype=float),
                                  {"units": "1", "long_name": "overall rms level "
                                   f"{self.overall.frequency_range[0]:g}-"
                                   f"{self.overall.frequency_range[1]:g} Hz (dB re {ref})"}),
                "waterfall_level": (("trace", "frequency"), w.level_db,
                                    {"units": "1", "long_name": f"{w.amplitude} level of the "
                                     f"waterfall trace (dB re {w.level_reference})"}),
                "critical_rpm": (("order", "mode"), self.campbell.critical_rpm,
                                 {"units": "min-1", "long_name": "speed where the order crosses "
                                  "the natural frequency"}),
                "natural_frequency": ("mode", self.campbell.natural_frequencies_hz,
                                      {"units": "Hz", "long_name": "natural frequency"}),
                "resonance_order": ("resonance", p.order,
                                    {"units": "1", "long_name": "order of the resonating cut"}),
                "resonance_rpm": ("resonance", p.rpm,
                                  {"units": "min-1", "long_name": "speed of the cut maximum"}),
                "resonance_frequency": ("resonance", p.frequency_hz,
                                        {"units": "Hz", "long_name": "frequency of the cut "
                                         "maximum (order x speed / 60)"}),
                "resonance_level": ("resonance", p.level_db,
                                    {"units": "1", "long_name": f"level of the cut maximum "
                                     f"(dB re {ref})"}),
                "resonance_rise": ("resonance", p.rise_db,
                                   {"units": "1", "long_name": "prominence of the cut maximum "
                                    "(dB)"}),
                "resonance_width": ("resonance", p.width_rpm,
                                    {"units": "min-1", "long_name": "-3 dB speed span of the "
                                     "cut maximum"}),
                "resonance_mode": ("resonance", np.asarray(p.mode, dtype=str),
                                   {"units": "1", "long_name": "natural frequency the order "
                                    "crosses there"}),
            },
            coords={
                "order": ("order", np.asarray(c.orders, dtype=float),
                          {"units": "1", "long_name": "cut order (cycles per revolution)"}),
                "order_name": ("order", np.asarray(self.order_names, dtype=str),
                               {"units": "1", "long_name": "name of the cut order"}),
                "time": ("time", np.asarray(c.time, dtype=float),
                         {"units": "s", "long_name": "cut frame centre time"}),
                "rpm": ("time", np.asarray(c.rpm, dtype=float),
                        {"units": "min-1", "long_name": "shaft speed at the cut frame centre"}),
                "map_time": ("map_time", np.asarray(self.overall.time, dtype=float),
                             {"units": "s", "long_name": "map frame centre time"}),
                "map_rpm": ("map_time", np.asarray(self.overall.rpm, dtype=float),
                            {"units": "min-1", "long_name": "shaft speed at the map frame "
                             "centre"}),
                "trace": ("trace", np.arange(len(w)), {"units": "1",
                                                       "long_name": "waterfall trace"}),
                "trace_rpm": ("trace", w.rpm, {"units": "min-1",
                                               "long_name": "speed of the waterfall trace"}),
                "frequency": ("frequency", w.frequency, {"units": "Hz",
                                                          "long_name": "frequency"}),
                "mode": ("mode", np.arange(self.campbell.natural_frequencies_hz.size),
                         {"units": "1", "long_name": "mode index"}),
                "mode_name": ("mode", np.asarray(self.natural_names, dtype=str),
                              {"units": "1", "long_name": "name of the natural frequency"}),
                "resonance": ("resonance", np.arange(len(p)),
                              {"units": "1", "long_name": "cut resonance, strongest first"}),
            },
            attrs={
                "signal": self.name,
                "signal_units": self.units,
                "order_resolution": float(self.resolution),
                "order_band": float(c.bandwidth),
                "cut_window": c.window,
                "map_resolution_hz": float(w.resolution_hz),
                "revolutions": float(self.revolutions),
                "min_rise_db": float(self.min_rise_db),
                "dynamic_range_db": float(self.dynamic_range_db),
                "natural_tolerance": float(self.natural_tolerance),
                "varying_speed": int(self.varying_speed),
                "min_speed_ratio": float(self.min_speed_ratio),
                "dropped_orders": "; ".join(f"{n} ({o:.6g}): {why}"
                                            for n, o, why in self.dropped),
                "comment": " ".join(self.notes),
            },
        )
        return cf_dataset(ds, title=f"run-up levels of {self.name}",
                          producer="analysis.runup_levels.runup_levels",
                          inputs={"signal": self.name, "speed_reference": c.reference})

    def plot(self, kind: str = "cuts", **kwargs: Any) -> Figure:
        """Figure of ``kind`` ``"cuts"`` (order cuts and overall level), ``"waterfall"`` or
        ``"campbell"`` (see :mod:`analysis.runup_level_plots`)."""
        builders: dict[str, Callable[..., Figure]] = {
            "cuts": rp.order_cuts_levels_figure, "waterfall": rp.waterfall_figure,
            "campbell": rp.campbell_levels_figure}
        if kind not in builders:
            raise ValueError(f"kind = {kind!r}; admissible: {', '.join(builders)}")
        return builders[kind](self, **kwargs)


# --------------------------------------------------------------------------- computation


def _speed_per_sample(fs: float, rpm: Any, angle: Any, n: int) -> np.ndarray:
    """Speed [min-1] per sample from ``rpm`` or ``angle`` (checked lengths and values)."""
    if (rpm is None) == (angle is None):
        raise ValueError("give the speed reference as rpm= or angle= (one of them)")
    ref = np.asarray(rpm if rpm is not None else angle, dtype=float)
    name = "rpm" if rpm is not None else "angle"
    if ref.ndim != 1 or ref.size != n:
        raise ValueError(f"{name} must be 1-D with one value per sample ({n}), got shape "
                         f"{ref.shape}")
    require_finite(ref, name)
    if rpm is not None:
        return np.abs(ref)
    return np.abs(np.gradient(ref)) * fs * 60.0 / (2.0 * np.pi)


def _revolutions(speed: np.ndarray, fs: float) -> float:
    """Revolutions while the shaft turns above 2 % of its top speed."""
    moving = speed > _STANDSTILL * float(speed.max())
    return float(np.sum(speed[moving]) / fs / 60.0)


def runup_levels(
    x: Any,
    fs: float | None = None,
    rpm: Any = None,
    orders: Any = None,
    *,
    angle: Any = None,
    time: Any = None,
    order_names: Sequence[str] | None = None,
    optional_orders: Mapping[str, float] | None = None,
    order_resolution: float | None = None,
    overlap: float = 0.75,
    frequency_map: RpmFrequencyMap | None = None,
    map_resolution: float | None = None,
    frequency_range: tuple[float, float] | None = None,
    natural_frequencies_hz: Any = (),
    natural_names: Sequence[str] | None = None,
    natural_tolerance: float = 0.05,
    min_rise_db: float = 6.0,
    dynamic_range_db: float = 40.0,
    min_speed_ratio: float = 1.3,
    waterfall_traces: int = 24,
    units: str | None = None,
    name: str | None = None,
) -> RunupLevels:
    """Order cuts, overall level, waterfall, Campbell data and cut resonances of one channel.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One channel (1-D), sampled at ``fs``.
    fs : float, optional
        Sample rate [Hz] (or give ``time``).
    rpm : array_like, optional
        Speed of the reference shaft [min-1] per sample.
    orders : array_like
        Orders to cut (> 0, multiples of the reference shaft): always cut.
    angle : array_like, optional
        Reference-shaft angle [rad] per sample instead of ``rpm`` (a tacho's; more accurate).
    time : array_like, optional
        Uniform time axis [s] instead of ``fs``.
    order_names : sequence of str, optional
        A name per order (default ``"order 24"``).
    optional_orders : mapping of str to float, optional
        Named orders (catalogue lines: fault orders, sidebands) cut only where the resolution
        separates them from every order cut before them (required orders first, then these
        in their order); the others are listed in :attr:`RunupLevels.dropped` with the reason.
    order_resolution : float, optional
        Resolution bandwidth of the cut frames [orders] (default: see the module docstring).
        A given resolution must leave at least :data:`MIN_GIVEN_FRAMES` frames of
        ``ENBW_lines / order_resolution`` revolutions in the record.
    overlap : float, default 0.75
        Overlap of the cut frames (and of a map computed here).
    frequency_map : RpmFrequencyMap, optional
        A single-channel map of ``x`` already computed (e.g. for a sonogram); default: a Hann
        map with ``map_resolution`` [Hz] (default of :func:`analysis.maps.rpm_frequency_map`).
    map_resolution : float, optional
        Resolution bandwidth of the map computed here [Hz].
    frequency_range : (float, float), optional
        Band of the overall level and the waterfall [Hz] (default: the whole map).
    natural_frequencies_hz : array_like
        Natural frequencies [Hz] for the Campbell data and the cut resonances.
    natural_names : sequence of str, optional
        Their names (default ``f1, f2, ...``).
    natural_tolerance : float, default 0.05
        A cut maximum at speed ``n`` is attributed to the natural frequency ``f_i`` when the
        critical speed ``60 f_i / order`` lies within ``natural_tolerance`` of itself plus
        half the maximum's -3 dB width of ``n``.
    min_rise_db : float, default 6
        Prominence a cut maximum needs to count as a resonance [dB].
    dynamic_range_db : float, default 40
        A cut maximum more than this below the highest level of all cuts is background (noise
        floor), not a resonance [dB].
    min_speed_ratio : float, default 1.3
        A record whose highest cut speed is below this multiple of its lowest is treated as
        constant speed: no cut resonances (levels over time).
    waterfall_traces : int, default 24
        Spectra in the waterfall.
    units, name : str, optional
        Metadata of ``x`` (default from a DataArray's attributes, else ``"1"`` and ``"x"``).

    Returns
    -------
    RunupLevels

    Raises
    ------
    ValueError
        Bad input (named), or an ``order_resolution`` finer than the record allows (the
        message gives the finest admissible one).

    Notes
    -----
    A cut's level is ``sqrt(sum_k G_k / ENBW_lines)`` over the lines of the band (the rms of
    a sinusoid whose main lobe lies in the band); the overall level the same sum over every
    line of the map in ``frequency_range`` (Brandt 2011, sec. 10.3).
    """
    if hasattr(x, "dims") and hasattr(x, "values"):
        attrs = dict(getattr(x, "attrs", {}))
        units = units if units is not None else str(attrs.get("units", "1"))
        name = name if name is not None else str(getattr(x, "name", None) or "x")
        if time is None and fs is None and "time" in getattr(x, "coords", {}):
            time = np.asarray(x["time"].values, dtype=float)
        x = x.values
    sig = np.asarray(x, dtype=float)
    if sig.ndim != 1:
        raise ValueError(f"x must be one channel (1-D), got shape {sig.shape}")
    require_finite(sig, "x")
    if fs is None:
        if time is None:
            raise ValueError("give the sample rate fs or the time axis time")
        fs = uniform_rate(time)
    fs = float(optional_positive(fs, "fs", "Hz"))
    units = units or "1"
    name = name or "x"
    for value, what in ((natural_tolerance, "natural_tolerance"), (min_rise_db, "min_rise_db"),
                        (dynamic_range_db, "dynamic_range_db"),
                        (min_speed_ratio, "min_speed_ratio")):
        optional_positive(value, what, "")
    if isinstance(waterfall_traces, bool) or not isinstance(waterfall_traces, int) \
            or not 2 <= waterfall_traces <= 1000:
        raise ValueError(f"waterfall_traces = {waterfall_traces!r} must be an integer in "
                         "2..1000")
    fn = np.atleast_1d(np.asarray(natural_frequencies_hz, dtype=float))
    fn_names = (list(natural_names) if natural_names is not None
                else [f"f{i + 1}" for i in range(fn.size)])
    if len(fn_names) != fn.size:
        raise ValueError(f"natural_names: {len(fn_names)} names for {fn.size} frequencies")
    speed = _speed_per_sample(fs, rpm, angle, sig.size)
    if not float(speed.max()) > 0:
        raise ValueError("the reference shaft does not turn (speed 0 everywhere)")
    revs = _revolutions(speed, fs)
    enbw, _ = enbw_and_lobe()
    items, notes = cut_order_list(orders, order_names, optional_orders)
    required = np.asarray([o for o, _, r in items if r])
    given = optional_positive(order_resolution, "order_resolution", "orders")
    if given is not None:
        finest = finest_order_resolution(revs)
        if given < finest:
            raise ValueError(
                f"order_resolution = {given:g} orders needs frames of {enbw / given:.4g} "
                f"revolutions, the record holds {revs:.4g}: admissible >= {finest:.3g} orders "
                f"(at least {MIN_GIVEN_FRAMES} frames)")
        res = given
    else:
        res = default_cut_resolution(required, revs, enbw)
        if res > default_order_resolution(required, None):
            notes.append(f"order resolution {res:.3g} orders: the record holds {revs:.4g} "
                         f"revolutions; a cut frame ({enbw / res:.3g} revolutions) spans at "
                         f"most 1/{CUT_FRAMES} of them where the orders stay separated, "
                         f"never more than 1/{MIN_CUT_FRAMES}")
    reach = separation_orders(res)
    top_order = 0.5 * fs * 60.0 / float(speed.max()) / 1.25 - 0.5 * reach
    kept, dropped = select_cut_orders(items, reach, top_order)
    if not kept:
        raise ValueError(f"no order to cut: every order lies above the highest order "
                         f"analysable at the top speed ({top_order:.4g})")
    ref = {"angle": angle} if angle is not None else {"rpm": rpm}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", OrderBandWarning)
        cut = order_cuts(sig, fs, **ref, orders=[o for o, _, _ in kept],
                         lines=[(n, o) for o, n, _ in kept], window=CUT_WINDOW, resolution=res,
                         overlap=overlap, amplitude="rms", scale="dB", units=units, name=name)
    notes += [str(w.message) for w in caught if issubclass(w.category, OrderBandWarning)]
    notes += list(cut.notes)
    # orders whose band leaves the analysed range everywhere
    alive = np.isfinite(np.asarray(cut.values, dtype=float)).any(axis=-1)
    names = [n for _, n, _ in kept]
    required_cut = [r for _, _, r in kept]
    if not alive.all():
        for i in np.flatnonzero(~alive):
            dropped.append((names[i], float(cut.orders[i]), "its band lies above the analysed "
                            "orders at every speed"))
        if not alive.any():
            raise ValueError("no order cut holds a level: the cut orders lie above the "
                             "analysed orders at every speed")
        cut = dataclasses.replace(cut, orders=cut.orders[alive], values=cut.values[alive])
        names = [n for n, a in zip(names, alive, strict=True) if a]
        required_cut = [r for r, a in zip(required_cut, alive, strict=True) if a]
    m = frequency_map
    if m is None:
        m = rpm_frequency_map(sig, fs, **ref, resolution=map_resolution, window="hann",
                              overlap=overlap, amplitude="rms", units=units, name=name)
    elif not isinstance(m, RpmFrequencyMap) or m.values.ndim != 2:
        raise ValueError("frequency_map must be a single-channel RpmFrequencyMap")
    f_hi = float(m.frequency[-1])
    band = (0.0, f_hi) if frequency_range is None else (float(frequency_range[0]),
                                                        min(float(frequency_range[1]), f_hi))
    overall = overall_level_from_map(m, frequency_range=band, scale="dB")
    waterfall = waterfall_from_map(m, band[1], waterfall_traces)
    r = np.asarray(cut.rpm, dtype=float)
    lo, hi = float(np.nanmin(r)), float(np.nanmax(r))
    varying = hi >= min_speed_ratio * max(lo, 1e-300)
    crange = (lo, hi) if varying else (0.0, 1.25 * hi)
    camp = campbell(fn[fn > 0], cut.orders, crange)
    keep_fn = [i for i in range(fn.size) if fn[i] > 0]
    peaks = (cut_resonances(cut, names, fn[keep_fn], [fn_names[i] for i in keep_fn],
                            min_rise_db=float(min_rise_db), tolerance=float(natural_tolerance),
                            dynamic_range_db=float(dynamic_range_db))
             if varying else CutPeaks.empty())
    return RunupLevels(
        name=name, units=units, cuts=cut, order_names=tuple(names),
        required=tuple(bool(r) for r in required_cut), overall=overall,
        waterfall=waterfall, campbell=camp,
        natural_names=tuple(n for n, f in zip(fn_names, fn, strict=True) if f > 0),
        peaks=peaks, resolution=float(res), revolutions=revs, speed_range=(lo, hi),
        varying_speed=bool(varying), dropped=tuple(dropped), notes=tuple(notes),
        min_rise_db=float(min_rise_db), dynamic_range_db=float(dynamic_range_db),
        natural_tolerance=float(natural_tolerance), min_speed_ratio=float(min_speed_ratio))
