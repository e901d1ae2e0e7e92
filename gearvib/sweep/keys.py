"""Key paths into gear-set descriptions: reading, replacing, value kinds and units.

A *key path* names one value of a gear-set description (the parsed TOML dict) by its keys joined
with dots, e.g. ``meshes.sun.damping_ratio``, ``geometry.planet_angles_deg`` or
``bodies.planet.support.radial``. A segment that is a non-negative integer indexes a list:
``body.0.mass`` is the mass of the first ``[[body]]`` of a ``type = "general"`` set, and
``geometry.planet_angles_deg.1`` the angle of the second planet. Paths starting with
``simulation.`` address the run settings (the ``[simulation]`` table).

Every table on the way must exist in the base description; the last key may be new (an optional
key the base does not set), which the gear-set checker of :mod:`gearvib.config` then accepts or
rejects by name.
"""

from __future__ import annotations

import copy
import json
import math
import re
from typing import Any

from gearvib.config import ConfigError

__all__ = [
    "KEY_UNITS",
    "get_path",
    "parse_path",
    "path_units",
    "set_path",
    "value_kind",
    "value_label",
]

_SEGMENT = re.compile(r"^[A-Za-z0-9_-]+$")

KEY_UNITS: dict[str, str] = {
    # run settings ([simulation])
    "speed_start_rpm": "min-1",
    "speed_end_rpm": "min-1",
    "duration": "s",
    "input_torque": "N m",
    "load_torque": "N m",
    "fs_out": "Hz",
    "dt": "s",
    "drive_stiffness": "N m rad-1",
    "drive_damping": "N m s rad-1",
    "gyroscopic": "1",
    "load_inertia": "kg m2",
    "synchronous_rpm": "min-1",
    "breakdown_torque": "N m",
    "breakdown_slip": "1",
    # geometry
    "module": "m",
    "module2": "m",
    "face_width": "m",
    "profile_shift": "1",
    "profile_shift_sun": "1",
    "profile_shift_ring": "1",
    "profile_shift_planet": "1",
    "n_planets": "1",
    "n_pairs": "1",
    "z": "1",
    "z1": "1",
    "z2": "1",
    "addendum": "m",
    "dedendum": "m",
    "base_radius1": "m",
    "base_radius2": "m",
    "centre_distance": "m",
    "radius": "m",
    "phase": "1",
    # bodies and supports
    "mass": "kg",
    "inertia": "kg m2",
    "radial": "N m-1",
    "tangential": "N m-1",
    "axial": "N m-1",
    "torsional": "N m rad-1",
    "radial_damping": "N s m-1",
    "tangential_damping": "N s m-1",
    "axial_damping": "N s m-1",
    "torsional_damping": "N m s rad-1",
    # meshes and stiffness models
    "backlash": "m",
    "damping": "N s m-1",
    "damping_ratio": "1",
    "k": "N m-1",
    "k_min": "N m-1",
    "k_max": "N m-1",
    "mean": "N m-1",
    "cos": "N m-1",
    "sin": "N m-1",
    "ramp": "1",
    "contact_ratio": "1",
    "C_M": "1",
    "C_R": "1",
    "basic_rack_dedendum": "1",
    "low_contact_factor": "1",
}
"""Units (UDUNITS strings) of the numeric keys of gear-set descriptions, by the last key."""

_TABLE_UNITS = {("shaft", "stiffness"): "N m rad-1", ("shaft", "damping"): "N m s rad-1"}


def parse_path(path: Any, where: str = "path") -> tuple[str | int, ...]:
    """Split a key path into its segments (integers for list indices).

    Raises
    ------
    ConfigError
        Not a non-empty string of dot-separated keys.
    """
    if not isinstance(path, str) or not path:
        raise ConfigError(f"{where} must be a non-empty string such as "
                          f"'meshes.sun.damping_ratio', got {path!r}")
    out: list[str | int] = []
    for seg in path.split("."):
        if not _SEGMENT.match(seg):
            raise ConfigError(f"{where} = {path!r}: segment {seg!r} is not admissible "
                              "(keys of letters, digits, '_' or '-', joined by '.')")
        out.append(int(seg) if seg.isdigit() else seg)
    return tuple(out)


