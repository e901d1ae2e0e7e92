"""An image scraper for the gallery (importable, so that Sphinx can pickle its settings)."""

from __future__ import annotations


class FigureScraper:
    """Gallery images of the Figures an example holds in variables.

    gearvib's ``.plot()`` methods build :class:`matplotlib.figure.Figure` objects without
    pyplot, which sphinx-gallery's own matplotlib scraper does not see.
    """

    def __init__(self) -> None:
        self.seen: set[int] = set()

    def __repr__(self) -> str:  # sphinx caches the configuration by repr
        return "FigureScraper()"

    def __call__(self, block, block_vars, gallery_conf):
        from matplotlib.figure import Figure
        from sphinx_gallery.scrapers import figure_rst

        paths = []
        for value in list(block_vars["example_globals"].values()):
            if isinstance(value, Figure) and id(value) not in self.seen:
                self.seen.add(id(value))
                path = next(block_vars["image_path_iterator"])
                value.savefig(path, dpi=100)
                paths.append(path)
        return figure_rst(paths, gallery_conf["src_dir"])
