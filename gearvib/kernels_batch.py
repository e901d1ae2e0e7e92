"""Batched run-up kernel: eight parameter sets of one topology advanced together, SIMD.

The variants of a sweep that differ only in values (mesh damping, stiffness, bearing
stiffness, masses, backlash, load, ...) share the sparsity pattern of every operator of
:func:`gearvib.kernels.pack`. This kernel stores their float data side by side, eight lanes on
the last axis (:func:`pack_batch`), decodes the sparse structure once and evaluates the
right-hand side of all eight in one pass on :data:`gearvib.lanes.lanes8` vectors: every term
of a sparse product is one vector multiply and add for the eight variants.

Bit for bit as single runs
--------------------------
Lane ``b`` performs the floating-point operations of :func:`gearvib.kernels.integrate_chunk`
for variant ``b``, in the same order, with no fused multiply-add (see :mod:`gearvib.lanes`):

* the sparse operators are stored with the union of the variants' patterns; an entry a variant
  does not have is stored as 0 and masked out of its sums (``lanes_madd_nz``), so each lane
  sums exactly its own terms in its own order;
* branches of the contact law become selects of both computed sides;
* the stiffness-table lookup (:func:`gearvib.lanes.lanes_table_pair`) repeats the single
  kernel's cell arithmetic on lanes; the per-step record and checks (:func:`_record8`) and the
  sub-step times at the stiffness jumps (:func:`_split_times8`) run on lanes where they compute
  and per lane where they store or insert, through the single kernel's own helpers
  (:func:`gearvib.kernels.insert_split`, :func:`~gearvib.kernels.speed_at`,
  :func:`~gearvib.kernels.table_at`) in its order.

Each variant keeps its own step splitting: a step whose stiffness jumps fall at different
times in different variants is split per lane, and the lanes advance in lockstep through the
largest number of sub-steps (a lane with fewer sub-steps is masked for the rest; its cost is
a wasted evaluation, not a different result). A variant that fails (non-finite state,
deflection or speed limit) is frozen at the step its single run stops at, and the others go
on. Models with local faults or manufacturing errors are not batched (their pair-by-pair
contact law is evaluated per mesh and per pair and is not written on lanes).

A batch has :data:`WIDTH` lanes; fewer variants are padded with copies of the first one (a
padded lane costs as much as a real one).

Specialised to the topology
---------------------------
:func:`integrate_chunk_batch` runs the batch in kernels specialised to its topology
(:func:`kernels_for`): :mod:`gearvib.batch_codegen` writes the right-hand side as straight-line
source (every sparse term with constant indices, the state vectors loaded once, the flank
forces kept in registers), and the RK4 step and the integrator of this module are compiled
again around it in a generated module. The module is written once, atomically, into numba's
cache folder of this module (``specialised/batch_<sha256>.py``; the name hashes its text,
which records the SHA-256 of the sources it embeds), and numba caches its compiled code like
any other. The generic kernels (:data:`GENERIC`: :func:`integrate_lanes` with sparse loops)
are used when ``GEARVIB_BATCH_KERNEL=generic`` or when no module can be written; both give
the same bits.

The compiled code of this module embeds helpers of :mod:`gearvib.kernels` and
:mod:`gearvib.lanes`. numba's cache checks only the defining file's modification time and
size, so it would load stale machine code after an edit of those files (an editable install).
At import, :func:`clear_stale_cache` compares a SHA-256 of both files with the one stored next
to this module's cache entries (``kernels_batch.deps-sha256`` in numba's cache folder for this
module) and removes the entries when they differ; numba then compiles again.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import inspect
import os
import secrets
import shutil
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numba import njit

from analysis.jit import prepare_cache, private_folder
from gearvib.batch_codegen import RowTerms, rhs_source
from gearvib.kernels import (
    DRIVE_MOTOR,
    DRIVE_SPEED,
    DRIVE_TORQUE,
    FP_C1,
    FP_C2,
    FP_CC,
    FP_KC,
    FP_OUTDIR,
    FP_SPEED_LIMIT,
    FP_T0,
    H_ACC0,
    H_BL,
    H_BP,
    H_BV,
    H_CI,
    H_CP,
    H_CV,
    H_DI,
    H_DV,
    H_FI,
    H_FP,
    H_FPAR,
    H_FV,
    H_GI,
    H_GP,
    H_GV,
    H_II,
    H_IPAR,
    H_IV,
    H_LI,
    H_LIMIT,
    H_LP,
    H_LV,
    H_MC,
    H_MLAW,
    H_N,
    H_ND,
    H_NI,
    H_NMESH,
    H_NO,
    H_OI,
    H_OV,
    H_PI,
    H_PP,
    H_PV,
    H_RFI,
    H_RFLAG,
    H_RFP,
    H_RFV,
    H_RVI,
    H_RVP,
    H_RVV,
    H_S0,
    H_VI,
    H_VP,
    H_VV,
    IP_CARRIER,
    IP_GYRO,
    IP_INPUT,
    IP_MODE,
    IP_OUTPUT,
    N_IPAR,
    STATUS_DEFLECTION,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_SPEED,
    KernelSystem,
    insert_split,
    n_signals,
    operators,
    pack,
    speed_at,
    table_at,
    work_shape,
)
from gearvib.lanes import (
    WIDTH,
    lanes_abs,
    lanes_any,
    lanes_bcast,
    lanes_coef,
    lanes_floor,
    lanes_load,
    lanes_madd,
    lanes_madd_nz,
    lanes_madd_nz2,
    lanes_msub_nz,
    lanes_scatter,
    lanes_splat,
    lanes_store,
    lanes_table_pair,
    where_gt,
    where_le,
    where_lt,
    where_ne0,
)

prepare_cache(__file__)

__all__ = [
    "BATCH_MESH_COLUMNS",
    "GENERIC",
    "KERNEL_ENV",
    "WIDTH",
    "BatchSystem",
    "KernelSet",
    "batch_work",
    "decode_rows",
    "evaluate_lanes",
    "evaluate_rhs_batch",
    "integrate_batch",
    "integrate_chunk_batch",
    "integrate_lanes",
    "kernel_namespace",
    "kernels_for",
    "pack_batch",
    "require_private",
    "rhs_loop_batch",
    "rhs_loop_lanes",
    "specialised_folder",
    "specialised_source",
    "topology_difference",
    "write_once",
]

#: Columns of the batched ``mesh_out``: ``F_L, -F_R, k_eff, state, delta, s, delta_R``.
BATCH_MESH_COLUMNS = 7

_U = np.uint64
_U1 = np.uint64(1)
_UW = np.uint64(WIDTH)

# float blocks of gearvib.kernels.pack that may hold one value in every lane
# (``BatchSystem.uniform``)
_B_LV, _B_CV, _B_GV, _B_VV, _B_FV, _B_PV, _B_RVV, _B_RFV = range(8)
_UNIFORM_BLOCKS = (H_LV, H_CV, H_GV, H_VV, H_FV, H_PV, H_RVV, H_RFV)
_UNIFORM_NAMES = ("lv", "cv", "gv", "vv", "fv", "pv", "rvv", "rfv")

# fields per row of BatchSystem.rows (row_terms)
_ROW_INPUT, _ROW_OUTPUT, _ROW_FIRST = range(3)
_ROW_FIELDS = 3

# rows of the lane scratch ``scr`` (shape (_N_SCR, WIDTH))
(_R_T, _R_PHI, _R_W, _R_SD, _R_NK, _R_BASE, _R_TAU, _R_NF, _R_DEFL, _R_SPEED, _R_NS,
 _R_LIVE) = range(12)
_N_SCR = 12


@njit(cache=True, inline="always")
def _dot(acc, ints, p0, p1, col, vals, val, y, off, mode):
    """``acc + sum_p vals[val + p] * y[off + ints[col + p]]`` per lane, term by term in the
    single kernel's order. ``mode`` (:attr:`BatchSystem.uniform`): 2 one value in every lane
    (loaded once), 1 a value per lane and none zero, 0 stored zeros (masked out)."""
    if mode == 2:
        for p in range(p0, p1):
            acc = lanes_madd(acc, lanes_bcast(vals, (val + p) * _UW),
                             lanes_load(y, (off + _U(ints[col + p])) * _UW))
    elif mode == 1:
        for p in range(p0, p1):
            acc = lanes_madd(acc, lanes_load(vals, (val + p) * _UW),
                             lanes_load(y, (off + _U(ints[col + p])) * _UW))
    else:
        for p in range(p0, p1):
            acc = lanes_madd_nz(acc, lanes_load(vals, (val + p) * _UW),
                                lanes_load(y, (off + _U(ints[col + p])) * _UW))
    return acc


@njit(cache=True, inline="always")
def _dot2(ints, p0, p1, col, vals, val, y, n, mode):
    """:func:`_dot` of ``q`` and of ``qdot`` with one vector, both from 0."""
    a = lanes_splat(0.0)
    b = lanes_splat(0.0)
    if mode == 2:
        for p in range(p0, p1):
            j = _U(ints[col + p])
            v = lanes_bcast(vals, (val + p) * _UW)
            a = lanes_madd(a, v, lanes_load(y, j * _UW))
            b = lanes_madd(b, v, lanes_load(y, (n + j) * _UW))
    elif mode == 1:
        for p in range(p0, p1):
            j = _U(ints[col + p])
            v = lanes_load(vals, (val + p) * _UW)
            a = lanes_madd(a, v, lanes_load(y, j * _UW))
            b = lanes_madd(b, v, lanes_load(y, (n + j) * _UW))
    else:
        for p in range(p0, p1):
            j = _U(ints[col + p])
            v = lanes_load(vals, (val + p) * _UW)
            a = lanes_madd_nz(a, v, lanes_load(y, j * _UW))
            b = lanes_madd_nz(b, v, lanes_load(y, (n + j) * _UW))
    return a, b


@njit(cache=True, inline="always")
def _mesh8(m, d, dd, dr, ddr, s, mo, vals, ints, tables):
    """Stiffness and contact law of mesh ``m`` on lanes (:func:`gearvib.kernels.
    flank_forces_two_lines`, branches as selects) from its deflections ``d, dd`` (left line),
    ``dr, ddr`` (back line) and position ``s``; stores the mesh quantities in ``mo[m]`` and
    returns ``(F_L, F_R)``."""
    n_mesh = _U(ints[H_NMESH])
    n_table = tables.shape[2]
    tw = _U(tables.shape[3])  # WIDTH: a table per lane; 1: one table every lane shares
    tstride = _U(n_table) * tw  # flat distance of two tables
    zero = lanes_splat(0.0)
    one = lanes_splat(1.0)
    kl, kr = lanes_table_pair(tables, m * tstride, (n_mesh + m) * tstride, n_table, tw, s)
    half = 0.5 * lanes_load(vals, (_U(ints[H_BL]) + m) * _UW)
    damping = lanes_load(vals, (_U(ints[H_MC]) + m) * _UW)
    fl = kl * (d - half) + damping * dd
    fl = where_gt(d, half, where_lt(fl, zero, zero, fl), zero)
    ke = where_gt(d, half, zero + kl, zero)
    st = where_gt(d, half, zero + one, zero)
    nhalf = -half
    fr = kr * (dr + half) + damping * ddr
    fr = where_lt(dr, nhalf, where_gt(fr, zero, zero, fr), zero)
    ke = where_lt(dr, nhalf, ke + kr, ke)
    st = where_lt(dr, nhalf, st + 2.0, st)
    _store_mesh8(mo, m, fl, fr, ke, st, d, s, dr)
    return fl, fr


@njit(cache=True, inline="always")
def _mesh8_viscous(m, d, dd, dr, ddr, s, mo, vals, ints, tables):
    """:func:`_mesh8` with the always-on damping law (:func:`gearvib.kernels.
    flank_forces_viscous`, branches as selects): the viscous force on the left line unless
    only the back flank is in contact."""
    n_mesh = _U(ints[H_NMESH])
    n_table = tables.shape[2]
    tw = _U(tables.shape[3])
    tstride = _U(n_table) * tw
    zero = lanes_splat(0.0)
    one = lanes_splat(1.0)
    kl, kr = lanes_table_pair(tables, m * tstride, (n_mesh + m) * tstride, n_table, tw, s)
    half = 0.5 * lanes_load(vals, (_U(ints[H_BL]) + m) * _UW)
    damping = lanes_load(vals, (_U(ints[H_MC]) + m) * _UW)
    sl = where_gt(d, half, kl * (d - half), zero)
    ke = where_gt(d, half, zero + kl, zero)
    st = where_gt(d, half, zero + one, zero)
    nhalf = -half
    sr = where_lt(dr, nhalf, kr * (dr + half), zero)
    ke = where_lt(dr, nhalf, ke + kr, ke)
    st = where_lt(dr, nhalf, st + 2.0, st)
    cl = sl + damping * dd
    fl = where_gt(d, half, cl, where_lt(dr, nhalf, sl, cl))
    fr = where_gt(d, half, sr, where_lt(dr, nhalf, sr + damping * ddr, sr))
    _store_mesh8(mo, m, fl, fr, ke, st, d, s, dr)
    return fl, fr


@njit(cache=True, inline="always")
def _store_mesh8(mo, m, fl, fr, ke, st, d, s, dr):
    """``mo[m] = (F_L, -F_R, k_eff, state, delta, s, delta_R)`` on lanes."""
    r = m * _U(BATCH_MESH_COLUMNS) * _UW
    lanes_store(mo, r, fl)
    lanes_store(mo, r + _UW, -fr)
    lanes_store(mo, r + _U(2) * _UW, ke)
    lanes_store(mo, r + _U(3) * _UW, st)
    lanes_store(mo, r + _U(4) * _UW, d)
    lanes_store(mo, r + _U(5) * _UW, s)
    lanes_store(mo, r + _U(6) * _UW, dr)


@njit(cache=True, inline="always")
def _torque8(y, scr, ints, vals, speed_tab, torque_tab):
    """The input torque of every lane at its time ``scr[_R_T]`` (drive modes of
    :func:`gearvib.kernels._rhs`)."""
    n = _U(ints[H_N])
    fpar = _U(ints[H_FPAR])
    mode = ints[H_IPAR + IP_MODE]
    k_in = _U(ints[H_IPAR + IP_INPUT])  # >= 0: every model has an input rotation
    if mode == DRIVE_SPEED:
        t0 = scr[_R_T, 0]
        phi, w = speed_at(speed_tab, t0)
        one_time = True
        for b in range(1, WIDTH):
            one_time = one_time and scr[_R_T, b] == t0
        if one_time:  # the lanes at one time (the usual case) share the drive
            phi_v = lanes_splat(phi)
            w_v = lanes_splat(w)
        else:
            for b in range(WIDTH):
                tb = scr[_R_T, b]
                if b > 0 and tb != scr[_R_T, b - 1]:
                    phi, w = speed_at(speed_tab, tb)
                scr[_R_PHI, b] = phi
                scr[_R_W, b] = w
            phi_v = lanes_load(scr, _R_PHI * WIDTH)
            w_v = lanes_load(scr, _R_W * WIDTH)
        nd = _U(ints[H_ND])
        if nd == 0:  # a coupling on the input coordinate
            ang = lanes_load(y, k_in * _UW)
            rate = lanes_load(y, (n + k_in) * _UW)
        else:  # a controller on the rigid-body coordinate (a stored zero masked out)
            di = _U(ints[H_DI])
            dv = _U(ints[H_DV])
            ang = lanes_splat(0.0)
            rate = lanes_splat(0.0)
            for p in range(nd):
                j = _U(ints[di + p])
                v = lanes_load(vals, (dv + p) * _UW)
                ang = lanes_madd_nz(ang, v, lanes_load(y, j * _UW))
                rate = lanes_madd_nz(rate, v, lanes_load(y, (n + j) * _UW))
        torque = lanes_load(vals, (fpar + _U(FP_KC)) * _UW) * (phi_v - ang) + lanes_load(
            vals, (fpar + _U(FP_CC)) * _UW) * (w_v - rate)
    elif mode in (DRIVE_TORQUE, DRIVE_MOTOR):
        for b in range(WIDTH):
            x = scr[_R_T, b] if mode == DRIVE_TORQUE else y[n + k_in, b]
            scr[_R_PHI, b] = table_at(torque_tab, x)
        torque = lanes_load(scr, _R_PHI * WIDTH)
    else:
        torque = lanes_splat(0.0)
    return torque


@njit(cache=True, inline="always")
def _load8(y, ints, vals):
    """The load torque of every lane (:func:`gearvib.kernels._rhs`)."""
    n = _U(ints[H_N])
    fpar = _U(ints[H_FPAR])
    zero = lanes_splat(0.0)
    k_out = ints[H_IPAR + IP_OUTPUT]
    load = zero
    if k_out >= 0:
        e = lanes_load(vals, (fpar + _U(FP_OUTDIR)) * _UW)
        wo = e * lanes_load(y, (n + _U(k_out)) * _UW)
        load = -e * (
            lanes_load(vals, (fpar + _U(FP_T0)) * _UW)
            + lanes_load(vals, (fpar + _U(FP_C1)) * _UW) * wo
            + lanes_load(vals, (fpar + _U(FP_C2)) * _UW) * wo * lanes_abs(wo)
        )
    return load


@njit(cache=True, _nrt=False)
def _rhs8(y, dy, mo, scr, ints, vals, uniform, rows, forces, tables, speed_tab, torque_tab):
    """The right-hand side of :func:`gearvib.kernels._rhs` for eight variants at once.

    ``y, dy``: shape ``(2 n, WIDTH)``; ``mo``: ``(n_mesh, BATCH_MESH_COLUMNS, WIDTH)``; the
    lanes' times in ``scr[_R_T]``; ``forces``: scratch ``(2 n_mesh, WIDTH)``. Operation by
    operation the single kernel's (module doc), in another loop order: the meshes' flank
    forces first, then every acceleration row in one pass (its stiffness and damping sum,
    gyroscopic term, input torque, load and the mesh forces in mesh order, as the single
    kernel adds them to that row: ``rows``, :func:`row_terms`), so a row stays in a
    register instead of going through memory once per mesh.
    """
    n = _U(ints[H_N])
    n_mesh = _U(ints[H_NMESH])
    zero = lanes_splat(0.0)
    # the meshes: deflections, positions, stiffness, flank forces
    vp = _U(ints[H_VP])
    vi = _U(ints[H_VI])
    vv = _U(ints[H_VV])
    pp = _U(ints[H_PP])
    pi = _U(ints[H_PI])
    pv = _U(ints[H_PV])
    s0 = _U(ints[H_S0])
    rflag = _U(ints[H_RFLAG])
    rvp = _U(ints[H_RVP])
    rvi = _U(ints[H_RVI])
    rvv = _U(ints[H_RVV])
    m_v = uniform[_B_VV]
    m_rv = uniform[_B_RVV]
    m_p = uniform[_B_PV]
    ml = _U(ints[H_MLAW])
    for m in range(n_mesh):
        d, dd = _dot2(ints, _U(ints[vp + m]), _U(ints[vp + m + _U1]), vi, vals, vv, y, n, m_v)
        two_lines = ints[rflag + m] != 0
        dr = d
        ddr = dd
        if two_lines:  # the back flank's own line of action
            dr, ddr = _dot2(ints, _U(ints[rvp + m]), _U(ints[rvp + m + _U1]), rvi, vals, rvv,
                            y, n, m_rv)
        s = _dot(lanes_load(vals, (s0 + m) * _UW), ints, _U(ints[pp + m]),
                 _U(ints[pp + m + _U1]), pi, vals, pv, y, _U(0), m_p)
        if ints[ml + m] != 0:  # the always-on damping law (every lane: part of the topology)
            fl, fr = _mesh8_viscous(m, d, dd, dr, ddr, s, mo, vals, ints, tables)
        else:
            fl, fr = _mesh8(m, d, dd, dr, ddr, s, mo, vals, ints, tables)
        # one line of action: the summed force (slot 2 m), else F_L and F_R
        lanes_store(forces, _U(2) * m * _UW, fl if two_lines else fl + fr)
        lanes_store(forces, (_U(2) * m + _U1) * _UW, fr)
    torque = _torque8(y, scr, ints, vals, speed_tab, torque_tab)
    load = _load8(y, ints, vals)
    # the rows: qdot, then qddot term by term in the single kernel's order
    lp = _U(ints[H_LP])
    li = _U(ints[H_LI])
    lv = _U(ints[H_LV])
    a0 = _U(ints[H_ACC0])
    m_l = uniform[_B_LV]
    carrier = ints[H_IPAR + IP_CARRIER]
    gyro = ints[H_IPAR + IP_GYRO] != 0 and carrier >= 0
    om = zero
    if gyro:
        om = lanes_load(y, (n + _U(carrier)) * _UW)
    om2 = om * om
    cp = _U(ints[H_CP])
    ci = _U(ints[H_CI])
    cv = _U(ints[H_CV])
    gp = _U(ints[H_GP])
    gi = _U(ints[H_GI])
    gv = _U(ints[H_GV])
    m_c = uniform[_B_CV]
    m_g = uniform[_B_GV]
    u_f = uniform[_B_FV] == 2 and uniform[_B_RFV] == 2
    for i in range(n):
        lanes_store(dy, i * _UW, lanes_load(y, (n + i) * _UW))
        acc = _dot(lanes_load(vals, (a0 + i) * _UW), ints, _U(ints[lp + i]),
                   _U(ints[lp + i + _U1]), li, vals, lv, y, _U(0), m_l)
        if gyro:
            acc_c = _dot(zero, ints, _U(ints[cp + i]), _U(ints[cp + i + _U1]), ci, vals, cv,
                         y, _U(0), m_c)
            acc_g = _dot(zero, ints, _U(ints[gp + i]), _U(ints[gp + i + _U1]), gi, vals, gv,
                         y, n, m_g)
            acc = acc + (om2 * acc_c + om * acc_g)
        r0 = _U(i) * _U(_ROW_FIELDS)
        p_in = rows[r0 + _U(_ROW_INPUT)]
        if p_in >= 0:
            acc = lanes_madd_nz2(acc, lanes_load(vals, _U(p_in) * _UW), torque)
        p_out = rows[r0 + _U(_ROW_OUTPUT)]
        if p_out >= 0:
            acc = lanes_madd_nz(acc, lanes_load(vals, _U(p_out) * _UW), load)
        for q in range(_U(rows[r0 + _U(_ROW_FIRST)]),
                       _U(rows[r0 + _U(_ROW_FIELDS + _ROW_FIRST)])):
            e0 = _U(rows[q])
            acc = lanes_msub_nz(acc, lanes_load(forces, (e0 >> _U(32)) * _UW),
                                lanes_coef(vals, (e0 & _U(0xFFFFFFFF)) * _UW, u_f))
        lanes_store(dy, (n + _U(i)) * _UW, acc)


@njit(cache=True, _nrt=False)
def _split_times8(y, dt, ints, vals, uniform, mo, scr, splits, n_split, status):
    """``gearvib.kernels._split_times`` of every live lane (healthy meshes), the
    extrapolation and the candidate times computed on lanes; each lane's candidates are
    inserted into its sorted list in the single kernel's order. Returns the largest count."""
    n = _U(ints[H_N])
    pp = _U(ints[H_PP])
    pi = _U(ints[H_PI])
    pv = _U(ints[H_PV])
    bp = _U(ints[H_BP])
    bv = _U(ints[H_BV])
    m_p = uniform[_B_PV]
    tol = 1e-9 * dt
    zero = lanes_splat(0.0)
    one = lanes_splat(1.0)
    for b in range(WIDTH):
        n_split[b] = 0
    for m in range(_U(ints[H_NMESH])):
        b0 = _U(ints[bp + m])
        b1 = _U(ints[bp + m + _U1])
        if b1 == b0:
            continue
        s = lanes_load(mo, (m * _U(BATCH_MESH_COLUMNS) + _U(5)) * _UW)
        sd = _dot(zero, ints, _U(ints[pp + m]), _U(ints[pp + m + _U1]), pi, vals, pv, y, n,
                  m_p)
        s_end = s + sd * dt
        lo = where_lt(s_end, s, s_end, s)
        hi = where_gt(s_end, s, s_end, s)
        base = lanes_floor(lo)
        lanes_store(scr, _R_SD * WIDTH, sd)
        lanes_store(scr, _R_BASE * WIDTH, base)
        lanes_store(scr, _R_NK * WIDTH, lanes_floor(hi) - base)
        k_most = 0
        for b in range(WIDTH):
            if status[b, 0] == STATUS_OK and scr[_R_SD, b] != 0.0:
                k_most = max(k_most, int(scr[_R_NK, b]) + 1)
        reach = 2.0 * sd * dt
        for k in range(k_most):
            bk = base + float(k)
            for q in range(b0, b1):
                x = bk + lanes_load(vals, (bv + q) * _UW) - s
                # lanes whose time x / sd can lie in (0, dt): of the sign of sd and within
                # twice the step (a safe bound on the rounded quotient); no others divide
                near = where_gt(sd, zero, where_gt(x, zero, where_le(x, reach, one, zero), zero),
                                where_lt(x, zero, where_le(reach, x, one, zero), zero))
                if not lanes_any(near):
                    continue
                lanes_store(scr, _R_TAU * WIDTH, x / sd)
                for b in range(WIDTH):
                    if (status[b, 0] == STATUS_OK and scr[_R_SD, b] != 0.0
                            and k < int(scr[_R_NK, b]) + 1):
                        n_split[b] = insert_split(splits[:, b], n_split[b], scr[_R_TAU, b], dt,
                                                  tol)
    most = 0
    for b in range(WIDTH):
        most = max(most, n_split[b])
    return most


