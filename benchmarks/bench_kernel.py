"""Benchmark of the run-up kernel per core (not a timed test).

Run ``python3 benchmarks/bench_kernel.py [--quick]``. For ``paper-case1`` and
``paper-case1-elastic`` (each preset's own run, as ``gearvib simulate <preset>`` makes it: 1 s
run-up 0 -> 4000 min^-1 at 60 N m input torque, the drive a spring-damper on the sun, the
automatic step; in the C comparison also both with every mesh under the always-on ``viscous``
damping law, and the elastic model under gearvib's default drive), it prints side by side:

* **ns per right-hand-side evaluation**, numba kernel against a plain C loop of the same
  algorithm (``benchmarks/c/rk4_kernel.c``, compiled here with ``gcc -O2`` and, second, with
  ``-march=native -ffp-contract=off`` (the host's instruction set, as numba uses it), and
  called through ctypes on the same packed arrays): the whole RK4 loop of
  :func:`gearvib.kernels.integrate_chunk` (sub-steps at the stiffness jumps, recorded rows)
  divided by its number of right-hand-side evaluations, and a loop of right-hand sides alone
  over recorded states. The C output is checked to be bit-identical to the numba kernel's
  before any time is reported.
* **batched against single throughput per core**: 8 variants of the gear set advanced by one
  call of :func:`gearvib.kernels_batch.integrate_chunk_batch`, against the 8 runs one after
  another (:func:`gearvib.kernels.integrate_chunk`), both on systems packed beforehand (a
  sweep packs once per run; packing 8 variants takes about 4 ms); rounds of single, batch
  interleaved, the median ratio and its spread over the rounds. Two variant sets: the sun-mesh
  damping ratio alone, and the damping with the planet bearing stiffness (then the stiffness
  operator differs per lane, with stored zeros where the lanes' patterns differ). Also the
  right-hand sides alone (single and batched loops over recorded states) and a batch of 8
  copies of one variant (every lane takes the same sub-steps: no lane waits). Every batched
  variant's rows are checked bit-identical to its single run's before any time is reported.
  The batch runs the kernel specialised to the topology (generated right-hand side); the
  generic kernel (sparse loops, :data:`gearvib.kernels_batch.GENERIC`) is timed alongside.
  ``--batch-only`` skips the C comparison.
* ``--compile``: the first call of the batched kernel in fresh processes with an empty numba
  cache, generic and specialised (the compile time a first sweep pays), and with that cache.

Every time is CPU time of a fixed window (the machine is shared), numba compilation excluded;
the C comparison reports the best of several repetitions. Without ``gcc`` on the path the C
comparison is skipped with a message. ``--quick`` is a smoke run: 5 ms windows from t = 0.05 s
(~200 min^-1), one repetition and one round, the gcc -O2 build only and the first batched row
(every check of bit-identity of those still made; its ratios mean little).
"""

from __future__ import annotations

import argparse
import ctypes
import dataclasses
import os
import shutil
import subprocess
import tempfile
import time

import numpy as np

from gearvib import kernels as kn
from gearvib import kernels_batch as kb
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.simulate import (
    SpeedRamp,
    choose_step,
    prepare_run,
    static_equilibrium,
    with_coupling,
)
from gearvib.simulation.frequencies import stiffest_matrix, undamped_frequencies
from gearvib.simulation.settings import conditions_from_settings, read_run_settings
from gearvib.sweep.keys import set_path

HERE = os.path.dirname(os.path.abspath(__file__))
C_SOURCE = os.path.join(HERE, "c", "rk4_kernel.c")
CFLAGS = ["-O2", "-shared", "-fPIC"]
#: A second build with the host's instruction set, as numba's LLVM uses it (SSE4.1 rounding,
#: AVX); no contraction into fused multiply-adds, so it stays bit-identical.
CFLAGS_NATIVE = ["-O2", "-march=native", "-ffp-contract=off", "-shared", "-fPIC"]
I64 = ctypes.POINTER(ctypes.c_int64)
F64 = ctypes.POINTER(ctypes.c_double)
#: The constants of gearvib.kernels the C file mirrors, in the order of its ``GV_LAYOUT``.
HEADER_NAMES = (
    "H_N", "H_NMESH", "H_IPAR", "IP_MODE", "IP_INPUT", "IP_OUTPUT", "IP_CARRIER", "IP_GYRO",
    "N_IPAR", "FP_KC", "FP_CC", "FP_OUTDIR", "FP_T0", "FP_C1", "FP_C2", "FP_SPEED_LIMIT",
    "H_LP", "H_LI", "H_CP", "H_CI", "H_GP", "H_GI", "H_II", "H_OI", "H_VP", "H_VI", "H_FP",
    "H_FI", "H_PP", "H_PI", "H_BP", "H_RFLAG", "H_RVP", "H_RVI", "H_RFP", "H_RFI", "H_FREC",
    "H_FINT", "H_MLAW", "H_DI", "H_ACC0", "H_LV", "H_CV", "H_GV", "H_IV", "H_OV", "H_VV",
    "H_FV", "H_PV", "H_S0", "H_BL", "H_MC", "H_FPAR", "H_LIMIT", "H_BV", "H_RVV", "H_RFV",
    "H_FVAL", "H_DV", "H_NI", "H_NO", "H_FPASS", "H_ND", "N_HEADER", "DRIVE_NONE",
    "DRIVE_SPEED", "DRIVE_TORQUE", "DRIVE_MOTOR", "MESH_OUT_COLUMNS",
)


