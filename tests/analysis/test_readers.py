"""Tests of analysis.readers: round trips through files written by the library itself or by the
reference libraries (pyuff, npTDMS, scipy.io), the real UFF 58/58b files of
/work/shared/data/uff (read in place, never copied), and the error paths."""

from __future__ import annotations

import os
import struct
import sys
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from analysis.readers import (
    ChannelData,
    ReaderError,
    build_dataset,
    read,
    read_csv,
    read_mat,
    read_netcdf,
    read_tdms,
    read_uff,
    read_wav,
    to_udunits,
    write_csv,
    write_mat,
    write_netcdf,
    write_wav,
)
from analysis.readers.layout import clean_attrs, sanitize_names


def _uff_dir() -> Path:
    """The shared UFF files: beside the checkout (as CI lays it out), else /work/shared."""
    here = Path(__file__).resolve().parents[2]
    for base in (here.parent / "shared", Path("/work/shared")):
        if (base / "data" / "uff").is_dir():
            return base / "data" / "uff"
    return here.parent / "shared" / "data" / "uff"


UFF_DIR = _uff_dir()
FS = 2048.0


@pytest.fixture
def sample() -> xr.Dataset:
    t = np.arange(1024) / FS
    return build_dataset(
        [
            ChannelData(
                "ring x", 3.0 * np.sin(2 * np.pi * 50 * t), "m s-2", attrs={"sensitivity": 10.2}
            ),
            ChannelData("force-1", 100.0 * np.cos(2 * np.pi * 7 * t), "N"),
        ],
        FS,
        source_format="test",
        source_file="memory",
        attrs={"title": "sample", "time_coverage_start": "2024-05-01T10:00:00"},
    )


def assert_layout(ds: xr.Dataset, fs: float) -> None:
    assert ds.attrs["Conventions"] == "CF-1.11"
    assert ds.attrs["sample_rate_hz"] == pytest.approx(fs, rel=1e-9)
    assert ds.time.attrs["units"].startswith("seconds since ")  # CF time (analysis.cf)
    assert (ds.time.attrs["standard_name"], ds.time.attrs["axis"]) == ("time", "T")
    assert ds.time.dtype == np.float64
    np.testing.assert_allclose(np.diff(ds.time.values), 1.0 / fs, rtol=1e-9)
    for v in ds.data_vars:
        assert ds[v].dims == ("time",)
        assert {"units", "long_name"} <= set(ds[v].attrs)
        assert str(v).isidentifier()


# ----------------------------------------------------------------------------------------------
# layout
# ----------------------------------------------------------------------------------------------


def test_layout_builds_cf_dataset(sample):
    assert_layout(sample, FS)
    assert list(sample.data_vars) == ["ring_x", "force_1"]
    assert sample.ring_x.attrs["source_channel"] == "ring x"
    assert sample.ring_x.attrs["units"] == "m s-2"


def test_layout_nan_names_channel_and_index():
    x = np.ones(50)
    x[17] = np.nan
    with pytest.raises(ReaderError, match=r"'acc'.*first at sample index 17"):
        build_dataset([ChannelData("acc", x)], 100.0, source_format="t", source_file="f.csv")


def test_layout_empty_and_unequal_channels():
    with pytest.raises(ReaderError, match="'a' in f is empty"):
        build_dataset([ChannelData("a", [])], 1.0, source_format="t", source_file="f")
    with pytest.raises(ReaderError, match=r"unequal length.*'a': 3.*'b': 4"):
        build_dataset(
            [ChannelData("a", [1, 2, 3]), ChannelData("b", [1, 2, 3, 4])], 1.0, source_format="t"
        )
    with pytest.raises(ReaderError, match="no channels"):
        build_dataset([], 1.0, source_format="t")


def test_sanitize_names_unique_identifiers():
    names = sanitize_names(["Mic 01", "1+Z", "1+Z", "time", "class", "", "a/b"])
    assert names == ["Mic_01", "ch_1_Z", "ch_1_Z_2", "time_ch", "class_ch", "channel", "a_b"]
    assert all(n.isidentifier() for n in names)


def test_clean_attrs_makes_netcdf_storable():
    out = clean_attrs({"ok": True, "cfg": {"a": 1}, "none": None, "x": 1.5, "s": "t"})
    assert out == {"ok": 1, "cfg": '{"a": 1}', "x": 1.5, "s": "t"}
    assert out["ok"].dtype == np.int8


