"""Independent lumped models of the multi-stage presets, written out by hand for the tests.

Nothing here uses :mod:`gearvib.assembly`: the base radii come from the involute formulas of
standard (unshifted) gears, the mesh deflections from the pitch-line kinematics, and the mass
and stiffness matrices are assembled coordinate by coordinate.

Deflection of a mesh along its line of action (normal direction, helical gears: times
``cos(beta_b)``), absolute rotations, every gear turning counter-clockwise positive:

* external pair 1-2 (``e`` the unit vector from gear 1's axis to gear 2's, ``t`` = ``e`` turned
  by +90 deg, ``n = cos(alpha) t + sin(alpha) e``): a positive rotation of either gear moves its
  teeth at the contact into the other's, and gear 1 moving along ``n`` presses into gear 2, so
  ``delta = r_b1 theta_1 + r_b2 theta_2 + (d_1 - d_2) . n``;
* a planet on a carrier (rigid pin): the planet centre moves with the carrier, ``a theta_c``
  tangentially, so the sun mesh reads ``r_bs theta_s + r_bp theta_p - (r_bs + r_bp) theta_c``
  and the mesh with a fixed ring ``-r_bp theta_p - (r_br - r_bp) theta_c`` (the ring's
  base radius ``r_br``), and the carrier's inertia gains ``N m_p a^2``.

A loaded back flank has the mirror-image line of action; with isotropic bearings on both gears
of a parallel pair (and no other mesh acting on their translations) the mirror image changes
no eigenvalue (``d . e -> -d . e`` maps one onto the other), so the left line serves every
mesh here.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import scipy.linalg

from gearvib.config import load_config


def transverse(module: float, z: int, alpha_n_deg: float = 20.0, beta_deg: float = 0.0
               ) -> tuple[float, float, float]:
    """Base radius [m], transverse pressure angle [rad] and cos(beta_b) of a standard gear.

    ``m_t = m_n / cos(beta)``, ``tan(alpha_t) = tan(alpha_n) / cos(beta)``, ``r_b = |z| m_t
    cos(alpha_t) / 2``, ``tan(beta_b) = tan(beta) cos(alpha_t)``.
    """
    beta = math.radians(beta_deg)
    alpha_t = math.atan(math.tan(math.radians(alpha_n_deg)) / math.cos(beta))
    r_b = abs(z) * module / math.cos(beta) * math.cos(alpha_t) / 2.0
    beta_b = math.atan(math.tan(beta) * math.cos(alpha_t))
    return r_b, alpha_t, math.cos(beta_b)


class Lumped:
    """Coordinates with their inertias, springs ``k (v . q)^2 / 2`` and the eigenfrequencies."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self.inertia: list[float] = []
        self.springs: list[tuple[float, dict[str, float]]] = []

    def dof(self, name: str, inertia: float) -> None:
        self.names.append(name)
        self.inertia.append(float(inertia))

    def add_inertia(self, name: str, extra: float) -> None:
        self.inertia[self.names.index(name)] += float(extra)

    def spring(self, k: float, coef: dict[str, float]) -> None:
        self.springs.append((float(k), dict(coef)))

    def frequencies_hz(self) -> np.ndarray:
        n = len(self.names)
        kk = np.zeros((n, n))
        for k, coef in self.springs:
            v = np.zeros(n)
            for name, c in coef.items():
                v[self.names.index(name)] += c
            kk += k * np.outer(v, v)
        w2 = scipy.linalg.eigh(kk, np.diag(self.inertia), eigvals_only=True)
        return np.sqrt(np.clip(w2, 0.0, None)) / (2 * math.pi)


def preset_with(name: str, k_mesh: dict[str, float], bearings: dict[str, float] | None = None
                ) -> dict:
    """A preset's description with constant mesh stiffness per stage mesh family
    (``"stage1.sun"``, ``"stage2.pinion"``, ...) and, optionally, isotropic radial bearings
    (``{"stage2.pinion": k, ...}``; a gear on a housing pin gets radial = tangential = k)."""
    cfg = copy.deepcopy(load_config(name)[0])
    cfg.pop("simulation", None)
    for key, k in k_mesh.items():
        stage, mesh = key.split(".")
        cfg[stage]["meshes"][mesh]["stiffness"] = {"model": "constant", "k": k}
    for key, k in (bearings or {}).items():
        stage, body = key.split(".")
        cfg[stage]["bodies"][body]["support"] = {"radial": k, "tangential": k}
    return cfg


def _add_translations(model: Lumped, body: str, mass: float, k_bearing: float) -> None:
    for c in ("x", "y"):
        model.dof(f"{body}.{c}", mass)
        model.spring(k_bearing, {f"{body}.{c}": 1.0})


