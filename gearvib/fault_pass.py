"""The faulty-mesh pass of one fault configuration, written as straight-line code and compiled.

The generic pass of the kernel (:func:`gearvib.kernels._faulty_meshes`) walks the packed
system for every faulty mesh at every right-hand side: the mesh's sparse deflection,
position and force vectors (a bound load, an index load and a loop test per term), its fault
record (law, mesh-wide deviations, eccentricity terms) and a dispatch on the law. Within one
system all of these are constants. :func:`pass_source` writes the pass of a packed system as
straight-line Python source: every product term with its state index and its float-block row
as integer constants, the law of each mesh chosen when the source is written, the
eccentricity terms unrolled. Values (vector entries, backlash, damping, fault amplitudes) are
still read from the float block, so a configuration that differs only in values (another
amplitude, severity or tooth) shares the source and its compiled code.

The source compiles to a C-callable function (``numba.cfunc``) of six data pointers, which the
generic kernel calls through :data:`gearvib.kernels.H_FPASS` (an indirect call; a compiled
numba function would take every array as a struct, about 15 ns a call) with the lengths of
the integer block, the float block and the tables (:data:`gearvib.kernels.PASS_SIGNATURE`,
the signature of the generic pass :func:`gearvib.kernels.generic_pass` too). It is compiled once
per source (about a second) and then loaded from numba's cache next to the generated module
(:func:`gearvib.kernels_batch.specialised_folder`, written atomically by
:func:`gearvib.kernels_batch.write_once`; one module per source and process).

Bit for bit: every sum is written term by term in the order of the generic pass, and the laws
are the generic pass's helpers (:func:`gearvib.kernels.interp_cell`,
:func:`~gearvib.kernels.cos_sin`, :func:`~gearvib.kernels.mean_offset`,
:func:`~gearvib.kernels.faulty_flanks`, :func:`~gearvib.kernels.stiffness_flanks`,
:func:`~gearvib.kernels.flank_forces_two_lines`,
:func:`~gearvib.kernels.flank_forces_viscous`; the mesh-damping law of each mesh chosen when
the source is written), so a run gives the same record with either pass (tested for every
law). ``GEARVIB_FAULT_PASS=generic`` in the environment keeps the generic pass (comparisons,
benchmarks).
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numba.core.errors import NumbaError

import gearvib.kernels as kn
from gearvib.faults.law import LAW_MEAN_OFFSET, LAW_PAIRS, LAW_SHIFTED, LAW_STIFFNESS

__all__ = [
    "DEPENDENCIES",
    "PASS_ENV",
    "dependency_digest",
    "pass_address",
    "pass_source",
    "specialised_folder",
    "with_fault_pass",
]

#: Environment variable: ``generic`` keeps the generic faulty-mesh pass.
PASS_ENV = "GEARVIB_FAULT_PASS"
#: Files (next to this module) whose code a generated pass embeds: its text records their
#: SHA-256, so its name changes with them.
DEPENDENCIES = ("kernels.py", "fault_pass.py", "faults/law.py")

# compiled passes of this process, by source digest (the functions stay referenced: their
# addresses are valid for the life of the process)
_PASSES: dict[str, Any] = {}


def specialised_folder() -> Path:
    """Where the generated passes are written: numba's folder of generated modules
    (:func:`gearvib.kernels_batch.specialised_folder`, imported on use: a healthy run does
    not load the batched kernels)."""
    from gearvib.kernels_batch import specialised_folder as folder

    return folder()


@functools.cache
def dependency_digest() -> str:
    """SHA-256 of the files :data:`DEPENDENCIES` (their bytes, in order, as
    :func:`gearvib.kernels_batch.dependency_digest`; read once per process, as their code
    is)."""
    from gearvib.kernels_batch import dependency_digest as digest

    return digest(DEPENDENCIES)


class _Lines:
    """Indented source lines."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def add(self, depth: int, text: str) -> None:
        self.lines.append("    " * depth + text)


