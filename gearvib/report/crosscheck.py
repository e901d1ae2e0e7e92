"""Cross-check of a rendered report: do its tables and its text agree with each other?

:func:`cross_check` reads ``report.html`` back (the PDF carries the same sections) and checks
what a careful reader would:

* every Floquet region has the same candidate in the Floquet table, the band-growth table and
  the comparison of the cases;
* a region's candidate is a row of the theory-candidate table, allowed, marked as attributed,
  with its centre speed inside the region (within the attribution tolerance);
* the counts in the text equal the rows of the tables they summarise (rises and their
  mechanisms, resonance regions, the regions of each case in the comparison), and each
  resonance region's summary matches the rises inside it;
* a peak label carries at most two expressions;
* a stated average chance of the explanations equals the mean of the rise table's 'chance'
  column over the explained rises (and no chance is stated when none is explained; an
  unexplained rise has no chance of its explanation);
* no range has equal ends ("between 1500 and 1500", "1500–1500 min⁻¹");
* at most one cause is called "likely" (in a table column, or in one paragraph): the others
  are ranked as "possible";
* the summary page agrees with the pages it summarises: each row of a "Strongest resonances"
  table is the row of the same rank of the cut-resonance table of its signal, its explanation
  is a row of the rise table, the text's strongest resonance is rank 1, and the counts of the
  key numbers equal the rows of the tables they count.

It returns the disagreements as sentences (an empty list: the report is consistent), so a test
or a user can run it on any report: ``cross_check(Path("out/report.html").read_text())``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from html.parser import HTMLParser

__all__ = ["ReportTable", "cross_check", "parse_report"]

_SPEED_RTOL = 0.011  # attribution tolerance (1 %) plus the rounding of the printed speeds


@dataclass
class ReportTable:
    """A table of a rendered report: caption, header and rows (cell texts)."""

    caption: str
    header: list[str] = field(default_factory=list)
    rows: list[list[str]] = field(default_factory=list)
    section: str = ""

    def column(self, name: str) -> list[str]:
        """The cells of the column whose header is ``name``."""
        j = self.header.index(name)
        return [r[j] if j < len(r) else "" for r in self.rows]


class _Parser(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tables: list[ReportTable] = []
        self.paragraphs: list[tuple[str, str]] = []
        self.section = ""
        self._text: list[str] | None = None
        self._cell: list[str] | None = None
        self._row: list[str] | None = None
        self._head = False
        self._table: ReportTable | None = None

    def handle_starttag(self, tag: str, attrs: list) -> None:
        if tag == "section":
            self.section = dict(attrs).get("id", "")
        elif tag == "table":
            self._table = ReportTable("", section=self.section)
        elif tag in ("caption", "p"):
            self._text = []
        elif tag == "thead":
            self._head = True
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag: str) -> None:
        if tag == "table" and self._table is not None:
            self.tables.append(self._table)
            self._table = None
        elif tag == "caption" and self._table is not None and self._text is not None:
            self._table.caption = "".join(self._text).strip()
            self._text = None
        elif tag == "p" and self._text is not None:
            self.paragraphs.append((self.section, "".join(self._text).strip()))
            self._text = None
        elif tag == "thead":
            self._head = False
        elif tag in ("td", "th") and self._cell is not None and self._row is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None and self._table is not None:
            if self._head:
                self._table.header = self._row
            elif self._row != ["(none)"]:
                self._table.rows.append(self._row)
            self._row = None

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self._cell.append(data)
        elif self._text is not None:
            self._text.append(data)


def parse_report(html: str) -> tuple[list[ReportTable], list[tuple[str, str]]]:
    """Tables and paragraphs ``(section id, text)`` of a rendered report."""
    p = _Parser()
    p.feed(html)
    return p.tables, p.paragraphs


def _find(tables: list[ReportTable], prefix: str) -> ReportTable | None:
    return next((t for t in tables if t.caption.startswith(prefix)), None)


def _span(text: str) -> tuple[float, float] | None:
    """``"1347–1407"`` -> (1347, 1407); a single speed ``"1676"`` -> (1676, 1676)."""
    m = re.match(r"\s*(?:≤ )?(\d+(?:\.\d+)?)\s*–\s*(\d+(?:\.\d+)?)", text)
    if m:
        return float(m.group(1)), float(m.group(2))
    m = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*", text)
    return (float(m.group(1)), float(m.group(1))) if m else None


def _number(text: str) -> float:
    return float(re.sub(r"[^0-9.\-]", "", text) or "nan")


def cross_check(html: str) -> list[str]:
    """Disagreements between the tables and the text of a rendered report (HTML).

    Parameters
    ----------
    html : str
        ``report.html`` as written by :func:`gearvib.report.build_report`.

    Returns
    -------
    list of str
        One sentence per disagreement; empty when the report is consistent.
    """
    tables, paragraphs = parse_report(html)
    problems: list[str] = []
    cases = [t.caption[len("Provenance of "):] for t in tables
             if t.caption.startswith("Provenance of ")]
    floquet: dict[str, dict[tuple[float, float], str]] = {}
    regions_of: dict[str, int] = {}
    for case in cases:
        fl = _find(tables, f"Unstable speed intervals of {case} (Floquet)")
        cand = _find(tables, f"Theory candidates of {case} ")
        labels: dict[tuple[float, float], str] = {}
        if fl is not None:
            for lo_s, hi_s, lab in zip(fl.column("from [min⁻¹]"), fl.column("to [min⁻¹]"),
                                       fl.column("candidate"), strict=True):
                key = (_number(lo_s), _number(hi_s))
                labels[key] = lab
                if lab == "unattributed":
                    continue
                if cand is None:
                    problems.append(f"{case}: no theory-candidate table for the label {lab!r}")
                    continue
                hits = [r for r in cand.rows if r[cand.header.index("label")] == lab]
                if not hits:
                    problems.append(f"{case}: Floquet region {key[0]:.0f}–{key[1]:.0f} is "
                                    f"labelled {lab!r}, which the candidate table does not list")
                    continue
                row = hits[0]
                speed = _number(row[cand.header.index("speed [min⁻¹]")])
                if not key[0] * (1 - _SPEED_RTOL) <= speed <= key[1] * (1 + _SPEED_RTOL):
                    problems.append(f"{case}: Floquet region {key[0]:.0f}–{key[1]:.0f} is "
                                    f"labelled {lab!r}, but the candidate table puts it at "
                                    f"{speed:.0f} min⁻¹")
                if not row[cand.header.index("allowed")].startswith("yes"):
                    problems.append(f"{case}: region label {lab!r} is a suppressed candidate")
                if row[cand.header.index("Floquet region")] != "yes":
                    problems.append(f"{case}: candidate {lab!r} labels a Floquet region but is "
                                    "not marked so in the candidate table")
        floquet[case] = labels
        growth = _find(tables, f"Band growth in {case}")
        if growth is not None:
            for band, lab in zip(growth.column("band [min⁻¹]"), growth.column("candidate"),
                                 strict=True):
                sp = _span(band)
                if sp is None:
                    continue
                if sp not in labels:
                    problems.append(f"{case}: growing band {band} is not a Floquet region")
                elif labels[sp] != lab:
                    problems.append(f"{case}: band {band} is {lab!r} in the growth table but "
                                    f"{labels[sp]!r} in the Floquet table")
        # rises and regions against the summary sentence
        rises = _find(tables, f"Rises of {case}")
        regions = _find(tables, f"Resonance regions of {case} ")
        summary = next((t for s, t in paragraphs if s == "resonances"
                        and t.startswith(f"{case}: ") and " rise" in t.split(";")[0]), None)
        if rises is not None and summary is not None:
            m = re.match(rf"{re.escape(case)}: (\d+) rises?: (\d+) forced resonances?, (\d+) "
                         r"parametric instabilit(?:y|ies), (\d+) unexplained", summary)
            if not m:
                problems.append(f"{case}: resonance summary not understood: {summary[:80]!r}")
            else:
                n, forced, para, unex = (int(x) for x in m.groups())
                mech = [c.split(":")[0].strip() for c in rises.column("mechanism: cause")]
                if len(rises.rows) != n:
                    problems.append(f"{case}: the text counts {n} rises, the table lists "
                                    f"{len(rises.rows)}")
                for word, k in (("forced", forced), ("parametric", para),
                                ("unexplained", unex)):
                    if sum(x == word for x in mech) != k:
                        problems.append(f"{case}: the text counts {k} {word} rises, the table "
                                        f"{sum(x == word for x in mech)}")
            m2 = re.search(r"; (\d+) speed regions?\.", summary)
            if regions is not None and m2 and int(m2.group(1)) != len(regions.rows):
                problems.append(f"{case}: the text counts {m2.group(1)} speed regions, the "
                                f"table lists {len(regions.rows)}")
        if rises is not None and regions is not None:
            problems += _check_regions(case, rises, regions)
            regions_of[case] = len(regions.rows)
    # the comparison: counts and Floquet labels of each case
    for _, text in paragraphs:
        for m in re.finditer(r"(\S+): (\d+) resonance regions? \(total [^)]*\) against (\d+) "
                             r"in (\S+) \(total", text):
            other, n_o, n_r, ref = m.group(1), int(m.group(2)), int(m.group(3)), m.group(4)
            for case, n in ((other, n_o), (ref, n_r)):
                if case in regions_of and regions_of[case] != n:
                    problems.append(f"comparison: {case} has {n} resonance regions in the text, "
                                    f"{regions_of[case]} in its region table")
    for t in tables:
        if not t.caption.startswith("Floquet unstable intervals, matched by overlap"):
            continue
        names = [h[:-len(" candidate")] for h in t.header if h.endswith(" candidate")]
        for row in t.rows:
            for case in names:
                span_col = t.header.index(f"{case} [min⁻¹] (width)")
                lab_col = t.header.index(f"{case} candidate")
                sp = _span(row[span_col])
                if sp is None or case not in floquet:
                    continue
                if sp not in floquet[case]:
                    problems.append(f"comparison: {case} interval {row[span_col]} is not in its "
                                    "Floquet table")
                elif floquet[case][sp] != row[lab_col]:
                    problems.append(f"comparison: {case} interval {row[span_col]} is "
                                    f"{row[lab_col]!r}, its Floquet table says "
                                    f"{floquet[case][sp]!r}")
    for t in tables:
        if t.caption.startswith("Peaks of "):
            for lab in t.column("peak"):
                if lab.split("(+")[0].count("≈") > 2:
                    problems.append(f"{t.caption}: peak label with more than two expressions: "
                                    f"{lab!r}")
    problems += _check_chance(tables, paragraphs)
    problems += _check_ranges(tables, paragraphs)
    problems += _check_likely(tables, paragraphs)
    problems += _check_summary(tables, paragraphs)
    return problems


_CHANCE = re.compile(r"^(?P<case>\S+): (?P<n>\d+) rises?: .*?with a chance of (?P<pct>\d+) %"
                     r"(?: on average over the (?P<k>\d+) explained rises| \(the explained "
                     r"rise\))?")


def _percent(text: str) -> float | None:
    m = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*%\s*", text)
    return float(m.group(1)) if m else None


def _check_chance(tables: list[ReportTable], paragraphs: list[tuple[str, str]]) -> list[str]:
    """A stated (average) chance against the 'chance' column of the explained rises."""
    out = []
    for t in tables:
        if not t.caption.startswith(("Rises of ", "Planet-mode rises of ")) or \
                "chance" not in t.header:
            continue
        for row, chance in zip(t.rows, t.column("chance"), strict=True):
            mech = row[t.header.index("mechanism: cause")]
            if mech.startswith("unexplained") and _percent(chance) is not None:
                out.append(f"{t.caption}: the unexplained rise at {row[0]} min⁻¹ states a "
                           f"chance of its explanation ({chance})")
    for _, text in paragraphs:
        if "with a chance of" not in text:
            continue
        m = _CHANCE.match(text)
        if not m:
            continue
        case = m.group("case")
        rises = _find(tables, f"Rises of {case}")
        if rises is None or "chance" not in rises.header:
            continue
        mechanisms = rises.column("mechanism: cause")
        percents = [_percent(c) for c, x in zip(rises.column("chance"), mechanisms, strict=True)
                    if not x.startswith("unexplained")]
        values = [v for v in percents if v is not None]
        stated = float(m.group("pct"))
        if not values:
            out.append(f"{case}: the text states a chance of {stated:.0f} % although the rise "
                       "table explains no rise")
            continue
        if m.group("k") is not None and int(m.group("k")) != len(values):
            out.append(f"{case}: the text averages the chance over {m.group('k')} explained "
                       f"rises, the rise table explains {len(values)}")
        mean = sum(values) / len(values)
        if abs(mean - stated) > 1.0:
            out.append(f"{case}: the text states a chance of {stated:.0f} % on average, the "
                       f"rise table's explained rises average {mean:.1f} % "
                       f"({', '.join(f'{v:.0f} %' for v in values)})")
    return out


_NUM = r"(-?\d+(?:\.\d+)?)"
_BETWEEN = re.compile(rf"between {_NUM} and {_NUM}")
_RANGE_UNIT = re.compile(rf"(?<![\d.]){_NUM}\s*–\s*{_NUM}\s*(?:min⁻¹|min-1|Hz|orders|s\b)")
_RANGE_CELL = re.compile(rf"(?:≤ )?{_NUM}–{_NUM}(?: ≥)?")


def _check_ranges(tables: list[ReportTable], paragraphs: list[tuple[str, str]]) -> list[str]:
    """Ranges whose two ends are printed alike ("between 1500 and 1500")."""
    out = []
    texts = [(f"text of section {sid!r}", t) for sid, t in paragraphs]
    texts += [(t.caption, c) for t in tables for r in t.rows for c in r]
    for where, text in texts:
        for m in (*_BETWEEN.finditer(text), *_RANGE_UNIT.finditer(text)):
            if float(m.group(1)) == float(m.group(2)):
                out.append(f"{where}: a range with equal ends: {m.group(0)!r}")
    for t in tables:
        for r in t.rows:
            for c in r:
                cell = _RANGE_CELL.fullmatch(c.strip())
                if cell and float(cell.group(1)) == float(cell.group(2)):
                    out.append(f"{t.caption}: a range with equal ends: {c!r}")
    return sorted(set(out), key=out.index)


def _check_likely(tables: list[ReportTable], paragraphs: list[tuple[str, str]]) -> list[str]:
    """At most one cause called "likely" per table column and per paragraph."""
    out = []
    for t in tables:
        for j, h in enumerate(t.header):
            cells = [r[j] for r in t.rows if j < len(r)]
            n = sum(c.strip().lower().startswith("likely") for c in cells)
            if n > 1:
                out.append(f"{t.caption}: {n} causes called likely in column {h!r} (rank "
                           "them: one likely, the others possible)")
    for _, text in paragraphs:
        n = len(re.findall(r"\blikely\b", text, flags=re.I))
        if n > 1:
            out.append(f"a paragraph calls {n} causes likely: {text[:90]!r}")
    return out


def _check_summary(tables: list[ReportTable], paragraphs: list[tuple[str, str]]) -> list[str]:
    """The summary page against the pages it summarises."""
    out = []
    for t in tables:
        m = re.match(r"Strongest resonances of (.+?), (.+) \(rank 1", t.caption)
        if not m:
            continue
        case, signal = m.group(1), m.group(2)
        cut = _find(tables, f"Resonances of the order cuts of {case}, {signal}")
        if cut is None:
            out.append(f"{t.caption}: no cut-resonance table of {case}, {signal}")
            continue
        by_rank = {r[0]: r for r in cut.rows}
        for r in t.rows:
            c = by_rank.get(r[0])
            if c is None:
                out.append(f"{t.caption}: rank {r[0]} is not in {cut.caption}")
                continue
            if tuple(r[:7]) != tuple(c[:7]) or r[7] != c[8]:
                out.append(f"{t.caption}: rank {r[0]} reads {r[:8]!r}, {cut.caption} "
                           f"{(*c[:7], c[8])!r}")
            expl = r[t.header.index("explanation")] if "explanation" in t.header else "–"
            if expl != "–":
                out += _check_explanation(t.caption, r[0], expl, _find(tables, f"Rises of {case}"))
        first = next((x for _, x in paragraphs
                      if x.startswith(f"{case}: strongest resonance of the {signal}: ")), None)
        if first is not None and t.rows:
            r1 = t.rows[0]
            head = f"{r1[1]} at {r1[3]} min⁻¹ ({r1[4]} Hz)"
            if head not in first:
                out.append(f"{case}: the text's strongest resonance is not rank 1 of "
                           f"{t.caption} ({head})")
    for t in tables:
        if not t.caption.startswith("Key numbers of "):
            continue
        case = t.caption[len("Key numbers of "):]
        for q, v in t.rows:
            m = re.fullmatch(r"resonances of the order cuts \((.+)\)", q)
            if m:
                cut = _find(tables, f"Resonances of the order cuts of {case}, {m.group(1)}")
                n = int(_number(v.split()[0]))
                if cut is not None and n != len(cut.rows):
                    out.append(f"{case}: the key numbers count {n} cut resonances of "
                               f"{m.group(1)}, the table lists {len(cut.rows)}")
            m = re.fullmatch(r"highest order-cut level \((.+)\)", q)
            if m:
                out += _check_highest_cut(case, m.group(1), v, tables)
            m = re.fullmatch(r"(\d+) rises? in (\d+) speed regions?", v)
            if q.startswith("rises of the") and m:
                rises = _find(tables, f"Rises of {case}")
                regions = _find(tables, f"Resonance regions of {case} ")
                if rises is not None and int(m.group(1)) != len(rises.rows):
                    out.append(f"{case}: the key numbers count {m.group(1)} rises, the rise "
                               f"table lists {len(rises.rows)}")
                if regions is not None and int(m.group(2)) != len(regions.rows):
                    out.append(f"{case}: the key numbers count {m.group(2)} speed regions, the "
                               f"region table lists {len(regions.rows)}")
    return out


def _check_highest_cut(case: str, signal: str, value: str, tables: list[ReportTable]
                       ) -> list[str]:
    """A key number ``"2× mesh (51.18): 52.3 dB re 1 N at 2498 min⁻¹"`` against the highest
    row of the cut-level table of that signal."""
    cut = _find(tables, f"Order-cut levels of {case}, {signal}")
    m = re.fullmatch(r"(.+) \(([\d.]+)\): (-?[\d.]+) .* at (\d+) min⁻¹", value)
    if cut is None or m is None:
        return [f"{case}: the highest order-cut level of {signal} ({value!r}) has no "
                "cut-level table to agree with"]
    col = next(j for j, h in enumerate(cut.header) if h.startswith("max level"))
    rows = [r for r in cut.rows if r[col] != "–"]
    if not rows:
        return [f"{case}: the key numbers state a highest cut level of {signal}, its table "
                "has none"]
    top = max(rows, key=lambda r: float(r[col]))
    if (top[1], top[0], top[col], top[3]) != m.groups():
        return [f"{case}: the key numbers' highest order-cut level of {signal} reads "
                f"{value!r}, the cut-level table's highest row {top!r}"]
    return []


def _check_explanation(where: str, rank: str, expl: str, rises: ReportTable | None
                       ) -> list[str]:
    m = re.fullmatch(r"(.+) at (\d+) min⁻¹", expl)
    if rises is None or m is None:
        return [f"{where}: rank {rank}: explanation {expl!r} names no row of a rise table"]
    speeds = rises.column("speed")
    mech = rises.column("mechanism: cause")
    if not any(sp == m.group(2) and mc == m.group(1) for sp, mc in zip(speeds, mech,
                                                                       strict=True)):
        return [f"{where}: rank {rank}: explanation {expl!r} is not a row of {rises.caption}"]
    return []


def _check_regions(case: str, rises: ReportTable, regions: ReportTable) -> list[str]:
    """Each region's rises and summary against the rises inside its speed span."""
    out = []
    speeds = [_number(s) for s in rises.column("speed")]
    mech = rises.column("mechanism: cause")
    total = 0
    for row in regions.rows:
        sp = _span(row[0])
        n = int(row[regions.header.index("rises")])
        total += n
        if sp is None:
            continue
        inside = [m for s, m in zip(speeds, mech, strict=True) if sp[0] <= s <= sp[1]]
        if len(inside) != n:
            out.append(f"{case}: region {row[0]} counts {n} rises, the rise table has "
                       f"{len(inside)} there")
        summary = row[regions.header.index("mechanisms (rises)")]
        n_un = sum(m.startswith("unexplained") for m in inside)
        m_un = re.search(r"unexplained: (\d+) rises?", summary)
        if (int(m_un.group(1)) if m_un else 0) != n_un:
            out.append(f"{case}: region {row[0]} summary {summary!r} does not match its "
                       f"{n_un} unexplained rises")
        for m in inside:
            if ":" in m and not m.startswith("unexplained"):
                cause = m.split(":", 1)[1].strip()
                if cause not in summary:
                    out.append(f"{case}: region {row[0]} summary {summary!r} omits the rise "
                               f"{m!r}")
    if total != len(rises.rows):
        out.append(f"{case}: the regions count {total} rises, the rise table lists "
                   f"{len(rises.rows)}")
    return out
