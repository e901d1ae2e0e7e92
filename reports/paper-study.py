"""The paper-reproduction study of issue #16 (write-up: ``reports/paper-study.md``).

Which values of the parameters the paper does not give (mesh damping, stiffness-variation shape
and amplitude, contact ratio, tooth geometry, drive, run-up rate, load) reproduce the resonance
speeds of its Figures 7 and 11 (1500, 2600 and 3100 min^-1, orders 1-7) and its
case-1-vs-case-2 finding?

Every sweep is a ``gearvib sweep`` description in ``reports/paper-study/sweep-*.toml`` whose
first parameter is the planet arrangement (paper case 1 / case 2), so every combination of the
other parameters is run for both cases. This script runs them through the public sweep API,
measures every run with the metrics defined below (public analysis API only) and draws the
figures of the write-up::

    python reports/paper-study.py run      [--out DIR] [--workers N] [SWEEP ...]
    python reports/paper-study.py metrics  [--out DIR] [SWEEP ...]  # -> metrics.csv, forcing.csv
    python reports/paper-study.py figures  [--out DIR]              # -> fig-*.png
    python reports/paper-study.py all      [--out DIR] [--workers N]
    python reports/paper-study.py all --quick    # only the key sweeps (4 runs, about 20 s)

The whole study (10 sweeps, 170 runs of 1 s) took 343-489 s on 2 busy shared cores (about
150 CPU-seconds).
``DIR`` (default ``paper-study-out``) holds the run files (about 5 MB each); the metrics table,
the forcing table and the figures are small, committed, and the same byte for byte on every
run. A sweep resumes: finished runs are read, not simulated again.

Metrics (all on the signed normal force of the sun-planet1 mesh, drive flank positive, as in
the report's sonogram):

* **order tracks** ``L_k(n)``: rms level of mesh orders ``k = 1..7`` against input speed
  ``n`` [dB re 1 N] (:func:`analysis.orders.order_cuts`, mesh-angle reference, Hann, 0.1-order
  resolution = frames of 10 mesh cycles, 75 % overlap); a band reaching above 0.3 ``fs_out``
  (where the output's anti-alias filter stops being flat) is left out (NaN).
* **rise at a paper speed** ``R_k(s)``: the maximum of ``L_k`` within ``|n - s| <= 5 % s``
  minus the median of ``L_k`` over the surroundings ``5 % s < |n - s| <= 25 % s`` (speeds
  below 600 min^-1 left out).
* **resonant orders at s**, ``N(s)``: orders with ``R_k(s) >= 6 dB`` (the rise the report's
  resonance detection counts). The paper: orders 1-7 at 1500 min^-1, and resonances at 2600
  and 3100 min^-1. **Paper score** = number of paper speeds with ``N(s) >= 2`` (0..3).
* **dominance** ``D``: the largest overall level (energy sum of the order tracks) inside the
  three +-5 % windows minus the largest outside them (600-4000 min^-1) [dB]; > 0 when the
  run's strongest response is at a paper speed. ``peak_rpm``: speed of the largest level.
* **case 2 against case 1** (same parameters): ``dL`` = mean over orders 1-7 and speeds
  600-4000 min^-1 of ``L_k(case 2) - L_k(case 1)`` [dB] (absolute loudness); the report's
  resonance regions (:func:`gearvib.report.analyse_case`, :func:`gearvib.report.compare_cases`:
  count and energy sum of the region strengths, and its "fewer or weaker" verdict); and the
  **planet-mode spots** of case 2: detected rises within 3 % of the planet-mode frequency
  (f3 = f4). **Case finding** = ``dL < 0`` and fewer-or-weaker and planet spots > 0.
* **plausible**: largest dynamic factor ``K_v <= 10`` and contact loss ``<= 20 %`` of the run
  in both cases (``sweep.nc``). A run outside (a lightly damped drive or a large stiffness
  amplitude let the teeth rattle: ``K_v`` of 250-390) lights up every order everywhere; its
  "resonances" say nothing about the paper's, so it is not counted as a match.
* **match** (plausible sets only): ``N(1500) >= 2``, paper score 3 and the case finding.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from analysis.orders import order_cuts

HERE = Path(__file__).resolve().parent / "paper-study"
PAPER_SPEEDS = (1500.0, 2600.0, 3100.0)
ORDERS = np.arange(1.0, 8.0)
WINDOW = 0.05  # +-5 % speed window around a paper speed
SURROUND = 0.25  # the background of a window: the speeds 5-25 % away from it
RISE_DB = 6.0  # rise above the background that counts as a resonance of an order (as the report)
KV_MAX = 10.0  # above: the teeth rattle (plausibility gate)
CONTACT_LOSS_MAX = 0.2
QUICK = ("key-preset", "key")  # the sweeps of --quick (and of the run figures)
LOW_RPM = 600.0  # speeds below are left out (orders overlap, start transient)
FORCE_MESH = "sun-planet1"
PASSBAND = 0.3  # of fs_out: the flat part of the output's decimation filter
CASE_LABELS = ("case 1", "case 2")


# --------------------------------------------------------------------------------- metrics


def signed_force(ds: xr.Dataset, mesh: str = FORCE_MESH) -> np.ndarray:
    """Normal force of a mesh, drive (left) flank positive, back flank negative [N]."""
    f = ds["normal_force"].sel(mesh=mesh)
    return np.asarray(f.sel(flank="left").values - f.sel(flank="right").values, dtype=float)


def order_tracks(ds: xr.Dataset, mesh: str = FORCE_MESH, resolution: float = 0.1,
                 overlap: float = 0.75) -> tuple[np.ndarray, np.ndarray]:
    """Levels of mesh orders 1..7 against input speed.

    Returns
    -------
    rpm : ndarray, shape (n_frames,)
        Input speed at the frame centres [min^-1].
    levels : ndarray, shape (7, n_frames)
        rms level [dB re 1 N]; NaN where the order band leaves the flat pass band.
    """
    x = signed_force(ds, mesh)
    t = np.asarray(ds["time"].values, dtype=float)
    mesh_rpm = 60.0 * np.asarray(ds["mesh_frequency"].sel(mesh=mesh).values, dtype=float)
    inp = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
    moving = mesh_rpm >= 0.01 * mesh_rpm.max()
    first = int(np.argmax(moving))
    fs = float(ds.attrs["fs_out"])
    xs = x[first:] - x[first:].mean()
    cut = order_cuts(xs, None, mesh_rpm[first:], ORDERS, time=t[first:], window="hann",
                     resolution=resolution, overlap=overlap, samples_per_rev=24,
                     max_order=9.0, units="N")
    v = np.asarray(cut.values, dtype=float).copy()
    top = (ORDERS[:, None] + 0.5 * cut.bandwidth) * cut.rpm[None, :] / 60.0
    v[top > PASSBAND * fs] = np.nan
    with np.errstate(divide="ignore"):
        levels = 20.0 * np.log10(v)
    return np.interp(cut.time, t, inp), levels


def speed_metrics(rpm: np.ndarray, levels: np.ndarray,
                  speeds: Sequence[float] = PAPER_SPEEDS) -> dict:
    """Local rise ``R_k(s)`` and resonant orders ``N(s)`` at the given speeds.

    ``R_k(s)`` is the maximum of ``L_k`` within ``+-WINDOW s`` minus the median of ``L_k`` over
    the surroundings ``WINDOW s < |n - s| <= SURROUND s`` (both sides); an order is resonant
    at ``s`` when ``R_k(s) >= RISE_DB``.
    """
    out = {}
    for s in speeds:
        d = np.abs(rpm - s)
        inw = d <= WINDOW * s
        ring = (d > WINDOW * s) & (d <= SURROUND * s) & (rpm >= LOW_RPM)
        rise = np.full(levels.shape[0], np.nan)
        for k in range(levels.shape[0]):
            a, b = levels[k, inw], levels[k, ring]
            if np.isfinite(a).any() and np.isfinite(b).sum() >= 3:
                rise[k] = np.nanmax(a) - np.nanmedian(b)
        resonant = rise >= RISE_DB
        out[s] = {"rise": rise, "n_orders": int(resonant.sum()),
                  "orders": [int(k + 1) for k in np.flatnonzero(resonant)],
                  "best_rise": float(np.nanmax(rise)) if np.isfinite(rise).any() else math.nan}
    return out


def overall_level(levels: np.ndarray) -> np.ndarray:
    """Energy sum of the order tracks per frame [dB re 1 N]."""
    p = np.nansum(10.0 ** (levels / 10.0), axis=0)
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(np.where(p > 0, p, np.nan))


def dominance(rpm: np.ndarray, levels: np.ndarray,
              speeds: Sequence[float] = PAPER_SPEEDS) -> float:
    """Largest overall level inside the paper windows minus the largest outside [dB]."""
    o = overall_level(levels)
    ok = (rpm >= LOW_RPM) & np.isfinite(o)
    inside = np.zeros(rpm.shape, dtype=bool)
    for s in speeds:
        inside |= np.abs(rpm - s) <= WINDOW * s
    if not (ok & inside).any() or not (ok & ~inside).any():
        return math.nan
    return float(np.max(o[ok & inside]) - np.max(o[ok & ~inside]))


def run_metrics(ds: xr.Dataset) -> dict:
    """The per-run metrics of the study (see the module docstring)."""
    rpm, levels = order_tracks(ds)
    sm = speed_metrics(rpm, levels)
    row: dict = {}
    score = 0
    for s in PAPER_SPEEDS:
        m = sm[s]
        tag = f"{int(s)}"
        row[f"N_{tag}"] = m["n_orders"]
        row[f"orders_{tag}"] = " ".join(str(k) for k in m["orders"])
        row[f"rise_{tag}"] = round(m["best_rise"], 2)
        score += m["n_orders"] >= 2
    row["paper_score"] = int(score)
    row["dominance_db"] = round(dominance(rpm, levels), 2)
    ok = rpm >= LOW_RPM
    o = overall_level(levels)
    row["peak_rpm"] = round(float(rpm[ok][np.nanargmax(o[ok])]), 0)
    row["mean_level_db"] = round(float(np.nanmean(levels[:, ok])), 3)
    return row


def _analysis(ds: xr.Dataset):
    from gearvib.report import AnalysisSettings, analyse_case

    return analyse_case(ds, settings=AnalysisSettings(stability_points=120))


def planet_spots(ca) -> tuple[int, float]:
    """Detected rises within 3 % of the planet-mode frequency: count and strongest [dB]."""
    kinds = list(ca.modal.kinds) if ca.modal is not None else []
    fp = [f for f, k in zip(ca.modal.frequencies_hz, kinds, strict=True)
          if k == "planet"] if kinds else []
    if not fp:
        return 0, math.nan
    f0 = float(fp[0])
    r = ca.resonances
    sel = np.abs(np.asarray(r.frequency, dtype=float) - f0) <= 0.03 * f0
    return int(sel.sum()), (float(np.max(np.asarray(r.strength_db)[sel])) if sel.any()
                            else math.nan)


def pair_metrics(ds1: xr.Dataset, ds2: xr.Dataset) -> dict:
    """Case 2 against case 1 with the same other parameters."""
    from gearvib.report import compare_cases

    rpm1, l1 = order_tracks(ds1)
    rpm2, l2 = order_tracks(ds2)
    n = min(rpm1.size, rpm2.size)
    ok = rpm1[:n] >= LOW_RPM
    d = l2[:, :n][:, ok] - l1[:, :n][:, ok]
    ca1, ca2 = _analysis(ds1), _analysis(ds2)
    ca1.name, ca2.name = "case 1", "case 2"
    cmp = compare_cases(ca1, ca2)
    n_planet, s_planet = planet_spots(ca2)
    hits = [sum(any(r.rpm_low * (1 - WINDOW) <= s <= r.rpm_high * (1 + WINDOW)
                    for r in ca.regions) for s in PAPER_SPEEDS) for ca in (ca1, ca2)]
    return {
        "paper_regions_1": hits[0], "paper_regions_2": hits[1],
        "dL_db": round(float(np.nanmean(d)), 3),
        "regions_1": cmp.n_regions[0], "regions_2": cmp.n_regions[1],
        "strength_1_db": round(cmp.total_strength_db[0], 2),
        "strength_2_db": round(cmp.total_strength_db[1], 2),
        "fewer_or_weaker": bool(cmp.fewer_or_weaker),
        "planet_spots_2": n_planet,
        "planet_strength_2_db": round(s_planet, 2) if math.isfinite(s_planet) else math.nan,
        "regions_rpm_1": " ".join(f"{r.rpm_peak:.0f}" for r in ca1.regions),
        "regions_rpm_2": " ".join(f"{r.rpm_peak:.0f}" for r in ca2.regions),
    }


def plausible(row: dict) -> bool:
    """No rattling: ``K_v <= KV_MAX`` and contact loss ``<= CONTACT_LOSS_MAX`` in both cases."""
    return all(float(row[f"Kv_{t}"]) <= KV_MAX
               and float(row[f"contact_loss_{t}"]) <= CONTACT_LOSS_MAX for t in ("1", "2"))


def reproduces_case_finding(pair: dict) -> bool:
    """Case 2 quieter (dL < 0), fewer or weaker regions, planet modes still excited."""
    return bool(pair["dL_db"] < 0 and pair["fewer_or_weaker"] and pair["planet_spots_2"] > 0)


# -------------------------------------------------------------------------------- theory

def _trapezoid(ramp_sun: float, ramp_ring: float) -> dict:
    return {"sun": {"model": "trapezoidal", "k_min": 2.6667e7, "k_max": 4.3333e7, "ramp": ramp_sun},
            "ring": {"model": "trapezoidal", "k_min": 3.0e7, "k_max": 5.0e7, "ramp": ramp_ring}}


THEORY_SETS = (  # (label, preset, changes of the description as {key path: value})
    ("paper-case1 (preset)", "paper-case1", {}),
    ("rectangular x_s = +0.3", "paper-case1", {"geometry.profile_shift_sun": 0.3}),
    ("ramps 0.2/0.1 x_s = 0", "paper-case1",
     {"meshes.sun.stiffness": _trapezoid(0.2, 0.1)["sun"],
      "meshes.ring.stiffness": _trapezoid(0.2, 0.1)["ring"]}),
    ("z_p = 41", "paper-case1", {"geometry.z_planet": 41, "bodies.planet.inertia": 1.61e-3}),
    ("paper-case1-study", "paper-case1-study", {}),
    ("paper-case2 (preset)", "paper-case2", {}),
    ("paper-case2-study", "paper-case2-study", {}),
)


def _set_path(cfg: dict, path: str, value) -> None:
    keys = path.split(".")
    node = cfg
    for k in keys[:-1]:
        node = node[k]
    node[keys[-1]] = value


def mesh_forcing(preset: str, changes: dict | None = None, torque: float = 60.0,
                 mesh: int = 0, harmonics: int = 4, low_hz: float = 500.0) -> list[dict]:
    """Quasi-static forcing of every gear mode by every harmonic of the mesh stiffness.

    The static deflection ``x0`` under the input torque (mean stiffness ``K``, the model's
    balanced nominal load) meets the stiffness variation ``K(t) = K + sum_l (K_l e^{i l W t} +
    c.c.)`` (:meth:`gearvib.stability.PeriodicGearSystem.harmonics`): the force ``-K(t) x0``
    drives mode ``i`` (mass-normalised ``phi_i``, ``w_i``) at ``l`` times the mesh frequency,
    i.e. at the input speed where ``l f_mesh = f_i``. Returned per mode and harmonic: the
    quasi-static amplitude of that modal response in the force of mesh ``mesh`` (sun-planet1),
    ``F = 2 k_mesh |sum_i (v . phi_i) (phi_i^T K_l x0) / w_i^2|`` [N] (``v`` the mesh's line of
    action, the sum over a degenerate pair so that the result does not depend on its basis);
    at resonance it is amplified by about ``1 / (2 zeta)`` (less in a fast run-up).
    """
    import copy

    import scipy.linalg

    from gearvib.assembly import assemble
    from gearvib.config import gearset_from_dict, load_config
    from gearvib.stability import periodic_system

    cfg = copy.deepcopy(load_config(preset)[0])
    cfg.pop("simulation", None)
    for k, v in (changes or {}).items():
        _set_path(cfg, k, v)
    model = assemble(gearset_from_dict(cfg))
    k_bar = model.mean_stiffness_matrix()
    _, k_hat = periodic_system(model).harmonics(harmonics)
    x0 = np.linalg.lstsq(k_bar, torque * model.nominal_load(), rcond=None)[0]
    w2, phi = scipy.linalg.eigh(k_bar, model.mass)
    f = np.sqrt(np.abs(w2)) / (2.0 * math.pi)
    v = model.mesh_vectors[mesh]
    k_mesh = float(model.mean_mesh_stiffness()[mesh])
    rows = []
    elastic = np.flatnonzero(f > low_hz)
    for name, f0 in paper_mode_names(f[elastic], low_hz):
        group = [i for i in elastic if abs(f[i] - f0) <= 0.005 * f0]  # a degenerate pair: both
        for ell in range(1, harmonics + 1):
            resp = sum((v @ phi[:, i]) * (phi[:, i] @ k_hat[ell - 1] @ x0) / w2[i] for i in group)
            rows.append({"mode": name, "f_hz": round(float(f0), 1), "harmonic": ell,
                         "rpm": round(float(f0 / (ell * model.mesh_frequency_per_rpm)), 0),
                         "force_n": round(float(2.0 * k_mesh * abs(resp)), 3)})
    return rows


def write_forcing() -> Path:
    """:func:`mesh_forcing` of the :data:`THEORY_SETS` -> ``reports/paper-study/forcing.csv``."""
    rows = []
    for label, preset, changes in THEORY_SETS:
        rows += [{"set": label, **r} for r in mesh_forcing(preset, changes)]
    target = HERE / "forcing.csv"
    tmp = target.with_suffix(".tmp")
    with tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    tmp.replace(target)
    return target


# ------------------------------------------------------------------------------ the sweeps


def sweep_files(names: Sequence[str] = ()) -> list[Path]:
    """The study's sweep descriptions, in order (all, or those named ``sweep-<name>.toml``)."""
    files = sorted(HERE.glob("sweep-*.toml"))
    if names:
        want = {f"sweep-{n}.toml" if not n.startswith("sweep-") else n for n in names}
        want = {w if w.endswith(".toml") else w + ".toml" for w in want}
        files = [f for f in files if f.name in want]
        if not files:
            raise SystemExit(f"no sweep named {', '.join(names)} in {HERE}")
    return files


