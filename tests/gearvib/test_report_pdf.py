"""Tests of the PDF report (gearvib.report.pdf): a typeset document with the HTML's content.

The demo (``gearvib demo --duration 0.25``: the paper's cases 1 and 2, default analysis; fixture
``demo_study`` in conftest.py) is run once per session; its PDF is read back with pdfminer.six
(text with the box of every character) and checked against the page layout and against the
HTML report built from the same sections.
Synthetic documents check the table layout rules (wrapping, repeated header rows, smaller font
for wide tables, long words) without a simulation.
"""

from __future__ import annotations

import itertools
import json
import re
from html import unescape
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure
from pdfminer.high_level import extract_pages
from pdfminer.layout import LAParams, LTChar, LTPage, LTTextContainer
from pdfminer.pdfdocument import PDFDocument
from pdfminer.pdfpage import PDFPage
from pdfminer.pdfparser import PDFParser

from gearvib.io import read_run, write_netcdf
from gearvib.report import SECTION_IDS, AnalysisSettings, build_report
from gearvib.report.case import analyse_case
from gearvib.report.document import FigureImages
from gearvib.report.html import render_html
from gearvib.report.pdf import PAGE, column_widths, write_pdf
from gearvib.report.sections import Block, Section, report_sections
from gearvib.report.wording import count

DEMO_MAX_PAGES = 24  # the demo report has 21 pages with the summary and the NVH pages
# (13 before them; matplotlib pages before: 50)
TOL = 0.5  # pt


@pytest.fixture(scope="module")
def demo(demo_study) -> Path:
    return demo_study.out_dir


@pytest.fixture(scope="module")
def pages(demo) -> list[LTPage]:
    return list(extract_pages(demo / "report.pdf", laparams=LAParams()))


def _chars(obj):
    if isinstance(obj, LTChar):
        yield obj
    elif hasattr(obj, "__iter__"):
        for child in obj:
            yield from _chars(child)


def _text(page: LTPage) -> str:
    return "".join(o.get_text() for o in page if isinstance(o, LTTextContainer))


def _flat(text: str) -> str:
    return "".join(text.split())


def _in_pdf(item: str, pdf: str, *, min_piece: int = 3, window: int = 400) -> bool:
    """Is ``item`` (flattened) in the flattened PDF text, allowing a wrapped table cell?

    A cell that wraps over several lines is extracted line by line, interleaved with the lines
    of its neighbours in the same table row. So the item must be found as consecutive pieces
    (each the longest prefix of the rest that the PDF holds, at least ``min_piece``
    characters), each starting at most ``window`` characters after the end of the previous one.
    """
    if item in pdf:
        return True
    start, rest = 0, item
    while rest:
        found = -1
        for n in range(len(rest), min_piece - 1, -1):
            k = pdf.find(rest[:n], start, start + window + n if start else None)
            if k >= 0:
                found = k
                break
        if found < 0:
            return False
        start, rest = found + n, rest[n:]
        if 0 < len(rest) < min_piece:
            return pdf.find(rest, start, start + window + len(rest)) >= 0
    return True


def _lines(page: LTPage) -> list[str]:
    """The text of every baseline of a page, top to bottom, characters left to right."""
    rows: dict[float, list[LTChar]] = {}
    for c in _chars(page):
        rows.setdefault(round(c.y0, 1), []).append(c)
    return ["".join(c.get_text() for c in sorted(rows[y], key=lambda c: c.x0))
            for y in sorted(rows, reverse=True)]


class _Content(HTMLParser):
    """Text of every heading, paragraph, table caption, table cell and figure caption."""

    TAGS = ("h1", "h2", "h3", "p", "caption", "th", "td", "figcaption")

    def __init__(self) -> None:
        super().__init__()
        self.items: list[tuple[str, str]] = []
        self._tag: str | None = None
        self._buf: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag in self.TAGS:
            self._tag, self._buf = tag, []

    def handle_endtag(self, tag):
        if tag == self._tag:
            self.items.append((tag, "".join(self._buf)))
            self._tag = None

    def handle_data(self, data):
        if self._tag is not None:
            self._buf.append(data)


def _html_items(html: str) -> list[tuple[str, str]]:
    parser = _Content()
    parser.feed(html)
    return parser.items


# --------------------------------------------------------------------------- the demo report


