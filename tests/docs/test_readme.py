"""The README is a front page: short, and its Python examples run as printed."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
CWRU = Path("/work/shared/data/cwru")


def _blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.S)


def test_readme_is_a_front_page() -> None:
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 250
    # every docs page it links to exists
    for link in re.findall(r"\]\(((?:docs|benchmarks)/[^)#]+)", text):
        assert (ROOT / link).is_file(), link


@pytest.mark.parametrize("index", range(len(_blocks())))
def test_readme_python_examples_run(index, tmp_path, monkeypatch) -> None:
    block = _blocks()[index]
    if "IR007_0.mat" in block:
        if not (CWRU / "IR007_0.mat").is_file():
            pytest.skip("the CWRU record is not on this machine")
        os.symlink(CWRU / "IR007_0.mat", tmp_path / "IR007_0.mat")
    monkeypatch.chdir(tmp_path)
    exec(compile(block, f"README.md python block {index}", "exec"), {"__name__": "readme"})
    assert list(tmp_path.glob("*.png")), "each example saves its figure"
