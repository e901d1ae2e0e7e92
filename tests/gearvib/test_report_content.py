"""Issue #15: reports whose tables agree, on every gear-set type and drive, with readable
figures, a bounded stability analysis and nothing left behind when interrupted.

Every report built here passes :func:`gearvib.report.crosscheck.cross_check`: the same Floquet
region has the same candidate in every table, a label's speed is that of its row in the
candidate table, and the counts in the text equal the rows of the tables. The demo report is
the session fixture of conftest.py; the others are short runs (0.25-0.4 s) with the coarse
stability chart where the full one would only cost time.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from gearvib.config import ConfigError
from gearvib.io import read_run
from gearvib.report import AnalysisSettings, Study, build_report, load_study, run_study
from gearvib.report.case import analyse_case
from gearvib.report.case_analysis import MARKER_BUDGET
from gearvib.report.crosscheck import cross_check, parse_report
from gearvib.report.figures import (
    order_map_figure,
    sonogram_figure,
    spectra_figure,
    stability_figure,
    tooth_force_figure,
)
from gearvib.report.sections import report_sections

REPO = Path(__file__).resolve().parents[2]
COARSE = AnalysisSettings(stability="coarse", map_resolution_hz=40.0)


def _html(result) -> str:
    return result.report.html.read_text(encoding="utf-8")


def _tables(html: str) -> dict:
    tables, _ = parse_report(html)
    return {t.caption: t for t in tables}


@pytest.fixture(scope="module")
def elastic(tmp_path_factory):
    """The shipped recipe (rigid against elastic bearings), 0.25 s run-ups."""
    out = tmp_path_factory.mktemp("elastic")
    return run_study(load_study(REPO / "gearvib" / "recipes" / "paper-case1-elastic.toml"), out,
                     progress=False, duration=0.25)


@pytest.fixture(scope="module")
def two_stage(tmp_path_factory):
    out = tmp_path_factory.mktemp("two-stage")
    return run_study(Study.for_presets(["two-stage-example"], analysis=COARSE), out,
                     progress=False, duration=0.25)


@pytest.fixture(scope="module")
def wolfrom(tmp_path_factory):
    out = tmp_path_factory.mktemp("wolfrom")
    return run_study(Study.for_presets(["wolfrom-example"], analysis=COARSE), out,
                     progress=False, duration=0.25)


@pytest.fixture(scope="module")
def demo_cases(demo_study):
    """The demo's two cases analysed again (the figure builders need the objects)."""
    return [analyse_case(read_run(p)) for p in demo_study.runs.values()]


# --------------------------------------------------------------------------- cross-checks


@pytest.mark.parametrize("report", ["demo_study", "elastic", "two_stage", "wolfrom"])
def test_every_report_passes_the_cross_check_of_its_tables(report, request):
    result = request.getfixturevalue(report)
    html = _html(result)
    assert cross_check(html) == []
    assert "Floquet" in html and not re.search(r"\bnan\b", re.sub(r"base64,[^\"]+", "", html))


def test_cross_check_finds_what_contradicts(demo_study):
    """The check is not vacuous: relabelling a region in one table, dropping a rise or
    miscounting regions are found."""
    html = _html(demo_study)
    assert "2 (f3=f4)/4</td>" in html
    bad = html.replace("<td>2 (f3=f4)/4</td><td>2.", "<td>2 f2/4</td><td>2.", 1)  # growth
    assert bad != html and any("growth table" in p for p in cross_check(bad))
    bad = html.replace("<td>2 (f3=f4)/3</td><td>parametric", "<td>2 f5/4</td><td>parametric",
                       1)
    assert any("candidate table puts it" in p or "growth table" in p for p in cross_check(bad))
    bad = re.sub(r"(; )(\d+)( speed regions?\.)", lambda m: f"{m[1]}{int(m[2]) + 1}{m[3]}",
                 html, count=1)
    assert any("speed region" in p for p in cross_check(bad))