def test_demo_pdf_is_a_short_numbered_document(demo, pages):
    n = len(pages)
    assert 6 <= n <= DEMO_MAX_PAGES
    for k, page in enumerate(pages, start=1):
        footer = [c for c in _chars(page) if c.y1 < PAGE.bottom]
        line = _flat("".join(c.get_text() for c in sorted(footer, key=lambda c: c.x0)))
        assert line == f"gearvibdemo:thepaper'scases1and2page{k}of{n}", line


def test_every_character_inside_the_margins(pages):
    bad = []
    for page in pages:
        for c in _chars(page):
            inside_x = PAGE.left - TOL <= c.x0 and c.x1 <= PAGE.width - PAGE.right + TOL
            in_frame = PAGE.bottom - TOL <= c.y0 and c.y1 <= PAGE.height - PAGE.top + TOL
            in_footer = PAGE.footer - 3 <= c.y0 and c.y1 <= PAGE.bottom
            if not (inside_x and (in_frame or in_footer)):
                bad.append((page.pageid, c.get_text(), round(c.x0), round(c.y0)))
    assert not bad, bad[:20]


def test_no_text_is_drawn_over_other_text(pages):
    """Characters on one baseline do not overlap (cell text never runs into the next cell)."""
    for page in pages:
        lines: dict[float, list[LTChar]] = {}
        for c in _chars(page):  # (as _lines, keeping the boxes)
            if c.get_text().strip():
                lines.setdefault(round(c.y0, 1), []).append(c)
        for line in lines.values():
            line.sort(key=lambda c: c.x0)
            for a, b in itertools.pairwise(line):
                assert b.x0 >= a.x1 - 0.3 * a.width, (page.pageid, a.get_text(), b.get_text())


def test_pages_are_well_filled(pages):
    top = PAGE.height - PAGE.top
    fill = []
    for page in pages:
        low = min(o.y0 for o in page if o.y0 > PAGE.bottom - 1)
        fill.append((top - low) / PAGE.text_height)
    # the contents end the front matter (summary) and the first section starts a new page
    contents = next(k for k, p in enumerate(pages) if "Contents" in _text(p))
    body = [f for k, f in enumerate(fill[:-1]) if k != contents]
    assert min(body) > 0.5, fill  # no heading or small table alone on a page
    assert np.mean(fill) > 0.75, fill


def test_pdf_carries_every_heading_caption_and_cell_of_the_html(demo, pages):
    html = (demo / "report.html").read_text(encoding="utf-8")
    items = _html_items(html)
    kinds = {k for k, _ in items}
    assert {"h1", "h2", "h3", "caption", "th", "td", "figcaption"} <= kinds
    assert len(items) > 500
    pdf = _flat("".join(_text(p) for p in pages))
    missing = [(k, t) for k, t in items if not _in_pdf(_flat(t), pdf)]
    assert not missing, missing[:10]


def test_contents_and_anchors_point_at_the_sections(demo, pages):
    with open(demo / "report.pdf", "rb") as fh:
        doc = PDFDocument(PDFParser(fh))
        page_no = {p.pageid: k for k, p in enumerate(PDFPage.create_pages(doc), start=1)}
        outline = [(level, title, dest) for level, title, dest, *_ in doc.get_outlines()]
        dests = {sid: doc.get_dest(sid) for sid in SECTION_IDS}
    html = (demo / "report.html").read_text(encoding="utf-8")
    sections = [(sid, unescape(t)) for sid, t in
                re.findall(r'<section id="([a-z-]+)">\n<h2>(.*?)</h2>', html)]
    assert [t for level, t, _ in outline if level == 1] == [t for _, t in sections]
    first = next(k for k, p in enumerate(pages) if "Contents" in _text(p))
    assert first <= 2  # after the summary (the front section)
    contents = {}  # contents entries: title, dot leader, page number on one line
    for line in _lines(pages[first]):
        m = re.fullmatch(r"(.*?)\s*(?:\.\s*){3,}(\d+)", line.strip())
        if m:
            contents[_flat(m.group(1))] = int(m.group(2))
    assert len(contents) == len(sections)
    for sid, title in sections:
        page = page_no[dests[sid][0].objid]  # named destination = the HTML anchor
        assert _flat(title) in _flat(_text(pages[page - 1]))
        assert contents[_flat(title)] == page, (title, page)


