"""The verdict of a diagnosis (gearvib.diagnosis.verdict): likely / possible / unlikely from
all the evidence, ``none`` only when nothing stands, the local-tooth-fault fallback when the
kind cannot be told (fast tests on hand-made causes; the diagnoses are in test_diagnosis*.py).
"""

import numpy as np
import pytest

from analysis.diagnosis import Cause, FamilyEvidence, family_evidence, family_lines
from analysis.diagnosis_impacts import IMPACT_CHANCE, MIN_RELATIVE_DB, ImpactEvidence
from gearvib.diagnosis.verdict import (
    FAMILY_CHANCE,
    FAMILY_HITS,
    KIND_MAX_MISMATCH_DB,
    LOCAL_FAULT,
    SUPPORT_CHANCE,
    SUPPORTED_MARGIN,
    rank_causes,
)

LOCAL = ("crack", "pitting", "broken_tooth")
T = 0.4


def _rank(causes, families=None, mismatch=None):
    return rank_causes(causes, T, families=families or {}, mismatch=mismatch or {},
                       local_kinds=LOCAL, none_evidence=("12 rising peaks",))


def _fam(hits, rising, chance, name="planet_fault"):
    return FamilyEvidence(name, 2.85, rising, hits, 0.05, chance)


def test_a_cause_just_under_the_threshold_is_possible_not_none():
    """Issue 30: a cause at 0.398 under the threshold 0.4 became {"cause": "none",
    "score": 0.6} first; it is 'possible' and leads."""
    out = _rank([Cause("eccentricity", "sun", 0.398, ("e",), "ecc sun"),
                 Cause("pin_error", "planet", 0.1, (), "pin")])
    assert [(c.cause, c.verdict) for c in out] == [("eccentricity", "possible"),
                                                    ("pin_error", "unlikely")]
    assert "near the threshold" in out[0].evidence[-1]
    assert all(c.cause != "none" for c in out)
    js = out[0].to_dict()
    assert js["verdict"] == "possible" and list(js) == ["cause", "member", "score", "verdict",
                                                        "evidence"]


def test_a_family_carrying_the_rises_makes_its_causes_possible():
    """Issue 30: 'planet_fault (order 2.85): 45 of 207 rising peaks on its lines (coincidence
    chance 7.9e-31)' with a poor score must not end as none."""
    fam = _fam(45, 207, 7.9e-31)
    causes = [Cause("crack", "planet", 0.12, (), "crack planet"),
              Cause("pitting", "planet", 0.05, (), "pitting planet"),
              Cause("crack", "sun", 0.25, (), "crack sun")]
    out = _rank(causes, {("crack", "planet"): fam, ("pitting", "planet"): fam},
                {("crack", "planet"): 3.0, ("pitting", "planet"): 5.0})
    assert out[0].cause != "none" and out[0].member == "planet"
    assert out[0].verdict == "possible" and "45 of 207" in out[0].evidence[-1]
    # the possible causes before the better-scoring unlikely one
    assert [c.verdict for c in out].index("unlikely") == 2
    assert out[-1].cause == "crack" and out[-1].member == "sun"


@pytest.mark.parametrize(("hits", "chance"), [(FAMILY_HITS - 1, 1e-40),
                                              (45, FAMILY_CHANCE * 10)])
def test_weak_family_evidence_leaves_none_first(hits, chance):
    causes = [Cause("crack", "planet", 0.2, (), "crack planet"),
              Cause("crack", "sun", 0.1, (), "crack sun")]
    out = _rank(causes, {("crack", "planet"): _fam(hits, 207, chance)})
    assert out[0].cause == "none" and out[0].score == pytest.approx(0.8)
    assert out[0].verdict == "" and "12 rising peaks" in out[0].evidence
    assert [c.verdict for c in out[1:]] == ["unlikely", "unlikely"]


def test_a_score_near_the_threshold_with_its_family_behind_it_is_possible():
    s = T - SUPPORTED_MARGIN + 0.01
    causes = [Cause("crack", "ring", s, (), "crack ring"), Cause("crack", "sun", 0.1, (), "s")]
    out = _rank(causes, {("crack", "ring"): _fam(21, 515, SUPPORT_CHANCE / 2, "ring_fault")})
    assert (out[0].cause, out[0].member, out[0].verdict) == ("crack", "ring", "possible")
    assert "21 of 515" in out[0].evidence[-1]
    # the same score without its family behind it: nothing stands out
    out = _rank(causes, {("crack", "ring"): _fam(21, 515, SUPPORT_CHANCE * 2, "ring_fault")})
    assert out[0].cause == "none"


def _impact(chance, relative_db=-3.0, method="envelope", family="ring_fault"):
    return ImpactEvidence(family, 4.0, method, 10, 6, 40.0, chance, relative_db)


def test_detected_tooth_impacts_make_the_members_local_faults_possible():
    """The 4-planet ring fault of the independent benchmark: no simulated signature explains
    the record (scores 0.00-0.01), but its impacts stand above the mesh band: the ring's local
    faults are possible and lead, the other causes stay unlikely."""
    imp = _impact(1.4e-6, float("nan"), "synchronous")
    causes = [Cause("pitting", "ring", 0.006, (), "p ring"),
              Cause("crack", "ring", 0.0, (), "c ring"),
              Cause("pin_error", "planet", 0.16, (), "pin"),
              Cause("eccentricity", "sun", 0.1, (), "ecc")]
    impacts = {("pitting", "ring"): imp, ("crack", "ring"): imp}
    out = rank_causes(causes, T, families={}, mismatch={}, local_kinds=LOCAL, impacts=impacts)
    assert out[0].member == "ring" and out[0].verdict == "possible"
    assert out[0].cause in (*LOCAL, LOCAL_FAULT)
    assert "tooth impacts" in " ".join(out[0].evidence)
    assert {(c.cause, c.verdict) for c in out if c.member != "ring"} == {
        ("pin_error", "unlikely"), ("eccentricity", "unlikely")}
    # impacts only count for local tooth faults: an eccentricity keeps its verdict
    out = rank_causes(causes, T, families={}, mismatch={}, local_kinds=LOCAL,
                      impacts={("eccentricity", "sun"): imp})
    assert out[0].cause == "none"


