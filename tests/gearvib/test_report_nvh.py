"""Issue #29: the NVH pages (order cuts, overall level, waterfall, Campbell), the summary
(first) page, readable provenance, the consistency cross-check and ``gearvib report --orders
--order-resolution``.

One short run of paper-case1 with a housing accelerometer (300 -> 3600 min-1 in 0.4 s, no
Floquet chart) and one at constant speed; the cross-check itself is tested on hand-made
reports (fast).
"""

from __future__ import annotations

import re

import pytest

from gearvib.cli import main
from gearvib.report import SECTION_IDS, Study, run_study
from gearvib.report.blocks import Block, Section
from gearvib.report.crosscheck import cross_check, parse_report
from gearvib.report.document import FigureImages
from gearvib.report.html import render_html
from gearvib.report.study import AnalysisSettings
from gearvib.report.verdict import readable, settings_rows
from gearvib.report.wording import span

SENSOR = '''
[[sensor]]
name = "top"
angle_deg = 90.0
housing_modes = [{ frequency_hz = 3000.0, damping_ratio = 0.02, gain = 1.0 }]
'''


def _html(sections: list[Section]) -> str:
    return render_html(sections, title="t", subtitle="s", images=FigureImages())


# --------------------------------------------------------------------------- fast: wording


def test_span_writes_equal_ends_once():
    assert span(1500.0, 1500.2, "min⁻¹") == "1500.0–1500.2 min⁻¹"
    assert span(1500.0, 1500.0001, "min⁻¹") == "1500 min⁻¹"
    assert span(300.0, 3600.0) == "300–3600"


def test_settings_are_readable_rows_not_json():
    st = AnalysisSettings(cut_orders=(1.0, 24.0), order_resolution=0.5)
    rows = dict(settings_rows(st, prefix=""))
    assert rows["order cuts"].startswith("1×–3× mesh and 1, 24")
    assert rows["order-cut resolution"] == "0.5 orders"
    assert not any("{" in v or '"' in v for v in rows.values())
    assert readable('{"a_b": 1.0, "c": [1, 2]}') == "a b = 1; c = 1, 2"


def test_with_cuts_checks_the_range():
    st = AnalysisSettings()
    assert st.with_cuts([1, 24], 0.25).cut_orders == (1.0, 24.0)
    assert st.with_cuts(None, None) is st
    for orders, res in (([0.0], None), ([True], None), (["1"], None), ([1.0] * 21, None),
                        (None, 0.001), (None, 11.0), (None, float("nan"))):
        with pytest.raises(ValueError, match="--order"):
            st.with_cuts(orders, res)


# --------------------------------------------------------------------------- fast: check


def _rises(chance: str) -> Block:
    return Block("table", "Rises of c1 (tooth force)", ("speed", "mechanism: cause", "chance"),
                 (("1676", "forced: 3 f_mesh = f5", chance), ("1200", "unexplained", "–")))


def test_cross_check_finds_a_collapsed_range_and_a_wrong_chance():
    ok = [Section("resonances", "R", (
        Block("text", "c1: 2 rises: 1 forced resonance, 0 parametric instabilities, 1 "
                      "unexplained (50 %); a random rise would get such an explanation with a "
                      "chance of 28 % (the explained rise)"), _rises("28 %")))]
    assert cross_check(_html(ok)) == []
    bad = [Section("resonances", "R", (
        Block("text", "c1: 2 rises: 1 forced resonance, 0 parametric instabilities, 1 "
                      "unexplained (50 %); a random rise would get its explanation with a "
                      "chance of 0 % on average"), _rises("28 %"),
        Block("text", "the speed varies only between 1500 and 1500 min⁻¹")))]
    found = cross_check(_html(bad))
    assert any("chance of 0 %" in p or "28" in p for p in found), found
    assert any("equal ends" in p for p in found), found


def test_cross_check_finds_two_likely_causes_and_a_summary_disagreement():
    cut = Block("table", "Resonances of the order cuts of c1, acc",
                ("rank", "cut", "order", "speed [min⁻¹]", "frequency [Hz]", "level [dB re 1]",
                 "rise [dB]", "-3 dB span [min⁻¹]", "natural frequency crossed"),
                (("1", "2× mesh", "51.18", "2498", "2131", "52.3", "11.5", "449", "f5 (2201 Hz)"),))
    strongest = Block("table", "Strongest resonances of c1, acc (rank 1 is the one to inspect "
                      "first)", ("rank", "cut", "order", "speed [min⁻¹]", "frequency [Hz]",
                                 "level [dB re 1]", "rise [dB]", "natural frequency crossed",
                                 "explanation"),
                      (("1", "2× mesh", "51.18", "2498", "2131", "52.3", "11.5", "f5 (2201 Hz)",
                        "–"),))
    ok = [Section("summary", "S", (strongest,)), Section("order-cuts", "O", (cut,))]
    assert cross_check(_html(ok)) == []
    moved = Block("table", strongest.text, strongest.header,
                  (("1", "2× mesh", "51.18", "2600", "2131", "52.3", "11.5", "f5 (2201 Hz)",
                    "–"),))
    found = cross_check(_html([Section("summary", "S", (moved,)),
                               Section("order-cuts", "O", (cut,))]))
    assert any("rank 1 reads" in p for p in found), found
    two = [Section("summary", "S", (Block("text", "Likely cause: f5. Also likely: f2."),))]
    assert any("likely" in p for p in cross_check(_html(two)))