def test_demo_pdf_is_undated_and_titled(demo):
    data = (demo / "report.pdf").read_bytes()
    assert data.startswith(b"%PDF-")
    assert b"/CreationDate" not in data and b"/ModDate" not in data
    with open(demo / "report.pdf", "rb") as fh:
        info = PDFDocument(PDFParser(fh)).info[0]
    assert info["Title"] == b"gearvib demo: the paper's cases 1 and 2"
    assert info["Creator"].startswith(b"gearvib ")


# --------------------------------------------------------------------------- titles, wording


def test_titles_come_from_the_gear_sets_not_file_names(demo, tmp_path):
    ds = read_run(demo / "paper-case1.nc")
    cfg = json.loads(ds.attrs["config_json"])
    for key in ("case", "label", "study"):
        cfg["model"].pop(key)
    ds.attrs["config_json"] = json.dumps(cfg)
    run = write_netcdf(ds, tmp_path / "two.nc")
    quick = AnalysisSettings(stability_points=8, map_resolution_hz=40.0)
    paths = build_report([run], tmp_path / "out", analysis=quick)
    html = paths.html.read_text(encoding="utf-8")
    title = re.search(r"<h1>(.*?)</h1>", html).group(1)
    assert title == "Order-analysis report: Paper example, case 1: 3 planets at 120 deg " \
                    "(z_s = 33, z_r = -114), rigid bearings"
    subtitle = re.search(r"</h1>\n<p>(.*?)</p>", html).group(1)
    assert subtitle.startswith("Case two (Paper example, case 1:")
    assert "two (two)" not in html and "two: two" not in html and "gearvib report:" not in html


def test_counts_are_pluralised(demo):
    ds = read_run(demo / "paper-case1.nc")
    ds.attrs["config_json"] = "{}"  # no gear set: no Floquet chart, a quick analysis
    ca = analyse_case(ds, name="bare", settings=AnalysisSettings(map_resolution_hz=40.0))
    assert len(ca.regions) >= 2
    text, regions = {}, ca.regions
    for n in (1, 2):
        ca.regions = regions[:n]
        (res,) = [s for s in report_sections([ca]) if s.id == "resonances"]
        text[n] = next(b.text for b in res.blocks if b.kind == "text")
    assert "; 1 speed region." in text[1]
    assert "; 2 speed regions." in text[2]
    assert not re.search(r"\b1 (regions|rises|speed regions|forced resonances|parametric "
                         r"instabilities)\b", text[1] + text[2])
    assert not re.search(r"\b([02-9]|\d\d+) (rise|forced resonance|parametric instability),",
                         text[1] + text[2])
    assert count(1, "mesh", "meshes") == "1 mesh" and count(0, "region") == "0 regions"


# --------------------------------------------------------------------------- table layout


def _synthetic_sections() -> list[Section]:
    long_rows = [(f"{i}", f"{1000 + 7.5 * i:.1f}", "principal" if i % 2 else "sum",
                  f"value with a few words in row {i}") for i in range(150)]
    wide_header = ("speed [min⁻¹]", "f_mesh [Hz]", "f [Hz]", "order", "mode", "rise [dB]",
                   "mechanism", "note", "comment")
    wide_rows = [(f"{800 + i}", f"{340 + i}", f"{1780 + i}", "5", "f3=f4", "13.9",
                  "parametric instability (principal, n=3) near the planet mode pair",
                  "coincides with principal region n=4 of f3=f4 and the sum region "
                  "(f2 + f5)/4", "§§§") for i in range(12)]
    hashes = [("configuration SHA-256", "0123456789abcdef" * 12),
              ("analysis settings", json.dumps({f"key_{i}": i / 7 for i in range(30)}))]
    return [
        Section("long", "A long table", (
            Block("heading", "case ≈ 2 f₂/4 at 840 min⁻¹"),
            Block("text", "Paragraph text wraps at the text width. " * 30),
            Block("table", "Long table", ("n", "f_mesh [Hz]", "kind", "text"),
                  tuple(long_rows)),)),
        Section("wide", "A wide table", (
            Block("table", "Wide table", wide_header, tuple(wide_rows)),
            Block("table", "Unbreakable words", ("item", "value"), tuple(hashes)),
            Block("table", "Empty table", ("a", "b"), ()),
            Block("figure", "A figure that could not be drawn", figure=lambda: None))),
    ]


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    out = tmp_path_factory.mktemp("synthetic")
    sections = _synthetic_sections()
    n = write_pdf(sections, out / "a.pdf", title="Synthetic", subtitle="tables")
    return out, sections, n, list(extract_pages(out / "a.pdf", laparams=LAParams()))