def _range(ints: np.ndarray, ptr: int, m: int) -> range:
    return range(int(ints[ptr + m]), int(ints[ptr + m + 1]))


def _dot(out: _Lines, depth: int, name: str, ints: np.ndarray, ptr: int, idx: int, val: int,
         m: int, shift: int, start: str = "0.0") -> None:
    """``name = start + sum vals[val + p] * y[shift + ints[idx + p]]``, term by term."""
    out.add(depth, f"{name} = {start}")
    for p in _range(ints, ptr, m):
        out.add(depth, f"{name} += vals[{val + p}] * y[{shift + int(ints[idx + p])}]")


def _forces(out: _Lines, depth: int, name: str, ints: np.ndarray, ptr: int, idx: int,
            val: int, m: int, n: int) -> None:
    """``dy[n + ints[idx + p]] -= name * vals[val + p]`` for the terms of mesh ``m``, when
    ``name`` is not zero."""
    terms = _range(ints, ptr, m)
    if not terms:
        return
    out.add(depth, f"if {name} != 0.0:")
    for p in terms:
        out.add(depth + 1, f"dy[{n + int(ints[idx + p])}] -= {name} * vals[{val + p}]")


def _mesh(out: _Lines, ints: np.ndarray, h: dict[str, int], m: int) -> None:
    """The pass of faulty mesh ``m``: :func:`gearvib.kernels._faulty_meshes` with its
    record's branches taken and its loops unrolled (``h``: the header entries by name)."""
    n = h["n"]
    r = h["fint"] + int(ints[h["frec"] + m])
    two_lines = int(ints[h["rflag"] + m]) != 0
    out.add(1, f"if mesh_out[{m}, 7] != 0.0:")
    _dot(out, 2, "d", ints, h["vp"], h["vi"], h["vv"], m, 0)
    _dot(out, 2, "dd", ints, h["vp"], h["vi"], h["vv"], m, n)
    if two_lines:
        _dot(out, 2, "dr", ints, h["rvp"], h["rvi"], h["rvv"], m, 0)
        _dot(out, 2, "ddr", ints, h["rvp"], h["rvi"], h["rvv"], m, n)
    else:
        out.add(2, "dr = d")
        out.add(2, "ddr = dd")
    _dot(out, 2, "s", ints, h["pp"], h["pi"], h["pv"], m, 0, start=f"vals[{h['s0'] + m}]")
    out.add(2, f"half = 0.5 * vals[{h['bl'] + m}]")
    if int(ints[r + kn.F_MESHWIDE]) != 0:  # kernels._deviation_offsets
        cv = h["fval"] + int(ints[r + kn.F_CONSTV])
        out.add(2, f"el = vals[{cv}]")
        out.add(2, f"er = vals[{cv + 1}]")
        out.add(2, "edl = 0.0")
        out.add(2, "edr = 0.0")
        ei = h["fint"] + int(ints[r + kn.F_ECCI])
        ev = h["fval"] + int(ints[r + kn.F_ECCV])
        for e in range(int(ints[r + kn.F_NECC])):
            dg, dc = int(ints[ei + 2 * e]), int(ints[ei + 2 * e + 1])
            out.add(2, "ang = 0.0")
            out.add(2, "rate = 0.0")
            if dg >= 0:
                out.add(2, f"ang += y[{dg}]")
                out.add(2, f"rate += y[{n + dg}]")
            if dc >= 0:
                out.add(2, f"ang -= y[{dc}]")
                out.add(2, f"rate -= y[{n + dc}]")
            out.add(2, f"ca, sa = cos_sin(ang, mesh_out, U({m}), {e})")
            b = ev + 6 * e
            out.add(2, f"el += vals[{b}] * (ca * vals[{b + 1}] - sa * vals[{b + 2}])")
            out.add(2, f"er += vals[{b + 3}] * (ca * vals[{b + 4}] - sa * vals[{b + 5}])")
            out.add(2, f"edl -= vals[{b}] * (sa * vals[{b + 1}] + ca * vals[{b + 2}]) * rate")
            out.add(2, f"edr -= vals[{b + 3}] * (sa * vals[{b + 4}] + ca * vals[{b + 5}]) * rate")
    else:
        out.add(2, "el = 0.0")
        out.add(2, "er = 0.0")
        out.add(2, "edl = 0.0")
        out.add(2, "edr = 0.0")
    law = int(ints[r + kn.F_LAW])
    mc = f"vals[{h['mc'] + m}]"
    viscous = int(ints[h["mlaw"] + m]) != 0  # the mesh-damping law (kernels.DAMPING_*)
    pair_law = (f"faulty_flanks(ints, vals, tables, U({m}), U({r}), s, d, dd, dr, ddr, el, er, "
                f"edl, edr, half, {mc}, mesh_out, {viscous})")
    if law == LAW_STIFFNESS:
        out.add(2, f"fl, fr, ke, st = stiffness_flanks(ints, vals, tables, U({m}), U({r}), s, "
                   f"d + el, dd + edl, dr + er, ddr + edr, half, {mc}, mesh_out, {viscous})")
    elif law == LAW_PAIRS:
        out.add(2, f"fl, fr, ke, st = {pair_law}")
    elif law in (LAW_SHIFTED, LAW_MEAN_OFFSET):
        out.add(2, "i0, i1, w = interp_cell(n_table, s)")
        out.add(2, f"kl = (1.0 - w) * tables[0, {m}, i0] + w * tables[0, {m}, i1]")
        out.add(2, f"kr = (1.0 - w) * tables[1, {m}, i0] + w * tables[1, {m}, i1]")
        flanks = "flank_forces_viscous" if viscous else "flank_forces_two_lines"
        shifted = (f"{flanks}(d + el, dd + edl, dr + er, ddr + edr, kl, kr, 2.0 * half, "
                   f"{mc})")
        if law == LAW_SHIFTED:
            out.add(2, f"fl, fr, ke, st = {shifted}")
        else:
            out.add(2, f"mean, holds = mean_offset(ints, vals, U({r}), s, i0, d, dr, el, er, "
                       f"kl, kr, half, mesh_out, U({m}))")
            out.add(2, "if holds:")
            out.add(3, "el += mean")
            out.add(3, "er += mean")
            out.add(3, f"fl, fr, ke, st = {shifted}")
            out.add(2, "else:")
            out.add(3, f"fl, fr, ke, st = {pair_law}")
    else:  # pragma: no cover - a law this module does not know: written by faults.law
        raise ValueError(f"fault law {law} of mesh {m} is not known to gearvib.fault_pass")
    # kernels._add_mesh_forces
    if two_lines:
        _forces(out, 2, "fl", ints, h["fp"], h["fi"], h["fv"], m, n)
        _forces(out, 2, "fr", ints, h["rfp"], h["rfi"], h["rfv"], m, n)
    else:
        out.add(2, "f = fl + fr")
        _forces(out, 2, "f", ints, h["fp"], h["fi"], h["fv"], m, n)
    for col, value in enumerate(("fl", "-fr", "ke", "st", "d", "s", "dr")):
        out.add(2, f"mesh_out[{m}, {col}] = {value}")