def build_c(tmp: str, flags: list[str], name: str) -> ctypes.CDLL:
    """Compile the C baseline with ``flags`` (never fast-math) and load it."""
    gcc = shutil.which("gcc")
    if gcc is None:
        raise SystemExit("bench_kernel needs gcc for the C baseline")
    lib = os.path.join(tmp, f"rk4_kernel_{name}.so")
    subprocess.run([gcc, *flags, "-o", lib, C_SOURCE, "-lm"], check=True)
    c = ctypes.CDLL(lib)
    c.gv_header_size.restype = ctypes.c_int64
    c.gv_header_layout.restype = ctypes.c_int64
    c.gv_header_layout.argtypes = [I64, ctypes.c_int64]
    layout = np.zeros(len(HEADER_NAMES) + 1, dtype=np.int64)
    n_layout = c.gv_header_layout(ptr(layout, I64), layout.size)
    expected = [getattr(kn, name) for name in HEADER_NAMES]
    if c.gv_header_size() != kn.N_HEADER or n_layout != len(HEADER_NAMES) or list(
            layout[:n_layout]) != expected:
        wrong = [name for name, a, b in zip(HEADER_NAMES, layout, expected, strict=False)
                 if a != b]
        raise SystemExit("benchmarks/c/rk4_kernel.c is out of date with gearvib.kernels' header"
                         f" (entries that differ: {wrong or 'their number'})")
    c.gv_integrate_chunk.restype = ctypes.c_int64
    c.gv_integrate_chunk.argtypes = [
        I64, F64, F64, ctypes.c_int64, F64, ctypes.c_int64, F64, ctypes.c_int64, F64,
        ctypes.c_int64, ctypes.c_int64, ctypes.c_double, F64, ctypes.c_int64, ctypes.c_int64,
        I64, I64, ctypes.c_int64, F64, ctypes.c_int64, F64, I64,
    ]
    c.gv_rhs_loop.restype = ctypes.c_double
    c.gv_rhs_loop.argtypes = [
        I64, F64, F64, ctypes.c_int64, F64, ctypes.c_int64, F64, ctypes.c_int64, F64,
        ctypes.c_int64, ctypes.c_double, ctypes.c_double, ctypes.c_int64, F64, F64,
    ]
    return c


#: The runs of the C comparison (their records bit-identical too, so every branch of the C
#: file is checked), each the preset's own run (``gearvib simulate <preset>``: 0 -> 4000
#: min^-1 in 1 s at 60 N m, the drive a spring-damper on the sun); ``controller``: gearvib's
#: default drive instead (a controller on the rigid-body mode, no damping added to the elastic
#: modes; paper-case1 under it runs away near 0.5 s, the elastic model does not); ``viscous``:
#: every mesh under the always-on damping law.
C_CASES = ("paper-case1", "paper-case1-elastic", "paper-case1-elastic controller",
           "paper-case1 viscous", "paper-case1-elastic viscous")


def preset_conditions(cfg: dict) -> SpeedRamp:
    """The run of a preset's ``[simulation]`` table, its drive included."""
    return conditions_from_settings(read_run_settings(cfg.get("simulation", {})))


def c_case(name: str, t_start: float = 0.4) -> Case:
    """The packed run of an entry of :data:`C_CASES` at ``t_start``."""
    preset, _, variant = name.partition(" ")
    cfg, base = load_config(preset)
    cond = preset_conditions(cfg)
    if variant == "viscous":
        for family in ("sun", "ring"):
            cfg = set_path(cfg, f"meshes.{family}.damping_law", variant)
    elif variant == "controller":
        cond = dataclasses.replace(cond, coupling=None)
    return Case(assemble(gearset_from_dict(cfg, base=base)), cond, t_start)


