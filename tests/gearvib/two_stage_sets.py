"""Two-stage gear sets for the tests of several mesh frequencies (built from TOML dicts).

``paper_stage()`` is the stage of the preset ``paper-case1`` (z_s = 33, z_r = -114, three
planets at 120°). ``other_stage()`` is a second, different stage (z_s = 21, z_r = -78,
z_p = 28, module 3 mm). Stage 1's carrier drives stage 2's sun through a rigid shaft.
"""

from __future__ import annotations

import copy

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.model import AssembledModel


def paper_stage(backlash: float | None = None) -> dict:
    """The description of ``paper-case1`` as a stage table (optionally another backlash)."""
    cfg, _ = load_config("paper-case1")
    stage = {k: copy.deepcopy(v) for k, v in cfg.items()
             if k not in ("name", "title", "simulation")}
    if backlash is not None:
        for mesh in stage["meshes"].values():
            mesh["backlash"] = backlash
    return stage


def other_stage() -> dict:
    """A second stage with its own tooth numbers, module, inertias and mesh stiffness."""
    stage = paper_stage()
    stage["geometry"].update(module=3e-3, z_sun=21, z_ring=-78, z_planet=28)
    stage["bodies"]["sun"]["inertia"] = 4e-3
    stage["bodies"]["carrier"]["inertia"] = 0.15
    stage["bodies"]["planet"]["inertia"] = 2.5e-3
    stage["meshes"]["sun"]["stiffness"].update(k_min=4.0e7, k_max=6.5e7)
    stage["meshes"]["ring"]["stiffness"].update(k_min=4.5e7, k_max=7.5e7)
    return stage


def two_stage_config(stage1: dict, stage2: dict, name: str = "two-stage-test") -> dict:
    """A ``type = "two-stage"`` description with a ``[simulation]`` table."""
    return {"name": name, "type": "two-stage", "stage1": stage1, "stage2": stage2,
            "simulation": {"speed_start_rpm": 0.0, "speed_end_rpm": 6000.0, "duration": 1.0,
                           "input_torque": 60.0}}


def two_stage_model(stage1: dict, stage2: dict) -> AssembledModel:
    """Assembled two-stage set."""
    return assemble(gearset_from_dict(two_stage_config(stage1, stage2)))
