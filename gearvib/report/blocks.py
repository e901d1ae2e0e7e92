"""The building blocks of a report: :class:`Block` (heading, paragraph, table, figure) and
:class:`Section` (a titled list of blocks with a stable id).

Every report -- simulated runs (:mod:`gearvib.report.sections`), measurements
(:mod:`gearvib.report.measured`), comparisons and diagnoses -- is a list of sections that the
HTML writer (:mod:`gearvib.report.html`) and the PDF writer (:mod:`gearvib.report.pdf`) render
alike. Page builders (:mod:`gearvib.report.nvh`, :mod:`gearvib.report.verdict`) return blocks.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Block", "Section"]


@dataclass(frozen=True)
class Block:
    """One element of a report section.

    Attributes
    ----------
    kind : str
        ``"heading"``, ``"text"``, ``"table"`` or ``"figure"``.
    text : str
        Heading or paragraph text, table or figure caption.
    header : tuple of str
        Table header.
    rows : tuple of tuple of str
        Table rows.
    figure : callable or None
        ``figure() -> Figure | None`` building the figure on demand.
    """

    kind: str
    text: str = ""
    header: tuple[str, ...] = ()
    rows: tuple[tuple[str, ...], ...] = ()
    figure: Any = None


@dataclass(frozen=True)
class Section:
    """A report section with a stable id (the HTML anchor).

    Attributes
    ----------
    id : str
        HTML anchor and PDF named destination.
    title : str
        Section title.
    blocks : tuple of Block
        Its content.
    front : bool
        A front section (the summary, the verdict): written before the table of contents, so
        that the first page of the PDF and the top of the HTML page show it.
    """

    id: str
    title: str
    blocks: tuple[Block, ...]
    front: bool = False
