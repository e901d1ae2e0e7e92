"""Measured frequency response functions: UFF 58 (function type 4) and CSV."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.readers.frf import FrequencyResponse, read_frf, read_frf_csv, read_frf_uff
from analysis.readers.layout import ReaderError

pyuff = pytest.importorskip("pyuff")


def write_uff(path, f, data, numerator: int, unit: str = "m/s2", func_type: int = 4) -> None:
    pyuff.UFF(str(path)).write_sets(pyuff.prepare_58(
        func_type=func_type, ordinate_spec_data_type=numerator, orddenom_spec_data_type=13,
        abscissa_spec_data_type=18, x=f, data=data, ordinate_axis_units_lab=unit,
        orddenom_axis_units_lab="N", abscissa_axis_units_lab="Hz", id1="housing",
        rsp_node=1, rsp_dir=1, ref_node=2, ref_dir=1), mode="overwrite")


def accelerance(f: np.ndarray) -> np.ndarray:
    w = 2 * np.pi * f
    wk = 2 * np.pi * 1200.0
    return 0.8 * (-w * w) / (wk * wk - w * w + 2j * 0.04 * wk * w)


@pytest.mark.parametrize("numerator,power", [(12, 0), (11, 1), (8, 2)])
def test_uff_frf_becomes_accelerance(tmp_path, numerator, power) -> None:
    """Acceleration, velocity and displacement over force (types 12, 11, 8 over 13) are read
    and converted to accelerance by (i w)^n."""
    f = np.linspace(1.0, 5000.0, 2000)
    h = accelerance(f)
    path = tmp_path / "frf.uff"
    write_uff(path, f, h / (2j * np.pi * f) ** power, numerator)
    frf = read_frf(path)
    assert frf.quantity == {12: "accelerance", 11: "mobility", 8: "receptance"}[numerator]
    np.testing.assert_allclose(frf.frequency, f, rtol=1e-5)
    np.testing.assert_allclose(frf.accelerance(), h, rtol=2e-5)


def test_uff_in_g_per_newton(tmp_path) -> None:
    f = np.linspace(10.0, 100.0, 10)
    path = tmp_path / "g.uff"
    write_uff(path, f, np.ones(10, dtype=complex), 12, unit="g")
    np.testing.assert_allclose(read_frf_uff(path).values, 9.80665)


def test_csv_real_imag_and_magnitude_phase(tmp_path) -> None:
    f = np.linspace(0.0, 3000.0, 301)
    h = accelerance(f)
    a = tmp_path / "a.csv"
    rows = "".join(f"{x},{float(v.real)!r},{float(v.imag)!r}\n" for x, v in zip(f, h, strict=True))
    a.write_text("f,re,im\n" + rows)
    np.testing.assert_allclose(read_frf(a).values, h, rtol=1e-12, atol=1e-15)
    b = tmp_path / "b.txt"
    rows = "".join(f"{x}\t{float(abs(v))!r}\t{float(np.degrees(np.angle(v)))!r}\n"
                   for x, v in zip(f, h, strict=True))
    b.write_text("# magnitude and phase\n" + rows)
    frf = read_frf_csv(b, columns="magnitude_phase")
    np.testing.assert_allclose(frf.values, h, rtol=1e-9, atol=1e-12)


def test_bad_files(tmp_path) -> None:
    path = tmp_path / "time.uff"
    write_uff(path, np.linspace(0, 1, 10), np.ones(10), 12, func_type=1)
    with pytest.raises(ReaderError, match="no frequency response function"):
        read_frf(path)
    path = tmp_path / "force.uff"
    pyuff.UFF(str(path)).write_sets(pyuff.prepare_58(
        func_type=4, ordinate_spec_data_type=13, orddenom_spec_data_type=13,
        abscissa_spec_data_type=18, x=np.linspace(1, 10, 10), data=np.ones(10, complex),
        id1="x", rsp_node=1, rsp_dir=1, ref_node=2, ref_dir=1), mode="overwrite")
    with pytest.raises(ReaderError, match="response data type 13 over 13"):
        read_frf(path)
    bad = tmp_path / "bad.csv"
    bad.write_text("0,1,0\n10,oops,1\n")
    with pytest.raises(ReaderError, match="line 2"):
        read_frf(bad)
    short = tmp_path / "short.csv"
    short.write_text("0,1,0\n")
    with pytest.raises(ReaderError, match=">= 2"):
        read_frf(short)
    down = tmp_path / "down.csv"
    down.write_text("10,1,0\n5,1,0\n")
    with pytest.raises(ReaderError, match="strictly increasing"):
        read_frf(down)
    with pytest.raises(FileNotFoundError):
        read_frf(tmp_path / "none.csv")
    with pytest.raises(ValueError, match="quantity"):
        FrequencyResponse(np.array([0.0, 1.0]), np.ones(2), "inertance")
