"""Rolling-bearing causes of ``diagnose`` (gearvib.diagnosis.bearings): ranked from their
lines on an independent impulse generator, on the real CWRU records (skipped when absent),
beside the gear faults of a gear set, and never raised by noise or random lines."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from analysis.diagnosis import Cause
from analysis.line_evidence import MAX_CHANCE
from analysis.measurement import load_measurement
from gearvib.diagnosis import Record, diagnose
from gearvib.diagnosis.bearings import (
    BEARING_CAUSES,
    LIKELY_HARMONICS,
    bearing_causes,
    chance_score,
)
from gearvib.diagnosis.verdict import rank_causes
from tests.independent.bearing_signals import bearing_bursts

REPO = Path(__file__).resolve().parents[2]
CWRU = Path("/work/shared/data/cwru")
needs_cwru = pytest.mark.skipif(not (CWRU / "IR007_0.mat").is_file()
                                or not (CWRU / "normal_0.mat").is_file(),
                                reason="CWRU records not available (/work/shared/data/cwru)")
FS = 12000.0
RPM = 1797.0
# published multiples of the shaft speed of the SKF 6205-2RS JEM (CWRU README)
BPFI, BPFO = 5.4152, 3.5848


def _impulses(rate_hz: float, seconds: float, rng: np.random.Generator, *,
              modulation_hz: float = 0.0, resonance_hz: float = 2800.0,
              snr_db: float = -6.0) -> np.ndarray:
    """Bursts at ``rate_hz`` through a 2.8 kHz resonance in noise (:func:`bearing_bursts`)."""
    return bearing_bursts(rate_hz, seconds, rng, fs=FS, resonance_hz=resonance_hz,
                          snr_db=snr_db, modulation_hz=modulation_hz)


def _record(x: np.ndarray, rpm: float = RPM) -> Record:
    return Record(x, FS, np.full(x.size, rpm), name="acc")


def test_chance_score_meets_the_threshold_at_the_detection_limit():
    assert chance_score(MAX_CHANCE, 0.4) == pytest.approx(0.4)
    assert chance_score(1.0, 0.4) == 0.0
    assert chance_score(float("nan"), 0.4) == 0.0
    assert chance_score(0.0, 0.4) == 1.0
    # threshold * log(p) / log(MAX_CHANCE) reaches 1 at p = MAX_CHANCE ** (1 / threshold)
    assert chance_score(MAX_CHANCE ** 2.5, 0.4) == pytest.approx(1.0)
    assert chance_score(1e-3, 0.4) == pytest.approx(0.4 * math.log(1e-3) / math.log(MAX_CHANCE))
    p = np.logspace(-12, 0, 50)
    s = [chance_score(float(v), 0.4) for v in p]
    assert np.all(np.diff(s) <= 0)


def test_a_bearing_cause_keeps_its_own_verdict_in_the_ranking():
    gear = Cause("crack", "sun", 0.42)
    bearing = Cause("inner_race_fault", "drive-end", 0.9, ("BPFI detected",), "", "likely")
    weak = Cause("cage_fault", "drive-end", 0.0, (), "", "unlikely")
    ranked = rank_causes([gear, weak, bearing], 0.4, families={}, mismatch={},
                         local_kinds=("crack",))
    assert [c.cause for c in ranked] == ["inner_race_fault", "crack", "cage_fault"]
    assert [c.verdict for c in ranked] == ["likely", "likely", "unlikely"]
    # a bearing that is unlikely does not make the ranking lead with a cause
    ranked = rank_causes([weak], 0.4, families={}, mismatch={}, local_kinds=())
    assert ranked[0].cause == "none"


@pytest.mark.parametrize(("rate", "cause", "modulation"),
                         [(BPFO, "outer_race_fault", 0.0), (BPFI, "inner_race_fault", 1.0)])
def test_an_independent_bearing_fault_is_ranked_first(rate, cause, modulation):
    f_r = RPM / 60.0
    x = _impulses(rate * f_r, 3.0, np.random.default_rng(5), modulation_hz=modulation * f_r)
    d = diagnose(_record(x), "cwru-drive-end")
    lead = d.causes[0]
    assert (lead.cause, lead.member, lead.verdict) == (cause, "drive-end bearing", "likely")
    assert lead.score >= d.threshold
    assert [c.cause for c in d.likely] == [cause], [c.to_dict() for c in d.causes]
    assert d.line_check is not None and d.signatures == {}
    assert {c.cause for c in d.causes} == {*BEARING_CAUSES.values()}


def test_noise_and_random_lines_raise_no_bearing_cause():
    """White noise, noise modulated at random frequencies and bursts at a random rate away
    from every bearing line: no bearing cause likely (docs/diagnosis.md states the rate
    measured over many more records by benchmarks/bench_bearing_alarms.py)."""
    rng = np.random.default_rng(21)
    f_r = RPM / 60.0
    lines = np.array([BPFI, BPFO, 2.357, 0.39828]) * f_r
    alarms = []
    for i in range(6):
        n = int(2.0 * FS)
        t = np.arange(n) / FS
        if i % 3 == 0:
            x = rng.standard_normal(n)
        elif i % 3 == 1:
            f = rng.uniform(5.0, 600.0, 8)
            x = (1.0 + 0.3 * np.sum(np.cos(2 * np.pi * f[:, None] * t), axis=0)
                 ) * rng.standard_normal(n)
        else:
            while True:
                rate = rng.uniform(8.0, 200.0)
                if np.all(np.abs(rate / lines - 1.0) > 0.05):
                    break
            x = _impulses(rate, 2.0, rng, snr_db=-3.0)
        d = diagnose(_record(x), "cwru-drive-end")
        alarms += [c.cause for c in d.likely]
    assert alarms == []


def test_bearing_causes_follow_the_check():
    f_r = RPM / 60.0
    x = _impulses(BPFO * f_r, 3.0, np.random.default_rng(8))
    d = diagnose(_record(x), "cwru-drive-end")
    fl = d.line_check
    causes = bearing_causes(fl, 0.4)
    for fam, st, c in zip(fl.families, fl.envelope_evidence.status, causes, strict=True):
        assert c.cause == BEARING_CAUSES[fam.kind] and c.member == fam.source
        strong = st == "detected" and fl.envelope_evidence.checks[
            fl.families.index(fam)].harmonics_found >= LIKELY_HARMONICS
        assert (c.verdict == "likely") == strong
        assert (c.score >= 0.4) == strong


def test_a_machine_without_bearings_is_refused(tmp_path):
    (tmp_path / "rig.toml").write_text('name = "bare"\ntype = "shafts"\n[operation]\n'
                                       'input = "motor"\n[[shaft]]\nname = "motor"\n')
    with pytest.raises(Exception, match="rolling_bearing"):
        diagnose(_record(np.random.default_rng(0).standard_normal(6000)),
                 str(tmp_path / "rig.toml"))


@needs_cwru
def test_cwru_inner_race_record_is_diagnosed_as_an_inner_race_fault(tmp_path):
    """The command line as a user runs it on the real records: IR007 -> inner race first and
    likely, its report with the bearing section; normal_0 -> nothing."""
    def run(name: str) -> dict:
        x = "X105" if name.startswith("IR") else "X097"
        out = subprocess.run(
            [sys.executable, "-m", "gearvib", "diagnose", str(CWRU / name), "--gearset",
             "cwru-drive-end", "--fs", "12000", "--rpm-from", f"{x}RPM", "--channel",
             f"{x}_DE_time", "-o",
             str(tmp_path / name), "--json"], capture_output=True, text=True, timeout=300,
            cwd=tmp_path)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout)

    ir = run("IR007_0.mat")
    lead = ir["causes"][0]
    assert (lead["cause"], lead["member"], lead["verdict"]) == (
        "inner_race_fault", "drive-end bearing", "likely")
    assert [c["cause"] for c in ir["causes"] if c["verdict"] == "likely"] == ["inner_race_fault"]
    html = (tmp_path / "IR007_0.mat" / "report.html").read_text()
    assert "Rolling bearings: their lines in the envelope spectrum" in html
    assert "BPFI (drive-end bearing) detected" in html
    normal = run("normal_0.mat")
    assert normal["causes"][0]["cause"] == "none"
    assert not [c for c in normal["causes"] if c["verdict"] in ("likely", "possible")]


@needs_cwru
def test_a_gear_set_ranks_its_declared_bearing_beside_the_gear_faults(tmp_path):
    """paper-case1 with a bearing declared on the sun shaft, diagnosed on the CWRU inner-race
    record (the shaft speed as the sun's): the bearing's inner race leads. Only the healthy
    gear set is simulated (no gear kinds), to keep the test short."""
    toml = (REPO / "gearvib" / "presets" / "paper-case1.toml").read_text()
    toml += ('\n[[rolling_bearing]]\nname = "input bearing"\nmember = "sun"\nn_rolling = 9\n'
             'rolling_diameter = 7.94e-3\npitch_diameter = 39.04e-3\n')
    (tmp_path / "set.toml").write_text(toml)
    m = load_measurement(CWRU / "IR007_0.mat", fs=FS, rpm_from="X105RPM",
                         channel="X105_DE_time")
    rec = Record.from_measurement(m, "X105_DE_time")
    d = diagnose(rec, str(tmp_path / "set.toml"), kinds=(), library=False, workers=1)
    lead = d.causes[0]
    assert (lead.cause, lead.member, lead.verdict) == ("inner_race_fault", "input bearing",
                                                       "likely")
    assert d.line_check is not None
    assert {c.member for c in d.causes if c.cause in BEARING_CAUSES.values()} == {
        "input bearing"}