def sweep_name(path: Path) -> str:
    return path.stem.removeprefix("sweep-")


def run_sweeps(out: Path, workers: int, names: Sequence[str] = ()) -> None:
    """Run (or resume) every sweep into ``out/<name>``; failed cases are kept as failed."""
    from gearvib.sweep import load_sweep, run_sweep

    for path in sweep_files(names):
        res = run_sweep(load_sweep(path), out / sweep_name(path), workers=workers)
        ds = res.dataset
        print(f"{sweep_name(path)}: {ds.sizes['case']} cases, "
              f"{int((ds['status'].values != 'ok').sum())} failed", flush=True)


def open_sweep(out: Path, name: str) -> xr.Dataset:
    """``out/<name>/sweep.nc``, or a clear error naming the command that makes it."""
    path = out / name / "sweep.nc"
    if not path.is_file():
        raise SystemExit(f"no finished sweep {name!r} in {out} ({path} is missing): run "
                         f"'python reports/paper-study.py run {name} --out {out}' first")
    return xr.open_dataset(path)


def _parameter_columns(sw: xr.Dataset) -> list[str]:
    params = json.loads(sw.attrs["parameters_json"])
    return [p["path"] for p in params]


def _value(sw: xr.Dataset, name: str, i: int) -> str:
    v = sw[name].values[i]
    return f"{float(v):g}" if np.issubdtype(np.asarray(v).dtype, np.number) else str(v)