def _planetary(model: Lumped, cfg: dict, stage: str, k_mesh: dict[str, float],
               bearings: dict[str, float], n_planets: int) -> tuple[str, str]:
    """A simple stage with its ring fixed (sun and carrier as rotations, planets on rigid
    pins); returns the names of the sun and carrier rotations."""
    s = cfg[stage]
    g = s["geometry"]
    m, a_n, beta = g["module"], g.get("pressure_angle_deg", 20.0), g.get("helix_angle_deg", 0.0)
    rb_s, alpha, cb = transverse(m, g["z_sun"], a_n, beta)
    rb_p, _, _ = transverse(m, g["z_planet"], a_n, beta)
    rb_r, _, _ = transverse(m, g["z_ring"], a_n, beta)
    r_s = g["z_sun"] * m / math.cos(math.radians(beta)) / 2
    r_p = g["z_planet"] * m / math.cos(math.radians(beta)) / 2
    a = r_s + r_p  # centre distance of unshifted gears
    sun, car = f"{stage}.sun", f"{stage}.carrier"
    b = s["bodies"]
    model.dof(sun, b["sun"]["inertia"])
    model.dof(car, b["carrier"]["inertia"] + n_planets * b["planet"]["mass"] * a ** 2)
    k_bs = bearings.get(sun)
    if k_bs:
        _add_translations(model, sun, b["sun"]["mass"], k_bs)
    for i in range(n_planets):
        p = f"{stage}.planet{i + 1}"
        model.dof(p, b["planet"]["inertia"])
        psi = 2 * math.pi * i / n_planets
        e = np.array([math.cos(psi), math.sin(psi)])
        t = np.array([-e[1], e[0]])
        n = math.cos(alpha) * t + math.sin(alpha) * e
        coef = {sun: cb * rb_s, p: cb * rb_p, car: -cb * (rb_s + rb_p)}
        if k_bs:
            coef.update({f"{sun}.x": cb * n[0], f"{sun}.y": cb * n[1]})
        model.spring(k_mesh[f"{stage}.sun"], coef)
        model.spring(k_mesh[f"{stage}.ring"], {p: -cb * rb_p, car: -cb * (rb_r - rb_p)})
    return sun, car


def _pair(model: Lumped, cfg: dict, stage: str, k: float, bearings: dict[str, float],
          pinion: str | None = None, wheel: str | None = None) -> tuple[str, str]:
    """A parallel pair; ``pinion``/``wheel`` name existing rotations to join rigidly (the
    same shaft), else new ones are made. Returns the pinion's and the wheel's rotations."""
    s = cfg[stage]
    g = s["geometry"]
    m, a_n, beta = g["module"], g.get("pressure_angle_deg", 20.0), g.get("helix_angle_deg", 0.0)
    rb_p, alpha, cb = transverse(m, g["z_pinion"], a_n, beta)
    rb_w, _, _ = transverse(m, g["z_wheel"], a_n, beta)
    b = s["bodies"]
    names = {}
    for gear, given in (("pinion", pinion), ("wheel", wheel)):
        if given is None:
            names[gear] = f"{stage}.{gear}"
            model.dof(names[gear], b[gear]["inertia"])
        else:
            names[gear] = given
            model.add_inertia(given, b[gear]["inertia"])
    phi = math.radians(g.get("axis_angle_deg", 0.0))
    e = np.array([math.cos(phi), math.sin(phi)])
    n = math.cos(alpha) * np.array([-e[1], e[0]]) + math.sin(alpha) * e
    coef = {names["pinion"]: cb * rb_p, names["wheel"]: cb * rb_w}
    for gear, sign in (("pinion", 1.0), ("wheel", -1.0)):
        kb = bearings.get(f"{stage}.{gear}")
        if kb:
            _add_translations(model, f"{stage}.{gear}", b[gear]["mass"], kb)
            coef[f"{stage}.{gear}.x"] = sign * cb * n[0]
            coef[f"{stage}.{gear}.y"] = sign * cb * n[1]
    model.spring(k, coef)
    return names["pinion"], names["wheel"]


def rig_lumped(cfg: dict, k_mesh: dict[str, float], bearings: dict[str, float]) -> Lumped:
    """``planetary-parallel-rig``: motor - coupling - sun; carrier - shaft - stage-2 pinion;
    stage-2 wheel - shaft - stage-3 pinion; stage-3 wheel - coupling - brake."""
    model = Lumped()
    bodies = {b["name"]: b for b in cfg["body"]}
    model.dof("motor", bodies["motor"]["inertia"])
    sun, car = _planetary(model, cfg, "stage1", k_mesh, bearings, 4)
    p2, w2 = _pair(model, cfg, "stage2", k_mesh["stage2.pinion"], bearings)
    p3, w3 = _pair(model, cfg, "stage3", k_mesh["stage3.pinion"], bearings)
    model.dof("brake", bodies["brake"]["inertia"])
    c = {(x["body1"], x["body2"]): x["stiffness"] for x in cfg["coupling"]}
    model.spring(c[("motor", "stage1.sun")], {"motor": 1.0, sun: -1.0})
    model.spring(c[("stage3.wheel", "brake")], {w3: 1.0, "brake": -1.0})
    shafts = [x["stiffness"] for x in cfg["shaft"]]
    model.spring(shafts[0], {car: 1.0, p2: -1.0})
    model.spring(shafts[1], {w2: 1.0, p3: -1.0})
    return model