@pytest.mark.parametrize(
    ("label", "units", "factor"),
    [
        ("m/s2", "m s-2", 1.0),
        ("m/s²", "m s-2", 1.0),
        ("m/s^2", "m s-2", 1.0),
        ("g", "m s-2", 9.80665),
        ("Pa", "Pa", 1.0),
        ("rpm", "min-1", 1.0),
        ("rad/s", "rad s-1", 1.0),
        ("NONE", "1", 1.0),
        ("N", "N", 1.0),
    ],
)
def test_to_udunits(label, units, factor):
    assert to_udunits(label) == (units, factor)


# ----------------------------------------------------------------------------------------------
# netCDF
# ----------------------------------------------------------------------------------------------


def test_netcdf_round_trip_identical(sample, tmp_path):
    path = write_netcdf(sample, tmp_path / "rec.nc")
    back = read_netcdf(path)
    xr.testing.assert_identical(back, sample)
    with netCDF4.Dataset(path) as nc:
        assert "_FillValue" not in nc["time"].ncattrs()
        assert "_FillValue" not in nc["ring_x"].ncattrs()
    assert read(path).equals(sample)


def test_netcdf_write_is_atomic(sample, tmp_path, monkeypatch):
    target = tmp_path / "rec.nc"
    write_netcdf(sample, target)
    before = target.read_bytes()

    def broken(self, path, **kwargs):
        Path(path).write_bytes(b"half written")
        raise RuntimeError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", broken)
    with pytest.raises(RuntimeError, match="disk full"):
        write_netcdf(sample * 2, target)
    assert target.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["rec.nc"]


def test_netcdf_write_abandoned_by_an_interrupt_leaves_nothing(sample, tmp_path, monkeypatch):
    """A write that an interrupt abandons in its worker thread may create its file only after
    the clean-up; the private temporary folder is gone by then, so the late create fails (the
    old plain temporary file was re-created and stayed)."""
    import _thread
    import threading
    import time

    release = threading.Event()
    outcome: list[object] = []

    def late(self, path, **kwargs):
        release.wait(10.0)
        try:
            Path(path).write_bytes(b"late")
            outcome.append("created")
        except OSError as exc:
            outcome.append(exc)

    monkeypatch.setattr(xr.Dataset, "to_netcdf", late)
    threading.Timer(0.2, _thread.interrupt_main).start()
    with pytest.raises(KeyboardInterrupt):
        write_netcdf(sample, tmp_path / "rec.nc")
    release.set()
    t0 = time.monotonic()
    while not outcome and time.monotonic() - t0 < 10.0:
        time.sleep(0.01)
    assert outcome and isinstance(outcome[0], FileNotFoundError), outcome
    assert os.listdir(tmp_path) == []


def test_netcdf_corrupt_file(sample, tmp_path):
    path = write_netcdf(sample, tmp_path / "rec.nc")
    cut = tmp_path / "cut.nc"
    cut.write_bytes(path.read_bytes()[:300])
    with pytest.raises(ReaderError, match=r"cut\.nc.*not a readable netCDF"):
        read_netcdf(cut)


# ----------------------------------------------------------------------------------------------
# WAV
# ----------------------------------------------------------------------------------------------


def test_wav_float_round_trip(sample, tmp_path):
    ds = sample[["ring_x"]]
    cal = write_wav(ds, tmp_path / "a.wav")
    back = read_wav(tmp_path / "a.wav", calibration=cal, unit="m s-2", channel_names=["ring x"])
    assert_layout(back, FS)
    assert back.ring_x.attrs["units"] == "m s-2"
    np.testing.assert_allclose(back.ring_x, ds.ring_x, atol=3.0 * 2.0**-23)


def test_wav_int16_round_trip_two_channels(sample, tmp_path):
    cal = write_wav(sample, tmp_path / "b.wav", dtype="int16")
    back = read(tmp_path / "b.wav", calibration=cal)
    assert list(back.data_vars) == ["ch1", "ch2"]
    assert back.ch1.attrs["wav_bits_per_sample"] == 16
    np.testing.assert_allclose(back.ch2, sample.force_1, atol=0.51 * cal)


def test_wav_24bit_counts(tmp_path):
    """A 24-bit file built byte by byte: counts must come back as the true 24-bit codes."""
    counts = np.array([0, 1, -1, 8388607, -8388608, 123456], dtype=np.int64)
    frames = b"".join(int(c).to_bytes(3, "little", signed=True) for c in counts)
    fmt = struct.pack("<HHIIHH", 1, 1, 8000, 8000 * 3, 3, 24)
    body = (
        b"WAVE"
        + b"fmt "
        + struct.pack("<I", 16)
        + fmt
        + b"data"
        + struct.pack("<I", len(frames))
        + frames
    )
    path = tmp_path / "c.wav"
    path.write_bytes(b"RIFF" + struct.pack("<I", len(body)) + body)
    ds = read_wav(path, calibration=[2.0], unit="Pa")
    np.testing.assert_array_equal(ds.ch1.values, 2.0 * counts)
    assert ds.attrs["sample_rate_hz"] == 8000.0


