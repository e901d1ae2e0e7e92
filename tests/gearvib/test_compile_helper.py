"""The first compilation shared with a helper process (gearvib.compile_helper).

What must hold: the parts compiled ahead carry exactly the argument types a run passes (else
the run compiles a second specialisation and the helper's work is lost), the helper delivers
its parts in order and ends, the command never waits longer than the helper lives or the
timeout, and no helper is started when switched off or on one core. That a run's results do
not depend on who compiled what is checked with fresh caches in
``benchmarks/bench_cli.py --first-run`` (and in RESULTS.md: identical machine code).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from gearvib import compile_helper
from gearvib import kernels as kn

# A short run and the order analysis's public functions in a fresh process (warm cache: every
# function is loaded with the signature the run uses); then every part compiled ahead. Prints
# each dispatcher's signatures before and after, and the kernel's own signature's argument
# types.
_PROBE = r"""
import json
import numpy as np
from gearvib import kernels as kn
from analysis import sinc
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.simulate import simulate
from gearvib.simulation.settings import conditions_from_settings, read_run_settings

cfg, base = load_config("paper-case1")
run = read_run_settings(cfg["simulation"], {"speed_start_rpm": 1000.0, "speed_end_rpm": 1100.0,
                                            "duration": 0.02})
simulate(assemble(gearset_from_dict(cfg, base=base)), conditions_from_settings(run),
         progress=False)
x = np.sin(np.arange(400.0) / 7.0)[None, :]
sinc.interpolate(x, np.linspace(20.0, 300.0, 50))
sinc.positions(np.linspace(0.0, 10.0, 64), np.arange(64) / 1e3, 1.0, 0.1, 0, 20, 0.0, 1e3)
sinc.decimate(x, np.ones(9) / 9.0, 2, 4, 10)
public = {"speed_profile": kn.speed_profile, "periodic_interp": kn.periodic_interp,
          "shift_rigid": kn.shift_rigid, "fir_decimate": kn.fir_decimate,
          "sinc_interpolate": sinc._interpolate, "sinc_positions": sinc._positions,
          "sinc_decimate": sinc._decimate}
before = {k: [str(s) for s in d.signatures] for k, d in public.items()}
kernel = [repr(t) for t in kn.integrate_chunk_compiled.signatures[0]]
system = [repr(t) for t in kn.integrate_chunk_compiled.signatures[0][4].types]
for part in kn.KERNEL_PARTS:
    kn.compile_ahead(part)
sinc.compile_ahead()
after = {k: [str(s) for s in d.signatures] for k, d in public.items()}
ahead = {"step_search": [str(s) for s in kn._split_times.signatures],
         "kernel": [str(s) for s in kn.integrate_chunk_compiled.signatures]}
print(json.dumps({"before": before, "after": after, "kernel": kernel, "system": system,
                  "ahead": ahead}))
