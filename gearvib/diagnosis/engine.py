"""Simulation in the loop: simulate every candidate fault and score it against a measurement.

:func:`diagnose` takes a measured housing signal with the speed of a shaft, the healthy gear set
(of any type: planetary sets, parallel stages, trains) and optionally a measured healthy
baseline, simulates the healthy gear set and every candidate fault
(:mod:`gearvib.diagnosis.candidates`) through the sweep machinery (one case per candidate, all
cores, run files reused when the same diagnosis runs again) and ranks the candidates with
:mod:`analysis.diagnosis`. The orders are counted on :func:`order_reference`; every member's
fault lines, rotation and mesh come from the kinematic catalogue in those orders.
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import os
import tempfile
import time as _time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from analysis.checks import require_instance
from analysis.diagnosis import (
    DEFAULT_REVOLUTIONS,
    DEFAULT_THRESHOLD,
    Cause,
    Diagnosis,
    OrderProfile,
    deadband_db,
    dynamic_range_db,
    family_evidence,
    impulse_mismatch_db,
    near_modes,
    order_locking,
    order_profile,
    prominence_db,
    rising_peaks,
    shaft_line_mask,
    sideband_ratios,
    signature_score,
    with_noise_floor,
)
from analysis.diagnosis_impacts import MIN_REVOLUTIONS
from gearvib import tempfiles
from gearvib.checks import check_count, check_path, check_real, short
from gearvib.config import ConfigError
from gearvib.diagnosis.bearings import bearing_causes, bearing_fault_lines
from gearvib.diagnosis.candidates import (
    KINDS,
    LOCAL_KINDS,
    Candidate,
    candidate_faults,
    candidate_members,
    severity_text,
)
from gearvib.diagnosis.cases import ProfileJob, ProfileSettings, profile_case
from gearvib.diagnosis.impacts import member_impacts
from gearvib.diagnosis.library import default_library, entry_key, library_folder, load_entry
from gearvib.diagnosis.lines import (
    MemberLines,
    cause_family,
    family_table,
    kinematics,
    member_lines,
    order_reference,
)
from gearvib.diagnosis.record import Record
from gearvib.diagnosis.rig import diagnose_rig, first_bins
from gearvib.diagnosis.verdict import LOCAL_FAULT, rank_causes
from gearvib.execution import MAX_WORKERS
from gearvib.simulation.conditions import MAX_DURATION

__all__ = ["ASSUMED_SENSORS", "Record", "diagnose", "order_reference"]

_FLAT = [{"frequency_hz": 5.0, "damping_ratio": 0.7, "gain": 1.0}]
ASSUMED_SENSORS = (
    {"name": "hann60", "angle_deg": 90.0, "window": "hann", "width_deg": 60.0,
     "housing_modes": _FLAT},
    {"name": "hann120", "angle_deg": 90.0, "window": "hann", "width_deg": 120.0,
     "housing_modes": _FLAT},
    {"name": "exp30", "angle_deg": 90.0, "window": "exponential", "width_deg": 30.0,
     "housing_modes": _FLAT},
    {"name": "exp70", "angle_deg": 90.0, "window": "exponential", "width_deg": 70.0,
     "housing_modes": _FLAT},
)
"""Transfer paths the simulations assume: accelerometers with Hann and exponential windows
of several widths and a housing response that is flat (1 kg-1) above 10 Hz (a heavily damped
mode at 5 Hz). A spectrum's prominence is taken as the largest over these paths: what a
healthy gearbox can show through any of them is not counted as a fault."""

MESH_HARMONICS = 5.5
"""Analysed band: up to 5.5 mesh harmonics (limited by the sample rate)."""

SKIP_S = 0.2
"""Start-up transient left out of every simulation [s]."""

SIM_SEGMENTS = 3
"""Averaged segments of every simulated profile: a candidate is simulated over
``revolutions * (SIM_SEGMENTS + 1) / 2`` carrier revolutions (50 % overlap) plus one of
margin and the start-up, whatever the record's length (``docs/diagnosis.md``)."""

