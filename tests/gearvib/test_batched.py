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
from gearvib.simulate import DriveCoupling, SpeedRamp, TorqueDriven, prepare_run
from gearvib.sweep.keys import set_path
from tests.gearvib.batch_support import RAMP, start_state


def _variant(preset: str, damping: float, radial: float | None = None):
    cfg, base = load_config(preset)
    d = set_path(cfg, "meshes.sun.damping_ratio", damping)
    if radial is not None:
        d = set_path(d, "bodies.planet.support.radial", radial)
    return assemble(gearset_from_dict(d, base=base))


@pytest.fixture(scope="module")
def elastic_variants():
    models = [_variant("paper-case1-elastic", 0.005 * (1 + k), 1.5e8 * (1 + 0.05 * k))
              for k in range(4)]
    return [start_state(m) for m in models]


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
    runs = [start_state(m) for m in models]
    _assert_batch_equals_singles([s for s, _ in runs], [y for _, y in runs], 1e-5, 300)
    _assert_batch_equals_singles([runs[0][0]], [runs[0][1]], 1e-5, 100)


def test_topology_differences_are_named(elastic_variants):
    elastic = elastic_variants[0][0]
    rigid, _ = start_state(_variant("paper-case1", 0.005))
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
    on_input = prepare_run(_variant("paper-case1-elastic", 0.005),
                           dataclasses.replace(RAMP, coupling=DriveCoupling(3000.0, 5.0)),
                           False).system
    with pytest.raises(ValueError, match=r"variant 1 .*drive coupling \(on the input member "
                                         r"or on the rigid-body mode\)"):
        kb.pack_batch([elastic, on_input])
    cracked = prepare_run(_variant("paper-case1-elastic", 0.005).with_faults(
        [Crack("sun", 3, severity=0.3)]), RAMP, False).system
    with pytest.raises(ValueError, match="variant 1 has local faults"):
        kb.pack_batch([elastic, cracked])
    with pytest.raises(ValueError, match="at least one"):
        kb.pack_batch([])
    with pytest.raises(ValueError, match="at most 8"):
        kb.pack_batch([elastic] * 9)


def _elastic(damping: float, radial: float | None = None, k_max: float | None = None):
    cfg, base = load_config("paper-case1-elastic")
    d = set_path(cfg, "meshes.sun.damping_ratio", damping)
    if radial is not None:
        d = set_path(d, "bodies.planet.support.radial", radial)
    if k_max is not None:
        d = set_path(d, "meshes.sun.stiffness.k_max", k_max)
    return start_state(assemble(gearset_from_dict(d, base=base)))


def test_full_batch_and_more_than_one_batch(elastic_variants):
    """Nine variants: one full batch of eight lanes and one of one lane (padded)."""
    runs = list(elastic_variants) + [_elastic(0.005 * (1 + k), 1.4e8 * (1 + 0.03 * k))
                                     for k in range(5)]
    assert len(runs) == kb.WIDTH + 1
    _assert_batch_equals_singles([s for s, _ in runs], [y for _, y in runs], 8e-6, 150)


def test_lanes_with_their_own_stiffness_tables():
    """Variants of the sun-mesh stiffness amplitude: a stiffness table per lane."""
    runs = [_elastic(0.005, k_max=4.3333e7 * (1 + 0.1 * k)) for k in range(3)]
    batch = kb.pack_batch([s for s, _ in runs])
    assert batch.tables.shape[-1] == kb.WIDTH  # not one shared table
    rec = _assert_batch_equals_singles([s for s, _ in runs], [y for _, y in runs], 8e-6, 300)
    assert not np.array_equal(rec[0], rec[2])


def test_shared_and_uniform_data_are_loaded_once(elastic_variants):
    """Damping variants share the tables and every geometric operator; bearing-stiffness
    variants differ in the stiffness operator, whose common pattern holds stored zeros."""
    damping = kb.pack_batch([_elastic(0.005 * (1 + k))[0] for k in range(3)])
    assert damping.tables.shape[-1] == 1
    assert damping.uniform.tolist()[3:] == [2, 2, 2, 2, 2]  # mesh vectors, forces, ...
    bearing = kb.pack_batch([s for s, _ in elastic_variants])
    assert bearing.uniform[0] == 0  # stiffness and damping: per lane, with stored zeros