def test_floquet_labels_hold_at_their_regions(demo_study):
    """The 839-844 min^-1 region of case 1 is 2 (f3=f4)/10 (the old report said 2 f2/4, 1478
    min^-1 away), and that candidate is a row of the candidate table at 843 min^-1."""
    t = _tables(_html(demo_study))
    fl = t["Unstable speed intervals of paper-case1 (Floquet)"]
    rows = {(r[0], r[1]): r[5] for r in fl.rows}
    assert rows[("839", "844")] == "2 (f3=f4)/10"
    assert rows[("2084", "2123")] == "2 (f3=f4)/4"
    cand = next(v for k, v in t.items() if k.startswith("Theory candidates of paper-case1"))
    row = next(r for r in cand.rows if r[4] == "2 (f3=f4)/10")
    assert row[0] == "843" and row[5] == "yes" and row[6] == "yes"
    assert "growing solution: f4" in " ".join(r[7] for r in fl.rows if r[0] == "839")


# --------------------------------------------------------------------------- gear-set types


def test_two_stage_report_covers_both_stages(two_stage):
    html = _html(two_stage)
    t = _tables(html)
    params = dict(t["Gear set and run of two-stage-example"].rows)
    assert "z_sun = 21" in params["geometry [stage1]"]
    assert "z_sun = 24" in params["geometry [stage2]"]
    assert "stiffness = 130000" in params["shaft"]
    stiff = t["Summed mesh stiffness per central gear"]
    assert [r[1] for r in stiff.rows] == ["s1.sun", "s1.ring", "s2.sun", "s2.ring"]
    assert all(float(r[5]) > 0 for r in stiff.rows)
    # tooth forces of both stages, one panel each
    fig = _figure(two_stage, "tooth-forces")
    assert len([a for a in fig.axes if a.get_ylabel().startswith("normal")]) == 2
    # the mesh orders of both stages cross the natural frequencies (each its own crossings),
    # and a rise on a mesh order names its stage
    crossings = t["Crossings in two-stage-example"].column("crossing")
    assert any(c.endswith("[stage 1]") for c in crossings)
    assert any(c.endswith("[stage 2]") for c in crossings)
    rises = t["Rises of two-stage-example"]
    for on, cause in zip(rises.column("on"), rises.column("mechanism: cause"), strict=True):
        if on.startswith("k="):
            assert on.endswith(("(s1)", "(s2)"))
            assert ":" not in cause or cause.endswith(("[stage 1]", "[stage 2]"))
    # no statement of the paper's example for another gear set
    for text in ("at 1500 min⁻¹", "paper eq. 5", "0.8e8", "keep their numbers",
                 "Statements of the paper"):
        assert text not in html, text


def test_wolfrom_report_covers_both_toothings(wolfrom):
    html = _html(wolfrom)
    t = _tables(html)
    stiff = t["Summed mesh stiffness per central gear"]
    assert [r[1] for r in stiff.rows] == ["sun", "ring1", "ring2"]
    assert [r[2] for r in stiff.rows] == ["sun, ring1", "sun, ring1", "ring2"]
    assert "z = -69/24" in " ".join(v for k, v in t["Gear set and run of wolfrom-example"].rows)
    rises = t["Rises of wolfrom-example"]
    groups = {m.group(1) for c in rises.column("mechanism: cause")
              for m in [re.search(r"\[(.*)\]$", c)] if m}
    assert groups <= {"sun, ring1", "ring2"} and groups
    assert "at 1500 min⁻¹" not in html


def _figure(result, section: str):
    from gearvib.report.case import analyse_case as analyse

    ca = analyse(read_run(next(iter(result.runs.values()))))
    return {"tooth-forces": tooth_force_figure}[section](ca)


