"""Tests of gearvib.report: study recipes, end-to-end study of the paper's cases, report content.

One shortened study of both paper cases (the demo, 0 -> 4000 min-1 in 0.25 s; fixture
``demo_study`` in conftest.py) is run once per session and shared by the content tests.
"""

from __future__ import annotations

import base64
import io
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from gearvib.config import ConfigError
from gearvib.io import GearvibFileError, read_run
from gearvib.report import (
    SECTION_IDS,
    AnalysisSettings,
    Study,
    build_report,
    load_study,
    run_study,
)
from gearvib.report.case import analyse_case
from gearvib.report.case_stiffness import summed_sun_stiffness
from gearvib.report.wording import count

REPO = Path(__file__).resolve().parents[2]
QUICK = AnalysisSettings(stability_points=120, map_resolution_hz=40.0)


@pytest.fixture(scope="module")
def study_run(demo_study):
    return demo_study


@pytest.fixture(scope="module")
def html_text(study_run):
    return study_run.report.html.read_text(encoding="utf-8")


def _section(html: str, sid: str) -> str:
    m = re.search(rf'<section id="{sid}">(.*?)</section>', html, flags=re.S)
    assert m, f"section {sid} missing"
    return m.group(1)


# --------------------------------------------------------------------------- recipes


def test_load_study_resolves_relative_paths_and_defaults(tmp_path):
    gs = tmp_path / "sets" / "mine.toml"
    gs.parent.mkdir()
    gs.write_text((REPO / "gearvib" / "presets" / "paper-case2.toml").read_text())
    recipe = tmp_path / "s.toml"
    recipe.write_text('[study]\ntitle = "T"\ncases = [{name = "a", config = "paper-case1"}, '
                      '{name = "b", config = "sets/mine.toml"}]\n[run]\nduration = 0.5\n')
    st = load_study(recipe)
    assert st.title == "T" and st.reference_case == "a"
    assert Path(st.cases[1].config) == gs
    assert st.run.duration == 0.5 and st.run.speed_end_rpm is None
    assert st.analysis == AnalysisSettings()


@pytest.mark.parametrize(("text", "needle"), [
    ('[study]\ncases = [{name = "a", config = "paper-case1"}]\n[run]\nspeed_max = 1.0\n',
     "'speed_max'"),
    ('[study]\ncases = [{name = "a", config = "paper-case1", colour = 1}]\n', "'colour'"),
    ('[study]\ncases = [{name = "a", config = "paper-case1"}]\n[analysis]\nnmax = 3\n',
     "'nmax'"),
    ('[studdy]\ncases = []\n', "'studdy'"),
    ('[study]\ncases = [{name = "a", config = "no-such-preset"}]\n', "no-such-preset"),
    ('[study]\ncases = [{name = "a", config = "paper-case1"}, {name = "a", config = '
     '"paper-case2"}]\n', "used twice"),
])
def test_load_study_rejects_bad_recipes_naming_the_key(tmp_path, text, needle):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(ConfigError, match=re.escape(needle)):
        load_study(p)


def test_shipped_recipes_load(tmp_path, capsys):
    """Every example prints, and loads from an unrelated folder (presets only, no paths)."""
    from gearvib.cli import main
    from gearvib.config import list_examples
    from gearvib.sweep import load_sweep

    assert {"paper-cases", "paper-case1-elastic", "paper-cases-study",
            "sweep-damping-phasing"} <= set(list_examples())
    for name in list_examples():
        assert main(["example", name]) == 0
        f = tmp_path / f"{name}.toml"
        f.write_text(capsys.readouterr().out)
        if name.startswith("sweep"):
            assert len(load_sweep(f).cases()) == 6
        else:
            st = load_study(f)
            # 1 s run-ups, set by the recipe or (None) by the presets' [simulation]
            assert len(st.cases) == 2 and st.run.duration in (1.0, None), name
    assert main(["example"]) == 0 and "paper-cases" in capsys.readouterr().out


