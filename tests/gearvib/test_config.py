"""TOML descriptions, presets and their error messages."""

from __future__ import annotations

import copy
import math

import pytest

from gearvib.assembly import assemble
from gearvib.config import (
    ConfigError,
    config_hash,
    gearset_from_dict,
    list_presets,
    load_config,
    load_gearset,
)
from gearvib.structure import Body

LUMPED_TOML = """
name = "lumped-pair-set"
type = "general"

[operation]
fixed = "ring"
input = "sun"
output = "carrier"

[[body]]
name = "sun"
role = "central"
mass = 0.4
inertia = 3.4e-4
support = { radial = 1e8, torsional = "free" }

[[body]]
name = "ring"
role = "central"
mass = 2.35
inertia = 2.0e-2
support = { radial = 1e8 }

[[body]]
name = "carrier"
role = "carrier"
mass = 5.43
inertia = 2.0e-2
support = { radial = 1e8 }

[[body]]
name = "p1"
role = "planet"
carrier = "carrier"
angle_deg = 0.0
mass = 0.66
inertia = 3.9e-4
support = { radial = 1e8, tangential = 1e8 }

[[mesh]]
name = "sun-p1"
gear1 = "sun"
gear2 = "p1"
base_radius1 = 0.0297
base_radius2 = 0.0254
pressure_angle_deg = 24.6
z1 = 32
z2 = 28
stiffness = { model = "constant", k = 5e8 }

[[mesh]]
name = "ring-p1"
gear1 = "ring"
gear2 = "p1"
base_radius1 = -0.0805
base_radius2 = 0.0254
pressure_angle_deg = 24.6
stiffness = { model = "constant", k = 5e8 }
"""


def _lumped(tmp_path, text=LUMPED_TOML):
    p = tmp_path / "set.toml"
    p.write_text(text)
    return p


def test_presets_are_listed_and_load():
    names = list_presets()
    assert {"paper-case1", "paper-case2", "paper-case1-elastic"} <= set(names)
    for n in names:
        assert assemble(load_gearset(n)).n_dof > 0


def test_lumped_literature_model_from_toml(tmp_path):
    # ring base radius consistent with the sun mesh: (r_bs + r_bp)/cos a = (|r_br| - r_bp)/cos a
    a = (0.0297 + 0.0254) / math.cos(math.radians(24.6))
    r_br = a * math.cos(math.radians(24.6)) + 0.0254
    text = LUMPED_TOML.replace("base_radius1 = -0.0805", f"base_radius1 = {-r_br!r}")
    model = assemble(load_gearset(_lumped(tmp_path, text)))
    assert model.n_dof == 11  # 3 central x (x, y, theta) - ring theta + planet 3
    assert model.kinematic_ratios["ring"] == 0.0


def test_inconsistent_lumped_radii_are_rejected(tmp_path):
    text = LUMPED_TOML.replace("base_radius1 = -0.0805", "base_radius1 = -0.0900")
    with pytest.raises(ValueError, match="planet radius"):
        assemble(load_gearset(_lumped(tmp_path, text)))


def test_unknown_preset_names_the_alternatives():
    with pytest.raises(ConfigError, match=r"unknown preset 'paper-case9'.*paper-case1"):
        load_gearset("paper-case9")


@pytest.mark.parametrize(("section", "key"), [
    (None, "colour"), ("geometry", "teeth_sun"), ("operation", "driven"),
    ("bodies.sun", "weight"), ("meshes.sun", "stiffnes"),
])
def test_unknown_key_is_named(section, key):
    cfg, _ = load_config("paper-case1")
    cfg = copy.deepcopy(cfg)
    table = cfg
    if section:
        for part in section.split("."):
            table = table[part]
    table[key] = 1
    with pytest.raises(ConfigError, match=f"unknown key '{key}'"):
        gearset_from_dict(cfg)


def test_unknown_stiffness_key_is_named():
    cfg, _ = load_config("paper-case1")
    cfg["meshes"]["sun"]["stiffness"]["kmin"] = 1.0
    with pytest.raises((ConfigError, ValueError), match="kmin"):
        gearset_from_dict(cfg)


