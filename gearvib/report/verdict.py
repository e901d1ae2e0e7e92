"""The first page of a report: the verdict, and readable provenance.

:func:`summary_blocks` writes what a reader looks for before anything else: per case the key
numbers, the strongest resonances (speed, order, frequency, level) and the one likely cause to
inspect first, the others "possible", ranked. Every number is read from the objects the
report's other sections show (:class:`gearvib.report.nvh.SignalLevels`, the rise tables), so
the summary cannot disagree with them; :func:`gearvib.report.crosscheck.cross_check` checks
that it does not.

:func:`settings_rows` and :func:`readable` turn analysis settings and stored JSON into table
rows a reader can read (no raw JSON in a report).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from gearvib.report.blocks import Block
from gearvib.report.nvh import MARKED_RESONANCES, SignalLevels, cut_resonance_rows
from gearvib.report.study import AnalysisSettings
from gearvib.report.wording import span

__all__ = [
    "STRONGEST_HEADER",
    "SUMMARY_ID",
    "SUMMARY_TITLE",
    "CaseSummary",
    "RiseMatch",
    "level_key_numbers",
    "mode_descriptions",
    "readable",
    "rise_explanation",
    "settings_rows",
    "settings_summary",
    "summary_blocks",
]

SUMMARY_ID = "summary"
"""Section id of the first page."""

SUMMARY_TITLE = "Summary: key numbers, strongest resonances, what to inspect first"
"""Title of the first page."""

STRONGEST_HEADER = ("rank", "cut", "order", "speed [min⁻¹]", "frequency [Hz]", "level",
                    "rise [dB]", "natural frequency crossed", "explanation")
"""Columns of the strongest-resonance table of the summary (the first columns are those of
the cut-resonance table, :data:`gearvib.report.nvh.CUT_RESONANCE_HEADER`, without the span)."""


@dataclass(frozen=True)
class RiseMatch:
    """A row of a report's rise table that classifies a cut resonance.

    Attributes
    ----------
    mechanism : str
        ``"forced resonance"``, ``"parametric instability"``, ``"unexplained"``.
    cause : str
        Its cause as the rise table writes it (``"3 f_mesh = f5"``; ``""`` if none).
    rpm : float
        Speed of the rise [min⁻¹].
    strength_db : float
        Its rise [dB].
    source : str
        The signal of the rise table (``"tooth force sun-planet1"``).
    """

    mechanism: str
    cause: str
    rpm: float
    strength_db: float
    source: str

    @property
    def short(self) -> str:
        """As the rise table's "mechanism: cause" column, with the speed: ``"forced: 3
        f_mesh = f5 at 1676 min⁻¹"``."""
        head = self.mechanism.split()[0] + (f": {self.cause}" if self.cause else "")
        return f"{head} at {self.rpm:.0f} min⁻¹"

    @property
    def sentence(self) -> str:
        """``"forced resonance 3 f_mesh = f5 (rise table of the tooth force sun-planet1:
        17.7 dB at 1676 min⁻¹)"``."""
        what = self.mechanism + (f" {self.cause}" if self.cause else "")
        return (f"{what} (rise table of the {self.source}: {self.strength_db:.1f} dB at "
                f"{self.rpm:.0f} min⁻¹)")


@dataclass(frozen=True)
class CaseSummary:
    """What the summary says about one case (or measurement).

    Attributes
    ----------
    case : str
        Case name.
    key_numbers : list of (str, str)
        Quantity and value (units in the quantity or the value).
    levels : list of SignalLevels
        The signals of the NVH pages (the primary one is ranked).
    explain : callable or None
        ``explain(rank) -> RiseMatch | None``: the row of the report's rise table that
        classifies the ``rank``-th strongest cut resonance of the primary signal.
    modes : dict of str to str
        Natural-frequency name -> what kind of mode it is (type, dominant mesh).
    """

    case: str
    key_numbers: list[tuple[str, str]]
    levels: list[SignalLevels]
    explain: Callable[[int], RiseMatch | None] | None = None
    modes: dict[str, str] | None = None

    @property
    def primary(self) -> SignalLevels | None:
        """The ranked signal (the first primary one with levels)."""
        return next((s for s in self.levels if s.primary and s.levels is not None), None)