def wind_lumped(cfg: dict, k_mesh: dict[str, float], bearings: dict[str, float]) -> Lumped:
    """``wind-turbine-example``: carrier (rotor side) - planetary - sun - low-speed shaft -
    stage-2 wheel; stage-2 pinion and stage-3 wheel on one rigid shaft; stage-3 pinion -
    coupling - generator."""
    model = Lumped()
    sun, _ = _planetary(model, cfg, "stage1", k_mesh, bearings, 3)
    p2, w2 = _pair(model, cfg, "stage2", k_mesh["stage2.pinion"], bearings)
    p3, _ = _pair(model, cfg, "stage3", k_mesh["stage3.pinion"], bearings, wheel=p2)
    gen = {b["name"]: b for b in cfg["body"]}["generator"]
    model.dof("generator", gen["inertia"])
    assert cfg["shaft"][1]["stiffness"] == "rigid"  # joined above (wheel=p2)
    model.spring(cfg["shaft"][0]["stiffness"], {sun: 1.0, w2: -1.0})
    model.spring(cfg["coupling"][0]["stiffness"], {p3: 1.0, "generator": -1.0})
    return model


PLANETARY_AND_PAIR = """
# paper-case1 as stage 1, a parallel reduction stage on the carrier shaft as stage 2
name = "planetary-and-pair"
type = "multi-stage"

[stage1]
type = "simple"
[stage1.operation]
fixed = "ring"
input = "sun"
output = "carrier"
[stage1.geometry]
module = 2.5e-3
pressure_angle_deg = 20.0
face_width = 0.02
z_sun = 33
z_ring = -114
z_planet = 40
planet_angles_deg = [0.0, 120.0, 240.0]
[stage1.bodies.sun]
mass = 1.6
inertia = 1.70e-3
[stage1.bodies.ring]
mass = 6.0
inertia = 0.2
[stage1.bodies.carrier]
mass = 4.0
inertia = 4.0e-2
[stage1.bodies.planet]
mass = 1.15
inertia = 1.46e-3
[stage1.meshes.sun]
stiffness = { model = "rectangular", k_min = 2.6667e7, k_max = 4.3333e7 }
backlash = 40e-6
damping_ratio = 0.005
[stage1.meshes.ring]
stiffness = { model = "rectangular", k_min = 3.0e7, k_max = 5.0e7 }
backlash = 40e-6
damping_ratio = 0.005

[stage2]
type = "parallel"
[stage2.geometry]
module = 2.5e-3
pressure_angle_deg = 20.0
face_width = 0.02
z_pinion = 25
z_wheel = 41
axis_angle_deg = 180.0
[stage2.bodies.pinion]
mass = 1.0
inertia = 1.5e-3
[stage2.bodies.wheel]
mass = 2.5
inertia = 6.0e-3
[stage2.meshes.pinion]
stiffness = { model = "rectangular", k_min = 1.2e8, k_max = 1.8e8 }
backlash = 40e-6
damping_ratio = 0.005

[simulation]
speed_start_rpm = 0.0
speed_end_rpm = 3000.0
duration = 1.0
input_torque = 60.0
fs_out = 25000.0
# paper-case1's light mesh damping (0.5 %) needs the drive's damping, as in the paper presets
# (tests/gearvib/preset_drive.py): the spring-damper on the sun with the values of the
# earlier default drive (under the default controller the crack candidates' runs at 1300 ->
# 1700 min-1 blow up 1.45 s into the run)
drive_stiffness = 3430.4886847087905     # N m/rad
drive_damping = 9.168750812548552        # N m s/rad
"""
"""A planetary stage (``paper-case1``) and a parallel pair (25/41, wheel axis at 180 deg),
driven as the paper presets (a spring-damper on the sun)."""


def heavy_wolfrom() -> str:
    """``wolfrom-example`` with heavier sun (1e-3 kg m^2) and planets (2e-3 kg m^2) and 100 N m
    at the sun: its highest natural frequency falls from 14 to 6.8 kHz (twice the step)."""
    import re

    from gearvib.config import preset_text

    text = preset_text("wolfrom-example").replace('name = "wolfrom-example"',
                                                  'name = "wolfrom-heavy"')
    text = re.sub(r"\[bodies.sun\][^\[]*", "[bodies.sun]\nmass = 0.8\ninertia = 1.0e-3\n\n", text)
    text = re.sub(r"\[bodies.planet\][^\[]*", "[bodies.planet]\nmass = 1.0\ninertia = 2.0e-3\n\n",
                  text)
    return text.replace("input_torque = 20.0 ", "input_torque = 100.0 ")
