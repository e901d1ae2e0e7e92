"""The PDF report: an A4 document typeset with ReportLab's platypus layout engine.

The PDF renders the same :class:`~gearvib.report.figures.Section` list as the HTML report
(:mod:`gearvib.report.html`), block by block, with the same figure images
(:class:`~gearvib.report.document.FigureImages`):

* a title page head with the subtitle, the front sections (the summary or verdict), a
  contents list with page numbers (built in as many passes as the page numbers need), then the
  sections flowing one after the other;
* every section title is a named destination with the section's HTML id (``report.pdf#modes``
  opens the modes section) and an outline entry; the case headings below it are outline
  entries too;
* paragraphs wrap at the text width; tables are real tables whose cells wrap, with column
  widths from their content, the header row repeated on every page a table runs over, and a
  smaller font for wide tables (7 pt from six columns, down to 6 pt until the longest word of
  every column fits); a caption stays with its table, a heading with what follows it;
* figures span the text width with the caption below, kept on one page (scaled down by up to
  15 % where that keeps them on the page they start on);
* every page has a footer with the report title and "page N of M".

Text is set in DejaVu Sans, the font shipped with matplotlib (so the symbols of the report, such
as min⁻¹, ≈, Δ, μ, print on every machine), embedded as a subset. The output is deterministic:
ReportLab's invariant mode (fixed document id) and a document information dictionary without
dates, so the same input gives the same bytes.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING
from xml.sax.saxutils import escape

import matplotlib
from reportlab import rl_config
from reportlab.lib import colors
from reportlab.lib.fonts import addMapping
from reportlab.lib.pagesizes import A4
from reportlab.lib.styles import ParagraphStyle
from reportlab.lib.units import mm
from reportlab.lib.utils import ImageReader
from reportlab.pdfbase import pdfmetrics
from reportlab.pdfbase.pdfdoc import PDFDictionary, PDFInfo, PDFName, PDFString
from reportlab.pdfbase.ttfonts import TTFont
from reportlab.pdfgen.canvas import Canvas
from reportlab.platypus import (
    BaseDocTemplate,
    CondPageBreak,
    Flowable,
    Frame,
    IndexingFlowable,
    KeepTogether,
    PageTemplate,
    Paragraph,
    Spacer,
    Table,
    TableStyle,
)
from reportlab.platypus.tableofcontents import TableOfContents

from gearvib import __version__
from gearvib.report.blocks import Block, Section
from gearvib.report.document import (
    EMPTY_TABLE,
    PDF_DPI,
    FigureImages,
    footer_text,
    is_emphasised,
    missing_figure_text,
)

if TYPE_CHECKING:
    from PIL import Image

__all__ = ["PAGE", "PageLayout", "column_widths", "write_pdf"]


@dataclass(frozen=True)
class PageLayout:
    """Page geometry of the PDF report [pt; 1 pt = 1/72 in].

    Attributes
    ----------
    width, height : float
        Page size (A4 portrait).
    left, right, top, bottom : float
        Margins of the text frame.
    footer : float
        Baseline of the footer above the lower page edge (inside the bottom margin).
    """

    width: float
    height: float
    left: float
    right: float
    top: float
    bottom: float
    footer: float

    @property
    def text_width(self) -> float:
        """Width of the text frame."""
        return self.width - self.left - self.right

    @property
    def text_height(self) -> float:
        """Height of the text frame."""
        return self.height - self.top - self.bottom


PAGE = PageLayout(width=A4[0], height=A4[1], left=18 * mm, right=18 * mm, top=15 * mm,
                  bottom=17 * mm, footer=9 * mm)
"""Page layout of the report."""

_FONT, _BOLD = "GearvibSans", "GearvibSans-Bold"
_FONT_FILES = {_FONT: "DejaVuSans.ttf", _BOLD: "DejaVuSans-Bold.ttf",
               "GearvibSans-Oblique": "DejaVuSans-Oblique.ttf",
               "GearvibSans-BoldOblique": "DejaVuSans-BoldOblique.ttf"}

_TABLE_SIZES = (8.0, 7.5, 7.0, 6.5, 6.0)  # font sizes tried for a table, largest first
_WIDE_TABLE_COLUMNS = 6  # from this many columns a table starts at 7 pt
_CELL_PAD_X, _CELL_PAD_Y = 3.0, 1.6
_SHORT_TABLE_ROWS = 25  # tables up to this many rows are kept on one page with their caption
_FIGURE_MAX_HEIGHT = 0.72  # of the text height (the caption and a heading fit beside it)
_FIGURE_SHRINK = 0.15  # a figure may shrink this much to fit the rest of a page


def _register_fonts() -> None:
    """Register DejaVu Sans from matplotlib's data folder (once per process)."""
    known = set(pdfmetrics.getRegisteredFontNames())
    folder = Path(matplotlib.get_data_path()) / "fonts" / "ttf"
    for name, file in _FONT_FILES.items():
        if name not in known:
            pdfmetrics.registerFont(TTFont(name, str(folder / file)))
    for bold, italic, name in ((0, 0, _FONT), (1, 0, _BOLD), (0, 1, "GearvibSans-Oblique"),
                               (1, 1, "GearvibSans-BoldOblique")):
        addMapping(_FONT, bold, italic, name)