def pass_source(ints: np.ndarray, tables: np.ndarray) -> str:
    """Python source of a module whose ``fault_pass`` is the faulty-mesh pass of a packed
    system with integer block ``ints`` and stiffness ``tables`` (:func:`gearvib.kernels.pack`;
    module docstring). The float block's values are not part of it (read at run time).

    Raises
    ------
    ValueError
        The system has no faulty mesh.
    """
    ints = np.asarray(ints)
    h = {name: int(ints[getattr(kn, f"H_{name.upper()}")]) for name in (
        "n", "nmesh", "vp", "vi", "vv", "fp", "fi", "fv", "pp", "pi", "pv", "s0", "bl", "mc",
        "rflag", "rvp", "rvi", "rvv", "rfp", "rfi", "rfv", "frec", "fint", "fval", "mlaw")}
    n, n_mesh = h["n"], h["nmesh"]
    faulty = [m for m in range(n_mesh) if int(ints[h["frec"] + m]) >= 0]
    if not faulty:
        raise ValueError("the system has no faulty mesh: nothing to specialise")
    body = _Lines()
    for m in faulty:
        _mesh(body, ints, h, m)
    shape = tuple(int(k) for k in tables.shape)
    return (
        f'"""Faulty-mesh pass of one fault configuration, generated by gearvib.fault_pass '
        f'(do not edit).\n\nsha256 of {", ".join(DEPENDENCIES)}: {dependency_digest()}\n"""\n\n'
        "import numpy as np\n"
        "from numba import carray, cfunc, types\n\n"
        "from gearvib.kernels import (cos_sin, faulty_flanks, flank_forces_two_lines,\n"
        "                             flank_forces_viscous, interp_cell, mean_offset,\n"
        "                             stiffness_flanks)\n\n"
        "U = np.uint64\n"
        "F = types.CPointer(types.float64)\n"
        "I = types.CPointer(types.int64)\n\n\n"
        "@cfunc(types.void(F, F, F, I, F, F, types.intp, types.intp, types.intp), cache=True)\n"
        "def fault_pass(yp, dyp, mp, ip, vp, tp, n_ints, n_vals, n_tab):\n"
        f"    y = carray(yp, ({2 * n},))\n"
        f"    dy = carray(dyp, ({2 * n},))\n"
        f"    mesh_out = carray(mp, ({n_mesh}, {kn.MESH_OUT_COLUMNS}))\n"
        "    ints = carray(ip, (n_ints,))\n"
        "    vals = carray(vp, (n_vals,))\n"
        f"    tables = carray(tp, {shape!r})\n"
        f"    n_table = {shape[2]}\n"
        + "\n".join(body.lines) + "\n")


