"""Peak labels in the paper's style (section 3.2) on a synthetic spectrum with known content."""

from __future__ import annotations

import re

import numpy as np
import pytest
import scipy.signal

from analysis.instability import label_peaks

NAMES = ["f2", "f3", "f4", "f5"]
FN = [1250.0, 1800.0, 1800.0, 2200.0]
F_MESH = 640.0
# content: f3/6, f2/2, f3/2, f2, 2 f_mesh, (f2+f3)/2, f3, f5, 2 f2, f2+f3, f2+f5, 2 f3, none
CONTENT = [300.0, 625.0, 900.0, 1250.0, 1280.0, 1525.0, 1800.0, 2200.0, 2500.0, 3050.0,
           3450.0, 3600.0, 2750.0]


def synthetic_peaks():
    fs, n = 16384.0, 32768
    t = np.arange(n) / fs
    rng = np.random.default_rng(7)
    x = sum(np.cos(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi)) for f in CONTENT)
    x = x + 0.01 * rng.normal(size=n)
    spec = np.abs(np.fft.rfft(x * np.hanning(n)))
    freqs = np.fft.rfftfreq(n, 1 / fs)
    idx, _ = scipy.signal.find_peaks(spec, height=0.2 * spec.max())
    # parabolic interpolation on the log magnitude
    a, b, c = np.log(spec[idx - 1]), np.log(spec[idx]), np.log(spec[idx + 1])
    return freqs[idx] + 0.5 * (a - c) / (a - 2 * b + c) * (fs / n)


def evaluate(expr: str) -> float:
    """Independent evaluation of an expression like '(f2 + f3)/2' or '2 f_mesh'."""
    env = dict(zip(NAMES, FN, strict=True)) | {"f_mesh": F_MESH}
    py = re.sub(r"(\d) (f)", r"\1*\2", expr)
    return float(eval(py, {"__builtins__": {}}, env))


def test_paper_style_list_on_synthetic_spectrum():
    peaks = synthetic_peaks()
    assert np.allclose(np.sort(peaks), np.sort(CONTENT), atol=0.05)
    res = label_peaks(peaks, FN, mesh_frequency_hz=F_MESH, names=NAMES)
    by_peak = {round(p): lab for p, lab in zip(res.peak_frequencies_hz, res.labels, strict=True)}
    assert by_peak[1800] == "1800 Hz ≈ f3 ≈ f4"
    assert by_peak[3600] == "3600 Hz ≈ 2 f3 ≈ 2 f4"
    assert by_peak[3050] == "3050 Hz ≈ f2 + f3 ≈ f2 + f4"
    assert by_peak[3450] == "3450 Hz ≈ f2 + f5"
    assert by_peak[2200] == "2200 Hz ≈ f5"
    assert by_peak[900] == "900 Hz ≈ f3/2 ≈ f4/2"
    assert by_peak[1525] == "1525 Hz ≈ (f2 + f3)/2 ≈ (f2 + f4)/2"
    assert by_peak[1280] == "1280 Hz ≈ f2 ≈ 2 f_mesh"
    assert by_peak[2500] == "2500 Hz ≈ 2 f2 ≈ 4 f_mesh"
    assert by_peak[300] == "300 Hz ≈ f3/6 ≈ f4/6"
    assert "f2/2" in by_peak[625]
    assert by_peak[2750] == "2750 Hz: no match"
    # every listed match is within tolerance, checked by evaluating the expression
    for p, matches in zip(res.peak_frequencies_hz, res.matches, strict=True):
        for m in matches:
            value = evaluate(m.expression)
            assert m.value_hz == pytest.approx(value)
            assert abs(p - value) <= 0.03 * value
    # and nothing within tolerance is missed among these forms
    for p, matches in zip(res.peak_frequencies_hz, res.matches, strict=True):
        listed = {m.expression for m in matches}
        for i, name in enumerate(NAMES):
            for n in range(2, 7):
                if abs(p - FN[i] / n) <= 0.03 * FN[i] / n:
                    assert f"{name}/{n}" in listed


def test_tolerance_and_dataset():
    res = label_peaks([312.5, 305.0], FN, names=NAMES, tolerance=0.01)
    assert res.labels[0] == "312 Hz ≈ f2/4"  # 312.5 Hz rounds to 312 in the label
    assert res.labels[1] == "305 Hz: no match"
    wide = label_peaks([305.0], FN, names=NAMES, tolerance=0.03)
    assert wide.labels[0] == "305 Hz ≈ f2/4 ≈ f3/6 ≈ f4/6"  # the paper's "300 Hz ≈ f2/4 ≈ f3/6"
    ds = wide.to_dataset()
    assert ds.n_matches.item() == 3 and ds.best_expression.item() == "f3/6"  # 1.7 % vs 2.4 %
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert str(wide) == wide.labels[0]
    from matplotlib.figure import Figure

    assert isinstance(wide.plot(), Figure)


def test_default_names_and_errors():
    res = label_peaks([200.0], [100.0, 300.0])
    assert res.labels[0] == "200 Hz ≈ 2 f1 ≈ (f1 + f2)/2"
    with pytest.raises(ValueError, match="must be > 0"):
        label_peaks([100.0], [100.0, 0.0])
    with pytest.raises(ValueError, match="names has 1"):
        label_peaks([100.0], [100.0, 200.0], names=["a"])
    with pytest.raises(ValueError, match="peak_frequencies_hz"):
        label_peaks([-1.0], [100.0])
    with pytest.raises(ValueError, match="tolerance"):
        label_peaks([100.0], [100.0], tolerance=0.0)
