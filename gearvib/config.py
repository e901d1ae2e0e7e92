"""Gear-set descriptions in TOML, and the built-in presets.

A description is a TOML file (or the equivalent dict) with a ``type`` that selects a builder:
``simple``, ``wolfrom``, ``ravigneaux``, ``parallel`` (a parallel-axis gear pair, optionally
with an idler), ``two-stage``, ``multi-stage`` (``[stage1]`` ... ``[stageN]`` of any of the
former in series, joined by ``[[shaft]]``) or ``general`` (bodies, meshes and couplings listed
one by one; this is also how a literature model given directly by its lumped parameters is
written). A machine without gears (shafts and rolling bearings, e.g. a bearing test rig) is
``type = "shafts"`` (:mod:`gearvib.rig`): it serves measured reports and the catalogue, not
the simulator; :func:`load_description` reads either kind, :func:`load_gearset` gear sets
only. All values are SI (m, kg, kg m^2, N/m, N s/m), angles are in degrees
in keys ending in ``_deg``. A support stiffness may be ``"rigid"`` (the DOF is removed) or
``"free"`` (0). Every table is checked: an unknown key is an error that names the key and the
admissible ones, and every value is type- and range-checked (numbers finite, integers such as
tooth numbers integers -- ``33.9`` and ``"33"`` are refused --, counts and list lengths
bounded, ``n_planets`` and ``planet_angles_deg`` consistent). See the README for a full example.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import re
import tomllib
from dataclasses import replace
from importlib import resources
from pathlib import Path
from typing import Any, cast

from gearvib.checks import TABLE, check_integer, check_number
from gearvib.checks import short as _short
from gearvib.faults.description import FaultError, faults_from_list
from gearvib.geometry import MAX_TEETH, Toothing
from gearvib.paths import exists, is_file
from gearvib.sensors.description import SensorError, sensors_from_list
from gearvib.stages import HOUSING, MAX_STAGES, multi_stage, parallel_stage, stage_prefix
from gearvib.stiffness import MAX_FOURIER, MAX_STIFFNESS, stiffness_from_dict
from gearvib.structure import (
    MAX_PLANETS,
    RIGID,
    Body,
    Coupling,
    GearSet,
    Mesh,
    Role,
    Support,
    check_damping_law,
    ravigneaux,
    simple_planetary,
    two_stage,
    wolfrom,
)
from gearvib.structure import MeshSpec as _MeshSpec

__all__ = [
    "MAX_LIST",
    "MAX_PLANETS",
    "MAX_TEETH",
    "MAX_TOML_BYTES",
    "MAX_TOML_DEPTH",
    "ConfigError",
    "check_keys",
    "config_hash",
    "description_from_dict",
    "example_text",
    "example_titles",
    "gearset_from_dict",
    "list_examples",
    "list_presets",
    "list_rigs",
    "load_config",
    "load_description",
    "load_gearset",
    "preset_text",
    "preset_titles",
    "read_toml",
    "rig_from_dict",
    "rig_titles",
]


class ConfigError(ValueError):
    """Invalid input: a gear-set description, run settings or a study recipe.

    The message names the key (or command-line option) and what is admissible.
    """


MAX_LIST = 100_000
"""Longest list of numbers accepted in a description (stiffness curves, tables)."""
MAX_DAMPING_RATIO = 10.0
"""Largest mesh damping ratio accepted."""
MAX_DAMPING = 1e12
"""Largest damping [N s/m, N m s/rad] accepted."""
MASS_RANGE = (1e-9, 1e9)
"""Admissible masses [kg] (zero and negative masses get the builder's own message)."""
INERTIA_RANGE = (1e-15, 1e9)
"""Admissible moments of inertia [kg m^2]."""
MIN_LENGTH = 1e-5
"""Smallest module, face width or radius [m] accepted (0.01 mm)."""
MAX_SHIFT = 10.0
"""Largest profile-shift coefficient (absolute value) accepted."""
MAX_BODIES = 200
"""Most ``[[body]]``, ``[[mesh]]`` or ``[[coupling]]`` entries accepted."""


_TOP = {"name", "title", "description", "type", "operation", "geometry", "bodies", "meshes",
        "body", "mesh", "coupling", "stage1", "stage2", "shaft", "simulation", "references",
        "fault", "sensor", "rolling_bearing"}
_STAGE_KEY = re.compile(r"stage([1-9][0-9]?)")
"""Top-level keys of the stages of a ``multi-stage`` description (``stage1`` ...)."""
_COMMON_TOP = {"name", "title", "description", "type", "simulation", "references", "body",
               "coupling", "operation", "fault", "sensor", "rolling_bearing"}
_TYPE_KEYS = {
    "simple": {"geometry", "bodies", "meshes"},
    "wolfrom": {"geometry", "bodies", "meshes"},
    "ravigneaux": {"geometry", "bodies", "meshes"},
    "parallel": {"geometry", "bodies", "meshes"},
    "general": {"mesh"},
    "two-stage": {"stage1", "stage2", "shaft"},
    "multi-stage": {"shaft"},
}
"""Top-level keys per ``type`` besides the common ones (``[[body]]`` and ``[[coupling]]``
join adjacent drive components to any type; ``[[mesh]]`` is for ``general`` only)."""
_OPERATION = {"fixed", "input", "output"}
_SUPPORT = {"radial", "tangential", "axial", "torsional", "radial_damping",
            "tangential_damping", "axial_damping", "torsional_damping"}
_BODY = {"mass", "inertia", "support", "comment"}
_BODY_GENERAL = _BODY | {"name", "role", "carrier", "angle_deg", "radius"}
_MESH_SPEC = {"stiffness", "back_stiffness", "backlash", "damping", "damping_ratio",
              "damping_law", "comment"}
_MESH_GENERAL = _MESH_SPEC | {"name", "gear1", "gear2", "toothing1", "toothing2",
                              "base_radius1", "base_radius2", "pressure_angle_deg",
                              "helix_angle_deg", "z1", "z2", "phase", "centre_distance",
                              "tooth_offset1_deg", "tooth_offset2_deg"}
_TOOTHING = {"z", "module", "pressure_angle_deg", "helix_angle_deg", "profile_shift",
             "face_width", "addendum", "dedendum"}
_COUPLING = {"body1", "body2", "stiffness", "damping"}
_STIFFNESS_TEXT = {"model", "path", "position_unit", "stiffness_unit", "source"}
_SIMULATION = {"drive", "speed_start_rpm", "speed_end_rpm", "duration", "input_torque",
               "load_torque", "load_inertia", "drive_stiffness", "drive_damping", "motor",
               "fs_out", "dt", "gyroscopic"}
"""Keys of ``[simulation]``; their values are checked by :mod:`gearvib.simulation.settings`."""
_WOLFROM_SHIFTS = ("profile_shift_sun", "profile_shift_ring1", "profile_shift_planet1",
                   "profile_shift_ring2", "profile_shift_planet2")
_RAVIGNEAUX_SHIFTS = ("profile_shift_sun_small", "profile_shift_sun_large", "profile_shift_ring",
                      "profile_shift_planet_short", "profile_shift_planet_long")
_SOLVED_SHIFTS = {"profile_shift_planet", "profile_shift_planet1", "profile_shift_planet_long"}
"""Planet profile shifts solved for a common centre distance when not given."""
_GEOMETRY = {
    "simple": {"module", "pressure_angle_deg", "helix_angle_deg", "face_width", "z_sun",
               "z_ring", "z_planet", "profile_shift_sun", "profile_shift_ring",
               "profile_shift_planet", "planet_angles_deg", "n_planets"},
    "wolfrom": {"module", "module2", "pressure_angle_deg", "face_width", "z_sun", "z_ring1",
                "z_ring2", "z_planet1", "z_planet2", "n_planets", "planet_step_offset_deg",
                "helix_angle_deg", "helix_angle2_deg", *_WOLFROM_SHIFTS},
    "ravigneaux": {"module", "pressure_angle_deg", "face_width", "z_sun_small", "z_sun_large",
                   "z_ring", "z_planet_short", "z_planet_long", "n_pairs",
                   "planet_mesh_phases", "helix_angle_deg", *_RAVIGNEAUX_SHIFTS},
}
_BODIES = {
    "simple": ("sun", "ring", "carrier", "planet"),
    "wolfrom": ("sun", "ring1", "ring2", "carrier", "planet"),
    "ravigneaux": ("sun_small", "sun_large", "ring", "carrier", "planet_short", "planet_long"),
}
_PARALLEL_GEOMETRY = {"module", "pressure_angle_deg", "helix_angle_deg", "face_width", "z_pinion",
                      "z_wheel", "z_idler", "profile_shift_pinion", "profile_shift_wheel",
                      "profile_shift_idler", "centre_distance", "axis_angle_deg",
                      "idler_angle_deg"}
_PARALLEL_BODIES = ("pinion", "wheel", "idler", HOUSING)
_PARALLEL_MESHES = ("pinion", "wheel")
"""``[meshes.pinion]``: the pinion's mesh (with the wheel or the idler); ``[meshes.wheel]``: the
wheel's mesh with the idler (only with an idler; default the pinion's)."""
_DEFAULT_ROLES = {
    "simple": ("ring", "sun", "carrier"),
    "wolfrom": ("ring1", "sun", "ring2"),
    "ravigneaux": ("sun_large", "sun_small", "ring"),
}
_MESHES = {
    "simple": ("sun", "ring"),
    "wolfrom": ("sun", "ring", "ring1", "ring2"),
    "ravigneaux": ("sun", "ring", "planet"),
}


def check_keys(table: Any, allowed: set[str], where: str) -> dict:
    """Return ``table``; raise :class:`ConfigError` naming the first unknown key."""
    if not isinstance(table, dict):
        raise ConfigError(f"{where} must be a table, got {type(table).__name__}")
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ConfigError(
            f"unknown key {unknown[0]!r} in {where} (admissible: {', '.join(sorted(allowed))})"
        )
    return table


def _require(table: dict, key: str, where: str) -> Any:
    if key not in table:
        raise ConfigError(f"missing key {key!r} in {where}")
    return table[key]


def _number(value: Any, where: str, *, low: float | None = None, high: float | None = None,
            strict: bool = False) -> float:
    """A finite number (a bool, a string or a number beyond the float range is refused).

    ``low``/``high``: admissible bounds (``strict``: ``> low``).
    """
    return check_number(value, where, low=low, high=high, low_open=strict, error=ConfigError,
                        wording=TABLE)


def _finite(value: Any, where: str) -> float:
    return _number(value, where)


def _positive_in(value: Any, where: str, bounds: tuple[float, float]) -> float:
    """A finite number; positive values must lie in ``bounds`` (zero and negative values are
    left to the builder, whose message says "must be > 0")."""
    v = _number(value, where, high=bounds[1])
    if 0 < v < bounds[0]:
        raise ConfigError(f"{where} = {v!r} is not admissible (admissible: {bounds[0]:g} .. "
                          f"{bounds[1]:g})")
    return v


def _string(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value:
        raise ConfigError(f"{where} must be a non-empty string, got {_short(value)}")
    return value


def _numbers(value: Any, where: str, *, max_len: int = MAX_LIST, min_len: int = 0,
             magnitude: float | None = None) -> list[float]:
    """A list of finite numbers of bounded length (and magnitude)."""
    if not isinstance(value, list | tuple):
        raise ConfigError(f"{where} must be a list of numbers, got {_short(value)}")
    if not min_len <= len(value) <= max_len:
        raise ConfigError(f"{where} has {len(value)} values (admissible: {min_len}..{max_len})")
    low = -magnitude if magnitude is not None else None
    return [_number(v, f"{where}[{i}]", low=low, high=magnitude) for i, v in enumerate(value)]


def _stiffness_value(value: Any, where: str) -> float:
    if isinstance(value, str):
        if value == "rigid":
            return RIGID
        if value == "free":
            return 0.0
        raise ConfigError(f"{where} = {_short(value)}: admissible are a number >= 0, 'rigid' "
                          "or 'free'")
    return _number(value, where, low=0.0, high=MAX_STIFFNESS)


def _support(table: dict | None, where: str) -> Support:
    if table is None:
        return Support()
    check_keys(table, _SUPPORT, where)
    kw = {}
    for k, v in table.items():
        kw[k] = _stiffness_value(v, f"{where}.{k}") if not k.endswith("_damping") else \
            _number(v, f"{where}.{k}", low=0.0, high=MAX_DAMPING)
    try:
        return Support(**kw)
    except ValueError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _body(name: str, table: dict, role: Role, where: str) -> Body:
    check_keys(table, _BODY, where)
    try:
        # planet templates get their carrier and angle from the builder
        return Body(name=name, role=role, carrier="carrier" if role == "planet" else None,
                    mass=_positive_in(_require(table, "mass", where), f"{where}.mass",
                                      MASS_RANGE),
                    inertia=_positive_in(_require(table, "inertia", where),
                                         f"{where}.inertia", INERTIA_RANGE),
                    support=_support(table.get("support"), f"{where}.support"))
    except ValueError as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(f"{where}: {exc}") from None


def _stiffness_dict(table: Any, where: str, base: Path | None) -> dict:
    """The checked stiffness table with a relative CSV ``path`` resolved against ``base``."""
    if not isinstance(table, dict):
        raise ConfigError(f"{where} must be a table such as {{model = \"constant\", k = 1e8}}")
    d = dict(table)
    for k, v in d.items():  # values: finite numbers, bounded lists, or strings
        if k in _STIFFNESS_TEXT and not isinstance(v, str):
            raise ConfigError(f"{where}.{k} must be a string, got {_short(v)}")
        if isinstance(v, list | tuple):
            _numbers(v, f"{where}.{k}", max_len=MAX_FOURIER if k in ("cos", "sin")
                     else MAX_LIST, magnitude=MAX_STIFFNESS)
        elif isinstance(v, int | float) and not isinstance(v, bool):
            _number(v, f"{where}.{k}", low=-MAX_STIFFNESS, high=MAX_STIFFNESS)
        elif not isinstance(v, str | bool):
            raise ConfigError(f"{where}.{k} must be a number, a string or a list of numbers, "
                              f"got {_short(v)}")
    if "path" in d:
        if not isinstance(d["path"], str) or not d["path"]:
            raise ConfigError(f"{where}.path must be a file name, got {_short(d['path'])}")
        if base is not None and not Path(d["path"]).is_absolute():
            d["path"] = str(base / d["path"])
    return d


def _stiffness_table(table: Any, where: str, base: Path | None, deferred: bool):
    """A stiffness model, or its checked table when the builder supplies the geometry."""
    d = _stiffness_dict(table, where, base)
    if deferred:
        return d
    try:
        return stiffness_from_dict(d)
    except (ValueError, TypeError, KeyError, OverflowError) as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _mesh_spec(table: dict, where: str, base: Path | None,
               deferred: bool = False) -> _MeshSpec:
    check_keys(table, _MESH_SPEC, where)
    try:
        return _MeshSpec(
            stiffness=_stiffness_table(_require(table, "stiffness", where),
                                       f"{where}.stiffness", base, deferred),
            back_stiffness=_stiffness_table(table["back_stiffness"], f"{where}.back_stiffness",
                                            base, deferred)
            if "back_stiffness" in table else None,
            backlash=_number(table.get("backlash", 0.0), f"{where}.backlash", low=-0.01,
                             high=0.01),
            damping=_number(table["damping"], f"{where}.damping", low=0.0, high=MAX_DAMPING)
            if "damping" in table else None,
            damping_ratio=_number(table["damping_ratio"], f"{where}.damping_ratio", low=0.0,
                                  high=MAX_DAMPING_RATIO)
            if "damping_ratio" in table else None,
            damping_law=_damping_law(table.get("damping_law", "gated"), f"{where}.damping_law"),
        )
    except ValueError as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(f"{where}: {exc}") from None


def _damping_law(value: Any, where: str) -> str:
    """A mesh-damping law name (``"gated"`` or ``"viscous"``)."""
    try:
        return check_damping_law(value, where)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None


def _toothing(table: dict, where: str) -> Toothing:
    check_keys(table, _TOOTHING, where)
    kw: dict[str, Any] = {"z": _tooth_number(_require(table, "z", where), f"{where}.z"),
                          "module": _number(_require(table, "module", where), f"{where}.module",
                                            low=MIN_LENGTH, high=1.0)}
    if "pressure_angle_deg" in table:
        kw["pressure_angle"] = math.radians(_number(table["pressure_angle_deg"],
                                                    f"{where}.pressure_angle_deg"))
    if "helix_angle_deg" in table:
        kw["helix_angle"] = math.radians(_number(table["helix_angle_deg"],
                                                 f"{where}.helix_angle_deg"))
    for k, lo, hi in (("profile_shift", -MAX_SHIFT, MAX_SHIFT), ("face_width", MIN_LENGTH, 10.0),
                      ("addendum", 0.0, 10.0), ("dedendum", 0.0, 10.0)):
        if k in table:
            kw[k] = _number(table[k], f"{where}.{k}", low=lo, high=hi)
    try:
        return Toothing(**kw)
    except ValueError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _operation(cfg: dict) -> dict:
    op = check_keys(_require(cfg, "operation", "the description"), _OPERATION, "[operation]")
    fixed = op.get("fixed", [])
    if isinstance(fixed, str):
        fixed = [fixed]
    if not isinstance(fixed, list) or not all(isinstance(f, str) and f for f in fixed):
        raise ConfigError(f"[operation].fixed must name a member (a string) or list members, "
                          f"got {_short(fixed)}")
    return {"fixed": list(fixed),
            "input": _string(_require(op, "input", "[operation]"), "[operation].input"),
            "output": _string(_require(op, "output", "[operation]"), "[operation].output")}


def _integer(value: Any, where: str, *, low: int | None = None, high: int | None = None
             ) -> int:
    """An integer key (a float with a fraction, a bool or a string is refused)."""
    return check_integer(value, where, low=low, high=high, error=ConfigError, wording=TABLE)


def _tooth_number(value: Any, where: str) -> int:
    """A signed tooth number: an integer, ``3 <= |z| <= MAX_TEETH``."""
    z = _integer(value, where, low=-MAX_TEETH, high=MAX_TEETH)
    if abs(z) < 3:
        raise ConfigError(f"{where} = {z} is not admissible (admissible: 3 <= |z| <= "
                          f"{MAX_TEETH}, negative for internal toothing)")
    return z


def _builder_meshes(kind: str, meshes_t: dict, base: Path | None) -> dict[str, _MeshSpec]:
    """The mesh families of a builder; Wolfrom's two rings may share ``[meshes.ring]``."""
    def spec(key: str) -> _MeshSpec:
        return _mesh_spec(_require(meshes_t, key, "[meshes]"), f"[meshes.{key}]", base,
                          deferred=True)

    if kind != "wolfrom":
        return {k: spec(k) for k in _MESHES[kind]}
    out = {"sun": spec("sun")}
    if "ring" in meshes_t:
        both = [k for k in ("ring1", "ring2") if k in meshes_t]
        if both:
            raise ConfigError(f"[meshes.ring] describes both rings; remove it or [meshes."
                              f"{both[0]}] (give [meshes.ring] or [meshes.ring1] and "
                              "[meshes.ring2])")
        out["ring1"] = out["ring2"] = spec("ring")
    else:
        missing = [k for k in ("ring1", "ring2") if k not in meshes_t]
        if missing:
            raise ConfigError(f"missing key {missing[0]!r} in [meshes] (give [meshes.ring] for "
                              "both rings, or [meshes.ring1] and [meshes.ring2])")
        out["ring1"], out["ring2"] = spec("ring1"), spec("ring2")
    return out


def _builder_set(kind: str, cfg: dict, base: Path | None) -> GearSet:
    geo = check_keys(_require(cfg, "geometry", "the description"), _GEOMETRY[kind],
                      "[geometry]")
    bodies_t = check_keys(_require(cfg, "bodies", "the description"), set(_BODIES[kind]),
                           "[bodies]")
    meshes_t = check_keys(_require(cfg, "meshes", "the description"), set(_MESHES[kind]),
                           "[meshes]")
    roles: dict[str, Role] = {"carrier": "carrier"}
    bodies = {}
    for bname in _BODIES[kind]:
        role: Role = "planet" if bname.startswith("planet") else roles.get(bname, "central")
        t = _require(bodies_t, bname, "[bodies]")
        body = _body(bname, t, role, f"[bodies.{bname}]")
        bodies[bname] = body
    specs = _builder_meshes(kind, meshes_t, base)
    op = _operation(cfg)
    # roles naming an added [[body]] (a motor, a load) are set after the build
    own = set(_BODIES[kind])
    default = dict(zip(("fixed", "input", "output"), _DEFAULT_ROLES[kind], strict=True))
    for key in ("input", "output"):
        if op[key] not in own:
            op[key] = default[key]
    if any(f not in own for f in op["fixed"]):
        op["fixed"] = [default["fixed"]]
    g = {k: v for k, v in geo.items()}
    common: dict[str, Any] = {
        "module": _number(_require(g, "module", "[geometry]"), "[geometry].module",
                          low=MIN_LENGTH, high=1.0)}
    g.pop("module")
    if "pressure_angle_deg" in g:
        common["pressure_angle"] = math.radians(_number(g.pop("pressure_angle_deg"),
                                                        "[geometry].pressure_angle_deg"))
    if "helix_angle_deg" in g:
        common["helix_angle"] = math.radians(_number(g.pop("helix_angle_deg"),
                                                     "[geometry].helix_angle_deg"))
    if "face_width" in g:
        common["face_width"] = _number(g.pop("face_width"), "[geometry].face_width",
                                       low=MIN_LENGTH, high=10.0)
    name = str(cfg.get("name", kind))

    def z(key: str) -> int:
        return _tooth_number(_require(g, key, "[geometry]"), f"[geometry].{key}")

    def count(key: str, default: int) -> int:
        return _integer(g.get(key, default), f"[geometry].{key}", low=1, high=MAX_PLANETS)

    def shift(key: str) -> float:
        return _number(g[key], f"[geometry].{key}", low=-MAX_SHIFT, high=MAX_SHIFT)

    def pinion(planet: str, ring: str) -> None:
        # an internal gear meshes only with a pinion of fewer teeth
        if planet in g and ring in g and z(planet) >= abs(z(ring)):
            raise ConfigError(f"[geometry].{planet} = {z(planet)} is not admissible with "
                              f"{ring} = {z(ring)} (admissible: fewer teeth than the ring, "
                              f"{planet} < {abs(z(ring))})")

    def shifts(keys: tuple[str, ...]) -> dict[str, Any]:
        """Profile shifts (finite numbers; a solved planet shift defaults to None)."""
        return {k: _finite(g[k], f"[geometry].{k}") if k in g else
                (None if k in _SOLVED_SHIFTS else 0.0) for k in keys}

    if len(op["fixed"]) != 1 and kind != "simple":
        raise ConfigError(f"[operation].fixed must name one member for type = {kind!r}, got "
                          f"{op['fixed']!r}")
    for key in ("pressure_angle_deg", "helix_angle_deg"):
        if key in geo:
            _number(geo[key], f"[geometry].{key}", low=-90.0, high=90.0)
    pinion("z_planet", "z_ring")
    pinion("z_planet1", "z_ring1")
    pinion("z_planet2", "z_ring2")
    pinion("z_planet_long", "z_ring")
    try:
        if kind == "simple":
            angles = g.pop("planet_angles_deg", None)
            if angles is not None:
                angles = _numbers(angles, "[geometry].planet_angles_deg", min_len=1,
                                  max_len=MAX_PLANETS)
                if "n_planets" in g and count("n_planets", 1) != len(angles):
                    raise ConfigError(
                        f"[geometry]: n_planets = {count('n_planets', 1)} disagrees with the "
                        f"{len(angles)} planet_angles_deg; give one of them (or make them "
                        "agree)")
            elif "n_planets" not in g:
                raise ConfigError("missing key 'n_planets' or 'planet_angles_deg' in "
                                  "[geometry]")
            return simple_planetary(
                z_sun=z("z_sun"), z_ring=z("z_ring"),
                z_planet=z("z_planet") if "z_planet" in g else None,
                n_planets=count("n_planets", 1) if "n_planets" in g else None,
                planet_angles=[math.radians(a) for a in angles] if angles is not None
                else None,
                profile_shift_sun=shift("profile_shift_sun") if "profile_shift_sun" in g
                else 0.0,
                profile_shift_ring=shift("profile_shift_ring") if "profile_shift_ring" in g
                else 0.0,
                profile_shift_planet=shift("profile_shift_planet")
                if "profile_shift_planet" in g else None,
                sun=bodies["sun"], ring=bodies["ring"], carrier=bodies["carrier"],
                planet=bodies["planet"], sun_mesh=specs["sun"], ring_mesh=specs["ring"],
                fixed=op["fixed"][0] if op["fixed"] else "", input=op["input"],
                output=op["output"], name=name, config=cfg, **common)
        if kind == "wolfrom":
            return wolfrom(
                z_sun=z("z_sun"), z_ring1=z("z_ring1"), z_ring2=z("z_ring2"),
                z_planet1=z("z_planet1"), z_planet2=z("z_planet2"),
                module2=_number(g["module2"], "[geometry].module2", low=MIN_LENGTH,
                                high=1.0) if "module2" in g else None,
                step_offset=math.radians(_finite(g.get("planet_step_offset_deg", 0.0),
                                                 "[geometry].planet_step_offset_deg")),
                helix_angle2=math.radians(_finite(g["helix_angle2_deg"],
                                                  "[geometry].helix_angle2_deg"))
                if "helix_angle2_deg" in g else None,
                **shifts(_WOLFROM_SHIFTS),
                n_planets=count("n_planets", 3), sun=bodies["sun"], ring1=bodies["ring1"],
                ring2=bodies["ring2"], carrier=bodies["carrier"], planet=bodies["planet"],
                sun_mesh=specs["sun"], ring1_mesh=specs["ring1"], ring2_mesh=specs["ring2"],
                fixed=op["fixed"][0], input=op["input"], output=op["output"], name=name,
                config=cfg, **common)
        phases = g.get("planet_mesh_phases")
        if phases is not None:
            if not isinstance(phases, list):
                raise ConfigError("[geometry].planet_mesh_phases must be a list (one mesh "
                                  "position per planet pair, cycles)")
            phases = _numbers(phases, "[geometry].planet_mesh_phases", max_len=MAX_PLANETS)
        return ravigneaux(
            z_sun_small=z("z_sun_small"), z_sun_large=z("z_sun_large"), z_ring=z("z_ring"),
            z_planet_short=z("z_planet_short"), z_planet_long=z("z_planet_long"),
            n_pairs=count("n_pairs", 3), planet_mesh_phases=phases,
            **shifts(_RAVIGNEAUX_SHIFTS),
            sun_small=bodies["sun_small"], sun_large=bodies["sun_large"], ring=bodies["ring"],
            carrier=bodies["carrier"], planet_short=bodies["planet_short"],
            planet_long=bodies["planet_long"], sun_mesh=specs["sun"], ring_mesh=specs["ring"],
            planet_mesh=specs["planet"], fixed=op["fixed"][0], input=op["input"],
            output=op["output"], name=name, config=cfg, **common)
    except KeyError as exc:
        raise ConfigError(f"missing key {exc.args[0]!r} in [geometry]") from None
    except (ValueError, OverflowError) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(str(exc)) from None


def _parallel_set(cfg: dict, base: Path | None) -> GearSet:
    """A ``type = "parallel"`` description: pinion, wheel (optional idler) on fixed axes."""
    geo = check_keys(_require(cfg, "geometry", "the description"), _PARALLEL_GEOMETRY,
                     "[geometry]")
    bodies_t = check_keys(_require(cfg, "bodies", "the description"), set(_PARALLEL_BODIES),
                          "[bodies]")
    meshes_t = check_keys(_require(cfg, "meshes", "the description"), set(_PARALLEL_MESHES),
                          "[meshes]")

    def z(key: str) -> int:
        return _tooth_number(_require(geo, key, "[geometry]"), f"[geometry].{key}")

    def number(key: str, low: float, high: float, default: float = 0.0) -> float:
        return _number(geo.get(key, default), f"[geometry].{key}", low=low, high=high)

    z_idler = z("z_idler") if "z_idler" in geo else None
    if ("idler" in bodies_t) != (z_idler is not None):
        raise ConfigError("[bodies.idler] and [geometry].z_idler go together: give both (a "
                          "stage with an idler) or neither")
    if "wheel" in meshes_t and z_idler is None:
        raise ConfigError("[meshes.wheel] describes the idler-wheel mesh: admissible only with "
                          "an idler ([geometry].z_idler); the pinion-wheel mesh is "
                          "[meshes.pinion]")
    bodies = {}
    for bname in _PARALLEL_BODIES:
        if bname in bodies_t or bname in ("pinion", "wheel"):
            part: Role = "carrier" if bname == HOUSING else "central"
            bodies[bname] = _body(bname, _require(bodies_t, bname, "[bodies]"), part,
                                  f"[bodies.{bname}]")
    spec = _mesh_spec(_require(meshes_t, "pinion", "[meshes]"), "[meshes.pinion]", base,
                      deferred=True)
    spec_w = _mesh_spec(meshes_t["wheel"], "[meshes.wheel]", base, deferred=True) \
        if "wheel" in meshes_t else None
    own = set(bodies) | {HOUSING}
    op: dict[str, Any] = {"fixed": [HOUSING], "input": "pinion", "output": "wheel"}
    if "operation" in cfg:
        given = _operation(cfg)
        for key in ("input", "output"):  # a role naming an added [[body]] is set afterwards
            if given[key] in own:
                op[key] = given[key]
        if "fixed" in cfg["operation"] and all(f in own for f in given["fixed"]):
            op["fixed"] = given["fixed"]
    if len(op["fixed"]) != 1:
        raise ConfigError(f"[operation].fixed must name one member for type = 'parallel', got "
                          f"{op['fixed']!r}")
    for key in ("pressure_angle_deg", "helix_angle_deg"):
        if key in geo:
            _number(geo[key], f"[geometry].{key}", low=-90.0, high=90.0)
    kw: dict[str, Any] = {}
    if "pressure_angle_deg" in geo:
        kw["pressure_angle"] = math.radians(_number(geo["pressure_angle_deg"],
                                                    "[geometry].pressure_angle_deg"))
    if "helix_angle_deg" in geo:
        kw["helix_angle"] = math.radians(_number(geo["helix_angle_deg"],
                                                 "[geometry].helix_angle_deg"))
    if "face_width" in geo:
        kw["face_width"] = number("face_width", MIN_LENGTH, 10.0)
    if "centre_distance" in geo:
        kw["centre_distance"] = number("centre_distance", MIN_LENGTH, 100.0)
    for key in ("profile_shift_pinion", "profile_shift_wheel", "profile_shift_idler"):
        if key in geo:
            kw[key] = number(key, -MAX_SHIFT, MAX_SHIFT)
    for key in ("axis_angle_deg", "idler_angle_deg"):
        if key in geo:
            kw[key[:-4]] = math.radians(number(key, -3600.0, 3600.0))
    try:
        return parallel_stage(
            z_pinion=z("z_pinion"), z_wheel=z("z_wheel"), z_idler=z_idler,
            module=_number(_require(geo, "module", "[geometry]"), "[geometry].module",
                           low=MIN_LENGTH, high=1.0),
            pinion=bodies["pinion"], wheel=bodies["wheel"], idler=bodies.get("idler"),
            housing=bodies.get(HOUSING), mesh=spec, idler_mesh=spec_w,
            fixed=op["fixed"][0], input=op["input"], output=op["output"],
            name=str(cfg.get("name", "parallel")), config=cfg, **kw)
    except (ValueError, OverflowError) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(str(exc)) from None


def _stage_keys(cfg: dict) -> list[str]:
    """The ``stageN`` keys of a multi-stage description, checked: 2 .. MAX_STAGES, numbered
    1 .. N without gaps."""
    numbers = sorted(int(m.group(1)) for k in cfg if (m := _STAGE_KEY.fullmatch(str(k))))
    if len(numbers) < 2:
        raise ConfigError("a description of type = 'multi-stage' needs [stage1], [stage2], ... "
                          f"(at least two stages; found {len(numbers)})")
    if len(numbers) > MAX_STAGES:
        raise ConfigError(f"a multi-stage description has {len(numbers)} stages (admissible: "
                          f"2 .. {MAX_STAGES})")
    missing = [k for k in range(1, numbers[-1] + 1) if k not in numbers]
    if missing:
        raise ConfigError(f"missing key 'stage{missing[0]}' in the description: stages are "
                          f"numbered stage1 .. stageN without gaps (found "
                          f"{', '.join(f'stage{k}' for k in numbers)})")
    return [f"stage{k}" for k in numbers]


def _stage_sets(cfg: dict, keys: list[str], base: Path | None,
                nested: tuple[str, ...]) -> list[GearSet]:
    """The stage descriptions of a two- or multi-stage description, each built on its own."""
    stages = []
    for key in keys:
        stage = _require(cfg, key, "the description")
        if not isinstance(stage, dict):
            raise ConfigError(f"[{key}] must be a table (a gear-set description)")
        if "simulation" in stage:
            raise ConfigError(f"[{key}.simulation] is not admissible: give [simulation] once, "
                              "at the top level")
        for extra in ("fault", "sensor", "rolling_bearing"):
            if extra in stage:
                prefix = stage_prefix(int(key[5:])) if "multi-stage" in nested else \
                    f"s{key[5:]}."
                raise ConfigError(f"[[{key}.{extra}]] is not admissible: give [[{extra}]] at "
                                  f"the top level (members named {prefix}sun, {prefix}planet1, "
                                  "...)")
        if stage.get("type", "simple") in nested:
            raise ConfigError(f"[{key}].type = {stage.get('type')!r} is not admissible: a stage "
                              "is one gear set (simple, wolfrom, ravigneaux, parallel, general)")
        try:
            stages.append(gearset_from_dict({**stage, "name": key}, base=base))
        except ConfigError as exc:
            raise ConfigError(f"[{key}]: {exc}") from None
    return stages


def _multi_stage_set(cfg: dict, base: Path | None) -> GearSet:
    """A ``type = "multi-stage"`` description: ``[stage1]`` ... ``[stageN]`` in series."""
    keys = _stage_keys(cfg)
    stages = _stage_sets(cfg, keys, base, ("two-stage", "multi-stage"))
    table = cfg.get("shaft", [{}] * (len(keys) - 1))
    if not isinstance(table, list) or len(table) != len(keys) - 1:
        raise ConfigError(f"[[shaft]] must be an array of {len(keys) - 1} tables (shaft k joins "
                          "the output of stage k and the input of stage k + 1; omit it for "
                          "rigid shafts)")
    shafts = []
    for i, t in enumerate(table):
        where = f"[[shaft]] #{i + 1}"
        check_keys(t, {"stiffness", "damping", "comment"}, where)
        shafts.append((_stiffness_value(t.get("stiffness", "rigid"), f"{where}.stiffness"),
                       _number(t.get("damping", 0.0), f"{where}.damping", low=0.0,
                               high=MAX_DAMPING)))
    try:
        gs = multi_stage(stages, shafts=shafts, name=str(cfg.get("name", "multi-stage")),
                         config=cfg)
    except (ValueError, OverflowError) as exc:
        raise ConfigError(str(exc)) from None
    return _with_extras(gs, cfg, _operation(cfg) if "operation" in cfg else None)


def _extra_bodies(cfg: dict, required: bool) -> list[Body]:
    """The ``[[body]]`` list (keys checked; every value type- and range-checked)."""
    table = _require(cfg, "body", "the description") if required else cfg.get("body", [])
    if not isinstance(table, list) or len(table) > MAX_BODIES:
        raise ConfigError(f"[[body]] must be an array of at most {MAX_BODIES} tables")
    bodies = []
    for i, t in enumerate(table):
        where = f"[[body]] #{i + 1}"
        check_keys(t, _BODY_GENERAL, where)
        name = _require(t, "name", where)
        if not isinstance(name, str) or not name:
            raise ConfigError(f"{where}.name must be a non-empty string, got {name!r}")
        where = f"[[body]] {_short(name)}"
        role = _string(_require(t, "role", where), f"{where}.role")
        carrier = t.get("carrier")
        if carrier is not None and not isinstance(carrier, str):
            raise ConfigError(f"{where}.carrier must be the name of a carrier body")
        try:
            bodies.append(Body(
                name=name, role=cast(Role, role),  # Body refuses any other role
                mass=_positive_in(_require(t, "mass", where), f"{where}.mass", MASS_RANGE),
                inertia=_positive_in(_require(t, "inertia", where), f"{where}.inertia",
                                     INERTIA_RANGE),
                support=_support(t.get("support"), f"{where}.support"),
                carrier=carrier,
                angle=math.radians(_number(t.get("angle_deg", 0.0), f"{where}.angle_deg",
                                           low=-3600.0, high=3600.0)),
                radius=_number(t["radius"], f"{where}.radius", low=MIN_LENGTH, high=100.0)
                if "radius" in t else None))
        except ValueError as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError(f"{where}: {exc}") from None
    return bodies


def _couplings(cfg: dict) -> list[Coupling]:
    """The ``[[coupling]]`` list."""
    table = cfg.get("coupling", [])
    if not isinstance(table, list) or len(table) > MAX_BODIES:
        raise ConfigError(f"[[coupling]] must be an array of at most {MAX_BODIES} tables")
    couplings = []
    for i, t in enumerate(table):
        where = f"[[coupling]] #{i + 1}"
        check_keys(t, _COUPLING, where)
        names = []
        for key in ("body1", "body2"):
            v = _require(t, key, where)
            if not isinstance(v, str):
                raise ConfigError(f"{where}.{key} must be a body name, got {v!r}")
            names.append(v)
        try:
            couplings.append(Coupling(
                names[0], names[1],
                _stiffness_value(t.get("stiffness", "rigid"), f"{where}.stiffness"),
                _number(t.get("damping", 0.0), f"{where}.damping", low=0.0,
                        high=MAX_DAMPING)))
        except ValueError as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError(f"{where}: {exc}") from None
    return couplings


def _with_extras(gs: GearSet, cfg: dict, op: dict | None) -> GearSet:
    """Add the ``[[body]]`` and ``[[coupling]]`` entries and the operating roles."""
    bodies = _extra_bodies(cfg, required=False)
    couplings = _couplings(cfg)
    if not bodies and not couplings and op is None:
        return gs
    op = op or {"fixed": list(gs.fixed), "input": gs.input, "output": gs.output}
    try:
        return replace(gs, bodies=gs.bodies + tuple(bodies),
                       couplings=gs.couplings + tuple(couplings), fixed=tuple(op["fixed"]),
                       input=op["input"], output=op["output"])
    except (ValueError, OverflowError) as exc:
        raise ConfigError(str(exc)) from None


def _general_set(cfg: dict, base: Path | None) -> GearSet:
    bodies = _extra_bodies(cfg, required=True)
    meshes = []
    mesh_tables = _require(cfg, "mesh", "the description")
    if not isinstance(mesh_tables, list) or not 1 <= len(mesh_tables) <= MAX_BODIES:
        raise ConfigError(f"[[mesh]] must be an array of 1..{MAX_BODIES} tables")
    for i, t in enumerate(mesh_tables):
        where = f"[[mesh]] #{i + 1}"
        check_keys(t, _MESH_GENERAL, where)
        spec = _mesh_spec({k: v for k, v in t.items() if k in _MESH_SPEC}, where, base)
        kw: dict[str, Any] = {}
        for k in ("base_radius1", "base_radius2"):
            if k in t:
                kw[k] = _number(t[k], f"{where}.{k}", low=-100.0, high=100.0)
        if "centre_distance" in t:
            kw["centre_distance"] = _number(t["centre_distance"], f"{where}.centre_distance",
                                            high=100.0)
        if "phase" in t:
            kw["phase"] = _number(t["phase"], f"{where}.phase")
        for k in ("z1", "z2"):
            if k in t:
                kw[k] = _tooth_number(t[k], f"{where}.{k}")
        if "z1" in kw and "z2" in kw and kw["z1"] + kw["z2"] == 0:
            raise ConfigError(f"{where}: z1 = {kw['z1']} and z2 = {kw['z2']} cannot mesh (an "
                              "internal gear needs more teeth than its pinion)")
        for k in ("tooth_offset1_deg", "tooth_offset2_deg"):
            if k in t:
                kw[k[:-4]] = math.radians(_finite(t[k], f"{where}.{k}"))
        if "pressure_angle_deg" in t:
            kw["pressure_angle"] = math.radians(_number(t["pressure_angle_deg"],
                                                        f"{where}.pressure_angle_deg"))
        if "helix_angle_deg" in t:
            kw["helix_angle"] = math.radians(_number(t["helix_angle_deg"],
                                                     f"{where}.helix_angle_deg"))
        for k in ("toothing1", "toothing2"):
            if k in t:
                kw[k] = _toothing(t[k], f"{where}.{k}")
        names = {k: _string(_require(t, k, where), f"{where}.{k}")
                 for k in ("name", "gear1", "gear2")}
        try:
            stiffness, back_stiffness = spec.models()  # built: not deferred
            meshes.append(Mesh(
                name=names["name"], gear1=names["gear1"], gear2=names["gear2"],
                stiffness=stiffness, back_stiffness=back_stiffness, backlash=spec.backlash,
                damping=spec.damping, damping_ratio=spec.damping_ratio,
                damping_law=spec.damping_law, **kw))
        except (ValueError, OverflowError, ZeroDivisionError) as exc:
            raise ConfigError(f"{where}: {exc}") from None
    couplings = _couplings(cfg)
    op = _operation(cfg)
    try:
        return GearSet(name=str(cfg.get("name", "general")), bodies=tuple(bodies),
                       meshes=tuple(meshes), fixed=tuple(op["fixed"]), input=op["input"],
                       output=op["output"], couplings=tuple(couplings), config=cfg)
    except (ValueError, OverflowError) as exc:
        raise ConfigError(str(exc)) from None


def gearset_from_dict(cfg: dict, *, base: Path | None = None) -> GearSet:
    """Build a :class:`GearSet` from a description dict (parsed TOML), with its ``[[fault]]``,
    ``[[sensor]]`` and ``[[rolling_bearing]]`` tables (:mod:`gearvib.faults`,
    :mod:`gearvib.sensors`, :mod:`gearvib.rolling_bearings`).

    See :func:`_gearset_from_dict` for the parameters and errors.
    """
    return _with_faults_and_sensors(_gearset_from_dict(cfg, base=base), cfg, base)


def _with_faults_and_sensors(gs: GearSet, cfg: dict, base: Path | None) -> GearSet:
    """The ``[[fault]]`` and ``[[sensor]]`` tables of a description added to its gear set
    (checked here; against the bodies and teeth when the set is assembled)."""
    if not isinstance(cfg, dict) or not {"fault", "sensor", "rolling_bearing"} & set(cfg):
        return gs
    # on demand: the bearing lines need analysis.catalogue (xarray), which `modes` does not
    from gearvib.rolling_bearings import RollingBearingError, rolling_bearings_from_list

    try:
        faults = faults_from_list(cfg.get("fault"), base=base)
        sensors = sensors_from_list(cfg.get("sensor"), base=base)
        bearings = rolling_bearings_from_list(cfg.get("rolling_bearing"))
        members = {b.name: b.carrier if b.role == "planet" else None for b in gs.bodies}
        for b in bearings:  # member names checked now, not when the catalogue is asked for
            b.resolve(members)
    except (FaultError, SensorError, RollingBearingError) as exc:
        raise ConfigError(str(exc)) from None
    return replace(gs, faults=gs.faults + faults, sensors=gs.sensors + sensors,
                   rolling_bearings=gs.rolling_bearings + bearings)


def _gearset_from_dict(cfg: dict, *, base: Path | None = None) -> GearSet:
    """Build a :class:`GearSet` from a description dict (parsed TOML).

    Parameters
    ----------
    cfg : dict
        The description; see the module docstring and the README.
    base : Path, optional
        Directory against which relative file paths (CSV stiffness curves) are resolved.

    Raises
    ------
    ConfigError
        Unknown or missing keys, inadmissible values, or an inconsistent gear set.
    """
    if not isinstance(cfg, dict):
        raise ConfigError(f"a description must be a table (dict), got {type(cfg).__name__}")
    cfg = copy.deepcopy(cfg)
    stage_keys = {k for k in cfg if _STAGE_KEY.fullmatch(str(k))}
    check_keys(cfg, _TOP | stage_keys, "the description (top level)")
    if "simulation" in cfg:
        check_keys(cfg["simulation"], _SIMULATION, "[simulation]")
    for key in ("name", "title", "description"):
        if key in cfg and not isinstance(cfg[key], str):
            raise ConfigError(f"{key} must be a string, got {_short(cfg[key])}")
    if "references" in cfg and not (isinstance(cfg["references"], str | list)):
        raise ConfigError("references must be a string or a list")
    kind = cfg.get("type", "simple")
    if kind == RIG_TYPE:
        raise ConfigError(f"type = {RIG_TYPE!r} describes shafts and rolling bearings without "
                          "gears: it has no dynamic model to simulate or analyse; it serves "
                          "measured reports (gearvib report MEASURED --gearset RIG) and "
                          "gearvib catalogue")
    if not isinstance(kind, str) or kind not in _TYPE_KEYS:
        raise ConfigError(f"unknown type {_short(kind)} (admissible: simple, wolfrom, ravigneaux, "
                          f"parallel, two-stage, multi-stage, general, {RIG_TYPE})")
    check_keys(cfg, _COMMON_TOP | _TYPE_KEYS[kind] | (stage_keys if kind == "multi-stage"
                                                      else set()),
               f"a description of type = {kind!r}")
    if kind in _GEOMETRY:
        return _with_extras(_builder_set(kind, cfg, base), cfg, _operation(cfg))
    if kind == "parallel":
        op = _operation(cfg) if "operation" in cfg else None
        if op is not None and "fixed" not in cfg["operation"]:
            op["fixed"] = [HOUSING]  # the housing stands still unless said otherwise
        return _with_extras(_parallel_set(cfg, base), cfg, op)
    if kind == "general":
        return _general_set(cfg, base)
    if kind == "multi-stage":
        return _multi_stage_set(cfg, base)
    stages = _stage_sets(cfg, ["stage1", "stage2"], base, ("two-stage", "multi-stage"))
    shaft = check_keys(cfg.get("shaft", {}), {"stiffness", "damping"}, "[shaft]")
    try:
        gs = two_stage(stages[0], stages[1], shaft_stiffness=_stiffness_value(
            shaft.get("stiffness", "rigid"), "[shaft].stiffness"),
                       shaft_damping=_number(shaft.get("damping", 0.0), "[shaft].damping",
                                             low=0.0, high=MAX_DAMPING),
                       name=str(cfg.get("name", "two-stage")), config=cfg)
    except (ValueError, OverflowError) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(str(exc)) from None
    return _with_extras(gs, cfg, _operation(cfg) if "operation" in cfg else None)


RIG_TYPE = "shafts"
"""``type`` of a description of shafts and rolling bearings without gears."""
_RIG_TOP = {"name", "title", "description", "type", "references", "operation", "shaft",
            "rolling_bearing"}
_RIG_SHAFT = {"name", "ratio", "comment"}


def rig_from_dict(cfg: dict) -> Any:
    """A :class:`gearvib.rig.ShaftRig` from a ``type = "shafts"`` description (parsed TOML).

    Keys: ``name``, ``title``, ``description``, ``references``, ``[operation].input`` (the
    input shaft, default the first), ``[[shaft]]`` (``name``, ``ratio`` = speed per input
    speed, default 1) and ``[[rolling_bearing]]`` (:mod:`gearvib.rolling_bearings`; members
    are the shafts).

    Raises
    ------
    ConfigError
        An unknown or missing key, a value of the wrong type or out of range, a shaft named
        twice or ``ground``, an input that is not a shaft or whose ratio is not 1, a bearing
        on a member that is not a shaft.
    """
    from gearvib.rig import MAX_SHAFTS, Shaft, ShaftRig, check_ratio
    from gearvib.rolling_bearings import RollingBearingError, rolling_bearings_from_list

    if not isinstance(cfg, dict):
        raise ConfigError(f"a description must be a table (dict), got {type(cfg).__name__}")
    where = f"a description of type = {RIG_TYPE!r}"
    check_keys(cfg, _RIG_TOP, where)
    if cfg.get("type") != RIG_TYPE:
        raise ConfigError(f"type must be {RIG_TYPE!r} for a description of shafts and bearings, "
                          f"got {_short(cfg.get('type'))}")
    for key in ("name", "title", "description"):
        if key in cfg and not isinstance(cfg[key], str):
            raise ConfigError(f"{key} must be a string, got {_short(cfg[key])}")
    if "references" in cfg and not isinstance(cfg["references"], str | list):
        raise ConfigError("references must be a string or a list")
    tables = _require(cfg, "shaft", where)
    if not isinstance(tables, list) or not 1 <= len(tables) <= MAX_SHAFTS:
        raise ConfigError(f"[[shaft]] must be an array of 1..{MAX_SHAFTS} tables (one per "
                          "shaft)")
    shafts = []
    for i, t in enumerate(tables):
        w = f"[[shaft]] #{i + 1}"
        check_keys(t, _RIG_SHAFT, w)
        name = _string(_require(t, "name", w), f"{w}.name")
        if len(name) > 100 or name == "ground":
            raise ConfigError(f"{w}.name = {_short(name)} is not admissible (a name of at most "
                              "100 characters other than 'ground', the housing)")
        try:
            ratio = check_ratio(t.get("ratio", 1.0), f"[[shaft]] {name!r}.ratio")
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
        shafts.append(Shaft(name, ratio))
    names = [s.name for s in shafts]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ConfigError(f"[[shaft]]: name {twice[0]!r} is used twice")
    op = check_keys(cfg.get("operation", {}), {"input"}, "[operation]")
    inp = _string(op.get("input", names[0]), "[operation].input")
    if inp not in names:
        raise ConfigError(f"[operation].input = {_short(inp)} is not a shaft (admissible: "
                          f"{', '.join(names)})")
    ratio_in = shafts[names.index(inp)].ratio
    if ratio_in != 1.0:
        raise ConfigError(f"[operation].input = {inp!r} has ratio {ratio_in:g}; the input "
                          "shaft's ratio is 1 (ratios are speeds per input speed)")
    try:
        bearings = rolling_bearings_from_list(cfg.get("rolling_bearing"))
        members: dict[str, str | None] = {n: None for n in names}
        for b in bearings:
            b.resolve(members)
    except RollingBearingError as exc:
        raise ConfigError(str(exc)) from None
    return ShaftRig(name=str(cfg.get("name", RIG_TYPE)), shafts=tuple(shafts), input=inp,
                    rolling_bearings=bearings, title=str(cfg.get("title", "")),
                    config=copy.deepcopy(cfg))


def description_from_dict(cfg: dict, *, base: Path | None = None) -> Any:
    """A :class:`GearSet`, or a :class:`gearvib.rig.ShaftRig` for ``type = "shafts"``."""
    if isinstance(cfg, dict) and cfg.get("type") == RIG_TYPE:
        return rig_from_dict(cfg)
    return gearset_from_dict(cfg, base=base)


def load_description(name_or_path: str | Path) -> Any:
    """A gear set or a rig of shafts and bearings from a TOML file, a preset or a rig name.

    Returns
    -------
    GearSet or gearvib.rig.ShaftRig
    """
    cfg, base = load_config(name_or_path)
    return description_from_dict(cfg, base=base)


def list_rigs() -> list[str]:
    """Names of the built-in rig descriptions (shafts and bearings, no gears)."""
    files = resources.files("gearvib.rigs").iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def rig_titles() -> dict[str, str]:
    """``{name: title}`` of every built-in rig description."""
    return {name: str(tomllib.loads(preset_text(name)).get("title", "")) for name in
            list_rigs()}


def list_presets() -> list[str]:
    """Names of the built-in presets."""
    files = resources.files("gearvib.presets").iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def preset_text(name: str) -> str:
    """The TOML text of a built-in preset (comments included), to start a file from.

    Raises
    ------
    ConfigError
        For an unknown preset (the message lists the available ones).
    """
    if name in list_rigs():
        return resources.files("gearvib.rigs").joinpath(f"{name}.toml").read_text("utf-8")
    if name not in list_presets():
        raise ConfigError(f"unknown preset {_short(name)} (available: "
                          f"{', '.join(list_presets() + list_rigs())})")
    return resources.files("gearvib.presets").joinpath(f"{name}.toml").read_text("utf-8")


def list_examples() -> list[str]:
    """Names of the example recipes shipped with gearvib (studies and sweeps)."""
    files = resources.files("gearvib.recipes").iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def example_text(name: str) -> str:
    """The TOML text of an example recipe (comments included), to start a study or sweep from.

    Raises
    ------
    ConfigError
        For an unknown example (the message lists the available ones).
    """
    if name not in list_examples():
        raise ConfigError(f"unknown example {_short(name)} (available: "
                          f"{', '.join(list_examples())})")
    return resources.files("gearvib.recipes").joinpath(f"{name}.toml").read_text("utf-8")


def example_titles() -> dict[str, str]:
    """``{name: title}`` of every example: a study's ``[study].title``, a sweep's ``title``."""
    out = {}
    for name in list_examples():
        doc = tomllib.loads(example_text(name))
        out[name] = str(doc.get("study", {}).get("title", "") or doc.get("title", ""))
    return out


def preset_titles() -> dict[str, str]:
    """``{name: title}`` of every built-in preset (its ``title`` key)."""
    return {name: str(tomllib.loads(preset_text(name)).get("title", "")) for name in
            list_presets()}


MAX_TOML_BYTES = 16 * 2**20
"""Largest description file read (16 MiB; a gear set, study or sweep needs a few kB)."""

MAX_TOML_DEPTH = 64
"""Deepest nesting of arrays and inline tables accepted in a description file."""


def _nesting_depth(text: str) -> int:
    """Deepest nesting of ``[``/``{`` outside strings and comments (an upper bound: table
    headers ``[a]`` count one level)."""
    depth = deepest = 0
    quote = ""
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if quote:
            if c == "\\" and quote == '"':
                i += 2
                continue
            if text.startswith(quote, i):
                i += len(quote)
                quote = ""
                continue
        elif c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        elif c in "\"'":
            quote = c * 3 if text.startswith(c * 3, i) else c
            i += len(quote)
            continue
        elif c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in "]}":
            depth = max(depth - 1, 0)
        i += 1
    return deepest


def read_toml(path: str | Path, what: str = "file") -> dict:
    """Read a TOML file with errors that name it and never a traceback.

    Parameters
    ----------
    path : path-like
        The file.
    what : str
        What the file is, for the message (``"configuration file"``, ``"sweep file"``, ...).

    Returns
    -------
    dict
        The parsed document.

    Raises
    ------
    ConfigError
        The file is missing or unreadable, larger than :data:`MAX_TOML_BYTES`, not UTF-8,
        invalid TOML, nested deeper than :data:`MAX_TOML_DEPTH` or holds an integer with more
        digits than Python converts (the message names the file, and the line where known).
    """
    p = Path(path)
    if not is_file(p):
        raise ConfigError(f"{what} {_short(str(p))} not found")
    try:
        size = p.stat().st_size
        if size > MAX_TOML_BYTES:
            raise ConfigError(f"{p}: {size} bytes; admissible: a description file of at most "
                              f"{MAX_TOML_BYTES // 2**20} MiB")
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{p}: not a UTF-8 text file ({exc.reason})") from None
    except OSError as exc:
        raise ConfigError(f"{p}: cannot be read ({exc.strerror or exc})") from None
    if _nesting_depth(text) > MAX_TOML_DEPTH:
        raise ConfigError(f"{p}: arrays or inline tables nested deeper than "
                          f"{MAX_TOML_DEPTH} levels; admissible: at most {MAX_TOML_DEPTH}")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: invalid TOML: {exc}") from None
    except ValueError as exc:  # an integer beyond Python's digit limit (int_max_str_digits)
        raise ConfigError(f"{p}: {_long_integer(text) or _short(str(exc))}") from None
    except RecursionError:
        raise ConfigError(f"{p}: nested too deeply to be read") from None


def _long_integer(text: str) -> str:
    """Where the first integer of more than 4300 digits is, as ``line N (key)``."""
    import re

    m = re.search(r"[0-9_]{4300,}", text)
    if m is None:
        return ""
    line = text.count("\n", 0, m.start()) + 1
    start = text.rfind("\n", 0, m.start()) + 1
    key = text[start:m.start()].split("=")[0].strip()
    return (f"line {line}{f' ({_short(key)})' if key else ''}: an integer of "
            f"{m.end() - m.start()} digits; admissible: at most 4300 digits")


def load_config(name_or_path: str | Path) -> tuple[dict, Path | None]:
    """Read a description from a TOML file or a preset name.

    Returns
    -------
    (dict, Path or None)
        The parsed description and the directory of the file (None for presets).
    """
    p = Path(name_or_path)
    if p.suffix == ".toml" or exists(p):
        return read_toml(p, "configuration file"), p.parent
    name = str(name_or_path)
    if name not in list_presets() and name not in list_rigs():
        raise ConfigError(
            f"unknown preset {_short(name)} (available: "
            f"{', '.join(list_presets() + list_rigs())}; or give a path to a .toml file)"
        )
    return tomllib.loads(preset_text(name)), None


def load_gearset(name_or_path: str | Path) -> GearSet:
    """Load a gear set from a TOML file or a preset name (``paper-case1``, ...); a
    ``type = "shafts"`` description is refused (:func:`load_description` reads it)."""
    cfg, base = load_config(name_or_path)
    return gearset_from_dict(cfg, base=base)


def config_hash(cfg: dict) -> str:
    """SHA-256 of the canonical JSON of a description (provenance)."""
    text = json.dumps(cfg, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()
