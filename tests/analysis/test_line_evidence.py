"""analysis.line_evidence: line families checked with their chance of a coincidence.

Spectra are built in the tests: chi-square noise (a Welch average of 7 segments), lines of
chosen power at chosen positions. The stated chance is compared with the detection rate of
families placed at random in spectra with many random lines (the chance is a false-alarm
probability, so the two must agree), and the claims of a detected family with the lattice of
an inner-race fault (``h f_1 + k f_r``) that other families' windows catch.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.line_evidence import (
    LineEvidence,
    family_chance,
    line_evidence,
    prominent_lines,
    strength,
)
from analysis.lines import LineFamily, check_lines

SPACING = 0.25
AXIS = np.arange(0.0, 1000.0, SPACING)


def noise(rng: np.random.Generator) -> np.ndarray:
    """Welch-like power: chi-square with 14 degrees of freedom, mean 1."""
    return rng.chisquare(14, AXIS.size) / 14.0


def add_line(power: np.ndarray, f: float, db: float) -> None:
    power[round(f / SPACING)] += 10.0 ** (db / 10.0)


def test_prominent_lines_and_their_prominence():
    rng = np.random.default_rng(0)
    pw = noise(rng)
    for f, db in ((100.0, 20.0), (250.0, 12.0), (600.0, 30.0)):
        add_line(pw, f, db)
    pos, prom = prominent_lines(AXIS, pw, threshold_db=10.0)
    np.testing.assert_allclose(pos, [100.0, 250.0, 600.0])
    np.testing.assert_allclose(prom, [20.0, 12.0, 30.0], atol=1.0)  # over a median ~0.95
    with pytest.raises(ValueError, match="floor_lines = 0 is not admissible"):
        prominent_lines(AXIS, pw, floor_lines=0)


def test_a_family_in_noise_is_detected_with_a_small_chance():
    rng = np.random.default_rng(1)
    pw = noise(rng)
    for h in (1, 2, 3):
        add_line(pw, h * 87.25, 20.0 - 3 * h)
    fam = LineFamily("BPFX", 87.0, 3)  # nominal 0.3 % low: found within the tolerance
    ev = line_evidence(AXIS, pw, [fam, LineFamily("other", 131.3, 3)])
    assert list(ev.status) == ["detected", "not detected"]
    assert ev.checks[0].harmonics_found == 3 and ev.chance[0] < 1e-3
    assert strength(ev.checks[0]) == pytest.approx(14.0, abs=1.5)  # the 2nd harmonic's
    ds = ev.to_dataset()
    assert ds["status"].values.tolist() == ["detected", "not detected"]
    assert ds["fundamental"].attrs["units"] == "Hz" and ds.attrs["Conventions"] == "CF-1.11"
    fig = ev.plot()
    assert fig.axes[0].get_legend() is not None
    assert "BPFX: detected (3/3" in fig.axes[0].get_legend().get_texts()[0].get_text()


def test_a_family_alone_in_its_spectrum_has_a_small_but_not_zero_chance():
    """Noise and only the family's own lines: no background line as strong as the family, so
    the chance rests on the floor of half a line over the spectrum (``half / span`` per
    window), computed here from the check's own windows: small, but never exactly 0."""
    rng = np.random.default_rng(3)
    pw = noise(rng)
    for h in (1, 2, 3):
        add_line(pw, h * 87.25, 25.0)
    c = check_lines(AXIS, pw, LineFamily("BPFX", 87.0, 3))
    pos, prom = prominent_lines(AXIS, pw, threshold_db=c.threshold_db)
    assert c.detected and set(np.round(pos[prom >= strength(c)], 2)) <= {87.25, 174.5, 261.75}
    chance = family_chance(AXIS, c, pos, prom)
    span = AXIS[-1] - AXIS[1]
    q1 = (c.tolerance * 87.0 + SPACING) / span
    q2, q3 = ((0.5 * h + 1.0) * SPACING / span for h in (2, 3))
    assert chance == pytest.approx(q1 * (1.0 - (1.0 - q2) * (1.0 - q3)), rel=1e-9)
    assert 0.0 < chance < 1e-4
    ev = line_evidence(AXIS, pw, LineFamily("BPFX", 87.0, 3))
    assert ev.status[0] == "detected" and ev.chance[0] == pytest.approx(chance)


