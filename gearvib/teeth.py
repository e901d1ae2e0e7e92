"""Which teeth form the tooth pair in contact: the tooth map of every mesh.

The mesh position ``s`` of a mesh counts tooth pairs: the pair that entered contact at
``s = j`` (``j`` an integer, the *pair counter*) is at the path position ``u = s - j``
[base pitches] while ``0 <= u < eps_alpha``. Because ``s`` follows from the actual rotation
angles of both gears (``s = [z1 (theta1 - theta_c) - z2 (theta2 - theta_c)] / 4 pi + s0``), so
does the pair counter, and the tooth of each gear in pair ``j`` is::

    tooth_g(j) = (sign_g j + tooth_g(0)) mod |z_g|

with ``sign = +1`` when the gear's teeth enter the mesh in increasing order (central gears,
and planets as ``gear2``) and ``-1`` for a planet that is ``gear1`` of a planet-planet mesh (it
turns the other way).

Tooth numbering
---------------
The teeth of every gear are numbered from 0 in the order in which they enter its meshes in
forward operation (the sun turning forward relative to the carrier): tooth ``k + 1`` follows
tooth ``k`` into every mesh of the gear. On a central gear with signed tooth number ``z`` tooth
``k`` lies at the body angle ``beta_0 - 2 pi k / z`` (the sun's teeth are counted clockwise,
the ring's counter-clockwise); on a planet at ``beta_0 + 2 pi k / z_p`` (counter-clockwise).

* Tooth 0 of a central gear is its tooth in pair ``j = 0`` of its first mesh (model order;
  planet 1 for the builders): the pair that entered contact last before the reference
  configuration (every rotation zero). Its other meshes follow from the assembly constant of
  the gear (``s0 = -z psi / 2 pi + c``, the same ``c`` at every planet): the tooth facing the
  planet at ``psi`` is ``z psi / 2 pi`` teeth further, so ``tooth(0) = -round(c_m - c_ref)``.
* Tooth 0 of a planet (per toothing) is its tooth in pair 0 of its first mesh. In its other
  meshes the tooth in pair 0 follows from the tooth directions of the real tooth geometry
  (:func:`gearvib.geometry.planet_tooth_angle`: the centre line of the tooth that entered
  contact last); lumped meshes without tooth geometry use the direction of the contact point
  instead, which can be one tooth off.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from gearvib.checks import check_array, check_count, check_instance, check_items, short
from gearvib.geometry import MAX_TEETH, MeshGeometry, planet_tooth_angle
from gearvib.structure import Body, Mesh

__all__ = ["TOOTH_MAP_COLUMNS", "mesh_tooth_map", "pair_teeth"]

TOOTH_MAP_COLUMNS = ("sign1", "tooth1", "sign2", "tooth2")
"""Columns of the tooth map: pair-counter sign and tooth in pair 0 of gear1 and gear2
(sign 0: the mesh has no tooth numbers)."""


def pair_teeth(tooth_map_row: np.ndarray, z1: int, z2: int, j: int) -> tuple[int, int]:
    """Teeth of gear1 and gear2 in pair ``j`` of a mesh (``tooth_map_row`` of
    :func:`mesh_tooth_map`)."""
    row = check_array(tooth_map_row, "tooth_map_row", ndim=1, max_abs=1e15)
    if row.size != 4 or not np.all(row == np.round(row)):
        raise ValueError(f"tooth_map_row must hold 4 integers ({', '.join(TOOTH_MAP_COLUMNS)}); "
                         f"got {short(tooth_map_row)}")
    for key, z in (("z1", z1), ("z2", z2)):
        check_count(z, key, low=-MAX_TEETH, high=MAX_TEETH)
        if z == 0:
            raise ValueError(f"{key} = 0 is not admissible (admissible: a signed tooth number)")
    j = check_count(j, "j")
    s1, t1, s2, t2 = (int(v) for v in row)
    return (s1 * j + t1) % abs(z1), (s2 * j + t2) % abs(z2)


def mesh_tooth_map(meshes, bodies: Mapping, resolved: Mapping, s0: np.ndarray,
                   centre: Mapping[str, np.ndarray]) -> np.ndarray:
    """Tooth map of every mesh (module docstring), shape ``(n_mesh, 4)``, int64.

    Parameters
    ----------
    meshes : sequence of Mesh
        The meshes of the gear set, in model order.
    bodies : mapping of str to Body
        Bodies by name.
    resolved : mapping of str to ResolvedMesh
        Resolved mesh parameters by mesh name (:func:`gearvib.assembly.resolve_mesh`).
    s0 : ndarray, shape (n_mesh,)
        Mesh positions at the reference configuration [cycles, 0..1).
    centre : mapping of str to ndarray
        Centre of every body at the reference configuration [m].
    """
    meshes = check_items(meshes, Mesh, "meshes")
    for key, mapping in (("bodies", bodies), ("resolved", resolved), ("centre", centre)):
        check_instance(mapping, Mapping, key)
    s0 = check_array(s0, "s0", ndim=1, min_size=0, max_abs=1e9)
    if s0.size != len(meshes):
        raise ValueError(f"s0 needs one mesh position per mesh ({len(meshes)}); got {s0.size}")
    for m in meshes:
        check_instance(resolved.get(m.name), "gearvib.assembly.ResolvedMesh",
                         f"resolved[{short(m.name)}]")  # by name: assembly imports teeth
        for g in (m.gear1, m.gear2):
            if not isinstance(bodies.get(g), Body):
                raise ValueError(f"bodies has no Body {short(g)} (of mesh {short(m.name)})")
            c = centre.get(g)
            if not (isinstance(c, np.ndarray | list | tuple) and np.shape(c) == (2,)):
                raise ValueError(f"centre of {short(g)} must be an (x, y) pair [m]; got "
                                 f"{short(c)}")
            check_array(c, f"centre of {short(g)}", max_abs=1e6)
    out = np.zeros((len(meshes), 4), dtype=np.int64)
    c_ref: dict[str, float] = {}
    planet_ref: dict[tuple, float] = {}
    for k, m in enumerate(meshes):
        r = resolved[m.name]
        if r.z1 is None or r.z2 is None:
            continue
        b1, b2 = bodies[m.gear1], bodies[m.gear2]
        z1, z2 = int(r.z1), int(r.z2)
        if b1.role == "central":
            c = float(s0[k]) + z1 * b2.angle / (2.0 * math.pi)
            ref = c_ref.setdefault(m.gear1, c)
            out[k, 0] = 1
            out[k, 1] = (-round(c - ref)) % abs(z1)
        else:
            out[k, 0] = -1
            out[k, 1] = _planet_tooth(m, k, b1.name, True, z1, r.geometry, bodies, centre, s0,
                                      planet_ref)
        out[k, 2] = 1
        out[k, 3] = _planet_tooth(m, k, b2.name, False, z2, r.geometry, bodies, centre, s0,
                                  planet_ref)
    return out


def _planet_tooth(m, k: int, planet: str, is_gear1: bool, z: int, g: MeshGeometry | None,
                  bodies: Mapping, centre: Mapping, s0: np.ndarray,
                  planet_ref: dict[tuple, float]) -> int:
    """Tooth of ``planet`` in pair 0 of mesh ``k``, counted from the planet's tooth 0."""
    mate = m.gear2 if is_gear1 else m.gear1
    d = centre[mate] - centre[planet]
    mate_dir = math.atan2(d[1], d[0])
    sign = -1.0 if is_gear1 else 1.0
    toothing = None
    if g is not None:
        toothing = g.gear1 if is_gear1 else g.gear2
    if g is not None and toothing is not None and not toothing.internal:
        beta = planet_tooth_angle(g, planet_is_gear1=is_gear1, mate_direction=mate_dir,
                                  position=float(s0[k]))
        beta -= m.tooth_offset1 if is_gear1 else m.tooth_offset2
    else:
        # lumped mesh: the contact point's direction (towards an external mate, away from an
        # internal one), turned back by the fraction of a pitch the pair has run since entry
        internal_mate = bodies[mate].role == "central" and _internal(m, is_gear1)
        contact = mate_dir + (math.pi if internal_mate else 0.0)
        beta = contact - sign * 2.0 * math.pi * float(s0[k]) / abs(z)
    offset = m.tooth_offset1 if is_gear1 else m.tooth_offset2
    ref = planet_ref.setdefault((planet, abs(z), round(offset, 12)), beta)
    return round(abs(z) * (beta - ref) / (2.0 * math.pi)) % abs(z)


def _internal(m, is_gear1: bool) -> bool:
    """The mate of the planet in mesh ``m`` has internal toothing (from the signed numbers)."""
    z_mate = m.z2 if is_gear1 else m.z1
    if z_mate is None:
        toothing = m.toothing2 if is_gear1 else m.toothing1
        z_mate = toothing.z if toothing is not None else None
    if z_mate is None:
        rb = m.base_radius2 if is_gear1 else m.base_radius1
        return rb is not None and rb < 0
    return z_mate < 0
