"""Resonance detection and classification on simulated run-ups of the paper's case 1.

Two run-ups 0 -> 4000 min-1 at 60 N m: the paper's 1 s and a slower 8 s one (simulated once per
test session). Analysed like the report: the sun-mesh tooth force (forced resonances of the
rotational modes f2 and f5 where the mesh orders cross them) and, for the slower run, the
difference of two planets' tooth forces, which holds only the planet modes f3 = f4: the mesh
harmonics do not force them (in-phase planets), but inside the Floquet-unstable bands of the
slow run they grow from round-off by tens of dB (parametric instability).
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.instability import FORCED, PARAMETRIC, UNEXPLAINED, detect_resonances
from analysis.maps import rpm_frequency_map
from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.modal import modal_analysis
from gearvib.simulate import SpeedRamp, simulate
from gearvib.stability import mesh_phasing, stability_over_speed
from tests.gearvib.preset_drive import preset_coupling

H = 0.42653061  # mesh frequency per sun speed, paper eq. (5) [Hz per min-1]


@pytest.fixture(scope="session")
def case1():
    """The preset's drive (a spring-damper on the sun, its [simulation] section) in the runs
    and in the chart: with the default speed drive, which adds no damping to the elastic
    modes, the paper set's rotational modes are parametrically unstable without bound (the
    1 s run-up stops at 2960 min^-1)."""
    model = assemble(load_gearset("paper-case1"))
    drive = preset_coupling("paper-case1")
    modal = modal_analysis(model)
    keep = np.array([k != "rigid-body" for k in modal.kinds])
    chart = stability_over_speed(model, np.linspace(80.0, 4000.0, 300), coupling=drive)
    rule, families = mesh_phasing(model, modal)
    runs = {d: simulate(model, SpeedRamp(0.0, 4000.0, d, input_torque=60.0, coupling=drive),
                        progress=False).to_dataset() for d in (1.0, 8.0)}
    return {"fn": modal.frequencies_hz[keep], "names": [f"f{i + 1}" for i in np.flatnonzero(keep)],
            "chart": chart, "rule": rule, "families": families, "runs": runs}


def _analyse(case1, duration, channel):
    ds = case1["runs"][duration]
    force = ds["normal_force"].sel(flank="left").values - ds["normal_force"].sel(
        flank="right").values
    names = [str(m) for m in ds["mesh"].values]
    x = force[names.index("sun-planet1")]
    if channel == "planet difference":
        x = x - force[names.index("sun-planet2")]
    rpm = np.abs(ds["input_speed"].values)
    t = ds["time"].values
    m = rpm_frequency_map(x - x.mean(), None, rpm, time=t, resolution=20.0, window="hann",
                          overlap=0.9, amplitude="rms", units="N")
    fn = case1["fn"]
    map_ds = m.to_dataset().sel(frequency=slice(0.0, 2.2 * fn.max()))
    return detect_resonances(
        map_ds, natural_frequencies_hz=fn, mesh_frequency_per_rpm=H, orders=range(1, 8),
        names=case1["names"], chart=case1["chart"], mode_families=case1["families"],
        mesh_harmonic_rule=case1["rule"], speed_profile=(t, rpm), natural_uncertainty=0.03,
        dynamic_range_db=40.0, frequency_range=(0.15 * fn.min(), 2.2 * fn.max()))


def test_fast_runup_forced_resonances_and_too_fast_bands(case1):
    res = _analyse(case1, 1.0, "sun mesh")
    assert res.counts()[UNEXPLAINED] == 0, str(res)
    assert res.counts()[FORCED] >= 3
    causes = set(res.cause[res.mechanism == FORCED])
    assert {"1 f_mesh = f2", "2 f_mesh = f5", "3 f_mesh = f5"} <= causes
    # nothing from the start: the quasi-static region and the first frame are left out
    assert res.rpm.min() > 500.0
    # the planet modes are never forced by the in-phase mesh harmonics
    st = {(c.harmonic, c.mode): c.status for c in res.crossings}
    assert [st[(k, "f3=f4")] for k in range(2, 8)] == ["not forced (mesh phasing)"] * 6
    # the 1 s run crosses the 40 min-1 wide planet-mode band in about 10 ms: too fast
    g = res.growth
    i = int(np.argmin(np.abs(g.lower_rpm - 2084.0)))
    assert g.upper_rpm[i] - g.lower_rpm[i] == pytest.approx(39.0, abs=3.0)
    assert g.time_in_band[i] == pytest.approx(9.7e-3, rel=0.05)
    assert not g.can_grow.any()
    assert "run-up of >=" in g.advice[i]


def test_slow_runup_forced_resonances_of_every_order(case1):
    res = _analyse(case1, 8.0, "sun mesh")
    assert res.counts() == {FORCED: 7, PARAMETRIC: 0, UNEXPLAINED: 0}, str(res)
    expected = {1: ("f2", 1261.05), **{k: ("f5", 2201.42) for k in range(2, 8)}}
    for k, (mode, f) in expected.items():
        i = int(np.flatnonzero((res.order == k) & (res.mechanism == FORCED))[0])
        assert res.mode[i] == mode
        # the cause is this ray's own crossing, or (order 7) the 6 f_mesh = f5 resonance seen
        # through the mesh-stiffness modulation at f5 + f_mesh
        kk = int(res.cause[i].split()[0])
        assert kk == k or (k, kk) == (7, 6), res.cause[i]
        assert res.predicted_rpm[i] == pytest.approx(f / (kk * H), rel=1e-3)
        assert res.rpm[i] == pytest.approx(f / (kk * H), rel=0.2)
    assert np.prod(res.coincidence[res.mode == "f5"]) < 0.01  # six f5 rises: no coincidence
    # both planet-mode bands can grow in 8 s, the narrow 2 f2/7 band cannot
    g = res.growth
    assert sorted(np.round(g.lower_rpm[g.can_grow], -1)) == [2080.0, 2770.0]


def test_slow_runup_planet_modes_grow_parametrically(case1):
    res = _analyse(case1, 8.0, "planet difference")
    assert res.counts()[FORCED] == 0 and res.counts()[UNEXPLAINED] == 0, str(res)
    par = res.mechanism == PARAMETRIC
    assert set(res.cause[par]) == {"2 (f3=f4)/4", "2 (f3=f4)/3"}
    # the response sits at f3 = f4 and, in the n = 3 band, at f3 +- f_mesh sidebands
    f34 = 1797.74
    at = res.cause == "2 (f3=f4)/3"
    fm = res.f_mesh[at]
    d = np.minimum.reduce([np.abs(res.frequency[at] - abs(f34 + j * fm)) for j in (-1, 0, 1, 2)])
    assert np.all(d < 0.05 * f34)
    assert np.all((res.rpm[at] > 2700) & (res.rpm[at] < 2900))
    assert float(np.max(res.coincidence[par])) < 0.1  # the bands cover little of the run