@pytest.mark.parametrize(("path", "value", "pattern"), [
    (("geometry", "planet_angles_deg"), [0.0, 121.0, 240.0], r"121"),
    (("bodies", "sun", "mass"), 0.0, r"mass"),
    (("bodies", "planet", "inertia"), -1.0, r"inertia"),
    (("bodies", "sun", "mass"), float("nan"), r"NaN"),
    (("meshes", "sun", "stiffness", "k_min"), -1e7, r"k_min"),
    (("geometry", "planet_angles_deg"), [0.0, 2.4489795918367347, 120.0], r"overlap"),
])
def test_bad_values_give_clear_errors(path, value, pattern):
    cfg, _ = load_config("paper-case1")
    t = cfg
    for p in path[:-1]:
        t = t[p]
    t[path[-1]] = value
    with pytest.raises(ValueError, match=pattern):
        gearset_from_dict(cfg)


def test_contact_ratio_below_one_is_rejected():
    cfg, _ = load_config("paper-case1")
    cfg["geometry"]["module"] = 2.5e-3
    cfg["meshes"]["sun"]["stiffness"] = {"model": "rectangular", "k_min": 1e7, "k_max": 2e7,
                                         "contact_ratio": 0.9}
    with pytest.raises(ValueError, match=r"contact.ratio"):
        gearset_from_dict(cfg)


def test_negative_support_stiffness_is_rejected():
    cfg, _ = load_config("paper-case1-elastic")
    cfg["bodies"]["planet"]["support"]["radial"] = -1e8
    with pytest.raises(ValueError, match="radial"):
        gearset_from_dict(cfg)


def test_config_hash_is_stable_and_sensitive():
    cfg, _ = load_config("paper-case1")
    h = config_hash(cfg)
    assert h == config_hash(copy.deepcopy(cfg))
    cfg["meshes"]["sun"]["backlash"] = 1e-5
    assert h != config_hash(cfg)


def test_body_validation_names_the_body():
    with pytest.raises(ValueError, match="'sun'"):
        Body("sun", "central", mass=-1.0, inertia=1.0)


@pytest.mark.parametrize("value", ["Viscous", "none", 1, True, None, "x" * 500])
def test_bad_damping_law_names_the_key_and_the_laws(value):
    cfg, _ = load_config("paper-case1")
    cfg["meshes"]["ring"]["damping_law"] = value
    with pytest.raises(ConfigError, match=r"\[meshes\.ring\]\.damping_law = .* is not "
                                          r"admissible \(admissible: 'gated', 'viscous'\)"
                       ) as err:
        gearset_from_dict(cfg)
    assert len(str(err.value)) < 200  # a long value is shortened


def test_damping_law_per_mesh_family_and_in_general_sets():
    """``damping_law`` of a mesh family (builders) or of a ``[[mesh]]`` (general sets) reaches
    the model; the default is the gated law on every mesh (and no law list is stored)."""
    cfg, _ = load_config("paper-case1")
    assert assemble(gearset_from_dict(cfg)).mesh_damping_laws == ()
    cfg["meshes"]["sun"]["damping_law"] = "viscous"
    model = assemble(gearset_from_dict(cfg))
    assert model.mesh_damping_laws == ("viscous",) * 3 + ("gated",) * 3
    assert list(model.viscous_meshes) == [True] * 3 + [False] * 3
    general = {
        "name": "pair", "type": "general",
        "operation": {"fixed": "carrier", "input": "pinion", "output": "wheel"},
        "body": [
            {"name": "pinion", "role": "central", "mass": 1.0, "inertia": 1e-3,
             "support": {"radial": "rigid", "axial": "rigid", "torsional": "free"}},
            {"name": "carrier", "role": "carrier", "mass": 1.0, "inertia": 1.0,
             "support": {"radial": "rigid", "axial": "rigid"}},
            {"name": "wheel", "role": "planet", "carrier": "carrier", "mass": 1.0,
             "inertia": 1e-3,
             "support": {"radial": "rigid", "axial": "rigid", "tangential": "rigid"}},
        ],
        "mesh": [{"name": "pinion-wheel", "gear1": "pinion", "gear2": "wheel",
                  "base_radius1": 0.05, "base_radius2": 0.05, "pressure_angle_deg": 20.0,
                  "stiffness": {"model": "constant", "k": 1e8}, "damping": 100.0,
                  "damping_law": "viscous"}],
    }
    assert assemble(gearset_from_dict(general)).mesh_damping_laws == ("viscous",)
    general["mesh"][0]["damping_law"] = "wet"
    with pytest.raises(ConfigError, match=r"damping_law = 'wet'"):
        gearset_from_dict(general)