def test_right_hand_side_per_lane_at_its_own_time(elastic_variants):
    """The batched right-hand side against the single one, lane by lane, at different times
    and states (the drive evaluated per lane)."""
    systems = [s for s, _ in elastic_variants]
    batch = kb.pack_batch(systems)
    rng = np.random.default_rng(3)
    y0 = np.array([y for _, y in elastic_variants])
    y = np.empty((y0.shape[1], kb.WIDTH))
    t = np.empty(kb.WIDTH)
    for b in range(kb.WIDTH):
        k = b % len(systems)
        y[:, b] = y0[k] * (1 + 1e-4 * rng.standard_normal(y0.shape[1]))
        t[b] = 0.1 + 0.01 * b
    dy, mo = kb.evaluate_rhs_batch(t, y, batch)
    for b in range(kb.WIDTH):
        system = systems[b] if b < len(systems) else systems[0]  # padded with variant 0
        dy1, mo1 = kn.evaluate_rhs(t[b], np.ascontiguousarray(y[:, b]), system.astuple())
        assert dy[:, b].tobytes() == dy1.tobytes()
        assert mo[:, :, b].tobytes() == mo1.tobytes()


def test_torque_driven_variants():
    """The torque drive (a table of time), from rest."""
    cond = TorqueDriven(60.0, load_inertia=0.1, duration=0.1, max_rpm=4000)
    cfg, base = load_config("paper-case1-elastic")
    systems = []
    for k in range(2):
        d = set_path(cfg, "meshes.sun.damping_ratio", 0.005 * (1 + k))
        setup = prepare_run(assemble(gearset_from_dict(d, base=base)), cond, False)
        setup.system.deflection_limit[:] = 1.0
        systems.append(setup.system)
    assert systems[0].ipar[0] == kn.DRIVE_TORQUE
    y0 = np.zeros((2, 2 * systems[0].n_dof))
    rec = _assert_batch_equals_singles(systems, y0, 8e-6, 300)
    assert np.any(rec[:, -1, : systems[0].n_dof] != 0.0)  # the drive moved them


def test_a_failing_variant_stops_where_its_single_run_does(elastic_variants):
    """A variant whose deflection limit is exceeded stops at its single run's step, with the
    same status, rows and state; the others go on to the end."""
    systems = [dataclasses.replace(s) for s, _ in elastic_variants[:3]]
    y0 = np.array([y for _, y in elastic_variants[:3]])
    n_steps = 200
    # a limit the deflections of variant 1 reach half-way between their start and their peak
    r, *_ = kn.integrate(systems[1], y0[1], 8e-6, n_steps)
    n = systems[1].n_dof
    peak = [np.abs(kn.evaluate_rhs(i * 8e-6, r[i, : 2 * n], systems[1].astuple())[1][:, [4, 6]]
                   ).max() for i in range(0, n_steps + 1, 10)]
    systems[1].deflection_limit = np.full_like(systems[1].deflection_limit,
                                               0.5 * (peak[0] + max(peak)))
    rec, changes, status, y_end = kb.integrate_batch(systems, y0, 8e-6, n_steps)
    r, ch, st, y1 = kn.integrate(systems[1], y0[1], 8e-6, n_steps)
    assert st[0] == kn.STATUS_DEFLECTION and 0 < st[1] < n_steps
    assert status[1].tolist() == st.tolist()
    last = st[1] + 1  # rows up to and including the failed step
    assert rec[1, :last].tobytes() == r[:last].tobytes()
    assert y_end[1].tobytes() == y1.tobytes()
    assert np.array_equal(changes[1], ch)
    for b in (0, 2):
        r, ch, st, y1 = kn.integrate(systems[b], y0[b], 8e-6, n_steps)
        assert status[b, 0] == kn.STATUS_OK and st[0] == kn.STATUS_OK
        assert rec[b].tobytes() == r.tobytes() and y_end[b].tobytes() == y1.tobytes()