def test_long_table_repeats_its_header_row_on_every_page(synthetic):
    _, _, n, pages = synthetic
    assert n == len(pages) >= 3
    with_rows = [p for p in pages if re.search(r"valuewithafewwordsinrow\d+", _flat(_text(p)))]
    assert len(with_rows) >= 3
    for p in with_rows:  # the header row: bold text at the table's font size, top line
        head = sorted((c for c in _chars(p) if "Bold" in c.fontname and c.size < 8.1),
                      key=lambda c: (-round(c.y0), c.x0))
        assert _flat("".join(c.get_text() for c in head)) == "nf_mesh[Hz]kindtext"
    rows = sorted(int(m) for p in with_rows for m in re.findall(r"in row (\d+)\b", _text(p)))
    assert rows == list(range(150))  # every row once, none lost at a page break


def test_wide_tables_get_a_smaller_font_and_fit(synthetic):
    _, _, _, pages = synthetic
    sizes: dict[str, set[float]] = {"long": set(), "wide": set()}
    for p in pages:
        for c in _chars(p):
            t = c.get_text()
            if t == "§":
                sizes["wide"].add(round(c.size, 1))
            elif t == "w" and PAGE.bottom < c.y0:
                sizes["long"].add(round(c.size, 1))
            assert PAGE.left - TOL <= c.x0 and c.x1 <= PAGE.width - PAGE.right + TOL
    assert sizes["wide"] and max(sizes["wide"]) <= 7.0
    assert 8.0 in sizes["long"]


def test_placeholders_and_unicode_come_through(synthetic):
    _, _, _, pages = synthetic
    text = _flat("".join(_text(p) for p in pages))
    assert "(none)" in text
    assert _flat("A figure that could not be drawn (not available)") in text
    assert "case≈2f₂/4at840min⁻¹" in text
    assert "0123456789abcdef" * 12 in text  # the long word is split at the cell edge, kept


def test_synthetic_pdf_is_byte_identical_across_runs_and_paths(synthetic, tmp_path):
    out, sections, _, _ = synthetic
    write_pdf(sections, tmp_path / "other-name.pdf", title="Synthetic", subtitle="tables")
    assert (tmp_path / "other-name.pdf").read_bytes() == (out / "a.pdf").read_bytes()


def test_html_and_pdf_share_one_rendering_of_each_figure(tmp_path):
    calls = []

    def draw():
        calls.append(1)
        fig = Figure(figsize=(8, 4))
        fig.add_subplot().plot([0, 1], [1, 0])
        return fig

    sections = [Section("s", "S", (Block("figure", "caption", figure=draw),))]
    images = FigureImages()
    html = render_html(sections, title="T", images=images)
    write_pdf(sections, tmp_path / "f.pdf", title="T", images=images)
    assert len(calls) == 1
    assert "caption" in html and "caption" in _text(next(iter(extract_pages(tmp_path /
                                                                             "f.pdf"))))


@pytest.mark.parametrize(("natural", "minimum", "available", "kept"), [
    ([50, 60, 70], [20, 20, 20], 300, [0, 1, 2]),            # fits: natural widths
    ([40, 400, 30, 600], [30, 60, 25, 80], 480, [0, 2]),     # narrow columns keep theirs
    ([10, 1000, 50], [5, 400, 45], 470, [0, 2]),
    ([300, 300, 120], [290, 10, 10], 400, []),   # a narrow column must not starve the others
    ([300, 300], [290, 280], 400, []),           # minimums do not fit: scaled
    ([10, 2000], [10, 500], 480, []),            # a 500 pt word: all scaled
])
def test_column_widths_fit_and_favour_narrow_columns(natural, minimum, available, kept):
    w = column_widths(natural, minimum, available)
    assert sum(w) <= available + 1e-9
    for j in kept:
        assert w[j] == natural[j]
    if sum(natural) > available and sum(minimum) < available:
        assert all(wj >= mj - 1e-9 for wj, mj in zip(w, minimum, strict=True))
        assert sum(w) == pytest.approx(available)
    if sum(minimum) >= available:
        assert w == pytest.approx([available * m / sum(minimum) for m in minimum])
