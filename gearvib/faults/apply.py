"""Faults against an assembled model: which meshes and teeth each one touches, checked.

:func:`add_faults` is :meth:`gearvib.model.AssembledModel.with_faults`: it checks every fault
against the model (member, tooth range, meshes, planets), applies a planet-specific backlash
to the model's backlash array and keeps the descriptions in ``model.faults``; the run turns
them into kernel arrays (:mod:`gearvib.faults.law`). :func:`fault_targets` lists the meshes a
fault acts on, :func:`mesh_lines` the lines of action of every mesh.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from gearvib.checks import check_instance, short
from gearvib.faults.description import (
    Fault,
    FaultError,
    PinError,
    PitchError,
    PlanetBacklash,
    faults_from_list,
)
from gearvib.model import AssembledModel

__all__ = ["MeshLine", "Target", "add_faults", "fault_targets", "mesh_lines", "tooth_count"]


@dataclass(frozen=True)
class Target:
    """One mesh a fault acts on.

    Attributes
    ----------
    mesh : int
        Mesh index in the model.
    side : int
        1: the member is the mesh's gear1, 2: its gear2.
    z : int
        Signed tooth number of the member in that mesh (0 without tooth numbers).
    """

    mesh: int
    side: int
    z: int


@dataclass(frozen=True)
class MeshLine:
    """Lines of action of a mesh in the carrier frame at the reference configuration.

    Attributes
    ----------
    left, right : ndarray, shape (2,)
        Unit vectors of the left (drive) and right (back) flank's line of action
        (:mod:`gearvib.assembly`).
    cos_beta : float
        ``cos(beta_b)``: an in-plane displacement ``d`` of gear1 changes the deflection by
        ``cos_beta d . n`` (gear2: ``-cos_beta d . n``).
    theta_coefficient1, theta_coefficient2 : float
        ``cos(beta_b) sigma r_b`` of gear1 and gear2: deflection per unit rotation [m/rad].
    """

    left: np.ndarray
    right: np.ndarray
    cos_beta: float
    theta_coefficient1: float
    theta_coefficient2: float


def _bodies(model: AssembledModel) -> dict[str, str]:
    check_instance(model, AssembledModel, "model")
    return {b["name"]: b["role"] for b in model.meta.get("bodies", [])}


def _meshes(model: AssembledModel) -> list[dict]:
    check_instance(model, AssembledModel, "model")
    meshes = model.meta.get("meshes", [])
    if len(meshes) != model.n_mesh:
        raise FaultError("the model carries no mesh description (meta['meshes']); faults need "
                         "a model built by gearvib.assembly.assemble")
    return meshes


def mesh_lines(model: AssembledModel) -> list[MeshLine]:
    """Lines of action of every mesh, rebuilt from the model's description as the assembly
    builds them (``n_L = cos a t + sigma sin a e``, ``n_R = cos a t - sigma sin a e``, ``e``
    from gear1's centre to gear2's, ``t`` = ``e`` turned by +90 deg)."""
    check_instance(model, AssembledModel, "model")
    planets = {p["name"]: p for p in model.meta.get("planets", [])}

    def centre(name: str) -> np.ndarray:
        p = planets.get(name)
        if p is None:
            return np.zeros(2)
        a = math.radians(p["angle_deg"])
        return p["radius"] * np.array([math.cos(a), math.sin(a)])

    out = []
    for m in _meshes(model):
        diff = centre(m["gear2"]) - centre(m["gear1"])
        e = diff / np.hypot(*diff)
        t = np.array([-e[1], e[0]])
        sigma = -1.0 if m["base_radius1"] * m["base_radius2"] < 0 else 1.0
        alpha = math.radians(m["pressure_angle_deg"])
        cb = math.cos(math.radians(m["base_helix_angle_deg"]))
        ca, sa = math.cos(alpha), math.sin(alpha)
        out.append(MeshLine(ca * t + sigma * sa * e, ca * t - sigma * sa * e, cb,
                            cb * sigma * m["base_radius1"], cb * sigma * m["base_radius2"]))
    return out


def tooth_count(model: AssembledModel, member: str) -> dict[int, list[int]]:
    """``{|z|: [mesh, ...]}``: the toothings of a member and the meshes that use each."""
    out: dict[int, list[int]] = {}
    for k, m in enumerate(_meshes(model)):
        for g, z in ((m["gear1"], m.get("z1")), (m["gear2"], m.get("z2"))):
            if g == member and z is not None:
                out.setdefault(abs(int(z)), []).append(k)
    return out


def fault_targets(model: AssembledModel, fault: Fault) -> list[Target]:
    """The meshes a fault acts on (checked: member, mates, toothing, tooth range).

    Raises
    ------
    FaultError
        Unknown member or mate, a member without teeth, a tooth out of range, a stepped planet
        whose toothing is not selected by ``mate``.
    """
    check_instance(fault, Fault, "fault")
    bodies = _bodies(model)
    meshes = _meshes(model)
    label = f"{fault.kind} fault on {short(fault.member)}"
    if fault.member not in bodies:
        toothed = sorted({m["gear1"] for m in meshes} | {m["gear2"] for m in meshes})
        raise FaultError(f"{label}: no body {fault.member!r} in the gear set (bodies with "
                         f"teeth: {', '.join(toothed)})")
    for mate in fault.mate:
        if mate not in bodies:
            raise FaultError(f"{label}: mate {mate!r} is not a body of the gear set")
    targets = []
    for k, m in enumerate(meshes):
        for side, own, other in ((1, m["gear1"], m["gear2"]), (2, m["gear2"], m["gear1"])):
            if own != fault.member or (fault.mate and other not in fault.mate):
                continue
            z = m.get(f"z{side}")
            targets.append(Target(k, side, int(z) if z is not None else 0))
    if not targets:
        if fault.mate:
            raise FaultError(f"{label}: {fault.member!r} does not mesh with "
                             f"{', '.join(fault.mate)}")
        raise FaultError(f"{label}: {fault.member!r} has no teeth ({bodies[fault.member]}); "
                         "faults and errors need a toothed member (sun, planet, ring)")
    if isinstance(fault, PinError):
        if bodies[fault.member] != "planet":
            raise FaultError(f"{label}: a pin error needs a planet (got a "
                             f"{bodies[fault.member]} member)")
        return targets
    if isinstance(fault, PlanetBacklash):
        return targets
    toothed = [t for t in targets if t.z != 0]
    needs_teeth = getattr(fault, "tooth", None) is not None or fault.kind in (
        "crack", "pitting", "broken_tooth", "pitch_error")
    if needs_teeth and len(toothed) < len(targets):
        bad = [meshes[t.mesh]["name"] for t in targets if t.z == 0]
        raise FaultError(f"{label}: mesh {bad[0]!r} has no tooth numbers (give z1, z2): the "
                         "faulty tooth cannot be placed")
    sizes = sorted({abs(t.z) for t in toothed})
    if needs_teeth and len(sizes) > 1:
        by_size = tooth_count(model, fault.member)
        desc = "; ".join(f"z = {z} with " + ", ".join(
            meshes[k]["gear1"] if meshes[k]["gear2"] == fault.member else meshes[k]["gear2"]
            for k in by_size[z]) for z in sizes)
        raise FaultError(f"{label}: {fault.member!r} has several toothings ({desc}); select "
                         "one by mate")
    tooth = getattr(fault, "tooth", None)
    if tooth is not None and sizes and not 0 <= tooth < sizes[0]:
        raise FaultError(f"{label}: tooth = {tooth} is not admissible (admissible: 0 .. "
                         f"{sizes[0] - 1}; {fault.member!r} has {sizes[0]} teeth)")
    if isinstance(fault, PitchError) and sizes:
        fault.cumulative_deviations(sizes[0])  # checks the list length
    if model.mesh_teeth is None and needs_teeth:
        raise FaultError(f"{label}: the model has no tooth map (build it with "
                         "gearvib.assembly.assemble)")
    return targets


def add_faults(model: AssembledModel, faults: Sequence) -> AssembledModel:
    """:meth:`AssembledModel.with_faults` (see there)."""
    check_instance(model, AssembledModel, "model")
    new = faults_from_list(list(faults))
    every = (*model.faults, *new)
    backlash = np.array(model.mesh_backlash, dtype=float, copy=True)
    seen_backlash: dict[int, str] = {}
    pins: set[str] = set()
    for f in every:
        targets = fault_targets(model, f)
        if isinstance(f, PinError):
            if f.member in pins:
                raise FaultError(f"pin error of {f.member!r} is given twice; give one with both "
                                 "components")
            pins.add(f.member)
        if isinstance(f, PlanetBacklash):
            for t in targets:
                name = model.mesh_names[t.mesh]
                if t.mesh in seen_backlash:
                    raise FaultError(f"backlash of mesh {name!r} is given twice "
                                     f"({seen_backlash[t.mesh]} and {f.label})")
                seen_backlash[t.mesh] = f.label
    for f in new:
        if isinstance(f, PlanetBacklash):
            for t in fault_targets(model, f):
                backlash[t.mesh] = f.backlash
    return replace(model, faults=every, mesh_backlash=backlash)