def test_summed_sun_stiffness_matches_paper_figures_9_and_10():
    from gearvib.assembly import assemble
    from gearvib.config import load_gearset

    s1 = summed_sun_stiffness(assemble(load_gearset("paper-case1")))
    s2 = summed_sun_stiffness(assemble(load_gearset("paper-case2")))
    assert s1.minimum == pytest.approx(0.8e8, rel=1e-3)
    assert s1.maximum == pytest.approx(1.3e8, rel=1e-3)
    assert s2.peak_to_peak < 0.75 * s1.peak_to_peak


# --------------------------------------------------------------------------- end to end


def test_study_writes_runs_with_full_configuration(study_run):
    assert set(study_run.runs) == {"paper-case1", "paper-case2"}
    ds = read_run(study_run.runs["paper-case1"])
    cfg = json.loads(ds.attrs["config_json"])["model"]
    assert cfg["case"] == "paper-case1"
    assert cfg["gearset"]["geometry"]["z_sun"] == 33
    assert cfg["run"]["duration"] == 0.25 and cfg["run"]["speed_end_rpm"] == 4000.0
    assert float(ds["input_speed"][-1]) == pytest.approx(4000.0)
    leftovers = [p.name for p in study_run.out_dir.iterdir() if p.name.startswith(".")]
    assert leftovers == []


def test_html_has_every_section_in_order(study_run, html_text):
    ids = re.findall(r'<section id="([a-z-]+)">', html_text)
    assert ids == list(SECTION_IDS)
    assert study_run.report.sections == SECTION_IDS
    assert "<script" not in html_text.lower()
    assert not re.search(r'(src|href)="(https?:|//)', html_text)  # self-contained


def test_embedded_images_decode(html_text):
    from PIL import Image

    images = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html_text)
    # forces 2, spectra 2, stiffness 1, sonograms 2, order maps 2, stability 2
    assert len(images) >= 11
    for data in images:
        im = Image.open(io.BytesIO(base64.b64decode(data)))
        im.load()
        assert im.format == "PNG"
        assert 300 <= im.width <= 2000 and 200 <= im.height <= 2000
        assert len(im.convert("RGB").getcolors(maxcolors=1 << 16) or range(1 << 16)) > 10


def test_pdf_has_pages_and_no_dates(study_run):
    data = study_run.report.pdf.read_bytes()
    assert data.startswith(b"%PDF-")
    pages = len(re.findall(rb"/Type\s*/Page(?!s)", data))
    assert 6 <= pages == study_run.report.pdf_pages <= 24  # 21 with the NVH pages
    assert b"/CreationDate" not in data and b"/ModDate" not in data


def test_report_states_mesh_frequency_at_1500_rpm(html_text):
    sono = _section(html_text, "sonograms")
    m = re.search(r"at 1500 min⁻¹ f_mesh = (\d+) Hz", sono)
    assert m and int(m.group(1)) == 640  # paper: "1500 rpm (meshing frequency ≈ 640 Hz)"
    assert "f2/2" in sono  # 640 Hz ≈ f2/2 ≈ 630 Hz, as in the paper


def test_report_lists_identified_regions(study_run, html_text):
    res = _section(html_text, "resonances")
    assert "Resonance regions of paper-case1" in res
    table = res.split("Resonance regions of paper-case1")[1].split("</table>")[0]
    rows = re.findall(r"<tr><td>(\d+)(?:–(\d+))?</td>", table)  # one speed: written once
    assert rows, "no resonance region listed for paper-case1"
    for lo, hi in rows:
        assert 0 <= int(lo) < int(hi or 1e9) and int(hi or lo) <= 4000
    stab = _section(html_text, "stability")
    assert "Unstable speed intervals of paper-case1" in stab
    assert "parametric instability" in stab
    # first-order widths beside the Floquet intervals: the planet-pair principal regions agree
    first = stab.split("First-order perturbation regions of paper-case1")[1].split("</table>")[0]
    fo = {lab: (int(a), int(b)) for lab, a, b in
          re.findall(r"<tr><td>([^<]+)</td><td>(\d+)</td><td>(\d+)</td>", first)}
    lo, hi = fo["2 (f3=f4)/3"]
    assert 2700 < lo < 2810 < hi < 2900  # Floquet: 2773-2835 min-1


