"""Several mesh frequencies: model groups, ``mesh_frequency(mesh, time)`` in the Dataset and the
report of a two-stage set, checked against the kinematics worked by hand.

Hand kinematics (ring fixed, sun in, carrier out in both stages; speeds in min^-1):
``n_c = n_s z_s / (z_s + |z_r|)``, mesh frequency ``f = z_s |n_s - n_c| / 60``, and the stage-2
sun turns with the stage-1 carrier.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict
from gearvib.report import AnalysisSettings
from gearvib.report.case import analyse_case
from gearvib.report.figures import order_map_figure, sonogram_figure
from gearvib.report.html import render_html
from gearvib.report.sections import report_sections
from gearvib.simulate import SpeedRamp, simulate
from gearvib.structure import Body, MeshSpec, wolfrom
from tests.gearvib.preset_drive import input_coupling
from tests.gearvib.two_stage_sets import other_stage, paper_stage, two_stage_config

Z_S1, Z_R1, Z_S2, Z_R2 = 33, 114, 21, 78


def hand_mesh_frequencies(n_in: float) -> tuple[float, float]:
    """Stage-1 and stage-2 mesh frequencies [Hz] at input speed ``n_in`` [min^-1]."""
    n_c1 = n_in * Z_S1 / (Z_S1 + Z_R1)
    n_s2 = n_c1  # the stage-1 output drives stage 2
    n_c2 = n_s2 * Z_S2 / (Z_S2 + Z_R2)
    return Z_S1 * abs(n_in - n_c1) / 60.0, Z_S2 * abs(n_s2 - n_c2) / 60.0


@pytest.fixture(scope="module")
def config() -> dict:
    return two_stage_config(paper_stage(), other_stage())


@pytest.fixture(scope="module")
def model(config):
    return assemble(gearset_from_dict(config))


@pytest.fixture(scope="module")
def run(model, config):
    """A short run-up 0 -> 6000 min^-1 in 0.25 s carrying its gear-set description (driven
    through a spring-damper on the input, as the paper presets: the paper stages' light mesh
    damping leaves them parametrically unstable under the default speed drive)."""
    run = dict(config["simulation"], duration=0.25, fs_out=20000.0)
    res = simulate(model, SpeedRamp(0.0, 6000.0, 0.25, input_torque=60.0,
                                    coupling=input_coupling(model)), fs_out=20000.0,
                   config={"gearset": config, "run": run, "case": "two-stage"})
    return res.to_dataset()


def test_model_has_one_mesh_frequency_per_stage(model):
    f1, f2 = hand_mesh_frequencies(1.0)
    groups = model.mesh_frequency_groups()
    assert [g.name for g in groups] == ["stage 1", "stage 2"]
    assert groups[0].frequency_per_rpm == pytest.approx(f1, rel=1e-12)
    assert groups[1].frequency_per_rpm == pytest.approx(f2, rel=1e-12)
    assert all(n.startswith("s1.") for n in groups[0].mesh_names)
    assert all(n.startswith("s2.") for n in groups[1].mesh_names)
    assert len(groups[0].meshes) == len(groups[1].meshes) == 6
    # per mesh, and the signed rate the kernels advance the mesh position with
    expected = np.array([f1] * 6 + [f2] * 6)
    np.testing.assert_allclose(model.mesh_frequencies_per_rpm, expected, rtol=1e-12)
    np.testing.assert_allclose(np.abs(model.mesh_position_rates_per_rpm()), expected, rtol=1e-9)
    with pytest.raises(ValueError, match=r"2 mesh frequencies.*stage 1.*stage 2"):
        _ = model.mesh_frequency_per_rpm


def test_single_stage_keeps_its_scalar_mesh_frequency():
    m = assemble(gearset_from_dict({**paper_stage(), "name": "one"}))
    (g,) = m.mesh_frequency_groups()
    assert m.mesh_frequency_per_rpm == g.frequency_per_rpm == pytest.approx(
        hand_mesh_frequencies(1.0)[0], rel=1e-12)


def test_wolfrom_toothings_have_their_own_mesh_frequency():
    """Stepped planet: sun and ring 1 mesh with toothing 1, ring 2 with toothing 2, so
    f_ring2 / f_sun = z_p2 / z_p1 = 24/27 (same planet speed relative to the carrier)."""
    def central(name: str) -> Body:
        return Body(name, "central", 1.0, 1e-3)

    spec = MeshSpec(stiffness={"model": "rectangular", "k_min": 3e7, "k_max": 5e7})
    gs = wolfrom(z_sun=18, z_ring1=-72, z_ring2=-69, z_planet1=27, z_planet2=24, module=2e-3,
                 module2=2e-3 * 45 / 45, sun=central("sun"), ring1=central("ring1"),
                 ring2=central("ring2"),
                 carrier=Body("carrier", "carrier", 2.0, 1e-2),
                 planet=Body("planet", "planet", 0.3, 1e-4, carrier="carrier"), sun_mesh=spec,
                 ring_mesh=spec)
    m = assemble(gs)
    groups = m.mesh_frequency_groups()
    assert [g.name for g in groups] == ["sun, ring1", "ring2"]
    r = m.kinematic_ratios
    f_sun = 18 * abs(r["sun"] - r["carrier"]) / 60
    assert groups[0].frequency_per_rpm == pytest.approx(f_sun, rel=1e-9)
    assert groups[1].frequency_per_rpm / groups[0].frequency_per_rpm == pytest.approx(24 / 27,
                                                                                      rel=1e-9)


def test_dataset_mesh_frequency_per_mesh_matches_hand_kinematics(run):
    mf = run["mesh_frequency"]
    assert mf.dims == ("mesh", "time")
    assert mf.attrs["units"] == "Hz" and mf.attrs["long_name"]
    n_in = run["input_speed"].values
    f1, f2 = hand_mesh_frequencies(1.0)
    np.testing.assert_allclose(mf.sel(mesh="s1.sun-planet2").values, f1 * np.abs(n_in),
                               rtol=1e-12)
    np.testing.assert_allclose(mf.sel(mesh="s2.ring-planet3").values, f2 * np.abs(n_in),
                               rtol=1e-12)
    # at the end of the ramp, 6000 min^-1: 2559.18 Hz and 371.43 Hz (hand values)
    assert mf.sel(mesh="s1.sun-planet1").values[-1] == pytest.approx(2559.1837, abs=1e-3)
    assert mf.sel(mesh="s2.sun-planet1").values[-1] == pytest.approx(371.4286, abs=1e-3)
    # the simulated member speeds follow the same kinematics (drive-coupling lag < 0.5 %)
    n_s2 = run["speed"].sel(member="s1.carrier").values[-1]  # s2.sun is joined to it
    n_c2 = run["speed"].sel(member="s2.carrier").values[-1]
    assert Z_S2 * abs(n_s2 - n_c2) / 60 == pytest.approx(371.43, rel=5e-3)
    # the coordinate follows every tooth-force variable of a mesh
    assert "mesh_frequency" in run["normal_force"].sel(mesh="s2.sun-planet1").coords


def test_stage2_tooth_force_spectrum_peaks_at_the_stored_mesh_frequency(model):
    """Constant 3000 min^-1: the stage-2 tooth force's strongest line is the Dataset's stage-2
    mesh frequency (185.7 Hz by hand), and the stage-1 force's is the stage-1 one (1279.6 Hz)."""
    res = simulate(model, SpeedRamp(3000.0, 3000.0, 0.3, input_torque=60.0,
                                    coupling=input_coupling(model)), fs_out=20000.0)
    ds = res.to_dataset()
    f1, f2 = (3000.0 * f for f in hand_mesh_frequencies(1.0))
    keep = ds["time"].values > 0.1
    for mesh, f_hand, band in (("s2.sun-planet1", f2, (100.0, 300.0)),
                               ("s1.sun-planet1", f1, (1000.0, 1500.0))):
        stored = float(ds["mesh_frequency"].sel(mesh=mesh).values[-1])
        assert stored == pytest.approx(f_hand, rel=1e-12)
        x = ds["normal_force"].sel(mesh=mesh, flank="left").values[keep]
        spec = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(x.size)))
        freqs = np.fft.rfftfreq(x.size, 1.0 / 20000.0)
        sel = (freqs > band[0]) & (freqs < band[1])
        peak = freqs[sel][np.argmax(spec[sel])]
        assert abs(peak - stored) <= freqs[1], (mesh, peak, stored)