MAX_REVOLUTIONS = 10_000
"""Most carrier revolutions per profile segment (``revolutions``)."""

SPEED_STEP = 0.005
"""Relative grid of the simulated mean speed: records within +-0.25 % share candidates."""

SPAN_STEP = 0.01
"""Grid of the simulated speed span (end - start) relative to the mean speed: a record whose
fitted ramp spans less than 0.5 % of its speed is simulated at constant speed."""


def operating_point(start_rpm: float, end_rpm: float) -> tuple[float, float]:
    """The simulated input speeds (start, end) [min-1] of a measured ramp.

    The mean speed is rounded to the nearest point of a geometric grid of step
    :data:`SPEED_STEP` (0.5 %), the span ``(end - start) / mean`` to a multiple of
    :data:`SPAN_STEP`: records of one operating point share their candidates (the library
    key), however long they are and within +-0.25 % of speed. The results are exact
    functions of the two grid indices, rounded to 0.001 min-1.

    Raises
    ------
    ValueError
        A speed that is not finite or not > 0 (at either end, also after rounding).
    """
    lo = min(start_rpm, end_rpm)
    if not (math.isfinite(start_rpm) and math.isfinite(end_rpm) and lo > 0):
        raise ValueError("diagnosis: the measured speed profile reaches standstill; give a "
                         "record at speed")
    mean = 0.5 * (start_rpm + end_rpm)
    step = math.log1p(SPEED_STEP)
    k = round(math.log(mean) / step)
    j = round((end_rpm - start_rpm) / mean / SPAN_STEP)
    m = math.exp(k * step)
    start, end = round(m * (1 - j * SPAN_STEP / 2), 3), round(m * (1 + j * SPAN_STEP / 2), 3)
    if min(start, end) <= 0:
        raise ValueError("diagnosis: the measured speed profile reaches standstill; give a "
                         "record at speed")
    return start, end


def simulated_duration(start_rpm: float, end_rpm: float, input_per_carrier: float,
                       revolutions: int) -> float:
    """Length [s] of a candidate run: :data:`SIM_SEGMENTS` profile segments of
    ``revolutions`` carrier revolutions (50 % overlap), one revolution of margin and the
    start-up :data:`SKIP_S`, on the ramp ``start -> end`` (input speeds, min-1), rounded up
    to 0.01 s."""
    revs = revolutions * (SIM_SEGMENTS + 1) / 2 + 1
    fc_mean = 0.5 * (start_rpm + end_rpm) / input_per_carrier / 60.0
    return math.ceil(100.0 * revs / fc_mean) / 100.0 + SKIP_S


def _library(library: str | os.PathLike | bool | None,
             stack: contextlib.ExitStack) -> Path:
    """The folder of this code's library entries (a temporary one for ``library=False``)."""
    if library is False:
        return library_folder(stack.enter_context(tempfile.TemporaryDirectory(
            prefix="gearvib-diagnosis-")))
    if library is None or library is True:
        try:
            return library_folder(default_library())
        except PermissionError as exc:
            warnings.warn(f"{exc}; the candidates are simulated without a library",
                          RuntimeWarning, stacklevel=3)
            return _library(False, stack)
    return library_folder(library)


def entry_description(cfg: dict, base: Path | None, fault: list[dict], sensors: list[dict],
                      run: dict, settings: ProfileSettings) -> dict:
    """What the order profiles of one simulated candidate depend on (a library entry's key):
    the healthy gear-set description (its ``[[sensor]]`` tables replaced by the assumed
    ones) and its folder, the fault, the assumed sensors, the run and profile settings."""
    desc = {k: v for k, v in cfg.items() if k != "sensor"}
    return {"what": "gearvib diagnosis candidate profiles", "gearset": desc,
            "gearset_dir": str(base.resolve()) if base is not None else "",
            "fault": fault, "sensors": sensors, "run": run, "profile": settings.describe()}


