"""Run a study end to end, and build reports from netCDF runs alone.

:func:`run_study` simulates every case of a :class:`~gearvib.report.study.Study` (load the gear
set, assemble, modal analysis, run-up), writes ``<out_dir>/<case>.nc`` and then the report
(``report.html`` and ``report.pdf``) with :func:`build_report`. :func:`build_report` needs only
the run files: the gear set is rebuilt from the ``config_json`` attribute every run carries.

Every output is written atomically (a temporary file in the output folder, renamed when
complete), so an error or Ctrl-C never leaves a half-written file. The output folder is checked
for writability before any work is done, but created only when the first file is written into
it; a folder this call created and left empty (an error or Ctrl-C before the first file) is
removed again. Run files of the cases that finished stay: they are complete, and
``gearvib report out/*.nc -o out`` builds the report from them without simulating again.
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
from typing import Any

import xarray as xr

from analysis.checks import require_instance
from gearvib import tempfiles
from gearvib.assembly import assemble
from gearvib.checks import check_path, cut
from gearvib.compile_helper import ORDER_ANALYSIS, await_part
from gearvib.config import gearset_from_dict
from gearvib.io import GearvibFileError, atomic_write, read_run, write_netcdf
from gearvib.modal import modal_analysis
from gearvib.paths import exists
from gearvib.report.case import analyse_case
from gearvib.report.case_analysis import CaseAnalysis
from gearvib.report.case_run import run_description
from gearvib.report.compare import Comparison, compare_cases
from gearvib.report.document import FigureImages
from gearvib.report.html import render_html
from gearvib.report.pdf import write_pdf
from gearvib.report.sections import report_sections
from gearvib.report.study import (
    AnalysisSettings,
    Study,
    check_cut_resolution,
    check_report_duration,
    check_report_size,
    resolve_run,
)
from gearvib.simulate import SimulationError, simulate
from gearvib.simulation.settings import conditions_from_settings

__all__ = ["ReportPaths", "StudyResult", "build_report", "check_output_dir", "check_study",
           "run_study"]

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
    """Check that the output folder can be used, without creating it.

    An existing folder gets a write test (a temporary file, removed at once); a missing one
    needs its nearest existing parent to be a writable folder (same test there). The folder
    itself is created by :func:`_output_folder` when the first file is written.

    Raises
    ------
    ValueError
        ``out_dir`` exists and is not a directory, or a parent is a file.
    PermissionError
        The folder (or the parent it would be created in) is not writable; nothing is created.
    """
    p = check_path(out_dir, "out_dir")
    shown = cut(repr(str(p)), 200)
    if exists(p) and not p.is_dir():
        raise ValueError(f"output folder {shown} exists and is not a directory")
    q = p
    while not exists(q) and q != q.parent:
        q = q.parent
    if exists(q) and not q.is_dir():
        raise ValueError(f"cannot create output folder {shown}: {cut(repr(str(q)), 200)} is a "
                         "file")
    try:
        fd, probe = tempfile.mkstemp(dir=q, prefix=tempfiles.prefix("write-test"),
                                     suffix=".tmp")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise PermissionError(f"output folder {shown} is not writable "
                              f"({exc.strerror or exc})") from None
    return p


class _OutputFolder:
    """Creates the output folder when the first file is written; removes what it created if it
    is still empty when the work ends with an error or Ctrl-C."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.created: list[Path] = []

    def ensure(self) -> Path:
        """Create the folder (and missing parents) now; returns it."""
        if not self.path.exists():
            q = self.path
            missing = []
            while not q.exists() and q != q.parent:
                missing.append(q)
                q = q.parent
            self.path.mkdir(parents=True, exist_ok=True)
            self.created += missing  # deepest first
        return self.path

    def __enter__(self) -> _OutputFolder:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        if exc_type is None:
            return
        for d in self.created:
            with contextlib.suppress(OSError):
                d.rmdir()  # only if empty


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