@njit(cache=True, _nrt=False)
def _record8(g, y, mo, scr, record, row, flank_state, contact_changes, count_until, ints,
             vals, status):
    """The per-step header of :func:`gearvib.kernels.integrate_chunk` (record the sample,
    count contact changes, check it) for every live lane at once: the same rows (each
    vector stored lane by lane), the same contact-change counts and the same checks in the
    same priority (a non-finite state, then a deflection limit, then the speed limit). Sets
    the status of the lanes that fail and returns their number. Rows of lanes that failed
    earlier are written too (unspecified, as the rows after a single run's failed step)."""
    n = _U(ints[H_N])
    n_mesh = _U(ints[H_NMESH])
    n2 = _U(2) * n
    lim = _U(ints[H_LIMIT])
    k_in = ints[H_IPAR + IP_INPUT]
    stride = _U(record.shape[1]) * _U(record.shape[2])  # one lane's record to the next
    base = _U(row) * _U(record.shape[2])
    zero = lanes_splat(0.0)
    one = lanes_splat(1.0)
    inf = lanes_splat(np.inf)
    nonfinite = zero
    for i in range(n2):
        v = lanes_load(y, i * _UW)
        lanes_scatter(record, base + i, stride, v)
        nonfinite = where_lt(lanes_abs(v), inf, nonfinite, one)
    deflection = zero
    for m in range(n_mesh):
        r = m * _U(BATCH_MESH_COLUMNS) * _UW
        lanes_scatter(record, base + n2 + m, stride, lanes_load(mo, r))
        lanes_scatter(record, base + n2 + n_mesh + m, stride, lanes_load(mo, r + _UW))
        lanes_scatter(record, base + n2 + _U(2) * n_mesh + m, stride,
                      lanes_load(mo, r + _U(2) * _UW))
        lm = lanes_load(vals, (lim + m) * _UW)
        deflection = where_le(lanes_abs(lanes_load(mo, r + _U(4) * _UW)), lm, deflection, one)
        deflection = where_le(lanes_abs(lanes_load(mo, r + _U(6) * _UW)), lm, deflection, one)
    speed = zero
    if k_in >= 0:
        speed = where_le(lanes_abs(lanes_load(y, (n + _U(k_in)) * _UW)),
                         lanes_load(vals, (_U(ints[H_FPAR]) + _U(FP_SPEED_LIMIT)) * _UW),
                         zero, one)
    lanes_store(scr, _R_NF * WIDTH, nonfinite)
    lanes_store(scr, _R_DEFL * WIDTH, deflection)
    lanes_store(scr, _R_SPEED * WIDTH, speed)
    failed = 0
    for b in range(WIDTH):
        if status[b, 0] != STATUS_OK:
            continue
        for m in range(n_mesh):
            st = int(mo[m, 3, b])
            if flank_state[b, m] >= 0 and st != flank_state[b, m] and g <= count_until:
                contact_changes[b, m] += 1
            flank_state[b, m] = st
        bad = STATUS_OK
        if scr[_R_NF, b] != 0.0:
            bad = STATUS_NONFINITE
        elif scr[_R_DEFL, b] != 0.0:
            bad = STATUS_DEFLECTION
        elif scr[_R_SPEED, b] != 0.0:
            bad = STATUS_SPEED
        if bad != STATUS_OK:
            status[b, 0] = bad
            status[b, 1] = g
            failed += 1
    return failed


