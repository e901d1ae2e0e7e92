"""The kinematic frequency catalogue of a gear set in one call.

:func:`gear_set_catalogue` reads the tooth numbers of every mesh, the planet angles and carriers
from a :class:`~gearvib.structure.GearSet` (or an assembled model) and the member speeds from
the rigid-body kinematics of the assembly (``AssembledModel.kinematic_ratios``), and hands them
to :func:`analysis.catalogue.kinematic_catalogue`. Each mesh frequency is computed from its own
tooth number and the speed of its gear relative to its carrier, so sets with several mesh
frequencies (stepped Wolfrom planets, two stages) get one line per distinct mesh.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from analysis.catalogue import KinematicCatalogue, RollingBearing, ToothMesh, kinematic_catalogue
from analysis.checks import require_instance
from gearvib.model import AssembledModel
from gearvib.structure import GearSet

__all__ = ["gear_set_catalogue"]


def _from_gear_set(gs: GearSet) -> tuple[list[ToothMesh], dict[str, float]]:
    meshes, angles = [], {}
    for m in gs.meshes:
        z1 = m.z1 if m.z1 is not None else (m.toothing1.z if m.toothing1 is not None else None)
        z2 = m.z2 if m.z2 is not None else (m.toothing2.z if m.toothing2 is not None else None)
        if z1 is None or z2 is None:
            raise ValueError(f"mesh {m.name!r} has no tooth numbers (give z1 and z2): the "
                             "catalogue needs them for the mesh frequency")
        carrier = gs.body(m.gear2).carrier
        meshes.append(ToothMesh(m.name, m.gear1, m.gear2, int(z1), int(z2), str(carrier)))
    for b in gs.planets:
        angles[b.name] = math.degrees(b.angle)
    return meshes, angles


def _from_model(model: AssembledModel) -> tuple[list[ToothMesh], dict[str, float]]:
    planets = {p["name"]: p for p in model.meta.get("planets", [])}
    meshes = []
    for m in model.meta.get("meshes", []):
        if m.get("z1") is None or m.get("z2") is None:
            raise ValueError(f"mesh {m['name']!r} has no tooth numbers: the catalogue needs "
                             "them for the mesh frequency")
        p = planets.get(m["gear2"])
        if p is None:
            raise ValueError(f"mesh {m['name']!r}: {m['gear2']!r} is not a planet of the model")
        meshes.append(ToothMesh(m["name"], m["gear1"], m["gear2"], int(m["z1"]), int(m["z2"]),
                                str(p["carrier"])))
    if not meshes:
        raise ValueError("the model describes no meshes (meta['meshes'] is empty)")
    return meshes, {n: float(p["angle_deg"]) for n, p in planets.items()}


def gear_set_catalogue(
    gear_set: GearSet | AssembledModel,
    *,
    reference: str | None = None,
    speed_rpm: float | None = None,
    speeds_rpm: Any = None,
    bearings: Sequence[RollingBearing] = (),
    sensor: str | None = None,
    model: AssembledModel | None = None,
    **kwargs: Any,
) -> KinematicCatalogue:
    """Kinematic frequency catalogue of a gear set.

    Parameters
    ----------
    gear_set : GearSet or AssembledModel
        The gear set (assembled here when a :class:`GearSet` is given and ``model`` is not).
    reference : str, optional
        Reference shaft of the orders (default: the input member).
    speed_rpm : float, optional
        Speed of the reference shaft [min-1] for the frequencies.
    speeds_rpm : array_like, optional
        Reference speeds of a run-up [min-1].
    bearings : sequence of RollingBearing
        Rolling bearings with their geometry, added to those of the gear set's
        ``[[rolling_bearing]]`` tables (:mod:`gearvib.rolling_bearings`).
    sensor : str, optional
        Member carrying the sensor (default: the first fixed member, else the housing).
    model : AssembledModel, optional
        The assembly of ``gear_set`` if already at hand (saves assembling again).
    **kwargs
        ``mesh_harmonics``, ``harmonics``, ``sidebands`` of
        :func:`analysis.catalogue.kinematic_catalogue`.

    Returns
    -------
    KinematicCatalogue
    """
    if model is not None:
        require_instance(model, AssembledModel, "model")
    if isinstance(gear_set, GearSet):
        meshes, angles = _from_gear_set(gear_set)
        if model is None:
            from gearvib.assembly import assemble

            model = assemble(gear_set)
        name = gear_set.name
        bearings = [*gear_set.bearings(), *bearings]
    elif isinstance(gear_set, AssembledModel):
        model = gear_set
        meshes, angles = _from_model(model)
        name = str(model.meta.get("name", ""))
    else:
        raise ValueError(f"gear_set must be a GearSet or an AssembledModel; got "
                         f"{type(gear_set).__name__}")
    ratios = dict(model.kinematic_ratios)
    return kinematic_catalogue(
        ratios, meshes, reference=reference or model.input_member, planet_angles_deg=angles,
        fixed=tuple(model.fixed_members), sensor=sensor, bearings=bearings,
        speed_rpm=speed_rpm, speeds_rpm=speeds_rpm, name=name, **kwargs)
