"""Damaged, truncated and oversized files: every reader refuses them with a ReaderError that
names the file and the cause, before allocating what a corrupt header declares.

Inputs follow issue #11: a WAV (RF64) header declaring 10**12 samples in a 2 kB file, a
netCDF-3 header with 2**31 - 1 records, MAT arrays declaring huge dimensions, the MAT
structures that crashed scipy, truncated WAV/CSV/UFF/TDMS/MAT/netCDF files.
"""

from __future__ import annotations

import json
import os
import re
import struct
import subprocess
import sys
import textwrap
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import pytest

from analysis.readers import (
    ChannelData,
    ReaderError,
    build_dataset,
    integrity,
    read,
    read_csv,
    read_mat,
    read_netcdf,
    read_tdms,
    read_wav,
    write_netcdf,
)
from tests.analysis import reader_samples as samples

ROOT = Path(__file__).resolve().parents[2]


def _refused(path: Path, match: str, **options) -> str:
    """Read ``path``; it must raise a ReaderError naming the file and matching ``match``."""
    with pytest.raises(ReaderError, match=match) as err:
        read(path, **options)
    assert str(path) in str(err.value)
    return str(err.value)


def _small_peak(fn, limit: int = 64 * 2**20) -> None:
    """``fn()`` must raise ReaderError with a Python-heap peak below ``limit`` bytes (numpy
    reports its buffers to tracemalloc)."""
    tracemalloc.start()
    try:
        with pytest.raises(ReaderError):
            fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < limit, f"peak {peak / 2**20:.0f} MiB before the refusal"


# ----------------------------------------------------------------------------------------------
# WAV
# ----------------------------------------------------------------------------------------------


def _wav(tmp_path: Path, name: str = "a.wav", **kw) -> tuple[Path, samples.Sample]:
    values = np.random.default_rng(3).uniform(-1, 1, (2, 600))
    s = samples.wav_sample(
        values,
        8000,
        kw.pop("coding", "pcm16"),
        kw.pop("container", "RIFF"),
        kw.pop("extensible", False),
        **kw,
    )
    path = tmp_path / name
    path.write_bytes(s.data)
    return path, s


def test_wav_rf64_declaring_1e12_samples_in_2kB(tmp_path):
    path, _ = _wav(tmp_path, container="RF64")
    data = bytearray(path.read_bytes()[:2048])
    frames = 10**12
    struct.pack_into("<QQQ", data, 20, frames * 4 + 4096, frames * 4, frames)  # ds64 sizes
    path.write_bytes(data)
    _small_peak(lambda: read_wav(path))
    _refused(path, r"header declares 4000000004104 bytes but the file has 2048")


def test_wav_truncated_files_are_refused_where_scipy_reads_fewer_samples(tmp_path):
    """Twelve cuts inside the data chunk: scipy.io.wavfile returns fewer frames without a
    word; read_wav refuses every one, naming the missing bytes."""
    from scipy.io import wavfile

    path, _ = _wav(tmp_path, name="full.wav")
    data = path.read_bytes()
    cuts = 44 + 4 * np.linspace(10, 590, 12).astype(int)  # whole frames of 2 x 16 bit
    for k, cut in enumerate(cuts):
        short = tmp_path / f"cut{k}.wav"
        short.write_bytes(data[:cut])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wavfile.WavFileWarning)
            _, frames = wavfile.read(short)
        assert len(frames) == (cut - 44) // 4  # what the issue saw: silently fewer samples
        _refused(short, "truncated")


