"""Ravigneaux, Wolfrom and two-stage sets: assembly conditions, mesh phases, speed ratios."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.geometry import Toothing
from gearvib.stiffness import ConstantStiffness
from gearvib.structure import Body, MeshSpec, Support, ravigneaux, wolfrom

SPEC = MeshSpec(ConstantStiffness(3e8))


def _central(name: str) -> Body:
    return Body(name, "central", 2.0, 1e-2, Support())


def ravigneaux_set(z_s1=30, z_s2=36, z_r=-84, z_ps=18, z_pl=24, n_pairs=3, elastic=False,
                   **kw):
    """Ravigneaux builder set (module 2 mm); ``elastic`` planet bearings expose the lines of
    action in the mesh vectors."""
    sup = Support(radial=1e8, tangential=1e8) if elastic else Support()
    car = Body("carrier", "carrier", 3.0, 2e-2, Support())
    ps = Body("short", "planet", 0.3, 1e-4, sup, carrier="carrier")
    pl = Body("long", "planet", 0.5, 2e-4, sup, carrier="carrier")
    return ravigneaux(z_sun_small=z_s1, z_sun_large=z_s2, z_ring=z_r, z_planet_short=z_ps,
                      z_planet_long=z_pl, module=2e-3, n_pairs=n_pairs,
                      sun_small=_central("sun_small"), sun_large=_central("sun_large"),
                      ring=_central("ring"), carrier=car, planet_short=ps, planet_long=pl,
                      sun_mesh=SPEC, ring_mesh=SPEC, planet_mesh=SPEC, **kw)


def wolfrom_set(z_s=18, z_r1=-72, z_r2=-69, z_p1=27, z_p2=24, n=3, **kw):
    """Wolfrom builder set; ``module2`` keeps both steps on one centre distance."""
    car = Body("carrier", "carrier", 3.0, 2e-2, Support())
    pl = Body("planet", "planet", 0.5, 2e-4, Support(), carrier="carrier")
    kw.setdefault("module2", 2e-3 * (z_r1 + z_p1) / (z_r2 + z_p2))
    return wolfrom(z_sun=z_s, z_ring1=z_r1, z_ring2=z_r2, z_planet1=z_p1, z_planet2=z_p2,
                   module=2e-3, n_planets=n, sun=_central("sun"), ring1=_central("ring1"),
                   ring2=_central("ring2"), carrier=car, planet=pl, sun_mesh=SPEC,
                   ring_mesh=SPEC, **kw)


# --------------------------------------------------------------------------- assembly checks


def test_ravigneaux_assembly_conditions(monkeypatch):
    """Hand derivation (tooth phases at the contacts, pair n = pair 1 turned by dpsi): the long
    planet between large sun and ring needs (z_s2 + |z_r|) dpsi / 2 pi integer; going round
    small sun -> short planet -> long planet -> large sun, the two planet spins must agree,
    which needs (z_s1 + z_s2) dpsi / 2 pi integer."""
    assemble(ravigneaux_set())  # 66/3, 120/3
    with pytest.raises(ValueError, match=r"\(z_sun_small \+ z_sun_large\)/n_pairs = 67/3"):
        ravigneaux_set(z_s1=31)
    with pytest.raises(ValueError, match=r"z_sun_large \+ \|z_ring\|\)/n_pairs = 121/3"):
        ravigneaux_set(z_r=-85, z_pl=24)
    # the tooth-by-tooth assembly (builder check switched off) agrees with the condition,
    # also where (z_s1 - z_s2) / N would say the opposite: with 4 pairs z_s1 = 29 fits
    # (68/4; -10/4) and z_s1 = 31 does not (70/4; -8/4); a set whose four pairs fit on the
    # carrier (tip circles clear)
    import gearvib.structure as st

    monkeypatch.setattr(st, "check_ravigneaux_pairs", lambda *a: None)
    assemble(ravigneaux_set(z_s1=29, z_s2=39, z_r=-85, z_pl=23, n_pairs=4))
    with pytest.raises(ValueError, match=r"mesh 'sun_large-long2' cannot be assembled"):
        assemble(ravigneaux_set(z_s1=31, z_s2=39, z_r=-85, z_pl=23, n_pairs=4))


@pytest.mark.parametrize(
    ("z_s", "z_r1", "z_r2", "z_p1", "z_p2", "n"),
    [(18, -72, -69, 27, 24, 3), (18, -72, -70, 27, 24, 3), (16, -68, -64, 26, 22, 4),
     (16, -68, -67, 26, 25, 4), (16, -68, -69, 26, 25, 4), (16, -68, -66, 26, 24, 4)],
)
def test_wolfrom_stepped_planet_condition_matches_tooth_assembly(z_s, z_r1, z_r2, z_p1, z_p2, n,
                                                                 monkeypatch):
    """(z_s z_p2 + |z_r2| z_p1) / (N gcd(z_p1, z_p2)) integer <=> identical stepped planets fit
    (checked against the tooth-by-tooth propagation of the assembly, builder check bypassed)."""
    g = math.gcd(z_p1, z_p2)
    fits = (z_s * z_p2 - z_r2 * z_p1) % (n * g) == 0
    if fits:
        assemble(wolfrom_set(z_s, z_r1, z_r2, z_p1, z_p2, n))
    else:
        with pytest.raises(ValueError, match=r"identical stepped planets cannot be assembled"):
            wolfrom_set(z_s, z_r1, z_r2, z_p1, z_p2, n)
    # the assembly's own geometric check, without the builder's closed form
    import gearvib.structure as st

    monkeypatch.setattr(st, "check_stepped_planet_angles", lambda *a, **k: None)
    gs = wolfrom_set(z_s, z_r1, z_r2, z_p1, z_p2, n)
    if fits:
        assemble(gs)
    else:
        with pytest.raises(ValueError, match=r"mesh 'ring2-planet\d' cannot be assembled"):
            assemble(gs)


# --------------------------------------------------------------------------- mesh phases


def _flank_positions(model, gs, mesh_name: str, planet: str, tooth_angle: float) -> np.ndarray:
    """Mesh positions [cycles] of the planet's flank crossings with the mesh's line of action.

    Independent of :mod:`gearvib.geometry`'s involute bookkeeping: the line is read from the
    assembled mesh vector (elastic planet bearings: ``n`` from the zeta/eta entries, the moment
    arm from the rotation entry: ``X x n = v_theta``); the planet's flanks are polylines from the
    DIN tooth-thickness half angle at every radius; a contact is a crossing where the flank
    normal lies along the line. ``u`` is measured from the foot of gear2's centre towards the
    pitch point (where the line cuts the line of centres), and
    ``s = forward (u - path_start) / p_bt``.
    """
    k = model.mesh_names.index(mesh_name)
    mesh = next(m for m in gs.meshes if m.name == mesh_name)
    g = mesh.geometry
    body = gs.body(planet)
    v = model.mesh_vectors[k]
    idx = {name: i for i, name in enumerate(model.dof_names)}
    e_r = np.array([math.cos(body.angle), math.sin(body.angle)])
    e_t = np.array([-e_r[1], e_r[0]])
    n_vec = v[idx[f"{planet}.zeta"]] * e_r + v[idx[f"{planet}.eta"]] * e_t
    arm = v[idx[f"{planet}.theta"]]
    scale = np.hypot(*n_vec)
    n_vec, arm = n_vec / scale, arm / scale
    centres = {b.name: (np.zeros(2) if b.role != "planet" else
                        body_radius(model, b.name) * np.array([math.cos(b.angle),
                                                               math.sin(b.angle)]))
               for b in gs.bodies}
    cp = centres[planet]
    toothing = g.gear1 if mesh.gear1 == planet else g.gear2
    rb = abs(toothing.base_radius)
    assert abs(arm) == pytest.approx(rb, rel=1e-9)  # the line is tangent to the base circle
    r = np.linspace(rb * (1 + 1e-12), toothing.tip_radius, 2001)
    psi = np.array([toothing.thickness_half_angle(x) for x in r])
    foot = arm * np.array([n_vec[1], -n_vec[0]])  # the planet's foot, relative to its centre
    found = []
    for tooth in range(toothing.z):
        gam = tooth_angle + 2 * math.pi * tooth / toothing.z
        if math.cos(gam - math.atan2(foot[1], foot[0])) < 0.0:
            continue  # a tooth on the far side cannot reach the line near the foot
        for sgn in (1.0, -1.0):
            ang = gam + sgn * psi
            pts = cp + r[:, None] * np.stack([np.cos(ang), np.sin(ang)], axis=1)
            rel = pts - cp
            dist = rel[:, 0] * n_vec[1] - rel[:, 1] * n_vec[0] - arm
            for i in np.flatnonzero(np.sign(dist[:-1]) * np.sign(dist[1:]) < 0):
                w = dist[i] / (dist[i] - dist[i + 1])
                x = pts[i] + w * (pts[i + 1] - pts[i])
                tangent = (pts[i + 1] - pts[i]) / np.hypot(*(pts[i + 1] - pts[i]))
                if abs(tangent @ n_vec) < 1e-3:  # flank normal along the line of action
                    found.append(x)
    c2, c1 = centres[mesh.gear2], centres[mesh.gear1]
    # the planet's foot on the line, gear2's foot, and the pitch point (the line cuts the line
    # of centres there)
    p0 = cp + arm * np.array([n_vec[1], -n_vec[0]])
    foot2 = p0 + ((c2 - p0) @ n_vec) * n_vec
    t_pitch = np.linalg.solve(np.column_stack([n_vec, -(c2 - c1)]), c1 - p0)[0]
    pitch = p0 + t_pitch * n_vec
    # the flanks of the other side generate the line beyond the foot: keep the contact side
    found = [x for x in found if (x - p0) @ (pitch - p0) > 0]
    direction = (pitch - foot2) / np.hypot(*(pitch - foot2))
    u = np.array([(x - foot2) @ direction for x in found])
    assert np.hypot(*(pitch - foot2)) == pytest.approx(g.pitch_point, rel=1e-9)
    s = (g.forward_direction * (u - g.path_start) / g.base_pitch) % 1.0
    return s


def body_radius(model, planet: str) -> float:
    return next(p["radius"] for p in model.meta["planets"] if p["name"] == planet)


def _circular_spread(s: np.ndarray) -> float:
    return float(np.abs((s - s[0] + 0.5) % 1.0 - 0.5).max())


def _tooth_angle_for(model, gs, mesh_name: str, planet: str, position: float) -> float:
    """Planet tooth direction at which the brute-force position of ``mesh_name`` is ``position``
    (bisection over one tooth pitch on a fine scan)."""
    mesh = next(m for m in gs.meshes if m.name == mesh_name)
    z = abs(mesh.geometry.gear2.z if mesh.gear2 == planet else mesh.geometry.gear1.z)

    def err(angle: float) -> float:
        s = _flank_positions(model, gs, mesh_name, planet, angle)
        return (s[0] - position + 0.5) % 1.0 - 0.5

    grid = np.linspace(0.0, 2 * math.pi / z, 25)
    e = [err(a) for a in grid]
    for a0, a1, e0, e1 in zip(grid[:-1], grid[1:], e[:-1], e[1:], strict=True):
        if e0 == 0.0:
            return a0
        if e0 * e1 < 0 and abs(e0 - e1) < 0.5:  # a true zero, not the wrap-around
            for _ in range(50):
                am = 0.5 * (a0 + a1)
                em = err(am)
                if em * e0 <= 0:
                    a1 = am
                else:
                    a0, e0 = am, em
            return 0.5 * (a0 + a1)
    raise AssertionError("no tooth direction found")


def test_planet_planet_phases_against_tooth_profiles():
    """Within a pair: from the small-sun mesh position of the assembly, find the short planet's
    tooth direction on its real flanks, predict the short-long mesh from the same flanks; from
    that, the long planet's direction and its large-sun and ring meshes. Between pairs (hand
    derivation): pair n is pair 1 turned by dpsi; with the small sun kept, the short planet rolls
    back by z_s1 dpsi / z_ps, and the planet-planet position (which runs backwards in the
    forward motion, gear1 = short planet) grows by z_s1 dpsi / 2 pi: with 4 pairs at 90 deg and
    z_s1 = 29, +7.25 = +0.25 cycles per pair."""
    gs = ravigneaux_set(z_s1=29, z_s2=39, z_r=-85, z_pl=23, n_pairs=4, elastic=True)
    model = assemble(gs)
    s0 = dict(zip(model.mesh_names, model.mesh_position_offsets, strict=True))
    gamma_s = _tooth_angle_for(model, gs, "sun_small-short1", "short1", s0["sun_small-short1"])
    assert _circular_spread(np.array([*_flank_positions(model, gs, "sun_small-short1", "short1",
                                                        gamma_s), s0["sun_small-short1"]])) < 1e-6
    pp = _flank_positions(model, gs, "short1-long1", "short1", gamma_s)
    assert _circular_spread(np.append(pp, s0["short1-long1"])) < 1e-6
    gamma_l = _tooth_angle_for(model, gs, "short1-long1", "long1", s0["short1-long1"])
    for mesh in ("sun_large-long1", "ring-long1"):
        got = _flank_positions(model, gs, mesh, "long1", gamma_l)
        assert _circular_spread(np.append(got, s0[mesh])) < 1e-6, mesh
    # between pairs
    for i in range(2, 5):
        dpsi = math.pi / 2 * (i - 1)
        expected = (s0["short1-long1"] + 29 * dpsi / (2 * math.pi)) % 1.0
        assert (s0[f"short{i}-long{i}"] - expected + 0.5) % 1.0 - 0.5 == pytest.approx(0.0,
                                                                                   abs=1e-9)
        assert (s0[f"short{i}-long{i}"] - s0["short1-long1"]) % 1.0 == pytest.approx(
            0.25 * (i - 1) % 1.0, abs=1e-9)
    # a user phase overrides the derived one and leaves the others alone
    user = assemble(ravigneaux_set(z_s1=29, z_s2=39, z_r=-85, z_pl=23, n_pairs=4,
                                   planet_mesh_phases=[0.1, 0.2, 0.3, 0.4]))
    s1 = dict(zip(user.mesh_names, user.mesh_position_offsets, strict=True))
    assert [s1[f"short{i}-long{i}"] for i in range(1, 5)] == pytest.approx([0.1, 0.2, 0.3, 0.4])
    assert s1["ring-long3"] == pytest.approx(s0["ring-long3"], abs=1e-12)


def test_wolfrom_step_offset_turns_the_ring2_phases():
    """Turning the second toothing by w against the first moves every ring-2 contact by
    -z_p2 w / 2 pi (the planet is gear2: its mesh position falls as it turns forward) and
    leaves the sun and ring-1 contacts alone."""
    base = assemble(wolfrom_set())
    w = math.radians(2.0)
    turned = assemble(wolfrom_set(step_offset=w))
    for name, a, b in zip(base.mesh_names, base.mesh_position_offsets,
                          turned.mesh_position_offsets, strict=True):
        shift = -24 * w / (2 * math.pi) if name.startswith("ring2") else 0.0
        assert (b - a - shift + 0.5) % 1.0 - 0.5 == pytest.approx(0.0, abs=1e-9), name


# --------------------------------------------------------------------------- helical gears


def test_helical_axial_force_balance():
    """Right-hand sun (beta = 15 deg), ring with the planet's hand, axial bearings everywhere.
    Statics under T_s = 100 N m: every planet's two meshes push it axially by equal and
    opposite amounts (net ~0, so its axial bearing and the carrier's carry ~0); the sun takes
    N F_t tan(beta_w) = T_s tan(beta_b) / r_bs towards +z (the thrust of a right-hand driver
    points along its rotation vector), the ring as much towards -z."""
    from gearvib.simulate import SpeedRamp, prepare_run, static_equilibrium
    from gearvib.structure import simple_planetary

    beta = math.radians(15.0)
    ax = Support(radial=1e9, axial=5e8)
    sun = Body("sun", "central", 1.0, 1e-3, ax)
    ring = Body("ring", "central", 4.0, 0.1, ax)
    car = Body("carrier", "carrier", 3.0, 2e-2, ax)
    pl = Body("planet", "planet", 0.5, 2e-4, Support(radial=1e9, tangential=1e9, axial=3e8),
              carrier="carrier")
    gs = simple_planetary(z_sun=21, z_ring=-75, z_planet=27, module=2e-3, sun=sun, ring=ring,
                          carrier=car, planet=pl, sun_mesh=SPEC, ring_mesh=SPEC, n_planets=3,
                          helix_angle=beta)
    sun_t, ring_t = gs.meshes[0].toothing1, gs.meshes[3].toothing1
    planet_t = gs.meshes[0].toothing2
    assert sun_t.helix_angle > 0 and planet_t.helix_angle < 0 and ring_t.helix_angle < 0
    model = assemble(gs)
    torque = 100.0
    setup = prepare_run(model, SpeedRamp(0.0, 0.0, 1.0, input_torque=torque), False)
    q0, _ = static_equilibrium(setup.system, setup.mass, setup.rigid, np.zeros(model.n_dof))
    bv = model.bearing_vectors
    force = dict(zip(model.bearing_names, model.bearing_stiffness * (bv @ q0), strict=True))
    beta_b = gs.meshes[0].geometry.base_helix_angle
    g = gs.meshes[0].geometry
    f_t = torque / (3 * g.working_pitch_radius2 * 21 / 27)  # at the sun's working pitch circle
    tan_bw = math.tan(beta_b) / math.cos(g.working_pressure_angle)
    expected = 3 * f_t * tan_bw
    assert expected == pytest.approx(torque * math.tan(beta_b) / abs(sun_t.base_radius),
                                     rel=1e-9)
    assert force["sun.axial"] == pytest.approx(expected, rel=1e-6)
    assert force["ring.axial"] == pytest.approx(-expected, rel=1e-6)
    for name in ("planet1.axial", "planet2.axial", "planet3.axial", "carrier.axial"):
        assert abs(force[name]) < 1e-6 * expected, (name, force[name])
    # each planet: the two meshes' axial forces are equal and opposite (about 1/3 each)
    k_mesh = 3e8
    d = model.mesh_vectors @ q0
    iz = model.dof_names.index("planet1.z")
    f_sun, f_ring = k_mesh * d[0] * model.mesh_vectors[0, iz], k_mesh * d[3] * \
        model.mesh_vectors[3, iz]
    assert f_sun == pytest.approx(-f_ring, rel=1e-6)
    assert abs(f_sun) == pytest.approx(expected / 3, rel=1e-6)
    # mismatched hands are refused
    from gearvib.geometry import mesh_geometry

    with pytest.raises(ValueError, match="helix hands do not mesh"):  # ring with the sun's hand
        mesh_geometry(Toothing(-75, 2e-3, helix_angle=beta), planet_t)
    with pytest.raises(ValueError, match="helix hands do not mesh"):
        mesh_geometry(sun_t, Toothing(27, 2e-3, helix_angle=beta))


# --------------------------------------------------------------------------- presets


def preset_model(name: str):
    from gearvib.config import load_gearset

    return assemble(load_gearset(name))


def test_speed_ratios_against_willis():
    """Willis (z_i (n_i - n_c) = -z_p (n_p - n_c) per mesh, signed z), worked by hand."""
    # Ravigneaux, small sun in (1), large sun held: the long planet rolls on the held large sun,
    # n_pl - n_c = (z_s2 / z_pl) n_c; the chain small sun -> short -> long gives
    # n_pl - n_c = (z_s1 / z_pl)(n_s1 - n_c); so n_c = z_s1 / (z_s1 + z_s2) = 30/66 and the ring
    # (internal, same sense as the long planet): n_r - n_c = (z_pl / |z_r|)(n_pl - n_c).
    r = preset_model("ravigneaux-example").kinematic_ratios
    n_c = 30 / 66
    assert r["carrier"] == pytest.approx(n_c, rel=1e-12)
    assert r["planet_short1"] == pytest.approx(n_c - (30 / 18) * (1 - n_c), rel=1e-12)
    assert r["planet_long2"] == pytest.approx(n_c + (36 / 24) * n_c, rel=1e-12)
    assert r["ring"] == pytest.approx(n_c * (1 + 36 / 84), rel=1e-12)
    assert 1 / r["ring"] == pytest.approx(1.54, abs=5e-3)
    # Wolfrom, ring 1 held: n_c = z_s / (z_s + |z_r1|) = 0.2; stepped planet
    # n_p - n_c = -(z_s / z_p1)(1 - n_c); ring 2: n_r2 - n_c = (z_p2 / |z_r2|)(n_p - n_c)
    r = preset_model("wolfrom-example").kinematic_ratios
    n_c = 18 / 90
    n_p = n_c - (18 / 27) * (1 - n_c)
    assert r["carrier"] == pytest.approx(n_c, rel=1e-12)
    assert r["planet3"] == pytest.approx(n_p, rel=1e-12)
    assert r["ring2"] == pytest.approx(n_c + (24 / 69) * (n_p - n_c), rel=1e-9)
    assert 1 / r["ring2"] == pytest.approx(69.0, rel=1e-9)
    # two stages: each z_s / (z_s + |z_r|), the product at the output
    r = preset_model("two-stage-example").kinematic_ratios
    i1, i2 = 21 / 96, 24 / 102
    assert r["s1.carrier"] == pytest.approx(i1, rel=1e-12)
    assert r["s2.sun"] == pytest.approx(i1, rel=1e-12)
    assert r["s2.planet1"] == pytest.approx(i1 * (i2 - (24 / 27) * (1 - i2)), rel=1e-9)
    assert r["s2.carrier"] == pytest.approx(i1 * i2, rel=1e-12)


def _static_forces(model, torque):
    """Left and right flank forces of the static equilibrium at constant speed."""
    from gearvib.simulate import SpeedRamp, prepare_run, static_equilibrium

    setup = prepare_run(model, SpeedRamp(300.0, 300.0, 0.01, input_torque=torque), False)
    sy = setup.system
    q0, _ = static_equilibrium(sy, setup.mass, setup.rigid, setup.rigid * setup.omega0,
                               mesh_names=model.mesh_names)
    d = sy.mesh_vectors @ q0
    pos = sy.mesh_position_offsets + sy.mesh_position_vectors @ q0
    kl, kr = model.mesh_stiffness_at(pos), model.mesh_stiffness_at(pos, back=True)
    j = sy.backlash
    return (dict(zip(model.mesh_names, kl * np.maximum(d - j / 2, 0.0), strict=True)),
            dict(zip(model.mesh_names, kr * np.maximum(-d - j / 2, 0.0), strict=True)))


def _base_radius(model, mesh: str, which: int) -> float:
    m = next(x for x in model.meta["meshes"] if x["name"] == mesh)
    return abs(m[f"base_radius{which}"])


@pytest.mark.parametrize("torque", [1.5, 150.0])
def test_ravigneaux_statics_by_hand(torque):
    """Light (1 %) and heavy (the preset's 150 N m) load, positive backlash. Small-sun meshes
    T/(3 r_bs1); short planet torque balance: the planet-planet mesh carries the same force
    (on its right flank: the short planet drives the long one backwards in the mesh's own
    convention); ring meshes from the ring torque T / i, i = 1 / 0.6494; large-sun meshes from
    the remaining torque."""
    model = preset_model("ravigneaux-example")
    assert np.all(model.mesh_backlash > 0)
    left, right = _static_forces(model, torque)
    f_s1 = torque / (3 * _base_radius(model, "sun_small-planet_short1", 1))
    t_ring = torque / model.kinematic_ratios["ring"]
    f_r = t_ring / (3 * _base_radius(model, "ring-planet_long1", 1))
    f_s2 = (t_ring - torque) / (3 * _base_radius(model, "sun_large-planet_long1", 1))
    for i in (1, 2, 3):
        assert left[f"sun_small-planet_short{i}"] == pytest.approx(f_s1, rel=1e-6)
        assert right[f"planet_short{i}-planet_long{i}"] == pytest.approx(f_s1, rel=1e-6)
        assert right[f"ring-planet_long{i}"] == pytest.approx(f_r, rel=1e-6)
        assert left[f"sun_large-planet_long{i}"] == pytest.approx(f_s2, rel=1e-6)


@pytest.mark.parametrize("torque", [0.5, 5.0, 20.0])
def test_wolfrom_statics_by_hand(torque):
    """0.5 and 5 N m (light: the 5 N m case stopped before) and the preset's 20 N m. Sun
    meshes T/(3 r_bs); ring 2 carries T / i with i = 69; ring 1 the difference."""
    model = preset_model("wolfrom-example")
    left, right = _static_forces(model, torque)
    t_r2 = torque / model.kinematic_ratios["ring2"]
    for i in (1, 2, 3):
        assert left[f"sun-planet{i}"] == pytest.approx(
            torque / (3 * _base_radius(model, "sun-planet1", 1)), rel=1e-6)
        assert right[f"ring2-planet{i}"] == pytest.approx(
            t_r2 / (3 * _base_radius(model, "ring2-planet1", 1)), rel=1e-6)
        assert left[f"ring1-planet{i}"] == pytest.approx(
            (t_r2 - torque) / (3 * _base_radius(model, "ring1-planet1", 1)), rel=1e-6)


@pytest.mark.parametrize(("name", "light", "heavy"),
                         [("ravigneaux-example", 1.5, 150.0), ("wolfrom-example", 0.5, 20.0)])
def test_run_ups_with_backlash_at_light_and_heavy_load(name, light, heavy):
    """0 -> 1500 min^-1 in 0.05 s (alpha = 3142 rad/s^2), then 50 ms at 1500 min^-1. The drive
    then carries the input torque plus the inertia torque of the rigid-body motion, J_eff
    alpha with J_eff = r.M.r reduced to the input: checked on the second half of the ramp.
    The output turns at the kinematic ratio of the input: checked on the mean speeds of the
    constant part (within 1 %; measured 0.27 % for the Wolfrom set at 20 N m). During the
    ramp the Wolfrom set at 20 N m vibrates with contact loss (about 1100 flank changes) and
    its output's mean speed over 25 ms carries the drift of its mean deflection, 2.1 % (the
    drive, a controller on the rigid-body mode, adds no damping to the set)."""
    from gearvib.simulate import SpeedRamp, simulate

    model = preset_model(name)
    rigid = model.rigid_body_velocity()
    j_eff = float(rigid @ model.mass @ rigid)
    alpha = 1500 * 2 * math.pi / 60 / 0.05
    for torque in (light, heavy):
        res = simulate(model, SpeedRamp(0.0, 1500.0, 0.05, input_torque=torque), duration=0.1)
        assert np.all(np.isfinite(res.normal_force))
        late = (res.time > 0.025) & (res.time <= 0.05)
        expected = torque + j_eff * alpha
        assert res.drive_torque[late].mean() == pytest.approx(expected, rel=0.03), torque
        after = res.time > 0.05
        out = res.speed[res.members.index(model.output_member), after].mean()
        inp = res.speed[res.members.index(model.input_member), after].mean()
        assert out / inp == pytest.approx(model.kinematic_ratios[model.output_member],
                                          rel=0.01)


@pytest.mark.parametrize(
    ("name", "edit", "match"),
    [
        ("wolfrom-example", ("geometry", "planet_step_offset_deg", "2"),
         r"\[geometry\].planet_step_offset_deg must be a number"),
        ("wolfrom-example", ("geometry", "planet_step_offset_deg", float("inf")),
         r"planet_step_offset_deg = inf is not admissible"),
        ("wolfrom-example", ("geometry", "z_planet2", 24.5), r"\[geometry\].z_planet2 must be an "
                                                             r"integer"),
        ("wolfrom-example", ("geometry", "n_planets", 0), r"n_planets = 0 is not admissible"),
        ("wolfrom-example", ("geometry", "n_planets", 2), r"identical stepped planets cannot be "
                                                          r"assembled at 180°"),
        ("wolfrom-example", ("meshes", "ring", {"stiffness": {"model": "constant", "k": 1e8}}),
         r"\[meshes.ring\] describes both rings"),
        ("ravigneaux-example", ("geometry", "planet_mesh_phases", [0.1, 0.2]),
         r"planet_mesh_phases needs 3 finite values"),
        ("ravigneaux-example", ("geometry", "planet_mesh_phases", 0.1),
         r"planet_mesh_phases must be a list"),
        ("ravigneaux-example", ("geometry", "n_pairs", 4),
         r"\(z_sun_small \+ z_sun_large\)/n_pairs = 66/4 = 16.5 must be an integer"),
        ("ravigneaux-example", ("geometry", "z_sun_small", 31), r"= 67/3"),
        ("ravigneaux-example", ("operation", "fixed", ["sun_large", "ring"]),
         r"\[operation\].fixed must name one member"),
        ("two-stage-example", ("stage1", "simulation", {"duration": 1.0}),
         r"\[stage1.simulation\] is not admissible"),
        ("two-stage-example", (None, "geometry", {}), r"unknown key 'geometry' in a description "
                                                      r"of type = 'two-stage'"),
    ],
)
def test_bad_new_keys_name_the_key(name, edit, match):
    import copy

    from gearvib.config import ConfigError, gearset_from_dict, load_config

    cfg = copy.deepcopy(load_config(name)[0])
    section, key, value = edit
    (cfg if section is None else cfg[section])[key] = value
    with pytest.raises(ConfigError, match=match):
        gearset_from_dict(cfg)