@njit(cache=True, _nrt=False)
def _rk4_step8(t0, h, on, y, k1, k2, k3, k4, tmp, mo, scr, ints, vals, uniform, rows, forces,
               tables, speed_tab, torque_tab):
    """:func:`gearvib.kernels._rk4_step` of every lane from ``(t0, y)`` with the step ``h``
    (lane vectors); ``k1`` given; lanes where ``on`` is 0 keep their state."""
    n2 = _U(2 * ints[H_N])
    h2 = 0.5 * h
    h6 = h / 6.0
    lanes_store(scr, _R_T * WIDTH, t0 + h2)
    for i in range(n2):
        r = i * _UW
        lanes_store(tmp, r, lanes_load(y, r) + h2 * lanes_load(k1, r))
    _rhs8(tmp, k2, mo, scr, ints, vals, uniform, rows, forces, tables, speed_tab, torque_tab)
    for i in range(n2):
        r = i * _UW
        lanes_store(tmp, r, lanes_load(y, r) + h2 * lanes_load(k2, r))
    _rhs8(tmp, k3, mo, scr, ints, vals, uniform, rows, forces, tables, speed_tab, torque_tab)
    lanes_store(scr, _R_T * WIDTH, t0 + h)
    for i in range(n2):
        r = i * _UW
        lanes_store(tmp, r, lanes_load(y, r) + h * lanes_load(k3, r))
    _rhs8(tmp, k4, mo, scr, ints, vals, uniform, rows, forces, tables, speed_tab, torque_tab)
    for i in range(n2):
        r = i * _UW
        yi = lanes_load(y, r)
        new = yi + h6 * (lanes_load(k1, r) + 2.0 * (lanes_load(k2, r) + lanes_load(k3, r))
                         + lanes_load(k4, r))
        lanes_store(y, r, where_ne0(on, new, yi))


