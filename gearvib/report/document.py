"""What the HTML and the PDF writer share: figure images and the few presentation rules.

Both writers render the same list of :class:`~gearvib.report.figures.Section` objects (built by
:func:`gearvib.report.figures.report_sections`), block by block: headings, paragraphs, tables
(caption, header, rows) and figures (caption, figure builder). This module holds what must be
identical in both documents beyond the blocks themselves:

* :class:`FigureImages` calls each figure builder once and keeps the figure's pixels at every
  resolution the writers ask for (the HTML embeds a PNG at :data:`HTML_DPI`, the PDF places the
  pixels at :data:`PDF_DPI`), so the two documents show the same pictures and no figure is
  computed twice. A figure is drawn once, at the highest resolution; the lower ones are that
  image reduced (box filter), which halves the drawing time of a report. The PDF writer takes
  the pixels as they are (no PNG encoded and decoded again); a PNG is encoded only where one
  is embedded, without ``Software`` tag: the same input gives the same bytes.
* the text of an empty table (:data:`EMPTY_TABLE`), of a figure that could not be drawn
  (:func:`missing_figure_text`), the closing line (:func:`footer_text`) and which paragraphs
  are emphasised (:func:`is_emphasised`).
"""

from __future__ import annotations

import io
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from gearvib import __version__
from gearvib.report.sections import Block

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from PIL import Image

__all__ = [
    "EMPTY_TABLE",
    "HTML_DPI",
    "PDF_DPI",
    "FigureImage",
    "FigureImages",
    "figure_pixels",
    "figure_png",
    "figure_pngs",
    "footer_text",
    "is_emphasised",
    "missing_figure_text",
    "png_bytes",
]

EMPTY_TABLE = "(none)"
"""The single cell of a table without rows."""

HTML_DPI = 100
"""Resolution of the PNGs embedded in the HTML report [dots per inch of the figure size]."""

PDF_DPI = 200
"""Resolution of the PNGs placed in the PDF report (the figure is scaled to the text width,
about 6.9 in, so a 8 in wide figure prints at about 230 dpi)."""


def figure_png(fig: Figure, *, dpi: int = HTML_DPI) -> bytes:
    """PNG bytes of a figure, without the ``Software`` metadata (deterministic)."""
    return figure_pngs(fig, (dpi,))[int(dpi)]


def figure_pngs(fig: Figure, dpis: Iterable[int]) -> dict[int, bytes]:
    """PNG bytes of a figure at several resolutions, drawn once (:func:`figure_pixels`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (drawn on an Agg canvas; its ``dpi`` is restored afterwards).
    dpis : iterable of int
        Resolutions [dots per inch of the figure size].

    Returns
    -------
    dict of int to bytes
        PNG (RGB) per resolution, without ``Software`` tag (the same figure gives the same
        bytes).
    """
    return {dpi: png_bytes(image) for dpi, image in figure_pixels(fig, dpis).items()}


def png_bytes(image: Image.Image) -> bytes:
    """An image as PNG bytes (no ``Software`` tag: the same pixels give the same bytes)."""
    buf = io.BytesIO()
    image.save(buf, format="png")
    return buf.getvalue()


def figure_pixels(fig: Figure, dpis: Iterable[int]) -> dict[int, Image.Image]:
    """The pixels of a figure at several resolutions, drawn once.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (drawn on an Agg canvas; its ``dpi`` is restored afterwards).
    dpis : iterable of int
        Resolutions [dots per inch of the figure size].

    Returns
    -------
    dict of int to PIL.Image.Image
        RGB image per resolution: ``round(width_in * dpi)`` by ``round(height_in * dpi)``
        pixels. The figure is drawn at the highest resolution; each lower one is that image
        reduced with a box filter (the mean of the pixels each new pixel covers). The report
        figures are opaque: the alpha channel is dropped.
    """
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    wanted = sorted({int(d) for d in dpis})
    top = wanted[-1]
    w_in, h_in = (float(v) for v in fig.get_size_inches())
    canvas = FigureCanvasAgg(fig)
    saved = fig.dpi
    fig.dpi = top
    try:
        canvas.draw()
        full = Image.fromarray(np.asarray(canvas.buffer_rgba()), mode="RGBA").convert("RGB")
    finally:
        fig.dpi = saved
    out = {}
    for dpi in wanted:
        size = (max(1, round(w_in * dpi)), max(1, round(h_in * dpi)))
        out[dpi] = full if size == full.size else full.resize(size, Image.Resampling.BOX)
    return out


