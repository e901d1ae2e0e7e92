"""Assemble a :class:`~gearvib.structure.GearSet` into the flat :class:`AssembledModel`.

Steps: number the coordinates of every body, build the mass matrix, the mesh deflection and
mesh position vectors with the phase of every contact, the bearing and support springs, apply
the rigid supports and fixed members as linear constraints (``q_full = T q``), and solve the
rigid-body kinematics (the speed of every member per unit input speed).

Mesh deflection (Lin & Parker 1999, generalised with signed base radii)::

    delta = cos(beta_b) [ sigma (r_b1 theta_1 + r_b2 theta_2) + (d_1 - d_2) . n ]
            - sin(beta_b) h (z_1 - z_2)

with ``sigma = -1`` for an internal pair, ``n = cos(alpha) t + sigma sin(alpha) e`` the line
of action (``e`` the unit vector from gear 1 to gear 2, ``t`` = ``e`` turned by +90°), ``d`` the
in-plane displacement of each gear centre and ``h`` the helix hand of gear 1.

Back flank. The right (back) flank touches along the other common tangent of the base circles,
the mirror image of the left flank's line of action about the line of centres::

    n_R = cos(alpha) t - sigma sin(alpha) e

Derivation: ``n_L`` is the direction in which gear 1 pushes gear 2 on the left flank
(external pair: tangential ``+t`` and separating ``+e``; internal pair, gear 1 the ring: the
planet is pushed ``+t`` and towards the ring's axis, ``-e``). Gear 1 turning the other way
pushes gear 2 on its back flank with the tangential component reversed and the separating one
unchanged, ``-cos(alpha) t + sigma sin(alpha) e = -n_R``; with the deflection counted like the
left one's (negative in contact), the back-flank deflection is ``delta_R`` of the formula above
with ``n_R`` in place of ``n``. The rotations enter both alike (equal base radii) and so does
the axial term (a helical flank facing the other way has the opposite normal: the tangential
and the axial force reverse together, for either hand). Only the in-plane translations differ:
``mesh_back_vectors`` of the model (None when they are identical, i.e. when no translation of a
meshing gear is a coordinate).

Axial sign convention: ``z`` runs along the main axis so that positive rotations are
counter-clockwise seen from ``+z`` (right-hand rule); a positive helix angle is a right-hand
helix (ISO 21771); an internal gear has the hand of its planet. The flank of a right-hand gear
that faces its positive rotation has the outward normal ``theta_hat - tan(beta) z_hat``, so a
right-hand gear1 that drives (loaded left flank) is pushed towards ``+z`` and gear2 towards
``-z``: the axial term of ``delta`` is ``-sin(beta_b) h (z_1 - z_2)``. In a simple set with a
right-hand sun the sun is pushed towards ``+z`` by ``T_s tan(beta_b) / r_bs``, the ring towards
``-z`` by as much, and each planet gets equal and opposite axial forces from its two meshes
(a tilting couple, no net force).

Mesh position (paper eq. (3), both gears' angles)::

    s = [z_1 (theta_1 - theta_c) - z_2 (theta_2 - theta_c)] / (4 pi) + s_0,

``s_0 = -z_1 psi / 2 pi`` (+ the sun-ring phase of the planet's tooth geometry for further
central meshes of the same planet toothing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from gearvib.checks import check_count
from gearvib.geometry import (
    MeshGeometry,
    planet_mesh_position,
    planet_tooth_angle,
    sun_ring_phase,
)
from gearvib.model import AssembledModel
from gearvib.stiffness import MAX_TABLE
from gearvib.structure import RIGID, Body, GearSet, Mesh
from gearvib.teeth import mesh_tooth_map

__all__ = ["LUMPED_RADIUS_TOLERANCE", "N_TABLE", "ResolvedMesh", "assemble", "resolve_mesh"]

N_TABLE = 2048
"""Samples per mesh cycle of the stiffness tables handed to the kernels."""
LUMPED_RADIUS_TOLERANCE = 0.1
"""Largest relative difference between the planet radii that the lumped meshes of one planet
imply (``|r_b1 +- r_b2| / cos(alpha)``, or their ``centre_distance``) and the planet radius.

