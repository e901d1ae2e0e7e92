"""Sensors against an assembled model: defaults filled in and every name checked.

:func:`add_sensors` is :meth:`gearvib.model.AssembledModel.with_sensors`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from gearvib.checks import check_instance, short
from gearvib.model import AssembledModel
from gearvib.sensors.description import (
    HousingSensor,
    SensorError,
    Tacho,
    check_unique,
    sensors_from_list,
)

__all__ = ["add_sensors", "housing_meshes", "members_of"]


def members_of(member: str | tuple[str, ...]) -> tuple[str, ...]:
    """A sensor's housing member(s) as a tuple."""
    return (member,) if isinstance(member, str) else tuple(member)


def housing_meshes(model: AssembledModel, member: str | tuple[str, ...]) -> list[int]:
    """Meshes whose forces a housing sensor on ``member`` sees, in model order.

    A central gear: its meshes with planets. A carrier: the meshes of its planets (a
    parallel stage's housing holds the wheel's axis; the pinion's mesh with it is seen
    there). Several members: the union.
    """
    check_instance(model, AssembledModel, "model")
    if not (isinstance(member, str) or (isinstance(member, tuple) and member
                                        and all(isinstance(m, str) for m in member))):
        raise TypeError(f"member must be a member name or a tuple of them; got {short(member)}")
    planets = {p["name"]: p["carrier"] for p in model.meta.get("planets", [])}
    wanted = set(members_of(member))
    return [k for k, m in enumerate(model.meta.get("meshes", []))
            if m["gear2"] in planets and (m["gear1"] in wanted or planets[m["gear2"]] in wanted)]


def _default_housing(model: AssembledModel, name: str) -> str | tuple[str, ...]:
    fixed = [f for f in model.fixed_members if housing_meshes(model, f)]
    if not fixed:
        central = sorted({m["gear1"] for m in model.meta.get("meshes", [])})
        raise SensorError(f"sensor {name!r}: the gear set has no fixed member with meshes; "
                          f"give the housing member (one of {', '.join(central)})")
    return fixed[0] if len(fixed) == 1 else tuple(fixed)


def add_sensors(model: AssembledModel, sensors: Sequence) -> AssembledModel:
    """:meth:`AssembledModel.with_sensors` (see there)."""
    check_instance(model, AssembledModel, "model")
    new = sensors_from_list(list(sensors))
    checked: list[Tacho | HousingSensor] = []
    bodies = {b["name"]: b["role"] for b in model.meta.get("bodies", [])}
    for s in new:
        if isinstance(s, Tacho):
            member = s.member or model.input_member
            if model.rotation_dofs.get(member, -1) < 0:
                raise SensorError(f"tacho {s.name!r}: member {member!r} has no rotation (it is "
                                  "not a body of the set, or it is held at rest)")
            checked.append(replace(s, member=member))
            continue
        assert isinstance(s, HousingSensor)
        housing = s.member or _default_housing(model, s.name)
        for one in members_of(housing):
            if one not in bodies:
                raise SensorError(f"sensor {s.name!r}: member {one!r} is not a body of the set")
            if not housing_meshes(model, one):
                raise SensorError(f"sensor {s.name!r}: {one!r} meshes with no planet (a "
                                  "housing sensor sees the mesh forces of a central gear, or "
                                  "those of the planets of a carrier)")
        for b, _ in s.bearings:
            names = (f"{b}.x", f"{b}.y")
            if bodies.get(b) not in ("central", "carrier") or any(
                    n not in model.bearing_names for n in names):
                elastic = sorted({n.rsplit(".", 1)[0] for n in model.bearing_names
                                  if n.endswith((".x", ".y"))})
                raise SensorError(f"sensor {s.name!r}: bearings: {b!r} has no elastic radial "
                                  "bearing (members with one: "
                                  f"{', '.join(elastic) or 'none'})")
        checked.append(replace(s, member=housing))
    every = (*model.sensors, *checked)
    check_unique(every)
    return replace(model, sensors=every)
