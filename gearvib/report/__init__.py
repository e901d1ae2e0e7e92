"""Order-analysis reports (HTML and PDF) built from run-up Datasets.

Typical use::

    from gearvib.report import load_study, run_study, build_report

    result = run_study(load_study("study.toml"), "out")  # gearvib example paper-cases > study.toml
    result.report.html        # out/report.html (self-contained), out/report.pdf
    build_report(["out/case1.nc", "out/case2.nc"], "again")   # from the runs alone

Modules: :mod:`~gearvib.report.study` (recipes), :mod:`~gearvib.report.runner` (run and build),
:mod:`~gearvib.report.case` (the content of one run, computed once: :func:`analyse_case`), with
:mod:`~gearvib.report.case_analysis` (:class:`CaseAnalysis` and its table rows),
:mod:`~gearvib.report.case_run` (what a run file holds), :mod:`~gearvib.report.case_groups`
(mesh-frequency groups), :mod:`~gearvib.report.case_spectra` (tooth-force spectra),
:mod:`~gearvib.report.case_stiffness` (summed mesh stiffness),
:mod:`~gearvib.report.case_stability` (Floquet chart, theory candidates),
:mod:`~gearvib.report.case_parameters` (gear-set and mode tables),
:mod:`~gearvib.report.case_levels` (NVH levels of a run) and :mod:`~gearvib.report.rises`
(rise tables and speed regions, shared with the measured report);
:mod:`~gearvib.report.figures` (figures), :mod:`~gearvib.report.sections` (the document: sections
of headings, paragraphs, tables and figures), :mod:`~gearvib.report.compare` (case comparison),
:mod:`~gearvib.report.crosscheck` (checks that the tables of a rendered report agree),
:mod:`~gearvib.report.document` (what both writers share: figure images, placeholders),
:mod:`~gearvib.report.html`, :mod:`~gearvib.report.pdf` (writers; the PDF is typeset with
ReportLab), :mod:`~gearvib.report.wording` (counts with their nouns).

The report of a measurement: :mod:`~gearvib.report.measured` (build), with
:mod:`~gearvib.report.measured_analysis` (the analysis), :mod:`~gearvib.report.measured_case`
(its content and table rows), :mod:`~gearvib.report.measured_peaks` (peak selection and
labelling), :mod:`~gearvib.report.measured_resonances` (rises of the map, classified),
:mod:`~gearvib.report.measured_figures` (figures), :mod:`~gearvib.report.measured_sections`
(sections), :mod:`~gearvib.report.measured_nvh` (NVH and summary pages) and
:mod:`~gearvib.report.bearings` (fault lines); :mod:`~gearvib.report.measured_compare` compares
a measurement with a simulation.
"""

from gearvib.report.case import analyse_case
from gearvib.report.case_analysis import CaseAnalysis
from gearvib.report.compare import Comparison, compare_cases
from gearvib.report.runner import (
    ReportPaths,
    StudyResult,
    build_report,
    check_output_dir,
    run_study,
)
from gearvib.report.sections import SECTION_IDS
from gearvib.report.study import AnalysisSettings, Case, RunSettings, Study, load_study

__all__ = [
    "SECTION_IDS",
    "AnalysisSettings",
    "Case",
    "CaseAnalysis",
    "Comparison",
    "ReportPaths",
    "RunSettings",
    "Study",
    "StudyResult",
    "analyse_case",
    "build_report",
    "check_output_dir",
    "compare_cases",
    "load_study",
    "run_study",
]
