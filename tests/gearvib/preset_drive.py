"""The drive a preset's ``[simulation]`` section describes, for tests that run a preset's gear
set from Python with conditions of their own.

The paper presets drive the sun through a spring-damper (``drive_stiffness``,
``drive_damping``): their light mesh damping was chosen with it, and under the default speed
drive (a controller on the rigid-body mode, which adds no damping to the elastic modes) they
are parametrically unstable in several speed bands. A test whose subject is not the drive runs
such a set with the preset's own drive.
"""

from __future__ import annotations

from gearvib.config import load_config
from gearvib.simulate import DriveCoupling
from gearvib.simulation.settings import conditions_from_settings, read_run_settings


def preset_coupling(preset: str) -> DriveCoupling | None:
    """The drive coupling of ``preset``'s ``[simulation]`` section (None: the default)."""
    cfg, _ = load_config(preset)
    run = read_run_settings(cfg.get("simulation", {}))
    return getattr(conditions_from_settings(run), "coupling", None)


def input_coupling(model) -> DriveCoupling:
    """A spring-damper on the input member with the values of the default drive (the default
    drive before issue 27): for test sets built from the paper stages, whose light mesh damping
    needs the drive's damping on the rotational modes (as the paper presets' own drive)."""
    from gearvib.simulate import default_coupling

    default = default_coupling(model)
    return DriveCoupling(default.stiffness, default.damping)
