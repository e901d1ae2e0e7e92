"""Shared builders for gear-set tests: lumped Lin & Parker-style planetary sets, a gear pair, and
Wolfrom and Ravigneaux sets of nominal bodies."""

from __future__ import annotations

import math

from gearvib.stiffness import ConstantStiffness
from gearvib.structure import RIGID, Body, GearSet, Mesh, MeshSpec, Support, ravigneaux, wolfrom


def lumped_planetary(angles_deg, *, elastic: bool = True, z_sun: int = 32, z_ring: int = -96,
                     k_mesh: float = 5e8, k_bearing: float = 1e8) -> GearSet:
    """A lumped-parameter simple planetary set in the style of Lin & Parker (1999).

    All central members and planets have translations (``elastic``) or none (purely
    torsional); the ring is held through an elastic torsional support, sun and carrier through
    soft torsional supports (drive and load stiffness), so there is no rigid-body mode.
    """
    alpha = math.radians(24.6)
    r_bs, r_bp = 0.0297, 0.0254
    a = (r_bs + r_bp) / math.cos(alpha)
    r_br = a * math.cos(alpha) + r_bp
    kb = k_bearing if elastic else RIGID

    def central(name: str, m: float, j: float, kt: float) -> Body:
        return Body(name, "central", m, j, Support(radial=kb, torsional=kt))

    bodies = [
        central("sun", 0.4, 0.39 * r_bs**2, 1e7 * r_bs**2),
        central("ring", 2.35, 3.0 * r_br**2, 1e9 * r_br**2),
        Body("carrier", "carrier", 5.43, 6.29 * a**2, Support(radial=kb, torsional=1e7 * a**2)),
    ]
    meshes = []
    for i, psi in enumerate(angles_deg, start=1):
        bodies.append(Body(f"planet{i}", "planet", 0.66, 0.61 * r_bp**2,
                           Support(radial=kb, tangential=kb), carrier="carrier",
                           angle=math.radians(psi)))
        k = ConstantStiffness(k_mesh)
        meshes.append(Mesh(f"sun-planet{i}", "sun", f"planet{i}", k, base_radius1=r_bs,
                           base_radius2=r_bp, pressure_angle=alpha, z1=z_sun, z2=32))
        meshes.append(Mesh(f"ring-planet{i}", "ring", f"planet{i}", k, base_radius1=-r_br,
                           base_radius2=r_bp, pressure_angle=alpha, z1=z_ring, z2=32))
    return GearSet("lumped", tuple(bodies), tuple(meshes), fixed=("ring",), input="sun",
                   output="carrier")


def gear_pair(j1: float = 2e-3, j2: float = 5e-4, r1: float = 0.06, r2: float = 0.03,
              k: float = 3e8) -> GearSet:
    """Two gears on fixed axes: a central gear and a 'planet' on a fixed carrier."""
    alpha = math.radians(20.0)
    bodies = (
        Body("wheel", "central", 3.0, j1, Support()),
        Body("frame", "carrier", 10.0, 1.0, Support()),
        Body("pinion", "planet", 1.0, j2, Support(), carrier="frame", angle=0.0),
    )
    mesh = Mesh("wheel-pinion", "wheel", "pinion", ConstantStiffness(k), base_radius1=r1,
                base_radius2=r2, pressure_angle=alpha, z1=60, z2=30)
    return GearSet("pair", bodies, (mesh,), fixed=("frame",), input="wheel", output="pinion")




WOLFROM_TEETH = (18, -72, -69, 27, 24)
"""Tooth numbers ``z_sun, z_ring1, z_ring2, z_planet1, z_planet2`` of :func:`wolfrom_set`."""


def nominal_bodies(*names: str) -> list[Body]:
    """Central bodies of nominal mass (2 kg) and inertia (0.01 kg m^2), unsupported."""
    return [Body(n, "central", 2.0, 1e-2, Support()) for n in names]


def wolfrom_set() -> GearSet:
    """A Wolfrom set (:data:`WOLFROM_TEETH`) of nominal bodies, constant mesh stiffness."""
    zs, zr1, zr2, zp1, zp2 = WOLFROM_TEETH
    sun, r1, r2 = nominal_bodies("sun", "ring1", "ring2")
    car = Body("carrier", "carrier", 3.0, 2e-2, Support())
    pl = Body("planet", "planet", 0.5, 2e-4, Support(), carrier="carrier")
    spec = MeshSpec(ConstantStiffness(3e8))
    return wolfrom(z_sun=zs, z_ring1=zr1, z_ring2=zr2, z_planet1=zp1, z_planet2=zp2,
                   module=2e-3, module2=2e-3 * (zr1 + zp1) / (zr2 + zp2), sun=sun, ring1=r1,
                   ring2=r2, carrier=car, planet=pl, sun_mesh=spec, ring_mesh=spec)


def ravigneaux_set() -> GearSet:
    """A Ravigneaux set of nominal bodies: suns 30 and 36, ring -84, planets 18 (short) and 24
    (long), constant mesh stiffness."""
    s1, s2, ring = nominal_bodies("sun_small", "sun_large", "ring")
    car = Body("carrier", "carrier", 3.0, 2e-2, Support())
    ps = Body("short", "planet", 0.3, 1e-4, Support(), carrier="carrier")
    pl = Body("long", "planet", 0.5, 2e-4, Support(), carrier="carrier")
    spec = MeshSpec(ConstantStiffness(3e8))
    return ravigneaux(z_sun_small=30, z_sun_large=36, z_ring=-84, z_planet_short=18,
                      z_planet_long=24, module=2e-3, sun_small=s1, sun_large=s2, ring=ring,
                      carrier=car, planet_short=ps, planet_long=pl, sun_mesh=spec,
                      ring_mesh=spec, planet_mesh=spec)
