"""Bodies, supports, meshes and the planetary base structure; builders for common gear sets.

A gear set is a set of *bodies* (nodes carrying mass and inertia) joined by *meshes* (tooth
contacts), *supports* (bearings to ground, or of a planet on its carrier) and optional shaft
*couplings*. Following the paper, every planetary gear set is a combination of *base
structures*: one central gear (external or internal toothing, expressed by the sign of its
tooth number), one planet and the planet carrier. Base structures share bodies, so a simple set
with N planets is 2N base structures on four kinds of bodies, a Wolfrom set adds a second ring
meshing a stepped planet, and a Ravigneaux set adds planet-planet meshes.

Everything here is a plain description; :mod:`gearvib.assembly` turns it into matrices.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

from gearvib.checks import check_array, check_count, check_items, check_real, check_text, cut, short
from gearvib.geometry import (
    MAX_TEETH,
    MeshGeometry,
    Toothing,
    check_planet_angles,
    mesh_geometry,
    planet_profile_shift,
)
from gearvib.stiffness import MeshStiffness, stiffness_from_dict

__all__ = [
    "DAMPING_LAWS",
    "MAX_PLANETS",
    "RIGID",
    "BaseStructure",
    "Body",
    "Coupling",
    "GearSet",
    "Mesh",
    "MeshSpec",
    "Support",
    "check_damping_law",
    "check_ravigneaux_clearances",
    "check_ravigneaux_pairs",
    "check_stepped_planet_angles",
    "compose",
    "prefixed",
    "ravigneaux",
    "simple_planetary",
    "two_stage",
    "wolfrom",
]

RIGID = math.inf
"""Stiffness value of a rigid support: the corresponding DOF is removed."""
MAX_PLANETS = 64
"""Largest number of planets (or planet pairs) accepted."""

Role = Literal["central", "carrier", "planet"]


DAMPING_LAWS = ("gated", "viscous")
"""Mesh-damping laws: damping only on a flank in contact (default), or always on."""


def check_damping_law(value: object, name: str) -> str:
    """``value`` if it is one of :data:`DAMPING_LAWS`, else a ``ValueError`` naming ``name``."""
    if not (isinstance(value, str) and value in DAMPING_LAWS):
        raise ValueError(f"{name} = {short(value)} is not admissible (admissible: "
                         f"{', '.join(repr(v) for v in DAMPING_LAWS)})")
    return value


def _check_value(value: float, name: str, *, allow_zero: bool = True, allow_inf: bool = False):
    """A stiffness, damping, mass or inertia: a number >= 0 (> 0 unless ``allow_zero``),
    finite (``+inf`` too where ``allow_inf``: rigid)."""
    return check_real(value, name, low=0.0, low_open=not allow_zero, allow_inf=allow_inf)


@dataclass(frozen=True)
class Support:
    """Stiffness and damping of a body's support, per direction.

    For central members and carriers the support is to ground: ``radial`` acts on both in-plane
    translations, ``axial`` on the axial translation, ``torsional`` on the rotation. For planets
    the support is the planet bearing on its carrier: ``radial`` and ``tangential`` in the
    carrier frame, ``axial``; ``torsional`` is not used (the planet spins freely on its pin).

    A stiffness of :data:`RIGID` (``inf``) removes the DOF, ``0`` leaves it free. Units are
    N/m (translations) and N m/rad (rotation); damping in N s/m and N m s/rad.
    """

    radial: float = RIGID
    tangential: float = RIGID
    axial: float = RIGID
    torsional: float = 0.0
    radial_damping: float = 0.0
    tangential_damping: float = 0.0
    axial_damping: float = 0.0
    torsional_damping: float = 0.0

    def __post_init__(self) -> None:
        for name in ("radial", "tangential", "axial", "torsional"):
            _check_value(getattr(self, name), f"support {name} stiffness", allow_inf=True)
        for name in ("radial", "tangential", "axial", "torsional"):
            _check_value(getattr(self, f"{name}_damping"), f"support {name} damping")


@dataclass(frozen=True)
class Body:
    """A rigid body (node): central gear, carrier or planet.

    Parameters
    ----------
    name : str
        Unique name, used in DOF, mesh and output names.
    role : {"central", "carrier", "planet"}
        Central members (suns, rings) and carriers rotate about the main axis.
    mass : float
        Mass [kg] (> 0).
    inertia : float
        Polar moment of inertia about the body's own axis [kg m^2] (> 0).
    support : Support
        Bearing stiffness per direction (see :class:`Support`).
    carrier : str, optional
        For planets: the carrier they sit on.
    angle : float
        For planets: position angle on the carrier [rad] (the paper's assembly angle).
    radius : float, optional
        For planets: distance of the planet axis from the main axis [m]. Taken from the
        centre distance of the planet's first central-gear mesh when omitted.
    """

    name: str
    role: Role
    mass: float
    inertia: float
    support: Support = field(default_factory=Support)
    carrier: str | None = None
    angle: float = 0.0
    radius: float | None = None

    def __post_init__(self) -> None:
        check_text(self.name, "name of a body")
        w = short(self.name)
        if self.role not in ("central", "carrier", "planet"):
            raise ValueError(
                f"body {w}: role {short(self.role)} is not admissible "
                "(central, carrier or planet)"
            )
        _check_value(self.mass, f"mass of body {w}", allow_zero=False)
        _check_value(self.inertia, f"inertia of body {w}", allow_zero=False)
        if not isinstance(self.support, Support):
            raise TypeError(f"support of body {w} must be a Support; got "
                            f"{type(self.support).__name__}")
        check_text(self.carrier, f"carrier of body {w}", optional=True)
        if self.role == "planet" and not self.carrier:
            raise ValueError(f"planet {w} needs a carrier")
        check_real(self.angle, f"angle of planet {w}")
        if self.radius is not None:
            _check_value(self.radius, f"radius of planet {w}", allow_zero=False)


@dataclass(frozen=True)
class Mesh:
    """A tooth contact between ``gear1`` (central gear or first planet) and ``gear2`` (planet).

    Either tooth geometry (``toothing1``, ``toothing2``) or lumped parameters (signed base
    radii, working pressure angle) describe the contact; lumped values override geometry.

    Parameters
    ----------
    name : str
        Mesh name, e.g. ``"sun-planet1"``.
    gear1, gear2 : str
        Body names; ``gear2`` is always a planet.
    stiffness : MeshStiffness
        Left (drive) flank stiffness as a function of mesh position.
    toothing1, toothing2 : Toothing, optional
        Tooth geometry of the two gears (signed tooth numbers).
    base_radius1, base_radius2 : float, optional
        Signed base radii [m] (negative for internal toothing), for lumped models.
    pressure_angle : float, optional
        Working transverse pressure angle [rad], for lumped models.
    helix_angle : float
        Base helix angle [rad] for lumped models (0: spur), signed with the hand of gear1
        (> 0 right hand; an internal gear has the hand of its planet).
    z1, z2 : int, optional
        Signed tooth numbers for the mesh position and phasing of lumped models.
    back_stiffness : MeshStiffness, optional
        Right (back) flank stiffness; the drive-flank model when omitted.
    backlash : float
        Total normal backlash [m]; negative: both flanks in contact (preload).
    damping : float, optional
        Viscous mesh damping [N s/m].
    damping_ratio : float, optional
        Alternative to ``damping``: fraction of critical damping of the pair's torsional
        mode at the mean stiffness.
    damping_law : {"gated", "viscous"}
        ``"gated"`` (default): the damping acts only on a flank in contact and a flank never
        pulls (its force is floored at 0). ``"viscous"``: always on, ``c delta'`` whatever the
        contact, as in Kahraman & Singh (1990) (:func:`gearvib.kernels.flank_forces_viscous`).
    phase : float, optional
        Mesh position at the assembly reference [cycles]; computed from geometry if omitted.
    centre_distance : float, optional
        Operating centre distance [m] of a geometric mesh (default: zero backlash).
    tooth_offset1, tooth_offset2 : float
        For planets with several toothings (stepped planets): angle [rad] from the planet's
        reference tooth (a tooth of the toothing of its first central-gear mesh) to a tooth of
        the toothing used in this mesh, in the planet's positive rotation sense. 0 for a
        single toothing.
    """

    name: str
    gear1: str
    gear2: str
    stiffness: MeshStiffness
    toothing1: Toothing | None = None
    toothing2: Toothing | None = None
    base_radius1: float | None = None
    base_radius2: float | None = None
    pressure_angle: float | None = None
    helix_angle: float = 0.0
    z1: int | None = None
    z2: int | None = None
    back_stiffness: MeshStiffness | None = None
    backlash: float = 0.0
    damping: float | None = None
    damping_ratio: float | None = None
    damping_law: str = "gated"
    phase: float | None = None
    centre_distance: float | None = None
    tooth_offset1: float = 0.0
    tooth_offset2: float = 0.0

    def __post_init__(self) -> None:
        check_text(self.name, "name of a mesh")
        w = short(self.name)
        check_text(self.gear1, f"mesh {w}: gear1")
        check_text(self.gear2, f"mesh {w}: gear2")
        for label in ("toothing1", "toothing2"):
            t = getattr(self, label)
            if t is not None and not isinstance(t, Toothing):
                raise TypeError(f"mesh {w}: {label} must be a Toothing; got {type(t).__name__}")
        for label in ("base_radius1", "base_radius2", "pressure_angle", "damping",
                      "damping_ratio", "phase", "centre_distance"):
            check_real(getattr(self, label), f"mesh {w}: {label}", optional=True)
        for label in ("helix_angle", "backlash", "tooth_offset1", "tooth_offset2"):
            check_real(getattr(self, label), f"mesh {w}: {label}")
        for label in ("z1", "z2"):
            check_count(getattr(self, label), f"mesh {w}: {label}", optional=True,
                        low=-MAX_TEETH, high=MAX_TEETH)
        for label, model in (("stiffness", self.stiffness),
                             ("back_stiffness", self.back_stiffness)):
            if not (isinstance(model, MeshStiffness) or (model is None
                                                         and label == "back_stiffness")):
                raise TypeError(f"mesh {w}: {label} must be a MeshStiffness; got "
                                f"{type(model).__name__}")
        geometric = self.toothing1 is not None and self.toothing2 is not None
        lumped = self.base_radius1 is not None and self.base_radius2 is not None
        if not (geometric or lumped):
            raise ValueError(
                f"mesh {w} needs either toothing1/toothing2 or "
                "base_radius1/base_radius2 (+ pressure_angle)"
            )
        if lumped and not geometric and self.pressure_angle is None:
            raise ValueError(f"mesh {w}: lumped description needs pressure_angle")
        if self.pressure_angle is not None and not 0 <= self.pressure_angle < math.radians(60):
            raise ValueError(
                f"mesh {w}: pressure_angle {math.degrees(self.pressure_angle):.3g}° "
                "is not admissible (0° to 60°)"
            )
        for key in ("base_radius1", "base_radius2"):
            v = getattr(self, key)
            if v is not None and not (math.isfinite(v) and v != 0.0):
                raise ValueError(f"mesh {w}: {key} = {v!r} m is not admissible "
                                 "(admissible: finite, non-zero; negative for an internal gear)")
        for key in ("z1", "z2"):
            v = getattr(self, key)
            if v is not None and v == 0:
                raise ValueError(f"mesh {w}: {key} = {v!r} is not admissible "
                                 "(admissible: a non-zero signed tooth number)")
        if not (math.isfinite(self.helix_angle) and abs(self.helix_angle) < math.radians(45)):
            raise ValueError(f"mesh {w}: helix_angle {math.degrees(self.helix_angle):.4g}"
                             "° is not admissible (|beta_b| < 45°)")
        if self.centre_distance is not None and not (math.isfinite(self.centre_distance)
                                                     and self.centre_distance > 0):
            raise ValueError(f"mesh {w}: centre_distance = {self.centre_distance!r} m "
                             "is not admissible (admissible: > 0)")
        if self.damping is not None:
            _check_value(self.damping, f"damping of mesh {w}")
        if self.damping_ratio is not None:
            _check_value(self.damping_ratio, f"damping_ratio of mesh {w}")
        check_damping_law(self.damping_law, f"damping_law of mesh {w}")
        for label, model in (("stiffness", self.stiffness), ("back_stiffness",
                                                              self.back_stiffness)):
            if model is not None and not model.min >= 0:
                raise ValueError(
                    f"mesh {w}: {label} reaches {model.min:.4g} N/m; "
                    "admissible: >= 0"
                )

    @property
    def geometry(self) -> MeshGeometry | None:
        """Involute mesh geometry when both toothings are given."""
        if self.toothing1 is None or self.toothing2 is None:
            return None
        return mesh_geometry(self.toothing1, self.toothing2, self.centre_distance)


@dataclass(frozen=True)
class Coupling:
    """Torsional shaft between two bodies (``stiffness`` :data:`RIGID` joins them)."""

    body1: str
    body2: str
    stiffness: float = RIGID
    damping: float = 0.0

    def __post_init__(self) -> None:
        check_text(self.body1, "body1 of a coupling")
        check_text(self.body2, "body2 of a coupling")
        w = f"{short(self.body1)}-{short(self.body2)}"
        _check_value(self.stiffness, f"coupling {w} stiffness", allow_zero=False, allow_inf=True)
        _check_value(self.damping, f"coupling {w} damping")


@dataclass(frozen=True)
class BaseStructure:
    """The paper's base structure: a central gear, a planet and the carrier, with their mesh.

    ``variant`` tells the three forms: ``"external"`` (external central gear, e.g. a sun),
    ``"internal"`` (internal central gear, e.g. a ring) and ``"internal-planet"`` (an
    external central gear meshing an internally toothed planet).
    """

    central: Body
    planet: Body
    carrier: Body
    mesh: Mesh

    def __post_init__(self) -> None:
        for label, cls in (("central", Body), ("planet", Body), ("carrier", Body),
                           ("mesh", Mesh)):
            if not isinstance(getattr(self, label), cls):
                raise TypeError(f"base structure: {label} must be a {cls.__name__}; got "
                                f"{type(getattr(self, label)).__name__}")
        if self.central.role != "central":
            raise ValueError(f"base structure: {self.central.name!r} is not a central member")
        if self.planet.role != "planet" or self.planet.carrier != self.carrier.name:
            raise ValueError(
                f"base structure: {self.planet.name!r} is not a planet of "
                f"{self.carrier.name!r}"
            )
        if (self.mesh.gear1, self.mesh.gear2) != (self.central.name, self.planet.name):
            raise ValueError(
                f"base structure: mesh {self.mesh.name!r} does not join "
                f"{self.central.name!r} and {self.planet.name!r}"
            )

    @property
    def variant(self) -> str:
        """``"external"``, ``"internal"`` or ``"internal-planet"``."""
        z1 = _signed_z(self.mesh, 1)
        z2 = _signed_z(self.mesh, 2)
        if z2 is not None and z2 < 0:
            return "internal-planet"
        if z1 is not None and z1 < 0:
            return "internal"
        if self.mesh.base_radius1 is not None and self.mesh.base_radius1 < 0:
            return "internal"
        return "external"


def _signed_z(mesh: Mesh, which: int) -> int | None:
    t = mesh.toothing1 if which == 1 else mesh.toothing2
    if t is not None:
        return t.z
    return mesh.z1 if which == 1 else mesh.z2


@dataclass(frozen=True)
class GearSet:
    """A complete gear set: bodies, meshes, couplings and the operating roles.

    Parameters
    ----------
    name : str
        Name used in outputs.
    bodies : tuple of Body
        All bodies, names unique.
    meshes : tuple of Mesh
        All tooth contacts.
    fixed : tuple of str
        Members held at rest (their rotation is removed).
    input, output : str
        Driven and loaded members.
    couplings : tuple of Coupling
        Shafts joining members of different stages.
    config : dict
        The description this set was built from (kept for provenance).
    faults : tuple of Fault
        Local tooth faults and manufacturing errors (:mod:`gearvib.faults`), checked and
        applied by :func:`gearvib.assembly.assemble` and the run.
    sensors : tuple
        Virtual sensors (:mod:`gearvib.sensors`) that a run computes.
    rolling_bearings : tuple of RollingBearingSpec
        Rolling-bearing geometry (:mod:`gearvib.rolling_bearings`) for the catalogue's defect
        lines; the dynamics do not use it.
    """

    name: str
    bodies: tuple[Body, ...]
    meshes: tuple[Mesh, ...]
    fixed: tuple[str, ...]
    input: str
    output: str
    couplings: tuple[Coupling, ...] = ()
    config: dict = field(default_factory=dict, compare=False)
    faults: tuple = ()
    sensors: tuple = ()
    rolling_bearings: tuple = ()

    def with_faults(self, faults) -> GearSet:
        """This gear set with faults added (descriptions or ``[[fault]]`` tables).

        Checked against the set's bodies and teeth when it is assembled.
        """
        from gearvib.faults.description import faults_from_list

        return replace(self, faults=self.faults + faults_from_list(list(faults)))

    def with_sensors(self, sensors) -> GearSet:
        """This gear set with virtual sensors added (descriptions or ``[[sensor]]`` tables)."""
        from gearvib.sensors.description import sensors_from_list

        return replace(self, sensors=self.sensors + sensors_from_list(list(sensors)))

    def __post_init__(self) -> None:
        check_text(self.name, "name of a gear set")
        # the classes of faults, sensors and bearings by name: their modules import
        # numpy-light gearvib only, but the bearings' imports analysis (xarray)
        for label, cls in (("bodies", Body), ("meshes", Mesh), ("couplings", Coupling),
                           ("fixed", str), ("faults", "gearvib.faults.description.Fault"),
                           ("sensors", ("gearvib.sensors.description.HousingSensor",
                                        "gearvib.sensors.description.Tacho")),
                           ("rolling_bearings", "gearvib.rolling_bearings.RollingBearingSpec")):
            object.__setattr__(self, label, check_items(getattr(self, label), cls, label))
        check_text(self.input, "input")
        check_text(self.output, "output")
        if not isinstance(self.config, dict):
            raise TypeError(f"config must be a dict; got {type(self.config).__name__}")
        names = [b.name for b in self.bodies]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"gear set {short(self.name)}: duplicate body names "
                             f"{short(sorted(dup))}")
        known = set(names)
        by_name = {b.name: b for b in self.bodies}
        for b in self.bodies:
            if b.role == "planet" and (b.carrier not in known
                                       or by_name[b.carrier].role != "carrier"):
                raise ValueError(
                    f"planet {short(b.name)}: carrier {short(b.carrier)} is not a carrier of "
                    "this set"
                )
        mesh_names = [m.name for m in self.meshes]
        if len(set(mesh_names)) != len(mesh_names):
            raise ValueError(f"gear set {short(self.name)}: duplicate mesh names")
        for m in self.meshes:
            for g in (m.gear1, m.gear2):
                if g not in known:
                    raise ValueError(f"mesh {short(m.name)}: unknown body {short(g)}")
            if by_name[m.gear2].role != "planet":
                raise ValueError(f"mesh {short(m.name)}: gear2 {short(m.gear2)} must be a "
                                 "planet")
            if by_name[m.gear1].role == "carrier":
                raise ValueError(f"mesh {short(m.name)}: a carrier has no teeth")
        for role_name, member in (("input", self.input), ("output", self.output)):
            if member not in known:
                raise ValueError(f"{role_name} member {short(member)} is not a body of the set "
                                 f"(bodies: {short(sorted(known))})")
        for f in self.fixed:
            if f not in known:
                raise ValueError(f"fixed member {short(f)} is not a body of the set")
            if f in (self.input, self.output):
                raise ValueError(f"member {short(f)} cannot be fixed and {short(self.input)}/"
                                 f"{short(self.output)} at once")
        for c in self.couplings:
            for g in (c.body1, c.body2):
                if g not in known:
                    raise ValueError(f"coupling: unknown body {short(g)}")

    def bearings(self) -> list:
        """The ``[[rolling_bearing]]`` tables with their rings' members resolved (a planet's
        bearing turns with its carrier), in the catalogue form
        (:class:`analysis.catalogue.RollingBearing`), as :meth:`gearvib.rig.ShaftRig.bearings`."""
        members = {b.name: b.carrier if b.role == "planet" else None for b in self.bodies}
        return [b.resolve(members) for b in self.rolling_bearings]

    def body(self, name: str) -> Body:
        """The body called ``name``."""
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)

    @property
    def planets(self) -> tuple[Body, ...]:
        """All planets in description order."""
        return tuple(b for b in self.bodies if b.role == "planet")

    def base_structures(self) -> tuple[BaseStructure, ...]:
        """Every central-gear/planet/carrier triple (planet-planet meshes excluded)."""
        out = []
        for m in self.meshes:
            c = self.body(m.gear1)
            if c.role != "central":
                continue
            p = self.body(m.gear2)
            assert p.carrier is not None  # gear2 is a planet, which has its carrier
            out.append(BaseStructure(c, p, self.body(p.carrier), m))
        return tuple(out)

    def with_operation(self, *, fixed: Sequence[str] | None = None, input: str | None = None,
                       output: str | None = None) -> GearSet:
        """A copy with other operating roles."""
        return replace(
            self,
            fixed=tuple(self.fixed if fixed is None else fixed),
            input=self.input if input is None else input,
            output=self.output if output is None else output,
        )


def compose(name: str, base_structures: Iterable[BaseStructure], *, fixed: Sequence[str],
            input: str, output: str, extra_meshes: Iterable[Mesh] = (),
            extra_bodies: Iterable[Body] = (), couplings: Iterable[Coupling] = (),
            config: dict | None = None) -> GearSet:
    """Combine base structures that share bodies into one gear set.

    Bodies that appear in several base structures must be the same object description.
    """
    base_structures = check_items(list(base_structures) if isinstance(
        base_structures, Iterable) and not isinstance(base_structures, str | bytes | dict)
        else base_structures, BaseStructure, "base_structures")
    extra_meshes = check_items(list(extra_meshes) if isinstance(extra_meshes, Iterable)
                               and not isinstance(extra_meshes, str | bytes | dict)
                               else extra_meshes, Mesh, "extra_meshes")
    extra_bodies = check_items(list(extra_bodies) if isinstance(extra_bodies, Iterable)
                               and not isinstance(extra_bodies, str | bytes | dict)
                               else extra_bodies, Body, "extra_bodies")
    couplings = check_items(list(couplings) if isinstance(couplings, Iterable)
                            and not isinstance(couplings, str | bytes | dict)
                            else couplings, Coupling, "couplings")
    fixed = check_items(fixed, str, "fixed")
    if config is not None and not isinstance(config, dict):
        raise TypeError(f"config must be a dict; got {type(config).__name__}")
    bodies: dict[str, Body] = {}
    meshes: list[Mesh] = []

    def add(b: Body) -> None:
        old = bodies.get(b.name)
        if old is not None and old != b:
            raise ValueError(f"body {short(b.name)} is described differently in two base "
                             "structures")
        bodies[b.name] = b

    for bs in base_structures:
        for b in (bs.central, bs.carrier, bs.planet):
            add(b)
        meshes.append(bs.mesh)
    for b in extra_bodies:
        add(b)
    meshes.extend(extra_meshes)
    ordered = sorted(bodies.values(), key=lambda b: ("central", "carrier", "planet").index(
        b.role))
    return GearSet(name=name, bodies=tuple(ordered), meshes=tuple(meshes), fixed=tuple(fixed),
                   input=input, output=output, couplings=tuple(couplings),
                   config=dict(config or {}))


# --------------------------------------------------------------------------------------------
# Builders
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class MeshSpec:
    """Stiffness, backlash and damping shared by a family of meshes (all sun-planet, ...)."""

    stiffness: MeshStiffness | dict
    back_stiffness: MeshStiffness | dict | None = None
    backlash: float = 0.0
    damping: float | None = None
    damping_ratio: float | None = None
    damping_law: str = "gated"

    def __post_init__(self) -> None:
        for label in ("stiffness", "back_stiffness"):
            model = getattr(self, label)
            if not (isinstance(model, MeshStiffness | dict)
                    or (model is None and label == "back_stiffness")):
                raise TypeError(f"{label} must be a MeshStiffness or a stiffness table (dict); "
                                f"got {type(model).__name__}")
        check_real(self.backlash, "backlash")
        if self.damping is not None:
            _check_value(self.damping, "damping")
        if self.damping_ratio is not None:
            _check_value(self.damping_ratio, "damping_ratio")
        check_damping_law(self.damping_law, "damping_law")

    def resolve(self, geometry: MeshGeometry) -> MeshSpec:
        """Build stiffness models given as TOML tables (contact ratio from ``geometry``)."""
        def build(model):
            return stiffness_from_dict(model, geometry) if isinstance(model, dict) else model

        return replace(self, stiffness=build(self.stiffness),
                       back_stiffness=build(self.back_stiffness))

    def models(self) -> tuple[MeshStiffness, MeshStiffness | None]:
        """The stiffness and back-flank stiffness models of a spec whose tables are built
        (:meth:`resolve`)."""
        if isinstance(self.stiffness, dict) or isinstance(self.back_stiffness, dict):
            raise ValueError("a stiffness table needs the mesh geometry: resolve() the spec")
        return self.stiffness, self.back_stiffness


def _mesh(name: str, g1: str, g2: str, t1: Toothing, t2: Toothing, spec: MeshSpec,
          centre_distance: float | None = None) -> Mesh:
    spec = spec.resolve(mesh_geometry(t1, t2, centre_distance))
    stiffness, back_stiffness = spec.models()
    return Mesh(name=name, gear1=g1, gear2=g2, stiffness=stiffness, toothing1=t1,
                toothing2=t2, back_stiffness=back_stiffness, backlash=spec.backlash,
                damping=spec.damping, damping_ratio=spec.damping_ratio,
                damping_law=spec.damping_law, centre_distance=centre_distance)


def _planet(template: Body, index: int, carrier: Body, angle: float, radius: float) -> Body:
    """Planet ``index`` of a builder, placed at ``angle`` on ``carrier``."""
    return replace(template, name=f"{template.name}{index}", role="planet", carrier=carrier.name,
                   angle=angle, radius=radius)


def _base(central: Body, planet: Body, carrier: Body, t_central: Toothing, t_planet: Toothing,
          spec: MeshSpec, centre_distance: float) -> BaseStructure:
    """Base structure with the mesh named ``"<central>-<planet>"``."""
    return BaseStructure(central, planet, carrier, _mesh(
        f"{central.name}-{planet.name}", central.name, planet.name, t_central, t_planet, spec,
        centre_distance))


def _parts(**parts: object) -> None:
    """Refuse a builder argument of the wrong class: bodies (:class:`Body`), mesh
    descriptions (:class:`MeshSpec`, or ``None`` for an optional one), names (``str``) and
    ``config`` (a dict or ``None``), by their parameter names."""
    for name, value in parts.items():
        if name == "config":
            if value is not None and not isinstance(value, dict):
                raise TypeError(f"config must be a dict; got {type(value).__name__}")
        elif name.endswith("_mesh") or name == "mesh":
            if not isinstance(value, MeshSpec) and value is not None:
                raise TypeError(f"{name} must be a MeshSpec; got {type(value).__name__}")
        elif name in ("fixed", "input", "output", "name"):
            check_text(value, name, empty=name == "fixed")
        elif not isinstance(value, Body):
            raise TypeError(f"{name} must be a Body; got {type(value).__name__}")


def _planet_angles(z_sun: int, z_ring: int, n_planets: int | None,
                   angles: Sequence[float] | None) -> list[float]:
    n_planets = check_count(n_planets, "n_planets", low=1, high=MAX_PLANETS, optional=True)
    if angles is None:
        if n_planets is None:
            raise ValueError("give n_planets (>= 1) or planet angles")
        angles = [2 * math.pi * i / n_planets for i in range(n_planets)]
    angles = [float(a) for a in check_planet_angles(z_sun, z_ring, angles)]
    if len(angles) > MAX_PLANETS:
        raise ValueError(f"planet_angles: {len(angles)} planets (admissible: at most "
                         f"{MAX_PLANETS})")
    return angles


def _check_ring_and_sun(z_sun: int, z_ring: int, sun_key: str, ring_key: str) -> None:
    """Signs of the tooth numbers of a sun (external) and a ring (internal)."""
    check_count(z_sun, sun_key, low=-MAX_TEETH, high=MAX_TEETH)
    check_count(z_ring, ring_key, low=-MAX_TEETH, high=MAX_TEETH)
    if z_ring >= 0:
        raise ValueError(f"{ring_key} = {z_ring} must be negative (internal toothing)")
    if z_sun <= 0:
        raise ValueError(f"{sun_key} = {z_sun} must be positive (external toothing)")


def _common_centre_distance(sun: Toothing, ring: Toothing, planet: Toothing, solved: float,
                            key: str) -> float:
    """Centre distance shared by the sun-planet and ring-planet meshes (checked)."""
    a = mesh_geometry(sun, planet).centre_distance
    a_ring = mesh_geometry(ring, planet).centre_distance
    if not math.isclose(a, a_ring, rel_tol=1e-6):
        raise ValueError(
            f"centre distances differ: sun-planet {a * 1e3:.4f} mm, ring-planet "
            f"{a_ring * 1e3:.4f} mm; adjust {key} (the solved value would be {solved:.4f})"
        )
    return a


def check_ravigneaux_clearances(n_pairs: int, *, a_short: float, a_long: float, offset: float,
                                tip_short: float, tip_long: float, tip_ring: float,
                                tip_sun_small: float, names: Sequence[str] = (
                                    "planet_short", "planet_long", "ring", "sun_small"),
                                ) -> None:
    """Refuse Ravigneaux pairs whose tip circles collide where no mesh explains it.

    Pair ``i`` has its long planet at ``psi_i = 2 pi i / N`` on radius ``a_long`` and its
    short planet at ``psi_i + offset`` on ``a_short``. Checked (clearance > 0): the short
    planets against the ring's tip circle (``r_a,ring - (a_short + r_a,short)``), every two
    planets that do not mesh (the short planet and the long planets of the other pairs, the
    short planets, the long planets: centre distance minus both tip radii), and the long
    planets against the small sun (``a_long - r_a,long - r_a,sun``: the long planet reaches
    into the plane of the short planet and the small sun). The short planet and the large sun
    lie in different planes.

    Raises
    ------
    ValueError
        Naming the two bodies (with the pair number), their clearance [mm] and how it follows.
    """
    n_pairs = check_count(n_pairs, "n_pairs", low=1, high=MAX_PLANETS)
    for key, v in (("a_short", a_short), ("a_long", a_long), ("tip_short", tip_short),
                   ("tip_long", tip_long), ("tip_ring", tip_ring),
                   ("tip_sun_small", tip_sun_small)):
        check_real(v, key, low=0.0, low_open=True)
    check_real(offset, "offset", low=-2 * math.pi, high=2 * math.pi)
    if not (isinstance(names, Sequence) and len(names) == 4
            and all(isinstance(n, str) for n in names)):
        raise ValueError(f"names = {short(names)} is not admissible (admissible: four names)")
    short_, long_, ring, sun = (cut(n) for n in names)
    gap = tip_ring - (a_short + tip_short)
    if gap <= 0.0:
        raise ValueError(
            f"Ravigneaux set cannot be built: {short_} (every pair) collides with the {ring}: "
            f"clearance r_a,ring - (a_short + r_a,short) = {tip_ring * 1e3:.4f} - "
            f"({a_short * 1e3:.4f} + {tip_short * 1e3:.4f}) = {gap * 1e3:.4f} mm (must be "
            "> 0); use a smaller short planet or small sun, or a larger ring"
        )
    gap = a_long - tip_long - tip_sun_small
    if gap <= 0.0:
        raise ValueError(
            f"Ravigneaux set cannot be built: {long_} (every pair) collides with the {sun}: "
            f"clearance a_long - r_a,long - r_a,sun_small = {gap * 1e3:.4f} mm (must be > 0)"
        )
    planets = []
    for i in range(n_pairs):
        psi = 2 * math.pi * i / n_pairs
        planets.append((f"{long_}{i + 1}", a_long * math.cos(psi), a_long * math.sin(psi),
                        tip_long, i))
        planets.append((f"{short_}{i + 1}", a_short * math.cos(psi + offset),
                        a_short * math.sin(psi + offset), tip_short, i))
    for k, (n1, x1, y1, r1, i1) in enumerate(planets):
        for n2, x2, y2, r2, i2 in planets[k + 1:]:
            if i1 == i2:
                continue  # the short and long planet of one pair mesh
            gap = math.hypot(x2 - x1, y2 - y1) - r1 - r2
            if gap <= 0.0:
                raise ValueError(
                    f"Ravigneaux set cannot be built: the tip circles of {n1} and {n2} "
                    f"overlap: clearance (centre distance - both tip radii) {gap * 1e3:.4f} mm "
                    f"(must be > 0); use fewer pairs or smaller planets"
                )


def simple_planetary(*, z_sun: int, z_ring: int, module: float, sun: Body, ring: Body,
                     carrier: Body, planet: Body, sun_mesh: MeshSpec, ring_mesh: MeshSpec,
                     z_planet: int | None = None, n_planets: int | None = None,
                     planet_angles: Sequence[float] | None = None,
                     pressure_angle: float = math.radians(20.0), helix_angle: float = 0.0,
                     face_width: float = 0.02, profile_shift_sun: float = 0.0,
                     profile_shift_ring: float = 0.0, profile_shift_planet: float | None = None,
                     fixed: str = "ring", input: str = "sun", output: str = "carrier",
                     name: str = "simple-planetary", config: dict | None = None) -> GearSet:
    """A simple planetary set: sun, ring (``z_ring < 0``), carrier and N planets.

    ``planet`` is the template of every planet (its name gets the index appended, its angle is
    set from ``planet_angles``). The planet tooth number defaults to ``(|z_ring| - z_sun)//2``;
    when that leaves the centre distances unequal (``|z_ring| - z_sun`` odd), the planet
    profile shift is solved so that both meshes share one centre distance, unless given.
    """
    _parts(sun=sun, ring=ring, carrier=carrier, planet=planet, sun_mesh=sun_mesh,
           ring_mesh=ring_mesh, fixed=fixed, input=input, output=output, name=name,
           config=config)
    for key, spec in (("sun_mesh", sun_mesh), ("ring_mesh", ring_mesh)):
        if spec is None:
            raise TypeError(f"{key} must be a MeshSpec; got NoneType")
    _check_ring_and_sun(z_sun, z_ring, "z_sun", "z_ring")
    z_planet = check_count(z_planet, "z_planet", low=3, high=MAX_TEETH, optional=True)
    if z_planet is None:
        z_planet = (abs(z_ring) - z_sun) // 2
    angles = _planet_angles(z_sun, z_ring, n_planets, planet_angles)
    common = dict(module=module, pressure_angle=pressure_angle, face_width=face_width)
    t_sun = Toothing(z=z_sun, helix_angle=helix_angle, profile_shift=profile_shift_sun, **common)
    # an internal gear meshes with the hand of its planet: the ring has the planet's hand
    t_ring = Toothing(z=z_ring, helix_angle=-helix_angle, profile_shift=profile_shift_ring,
                      **common)
    if profile_shift_planet is None:
        profile_shift_planet = planet_profile_shift(t_sun, t_ring, z_planet)
    t_pl = Toothing(z=z_planet, helix_angle=-helix_angle, profile_shift=profile_shift_planet,
                    **common)
    g_sun = mesh_geometry(t_sun, t_pl)
    g_ring = mesh_geometry(t_ring, t_pl)
    a = g_sun.centre_distance
    if not math.isclose(a, g_ring.centre_distance, rel_tol=1e-6):
        raise ValueError(
            f"centre distances differ: sun-planet {a * 1e3:.4f} mm, ring-planet "
            f"{g_ring.centre_distance * 1e3:.4f} mm; adjust profile_shift_planet "
            f"(the solved value would be {planet_profile_shift(t_sun, t_ring, z_planet):.4f})"
        )
    check_planet_angles(z_sun, z_ring, angles, centre_distance=a,
                        planet_tip_radius=t_pl.tip_radius)
    sun_b = replace(sun, role="central")
    ring_b = replace(ring, role="central")
    car_b = replace(carrier, role="carrier")
    structures = []
    for i, psi in enumerate(angles, start=1):
        p = _planet(planet, i, car_b, psi, a)
        structures.append(_base(sun_b, p, car_b, t_sun, t_pl, sun_mesh, a))
        structures.append(_base(ring_b, p, car_b, t_ring, t_pl, ring_mesh, a))
    # order meshes: all sun meshes first, then ring meshes (reads naturally in outputs)
    structures.sort(key=lambda s: 0 if s.central.name == sun_b.name else 1)
    return compose(name, structures, fixed=(fixed,) if fixed else (), input=input,
                   output=output, config=config)


def wolfrom(*, z_sun: int, z_ring1: int, z_ring2: int, z_planet1: int, z_planet2: int,
            module: float, sun: Body, ring1: Body, ring2: Body, carrier: Body, planet: Body,
            sun_mesh: MeshSpec, ring_mesh: MeshSpec | None = None,
            ring1_mesh: MeshSpec | None = None, ring2_mesh: MeshSpec | None = None,
            n_planets: int = 3, pressure_angle: float = math.radians(20.0),
            face_width: float = 0.02, module2: float | None = None, step_offset: float = 0.0,
            helix_angle: float = 0.0, helix_angle2: float | None = None,
            profile_shift_sun: float = 0.0, profile_shift_ring1: float = 0.0,
            profile_shift_planet1: float | None = None, profile_shift_ring2: float = 0.0,
            profile_shift_planet2: float = 0.0,
            fixed: str = "ring1", input: str = "sun", output: str = "ring2",
            name: str = "wolfrom", config: dict | None = None) -> GearSet:
    """A Wolfrom set: sun, stepped planets (``z_planet1`` meshing sun and fixed ring 1,
    ``z_planet2`` meshing the output ring 2) and a free carrier.

    The second step may use its own module (``module2``) so that both steps share the centre
    distance. ``ring1_mesh`` and ``ring2_mesh`` describe the two ring meshes (``ring_mesh``
    both when they are alike). ``step_offset`` [rad] is the angle from a tooth of the first
    toothing to a tooth of the second (a manufacturing choice, measured in the planet's
    positive rotation sense); every stepped planet is identical.

    Helical gears follow the hand rules of :func:`simple_planetary`: ``helix_angle`` is the
    sun's (> 0 right hand); the planet's first toothing and ring 1 get the opposite hand (an
    external pair has opposite hands, the ring its planet's). ``helix_angle2`` is the helix
    angle of the planet's second toothing, signed with its hand, which ring 2 shares; by
    default the first toothing's (``-helix_angle``). Profile shifts (DIN 3960 signs):
    ``profile_shift_planet1`` is solved so that sun and ring 1 share the centre distance
    unless given (then they must agree); the second step meshes ring 2 at that centre
    distance with ``profile_shift_ring2`` and ``profile_shift_planet2``.

    Raises
    ------
    ValueError
        If the planets cannot be assembled: ``(z_s + |z_r1|) psi / 2 pi`` must be an integer
        at every planet angle ``psi`` (step 1) and, for identical stepped planets,
        ``(z_s z_p2 + |z_r2| z_p1) psi / (2 pi gcd(z_p1, z_p2))`` too (step 2; the planet may
        be inserted turned by any number of step-1 teeth); if neighbouring planets overlap
        (either step); if the centre distances of sun and ring 1 differ with a given
        ``profile_shift_planet1``; if a helix angle is out of range (``|beta| < 45°``).
    """
    _parts(sun=sun, ring1=ring1, ring2=ring2, carrier=carrier, planet=planet,
           sun_mesh=sun_mesh, ring_mesh=ring_mesh, ring1_mesh=ring1_mesh, ring2_mesh=ring2_mesh,
           fixed=fixed, input=input, output=output, name=name, config=config)
    if sun_mesh is None:
        raise TypeError("sun_mesh must be a MeshSpec; got NoneType")
    check_count(z_ring2, "z_ring2", low=-MAX_TEETH, high=MAX_TEETH)
    check_real(step_offset, "step_offset")
    check_real(helix_angle2, "helix_angle2", optional=True)
    check_real(module2, "module2", optional=True, low=0.0, low_open=True)
    if ring1_mesh is None or ring2_mesh is None:
        if ring_mesh is None:
            raise ValueError("wolfrom: give ring_mesh, or both ring1_mesh and ring2_mesh")
        ring1_mesh = ring1_mesh or ring_mesh
        ring2_mesh = ring2_mesh or ring_mesh
    if not math.isfinite(step_offset):
        raise ValueError(f"step_offset = {step_offset!r} must be finite")
    m2 = module if module2 is None else module2
    _check_ring_and_sun(z_sun, z_ring1, "z_sun", "z_ring1")
    if z_ring2 >= 0:
        raise ValueError(f"z_ring2 = {z_ring2} must be negative (internal toothing)")
    beta1 = -helix_angle  # the planet's first toothing and ring 1: opposite to the sun
    beta2 = beta1 if helix_angle2 is None else float(helix_angle2)
    common = dict(pressure_angle=pressure_angle, face_width=face_width)
    t_s = Toothing(z=z_sun, module=module, helix_angle=helix_angle,
                   profile_shift=profile_shift_sun, **common)
    t_r1 = Toothing(z=z_ring1, module=module, helix_angle=beta1,
                    profile_shift=profile_shift_ring1, **common)
    solved = planet_profile_shift(t_s, t_r1, z_planet1)
    t_p1 = Toothing(z=z_planet1, module=module, helix_angle=beta1,
                    profile_shift=solved if profile_shift_planet1 is None
                    else profile_shift_planet1, **common)
    a = _common_centre_distance(t_s, t_r1, t_p1, solved, "profile_shift_planet1")
    t_p2 = Toothing(z=z_planet2, module=m2, helix_angle=beta2,
                    profile_shift=profile_shift_planet2, **common)
    t_r2 = Toothing(z=z_ring2, module=m2, helix_angle=beta2, profile_shift=profile_shift_ring2,
                    **common)
    try:
        g2 = mesh_geometry(t_r2, t_p2, a)
    except ValueError as exc:
        raise ValueError(
            f"ring2-planet mesh at the common centre distance {a * 1e3:.4f} mm: {exc}; adjust "
            "module2, helix_angle2_deg or the step-2 profile shifts (profile_shift_ring2, "
            "profile_shift_planet2)"
        ) from None
    if g2.contact_ratio < 1:
        raise ValueError("ring2-planet contact ratio below 1 at the common centre distance")
    angles = _planet_angles(z_sun, z_ring1, n_planets, None)
    for t_p in (t_p1, t_p2):  # neighbouring planets must not overlap in either step
        check_planet_angles(z_sun, z_ring1, angles, centre_distance=a,
                            planet_tip_radius=t_p.tip_radius)
    check_stepped_planet_angles(z_sun, z_ring2, z_planet1, z_planet2, angles)
    sun_b, r1, r2 = (replace(b, role="central") for b in (sun, ring1, ring2))
    car_b = replace(carrier, role="carrier")
    structures = []
    for i, psi in enumerate(angles, start=1):
        p = _planet(planet, i, car_b, psi, a)
        structures.append(_base(sun_b, p, car_b, t_s, t_p1, sun_mesh, a))
        structures.append(_base(r1, p, car_b, t_r1, t_p1, ring1_mesh, a))
        bs2 = _base(r2, p, car_b, t_r2, t_p2, ring2_mesh, a)
        structures.append(replace(bs2, mesh=replace(bs2.mesh, tooth_offset2=step_offset)))
    return compose(name, structures, fixed=(fixed,), input=input, output=output,
                   config=config)


def check_stepped_planet_angles(z_sun: int, z_ring2: int, z_planet1: int, z_planet2: int,
                                angles: Sequence[float], tol: float = 1e-6) -> None:
    """Check that identical stepped planets fit the second ring at ``angles`` [rad].

    With the first step assembled (sun and ring 1), planet ``n`` at ``psi_n`` fits ring 2 iff
    ``(z_s z_p2 + |z_r2| z_p1) (psi_n - psi_1) / (2 pi g)`` is an integer, ``g =
    gcd(z_p1, z_p2)``. Derivation: turning planet 1's configuration to ``psi_n`` and rolling
    the planet back onto the sun turns it by ``(z_s + z_p1) dpsi / z_p1`` (mod one step-1
    pitch, the ways the planet can be inserted); ring 2 needs ``(z_r2 + z_p2) dpsi / z_p2``
    (signed ``z_r2``); both agree modulo ``2 pi / z_p2`` for some insertion iff the condition
    holds. Verified against the tooth-by-tooth assembly of :mod:`gearvib.assembly`.

    Raises
    ------
    ValueError
        Naming the planet angle, the condition and its value.
    """
    for key, z in (("z_sun", z_sun), ("z_ring2", z_ring2), ("z_planet1", z_planet1),
                   ("z_planet2", z_planet2)):
        check_count(z, key, low=-MAX_TEETH, high=MAX_TEETH)
    angles = [float(a) for a in check_array(angles, "angles", ndim=1)]
    if len(angles) > MAX_PLANETS:
        raise ValueError(f"angles: {len(angles)} planets (admissible: at most {MAX_PLANETS})")
    tol = check_real(tol, "tol", low=0.0)
    g = math.gcd(int(z_planet1), int(z_planet2))
    if g == 0:
        raise ValueError("z_planet1 and z_planet2 must not both be 0")
    total = z_sun * z_planet2 - z_ring2 * z_planet1
    for psi in angles[1:]:
        k = total * ((psi - angles[0]) % (2 * math.pi)) / (2 * math.pi * g)
        if abs(k - round(k)) > tol * max(1.0, abs(k)):
            raise ValueError(
                f"identical stepped planets cannot be assembled at {math.degrees(psi):.6g}°: "
                f"(z_sun·z_planet2 + |z_ring2|·z_planet1)·psi/(360°·gcd(z_planet1, z_planet2)) "
                f"= ({z_sun}·{z_planet2} + {-z_ring2}·{z_planet1})·psi/(360°·{g}) = {k:.4g} "
                "must be an integer (change z_ring2 or z_planet2, or the number of planets)"
            )


def ravigneaux(*, z_sun_small: int, z_sun_large: int, z_ring: int, z_planet_short: int,
               z_planet_long: int, module: float, sun_small: Body, sun_large: Body, ring: Body,
               carrier: Body, planet_short: Body, planet_long: Body, sun_mesh: MeshSpec,
               ring_mesh: MeshSpec, planet_mesh: MeshSpec, n_pairs: int = 3,
               pressure_angle: float = math.radians(20.0), face_width: float = 0.02,
               planet_mesh_phases: Sequence[float] | None = None, helix_angle: float = 0.0,
               profile_shift_sun_small: float = 0.0, profile_shift_sun_large: float = 0.0,
               profile_shift_ring: float = 0.0, profile_shift_planet_short: float = 0.0,
               profile_shift_planet_long: float | None = None,
               fixed: str = "sun_large", input: str = "sun_small", output: str = "ring",
               name: str = "ravigneaux", config: dict | None = None) -> GearSet:
    """A Ravigneaux set: small sun – short planets – long planets – ring, large sun – long
    planets, with planet-planet meshes (the paper's Figures 4 and 5).

    The long planet meshes the large sun, the ring and the short planet with one toothing;
    the short-planet position follows from the three centre distances (law of cosines). All
    mesh phases, the planet-planet ones included, follow from the tooth geometry in
    :func:`gearvib.assembly.assemble`; ``planet_mesh_phases`` (one mesh position per pair,
    cycles) overrides those of the planet-planet meshes.

    Helical gears follow the hand rules of :func:`simple_planetary`: ``helix_angle`` is the
    small sun's (> 0 right hand); the short planet has the opposite hand, the long planet
    (external mate of the short one) the small sun's, the large sun the opposite, and the ring
    the long planet's. Profile shifts (DIN 3960 signs): ``profile_shift_planet_long`` is
    solved so that large sun and ring share the centre distance unless given (then they must
    agree); the short planet meshes the small sun and the long planet at their zero-backlash
    centre distances with ``profile_shift_planet_short``.

    The tip circles are checked for collisions that the meshes do not explain: every short
    planet against the ring and against the planets of the neighbouring pairs, the long
    planets against each other and against the small sun (in the plane of the planet-planet
    mesh). The short planet and the large sun are taken to lie in different planes, as in
    every Ravigneaux set.

    Raises
    ------
    ValueError
        If the short and long planets cannot mesh, or the ``n_pairs`` equally spaced pairs
        cannot be assembled: ``(z_sun_large + |z_ring|) / n_pairs`` (long planets between
        large sun and ring) and ``(z_sun_small + z_sun_large) / n_pairs`` (a pair turned by
        one spacing must fit both suns through the short planet) must be integers; if two tip
        circles overlap (the message names both bodies and the clearance); if the centre
        distances of large sun and ring differ with a given ``profile_shift_planet_long``.
    """
    _parts(sun_small=sun_small, sun_large=sun_large, ring=ring, carrier=carrier,
           planet_short=planet_short, planet_long=planet_long, sun_mesh=sun_mesh,
           ring_mesh=ring_mesh, planet_mesh=planet_mesh, fixed=fixed, input=input,
           output=output, name=name, config=config)
    for key, spec in (("sun_mesh", sun_mesh), ("ring_mesh", ring_mesh),
                      ("planet_mesh", planet_mesh)):
        if spec is None:
            raise TypeError(f"{key} must be a MeshSpec; got NoneType")
    check_ravigneaux_pairs(z_sun_small, z_sun_large, z_ring, n_pairs)
    if planet_mesh_phases is not None:
        planet_mesh_phases = [float(p) for p in planet_mesh_phases]
        if len(planet_mesh_phases) != n_pairs or not all(map(math.isfinite,
                                                              planet_mesh_phases)):
            raise ValueError(f"planet_mesh_phases needs {n_pairs} finite values (one per pair)")
    _check_ring_and_sun(z_sun_large, z_ring, "z_sun_large", "z_ring")
    if z_sun_small <= 0:
        raise ValueError(f"z_sun_small = {z_sun_small} must be positive (external toothing)")
    common = dict(module=module, pressure_angle=pressure_angle, face_width=face_width)
    h = helix_angle  # small sun and long planet; short planet, large sun: -h; ring: +h
    t_s1 = Toothing(z=z_sun_small, helix_angle=h, profile_shift=profile_shift_sun_small,
                    **common)
    t_s2 = Toothing(z=z_sun_large, helix_angle=-h, profile_shift=profile_shift_sun_large,
                    **common)
    t_r = Toothing(z=z_ring, helix_angle=h, profile_shift=profile_shift_ring, **common)
    t_ps = Toothing(z=z_planet_short, helix_angle=-h, profile_shift=profile_shift_planet_short,
                    **common)
    solved = planet_profile_shift(t_s2, t_r, z_planet_long)
    t_pl = Toothing(z=z_planet_long, helix_angle=h,
                    profile_shift=solved if profile_shift_planet_long is None
                    else profile_shift_planet_long, **common)
    a_l = _common_centre_distance(t_s2, t_r, t_pl, solved, "profile_shift_planet_long")
    a_s = mesh_geometry(t_s1, t_ps).centre_distance
    d = mesh_geometry(t_ps, t_pl).centre_distance
    cos_d = (a_s**2 + a_l**2 - d**2) / (2 * a_s * a_l)
    if not -1 < cos_d < 1:
        raise ValueError("Ravigneaux: short and long planet cannot mesh at these centre "
                         "distances (check tooth numbers)")
    offset = math.acos(cos_d)
    check_ravigneaux_clearances(
        n_pairs, a_short=a_s, a_long=a_l, offset=offset, tip_short=t_ps.tip_radius,
        tip_long=t_pl.tip_radius, tip_ring=t_r.tip_radius, tip_sun_small=t_s1.tip_radius,
        names=(planet_short.name, planet_long.name, ring.name, sun_small.name))
    sun1, sun2, ring_b = (replace(b, role="central") for b in (sun_small, sun_large, ring))
    car_b = replace(carrier, role="carrier")
    structures, pp = [], []
    for i in range(n_pairs):
        psi = 2 * math.pi * i / n_pairs
        pl = _planet(planet_long, i + 1, car_b, psi, a_l)
        ps = _planet(planet_short, i + 1, car_b, psi + offset, a_s)
        structures.append(_base(sun1, ps, car_b, t_s1, t_ps, sun_mesh, a_s))
        structures.append(_base(sun2, pl, car_b, t_s2, t_pl, sun_mesh, a_l))
        structures.append(_base(ring_b, pl, car_b, t_r, t_pl, ring_mesh, a_l))
        mesh = _mesh(f"{ps.name}-{pl.name}", ps.name, pl.name, t_ps, t_pl, planet_mesh, d)
        if planet_mesh_phases is not None:
            mesh = replace(mesh, phase=planet_mesh_phases[i])
        pp.append(mesh)
    return compose(name, structures, extra_meshes=pp, fixed=(fixed,), input=input,
                   output=output, config=config)


def check_ravigneaux_pairs(z_sun_small: int, z_sun_large: int, z_ring: int,
                           n_pairs: int) -> None:
    """Check that ``n_pairs`` equally spaced Ravigneaux planet pairs can be assembled.

    Pair ``n`` is pair 1 turned by ``dpsi = 2 pi n / N``. Following the tooth phases at the
    contacts: the long planet between large sun and ring needs ``(z_s2 + |z_r|) dpsi / 2 pi``
    integer (as in a simple set); the spins that the small sun imposes on the short planet and
    the short planet on the long one must agree with the spin the large sun imposes on the
    long planet, which needs ``(z_s1 + z_s2) dpsi / 2 pi`` integer. Verified against the
    tooth-by-tooth assembly of :mod:`gearvib.assembly`.

    Raises
    ------
    ValueError
        Naming the failed condition and its value.
    """
    for key, z in (("z_sun_small", z_sun_small), ("z_sun_large", z_sun_large),
                   ("z_ring", z_ring)):
        check_count(z, key, low=-MAX_TEETH, high=MAX_TEETH)
    check_count(n_pairs, "n_pairs", low=1, high=MAX_PLANETS)
    for label, total in (("z_sun_large + |z_ring|", z_sun_large - z_ring),
                         ("z_sun_small + z_sun_large", z_sun_small + z_sun_large)):
        if total % n_pairs:
            raise ValueError(
                f"Ravigneaux set cannot be assembled with {n_pairs} equally spaced planet "
                f"pairs: ({label})/n_pairs = {total}/{n_pairs} = {total / n_pairs:.4g} must be "
                "an integer (both conditions: (z_sun_large + |z_ring|)/n_pairs and "
                "(z_sun_small + z_sun_large)/n_pairs)"
            )


def prefixed(gs: GearSet, prefix: str) -> tuple[list[Body], list[Mesh]]:
    """The bodies and meshes of ``gs`` with ``prefix`` put before every name (and carrier).

    Used to combine stages (:func:`two_stage`, :func:`gearvib.stages.multi_stage`).
    """
    if not isinstance(gs, GearSet):
        raise TypeError(f"gs must be a GearSet; got {type(gs).__name__}")
    check_text(prefix, "prefix", empty=True)
    ren = {b.name: f"{prefix}{b.name}" for b in gs.bodies}
    bodies = [replace(b, name=ren[b.name], carrier=ren.get(b.carrier) if b.carrier else None)
              for b in gs.bodies]
    meshes = [replace(m, name=f"{prefix}{m.name}", gear1=ren[m.gear1], gear2=ren[m.gear2])
              for m in gs.meshes]
    return bodies, meshes


def two_stage(stage1: GearSet, stage2: GearSet, *, shaft_stiffness: float = RIGID,
              shaft_damping: float = 0.0, name: str = "two-stage",
              config: dict | None = None) -> GearSet:
    """Two planetary stages in series: the output of stage 1 drives the input of stage 2.

    Bodies, meshes and the stages' own couplings are renamed with the prefixes ``s1.`` and
    ``s2.``; a torsional shaft (rigid by default) joins ``stage1.output`` and ``stage2.input``.
    """
    for key, stage in (("stage1", stage1), ("stage2", stage2)):
        if not isinstance(stage, GearSet):
            raise TypeError(f"{key} must be a GearSet; got {type(stage).__name__}")
    _parts(name=name, config=config)
    b1, m1 = prefixed(stage1, "s1.")
    b2, m2 = prefixed(stage2, "s2.")
    fixed = tuple(f"s1.{f}" for f in stage1.fixed) + tuple(f"s2.{f}" for f in stage2.fixed)
    coupling = Coupling(f"s1.{stage1.output}", f"s2.{stage2.input}", shaft_stiffness,
                        shaft_damping)
    own = tuple(replace(c, body1=f"{prefix}{c.body1}", body2=f"{prefix}{c.body2}")
                for prefix, stage in (("s1.", stage1), ("s2.", stage2))
                for c in stage.couplings)
    return GearSet(name=name, bodies=tuple(b1 + b2), meshes=tuple(m1 + m2), fixed=fixed,
                   input=f"s1.{stage1.input}", output=f"s2.{stage2.output}",
                   couplings=(*own, coupling), config=dict(config or {}))