@pytest.mark.parametrize(
    ("coding", "container", "extensible"),
    [
        ("pcm8", "RIFF", False),
        ("pcm12", "RIFF", False),
        ("pcm16", "RIFX", False),
        ("pcm20in32", "RIFF", True),
        ("pcm24", "RIFF", True),
        ("pcm24", "RF64", False),
        ("pcm40", "BW64", True),
        ("pcm64", "RIFF", False),
        ("float32", "RIFX", True),
        ("float64", "RF64", True),
    ],
)
def test_wav_codings_read_exact_codes(tmp_path, coding, container, extensible):
    """Files built byte by byte from the specification (independent of the reader): the
    integer codes (valid bits, left-justified) or floats come back exactly."""
    path, s = _wav(
        tmp_path, coding=coding, container=container, extensible=extensible, extra_chunk=True
    )
    ds = read_wav(path)
    for name, values in s.expected.items():
        np.testing.assert_array_equal(ds[name].values, values)
    bits = {"pcm20in32": 20, "pcm24": 24, "pcm40": 40}.get(coding)
    if bits:
        assert ds.ch1.attrs["wav_bits_per_sample"] == bits


def test_wav_agrees_with_scipy_on_standard_files(tmp_path):
    from scipy.io import wavfile

    rng = np.random.default_rng(5)
    for dtype in ("uint8", "int16", "int32", "float32"):
        if dtype.startswith("float"):
            x = rng.uniform(-1, 1, (300, 3)).astype(dtype)
        else:
            info = np.iinfo(dtype)
            x = rng.integers(info.min, info.max, (300, 3), endpoint=True, dtype=dtype)
        path = tmp_path / f"{dtype}.wav"
        wavfile.write(path, 48000, x)
        ds = read_wav(path)
        ref = x.astype(np.float64) - (128 if dtype == "uint8" else 0)
        for i in range(3):
            np.testing.assert_array_equal(ds[f"ch{i + 1}"].values, ref[:, i])


@pytest.mark.parametrize(
    ("patch", "match"),
    [
        (lambda d: struct.pack_into("<H", d, 22, 0), r"channel count 0"),
        (lambda d: struct.pack_into("<H", d, 32, 3), r"block alignment 3 bytes"),
        (lambda d: struct.pack_into("<H", d, 20, 2), r"format tag 0x0002 is not supported"),
        (lambda d: struct.pack_into("<H", d, 34, 48), r"48 bits per sample"),
        (lambda d: struct.pack_into("<I", d, 40, 2398), r"not a whole number of 4-byte frames"),
        (lambda d: d.__setitem__(slice(12, 16), b"junk"), r"no fmt chunk"),
        (lambda d: d.__setitem__(slice(0, 4), b"FORM"), r"not RIFF/RIFX/RF64/BW64"),
    ],
)
def test_wav_corrupt_header_fields(tmp_path, patch, match):
    path, _ = _wav(tmp_path)
    data = bytearray(path.read_bytes())
    patch(data)
    path.write_bytes(data)
    _refused(path, match)


def test_wav_two_data_chunks(tmp_path):
    path, _ = _wav(tmp_path)
    data = path.read_bytes() + b"data" + struct.pack("<I", 4) + b"\0" * 4
    path.write_bytes(data[:4] + struct.pack("<I", len(data) - 8) + data[8:])
    _refused(path, "2 data chunks")


# ----------------------------------------------------------------------------------------------
# CSV
# ----------------------------------------------------------------------------------------------


def test_csv_time_printed_with_8_decimals_at_25600_hz(tmp_path):
    """Rounding to 1e-8 s jitters the 39.0625 us step by 2.6e-4 relative: uniform within the
    print, so accepted; the rate is exactly 25600 Hz and the time axis is the exact grid."""
    n = 200_000
    t = 12.5 + np.arange(n) / 25600.0
    x = np.sin(2 * np.pi * 100 * t)
    path = tmp_path / "daq.csv"
    np.savetxt(
        path,
        np.column_stack([t, x]),
        fmt=["%.8f", "%.6e"],
        delimiter=",",
        header="time [s],acc [m/s2]",
        comments="",
    )
    ds = read_csv(path, time_column="time")
    assert ds.attrs["sample_rate_hz"] == 25600.0
    np.testing.assert_allclose(ds.time.values, t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ds.acc.values, x, rtol=1e-6)
    assert read_csv(path, time_column=0, fs=25600.0).sizes["time"] == n
    with pytest.raises(ValueError, match=r"fs = 25601\.0 Hz disagrees"):
        read_csv(path, time_column=0, fs=25601.0)