def _load_inputs(inputs: Sequence[RunInput] | RunInput) -> list[tuple[str, xr.Dataset]]:
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
    """The line under the title: the cases (with their labels) and their runs."""
    named = [c.name if c.label in ("", c.name) else f"{c.name} ({c.label})" for c in cases]
    runs = [c.run_text() for c in cases]
    if len(cases) == 1:
        return f"Case {named[0]}. Run: {runs[0]}."
    if len(set(runs)) == 1:
        return f"Cases: {'; '.join(named)}. Run of each case: {runs[0]}."
    return (f"Cases: {'; '.join(named)}. Runs: "
            + "; ".join(f"{c.name}: {r}" for c, r in zip(cases, runs, strict=True)) + ".")


def build_report(paths_or_datasets: Sequence[RunInput] | RunInput, out_dir: str | os.PathLike,
                 *, title: str | None = None, analysis: AnalysisSettings | None = None,
                 reference: str | None = None, progress: bool | None = False,
                 cut_orders: Sequence[float] | None = None,
                 order_resolution: float | None = None) -> ReportPaths:
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
    progress : bool or None
        Progress bar of the Floquet charts (None: on a terminal only).
    cut_orders : sequence of float, optional
        Orders cut besides the 1st to 3rd mesh harmonics (``--orders``), replacing the
        settings' ``cut_orders`` of every run.
    order_resolution : float, optional
        Resolution of the order cuts [orders] (``--order-resolution``; 0: automatic),
        replacing the settings' of every run.

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
    AnalysisSettings().with_cuts(cut_orders, order_resolution)  # checked before any file
    if analysis is not None:
        require_instance(analysis, AnalysisSettings, "analysis")
    for key, text in (("title", title), ("reference", reference)):
        if text is not None and not isinstance(text, str):
            raise TypeError(f"{key} must be a string; got {type(text).__name__}")
    if progress is not None and not isinstance(progress, bool):
        raise TypeError(f"progress must be a bool or None; got {type(progress).__name__}")
    runs = _load_inputs(paths_or_datasets)
    settings_of: dict[str, AnalysisSettings | None] = {}
    for name, ds in runs:  # before any analysis: the maps must fit into memory
        t = ds["time"].values
        fs = float(1.0 / (t[1] - t[0])) if t.size > 1 and t[1] > t[0] else 1.0
        stored = _caller(ds).get("analysis")
        settings = analysis or (AnalysisSettings.from_dict(stored) if isinstance(stored, dict)
                                else AnalysisSettings())
        check_report_size(t.size, fs, settings, f"run {name!r}")
        check_report_duration(t.size, fs, settings, f"run {name!r}")
        overridden = cut_orders is not None or order_resolution is not None
        settings_of[name] = (settings.with_cuts(cut_orders, order_resolution) if overridden
                             else analysis)
        if "input_angle" in ds.variables:
            a = ds["input_angle"].values
            check_cut_resolution(abs(float(a[-1]) - float(a[0])) / (2 * math.pi),
                                 settings_of[name] or settings, f"run {name!r}")
    with _OutputFolder(check_output_dir(out_dir)) as folder:
        return _build(runs, folder, title=title, analysis=settings_of, reference=reference,
                      progress=progress)