def _case_label(sw: xr.Dataset, column: str, i: int) -> str:
    """"case 1" (planets at 0/120/240 deg) or "case 2", from the planet-angle parameter."""
    angles = np.asarray(json.loads(str(sw[column].values[i]))
                        if str(sw[column].values[i]).startswith("[")
                        else sw[f"{column}.values"].values[i], dtype=float)
    return CASE_LABELS[0] if np.allclose(angles, [0.0, 120.0, 240.0]) else CASE_LABELS[1]


def sweep_rows(out: Path, name: str) -> list[dict]:
    """One metrics row per pair (case 1, case 2) of a finished sweep."""
    from gearvib.io import read_run

    sw = open_sweep(out, name)
    cols = _parameter_columns(sw)
    case_col, others = cols[0], cols[1:]
    key = {i: tuple(_value(sw, c, i) for c in others) for i in range(sw.sizes["case"])}
    label = {i: _case_label(sw, case_col, i) for i in range(sw.sizes["case"])}
    rows = []
    for i in range(sw.sizes["case"]):
        if label[i] != CASE_LABELS[0]:
            continue
        j = next(j for j in key if key[j] == key[i] and label[j] == CASE_LABELS[1])
        row = {"sweep": name, **{c: key[i][n] for n, c in enumerate(others)}}
        ok = [str(sw["status"].values[k]) == "ok" for k in (i, j)]
        row["status_1"], row["status_2"] = ("ok" if o else "failed" for o in ok)
        runs = []
        for k, good, tag in ((i, ok[0], "1"), (j, ok[1], "2")):
            if not good:
                row[f"failure_{tag}"] = str(sw["failure"].values[k])[:120]
                runs.append(None)
                continue
            ds = read_run(out / name / str(sw["run_file"].values[k]))
            runs.append(ds)
            row.update({f"{m}_{tag}": v for m, v in run_metrics(ds).items()})
            row[f"Kv_{tag}"] = round(float(np.nanmax(sw["dynamic_factor"].values[k])), 3)
            row[f"contact_loss_{tag}"] = round(
                float(np.nanmax(sw["contact_loss_fraction"].values[k])), 4)
            if "floquet_growth_rate" in sw:  # sweeps that ask for it ([summary] floquet_*)
                g = np.asarray(sw["floquet_growth_rate"].values[k], dtype=float)
                speeds = np.asarray(sw["floquet_speed"].values, dtype=float)
                row[f"floquet_max_{tag}"] = round(float(np.nanmax(g)), 2)
                row[f"floquet_unstable_rpm_{tag}"] = " ".join(f"{v:.0f}" for v in speeds[g > 0])
            row[f"run_{tag}"] = str(sw["run_file"].values[k])
        if runs[0] is not None and runs[1] is not None:
            pair = pair_metrics(runs[0], runs[1])
            row.update(pair)
            row["case_finding"] = reproduces_case_finding(pair)
            row["plausible"] = plausible(row)
            row["match"] = bool(row["plausible"] and row["N_1500_1"] >= 2
                                and row["paper_score_1"] == 3 and row["case_finding"])
        rows.append(row)
    return rows


