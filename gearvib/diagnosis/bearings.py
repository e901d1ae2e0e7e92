"""Rolling-bearing causes of a diagnosis: the declared bearings' fault lines in the record.

gearvib does not simulate rolling-bearing defects: a bearing fault is judged by its lines.
:func:`bearing_fault_lines` checks the four families of every declared ``[[rolling_bearing]]``
(BPFO, BPFI with sidebands at the rings' relative speed, BSF with sidebands at FTF, FTF) at
their own positions in the squared envelope (order) spectrum of the band the fast kurtogram
chooses, and in the order spectrum of the raw signal
(:func:`gearvib.fault_lines.check_fault_lines`);
:func:`bearing_causes` turns each family into a cause ranked beside the gear faults:

* **likely**: the family is *detected* in the envelope spectrum (its fundamental and another
  harmonic found, at a chance of a coincidence of at most
  :data:`analysis.line_evidence.MAX_CHANCE`, not explained by shaft or mesh harmonics) with at
  least :data:`LIKELY_HARMONICS` harmonics;
* **possible**: detected with fewer harmonics; or its lines are found in the envelope
  spectrum but a family of its shape at a random position would be found as easily; or it is
  detected only in the order spectrum of the raw signal;
* **unlikely**: otherwise (not found, explained by other lines, or above the demodulated band).

The score maps the chance ``p`` of a coincidence in the envelope spectrum onto the scores of
the simulated causes: ``threshold * log(p) / log(MAX_CHANCE)``, clipped to [0, 1], so that a
family is at the threshold exactly when its chance is at the detection limit, and at 1 when
``p <= MAX_CHANCE ** (1 / threshold)`` (1e-5 with the defaults).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.diagnosis import Cause
from analysis.line_evidence import MAX_CHANCE
from gearvib.fault_lines import FaultLines, catalogue_families, check_fault_lines, known_families

if TYPE_CHECKING:
    from analysis.measurement import Measurement

__all__ = ["BEARING_CAUSES", "KNOWN_TOP_ORDER", "LIKELY_HARMONICS", "bearing_causes",
           "bearing_fault_lines", "chance_score"]

BEARING_CAUSES = {"bearing_bpfo": "outer_race_fault", "bearing_bpfi": "inner_race_fault",
                  "bearing_bsf": "rolling_element_fault", "bearing_ftf": "cage_fault"}
"""Cause named for each bearing family (the ``cause`` of :class:`analysis.diagnosis.Cause`;
its ``member`` is the bearing's name)."""

LIKELY_HARMONICS = 3
"""Harmonics a family detected in the envelope spectrum must have found (its fundamental
among them) for its fault to be *likely*; with fewer it is *possible*. The squared envelope
of a signal modulated by one tone at ``f`` holds ``f`` and ``2 f`` and nothing above: a
two-line family is what any modulation near a bearing's rate gives, an impulse train (a
defect struck once per passage) fills many harmonics."""

FOUND = ("detected", "possible", "explained")
"""Statuses of a family whose lines were found (its chance of a coincidence means something)."""

KNOWN_TOP_ORDER = 200.0
"""Shaft and mesh harmonics up to this order are the known lines that can explain a bearing
family's lines."""


def chance_score(chance: float, threshold: float, max_chance: float = MAX_CHANCE) -> float:
    """Score in [0, 1] of a line family found at a chance ``chance`` of a coincidence.

    ``threshold * log(chance) / log(max_chance)``, clipped: equal to ``threshold`` at the
    detection limit ``max_chance``, 0 for a certain coincidence (chance 1 or not a number).
    """
    if not (isinstance(chance, float | int) and math.isfinite(chance)) or chance >= 1.0:
        return 0.0
    if chance <= 0.0:
        return 1.0
    return float(min(1.0, max(0.0, threshold * math.log(chance) / math.log(max_chance))))


def bearing_fault_lines(measurement: Measurement, description: Any, *,
                        channel: str | None = None, reference: str | None = None,
                        model: Any = None) -> FaultLines | None:
    """The declared bearings' fault families checked in a measurement.

    Parameters
    ----------
    measurement : Measurement
        The record with the speed of ``reference``.
    description : GearSet or ShaftRig
        The machine (:func:`gearvib.config.load_description`).
    channel : str, optional
        Vibration channel (default the measurement's first).
    reference : str, optional
        Member or shaft whose speed the measurement gives (default the description's input).
    model : AssembledModel, optional
        The gear set's assembly if already at hand (assembled here otherwise).

    Returns
    -------
    FaultLines or None
        None when the description declares no rolling bearing.

    Raises
    ------
    ValueError
        A reference that is not a rotating member or shaft of the description.
    """
    from gearvib.rig import ShaftRig

    bearings = description.bearings()
    if not bearings:
        return None
    if isinstance(description, ShaftRig):
        cat = description.catalogue(reference=reference, harmonics=3)
    else:
        from gearvib.assembly import assemble
        from gearvib.catalogue import gear_set_catalogue

        model = assemble(description) if model is None else model
        ref = reference or model.input_member
        ratios = dict(model.kinematic_ratios)
        if not ratios.get(ref):
            raise ValueError(f"reference = {ref!r} is not a rotating member of the gear set; "
                             f"admissible: {sorted(k for k, v in ratios.items() if v)}")
        cat = gear_set_catalogue(description, model=model, reference=ref, harmonics=3)
    fams = [f for f in catalogue_families(cat, bearings) if f.kind in BEARING_CAUSES]
    if not fams:
        return None
    return check_fault_lines(measurement, fams, known=known_families(cat, KNOWN_TOP_ORDER),
                             channel=channel)


def _chance(c: float) -> str:
    return "below 1e-12" if c < 1e-12 else f"{c:.2g}"


def bearing_causes(fault_lines: FaultLines, threshold: float) -> list[Cause]:
    """One cause per bearing family of a check, with its verdict and evidence.

    Parameters
    ----------
    fault_lines : FaultLines
        From :func:`bearing_fault_lines`.
    threshold : float
        The diagnosis's threshold (a family at the detection limit scores it).

    Returns
    -------
    list of Cause
        In the check's order; ``verdict`` set (``likely``, ``possible``, ``unlikely``) as the
        module docstring states.
    """
    env = fault_lines.envelope_evidence
    order = fault_lines.order_evidence
    where = ("squared envelope spectrum" if fault_lines.domain == "frequency"
             else "squared envelope order spectrum")
    b = fault_lines.envelope.band
    out = []
    for i, fam in enumerate(fault_lines.families):
        st = str(env.status[i])
        chance = float(env.chance[i])
        c = env.checks[i]
        harm = c.sideband == 0
        ev = [f"{fam.label} of {fam.source} (order {fam.order:.5g}) in the {where} of "
              f"{b.low:.5g}-{b.high:.5g} Hz: {st}, {c.harmonics_found} of {int(harm.sum())} "
              "harmonics found" + (f", chance of a coincidence {_chance(chance)}"
                                   if np.isfinite(chance) and st in FOUND else "")]
        if st == "explained":
            ev.append(f"its lines are those of {env.explained_by[i]}")
        o_st = str(order.status[i]) if order is not None else ""
        if order is not None:
            o_ch = float(order.chance[i])
            ev.append(f"order spectrum of the raw signal: {o_st}"
                      + (f", chance {_chance(o_ch)}" if np.isfinite(o_ch) and o_st in FOUND
                         else ""))
        score = chance_score(chance, threshold) if st in ("detected", "possible") else 0.0
        if st == "detected" and c.harmonics_found >= LIKELY_HARMONICS:
            verdict = "likely"
        elif st in ("detected", "possible") or o_st == "detected":
            verdict = "possible"
            if st == "detected":
                ev.append(f"possible: detected with {c.harmonics_found} harmonics, fewer than "
                          f"{LIKELY_HARMONICS} (one modulating tone near the rate gives two)")
            score = min(score, math.nextafter(threshold, 0.0))
        else:
            verdict = "unlikely"
        out.append(Cause(BEARING_CAUSES[fam.kind], fam.source, score, tuple(ev),
                         f"{fam.label} of {fam.source}", verdict))
    return out
