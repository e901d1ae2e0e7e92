"""The verdict of a diagnosis: every cause's standing from all the evidence, best first.

:func:`rank_causes` turns the scored causes of :func:`gearvib.diagnosis.diagnose` into the
ranked list a user reads:

* **likely**: the cause's score (how well its simulated signature explains the measured
  rises) is at or above the threshold;
* **possible**: below the threshold, but within :data:`POSSIBLE_MARGIN` of it; or within
  :data:`SUPPORTED_MARGIN` of it with its kinematic family's lines carrying the measured rises
  at a coincidence chance of at most :data:`SUPPORT_CHANCE`; or, at any score, with at least
  :data:`FAMILY_HITS` rising peaks on its family's lines at a coincidence chance of at most
  :data:`FAMILY_CHANCE` (:func:`analysis.diagnosis.family_evidence`): the measurement shows
  the member's fault frequencies even where the simulated signature (its assumed transfer
  path and fault model) does not match them well; or, for a local tooth fault, at any score
  with the member's tooth impacts *detected* in the record
  (:attr:`analysis.diagnosis_impacts.ImpactEvidence.detected`: the fault rate in the
  envelope, or its comb above the mesh band);
* **unlikely**: neither.

Likely causes come first, then possible ones, then the others, each by score. ``none`` leads
only when no cause is likely or possible. When the leading cause is a local tooth fault and
the sideband pattern cannot tell its kind (crack, pitting, broken tooth: their scores within
:data:`KIND_MARGIN` of each other, or even the best kind's pattern
:data:`KIND_MAX_MISMATCH_DB` or more from the measured one), a ``local_tooth_fault`` cause on
the member leads instead, with the kinds' figures in its evidence (``docs/diagnosis.md``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

from analysis.diagnosis import Cause, FamilyEvidence
from analysis.diagnosis_impacts import ImpactEvidence

__all__ = ["FAMILY_CHANCE", "FAMILY_HITS", "KIND_MARGIN", "KIND_MAX_MISMATCH_DB",
           "LOCAL_FAULT", "POSSIBLE_MARGIN", "SUPPORTED_MARGIN", "SUPPORT_CHANCE",
           "rank_causes"]

POSSIBLE_MARGIN = 0.05
"""A cause scoring within this of the threshold (below it) is *possible*."""

SUPPORTED_MARGIN = 0.1
"""A cause scoring within this of the threshold is *possible* when its family supports it
(coincidence chance at most :data:`SUPPORT_CHANCE`)."""

SUPPORT_CHANCE = 1e-2
"""Coincidence chance of a family's hits that supports a cause near the threshold."""

FAMILY_CHANCE = 1e-3
"""Coincidence chance of a family's hits (with at least :data:`FAMILY_HITS` of them) at or
below which its causes are at least *possible*, whatever their score."""

FAMILY_HITS = 10
"""Fewest rising peaks on a family's lines for the family evidence to count."""

KIND_MARGIN = 0.01
"""Lead in score below which the kind of a local tooth fault is not told."""

KIND_MAX_MISMATCH_DB = 6.0
"""Sideband-pattern mismatch [dB] of the best-fitting local kind at or above which no kind
fits the measured pattern (the kind is not told)."""

LOCAL_FAULT = "local_tooth_fault"
"""The cause named when the kind of a local tooth fault cannot be told."""

_ORDER = {"likely": 0, "possible": 1, "unlikely": 2}


def _verdict(c: Cause, threshold: float, fam: FamilyEvidence | None,
             impact: ImpactEvidence | None = None) -> tuple[str, str]:
    if c.score >= threshold:
        return "likely", ""
    if c.score >= threshold - POSSIBLE_MARGIN:
        return "possible", (f"possible: score {c.score:.2f} near the threshold "
                            f"{threshold:.2f}")
    if impact is not None and impact.detected:
        return "possible", (f"possible: the member's tooth impacts stand in the record "
                            f"({impact.family}, {impact.method}, chance {impact.chance:.2g}) "
                            f"though the simulated signature explains the measured rises "
                            f"poorly (score {c.score:.2f})")
    if fam is None or fam.hits == 0:
        return "unlikely", ""
    lines = (f"{fam.hits} of {fam.rising} rising peaks on its lines, coincidence chance "
             f"{fam.chance:.2g}")
    if c.score >= threshold - SUPPORTED_MARGIN and fam.chance <= SUPPORT_CHANCE:
        return "possible", (f"possible: score {c.score:.2f} near the threshold "
                            f"{threshold:.2f} and the measured rises fall on its family's "
                            f"lines ({lines})")
    if fam.hits >= FAMILY_HITS and fam.chance <= FAMILY_CHANCE:
        return "possible", (f"possible: the measured rises fall on its family's lines "
                            f"({lines}) though the simulated signature explains them poorly "
                            f"(score {c.score:.2f})")
    return "unlikely", ""