def test_csv_missing_or_jittered_sample_is_not_uniform(tmp_path):
    t = np.arange(1000) / 25600.0
    path = tmp_path / "gap.csv"
    np.savetxt(path, np.column_stack([np.delete(t, 500), np.ones(999)]), fmt="%.8f", delimiter=",")
    _refused(path, r"the step from sample index 499 to 500 is 7\.812e-05 s", time_column=0)
    jitter = t.copy()
    jitter[300] += 3e-8  # three times the print resolution
    np.savetxt(path, np.column_stack([jitter, np.ones(1000)]), fmt="%.8f", delimiter=",")
    _refused(path, r"sample index 299 to 300", time_column=0)


def test_csv_truncation(tmp_path):
    """A cut inside a number is refused; a cut at a line end gives the leading rows; a
    complete file without final newline is accepted when the column has a fixed format."""
    v = np.random.default_rng(1).uniform(-1, 1, (2, 50))
    s = samples.csv_sample(v, 1000.0, time_format="%.8f", value_format="%.6e")
    full = s.data
    path = tmp_path / "cut.csv"
    last_nl = full.rfind(b"\n", 0, len(full) - 1)
    path.write_bytes(full[: len(full) - 6])  # inside the last number: "-1.23456"
    msg = _refused(
        path, r"line 51: the file ends without end-of-line .* fewer digits", time_column=0
    )
    assert "e-0" not in msg and "e+0" not in msg  # no file content in the message
    path.write_bytes(full[: last_nl + 1])  # a whole line less
    ds = read_csv(path, time_column=0)
    np.testing.assert_array_equal(ds.ch1.values, s.expected["ch1"][:49])
    path.write_bytes(full[:-1])  # complete, no final newline
    assert read_csv(path, time_column=0).sizes["time"] == 50
    var = samples.csv_sample(v, 1000.0, time_format="%.8f", value_format="%.17g")
    path.write_bytes(var.data[:-1])  # variable width: a cut could not be seen
    _refused(
        path, r"not printed with a fixed number of digits.*end it with a newline", time_column=0
    )


def test_csv_errors_name_line_and_column_without_content(tmp_path):
    rows = [f"{i / 100:.2f},{i}.5" for i in range(150_000)]
    rows[120_000] = "1200.00,0x7fsecret"
    text = "# header comment\n\nt,a\n# a comment line\n" + "\n".join(rows) + "\n"
    path = tmp_path / "bad.csv"
    path.write_text(text)
    msg = _refused(path, r"line 120005, column 2: not a number", time_column=0)
    assert "secret" not in msg and "0x7f" not in msg


def test_csv_layouts_the_c_parser_refuses_still_read(tmp_path):
    """Whitespace-only lines and inline comments go through the line scan; decimal commas
    through the translated fast path; both give the values of a plain file."""
    path = tmp_path / "odd.csv"
    path.write_text("t,a\n0.0,1.5\n   \n0.1,2.5 # note\n\t\n0.2,3.5\n")
    ds = read_csv(path, time_column=0)
    np.testing.assert_array_equal(ds.a.values, [1.5, 2.5, 3.5])
    path.write_text("t;a [g]\n0,0;1,5\n0,1;-2,5\n0,2;3,0\n")
    ds = read_csv(path, time_column="t")
    np.testing.assert_allclose(ds.a.values, 9.80665 * np.array([1.5, -2.5, 3.0]))


def test_csv_memory_guard(tmp_path, monkeypatch):
    path = tmp_path / "m.csv"
    np.savetxt(path, np.ones((20_000, 4)), delimiter=",")
    monkeypatch.setattr(integrity, "available_memory", lambda: 100_000)
    _refused(path, r"about 2e\+04 rows x 4 columns needs .* of memory", fs=1.0)