# --------------------------------------------------------------------------- CLI options


@pytest.mark.parametrize(("args", "needle"), [
    (["--orders", "1,,2"], "not a list of orders"),
    (["--orders", "0,2"], "admissible: > 0 and <= 10000"),
    (["--orders", "x"], "not a number"),
    (["--orders", ",".join(["1"] * 21)], "at most 20"),
    (["--order-resolution", "0.001"], "0 for automatic, or 0.01..10"),
    (["--order-resolution", "inf"], "finite"),
])
def test_cli_order_options_are_range_checked(args, needle, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["report", str(tmp_path / "x.nc"), "-o", str(tmp_path / "o"), *args])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and needle in err and len(err.strip().splitlines()) == 1, err


# --------------------------------------------------------------------------- a sensor run


@pytest.fixture(scope="module")
def sensor_study(tmp_path_factory):
    d = tmp_path_factory.mktemp("nvh")
    from gearvib.config import preset_text

    (d / "case1.toml").write_text(preset_text("paper-case1") + SENSOR, encoding="utf-8")
    (d / "study.toml").write_text(
        '[study]\ntitle = "NVH"\ncases = [{name = "c1", config = "case1.toml"}]\n'
        "[run]\nspeed_start_rpm = 300.0\nspeed_end_rpm = 3600.0\nduration = 0.4\n"
        '[analysis]\nstability = "off"\nmap_resolution_hz = 40.0\n', encoding="utf-8")
    out = d / "out"
    code = main(["report", str(d / "study.toml"), "-o", str(out), "-q", "--orders", "1,24"])
    assert code == 0
    return out


def test_sensor_report_has_the_nvh_pages_first_and_is_consistent(sensor_study):
    html = (sensor_study / "report.html").read_text(encoding="utf-8")
    ids = re.findall(r'<section id="([a-z-]+)">', html)
    assert ids[:2] == ["summary", "order-cuts"] and ids == [i for i in SECTION_IDS
                                                           if i != "comparison"]
    assert cross_check(html) == []
    tables, paragraphs = parse_report(html)
    caps = [t.caption for t in tables]
    for signal in ("housing acceleration top", "tooth force sun-planet1"):
        assert f"Order-cut levels of c1, {signal}" in caps
    cut = next(t for t in tables if t.caption == "Order-cut levels of c1, housing acceleration "
               "top")
    names = cut.column("name")
    for n in ("1× mesh", "2× mesh", "3× mesh", "order 24"):
        assert any(n in x for x in names), (n, names)
    assert any(h.startswith("max level [dB re 1 m s-2]") for h in cut.header)
    # the summary ranks the housing acceleration (the sensor), and names one likely cause
    summary = [t for s, t in paragraphs if s == "summary"]
    assert any(t.startswith("c1: strongest resonance of the housing acceleration top") for t
               in summary)
    assert sum(len(re.findall(r"\blikely\b", t, flags=re.I)) for t in summary) == 1
    # readable provenance: no JSON object in any table cell
    assert not any(re.search(r'\{"\w+":', c) for t in tables for r in t.rows for c in r)
    for word in ("order cut", "overall level", "waterfall", "Campbell"):
        assert word.lower() in html.lower()
    assert "1500 and 1500" not in html and not re.search(r"\b(\d+)–\1 min⁻¹", html)


def test_sensor_report_pdf_opens_with_the_summary(sensor_study):
    from pdfminer.high_level import extract_text

    first = extract_text(sensor_study / "report.pdf", page_numbers=[0])
    assert "Summary: key numbers" in first and "strongest resonance" in first


def test_too_fine_order_resolution_is_refused_before_simulating(sensor_study, tmp_path,
                                                                 capsys):
    study = sensor_study.parent / "study.toml"
    code = main(["report", str(study), "-o", str(tmp_path / "o"), "--order-resolution", "0.05"])
    err = capsys.readouterr().err
    assert code == 2 and "admissible >=" in err and "--order-resolution" in err
    assert not (tmp_path / "o").exists()


def test_constant_speed_run_says_there_is_no_run_up(tmp_path):
    """1500 -> 1600 min-1 (less than x 1.3): levels over time, the summary says why."""
    study = Study.for_presets(["paper-case1"], analysis=AnalysisSettings(
        stability="off", map_resolution_hz=40.0), speed_start_rpm=1500.0,
        speed_end_rpm=1600.0, duration=0.3)
    res = run_study(study, tmp_path, progress=False)
    html = res.report.html.read_text(encoding="utf-8")
    assert cross_check(html) == []
    assert "no run-up" in html and "single point" in html
    assert not re.search(r"\b(\d+)–\1 min⁻¹", html)
    _, paragraphs = parse_report(html)
    assert any(s == "summary" and "no run-up" in t for s, t in paragraphs)