def _build(runs: list[tuple[str, xr.Dataset]], folder: _OutputFolder, *, title: str | None,
           analysis: AnalysisSettings | dict[str, AnalysisSettings | None] | None,
           reference: str | None, progress: bool | None) -> ReportPaths:
    first = _caller(runs[0][1])
    study = first.get("study", {}) if isinstance(first.get("study"), dict) else {}
    names = [n for n, _ in runs]
    ref = reference or str(study.get("reference", "")) or names[0]
    if ref not in names:
        ref = names[0]
    title = title or str(study.get("title", "")) or _default_title(runs)
    cases: list[CaseAnalysis] = []
    for n, ds in runs:
        t0 = time.perf_counter()
        st = analysis.get(n) if isinstance(analysis, dict) else analysis
        cases.append(analyse_case(ds, name=n, settings=st, progress=progress))
        log.info("analysed %s in %.1f s (Floquet chart %.1f s)", n, time.perf_counter() - t0,
                 cases[-1].stability_time_s)
    ref_case = next(c for c in cases if c.name == ref)
    comparisons = tuple(compare_cases(ref_case, c) for c in cases if c is not ref_case)
    sections = report_sections(cases, comparisons)
    subtitle = _subtitle(cases)
    images = FigureImages()  # every figure is drawn once, for both documents
    text = render_html(sections, title=title, subtitle=subtitle, images=images)
    out = folder.ensure()  # created only now, when there is something to write
    html_path, pdf_path = out / "report.html", out / "report.pdf"
    pages = atomic_write(pdf_path, lambda tmp: write_pdf(sections, tmp, title=title,
                                                    subtitle=subtitle, images=images))
    atomic_write(html_path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    log.info("report written: %s, %s (%d pages)", html_path, pdf_path, pages)
    return ReportPaths(html=html_path, pdf=pdf_path, pdf_pages=int(pages),
                       sections=tuple(s.id for s in sections), cases=tuple(names),
                       comparisons=comparisons)


def check_study(study: Study) -> list[tuple[Any, dict, Any, Any, dict]]:
    """Check every case of a study before the first (long) simulation.

    Every gear-set description is loaded and checked, every run resolved, and the report's
    maps are checked against the free memory (:func:`~gearvib.report.study.check_report_size`)
    and the run's duration (:func:`~gearvib.report.study.check_report_duration`).

    Returns
    -------
    list of tuple
        ``(case, description dict, base folder, GearSet, run settings)`` per case.

    Raises
    ------
    gearvib.config.ConfigError, ValueError
        The first case that cannot be run or reported, named.
    """
    prepared = []
    for case in study.cases:
        cfg, base = case.load()
        gs = gearset_from_dict(cfg, base=base)
        try:
            run = resolve_run(study.run, cfg)
        except ValueError as exc:
            raise type(exc)(f"case {case.name!r}: {exc}") from None
        n_out = math.floor(run["duration"] * run["fs_out"]) + 1
        check_report_size(n_out, run["fs_out"], study.analysis, f"case {case.name!r}")
        check_report_duration(n_out, run["fs_out"], study.analysis, f"case {case.name!r}")
        revs = 0.5 * (run["speed_start_rpm"] + run["speed_end_rpm"]) * run["duration"] / 60.0
        check_cut_resolution(revs, study.analysis, f"case {case.name!r}")
        prepared.append((case, cfg, base, gs, run))
    return prepared


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
    require_instance(study, Study, "study")
    if not isinstance(progress, bool):
        raise TypeError(f"progress must be a bool; got {type(progress).__name__}")
    if duration is not None:
        study = study.with_duration(duration)
    out = check_output_dir(out_dir)
    prepared = check_study(study)
    runs: dict[str, Path] = {}
    sim_time: dict[str, float] = {}
    n_steps = len(prepared) + 1

    def step(i: int, text: str) -> None:
        if progress:
            print(f"  [{i}/{n_steps}] {text}", file=sys.stderr, flush=True)

    with _OutputFolder(out) as folder:
        for i, (case, cfg, base, gs, run) in enumerate(prepared, start=1):
            what = run_description(run)
            step(i, f"simulating {case.name}: {what}")
            model = assemble(gs)
            modal = modal_analysis(model)
            config = {"gearset": cfg, "gearset_dir": str(base) if base is not None else None,
                      "run": run, "case": case.name, "label": case.label,
                      "analysis": study.analysis.to_dict(),
                      "study": {"title": study.title, "reference": study.reference_case}}
            log.info("simulating %s: %s", case.name, what)
            try:
                res = simulate(model, conditions_from_settings(run), dt=run.get("dt"),
                               fs_out=run["fs_out"], gyroscopic=bool(run.get("gyroscopic")),
                               progress=progress, config=config,
                               natural_frequencies=modal.elastic())
            except SimulationError as exc:
                raise SimulationError(f"case {case.name!r}: {exc}") from exc
            sim_time[case.name] = res.wall_time
            runs[case.name] = write_netcdf(res.to_dataset(), folder.ensure() / f"{case.name}.nc")
        step(n_steps, "analysing the runs and writing the report (maps, spectra, Floquet "
                      f"charts: stability = {study.analysis.stability!r})")
        # a first run: the order analysis from the compile helper, if it is compiling it
        await_part(ORDER_ANALYSIS)
        report = _build([(n, read_run(p)) for n, p in runs.items()], folder,
                        title=study.title, analysis=study.analysis,
                        reference=study.reference_case, progress=None if progress else False)
    return StudyResult(study=study, out_dir=out, runs=runs, report=report,
                       simulation_time_s=sim_time, wall_time_s=time.perf_counter() - t0)
