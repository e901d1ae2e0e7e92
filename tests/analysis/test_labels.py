"""Peak labels in the paper's style (section 3.2), with derived tolerances and coincidence odds.

The old labeller matched within 3 % and n <= 6 and gave a label to 61 % of random frequencies
between 200 and 4000 Hz; here the windows come from the resolution and the natural-frequency
uncertainty, the rate at which random peaks get a label is stated and checked, and the mesh-phasing
selection rule removes the combinations the planets cannot excite.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from analysis.instability import (
    MeshPhasingRule,
    instability_candidates,
    label_peaks,
    theory_lines,
)

NAMES = ["f2", "f3", "f4", "f5"]
FN = [1261.05, 1797.74, 1797.74, 2201.42]  # paper-case1 (gearvib modes)
FAMILIES = [("rotational", 0), ("planet", 1), ("planet", 1), ("rotational", 0)]
F_MESH = 640.0


def evaluate(expr: str) -> float:
    """Independent evaluation of an expression like '(f2 + f3)/2', '2 f2/3' or '2 f_mesh'."""
    env = dict(zip(NAMES, FN, strict=True)) | {"f_mesh": F_MESH}
    py = re.sub(r"(\d) (f)", r"\1*\2", expr.split(" ≈ ")[0])
    return float(eval(py, {"__builtins__": {}}, env))


def test_paper_style_list():
    peaks = [630.5, 1261.0, 1279.9, 1529.4, 1797.7, 2201.4, 2522.1, 3595.5, 1198.5, 2750.0]
    res = label_peaks(peaks, FN, names=NAMES, resolution_hz=1.0, mesh_frequency_hz=F_MESH)
    lab = dict(zip([round(p) for p in peaks], res.labels, strict=True))
    assert lab[630] == "630 Hz ≈ f2/2"              # the paper's "620 Hz ≈ f2/2"
    assert lab[1261] == "1261 Hz ≈ f2"
    assert lab[1280].startswith("1280 Hz ≈ 2 f_mesh")
    assert lab[1529] == "1529 Hz ≈ (f2 + f3)/2 ≈ (f2 + f4)/2"
    assert lab[1798] == "1798 Hz ≈ f3 ≈ f4"
    assert lab[2201] == "2201 Hz ≈ f5"
    assert lab[2522] == "2522 Hz ≈ 2 f2"
    assert lab[3596] == "3596 Hz ≈ 2 f3 ≈ 2 f4"
    assert lab[1198] == "1198 Hz ≈ 2 f3/3 ≈ 2 f4/3"
    assert lab[2750] == "2750 Hz: unexplained"
    # every match lies inside its window, and the window is what the docs say
    for p, ms in zip(res.peaks, res.matches, strict=True):
        for m in ms:
            assert m.value == pytest.approx(evaluate(m.expression))
            assert abs(p - m.value) <= m.tolerance
            u = 0.001 if "f_mesh" in m.expression else 0.01
            assert m.tolerance == pytest.approx(0.5 + u * m.value)
            assert 0 < m.coincidence < 1


def test_random_frequencies_get_far_fewer_labels():
    rng = np.random.default_rng(1)
    r = rng.uniform(200.0, 4000.0, 4000)
    old = label_peaks(r, FN, names=NAMES, tolerance=0.03, n_max=6, band=(200.0, 4000.0))
    new = label_peaks(r, FN, names=NAMES, resolution_hz=5.0, band=(200.0, 4000.0))
    rule = MeshPhasingRule(3, 33, 114)
    cand = instability_candidates(FN, n_max=4, mode_labels=NAMES, mode_families=FAMILIES,
                                  mesh_harmonic_rule=rule)
    ruled = label_peaks(r, FN, names=NAMES, resolution_hz=5.0, candidates=cand,
                        band=(200.0, 4000.0))
    rates = [float(np.mean(x.matched)) for x in (old, new, ruled)]
    assert rates[0] > 0.45                 # the old behaviour (3 % windows, n <= 6)
    assert rates[1] < 0.25                 # resolution 5 Hz, 1 % natural frequencies, n <= 4
    assert rates[2] < rates[1]             # in-phase planets: rot-planet sums suppressed
    for x, rate in zip((new, ruled), rates[1:], strict=True):
        stated = x.coverage["all"]
        assert rate == pytest.approx(stated, abs=3 * np.sqrt(stated * (1 - stated) / r.size))


def test_theory_lines_follow_the_selection_rule():
    rule = MeshPhasingRule(3, 33, 114)
    cand = instability_candidates(FN, n_max=3, mode_labels=NAMES, mode_families=FAMILIES,
                                  mesh_harmonic_rule=rule)
    lines = theory_lines(cand, names=NAMES)
    exprs = set(lines.expression)
    assert "(f2 + f5)/2" in exprs and "2 f2/3" in exprs and "f3 ≈ f4" in exprs
    assert not any("f2 + f3" in e for e in exprs)  # rot-planet: in-phase planets decouple
    assert np.all(lines.value > 0) and set(lines.families) == {"principal", "sum", "natural"}


def test_dataset_plot_and_errors():
    res = label_peaks([312.5, 305.0], FN, names=NAMES, resolution_hz=2.0, n_max=8)
    assert res.labels == ["312 Hz ≈ f2/4", "305 Hz: unexplained"]  # f2/4 = 2 f2/8
    ds = res.to_dataset()
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert int(ds.explained[0]) == 1 and str(ds.status[1].values) == "unexplained"
    from matplotlib.figure import Figure

    assert isinstance(res.plot(), Figure)
    with pytest.raises(ValueError, match="must be > 0"):
        label_peaks([100.0], [100.0, 0.0], resolution_hz=1.0)
    with pytest.raises(ValueError, match="names has 1"):
        label_peaks([100.0], [100.0, 200.0], names=["a"], resolution_hz=1.0)
    with pytest.raises(ValueError, match="peaks"):
        label_peaks([-1.0], [100.0], resolution_hz=1.0)
    with pytest.raises(ValueError, match="resolution_hz"):
        label_peaks([100.0], [100.0])
    with pytest.raises(ValueError, match="tolerance"):
        label_peaks([100.0], [100.0], tolerance=0.7)