@pytest.mark.parametrize(("chance", "relative_db"), [(IMPACT_CHANCE * 3, 0.0),
                                                     (1e-12, MIN_RELATIVE_DB - 1.0)])
def test_impacts_not_detected_leave_none_first(chance, relative_db):
    imp = _impact(chance, relative_db)
    assert not imp.detected
    causes = [Cause("crack", "ring", 0.05, (), "c"), Cause("crack", "sun", 0.1, (), "s")]
    out = rank_causes(causes, T, families={}, mismatch={}, local_kinds=LOCAL,
                      impacts={("crack", "ring"): imp})
    assert out[0].cause == "none"


def test_likely_before_possible_before_unlikely():
    causes = [Cause("crack", "sun", 0.36, (), "a"), Cause("eccentricity", "sun", 0.7, (), "b"),
              Cause("pin_error", "planet", 0.2, (), "c"),
              Cause("crack", "ring", 0.05, (), "d")]
    out = _rank(causes, {("crack", "ring"): _fam(30, 100, 1e-20, "ring_fault")})
    assert [(c.cause, c.member, c.verdict) for c in out] == [
        ("eccentricity", "sun", "likely"), ("crack", "sun", "possible"),
        ("crack", "ring", "possible"), ("pin_error", "planet", "unlikely")]


def test_local_tooth_fault_when_the_scores_of_the_kinds_are_within_the_margin():
    causes = [Cause("crack", "sun", 0.600, ("c",), "crack sun 30 %"),
              Cause("pitting", "sun", 0.595, ("p",), "pitting sun"),
              Cause("broken_tooth", "sun", 0.4, (), "broken sun"),
              Cause("crack", "ring", 0.2, (), "crack ring")]
    mism = {("crack", "sun"): 3.0, ("pitting", "sun"): 3.1, ("broken_tooth", "sun"): 6.0}
    out = _rank(causes, mismatch=mism)
    lead = out[0]
    assert (lead.cause, lead.member, lead.verdict) == (LOCAL_FAULT, "sun", "likely")
    assert lead.score == 0.6 and lead.variant == "crack sun 30 %"
    assert "not told" in lead.evidence[0] and "pitting 0.59 (3.1 dB)" in lead.evidence[0]
    # the kinds follow, in their order
    assert [c.cause for c in out[1:4]] == ["crack", "pitting", "broken_tooth"]


def test_local_tooth_fault_when_no_kind_fits_the_sideband_pattern():
    causes = [Cause("crack", "planet", 0.5, (), "a"), Cause("pitting", "planet", 0.3, (), "b")]
    out = _rank(causes, mismatch={("crack", "planet"): KIND_MAX_MISMATCH_DB + 2.5,
                                  ("pitting", "planet"): KIND_MAX_MISMATCH_DB + 3.0})
    assert (out[0].cause, out[0].member) == (LOCAL_FAULT, "planet")
    assert f"{KIND_MAX_MISMATCH_DB + 2.5:.1f} dB" in out[0].evidence[0]


def test_the_kind_is_named_when_it_is_told():
    causes = [Cause("crack", "sun", 0.6, (), "a"), Cause("pitting", "sun", 0.5, (), "b")]
    out = _rank(causes, mismatch={("crack", "sun"): 3.0, ("pitting", "sun"): 4.0})
    assert [c.cause for c in out] == ["crack", "pitting"]
    # a single local kind (no other kind to confuse it with) is named too
    assert _rank([Cause("crack", "sun", 0.6, (), "a")])[0].cause == "crack"
    # the fallback is for the leading local cause only, not for an eccentricity
    out = _rank([Cause("eccentricity", "sun", 0.6, (), "a"),
                 Cause("crack", "sun", 0.59, (), "b"), Cause("pitting", "sun", 0.59, (), "c")])
    assert out[0].cause == "eccentricity"


def test_family_rule_false_positive_rate_on_random_rises():
    """Random rises (40 of 2000 bins, band 0..125 carrier orders at 1/16) against the five
    fault families of paper-case1: the family rule (>= FAMILY_HITS hits at a chance <=
    FAMILY_CHANCE) makes a cause possible in at most 1 % of 400 records (nominal: 5 families
    x 1e-3; measured 0 of 400), the support rule (chance <= SUPPORT_CHANCE) fires in at most
    6 % (nominal 5 x 1 %)."""
    rng = np.random.default_rng(5)
    order = np.arange(2000) / 16
    fams = {name: (f, family_lines(f, mesh_order=114.0, mesh_harmonics=6, harmonics=10,
                                   sidebands=10, max_order=order[-1]))
            for name, f in (("sun_fault", 10.36), ("planet_fault", 2.85), ("ring_fault", 3.0),
                            ("sun_rotation", 3.4545), ("carrier", 1.0))}
    fired = supported = 0
    trials = 400
    for _ in range(trials):
        d = np.zeros(order.size)
        d[rng.choice(order.size, 40, replace=False)] = 10.0
        ev = family_evidence(order, d, 3.0, fams)
        fired += any(e.hits >= FAMILY_HITS and e.chance <= FAMILY_CHANCE for e in ev)
        supported += any(e.hits > 0 and e.chance <= SUPPORT_CHANCE for e in ev)
    assert fired / trials <= 0.01
    assert supported / trials <= 0.06