def pass_address(ints: np.ndarray, tables: np.ndarray) -> int:
    """Address of the compiled faulty-mesh pass of a packed system (generated, written and
    compiled once, then loaded from numba's cache), or 0 (the generic pass) when the system
    has no faulty mesh, :data:`PASS_ENV` is ``generic``, or no module can be written or
    compiled (with a warning; the run's results are the same)."""
    if os.environ.get(PASS_ENV, "").strip().lower() == "generic":
        return 0
    frec = int(ints[kn.H_FREC])
    if not np.any(ints[frec: frec + int(ints[kn.H_NMESH])] >= 0):
        return 0
    try:
        text = pass_source(ints, tables)
        digest = hashlib.sha256(text.encode()).hexdigest()[:32]
        func = _PASSES.get(digest)
        if func is None:
            from gearvib.kernels_batch import write_once

            path = specialised_folder() / f"fault_pass_{digest}.py"
            write_once(path, text)
            name = f"gearvib_fault_pass_{digest}"
            spec = importlib.util.spec_from_file_location(name, path)
            if spec is None or spec.loader is None:
                raise ImportError(f"no module spec for {path}")
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module  # before: the cfunc compiles (or loads) on import
            try:
                spec.loader.exec_module(module)
            except BaseException:
                del sys.modules[name]
                raise
            func = _PASSES[digest] = module.fault_pass
    except (OSError, ImportError, AttributeError, NumbaError) as exc:
        # unwritable folder, no sources, a source numba refuses: the generic pass (same bits)
        warnings.warn(f"gearvib: the faulty meshes run the generic pass (no pass compiled for "
                      f"the configuration: {exc})", RuntimeWarning, stacklevel=2)
        return 0
    return int(func.address)


def with_fault_pass(packed: tuple) -> tuple:
    """``packed`` (:meth:`gearvib.kernels.KernelSystem.astuple`) with the address of its
    compiled faulty-mesh pass in ``ints[H_FPASS]`` (:func:`pass_address`; 0 leaves the
    generic pass). Sets the entry in place; the tuple must stay in this process."""
    ints, tables = packed[0], packed[2]
    ints[kn.H_FPASS] = pass_address(ints, tables)
    return packed