def test_comparison_reports_fewer_weaker_or_explains(study_run, html_text):
    (cmp,) = study_run.report.comparisons
    assert (cmp.reference, cmp.other) == ("paper-case1", "paper-case2")
    assert cmp.stiffness_p2p[1] < cmp.stiffness_p2p[0]
    text = _section(html_text, "comparison")
    if cmp.fewer_or_weaker:
        assert "reproduces the paper" in text
    else:
        assert "does not reproduce" in text
        assert "Regions that got stronger or appeared" in text
        assert "one speed range only" in text
    assert count(cmp.n_regions[1], "resonance region") in text


def test_rebuild_from_netcdf_is_byte_identical(study_run, tmp_path):
    paths = [study_run.runs["paper-case1"], study_run.runs["paper-case2"]]
    again = build_report(paths, tmp_path / "again")  # settings and title from the runs
    assert again.html.read_bytes() == study_run.report.html.read_bytes()
    assert again.pdf.read_bytes() == study_run.report.pdf.read_bytes()


def test_report_without_stored_gearset_falls_back_to_dataset(study_run, tmp_path):
    ds = read_run(study_run.runs["paper-case1"])
    ds.attrs["config_json"] = "{}"
    ca = analyse_case(ds, name="bare", settings=QUICK)
    assert ca.model is None and ca.chart is None
    assert ca.mesh_frequency_per_rpm == pytest.approx(0.4265306, rel=1e-4)
    assert ca.stiffness and {st.source for st in ca.stiffness} == {"simulation"}
    assert [st.central for st in ca.stiffness] == ["sun", "ring"]
    assert any("gear-set description" in n for n in ca.notes)
    paths = build_report([ds], tmp_path / "bare")
    assert "comparison" not in paths.sections
    assert "not carry its gear-set description" in paths.html.read_text(encoding="utf-8")


# --------------------------------------------------------------------------- errors


def test_unusable_output_folder_fails_before_any_work(tmp_path, monkeypatch):
    import gearvib.report.runner as runner

    def boom(*args, **kwargs):
        raise AssertionError("simulate must not be called")

    monkeypatch.setattr(runner, "simulate", boom)
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    study = Study.for_presets(["paper-case1"], duration=0.1)
    with pytest.raises(ValueError, match=r"not a directory|is a file"):
        run_study(study, blocker, progress=False)
    with pytest.raises(ValueError, match="is a file"):
        run_study(study, blocker / "sub", progress=False)

    def no_write(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(runner.tempfile, "mkstemp", no_write)
    target = tmp_path / "new" / "out"
    with pytest.raises(PermissionError, match="not writable"):
        run_study(study, target, progress=False)
    assert not (tmp_path / "new").exists()  # nothing left behind
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


def test_unreadable_netcdf_gives_clear_error(tmp_path):
    bad = tmp_path / "broken.nc"
    bad.write_bytes(b"this is not netCDF")
    out = tmp_path / "out"
    with pytest.raises(GearvibFileError, match=r"broken\.nc"):
        build_report([bad], out)
    with pytest.raises(GearvibFileError, match="not found"):
        build_report([tmp_path / "missing.nc"], out)
    assert not out.exists()


# --------------------------------------------------------------------------- browser


def test_html_renders_in_headless_chromium(study_run, tmp_path):
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.skip("chromium not on PATH (CI installs it: .ci/run does apt-get install "
                    "chromium)")
    from PIL import Image

    shot = tmp_path / "shot.png"
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu",
           "--disable-background-networking", "--disable-component-update", "--no-first-run",
           "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}", "--enable-logging=stderr",
           "--v=0", "--hide-scrollbars", "--window-size=1100,9000", "--virtual-time-budget=5000",
           f"--screenshot={shot}", study_run.report.html.as_uri()]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    console = [ln for ln in proc.stderr.splitlines() if "CONSOLE" in ln]
    assert not [ln for ln in console if "error" in ln.lower()], console
    assert "ERR_" not in "\n".join(ln for ln in proc.stderr.splitlines() if "net::" in ln)
    im = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert im.shape[0] >= 9000 * 0.9
    rows = im.std(axis=(1, 2))
    assert (rows > 1).mean() > 0.3  # not blank: text, tables and plots down the page
    # the images are drawn: colour-map pixels (viridis greens/blues) are present
    r, g, b = im[..., 0], im[..., 1], im[..., 2]
    assert ((g > r + 40) & (b > r + 20)).sum() > 5000