def test_wav_errors(sample, tmp_path):
    cal = write_wav(sample, tmp_path / "d.wav", dtype="int16")
    with pytest.raises(ReaderError, match=r"2 channel.*1 channel_names"):
        read_wav(tmp_path / "d.wav", cal, channel_names=["x"])
    cut = tmp_path / "cut.wav"
    cut.write_bytes((tmp_path / "d.wav").read_bytes()[:30])
    with pytest.raises(ReaderError, match=r"cut\.wav.*not a readable WAV"):
        read_wav(cut)


# ----------------------------------------------------------------------------------------------
# CSV
# ----------------------------------------------------------------------------------------------


def test_csv_round_trip(sample, tmp_path):
    write_csv(sample, tmp_path / "r.csv")
    back = read(tmp_path / "r.csv", time_column="time")
    assert_layout(back, FS)
    np.testing.assert_array_equal(back.ring_x.values, sample.ring_x.values)
    assert back.ring_x.attrs["units"] == "m s-2"
    assert back.force_1.attrs["units"] == "N"


def test_csv_fs_header_units_and_decimal_comma(tmp_path):
    path = tmp_path / "de.txt"
    path.write_text("# exported\nacc [m/s2];speed [rpm]\n1,5;600\n2,5;610\n-0,5;620\n")
    ds = read_csv(path, fs=100.0)
    np.testing.assert_array_equal(ds.acc.values, [1.5, 2.5, -0.5])
    assert ds.acc.attrs["units"] == "m s-2"
    assert ds.speed.attrs["units"] == "min-1"
    ds2 = read_csv(path, fs=100.0, units={"acc": "g"})
    np.testing.assert_allclose(ds2.acc.values, 9.80665 * np.array([1.5, 2.5, -0.5]))


