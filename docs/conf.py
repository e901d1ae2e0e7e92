"""Sphinx configuration of the gearvib documentation (user guide, API reference, gallery).

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (warnings are errors;
the gallery's examples run during the build).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "docs" / "sphinxext"))
os.environ.setdefault("MPLBACKEND", "Agg")

from figure_scraper import FigureScraper  # noqa: E402

import gearvib  # noqa: E402

project = "gearvib"
author = "the gearvib developers"
copyright = "2026, the gearvib developers"
version = release = gearvib.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "numpydoc_template_cache",  # docs/sphinxext: numpydoc's template compiled once per build
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "**/_build", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.md5", "auto_examples/*.json"]
templates_path = ["_templates"]

myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]
suppress_warnings = ["myst.header"]

autosummary_generate = True
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "undoc-members": False}
autodoc_typehints = "none"  # numpydoc shows the documented types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False

sphinx_gallery_conf = {
    "image_scrapers": (FigureScraper(), "matplotlib"),
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
}

html_theme = "alabaster"
html_title = f"gearvib {release}"
html_static_path: list[str] = []
