"""Start states of batched-kernel tests (shared by test_batched.py and test_batched_codegen.py)."""

from __future__ import annotations

import numpy as np

from gearvib.simulate import SpeedRamp, prepare_run, static_equilibrium

RAMP = SpeedRamp(1500.0, 2500.0, 1.0, input_torque=60.0)


def start_state(model, cond=RAMP, gyroscopic: bool = False):
    """Kernel system and static-equilibrium state of a run (as simulate() prepares them)."""
    setup = prepare_run(model, cond, gyroscopic)
    qd0 = setup.rigid * setup.omega0
    q0, _ = static_equilibrium(setup.system, setup.mass, setup.rigid, qd0)
    setup.system.deflection_limit[:] = 1.0
    return setup.system, np.concatenate([q0, qd0])
