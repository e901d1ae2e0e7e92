"""Tooth-fault impacts of a diagnosis: every member's fault rate in the envelope and above the
mesh band (:func:`analysis.diagnosis_impacts.impact_check`).

:func:`member_impacts` checks the fault family of every candidate member with a local tooth
fault (``sun_fault``, ``planet_fault``, ``ring_fault``, ``gear_fault ...``) in the record and
returns the evidence per local-fault cause; :func:`gearvib.diagnosis.verdict.rank_causes`
makes a local tooth fault of a member whose impacts are *detected* at least *possible*
(``docs/diagnosis.md``).
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from analysis.diagnosis_impacts import (
    MIN_REVOLUTIONS,
    ImpactCheck,
    ImpactEvidence,
    ImpactFamily,
    impact_check,
)
from gearvib.diagnosis.candidates import LOCAL_KINDS
from gearvib.diagnosis.lines import MemberLines

__all__ = ["PASS_SIDEBANDS", "member_impacts"]

PASS_SIDEBANDS = 2
"""Planet-pass harmonics on either side of a mesh harmonic that belong to the mesh (the
half-width of the mesh lattice left out is this many times the planet count, in reference
orders; at least this many orders without planets)."""


def member_impacts(signal: np.ndarray, fs: float, rpm: np.ndarray, *,
                   lines: dict[str, MemberLines], members: list[Any], ms: dict[str, float],
                   model: Any, name: str = "measured"
                   ) -> tuple[ImpactCheck | None, dict[tuple[str, str], ImpactEvidence]]:
    """The impact check of a record and its evidence per local-fault cause.

    Parameters
    ----------
    signal, fs, rpm : array, float, array
        The record, its sample rate [Hz] and the reference shaft's speed per sample [min-1].
    lines : dict
        :func:`gearvib.diagnosis.lines.member_lines` of the candidate members.
    members : list
        The candidate members (:func:`gearvib.diagnosis.candidates.candidate_members`).
    ms : dict
        Member speeds in reference orders (the fixed-frame shaft orders: the healthy set's
        own modulations).
    model : AssembledModel
        The healthy set (its planets per carrier set the mesh lattice's width).
    name : str
        Channel name.

    Returns
    -------
    ImpactCheck or None, dict
        The check and ``(kind, member) -> ImpactEvidence`` for every local kind of every
        member with a fault family; ``None`` and no evidence when the record covers fewer
        than ``MIN_REVOLUTIONS + 1`` revolutions of the reference shaft (too short to tell
        impacts from noise: the diagnosis goes on without this evidence).
    """
    if float(np.sum(rpm)) / (60.0 * fs) < MIN_REVOLUTIONS + 1:
        return None, {}
    meshes = sorted({ln.mesh for ln in lines.values() if ln.mesh > 0})
    fams: dict[str, float] = {}
    for m in members:
        ln = lines[m.name]
        if ln.fault is not None and ln.fault > 0:
            fams.setdefault(ln.fault_family, ln.fault)
    per_carrier = Counter(str(p.get("carrier", "")) for p in model.meta.get("planets", []))
    span = float(PASS_SIDEBANDS * max(1, max(per_carrier.values(), default=1)))
    check = impact_check(signal, fs, rpm, mesh_orders=meshes,
                         families=[ImpactFamily(k, v) for k, v in fams.items()],
                         known_orders=[abs(v) for k, v in ms.items() if k != "ground" and v],
                         span=span, name=name)
    by_family = {e.family: e for e in check.evidence}
    out = {}
    for m in members:
        e = by_family.get(lines[m.name].fault_family)
        if e is not None:
            for kind in LOCAL_KINDS:
                out[(kind, m.name)] = e
    return check, out
