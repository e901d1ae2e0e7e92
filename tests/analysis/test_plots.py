"""Figure builders: figures build, axes are labelled, PNG export works (Agg backend)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure

from analysis.maps import campbell, overall_level, rpm_frequency_map, rpm_order_map
from analysis.orders import angle_from_speed, order_cuts, order_spectrum
from analysis.spectrum import spectrum

FS = 2048.0


@pytest.fixture(scope="module")
def runup():
    t = np.arange(int(4 * FS)) / FS
    rpm = 600 + 1800 * t / 4
    th = angle_from_speed(t, rpm)
    return t, rpm, np.sin(3 * th) + 0.5 * np.sin(7 * th)


def _check(fig: Figure, tmp_path, name: str) -> None:
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    assert ax.get_xlabel() and ax.get_ylabel()
    path = tmp_path / f"{name}.png"
    fig.savefig(path, dpi=50)
    assert path.stat().st_size > 1000


def test_spectrum_figure_with_labelled_peaks(tmp_path):
    t = np.arange(4096) / FS
    s = spectrum(np.sin(2 * np.pi * 100 * t) + 0.1 * np.sin(2 * np.pi * 300 * t), FS)
    p = s.peaks(max_peaks=2)
    fig = s.plot(peaks=p, labels=["mesh", "2× mesh"])
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert texts == ["mesh", "2× mesh"]
    _check(fig, tmp_path, "spectrum")
    with pytest.raises(ValueError, match="labels"):
        s.plot(peaks=p, labels=["only one"])


def test_map_figures(runup, tmp_path):
    _t, rpm, x = runup
    fm = rpm_frequency_map(x, FS, rpm, scale="dB", units="m s-2")
    fig = fm.plot(hz_per_rpm=1 / 60, orders=(3, 7), natural_frequencies_hz=[150.0])
    ax = fig.axes[0]
    assert "speed" in ax.get_ylabel() and "frequency" in ax.get_xlabel()
    assert len(ax.lines) == 3  # two order rays and one natural-frequency line
    _check(fig, tmp_path, "sonogram")
    om = rpm_order_map(x, FS, rpm)
    fig = om.plot(orders=(3, 7))
    assert "order" in fig.axes[0].get_xlabel()
    _check(fig, tmp_path, "ordermap")


def test_cut_level_order_spectrum_and_campbell_figures(runup, tmp_path):
    _t, rpm, x = runup
    cut = order_cuts(x, FS, rpm, [3, 7])
    fig = cut.plot(labels=["3×", "7×"], db=True)
    assert [ln.get_label() for ln in fig.axes[0].lines] == ["3×", "7×"]
    _check(fig, tmp_path, "cuts")
    _check(overall_level(x, FS, rpm, scale="dB").plot(), tmp_path, "overall")
    _check(order_spectrum(x, FS, rpm, resolution=2.0).plot(), tmp_path, "orderspec")
    fig = campbell([100.0, 250.0], [3, 7], (600, 2400)).plot()
    assert len(fig.axes[0].lines) >= 4
    _check(fig, tmp_path, "campbell")