A lumped model in ``u = r theta`` coordinates does not need them to agree: the planet radius
(the carrier radius ``r_c`` of Lin & Parker) enters only through the planet bearings, and
published parameter sets differ by a few per cent. A larger difference is taken as an input
error (a wrong base radius, pressure angle or unit)."""


@dataclass(frozen=True)
class ResolvedMesh:
    """Mesh parameters after geometry and lumped values are merged."""

    base_radius1: float
    base_radius2: float
    pressure_angle: float
    base_helix_angle: float
    helix_hand: float
    z1: int | None
    z2: int | None
    centre_distance: float
    contact_ratio: float | None
    geometry: MeshGeometry | None

    @property
    def sigma(self) -> float:
        """+1 for an external pair, -1 for an internal pair."""
        return -1.0 if self.base_radius1 * self.base_radius2 < 0 else 1.0


def resolve_mesh(mesh: Mesh) -> ResolvedMesh:
    """Merge a mesh's tooth geometry with its lumped overrides."""
    if not isinstance(mesh, Mesh):
        raise TypeError(f"mesh must be a Mesh; got {type(mesh).__name__}")
    g = mesh.geometry
    if g is None:  # lumped: Mesh requires both base radii and the pressure angle then
        assert mesh.base_radius1 is not None and mesh.base_radius2 is not None
        assert mesh.pressure_angle is not None
        rb1, rb2, alpha = mesh.base_radius1, mesh.base_radius2, mesh.pressure_angle
    else:
        rb1 = mesh.base_radius1 if mesh.base_radius1 is not None else g.gear1.base_radius
        rb2 = mesh.base_radius2 if mesh.base_radius2 is not None else g.gear2.base_radius
        alpha = (mesh.pressure_angle if mesh.pressure_angle is not None
                 else g.working_pressure_angle)
    if g is not None and mesh.helix_angle == 0.0:
        beta_b = g.base_helix_angle
        hand = math.copysign(1.0, g.gear1.helix_angle) if g.gear1.helix_angle else 0.0
    else:
        beta_b = abs(mesh.helix_angle)
        hand = math.copysign(1.0, mesh.helix_angle) if mesh.helix_angle else 0.0
    z1 = mesh.z1 if mesh.z1 is not None else (g.gear1.z if g is not None else None)
    z2 = mesh.z2 if mesh.z2 is not None else (g.gear2.z if g is not None else None)
    if rb2 <= 0 and rb1 <= 0:
        raise ValueError(f"mesh {mesh.name!r}: two internal gears cannot mesh")
    sigma = -1.0 if rb1 * rb2 < 0 else 1.0
    if g is not None and mesh.base_radius1 is None:
        a = g.centre_distance
    else:
        a = abs(sigma * rb1 + rb2) / math.cos(alpha) if sigma > 0 else \
            abs(abs(rb1) - abs(rb2)) / math.cos(alpha)
        if mesh.centre_distance is not None:  # a lumped mesh's given centre distance is used
            if not math.isclose(mesh.centre_distance, a, rel_tol=LUMPED_RADIUS_TOLERANCE):
                raise ValueError(
                    f"mesh {mesh.name!r}: centre_distance {mesh.centre_distance * 1e3:.4f} mm "
                    f"differs by {abs(mesh.centre_distance - a) / a:.1%} from "
                    f"|r_b1 {'+' if sigma > 0 else '-'} r_b2| / cos(alpha) = {a * 1e3:.4f} mm "
                    f"(admissible: within {LUMPED_RADIUS_TOLERANCE:.0%}; check the units)"
                )
            a = float(mesh.centre_distance)
    return ResolvedMesh(rb1, rb2, alpha, beta_b, hand, z1, z2, a,
                        g.contact_ratio if g is not None else None, g)


class _Coordinates:
    """Full coordinate numbering before constraints."""

    def __init__(self, bodies: tuple[Body, ...], axial: bool):
        self.names: list[str] = []
        self.index: dict[tuple[str, str], int] = {}
        self.body_of: list[Body] = []
        for b in bodies:
            plane = ("zeta", "eta") if b.role == "planet" else ("x", "y")
            comps = (*plane, "z", "theta") if axial else (*plane, "theta")
            for c in comps:
                self.index[(b.name, c)] = len(self.names)
                self.names.append(f"{b.name}.{c}")
                self.body_of.append(b)

    def __len__(self) -> int:
        return len(self.names)

    def unit(self, body: str, comp: str) -> np.ndarray:
        v = np.zeros(len(self))
        v[self.index[(body, comp)]] = 1.0
        return v

    def get(self, body: str, comp: str) -> int:
        return self.index[(body, comp)]


