"""The documentation site builds with no warning: user guide, API reference from the numpydoc
docstrings, and the gallery, whose examples run during the build (issue 25)."""

from __future__ import annotations

import importlib
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"

pytestmark = pytest.mark.slow


def test_sphinx_build_has_no_warnings(tmp_path):
    pytest.importorskip("sphinx")
    out = tmp_path / "html"
    r = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b",
                        "html", "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
                       capture_output=True, text=True, timeout=1500, cwd=ROOT,
                       env={**__import__("os").environ, "MPLBACKEND": "Agg"})
    assert r.returncode == 0, (r.stdout[-3000:], r.stderr[-5000:])
    assert (out / "index.html").is_file() and (out / "api" / "index.html").is_file()
    examples = sorted((ROOT / "examples").glob("plot_*.py"))
    assert examples
    for ex in examples:
        page = (out / "auto_examples" / f"{ex.stem}.html").read_text()
        assert "<img" in page, f"{ex.name} shows no figure"


def _public_modules() -> set[str]:
    """Modules with a public ``__all__`` that users import (not the kernels' internals)."""
    internal = re.compile(r"(kernels|kernels_batch|presets|recipes|lanes|batch_codegen|"
                          r"fault_pass|cli|compile_helper|__main__|tempfiles|interrupts|paths|"
                          r"outputs|memory|checks|jit|threads|cfdata|sinc|frames|inputs|cf)$")
    names = set()
    for top in ("analysis", "gearvib"):
        pkg = importlib.import_module(top)
        for m in pkgutil.iter_modules(pkg.__path__, f"{top}."):
            if not internal.search(m.name):
                names.add(m.name)
    return names


def test_every_public_module_is_in_the_api_reference():
    listed = set(re.findall(r"^\s{3}((?:analysis|gearvib)[\w.]*)$",
                            (DOCS / "api" / "index.rst").read_text(), flags=re.M))
    missing = sorted(_public_modules() - listed)
    assert not missing, f"add to docs/api/index.rst: {missing}"


def test_every_user_guide_page_is_in_the_toctree():
    index = (DOCS / "index.md").read_text()
    pages = {p.stem for p in DOCS.glob("*.md")} - {"index", "changelog"}
    missing = sorted(p for p in pages if not re.search(rf"^{re.escape(p)}$", index, re.M))
    assert not missing, f"add to the toctree of docs/index.md: {missing}"
