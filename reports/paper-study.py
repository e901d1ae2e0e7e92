"""The paper-reproduction study of issue #16 (write-up: ``reports/paper-study.md``).

Which values of the parameters the paper does not give (mesh damping, stiffness-variation shape
and amplitude, contact ratio, drive, run-up rate, load) reproduce the resonance speeds of its
Figures 7 and 11 (1500, 2600 and 3100 min^-1, orders 1-7) and its case-1-vs-case-2 finding?

Every sweep is a ``gearvib sweep`` description in ``reports/paper-study/sweep-*.toml`` whose
first parameter is the planet arrangement (paper case 1 / case 2), so every combination of the
other parameters is run for both cases. This script runs them through the public sweep API,
measures every run with the metrics defined below (public analysis API only) and draws the
figures of the write-up::

    python reports/paper-study.py run      [--out DIR] [--workers N] [SWEEP ...]
    python reports/paper-study.py metrics  [--out DIR]   # -> reports/paper-study/metrics.csv
    python reports/paper-study.py figures  [--out DIR]   # -> reports/paper-study/*.png
    python reports/paper-study.py all      [--out DIR] [--workers N]
    python reports/paper-study.py all --quick    # only the key sweeps (4 runs, about 30 s)

``DIR`` (default ``paper-study-out``) holds the run files (about 9 MB each); the metrics table
and the figures are small and committed.

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
    fp = [f for f, k in zip(ca.modal.frequencies_hz, kinds) if k == "planet"] if kinds else []
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

    sw = xr.open_dataset(out / name / "sweep.nc")
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
    rows = old + rows
    fields: list[str] = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    tmp = target.with_suffix(".tmp")
    with tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
    tmp.replace(target)
    return target


def make_figures(out: Path) -> None:  # filled in below
    raise NotImplementedError


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("step", choices=("run", "metrics", "figures", "all"))
    ap.add_argument("sweeps", nargs="*", help="sweep names (default: all)")
    ap.add_argument("--out", type=Path, default=Path("paper-study-out"),
                    help="folder of the run files (default: paper-study-out)")
    ap.add_argument("--workers", type=int, default=1, help="local worker processes (default 1)")
    a = ap.parse_args(argv)
    if a.step in ("run", "all"):
        run_sweeps(a.out, a.workers, a.sweeps)
    if a.step in ("metrics", "all"):
        print(write_metrics(a.out, a.sweeps))
    if a.step in ("figures", "all"):
        make_figures(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
