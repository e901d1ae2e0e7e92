"""Classified rises of a map as the reports show them: speed regions and table rows.

Shared by the simulated report (:mod:`gearvib.report.case`) and the measured report
(:mod:`gearvib.report.measured`): :func:`resonance_regions` groups the rises
(:class:`analysis.instability.Resonances`) into speed regions (:class:`ResonanceRegion`),
:func:`rise_table_rows` and :func:`crossing_table_rows` write the rows of the rise and
crossing tables (:data:`RISE_HEADER`), and :func:`merged_modes` names repeated natural
frequencies as those tables do (``"f3=f4"``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from analysis.instability import FORCED, PARAMETRIC, UNEXPLAINED, Crossing, Resonances
from gearvib.report.wording import count, span

__all__ = ["REGION_HEADER", "RISE_HEADER", "ResonanceRegion", "crossing_table_rows",
           "merged_modes", "resonance_regions", "rise_table_rows"]


RISE_HEADER = ("speed", "f [Hz]", "on", "rise [dB]", "mechanism: cause", "chance", "evidence")
"""Columns of the tables of classified rises (rows: :func:`rise_table_rows`)."""

REGION_HEADER = ("speed [min⁻¹]", "peak speed", "f [Hz]", "rise [dB]", "rises",
                 "mechanisms (rises)")
"""Columns of the resonance-region tables (rows: :meth:`ResonanceRegion.table_row`)."""


@dataclass(frozen=True)
class ResonanceRegion:
    """Detected rises grouped by speed (one row of the region table).

    Attributes
    ----------
    rpm_low, rpm_high : float
        Speed span of the rises [min^-1].
    rpm_peak : float
        Speed of the strongest rise.
    frequency_hz : float
        Response frequency of the strongest rise [Hz].
    strength_db : float
        Rise of the strongest one above its background [dB].
    n_spots : int
        Number of rises.
    causes : tuple of (str, str, int)
        ``(mechanism, cause, rises)`` for every distinct explanation, strongest first.
    """

    rpm_low: float
    rpm_high: float
    rpm_peak: float
    frequency_hz: float
    strength_db: float
    n_spots: int
    causes: tuple[tuple[str, str, int], ...]

    @property
    def mechanisms(self) -> tuple[str, ...]:
        """Distinct ``"mechanism (cause)"`` texts, strongest first."""
        return tuple(m + (f" ({c})" if c else "") for m, c, _ in self.causes)

    def count(self, mechanism: str) -> int:
        """Rises of one mechanism (``FORCED``, ``PARAMETRIC``, ``UNEXPLAINED``)."""
        return sum(n for m, _, n in self.causes if m == mechanism)

    @property
    def classified(self) -> bool:
        """True if at least one rise is a forced resonance or a parametric instability."""
        return self.count(FORCED) + self.count(PARAMETRIC) > 0

    @property
    def summary(self) -> str:
        """Every explanation with its number of rises, explained ones first:
        ``"forced resonance: 3 f_mesh = f5 (2), 2 f_mesh = f5; unexplained: 1 rise"``."""
        parts = []
        for mech in (FORCED, PARAMETRIC):
            items = [f"{c}" + (f" ({n})" if n > 1 else "") for m, c, n in self.causes
                     if m == mech]
            if items:
                parts.append(f"{mech}: " + ", ".join(items))
        n_un = self.count(UNEXPLAINED)
        if n_un:
            parts.append(f"{UNEXPLAINED}: {count(n_un, 'rise')}")
        return "; ".join(parts)

    def table_row(self) -> tuple[str, ...]:
        """The region as a row of a region table (:data:`REGION_HEADER`)."""
        return (span(self.rpm_low, self.rpm_high), f"{self.rpm_peak:.0f}",
                f"{self.frequency_hz:.0f}", f"{self.strength_db:.1f}", str(self.n_spots),
                self.summary)


def rise_table_rows(res: Resonances, on_order: Callable[[int], str]) -> list[tuple[str, ...]]:
    """Rows of a table of classified rises (:data:`RISE_HEADER`), one a rise.

    Parameters
    ----------
    res : Resonances
        The classified rises.
    on_order : callable
        ``on_order(i)`` writes the "on" column of rise ``i`` when it lies on an order
        (``res.order[i]`` not 0); a rise on a natural frequency reads ``f_i``, on a map spot
        ``spot``.
    """
    feature = {"natural frequency": "f_i", "spot": "spot"}
    rows: list[tuple[str, ...]] = []
    for i in range(len(res)):
        on = on_order(i) if res.order[i] else feature.get(str(res.feature[i]), "–")
        rows.append((f"{res.rpm[i]:.0f}", f"{res.frequency[i]:.0f}", on,
                     f"{res.strength_db[i]:.1f}",
                     str(res.mechanism[i]).split()[0]
                     + (f": {res.cause[i]}" if res.cause[i] else ""),
                     # the chance of an explanation; an unexplained rise has none
                     "–" if str(res.mechanism[i]) == UNEXPLAINED
                     else f"{100 * res.coincidence[i]:.0f} %", str(res.note[i])))
    return rows


def crossing_table_rows(crossings: Sequence[Crossing], label: Callable[[Crossing], str]
                        ) -> list[tuple[str, ...]]:
    """Rows of a table of predicted crossings: ``label(c)``, natural frequency, speed and what
    was found there (a rise with its strength)."""
    return [(label(c), f"{c.frequency_hz:.0f}", f"{c.rpm:.0f}",
             c.status + (f" ({c.strength_db:.1f} dB)" if c.status == "rise" else ""))
            for c in crossings]


def resonance_regions(res: Resonances, *, rpm_gap: float) -> list[ResonanceRegion]:
    """Group rises into speed regions.

    Rises closer than ``rpm_gap`` join a region; a region spans at most ``4 rpm_gap`` (dense
    clutter must not chain into one region over the whole run-up).

    Parameters
    ----------
    res : Resonances
        Detected rises.
    rpm_gap : float
        Largest speed gap inside one region [min^-1].

    Returns
    -------
    list of ResonanceRegion
        Sorted by speed.
    """
    if not len(res):
        return []
    order = np.argsort(res.rpm, kind="stable")
    groups: list[list[int]] = [[int(order[0])]]
    for i in order[1:]:
        g = groups[-1]
        if res.rpm[i] - res.rpm[g[-1]] <= rpm_gap and res.rpm[i] - res.rpm[g[0]] <= 4 * rpm_gap:
            groups[-1].append(int(i))
        else:
            groups.append([int(i)])
    out = []
    for g in groups:
        idx = np.asarray(g)
        best = int(idx[np.argmax(res.strength_db[idx])])
        causes: dict[tuple[str, str], int] = {}
        for i in idx[np.argsort(res.strength_db[idx], kind="stable")[::-1]]:
            mech = str(res.mechanism[i])
            key = (mech, "" if mech == UNEXPLAINED else str(res.cause[i]))
            causes[key] = causes.get(key, 0) + 1
        out.append(ResonanceRegion(
            rpm_low=float(res.rpm[idx].min()), rpm_high=float(res.rpm[idx].max()),
            rpm_peak=float(res.rpm[best]), frequency_hz=float(res.frequency[best]),
            strength_db=float(res.strength_db[best]), n_spots=idx.size,
            causes=tuple((m, c, n) for (m, c), n in causes.items())))
    return out


def merged_modes(fn: np.ndarray, names: Sequence[str], rtol: float = 1e-3
                 ) -> tuple[np.ndarray, list[str]]:
    """Natural frequencies with repeated ones merged (``"f3=f4"``), as the rise tables name
    them."""
    out_f: list[float] = []
    out_n: list[str] = []
    for f, n in sorted(zip(np.asarray(fn, dtype=float), names, strict=True)):
        if out_f and abs(f - out_f[-1]) <= rtol * max(f, 1e-300):
            out_n[-1] = f"{out_n[-1]}={n}"
            continue
        out_f.append(float(f))
        out_n.append(str(n))
    return np.asarray(out_f), out_n
