"""Parallel-axis stages and trains of stages, built from the paper's base structure.

A parallel-axis gear pair is the base structure of the paper (a central gear, a planet and the
carrier) with a carrier that stands still: the *housing*. The pinion is the central gear on the
main axis, the wheel the "planet" whose axis sits on the housing at the centre distance; an
internal pair (a ring-shaped wheel) has the wheel as the central gear and the pinion inside it;
an idler is a second planet of the housing between pinion and wheel (a planet-planet mesh, as
in a Ravigneaux set). So the parallel stage comes out of the same description, assembly,
kinematics (the Willis equation with the carrier at rest is the ratio ``-z_1/z_2`` of a gear
pair), mesh positions and phases as every planetary set; nothing in the dynamics is special.

:func:`multi_stage` joins stages of any kind (simple, Wolfrom, Ravigneaux, parallel) in series:
the output member of stage ``k`` drives the input member of stage ``k + 1`` through a torsional
shaft. Members are named by their stage, ``stage1.sun``, ``stage2.pinion``, ...

References
----------
Paper (``/work/shared/seed``): "Vibration Analysis for Planetary Gears. Modeling and Multibody
Simulation", section 2: one base structure for every planetary gearbox, signed tooth numbers
and centre distances; the parallel pair is the base structure with a fixed carrier.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

from gearvib.checks import check_count, check_instance, check_items, check_real, check_text, short
from gearvib.geometry import MAX_TEETH, Toothing, mesh_geometry
from gearvib.structure import (
    RIGID,
    BaseStructure,
    Body,
    Coupling,
    GearSet,
    Mesh,
    MeshSpec,
    Support,
    compose,
    prefixed,
)

__all__ = ["HOUSING", "multi_stage", "parallel_stage", "stage_prefix"]

HOUSING = "housing"
"""Default name of the fixed carrier (the gearbox housing) of a parallel stage."""
MAX_STAGES = 16
"""Most stages of a train."""


def stage_prefix(index: int) -> str:
    """The name prefix of stage ``index`` (1-based) in a :func:`multi_stage` train."""
    return f"stage{check_count(index, 'index', low=1)}."


def _mesh(name: str, g1: str, g2: str, t1: Toothing, t2: Toothing, spec: MeshSpec,
          centre_distance: float) -> Mesh:
    spec = spec.resolve(mesh_geometry(t1, t2, centre_distance))
    stiffness, back_stiffness = spec.models()
    return Mesh(name=name, gear1=g1, gear2=g2, stiffness=stiffness, toothing1=t1,
                toothing2=t2, back_stiffness=back_stiffness, backlash=spec.backlash,
                damping=spec.damping, damping_ratio=spec.damping_ratio,
                centre_distance=centre_distance)


def _on_housing(body: Body, housing: Body, x: float, y: float) -> Body:
    """``body`` as a gear on a fixed axis of the housing at ``(x, y)`` [m]."""
    if body.support.torsional or body.support.torsional_damping:
        raise ValueError(
            f"{body.name!r}: a torsional support is not admissible for a gear on a housing pin "
            "(it turns freely on its bearing); join a load or a brake by [[coupling]] to a "
            "[[body]] instead")
    return replace(body, role="planet", carrier=housing.name, angle=math.atan2(y, x),
                   radius=math.hypot(x, y))


def parallel_stage(*, z_pinion: int, z_wheel: int, module: float, pinion: Body, wheel: Body,
                   mesh: MeshSpec, housing: Body | None = None, z_idler: int | None = None,
                   idler: Body | None = None, idler_mesh: MeshSpec | None = None,
                   pressure_angle: float = math.radians(20.0), helix_angle: float = 0.0,
                   face_width: float = 0.02, profile_shift_pinion: float = 0.0,
                   profile_shift_wheel: float = 0.0, profile_shift_idler: float = 0.0,
                   centre_distance: float | None = None, axis_angle: float = 0.0,
                   idler_angle: float = 0.0, fixed: str = HOUSING, input: str = "pinion",
                   output: str = "wheel", name: str = "parallel",
                   config: dict | None = None) -> GearSet:
    """A parallel-axis gear stage: pinion and wheel (and optionally an idler) on fixed axes.

    Parameters
    ----------
    z_pinion : int
        Pinion tooth number (> 0, external).
    z_wheel : int
        Wheel tooth number, signed: ``> 0`` an external pair, ``< 0`` an internal wheel (a
        ring-shaped gear on a fixed axis; ``|z_wheel| > z_pinion``).
    module : float
        Normal module [m] of every gear of the stage.
    pinion, wheel, idler : Body
        Mass, inertia and bearing support of each gear (the role is set here). For a gear on a
        housing pin (the wheel and the idler of an external stage, the pinion of an internal
        one) ``radial`` is the bearing along the line from the main axis to its axis and
        ``tangential`` across it; its ``torsional`` support is not admissible.
    mesh : MeshSpec
        The pinion's mesh (with the wheel, or with the idler).
    housing : Body, optional
        The fixed carrier; default a housing held rigidly (mass and inertia then do not
        matter).
    z_idler : int, optional
        Idler tooth number (> 0) between pinion and wheel (external pairs only).
    idler_mesh : MeshSpec, optional
        The idler-wheel mesh (default ``mesh``).
    pressure_angle, helix_angle, face_width : float
        Normal pressure angle [rad], helix angle of the pinion [rad] (> 0 right hand; an
        external mate gets the opposite hand, an internal wheel the pinion's) and face width
        [m].
    profile_shift_pinion, profile_shift_wheel, profile_shift_idler : float
        Profile-shift coefficients (DIN 3960 signs).
    centre_distance : float, optional
        Operating centre distance of a pair without idler [m] (default: zero backlash from the
        profile shifts; a larger one adds backlash through the geometry).
    axis_angle : float
        Direction of the second axis seen from the main axis [rad] (the wheel's, the idler's,
        or the pinion's inside an internal wheel): where the mesh sits on the housing, which a
        housing sensor's window weighs.
    idler_angle : float
        With an idler: the direction of the wheel axis seen from the idler axis, relative to
        the direction pinion -> idler [rad] (0: the three axes in line).
    fixed, input, output : str
        Operating roles (default housing held, pinion in, wheel out; a speed-increasing stage
        has ``input = "wheel"``, ``output = "pinion"``).
    name : str
        Name of the gear set.
    config : dict, optional
        The description (provenance).

    Returns
    -------
    GearSet
        Bodies ``pinion``, ``wheel`` (``idler``) and the housing; meshes named central gear
        first: ``pinion-wheel`` (external pair), ``wheel-pinion`` (internal wheel),
        ``pinion-idler`` and ``idler-wheel``.

    Raises
    ------
    ValueError
        Inadmissible tooth numbers, an idler with an internal wheel, tooth geometry that does
        not mesh (:func:`gearvib.geometry.mesh_geometry`), a wheel that would touch the pinion
        through a bent idler arrangement, a torsional support on a gear on a housing pin.

    Notes
    -----
    Speed ratio: with the carrier at rest the Willis equation of each base structure,
    ``z_1 (n_1 - n_c) = -z_2 (n_2 - n_c)``, gives ``n_wheel / n_pinion = -z_pinion / z_wheel``
    (signed ``z_wheel``: an internal wheel turns with the pinion); an idler reverses the sense
    once more and leaves the magnitude. Mesh frequency ``f = z_pinion |n_pinion| / 60``.
    """
    for key, part in (("pinion", pinion), ("wheel", wheel)):
        check_instance(part, Body, key)
    for key, optional in (("housing", housing), ("idler", idler)):
        if optional is not None:
            check_instance(optional, Body, key)
    check_instance(mesh, MeshSpec, "mesh")
    if idler_mesh is not None:
        check_instance(idler_mesh, MeshSpec, "idler_mesh")
    for key, text in (("fixed", fixed), ("input", input), ("output", output), ("name", name)):
        check_text(text, key, empty=key == "fixed")
    if config is not None:
        check_instance(config, dict, "config")
    check_count(z_pinion, "z_pinion", low=1, high=MAX_TEETH)
    check_count(z_wheel, "z_wheel", low=-MAX_TEETH, high=MAX_TEETH)
    check_count(z_idler, "z_idler", low=1, high=MAX_TEETH, optional=True)
    if z_wheel == 0:
        raise ValueError("z_wheel = 0 is not admissible (admissible: a non-zero integer, "
                         "negative for an internal wheel)")
    if z_wheel < 0 and -z_wheel <= z_pinion:
        raise ValueError(f"z_wheel = {z_wheel} is not admissible with z_pinion = {z_pinion}: an "
                         f"internal wheel needs more teeth than its pinion (|z_wheel| > "
                         f"{z_pinion})")
    for label, v in (("axis_angle", axis_angle), ("idler_angle", idler_angle)):
        check_real(v, label, low=-1e9, high=1e9)
    if housing is None:
        housing = Body(HOUSING, "carrier", 1.0, 1.0, Support())
    housing = replace(housing, role="carrier")
    common = dict(module=module, pressure_angle=pressure_angle, face_width=face_width)
    h = helix_angle
    t_p = Toothing(z=z_pinion, helix_angle=h, profile_shift=profile_shift_pinion, **common)
    # an external mate has the opposite hand, an internal gear the hand of its pinion
    t_w = Toothing(z=z_wheel, helix_angle=h if z_wheel < 0 else -h,
                   profile_shift=profile_shift_wheel, **common)
    e = (math.cos(axis_angle), math.sin(axis_angle))
    if z_idler is None:
        if idler is not None or idler_mesh is not None:
            raise ValueError("an idler body or idler mesh needs z_idler")
        if z_wheel > 0:
            a = mesh_geometry(t_p, t_w, centre_distance).centre_distance
            p_b = replace(pinion, role="central")
            w_b = _on_housing(wheel, housing, a * e[0], a * e[1])
            bs = BaseStructure(p_b, w_b, housing, _mesh(f"{p_b.name}-{w_b.name}", p_b.name,
                                                        w_b.name, t_p, t_w, mesh, a))
        else:
            a = mesh_geometry(t_w, t_p, centre_distance).centre_distance
            w_b = replace(wheel, role="central")
            p_b = _on_housing(pinion, housing, a * e[0], a * e[1])
            bs = BaseStructure(w_b, p_b, housing, _mesh(f"{w_b.name}-{p_b.name}", w_b.name,
                                                        p_b.name, t_w, t_p, mesh, a))
        return compose(name, [bs], fixed=(fixed,) if fixed else (), input=input,
                       output=output, config=config)
    if z_wheel < 0:
        raise ValueError("an idler is admissible between external gears only (z_wheel > 0)")
    if idler is None:
        raise ValueError("z_idler needs the idler's body (mass, inertia, support)")
    if centre_distance is not None:
        raise ValueError("centre_distance applies to a pair without idler (with an idler both "
                         "meshes run at their zero-backlash centre distances)")
    t_i = Toothing(z=z_idler, helix_angle=-h, profile_shift=profile_shift_idler, **common)
    t_w = replace(t_w, helix_angle=h)  # the wheel meshes the idler: the pinion's hand
    a1 = mesh_geometry(t_p, t_i).centre_distance
    a2 = mesh_geometry(t_i, t_w).centre_distance
    xi, yi = a1 * e[0], a1 * e[1]
    d = axis_angle + idler_angle
    xw, yw = xi + a2 * math.cos(d), yi + a2 * math.sin(d)
    gap = math.hypot(xw, yw) - t_p.tip_radius - t_w.tip_radius
    if gap <= 0.0:
        raise ValueError(
            f"the wheel would touch the pinion: centre distance {math.hypot(xw, yw) * 1e3:.3f} "
            f"mm, tip radii {t_p.tip_radius * 1e3:.3f} + {t_w.tip_radius * 1e3:.3f} mm "
            f"(clearance {gap * 1e3:.3f} mm, must be > 0); use an idler_angle closer to 0")
    p_b = replace(pinion, role="central")
    i_b = _on_housing(idler, housing, xi, yi)
    w_b = _on_housing(wheel, housing, xw, yw)
    bs = BaseStructure(p_b, i_b, housing, _mesh(f"{p_b.name}-{i_b.name}", p_b.name, i_b.name,
                                                t_p, t_i, mesh, a1))
    iw = _mesh(f"{i_b.name}-{w_b.name}", i_b.name, w_b.name, t_i, t_w,
               idler_mesh if idler_mesh is not None else mesh, a2)
    return compose(name, [bs], extra_meshes=[iw], extra_bodies=[w_b],
                   fixed=(fixed,) if fixed else (), input=input, output=output, config=config)


def multi_stage(stages: Sequence[GearSet], *,
                shafts: Sequence[tuple[float, float]] | None = None,
                prefixes: Sequence[str] | None = None, name: str = "multi-stage",
                config: dict | None = None) -> GearSet:
    """Stages in series: the output member of stage ``k`` drives the input of stage ``k + 1``.

    Parameters
    ----------
    stages : sequence of GearSet
        Two or more stages of any kind (planetary, parallel), each with its own fixed members
        and operating roles.
    shafts : sequence of (stiffness, damping), optional
        The torsional shaft after every stage but the last [N m/rad, N m s/rad]; default rigid
        (:data:`gearvib.structure.RIGID`) and undamped.
    prefixes : sequence of str, optional
        Name prefixes of the stages (default ``stage1.``, ``stage2.``, ...).
    name : str
        Name of the train.
    config : dict, optional
        The description (provenance).

    Returns
    -------
    GearSet
        Every body and mesh renamed with its stage's prefix (``stage2.pinion``,
        ``stage1.sun-planet1``), the stages' own couplings, then the shafts; input is the first
        stage's input, output the last stage's output, fixed every stage's fixed members.

    Raises
    ------
    ValueError
        Fewer than two stages, prefixes or shafts of the wrong number, repeated prefixes.
    """
    stages = list(check_items(stages, GearSet, "stages"))
    if not 2 <= len(stages) <= MAX_STAGES:
        raise ValueError(f"a train needs at least two stages (and at most {MAX_STAGES}), got "
                         f"{len(stages)}")
    n = len(stages)
    check_text(name, "name")
    if config is not None:
        check_instance(config, dict, "config")
    if prefixes is None:
        prefixes = [stage_prefix(k + 1) for k in range(n)]
    prefixes = list(check_items(prefixes, str, "prefixes"))
    if len(prefixes) != n or len(set(prefixes)) != n:
        raise ValueError(f"prefixes: {n} distinct names needed, got {short(prefixes)}")
    if shafts is None:
        shafts = [(RIGID, 0.0)] * (n - 1)
    shafts = list(check_items(shafts, (tuple, list), "shafts"))
    if len(shafts) != n - 1:
        raise ValueError(f"shafts: {n - 1} shafts join {n} stages, got {len(shafts)}")
    if any(len(s) != 2 for s in shafts):
        raise ValueError("shafts: every shaft is a pair (stiffness, damping)")
    bodies: list[Body] = []
    meshes: list[Mesh] = []
    fixed: list[str] = []
    own: list[Coupling] = []
    for prefix, stage in zip(prefixes, stages, strict=True):
        b, m = prefixed(stage, prefix)
        bodies += b
        meshes += m
        fixed += [f"{prefix}{f}" for f in stage.fixed]
        own += [replace(c, body1=f"{prefix}{c.body1}", body2=f"{prefix}{c.body2}")
                for c in stage.couplings]
    joints = [Coupling(f"{prefixes[k]}{stages[k].output}", f"{prefixes[k + 1]}"
                       f"{stages[k + 1].input}", k_s, c_s)
              for k, (k_s, c_s) in enumerate(shafts)]
    return GearSet(name=name, bodies=tuple(bodies), meshes=tuple(meshes), fixed=tuple(fixed),
                   input=f"{prefixes[0]}{stages[0].input}",
                   output=f"{prefixes[-1]}{stages[-1].output}", couplings=(*own, *joints),
                   config=dict(config or {}))