def test_csv_errors(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("t,a,b\n0,1,2\n0.1,,3\n0.2,1,4\n")
    with pytest.raises(ValueError, match=r"fs=.*time_column"):
        read_csv(path)
    with pytest.raises(ReaderError, match=r"line 3, column 2: empty value"):
        read_csv(path, time_column="t")
    path.write_text("t,a\n0,1\n0.1,2\n0.2,x1secret\n")
    with pytest.raises(ReaderError, match="line 4, column 2: not a number") as err:
        read_csv(path, time_column=0)
    assert "secret" not in str(err.value)  # the message never echoes file content
    path.write_text("t,a\n0.00,1\n0.10,2\n0.20,3\n0.40,4\n0.50,5\n")  # 0.30 is missing
    with pytest.raises(ReaderError, match="not uniformly sampled: the step from sample index 2"):
        read_csv(path, time_column="t")
    path.write_text("t,a\n0,1\n0.1\n")
    with pytest.raises(ReaderError, match="line 3: 1 columns, expected 2"):
        read_csv(path, time_column="t")
    path.write_text("t,a\n0,1\n0.1,nan\n")
    with pytest.raises(ReaderError, match=r"'a'.*sample index 1"):
        read_csv(path, time_column="t")


# ----------------------------------------------------------------------------------------------
# MAT
# ----------------------------------------------------------------------------------------------


def test_mat_round_trip(sample, tmp_path):
    write_mat(sample, tmp_path / "r.mat")
    back = read(tmp_path / "r.mat", time_variable="time")
    assert_layout(back, FS)
    np.testing.assert_array_equal(back.force_1.values, sample.force_1.values)
    assert back.force_1.attrs["units"] == "N"
    assert back.ring_x.attrs["units"] == "m s-2"


def test_mat_matrix_and_fs_scalar(tmp_path):
    from scipy.io import savemat

    data = np.arange(30.0).reshape(10, 3)
    savemat(tmp_path / "m.mat", {"acc": data, "Fs": 500.0})
    ds = read_mat(tmp_path / "m.mat", units="m/s2")
    assert list(ds.data_vars) == ["acc_1", "acc_2", "acc_3"]
    np.testing.assert_array_equal(ds.acc_2.values, data[:, 1])
    assert ds.attrs["sample_rate_hz"] == 500.0
    assert ds.acc_1.attrs["units"] == "m s-2"


def test_mat_errors(tmp_path):
    from scipy.io import savemat

    savemat(tmp_path / "nofs.mat", {"x": np.ones(5)})
    with pytest.raises(ReaderError, match="no sample rate"):
        read_mat(tmp_path / "nofs.mat")
    v73 = tmp_path / "big.mat"
    v73.write_bytes(b"MATLAB 7.3 MAT-file".ljust(116) + b"\0" * 8 + b"\x00\x02IM" + b"\0" * 512)
    with pytest.raises(ReaderError, match=r"v7\.3.*-v7"):
        read_mat(v73, fs=1.0)
    savemat(tmp_path / "two.mat", {"a": np.ones(5), "b": np.ones(6), "fs": 10.0})
    with pytest.raises(ReaderError, match="unequal length"):
        read_mat(tmp_path / "two.mat")


# ----------------------------------------------------------------------------------------------
# UFF 58 / 58b
# ----------------------------------------------------------------------------------------------


def _uff_set(i: int, dt: float = 1e-3, binary: int = 0, func_type: int = 1, n: int = 200):
    import pyuff

    x = np.arange(n) * dt
    return pyuff.prepare_58(
        binary=binary, func_type=func_type, id1=f"acc {i}", rsp_ent_name=f"acc {i}", rsp_node=i,
        rsp_dir=3, ref_node=0, ref_dir=0, ord_data_type=4, num_pts=n, abscissa_spacing=1,
        abscissa_min=0.0, abscissa_inc=dt, abscissa_spec_data_type=17,
        abscissa_axis_units_lab="s", ordinate_axis_units_lab="m/s2", ordinate_spec_data_type=12,
        orddenom_spec_data_type=0, data=np.sin(2 * np.pi * (i + 1) * 10 * x), x=x,
    )  # fmt: skip


def _write_uff(path: Path, sets) -> Path:
    import pyuff

    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return path


def test_uff_round_trip_pyuff_written(tmp_path):
    path = _write_uff(tmp_path / "w.uff", [_uff_set(0, binary=0), _uff_set(1, binary=1)])
    ds = read(path)
    assert_layout(ds, 1000.0)
    assert list(ds.data_vars) == ["acc_0", "acc_1"]
    t = np.arange(200) * 1e-3
    np.testing.assert_allclose(ds.acc_1.values, np.sin(2 * np.pi * 20 * t), atol=1e-12)
    assert ds.acc_0.attrs["units"] == "m s-2"
    assert ds.acc_0.attrs["rsp_dir"] == 3


def test_uff_sample_rate_mismatch_and_selection(tmp_path):
    path = _write_uff(tmp_path / "mix.uff", [_uff_set(0, dt=1e-3), _uff_set(1, dt=5e-4)])
    with pytest.raises(ReaderError, match=r"different sample intervals.*set 0.*set 1.*sets="):
        read_uff(path)
    ds = read_uff(path, sets=[1])
    assert ds.attrs["sample_rate_hz"] == 2000.0
    with pytest.raises(ValueError, match="sets"):
        read_uff(path, sets=[2])


def test_uff_rejects_non_time_function(tmp_path):
    path = _write_uff(tmp_path / "frf.uff", [_uff_set(0, func_type=4)])
    with pytest.raises(ReaderError, match="function type 4"):
        read_uff(path)


def test_uff_truncated(tmp_path):
    cut = tmp_path / "cut.uff"
    cut.write_bytes((UFF_DIR / "Sample_UFF58b_bin.uff").read_bytes()[:5000])
    with pytest.raises(ReaderError, match=r"cut\.uff.*last dataset is incomplete"):
        read_uff(cut)


def test_uff_missing_pyuff(monkeypatch):
    monkeypatch.setitem(sys.modules, "pyuff", None)
    with pytest.raises(ImportError, match=r'pip install "gearvib\[uff\]"'):
        read_uff(UFF_DIR / "binary8byte.uff")


@pytest.fixture(scope="module")
def mic():
    return read_uff(UFF_DIR / "Sample_UFF58_ascii.uff"), read_uff(UFF_DIR / "Sample_UFF58b_bin.uff")


def test_real_uff_ascii_and_binary_agree(mic):
    asc, binary = mic
    for ds in mic:
        assert ds.sizes["time"] == 79292
        assert 1.0 / ds.attrs["sample_rate_hz"] == pytest.approx(15.2588e-6, rel=1e-5)
        assert ds.Mic_01.attrs["units"] == "Pa"
        assert ds.attrs["time_coverage_start"] == "2016-04-18T13:49:58"
    assert asc.attrs["source_format"] == "uff58"
    assert binary.attrs["source_format"] == "uff58b"
    assert float(np.max(np.abs(asc.Mic_01 - binary.Mic_01))) <= 5e-7


def test_real_uff_mpstd_four_channels():
    ds = read_uff(UFF_DIR / "MPSTD_Set001_2024_10_08_10_27_07.uff")
    assert len(ds.data_vars) == 4
    assert ds.sizes["time"] == 222400
    assert ds.attrs["sample_rate_hz"] == 3200.0
    assert all(ds[v].attrs["units"] == "m s-2" for v in ds.data_vars)


def test_real_uff_binary8byte_5hz_sine():
    ds = read_uff(UFF_DIR / "binary8byte.uff")
    assert ds.sizes["time"] == 250
    assert ds.attrs["sample_rate_hz"] == 100.0
    (var,) = ds.data_vars
    assert ds[var].attrs["units"] == "m s-2"
    assert ds[var].attrs["source_units"] == "g"
    # 2.5 s record: bins are 0.4 Hz apart, so zero-pad (Hann window) to 0.004 Hz spacing
    x = ds[var].values
    n_fft = 100 * x.size
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n=n_fft))
    freq = np.fft.rfftfreq(n_fft, 1.0 / ds.attrs["sample_rate_hz"])
    assert abs(freq[np.argmax(spec)] - 5.0) < 0.01