def _candidate_profiles(config: str, cfg: dict, base: Path | None,
                        candidates: list[Candidate], run: dict, sensors: list[dict],
                        settings: ProfileSettings, folder: Path, work_dir: Path | None,
                        keep_runs: bool, workers: int | None, progress: bool
                        ) -> tuple[list[list[OrderProfile]], np.ndarray, dict[str, int]]:
    """Order profiles of the healthy set and every candidate, from the library or simulated.

    Entries found in the library ``folder`` are read; the others are simulated through
    :func:`gearvib.sweep.run_sweep` (one case per missing candidate; the assumed sensors
    replace the description's ``[[sensor]]`` tables), each worker computing the profiles of
    its run and writing them into the library (:func:`gearvib.diagnosis.cases.profile_case`).
    Either way the profiles come from the stored entries, so a diagnosis that finds them
    gives the same numbers, bit for bit, as the one that simulated them.

    Returns the profiles (per case, per sensor), the healthy model's natural frequencies [Hz]
    and the counts ``{"simulated", "reused"}``.
    """
    from gearvib.sweep import Parameter, Sweep, run_sweep

    faults: list[list[Any]] = [[]] + [[c.fault] for c in candidates]
    labels = ["healthy"] + [c.label for c in candidates]
    entries = [entry_key(entry_description(cfg, base, f, sensors, run, settings))
               for f in faults]
    data: list[Any] = [load_entry(folder, k, t) for k, t in entries]  # None: loaded below
    missing = [i for i, d in enumerate(data) if d is None]
    counts = {"simulated": 0, "reused": len(faults) - len(missing)}
    if missing:
        sweep = Sweep(base=config, parameters=(
            Parameter("fault", tuple(faults[i] for i in missing),
                      tuple(labels[i] for i in missing)),
            Parameter("sensor", (list(sensors),), ("assumed sensors",))),
            simulation=dict(run), title="gearvib diagnosis: candidate faults",
            max_cases=10_000)
        job = ProfileJob(settings, str(folder), tuple(entries[i] for i in missing), keep_runs)
        with contextlib.ExitStack() as stack:
            out = work_dir if work_dir is not None else Path(stack.enter_context(
                tempfile.TemporaryDirectory(prefix="gearvib-diagnosis-sweep-")))
            try:
                result = run_sweep(sweep, out, workers=workers, progress=progress,
                                   report=False, runner=functools.partial(profile_case, job))
            except BaseException:  # an interrupt: the stopped workers' temporary entries
                tempfiles.remove_stale(folder)
                raise
        if result.failed:
            i = result.failed[0]
            raise RuntimeError(f"diagnosis: the simulation of {labels[missing[i]]!r} failed: "
                               f"{result.dataset['failure'].values[i]}")
        counts["simulated"] = len(result.simulated)
        for i in missing:
            data[i] = load_entry(folder, *entries[i])
            if data[i] is None:
                raise RuntimeError(f"diagnosis: the library entry of {labels[i]!r} in {folder} "
                                   "was not written (is the folder shared with another "
                                   "diagnosis that removed it?)")
    n = min(d["order"].size for d in data)
    order = data[0]["order"][:n]
    profiles = [[OrderProfile(order, d["amplitude"][k, :n], "m s-2", settings.revolutions,
                              int(d["segments"]), (0.0, 0.0, 0.0), lab)
                 for k in range(d["amplitude"].shape[0])]
                for d, lab in zip(data, labels, strict=True)]
    return profiles, data[0]["natural_frequency"], counts


def _fit_ramp(t: np.ndarray, rpm: np.ndarray) -> tuple[float, float]:
    """Start and end speed of the straight line fitted to a speed record."""
    t = t - t[0]
    if t[-1] <= 0:
        return float(rpm[0]), float(rpm[0])
    a, b = np.polyfit(t, rpm, 1)
    return float(b), float(b + a * t[-1])