def test_report_uses_the_drive_of_the_description(tmp_path):
    """A motor and a torque drive are simulated as such (not as a speed ramp) and described
    without an "input torque nan"; a study's input torque cannot override a motor."""
    head = (REPO / "gearvib" / "presets" / "paper-case1.toml").read_text().split(
        "[simulation]")[0]
    sims = {"motor": 'drive = "motor"\nmotor = { synchronous_rpm = 3000.0, breakdown_torque '
                     '= 120.0, breakdown_slip = 0.15 }\nload_torque = [20.0, 0.0, 0.0]\n'
                     'load_inertia = 0.5\nduration = 0.25\n',
            "torque": 'drive = "torque"\ninput_torque = 40.0\nload_torque = [0.0, 0.0, 0.02]\n'
                      'load_inertia = 0.3\nduration = 0.25\n'}
    paths = []
    for drive, sim in sims.items():
        cfg = tmp_path / f"{drive}.toml"
        cfg.write_text(head + "[simulation]\n" + sim)
        paths.append(str(cfg))
    st = Study.for_presets(paths, analysis=AnalysisSettings(stability="off",
                                                            map_resolution_hz=40.0))
    result = run_study(st, tmp_path / "out", progress=False)
    html = _html(result)
    expected = {"motor": "induction motor (Kloss: synchronous 3000 min⁻¹",
                "torque": "constant input torque 40 N m"}
    for drive in sims:
        run = json.loads(read_run(result.runs[drive]).attrs["config_json"])["model"]["run"]
        assert run["drive"] == drive
        row = dict(_tables(html)[f"Gear set and run of {drive}"].rows)["run"]
        assert row.startswith(expected[drive]) and "reached" in row
    assert not re.search(r"\bnan\b", re.sub(r"base64,[^\"]+", "", html))
    assert "Floquet stability chart not computed" in html
    assert cross_check(html) == []
    with pytest.raises(ConfigError, match=r"\[run\]\.input_torque does not apply"):
        run_study(Study.for_presets(paths[:1], input_torque=10.0), tmp_path / "x",
                  progress=False)
    assert not (tmp_path / "x").exists()


# --------------------------------------------------------------------------- figures


def _texts(fig) -> list[str]:
    return [t.get_text() for ax in fig.axes for t in ax.texts]


def _no_overlap(fig) -> None:
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(r) for ax in fig.axes for t in ax.texts]
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not a.overlaps(b), (a, b)


def test_sonogram_labels_every_mesh_order_and_natural_frequency(demo_cases):
    for ca in demo_cases:
        fig = sonogram_figure(ca)
        texts = _texts(fig)
        assert {f"{k}×" for k in range(1, 8)} <= set(texts)
        assert {"f2", "f3=f4", "f5"} <= set(texts)
        _no_overlap(fig)
        # markers: explained rises only, at most MARKER_BUDGET
        marked = [ln for ln in fig.axes[0].get_lines() if ln.get_marker() in ("o", "s")]
        n = sum(len(ln.get_xdata()) for ln in marked)
        explained = sum(str(m) != "unexplained" for m in ca.resonances.mechanism)
        assert n == min(explained, MARKER_BUDGET)


def test_order_map_reaches_every_mesh_order_of_the_report(demo_cases):
    ca = demo_cases[0]
    fig = order_map_figure(ca)
    order = 60 * ca.mesh_frequency_per_rpm
    assert fig.axes[0].get_xlim()[1] >= 7 * order  # 179.1: the old map stopped at 145
    assert {f"{k}×" for k in range(1, 8)} <= set(_texts(fig))


def test_spectra_and_stability_labels_do_not_pile_up(demo_cases):
    for ca in demo_cases:
        fig = spectra_figure(ca)
        for ax in fig.axes:
            assert len(ax.texts) <= 6
            assert all(t.get_text().count("≈") <= 1 for t in ax.texts)
        _no_overlap(fig)
        fig = stability_figure(ca)
        assert len(fig.axes[0].texts) == len(ca.floquet_regions())
        _no_overlap(fig)


