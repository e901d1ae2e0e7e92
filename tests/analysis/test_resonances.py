"""Resonance detection on synthetic rpm-frequency maps with known spots."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from analysis.instability import MeshPhasingRule, detect_resonances, instability_candidates

FACTOR = 0.5  # mesh frequency per rpm [Hz/min-1]
FN = [1250.0, 1800.0, 1800.0, 2200.0]
NAMES = ["f2", "f3", "f4", "f5"]
FAMILIES = [("rotational", 0), ("translational", 1), ("translational", 1), ("rotational", 0)]


def synthetic_map(spots, seed=1):
    t = np.linspace(0.0, 10.0, 400)
    rpm = 400.0 * t
    f = np.arange(0.0, 4000.0, 4.0)
    rng = np.random.default_rng(seed)
    a = 1.0 + 0.1 * rng.random((t.size, f.size))
    fm = FACTOR * rpm
    for o in (1, 2, 3):  # constant order content along the rays (no rise)
        a += 3.0 * np.exp(-0.5 * ((f[None, :] - o * fm[:, None]) / 6.0) ** 2)
    for speed, freq, amp in spots:
        a += amp * np.exp(-0.5 * ((t[:, None] - speed / 400.0) / 0.1) ** 2
                          - 0.5 * ((f[None, :] - freq) / 8.0) ** 2)
    return xr.Dataset(
        {"amplitude": (("time", "frequency"), a, {"units": "N", "long_name": "force"})},
        coords={"time": ("time", t, {"units": "s"}), "frequency": ("frequency", f,
                                                                    {"units": "Hz"}),
                "rpm": ("time", rpm, {"units": "min-1"})},
    )


SPOTS = [
    (1800.0, 1800.0, 30.0),  # order 2 ray crosses f3 = f4: forced resonance
    (2 * 1250.0 / 3 / FACTOR, 1250.0, 20.0),  # f_mesh = 2 f2/3, response at f2 (1.5 f_mesh)
    ((1250.0 + 2200.0) / 2 / FACTOR, 2200.0, 20.0),  # f_mesh = (f2 + f5)/2, response at f5
    (1000.0, 3250.0, 15.0),  # off every ray and natural frequency
]


def test_classification_of_known_spots():
    ds = synthetic_map(SPOTS)
    res = detect_resonances(ds, natural_frequencies_hz=FN, mesh_frequency_per_rpm=FACTOR,
                            names=NAMES)
    assert len(res) == 4
    got = {round(r): (m, o, md) for r, m, o, md in
           zip(res.rpm, res.mechanism, res.order, res.mode, strict=True)}
    expected_rpm = [1800, 1667, 3450, 1000]
    rpms = sorted(got)
    for r, e in zip(rpms, sorted(expected_rpm), strict=True):
        assert abs(r - e) < 15  # one time bin is 10 rpm
    by = {e: got[min(got, key=lambda r, e=e: abs(r - e))] for e in expected_rpm}
    assert by[1800] == ("forced resonance", 2, "f3=f4")
    assert by[1667] == ("parametric instability (principal, n=3)", 0, "f2")
    assert by[3450] == ("parametric instability (sum, n=2)", 0, "f5")
    assert by[1000] == ("unclassified", 0, "")
    assert np.allclose(res.f_mesh, FACTOR * res.rpm)
    # strengths: the forced spot against the ray median (1 + 3), the others against the floor
    i_forced = int(np.flatnonzero(res.order == 2)[0])
    assert res.strength_db[i_forced] == pytest.approx(20 * np.log10(34.0 / 4.05), abs=0.5)
    assert np.all(res.strength_db >= 6.0)
    ds_out = res.to_dataset()
    for name, var in ds_out.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert set(ds_out.data_vars) >= {"speed", "time", "frequency", "order", "mechanism",
                                     "strength_db"}
    from matplotlib.figure import Figure

    assert isinstance(res.plot(ds), Figure)


def test_threshold_and_suppressed_candidates():
    ds = synthetic_map(SPOTS)
    res = detect_resonances(ds, natural_frequencies_hz=FN, mesh_frequency_per_rpm=FACTOR,
                            names=NAMES, threshold_db=24.5)
    # 20x over a floor of ~1.05 is ~26 dB; the forced spot is ~18.5 dB above its ray and the
    # 15x unclassified spot ~23.4 dB above the floor
    assert sorted(res.mechanism) == ["parametric instability (principal, n=3)",
                                     "parametric instability (sum, n=2)"]
    # in-phase planets (z_s = 33, N = 3): the rot-trans sum (f2 + f3=f4)/2 is suppressed
    cand = instability_candidates(FN, n_max=4, mode_labels=NAMES, mode_families=FAMILIES,
                                  mesh_harmonic_rule=MeshPhasingRule(3, 33, 114))
    spot = ((1250.0 + 1800.0) / 2 / FACTOR, 1250.0, 20.0)
    res = detect_resonances(synthetic_map([spot]), natural_frequencies_hz=FN,
                            mesh_frequency_per_rpm=FACTOR, names=NAMES, candidates=cand)
    assert len(res) == 1
    assert res.mechanism[0] == "unclassified"
    assert "suppressed" in res.note[0] and "(f2 + (f3=f4))/2" in res.note[0]
    # without the selection rule the same spot is a sum-type instability
    res = detect_resonances(synthetic_map([spot]), natural_frequencies_hz=FN,
                            mesh_frequency_per_rpm=FACTOR, names=NAMES)
    assert res.mechanism[0] == "parametric instability (sum, n=2)"


def test_no_spots_gives_empty_table():
    res = detect_resonances(synthetic_map([]), natural_frequencies_hz=FN,
                            mesh_frequency_per_rpm=FACTOR)
    assert len(res) == 0 and res.to_dataset().sizes["resonance"] == 0


def test_layout_errors():
    ds = synthetic_map([])
    kw = {"natural_frequencies_hz": FN, "mesh_frequency_per_rpm": FACTOR}
    with pytest.raises(ValueError, match="rpm"):
        detect_resonances(ds.drop_vars("rpm"), **kw)
    with pytest.raises(ValueError, match="no data variable"):
        detect_resonances(ds.rename({"amplitude": "level"}), **kw)
    with pytest.raises(ValueError, match="dims"):
        detect_resonances(ds.rename({"frequency": "freq"}), **kw)
    with pytest.raises(ValueError, match="non-negative"):
        detect_resonances(ds.assign(amplitude=-ds.amplitude), **kw)
    with pytest.raises(ValueError, match="must be > 0"):
        detect_resonances(ds, natural_frequencies_hz=[0.0], mesh_frequency_per_rpm=FACTOR)
    with pytest.raises(ValueError, match="mesh_frequency_per_rpm"):
        detect_resonances(ds, natural_frequencies_hz=FN, mesh_frequency_per_rpm=-1.0)
