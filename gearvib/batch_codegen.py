"""Source code of a batched right-hand side specialised to one topology.

The generic batched right-hand side (:func:`gearvib.kernels_batch._rhs8`) walks the sparse
operators of the packed system: for every term an index load, an address computation and a
loop test, and for every row a load of its bounds. Within one topology these are constants
(the union sparsity pattern every lane of a batch shares, and whether each operator holds
one value in every lane, per lane values or stored zeros). :func:`rhs_source` writes the
right-hand side of one such topology as straight-line Python source: every product term
with its float-block row as an integer constant, every state vector loaded once, the flank
forces kept as local values instead of going through memory. numba compiles it like any
other kernel (:mod:`gearvib.kernels_batch` writes, caches and loads the generated module).

Bit for bit: every sum is written term by term in the order of the generic kernel, which is
the single kernel's order (a term of a zero-masked operator with the same masked operation,
``lanes_madd_nz``), and the mesh law, drive and load are the generic kernel's inline helpers,
so every lane performs the same floating-point operations as its single run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gearvib.kernels import (
    H_ACC0,
    H_CI,
    H_CP,
    H_CV,
    H_GI,
    H_GP,
    H_GV,
    H_IPAR,
    H_LI,
    H_LP,
    H_LV,
    H_MLAW,
    H_N,
    H_NMESH,
    H_PI,
    H_PP,
    H_PV,
    H_RFLAG,
    H_RVI,
    H_RVP,
    H_RVV,
    H_S0,
    H_VI,
    H_VP,
    H_VV,
    IP_CARRIER,
    IP_GYRO,
)

__all__ = ["RowTerms", "rhs_source"]

#: Lanes per vector (:data:`gearvib.lanes.WIDTH`); the flat index of lane 0 of row ``r`` of
#: a lane array is ``r * LANES``.
LANES = 8


@dataclass(frozen=True)
class RowTerms:
    """What the batched right-hand side adds to each acceleration row after its stiffness,
    damping and gyroscopic sums (:func:`gearvib.kernels_batch.row_terms`, decoded).

    Attributes
    ----------
    inputs, outputs : list of int
        Per row the float-block row of its input-torque and load coefficient (-1: none).
    forces : list of list of (int, int)
        Per row the mesh terms in order: force slot (``2 m`` left or summed force of mesh
        ``m``, ``2 m + 1`` its right-flank force) and the float-block row of the coefficient.
    """

    inputs: list[int]
    outputs: list[int]
    forces: list[list[tuple[int, int]]]


class _Lines:
    """Lines of a function body and fresh local names."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.count = 0

    def __call__(self, line: str) -> None:
        self.lines.append("    " + line)

    def name(self, stem: str) -> str:
        self.count += 1
        return f"{stem}{self.count}"


def _coefficient(mode: int, row: int) -> str:
    """The lanes of float-block row ``row``: one value broadcast (mode 2) or eight."""
    fn = "lanes_bcast" if mode == 2 else "lanes_load"
    return f"{fn}(vals, {row * LANES})"


def _terms(body: _Lines, acc: str, ints: np.ndarray, p0: int, p1: int, col: int, val: int,
           offset: int, mode: int) -> str:
    """``acc + sum_p vals[val + p] * y[offset + ints[col + p]]`` term by term (as
    :func:`gearvib.kernels_batch._dot`); returns the local name of the sum."""
    for p in range(p0, p1):
        y = f"y{offset + int(ints[col + p])}"
        new = body.name("a")
        if mode == 0:  # stored zeros: masked out of the lanes that have no such entry
            body(f"{new} = lanes_madd_nz({acc}, lanes_load(vals, {(val + p) * LANES}), {y})")
        else:
            body(f"{new} = lanes_madd({acc}, {_coefficient(mode, val + p)}, {y})")
        acc = new
    return acc