@dataclass(frozen=True)
class _Styles:
    title: ParagraphStyle
    subtitle: ParagraphStyle
    contents: ParagraphStyle
    toc: ParagraphStyle
    h2: ParagraphStyle
    h3: ParagraphStyle
    body: ParagraphStyle
    verdict: ParagraphStyle
    table_caption: ParagraphStyle
    figure_caption: ParagraphStyle
    closing: ParagraphStyle


def _styles() -> _Styles:
    def st(name: str, size: float, *, bold: bool = False, lead: float = 1.3, before: float = 0,
           after: float = 0, colour: colors.Color = colors.black, keep: bool = False
           ) -> ParagraphStyle:
        return ParagraphStyle(name, fontName=_BOLD if bold else _FONT, fontSize=size,
                              leading=round(size * lead, 2), spaceBefore=before,
                              spaceAfter=after, textColor=colour, keepWithNext=int(keep),
                              allowWidows=0, allowOrphans=0)

    grey = colors.HexColor("#444444")
    return _Styles(
        title=st("title", 16, bold=True, lead=1.25, after=5),
        subtitle=st("subtitle", 8.5, after=8, colour=grey),
        contents=st("contents", 12, bold=True, before=2, after=3),
        toc=st("toc", 9, lead=1.35),
        h2=st("h2", 12.5, bold=True, lead=1.25, before=12, after=4, keep=True),
        h3=st("h3", 10, bold=True, lead=1.25, before=6, after=3, keep=True),
        body=st("body", 8.5, lead=1.35, after=4),
        verdict=st("verdict", 8.5, bold=True, lead=1.35, after=4),
        table_caption=st("table caption", 8.5, bold=True, before=4, after=3, keep=True),
        figure_caption=st("figure caption", 7.5, before=2, after=8, colour=grey),
        closing=st("closing", 7.5, before=10, colour=grey),
    )


def _text(s: str) -> str:
    """Plain text as ReportLab paragraph markup."""
    return escape(s)


# --------------------------------------------------------------------------- flowables


class _Heading(Paragraph):
    """A section or case heading: named destination, outline entry, contents entry."""

    def __init__(self, text: str, style: ParagraphStyle, *, key: str, level: int) -> None:
        super().__init__(f'<a name="{key}"/>{_text(text)}', style)
        self.plain_text = text
        self.key = key
        self.level = level


class _PageCount(IndexingFlowable):
    """Invisible last flowable recording the page count of every build pass.

    ReportLab repeats a build until every indexing flowable is satisfied; this one is satisfied
    when two passes end on the same page, so the footers' "of M" is the final page count.
    """

    def __init__(self) -> None:
        super().__init__()
        self.pages = 0
        self.previous = 0

    def beforeBuild(self) -> None:
        self.previous = self.pages

    def isSatisfied(self) -> bool:
        return self.pages == self.previous

    def wrap(self, availWidth: float, availHeight: float) -> tuple[float, float]:
        return 0.0, 0.0

    def draw(self) -> None:
        self.pages = self.canv.getPageNumber()