KIND_WEIGHT = 0.1
"""Score per dB of impulse mismatch (:func:`analysis.diagnosis.impulse_mismatch_db`) by which
a local tooth-fault kind falls behind the best-matching kind of its member
(``docs/diagnosis.md``)."""


def _local_kind_scores(best: dict[tuple[str, str], tuple[float, Candidate]],
                       candidates: list[Candidate], profiles: list[list[OrderProfile]],
                       meas: OrderProfile, lines: dict[str, MemberLines]
                       ) -> tuple[dict[tuple[str, str], float], dict[tuple[str, str], float]]:
    """Scores of the local tooth-fault kinds of each member, ranked by their impulse.

    Crack, pitting and a broken tooth of one member put lines at the same orders; the
    cosine score tells them apart by small margins. The shape of their sideband pattern
    (:func:`analysis.diagnosis.sideband_ratios`) differs with the width and form of the
    fault's impulse: each kind's mismatch (best variant, dB) against the measured pattern
    lowers its score by :data:`KIND_WEIGHT` per dB behind the best kind of the member; then
    all local kinds of the member are shifted so that the best keeps the member's best
    cosine score (the member's and the class's score, and so the threshold decision, are
    unchanged).

    Returns the adjusted scores and the mismatches [dB] per (kind, member).
    """
    by_label = dict(zip((c.label for c in candidates), profiles, strict=True))
    meas_cache: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    mism: dict[tuple[str, str], float] = {}
    for c in candidates:
        if c.cause not in LOCAL_KINDS:
            continue
        ln = lines.get(c.member)
        f = ln.fault if ln is not None else None
        if ln is None or f is None or not ln.mesh > 0:
            continue
        mesh = ln.mesh
        if c.member not in meas_cache:
            meas_cache[c.member] = sideband_ratios(meas, f, mesh)
        rm, rn = meas_cache[c.member]
        if rm.size == 0:
            continue
        sims = [sideband_ratios(p, f, mesh, with_noise=False)[0] for p in by_label[c.label]]
        if any(x.shape != rm.shape for x in sims):
            continue
        v = impulse_mismatch_db(rm, rn, sims)
        key = (c.cause, c.member)
        if np.isfinite(v) and (key not in mism or v < mism[key]):
            mism[key] = v
    out: dict[tuple[str, str], float] = {}
    for mem in {m for _, m in mism}:
        keys = [k for k in mism if k[1] == mem and k in best]
        if len(keys) < 2:
            continue
        dmin = min(mism[k] for k in keys)
        adj = {k: best[k][0] - KIND_WEIGHT * (mism[k] - dmin) for k in keys}
        shift = max(best[k][0] for k in keys) - max(adj.values())
        for k in keys:
            out[k] = float(min(1.0, max(0.0, adj[k] + shift)))
    return out, mism


