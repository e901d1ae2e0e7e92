"""Parallel-axis stages and mixed trains: kinematics, modes, catalogue, phases, sensors.

Independent references: the Willis equation and the gear-pair ratio worked by hand, lumped
models written out in :mod:`tests.gearvib.train_sets` (no gearvib assembly), catalogue lines
computed from the shaft speeds by hand.
"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.catalogue import gear_set_catalogue
from gearvib.cli import main
from gearvib.config import ConfigError, gearset_from_dict, load_config, load_gearset
from gearvib.geometry import mesh_phases
from gearvib.io import read_run, write_netcdf
from gearvib.modal import modal_analysis
from gearvib.phases import run_mesh_phases
from gearvib.simulate import SpeedRamp, simulate
from gearvib.stages import multi_stage, parallel_stage
from gearvib.stiffness import ConstantStiffness
from gearvib.structure import Body, MeshSpec, Support
from tests.gearvib.train_sets import Lumped, preset_with, rig_lumped, transverse, wind_lumped

K = {"stage1.sun": 3e8, "stage1.ring": 4e8, "stage2.pinion": 5e8, "stage3.pinion": 4.5e8}
BEARINGS = {"stage1.sun": 2e8, "stage2.pinion": 1.5e8, "stage2.wheel": 3e8,
            "stage3.pinion": 2.5e8, "stage3.wheel": 1e8}
SPEC = MeshSpec(ConstantStiffness(4e8))


def _gear(name: str, j: float, m: float = 2.0, k_b: float | None = None) -> Body:
    sup = Support() if k_b is None else Support(radial=k_b, tangential=k_b)
    return Body(name, "central", m, j, sup)


# --------------------------------------------------------------------------- kinematics


def test_parallel_pair_ratios_mesh_frequency_and_mode():
    """External pair: n_w / n_p = -z_p / z_w (Willis with the carrier at rest); internal
    wheel: +z_p / |z_w|; an idler reverses once more. Mesh frequency z_p n_p / 60. Torsional
    mode of a pair: w^2 = k (r_b1^2 / J_1 + r_b2^2 / J_2)."""
    p, w = _gear("pinion", 1e-3), _gear("wheel", 2e-2)
    ext = assemble(parallel_stage(z_pinion=20, z_wheel=50, module=3e-3, pinion=p, wheel=w,
                                  mesh=SPEC))
    assert ext.kinematic_ratios["wheel"] == pytest.approx(-20 / 50, rel=1e-12)
    assert ext.mesh_frequencies_per_rpm[0] * 60 == pytest.approx(20.0, rel=1e-12)
    rb_p, _, _ = transverse(3e-3, 20)
    rb_w, _, _ = transverse(3e-3, 50)
    hand = math.sqrt(4e8 * (rb_p**2 / 1e-3 + rb_w**2 / 2e-2)) / (2 * math.pi)
    assert modal_analysis(ext).frequencies_hz[-1] == pytest.approx(hand, rel=1e-12)
    internal = assemble(parallel_stage(z_pinion=20, z_wheel=-70, module=3e-3, pinion=p,
                                       wheel=w, mesh=SPEC))
    assert internal.mesh_names == ("wheel-pinion",)
    assert internal.kinematic_ratios["wheel"] == pytest.approx(20 / 70, rel=1e-12)
    idler = assemble(parallel_stage(z_pinion=20, z_wheel=50, z_idler=25, module=3e-3, pinion=p,
                                    wheel=w, idler=_gear("idler", 4e-4), mesh=SPEC,
                                    idler_angle=math.radians(40.0)))
    assert idler.kinematic_ratios["idler"] == pytest.approx(-20 / 25, rel=1e-12)
    assert idler.kinematic_ratios["wheel"] == pytest.approx(+20 / 50, rel=1e-12)
    # both meshes run at z_p n_p: one mesh-frequency group
    assert [g.mesh_names for g in idler.mesh_frequency_groups()] == [("pinion-idler",
                                                                      "idler-wheel")]
    chain = Lumped()
    for name, j in (("pinion", 1e-3), ("idler", 4e-4), ("wheel", 2e-2)):
        chain.dof(name, j)
    rb_i, _, _ = transverse(3e-3, 25)
    chain.spring(4e8, {"pinion": rb_p, "idler": rb_i})
    chain.spring(4e8, {"idler": rb_i, "wheel": rb_w})
    np.testing.assert_allclose(np.sort(modal_analysis(idler).frequencies_hz)[1:],
                               np.sort(chain.frequencies_hz())[1:], rtol=1e-10)


def test_speed_ratios_of_the_presets_against_willis():
    """Wind turbine (carrier in = 1): sun 1 + 99/21; stage 2 (wheel on the sun shaft)
    n_p = -n_w 82/23; stage 3 (wheel on the intermediate shaft) n_p = -n_w 88/22: 81.491.
    Rig (motor = sun = 1): carrier 28/128; n_w2 = -n_c 32/80; n_w3 = -n_w2 30/72: 1/27.43."""
    r = assemble(load_gearset("wind-turbine-example")).kinematic_ratios
    n_s = 1 + 99 / 21
    assert r["stage1.sun"] == pytest.approx(n_s, rel=1e-12)
    assert r["stage1.planet2"] == pytest.approx(1 - (21 / 39) * (n_s - 1), rel=1e-12)
    assert r["stage2.wheel"] == pytest.approx(n_s, rel=1e-12)
    assert r["stage2.pinion"] == pytest.approx(-n_s * 82 / 23, rel=1e-12)
    assert r["stage3.pinion"] == pytest.approx(n_s * 82 / 23 * 88 / 22, rel=1e-12)
    assert r["generator"] == pytest.approx(81.491, rel=1e-5)
    model = assemble(load_gearset("planetary-parallel-rig"))
    r = model.kinematic_ratios
    n_c = 28 / 128
    assert r["stage1.carrier"] == pytest.approx(n_c, rel=1e-12)
    assert r["stage2.wheel"] == pytest.approx(-n_c * 32 / 80, rel=1e-12)
    assert r["stage3.wheel"] == pytest.approx(n_c * 32 / 80 * 30 / 72, rel=1e-12)
    assert 1 / r["brake"] == pytest.approx(27.428571, rel=1e-7)
    # every mesh its own frequency: stage 1 |z_r| n_c, stage 2 z_p n_c, stage 3 z_p |n_w2|
    f = {g.name: 60 * g.frequency_per_rpm for g in model.mesh_frequency_groups()}
    assert f == pytest.approx({"stage 1": 100 * n_c, "stage 2": 32 * n_c,
                               "stage 3": 30 * n_c * 32 / 80}, rel=1e-12)
    res = simulate(model, SpeedRamp(1500.0, 1500.0, 0.01, input_torque=5.0))
    ds = res.to_dataset()
    i = list(ds["mesh"].values).index("stage3.pinion-wheel")
    assert float(ds["mesh_frequency"].values[i, -1]) == pytest.approx(
        30 * n_c * 32 / 80 * 25.0, rel=1e-12)


# --------------------------------------------------------------------------- modes


@pytest.mark.parametrize(("name", "lumped", "scale"),
                         [("planetary-parallel-rig", rig_lumped, 1.0),
                          ("wind-turbine-example", wind_lumped, 10.0)])
@pytest.mark.parametrize("bearings", [False, True])
def test_preset_modes_against_an_independent_lumped_model(name, lumped, scale, bearings):
    """Constant mesh stiffness, purely torsional (the presets' rigid bearings) and with
    isotropic radial bearings on the sun and every parallel-stage gear (their translations
    couple through the lines of action)."""
    k = {key: v * scale for key, v in K.items()}
    b = {key: v * scale**2 for key, v in BEARINGS.items()} if bearings else {}
    cfg = preset_with(name, k, b)
    model = assemble(gearset_from_dict(cfg))
    got = np.sort(modal_analysis(model).frequencies_hz)
    hand = np.sort(lumped(cfg, k, b).frequencies_hz())
    assert got.size == hand.size == model.n_dof
    np.testing.assert_allclose(got[1:], hand[1:], rtol=1e-9)
    assert abs(got[0]) < 1e-6 * got[-1] and hand[0] < 1e-6 * hand[-1]  # one rigid-body mode


def test_parallel_stage_gears_have_no_gyroscopic_terms():
    """The parallel stages' coordinates are in the fixed frame of their housing; the planetary
    stage's keep theirs (the first turning carrier)."""
    cfg = preset_with("planetary-parallel-rig", K, BEARINGS)
    model = assemble(gearset_from_dict(cfg))
    idx = {n: i for i, n in enumerate(model.dof_names)}
    for name in ("stage2.pinion.x", "stage2.wheel.zeta", "stage3.wheel.eta"):
        assert not np.any(model.gyroscopic[idx[name]]) and not np.any(
            model.centripetal[idx[name]])
    assert model.gyroscopic[idx["stage1.sun.x"], idx["stage1.sun.y"]] != 0.0
    assert model.dof_names[model.carrier_dof] == "stage1.carrier.theta"


# --------------------------------------------------------------------------- catalogue


def _line(cat, family, member, harmonic=1, sideband=0):
    sel = ((cat.family == family) & (cat.member == member) & (cat.harmonic == harmonic)
           & (cat.sideband == sideband))
    assert sel.sum() == 1, (family, member, harmonic, sideband)
    return float(cat.frequency_hz()[sel][0])


def test_parallel_stage_catalogue_by_hand():
    """Rig at 1500 min-1 of the motor: carrier and stage-2 pinion at 1500 x 28/128 = 328.125
    min-1 = 5.46875 Hz; stage-2 mesh 32 x 5.46875 = 175 Hz, wheel 2.1875 Hz; stage 3: pinion
    2.1875 Hz, mesh 30 x 2.1875 = 65.625 Hz, wheel 0.911458 Hz."""
    cat = gear_set_catalogue(load_gearset("planetary-parallel-rig"), speed_rpm=1500.0,
                             mesh_harmonics=3, harmonics=2, sidebands=2)
    f_p2, f_w2 = 5.46875, 2.1875
    f_m2, f_m3, f_w3 = 175.0, 65.625, 2.1875 * 30 / 72
    assert _line(cat, "mesh", "stage2.pinion-wheel") == pytest.approx(f_m2, rel=1e-12)
    assert _line(cat, "mesh", "stage2.pinion-wheel", 3) == pytest.approx(3 * f_m2, rel=1e-12)
    assert _line(cat, "mesh", "stage3.pinion-wheel") == pytest.approx(f_m3, rel=1e-12)
    # sidebands at the shaft speeds of both gears, k = 1, 2
    for member, f_g in (("stage2.pinion", f_p2), ("stage2.wheel", f_w2)):
        for k in (-2, -1, 1, 2):
            assert _line(cat, "shaft_sideband", member, 1, k) == pytest.approx(
                f_m2 + k * f_g, rel=1e-12)
        assert _line(cat, "shaft_sideband", member, 2, -1) == pytest.approx(
            2 * f_m2 - f_g, rel=1e-12)
    # a damaged tooth meets its one mate once per revolution
    assert _line(cat, "gear_fault", "stage2.pinion") == pytest.approx(f_p2, rel=1e-12)
    assert _line(cat, "gear_fault", "stage2.wheel") == pytest.approx(f_w2, rel=1e-12)
    assert _line(cat, "gear_fault", "stage2.wheel", 2) == pytest.approx(2 * f_w2, rel=1e-12)
    assert _line(cat, "gear_fault", "stage3.wheel") == pytest.approx(f_w3, rel=1e-12)
    assert _line(cat, "hunting_tooth", "stage2.pinion-wheel") == pytest.approx(
        f_m2 * 16 / (32 * 80), rel=1e-12)
    # no planet families on the fixed axes; the planetary stage keeps its own
    on_axes = np.array([str(m).startswith(("stage2", "stage3")) for m in cat.member])
    assert not np.any(np.isin(cat.family[on_axes], ["sun_fault", "planet_fault", "ring_fault",
                                                    "planet_pass", "sideband"]))
    n_c = 1500 * 28 / 128 / 60
    assert _line(cat, "sun_fault", "stage1.sun") == pytest.approx(4 * (25.0 - n_c), rel=1e-12)
    assert _line(cat, "planet_pass", "stage1.planet") == pytest.approx(4 * n_c, rel=1e-12)
    assert not any("stage2.housing" in n for n in cat.notes)


def test_idler_and_internal_wheel_catalogue():
    """An idler meets pinion and wheel: gear_fault h |n_i| (h = 2: both mates); one mesh
    line for both idler meshes. An internal wheel: gear_fault of the wheel at its speed."""
    p, w = _gear("pinion", 1e-3), _gear("wheel", 2e-2)
    gs = parallel_stage(z_pinion=20, z_wheel=50, z_idler=25, module=3e-3, pinion=p, wheel=w,
                        idler=_gear("idler", 4e-4), mesh=SPEC)
    cat = gear_set_catalogue(gs, speed_rpm=600.0, mesh_harmonics=2)
    assert np.sum((cat.family == "mesh") & (cat.harmonic == 1)) == 1
    assert _line(cat, "mesh", "pinion-idler/idler-wheel") == pytest.approx(200.0)
    assert _line(cat, "gear_fault", "idler", 2) == pytest.approx(2 * 8.0)
    assert _line(cat, "gear_fault", "wheel") == pytest.approx(4.0)
    gs = parallel_stage(z_pinion=20, z_wheel=-70, module=3e-3, pinion=p, wheel=w, mesh=SPEC)
    cat = gear_set_catalogue(gs, speed_rpm=700.0)
    assert _line(cat, "gear_fault", "wheel") == pytest.approx(700 / 60 * 20 / 70)
    assert _line(cat, "mesh", "wheel-pinion") == pytest.approx(700 / 60 * 20)


def test_cli_catalogue_json_carries_the_phasing_factor(capsys):
    """paper-case2 (unequal spacing): the first mesh harmonic passes with the in-phase content
    |sum exp(-i 33 psi_n)| / 3 = 0.440 (physics notes 2); a parallel stage's mesh passes
    with 1 (one 'planet'), its gear lines have none."""
    assert main(["catalogue", "paper-case2", "--speed", "1000", "--json"]) == 0
    lines = json.loads(capsys.readouterr().out)["lines"]
    mesh = next(x for x in lines if x["family"] == "mesh" and x["harmonic"] == 1)
    psi = np.radians([0.0, 122.449, 244.898])
    assert mesh["phasing"] == pytest.approx(abs(np.exp(-1j * 33 * psi).sum()) / 3, abs=1e-4)
    assert mesh["phasing"] == pytest.approx(0.440, abs=1e-3)
    assert all(x["phasing"] is None for x in lines if x["family"] in ("shaft", "sun_fault"))
    assert main(["catalogue", "planetary-parallel-rig", "--speed", "1500", "--json"]) == 0
    lines = json.loads(capsys.readouterr().out)["lines"]
    assert {x["phasing"] for x in lines if x["member"] == "stage2.pinion-wheel"
            and x["family"] == "mesh"} == {1.0}
    assert {x["phasing"] for x in lines if x["family"] == "gear_fault"} == {None}


# --------------------------------------------------------------------------- runs


def test_run_attributes_hold_the_mesh_phases(tmp_path):
    """paper-case2 (planets at 0, 122.45, 244.90 deg): the lag of planet n behind planet 1 is
    frac(z psi_n / 2 pi) for the sun (z = 33) and the ring (z = -114) alike, 0, 0.2245,
    0.4490 (gearvib.geometry.mesh_phases); read back from the written file. The wind turbine's
    parallel meshes carry one gear each: no lag."""
    model = assemble(load_gearset("paper-case2"))
    res = simulate(model, SpeedRamp(1000.0, 1000.0, 0.01, input_torque=10.0))
    write_netcdf(res.to_dataset(), tmp_path / "run.nc")
    table = run_mesh_phases(read_run(tmp_path / "run.nc"))
    assert list(table) == list(model.mesh_names)
    psi = np.radians([table[f"sun-planet{i}"]["planet_angle_deg"] for i in (1, 2, 3)])
    for central, z in (("sun", 33), ("ring", -114)):
        lags = [table[f"{central}-planet{i}"]["relative_phase"] for i in (1, 2, 3)]
        np.testing.assert_allclose(lags, mesh_phases(z, psi), atol=1e-9)
        assert {table[f"{central}-planet{i}"]["reference_mesh"] for i in (1, 2, 3)} == {
            f"{central}-planet1"}
    np.testing.assert_allclose(mesh_phases(33, psi), [0.0, 11 / 49, 22 / 49], atol=1e-9)
    np.testing.assert_allclose([table[m]["mesh_position"] for m in model.mesh_names],
                               model.mesh_position_offsets % 1.0, atol=1e-12)
    wt = assemble(load_gearset("wind-turbine-example"))
    res = simulate(wt, SpeedRamp(20.0, 20.0, 0.005, input_torque=1e4))
    table = run_mesh_phases(res.to_dataset())
    assert table["stage3.pinion-wheel"]["relative_phase"] == 0.0
    assert table["stage2.pinion-wheel"]["carrier"] == "stage2.housing"
    with pytest.raises(ValueError, match="mesh_phases_json"):
        run_mesh_phases({"title": "an old run"})


def test_housing_sensor_of_a_train_sees_every_stage():
    """With several fixed members the default sensor sees all of them: the ring meshes of
    the planetary stage through its window and each parallel mesh with the constant weight of
    its position (stage 3's wheel axis at 180 deg)."""
    from gearvib.sensors.signal import path_force, window_weight

    sensor = {"name": "acc", "angle_deg": 150.0, "window": "exponential", "width_deg": 60.0,
              "housing_modes": [{"frequency_hz": 5.0, "damping_ratio": 0.7, "gain": 1.0}]}
    model = assemble(load_gearset("planetary-parallel-rig")).with_sensors([sensor])
    assert model.sensors[0].member == ("stage1.ring", "stage2.housing", "stage3.housing")
    res = simulate(model, SpeedRamp(1500.0, 1500.0, 0.02, input_torque=5.0))
    p = path_force(res, model, model.sensors[0])
    planets = {q["name"]: q for q in model.meta["planets"]}
    theta_c = res.rotation[res.members.index("stage1.carrier")]
    hand = np.zeros_like(p)
    for k, name in enumerate(model.mesh_names):
        meta = model.meta["meshes"][k]
        if name.startswith("stage1.sun"):
            continue  # the sun is no housing member
        pl = planets[meta["gear2"]]
        turn = theta_c if pl["carrier"] == "stage1.carrier" else 0.0
        delta = turn + math.radians(pl["angle_deg"]) - math.radians(150.0)
        hand += window_weight("exponential", 60.0, delta) * res.normal_force[k].sum(axis=0)
    np.testing.assert_allclose(p, hand, rtol=1e-12, atol=1e-12 * np.abs(hand).max())
    w3 = window_weight("exponential", 60.0, np.radians([180.0 - 150.0]))[0]
    assert w3 == pytest.approx(math.exp(-0.5))


# --------------------------------------------------------------------------- descriptions


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (("stage2", "geometry", "z_wheel", 0), r"\[stage2\]: \[geometry\].z_wheel = 0 is not "
                                               r"admissible"),
        (("stage2", "geometry", "z_wheel", -20), r"internal wheel needs more teeth"),
        (("stage2", "geometry", "axis_deg", 1.0), r"unknown key 'axis_deg' in \[geometry\]"),
        (("stage2", "meshes", "wheel", {"stiffness": {"model": "constant", "k": 1e8}}),
         r"\[meshes.wheel\] describes the idler-wheel mesh"),
        (("stage2", "geometry", "z_idler", 25), r"\[bodies.idler\] and \[geometry\].z_idler "
                                                r"go together"),
        (("stage2", "bodies", "wheel", {"mass": 1.0, "inertia": 1e-2,
                                        "support": {"torsional": 1e3}}),
         r"torsional support is not admissible"),
        ((None, "shaft", [{"stiffness": 1e4}]), r"\[\[shaft\]\] must be an array of 2 tables"),
        ((None, "stage5", {"type": "simple"}), r"missing key 'stage4'"),
        ((None, "stage2", {"type": "two-stage"}), r"\[stage2\].type = 'two-stage' is not "
                                                  r"admissible"),
        (("stage3", "fault", [{"kind": "crack"}]), r"\[\[stage3.fault\]\] is not admissible.*"
                                                   r"stage3.sun"),
        ((None, "type", "multistage"), r"unknown type 'multistage'"),
    ],
)
def test_bad_train_descriptions_name_the_key(edit, match):
    cfg = copy.deepcopy(load_config("planetary-parallel-rig")[0])
    stage, key, *rest = edit
    if stage is None:
        cfg[key] = rest[0]
    elif len(rest) == 2:
        cfg[stage][key][rest[0]] = rest[1]
    else:
        cfg[stage][key] = rest[0]
    with pytest.raises(ConfigError, match=match):
        gearset_from_dict(cfg)