def batch_work(n_dof: int, n_mesh: int) -> tuple:
    """The ``work`` buffers of :func:`integrate_chunk_batch` (allocated once per run)."""
    return (np.empty((5, 2 * n_dof, WIDTH)),  # RK4 stages k1..k4, tmp
            np.empty((n_mesh, BATCH_MESH_COLUMNS, WIDTH)),  # mesh quantities, lanes last
            np.empty((2 * n_mesh, WIDTH)),  # flank forces
            np.zeros((_N_SCR, WIDTH)),  # lane scratch
            np.empty((WIDTH, 2 * n_dof)),  # states of failed lanes
            np.empty((work_shape(n_dof, n_mesh)[1], WIDTH)),  # sub-step times, lanes last
            np.zeros(WIDTH, dtype=np.int64))  # their counts


@njit(cache=True, _nrt=False)
def integrate_lanes(
    y: np.ndarray,
    first_step: int,
    n_steps: int,
    dt: float,
    batch: tuple,
    record: np.ndarray,
    record_offset: int,
    flank_state: np.ndarray,
    contact_changes: np.ndarray,
    count_until: int,
    work: tuple,
    status: np.ndarray,
) -> None:
    """:func:`gearvib.kernels.integrate_chunk` of the :data:`WIDTH` lanes of a batch
    (:func:`integrate_chunk_batch`, generic or in a module specialised to the topology).

    Parameters
    ----------
    y : ndarray, shape (2 n, WIDTH)
        States (one column per lane); updated in place.
    first_step, n_steps, dt, record_offset, count_until
        As in :func:`gearvib.kernels.integrate_chunk`.
    batch : tuple
        :meth:`BatchSystem.astuple`.
    record : ndarray, shape (WIDTH, rows, 2 n + 3 n_mesh)
        Recorded rows per lane.
    flank_state, contact_changes : ndarray of int64, shape (WIDTH, n_mesh)
        As in :func:`gearvib.kernels.integrate_chunk`, per lane.
    work : tuple
        :func:`batch_work`.
    status : ndarray of int64, shape (WIDTH, 2)
        Per lane ``(STATUS_*, global step)`` as the single kernel's. A lane that failed
        before this chunk (status not ``STATUS_OK``) is not advanced; one that fails in it
        keeps the state of its failed step, the others go on.
    """
    ints, vals, uniform, rows, tables, speed_tab, torque_tab = batch
    stages, mesh_out, forces, scr, lane_y, splits, n_split = work
    n2 = 2 * ints[H_N]
    k1 = stages[0]
    k2 = stages[1]
    k3 = stages[2]
    k4 = stages[3]
    tmp = stages[4]
    cap = splits.shape[0]
    zero = lanes_splat(0.0)
    dtv = lanes_splat(dt)
    n_live = 0
    for b in range(WIDTH):
        if status[b, 0] == STATUS_OK:
            status[b, 1] = first_step + n_steps
            n_live += 1
        else:  # a lane that failed earlier: a finite stand-in state, restored at the end
            for i in range(n2):
                lane_y[b, i] = y[i, b]
                y[i, b] = 0.0
    for step in range(n_steps):
        if n_live == 0:
            break
        g = first_step + step
        t = g * dt
        for b in range(WIDTH):
            scr[_R_T, b] = t
        _rhs8(y, k1, mesh_out, scr, ints, vals, uniform, rows, forces, tables, speed_tab,
              torque_tab)
        row = record_offset + step
        if _record8(g, y, mesh_out, scr, record, row, flank_state, contact_changes,
                    count_until, ints, vals, status) > 0:
            for b in range(WIDTH):
                if status[b, 0] != STATUS_OK and status[b, 1] == g:  # failed here
                    n_live -= 1
                    for i in range(n2):  # lane_y keeps the failed state; a finite stand-in
                        lane_y[b, i] = y[i, b]
                        y[i, b] = 0.0
        if n_live == 0:
            break
        most = _split_times8(y, dt, ints, vals, uniform, mesh_out, scr, splits, n_split,
                             status)
        for b in range(WIDTH):
            scr[_R_NS, b] = n_split[b]
            scr[_R_LIVE, b] = 1.0 if status[b, 0] == STATUS_OK else 0.0
        n_sub = lanes_load(scr, _R_NS * WIDTH)
        live = lanes_load(scr, _R_LIVE * WIDTH)
        ta = zero
        for j in range(most + 1):
            jv = lanes_splat(float(j))
            tb = dtv
            if j < cap:
                tb = where_lt(jv, n_sub, lanes_load(splits, j * WIDTH), dtv)
            on = where_le(jv, n_sub, live, zero)  # this sub-step is one of the lane's
            tb = where_ne0(on, tb, ta)  # a waiting lane takes a zero step, masked
            t0 = t + ta
            if j > 0:
                lanes_store(scr, _R_T * WIDTH, t0)
                _rhs8(y, k1, mesh_out, scr, ints, vals, uniform, rows, forces, tables,
                      speed_tab, torque_tab)
            _rk4_step8(t0, tb - ta, on, y, k1, k2, k3, k4, tmp, mesh_out, scr, ints, vals,
                       uniform, rows, forces, tables, speed_tab, torque_tab)
            ta = tb
    for b in range(WIDTH):  # the failed lanes' states
        if status[b, 0] != STATUS_OK:
            for i in range(n2):
                y[i, b] = lane_y[b, i]


