"""The first-run notice: a cold numba cache is detected and announced before the run."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

import gearvib.compile_helper as compile_helper
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
    # the main kernel's index and data copied in (same source: numba's stamp matches); the
    # files of its current line only (a folder can hold stale ones of an edited kernels.py)
    folder.mkdir(parents=True, exist_ok=True)
    copied = 0
    line = kernels.integrate_chunk_compiled.py_func.__code__.co_firstlineno
    for f in warm.glob(f"kernels.integrate_chunk_compiled-{line}.*"):
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


@pytest.mark.parametrize(("cached", "quiet", "told"), [
    (False, False, True), (False, True, False), (True, False, False), (None, False, False)])
def test_simulate_announces_a_compilation(tmp_path, capsys, monkeypatch, cached, quiet, told):
    monkeypatch.setattr(jit_cache, "kernels_cached", lambda: cached)
    started, shared = _fake_helper(monkeypatch)
    assert main(["simulate", "paper-case1", "-o", str(tmp_path / "x.nc"), "--speed",
                 "1400:1600", "--duration", "0.01", *(["-q"] if quiet else [])]) == 0
    err = capsys.readouterr().err
    assert ("compiling the simulation kernels" in err) is told
    if told:
        assert err.count("\n") >= 1 and err.splitlines()[0] == jit_cache.FIRST_RUN_NOTICE
    # the helper starts first thing on a cold cache; its compilation is shared before the run
    assert started == ([False] if cached is False else [])
    assert shared == ([(False, "helper")] if cached is False else [])


def _fake_helper(monkeypatch) -> tuple[list, list]:
    """Record the helper's start (``order_analysis``) and the shared compilation
    (``order_analysis``, the helper handed over) instead of starting processes."""
    started: list = []
    shared: list = []

    def start(order_analysis=False):
        started.append(order_analysis)
        return "helper"

    monkeypatch.setattr(compile_helper, "start", start)
    monkeypatch.setattr(compile_helper, "share_first_compilation",
                        lambda order_analysis=False, helper=None:
                        shared.append((order_analysis, helper)))
    return started, shared


def test_demo_shares_its_first_compilation_with_the_order_analysis(tmp_path, monkeypatch):
    monkeypatch.setattr(jit_cache, "kernels_cached", lambda: False)
    started, shared = _fake_helper(monkeypatch)
    import gearvib.report

    monkeypatch.setattr(gearvib.report, "run_study", lambda *a, **k: (_ for _ in ()).throw(
        RuntimeError("stop before the runs")))
    with contextlib.suppress(RuntimeError):  # main may report it instead
        assert main(["demo", "-o", str(tmp_path / "demo"), "--quiet"]) != 0
    assert started == [True]
    assert shared == [(True, "helper")]
    assert not (tmp_path / "demo").exists()  # nothing written before the runs


def test_a_refused_command_leaves_its_early_helper_to_end(tmp_path, monkeypatch, capsys):
    """The helper starts before the inputs are checked; a command refused afterwards stops
    without sharing the compilation (the helper ends on its own after its part)."""
    monkeypatch.setattr(jit_cache, "kernels_cached", lambda: False)
    started, shared = _fake_helper(monkeypatch)
    assert main(["simulate", str(tmp_path / "missing.toml"), "-o", str(tmp_path / "x.nc")]) != 0
    assert "not found" in capsys.readouterr().err
    assert started == [False] and shared == []


def _helpers(cache: Path) -> set[int]:
    """Running compile helpers whose numba cache is ``cache`` (Linux /proc)."""
    found = set()
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            cmd = (proc / "cmdline").read_bytes()
            env = (proc / "environ").read_bytes() if b"gearvib.compile_helper" in cmd else b""
            status = (proc / "status").read_text() if env else ""
        except OSError:
            continue
        if f"NUMBA_CACHE_DIR={cache}".encode() in env.split(b"\0") and "\nState:\tZ" not in status:
            found.add(int(proc.name))
    return found


@pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="needs Linux /proc")
def test_first_run_interrupted_while_its_compilation_is_shared(tmp_path, monkeypatch):
    """Ctrl-C while the command and its helper compile (a cold cache): the command stops as
    always (code 130, one line); the helper, in its own session, is not interrupted but ends
    on its own within seconds, and leaves no temporary file in numba's cache."""
    import signal
    import threading

    from tests.cli.signal_helpers import run_and_signal

    cache = tmp_path / "numba-cache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    monkeypatch.delenv("GEARVIB_COMPILE_HELPER", raising=False)
    seen: set[int] = set()
    stop = threading.Event()

    def watch() -> None:
        while not stop.is_set():
            seen.update(_helpers(cache))
            time.sleep(0.05)

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    try:
        r = run_and_signal(["simulate", "paper-case1", "-o", "run.nc", "--duration", "0.05"],
                           tmp_path, signal.SIGINT, delay=2.0)
    finally:
        stop.set()
        watcher.join()
    assert r.signalled and r.returncode == 130, r
    assert "Traceback" not in r.stderr and r.stderr.rstrip().splitlines()[-1].startswith(
        "gearvib: interrupted"), r.stderr
    assert not (tmp_path / "run.nc").exists()
    assert seen, "no compile helper was started"
    deadline = time.monotonic() + 60
    while _helpers(cache) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _helpers(cache)
    assert not [p for p in cache.rglob("*") if ".tmp" in p.name]