def test_compared_figures_share_their_scales_and_in_phase_forces_are_named(demo_cases):
    sections = {s.id: s for s in report_sections(demo_cases)}
    figs = [b.figure() for b in sections["tooth-forces"].blocks if b.kind == "figure"]
    assert figs[0].axes[0].get_ylim() == figs[1].axes[0].get_ylim()
    labels = [t.get_text() for t in figs[0].axes[0].get_legend().get_texts()]
    assert labels == ["sun-planet1 = sun-planet2 = sun-planet3 (identical: in phase)"]
    labels2 = [t.get_text() for t in figs[1].axes[0].get_legend().get_texts()]
    assert labels2 == ["sun-planet1", "sun-planet2", "sun-planet3"]  # case 2: offset planets
    spec = [b.figure() for b in sections["spectra"].blocks if b.kind == "figure"]
    assert spec[0].axes[0].get_ylim() == spec[1].axes[0].get_ylim()
    son = [b.figure() for b in sections["sonograms"].blocks if b.kind == "figure"][::2]
    clims = [next(c for c in f.axes[0].collections if hasattr(c, "get_clim")).get_clim()
             for f in son]
    assert clims[0] == clims[1]


# --------------------------------------------------------------------------- time and folders


def test_stability_setting_coarse_off_and_checked(demo_study, tmp_path):
    runs = list(demo_study.runs.values())[:1]
    ca = analyse_case(read_run(runs[0]), settings=AnalysisSettings(stability="coarse"))
    assert ca.chart is not None and ca.chart.mesh_frequencies_hz.size == 80
    # 80 speeds are 49 min^-1 apart: the 5 min^-1 wide region at 839 min^-1 falls between two,
    # the wider ones are found with the full chart's boundaries (to 0.5 min^-1) and labels
    regions = ca.floquet_regions()
    assert [r["label"] for r in regions] == ["2 (f3=f4)/4", "2 (f3=f4)/3"]
    for r, (lo, hi) in zip(regions, ((2084.1, 2122.5), (2773.7, 2837.3)), strict=True):
        assert r["lower_rpm"] == pytest.approx(lo, abs=0.5)
        assert r["upper_rpm"] == pytest.approx(hi, abs=0.5)
    off = analyse_case(read_run(runs[0]), settings=AnalysisSettings(stability="off"))
    assert off.chart is None and any("stability = \"off\"" in n for n in off.notes)
    with pytest.raises(ConfigError, match="stability"):
        AnalysisSettings.from_dict({"stability": "fast"})
    recipe = tmp_path / "r.toml"
    recipe.write_text('[study]\ncases = [{name = "a", config = "paper-case1"}]\n'
                      '[analysis]\nstability = "coarse"\n')
    assert load_study(recipe).analysis.stability == "coarse"


def test_interrupted_report_leaves_no_folder(demo_study, tmp_path, monkeypatch):
    """Ctrl-C while analysing (e.g. in the Floquet chart) or simulating: the output folder,
    created only when a file is written, does not exist afterwards."""
    import gearvib.report.runner as runner

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "analyse_case", interrupt)
    target = tmp_path / "new" / "out"
    with pytest.raises(KeyboardInterrupt):
        build_report(list(demo_study.runs.values()), target)
    assert not (tmp_path / "new").exists()
    monkeypatch.setattr(runner, "simulate", interrupt)
    with pytest.raises(KeyboardInterrupt):
        run_study(Study.for_presets(["paper-case1"], duration=0.15), target, progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_twenty_dof_trapezoidal_report_finishes(tmp_path):
    """The 20-DOF four-planet set with elastic bearings and trapezoidal mesh stiffness (its
    Floquet chart ran 21 minutes at 7 GB without output before): the shipped recipe, 1 s
    run-up, full chart (300 speeds); about 18 s on the 2-core machine (README)."""
    result = run_study(load_study(REPO / "reports" / "four-planet-trapezoidal.toml"),
                       tmp_path / "out", progress=False)
    html = _html(result)
    assert cross_check(html) == []
    t = _tables(html)
    assert "20 (8 meshes, " in dict(t["Gear set and run of four-planet"].rows)[
        "degrees of freedom"]
    fl = t["Unstable speed intervals of four-planet (Floquet)"]
    assert len(fl.rows) >= 5
    prov = dict(t["Provenance of four-planet"].rows)
    assert prov["Floquet chart"].startswith("300 speeds (full)")
    assert np.all([r[5] != "" for r in fl.rows])