def test_report_states_and_draws_the_stage2_mesh_frequency(run):
    settings = AnalysisSettings(stability_points=40, map_resolution_hz=40.0)
    ca = analyse_case(run, settings=settings)
    f1, f2 = hand_mesh_frequencies(1.0)
    assert [n for n, _ in ca.mesh_frequencies] == ["stage 1", "stage 2"]
    assert ca.mesh_frequencies[1][1] == pytest.approx(f2, rel=1e-12)
    # order lines: one family per mesh frequency, k x f_g x rpm
    fig = sonogram_figure(ca)
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    for name, f in (("stage 1", f1), ("stage 2", f2)):
        ln = lines[f"mesh orders, {name}"]
        freq, rpm = ln.get_data()
        np.testing.assert_allclose(np.asarray(freq) / np.asarray(rpm), f, rtol=1e-12)
    omap = order_map_figure(ca)
    assert omap is not None
    labels = [t.get_text() for t in omap.legends[0].get_texts()]
    assert labels == [f"stage 1: k × {60 * f1:.4g}", f"stage 2: k × {60 * f2:.4g}"]
    # the Floquet chart and the candidates name the mesh frequency they belong to
    assert ca.chart is not None and ca.chart.mesh_frequency_names == ("stage 1", "stage 2")
    assert set(ca.candidates.mesh_frequency) == {"stage 1", "stage 2"}
    s2 = ca.candidates.mesh_frequency == "stage 2"
    np.testing.assert_allclose(ca.candidates.f_mesh_hz[s2] / ca.candidates.rpm[s2], f2,
                               rtol=1e-12)
    html = render_html(report_sections([ca]), title="two-stage")  # what build_report writes
    m = re.search(r"mesh frequency per input speed, stage 2</td><td>([0-9.]+) Hz", html)
    assert m and float(m.group(1)) == pytest.approx(f2, rel=1e-5)
    # every mesh frequency at the top speed (6000 min^-1); the paper's speeds (1500 min^-1 ...)
    # are not given for a set that is not the paper's
    m = re.search(r"f_mesh,stage 2 = [0-9.]+ Hz per min⁻¹ × n_in \([0-9.]+ mesh cycles per "
                  r"input revolution; (\d+) Hz at 6000 min⁻¹", html)
    assert m and int(m.group(1)) == round(6000 * f2) == 371
    m = re.search(r"f_mesh,stage 1 = [^;]+; (\d+) Hz at 6000 min⁻¹", html)
    assert m and int(m.group(1)) == round(6000 * f1) == 2559
    assert "at 1500 min⁻¹" not in html and not ca.paper_set
    assert "[stage 2]" in html  # candidate rows per mesh frequency


def test_report_of_stored_run_without_gearset_reads_every_mesh_frequency(run):
    ds = run.copy()
    ds.attrs["config_json"] = "{}"
    ca = analyse_case(ds, settings=AnalysisSettings(stability_points=20,
                                                    map_resolution_hz=40.0))
    f1, f2 = hand_mesh_frequencies(1.0)
    assert [n for n, _ in ca.mesh_frequencies] == ["stage 1", "stage 2"]
    assert ca.mesh_frequencies[0][1] == pytest.approx(f1, rel=1e-9)
    assert ca.mesh_frequencies[1][1] == pytest.approx(f2, rel=1e-9)
    assert set(ca.candidates.mesh_frequency) == {"stage 1", "stage 2"}
    assert math.isclose(ca.mesh_frequency_per_rpm, f1, rel_tol=1e-9)
