"""The NVH pages of a report: order cuts, overall level, waterfall and Campbell diagram.

What a Simcenter Testlab or ArtemiS user opens a run-up report for first: the order cuts of
the mesh orders in dB over rpm with the overall level, a waterfall and a Campbell diagram with
the order rays and the model's natural frequencies. This module builds these pages for any
report -- simulated runs and studies (:mod:`gearvib.report.sections`: the housing acceleration
of every ``[[sensor]]`` and the tooth force) and measurements
(:mod:`gearvib.report.measured`) -- from :class:`SignalLevels`, each holding the
:class:`analysis.runup_levels.RunupLevels` of one signal (computed in :mod:`analysis`; the
figures come from :mod:`analysis.runup_level_plots`).

* :func:`cut_orders` chooses the orders to cut: the 1st to 3rd harmonic of every mesh
  frequency and the orders asked for (always cut), and the catalogue's named sideband, fault,
  planet-pass and shaft orders (cut where the resolution separates them; the others are
  listed with the reason).
* :func:`signal_levels` computes one signal's levels (a failure becomes a note, except a
  resolution the user asked for that the run cannot give, which is an error naming it).
* :func:`levels_blocks` writes the section: per signal a figure of the cuts with the overall
  level, the table of the cut levels, the table of the cut resonances and, for the primary
  signal, the waterfall and the Campbell diagram.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.runup_level_plots import (
    MAX_CURVES,
    campbell_levels_figure,
    order_cuts_levels_figure,
    waterfall_figure,
)
from analysis.runup_levels import RunupLevels, runup_levels
from analysis.waterfall import level_reference
from gearvib.report.blocks import Block
from gearvib.report.study import AnalysisSettings
from gearvib.report.wording import span

__all__ = [
    "LEVELS_SECTION_ID",
    "LEVELS_TITLE",
    "MARKED_RESONANCES",
    "MESH_HARMONICS",
    "SignalLevels",
    "catalogue_orders",
    "constant_speed_text",
    "cut_level_rows",
    "cut_orders",
    "cut_resonance_rows",
    "levels_blocks",
    "report_note",
    "signal_levels",
]

LEVELS_SECTION_ID = "order-cuts"
"""Section id (HTML anchor, PDF destination) of the NVH pages."""

LEVELS_TITLE = "Order cuts, overall level, waterfall and Campbell diagram"
"""Title of the NVH section."""

MESH_HARMONICS = 3
"""Mesh harmonics always cut (1x, 2x, 3x of every mesh frequency)."""

MARKED_RESONANCES = 5
"""The strongest cut resonances numbered in the figures and listed on the summary page."""

_FAULTS = ("sun_fault", "planet_fault", "ring_fault", "gear_fault")


@dataclass(frozen=True)
class SignalLevels:
    """The NVH pages' data of one signal.

    Attributes
    ----------
    case : str
        Case (or measurement) name.
    signal : str
        What the signal is, e.g. ``"housing acceleration top"``, ``"tooth force sun-planet1"``.
    levels : RunupLevels or None
        The levels (None when they could not be computed: see :attr:`note`).
    primary : bool
        The signal the summary page ranks (the first housing sensor, else the tooth force or
        the measured channel); it also gets the waterfall and the Campbell diagram.
    note : str
        Why there are no levels.
    reference : str
        The reference shaft of the orders (e.g. ``"input shaft sun"``).
    """

    case: str
    signal: str
    levels: RunupLevels | None
    primary: bool = True
    note: str = ""
    reference: str = "input shaft"

    @property
    def units(self) -> str:
        """Units of the signal (``""`` without levels)."""
        return self.levels.units if self.levels is not None else ""

    @property
    def level_unit(self) -> str:
        """``"dB re 1 N"``."""
        return f"dB re {level_reference(self.units)}"


# --------------------------------------------------------------------------- orders


def catalogue_orders(catalogue: Any, *, reference_member: str = "") -> dict[str, float]:
    """Named optional cut orders from a kinematic catalogue, in priority order.

    The first sideband on each side of the first mesh harmonic (planet-pass sidebands of a
    planetary mesh, shaft-rate sidebands of a fixed-axis mesh), the local-fault orders of every
    member, the planet-pass order and the reference shaft's order; only lines a sensor on the
    catalogue's member can see.

    Parameters
    ----------
    catalogue : analysis.catalogue.KinematicCatalogue
        The catalogue (orders of the reference shaft).
    reference_member : str
        Member whose rotation is order 1 (named ``"<member> shaft"``).

    Returns
    -------
    dict of str to float
        ``{name: order}``.
    """
    if catalogue is None:
        return {}
    fam = np.asarray(catalogue.family).astype(str)
    h = np.asarray(catalogue.harmonic)
    sb = np.asarray(catalogue.sideband)
    member = np.asarray(catalogue.member).astype(str)
    formula = np.asarray(catalogue.formula).astype(str)
    order = np.asarray(catalogue.order, dtype=float)
    vis = np.asarray(catalogue.visible, dtype=bool)
    meshes = {m for f, m in zip(fam, member, strict=True) if f == "mesh"}
    several = len(meshes) > 1
    out: dict[str, float] = {}

    def add(name: str, o: float) -> None:
        if name in out or not np.isfinite(o) or o <= 0:
            return
        out[name] = float(o)

    for family in ("sideband", "shaft_sideband"):
        for m in sorted({member[i] for i in np.flatnonzero((fam == family) & (h == 1) & vis)}):
            for sign in (-1, 1):
                rows = np.flatnonzero((fam == family) & (h == 1) & vis & (member == m)
                                      & (np.sign(sb) == sign))
                if rows.size:
                    j = int(rows[np.argmin(np.abs(sb[rows]))])
                    add(formula[j] + (f" ({m})" if several else ""), order[j])
    for i in np.flatnonzero(np.isin(fam, _FAULTS) & (h == 1) & vis):
        add(f"{member[i]} fault", order[i])
    for i in np.flatnonzero((fam == "planet_pass") & (h == 1) & vis):
        add("planet pass" + (f" ({member[i]})" if several else ""), order[i])
    if reference_member:
        for i in np.flatnonzero((fam == "shaft") & (h == 1) & (member == reference_member)):
            add(f"{reference_member} shaft", order[i])
    return out


def cut_orders(mesh_orders: Sequence[tuple[str, float]], extra: Sequence[float] = ()
               ) -> tuple[list[float], list[str]]:
    """The orders always cut: 1x to 3x of every mesh frequency and the orders asked for.

    Parameters
    ----------
    mesh_orders : sequence of (str, float)
        Name of each mesh frequency (``"mesh"``, ``"stage 2"``) and its order (mesh cycles per
        revolution of the reference shaft).
    extra : sequence of float
        Orders asked for (``--orders``), named ``"order 24"``.

    Returns
    -------
    orders, names : list of float, list of str
    """
    orders, names = [], []
    several = len(mesh_orders) > 1
    for gname, o in mesh_orders:
        for k in range(1, MESH_HARMONICS + 1):
            orders.append(k * float(o))
            names.append(f"{k}× mesh" + (f" ({gname})" if several else ""))
    for o in extra:
        orders.append(float(o))
        names.append(f"order {float(o):g}")
    return orders, names


def signal_levels(x: Any, fs: float, *, case: str, signal: str, mesh_orders: Sequence[
        tuple[str, float]], settings: AnalysisSettings, catalogue: Any = None,
                  reference_member: str = "", angle: Any = None, rpm: Any = None,
                  natural_frequencies_hz: Any = (), natural_names: Sequence[str] = (),
                  frequency_map: Any = None, frequency_range: tuple[float, float] | None = None,
                  units: str = "1", primary: bool = True, reference: str = "input shaft",
                  min_speed_ratio: float = 1.3,
                  named_orders: Sequence[tuple[str, float]] = ()) -> SignalLevels:
    """Levels of one signal for the NVH pages.

    Parameters
    ----------
    x : array_like
        The signal (one channel) at ``fs``.
    fs : float
        Sample rate [Hz].
    case, signal : str
        Case name and what the signal is (for captions and table names).
    mesh_orders : sequence of (str, float)
        Mesh frequencies as orders of the reference shaft (:func:`cut_orders`).
    settings : AnalysisSettings
        ``cut_orders`` (orders asked for), ``order_resolution`` (0: automatic),
        ``map_overlap``, ``threshold_db`` (the rise of a cut resonance), ``tolerance``.
    catalogue : KinematicCatalogue, optional
        Its named orders are cut where they are separated (:func:`catalogue_orders`).
    reference_member : str
        Member whose rotation is order 1.
    angle, rpm : array_like
        Reference-shaft angle [rad] or speed [min-1] per sample.
    natural_frequencies_hz, natural_names
        The model's natural frequencies and their names.
    frequency_map : RpmFrequencyMap, optional
        A map of ``x`` already computed (the sonogram's); else one is computed with the
        report's map settings.
    frequency_range : (float, float), optional
        Band of the overall level and the waterfall [Hz].
    units : str
        Units of ``x``.
    primary : bool
        See :class:`SignalLevels`.
    reference : str
        The reference shaft, for captions.
    min_speed_ratio : float
        Speed ratio below which the record counts as constant speed.
    named_orders : sequence of (str, float)
        Further orders always cut, with their names (e.g. the order rays a map shows when
        there is no gear set).

    Returns
    -------
    SignalLevels

    Raises
    ------
    ValueError
        ``order_resolution`` finer than the run allows (the message gives the finest
        admissible); other failures become :attr:`SignalLevels.note`.
    """
    orders, names = cut_orders(mesh_orders, settings.cut_orders)
    for n, o in named_orders:
        if not any(abs(o - v) <= 1e-6 * max(1.0, o) for v in orders):
            orders.append(float(o))
            names.append(str(n))
    if not orders:
        raise ValueError("no order to cut: give mesh orders, named orders or cut_orders")
    optional = catalogue_orders(catalogue, reference_member=reference_member)
    try:
        lv = runup_levels(
            x, fs, rpm=rpm, angle=angle, orders=orders, order_names=names,
            optional_orders=optional, order_resolution=settings.order_resolution or None,
            overlap=min(max(settings.map_overlap, 0.5), 0.9), frequency_map=frequency_map,
            map_resolution=settings.map_resolution_hz, frequency_range=frequency_range,
            natural_frequencies_hz=natural_frequencies_hz, natural_names=list(natural_names),
            natural_tolerance=max(settings.tolerance, 0.05), min_rise_db=settings.threshold_db
            or 6.0, min_speed_ratio=min_speed_ratio, units=units, name=signal)
    except ValueError as exc:
        if str(exc).startswith("order_resolution"):
            raise ValueError(f"{case}, {signal}: {exc} (--order-resolution)") from None
        return SignalLevels(case, signal, None, primary, f"no order cuts: {exc}", reference)
    return SignalLevels(case, signal, lv, primary, "", reference)


# --------------------------------------------------------------------------- tables


def cut_level_rows(sl: SignalLevels) -> list[tuple[str, ...]]:
    """Rows of the cut-level table: order, name, highest level and its speed, median."""
    lv = sl.levels
    if lv is None:
        return []
    rows: list[tuple[str, ...]] = []
    for o, name, top, at, med in lv.order_statistics():
        rows.append((f"{o:.4g}", name, "–" if not np.isfinite(top) else f"{top:.1f}",
                     "–" if not np.isfinite(at) else f"{at:.0f}",
                     "–" if not np.isfinite(med) else f"{med:.1f}"))
    return rows


CUT_LEVEL_HEADER = ("order", "name", "max level", "at speed [min⁻¹]", "median level")
"""Columns of the cut-level table (levels in the unit the caption states)."""

CUT_RESONANCE_HEADER = ("rank", "cut", "order", "speed [min⁻¹]", "frequency [Hz]", "level",
                        "rise [dB]", "-3 dB span [min⁻¹]", "natural frequency crossed")
"""Columns of the cut-resonance table (levels in the unit the caption states)."""


def cut_resonance_rows(sl: SignalLevels, n: int | None = None) -> list[tuple[str, ...]]:
    """Rows of the cut-resonance table, strongest level first (the first ``n``)."""
    lv = sl.levels
    if lv is None:
        return []
    p = lv.peaks
    k = len(p) if n is None else min(n, len(p))
    return [(str(i + 1), str(p.name[i]), f"{p.order[i]:.4g}", f"{p.rpm[i]:.0f}",
             f"{p.frequency_hz[i]:.0f}", f"{p.level_db[i]:.1f}", f"{p.rise_db[i]:.1f}",
             f"{p.width_rpm[i]:.0f}",
             f"{p.mode[i]} ({p.mode_frequency_hz[i]:.0f} Hz)" if p.mode[i] else "none")
            for i in range(k)]


def cut_level_caption(sl: SignalLevels) -> str:
    """Caption of the cut-level table (names the case and the signal)."""
    return f"Order-cut levels of {sl.case}, {sl.signal}"


def cut_level_header(sl: SignalLevels) -> tuple[str, ...]:
    """:data:`CUT_LEVEL_HEADER` with the level unit."""
    u = sl.level_unit
    return ("order", "name", f"max level [{u}]", "at speed [min⁻¹]", f"median level [{u}]")


def cut_resonance_caption(sl: SignalLevels) -> str:
    """Caption of the cut-resonance table."""
    return f"Resonances of the order cuts of {sl.case}, {sl.signal}"


def cut_resonance_header(sl: SignalLevels) -> tuple[str, ...]:
    """:data:`CUT_RESONANCE_HEADER` with the level unit."""
    h = list(CUT_RESONANCE_HEADER)
    h[5] = f"level [{sl.level_unit}]"
    return tuple(h)


# --------------------------------------------------------------------------- blocks


def report_note(note: str) -> str:
    """A note of :func:`analysis.runup_levels.runup_levels` in the report's words (the CLI
    option instead of the keyword)."""
    return note.replace("give a finer resolution= (orders four resolutions apart are "
                        "separated) or a narrower band",
                        "a longer run or a finer --order-resolution separates them (orders "
                        "four resolutions apart are separated)")


def constant_speed_text(sl: SignalLevels) -> str:
    """What a record without a run-up shows: levels over time, no resonances over speed."""
    lv = sl.levels
    assert lv is not None
    lo, hi = lv.speed_range
    return (f"{sl.case}, {sl.signal}: no run-up: the {sl.reference} turns at "
            f"{span(lo, hi, 'min⁻¹')} (less than {lv.min_speed_ratio:g} times from lowest to "
            "highest), so an order cut over speed would be a single point. The cuts and the "
            "overall level are shown over time (they tell whether the levels are steady), the "
            "waterfall holds spectra over time and the Campbell diagram marks the operating "
            "speed; no resonance over speed can be ranked. The spectra show the orders' "
            "levels at this speed.")


def _panels(sl: SignalLevels) -> list[list[int]]:
    lv = sl.levels
    assert lv is not None
    req = [i for i, r in enumerate(lv.required) if r]
    opt = [i for i, r in enumerate(lv.required) if not r]
    chunks = [req[i:i + MAX_CURVES] for i in range(0, len(req), MAX_CURVES)]
    chunks += [opt[i:i + MAX_CURVES] for i in range(0, len(opt), MAX_CURVES)]
    return [c for c in chunks if c]


def levels_blocks(items: Sequence[SignalLevels], *, heading: bool = True,
                  explain_resonances: bool = True) -> list[Block]:
    """Blocks of the NVH section for the signals of one case (or measurement).

    Per signal: a paragraph on what was cut (and what not, why), the figure of the order cuts
    with the overall level, the cut-level table, the cut-resonance table; for the primary
    signal also the waterfall and the Campbell diagram. ``explain_resonances``: say once what
    a cut resonance is (before the first cut-resonance table).
    """
    out: list[Block] = []
    if not items:
        return out
    if heading:
        out.append(Block("heading", items[0].case))
    for sl in items:
        lv = sl.levels
        if lv is None:
            out.append(Block("text", f"{sl.case}, {sl.signal}: {sl.note}"))
            continue
        lo_f, hi_f = lv.overall.frequency_range
        over = "speed" if lv.varying_speed else "time (constant speed)"
        text = (f"{sl.case}, {sl.signal}: order cuts over {over} of the orders "
                + ", ".join(f"{n} ({o:.4g})" for o, n in zip(lv.orders, lv.order_names,
                                                             strict=True))
                + f" of the {sl.reference}; rms level in {sl.level_unit}, flat-top frames of "
                f"resolution {lv.resolution:.3g} orders ({lv.revolutions:.0f} revolutions "
                f"analysed), band {lv.cuts.bandwidth:.3g} orders around each order. The overall "
                f"level sums the lines of the rpm-frequency map from {lo_f:.3g} to {hi_f:.4g} "
                "Hz.")
        if lv.dropped:
            text += (f" Not cut, as the cuts need {lv.separation:.3g} orders between each other "
                     "and from order 0 at this resolution (a longer run or a finer "
                     "--order-resolution separates more): "
                     + "; ".join(f"{n} ({o:.4g}: {why})" for n, o, why in lv.dropped) + ".")
        out.append(Block("text", text))
        if not lv.varying_speed:
            out.append(Block("text", constant_speed_text(sl)))
        out += [Block("text", f"{sl.case}, {sl.signal}: note: {report_note(n)}")
                for n in lv.notes]
        marks = min(MARKED_RESONANCES, len(lv.peaks)) if sl.primary else 0
        panels = _panels(sl)
        out.append(Block(
            "figure", f"{sl.case}: order cuts of the {sl.signal} [{sl.level_unit}] over the "
            f"{sl.reference} speed; black: overall level {lo_f:.3g}–{hi_f:.4g} Hz"
            + (f"; circles numbered 1–{marks}: the strongest resonances (table below)"
               if marks else "") + ".",
            figure=lambda lv=lv, p=panels, m=marks: order_cuts_levels_figure(
                lv, panels=p, marks=m)))
        out.append(Block("table", cut_level_caption(sl), cut_level_header(sl),
                         tuple(cut_level_rows(sl))))
        if lv.varying_speed and explain_resonances:
            explain_resonances = False
            out.append(Block("text", "A resonance of a cut is a "
                             f"maximum at least {lv.min_rise_db:g} dB above the higher of the "
                             "two minima that separate it from a higher level (its rise), "
                             f"within {lv.dynamic_range_db:g} dB of the highest cut level; it "
                             "crosses a natural frequency f_i when the critical speed 60 f_i / "
                             f"order lies within {100 * lv.natural_tolerance:g} % plus half "
                             "its -3 dB span of its speed."))
        if lv.varying_speed:
            out.append(Block("table", cut_resonance_caption(sl), cut_resonance_header(sl),
                             tuple(cut_resonance_rows(sl))))
        if not sl.primary:
            continue
        out.append(Block(
            "figure", f"{sl.case}: waterfall of the {sl.signal}: {len(lv.waterfall)} rms "
            f"spectra ({lv.waterfall.window}, RBW {lv.waterfall.resolution_hz:.3g} Hz) at "
            "evenly spaced speeds, each drawn on its speed (height: level, 50 dB shown, scale "
            "bar 20 dB); dashed: the cut orders, dotted: natural frequencies.",
            figure=lambda lv=lv, f=hi_f: waterfall_figure(lv, frequency_max=f)))
        out.append(Block(
            "figure", f"{sl.case}: Campbell diagram of the {sl.signal}: each cut order is a "
            "ray (frequency = order × speed / 60) coloured and sized by its level, dotted "
            "horizontal lines are the natural frequencies, open circles the critical speeds "
            "where a ray crosses one"
            + (f", numbers the strongest resonances 1–{marks}" if marks else "") + ".",
            figure=lambda lv=lv, f=hi_f, m=marks: campbell_levels_figure(
                lv, frequency_max=f, marks=m)))
    return out
