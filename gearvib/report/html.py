"""Self-contained HTML report: one file, images embedded as base64 PNG, no scripts.

The page is built with :class:`string.Template` and :func:`html.escape` (no template engine),
from the sections of :func:`gearvib.report.figures.report_sections` -- the same list the PDF
writer (:mod:`gearvib.report.pdf`) renders, with the same figure images
(:class:`~gearvib.report.document.FigureImages`). Every section has a stable ``id``
(``summary``, ``order-cuts``, ``parameters``, ``modes``, ...), which is also the PDF's named
destination of that section. Front sections (the summary, a verdict) stand above the table of
contents. PNGs are written without the ``Software`` tag, so the same input
gives the same bytes.
"""

from __future__ import annotations

import base64
from collections.abc import Sequence
from html import escape
from string import Template

from gearvib import __version__
from gearvib.report.blocks import Block, Section
from gearvib.report.document import (
    EMPTY_TABLE,
    HTML_DPI,
    FigureImages,
    footer_text,
    is_emphasised,
    missing_figure_text,
)

__all__ = ["render_html"]

_PAGE = Template("""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="generator" content="gearvib $version">
<title>$title</title>
<style>
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
       max-width: 1100px; margin: 2em auto; padding: 0 1em; color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; border-bottom: 2px solid #444; }
h2 { font-size: 1.3em; margin-top: 2em; border-bottom: 1px solid #aaa; }
h3 { font-size: 1.05em; margin-top: 1.2em; }
table { border-collapse: collapse; margin: 0.6em 0 1.2em; font-size: 0.85em; }
caption { text-align: left; font-weight: 600; padding-bottom: 0.3em; }
th, td { border: 1px solid #bbb; padding: 2px 6px; text-align: left; vertical-align: top; }
th { background: #eee; }
figure { margin: 1em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 0.85em; color: #444; }
nav ol { columns: 2; font-size: 0.9em; }
p.verdict { font-weight: 600; }
</style>
</head>
<body>
<h1>$title</h1>
<p>$subtitle</p>
$front
<nav><ol>
$toc
</ol></nav>
$sections
<footer><p>$footer</p></footer>
</body>
</html>
""")


def _table(b: Block) -> str:
    head = "".join(f"<th>{escape(h)}</th>" for h in b.header)
    body = "\n".join("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in r) + "</tr>"
                     for r in b.rows)
    if not b.rows:
        body = f'<tr><td colspan="{len(b.header)}">{escape(EMPTY_TABLE)}</td></tr>'
    return (f"<table>\n<caption>{escape(b.text)}</caption>\n<thead><tr>{head}</tr></thead>\n"
            f"<tbody>\n{body}\n</tbody>\n</table>")


def _block(b: Block, section_id: str, images: FigureImages) -> str:
    if b.kind == "heading":
        return f"<h3>{escape(b.text)}</h3>"
    if b.kind == "text":
        cls = ' class="verdict"' if is_emphasised(b, section_id) else ""
        return f"<p{cls}>{escape(b.text)}</p>"
    if b.kind == "table":
        return _table(b)
    if b.kind == "figure":
        image = images.get(b)
        if image is None:
            return f"<p>{escape(missing_figure_text(b))}</p>"
        data = base64.b64encode(image.at(HTML_DPI)).decode("ascii")
        return (f'<figure><img alt="{escape(b.text, quote=True)}" '
                f'src="data:image/png;base64,{data}">'
                f"<figcaption>{escape(b.text)}</figcaption></figure>")
    raise ValueError(f"unknown block kind {b.kind!r}")


def render_html(sections: Sequence[Section], *, title: str, subtitle: str = "",
                images: FigureImages | None = None) -> str:
    """The complete HTML page.

    Parameters
    ----------
    sections : sequence of Section
        From :func:`gearvib.report.figures.report_sections`.
    title : str
        Page title.
    subtitle : str
        A line under the title.
    images : FigureImages, optional
        Figure images shared with the PDF writer (default: rendered here).

    Returns
    -------
    str
        The page (UTF-8 text, no external resources).
    """
    images = images if images is not None else FigureImages((HTML_DPI,))
    toc = "\n".join(f'<li><a href="#{s.id}">{escape(s.title)}</a></li>' for s in sections)
    front: list[str] = []
    parts: list[str] = []
    for s in sections:
        inner = "\n".join(_block(b, s.id, images) for b in s.blocks)
        (front if s.front else parts).append(
            f'<section id="{s.id}">\n<h2>{escape(s.title)}</h2>\n{inner}\n</section>')
    return _PAGE.substitute(title=escape(title), subtitle=escape(subtitle), toc=toc,
                            front="\n".join(front), sections="\n".join(parts),
                            version=escape(__version__), footer=escape(footer_text()))