def level_key_numbers(items: Sequence[SignalLevels]) -> list[tuple[str, str]]:
    """Key numbers of the signals' levels: highest overall level, strongest cut, resonances."""
    rows: list[tuple[str, str]] = []
    for sl in items:
        lv = sl.levels
        if lv is None:
            rows.append((f"order cuts ({sl.signal})", sl.note or "not available"))
            continue
        top, at = lv.overall_maximum()
        lo_f, hi_f = lv.overall.frequency_range
        rows.append((f"highest overall level ({sl.signal}, {lo_f:.3g}–{hi_f:.4g} Hz)",
                     f"{top:.1f} {sl.level_unit} at {at:.0f} min⁻¹"))
        stats = [s for s in lv.order_statistics() if math.isfinite(s[2])]
        if stats:
            o, name, lvl, rpm, _ = max(stats, key=lambda s: s[2])
            rows.append((f"highest order-cut level ({sl.signal})",
                         f"{name} ({o:.4g}): {lvl:.1f} {sl.level_unit} at {rpm:.0f} min⁻¹"))
        if lv.varying_speed:
            rows.append((f"resonances of the order cuts ({sl.signal})",
                         f"{len(lv.peaks)} (rise >= {lv.min_rise_db:g} dB)"))
    return rows


def _where(row: tuple[str, ...]) -> str:
    """``"3× mesh at 1680 min⁻¹ (2150 Hz)"``."""
    return f"{row[1]} at {row[3]} min⁻¹ ({row[4]} Hz)"


def _crossing(row: tuple[str, ...], modes: dict[str, str] | None) -> str:
    """``"crossing f5 (2201 Hz; rotational mode, dominant mesh sun-planet1 (27 %))"``."""
    crossed = row[7]
    if crossed == "none":
        return "crossing no natural frequency of the model"
    mode = crossed.split(" (")[0]
    extra = (modes or {}).get(mode, "")
    return f"crossing {crossed[:-1]}; {extra})" if extra else f"crossing {crossed}"


def _strongest_rows(cs: CaseSummary) -> list[tuple[str, ...]]:
    sl = cs.primary
    if sl is None:
        return []
    rows = []
    for r in cut_resonance_rows(sl, MARKED_RESONANCES):
        rank = int(r[0])
        match = cs.explain(rank - 1) if cs.explain is not None else None
        rows.append((*r[:7], r[8], match.short if match is not None else "–"))
    return rows


def summary_blocks(cases: Sequence[CaseSummary], *, inputs: Sequence[tuple[str, str]] = ()
                   ) -> list[Block]:
    """The blocks of the summary (first) page.

    Per case: one paragraph with the strongest resonance of the primary signal and the likely
    cause to inspect first (only the first is "likely"; the next two are "possible"), the key
    numbers, the strongest resonances ranked by level. Then the inputs and settings.

    Parameters
    ----------
    cases : sequence of CaseSummary
        One per case, in report order.
    inputs : sequence of (str, str)
        Version, inputs and settings (a table; see :func:`settings_rows`).
    """
    out: list[Block] = []
    several = len(cases) > 1
    for cs in cases:
        if several:
            out.append(Block("heading", cs.case))
        sl = cs.primary
        rows = _strongest_rows(cs)
        if sl is None or sl.levels is None:  # (primary has levels)
            out.append(Block("text", f"{cs.case}: no order cuts, so no resonance ranking "
                             "(see the notes of the order-cut section)."))
        elif not sl.levels.varying_speed:
            out.append(Block("text", f"{cs.case}: no run-up: constant speed "
                             f"({span(*sl.levels.speed_range, 'min⁻¹')}), so the order cuts "
                             "are levels over time and there is no resonance over speed to "
                             "rank; the key numbers give the levels at this speed."))
        elif not rows:
            out.append(Block("text", f"{cs.case}: no order cut of the {sl.signal} rises "
                             f"{sl.levels.min_rise_db:g} dB or more above its surroundings "
                             "in this run: no resonance to inspect."))
        else:
            first = rows[0]
            match = cs.explain(0) if cs.explain is not None else None
            if match is not None:
                cause = match.sentence
            elif first[7] != "none":
                cause = (f"the {first[1]} order exciting {first[7].split(' (')[0]} (not among "
                         "the rises of the rise table)")
            else:
                cause = ("a resonance of no natural frequency of the model: look for a "
                         "structure the model lacks (e.g. a housing mode) or a wrong stiffness")
            text = (f"{cs.case}: strongest resonance of the {sl.signal}: {_where(first)}, "
                    f"{first[5]} {sl.level_unit}, {first[6]} dB above its surroundings, "
                    f"{_crossing(first, cs.modes)}. Likely cause, to inspect first: {cause}.")
            if len(rows) > 1:
                text += " Possible as well, ranked: " + "; ".join(
                    f"({r[0]}) {_where(r)}, {_crossing(r, None)}" for r in rows[1:3]) + "."
            out.append(Block("text", text))
        out.append(Block("table", f"Key numbers of {cs.case}", ("quantity", "value"),
                         tuple(cs.key_numbers + level_key_numbers(cs.levels))))
        if sl is not None and rows:
            header = (*STRONGEST_HEADER[:5], f"level [{sl.level_unit}]", *STRONGEST_HEADER[6:])
            out.append(Block("table", f"Strongest resonances of {cs.case}, {sl.signal} "
                             "(rank 1 is the one to inspect first)", header, tuple(rows)))
    if inputs:
        out.append(Block("table", "Inputs and settings", ("item", "value"), tuple(inputs)))
    return out


