"""Diagnosis of a machine without gears: the faults of its declared rolling bearings.

Nothing is simulated: the causes are the bearing fault families judged by their lines in the
envelope spectrum (:mod:`gearvib.diagnosis.bearings`). :func:`first_bins` (profiles of one
diagnosis on a common order band) is shared with :mod:`gearvib.diagnosis.engine`.
"""

from __future__ import annotations

import time as _time
from pathlib import Path

import numpy as np

from analysis.diagnosis import (
    Diagnosis,
    OrderProfile,
    deadband_db,
    order_profile,
    prominence_db,
)
from gearvib.config import ConfigError
from gearvib.diagnosis.bearings import bearing_causes, bearing_fault_lines
from gearvib.diagnosis.record import Record
from gearvib.diagnosis.verdict import rank_causes

__all__ = ["diagnose_rig", "first_bins"]


def first_bins(p: OrderProfile, n: int) -> OrderProfile:
    """The profile's first ``n`` order bins (profiles of one diagnosis on a common band)."""
    return OrderProfile(p.order[:n], p.amplitude[:n], p.units, p.revolutions, p.segments,
                        p.speed_rpm, p.name)


def diagnose_rig(measured: Record, cfg: dict, base: Path | None, *, config: str,
                  baseline: Record | None, threshold: float, revolutions: int) -> Diagnosis:
    """Diagnosis of a machine without gears (``type = "shafts"``): the causes are the faults of
    its declared rolling bearings, judged by their lines (:mod:`gearvib.diagnosis.bearings`);
    nothing is simulated. The order profiles (measured, baseline) are kept for the report."""
    from gearvib.config import description_from_dict

    t0 = _time.perf_counter()
    rig = description_from_dict(cfg, base=base)
    ref = measured.member or rig.input
    fl = bearing_fault_lines(measured.to_measurement(), rig, channel=measured.channel,
                             reference=ref)
    if fl is None:
        raise ConfigError(f"diagnosis: {rig.name!r} has no gears and declares no rolling "
                          "bearing; a machine without gears is diagnosed by its bearings' "
                          "lines: add [[rolling_bearing]] tables")
    names = ", ".join(b.name for b in rig.bearings())
    causes = rank_causes(bearing_causes(fl, threshold), threshold, families={}, mismatch={},
                         local_kinds=(), none_reason=(
                             f"no fault family of {names} is detected in the envelope "
                             "spectrum, and none is possible"))
    top_line = max(f.harmonics * f.order + f.sidebands * f.sideband_order for f in fl.families)

    def profile(r: Record, name: str) -> OrderProfile:
        rpm = np.abs(r.speed_rpm)
        nyq = 0.45 * r.fs / (float(rpm.max()) / 60.0)
        return order_profile(r.signal, r.fs, rpm, max_order=min(nyq, 1.3 * top_line + 2.0),
                             revolutions=revolutions, name=name, units=r.units)

    meas = profile(measured, "measured")
    base_prof = profile(baseline, "baseline") if baseline is not None else meas
    n = min(meas.order.size, base_prof.order.size)

    def cut(p: OrderProfile) -> OrderProfile:
        return first_bins(p, n)

    meas, base_prof = cut(meas), cut(base_prof)
    d_meas = prominence_db(meas) - prominence_db(base_prof)
    lead = causes[0]
    nxt = []
    if lead.verdict != "likely" and any(c.verdict == "possible" for c in causes):
        nxt.append("a longer record (finer envelope spectrum, lower chance of a coincidence) "
                   "and a sensor nearer the bearing")
    notes = [f"{rig.name} is a machine without gears: the causes are the faults of its "
             "declared rolling bearings, judged by their lines in the envelope spectrum; "
             "nothing is simulated", *fl.notes]
    if baseline is not None:
        notes.append("the baseline's order profile is shown; the bearing check uses the "
                     "measurement alone")
    attrs = {"gear_set": config, "speed_member": ref,
             "baseline": "measured" if baseline is not None else "none (machine without gears)",
             "machine": "shafts and rolling bearings, no gears"}
    d = Diagnosis(causes, threshold, meas.order, meas, base_prof, d_meas,
                  deadband_db(d_meas), {}, [], nxt, notes, ref, attrs, line_check=fl)
    d.timing = {"simulation_s": 0.0, "total_s": _time.perf_counter() - t0}
    return d