# ----------------------------------------------------------------------------------------------
# MAT: the scipy segfault and huge dimensions
# ----------------------------------------------------------------------------------------------


def _tag(mdtype: int, data: bytes) -> bytes:
    return struct.pack("<II", mdtype, len(data)) + data + b"\0" * (-len(data) % 8)


def _matrix(mclass: int, dims: list[int], name: bytes, *parts: bytes, flags: int = 0) -> bytes:
    body = (
        _tag(6, struct.pack("<II", mclass | flags, 0))
        + _tag(5, struct.pack(f"<{len(dims)}i", *dims))
        + _tag(1, name)
        + b"".join(parts)
    )
    return struct.pack("<II", 14, len(body)) + body


def _mat5(*elements: bytes) -> bytes:
    head = b"MATLAB 5.0 MAT-file, crafted by the gearvib tests".ljust(116) + b"\0" * 8
    return head + struct.pack("<H", 0x0100) + b"IM" + b"".join(elements)


_ACC = np.arange(4.0).tobytes()
_ONE = np.ones(1).tobytes()

#: Files on which scipy.io.loadmat (1.17) dies with SIGSEGV (all but the last, which raised
#: ZeroDivisionError), and what read_mat says instead.
CRASHERS = {
    "numeric type 0": (_mat5(_matrix(6, [1, 4], b"acc", _tag(0, _ACC))), "data type 0;"),
    "numeric type 11": (_mat5(_matrix(6, [1, 4], b"acc", _tag(11, _ACC))), "data type 11;"),
    "numeric type 14": (_mat5(_matrix(6, [1, 4], b"acc", _tag(14, _ACC))), r"type 14 \(miMATRIX"),
    "numeric type 20": (_mat5(_matrix(6, [1, 4], b"acc", _tag(20, _ACC))), "data type 20;"),
    "numeric type 1000": (_mat5(_matrix(6, [1, 4], b"acc", _tag(1000, _ACC))), "type 1000;"),
    "complex flag, no imaginary part": (
        _mat5(
            _matrix(6, [1, 4], b"acc", _tag(9, _ACC), flags=0x800),
            _matrix(6, [1, 1], b"fs", _tag(9, _ONE)),
        ),
        "imaginary part needs 8 bytes",
    ),
    "char type 11": (_mat5(_matrix(4, [1, 4], b"txt", _tag(11, b"abcd"))), "characters have"),
    "struct name length 0": (
        _mat5(
            _matrix(
                2,
                [1, 1],
                b"s",
                struct.pack("<HHI", 5, 4, 0),
                _tag(1, b"ab\0\0"),
                _matrix(6, [1, 1], b"", _tag(9, _ONE)),
            )
        ),
        "field-name length",
    ),
}

#: Dimensions scipy would allocate for before reading anything (cells, structs, blank chars).
HUGE = {
    "cell of 2**31-1 elements": (_mat5(_matrix(1, [1, 2**31 - 1], b"c")), "declares 2147483647"),
    "blank char of 4e18 characters": (
        _mat5(_matrix(4, [2**31 - 1, 2**31 - 1], b"t", _tag(16, b""))),
        "needs .* of memory",
    ),
    "double 2**31-1 x 2**31-1": (
        _mat5(_matrix(6, [2**31 - 1, 2**31 - 1], b"x", _tag(9, _ACC))),
        "dimensions declare 4611686014132420609 values",
    ),
    "negative dimension": (_mat5(_matrix(6, [1, -4], b"x", _tag(9, _ACC))), r"\[1, -4\]"),
    "v4 matrix of 2**31-1 x 2**31-1": (
        struct.pack("<5i", 0, 2**31 - 1, 2**31 - 1, 0, 2) + b"x\0" + _ACC,
        "declares data up to byte",
    ),
}


