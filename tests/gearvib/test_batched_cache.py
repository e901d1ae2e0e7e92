"""The batched kernel's numba cache is tied to the files its compiled code embeds
(gearvib/kernels.py, gearvib/lanes.py): an edit there removes the stale entries and the
modules generated from them (specialised kernels) at import."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from gearvib import kernels_batch as kb


def test_clear_stale_cache(tmp_path):
    entries = [tmp_path / "kernels_batch._rhs8-225.py311.nbi",
               tmp_path / "kernels_batch._rhs8-225.py311.1.nbc"]
    other = tmp_path / "kernels.integrate_chunk-846.py311.nbi"  # another module's: kept
    for p in [*entries, other]:
        p.write_bytes(b"x")
    assert kb.clear_stale_cache(tmp_path, "kernels_batch", "a" * 64)  # no record: cleared
    assert not any(p.exists() for p in entries) and other.exists()
    assert (tmp_path / "kernels_batch.deps-sha256").read_text().strip() == "a" * 64
    for p in entries:
        p.write_bytes(b"x")
    assert not kb.clear_stale_cache(tmp_path, "kernels_batch", "a" * 64)  # same: kept
    assert all(p.exists() for p in entries)
    assert kb.clear_stale_cache(tmp_path, "kernels_batch", "b" * 64)  # changed: cleared
    assert not any(p.exists() for p in entries)


def test_digest_follows_the_dependencies():
    here = Path(kb.__file__).resolve().parent
    assert {(here / n).is_file() for n in kb.DEPENDENCIES} == {True}
    assert len(kb.dependency_digest()) == 64


def test_import_removes_entries_of_other_dependencies(tmp_path):
    """In a fresh process with its own cache folder: a record of other dependencies (an
    edited kernels.py or lanes.py) makes the import remove the module's entries."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    code = ("import gearvib.kernels_batch as kb; "
            "print(kb.integrate_lanes._cache._cache_path)")
    run = [sys.executable, "-c", code]
    folder = Path(subprocess.run(run, env=env, capture_output=True, text=True,
                                 check=True).stdout.strip())
    marker = folder / "kernels_batch.deps-sha256"
    assert marker.read_text().strip() == kb.dependency_digest()
    stale = folder / "kernels_batch._rhs8-1.py311.nbi"
    stale.write_bytes(b"stale")
    generated = folder / "specialised" / "batch_0.py"  # a module generated from them
    generated.parent.mkdir()
    generated.write_text("")
    subprocess.run(run, env=env, capture_output=True, check=True)
    assert stale.exists() and generated.exists()  # same dependencies: kept
    marker.write_text("0" * 64 + "\n")  # compiled from other sources
    subprocess.run(run, env=env, capture_output=True, check=True)
    assert not stale.exists() and not generated.exists()
    assert marker.read_text().strip() == kb.dependency_digest()
