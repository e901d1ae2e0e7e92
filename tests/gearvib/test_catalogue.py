"""gearvib.catalogue: the kinematic catalogue of built gear sets against hand-worked formulas.

Sets: the paper's case 1 (preset), a 4-planet simple set, a Wolfrom set with stepped planets
(two mesh frequencies) and a two-stage set (stage-1 and stage-2 meshes), built with the
``gearvib.structure`` builders. The planet-phasing factors are checked against a housing signal
made from the simulator's own mesh positions (``mesh_position_vectors``, ``offsets``).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.catalogue import gear_set_catalogue
from gearvib.cli import main
from gearvib.config import load_gearset
from gearvib.stiffness import RectangularStiffness
from gearvib.structure import (
    Body,
    MeshSpec,
    Support,
    simple_planetary,
    two_stage,
)
from tests.gearvib.lumped_sets import (
    WOLFROM_TEETH,
    nominal_bodies,
    ravigneaux_set,
    wolfrom_set,
)


def line(cat, family, harmonic=1, sideband=0, member=None):
    sel = (cat.family == family) & (cat.harmonic == harmonic) & (cat.sideband == sideband)
    if member is not None:
        sel &= cat.member == member
    idx = np.flatnonzero(sel)
    assert idx.size == 1, (family, harmonic, sideband, member, list(cat.member[
        (cat.family == family) & (cat.harmonic == harmonic)]))
    return int(idx[0])


def _simple(zs=21, zr=-75, zp=27, n=4):
    sun, ring = nominal_bodies("sun", "ring")
    car = Body("carrier", "carrier", 3.0, 2e-2, Support())
    pl = Body("planet", "planet", 0.5, 2e-4, Support(), carrier="carrier")
    k = RectangularStiffness(2e8, 3e8, 1.6)
    return simple_planetary(z_sun=zs, z_ring=zr, z_planet=zp, module=2e-3, sun=sun, ring=ring,
                            carrier=car, planet=pl, sun_mesh=MeshSpec(k), ring_mesh=MeshSpec(k),
                            n_planets=n)


def test_paper_case1_preset():
    gs = load_gearset("paper-case1")
    cat = gear_set_catalogue(gs, speed_rpm=1500.0)
    f = cat.frequency_hz()
    assert cat.reference == "sun" and cat.sensor == "ring"
    assert f[line(cat, "mesh")] == pytest.approx(1500.0 / 60 * 33 * 114 / 147, rel=1e-9)
    assert f[line(cat, "planet_pass")] == pytest.approx(3 * 25.0 * 33 / 147, rel=1e-9)
    assert f[line(cat, "sun_fault")] == pytest.approx(3 * 25.0 * 114 / 147, rel=1e-9)
    assert f[line(cat, "planet_fault")] == pytest.approx(f[line(cat, "mesh")] / 40, rel=1e-9)
    # the same from the assembled model and from the GearSet
    cat2 = gear_set_catalogue(assemble(gs), speed_rpm=1500.0)
    assert np.allclose(cat2.order, cat.order) and list(cat2.family) == list(cat.family)
    # carrier as the reference shaft: the mesh order is |z_r| = 114
    cat3 = gear_set_catalogue(gs, reference="carrier", speed_rpm=100.0)
    assert cat3.order[line(cat3, "mesh")] == pytest.approx(114.0)


def test_four_planet_set_and_phasing_from_the_simulator_mesh_positions():
    gs = _simple()
    model = assemble(gs)
    cat = gear_set_catalogue(gs, model=model, speed_rpm=1000.0, mesh_harmonics=3)
    n_c = 21 / 96
    assert cat.order[line(cat, "mesh")] == pytest.approx(21 * (1 - n_c))
    assert cat.order[line(cat, "planet_pass")] == pytest.approx(4 * n_c)
    assert cat.order[line(cat, "sun_fault")] == pytest.approx(4 * (1 - n_c))
    assert cat.order[line(cat, "ring_fault")] == pytest.approx(4 * n_c)
    assert cat.phasing[line(cat, "mesh", 1)] == 0.0  # 21 = 1 (mod 4): sequential phasing
    assert cat.phasing[line(cat, "mesh", 2)] == 0.0
    # housing signal from the simulator's mesh positions, rigid-body motion, ring fixed
    r = model.rigid_body_velocity()
    rc = model.kinematic_ratios["carrier"]
    n_rev, per_rev = 8, 2048
    phi_c = 2 * np.pi * np.arange(n_rev * per_rev) / per_rev  # carrier angle
    theta_in = phi_c / rc
    planets = {p["name"]: np.radians(p["angle_deg"]) for p in model.meta["planets"]}

    def window(a):
        return np.exp(-0.5 * (np.angle(np.exp(1j * (a - 0.3))) / 0.5) ** 2)

    w1 = np.fft.fft(window(phi_c[:per_rev])) / per_rev
    for central in ("sun", "ring"):
        idx = [i for i, m in enumerate(model.mesh_names) if m.startswith(central)]
        for h in (1, 2, 3):
            x = np.zeros(phi_c.size)
            for i in idx:
                psi = planets[model.meta["meshes"][i]["gear2"]]
                s = (model.mesh_position_vectors[i] @ r) * theta_in \
                    + model.mesh_position_offsets[i]
                x += window(phi_c + psi) * np.cos(2 * np.pi * h * s)
            spec = np.abs(np.fft.rfft(x)) / x.size * 2
            sel = np.isin(cat.family, ["mesh", "sideband"]) & (cat.harmonic == h)
            for k in np.flatnonzero(sel):
                c = round(cat.order[k] / rc)
                amp = spec[c * n_rev]
                expected = abs(w1[(c - 75 * h) % per_rev]) * 4 * cat.phasing[k]
                assert amp == pytest.approx(expected, abs=1e-6 * spec.max()), (central, h, c)


def test_wolfrom_two_mesh_frequencies():
    zs, zr1, zr2, zp1, zp2 = WOLFROM_TEETH
    gs = wolfrom_set()
    cat = gear_set_catalogue(gs, speed_rpm=600.0)
    # hand-worked: ring 1 fixed, sun = 1
    n_c = zs / (zs - zr1)                                  # 0.2
    n_p = n_c - zs * (1 - n_c) / zp1                       # planet (both steps)
    n_r2 = n_c - zp2 * (n_p - n_c) / zr2                   # z_r2 (n_r2 - n_c) = -z_p2 (n_p - n_c)
    mesh1, mesh2 = zs * (1 - n_c), abs(zp2 * (n_p - n_c))  # 14.4 and 12.8
    assert mesh1 == pytest.approx(14.4) and mesh2 == pytest.approx(12.8)
    assert cat.order[line(cat, "mesh", member="sun-planet/ring1-planet")] == pytest.approx(mesh1)
    assert cat.order[line(cat, "mesh", member="ring2-planet")] == pytest.approx(mesh2)
    assert np.sum(cat.family == "mesh") == 2 * 7
    assert cat.order[line(cat, "shaft", member="ring2")] == pytest.approx(abs(n_r2))
    assert cat.order[line(cat, "ring_fault", member="ring2")] == pytest.approx(
        3 * abs(n_r2 - n_c))
    assert cat.order[line(cat, "ring_fault", member="ring1")] == pytest.approx(3 * n_c)
    assert cat.order[line(cat, "planet_pass")] == pytest.approx(3 * n_c)
    # the stepped planet meets three partners with two toothings: fault base |n_p - n_c|
    assert cat.order[line(cat, "planet_fault")] == pytest.approx(abs(n_p - n_c))
    assert cat.frequency_hz()[line(cat, "mesh", member="ring2-planet")] == pytest.approx(
        12.8 * 10.0)
    # sidebands around both mesh frequencies
    assert set(cat.member[cat.family == "sideband"]) == {"sun-planet/ring1-planet",
                                                         "ring2-planet"}


def test_ravigneaux_one_mesh_frequency_two_planet_groups():
    gs = ravigneaux_set()
    cat = gear_set_catalogue(gs, speed_rpm=1000.0)
    # large sun fixed, small sun in: z_s1 (1 - n_c) = z_s2 n_c (both equal the mesh rate,
    # through short and long planet), so n_c = 30/66 and every mesh has one frequency
    n_c = 30 / 66
    fm = 30 * (1 - n_c)
    assert np.sum(cat.family == "mesh") == 7  # one line per harmonic for all four meshes
    i = line(cat, "mesh")
    assert cat.order[i] == pytest.approx(fm)
    assert set(cat.member[i].split("/")) == {"sun_small-short", "sun_large-long", "ring-long",
                                             "short-long"}
    assert cat.order[line(cat, "planet_fault", member="short")] == pytest.approx(fm / 18)
    assert cat.order[line(cat, "planet_fault", member="long")] == pytest.approx(fm / 24)
    assert cat.order[line(cat, "sun_fault", member="sun_small")] == pytest.approx(3 * (1 - n_c))
    assert cat.order[line(cat, "sun_fault", member="sun_large")] == pytest.approx(3 * n_c)
    assert cat.order[line(cat, "ring_fault")] == pytest.approx(3 * fm / 84)
    assert cat.order[line(cat, "planet_pass", member="long")] == pytest.approx(3 * n_c)
    assert cat.sensor == "sun_large"
    # equally spaced pairs, all tooth numbers divisible by 3: every mesh harmonic passes
    assert np.all(cat.phasing[cat.family == "mesh"] == 1.0)


def test_two_stage_stage1_and_stage2_meshes():
    gs = two_stage(_simple(n=3), _simple(n=3), shaft_stiffness=5e5)
    cat = gear_set_catalogue(gs, speed_rpm=3000.0, mesh_harmonics=2)
    i1 = 21 / 96
    m1 = 21 * (1 - i1)              # stage 1: sun at 1, carrier at i1
    m2 = 21 * (i1 - i1 * i1)        # stage 2: sun at i1 (shaft), carrier at i1^2
    assert cat.order[line(cat, "mesh", member="s1.sun-planet/s1.ring-planet")] == \
        pytest.approx(m1)
    assert cat.order[line(cat, "mesh", member="s2.sun-planet/s2.ring-planet")] == \
        pytest.approx(m2)
    assert cat.order[line(cat, "shaft", member="s2.carrier")] == pytest.approx(i1 * i1)
    assert cat.order[line(cat, "planet_pass", member="s2.planet")] == pytest.approx(3 * i1 * i1)
    assert cat.order[line(cat, "sun_fault", member="s2.sun")] == pytest.approx(
        3 * (i1 - i1 * i1))
    # sensor on the first fixed member (stage-1 ring); both carriers turn relative to it
    assert cat.sensor == "s1.ring"


def test_cli_catalogue_json_and_table(capsys):
    assert main(["catalogue", "paper-case1", "--speed", "1500", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["reference"] == {"member": "sun", "speed_rpm": 1500.0}
    fams = {x["family"] for x in d["lines"]}
    assert {"shaft", "mesh", "planet_pass", "sun_fault", "planet_fault", "ring_fault",
            "sideband", "hunting_tooth", "assembly_phase"} <= fams
    for x in d["lines"]:
        assert set(x) == {"family", "harmonic", "sideband", "member", "frequency_hz", "order",
                          "phasing"}
        assert x["frequency_hz"] == pytest.approx(x["order"] * 25.0)
        # the phasing factor the table shows: planet-phased lines (mesh, sidebands, planet
        # pass) pass with 1 at z_s = 33, N = 3; the other families have none (null)
        phased = x["family"] in ("mesh", "sideband", "planet_pass")
        assert x["phasing"] == (1.0 if phased else None), x
    mesh = [x for x in d["lines"] if x["family"] == "mesh" and x["harmonic"] == 1]
    assert mesh[0]["frequency_hz"] == pytest.approx(639.7959, rel=1e-6)
    # only sidebands the phasing lets through (multiples of the planet pass for z_s = 33)
    assert all(x["sideband"] % 3 == 0 for x in d["lines"] if x["family"] == "sideband")
    assert main(["catalogue", "paper-case2", "--speed", "1000"]) == 0
    out = capsys.readouterr().out
    assert "sideband" in out and "reference: sun at 1000 min-1" in out
    assert main(["catalogue", "paper-case1", "--speed", "1000", "--reference", "nope"]) == 2
    assert "reference = 'nope'" in capsys.readouterr().err


def test_cli_catalogue_refuses_a_sideband_count_it_cannot_list(capsys):
    """1000 mesh harmonics with 1000 sidebands each took a minute and hundreds of MB of output:
    refused at once, naming both options and the bound."""
    assert main(["catalogue", "paper-case1", "--speed", "1500", "--mesh-harmonics", "1000",
                 "--sidebands", "1000"]) == 2
    err = capsys.readouterr().err
    assert "--mesh-harmonics 1000" in err and "--sidebands 1000" in err and "<= 20000" in err
    assert main(["catalogue", "paper-case1", "--speed", "1500", "--mesh-harmonics", "100",
                 "--sidebands", "99", "--json"]) == 0