def test_mat_crafted_crashers_are_refused_in_a_subprocess(tmp_path):
    """Each file is read by read_mat in a child process: a regression of the structure check
    would crash the child (reported here with its signal), not the test session."""
    cases = {**CRASHERS, **HUGE}
    for i, (data, _) in enumerate(cases.values()):
        (tmp_path / f"case{i}.mat").write_bytes(data)
    script = textwrap.dedent(
        """
        import json, sys
        from analysis.readers import read_mat, ReaderError
        out = []
        for path in sys.argv[1:]:
            try:
                read_mat(path, fs=1.0)
                out.append("accepted")
            except ReaderError as exc:
                out.append(str(exc))
            except Exception as exc:
                out.append(f"OTHER {type(exc).__name__}: {exc}")
        print(json.dumps(out))
        """
    )
    paths = [str(tmp_path / f"case{i}.mat") for i in range(len(cases))]
    proc = subprocess.run(
        [sys.executable, "-c", script, *paths],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert proc.returncode == 0, f"child died (signal {-proc.returncode}): {proc.stderr[-500:]}"
    messages = json.loads(proc.stdout)
    for (name, (_, match)), msg, path in zip(cases.items(), messages, paths, strict=True):
        assert path in msg, f"{name}: {msg}"
        assert re.search(match, msg), f"{name}: {msg!r} !~ {match!r}"


def test_mat_huge_dimensions_allocate_nothing(tmp_path):
    for i, (data, _) in enumerate(HUGE.values()):
        path = tmp_path / f"h{i}.mat"
        path.write_bytes(data)
        _small_peak(lambda path=path: read_mat(path, fs=1.0))


def test_mat_compressed_variable_beyond_memory(tmp_path, monkeypatch):
    from scipy.io import savemat

    path = tmp_path / "bomb.mat"
    savemat(path, {"x": np.zeros(2_000_000), "fs": 1.0}, do_compression=True)
    assert path.stat().st_size < 100_000  # 16 MB of zeros compress ~1000:1
    monkeypatch.setattr(integrity, "available_memory", lambda: 4_000_000)
    _refused(path, r"needs .* of memory, but only .* can be used")


def test_mat_truncated_and_unreadable_variable(tmp_path):
    from scipy.io import savemat

    path = tmp_path / "t.mat"
    savemat(path, {"acc": np.ones(100), "fs": 10.0})
    data = path.read_bytes()
    path.write_bytes(data[:-100])
    _refused(path, r"not a readable MAT file: variable 0 .* declares data up to byte .* truncated")


def test_mat_deep_nesting_is_refused(tmp_path):
    inner = _matrix(6, [1, 1], b"", _tag(9, _ONE))
    for _ in range(80):
        inner = _matrix(1, [1, 1], b"", inner)
    path = tmp_path / "deep.mat"
    path.write_bytes(_mat5(inner))
    _refused(path, "nested deeper than 64 levels", fs=1.0)


# ----------------------------------------------------------------------------------------------
# netCDF
# ----------------------------------------------------------------------------------------------


@pytest.fixture
def nc3(tmp_path) -> Path:
    path = tmp_path / "c3.nc"
    v = np.random.default_rng(2).uniform(-1, 1, (1, 40))
    path.write_bytes(samples.netcdf_sample(v, 100.0, version=3).data)
    return path


def test_netcdf3_with_2_31_records(tmp_path):
    """A record dimension with 2**31 - 1 records in a 1 kB file (xarray allocated 16 GiB)."""
    ds = build_dataset([ChannelData("a", np.arange(10.0))], 10.0, source_format="t")
    path = tmp_path / "rec.nc"
    enc = {v: {"_FillValue": None} for v in ds.variables}
    ds.to_netcdf(path, format="NETCDF3_CLASSIC", unlimited_dims=["time"], encoding=enc)
    data = bytearray(path.read_bytes())
    struct.pack_into(">i", data, 4, 2**31 - 1)
    path.write_bytes(data)
    _small_peak(lambda: read_netcdf(path))
    _refused(path, r"2147483647 records of variable .* end at byte \d+, but the file has")


def test_netcdf3_attribute_length_beyond_the_file(nc3):
    """The length of the 'Conventions' text set to ~4e9: netCDF-C allocated 4 GiB while
    parsing the header; the header walk refuses it first."""
    data = bytearray(nc3.read_bytes())
    at = data.index(b"Conventions") + len(b"Conventions") + 1 + 4  # after padding and type
    at = data.index(struct.pack(">I", 7), at - 4)
    data[at] = 0xFF
    nc3.write_bytes(data)
    _refused(nc3, r"global attribute 'Conventions' length = 4278190087 .* corrupt header")


def test_netcdf3_truncated(nc3):
    nc3.write_bytes(nc3.read_bytes()[:-8])
    _refused(nc3, r"variable '\w+' end at byte .* truncated")


def test_netcdf4_checksum_finds_a_flipped_data_byte(tmp_path):
    import h5py

    ds = build_dataset([ChannelData("a", np.linspace(0, 1, 500), "V")], 100.0, source_format="t")
    path = write_netcdf(ds, tmp_path / "c.nc")
    with h5py.File(path) as fh:
        info = fh["a"].id.get_chunk_info(0)
    data = bytearray(path.read_bytes())
    data[info.byte_offset + info.size // 2] ^= 0x10
    path.write_bytes(data)
    _refused(path, "not a readable netCDF file")


def test_netcdf4_declaring_more_than_zlib_can_hold(tmp_path):
    import netCDF4

    path = tmp_path / "huge.nc"
    with netCDF4.Dataset(path, "w") as nc:
        nc.createDimension("time", 10**10)
        nc.createVariable("a", "f8", ("time",), zlib=True, chunksizes=(2**20,))
    _small_peak(lambda: read_netcdf(path))
    _refused(path, r"declares 74.5 GiB of variable data .* more than zlib")


# ----------------------------------------------------------------------------------------------
# TDMS and UFF
# ----------------------------------------------------------------------------------------------


def test_tdms_truncated_segment_is_refused_where_nptdms_reads_fewer(tmp_path):
    from nptdms import TdmsFile

    v = np.random.default_rng(4).uniform(-1, 1, (2, 300))
    path = tmp_path / "t.tdms"
    path.write_bytes(samples.tdms_bytes(v, 1e-3, segments=2)[:-100])
    assert len(TdmsFile.read(str(path))["rig"]["acc 1"]) < 300  # silently fewer
    _refused(path, r"segment 1 at byte \d+ declares \d+ bytes .* truncated")


def test_tdms_incomplete_segment_and_huge_value_count(tmp_path):
    v = np.random.default_rng(4).uniform(-1, 1, (1, 100))
    data = bytearray(samples.tdms_bytes(v, 1e-3, segments=1))
    path = tmp_path / "t.tdms"
    path.write_bytes(data[:12] + b"\xff" * 8 + data[20:])
    _refused(path, "never completed")
    # the raw-data index of 'acc 0': length 20, type 10 (double), dimension 1, count 100
    index = struct.pack("<III", 20, 10, 1) + struct.pack("<Q", 100)
    at = data.index(index) + 12
    struct.pack_into("<Q", data, at, 10**12)
    path.write_bytes(data)
    _small_peak(lambda: read_tdms(path))  # npTDMS caps the count at the data present ...
    _refused(path, r"npTDMS reports .* not a multiple of the chunk size")  # ... and says so


def test_uff_truncated_second_set_is_refused_where_pyuff_drops_it(tmp_path):
    import pyuff

    v = np.random.default_rng(6).uniform(-1, 1, (2, 200))
    data = samples.uff_bytes(v, 1e-3, binary=0)
    path = tmp_path / "u.uff"
    path.write_bytes(data[: len(data) - 300])
    assert len(pyuff.UFF(str(path)).get_set_types()) == 1  # the cut set disappears
    _refused(path, r"3 '-1' block delimiters; .* last dataset is incomplete")
    values = np.random.default_rng(6).uniform(-1, 1, (1, 50))
    bad = samples.uff_bytes(values, 1e-3, binary=0).replace(b"        50", b"    500000", 1)
    path.write_bytes(bad)
    _refused(path, r"declares 500000 samples but holds 50")


# ----------------------------------------------------------------------------------------------
# the shared checks
# ----------------------------------------------------------------------------------------------


def test_reading_turns_parser_failures_into_reader_errors(tmp_path):
    path = tmp_path / "x.dat"
    match = r"x\.dat: not a readable XYZ file .* ZeroDivisionError"
    with pytest.raises(ReaderError, match=match), integrity.reading(path, "XYZ"):
        1 / 0  # noqa: B018
    with (
        pytest.raises(ReaderError, match="needs more memory than is available"),
        integrity.reading(path, "XYZ"),
    ):
        raise MemoryError
    with pytest.raises(ImportError), integrity.reading(path, "XYZ"):
        raise ImportError("pip install it")


def test_describe_masks_file_content():
    exc = ValueError("could not convert string to float: 'root:x:0:0:secret'")
    assert integrity.describe(exc) == "ValueError: could not convert string to float: '…'"
    assert len(integrity.describe(ValueError("x" * 5000))) < 300


def test_available_memory_and_guard(monkeypatch, tmp_path):
    avail = integrity.available_memory()
    assert 0 < avail <= os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    monkeypatch.setattr(integrity, "available_memory", lambda: 1000)
    with pytest.raises(ReaderError, match=r"f\.bin: 3 channels needs 2 kB of memory"):
        integrity.require_memory(2000, tmp_path / "f.bin", "3 channels")
    integrity.require_memory(700, tmp_path / "f.bin", "3 channels")


def test_issue_inputs_do_not_allocate_gib_in_a_bounded_child(tmp_path):
    """The oversized inputs read in a child whose address space is limited to its size plus
    512 MiB: a header-declared allocation that slipped past a guard fails the child."""
    wav, _ = _wav(tmp_path, container="RF64")
    data = bytearray(wav.read_bytes()[:2048])
    struct.pack_into("<QQQ", data, 20, 4 * 10**12 + 4096, 4 * 10**12, 10**12)
    wav.write_bytes(data)
    ds = build_dataset([ChannelData("a", np.arange(10.0))], 10.0, source_format="t")
    nc = tmp_path / "rec.nc"
    enc = {v: {"_FillValue": None} for v in ds.variables}
    ds.to_netcdf(nc, format="NETCDF3_CLASSIC", unlimited_dims=["time"], encoding=enc)
    raw = bytearray(nc.read_bytes())
    struct.pack_into(">i", raw, 4, 2**31 - 1)
    at = raw.index(struct.pack(">I", 7), raw.index(b"Conventions"))
    raw[at] = 0xFF
    nc.write_bytes(raw)
    mats = []
    for i, (blob, _) in enumerate(HUGE.values()):
        mats.append(tmp_path / f"h{i}.mat")
        mats[-1].write_bytes(blob)
    script = textwrap.dedent(
        """
        import resource, sys
        from analysis.readers import read, ReaderError
        with open("/proc/self/statm") as fh:
            vm = int(fh.read().split()[0]) * resource.getpagesize()
        limit = vm + 512 * 2**20
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        for path in sys.argv[1:]:
            try:
                read(path, **({"fs": 1.0} if path.endswith(".mat") else {}))
                print("accepted", path)
            except ReaderError as exc:
                print("refused", exc)
        """
    )
    paths = [str(p) for p in (wav, nc, *mats)]
    proc = subprocess.run(
        [sys.executable, "-c", script, *paths],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr[-800:]
    lines = proc.stdout.splitlines()
    assert len(lines) == len(paths) and all(line.startswith("refused") for line in lines), lines
    assert "needs more memory" not in proc.stdout  # refused by a guard, not by MemoryError


def test_reader_error_is_a_value_error_and_missing_files_are_os_errors(tmp_path):
    assert issubclass(ReaderError, ValueError)
    for suffix in (".wav", ".csv", ".mat", ".nc", ".uff", ".tdms"):
        with pytest.raises(FileNotFoundError, match=r"missing\."):
            read(tmp_path / f"missing{suffix}", **({"fs": 1.0} if suffix == ".csv" else {}))


# ----------------------------------------------------------------------------------------------
# the printed time axis
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("fmt", "fs", "n", "start"),
    [
        ("%.8f", 25600.0, 100_000, 0.0),
        ("%.8f", 51200.0, 50_000, 3600.0),
        ("%.6e", 51200.0, 3_000, 0.0),
        ("%.17g", 3000.0, 10_000, 0.25),
        ("%.6g", 1000.0, 5_000, 0.0),
        ("%.3f", 100.0, 1_000, 7.0),
    ],
)
def test_uniform_rate_within_the_print(fmt, fs, n, start):
    """A uniform grid printed with a given format is accepted at its exact rate; a missing
    sample is named by the step it makes; a shift of 3 print units is refused."""
    from analysis.readers.timebase import print_precision, uniform_rate

    t = start + np.arange(n) / fs
    tokens = [fmt % v for v in t]
    printed = np.array([float(x) for x in tokens])
    precision = print_precision(tokens[:1000] + tokens[-1000:])
    rate, t0 = uniform_rate(printed, precision)
    assert rate == fs and t0 == printed[0]
    gap = np.delete(printed, n // 2)
    with pytest.raises(ValueError, match=f"step from sample index {n // 2 - 1} to {n // 2}"):
        uniform_rate(gap, precision)
    shifted = printed.copy()
    shifted[n // 3] += 3 * float(precision.bound(shifted[n // 3 : n // 3 + 1])[0]) * 2
    with pytest.raises(ValueError, match=f"sample index {n // 3 - 1} to {n // 3}|index {n // 3}"):
        uniform_rate(shifted, precision)


def test_print_precision_of_common_formats():
    from analysis.readers.timebase import print_precision

    assert print_precision(["0.00000000", "0.00003906"]).absolute == 1e-8
    dyadic = ["0", "0.5", "0.0009765625", "0.0029296875"]  # %.17g of i / 1024 s
    assert print_precision(dyadic).absolute == pytest.approx(1e-10)
    p = print_precision(["0.000000e+00", "3.906250e-05"])
    assert (p.absolute, p.relative) == (0.0, pytest.approx(1e-6))
    assert print_precision(["1", "2", "3"]).absolute == 1.0


def test_uff_and_tdms_memory_guards(tmp_path, monkeypatch):
    v = np.random.default_rng(8).uniform(-1, 1, (2, 4000))
    uff = tmp_path / "m.uff"
    uff.write_bytes(samples.uff_bytes(v, 1e-3, binary=0))
    tdms = tmp_path / "m.tdms"
    tdms.write_bytes(samples.tdms_bytes(v, 1e-3))
    monkeypatch.setattr(integrity, "available_memory", lambda: 50_000)
    _refused(uff, r"pyuff's parse of the file needs .* of memory")
    _refused(tdms, r"group 'rig' .* needs .* of memory")


def test_write_netcdf_refuses_a_fifo_and_leaves_it_in_place(tmp_path):
    """A device, FIFO or socket is not replaced by the atomic rename (as root, a write to
    /dev/null would have made it a regular file); a FIFO stands in for a device here."""
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    ds = build_dataset([ChannelData("a", np.linspace(0, 1, 50), "V")], 100.0, source_format="t")
    with pytest.raises(ValueError, match="pipe is not a regular file"):
        write_netcdf(ds, fifo)
    assert fifo.is_fifo() and list(tmp_path.iterdir()) == [fifo]
