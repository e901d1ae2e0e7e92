"""The first-run notice: a cold numba cache is detected and announced before the run."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import gearvib.jit_cache as jit_cache
from gearvib.cli import main

_ASK = ("from gearvib.jit_cache import kernels_cached; from gearvib import kernels; "
        "print(kernels_cached(), kernels.integrate_chunk_compiled._cache._cache_path)")


def _ask(cache: Path) -> tuple[str, Path]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    out = subprocess.run([sys.executable, "-c", _ASK], capture_output=True, text=True, env=env,
                         check=True, timeout=300).stdout.split()
    return out[0], Path(out[1])


def test_cold_and_warm_cache_are_told_apart(tmp_path):
    from gearvib import kernels
    from gearvib.assembly import assemble
    from gearvib.config import gearset_from_dict, load_config
    from gearvib.simulate import SpeedRamp, simulate

    cfg, base = load_config("paper-case1")  # this process's cache holds the kernel after this
    simulate(assemble(gearset_from_dict(cfg, base=base)), SpeedRamp(1000, 1000, 0.002),
             progress=False)
    warm = Path(kernels.integrate_chunk_compiled._cache._cache_path)
    empty = tmp_path / "cache"
    empty.mkdir()
    answer, folder = _ask(empty)  # a fresh cache folder: the first run compiles
    assert answer == "False"
    # the main kernel's index and data copied in (same source: numba's stamp matches)
    folder.mkdir(parents=True, exist_ok=True)
    copied = 0
    for f in warm.glob("kernels.integrate_chunk_compiled-*"):
        shutil.copy2(f, folder / f.name)
        copied += 1
    assert copied >= 2
    assert _ask(empty)[0] == "True"
    # the data file alone (no index) counts as cold; a damaged index as unknown (no notice)
    index = next(folder.glob("kernels.integrate_chunk_compiled-*.nbi"))
    content = index.read_bytes()
    index.unlink()
    assert _ask(empty)[0] == "False"
    index.write_bytes(content[: len(content) // 2])
    assert _ask(empty)[0] in ("False", "None")


@pytest.mark.parametrize(("cached", "told"), [(False, True), (True, False), (None, False)])
def test_simulate_announces_a_compilation(tmp_path, capsys, monkeypatch, cached, told):
    monkeypatch.setattr(jit_cache, "kernels_cached", lambda: cached)
    assert main(["simulate", "paper-case1", "-o", str(tmp_path / "x.nc"), "--speed",
                 "1400:1600", "--duration", "0.01"]) == 0
    err = capsys.readouterr().err
    assert ("compiling the simulation kernels" in err) is told
    if told:
        assert err.count("\n") >= 1 and err.splitlines()[0] == jit_cache.FIRST_RUN_NOTICE
