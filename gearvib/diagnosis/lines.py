"""Kinematic lines of the candidate members of a diagnosis, in orders of the reference shaft.

:func:`order_reference` chooses the shaft whose orders a diagnosis counts; :func:`kinematics`
assembles the healthy gear set and its catalogue in those orders; :func:`member_lines` gives
every candidate member's fault fundamental, rotation, carrier and mesh order, and
:func:`family_table` the catalogue families (with harmonics and mesh sidebands) whose lines
the family evidence checks.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from analysis.diagnosis import family_lines, phasing_shifts
from gearvib.config import ConfigError, gearset_from_dict
from gearvib.diagnosis.candidates import LOCAL_KINDS

__all__ = ["FAMILY_MESH_HARMONICS", "Kinematics", "MemberLines", "cause_family",
           "family_table", "fault_shifts", "kinematics", "member_lines", "order_reference"]


def order_reference(gs: Any, model: Any) -> str:
    """The shaft whose orders a diagnosis counts.

    The carrier when exactly one carrier turns (every simple, Wolfrom and Ravigneaux set, and
    a train with one planetary stage: the fault frequencies of its members are then orders of
    moderate size); otherwise (several planetary stages, parallel stages only) the slowest
    turning shaft, so that every fault frequency is an order of at least its own.

    Parameters
    ----------
    gs : GearSet
        The gear set.
    model : AssembledModel
        Its assembly (kinematic ratios).

    Returns
    -------
    str
        The member's name (``"carrier"`` for every simple set with a turning carrier).
    """
    r = model.kinematic_ratios
    carriers = [b.name for b in gs.bodies if b.role == "carrier" and abs(r.get(b.name, 0.0))
                > 1e-12]
    if len(carriers) == 1:
        return carriers[0]
    on_moving = {b.name for b in gs.bodies if b.role == "planet"
                 and abs(r.get(str(b.carrier), 0.0)) > 1e-12}
    shafts = [(abs(r[b.name]), i, b.name) for i, b in enumerate(gs.bodies)
              if abs(r.get(b.name, 0.0)) > 1e-12 and b.name not in on_moving]
    return min(shafts)[2]


@dataclass(frozen=True)
class Kinematics:
    """The healthy gear set, its assembly, the reference of the orders
    (:func:`order_reference`), its catalogue in reference orders and the member speeds in
    reference orders."""

    gs: Any
    model: Any
    reference: str
    cat: Any
    ms: dict[str, float]

    def ratio(self, member: str) -> float:
        """Reference speed per unit speed of ``member``."""
        if member not in self.ms or self.ms[member] == 0:
            raise ConfigError(f"the speed reference {member!r} is not a rotating member of the "
                              "gear set (admissible: "
                              f"{', '.join(k for k, v in self.ms.items() if v)})")
        return 1.0 / abs(self.ms[member])


def kinematics(cfg: dict, base: Path | None) -> Kinematics:
    from gearvib.assembly import assemble
    from gearvib.catalogue import gear_set_catalogue

    gs = gearset_from_dict(cfg, base=base)
    model = assemble(gs)
    reference = order_reference(gs, model)
    cat = gear_set_catalogue(gs, model=model, reference=reference, speed_rpm=1000.0,
                             mesh_harmonics=4, harmonics=6, sidebands=3)
    return Kinematics(gs, model, reference, cat,
                       {k: float(v) for k, v in cat.member_speeds.items()})


_DIGITS = re.compile(r"\d+$")


@dataclass(frozen=True)
class MemberLines:
    """Kinematic lines of a candidate member (orders of the reference shaft).

    ``fault``: the fundamental of a local tooth fault (its catalogue family's first line),
    ``rotation``: its rotation relative to its carrier (eccentricity), ``carrier``: its
    carrier's rotation (pin errors), ``mesh``: the mesh frequency its faults modulate; the
    ``*_family`` names key the family evidence; ``fault_shifts``: per mesh harmonic, where
    the planet phasing moves the fault's sidebands (:func:`analysis.diagnosis.phasing_shifts`;
    None: not moved).
    """

    fault: float | None
    fault_family: str
    rotation: float
    rotation_family: str
    carrier: float
    carrier_family: str
    mesh: float
    fault_shifts: tuple[tuple[float, ...], ...] | None = None


def member_lines(cat: Any, ms: dict[str, float], members: list[Any],
                  model: Any) -> dict[str, MemberLines]:
    """Lines of every candidate member from the catalogue (reference orders).

    The fault fundamental is the catalogue's first line of the member's fault family
    (``sun_fault``, ``ring_fault``, ``planet_fault`` or ``gear_fault``); the mesh order the
    catalogue's mesh line nearest to the member's own mesh frequency. Family keys are the
    catalogue family names where one member has them (``sun_fault``, ``planet_rotation``,
    ``carrier``: a simple set), else qualified by the member (``gear_fault stage2.pinion``).
    """
    fam = np.asarray(cat.family)
    order = np.asarray(cat.order, float)
    first = (np.asarray(cat.harmonic) == 1) & (np.asarray(cat.sideband) == 0)
    member_col = np.asarray(cat.member).astype(str)
    mesh_lines = np.sort(order[(fam == "mesh") & first])
    # the mesh rate |z_1 (n_1 - n_c)| of every mesh a member's teeth take part in
    rates: dict[str, list[float]] = {}
    planets = {p["name"]: p["carrier"] for p in model.meta.get("planets", [])}
    for d in model.meta.get("meshes", []):
        if d.get("z1") is None:
            continue
        rate = abs(int(d["z1"]) * (ms[d["gear1"]] - ms[planets[d["gear2"]]]))
        for g in (d["gear1"], d["gear2"]):
            rates.setdefault(str(g), []).append(rate)
    found: dict[str, tuple[str, str, float | None]] = {}
    for m in members:
        cat_name = m.name if not m.planets else (_DIGITS.sub("", m.target) or m.target)
        fault = None
        fault_fam = ""
        for family in ("sun_fault", "ring_fault", "planet_fault", "gear_fault"):
            sel = (fam == family) & first & (member_col == cat_name)
            if sel.any():
                fault, fault_fam = float(order[sel][0]), family
                break
        found[m.name] = (cat_name, fault_fam, fault)
    names_of: dict[str, set[str]] = {}
    for cat_name, family, _ in found.values():
        names_of.setdefault(family, set()).add(cat_name)
    count = {family: len(names) for family, names in names_of.items()}
    turning = sorted({m.carrier for m in members if abs(ms.get(m.carrier, 0.0)) > 0})
    out = {}
    for m in members:
        cat_name, family, fault = found[m.name]
        # the member's own (first) mesh frequency, snapped to the catalogue's line
        own = rates.get(m.target, [])
        if not mesh_lines.size:
            mesh = 0.0
        elif own:
            mesh = float(mesh_lines[np.argmin(np.abs(mesh_lines - own[0]))])
        else:
            mesh = float(mesh_lines[-1])
        key = family if count.get(family, 0) == 1 else f"{family} {cat_name}"
        c_key = "carrier" if len(turning) <= 1 else f"carrier {m.carrier}"
        out[m.name] = MemberLines(fault, key, abs(ms.get(m.target, 0.0) - ms.get(m.carrier, 0.0)),
                             f"{cat_name}_rotation", abs(ms.get(m.carrier, 0.0)), c_key, mesh,
                             fault_shifts(m.target, family, ms, model, planets))
    return out


def fault_shifts(gear: str, family: str, ms: dict[str, float], model: Any,
                  planets: dict[str, str]) -> tuple[tuple[float, ...], ...] | None:
    """Per mesh harmonic, where the planet phasing puts the sidebands of a local fault on the
    central gear ``gear`` (:func:`analysis.diagnosis.phasing_shifts`, the sensor on the
    housing); None for another family or a gear without planet meshes."""
    if family not in ("sun_fault", "ring_fault"):
        return None
    meshes = [d for d in model.meta.get("meshes", []) if str(d["gear1"]) == gear
              and d.get("z1") is not None and d["gear2"] in planets]
    if not meshes:
        return None
    carrier = planets[meshes[0]["gear2"]]
    mates = {d["gear2"] for d in meshes if planets[d["gear2"]] == carrier}
    psi = [math.radians(float(p["angle_deg"])) for p in model.meta.get("planets", [])
           if p["name"] in mates]
    z = int(meshes[0]["z1"])
    rel = ms[gear] - ms[carrier]
    pass_order = math.copysign(1.0, z * rel) * ms[carrier] if rel else 0.0
    return tuple(phasing_shifts(z, psi, pass_order=pass_order,
                                mesh_harmonics=FAMILY_MESH_HARMONICS))


FAMILY_MESH_HARMONICS = 6
"""Mesh harmonics whose sidebands a family's lines include (the family evidence)."""