def _planet_frame(psi: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([math.cos(psi), math.sin(psi)]), np.array([-math.sin(psi), math.cos(psi)])


def _add_displacement(v: np.ndarray, coords: _Coordinates, body: Body, direction: np.ndarray,
                      factor: float) -> None:
    """Add ``factor * (d_body . direction)`` to ``v`` (in-plane displacement of a centre)."""
    if body.role == "planet":
        e_r, e_t = _planet_frame(body.angle)
        v[coords.get(body.name, "zeta")] += factor * float(e_r @ direction)
        v[coords.get(body.name, "eta")] += factor * float(e_t @ direction)
    else:
        v[coords.get(body.name, "x")] += factor * direction[0]
        v[coords.get(body.name, "y")] += factor * direction[1]


def _planet_radius(gs: GearSet, body: Body, resolved: dict[str, ResolvedMesh]) -> float:
    """Planet axis radius: given (``Body.radius``), or the first central-gear mesh's centre
    distance.

    Meshes with tooth geometry must agree with it to 1e-6 (the teeth need one centre
    distance); lumped meshes to :data:`LUMPED_RADIUS_TOLERANCE`.
    """
    a = body.radius
    first, first_exact = None, False
    for m in gs.meshes:
        if m.gear2 != body.name or gs.body(m.gear1).role != "central":
            continue
        r = resolved[m.name]
        am = r.centre_distance
        exact = r.geometry is not None and m.base_radius1 is None
        if a is None:
            a, first, first_exact = am, m.name, exact
            continue
        tol = 1e-6 if exact and (first_exact or first is None) else LUMPED_RADIUS_TOLERANCE
        if not math.isclose(a, am, rel_tol=tol):
            source = f"mesh {first!r}" if first else "the given radius"
            if tol < LUMPED_RADIUS_TOLERANCE:
                hint = ("the teeth need one centre distance: make the profile shifts or the "
                        "given radius consistent")
            else:
                hint = (f"a lumped model accepts up to {LUMPED_RADIUS_TOLERANCE:.0%} (base radii "
                        "and pressure angles of a publication rarely agree exactly); more is "
                        "taken as an input error: check the base radii, pressure angles and "
                        "units, or give the planet's radius")
            raise ValueError(
                f"planet {body.name!r}: mesh {m.name!r} implies a planet radius of "
                f"{am * 1e3:.4f} mm, {source} gives {a * 1e3:.4f} mm "
                f"({abs(am - a) / a:.2%} apart); {hint}"
            )
    if a is None:
        raise ValueError(f"planet {body.name!r}: give its radius (no central-gear mesh)")
    return a


def _null_space(a: np.ndarray) -> np.ndarray:
    """Null space of ``a`` with every row scaled to a unit maximum (mixed units)."""
    scale = np.abs(a).max(axis=1, keepdims=True)
    scale[scale == 0] = 1.0
    return scipy.linalg.null_space(a / scale, rcond=1e-9)


def _constraint_matrix(n: int, rows: list[np.ndarray], dependents: list[int],
                       names: list[str]) -> tuple[np.ndarray, list[int]]:
    """``T`` with ``q_full = T q_reduced`` for constraints ``rows @ q_full = 0``."""
    if len(set(dependents)) != len(dependents):
        dup = sorted({names[d] for d in dependents if dependents.count(d) > 1})
        raise ValueError(f"coordinate(s) {dup} are constrained twice (fixed and rigidly coupled?)")
    independent = [i for i in range(n) if i not in set(dependents)]
    t = np.zeros((n, len(independent)))
    t[independent, range(len(independent))] = 1.0
    if rows:
        a = np.array(rows)
        a_d = a[:, dependents]
        a_i = a[:, independent]
        t[dependents, :] = -np.linalg.solve(a_d, a_i)
        t[np.abs(t) < 1e-14] = 0.0
    return t, independent


def assemble(gs: GearSet, *, n_table: int = N_TABLE) -> AssembledModel:
    """Assemble a gear set into flat arrays.

    Parameters
    ----------
    gs : GearSet
        The gear-set description.
    n_table : int
        Samples per mesh cycle of the stiffness tables.

    Returns
    -------
    AssembledModel

    Raises
    ------
    ValueError
        For inconsistent geometry (planet radius vs centre distance), a set that is locked or
        has more than one rigid-body degree of freedom, or meshes without tooth numbers that
        need a mesh position.
    """
    if not isinstance(gs, GearSet):
        raise TypeError(f"gs must be a GearSet; got {type(gs).__name__}")
    check_count(n_table, "n_table", low=1, high=MAX_TABLE)
    resolved = {m.name: resolve_mesh(m) for m in gs.meshes}
    axial = any(r.base_helix_angle != 0.0 for r in resolved.values())
    coords = _Coordinates(gs.bodies, axial)
    n = len(coords)
    bodies = {b.name: b for b in gs.bodies}

    radius = {b.name: _planet_radius(gs, b, resolved) for b in gs.planets}
    centre = {name: np.zeros(2) for name in bodies}
    for b in gs.planets:
        centre[b.name] = radius[b.name] * np.array([math.cos(b.angle), math.sin(b.angle)])

    # ---- mass ---------------------------------------------------------------------------
    mass = np.zeros(n)
    for i, b in enumerate(coords.body_of):
        mass[i] = b.inertia if coords.names[i].endswith(".theta") else b.mass
    gyro = np.zeros((n, n))
    centripetal = np.zeros((n, n))
    still = _still_frames(gs, bodies)
    for b in gs.bodies:
        if b.name in still:
            continue  # coordinates of a stage whose carrier is held: no frame rotation
        c1, c2 = ("zeta", "eta") if b.role == "planet" else ("x", "y")
        i, j = coords.get(b.name, c1), coords.get(b.name, c2)
        gyro[i, j], gyro[j, i] = -2 * b.mass, 2 * b.mass
        centripetal[i, i] = centripetal[j, j] = b.mass

    # ---- meshes ---------------------------------------------------------------------------
    n_mesh = len(gs.meshes)
    v_mesh = np.zeros((n_mesh, n))
    v_back = np.zeros((n_mesh, n))
    w_mesh = np.zeros((n_mesh, n))
    s0 = np.zeros(n_mesh)
    mesh_meta = []
    for k, m in enumerate(gs.meshes):
        r = resolved[m.name]
        b1, b2 = bodies[m.gear1], bodies[m.gear2]
        carrier = b2.carrier
        assert carrier is not None  # gear2 is a planet, which has its carrier (GearSet checks)
        if b1.role == "planet" and b1.carrier != carrier:
            raise ValueError(f"mesh {m.name!r}: planets on different carriers cannot mesh")
        diff = centre[b2.name] - centre[b1.name]
        dist = float(np.hypot(*diff))
        if b1.role == "planet" and not math.isclose(dist, r.centre_distance, rel_tol=1e-6):
            raise ValueError(
                f"mesh {m.name!r}: planet centres are {dist * 1e3:.4f} mm apart, the mesh needs "
                f"{r.centre_distance * 1e3:.4f} mm"
            )
        e = diff / dist
        t = np.array([-e[1], e[0]])
        sigma = r.sigma
        ca, sa = math.cos(r.pressure_angle), math.sin(r.pressure_angle)
        # left (drive) flank line of action and its mirror image about the line of centres,
        # the back flank's (module docstring, "Back flank")
        n_left = ca * t + sigma * sa * e
        n_back = ca * t - sigma * sa * e
        cb = math.cos(r.base_helix_angle)
        v = np.zeros(n)
        v[coords.get(b1.name, "theta")] += cb * sigma * r.base_radius1
        v[coords.get(b2.name, "theta")] += cb * sigma * r.base_radius2
        if axial and r.base_helix_angle:
            # axial part of the contact normal: a right-hand gear1 (h = +1) driving in the
            # positive sense is pushed towards +z (see the module docstring); the back flank
            # reverses the tangential and the axial force together, so the term is the same
            sb = math.sin(r.base_helix_angle) * r.helix_hand
            v[coords.get(b1.name, "z")] -= sb
            v[coords.get(b2.name, "z")] += sb
        vb = v.copy()
        _add_displacement(v, coords, b1, n_left, cb)
        _add_displacement(v, coords, b2, n_left, -cb)
        _add_displacement(vb, coords, b1, n_back, cb)
        _add_displacement(vb, coords, b2, n_back, -cb)
        v_mesh[k] = v
        v_back[k] = vb

        varying = not math.isclose(m.stiffness.min, m.stiffness.max, rel_tol=1e-12)
        if r.z1 is None or r.z2 is None:
            if varying:
                raise ValueError(
                    f"mesh {m.name!r}: a time-varying stiffness needs tooth numbers z1, z2 to "
                    "place the mesh position"
                )
        else:
            ic = coords.get(carrier, "theta")
            w = np.zeros(n)
            w[coords.get(b1.name, "theta")] += r.z1
            w[coords.get(b2.name, "theta")] -= r.z2
            w[ic] += -r.z1 + r.z2
            w_mesh[k] = w / (4 * math.pi)
        mesh_meta.append({
            "name": m.name, "gear1": m.gear1, "gear2": m.gear2,
            "z1": r.z1, "z2": r.z2,
            "base_radius1": r.base_radius1, "base_radius2": r.base_radius2,
            "pressure_angle_deg": math.degrees(r.pressure_angle),
            "base_helix_angle_deg": math.degrees(r.base_helix_angle),
            "centre_distance": r.centre_distance,
            "contact_ratio": r.contact_ratio,
            "backlash": m.backlash,
            "stiffness": m.stiffness.to_dict(),
        })

    s0[:] = _mesh_positions(gs, resolved, bodies, centre)
    for k, meta_k in enumerate(mesh_meta):
        s0[k] -= math.floor(s0[k])
        if min(s0[k], 1.0 - s0[k]) < 1e-9:  # exact integers from the assembly condition
            s0[k] = 0.0
        meta_k["mesh_position_at_assembly"] = float(s0[k])
        meta_k["phase_lag"] = float((1.0 - s0[k]) % 1.0)

    # ---- supports, bearings, couplings, constraints ------------------------------------------
    k_full = np.zeros((n, n))
    c_full = np.zeros((n, n))
    rows: list[np.ndarray] = []
    deps: list[int] = []
    bearings: list[tuple[str, np.ndarray, float, float]] = []

    def spring(u: np.ndarray, k: float, c: float) -> None:
        k_full[:] += k * np.outer(u, u)
        c_full[:] += c * np.outer(u, u)

    def support(name: str, u: np.ndarray, dep: int, k: float, c: float, listed: bool) -> None:
        if math.isinf(k):
            rows.append(u)
            deps.append(dep)
        elif k > 0 or c > 0:
            spring(u, k, c)
            if listed:
                bearings.append((name, u, k, c))

    for b in gs.bodies:
        s = b.support
        if b.role == "planet":
            car = b.carrier
            assert car is not None  # a planet has its carrier (Body checks)
            e_r, e_t = _planet_frame(b.angle)
            a = radius[b.name]
            u_r = coords.unit(b.name, "zeta")
            _add_displacement(u_r, coords, bodies[car], e_r, -1.0)
            u_t = coords.unit(b.name, "eta")
            _add_displacement(u_t, coords, bodies[car], e_t, -1.0)
            u_t[coords.get(car, "theta")] -= a
            support(f"{b.name}.radial", u_r, coords.get(b.name, "zeta"), s.radial,
                    s.radial_damping, True)
            support(f"{b.name}.tangential", u_t, coords.get(b.name, "eta"), s.tangential,
                    s.tangential_damping, True)
            if axial:
                u_z = coords.unit(b.name, "z") - coords.unit(car, "z")
                support(f"{b.name}.axial", u_z, coords.get(b.name, "z"), s.axial,
                        s.axial_damping, True)
        else:
            for comp in ("x", "y"):
                support(f"{b.name}.{comp}", coords.unit(b.name, comp), coords.get(b.name, comp),
                        s.radial, s.radial_damping, True)
            if axial:
                support(f"{b.name}.axial", coords.unit(b.name, "z"), coords.get(b.name, "z"),
                        s.axial, s.axial_damping, True)
            # a fixed member is held rigidly unless it has an elastic torsional support,
            # through which it is then held (Lin & Parker's k_ru)
            k_t = s.torsional
            if b.name in gs.fixed and not (0 < k_t < math.inf):
                k_t = RIGID
            support(f"{b.name}.torsion", coords.unit(b.name, "theta"),
                    coords.get(b.name, "theta"), k_t, s.torsional_damping, False)
    for cp in gs.couplings:
        u = coords.unit(cp.body1, "theta") - coords.unit(cp.body2, "theta")
        support(f"coupling.{cp.body1}-{cp.body2}", u, coords.get(cp.body2, "theta"),
                cp.stiffness, cp.damping, False)

    tmat, kept = _constraint_matrix(n, rows, deps, coords.names)

    def reduce_matrix(a: np.ndarray) -> np.ndarray:
        return tmat.T @ a @ tmat

    m_red = reduce_matrix(np.diag(mass))
    k_red = reduce_matrix(k_full)
    c_red = reduce_matrix(c_full)
    v_red = v_mesh @ tmat
    vb_red = v_back @ tmat
    # the back flank's line of action differs from the left one's only by the relative
    # displacement of the gear centres along the line of centres: where the reduced coordinates
    # have none (rigid in-plane bearings) the two vectors agree up to rounding and the left one
    # is used for both, so such models keep one set of vectors (and their results bit for bit)
    same = np.abs(vb_red - v_red).max(axis=1, initial=0.0) <= BACK_LINE_RTOL * np.abs(
        v_red).max(axis=1, initial=0.0)
    vb_red[same] = v_red[same]
    back_red = None if same.all() else np.ascontiguousarray(vb_red)
    w_red = w_mesh @ tmat
    dof_names = tuple(coords.names[i] for i in kept)

    rotation_dofs: dict[str, int] = {}
    for b in gs.bodies:
        row = tmat[coords.get(b.name, "theta")]
        nz = np.flatnonzero(row)
        rotation_dofs[b.name] = int(nz[0]) if nz.size == 1 and row[nz[0]] == 1.0 else -1

    # ---- stiffness tables and damping ----------------------------------------------------------
    tables = np.array([m.stiffness.table(n_table) for m in gs.meshes]).reshape(n_mesh, n_table)
    back = np.array([(m.back_stiffness or m.stiffness).table(n_table)
                     for m in gs.meshes]).reshape(n_mesh, n_table)
    if (tables < 0).any() or (back < 0).any() or not np.isfinite(tables).all():
        raise ValueError("mesh stiffness tables must be finite and >= 0")
    damping = np.zeros(n_mesh)
    for k, m in enumerate(gs.meshes):
        if m.damping is not None:
            damping[k] = m.damping
        elif m.damping_ratio:
            r = resolved[m.name]
            inv = 0.0
            for g, rb in ((m.gear1, r.base_radius1), (m.gear2, r.base_radius2)):
                if g not in gs.fixed:
                    inv += rb**2 / bodies[g].inertia
            m_eq = 1.0 / inv if inv > 0 else math.inf
            damping[k] = 2.0 * m.damping_ratio * math.sqrt(m.stiffness.mean * m_eq)

    # ---- rigid-body kinematics -----------------------------------------------------------------
    # undeformed meshes and bearings, fixed members at rest, shafts turning as one piece;
    # torsional supports of the other members are drive/load stiffness and do not count, unless
    # the set would otherwise have several degrees of freedom: then members held by a torsional
    # support that are neither input nor output are the reaction members, at rest
    i_in = rotation_dofs[gs.input]
    if i_in < 0:
        raise ValueError(f"input member {gs.input!r} has no free rotation (it is held rigidly "
                         "or joined rigidly to a fixed member)")
    kin_rows = [v_mesh]
    if bearings:
        kin_rows.append(np.array([u for _, u, _, _ in bearings]))
    for f in gs.fixed:
        kin_rows.append(coords.unit(f, "theta")[None, :])
    for cp in gs.couplings:
        kin_rows.append((coords.unit(cp.body1, "theta") - coords.unit(cp.body2, "theta"))[None])
    null = _null_space(np.vstack(kin_rows) @ tmat)
    supported = [b.name for b in gs.bodies if b.role != "planet" and b.name not in gs.fixed
                 and 0 < b.support.torsional < math.inf]
    reaction = [b for b in supported if b not in (gs.input, gs.output)]
    held: list[str] = []
    if null.shape[1] > 1 and reaction:
        rows = [coords.unit(b, "theta")[None, :] for b in reaction]
        null_held = _null_space(np.vstack([*kin_rows, *rows]) @ tmat)
        if null_held.shape[1] == 0:
            raise ValueError(
                f"gear set {gs.name!r}: members {reaction} are held by torsional supports; "
                "with all of them at rest nothing can turn, so the kinematics (speeds, mesh "
                "frequency) are not defined: name the reaction member in operation.fixed (a "
                "fixed member with a finite torsional stiffness is held through it)"
            )
        null, held = null_held, reaction
    if null.shape[1] == 0:
        rigid_shafts = [f"{c.body1}-{c.body2}" for c in gs.couplings if math.isinf(c.stiffness)]
        raise ValueError(
            f"gear set {gs.name!r} is locked: with the meshes undeformed, fixed members "
            f"{list(gs.fixed)} at rest and the rigid couplings {rigid_shafts}, nothing can turn "
            "(too many members fixed or rigidly joined)"
        )
    if null.shape[1] > 1:
        free = [b.name for b in gs.bodies if b.role != "planet" and b.name not in gs.fixed
                and b.name not in held]
        raise ValueError(
            f"gear set {gs.name!r} has {null.shape[1]} rigid-body degrees of freedom with fixed "
            f"members {list(gs.fixed)}: {free} can turn independently (torsional supports "
            f"of the input and output, {[b for b in supported if b not in reaction]}, are "
            "drive/load stiffness and do not count); fix one more member (operation.fixed) or "
            "hold a reaction member by a torsional support"
        )
    mode = null[:, 0] / null[i_in, 0]
    ratios = {}
    full_mode = tmat @ mode
    for b in gs.bodies:
        ratios[b.name] = float(full_mode[coords.get(b.name, "theta")])
    for name in (*gs.fixed, *held):
        ratios[name] = 0.0  # exactly at rest (the null space gives it to rounding)

    # mesh frequency of every mesh per input speed, |z1 (n1 - n_c)| / 60 (paper eq. 5); NaN
    # without tooth numbers. Stages and planet toothings may differ (two-stage, Wolfrom).
    f_per_rpm = np.full(n_mesh, math.nan)
    for k, m in enumerate(gs.meshes):
        z1 = resolved[m.name].z1
        if z1 is not None:
            car = bodies[m.gear2].carrier
            assert car is not None  # gear2 is a planet
            f_per_rpm[k] = abs(z1 * (ratios[m.gear1] - ratios[car])) / 60.0

    bearing_vectors = (np.array([u for _, u, _, _ in bearings]) @ tmat if bearings
                       else np.zeros((0, len(kept))))
    # the carrier whose speed drives the gyroscopic terms: the first one that turns (a parallel
    # stage's housing is a carrier at rest)
    carriers = [b.name for b in gs.bodies if b.role == "carrier" and rotation_dofs[b.name] >= 0]
    meta = {
        "name": gs.name,
        "meshes": mesh_meta,
        "planets": [{"name": b.name, "carrier": b.carrier, "angle_deg": math.degrees(b.angle),
                     "radius": radius[b.name]} for b in gs.planets],
        "bodies": [{"name": b.name, "role": b.role} for b in gs.bodies],
        "config": gs.config,
    }
    if held:  # members at rest in the kinematics through their torsional supports
        meta["kinematics_at_rest"] = list(gs.fixed) + held
    model = AssembledModel(
        dof_names=dof_names,
        dof_units=tuple("rad" if d.endswith(".theta") else "m" for d in dof_names),
        mass=m_red,
        stiffness=k_red,
        damping=c_red,
        gyroscopic=reduce_matrix(gyro),
        centripetal=reduce_matrix(centripetal),
        mesh_names=tuple(m.name for m in gs.meshes),
        mesh_vectors=np.ascontiguousarray(v_red),
        mesh_back_vectors=back_red,
        mesh_position_vectors=np.ascontiguousarray(w_red),
        mesh_position_offsets=s0,
        mesh_stiffness_tables=np.ascontiguousarray(tables, dtype=float),
        mesh_back_tables=np.ascontiguousarray(back, dtype=float),
        mesh_backlash=np.array([m.backlash for m in gs.meshes], dtype=float),
        mesh_damping=damping,
        bearing_names=tuple(name for name, _, _, _ in bearings),
        bearing_vectors=np.ascontiguousarray(bearing_vectors),
        bearing_stiffness=np.array([k for _, _, k, _ in bearings], dtype=float),
        bearing_damping=np.array([c for _, _, _, c in bearings], dtype=float),
        rotation_dofs=rotation_dofs,
        carrier_dof=rotation_dofs[carriers[0]] if carriers else -1,
        input_member=gs.input,
        output_member=gs.output,
        fixed_members=tuple(gs.fixed),
        kinematic_ratios=ratios,
        mesh_frequencies_per_rpm=f_per_rpm,
        meta=meta,
        mesh_teeth=mesh_tooth_map(gs.meshes, bodies, resolved, s0, centre),
        mesh_damping_laws=tuple(m.damping_law for m in gs.meshes)
        if any(m.damping_law != "gated" for m in gs.meshes) else (),
    )
    if gs.faults:
        model = model.with_faults(gs.faults)
    if gs.sensors:
        model = model.with_sensors(gs.sensors)
    return model


def _still_frames(gs: GearSet, bodies: dict[str, Body]) -> set[str]:
    """Bodies whose coordinates are those of a stage with a held carrier (a parallel stage).

    A planet belongs to its carrier, a central gear to the carrier of the planets it meshes,
    a carrier to itself; such a body of a held carrier has its translations in a frame that
    does not turn, so it gets no gyroscopic or centripetal terms. (Bodies of another turning
    carrier keep them, with the speed of the first turning carrier, as before; a set in which
    no carrier turns keeps its matrices, which no run uses.)
    """
    frame: dict[str, str] = {}
    for b in gs.bodies:
        if b.role == "planet":
            frame[b.name] = str(b.carrier)
        elif b.role == "carrier":
            frame[b.name] = b.name
    for m in gs.meshes:
        if bodies[m.gear1].role == "central":
            frame.setdefault(m.gear1, str(bodies[m.gear2].carrier))
    if all(b.name in gs.fixed for b in gs.bodies if b.role == "carrier"):
        return set()  # no carrier turns: the terms are never used (a star set keeps its G)
    return {name for name, c in frame.items() if c in gs.fixed}


BACK_LINE_RTOL = 1e-12
"""Relative difference below which a back-flank deflection vector is taken as the left one's
(the difference is then rounding: no relative displacement along the line of centres)."""

PHASE_TOLERANCE = 2e-3
"""Largest mismatch [mesh cycles] between the two ways a mesh position follows from the
assembly (from the central gear and from the planet's teeth) before the set is refused; it
admits planet angles rounded to 1e-3 of the smallest assembly step."""


def _mesh_positions(gs: GearSet, resolved: dict[str, ResolvedMesh], bodies: dict[str, Body],
                    centre: dict[str, np.ndarray]) -> np.ndarray:
    """Mesh position of every contact in the reference configuration ``q = 0`` [cycles].

    Every gear has one orientation at assembly. A central gear is described by the constant
    ``c`` of ``s = -z psi / 2 pi + c`` (rotational symmetry: the mesh with a planet at ``psi``
    sees the gear turned by ``-psi``; one ``c`` per central gear and planet geometry), a planet
    by the direction of its reference tooth (:func:`gearvib.geometry.planet_tooth_angle`;
    further toothings of a stepped planet are turned by their ``tooth_offset``). The positions
    follow by propagation through the meshes, starting from ``c = 0`` for the first central gear
    (the paper's ``s0 = -z psi / 2 pi``) and again for any gear not reached through tooth
    geometry (lumped meshes). A mesh reached both ways must agree within
    :data:`PHASE_TOLERANCE`, otherwise the gears cannot be assembled there (ValueError naming
    the mesh). A mesh with a given ``phase`` keeps it; the propagation uses its derived value,
    so an override changes that mesh only.
    Meshes without tooth numbers get 0 (constant stiffness: the position does not matter).
    """
    meshes = gs.meshes
    n_mesh = len(meshes)
    s0 = np.zeros(n_mesh)
    done = np.zeros(n_mesh, dtype=bool)
    c: dict[tuple, float] = {}
    tooth: dict[str, float] = {}  # planet -> direction of its reference tooth [rad]
    ref_mesh: dict[str, int] = {}  # planet -> mesh its reference tooth came from

    def central_key(m: Mesh) -> tuple:
        r = resolved[m.name]
        g = r.geometry
        return (m.gear1, g.gear2 if g is not None else r.z2, round(r.centre_distance, 12))

    def planet_geometry(m: Mesh, planet: str):
        """(geometry, planet_is_gear1, mate direction, tooth offset) or None."""
        g = resolved[m.name].geometry
        if g is None:
            return None
        is1 = m.gear1 == planet
        toothing = g.gear1 if is1 else g.gear2
        if toothing.internal:
            return None
        mate = m.gear2 if is1 else m.gear1
        d = centre[mate] - centre[planet]
        offset = m.tooth_offset1 if is1 else m.tooth_offset2
        return g, is1, math.atan2(d[1], d[0]), offset

    def from_planet(k: int, planet: str) -> float | None:
        pg = planet_geometry(meshes[k], planet)
        if pg is None or planet not in tooth:
            return None
        g, is1, mate, offset = pg
        ref = ref_mesh[planet]
        if (meshes[k].gear1 != planet and bodies[meshes[ref].gear1].role == "central"
                and bodies[meshes[k].gear1].role == "central"):
            rel = _relative_phase(meshes[ref], meshes[k], resolved)
            if rel is not None:  # sun and ring on one planet toothing: the closed form
                return s0[ref] + rel
        return planet_mesh_position(g, planet_is_gear1=is1, mate_direction=mate,
                                    tooth_angle=tooth[planet] + offset)

    def set_planet(k: int, planet: str) -> None:
        pg = planet_geometry(meshes[k], planet)
        if pg is None or planet in tooth:
            return
        g, is1, mate, offset = pg
        tooth[planet] = planet_tooth_angle(g, planet_is_gear1=is1, mate_direction=mate,
                                           position=s0[k]) - offset
        ref_mesh[planet] = k

    def check(k: int, planet: str) -> None:
        other = from_planet(k, planet)
        if other is None or ref_mesh.get(planet) == k:
            return
        ref = meshes[ref_mesh[planet]]
        mismatch = abs((s0[k] - other + 0.5) % 1.0 - 0.5)
        pg, pr = planet_geometry(meshes[k], planet), planet_geometry(ref, planet)
        ref_toothing = pr[0].gear1 if pr[1] else pr[0].gear2
        if (pg[0].gear1 if pg[1] else pg[0].gear2) != ref_toothing:
            # another toothing of a stepped planet: the planet may be inserted turned by any
            # number of teeth of its reference toothing
            g, is1, mate, offset = pg
            for turn in range(1, abs(ref_toothing.z)):
                alt = planet_mesh_position(
                    g, planet_is_gear1=is1, mate_direction=mate,
                    tooth_angle=tooth[planet] + offset + 2 * math.pi * turn / ref_toothing.z)
                mismatch = min(mismatch, abs((s0[k] - alt + 0.5) % 1.0 - 0.5))
        if mismatch > PHASE_TOLERANCE:
            m = meshes[k]
            raise ValueError(
                f"mesh {m.name!r} cannot be assembled: the teeth of {planet!r} put it at mesh "
                f"position {other % 1.0:.4f} (from mesh {ref.name!r}), the other gear at "
                f"{s0[k] % 1.0:.4f} ({mismatch:.3g} cycles apart); identical planets do not fit "
                "at these angles with these tooth numbers"
            )

    def assign(k: int) -> bool:
        m = meshes[k]
        r = resolved[m.name]
        b1, b2 = bodies[m.gear1], bodies[m.gear2]
        if r.z1 is None or r.z2 is None:
            s0[k] = 0.0
            return True
        if b1.role == "central":
            key = central_key(m)
            if key in c:
                s0[k] = -r.z1 * b2.angle / (2 * math.pi)
                s0[k] += c[key]
                if b2.name in tooth:
                    check(k, b2.name)
                else:
                    set_planet(k, b2.name)
                return True
            value = from_planet(k, b2.name)
            if value is None:
                return False
            s0[k] = value
            c[key] = value + r.z1 * b2.angle / (2 * math.pi)
            return True
        # planet-planet mesh
        for known, other in ((b1.name, b2.name), (b2.name, b1.name)):
            value = from_planet(k, known)
            if value is not None:
                s0[k] = value
                if other in tooth:
                    check(k, other)
                else:
                    set_planet(k, other)
                return True
        return False

    while not done.all():
        progress = False
        for k in np.flatnonzero(~done).tolist():
            if assign(k):
                done[k] = progress = True
        if progress:
            continue
        # nothing follows from what is known: fix the orientation of the next gear
        k = int(np.flatnonzero(~done)[0])
        m = meshes[k]
        if bodies[m.gear1].role == "central":
            c[central_key(m)] = 0.0
        else:
            s0[k] = 0.0
            done[k] = True
            set_planet(k, m.gear1)
            set_planet(k, m.gear2)
    for k, m in enumerate(meshes):
        if m.phase is not None:
            s0[k] = m.phase
    return s0


def _relative_phase(ref: Mesh, mesh: Mesh, resolved: dict[str, ResolvedMesh]) -> float | None:
    """Closed-form mesh-position offset of ``mesh`` relative to ``ref`` at the same planet.

    Sun and ring meshing one planet toothing (:func:`gearvib.geometry.sun_ring_phase`); None
    for every other pair of meshes.
    """
    g_ref, g = resolved[ref.name].geometry, resolved[mesh.name].geometry
    if g_ref is None or g is None or g_ref.gear2 != g.gear2:
        return None
    if g_ref.gear1.z > 0 > g.gear1.z:
        return sun_ring_phase(g_ref, g)
    if g.gear1.z > 0 > g_ref.gear1.z:
        return -sun_ring_phase(g, g_ref)
    return None