def row_terms(ints: np.ndarray) -> np.ndarray:
    """Which terms the single kernel adds to each acceleration row after its stiffness,
    damping and gyroscopic sums, in its order (the input of :func:`_rhs8`'s row pass).

    Per row ``i`` of ``qddot``, ``_ROW_FIELDS`` entries: the float-block row of its
    coefficient of the input torque (-1: none), of the load (-1: none), and where its mesh
    terms start; one more row holds the end. Each mesh term is ``slot << 32 | coefficient``:
    ``slot`` ``2 m`` is mesh ``m``'s left-flank force (the summed force of a mesh with one
    line of action), ``2 m + 1`` its right-flank force; the terms are in mesh order and, in a
    mesh, left before right, as :func:`gearvib.kernels._rhs` subtracts them.
    """
    n = int(ints[H_N])
    n_mesh = int(ints[H_NMESH])
    head = np.full((n + 1, _ROW_FIELDS), -1, dtype=np.int64)
    for p in range(int(ints[H_NI])):
        head[ints[ints[H_II] + p], _ROW_INPUT] = ints[H_IV] + p
    for p in range(int(ints[H_NO])):
        head[ints[ints[H_OI] + p], _ROW_OUTPUT] = ints[H_OV] + p
    terms: list[list[int]] = [[] for _ in range(n)]
    for m in range(n_mesh):
        blocks = [(H_FP, H_FI, H_FV, 2 * m)]
        if ints[ints[H_RFLAG] + m] != 0:
            blocks.append((H_RFP, H_RFI, H_RFV, 2 * m + 1))
        for hp, hi, hv, slot in blocks:
            for p in range(ints[ints[hp] + m], ints[ints[hp] + m + 1]):
                terms[ints[ints[hi] + p]].append(slot << 32 | int(ints[hv] + p))
    start = head.size
    for i in range(n):
        head[i, _ROW_FIRST] = start
        start += len(terms[i])
    head[n, _ROW_FIRST] = start
    return np.concatenate([head.ravel(), np.array([t for r in terms for t in r],
                                                  dtype=np.int64)])