def test_the_chance_is_the_detection_rate_of_families_placed_at_random():
    """Spectra with about one random line per 5 Hz (10 to 30 dB): the mean stated chance of
    families at random positions equals the rate at which they are detected."""
    rng = np.random.default_rng(2)
    detected, chance = [], []
    for _ in range(40):
        pw = noise(rng)
        for f in rng.uniform(5.0, 999.0, 200):
            add_line(pw, f, rng.uniform(10.0, 30.0))
        lines, _ = prominent_lines(AXIS, pw)
        for f1 in rng.uniform(40.0, 150.0, 20):
            c = check_lines(AXIS, pw, LineFamily("x", f1, 3))
            detected.append(c.detected)
            chance.append(family_chance(AXIS, c, lines))  # at the threshold
    rate, stated = float(np.mean(detected)), float(np.mean(chance))
    assert 0.05 < rate < 0.3  # a dense spectrum: a random family is often "detected"
    assert stated == pytest.approx(rate, rel=0.3)


def test_a_family_caught_by_random_lines_is_only_possible():
    rng = np.random.default_rng(3)
    pw = noise(rng)
    for f in np.arange(3.0, 1000.0, 2.1):  # a line every 2.1 Hz (beats of many tones)
        add_line(pw, f + rng.uniform(-0.3, 0.3), 15.0)
    fams = [LineFamily(f"r{i}", f1, 3) for i, f1 in enumerate(rng.uniform(40, 150, 60))]
    ev = line_evidence(AXIS, pw, fams)
    st = ev.status
    # the check alone finds most of them; the chance says they are no evidence: at most a
    # few in a hundred reported detected (the chance is a p-value, max_chance = 1 %)
    assert np.sum([c.detected for c in ev.checks]) > 30
    assert np.sum(st == "possible") > 25 and np.sum(st == "detected") <= 2
    assert np.all(ev.chance[st == "possible"] > ev.max_chance)


def test_lines_of_a_stronger_family_explain_a_weaker_one():
    """An inner-race fault: BPFI 162 Hz with its shaft-modulation lattice h BPFI + k f_r
    (f_r = 29.95 Hz); a BSF family whose windows hold lattice points (BPFI - 3 f_r = 72.3,
    2 BPFI - 6 f_r = 144.7) is explained by BPFI, and a family on shaft harmonics by the
    shaft."""
    rng = np.random.default_rng(4)
    pw = noise(rng)
    fr, bpfi = 29.95, 162.2
    for h in (1, 2, 3):
        add_line(pw, h * bpfi, 36.0 - 2 * h)
        for k in range(-6, 7):
            if k and 0 < h * bpfi + k * fr < 1000:
                add_line(pw, abs(h * bpfi + k * fr), 20.0 - abs(k))
    for k in range(1, 30):
        add_line(pw, k * fr, 15.0)
    fams = [LineFamily("BPFI", bpfi, 3, fr, 1), LineFamily("BSF", 71.6, 3),
            LineFamily("X", 2 * fr * 1.003, 3)]
    shaft = LineFamily("shaft", fr, harmonics=33)
    ev = line_evidence(AXIS, pw, fams, known=[shaft])
    assert list(ev.status) == ["detected", "explained", "explained"]
    assert ev.explained_by == ("", "BPFI", "shaft")
    assert ev.checks[1].detected  # the check alone would have called it
    assert "explained by BPFI" in ev.rows()[1][2]
    # without the knowledge of the shaft, its harmonics look like a family of their own
    alone = line_evidence(AXIS, pw, fams[2:])
    assert alone.status[0] == "detected"


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"families": []}, ValueError, "families must be LineFamily objects"),
    ({"families": ["BPFI"]}, ValueError, "families must be LineFamily objects"),
    ({"max_chance": 0.0}, ValueError, r"max_chance = 0.0 is not admissible: 0 < p <= 1"),
    ({"max_chance": True}, TypeError, "max_chance = True is not admissible"),
    ({"known": [3.0]}, ValueError, "known must be LineFamily objects"),
    ({"local_width": 1.5}, ValueError, "local_width = 1.5 is not admissible"),
])
def test_bad_arguments_are_named(kwargs, error, match):
    pw = noise(np.random.default_rng(5))
    args = {"families": [LineFamily("x", 100.0, 3)], **kwargs}
    with pytest.raises(error, match=match):
        line_evidence(AXIS, pw, **args)


def test_a_family_beyond_the_spectrum_is_outside():
    pw = noise(np.random.default_rng(6))
    ev = line_evidence(AXIS[:400], pw[:400], [LineFamily("high", 150.0, 3)])
    assert isinstance(ev, LineEvidence) and list(ev.status) == ["outside"]
    assert np.isnan(ev.chance[0]) and ev.rows()[0][-1] == "–"
