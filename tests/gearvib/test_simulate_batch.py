"""simulate_batch: variants of one gear set on the batched kernel, each result bit-identical
to simulate() of the variant (datasets compared with xr.testing.assert_identical and the raw
arrays byte for byte)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.faults import Crack
from gearvib.sensors import HousingMode, HousingSensor
from gearvib.simulate import (
    SimulationError,
    SpeedRamp,
    TorqueDriven,
    batch_groups,
    simulate,
    simulate_batch,
)
from gearvib.sweep.keys import set_path

RAMP = SpeedRamp(1500.0, 2500.0, 1.0, input_torque=60.0)
DURATION = 4e-3


def _variant(preset: str, damping: float, radial: float | None = None):
    cfg, base = load_config(preset)
    d = set_path(cfg, "meshes.sun.damping_ratio", damping)
    if radial is not None:
        d = set_path(d, "bodies.planet.support.radial", radial)
    return assemble(gearset_from_dict(d, base=base))


def _assert_same_as_single(models, results, **kw):
    assert len(results) == len(models)
    for k, (model, res) in enumerate(zip(models, results, strict=True)):
        single = simulate(model, RAMP, duration=DURATION, progress=False, **kw)
        ds_b, ds_s = res.to_dataset(), single.to_dataset()
        xr.testing.assert_identical(ds_b, ds_s)
        for name in ds_s.variables:
            a, b = np.asarray(ds_b[name].values), np.asarray(ds_s[name].values)
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), (k, name)


@pytest.mark.parametrize("n_variants", [3, 9])
def test_mesh_damping_variants_of_paper_case1(n_variants):
    models = [_variant("paper-case1", 0.01 + 0.004 * k) for k in range(n_variants)]
    results = simulate_batch(models, RAMP, duration=DURATION)
    _assert_same_as_single(models, results)
    # the variants really differ
    assert not np.array_equal(results[0].normal_force, results[-1].normal_force)


def test_variants_with_a_virtual_sensor():
    sensor = HousingSensor("top", 30.0, window="hann", width_deg=90.0,
                           housing_modes=(HousingMode(3000.0, 0.05, 1.0),))
    models = [_variant("paper-case1", z).with_sensors([sensor]) for z in (0.01, 0.03)]
    results = simulate_batch(models, RAMP, duration=DURATION)
    assert results[0].sensor_acceleration is not None
    _assert_same_as_single(models, results)


def test_bearing_stiffness_variants_of_paper_case1_elastic():
    models = [_variant("paper-case1-elastic", 0.01, 1.5e8 * (1 + 0.1 * k)) for k in range(3)]
    results = simulate_batch(models, RAMP, duration=DURATION)  # one default time grid
    _assert_same_as_single(models, results)
    assert not np.array_equal(results[0].bearing_force, results[-1].bearing_force)
    # a stiffness 10x higher moves the default step: refused, with the remedy named ...
    stiff = [models[0], _variant("paper-case1-elastic", 0.01, 1.5e9)]
    with pytest.raises(ValueError, match=r"variant 1 cannot share a batch .* time grid .*dt"):
        simulate_batch(stiff, RAMP, duration=DURATION)
    # ... which works
    dt = 1 / (20_000.0 * 300)
    _assert_same_as_single(stiff, simulate_batch(stiff, RAMP, duration=DURATION, dt=dt), dt=dt)


def test_a_blow_up_is_the_variants_own():
    """A variant whose input speed runs away (torque drive, no load) fails as its single
    run does: raised, or returned in its place; the other variants are the single runs'."""
    model = _variant("paper-case1", 0.01)
    ratio = abs(model.kinematic_ratios[model.output_member])
    kw = dict(load_inertia=0.01, start_rpm=10, max_rpm=20, duration=0.02)
    balanced = TorqueDriven(60.0, load_torque=(60.0 / ratio, 0.0, 0.0), **kw)
    runaway = TorqueDriven(60.0, **kw)
    with pytest.raises(SimulationError) as single:
        simulate(model, runaway, progress=False)
    conds = [balanced, runaway, balanced]
    out = simulate_batch([model] * 3, conds, errors="return")
    assert isinstance(out[1], SimulationError)
    assert str(out[1]) == str(single.value)  # same step, same cause
    ref = simulate(model, balanced, progress=False).to_dataset()
    for k in (0, 2):
        xr.testing.assert_identical(out[k].to_dataset(), ref)
    with pytest.raises(SimulationError, match="variant 1: numerical blow-up"):
        simulate_batch([model] * 3, conds)


def test_refusals_name_what_differs():
    healthy = _variant("paper-case1", 0.01)
    with pytest.raises(ValueError, match="at least one model"):
        simulate_batch([], RAMP)
    with pytest.raises(ValueError, match="number of coordinates"):
        simulate_batch([healthy, _variant("paper-case1-elastic", 0.01)], RAMP,
                       duration=DURATION, dt=1 / 1.6e6)
    with pytest.raises(ValueError, match=r"speed table of the drive"):
        simulate_batch([healthy, healthy], [RAMP, SpeedRamp(1500.0, 2600.0, 1.0,
                                                            input_torque=60.0)],
                       duration=DURATION, dt=1 / 1.6e6)
    cracked = healthy.with_faults([Crack(member="sun", tooth=0, severity=0.3)])
    with pytest.raises(ValueError, match=r"models\[1\] has local tooth faults"):
        simulate_batch([healthy, cracked], RAMP, duration=DURATION)
    with pytest.raises(ValueError, match="errors = 'ignore'"):
        simulate_batch([healthy], RAMP, errors="ignore")
    with pytest.raises(ValueError, match="conditions must be one value or one per model"):
        simulate_batch([healthy, healthy], [RAMP])


def test_batch_groups():
    """Variants split into what simulate_batch accepts: by default time grid, faults alone."""
    soft = [_variant("paper-case1-elastic", 0.01, r) for r in (1.5e8, 1.65e8)]
    stiff = _variant("paper-case1-elastic", 0.01, 1.5e9)
    cracked = soft[0].with_faults([Crack(member="sun", tooth=0, severity=0.3)])
    models = [soft[0], stiff, cracked, soft[1], stiff]
    assert batch_groups(models, RAMP, duration=DURATION) == [[0, 3], [1, 4], [2]]
    # with one explicit step the healthy variants share one batch
    assert batch_groups(models, RAMP, duration=DURATION, dt=1 / (20_000.0 * 300)) == \
        [[0, 1, 3, 4], [2]]
    many = batch_groups([soft[0]] * 10, RAMP, duration=DURATION)
    assert [len(g) for g in many] == [8, 2]