# --------------------------------------------------------------------------- provenance


_SETTING_TEXT: dict[str, Callable[[Any], str]] = {
    "n_max": lambda v: f"2 f_i/n, (f_i + f_j)/n up to n = {v}",
    "stability_points": lambda v: f"{v} speeds",
    "stability": lambda v: {"full": "full (max|μ| to 1e-7 near the limit)",
                            "coarse": "coarse (at most 80 speeds)",
                            "off": "off (no Floquet chart)"}.get(str(v), str(v)),
    "map_resolution_hz": lambda v: f"{v:g} Hz (Hann)",
    "map_overlap": lambda v: f"{v:g}",
    "orders": lambda v: "automatic (up to the highest natural frequency, 7 to 20)" if not v
    else f"1–{v}",
    "threshold_db": lambda v: f"{v:g} dB",
    "tolerance": lambda v: f"{100 * v:g} %",
    "frequency_max_hz": lambda v: "automatic (2.2 × the highest natural frequency)" if not v
    else f"{v:g} Hz",
    "force_mesh": lambda v: str(v) or "the first sun mesh",
    "spectrum_peaks": lambda v: f"{v}",
    "cut_orders": lambda v: ("1×–3× mesh" + (" and " + ", ".join(f"{o:g}" for o in v)
                                             if v else "")
                             + ", with the catalogue's fault and sideband orders where "
                             "separated"),
    "order_resolution": lambda v: "automatic" if not v else f"{v:g} orders",
}

_SETTING_NAMES = {
    "n_max": "theory candidates", "stability_points": "Floquet chart speeds",
    "stability": "Floquet chart", "map_resolution_hz": "map resolution (RBW)",
    "map_overlap": "map frame overlap", "orders": "mesh orders drawn",
    "threshold_db": "rise threshold", "tolerance": "natural-frequency tolerance",
    "frequency_max_hz": "frequency range", "force_mesh": "tooth force analysed",
    "spectrum_peaks": "peaks per spectrum", "cut_orders": "order cuts",
    "order_resolution": "order-cut resolution",
}


def settings_rows(settings: AnalysisSettings | dict, keys: Sequence[str] | None = None,
                  prefix: str = "setting: ") -> list[tuple[str, str]]:
    """Analysis settings as readable ``(item, value)`` rows (no JSON).

    Parameters
    ----------
    settings : AnalysisSettings or dict
        The settings.
    keys : sequence of str, optional
        Which settings (default: all, in their order).
    prefix : str
        Put before each item.
    """
    d = settings.to_dict() if isinstance(settings, AnalysisSettings) else dict(settings)
    rows = []
    for k in keys or list(d):
        if k not in d:
            continue
        v = d[k]
        text = _SETTING_TEXT.get(k, readable)(v)
        rows.append((prefix + _SETTING_NAMES.get(k, k.replace("_", " ")), text))
    return rows


def settings_summary(settings: AnalysisSettings) -> str:
    """The analysis settings in one readable line (the full list: :func:`settings_rows`)."""
    st = settings
    parts = [f"maps Hann, RBW {st.map_resolution_hz:g} Hz, overlap {st.map_overlap:g}",
             "order cuts 1×–3× mesh" + (" and orders " + ", ".join(f"{o:g}" for o in
                                                                  st.cut_orders)
                                        if st.cut_orders else "")
             + (f", resolution {st.order_resolution:g} orders" if st.order_resolution
                else ", automatic resolution"),
             f"rises >= {st.threshold_db:g} dB", f"natural-frequency tolerance "
             f"{100 * st.tolerance:g} %",
             f"Floquet chart {st.stability}" + (f", {st.stability_points} speeds"
                                               if st.stability != "off" else ""),
             f"theory candidates n <= {st.n_max}"]
    return "; ".join(parts)