def test_python_builders_match_the_description():
    """The Python builders give the rig the TOML describes: the same model."""
    cfg = copy.deepcopy(load_config("planetary-parallel-rig")[0])
    stages = [gearset_from_dict({**cfg[k], "name": k}) for k in ("stage1", "stage2", "stage3")]
    gs = multi_stage(stages, shafts=[(x["stiffness"], x["damping"]) for x in cfg["shaft"]])
    ref = gearset_from_dict({k: v for k, v in cfg.items() if k not in ("body", "coupling",
                                                                       "operation")})
    a, b = assemble(gs), assemble(ref)
    assert a.dof_names == b.dof_names and a.mesh_names == b.mesh_names
    np.testing.assert_array_equal(a.stiffness, b.stiffness)
    np.testing.assert_array_equal(a.mesh_vectors, b.mesh_vectors)
    np.testing.assert_array_equal(a.mesh_position_offsets, b.mesh_position_offsets)
    with pytest.raises(ValueError, match="at least two stages"):
        multi_stage(stages[:1])


def test_stability_cycle_budget_of_a_three_stage_train():
    """Mesh ratios 1 : 4.733 : 18.11 (99, 3280/7, 288640/161 per carrier revolution): no common
    period within 256 cycles detunes them by <= 1e-3 (0.0036 at best), 512 do (19 : 90 : 344,
    8e-4); the rig's ratios 1 : 8/25 : 3/25 have an exact period (25 + 8 + 3 cycles)."""
    from gearvib.stability import MAX_CYCLES, common_period, cycle_budget

    wt = assemble(load_gearset("wind-turbine-example"))
    assert cycle_budget(wt) == 2 * MAX_CYCLES
    groups = wt.mesh_frequency_groups()
    ratios = [g.frequency_per_rpm / groups[0].frequency_per_rpm for g in groups]
    np.testing.assert_allclose(ratios, [1, 3280 / 7 / 99, 288640 / 161 / 99], rtol=1e-12)
    cp = common_period(ratios, max_cycles=512)
    assert cp.cycles == (19, 90, 344) and cp.max_detuning < 1e-3
    rig = assemble(load_gearset("planetary-parallel-rig"))
    assert cycle_budget(rig) == MAX_CYCLES
    assert common_period([g.frequency_per_rpm / rig.mesh_frequency_groups()[0].frequency_per_rpm
                          for g in rig.mesh_frequency_groups()]).cycles == (25, 8, 3)
    assert cycle_budget(assemble(load_gearset("paper-case1"))) == MAX_CYCLES