def rhs_source(ints: np.ndarray, modes: dict[str, int], rows: RowTerms,
               name: str = "_rhs8") -> str:
    """Python source of the batched right-hand side of one topology.

    The function has the generic kernel's signature, ``name(y, dy, mo, scr, ints, vals,
    uniform, rows, forces, tables, speed_tab, torque_tab)`` (``forces`` unused); it expects
    the names of :mod:`gearvib.kernels_batch` (lane operations, ``_mesh8``,
    ``_mesh8_viscous``, ``_torque8``, ``_load8``, ``_U``, ``njit``) in its module.

    Parameters
    ----------
    ints : ndarray of int64
        The packed integer array of the batch (sizes, drive, sparsity patterns).
    modes : dict of str to int
        Per float block of a sparse operator (``"lv", "cv", "gv", "vv", "fv", "pv", "rvv",
        "rfv"``) its mode: 2 one value in every lane, 1 a value per lane, 0 stored zeros
        (:attr:`gearvib.kernels_batch.BatchSystem.uniform`).
    rows : RowTerms
        The terms of each acceleration row after its operator sums.
    name : str
        Name of the function.
    """
    ints = np.asarray(ints, dtype=np.int64)
    n = int(ints[H_N])
    n_mesh = int(ints[H_NMESH])
    body = _Lines()
    body("zero = lanes_splat(0.0)")
    for j in range(2 * n):
        body(f"y{j} = lanes_load(y, {j * LANES})")
    vp, vi, vv = (int(ints[h]) for h in (H_VP, H_VI, H_VV))
    pp, pi, pv = (int(ints[h]) for h in (H_PP, H_PI, H_PV))
    rvp, rvi, rvv = (int(ints[h]) for h in (H_RVP, H_RVI, H_RVV))
    s0, rflag, mlaw = int(ints[H_S0]), int(ints[H_RFLAG]), int(ints[H_MLAW])
    force = {}
    for m in range(n_mesh):
        p0, p1 = int(ints[vp + m]), int(ints[vp + m + 1])
        d = _terms(body, "zero", ints, p0, p1, vi, vv, 0, modes["vv"])
        dd = _terms(body, "zero", ints, p0, p1, vi, vv, n, modes["vv"])
        two_lines = int(ints[rflag + m]) != 0
        dr, ddr = d, dd
        if two_lines:  # the back flank's own line of action
            q0, q1 = int(ints[rvp + m]), int(ints[rvp + m + 1])
            dr = _terms(body, "zero", ints, q0, q1, rvi, rvv, 0, modes["rvv"])
            ddr = _terms(body, "zero", ints, q0, q1, rvi, rvv, n, modes["rvv"])
        body(f"s_{m} = lanes_load(vals, {(s0 + m) * LANES})")
        s = _terms(body, f"s_{m}", ints, int(ints[pp + m]), int(ints[pp + m + 1]), pi, pv, 0,
                   modes["pv"])
        law = "_mesh8_viscous" if int(ints[mlaw + m]) != 0 else "_mesh8"  # damping law
        body(f"fl{m}, fr{m} = {law}(_U({m}), {d}, {dd}, {dr}, {ddr}, {s}, mo, vals, ints, "
             "tables)")
        if two_lines:
            force[2 * m] = f"fl{m}"
        else:  # one line of action: the summed force
            body(f"fs{m} = fl{m} + fr{m}")
            force[2 * m] = f"fs{m}"
        force[2 * m + 1] = f"fr{m}"
    body("torque = _torque8(y, scr, ints, vals, speed_tab, torque_tab)")
    body("load = _load8(y, ints, vals)")
    lp, li, lv, a0 = (int(ints[h]) for h in (H_LP, H_LI, H_LV, H_ACC0))
    cp, ci, cv = (int(ints[h]) for h in (H_CP, H_CI, H_CV))
    gp, gi, gv = (int(ints[h]) for h in (H_GP, H_GI, H_GV))
    carrier = int(ints[H_IPAR + IP_CARRIER])
    gyro = int(ints[H_IPAR + IP_GYRO]) != 0 and carrier >= 0
    if gyro:
        body(f"om = y{n + carrier}")
        body("om2 = om * om")
    shared_forces = modes["fv"] == 2 and modes["rfv"] == 2
    for i in range(n):
        body(f"lanes_store(dy, {i * LANES}, y{n + i})")
        body(f"r{i} = lanes_load(vals, {(a0 + i) * LANES})")
        acc = _terms(body, f"r{i}", ints, int(ints[lp + i]), int(ints[lp + i + 1]), li, lv, 0,
                     modes["lv"])
        if gyro:
            ac = _terms(body, "zero", ints, int(ints[cp + i]), int(ints[cp + i + 1]), ci, cv,
                        0, modes["cv"])
            ag = _terms(body, "zero", ints, int(ints[gp + i]), int(ints[gp + i + 1]), gi, gv,
                        n, modes["gv"])
            new = body.name("a")
            body(f"{new} = {acc} + (om2 * {ac} + om * {ag})")
            acc = new
        if rows.inputs[i] >= 0:
            new = body.name("a")
            body(f"{new} = lanes_madd_nz2({acc}, lanes_load(vals, {rows.inputs[i] * LANES}), "
                 "torque)")
            acc = new
        if rows.outputs[i] >= 0:
            new = body.name("a")
            body(f"{new} = lanes_madd_nz({acc}, lanes_load(vals, {rows.outputs[i] * LANES}), "
                 "load)")
            acc = new
        for slot, row in rows.forces[i]:
            new = body.name("a")
            body(f"{new} = lanes_msub_nz({acc}, {force[slot]}, "
                 f"{_coefficient(2 if shared_forces else 1, row)})")
            acc = new
        body(f"lanes_store(dy, {(n + i) * LANES}, {acc})")
    head = [
        "@njit(cache=True, _nrt=False)",
        f"def {name}(y, dy, mo, scr, ints, vals, uniform, rows, forces, tables, speed_tab,",
        "        torque_tab):",
        f'    """Batched right-hand side of one topology ({n} coordinates, {n_mesh} meshes),',
        '    generated by gearvib.batch_codegen."""',
    ]
    return "\n".join(head + body.lines) + "\n"