def test_real_uff_catman_partly_filled_last_line():
    ds = read_uff(UFF_DIR / "time-history-not-all-columns-filled.uff")
    assert ds.sizes["time"] == 13
    assert 1.0 / ds.attrs["sample_rate_hz"] == pytest.approx(50e-6)
    (var,) = ds.data_vars
    assert ds[var].attrs["units"] == "m s-2"


# ----------------------------------------------------------------------------------------------
# TDMS
# ----------------------------------------------------------------------------------------------


def _write_tdms(path: Path, channels, groups=("rig",)) -> Path:
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    objs = [RootObject({"title": "run-up 3"})] + [GroupObject(g) for g in groups]
    for group, name, data, props in channels:
        objs.append(ChannelObject(group, name, data, properties=props))
    with TdmsWriter(str(path)) as w:
        w.write_segment(objs)
    return path


def test_tdms_round_trip(tmp_path):
    t = np.arange(500) / 5000.0
    props = {
        "wf_increment": 1 / 5000.0,
        "wf_start_time": np.datetime64("2024-03-01T08:00:00"),
        "unit_string": "m/s^2",
    }
    acc = np.sin(2 * np.pi * 100 * t)
    path = _write_tdms(
        tmp_path / "r.tdms",
        [("rig", "acc x", acc, props), ("rig", "tacho", np.cos(t), {**props, "unit_string": "V"})],
    )
    ds = read(path)
    assert_layout(ds, 5000.0)
    np.testing.assert_array_equal(ds.acc_x.values, acc)
    assert ds.acc_x.attrs["units"] == "m s-2"
    assert ds.tacho.attrs["units"] == "V"
    assert ds.attrs["time_coverage_start"].startswith("2024-03-01T08:00:00")
    assert ds.attrs["title"] == "run-up 3"


def test_tdms_errors(tmp_path):
    a = {"wf_increment": 1e-3}
    b = {"wf_increment": 5e-4}
    path = _write_tdms(
        tmp_path / "m.tdms",
        [("g1", "x", np.ones(10), a), ("g1", "y", np.ones(10), b), ("g2", "z", np.ones(8), a)],
        groups=("g1", "g2"),
    )
    with pytest.raises(ReaderError, match=r"several groups \['g1', 'g2'\]"):
        read_tdms(path)
    with pytest.raises(ReaderError, match=r"different wf_increment.*'x'.*'y'"):
        read_tdms(path, group="g1")
    assert read_tdms(path, group="g2").sizes["time"] == 8
    with pytest.raises(ReaderError, match="group 'g3' not found"):
        read_tdms(path, group="g3")
    bad = tmp_path / "bad.tdms"
    bad.write_bytes(b"garbage" * 20)
    with pytest.raises(ReaderError, match=r"bad\.tdms.*not a readable TDMS"):
        read_tdms(bad)


def test_tdms_missing_nptdms(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "nptdms", None)
    with pytest.raises(ImportError, match=r'pip install "gearvib\[tdms\]"'):
        read_tdms(tmp_path / "x.tdms")


# ----------------------------------------------------------------------------------------------
# dispatcher
# ----------------------------------------------------------------------------------------------


def test_read_unknown_extension(tmp_path):
    with pytest.raises(ValueError, match=r"extension '\.xyz'.*\.uff"):
        read(tmp_path / "a.xyz")
    with pytest.raises(ValueError, match="format = 'hdf'"):
        read(tmp_path / "a.csv", format="hdf")