def rank_causes(causes: Sequence[Cause], threshold: float, *,
                families: Mapping[tuple[str, str], FamilyEvidence | None],
                mismatch: Mapping[tuple[str, str], float],
                local_kinds: Sequence[str], none_evidence: Sequence[str] = (),
                none_reason: str | None = None,
                impacts: Mapping[tuple[str, str], ImpactEvidence] | None = None) -> list[Cause]:
    """The causes with their verdicts, best first, with ``none`` or the kind fallback first.

    Parameters
    ----------
    causes : sequence of Cause
        One per (cause, member), scored; their verdicts are set here, but for causes that
        come with a verdict of their own (the bearing faults of
        :mod:`gearvib.diagnosis.bearings`, judged by their lines).
    threshold : float
        Score above which a cause is likely.
    families : mapping
        ``(cause, member) -> FamilyEvidence`` of the family the cause raises (or None).
    mismatch : mapping
        ``(cause, member) -> sideband-pattern mismatch [dB]`` of the local kinds
        (:func:`analysis.diagnosis.impulse_mismatch_db`).
    local_kinds : sequence of str
        The local tooth-fault kinds (crack, pitting, broken tooth).
    none_evidence : sequence of str
        Evidence lines of the ``none`` entry.
    none_reason : str, optional
        Its first evidence line (default: no simulated candidate explains the measured
        differences and no fault family carries the measured rises, with the best score).
    impacts : mapping, optional
        ``(cause, member) -> ImpactEvidence`` of the local tooth faults
        (:func:`gearvib.diagnosis.impacts.member_impacts`): detected impacts make a local
        tooth fault (one of ``local_kinds``) at least possible.

    Returns
    -------
    list of Cause
        Likely, possible, unlikely causes, each group by score (ties by cause and member);
        first a ``none`` entry (score ``1 - best score``) when none is likely or possible, or
        a :data:`LOCAL_FAULT` entry when the leading cause is a local tooth fault whose kind
        cannot be told.

    Notes
    -----
    The family rules keep the verdict on all the evidence: the cosine score compares the
    measured rises with one simulated fault seen through assumed transfer paths, the family
    evidence only asks whether the rises stand at the member's fault frequencies. With
    ``FAMILY_CHANCE = 1e-3`` and a handful of families per gear set, random rises make a
    cause possible in well under 1 % of records (binomial tail,
    :func:`analysis.diagnosis.family_evidence`; measured in
    ``tests/gearvib/test_diagnosis_verdict.py``); the rate on healthy records is stated in
    ``docs/diagnosis.md``.
    """
    ranked = []
    for c in causes:
        if c.verdict:  # judged by its own evidence (a bearing's lines)
            ranked.append(c)
            continue
        imp = (impacts or {}).get((c.cause, c.member)) if c.cause in local_kinds else None
        v, why = _verdict(c, threshold, families.get((c.cause, c.member)), imp)
        ranked.append(replace(c, verdict=v, evidence=(*c.evidence, why) if why else c.evidence))
    ranked.sort(key=lambda c: (_ORDER[c.verdict], -c.score, c.cause, c.member))
    best = max((c.score for c in ranked), default=0.0)
    if not ranked or ranked[0].verdict == "unlikely":
        why = none_reason or (
            f"no candidate explains the measured differences (best score {best:.2f} < "
            f"threshold {threshold:.2f}) and no fault family carries the measured rises")
        return [Cause("none", "", 1.0 - best, (why, *none_evidence), "", ""), *ranked]
    top = ranked[0]
    if top.cause in local_kinds:
        kinds = [c for c in ranked if c.member == top.member and c.cause in local_kinds]
        told, why = _kind_told(kinds, mismatch)
        if not told:
            names = ", ".join(f"{c.cause} {c.score:.2f}" + (
                f" ({mismatch[(c.cause, c.member)]:.1f} dB)" if (c.cause, c.member) in mismatch
                else "") for c in kinds)
            lead = Cause(LOCAL_FAULT, top.member, top.score, (
                f"local tooth fault on {top.member}: {why}; the kinds' scores (sideband-pattern "
                f"mismatch): {names}", *top.evidence), top.variant, top.verdict)
            return [lead, *ranked]
    return ranked


def _kind_told(kinds: list[Cause], mismatch: Mapping[tuple[str, str], float]
               ) -> tuple[bool, str]:
    """Whether the leading local kind of a member is told from the others, and why not."""
    if len(kinds) < 2:
        return True, ""
    gap = kinds[0].score - kinds[1].score
    if gap < KIND_MARGIN:
        return False, (f"the kind is not told ({kinds[0].cause} leads {kinds[1].cause} by "
                       f"{gap:.3f} < {KIND_MARGIN:g})")
    m = mismatch.get((kinds[0].cause, kinds[0].member))
    if m is not None and m >= KIND_MAX_MISMATCH_DB:
        return False, (f"the kind is not told (even the best-fitting kind's sideband pattern "
                       f"is {m:.1f} dB from the measured one, >= {KIND_MAX_MISMATCH_DB:g} dB)")
    return True, ""