def ptr(a: np.ndarray, kind=F64):
    return a.ctypes.data_as(kind)


class Case:
    """A packed run of a model: system, initial state at ``t_start``, step."""

    def __init__(self, model, cond, t_start: float):
        setup = prepare_run(model, cond, False)
        system = setup.system
        k_max = with_coupling(stiffest_matrix(model, setup.torque_sign), setup.mass,
                              setup.rigid, int(system.ipar[kn.IP_INPUT]), setup.coupling)
        f_nat = float(undamped_frequencies(setup.mass, k_max).max())
        f_mesh = float(np.nanmax(model.mesh_frequencies_per_rpm)) * setup.speed_max * 30 / np.pi
        self.step = choose_step(f_nat, f_mesh, speed_max_rpm=setup.speed_max * 30 / np.pi)
        qd0 = setup.rigid * setup.omega0
        q0, _ = static_equilibrium(system, setup.mass, setup.rigid, qd0)
        delta0 = np.abs(system.mesh_vectors @ q0)
        system.deflection_limit[:] = np.maximum(1e3 * (delta0 + np.abs(system.backlash) / 2),
                                                1e-3)
        self.system = system
        self.packed = system.astuple()
        self.n, self.nm = system.n_dof, system.n_mesh
        self.dt = self.step.dt
        # advance to t_start (the state of the run there is the benchmark's start)
        y = np.concatenate([q0, qd0])
        self.first = round(t_start / self.dt)
        if self.first:
            self.run_numba(y, 0, self.first)
        self.y0 = y

    def buffers(self, n_steps: int):
        return (np.empty((n_steps, kn.n_signals(self.n, self.nm))),
                np.full(self.nm, -1, dtype=np.int64), np.zeros(self.nm, dtype=np.int64),
                np.empty(kn.work_shape(self.n, self.nm)),
                np.empty((self.nm, kn.MESH_OUT_COLUMNS)), np.zeros(2, dtype=np.int64))

    def run_numba(self, y: np.ndarray, first: int, n_steps: int) -> np.ndarray:
        record, fs, ch, work, mo, status = self.buffers(n_steps)
        kn.integrate_chunk(y, first, n_steps, self.dt, self.packed, record, 0, fs, ch,
                           first + n_steps, work, mo, status)
        assert status[0] == kn.STATUS_OK
        return record

    def run_c(self, c, y: np.ndarray, first: int, n_steps: int) -> tuple[np.ndarray, int]:
        ints, vals, tables, sp, tq = self.packed
        record, fs, ch, work, mo, status = self.buffers(n_steps)
        n_rhs = c.gv_integrate_chunk(
            ptr(ints, I64), ptr(vals), ptr(tables), tables.shape[2], ptr(sp), sp.shape[1],
            ptr(tq), tq.shape[1], ptr(y), first, n_steps, self.dt, ptr(record), record.shape[1],
            0, ptr(fs, I64), ptr(ch, I64), first + n_steps, ptr(work), work.shape[1], ptr(mo),
            ptr(status, I64))
        assert status[0] == kn.STATUS_OK
        return record, n_rhs


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return min(times)


def rhs_per_eval(case: Case, c, n_steps: int, repeat: int) -> dict:
    """ns per right-hand side: whole RK4 loop, numba vs C, after a bit-identity check."""
    y_n = case.y0.copy()
    rec_n = case.run_numba(y_n, case.first, n_steps)
    y_c = case.y0.copy()
    rec_c, n_rhs = case.run_c(c, y_c, case.first, n_steps)
    identical = np.array_equal(rec_n, rec_c) and np.array_equal(y_n, y_c)
    if not identical:
        raise SystemExit(f"C and numba records differ (max |diff| "
                         f"{np.nanmax(np.abs(rec_n - rec_c)):.3g}): the baseline is not the "
                         "same algorithm")
    t_n = best(lambda: case.run_numba(case.y0.copy(), case.first, n_steps), repeat)
    t_c = best(lambda: case.run_c(c, case.y0.copy(), case.first, n_steps), repeat)
    # right-hand sides alone, at the recorded states
    states = np.ascontiguousarray(rec_n[:, : 2 * case.n])
    ints, vals, tables, sp, tq = case.packed
    dy = np.empty(2 * case.n)
    mo = np.empty((case.nm, kn.MESH_OUT_COLUMNS))
    t0 = case.first * case.dt
    n_eval = n_rhs

    def loop_c():
        return c.gv_rhs_loop(ptr(ints, I64), ptr(vals), ptr(tables), tables.shape[2], ptr(sp),
                             sp.shape[1], ptr(tq), tq.shape[1], ptr(states), states.shape[0],
                             t0, case.dt, n_eval, ptr(dy), ptr(mo))

    def loop_n():
        return kn.rhs_loop(states, t0, case.dt, n_eval, case.packed, dy, mo)

    if loop_c() != loop_n():
        raise SystemExit("C and numba right-hand sides differ")
    r_n = best(loop_n, repeat)
    r_c = best(loop_c, repeat)
    return {"n_rhs": n_rhs, "steps": n_steps, "loop_numba": t_n / n_rhs * 1e9,
            "loop_c": t_c / n_rhs * 1e9, "rhs_numba": r_n / n_eval * 1e9,
            "rhs_c": r_c / n_eval * 1e9}


