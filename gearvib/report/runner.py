"""Run a study end to end, and build reports from netCDF runs alone.

:func:`run_study` simulates every case of a :class:`~gearvib.report.study.Study` (load the gear
set, assemble, modal analysis, run-up), writes ``<out_dir>/<case>.nc`` and then the report
(``report.html`` and ``report.pdf``) with :func:`build_report`. :func:`build_report` needs only
the run files: the gear set is rebuilt from the ``config_json`` attribute every run carries.

Every output is written atomically (a temporary file in the output folder, renamed when
complete), so an error or Ctrl-C never leaves a half-written file; the output folder is checked
for writability before any work is done.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import xarray as xr

from gearvib import tempfiles
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict
from gearvib.io import GearvibFileError, atomic_write, read_run, write_netcdf
from gearvib.modal import modal_analysis
from gearvib.report.compare import Comparison, compare_cases
from gearvib.report.document import FigureImages
from gearvib.report.figures import CaseAnalysis, analyse_case, report_sections
from gearvib.report.html import render_html
from gearvib.report.pdf import write_pdf
from gearvib.report.study import AnalysisSettings, Study, check_report_size, resolve_run
from gearvib.simulate import SimulationError, SpeedRamp, simulate

__all__ = ["ReportPaths", "StudyResult", "build_report", "check_output_dir", "run_study"]

log = logging.getLogger("gearvib.report")

RunInput = str | os.PathLike | xr.Dataset


@dataclass(frozen=True)
class ReportPaths:
    """Files of a built report.

    Attributes
    ----------
    html : Path
        The self-contained HTML report.
    pdf : Path
        The PDF report.
    pdf_pages : int
        Number of PDF pages.
    sections : tuple of str
        Section ids in the report, in order.
    cases : tuple of str
        Case names in the report, in order.
    comparisons : tuple of Comparison
        The case comparisons shown (each non-reference case against the reference).
    """

    html: Path
    pdf: Path
    pdf_pages: int
    sections: tuple[str, ...]
    cases: tuple[str, ...]
    comparisons: tuple[Comparison, ...] = field(default=(), repr=False)


@dataclass(frozen=True)
class StudyResult:
    """Outcome of :func:`run_study`.

    Attributes
    ----------
    study : Study
        The study that was run (with the duration override applied).
    out_dir : Path
        Output folder.
    runs : dict of str to Path
        netCDF file of every case.
    report : ReportPaths
        The report files.
    simulation_time_s : dict of str to float
        Wall time of each simulation [s].
    wall_time_s : float
        Wall time of the whole study [s].
    """

    study: Study
    out_dir: Path
    runs: dict[str, Path]
    report: ReportPaths
    simulation_time_s: dict[str, float]
    wall_time_s: float


def check_output_dir(out_dir: str | os.PathLike) -> Path:
    """Create the output folder if needed and check that files can be written into it.

    Raises
    ------
    ValueError
        ``out_dir`` exists and is not a directory.
    PermissionError
        The folder cannot be created or is not writable (nothing is left behind).
    """
    p = Path(out_dir)
    if p.exists() and not p.is_dir():
        raise ValueError(f"output folder {str(p)!r} exists and is not a directory")
    created: list[Path] = []
    q = p
    while not q.exists() and q != q.parent:
        created.append(q)
        q = q.parent
    if q.exists() and not q.is_dir():
        raise ValueError(f"cannot create output folder {str(p)!r}: {str(q)!r} is a file")
    try:
        p.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=p, prefix=tempfiles.prefix("write-test"),
                                     suffix=".tmp")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        for d in created:  # remove what this call created, deepest first
            with contextlib.suppress(OSError):
                d.rmdir()
        raise PermissionError(f"output folder {str(p)!r} is not writable "
                              f"({exc.strerror or exc})") from None
    return p


def _caller(ds: xr.Dataset) -> dict:
    import json

    try:
        cfg = json.loads(ds.attrs.get("config_json", "") or "{}")
    except ValueError:
        return {}
    inner = cfg.get("model", {}) if isinstance(cfg, dict) else {}
    return inner if isinstance(inner, dict) else {}


def _gearset(ds: xr.Dataset) -> dict:
    """The gear-set description stored in a run (``{}`` if none)."""
    gs = _caller(ds).get("gearset")
    return gs if isinstance(gs, dict) else {}


def _load_inputs(inputs: Sequence[RunInput]) -> list[tuple[str, xr.Dataset]]:
    if isinstance(inputs, str | os.PathLike | xr.Dataset):
        inputs = [inputs]
    if not inputs:
        raise ValueError("no runs given: pass netCDF files or Datasets")
    out = []
    for item in inputs:
        if isinstance(item, xr.Dataset):
            ds, stem = item, ""
        elif isinstance(item, str | os.PathLike):
            ds, stem = read_run(item), Path(item).stem
        else:
            raise TypeError(f"expected a netCDF path or an xarray.Dataset, got "
                            f"{type(item).__name__}")
        if "normal_force" not in ds.variables or "input_speed" not in ds.variables:
            where = f"{item}" if stem else "the dataset"
            raise GearvibFileError(f"{where} is not a gearvib run-up (no normal_force / "
                                   "input_speed)")
        name = (str(_caller(ds).get("case", "")) or stem or str(_gearset(ds).get("name", ""))
                or "run")
        out.append((name, ds))
    seen: dict[str, int] = {}
    unique = []
    for name, ds in out:
        seen[name] = seen.get(name, 0) + 1
        unique.append((name if seen[name] == 1 else f"{name}-{seen[name]}", ds))
    return unique


def _default_title(runs: Sequence[tuple[str, xr.Dataset]]) -> str:
    """Report title from the gear sets of the runs (their title, else their names)."""
    sets: dict[str, str] = {}
    for name, ds in runs:
        gs = _gearset(ds)
        key = str(gs.get("name", "")) or name
        sets.setdefault(key, str(gs.get("title", "")))
    if len(sets) == 1:
        ((key, gs_title),) = sets.items()
        return f"Order-analysis report: {gs_title or key}"
    return "Order-analysis report: " + ", ".join(sets)


def _subtitle(cases: Sequence[CaseAnalysis]) -> str:
    """The line under the title: the cases (with their labels) and their run-ups."""
    named = [c.name if c.label in ("", c.name) else f"{c.name} ({c.label})" for c in cases]
    runs = [f"{c.run['speed_start_rpm']:g} → {c.run['speed_end_rpm']:g} min⁻¹ in "
            f"{c.run['duration']:g} s" for c in cases]
    if len(cases) == 1:
        return f"Case {named[0]}. Run-up {runs[0]}."
    if len(set(runs)) == 1:
        return f"Cases: {'; '.join(named)}. Run-up of each case {runs[0]}."
    return (f"Cases: {'; '.join(named)}. Run-up "
            + ", ".join(f"{c.name}: {r}" for c, r in zip(cases, runs, strict=True)) + ".")


def build_report(paths_or_datasets: Sequence[RunInput] | RunInput, out_dir: str | os.PathLike,
                 *, title: str | None = None, analysis: AnalysisSettings | None = None,
                 reference: str | None = None) -> ReportPaths:
    """Build ``report.html`` and ``report.pdf`` from run-up files or Datasets.

    Parameters
    ----------
    paths_or_datasets : path-like, Dataset or a sequence of them
        Runs written by :func:`run_study` / :func:`gearvib.io.write_netcdf` (or in memory).
    out_dir : path-like
        Output folder (created if missing; must be writable).
    title : str, optional
        Report title (default: the study title stored in the runs).
    analysis : AnalysisSettings, optional
        Analysis settings (default: those stored in each run, else the defaults).
    reference : str, optional
        Case the others are compared with (default: the stored study reference, else the
        first case).

    Returns
    -------
    ReportPaths

    Raises
    ------
    gearvib.io.GearvibFileError
        An input file is missing, unreadable or not a gearvib run (before anything is written).
    ValueError, PermissionError
        The output folder is not usable (before any computation).
    """
    runs = _load_inputs(paths_or_datasets)  # type: ignore[arg-type]
    for name, ds in runs:  # before any analysis: the maps must fit into memory
        t = ds["time"].values
        fs = float(1.0 / (t[1] - t[0])) if t.size > 1 and t[1] > t[0] else 1.0
        stored = _caller(ds).get("analysis")
        settings = analysis or (AnalysisSettings.from_dict(stored) if isinstance(stored, dict)
                                else AnalysisSettings())
        check_report_size(t.size, fs, settings, f"run {name!r}")
    out = check_output_dir(out_dir)
    first = _caller(runs[0][1])
    study = first.get("study", {}) if isinstance(first.get("study"), dict) else {}
    names = [n for n, _ in runs]
    ref = reference or str(study.get("reference", "")) or names[0]
    if ref not in names:
        ref = names[0]
    title = title or str(study.get("title", "")) or _default_title(runs)
    cases: list[CaseAnalysis] = [analyse_case(ds, name=n, settings=analysis) for n, ds in runs]
    ref_case = next(c for c in cases if c.name == ref)
    comparisons = tuple(compare_cases(ref_case, c) for c in cases if c is not ref_case)
    sections = report_sections(cases, comparisons)
    subtitle = _subtitle(cases)
    html_path, pdf_path = out / "report.html", out / "report.pdf"
    images = FigureImages()  # every figure is drawn once, for both documents
    text = render_html(sections, title=title, subtitle=subtitle, images=images)
    pages = atomic_write(pdf_path, lambda tmp: write_pdf(sections, tmp, title=title,
                                                    subtitle=subtitle, images=images))
    atomic_write(html_path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    log.info("report written: %s, %s (%d pages)", html_path, pdf_path, pages)
    return ReportPaths(html=html_path, pdf=pdf_path, pdf_pages=int(pages),  # type: ignore[arg-type]
                       sections=tuple(s.id for s in sections), cases=tuple(names),
                       comparisons=comparisons)


def run_study(study: Study, out_dir: str | os.PathLike, *, progress: bool = True,
              duration: float | None = None) -> StudyResult:
    """Simulate every case of a study, write the runs and the report.

    Parameters
    ----------
    study : Study
        The recipe (:func:`gearvib.report.study.load_study` or :meth:`Study.for_presets`).
    out_dir : path-like
        Output folder: ``<case>.nc`` per case, ``report.html``, ``report.pdf``. Checked for
        writability before any work.
    progress : bool
        Show a progress bar per simulation (hidden on non-TTY output).
    duration : float, optional
        Override the run-up duration [s] (same speed range), e.g. for a quick look.

    Returns
    -------
    StudyResult

    Raises
    ------
    gearvib.config.ConfigError
        A case's gear-set description is invalid (checked for all cases first).
    PermissionError, ValueError
        The output folder is not usable.
    gearvib.simulate.SimulationError
        A run-up blew up (the message names the case).
    """
    t0 = time.perf_counter()
    if duration is not None:
        study = study.with_duration(duration)
    out = check_output_dir(out_dir)
    prepared = []
    for case in study.cases:  # check every description before the first (long) simulation
        cfg, base = case.load()
        gs = gearset_from_dict(cfg, base=base)
        run = resolve_run(study.run, cfg)
        check_report_size(math.floor(run["duration"] * run["fs_out"]) + 1, run["fs_out"],
                          study.analysis, f"case {case.name!r}")
        prepared.append((case, cfg, base, gs, run))
    runs: dict[str, Path] = {}
    sim_time: dict[str, float] = {}
    n_steps = len(prepared) + 1

    def step(i: int, text: str) -> None:
        if progress:
            print(f"  [{i}/{n_steps}] {text}", file=sys.stderr, flush=True)

    for i, (case, cfg, base, gs, run) in enumerate(prepared, start=1):
        step(i, f"simulating {case.name}: {run['speed_start_rpm']:g} -> "
             f"{run['speed_end_rpm']:g} min-1 in {run['duration']:g} s")
        model = assemble(gs)
        modal = modal_analysis(model)
        config = {"gearset": cfg, "gearset_dir": str(base) if base is not None else None,
                  "run": run, "case": case.name, "label": case.label,
                  "analysis": study.analysis.to_dict(),
                  "study": {"title": study.title, "reference": study.reference_case}}
        ramp = SpeedRamp(run["speed_start_rpm"], run["speed_end_rpm"], run["duration"],
                         input_torque=run["input_torque"])
        log.info("simulating %s: %g -> %g min-1 in %g s", case.name, run["speed_start_rpm"],
                 run["speed_end_rpm"], run["duration"])
        try:
            res = simulate(model, ramp, fs_out=run["fs_out"], progress=progress, config=config,
                           natural_frequencies=modal.elastic())
        except SimulationError as exc:
            raise SimulationError(f"case {case.name!r}: {exc}") from exc
        sim_time[case.name] = res.wall_time
        runs[case.name] = write_netcdf(res.to_dataset(), out / f"{case.name}.nc")
    step(n_steps, "analysing the runs and writing the report (maps, spectra, Floquet charts)")
    report = build_report(list(runs.values()), out, title=study.title,
                          analysis=study.analysis, reference=study.reference_case)
    return StudyResult(study=study, out_dir=out, runs=runs, report=report,
                       simulation_time_s=sim_time, wall_time_s=time.perf_counter() - t0)