class BatchSystem:
    """:data:`WIDTH` kernel systems of one topology packed side by side (:func:`pack_batch`).

    Attributes
    ----------
    ints : ndarray of int64
        The packed integer array every lane shares (:func:`gearvib.kernels.pack` with the
        union of the lanes' sparsity patterns).
    vals : ndarray, shape (n_vals, WIDTH)
        The packed float arrays, one column per lane.
    tables : ndarray, shape (2, n_mesh, n_table, WIDTH) or (2, n_mesh, n_table, 1)
        Flank stiffness tables per lane, or one set every lane shares (when the variants'
        tables are equal).
    speed_table, torque_table : ndarray
        The drive tables every lane shares.
    rows : ndarray of int64
        :func:`row_terms` of ``ints``.
    uniform : ndarray of int64
        Per sparse operator (stiffness and damping, centripetal, gyroscopic, mesh vectors,
        mesh force vectors, mesh-position vectors, back-flank vectors and force vectors): 2
        when every lane holds the same values (e.g. the geometry of variants that differ in
        damping), which the kernel then loads once for all lanes; 1 when the lanes differ but
        no stored entry is zero; 0 when some lane stores a zero (an entry of the common
        pattern it does not have), which its sums skip.
    n_variants : int
        Lanes that hold a variant; the others repeat variant 0.
    """

    def __init__(self, ints, vals, tables, speed_table, torque_table, n_variants: int):
        self.ints = ints
        self.vals = np.ascontiguousarray(vals)
        self.tables = np.ascontiguousarray(tables)
        self.speed_table = speed_table
        self.torque_table = torque_table
        self.n_variants = n_variants
        modes = []
        for h in _UNIFORM_BLOCKS:
            block = self.vals[ints[h]:ints[h + 1]]  # up to the next block's start
            modes.append(2 if np.all(block == block[:, :1]) else 1 if np.all(block != 0.0)
                         else 0)
        self.uniform = np.array(modes, dtype=np.int64)
        self.rows = row_terms(ints)

    @property
    def n_dof(self) -> int:
        return int(self.ints[H_N])

    @property
    def n_mesh(self) -> int:
        return int(self.ints[H_NMESH])

    def astuple(self) -> tuple:
        """The ``batch`` argument of :func:`integrate_chunk_batch`."""
        return (self.ints, self.vals, self.uniform, self.rows, self.tables, self.speed_table,
                self.torque_table)


_BLOCK_NAMES = {
    "lp": "sparsity of the stiffness and damping operators",
    "li": "sparsity of the stiffness and damping operators",
    "cp": "sparsity of the centripetal operator", "ci": "sparsity of the centripetal operator",
    "gp": "sparsity of the gyroscopic operator", "gi": "sparsity of the gyroscopic operator",
    "ii": "coordinates the input torque acts on", "oi": "coordinates the load acts on",
    "vp": "sparsity of the mesh vectors", "vi": "sparsity of the mesh vectors",
    "fp": "sparsity of the mesh force vectors", "fi": "sparsity of the mesh force vectors",
    "pp": "sparsity of the mesh-position vectors", "pi": "sparsity of the mesh-position vectors",
    "bp": "number of stiffness jumps per mesh (shape of the stiffness tables)",
    "rflag": "meshes with a distinct back-flank line of action",
    "rvp": "sparsity of the back-flank vectors", "rvi": "sparsity of the back-flank vectors",
    "rfp": "sparsity of the back-flank force vectors",
    "rfi": "sparsity of the back-flank force vectors",
    "frec": "local faults or manufacturing errors", "fint": "local faults or manufacturing errors",
    "mlaw": "mesh-damping laws (gated or viscous)",
    "di": "drive coupling (on the input member or on the rigid-body mode)",
}
_INT_BLOCKS = tuple(_BLOCK_NAMES)


def topology_difference(a: tuple, b: tuple) -> str | None:
    """What differs between the topologies of two packed systems (:func:`pack`), or None.

    Two systems can share a batch (:func:`pack_batch`) when their packed integer arrays (sizes,
    drive, sparsity patterns, jump counts) and their drive tables are equal and the float
    arrays and stiffness tables have the same shapes.
    """
    ia, ib = a[0], b[0]
    if ia[H_N] != ib[H_N]:
        return f"number of coordinates ({ia[H_N]} vs {ib[H_N]})"
    if ia[H_NMESH] != ib[H_NMESH]:
        return f"number of meshes ({ia[H_NMESH]} vs {ib[H_NMESH]})"
    names = ("drive mode", "input coordinate", "output coordinate", "carrier coordinate",
             "gyroscopic switch")
    for k in range(N_IPAR):
        if ia[H_IPAR + k] != ib[H_IPAR + k]:
            return f"{names[k]} ({ia[H_IPAR + k]} vs {ib[H_IPAR + k]})"
    for k, name in enumerate(_INT_BLOCKS):
        h = H_LP + k
        ea = ia[h + 1] if h + 1 < H_LP + len(_INT_BLOCKS) else ia.size
        eb = ib[h + 1] if h + 1 < H_LP + len(_INT_BLOCKS) else ib.size
        if not np.array_equal(ia[ia[h]:ea], ib[ib[h]:eb]):
            return _BLOCK_NAMES[name]
    if not np.array_equal(ia, ib) or a[1].shape != b[1].shape:
        return "layout of the packed arrays"
    if a[2].shape != b[2].shape:
        return f"stiffness table length ({a[2].shape[2]} vs {b[2].shape[2]} samples per cycle)"
    if a[3].shape != b[3].shape or not np.array_equal(a[3], b[3]):
        return "speed table of the drive"
    if a[4].shape != b[4].shape or not np.array_equal(a[4], b[4]):
        return "torque table of the drive"
    return None


def pack_batch(systems: list) -> BatchSystem:
    """Pack up to :data:`WIDTH` systems of one topology for :func:`integrate_chunk_batch`.

    Every sparse operator is stored with the union of the variants' patterns (an entry that is
    exactly zero in one variant only, e.g. a rounding residue of a rotated bearing stiffness,
    is stored as 0 there and masked out of its sums), so the variants share one integer
    array. Fewer than :data:`WIDTH` variants are padded with copies of the first.

    Parameters
    ----------
    systems : list of KernelSystem
        The variants: the same coordinates, meshes, drive and stiffness-jump counts
        (:func:`topology_difference`), no local faults or manufacturing errors.

    Raises
    ------
    ValueError
        No or more than :data:`WIDTH` variants, a variant with faults, or variants whose
        topologies differ (the message names the variant and what differs).
    """
    if not systems:
        raise ValueError("pack_batch needs at least one system")
    if len(systems) > WIDTH:
        raise ValueError(f"pack_batch packs at most {WIDTH} systems, got {len(systems)} "
                         "(integrate_batch splits larger sets)")
    for k, s in enumerate(systems):
        if not isinstance(s, KernelSystem):
            raise TypeError(f"variant {k} is a {type(s).__name__}, not a KernelSystem")
        if s.fault_records is not None and np.any(s.fault_records >= 0):
            raise ValueError(f"variant {k} has local faults or manufacturing errors; such "
                             "models are not batched (simulate them one by one)")
        s0 = systems[0]
        if k and (s.n_dof, s.n_mesh) != (s0.n_dof, s0.n_mesh):
            raise ValueError(f"variant {k} does not share the topology of variant 0: its "
                             f"number of coordinates / meshes ({s.n_dof} / {s.n_mesh}) differs "
                             f"({s0.n_dof} / {s0.n_mesh})")
        if k and s.ipar[IP_MODE] == s0.ipar[IP_MODE] and (
                (s.drive_sensing is None) != (s0.drive_sensing is None)):
            raise ValueError(f"variant {k} does not share the topology of variant 0: its "
                             "drive coupling (on the input member or on the rigid-body mode) "
                             "differs")
        if k and s.left_tables.shape != s0.left_tables.shape:
            raise ValueError(f"variant {k} does not share the topology of variant 0: its "
                             f"stiffness table length ({s.left_tables.shape[1]} samples per "
                             f"cycle) differs ({s0.left_tables.shape[1]})")
    ops = [operators(s) for s in systems]
    patterns = [np.logical_or.reduce([o[k] != 0.0 for o in ops]) for k in range(len(ops[0]))]
    packed = [pack(s, patterns) for s in systems]
    for k, p in enumerate(packed[1:], start=1):
        if (why := topology_difference(packed[0], p)) is not None:
            raise ValueError(f"variant {k} does not share the topology of variant 0: its "
                             f"{why} differs")
    lanes = packed + [packed[0]] * (WIDTH - len(packed))
    vals = np.stack([p[1] for p in lanes], axis=-1)
    if all(np.array_equal(p[2], packed[0][2]) for p in packed[1:]):
        tables = packed[0][2][..., None]  # one table for every lane (no copies to stream)
    else:
        tables = np.stack([p[2] for p in lanes], axis=-1)
    return BatchSystem(packed[0][0], vals, tables, packed[0][3], packed[0][4], len(systems))


