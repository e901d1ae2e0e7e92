"""The table rows and map lines that the simulated and the measured reports share."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from analysis.instability import Crossing
from gearvib.report.case_analysis import CaseAnalysis
from gearvib.report.measured_case import MeasuredCase
from gearvib.report.rises import (
    REGION_HEADER,
    RISE_HEADER,
    ResonanceRegion,
    crossing_table_rows,
    rise_table_rows,
)


class _Rises(SimpleNamespace):
    def __len__(self) -> int:
        return len(self.rpm)


RISES = _Rises(
    rpm=np.array([1000.4, 2500.6, 1234.5]), frequency=np.array([500.2, 1200.7, 42.0]),
    order=np.array([2, 0, 0]), groups=np.array(["sun", "", ""], dtype=object),
    feature=np.array(["", "natural frequency", "spot"], dtype=object),
    strength_db=np.array([12.34, 8.0, 3.3]),
    mechanism=np.array(["forced resonance", "parametric instability", "unexplained"],
                       dtype=object),
    cause=np.array(["2 f_mesh = f5", "", ""], dtype=object),
    coincidence=np.array([0.123, 0.5, 0.999]), note=np.array(["n1", "", "n3"], dtype=object),
    crossings=(Crossing(2, "f5", 500.0, 1000.0, "rise", 12.3, "sun"),
               Crossing(3, "f7", 800.4, 1600.6, "no rise", 0.0, "ring")))
REST = [("2501", "1201", "f_i", "8.0", "parametric", "50 %", ""),
        ("1234", "42", "spot", "3.3", "unexplained", "–", "n3")]  # no chance: unexplained


def test_rise_rows_write_every_column():
    rows = rise_table_rows(RISES, lambda i: f"order {RISES.order[i]}")
    assert rows == [("1000", "500", "order 2", "12.3", "forced: 2 f_mesh = f5", "12 %", "n1"),
                    *REST]
    assert all(len(r) == len(RISE_HEADER) for r in rows)


def test_both_reports_name_the_order_their_way():
    groups = [SimpleNamespace(name="sun", short="S"), SimpleNamespace(name="ring", short="R")]
    case = SimpleNamespace(resonances=RISES, planet_resonances=None, groups=groups,
                           several_mesh_frequencies=True)
    assert CaseAnalysis.resonance_rows(case)[0][2] == "k=2 (S)"
    assert CaseAnalysis.resonance_rows(case, planet=True) == []
    assert CaseAnalysis.crossing_rows(case) == [
        ("2 × f_mesh = f5 [sun]", "500", "1000", "rise (12.3 dB)"),
        ("3 × f_mesh = f7 [ring]", "800", "1601", "no rise")]
    measured = SimpleNamespace(resonances=RISES, has_gearset=True, mesh_groups=groups)
    assert MeasuredCase.resonance_rows(measured)[0][2] == "k=2 (sun)"
    assert MeasuredCase.resonance_rows(measured)[1:] == REST
    no_set = SimpleNamespace(resonances=RISES, has_gearset=False, mesh_groups=groups)
    assert MeasuredCase.resonance_rows(no_set)[0][2] == "sun"
    assert MeasuredCase.crossing_rows(no_set)[1] == ("ring = f7", "800", "1601", "no rise")
    assert crossing_table_rows((), str) == []


def test_region_row():
    region = ResonanceRegion(900.0, 1100.0, 1000.0, 500.0, 12.34, 2,
                             (("forced resonance", "2 f_mesh = f5", 2),))
    row = region.table_row()
    assert row == ("900–1100", "1000", "500", "12.3", "2", "forced resonance: 2 f_mesh = f5 (2)")
    assert len(row) == len(REGION_HEADER)


def test_natural_frequency_lines_merge_repeated_frequencies():
    from gearvib.report.figures import natural_frequency_lines

    drawn = []
    ax = SimpleNamespace(axvline=lambda f, **style: drawn.append((f, style["ls"])))
    named = natural_frequency_lines(ax, [300.0, 100.0, 100.00001, 5000.0], ["f3", "f1", "f2", "f9"],
                                    fmax=1000.0)
    assert named == [(100.0, "f1=f2"), (300.0, "f3")]
    assert drawn == [(100.0, ":"), (100.00001, ":"), (300.0, ":")]