def _describe(node: Any) -> str:
    if isinstance(node, dict):
        return "a table"
    if isinstance(node, list):
        return f"a list of {len(node)}"
    return f"the value {node!r}"


def _step(node: Any, seg: str | int, done: str, path: str, last: bool) -> Any:
    where = f"[{done}]" if done else "the top level"
    if isinstance(node, dict):
        if isinstance(seg, int):
            raise ConfigError(f"path {path!r}: {where} is a table, not a list; index {seg} is "
                              "not admissible")
        if seg not in node:
            if last:
                return None
            keys = ", ".join(sorted(str(k) for k in node)) or "none"
            raise ConfigError(f"path {path!r}: unknown key {seg!r} in {where} of the base "
                              f"description (keys there: {keys})")
        return node[seg]
    if isinstance(node, list):
        if not isinstance(seg, int):
            raise ConfigError(f"path {path!r}: {where} is a list; the next segment must be an "
                              f"index 0..{len(node) - 1}, got {seg!r}")
        if not 0 <= seg < len(node):
            raise ConfigError(f"path {path!r}: index {seg} out of range for {where} "
                              f"(admissible 0..{len(node) - 1})")
        return node[seg]
    raise ConfigError(f"path {path!r}: {where} is {_describe(node)}, which has no key {seg!r}")


def get_path(desc: dict, path: str) -> tuple[bool, Any]:
    """``(exists, value)`` of a key path in a description.

    Raises
    ------
    ConfigError
        A table or list on the way does not exist (the message names the path and the keys
        that do exist there).
    """
    segs = parse_path(path)
    node: Any = desc
    done: list[str] = []
    for i, seg in enumerate(segs):
        last = i == len(segs) - 1
        if last and isinstance(node, dict) and seg not in node and isinstance(seg, str):
            return False, None
        node = _step(node, seg, ".".join(done), path, last)
        done.append(str(seg))
    return True, node


def set_path(desc: dict, path: str, value: Any) -> dict:
    """A deep copy of ``desc`` with the value at ``path`` replaced (or the last key added)."""
    out = copy.deepcopy(desc)
    segs = parse_path(path)
    node: Any = out
    done: list[str] = []
    for seg in segs[:-1]:
        node = _step(node, seg, ".".join(done), path, False)
        done.append(str(seg))
    last = segs[-1]
    _step(node, last, ".".join(done), path, True)  # checks the container and the index
    node[last] = copy.deepcopy(value)
    return out


def value_kind(value: Any) -> str:
    """``"number"``, ``"bool"``, ``"string"``, ``"list"`` or ``"table"`` (else ``"other"``)."""
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int | float):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list | tuple):
        return "list"
    if isinstance(value, dict):
        return "table"
    return "other"


def value_label(value: Any) -> str:
    """Compact, canonical text of a value (JSON with sorted keys, integral floats kept short)."""

    def norm(v: Any) -> Any:
        if isinstance(v, float) and math.isfinite(v) and v == int(v) and abs(v) < 1e15:
            return int(v)
        if isinstance(v, list | tuple):
            return [norm(x) for x in v]
        if isinstance(v, dict):
            return {k: norm(x) for k, x in v.items()}
        return v

    if isinstance(value, str):
        return value
    return json.dumps(norm(value), sort_keys=True, separators=(", ", ": "))


def path_units(path: str) -> str | None:
    """Units of the value at ``path`` from :data:`KEY_UNITS`, or None when unknown.

    Angles in keys ending in ``_deg`` are in ``degree``; a list index takes the units of its
    list.
    """
    segs = [s for s in parse_path(path) if isinstance(s, str)]
    if not segs:
        return None
    key = segs[-1]
    if len(segs) >= 2 and (segs[-2], key) in _TABLE_UNITS:
        return _TABLE_UNITS[(segs[-2], key)]
    if key.endswith("_deg"):
        return "degree"
    if key.endswith("_rpm"):
        return "min-1"
    if key.startswith("z_"):
        return "1"
    return KEY_UNITS.get(key)
