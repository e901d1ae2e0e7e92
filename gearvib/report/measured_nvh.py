"""The NVH pages and the summary page of a measured report (:mod:`gearvib.report.measured`).

:func:`measured_levels` computes the order cuts, overall level, waterfall and Campbell data of
the measured channel (:func:`gearvib.report.nvh.signal_levels`) with what the measured case
knows: the gear set's mesh orders and catalogue, or without a gear set the order rays the map
shows (else shaft orders 1 to 3), and the orders asked for (``cut_orders``).
:func:`with_level_pages` puts the summary (first) and the NVH section (second) in front of the
measured report's sections; the rest of the report is unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from gearvib import __version__
from gearvib.report.blocks import Section
from gearvib.report.nvh import (
    LEVELS_SECTION_ID,
    LEVELS_TITLE,
    SignalLevels,
    levels_blocks,
    signal_levels,
)
from gearvib.report.rises import merged_modes
from gearvib.report.verdict import (
    SUMMARY_ID,
    SUMMARY_TITLE,
    CaseSummary,
    RiseMatch,
    mode_descriptions,
    rise_explanation,
    settings_summary,
    summary_blocks,
)
from gearvib.report.wording import count, span

if TYPE_CHECKING:
    from gearvib.report.measured_case import MeasuredCase

__all__ = ["MAX_RAY_CUTS", "measured_levels", "measured_summary", "with_level_pages"]

MAX_RAY_CUTS = 5
"""Without a gear set (and without ``cut_orders``), the strongest order rays of the map cut."""


def _ray_orders(mc: MeasuredCase) -> list[tuple[str, float]]:
    f = mc.features
    if f is None or not np.size(f.orders):
        return []
    o = np.asarray(f.orders, dtype=float)
    s = np.asarray(f.order_strength_db, dtype=float)
    keep = np.flatnonzero(o >= 0.5)
    keep = keep[np.argsort(s[keep])[::-1][:MAX_RAY_CUTS]]
    return [(f"map ray {o[i]:.4g}", float(o[i])) for i in sorted(keep, key=lambda i: o[i])]


def measured_levels(mc: MeasuredCase, *, min_speed_ratio: float = 1.3) -> SignalLevels:
    """Levels of the measured channel for the NVH pages.

    Parameters
    ----------
    mc : MeasuredCase
        The analysed measurement.
    min_speed_ratio : float
        Speed ratio below which the record counts as constant speed (the measured report's).

    Returns
    -------
    SignalLevels
    """
    m = mc.measurement
    x = np.asarray(m.channel(mc.channel).values, dtype=float)
    mesh = [(g, 60.0 * f) for g, f, _ in mc.mesh_groups]
    named: list[tuple[str, float]] = []
    if not mesh and not mc.settings.cut_orders:
        named = _ray_orders(mc) or [(f"shaft order {k}", float(k)) for k in (1, 2, 3)]
    fn, names = merged_modes(mc.natural_frequencies_hz, mc.mode_names)
    fmap = mc.fmap
    lo_f = 2.0 * float(fmap.resolution_hz) if fmap is not None else 0.0
    ref = {"angle": np.asarray(m.angle.values, dtype=float)} if m.angle is not None else {
        "rpm": np.asarray(m.speed_rpm.values, dtype=float)}
    member = mc.reference_member
    return signal_levels(
        x - x.mean(), m.fs, case=mc.name, signal=mc.channel, mesh_orders=mesh,
        settings=mc.settings, catalogue=mc.catalogue, reference_member=member,
        natural_frequencies_hz=fn, natural_names=names, frequency_map=fmap,
        frequency_range=(lo_f, mc.frequency_max_hz), units=mc.units, primary=True,
        reference=f"reference shaft ({member})" if member else "reference shaft",
        min_speed_ratio=min_speed_ratio, named_orders=named, **ref)


def measured_summary(mc: MeasuredCase, sl: SignalLevels) -> CaseSummary:
    """Key numbers of the measurement and the rise table as the explanation of its strongest
    cut resonances."""
    m = mc.measurement
    t = m.time
    lo, hi = mc.speed_range
    key = [("record", f"{t.size} samples at {m.fs:g} Hz, {t[-1] - t[0] + 1 / m.fs:.4g} s, "
                      f"channel {mc.channel} [{mc.units}]"),
           ("reference speed", span(lo, hi, "min⁻¹") + ("" if mc.varying_speed else
                                                       " (constant speed)"))]
    for g, f, _ in mc.mesh_groups:
        key.append((f"mesh frequency ({g})", f"{span(f * lo, f * hi, 'Hz')} (order "
                                             f"{60 * f:.4g} of the reference shaft)"))
    fn, names = merged_modes(mc.natural_frequencies_hz, mc.mode_names)
    if fn.size:
        shown = [(n, f) for n, f in zip(names, fn, strict=True) if f <= mc.frequency_max_hz]
        key.append((f"natural frequencies of the model up to {mc.frequency_max_hz:.0f} Hz",
                    ", ".join(f"{n} {f:.0f} Hz" for n, f in shown[:8])
                    + (f" and {len(shown) - 8} more" if len(shown) > 8 else "") or "none"))
    if mc.resonances is not None:
        key.append((f"rises of the sonogram ({mc.channel})",
                    f"{count(len(mc.resonances), 'rise')} in "
                    f"{count(len(mc.regions), 'speed region')}"))

    def explain(rank: int) -> RiseMatch | None:
        return rise_explanation(mc.resonances, sl, rank, rpm_tolerance=0.03 * hi,
                                source=mc.channel)

    return CaseSummary(mc.name, key, [sl], explain, mode_descriptions(mc.mode_rows()))


def _inputs(mc: MeasuredCase) -> list[tuple[str, str]]:
    m = mc.measurement
    rows = [("gearvib version", __version__),
            ("measurement", f"{m.source.get('file') or '(in memory)'} "
                            f"({m.source.get('format', '')})"),
            ("channel", f"{mc.channel} [{mc.units}]"), ("speed reference", m.reference),
            ("gear set", mc.gearset_name or "(none)"),
            ("analysis settings", settings_summary(mc.settings)),
            ("details", "every setting and channel: sections Measurement and Provenance")]
    return rows


def with_level_pages(sections: Sequence[Section], mc: MeasuredCase, sl: SignalLevels
                     ) -> list[Section]:
    """The summary (a front section) and the NVH section before the measured report's own."""
    summary = Section(SUMMARY_ID, SUMMARY_TITLE,
                      tuple(summary_blocks([measured_summary(mc, sl)], inputs=_inputs(mc))),
                      front=True)
    pages = Section(LEVELS_SECTION_ID, LEVELS_TITLE, tuple(levels_blocks([sl], heading=False)))
    return [summary, pages, *sections]
