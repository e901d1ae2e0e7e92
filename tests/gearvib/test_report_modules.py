"""The report package's module structure: the names of the split modules stay importable from
their old paths, imports run one way, and no module takes another's private names."""

from __future__ import annotations

import ast
import graphlib
import importlib
from pathlib import Path

import pytest

REPORT = Path(__file__).resolve().parents[2] / "gearvib" / "report"

#: public names of gearvib.report.case and gearvib.report.measured before they were split
#: (issue 25), with the module that holds each now
MOVED = {
    "gearvib.report.case": {
        "case_analysis": ("MARKER_BUDGET", "PAPER_SPEEDS_RPM", "CaseAnalysis",
                          "key_speed_rows"),
        "case_groups": ("AUTO_ORDERS", "MeshGroup"),
        "case_levels": ("MAX_SENSORS",),
        "case_run": ("run_description", "signed_force"),
        "case_spectra": ("ForceSpectrum",),
        "case_stability": ("STABILITY_MODES",),
        "case_stiffness": ("SummedStiffness", "summed_stiffness", "summed_sun_stiffness"),
        "rises": ("REGION_HEADER", "RISE_HEADER", "ResonanceRegion", "crossing_table_rows",
                  "merged_modes", "resonance_regions", "rise_table_rows"),
        "case": ("PLANET_SIGNAL_GROWTH_DB", "SPOT_RANGE_DB", "analyse_case"),
    },
    "gearvib.report.measured": {
        "measured_analysis": ("MIN_SPEED_RATIO", "analyse_measurement"),
        "measured_case": ("MeasuredCase",),
        "measured_peaks": ("MAX_LABEL_CHANCE", "PEAK_HEADER", "PEAK_RANGE_DB"),
        "measured_resonances": ("MAX_RAYS",),
        "measured_figures": ("order_map_figure", "record_figure", "sonogram_figure",
                             "spectra_figure"),
        "measured_sections": ("MEASURED_SECTION_IDS", "TITLES", "measured_sections"),
        "measured": ("MeasuredReportPaths", "build_measured_report", "is_simulated_run"),
    },
}


@pytest.mark.parametrize("old", sorted(MOVED))
def test_moved_names_stay_importable_from_their_old_module(old):
    module = importlib.import_module(old)
    for home, names in MOVED[old].items():
        new = importlib.import_module(f"gearvib.report.{home}")
        for name in names:
            assert getattr(module, name) is getattr(new, name), f"{old}.{name}"
            assert name in getattr(new, "__all__", ()), f"{home} does not export {name}"


def _module_imports(everywhere: bool = False) -> dict[str, list[tuple[str, list[str]]]]:
    """Per module of gearvib.report: its imports of gearvib modules, ``(module, names)``; at
    module level (not in functions or ``if TYPE_CHECKING`` blocks) unless ``everywhere``."""
    out = {}
    for path in sorted(REPORT.glob("*.py")):
        name = "gearvib.report" + ("" if path.stem == "__init__" else f".{path.stem}")
        tree = ast.parse(path.read_text(encoding="utf-8"))
        nodes = ast.walk(tree) if everywhere else tree.body
        out[name] = [(n.module, [a.name for a in n.names]) for n in nodes
                     if isinstance(n, ast.ImportFrom) and (n.module or "").startswith("gearvib")]
    return out


def test_report_modules_import_one_way():
    graph = {m: {dep for dep, _ in imps if dep.startswith("gearvib.report")}
             for m, imps in _module_imports().items()}
    assert len(graph) > 30
    graphlib.TopologicalSorter(graph).prepare()  # raises CycleError on a cycle


def test_no_report_module_takes_private_names():
    private = {m: [n for _, names in imps for n in names
                   if n.startswith("_") and not n.startswith("__")]
               for m, imps in _module_imports(everywhere=True).items()}
    assert not {m: n for m, n in private.items() if n}