def _lanes_state(y0: np.ndarray, n_variants: int) -> np.ndarray:
    """States ``(n_variants, 2 n)`` as kernel lanes ``(2 n, WIDTH)`` (padded with row 0)."""
    y = np.empty((y0.shape[1], WIDTH))
    y[:, :n_variants] = y0.T
    y[:, n_variants:] = y0[:1].T
    return y


def integrate_batch(
    systems: list, y0: np.ndarray, dt: float, n_steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`gearvib.kernels.integrate` of several variants of one topology, batched.

    The variants go through :func:`integrate_chunk_batch` :data:`WIDTH` at a time; each
    variant's results are bit-identical to its single run's.

    Parameters
    ----------
    systems : list of KernelSystem
        The variants (:func:`pack_batch`).
    y0 : ndarray, shape (n_variants, 2 n)
        Initial states.
    dt, n_steps
        As in :func:`gearvib.kernels.integrate`.

    Returns
    -------
    record : ndarray, shape (n_variants, n_steps + 1, 2 n + 3 n_mesh)
        Samples per variant (the rows after a failed variant's failed step are unspecified,
        as the single run leaves them).
    contact_changes : ndarray of int64, shape (n_variants, n_mesh)
    status : ndarray of int64, shape (n_variants, 2)
        ``(STATUS_*, step)`` per variant.
    y : ndarray, shape (n_variants, 2 n)
        States after the last step (of a failed variant: at its failed step).
    """
    if not systems:
        raise ValueError("integrate_batch needs at least one system")
    n = systems[0].n_dof
    nm = systems[0].n_mesh
    y0 = np.asarray(y0, dtype=np.float64)
    if y0.shape != (len(systems), 2 * n):
        raise ValueError(f"y0 must have shape ({len(systems)}, {2 * n}), got {y0.shape}")
    record = np.empty((len(systems), n_steps + 1, n_signals(n, nm)))
    changes = np.zeros((len(systems), nm), dtype=np.int64)
    status = np.zeros((len(systems), 2), dtype=np.int64)
    y_end = np.empty_like(y0)
    for first in range(0, len(systems), WIDTH):
        group = systems[first : first + WIDTH]
        k = len(group)
        batch = pack_batch(group)
        y = _lanes_state(y0[first : first + k], k)
        rec = np.empty((WIDTH, n_steps + 1, n_signals(n, nm)))
        fs = np.full((WIDTH, nm), -1, dtype=np.int64)
        ch = np.zeros((WIDTH, nm), dtype=np.int64)
        st = np.zeros((WIDTH, 2), dtype=np.int64)
        integrate_chunk_batch(y, 0, n_steps + 1, float(dt), batch.astuple(), rec, 0, fs, ch,
                              n_steps, batch_work(n, nm), st)
        record[first : first + k] = rec[:k]
        changes[first : first + k] = ch[:k]
        status[first : first + k] = st[:k]
        y_end[first : first + k] = y[:, :k].T
    return record, changes, status, y_end


@njit(cache=True)
def evaluate_lanes(t, y, batch):
    ints, vals, uniform, rows, tables, speed_tab, torque_tab = batch
    dy = np.empty_like(y)
    mo = np.empty((ints[H_NMESH], BATCH_MESH_COLUMNS, WIDTH))
    forces = np.empty((2 * ints[H_NMESH], WIDTH))
    scr = np.zeros((_N_SCR, WIDTH))
    for b in range(WIDTH):
        scr[_R_T, b] = t[b]
    _rhs8(y, dy, mo, scr, ints, vals, uniform, rows, forces, tables, speed_tab, torque_tab)
    return dy, mo


def evaluate_rhs_batch(t: np.ndarray, y: np.ndarray, batch: BatchSystem,
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Right-hand sides of the lanes at times ``t`` (shape (WIDTH,)) and states ``y`` (shape
    (2 n, WIDTH)); returns ``dy`` and the mesh quantities (shape (n_mesh, 7, WIDTH)). For
    tests and cross-checks against :func:`gearvib.kernels.evaluate_rhs` (allocating)."""
    t = np.ascontiguousarray(np.broadcast_to(np.asarray(t, dtype=np.float64), (WIDTH,)))
    y = np.ascontiguousarray(y, dtype=np.float64)
    if y.shape != (2 * batch.n_dof, WIDTH):
        raise ValueError(f"y must have shape ({2 * batch.n_dof}, {WIDTH}), got {y.shape}")
    return kernels_for(batch.astuple()).evaluate(t, y, batch.astuple())


@njit(cache=True)
def rhs_loop_lanes(states, t0, dt, n_eval, batch, dy, mesh_out):
    """``n_eval`` batched right-hand sides at ``states[r]`` (shape (rows, 2 n, WIDTH),
    cycled), every lane at time ``t0 + r dt``: the batched counterpart of
    :func:`gearvib.kernels.rhs_loop` for benchmarks; returns a check value."""
    ints, vals, uniform, rows, tables, speed_tab, torque_tab = batch
    scr = np.zeros((_N_SCR, WIDTH))
    forces = np.empty((2 * ints[H_NMESH], WIDTH))
    check = 0.0
    r = 0
    n2 = states.shape[1]
    for _ in range(n_eval):
        for b in range(WIDTH):
            scr[_R_T, b] = t0 + r * dt
        _rhs8(states[r], dy, mesh_out, scr, ints, vals, uniform, rows, forces, tables,
              speed_tab,
              torque_tab)
        check += dy[n2 - 1, 0]
        r += 1
        if r == states.shape[0]:
            r = 0
    return check


# --- kernels specialised to a topology ----------------------------------------------------

#: Environment variable: ``generic`` runs every batch through the generic kernel (for
#: comparisons); anything else (default) specialises the kernel to each batch's topology.
KERNEL_ENV = "GEARVIB_BATCH_KERNEL"


class KernelSet(NamedTuple):
    """The compiled batched kernels of one topology (or the generic ones)."""

    integrate: Callable
    """:func:`integrate_lanes` (arguments of :func:`integrate_chunk_batch`)."""
    rhs_loop: Callable
    """:func:`rhs_loop_lanes`."""
    evaluate: Callable
    """:func:`evaluate_lanes`."""
    source: Path | None
    """The generated module, or None for the generic kernels."""


GENERIC = KernelSet(integrate_lanes, rhs_loop_lanes, evaluate_lanes, None)
"""The generic kernels (any topology; sparse loops)."""

#: Functions a specialised module compiles again with its own right-hand side, from their
#: source here (in this order: each calls only names defined before it or in this module).
_SPECIALISED_COPIES = (_rk4_step8, integrate_lanes, rhs_loop_lanes, evaluate_lanes)
_KERNELS: dict[bytes, KernelSet] = {}


def kernel_namespace() -> dict:
    """The names of this module, for a generated module (:func:`specialised_source`)."""
    return {k: v for k, v in globals().items() if not k.startswith("__")}


def decode_rows(rows: np.ndarray, n: int) -> RowTerms:
    """:func:`row_terms` as lists (the input of :func:`gearvib.batch_codegen.rhs_source`)."""
    head = np.asarray(rows[: (n + 1) * _ROW_FIELDS]).reshape(n + 1, _ROW_FIELDS)
    forces = [[(int(e) >> 32, int(e) & 0xFFFFFFFF)
               for e in rows[head[i, _ROW_FIRST]: head[i + 1, _ROW_FIRST]]] for i in range(n)]
    return RowTerms([int(x) for x in head[:n, _ROW_INPUT]],
                    [int(x) for x in head[:n, _ROW_OUTPUT]], forces)


def specialised_source(batch: tuple) -> str:
    """Python source of a module with the batched kernels of ``batch``'s topology.

    Its right-hand side is :func:`gearvib.batch_codegen.rhs_source` of the batch's packed
    integers and operator modes; :func:`integrate_lanes`, :func:`rhs_loop_lanes`,
    :func:`evaluate_lanes` and the RK4 step are this module's source, compiled there with
    that right-hand side. The header records the SHA-256 of the files whose code it embeds.
    """
    ints, uniform, rows = batch[0], batch[2], batch[3]
    modes = {name: int(uniform[k]) for k, name in enumerate(_UNIFORM_NAMES)}
    rhs = rhs_source(ints, modes, decode_rows(rows, int(ints[H_N])))
    copies = "\n\n".join(inspect.getsource(f.py_func) for f in _SPECIALISED_COPIES)
    return (f'"""Batched kernels of one gear-set topology, generated by gearvib.kernels_batch '
            f'(do not edit).\n\nsha256 of {", ".join(SPECIALISED_DEPENDENCIES)}: '
            f'{dependency_digest(SPECIALISED_DEPENDENCIES)}\n"""\n\n'
            "from gearvib.kernels_batch import kernel_namespace\n\n"
            "globals().update(kernel_namespace())\n\n\n"
            f"{rhs}\n\n{copies}")


def specialised_folder() -> Path:
    """Where generated modules are written: ``specialised`` in numba's cache folder of this
    module (next to it, under ``NUMBA_CACHE_DIR`` or in the user's cache, whichever numba
    and :func:`analysis.jit.prepare_cache` chose as writable)."""
    return Path(integrate_lanes._cache._cache_path) / "specialised"


def require_private(folder: Path) -> None:
    """Refuse a folder of generated modules that another user could write to (the folder or
    its parent not private, :func:`analysis.jit.private_folder`): its modules are executed.
    The folder is made with mode 0700 where missing.

    Raises
    ------
    PermissionError
        Naming the folder; the callers then run the generic kernels with a warning.
    """
    for f in (folder.parent, folder):
        if not private_folder(f):
            raise PermissionError(f"folder {f} is not private to this user (owned by another "
                                  "user, a symbolic link, or writable by others): generated "
                                  "modules are not written or loaded there")


def write_once(path: Path, text: str) -> None:
    """Create ``path`` with ``text`` atomically unless it holds ``text`` already.

    The text goes to a temporary file first, which is then hard-linked to ``path`` (fails
    when another process was first: its file is complete and kept) or, where hard links are
    not available, renamed over it. A file with other content (a torn write of an older
    version) is replaced. Sweep workers that generate the same module concurrently thus
    never see a partial file, and an existing file keeps its modification time (numba's
    cache index of it stays valid). The folder must be private (:func:`require_private`).
    """
    require_private(path.parent)
    with contextlib.suppress(OSError):
        if path.read_text() == text:
            return
    tmp = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
    tmp.write_text(text)
    try:
        try:
            os.link(tmp, path)
        except FileExistsError:
            if path.read_text() != text:
                os.replace(tmp, path)
        except OSError:  # no hard links here
            os.replace(tmp, path)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _load_specialised(batch: tuple) -> KernelSet:
    try:
        text = specialised_source(batch)
        digest = hashlib.sha256(text.encode()).hexdigest()[:32]
        path = specialised_folder() / f"batch_{digest}.py"
        write_once(path, text)
        name = f"gearvib_batch_{digest}"
        spec = importlib.util.spec_from_file_location(name, path)
        if spec is None or spec.loader is None:
            raise ImportError(f"no module spec for {path}")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    except (OSError, ImportError, AttributeError) as exc:  # unwritable, no sources: generic
        warnings.warn(f"gearvib: the batched kernel runs generic (no module specialised to "
                      f"the topology: {exc})", RuntimeWarning, stacklevel=3)
        return GENERIC
    sys.modules[name] = module
    return KernelSet(module.integrate_lanes, module.rhs_loop_lanes, module.evaluate_lanes,
                     path)


def kernels_for(batch: tuple) -> KernelSet:
    """The kernels for a packed batch (:meth:`BatchSystem.astuple`): specialised to its
    topology and operator modes (generated, written and compiled once, then loaded from
    numba's cache; one module per topology and process), or :data:`GENERIC` when
    :data:`KERNEL_ENV` is ``generic`` or no module can be written."""
    if os.environ.get(KERNEL_ENV, "").strip().lower() == "generic":
        return GENERIC
    key = batch[0].tobytes() + batch[2].tobytes()
    kernels = _KERNELS.get(key)
    if kernels is None:
        kernels = _KERNELS[key] = _load_specialised(batch)
    return kernels


def integrate_chunk_batch(
    y: np.ndarray,
    first_step: int,
    n_steps: int,
    dt: float,
    batch: tuple,
    record: np.ndarray,
    record_offset: int,
    flank_state: np.ndarray,
    contact_changes: np.ndarray,
    count_until: int,
    work: tuple,
    status: np.ndarray,
) -> None:
    """:func:`gearvib.kernels.integrate_chunk` of the :data:`WIDTH` lanes of a batch, in the
    kernel specialised to its topology (:func:`kernels_for`; arguments of
    :func:`integrate_lanes`)."""
    kernels_for(batch).integrate(y, first_step, n_steps, dt, batch, record, record_offset,
                                 flank_state, contact_changes, count_until, work, status)


def rhs_loop_batch(states: np.ndarray, t0: float, dt: float, n_eval: int, batch: tuple,
                   dy: np.ndarray, mesh_out: np.ndarray) -> float:
    """``n_eval`` batched right-hand sides at ``states[r]`` (shape (rows, 2 n, WIDTH),
    cycled), every lane at time ``t0 + r dt``: the batched counterpart of
    :func:`gearvib.kernels.rhs_loop` for benchmarks, in the kernel of :func:`kernels_for`;
    returns a check value."""
    return kernels_for(batch).rhs_loop(states, t0, dt, n_eval, batch, dy, mesh_out)


DEPENDENCIES = ("kernels.py", "lanes.py")
"""Files (next to this module) whose code the compiled functions of this module embed."""
SPECIALISED_DEPENDENCIES = ("kernels.py", "lanes.py", "kernels_batch.py", "batch_codegen.py")
"""Files whose code a specialised module embeds (its name hashes its text, which records
their SHA-256)."""


def dependency_digest(names: tuple[str, ...] = DEPENDENCIES) -> str:
    """SHA-256 of the files ``names`` next to this module (their bytes, in order)."""
    h = hashlib.sha256()
    here = Path(__file__).resolve().parent
    for name in names:
        h.update(name.encode())
        h.update((here / name).read_bytes())
    return h.hexdigest()


def clear_stale_cache(cache_dir: str | os.PathLike, stem: str, digest: str) -> bool:
    """Remove the cached functions of module ``stem`` in ``cache_dir`` unless they were
    compiled from dependencies with SHA-256 ``digest``; then record ``digest``.

    numba keys its cache entries (``<stem>.<function>-<line>.pyXY.nbi`` and ``.nbc``) on the
    defining file alone; the record ``<stem>.deps-sha256`` ties them to the files they embed.

    Returns
    -------
    bool
        True if the entries were removed (record missing or different).
    """
    folder = Path(cache_dir)
    marker = folder / f"{stem}.deps-sha256"
    try:
        if marker.read_text().strip() == digest:
            return False
    except OSError:
        pass
    for p in [*folder.glob(f"{stem}.*.nbi"), *folder.glob(f"{stem}.*.nbc")]:
        with contextlib.suppress(OSError):
            p.unlink()
    with contextlib.suppress(OSError):  # written atomically; an unwritable folder has no cache
        tmp = folder / f".{marker.name}.{os.getpid()}.tmp"
        tmp.write_text(digest + "\n")
        os.replace(tmp, marker)
    return True


def _check_cache() -> None:
    # numba's cache folder of this module (next to it, NUMBA_CACHE_DIR or the user cache):
    # numba's FunctionCache knows it; it loads entries only at the first call, after this
    try:
        folder = integrate_lanes._cache._cache_path
    except AttributeError:  # pragma: no cover - another numba layout: no check
        return
    if clear_stale_cache(folder, Path(__file__).stem, dependency_digest()):
        # modules generated from other sources (never loaded again: their names hash them)
        shutil.rmtree(Path(folder) / "specialised", ignore_errors=True)


_check_cache()