"""


@pytest.fixture(scope="module")
def probe() -> dict:
    out = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                         check=True, timeout=600).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_parts_compiled_ahead_are_the_specialisations_a_run_uses(probe):
    for name, sigs in probe["before"].items():
        assert len(sigs) == 1, f"{name}: the run used {sigs}"
        assert probe["after"][name] == sigs, f"{name}: compiled ahead for other types"


def test_kernel_parts_take_the_kernel_argument_types(probe):
    # integrate_chunk_compiled(y, first_step, n_steps, dt, system, record, record_offset,
    # flank_state, contact_changes, count_until, work, mesh_out, status, rhs) passes y, rows
    # of work (C-contiguous 1-d, as work[i] of a C-contiguous 2-d array), mesh_out and the
    # system's arrays to _split_times (and their data to the right-hand side's C function,
    # whose signature is fixed)
    kernel = probe["kernel"]
    assert len(probe["ahead"]["kernel"]) == 1  # compile_ahead("kernel"): the run's own types
    y, dt, work, mesh_out = kernel[0], kernel[3], kernel[10], kernel[11]
    ints, vals, *_ = probe["system"]
    row = work.replace("Array(float64, 2,", "Array(float64, 1,")
    assert y == row  # both array(float64, 1d, C)
    assert probe["ahead"]["step_search"] == [
        f"({y}, {dt}, {ints}, {vals}, {mesh_out}, {row})"]


def test_unknown_part_is_refused():
    with pytest.raises(ValueError,
                       match="part must be one of setup, rhs, step_search, kernel, output"):
        kn.compile_ahead("everything")


def test_helper_delivers_its_parts_in_order_and_ends(monkeypatch):
    monkeypatch.delenv(compile_helper.ENV_SWITCH, raising=False)
    monkeypatch.setattr(compile_helper, "_cores", lambda: 2)
    helper = compile_helper.start(order_analysis=True)
    assert helper is not None
    assert helper.wait(compile_helper.ORDER_ANALYSIS, timeout=300)
    deadline = time.monotonic() + 60
    while not helper.ended and time.monotonic() < deadline:
        time.sleep(0.05)
    assert helper.ended
    assert helper.delivered == (*compile_helper.HELPER_PARTS, compile_helper.ORDER_ANALYSIS)


def _fake(code: str, parts: tuple[str, ...] = ()) -> compile_helper.CompileHelper:
    return compile_helper.CompileHelper(subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stdin=subprocess.DEVNULL,
        text=True), parts)


def test_shared_compilation_with_a_helper_started_earlier(monkeypatch):
    monkeypatch.setattr(compile_helper, "start",
                        lambda order_analysis=False: pytest.fail("a second helper started"))
    compiled = []
    monkeypatch.setattr(kn, "compile_ahead", compiled.append)
    parts = "\n".join(compile_helper.HELPER_PARTS)
    helper = _fake(f"print({parts!r}, flush=True)", compile_helper.HELPER_PARTS)
    monkeypatch.setattr(compile_helper, "_SHARED", [])
    assert compile_helper.share_first_compilation(helper=helper) is helper
    assert compiled == list(compile_helper.MAIN_PARTS)  # this process's share, then the wait
    assert helper.delivered == compile_helper.HELPER_PARTS
    assert compile_helper.await_part(compile_helper.HELPER_PARTS[0], timeout=0)  # asks it


def test_await_part_waits_only_for_a_part_the_helper_compiles(monkeypatch):
    monkeypatch.setattr(compile_helper, "_SHARED", [])
    assert not compile_helper.await_part(compile_helper.ORDER_ANALYSIS, timeout=5)  # none
    helper = _fake("import time; time.sleep(0.5); print('step_search', flush=True); "
                   "time.sleep(0.5); print('order_analysis', flush=True)",
                   parts=("step_search", "order_analysis"))
    monkeypatch.setattr(compile_helper, "_SHARED", [helper])
    t0 = time.monotonic()
    assert not compile_helper.await_part("kernel", timeout=30)  # not among its parts
    assert time.monotonic() - t0 < 0.4
    assert compile_helper.await_part(compile_helper.ORDER_ANALYSIS, timeout=60)
    assert helper.delivered == ("step_search", "order_analysis")
    assert compile_helper.await_part("step_search", timeout=0)


def test_await_part_gives_up_when_the_helper_ends_early(monkeypatch):
    helper = _fake("print('step_search', flush=True)", parts=("step_search", "order_analysis"))
    monkeypatch.setattr(compile_helper, "_SHARED", [helper])
    assert not compile_helper.await_part(compile_helper.ORDER_ANALYSIS, timeout=120)
    assert helper.ended and not helper.will_deliver(compile_helper.ORDER_ANALYSIS)


def test_wait_ends_with_the_helper():
    helper = _fake("print('step_search', flush=True)")
    t0 = time.monotonic()
    assert not helper.wait("setup", timeout=120)  # never delivered: returns when it ends
    assert time.monotonic() - t0 < 60
    assert helper.delivered == ("step_search",)
    assert helper.wait("step_search", timeout=0)


def test_wait_gives_up_after_its_timeout():
    helper = _fake("import time; time.sleep(30)")
    try:
        t0 = time.monotonic()
        assert not helper.wait("setup", timeout=0.3)
        assert 0.25 <= time.monotonic() - t0 < 10
        assert not helper.ended
    finally:
        helper._process.kill()


@pytest.mark.parametrize("how", ["switched off", "one core", "no interpreter"])
def test_no_helper(monkeypatch, how):
    monkeypatch.setattr(compile_helper, "_cores", lambda: 4)
    if how == "switched off":
        monkeypatch.setenv(compile_helper.ENV_SWITCH, "0")
    elif how == "one core":
        monkeypatch.setattr(compile_helper, "_cores", lambda: 1)
    else:
        monkeypatch.setattr(sys, "executable", "")
    assert compile_helper.start() is None
    assert compile_helper.share_first_compilation() is None


def test_helper_arguments_and_an_ended_parent():
    assert compile_helper.run_helper([]) == 2
    assert compile_helper.run_helper(["nine", "setup"]) == 2
    # a parent that is not this process's: the command has ended, nothing is compiled
    assert compile_helper.run_helper([str(os.getpid()), "no-such-part"]) == 0
    # a part that fails: exit code 1 (the command compiles what is missing)
    assert compile_helper.run_helper([str(os.getppid()), "no-such-part"]) == 1
