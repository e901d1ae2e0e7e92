"""Candidate causes of a diagnosis: the faults and errors simulated one by one.

Every candidate is a ``[[fault]]`` table of the gear-set description
(``docs/faults-sensors.md``), two or three sizes per kind and member (a light and a heavy one; a
broken tooth has one): which of a fault's lines reach above a measurement's noise depends on
its size, and the diagnosis keeps the better-scoring variant. A candidate's *cause* is the
fault ``kind`` and its *member* the body it sits on, named as in the gear set: ``sun``,
``planet``, ``ring`` of a simple set; ``ring2`` of a Wolfrom set; ``planet_short`` of a
Ravigneaux set; ``s2.sun`` of a two-stage set; ``stage2.pinion`` of a multi-stage train.

Every toothed member of every stage is a candidate for the local tooth faults (crack, pitting,
broken tooth); every toothed member that turns for an eccentricity; every planet on a turning
carrier for a pin position error. Planets that the gear set cannot tell apart (identical, on one
carrier and equally spaced: a rotation of the carrier by the planet spacing maps one onto the
next, so without a carrier phase reference their faults give the same spectra) are one
candidate member named after the group (``planet``, ``stage1.planet``, ``planet_long``),
simulated on its first planet.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from gearvib.checks import short
from gearvib.config import ConfigError

__all__ = ["KINDS", "Candidate", "CandidateMember", "candidate_faults", "candidate_members",
           "planets_equivalent", "severity_text"]

KINDS = ("crack", "pitting", "broken_tooth", "eccentricity", "pin_error")
"""Fault kinds a diagnosis considers (a subset may be asked for)."""

LOCAL_KINDS = ("crack", "pitting", "broken_tooth")
"""The local tooth faults."""


@dataclass(frozen=True)
class Candidate:
    """One simulated candidate fault.

    Attributes
    ----------
    cause : str
        Fault kind.
    member : str
        Reported member (``planet`` for interchangeable planets).
    fault : dict
        The ``[[fault]]`` table simulated.
    label : str
        Short unique label, e.g. ``"crack sun 50 %"``.
    """

    cause: str
    member: str
    fault: dict
    label: str


@dataclass(frozen=True)
class CandidateMember:
    """A member whose faults are candidates.

    Attributes
    ----------
    name : str
        Reported name (a planet group: its name without the number).
    target : str
        The body simulated (a group's first planet).
    planets : tuple of str
        The interchangeable planets it stands for (empty for a central gear).
    carrier : str
        The carrier of its meshes (its own for a planet; for a central gear the carrier of the
        planets it meshes).
    turns : bool
        Whether it turns (an eccentricity is a candidate).
    pin : bool
        A planet on a turning carrier (a pin position error is a candidate).
    """

    name: str
    target: str
    planets: tuple[str, ...]
    carrier: str
    turns: bool
    pin: bool

    @property
    def interchangeable(self) -> bool:
        """Several planets that the diagnosis cannot tell apart."""
        return len(self.planets) > 1


def planets_equivalent(cfg: dict) -> bool:
    """Whether the planets of a simple set are equally spaced (and so interchangeable)."""
    angles = sorted(float(a) % 360.0 for a in cfg.get("geometry", {}).get("planet_angles_deg",
                                                                          []))
    return _equally_spaced(angles)


def _equally_spaced(angles_deg: Sequence[float]) -> bool:
    angles = sorted(float(a) % 360.0 for a in angles_deg)
    n = len(angles)
    if n < 2:
        return True
    step = 360.0 / n
    return all(abs((a - angles[0]) - i * step) < 1e-6 for i, a in enumerate(angles))


CRACK_SEVERITIES = (0.3, 0.7)
"""Stiffness losses of the simulated tooth cracks (a light and a deep crack)."""

PITTING_VARIANTS = ((0.4, 0.35, 0.65, 3e-6), (0.5, 0.15, 0.45, 5e-6), (0.7, 0.2, 0.8, 10e-6))
"""Simulated pitting: (stiffness loss, path start, path end, depth [m]) — early pitting
about the pitch line and advanced spalling over most of the path."""

ECCENTRICITIES = (8e-6, 20e-6)
"""Simulated eccentricities [m]."""

PIN_ERRORS = (10e-6, 30e-6)
"""Simulated tangential pin position errors [m]."""

_NUMBER = re.compile(r"\d+$")


def _local(kind: str, member: str, target: str,
           toothing: tuple[int, tuple[str, ...]] | None = None) -> list[Candidate]:
    """The variants of a local tooth fault; ``toothing`` (tooth number, mates) selects one
    toothing of a member with several (a stepped planet), named ``z<teeth>`` in the label."""
    extra: dict = {"mate": list(toothing[1])} if toothing else {}
    name = f"{member} z{toothing[0]}" if toothing else member
    if kind == "crack":
        return [Candidate(kind, member, {"kind": "crack", "member": target, "tooth": 0,
                                         "severity": s, **extra},
                          f"crack {name} {100 * s:.0f} %") for s in CRACK_SEVERITIES]
    if kind == "pitting":
        return [Candidate(kind, member, {"kind": "pitting", "member": target, "tooth": 0,
                                         "severity": s, "path_start": a, "path_end": b,
                                         "depth": d, "flank": "both", **extra},
                          f"pitting {name} {100 * s:.0f} % {d * 1e6:.0f} um")
                for s, a, b, d in PITTING_VARIANTS]
    return [Candidate(kind, member, {"kind": "broken_tooth", "member": target, "tooth": 0,
                                     **extra}, f"broken_tooth {name}")]


def _toothings(gs, member: str) -> list[tuple[int, tuple[str, ...]]]:
    """The toothings of a member with several (tooth number, mating bodies), else ``[]``."""
    by_z: dict[int, list[str]] = {}
    for m in gs.meshes:
        for own, other, t, z in ((m.gear1, m.gear2, m.toothing1, m.z1),
                                 (m.gear2, m.gear1, m.toothing2, m.z2)):
            if own == member:
                teeth = z if z is not None else (t.z if t is not None else 0)
                by_z.setdefault(abs(int(teeth)), []).append(other)
    if len(by_z) < 2:
        return []
    return [(z, tuple(mates)) for z, mates in sorted(by_z.items(), reverse=True)]


def _stage(name: str) -> str:
    """The stage prefix of a member name (``"stage2."``, ``"s1."``, ``""``)."""
    return name.rsplit(".", 1)[0] + "." if "." in name else ""


def candidate_members(gs, model) -> list[CandidateMember]:
    """The members of a gear set whose faults are candidates, stage by stage.

    Within a stage: the external central gears (suns, a parallel stage's pinion), the planet
    groups (planets; a parallel stage's wheel and idler), the internal central gears (rings),
    each in the order of the description.

    Parameters
    ----------
    gs : GearSet
        The healthy gear set.
    model : AssembledModel
        Its assembly (planet angles, kinematics).

    Returns
    -------
    list of CandidateMember
        Planets of one carrier with one name stem (``planet1``, ``planet2``, ...) that are
        equally spaced form one member named by the stem; unequally spaced ones are members
        each.
    """
    bodies = {b.name: b for b in gs.bodies}
    angles = {p["name"]: float(p["angle_deg"]) for p in model.meta.get("planets", [])}
    ratios = model.kinematic_ratios
    toothed: list[str] = []
    external: set[str] = set()
    carrier_of: dict[str, str] = {}
    for m in gs.meshes:
        for g in (m.gear1, m.gear2):
            if g not in toothed:
                toothed.append(g)
        z1 = m.z1 if m.z1 is not None else (m.toothing1.z if m.toothing1 is not None else 1)
        if z1 > 0:
            external.add(m.gear1)
        carrier_of.setdefault(m.gear1, str(bodies[m.gear2].carrier))
        carrier_of.setdefault(m.gear2, str(bodies[m.gear2].carrier))
    order = [b.name for b in gs.bodies if b.name in toothed]
    stages: list[str] = []
    for name in order:
        if _stage(name) not in stages:
            stages.append(_stage(name))
    out: list[CandidateMember] = []
    for stage in stages:
        names = [n for n in order if _stage(n) == stage]
        central = [n for n in names if bodies[n].role != "planet"]
        groups: dict[tuple[str, str], list[str]] = {}
        for n in names:
            if bodies[n].role == "planet":
                groups.setdefault((str(bodies[n].carrier), _NUMBER.sub("", n) or n),
                                  []).append(n)

        def turns(n: str) -> bool:
            return abs(float(ratios.get(n, 0.0))) > 1e-12

        for n in central:
            if n in external:
                out.append(CandidateMember(n, n, (), carrier_of[n], turns(n), False))
        for (carrier, stem), ps in groups.items():
            pin = turns(carrier)
            if _equally_spaced([angles.get(p, 0.0) for p in ps]):
                out.append(CandidateMember(stem, ps[0], tuple(ps), carrier, turns(ps[0]), pin))
            else:
                out += [CandidateMember(p, p, (p,), carrier, turns(p), pin) for p in ps]
        for n in central:
            if n not in external:
                out.append(CandidateMember(n, n, (), carrier_of[n], turns(n), False))
    return out


def candidate_faults(cfg: dict, kinds: Sequence[str] = KINDS, *,
                     base: Path | None = None) -> list[Candidate]:
    """The candidate faults of a gear set of any type.

    Parameters
    ----------
    cfg : dict
        Gear-set description of any type (simple, Wolfrom, Ravigneaux, parallel, two- and
        multi-stage, general) without ``[[fault]]`` tables.
    kinds : sequence of str
        Fault kinds to consider (default :data:`KINDS`).
    base : Path, optional
        Folder of the description (relative file names in it).

    Returns
    -------
    list of Candidate
        For each local kind every toothed member (:func:`candidate_members`), then the
        eccentricities of the members that turn, then the pin errors of the planets on turning
        carriers; each in two or three sizes.

    Raises
    ------
    ConfigError
        An invalid description, one with ``[[fault]]`` tables or without meshes, or an unknown
        kind.
    """
    from gearvib.assembly import assemble
    from gearvib.config import gearset_from_dict

    if isinstance(kinds, str) or not isinstance(kinds, list | tuple):
        raise ConfigError(f"diagnosis: kinds must be a list of fault kinds, got {short(kinds)}")
    bad = [k for k in kinds if not isinstance(k, str) or k not in KINDS]
    if bad:
        raise ConfigError(f"diagnosis: unknown fault kind(s) {short(bad)} (admissible: "
                          f"{', '.join(KINDS)})")
    if not isinstance(cfg, dict):
        raise ConfigError(f"diagnosis: a gear-set description must be a table, got "
                          f"{type(cfg).__name__}")
    if cfg.get("fault"):
        raise ConfigError("diagnosis: the gear set must describe the healthy gearbox (remove "
                          "its [[fault]] tables)")
    gs = gearset_from_dict(cfg, base=base)
    if not gs.meshes:
        raise ConfigError("diagnosis: the gear set has no meshes")
    try:
        model = assemble(gs)
    except ValueError as exc:
        raise ConfigError(f"diagnosis: {exc}") from None
    members = candidate_members(gs, model)
    out: list[Candidate] = []
    for kind in LOCAL_KINDS:
        if kind in kinds:
            for m in members:
                toothings: list[tuple[int, tuple[str, ...]] | None] = [
                    *_toothings(gs, m.target)] or [None]
                for toothing in toothings:
                    out += _local(kind, m.name, m.target, toothing)
    if "eccentricity" in kinds:
        for m in members:
            if m.turns:
                out += [Candidate("eccentricity", m.name, {
                    "kind": "eccentricity", "member": m.target, "eccentricity": e,
                    "phase_deg": 0.0}, f"eccentricity {m.name} {e * 1e6:.0f} um")
                    for e in ECCENTRICITIES]
    if "pin_error" in kinds:
        for m in members:
            if m.pin:
                out += [Candidate("pin_error", m.name, {"kind": "pin_error", "member": m.target,
                                                        "tangential": e, "radial": 0.0},
                                  f"pin_error {m.name} {e * 1e6:.0f} um") for e in PIN_ERRORS]
    assert len({c.label for c in out}) == len(out)
    return out


def severity_text(c: Candidate) -> str:
    """What was simulated, for the evidence."""
    f = c.fault
    text = _severity(c)
    if f.get("mate"):
        text += f" (the toothing meshing {', '.join(f['mate'])})"
    return text


def _severity(c: Candidate) -> str:
    f = c.fault
    if c.cause == "crack":
        return f"tooth crack, stiffness loss {100 * f['severity']:.0f} %"
    if c.cause == "pitting":
        return (f"pitting {100 * f['severity']:.0f} %, {f['depth'] * 1e6:.0f} µm deep over "
                f"{100 * f['path_start']:.0f}-{100 * f['path_end']:.0f} % of the path")
    if c.cause == "broken_tooth":
        return "missing tooth"
    if c.cause == "eccentricity":
        return f"eccentricity {f['eccentricity'] * 1e6:.0f} µm"
    return f"pin position error {math.hypot(f['tangential'], f['radial']) * 1e6:.0f} µm"