def readable(value: Any) -> str:
    """A stored value as text a reader reads: JSON objects and lists as ``key = value; ...``,
    floats with 6 significant digits."""
    if isinstance(value, str):
        v = value.strip()
        if v[:1] in "{[":
            try:
                return readable(json.loads(v))
            except ValueError:
                return value
        return value
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, dict):
        return "; ".join(f"{k.replace('_', ' ')} = {readable(x)}" for k, x in value.items()) \
            or "(none)"
    if isinstance(value, list | tuple):
        return ", ".join(readable(x) for x in value) or "(none)"
    return str(value)


def mode_descriptions(rows: Sequence[Sequence[Any]]) -> dict[str, str]:
    """``{"f5": "planet mode, dominant mesh ring-planet1 (40 %)"}`` from mode-table rows
    ``(mode, f, type, [multiplicity,] dominant mesh)``."""
    out = {}
    for r in rows:
        name = str(r[0]) if str(r[0]).startswith("f") else f"f{r[0]}"
        kind, dom = str(r[2]), str(r[-1])
        out[name] = kind + (f" mode, dominant mesh {dom}" if dom and dom != "–" else " mode")
    # repeated pairs are named "f3=f4"
    for a in list(out):
        for b in list(out):
            if a < b and out[a] == out[b] and re.fullmatch(r"f\d+", a) and re.fullmatch(
                    r"f\d+", b):
                out[f"{a}={b}"] = out[a]
    return out


def rise_explanation(res: Any, sl: SignalLevels, rank: int, *, rpm_tolerance: float,
                     source: str) -> RiseMatch | None:
    """The rise-table row that explains the ``rank``-th cut resonance of ``sl`` (None if none).

    A cut ``"k× mesh"`` (``"k× mesh (stage 2)"``) resonance matches the strongest rise of the
    report's rise table on the ray of mesh order ``k`` (of that mesh frequency) within
    ``rpm_tolerance`` plus half the resonance's -3 dB span of its speed, if both tell the same
    story: a forced resonance of the natural frequency the cut crosses, or (the cut crossing
    none) a parametric or unexplained rise.

    Parameters
    ----------
    res : analysis.instability.Resonances or None
        The classified rises the report's rise table lists.
    sl : SignalLevels
        The signal whose cut resonances are ranked.
    rank : int
        Row of ``sl.levels.peaks`` (0: the strongest).
    rpm_tolerance : float
        Speed tolerance [min⁻¹].
    source : str
        The signal of the rise table (``"tooth force sun-planet1"``), for the text.

    Returns
    -------
    RiseMatch or None
    """
    lv = sl.levels
    if res is None or lv is None or not len(res) or rank >= len(lv.peaks):
        return None
    p = lv.peaks
    best = None
    for part in str(p.name[rank]).split(" = "):
        m = re.fullmatch(r"(\d+)× mesh(?: \((.+)\))?", part)
        if not m:
            continue
        k, grp = int(m.group(1)), m.group(2) or ""
        groups = res.groups
        for i in range(len(res)):
            if int(res.order[i]) != k or (grp and str(groups[i]) != grp):
                continue
            if abs(float(res.rpm[i]) - float(p.rpm[rank])) > rpm_tolerance + 0.5 * float(
                    p.width_rpm[rank]):
                continue
            if best is None or res.strength_db[i] > res.strength_db[best]:
                best = i
    if best is None:
        return None
    mech = str(res.mechanism[best])
    crossed = str(p.mode[rank])
    m = re.search(r"= (\S+)", str(res.cause[best]))
    if mech == "forced resonance" and (not crossed or m is None or m.group(1) != crossed):
        return None  # the rise table names another crossing than the cut: not the same
    if mech != "forced resonance" and crossed:
        return None
    cause = str(res.cause[best]) if res.cause[best] and mech != "unexplained" else ""
    return RiseMatch(mech, cause, float(res.rpm[best]), float(res.strength_db[best]), source)
