"""Compare two analysed runs: which resonance regions weakened, vanished or appeared.

The comparison of a case against a reference (e.g. the paper's case 2 against case 1) matches

* the resonance regions of the tooth-force sonogram (detected spots grouped by speed, see
  :func:`gearvib.report.figures.resonance_regions`): by speed, within a tolerance of a few
  percent of the top speed; the change of strength is given in dB;
* the unstable intervals of the Floquet stability charts: by overlap in speed; the change of
  width is relative;
* the natural frequencies, mode by mode;
* the peak-to-peak fluctuation of the summed stiffness of the first central gear (the sun).

It then checks the paper's statements that apply, decided by what differs between the two
gear-set descriptions: when only the planet angles differ (planet phasing, the paper's cases 1
and 2), the paper found *fewer resonance regions with less intensity*; when only the bearing
supports differ, it found *lower natural frequencies, wider instability regions and new ones*.
The verdict says whether this run reproduces that, and if not, which regions got stronger or
appeared. Any other pair of gear sets is compared without the paper's statements.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.checks import require_instance
from gearvib.checks import check_real
from gearvib.report.case_analysis import CaseAnalysis
from gearvib.report.rises import ResonanceRegion
from gearvib.report.wording import count, span

__all__ = ["Comparison", "FloquetChange", "RegionChange", "compare_cases"]

PAPER_PHASING = ("Paper, section 3.3: with the planets offset (case 2) the sun-mesh stiffness "
                 "oscillates less, so there are fewer resonance regions with less intensity "
                 "than in case 1; modifications usually improve one speed range only and "
                 "often cause new resonance regions.")
PAPER_BEARINGS = ("Paper, closing remarks of section 3: bearing stiffness lowers the natural "
                  "frequencies, widens the instability regions already present with rigid "
                  "bearings and adds new ones (planet translation).")


@dataclass(frozen=True)
class RegionChange:
    """One resonance region of either case and what happened to it.

    Attributes
    ----------
    status : str
        ``"weaker"``, ``"stronger"``, ``"unchanged"``, ``"vanished"`` (only in the reference)
        or ``"appeared"`` (only in the other case).
    reference, other : ResonanceRegion or None
        The matched regions.
    delta_db : float
        Strength change ``other - reference`` [dB] (NaN if unmatched).
    """

    status: str
    reference: ResonanceRegion | None
    other: ResonanceRegion | None
    delta_db: float

    @property
    def rpm(self) -> float:
        """Speed of the strongest spot (reference if present) [min^-1]."""
        r = self.reference or self.other
        return r.rpm_peak if r is not None else math.nan

    def row(self) -> tuple[str, ...]:
        """Formatted table row."""
        def speeds(r: ResonanceRegion | None) -> str:
            return "–" if r is None else span(r.rpm_low, r.rpm_high)

        def strength(r: ResonanceRegion | None) -> str:
            return "–" if r is None else f"{r.strength_db:.1f} ({r.n_spots})"

        texts = [r.summary for r in (self.reference, self.other) if r is not None]
        mech = texts[0] if len(set(texts)) == 1 else " | ".join(
            f"{name}: {t}" for name, t in zip(("reference", "other"), texts, strict=False))
        if self.reference is None or self.other is None:
            mech = texts[0]
        d = "–" if math.isnan(self.delta_db) else f"{self.delta_db:+.1f}"
        return (self.status, speeds(self.reference), strength(self.reference),
                speeds(self.other), strength(self.other), d, mech)


@dataclass(frozen=True)
class FloquetChange:
    """One unstable interval of the Floquet chart of either case.

    Attributes
    ----------
    status : str
        ``"wider"``, ``"narrower"``, ``"unchanged"``, ``"vanished"`` or ``"appeared"``.
    reference, other : (float, float) or None
        Speed interval [min^-1].
    candidate : str
        Theory candidate of the interval (the other case's if it has the interval).
    reference_candidate, other_candidate : str
        The candidate each case's Floquet table gives it ("" if unattributed or absent).
    """

    status: str
    reference: tuple[float, float] | None
    other: tuple[float, float] | None
    candidate: str
    reference_candidate: str = ""
    other_candidate: str = ""

    def row(self) -> tuple[str, ...]:
        """Formatted table row (each case's candidate as in its own Floquet table)."""
        def span(r: tuple[float, float] | None) -> str:
            return "–" if r is None else f"{r[0]:.0f}–{r[1]:.0f} ({r[1] - r[0]:.0f})"

        def lab(r: tuple[float, float] | None, text: str) -> str:
            return "–" if r is None else (text or "unattributed")

        return (self.status, span(self.reference), span(self.other),
                lab(self.reference, self.reference_candidate),
                lab(self.other, self.other_candidate))


@dataclass(frozen=True)
class Comparison:
    """Result of :func:`compare_cases`.

    Attributes
    ----------
    reference, other : str
        Case names.
    regions : list of RegionChange
        Resonance regions of the sonograms, matched by speed.
    floquet : list of FloquetChange
        Unstable intervals, matched by overlap (empty without stability charts).
    natural_frequencies : list of (str, float, float)
        ``(name, f_reference, f_other)`` [Hz], mode by mode.
    stiffness_p2p : (float or None, float or None)
        Peak-to-peak fluctuation of the summed stiffness of the first central gear (the sun
        of a simple set) [N/m].
    n_regions : (int, int)
        Resonance regions in each case.
    signal : str
        The signal whose regions are compared (e.g. the sonogram of a tooth force).
    differences : tuple of str
        Paths of the gear-set description that differ (``"geometry.planet_angles_deg"``).
    total_strength_db : (float, float)
        Energetic sum ``10 log10 sum 10^(s/10)`` of the region strengths (-inf if none).
    fewer_or_weaker : bool
        The other case has fewer regions and is not stronger in total (energetic sum of the
        region strengths, within ``db_tol``), or no more regions and weaker in total by more
        than ``db_tol``: the paper's "fewer resonance areas with less intensity".
    claims : list of (str, bool or None, str)
        ``(paper statement, reproduced?, evidence)`` for the statements that apply.
    verdict : str
        One-paragraph summary.
    explanation : list of str
        Details (regions that got stronger or appeared, the paper's caveats).
    """

    reference: str
    other: str
    regions: list[RegionChange]
    floquet: list[FloquetChange]
    natural_frequencies: list[tuple[str, float, float]]
    stiffness_p2p: tuple[float | None, float | None]
    n_regions: tuple[int, int]
    total_strength_db: tuple[float, float]
    fewer_or_weaker: bool
    claims: list[tuple[str, bool | None, str]] = field(default_factory=list)
    verdict: str = ""
    explanation: list[str] = field(default_factory=list)
    signal: str = "sonogram of the tooth force"
    differences: tuple[str, ...] = ()


def _energy_db(values: list[float]) -> float:
    if not values:
        return -math.inf
    return float(10.0 * np.log10(np.sum(10.0 ** (np.asarray(values) / 10.0))))


def _match_regions(ref: list[ResonanceRegion], oth: list[ResonanceRegion], tol_rpm: float,
                   db_tol: float) -> list[RegionChange]:
    pairs = []
    for i, a in enumerate(ref):
        for j, b in enumerate(oth):
            if b.rpm_low - tol_rpm <= a.rpm_high and a.rpm_low - tol_rpm <= b.rpm_high:
                pairs.append((abs(a.rpm_peak - b.rpm_peak), i, j))
    pairs.sort()
    used_i: set[int] = set()
    used_j: set[int] = set()
    out = []
    for _, i, j in pairs:
        if i in used_i or j in used_j:
            continue
        used_i.add(i)
        used_j.add(j)
        d = oth[j].strength_db - ref[i].strength_db
        status = "unchanged" if abs(d) <= db_tol else ("weaker" if d < 0 else "stronger")
        out.append(RegionChange(status, ref[i], oth[j], float(d)))
    out += [RegionChange("vanished", a, None, math.nan) for i, a in enumerate(ref)
            if i not in used_i]
    out += [RegionChange("appeared", None, b, math.nan) for j, b in enumerate(oth)
            if j not in used_j]
    out.sort(key=lambda c: c.rpm)
    return out


def _floquet_intervals(ca: CaseAnalysis) -> list[tuple[float, float, str]]:
    return [(r["lower_rpm"], r["upper_rpm"], r["label"]) for r in ca.floquet_regions()]


def _match_floquet(ref: list[tuple[float, float, str]], oth: list[tuple[float, float, str]],
                   rel_tol: float) -> list[FloquetChange]:
    used: set[int] = set()
    out = []
    for a in ref:
        best, best_ov = None, 0.0
        for j, b in enumerate(oth):
            ov = min(a[1], b[1]) - max(a[0], b[0])
            if j not in used and ov > best_ov:
                best, best_ov = j, ov
        if best is None:
            out.append(FloquetChange("vanished", (a[0], a[1]), None, a[2], a[2], ""))
            continue
        used.add(best)
        b = oth[best]
        wa, wb = a[1] - a[0], b[1] - b[0]
        rel = (wb - wa) / wa if wa > 0 else math.inf
        status = "unchanged" if abs(rel) <= rel_tol else ("wider" if rel > 0 else "narrower")
        out.append(FloquetChange(status, (a[0], a[1]), (b[0], b[1]), b[2] or a[2], a[2], b[2]))
    out += [FloquetChange("appeared", None, (b[0], b[1]), b[2], "", b[2])
            for j, b in enumerate(oth) if j not in used]
    # every change has a reference region, an other region or both
    out.sort(key=lambda c: (c.reference or c.other)[0])  # type: ignore[index]
    return out


def _fmt_region(r: ResonanceRegion) -> str:
    return (f"{span(r.rpm_low, r.rpm_high, 'min⁻¹')} (strongest {r.strength_db:.1f} dB at "
            f"{r.frequency_hz:.0f} Hz; {r.summary})")


_IGNORED = {"name", "title", "simulation", "description"}


def differences(a: Any, b: Any, path: str = "") -> set[str]:
    """Paths where two gear-set descriptions differ (names, titles and run settings ignored)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out: set[str] = set()
        for k in set(a) | set(b):
            if not path and k in _IGNORED:
                continue
            if k not in a or k not in b:
                out.add(f"{path}{k}")
            else:
                out |= differences(a[k], b[k], f"{path}{k}.")
        return out
    return set() if a == b else {path.rstrip(".")}


def _gearset(ca: CaseAnalysis) -> dict | None:
    inner = ca.config.get("model", {}) if isinstance(ca.config, dict) else {}
    gs = inner.get("gearset") if isinstance(inner, dict) else None
    return gs if isinstance(gs, dict) else None


def _kind_of_change(diff: set[str]) -> str:
    """``"phasing"`` (only the planet angles differ), ``"bearings"`` (only supports), else
    ``""``."""
    if not diff:
        return ""
    if all(d.startswith(("geometry.planet_angles_deg", "geometry.n_planets")) for d in diff):
        return "phasing"
    if all(d.startswith("bodies.") and ".support" in d for d in diff):
        return "bearings"
    return ""


def compare_cases(reference: CaseAnalysis, other: CaseAnalysis, *, rpm_tol: float | None = None,
                  db_tol: float = 1.0, width_rel_tol: float = 0.1) -> Comparison:
    """Compare ``other`` against ``reference``.

    Parameters
    ----------
    reference, other : CaseAnalysis
        The analysed runs (same speed range for a meaningful comparison).
    rpm_tol : float, optional
        Speed tolerance for matching resonance regions [min^-1]; default 3 % of the top speed.
    db_tol : float
        Strength changes within ``±db_tol`` count as unchanged [dB].
    width_rel_tol : float
        Relative width change of a Floquet interval that counts as wider/narrower.

    Returns
    -------
    Comparison
    """
    require_instance(reference, CaseAnalysis, "reference")
    require_instance(other, CaseAnalysis, "other")
    rpm_tol = check_real(rpm_tol, "rpm_tol", low=0.0, high=1e9, optional=True)
    db_tol = check_real(db_tol, "db_tol", low=0.0, high=1000.0)
    width_rel_tol = check_real(width_rel_tol, "width_rel_tol", low=0.0, high=1e6)
    top = max(reference.speed_range[1], other.speed_range[1])
    tol = 0.03 * top if rpm_tol is None else float(rpm_tol)
    changes = _match_regions(reference.regions, other.regions, tol, db_tol)
    floq = _match_floquet(_floquet_intervals(reference), _floquet_intervals(other),
                          width_rel_tol)
    nat = [(n, float(a), float(b)) for n, a, b in zip(
        reference.mode_names, reference.natural_frequencies_hz, other.natural_frequencies_hz,
        strict=False)]
    st_a, st_b = reference.main_stiffness, other.main_stiffness
    p2p = (st_a.peak_to_peak if st_a else None, st_b.peak_to_peak if st_b else None)
    gear = st_a.central if st_a else "sun"
    gs_a, gs_b = _gearset(reference), _gearset(other)
    diff = differences(gs_a, gs_b) if gs_a is not None and gs_b is not None else {"?"}
    kind = _kind_of_change(diff)
    n_ref, n_oth = len(reference.regions), len(other.regions)
    e_ref = _energy_db([r.strength_db for r in reference.regions])
    e_oth = _energy_db([r.strength_db for r in other.regions])
    fewer_or_weaker = ((n_oth < n_ref and e_oth <= e_ref + db_tol)
                       or (n_oth <= n_ref and e_oth < e_ref - db_tol))
    a, b = reference.name, other.name

    claims: list[tuple[str, bool | None, str]] = []
    explanation: list[str] = []
    region_text = (f"{b}: {count(n_oth, 'resonance region')} (total {e_oth:.1f} dB) "
                   f"against {n_ref} in {a} (total {e_ref:.1f} dB)")
    worse = [c for c in changes if c.status in ("stronger", "appeared")]
    better = [c for c in changes if c.status in ("weaker", "vanished")]
    phasing = (kind == "phasing" and p2p[0] is not None and p2p[1] is not None)
    if phasing:
        assert p2p[0] is not None and p2p[1] is not None  # (phasing)
        stiff_text = (f"summed {gear}-mesh stiffness fluctuation {p2p[1] / 1e8:.3f}e8 N/m "
                      f"peak-to-peak in {b} against {p2p[0] / 1e8:.3f}e8 N/m in {a}")
        claims.append((f"the summed {gear}-mesh stiffness oscillates less", p2p[1] < p2p[0],
                       stiff_text))
        claims.append(("fewer or weaker resonance regions", fewer_or_weaker, region_text))
    bearings = kind == "bearings"
    if bearings:
        lowered = (other.natural_frequencies_hz.min() < reference.natural_frequencies_hz.min()
                   if other.natural_frequencies_hz.size and
                   reference.natural_frequencies_hz.size else None)
        claims.append(("lower natural frequencies", lowered,
                       f"lowest natural frequency {other.natural_frequencies_hz.min():.0f} Hz "
                       f"in {b} against {reference.natural_frequencies_hz.min():.0f} Hz in {a}; "
                       f"{other.natural_frequencies_hz.size} against "
                       f"{count(reference.natural_frequencies_hz.size, 'elastic mode')}"))
        if floq:
            wider = [c for c in floq if c.status == "wider"]
            new = [c for c in floq if c.status == "appeared"]
            matched = [c for c in floq if c.reference and c.other]
            claims.append(("instability regions become wider",
                           bool(wider) and len(wider) >= len(matched) / 2,
                           f"{len(wider)} of {len(matched)} matched Floquet intervals wider"))
            claims.append(("new instability regions appear", bool(new),
                           f"{count(len(new), 'Floquet interval')} only in {b}"))
        else:
            claims.append(("instability regions become wider / new ones appear", None,
                           "no Floquet charts to compare"))
        claims.append(("new resonance regions in the sonogram",
                       any(c.status == "appeared" for c in changes),
                       f"{count(sum(c.status == 'appeared' for c in changes), 'region')} only in "
                       f"{b}"))

    if phasing:
        if fewer_or_weaker:
            verdict = (f"This run reproduces the paper's finding for planet phasing: {region_text}"
                       f"; the {claims[0][2]}.")
        else:
            partly = (" (fewer regions, but stronger in total)" if n_oth < n_ref else "")
            verdict = (f"This run does not reproduce the paper's finding of fewer and weaker "
                       f"resonance regions{partly}: {region_text}, although the "
                       f"{claims[0][2]}.")
            # stronger or appeared changes have an other region, weaker or vanished ones a
            # reference region
            if worse:
                explanation.append(
                    "Regions that got stronger or appeared in " + b + ": "
                    + "; ".join(f"{c.status} {_fmt_region(c.other)}"  # type: ignore[arg-type]
                                + (f" ({c.delta_db:+.1f} dB)" if c.status == "stronger"
                                   else "") for c in worse) + ".")
            if better:
                explanation.append(
                    "Regions that weakened or vanished: "
                    + "; ".join(f"{c.status} {_fmt_region(c.reference)}"  # type: ignore[arg-type]
                                for c in better) + ".")
            explanation.append(
                "Why: shifting the planets cancels the tangential (rotational) part of the "
                "stiffness variation, but the broken symmetry leaves the radial part "
                "un-equalised, so the planet modes are excited as strongly or more (the paper "
                "notes the same for its 3rd and 4th natural frequencies); and "
                "modifications usually improve one speed range only and can cause new "
                "resonance regions.")
        explanation.append(PAPER_PHASING)
    elif bearings:
        ok = [c for c in claims if c[1]]
        verdict = (f"{b} against {a}: {len(ok)} of {len(claims)} statements of the paper on "
                   "elastic bearings are reproduced (" + "; ".join(
                       f"{c[0]}: {'yes' if c[1] else ('n/a' if c[1] is None else 'no')}"
                       for c in claims) + f"). {region_text}.")
        explanation.append(PAPER_BEARINGS)
    else:
        what = ("the gear-set descriptions differ in " + ", ".join(sorted(diff)[:6])
                + (" ..." if len(diff) > 6 else "")) if diff and diff != {"?"} else (
            "the runs carry no gear-set descriptions to compare" if diff == {"?"} else
            "same gear set")
        verdict = (f"{b} against {a} ({what}; the paper's statements on planet phasing and "
                   f"bearing stiffness do not apply): {region_text}.")
    if floq:
        counts = {s: sum(c.status == s for c in floq) for s in
                  ("wider", "narrower", "unchanged", "vanished", "appeared")}
        explanation.append("Floquet intervals: " + ", ".join(
            f"{v} {k}" for k, v in counts.items() if v) + ".")
    signal = (f"sonogram of the tooth force {reference.force_mesh}"
              if reference.force_mesh == other.force_mesh else
              f"sonograms of the tooth forces {reference.force_mesh} and {other.force_mesh}")
    return Comparison(reference=a, other=b, regions=changes, floquet=floq,
                      natural_frequencies=nat, stiffness_p2p=p2p, n_regions=(n_ref, n_oth),
                      total_strength_db=(e_ref, e_oth), fewer_or_weaker=fewer_or_weaker,
                      claims=claims, verdict=verdict, explanation=explanation, signal=signal,
                      differences=tuple(sorted(diff - {"?"})))