class _UndatedInfo(PDFInfo):
    """Document information without creation and modification dates (reproducible files)."""

    def format(self, document):
        return PDFDictionary({"Title": PDFString(self.title),
                              "Subject": PDFString(self.subject),
                              "Creator": PDFString(self.creator),
                              "Producer": PDFString(self.producer),
                              "Trapped": PDFName("False")}).format(document)


class _ReportCanvas(Canvas):
    """ReportLab canvas: undated document information, section anchors as named destinations.

    ReportLab's invariant mode alone gives identical bytes too, but with a made-up creation
    date (2000-01-01); the report states no date at all. ReportLab resolves ``<a name>``
    targets only for links inside the document; listing the section ids in the catalogue's
    ``Dests`` makes ``report.pdf#modes`` open the modes section in a viewer, as ``#modes`` does
    in the HTML report. Both reach into the canvas's PDF document (``_doc``), so each is skipped
    if a ReportLab version lacks it (the tests notice).
    """

    def __init__(self, *args, anchors: Sequence[str] = (), **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.anchors = tuple(anchors)
        if hasattr(self, "_doc"):  # title, subject etc. are set on it by the document later
            self._doc.info = _UndatedInfo()

    def save(self) -> None:
        known = getattr(self, "_destinations", {})
        dests = {k: known[k] for k in self.anchors if k in known}
        catalog = getattr(getattr(self, "_doc", None), "Catalog", None)
        if dests and catalog is not None:
            catalog.Dests = PDFDictionary(dests)
        super().save()


class _Document(BaseDocTemplate):
    """One frame per page, a footer, and the contents/outline bookkeeping of the headings."""

    def __init__(self, target: str, *, title: str, subject: str, page_count: _PageCount
                 ) -> None:
        super().__init__(target, pagesize=(PAGE.width, PAGE.height), leftMargin=PAGE.left,
                         rightMargin=PAGE.right, topMargin=PAGE.top, bottomMargin=PAGE.bottom,
                         title=title, subject=subject, creator=f"gearvib {__version__}",
                         producer="ReportLab", invariant=1, pageCompression=1)
        self.report_title = title
        self.page_count = page_count
        frame = Frame(PAGE.left, PAGE.bottom, PAGE.text_width, PAGE.text_height, id="text",
                      leftPadding=0, rightPadding=0, topPadding=0, bottomPadding=0)
        self.addPageTemplates([PageTemplate(id="page", frames=[frame], onPage=self._footer)])

    def _footer(self, canv: Canvas, doc: BaseDocTemplate) -> None:
        size = 7.5
        total = self.page_count.previous
        right = f"page {canv.getPageNumber()}" + (f" of {total}" if total else "")
        room = PAGE.text_width - pdfmetrics.stringWidth(right, _FONT, size) - 12
        left = _shorten(self.report_title, room, _FONT, size)
        canv.saveState()
        canv.setStrokeColor(colors.HexColor("#999999"))
        canv.setLineWidth(0.4)
        canv.line(PAGE.left, PAGE.footer + 9, PAGE.width - PAGE.right, PAGE.footer + 9)
        canv.setFont(_FONT, size)
        canv.setFillColor(colors.HexColor("#444444"))
        canv.drawString(PAGE.left, PAGE.footer, left)
        canv.drawRightString(PAGE.width - PAGE.right, PAGE.footer, right)
        canv.restoreState()

    def afterFlowable(self, flowable: Flowable) -> None:
        if isinstance(flowable, _Heading):
            if flowable.level == 0:
                self.notify("TOCEntry", (0, _text(flowable.plain_text), self.page,
                                         flowable.key))
            self.canv.addOutlineEntry(flowable.plain_text, flowable.key, level=flowable.level,
                                      closed=flowable.level == 0)


def _shorten(text: str, width: float, font: str, size: float) -> str:
    """``text``, cut with an ellipsis to fit ``width``."""
    if pdfmetrics.stringWidth(text, font, size) <= width:
        return text
    while text and pdfmetrics.stringWidth(text + "…", font, size) > width:
        text = text[:-1]
    return text.rstrip() + "…"


# --------------------------------------------------------------------------- tables


def column_widths(natural: Sequence[float], minimum: Sequence[float], available: float
                  ) -> list[float]:
    """Column widths of a table that must fit ``available`` (automatic table layout).

    All columns get their natural (unwrapped) width when the table fits. Otherwise the columns
    that fit within an equal share of the width keep their natural width (short columns such
    as speeds and counts never wrap), and the remaining width is shared among the other
    columns in proportion to their natural widths, none below its minimum (longest word) width.
    When even the minimum widths do not fit, they are scaled down (long words are then split).

    Parameters
    ----------
    natural, minimum : sequence of float
        Width of the longest cell text and of the longest word, per column [pt].
    available : float
        Width to fill at most [pt].

    Returns
    -------
    list of float
        Column widths summing to at most ``available`` (to rounding).
    """
    minimum = [float(m) for m in minimum]
    nat = [max(float(n), m) for n, m in zip(natural, minimum, strict=True)]
    if sum(nat) <= available:
        return nat
    if sum(minimum) >= available:
        return [available * m / sum(minimum) for m in minimum]
    width: dict[int, float] = {}
    # invariant: the open columns' minimum widths fit into the free width
    while len(width) < len(nat):
        open_ = [j for j in range(len(nat)) if j not in width]
        free = available - sum(width.values())
        need = sum(minimum[j] for j in open_)
        narrow = [j for j in sorted(open_, key=lambda j: nat[j])
                  if nat[j] <= free / len(open_) and nat[j] - minimum[j] <= free - need]
        if narrow:  # the narrowest column that fits within an equal share keeps its width
            width[narrow[0]] = nat[narrow[0]]
            continue
        share = {j: free * nat[j] / sum(nat[i] for i in open_) for j in open_}
        short = [j for j in open_ if share[j] < minimum[j]]
        if not short:
            width.update(share)
            break
        width.update({j: minimum[j] for j in short})
    return [width[j] for j in range(len(nat))]


def _measure(cells: Sequence[str], font: str, size: float) -> tuple[float, float]:
    """Natural and minimum width of a column (cell padding included)."""
    pad = 2 * _CELL_PAD_X + 1
    nat = max((pdfmetrics.stringWidth(c, font, size) for c in cells), default=0.0)
    word = max((pdfmetrics.stringWidth(w, font, size) for c in cells for w in c.split()),
               default=0.0)
    return nat + pad, word + pad


def _table(b: Block, styles: _Styles) -> tuple[list[Flowable], bool]:
    """Caption and table of a table block; True if it is short enough to keep on one page."""
    width = PAGE.text_width
    n = max([len(b.header), *(len(r) for r in b.rows)], default=1)
    header = [*b.header, *[""] * (n - len(b.header))]
    rows = [[*r, *[""] * (n - len(r))] for r in b.rows]
    sizes = [s for s in _TABLE_SIZES if n < _WIDE_TABLE_COLUMNS or s <= 7.0]
    for size in sizes:
        measured = [(_measure([header[j]], _BOLD, size), _measure([r[j] for r in rows], _FONT,
                                                                  size)) for j in range(n)]
        natural = [max(h[0], c[0]) for h, c in measured]
        minimum = [max(h[1], c[1]) for h, c in measured]
        if sum(minimum) <= width:
            break
    cell = ParagraphStyle("cell", fontName=_FONT, fontSize=size, leading=round(1.22 * size, 2))
    head = ParagraphStyle("head", parent=cell, fontName=_BOLD)
    data: list[list[Flowable]] = [[Paragraph(_text(h), head) for h in header]]
    style = [("GRID", (0, 0), (-1, -1), 0.4, colors.HexColor("#b0b0b0")),
             ("BACKGROUND", (0, 0), (-1, 0), colors.HexColor("#ececec")),
             ("VALIGN", (0, 0), (-1, -1), "TOP"),
             ("LEFTPADDING", (0, 0), (-1, -1), _CELL_PAD_X),
             ("RIGHTPADDING", (0, 0), (-1, -1), _CELL_PAD_X),
             ("TOPPADDING", (0, 0), (-1, -1), _CELL_PAD_Y),
             ("BOTTOMPADDING", (0, 0), (-1, -1), _CELL_PAD_Y + 0.6)]
    if rows:
        data += [[Paragraph(_text(c), cell) for c in r] for r in rows]
    else:
        data.append([Paragraph(_text(EMPTY_TABLE), cell)] + [""] * (n - 1))
        style.append(("SPAN", (0, 1), (-1, 1)))
    table = Table(data, colWidths=column_widths(natural, minimum, width), repeatRows=1,
                  hAlign="LEFT", style=TableStyle(style))
    return [Paragraph(_text(b.text), styles.table_caption), table], len(rows) <= \
        _SHORT_TABLE_ROWS


# --------------------------------------------------------------------------- figures


class _Picture(Flowable):
    """A figure image at the text width, centred; :class:`_KeepFigure` may shrink it a little."""

    def __init__(self, image: Image.Image, width: float, height: float) -> None:
        super().__init__()
        self.image = image
        self.full_width, self.full_height = width, height
        self.scale = 1.0
        self.spaceBefore = 6.0

    def wrap(self, availWidth: float, availHeight: float) -> tuple[float, float]:
        self.available_width = availWidth
        return availWidth, self.full_height * self.scale

    def draw(self) -> None:
        w, h = self.full_width * self.scale, self.full_height * self.scale
        # mask=None: the figures are opaque, no soft mask for the constant alpha channel
        self.canv.drawImage(ImageReader(self.image),
                            0.5 * (self.available_width - w), 0, w, h, mask=None)


class _KeepFigure(KeepTogether):
    """A figure with its caption (and the headings before it) kept on one page.

    When the group is up to :data:`_FIGURE_SHRINK` too tall for the rest of the page, the
    figure is scaled down to fit there instead of leaving the space empty.
    """

    def __init__(self, flowables: list[Flowable], picture: _Picture) -> None:
        super().__init__(flowables)
        self.picture = picture

    def split(self, availWidth: float, availHeight: float) -> list[Flowable]:
        self.picture.scale = 1.0
        need = -availHeight
        for k, f in enumerate(self._content):
            need += f.wrapOn(self.canv, availWidth, availHeight)[1] + f.getSpaceAfter() + (
                f.getSpaceBefore() if k else 0.0)
        if need > 0:
            scale = (self.picture.full_height - need - 2.0) / self.picture.full_height
            if scale >= 1.0 - _FIGURE_SHRINK:
                self.picture.scale = scale
                return list(self._content)
        return super().split(availWidth, availHeight)


def _figure(b: Block, images: FigureImages, styles: _Styles) -> list[Flowable]:
    image = images.get(b)
    if image is None:
        return [Paragraph(_text(missing_figure_text(b)), styles.body)]
    w = PAGE.text_width
    h = w * image.aspect
    if h > _FIGURE_MAX_HEIGHT * PAGE.text_height:
        h = _FIGURE_MAX_HEIGHT * PAGE.text_height
        w = h / image.aspect
    return [_Picture(image.image(PDF_DPI), w, h), Paragraph(_text(b.text), styles.figure_caption)]


# --------------------------------------------------------------------------- story


def _story(sections: Sequence[Section], title: str, subtitle: str, images: FigureImages,
           styles: _Styles, page_count: _PageCount) -> list[Flowable]:
    toc = TableOfContents(dotsMinLevel=0, rightColumnWidth=30,
                          levelStyles=[ParagraphStyle("toc0", parent=styles.toc,
                                                      leftIndent=0, firstLineIndent=0)],
                          tableStyle=TableStyle([("VALIGN", (0, 0), (-1, -1), "TOP"),
                                                 ("LEFTPADDING", (0, 0), (-1, -1), 0),
                                                 ("RIGHTPADDING", (0, 0), (-1, -1), 0),
                                                 ("TOPPADDING", (0, 0), (-1, -1), 0.5),
                                                 ("BOTTOMPADDING", (0, 0), (-1, -1), 0.5)]))
    story: list[Flowable] = [Paragraph(_text(title), styles.title)]
    if subtitle:
        story.append(Paragraph(_text(subtitle), styles.subtitle))
    for s in [s for s in sections if s.front]:
        story += _section_story(s, images, styles)
    story += [Paragraph("Contents", styles.contents), toc, Spacer(1, 4)]
    for s in [s for s in sections if not s.front]:
        story += _section_story(s, images, styles)
    story += [Paragraph(_text(footer_text()), styles.closing), page_count]
    return story


def _section_story(s: Section, images: FigureImages, styles: _Styles) -> list[Flowable]:
    """The flowables of one section: heading, blocks, headings kept with what follows."""
    story: list[Flowable] = []
    pending: list[Flowable] = [_Heading(s.title, styles.h2, key=s.id, level=0)]
    for k, b in enumerate(s.blocks):
        if b.kind == "heading":
            pending.append(_Heading(b.text, styles.h3, key=f"{s.id}.{k}", level=1))
            continue
        if b.kind == "text":
            para = Paragraph(_text(b.text), styles.verdict if is_emphasised(b, s.id)
                             else styles.body)
            # text after a heading introduces what follows: kept with both
            (pending if pending else story).append(para)
            continue
        if b.kind == "table":
            unit, keep = _table(b, styles)
        elif b.kind == "figure":
            unit, keep = _figure(b, images, styles), True
        else:
            raise ValueError(f"unknown block kind {b.kind!r}")
        unit = pending + unit
        pending = []
        pictures = [f for f in unit if isinstance(f, _Picture)]
        if pictures:
            story.append(_KeepFigure(unit, pictures[0]))
        elif keep:
            story.append(KeepTogether(unit))
        else:  # a long table: headings, caption and a few rows at least, then it runs on
            story += [CondPageBreak(0.22 * PAGE.text_height), *unit]
    if pending:
        story.append(KeepTogether(pending))
    return story


def write_pdf(sections: Sequence[Section], path: str | Path, *, title: str,
              subtitle: str = "", images: FigureImages | None = None) -> int:
    """Write the report as an A4 PDF (to ``path``; the caller makes it atomic).

    Parameters
    ----------
    sections : sequence of Section
        From :func:`gearvib.report.figures.report_sections`.
    path : path-like
        Destination file.
    title, subtitle : str
        Report title (also the document title and footer) and the line below it.
    images : FigureImages, optional
        Figure images shared with the HTML writer (default: rendered here).

    Returns
    -------
    int
        Number of pages written.
    """
    _register_fonts()
    images = images if images is not None else FigureImages((PDF_DPI,))
    styles = _styles()
    count = _PageCount()
    doc = _Document(str(path), title=title, subject=subtitle, page_count=count)
    story = _story(sections, title, subtitle, images, styles, count)
    with _binary_streams():
        doc.multiBuild(story,
                       canvasmaker=partial(_ReportCanvas, anchors=[s.id for s in sections]))
    return count.pages


@contextlib.contextmanager
def _binary_streams() -> Iterator[None]:
    """Write the PDF's streams (figures above all) deflated but not ASCII85-encoded.

    ReportLab encodes every stream in ASCII85 by default (``rl_config.useA85``), in pure Python
    unless its optional C accelerator is installed: seconds per report for the figures, and a
    quarter more bytes. Binary streams are what PDF viewers expect. The global setting is
    restored afterwards.
    """
    saved = rl_config.useA85
    rl_config.useA85 = 0
    try:
        yield
    finally:
        rl_config.useA85 = saved
