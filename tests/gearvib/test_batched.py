"""The batched kernel: variants of one topology advanced together, each bit-identical to its
single run (:func:`gearvib.kernels_batch.integrate_batch` against
:func:`gearvib.kernels.integrate`)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gearvib import kernels as kn
from gearvib import kernels_batch as kb
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.faults import Crack
from gearvib.simulate import SpeedRamp, TorqueDriven, prepare_run, static_equilibrium
from gearvib.sweep.keys import set_path

RAMP = SpeedRamp(1500.0, 2500.0, 1.0, input_torque=60.0)


def _variant(preset: str, damping: float, radial: float | None = None):
    cfg, base = load_config(preset)
    d = set_path(cfg, "meshes.sun.damping_ratio", damping)
    if radial is not None:
        d = set_path(d, "bodies.planet.support.radial", radial)
    return assemble(gearset_from_dict(d, base=base))


def _start(model, cond=RAMP):
    """Kernel system and static-equilibrium state of a run (as simulate() prepares them)."""
    setup = prepare_run(model, cond, False)
    qd0 = setup.rigid * setup.omega0
    q0, _ = static_equilibrium(setup.system, setup.mass, setup.rigid, qd0)
    setup.system.deflection_limit[:] = 1.0
    return setup.system, np.concatenate([q0, qd0])


@pytest.fixture(scope="module")
def elastic_variants():
    models = [_variant("paper-case1-elastic", 0.005 * (1 + k), 1.5e8 * (1 + 0.05 * k))
              for k in range(4)]
    return [_start(m) for m in models]


def _assert_batch_equals_singles(systems, y0, dt, n_steps):
    rec, changes, status, y_end = kb.integrate_batch(systems, np.array(y0), dt, n_steps)
    assert np.all(status[:, 0] == kn.STATUS_OK)
    for b, (system, y) in enumerate(zip(systems, y0, strict=True)):
        r, ch, st, y1 = kn.integrate(system, y, dt, n_steps)
        assert st[0] == kn.STATUS_OK
        # bit for bit: the same bytes, not merely close values
        assert rec[b].tobytes() == r.tobytes(), f"variant {b} differs from its single run"
        assert np.array_equal(changes[b], ch)
        assert y_end[b].tobytes() == y1.tobytes()
    return rec


def test_batch_of_elastic_variants_is_bit_identical_to_single_runs(elastic_variants):
    systems = [s for s, _ in elastic_variants]
    # the variants' bearing stiffness leaves rounding residues in different entries of
    # M^-1 K: the batch's common pattern holds entries some variants do not have
    patterns = [kn.operators(s)[0] != 0.0 for s in systems]
    assert any(not np.array_equal(patterns[0], p) for p in patterns[1:])
    rec = _assert_batch_equals_singles(systems, [y for _, y in elastic_variants], 8e-6, 400)
    # the variants really differ (mesh damping, bearing stiffness)
    assert not np.array_equal(rec[0], rec[3])


def test_batch_with_different_sub_steps_per_variant(elastic_variants):
    """Shifted mesh phases: the variants reach their stiffness jumps at different times, so
    their steps are split into different numbers of sub-steps (the lockstep waits)."""
    system, y0 = elastic_variants[0]
    systems = []
    for k in range(3):
        s = dataclasses.replace(system, mesh_position_offsets=system.mesh_position_offsets
                                + 0.13 * k)
        systems.append(s)
    _assert_batch_equals_singles(systems, [y0] * 3, 8e-6, 300)


def test_batch_of_one_and_of_the_rigid_model():
    models = [_variant("paper-case1", 0.005 * (1 + k)) for k in range(2)]
    runs = [_start(m) for m in models]
    _assert_batch_equals_singles([s for s, _ in runs], [y for _, y in runs], 1e-5, 300)
    _assert_batch_equals_singles([runs[0][0]], [runs[0][1]], 1e-5, 100)


def test_topology_differences_are_named(elastic_variants):
    elastic = elastic_variants[0][0]
    rigid, _ = _start(_variant("paper-case1", 0.005))
    with pytest.raises(ValueError, match=r"variant 1 .*number of coordinates"):
        kb.pack_batch([elastic, rigid])
    torque = prepare_run(_variant("paper-case1-elastic", 0.005),
                         TorqueDriven(60.0, load_inertia=0.1, duration=0.1, max_rpm=4000),
                         False).system
    with pytest.raises(ValueError, match=r"variant 1 .*drive mode"):
        kb.pack_batch([elastic, torque])
    other_ramp = prepare_run(_variant("paper-case1-elastic", 0.005),
                             SpeedRamp(0.0, 1000.0, 1.0, input_torque=60.0), False).system
    with pytest.raises(ValueError, match="speed table"):
        kb.pack_batch([elastic, other_ramp])
    cracked = prepare_run(_variant("paper-case1-elastic", 0.005).with_faults(
        [Crack("sun", 3, severity=0.3)]), RAMP, False).system
    with pytest.raises(ValueError, match="variant 1 has local faults"):
        kb.pack_batch([elastic, cracked])
    with pytest.raises(ValueError, match="at least one"):
        kb.pack_batch([])