def write_metrics(out: Path, names: Sequence[str] = ()) -> Path:
    """Metrics of every pair of every sweep -> ``reports/paper-study/metrics.csv``."""
    rows = []
    for path in sweep_files(names):
        rows += sweep_rows(out, sweep_name(path))
        print(f"metrics: {sweep_name(path)} done", flush=True)
    target = HERE / "metrics.csv"
    old = []
    if names and target.exists():  # keep the rows of the sweeps not recomputed
        with target.open() as fh:
            done = {sweep_name(p) for p in sweep_files(names)}
            old = [r for r in csv.DictReader(fh) if r["sweep"] not in done]
    rank = {sweep_name(p): i for i, p in enumerate(sweep_files())}
    rows = sorted(old + rows, key=lambda r: rank.get(r["sweep"], len(rank)))  # file order
    # columns in a canonical order (the same whichever sweeps were recomputed): the sweep, its
    # parameters (key paths), then the metrics, each group sorted by name
    names = {k for r in rows for k in r} - {"sweep"}
    params = sorted(k for k in names if "." in k or k == "meshes")
    fields = ["sweep", *params, *sorted(names - set(params))]
    tmp = target.with_suffix(".tmp")
    with tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
    tmp.replace(target)
    return target


# ------------------------------------------------------------------------------- figures