N_BATCH = 8
#: Start of the batched comparison's window [s] (the run-up at about 1600 min^-1, as for C).
T_BATCH = 0.4
#: The batched variant sets: sun-mesh damping ratio x1 ... x2.75, with or without the planet
#: bearing stiffness x1 ... x1.35 (elastic model only).
VARIANT_SETS = ("damping", "damping+bearing")


def batch_variants(preset: str, which: str) -> list:
    """The 8 variants of ``preset`` of a set of :data:`VARIANT_SETS`."""
    cfg, base = load_config(preset)
    out = []
    for k in range(N_BATCH):
        d = set_path(cfg, "meshes.sun.damping_ratio", 0.005 * (1 + 0.25 * k))
        if which == "damping+bearing":
            d = set_path(d, "bodies.planet.support.radial", 1.5e8 * (1 + 0.05 * k))
        out.append(assemble(gearset_from_dict(d, base=base)))
    return out


def batched_vs_single(preset: str, which: str, window: float, rounds: int,
                      t_start: float = T_BATCH) -> dict:
    """Per-core throughput of one batched call against 8 single calls (packed beforehand),
    each the preset's own run."""
    cond = preset_conditions(load_config(preset)[0])
    cases = [Case(m, cond, t_start) for m in batch_variants(preset, which)]
    dt = cases[0].dt
    first = cases[0].first
    if any(c.dt != dt for c in cases):
        raise SystemExit("the variants' automatic steps differ")
    n_steps = round(window / dt)
    n, nm = cases[0].n, cases[0].nm
    t0 = time.process_time()
    batch = kb.pack_batch([c.system for c in cases])
    t_pack = time.process_time() - t0
    same = kb.pack_batch([cases[0].system] * N_BATCH)

    def run_batch(b, y0s, kernel=kb.integrate_chunk_batch):
        y = np.ascontiguousarray(np.array(y0s).T)
        rec = np.empty((kb.WIDTH, n_steps, kn.n_signals(n, nm)))
        fs = np.full((kb.WIDTH, nm), -1, dtype=np.int64)
        ch = np.zeros((kb.WIDTH, nm), dtype=np.int64)
        st = np.zeros((kb.WIDTH, 2), dtype=np.int64)
        kernel(y, first, n_steps, dt, b.astuple(), rec, 0, fs, ch, first + n_steps,
               kb.batch_work(n, nm), st)
        if np.any(st[:, 0] != kn.STATUS_OK):
            raise SystemExit(f"batched run failed: status {st.tolist()}")
        return rec

    if kb.kernels_for(batch.astuple()).source is None:
        raise SystemExit("the batch runs the generic kernel (no specialised module)")
    rec = run_batch(batch, [c.y0 for c in cases])
    rec_generic = run_batch(batch, [c.y0 for c in cases], kb.GENERIC.integrate)
    for b, c in enumerate(cases):
        single = c.run_numba(c.y0.copy(), first, n_steps).tobytes()
        if rec[b].tobytes() != single or rec_generic[b].tobytes() != single:
            raise SystemExit(f"batched variant {b} differs from its single run")

    def clock(fn) -> float:
        t0 = time.process_time()
        fn()
        return time.process_time() - t0

    single = lambda: [c.run_numba(c.y0.copy(), first, n_steps) for c in cases]  # noqa: E731
    ratios, ratios_same, ratios_generic = [], [], []
    for _ in range(rounds):  # single, batch, generic batch, single, batch of copies
        t_single = clock(single)
        ratios.append(t_single / clock(lambda: run_batch(batch, [c.y0 for c in cases])))
        ratios_generic.append(t_single / clock(lambda: run_batch(
            batch, [c.y0 for c in cases], kb.GENERIC.integrate)))
        ratios_same.append(clock(lambda: [cases[0].run_numba(cases[0].y0.copy(), first, n_steps)
                                          for _ in range(N_BATCH)])
                           / clock(lambda: run_batch(same, [cases[0].y0] * N_BATCH)))
    # right-hand sides alone over the recorded states of variant 0
    states = np.ascontiguousarray(rec[0][:, : 2 * n])
    lanes = np.ascontiguousarray(np.repeat(states[:, :, None], kb.WIDTH, axis=2))
    dy, mo = np.empty(2 * n), np.empty((nm, kn.MESH_OUT_COLUMNS))
    dyb, mob = np.empty((2 * n, kb.WIDTH)), np.empty((nm, kb.BATCH_MESH_COLUMNS, kb.WIDTH))
    n_eval = 20 * states.shape[0]
    t0 = first * dt
    kb.rhs_loop_batch(lanes, t0, dt, 10, batch.astuple(), dyb, mob)
    rhs = []
    for _ in range(rounds):
        t_s = clock(lambda: kn.rhs_loop(states, t0, dt, n_eval, cases[0].packed, dy, mo))
        t_b = clock(lambda: kb.rhs_loop_batch(lanes, t0, dt, n_eval // N_BATCH,
                                              batch.astuple(), dyb, mob))
        rhs.append((t_s / n_eval * 1e9, t_b / (n_eval // N_BATCH) * 1e9))
    rhs = np.array(rhs)
    return {"ratio": ratios, "same": ratios_same, "generic": ratios_generic,
            "rhs_single": float(np.median(rhs[:, 0])),
            "rhs_batch": float(np.median(rhs[:, 1])),
            "rhs_ratio": [N_BATCH * a / b for a, b in rhs], "pack": t_pack}


def _spread(x: list[float]) -> str:
    return f"{np.median(x):5.2f} ({min(x):.2f}-{max(x):.2f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 5 ms windows from t = 0.05 s, one repetition and round")
    parser.add_argument("--batch-only", action="store_true",
                        help="only the batched-against-single comparison")
    parser.add_argument("--compile", action="store_true",
                        help="only the compile time of the batched kernels (cold cache)")
    args = parser.parse_args()
    if args.compile:
        print_compile_times()
        return
    repeat = 1 if args.quick else 7
    window = 0.005 if args.quick else 0.1
    rounds = 1 if args.quick else 11
    t_start = 0.05 if args.quick else T_BATCH  # where the windows start in the run-up
    if args.batch_only:
        print_batched(window, rounds, t_start)
        return
    if shutil.which("gcc") is None:
        print("gcc not found: the comparison with the C kernel (benchmarks/c/rk4_kernel.c) is "
              "skipped")
    else:
        print_c_comparison(window, repeat, t_start, quick=args.quick)
    print_batched(window, rounds, t_start, quick=args.quick)


def print_c_comparison(window: float, repeat: int, t_start: float,
                       quick: bool = False) -> None:
    """The numba-against-C tables (gcc -O2, then with the host's instruction set; ``quick``:
    -O2 only)."""
    with tempfile.TemporaryDirectory() as tmp:
        builds = [("O2", CFLAGS), ("native", CFLAGS_NATIVE)][:1 if quick else None]
        libs = {name: build_c(tmp, flags, name) for name, flags in builds}
        cases = {}
        for name, flags in builds:
            c = libs[name]
            print(f"\nC baseline: gcc {' '.join(flags)} {os.path.relpath(C_SOURCE)}")
            print("ns per right-hand-side evaluation (CPU time, best of "
                  f"{repeat}; window {window} s of the run-up from t = {t_start} s, "
                  f"~{4000 * t_start:.0f} min^-1)")
            print(f"{'model':28s} {'RHS evals':>10s} {'RK4 loop numba':>15s} {'C':>8s} "
                  f"{'ratio':>6s} {'RHS alone numba':>16s} {'C':>8s} {'ratio':>6s}")
            for preset in C_CASES:
                if preset not in cases:
                    cases[preset] = c_case(preset, t_start)
                case = cases[preset]
                n_steps = round(window / case.dt)
                r = rhs_per_eval(case, c, n_steps, repeat)
                print(f"{preset:28s} {r['n_rhs']:10d} {r['loop_numba']:15.1f} "
                      f"{r['loop_c']:8.1f} {r['loop_numba'] / r['loop_c']:6.2f} "
                      f"{r['rhs_numba']:16.1f} {r['rhs_c']:8.1f} "
                      f"{r['rhs_numba'] / r['rhs_c']:6.2f}")
            print("(records of the C loop and of the numba kernel bit-identical)")


def print_batched(window: float, rounds: int, t_start: float = T_BATCH,
                  quick: bool = False) -> None:
    """The batched-against-single table (``quick``: its first row, the rigid-bearing set)."""
    load = os.getloadavg()[0]
    print(f"\nbatched kernel ({N_BATCH} variants in one call) against {N_BATCH} single runs, "
          f"{window} s from t = {t_start} s (~{4000 * t_start:.0f} min^-1): CPU time, median "
          f"(min-max) of {rounds} interleaved rounds; load average {load:.1f}")
    print(f"{'model':22s} {'variants':16s} {'throughput':>17s} {'generic kernel':>17s} "
          f"{'same sub-steps':>17s} {'RHS alone':>17s} {'ns/RHS single':>14s} "
          f"{'batch/lane':>11s}")
    rows = (("paper-case1", "damping"), ("paper-case1-elastic", "damping"),
            ("paper-case1-elastic", "damping+bearing"))
    for preset, which in rows[:1 if quick else None]:
        r = batched_vs_single(preset, which, window, rounds, t_start)
        print(f"{preset:22s} {which:16s} {_spread(r['ratio']):>17s} "
              f"{_spread(r['generic']):>17s} {_spread(r['same']):>17s} "
              f"{_spread(r['rhs_ratio']):>17s} {r['rhs_single']:14.0f} "
              f"{r['rhs_batch'] / N_BATCH:11.0f}")
    print("(throughput: 8 single runs' time / the batch's, kernel specialised to the "
          "topology; generic kernel: the same with the generic sparse loops; same sub-steps: "
          "8 copies of one variant, no lane waits; every batched variant of both kernels "
          "bit-identical to its single run)")
    print(f"load average at the end {os.getloadavg()[0]:.1f}")


_FIRST_CALL = """
import sys, time
import numpy as np
from gearvib import kernels as kn, kernels_batch as kb
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.simulate import SpeedRamp, prepare_run
from gearvib.sweep.keys import set_path
cfg, base = load_config(sys.argv[1])
systems = []
for k in range(8):
    d = set_path(cfg, "meshes.sun.damping_ratio", 0.005 * (1 + 0.25 * k))
    systems.append(prepare_run(assemble(gearset_from_dict(d, base=base)),
                               SpeedRamp(0.0, 4000.0, 1.0, input_torque=60.0), False).system)
batch = kb.pack_batch(systems)
n, nm = batch.n_dof, batch.n_mesh
rec = np.empty((kb.WIDTH, 3, kn.n_signals(n, nm)))
t0 = time.perf_counter()
kb.integrate_chunk_batch(np.zeros((2 * n, kb.WIDTH)), 0, 2, 1e-6, batch.astuple(), rec, 0,
                         np.full((kb.WIDTH, nm), -1), np.zeros((kb.WIDTH, nm), dtype=np.int64),
                         2, kb.batch_work(n, nm), np.zeros((kb.WIDTH, 2), dtype=np.int64))
print(time.perf_counter() - t0)
"""


def print_compile_times() -> None:
    """First call of the batched kernel in fresh processes with an empty numba cache (its
    own ``NUMBA_CACHE_DIR``; the single kernel's functions it calls are compiled too), then
    in a second process with that cache, generic and specialised kernel."""
    import sys
    print(f"\nfirst call of integrate_chunk_batch, wall time [s] (load average "
          f"{os.getloadavg()[0]:.1f}): empty numba cache / cache of the previous process")
    for preset in ("paper-case1", "paper-case1-elastic"):
        for kernel in ("generic", "specialised"):
            with tempfile.TemporaryDirectory() as cache:
                env = {**os.environ, "NUMBA_CACHE_DIR": cache, kb.KERNEL_ENV: kernel}
                times = [float(subprocess.run([sys.executable, "-c", _FIRST_CALL, preset],
                                              env=env, capture_output=True, text=True,
                                              check=True).stdout) for _ in range(2)]
            print(f"{preset:22s} {kernel:12s} {times[0]:6.2f} / {times[1]:5.2f}")

if __name__ == "__main__":
    main()