def family_table(lines: dict[str, MemberLines], members: list[Any], max_order: float
                  ) -> dict[str, tuple[float, np.ndarray]]:
    """Catalogue families of the candidate members: their fault lines, rotations (turning
    members) and carriers, each with harmonics and sidebands of the member's mesh."""
    base: dict[str, tuple[float, float, Any]] = {}
    for m in members:
        ln = lines[m.name]
        if ln.fault is not None:
            base.setdefault(ln.fault_family, (ln.fault, ln.mesh, ln.fault_shifts))
    for m in members:
        ln = lines[m.name]
        if m.turns:
            base.setdefault(ln.rotation_family, (ln.rotation, ln.mesh, None))
    for m in members:
        ln = lines[m.name]
        base.setdefault(ln.carrier_family, (ln.carrier, ln.mesh, None))
    out = {}
    for name, (f, mesh, shifts) in base.items():
        if f > 0:
            out[name] = (f, family_lines(f, mesh_order=mesh,
                                         mesh_harmonics=FAMILY_MESH_HARMONICS, harmonics=10,
                                         shifts=shifts,
                                         sidebands=10, max_order=max_order))
    return out


def cause_family(cause: str, lines: MemberLines) -> str:
    """The family whose lines a cause raises: its member's fault, rotation or carrier."""
    if cause in LOCAL_KINDS:
        return lines.fault_family
    if cause == "eccentricity":
        return lines.rotation_family
    return lines.carrier_family
