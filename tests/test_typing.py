"""The packages are typed (PEP 561: ``py.typed``) and mypy finds no error in them.

mypy runs with the configuration of ``pyproject.toml`` (``[tool.mypy]``: the files, the
third-party libraries without types) on the checkout, with its cache in a temporary folder, so
that every run checks from scratch as the CI does (about a minute of CPU).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("package", ["gearvib", "analysis"])
def test_packages_carry_the_pep561_marker(package):
    assert (ROOT / package / "py.typed").is_file()


@pytest.mark.slow
def test_mypy_finds_no_error(tmp_path):
    pytest.importorskip("mypy", reason="mypy is not installed (it is in the 'test' extra)")
    env = {k: v for k, v in os.environ.items() if not k.startswith("MYPY")}
    env["PYTHONPATH"] = str(ROOT)  # the checkout's packages, whatever is installed
    r = subprocess.run(
        [sys.executable, "-m", "mypy", "--cache-dir", str(tmp_path / "mypy-cache"),
         "--no-error-summary", "--hide-error-context", "--no-pretty"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=900,
    )
    errors = [line for line in r.stdout.splitlines() if ": error:" in line]
    assert r.returncode == 0 and not errors, "\n".join(errors) or r.stdout + r.stderr