SWEEP_COLOURS = {"damping-speed": "tab:blue", "drive": "tab:cyan", "damping-torque": "tab:orange",
                 "planet": "tab:green", "geometry": "tab:olive", "shape": "tab:purple",
                 "load": "tab:brown", "refine": "tab:red", "key": "k", "key-preset": "0.5"}


def _key_runs(out: Path, name: str) -> tuple:
    """The case-1 and case-2 run of a key sweep (``sweep-key*.toml``)."""
    from gearvib.io import read_run

    sw = open_sweep(out, name)
    col = _parameter_columns(sw)[0]
    runs = {_case_label(sw, col, i): read_run(out / name / str(sw["run_file"].values[i]))
            for i in range(sw.sizes["case"])}
    return runs[CASE_LABELS[0]], runs[CASE_LABELS[1]]


def _shade_paper_speeds(ax, vertical: bool = True) -> None:
    for s in PAPER_SPEEDS:
        lo, hi = s * (1 - WINDOW), s * (1 + WINDOW)
        (ax.axvspan if vertical else ax.axhspan)(lo, hi, color="0.85", zorder=0)


def figure_tracks(out: Path, target: Path) -> Path:
    """Order tracks L_k(n) of the preset paper-case1/2 and of the study presets (2 x 2)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11.0, 7.0), sharex=True, sharey=True,
                             layout="constrained")
    titles = {"key-preset": "presets paper-case1/2 (speed drive, 0.5 %)",
              "key": "study presets paper-case1/2-study"}
    colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.9, ORDERS.size))
    for r, name in enumerate(("key-preset", "key")):
        for c, ds in enumerate(_key_runs(out, name)):
            ax = axes[r, c]
            rpm, levels = order_tracks(ds)
            _shade_paper_speeds(ax)
            for k in range(ORDERS.size):
                ax.plot(rpm, levels[k], color=colours[k], lw=0.9, label=f"order {k + 1}")
            ax.set_title(f"{titles[name]}: {CASE_LABELS[c]}", fontsize=10)
            ax.set_xlim(LOW_RPM, 4000.0)
            ax.grid(alpha=0.3)
            if r == 1:
                ax.set_xlabel("sun speed [min⁻¹]")
            if c == 0:
                ax.set_ylabel("tooth force sun-planet1, rms [dB re 1 N]")
    axes[0, 1].legend(loc="lower right", fontsize=8, ncols=2)
    fig.suptitle("Mesh-order levels in the run-up (grey: ±5 % around the paper's 1500, 2600, "
                 "3100 min⁻¹)", fontsize=11)
    fig.savefig(target, dpi=90)
    plt.close(fig)
    return target


def paper_mode_names(freqs_hz, low_hz: float = 200.0) -> list[tuple[str, float]]:
    """The gear modes above ``low_hz`` named as in the paper (f2, f3=f4, f5, ...): mode 1 is
    the rigid-body rotation; a load shaft's mode far below the gear modes is not counted;
    equal frequencies (within 0.5 %) are one label."""
    out: list[tuple[str, float]] = []
    i = 2
    for f in sorted(float(x) for x in freqs_hz if x > low_hz):
        if out and abs(f - out[-1][1]) <= 0.005 * f:
            out[-1] = (f"{out[-1][0]}=f{i}", out[-1][1])
        else:
            out.append((f"f{i}", f))
        i += 1
    return out


def figure_sonograms(out: Path, target: Path, range_db: float = 50.0) -> Path:
    """Rpm-frequency maps (the paper's Figure 11 view) of the study presets, case 1 and 2, on
    one colour scale (top: the larger maximum of the two)."""
    import matplotlib.pyplot as plt

    cas = [_analysis(ds) for ds in _key_runs(out, "key")]
    fmax = PASSBAND * float(cas[0].dataset.attrs["fs_out"])
    maps = []
    for ca in cas:
        m = ca.fmap
        keep = m.frequency <= fmax
        with np.errstate(divide="ignore"):
            db = 20.0 * np.log10(np.asarray(m.values, dtype=float)[:, keep])
        o = np.argsort(m.rpm, kind="stable")
        maps.append((m.frequency[keep], m.rpm[o], db[o]))
    top = max(float(np.nanmax(d)) for _, _, d in maps)
    fig, axes = plt.subplots(1, 2, figsize=(12.0, 5.6), sharey=True, layout="constrained")
    for c, (ca, (f, rpm, db)) in enumerate(zip(cas, maps, strict=True)):
        ax = axes[c]
        im = ax.pcolormesh(f, rpm, db, shading="nearest", cmap="viridis",
                           vmin=top - range_db, vmax=top, rasterized=True)
        line = np.array([rpm.min(), rpm.max()])
        for k in range(1, 8):
            fk = k * ca.mesh_frequency_per_rpm * line
            ax.plot(fk, line, color="w", lw=0.7, ls="--")
            x_at = min(fk[1], 0.97 * fmax)
            ax.text(x_at, min(line[1], x_at / (k * ca.mesh_frequency_per_rpm)) - 40, f"{k}",
                    color="w", fontsize=8, ha="right", va="top")
        for name, fn in paper_mode_names(ca.natural_frequencies_hz):
            ax.axvline(fn, color="tab:orange", lw=0.9, ls=":")
            ax.text(fn, 0.02, f" {name}", color="w", fontsize=8, rotation=90, va="bottom",
                    ha="right", transform=ax.get_xaxis_transform())
        for sp in PAPER_SPEEDS:
            ax.axhline(sp, color="w", lw=0.6, ls=":")
        ax.set_xlim(0.0, fmax)
        ax.set_ylim(rpm.min(), rpm.max())
        ax.set_xlabel("frequency [Hz]")
        ax.set_title(f"paper-case{c + 1}-study: tooth force sun-planet1", fontsize=10)
    axes[0].set_ylabel("sun speed [min⁻¹]")
    fig.colorbar(im, ax=axes, label="rms level [dB re 1 N]")
    fig.suptitle("Sonograms, one colour scale (dashed: mesh orders 1-7; dotted orange: natural "
                 "frequencies; dotted white: 1500, 2600, 3100 min⁻¹)", fontsize=10)
    fig.savefig(target, dpi=80)
    plt.close(fig)
    return target


def _load_metrics() -> list[dict]:
    with (HERE / "metrics.csv").open() as fh:
        return list(csv.DictReader(fh))


def _f(row: dict, key: str) -> float:
    try:
        return float(row[key])
    except (KeyError, TypeError, ValueError):
        return math.nan


def figure_overview(target: Path) -> Path:
    """Every parameter set: paper speeds and orders at 1500 min^-1 (left), case 2 vs 1 (right)."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    rows = [r for r in _load_metrics() if r.get("status_1") == "ok" and r.get("status_2") == "ok"]
    rng = np.random.default_rng(0)  # jitter only (fixed seed: same figure every time)
    fig, (a, b) = plt.subplots(1, 2, figsize=(12.0, 5.0), layout="constrained")
    for r in rows:
        col = SWEEP_COLOURS.get(r["sweep"], "k")
        ok = r.get("plausible") == "True"
        face = col if ok else "none"
        mk = "*" if r.get("match") == "True" else "o"
        size = 130 if mk == "*" else 30
        a.scatter(_f(r, "N_1500_1") + rng.uniform(-0.25, 0.25),
                  _f(r, "paper_score_1") + rng.uniform(-0.2, 0.2),
                  s=size, marker=mk, facecolors=face, edgecolors=col, lw=1.0)
        b.scatter(_f(r, "dL_db"), _f(r, "strength_2_db") - _f(r, "strength_1_db"),
                  s=size, marker=mk, facecolors=face, edgecolors=col, lw=1.0)
    a.set_xlabel("case 1: orders resonant at 1500 min⁻¹, N(1500) (paper: 7)")
    a.set_ylabel("case 1: paper speeds reproduced (paper: 3)")
    a.set_xticks(range(8))
    a.set_yticks(range(4))
    a.grid(alpha=0.3)
    b.axhline(0.0, color="0.4", lw=0.8)
    b.axvline(0.0, color="0.4", lw=0.8)
    b.set_xlabel("case 2 − case 1: mean order level dL [dB]")
    b.set_ylabel("case 2 − case 1: total region strength [dB]")
    x0, x1 = b.get_xlim()
    y0, y1 = b.get_ylim()
    b.fill_between([x0, 0.0], y0, 0.0, color="tab:green", alpha=0.12, lw=0)
    b.set_xlim(x0, x1)
    b.set_ylim(y0, y1)
    b.grid(alpha=0.3)
    handles = [Line2D([], [], ls="", marker="o", color=c, label=n)
               for n, c in SWEEP_COLOURS.items() if any(r["sweep"] == n for r in rows)]
    handles += [Line2D([], [], ls="", marker="o", mfc="none", color="k",
                       label=f"implausible (K_v > {KV_MAX:g} or contact loss > "
                             f"{CONTACT_LOSS_MAX:.0%})"),
                Line2D([], [], ls="", marker="*", ms=12, color="k", label="match"),
                Line2D([], [], ls="", marker="s", ms=10, color="tab:green", alpha=0.3,
                       label="paper's case finding:\ncase 2 quieter, regions weaker")]
    b.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.suptitle(f"{len(rows)} parameter sets, each run as case 1 and case 2 (left: jittered; "
                 "the two key presets repeat sweep rows)",
                 fontsize=11)
    fig.savefig(target, dpi=90)
    plt.close(fig)
    return target


def figure_damping(target: Path) -> Path:
    """N(1500) and the region strength of case 2 against case 1 over mesh damping."""
    import matplotlib.pyplot as plt

    rows = _load_metrics()
    series = {
        "speed drive (preset), z_p = 40": [r for r in rows if r["sweep"] == "damping-speed"],
        "torque drive, z_p = 40": [r for r in rows if r["sweep"] == "damping-torque"],
        "torque drive, z_p = 41": [r for r in rows if r["sweep"] == "planet"
                                   and r.get("geometry.z_planet") in ("41", "41.0")],
        "torque, x_s = 0.3, ramps 0.2/0.1": [r for r in rows if r["sweep"] == "refine"
                                              and r.get("geometry.profile_shift_sun") == "0.3"
                                              and "0.2/0.1" in r.get("meshes", "")],
    }

    def zeta(r: dict) -> float:
        if r.get("meshes.sun.damping_ratio"):
            return 100.0 * _f(r, "meshes.sun.damping_ratio")
        return float(r["meshes"].split(",")[-1].strip().rstrip(" %").split()[-1])

    fig, (a, b) = plt.subplots(1, 2, figsize=(11.0, 4.2), layout="constrained")
    for (name, rs), mk in zip(series.items(), "osD^", strict=True):
        rs = [r for r in rs if r.get("status_1") == "ok" and r.get("status_2") == "ok"]
        z = np.array([zeta(r) for r in rs])
        o = np.argsort(z)
        a.plot(z[o], np.array([_f(r, "N_1500_1") for r in rs])[o], marker=mk, label=name)
        b.plot(z[o], np.array([_f(r, "strength_2_db") - _f(r, "strength_1_db")
                               for r in rs])[o], marker=mk, label=name)
    a.set_xlabel("mesh damping ratio [%]")
    a.set_ylabel("case 1: orders resonant at 1500 min⁻¹")
    b.set_xlabel("mesh damping ratio [%]")
    b.set_ylabel("case 2 − case 1: total region strength [dB]")
    b.axhline(0.0, color="0.4", lw=0.8)
    b.text(0.98, 0.02, "below 0: case 2 weaker (paper)", transform=b.transAxes, ha="right",
           fontsize=8)
    for ax in (a, b):
        ax.grid(alpha=0.3)
    a.legend(fontsize=8)
    fig.savefig(target, dpi=90)
    plt.close(fig)
    return target


def figure_forcing(target: Path) -> Path:
    """The quasi-static mesh forcing (forcing.csv) at the crossings the paper names."""
    import matplotlib.pyplot as plt

    with (HERE / "forcing.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    crossings = [("f2", 2, "f2 by 2nd harmonic\n(paper: 1500)"),
                 ("f5", 2, "f5 by 2nd harmonic\n(paper: 2600)"),
                 ("f2", 1, "f2 by 1st harmonic\n(paper window 3100)"),
                 ("f3=f4", 3, "f3=f4 by 3rd harm."),
                 ("f3=f4", 1, "f3=f4 by 1st harm.")]
    sets = [label for label, _, _ in THEORY_SETS]
    fig, ax = plt.subplots(figsize=(11.0, 4.6), layout="constrained")
    width = 0.8 / len(sets)
    colours = plt.get_cmap("tab10")
    for j, name in enumerate(sets):
        vals, rpms = [], []
        for mode, ell, _ in crossings:
            r = next(r for r in rows if r["set"] == name and r["mode"] == mode
                     and int(r["harmonic"]) == ell)
            vals.append(max(float(r["force_n"]), 0.1))
            rpms.append(float(r["rpm"]))
        x = np.arange(len(crossings)) + (j - (len(sets) - 1) / 2) * width
        ax.bar(x, vals, width, color=colours(j), label=name,
               hatch="//" if "case2" in name else None, edgecolor="w", lw=0.5)
    rpm_of = {(r["mode"], int(r["harmonic"])): float(r["rpm"]) for r in rows
              if r["set"] == sets[0]}
    ax.set_xticks(np.arange(len(crossings)),
                  [f"{t}\n{rpm_of[(m, ell)]:.0f} min⁻¹" for m, ell, t in crossings], fontsize=8)
    ax.set_yscale("log")
    ax.set_ylim(0.1, 5000.0)
    ax.set_ylabel("quasi-static force sun-planet1 [N]")
    ax.set_title("Forcing of each mode by a mesh harmonic: static deflection x stiffness "
                 "variation, 60 N m (static tooth force 516 N)", fontsize=10)
    ax.legend(fontsize=8, ncols=4, loc="upper center")
    ax.text(3.0, 0.15, "case 1: planet modes not forced (0)", ha="center", fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    fig.savefig(target, dpi=90)
    plt.close(fig)
    return target


def make_figures(out: Path, quick: bool = False) -> list[Path]:
    """The write-up's figures (PNG, next to metrics.csv)."""
    made = [figure_tracks(out, HERE / "fig-tracks.png"),
            figure_sonograms(out, HERE / "fig-sonograms.png")]
    if not quick:
        made += [figure_overview(HERE / "fig-overview.png"),
                 figure_damping(HERE / "fig-damping.png"),
                 figure_forcing(HERE / "fig-forcing.png")]
    for m in made:
        print(m, flush=True)
    return made


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("step", choices=("run", "metrics", "figures", "all"))
    ap.add_argument("sweeps", nargs="*", help="sweep names (default: all)")
    ap.add_argument("--out", type=Path, default=Path("paper-study-out"),
                    help="folder of the run files (default: paper-study-out)")
    ap.add_argument("--workers", type=int, default=1, help="local worker processes (default 1)")
    ap.add_argument("--quick", action="store_true",
                    help="only the key sweeps (presets paper-case1/2 and paper-case1/2-study: "
                         "4 runs); the overview figures keep the committed metrics")
    a = ap.parse_args(argv)
    if a.workers < 1:
        ap.error(f"--workers must be at least 1 (got {a.workers})")
    names = list(QUICK) if a.quick and not a.sweeps else a.sweeps
    t0 = time.perf_counter()
    if a.step in ("run", "all"):
        run_sweeps(a.out, a.workers, names)
    if a.step in ("metrics", "all"):
        print(write_metrics(a.out, names))
        print(write_forcing())
    if a.step in ("figures", "all"):
        make_figures(a.out, quick=a.quick)
    print(f"paper study ({a.step}{', quick' if a.quick else ''}): "
          f"{time.perf_counter() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