@dataclass(frozen=True)
class FigureImage:
    """One report figure, as pixels at every resolution it was rendered at.

    Attributes
    ----------
    width_in, height_in : float
        Figure size [in]; the image at ``dpi`` has ``round(width_in * dpi)`` pixels across.
    pixels : dict of int to PIL.Image.Image
        RGB image per resolution [dpi].
    """

    width_in: float
    height_in: float
    pixels: dict[int, Image.Image] = field(repr=False)
    _png: dict[int, bytes] = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def aspect(self) -> float:
        """Height over width."""
        return self.height_in / self.width_in

    def image(self, dpi: int) -> Image.Image:
        """The RGB image at ``dpi`` (one of the resolutions the figure was rendered at).

        Raises
        ------
        KeyError
            The figure was not rendered at ``dpi``.
        """
        try:
            return self.pixels[dpi]
        except KeyError:
            raise KeyError(f"figure rendered at {sorted(self.pixels)} dpi, not {dpi}") from None

    def at(self, dpi: int) -> bytes:
        """PNG bytes at ``dpi`` (encoded on the first call).

        Raises
        ------
        KeyError
            The figure was not rendered at ``dpi``.
        """
        if dpi not in self._png:
            self._png[dpi] = png_bytes(self.image(dpi))
        return self._png[dpi]


class FigureImages:
    """Builds each figure block once and keeps its PNGs for the HTML and PDF writers.

    Parameters
    ----------
    dpis : iterable of int
        Resolutions to render every figure at (default: :data:`HTML_DPI` and
        :data:`PDF_DPI`).
    """

    def __init__(self, dpis: Iterable[int] = (HTML_DPI, PDF_DPI)) -> None:
        self.dpis = tuple(sorted({int(d) for d in dpis}))
        if not self.dpis or min(self.dpis) < 10 or max(self.dpis) > 1200:
            raise ValueError(f"dpis must be resolutions in [10, 1200] dpi, got {self.dpis}")
        # keyed by id(block); the block is kept alive next to its image so the id stays unique
        self._cache: dict[int, tuple[Block, FigureImage | None]] = {}

    def get(self, block: Block) -> FigureImage | None:
        """The rendered figure of a ``"figure"`` block (None when it has no figure).

        Raises
        ------
        ValueError
            ``block`` is not a figure block.
        """
        if block.kind != "figure":
            raise ValueError(f"expected a figure block, got a {block.kind!r} block")
        hit = self._cache.get(id(block))
        if hit is not None and hit[0] is block:
            return hit[1]
        fig = block.figure() if block.figure is not None else None
        image = None
        if fig is not None:
            w, h = (float(v) for v in fig.get_size_inches())
            image = FigureImage(w, h, figure_pixels(fig, self.dpis))
        self._cache[id(block)] = (block, image)
        return image


def missing_figure_text(block: Block) -> str:
    """What stands in place of a figure that could not be drawn."""
    return f"{block.text} (not available)"


def is_emphasised(block: Block, section_id: str) -> bool:
    """True for a paragraph shown in bold: the verdict of a case comparison."""
    return block.kind == "text" and section_id == "comparison" and "reproduce" in block.text


def footer_text() -> str:
    """The closing line of the report."""
    return f"Generated by gearvib {__version__}. Same input files, same report."