def diagnose(measured: Record, config: str, *, baseline: Record | None = None,
             library: str | os.PathLike | bool | None = None,
             work_dir: str | os.PathLike | None = None, keep_runs: bool = False,
             workers: int | None = None,
             kinds: tuple[str, ...] = KINDS, sensors: tuple[dict, ...] | list[dict] | None = None,
             revolutions: int = DEFAULT_REVOLUTIONS, threshold: float = DEFAULT_THRESHOLD,
             max_duration: float = 30.0, progress: bool = False) -> Diagnosis:
    """Rank the candidate causes of what a measurement shows beyond a healthy baseline.

    Parameters
    ----------
    measured : Record
        Housing signal and shaft speed of the gearbox under investigation.
    config : str
        The healthy gear set: preset name or TOML path (no ``[[fault]]`` tables).
    baseline : Record, optional
        A measurement of the healthy gearbox with the same sensor. Without it the healthy
        simulation is the baseline (the transfer path then differs; prominences absorb the
        slowly varying part of the difference).
    library : path-like, bool or None
        Folder of the candidate library (:mod:`gearvib.diagnosis.library`): the order
        profiles of candidates simulated before at the same operating point are read from it
        instead of being simulated, new ones are added. ``None`` (default):
        :func:`gearvib.diagnosis.library.default_library` (a private folder in the user's
        cache); ``False``: none (every candidate simulated, nothing kept).
    work_dir : path-like, optional
        Folder of the candidates' sweep (``sweep.nc``; with ``keep_runs`` the run files
        ``runs/*.nc``); default a temporary folder.
    keep_runs : bool
        Write every simulated candidate run to ``work_dir/runs`` (and reuse the run files
        found there); needs ``work_dir``.
    workers : int, optional
        Local worker processes of the sweep (default all CPUs).
    kinds : tuple of str
        Fault kinds considered.
    sensors : tuple of dict, optional
        The ``[[sensor]]`` tables the simulations assume (default :data:`ASSUMED_SENSORS`);
        a simulated spectrum's prominence is the largest over them.
    revolutions : int
        Carrier revolutions per averaged segment (resolution ``1/revolutions`` orders).
    threshold : float
        Score above which a cause is likely, in (0, 1).
    max_duration : float
        The measured speed profile is fitted by a ramp over at most its first
        ``max_duration`` seconds [s].

    Returns
    -------
    analysis.diagnosis.Diagnosis

    Notes
    -----
    The candidates are simulated at the operating point of the record
    (:func:`operating_point`: a fitted ramp on a 0.5 % speed grid) over
    :data:`SIM_SEGMENTS` profile segments (:func:`simulated_duration`), not over the whole
    record: their profiles do not depend on the record's length, so a library entry serves
    every record of the operating point (``docs/diagnosis.md``).
    """
    from gearvib.config import load_config

    t0 = _time.perf_counter()
    require_instance(measured, Record, "measured")
    if baseline is not None:
        require_instance(baseline, Record, "baseline")
    if not isinstance(config, str | os.PathLike):
        raise TypeError(f"config must be a preset name or a file; got {type(config).__name__}")
    if library is not None and not isinstance(library, bool):
        check_path(library, "library")
    if work_dir is not None:
        check_path(work_dir, "work_dir")
    for flag_name, flag in (("keep_runs", keep_runs), ("progress", progress)):
        if not isinstance(flag, bool):
            raise TypeError(f"{flag_name} must be True or False; got {short(flag)}")
    if workers is not None:
        check_count(workers, "workers", low=1, high=MAX_WORKERS)
    if sensors is not None and (isinstance(sensors, str) or not isinstance(
            sensors, list | tuple) or not all(isinstance(t, dict) for t in sensors)):
        raise TypeError(f"sensors must be a list of [[sensor]] tables (dicts); got "
                        f"{short(sensors)}")
    check_count(revolutions, "revolutions", low=1, high=MAX_REVOLUTIONS)
    check_real(max_duration, "max_duration [s]", low=0.01, high=MAX_DURATION)
    check_real(threshold, "threshold")
    if not 0.0 < float(threshold) < 1.0:
        raise ValueError(f"threshold = {threshold!r} is not admissible (admissible: 0 < "
                         "threshold < 1)")
    if keep_runs and work_dir is None:
        raise ValueError("keep_runs = True needs work_dir (the folder of the run files)")
    cfg, base = load_config(config)
    if cfg.get("type") == "shafts":  # a machine without gears: its bearings' lines only
        return diagnose_rig(measured, cfg, base, config=str(config), baseline=baseline,
                             threshold=float(threshold), revolutions=int(revolutions))
    candidates = candidate_faults(cfg, kinds, base=base)
    kin = kinematics(cfg, base)
    ms = kin.ms
    input_member = kin.gs.input
    member = measured.member or input_member
    ratio = kin.ratio(member)
    members = candidate_members(kin.gs, kin.model)
    lines = member_lines(kin.cat, ms, members, kin.model)
    meshes = [ln.mesh for ln in lines.values() if ln.mesh > 0]
    if not meshes:
        raise ConfigError("diagnosis: the gear set has no meshes with tooth numbers")
    mesh = max(meshes)  # the band reaches MESH_HARMONICS harmonics of the fastest mesh
    max_order = MESH_HARMONICS * mesh
    c_rpm = np.abs(measured.speed_rpm) * ratio
    meas = order_profile(measured.signal, measured.fs, c_rpm, max_order=max_order,
                         revolutions=revolutions, name="measured", units=measured.units)
    max_order = float(meas.order[-1])
    # the operating point: the measured speed profile fitted by a ramp of the input member,
    # on the grid of the library (records of one operating point share candidates)
    t = np.arange(measured.signal.size) / measured.fs
    n_use = min(t.size, int(max_duration * measured.fs))
    in_rpm = np.abs(measured.speed_rpm[:n_use]) * ratio * abs(ms[input_member])
    start, end = operating_point(*_fit_ramp(t[:n_use], in_rpm))
    input_per_carrier = abs(ms[input_member])
    full_order = MESH_HARMONICS * mesh
    fc_max = max(start, end) / input_per_carrier / 60.0
    fs_out = float(max(5000.0, 1000.0 * np.ceil(2.6 * full_order * fc_max * 1.05 / 1000.0)))
    run = {"speed_start_rpm": start, "speed_end_rpm": end,
           "duration": simulated_duration(start, end, input_per_carrier, int(revolutions)),
           "fs_out": fs_out}
    sim_t0 = _time.perf_counter()
    sensors = [dict(x) for x in (sensors or ASSUMED_SENSORS)]
    settings = ProfileSettings(tuple(x["name"] for x in sensors), 1.0 / input_per_carrier,
                               full_order, int(revolutions), SKIP_S)
    with contextlib.ExitStack() as stack:
        folder = _library(library, stack)
        profiles, natural_hz, counts = _candidate_profiles(
            config, cfg, base, candidates, run, sensors, settings, folder,
            None if work_dir is None else Path(work_dir), keep_runs, workers, progress)
    sim_time = _time.perf_counter() - sim_t0
    if baseline is not None:
        b_ratio = kin.ratio(baseline.member or input_member)
        base_prof = order_profile(baseline.signal, baseline.fs,
                                  np.abs(baseline.speed_rpm) * b_ratio, max_order=max_order,
                                  revolutions=revolutions, name="baseline",
                                  units=baseline.units)
    else:
        base_prof = profiles[0][0]
    n = min(p.order.size for p in [meas, base_prof, *(q for ps in profiles for q in ps)])
    order = meas.order[:n]

    def cut(p: OrderProfile) -> OrderProfile:
        return first_bins(p, n)

    def prom(p: OrderProfile) -> np.ndarray:
        return prominence_db(cut(p))

    # the simulations get the measurement's dynamic range: what lies under its noise floor
    # is not a rise it could show
    meas_range = dynamic_range_db(cut(meas))

    def envelope(ps: list[OrderProfile]) -> np.ndarray:
        return np.max([prominence_db(with_noise_floor(cut(p), meas_range)) for p in ps],
                      axis=0)

    p_h = envelope(profiles[0])
    p_meas = prom(meas)
    p_base = prom(base_prof) if baseline is not None else p_h
    d_meas = p_meas - p_base
    dead = deadband_db(d_meas)
    signatures = {c.label: envelope(ps) - p_h
                  for c, ps in zip(candidates, profiles[1:], strict=True)}
    # the shafts' own lines (1x, 2x: unbalance, misalignment) are no evidence of a gear fault
    shafts = shaft_line_mask(order, [v for k, v in ms.items() if k != "ground"])
    scores = {lab: signature_score(d_meas, sig, deadband=dead, exclude=shafts)
              for lab, sig in signatures.items()}
    fams = family_table(lines, members, max_order)
    fam_ev = family_evidence(order, d_meas, dead, fams)
    fam_by = {f.family: f for f in fam_ev}
    # the local faults' impacts: their rate in the envelope, their comb above the mesh band
    impacts, impact_by = member_impacts(measured.signal[:n_use], measured.fs, c_rpm[:n_use],
                                        lines=lines, members=members, ms=ms, model=kin.model,
                                        name=measured.name)
    peaks = rising_peaks(order, d_meas, dead)
    # strongest rises first
    strength = np.interp(peaks, order, d_meas) if peaks.size else np.array([])
    top_peaks = peaks[np.argsort(-strength)][:10] if peaks.size else peaks
    fc_mean = meas.speed_rpm[1] / 60.0
    natural = {f"f{i + 1}": float(f) for i, f in enumerate(np.atleast_1d(natural_hz))
               if np.isfinite(f)}
    mode_notes = near_modes(top_peaks, fc_mean, natural)
    locking = order_locking(meas, measured.signal, measured.fs, c_rpm, top_peaks)
    # one entry per (cause, member): the best-scoring variant
    best: dict[tuple[str, str], tuple[float, Candidate]] = {}
    for c in candidates:
        s = scores[c.label]
        key = (c.cause, c.member)
        if key not in best or s > best[key][0]:
            best[key] = (s, c)
    kind_scores, mismatch = _local_kind_scores(
        best, candidates, [[cut(p) for p in ps] for ps in profiles[1:]], cut(meas), lines)
    groups = {m.name for m in members if m.interchangeable}
    causes = []
    cause_fams: dict[tuple[str, str], Any] = {}
    for (cause, mem), (s, c) in best.items():
        s = kind_scores.get((cause, mem), s)
        sig = signatures[c.label]
        sig_rises = order[sig > 3.0]
        found = 0
        if sig_rises.size:
            found = int(np.sum(np.interp(sig_rises, order, d_meas) > dead))
        ev = [f"simulated {severity_text(c)} on {c.fault['member']}: score {s:.2f}",
              f"the measurement rises above the noise deadband ({dead:.1f} dB) at {found} of "
              f"the {sig_rises.size} orders where the simulation rises by more than 3 dB"]
        if (cause, mem) in mismatch:
            ev.append(f"sideband pattern of the fault impulse (sidebands over their mesh "
                      f"harmonic, shape): {mismatch[(cause, mem)]:.1f} dB from the measured one "
                      f"(cosine score {best[(cause, mem)][0]:.2f})")
        fe = fam_by.get(cause_family(cause, lines[mem])) if mem in lines else None
        cause_fams[(cause, mem)] = fe
        if fe is not None:
            ev.append(fe.text())
        if (cause, mem) in impact_by and impact_by[(cause, mem)].lines:
            ev.append(impact_by[(cause, mem)].text())
        if mem in groups:
            ev.append("the planets are interchangeable (equally spaced): which planet cannot "
                      "be told without a carrier phase reference")
        causes.append(Cause(cause, mem, float(s), tuple(ev), c.label))
    fault_lines = None
    if kin.gs.rolling_bearings:  # the declared bearings, judged by their lines
        fault_lines = bearing_fault_lines(measured.to_measurement(), kin.gs,
                                          channel=measured.channel, reference=member,
                                          model=kin.model)
        if fault_lines is not None:
            causes.extend(bearing_causes(fault_lines, float(threshold)))
    causes = rank_causes(causes, float(threshold), families=cause_fams, mismatch=mismatch,
                         local_kinds=LOCAL_KINDS, impacts=impact_by, none_evidence=(
                             f"{peaks.size} rising peaks above the noise deadband of "
                             f"{dead:.1f} dB",))
    lead = causes[0]
    weak = lead.verdict != "likely"
    close = (len(causes) > 1 and causes[1].cause != "none" and lead.cause != "none"
             and lead.score - causes[1].score < 0.05)
    # what to measure next
    nxt = []
    if weak or close:
        lo, mean, hi = meas.speed_rpm
        if (hi - lo) / mean < 0.03:
            nxt.append("a run-up over the operating range: it tells order-locked features "
                       "(gear faults) from resonances")
        if meas.segments < 4:
            nxt.append(f"a longer record: {meas.segments} averaged segments of {revolutions} "
                       f"{kin.reference} revolutions; 8 or more halve the noise deadband")
        if baseline is None:
            nxt.append("the same sensor on the gearbox in a known healthy state (--baseline): "
                       "removes the difference between the real and the assumed transfer path")
        if dead > 6.0:
            nxt.append(f"a quieter signal (noise deadband {dead:.1f} dB): a sensor closer to "
                       "the ring gear, more averaging or a higher load")
        if lead.cause != "none" and any(c.member in groups for c in causes[:2]):
            nxt.append("a once-per-revolution carrier tacho to tell which planet")
    local = [c for c in causes if c.member == lead.member and c.cause in LOCAL_KINDS]
    if ((lead.cause in LOCAL_KINDS or lead.cause == LOCAL_FAULT) and len(local) > 1
            and (lead.cause == LOCAL_FAULT or local[0].score - local[1].score < 0.1)):
        nxt.append(f"an inspection of {lead.member} (borescope, oil debris): the kind of "
                   f"local tooth fault ({local[0].cause} or {local[1].cause}) differs in "
                   "the spectrum mainly by its size and impulse shape, which an unknown "
                   "transfer path hides")
    if close and not nxt:
        nxt.append("a second sensor position and another load: the leading causes differ "
                   "little on this record")
    if impacts is None:
        impact_note = (f"tooth-fault impacts: not checked (the record covers fewer than "
                       f"{MIN_REVOLUTIONS + 1} {kin.reference} revolutions)")
    else:
        detected = [e.family for e in impacts.evidence if e.detected]
        impact_note = (f"tooth-fault impacts (envelope without the mesh lattice; comb above "
                       f"the mesh band, orders {impacts.band[0]:.0f}-{impacts.band[1]:.0f}): "
                       + (f"detected for {', '.join(detected)}" if detected
                          else "none detected"))
    notes = [f"order locking: {locking}", *mode_notes, impact_note,
             f"resolution {1 / revolutions:.4g} {kin.reference} orders, {meas.segments} "
             f"segments, band up to order {max_order:.0f} ({max_order / mesh:.1f} mesh "
             "harmonics" + (" of the fastest mesh)" if len(set(meshes)) > 1 else ")"),
             f"{len(candidates)} candidate faults and the healthy set simulated over "
             f"{run['duration']:g} s at {run['speed_start_rpm']:g} -> "
             f"{run['speed_end_rpm']:g} min-1 (input)"]
    top = next((c for c in causes if c.cause != "none"), None)
    # the mesh the report's spectrum zooms into: that of the leading cause's member
    shown = lines[top.member].mesh if top is not None and top.member in lines else mesh
    attrs = {"gear_set": str(config), "speed_member": member, "mesh_order": float(shown),
             "mesh_orders_json": json.dumps(sorted(set(meshes))),
             "simulated_speed_rpm": f"{run['speed_start_rpm']} -> {run['speed_end_rpm']}",
             "simulated_duration_s": run["duration"],
             "assumed_sensors_json": json.dumps(sensors),
             "baseline": "measured" if baseline is not None else "simulated healthy gear set",
             "candidates_json": json.dumps([c.fault for c in candidates])}
    d = Diagnosis(causes, float(threshold), order, cut(meas), cut(base_prof), d_meas, dead,
                  signatures, fam_ev, nxt, notes, kin.reference, attrs,
                  line_check=fault_lines)
    # timing: not part of the report or the Dataset (same input, same output)
    d.timing = {"simulation_s": sim_time, "total_s": _time.perf_counter() - t0, **counts}
    return d
