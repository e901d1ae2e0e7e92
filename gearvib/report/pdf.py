"""Multi-page PDF report with the same content as the HTML report (matplotlib PdfPages).

Text and tables are drawn as monospaced text in A4 figures; figures are the same as in the HTML
report. The PDF metadata ``Creator``, ``Producer`` and ``CreationDate`` are cleared so the same
input gives the same bytes.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from gearvib.report.figures import Section, table_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["PDF_METADATA", "write_pdf"]

PDF_METADATA = {"Creator": None, "Producer": None, "CreationDate": None}

_A4 = (8.27, 11.69)
_LINES_PER_PAGE = 70


def _text_pages(title: str, lines: list[str]) -> list[Figure]:
    from matplotlib.figure import Figure

    pages = [lines[i:i + _LINES_PER_PAGE] for i in range(0, len(lines), _LINES_PER_PAGE)]
    figs = []
    for k, chunk in enumerate(pages or [[]]):
        fig = Figure(figsize=_A4, dpi=100)
        suffix = f" ({k + 1}/{len(pages)})" if len(pages) > 1 else ""
        fig.text(0.06, 0.96, title + suffix, fontsize=13, weight="bold", va="top")
        fig.text(0.06, 0.92, "\n".join(chunk), fontsize=8.5, va="top", family="monospace")
        figs.append(fig)
    return figs


def _section_pages(s: Section) -> list[Figure]:
    figs: list[Figure] = []
    text: list[str] = []

    def flush() -> None:
        if text:
            figs.extend(_text_pages(s.title, text))
            text.clear()

    for b in s.blocks:
        if b.kind == "heading":
            text += ["", b.text.upper(), ""]
        elif b.kind == "text":
            text += [*textwrap.wrap(b.text, 100), ""]
        elif b.kind == "table":
            flush()
            figs.extend(table_figure(f"{s.title}: {b.text}"[:110], b.header, b.rows))
        elif b.kind == "figure":
            fig = b.figure() if b.figure is not None else None
            if fig is None:
                text.append(f"{b.text} (not available)")
                continue
            flush()
            fig.text(0.01, 0.005, textwrap.shorten(b.text, 160), fontsize=6, va="bottom")
            figs.append(fig)
    flush()
    return figs


def write_pdf(sections: Sequence[Section], path: str | Path, *, title: str,
              subtitle: str = "") -> int:
    """Write the report as a multi-page PDF (to ``path``; the caller makes it atomic).

    Parameters
    ----------
    sections : sequence of Section
        From :func:`gearvib.report.figures.report_sections`.
    path : path-like
        Destination file.
    title, subtitle : str
        Title page text.

    Returns
    -------
    int
        Number of pages written.
    """
    from matplotlib.backends.backend_pdf import PdfPages

    cover = [*textwrap.wrap(subtitle, 90), "", "Contents:"]
    cover += [f"  {i + 1}. {s.title}  [{s.id}]" for i, s in enumerate(sections)]
    n = 0
    with PdfPages(path, metadata=dict(PDF_METADATA)) as pdf:
        for fig in _text_pages(title, cover):
            pdf.savefig(fig)
            n += 1
        for s in sections:
            for fig in _section_pages(s):
                pdf.savefig(fig)
                n += 1
    return n
