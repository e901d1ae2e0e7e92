"""Tests of the MATLAB v7.3 (HDF5) path of analysis.readers.read_mat.

The v7.3 files are written here with h5py the way MATLAB writes them (512-byte userblock with
the ``MATLAB 7.3 MAT-file`` header, ``MATLAB_class`` attributes, column-major arrays stored
with reversed dimensions, char as UTF-16 ``uint16``, structs as groups, cells as references
into ``#refs#``, empties as ``MATLAB_empty`` dimension vectors). The same content is written
as a v5 file with :func:`scipy.io.savemat`, and both must read into the same Dataset.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr
from scipy.io import savemat

from analysis.readers import ReaderError, read, read_mat
from analysis.readers.mat73 import MatlabObject, is_mat73, load_mat73

FS = 1000.0
HEADER_TEXT = (
    b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  8 10:00:00 2024 "
    b"HDF5 schema 1.00 ."
)

_CLASSES = {
    np.dtype(np.float64): "double",
    np.dtype(np.float32): "single",
    np.dtype(np.int8): "int8",
    np.dtype(np.uint8): "uint8",
    np.dtype(np.int16): "int16",
    np.dtype(np.uint16): "uint16",
    np.dtype(np.int32): "int32",
    np.dtype(np.uint32): "uint32",
    np.dtype(np.int64): "int64",
    np.dtype(np.uint64): "uint64",
    np.dtype(np.complex128): "double",
    np.dtype(np.complex64): "single",
}


# ----------------------------------------------------------------------------------------------
# a MATLAB-like v7.3 writer (test helper)
# ----------------------------------------------------------------------------------------------


def _mat_header() -> bytes:
    """The 512-byte userblock: 116 bytes of text, 8 bytes subsystem offset, version 0x0200 and
    the 'IM' endian indicator, then zeros."""
    head = HEADER_TEXT.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02" + b"IM"
    return head.ljust(512, b"\0")


def _class_attr(obj: Any, name: str) -> None:
    obj.attrs.create("MATLAB_class", np.bytes_(name))


def _matlab_shape(arr: np.ndarray) -> tuple[int, ...]:
    """MATLAB's shape of a value as scipy.io.savemat writes it (1-D -> row, scalar -> 1x1)."""
    if arr.ndim == 0:
        return (1, 1)
    if arr.ndim == 1:
        return (1, arr.size)
    return arr.shape


def _write_value(h5py: Any, parent: Any, name: str, value: Any, refs: Any) -> Any:
    if isinstance(value, dict):
        grp = parent.create_group(name)
        _class_attr(grp, "struct")
        vlen = h5py.vlen_dtype(np.dtype("S1"))
        fields = np.empty(len(value), dtype=object)
        for i, key in enumerate(value):
            fields[i] = np.frombuffer(key.encode("ascii"), dtype="S1")
        grp.attrs.create("MATLAB_fields", fields, dtype=vlen)
        for key, item in value.items():
            _write_value(h5py, grp, key, item, refs)
        return grp
    if isinstance(value, list) or (isinstance(value, np.ndarray) and value.dtype == object):
        cell = np.empty((1, len(value)), dtype=object)  # a cell row
        for j, item in enumerate(value):
            ref_name = f"{len(refs)}_{name}_{j}"
            cell[0, j] = _write_value(h5py, refs, ref_name, item, refs).ref
        dset = parent.create_dataset(name, data=cell.T, dtype=h5py.ref_dtype)
        _class_attr(dset, "cell")
        return dset
    if isinstance(value, str):
        codes = np.frombuffer(value.encode("utf-16-le"), dtype="<u2").reshape(1, -1)
        arr, cls = codes, "char"
    else:
        arr = np.asarray(value)
        if arr.dtype == np.bool_:
            arr, cls = arr.astype(np.uint8), "logical"
        else:
            cls = _CLASSES[arr.dtype]
        arr = arr.reshape(_matlab_shape(arr))
    if arr.size == 0:
        dset = parent.create_dataset(name, data=np.array(arr.shape, dtype=np.uint64))
        dset.attrs.create("MATLAB_empty", np.uint8(1))
    elif arr.dtype.kind == "c":
        part = arr.real.dtype
        compound = np.dtype([("real", part), ("imag", part)])
        stored = np.empty(arr.shape, dtype=compound)
        stored["real"], stored["imag"] = arr.real, arr.imag
        dset = parent.create_dataset(name, data=stored.T)
    else:
        dset = parent.create_dataset(name, data=arr.T)  # column-major: dimensions reversed
    _class_attr(dset, cls)
    if cls == "char":
        dset.attrs.create("MATLAB_int_decode", np.int32(2))
    return dset


def savemat73(path: Path, content: dict[str, Any]) -> Path:
    """Write ``content`` as MATLAB ``save(path, ..., '-v7.3')`` would."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w", userblock_size=512) as fh:
        refs = fh.create_group("#refs#")
        for name, value in content.items():
            _write_value(h5py, fh, name, value, refs)
        if not len(refs):
            del fh["#refs#"]
    with open(path, "r+b") as fh:
        fh.write(_mat_header())
    return path


def _both(tmp_path: Path, content: dict[str, Any], **options: Any) -> tuple[xr.Dataset, ...]:
    """Read ``content`` written as v5 (scipy) and as v7.3 (h5py); return both Datasets."""
    v5 = tmp_path / "v5.mat"
    savemat(v5, content, format="5")
    v73 = savemat73(tmp_path / "v73.mat", content)
    return read_mat(v5, **options), read_mat(v73, **options)


def assert_same_reading(ds5: xr.Dataset, ds73: xr.Dataset) -> None:
    """Same variables in the same order, values, dtypes, time axis and attributes, apart from
    the file name and the format tag."""
    assert list(ds73.data_vars) == list(ds5.data_vars)
    for var in ds5.data_vars:
        assert ds73[var].dtype == ds5[var].dtype, var
    np.testing.assert_array_equal(ds73["time"].values, ds5["time"].values)
    drop = ("source_file", "source_format")
    a = ds5.assign_attrs({k: "" for k in drop})
    b = ds73.assign_attrs({k: "" for k in drop})
    xr.testing.assert_identical(a, b)
    assert ds5.attrs["source_format"] == "mat"
    assert ds73.attrs["source_format"] == "mat73"


def _signal(n: int = 256) -> dict[str, Any]:
    t = np.arange(n) / FS
    return {
        "Fs": FS,
        "acc": np.stack([np.sin(2 * np.pi * 50 * t), 0.5 * np.cos(2 * np.pi * 120 * t)], 1),
        "comment": "ring gear accelerometers, run 3",
        "gain": np.int16(4),
        "mic": (0.2 * np.sin(2 * np.pi * 310 * t)).astype(np.float32),
        "time": 0.25 + t,
        "units": {"acc": "g", "mic": "Pa", "tacho": "rpm"},
        "tacho": 1500.0 + 10.0 * t,
    }


# ----------------------------------------------------------------------------------------------
# the file written by the helper looks like MATLAB's
# ----------------------------------------------------------------------------------------------


def test_helper_writes_matlab_layout(tmp_path):
    h5py = pytest.importorskip("h5py")
    path = savemat73(tmp_path / "m.mat", {"x": np.arange(6.0).reshape(3, 2), "s": "ab"})
    raw = path.read_bytes()
    assert raw.startswith(b"MATLAB 7.3 MAT-file")
    assert raw[124:128] == b"\x00\x02IM"
    assert raw[512:520] == b"\x89HDF\r\n\x1a\n"
    with h5py.File(path, "r") as fh:
        assert fh.userblock_size == 512
        assert fh["x"].shape == (2, 3)  # MATLAB 3x2 stored transposed
        assert fh["x"].attrs["MATLAB_class"] == b"double"
        assert fh["s"].dtype == np.uint16
        assert fh["s"].attrs["MATLAB_class"] == b"char"
    assert is_mat73(path)


# ----------------------------------------------------------------------------------------------
# round trips: v7.3 reads exactly like v5
# ----------------------------------------------------------------------------------------------


def test_round_trip_time_vector_units_struct(tmp_path):
    content = _signal()
    ds5, ds73 = _both(tmp_path, content, time_variable="time")
    assert_same_reading(ds5, ds73)
    assert list(ds73.data_vars) == ["acc_1", "acc_2", "mic", "tacho"]
    assert ds73.time.values[0] == 0.25
    assert ds73.attrs["sample_rate_hz"] == pytest.approx(FS)
    np.testing.assert_array_equal(ds73.acc_2.values, content["acc"][:, 1] * 9.80665)
    assert ds73.acc_1.attrs["units"] == "m s-2"
    assert ds73.acc_1.attrs["source_units"] == "g"
    assert ds73.mic.dtype == np.float32
    assert ds73.mic.attrs["units"] == "Pa"
    assert ds73.tacho.attrs["units"] == "min-1"
    assert ds73.attrs["mat_scalar_gain"] == 4.0


def test_round_trip_fs_scalar_and_wide_matrix(tmp_path):
    data = np.arange(30.0).reshape(3, 10)  # channels in rows: samples along the longer axis
    ds5, ds73 = _both(tmp_path, {"acc": data, "Fs": 500.0}, units="m/s2")
    assert_same_reading(ds5, ds73)
    assert list(ds73.data_vars) == ["acc_1", "acc_2", "acc_3"]
    np.testing.assert_array_equal(ds73.acc_2.values, data[1])
    assert ds73.attrs["sample_rate_hz"] == 500.0
    assert ds73.acc_1.attrs["units"] == "m s-2"


@pytest.mark.parametrize(
    "options",
    [
        {"fs": "rate", "variables": ["b", "a"]},
        {"fs": 250.0, "units": ["N", "V"], "variables": ["a", "c"]},
        {"fs": 250.0, "units": {"a": "m/s²", "c": "deg"}},
    ],
)
def test_round_trip_options(tmp_path, options):
    n = 40
    content = {
        "a": np.linspace(-1.0, 1.0, n),
        "b": np.arange(n, dtype=np.int32),
        "c": np.arange(n, dtype=np.uint8) % 2 == 0,  # logical: uint8 in both versions
        "rate": 250,
        "z": np.exp(1j * np.arange(n)),  # complex: not a channel in either version
        "cellvar": np.array(["x", np.arange(3.0)], dtype=object),  # cell: ignored
    }
    ds5, ds73 = _both(tmp_path, content, **options)
    assert_same_reading(ds5, ds73)
    assert ds73.attrs["sample_rate_hz"] == 250.0


def test_channel_names_sanitised_alike(tmp_path):
    content = {"fs": 100.0, "for": np.ones(5), "time": np.arange(5.0) / 100.0, "x1": np.ones(5)}
    ds5, ds73 = _both(tmp_path, content)  # no time_variable: 'time' is an ordinary channel
    assert_same_reading(ds5, ds73)
    assert list(ds73.data_vars) == ["for_ch", "time_ch", "x1"]


def test_channel_order_is_order_of_saving(tmp_path):
    """HDF5 lists names alphabetically; the channels keep the order the file was written in."""
    content = {"zeta": np.ones(6), "fs": 2.0, "alpha": np.zeros(6), "mid": np.arange(6.0)}
    ds5, ds73 = _both(tmp_path, content)
    assert_same_reading(ds5, ds73)
    assert list(ds73.data_vars) == ["zeta", "alpha", "mid"]


def test_read_dispatches_on_header(tmp_path):
    path = savemat73(tmp_path / "run.mat", {"fs": 10.0, "x": np.arange(4.0)})
    ds = read(path)
    np.testing.assert_array_equal(ds.x.values, np.arange(4.0))
    assert ds.attrs["source_format"] == "mat73"


def test_load_mat73_decodes_like_loadmat(tmp_path):
    from scipy.io import loadmat

    content = {
        "col": np.arange(3.0).reshape(3, 1),
        "cube": np.arange(24, dtype=np.int16).reshape(2, 3, 4),
        "empty": np.zeros((0, 3)),
        "name": "Zahnrad ä",
        "one": 1.5,
        "cellvar": np.array(["ab", np.arange(3.0)], dtype=object),
    }
    v5 = tmp_path / "v5.mat"
    savemat(v5, content, format="5")
    ref = loadmat(v5, squeeze_me=True, chars_as_strings=True)
    got = load_mat73(savemat73(tmp_path / "v73.mat", content))
    assert list(got) == list(content)
    for key in content:
        if key == "cellvar":
            assert got[key].shape == ref[key].shape == (2,)
            assert got[key][0] == ref[key][0] == "ab"
            np.testing.assert_array_equal(got[key][1], ref[key][1])
            continue
        np.testing.assert_array_equal(got[key], ref[key])
        assert np.asarray(got[key]).dtype == np.asarray(ref[key]).dtype, key
        assert np.shape(got[key]) == np.shape(ref[key]), key


def test_structs_cells_and_objects(tmp_path):
    h5py = pytest.importorskip("h5py")
    path = savemat73(
        tmp_path / "s.mat",
        {"fs": 100.0, "info": {"rig": "B2", "load": 0.8, "tags": ["a", "bc"]}, "x": np.ones(4)},
    )
    with h5py.File(path, "r+") as fh:  # a MATLAB string object: opaque uint32 handle
        obj = fh.create_dataset("label", data=np.array([[3707764736], [2], [1]], np.uint32))
        _class_attr(obj, "string")
        obj.attrs.create("MATLAB_object_decode", np.int32(3))
    got = load_mat73(path)
    assert got["info"]["rig"] == "B2"
    assert got["info"]["load"] == 0.8
    assert list(got["info"]["tags"]) == ["a", "bc"]
    assert isinstance(got["label"], MatlabObject)
    assert "#refs#" not in got
    ds = read_mat(path)
    assert list(ds.data_vars) == ["x"]
    with pytest.raises(ReaderError, match=r"'label' is not numeric"):
        read_mat(path, variables=["label"])


def test_struct_array_and_sparse(tmp_path):
    """s(1).a = 1; s(2).a = 'two' (fields hold references) and sparse([1 0; 0 2.5]), written
    by hand as MATLAB lays them out; read_mat skips both, as for v5."""
    h5py = pytest.importorskip("h5py")
    path = savemat73(tmp_path / "sa.mat", {"fs": 10.0, "x": np.arange(3.0)})
    with h5py.File(path, "r+") as fh:
        refs = fh.require_group("#refs#")
        one = _write_value(h5py, refs, "r1", 1.0, refs)
        two = _write_value(h5py, refs, "r2", "two", refs)
        grp = fh.create_group("s")
        _class_attr(grp, "struct")
        grp.create_dataset("a", data=np.array([[one.ref], [two.ref]]), dtype=h5py.ref_dtype)
        sp = fh.create_group("sp")
        _class_attr(sp, "double")
        sp.attrs.create("MATLAB_sparse", np.uint64(2))
        sp.create_dataset("data", data=np.array([1.0, 2.5]))
        sp.create_dataset("ir", data=np.array([0, 1], dtype=np.uint64))
        sp.create_dataset("jc", data=np.array([0, 1, 2], dtype=np.uint64))
    got = load_mat73(path)
    assert [item["a"] for item in got["s"]] == [1.0, "two"]
    np.testing.assert_array_equal(got["sp"].toarray(), [[1.0, 0.0], [0.0, 2.5]])
    assert list(read_mat(path).data_vars) == ["x"]


# ----------------------------------------------------------------------------------------------
# errors: the same as for v5
# ----------------------------------------------------------------------------------------------


def _messages(tmp_path: Path, content: dict[str, Any], **options: Any) -> tuple[str, str]:
    v5 = tmp_path / "v5.mat"
    savemat(v5, content, format="5")
    v73 = savemat73(tmp_path / "v73.mat", content)
    out = []
    for path in (v5, v73):
        with pytest.raises((ReaderError, ValueError)) as info:
            read_mat(path, **options)
        out.append((type(info.value), str(info.value).replace(str(path), "<file>")))
    assert out[0] == out[1]
    return out[1]


def test_nan_channel_error(tmp_path):
    x = np.ones(50)
    x[17] = np.nan
    kind, msg = _messages(tmp_path, {"fs": 100.0, "acc": x})
    assert kind is ReaderError
    assert "'acc' in <file>: 1 NaN/inf sample(s), first at sample index 17" in msg


def test_empty_channel_error(tmp_path):
    kind, msg = _messages(tmp_path, {"fs": 100.0, "acc": np.zeros(0)}, variables=["acc"])
    assert kind is ReaderError
    assert "'acc' in <file> is empty" in msg


def test_empty_variables_are_not_channels(tmp_path):
    """MATLAB's [] (an empty variable) is skipped when the channels are found automatically."""
    for ds in _both(tmp_path, {"fs": 100.0, "none": np.zeros(0), "acc": np.ones(5)}):
        assert list(ds.data_vars) == ["acc"]


def test_rate_mismatch_error(tmp_path):
    content = {"time": np.arange(10) / 100.0, "x": np.ones(10)}
    kind, msg = _messages(tmp_path, content, fs=200.0, time_variable="time")
    assert kind is ValueError
    assert "fs = 200.0 Hz disagrees with 'time'" in msg


@pytest.mark.parametrize(
    ("content", "options", "expected"),
    [
        ({"x": np.ones(5)}, {}, "no sample rate"),
        ({"a": np.ones(5), "b": np.ones(6), "fs": 10.0}, {}, "unequal length"),
        ({"a": np.ones(5), "fs": 10.0}, {"variables": ["nope"]}, r"\['nope'\] not in the file"),
        ({"a": np.ones(5), "s": "txt", "fs": 1.0}, {"variables": ["s"]}, "'s' is not numeric"),
        ({"a": np.ones(5)}, {"fs": "rate"}, "'rate' is not a numeric scalar"),
        ({"t": np.array([0.0, 1.0, 3.0]), "a": np.ones(3)}, {"time_variable": "t"}, "uniform"),
    ],
)
def test_other_errors_match_v5(tmp_path, content, options, expected):
    _, msg = _messages(tmp_path, content, **options)
    assert re.search(expected, msg), msg


def test_truncated_file_error(tmp_path):
    full = savemat73(tmp_path / "full.mat", _signal(4096))
    cut = tmp_path / "cut.mat"
    cut.write_bytes(full.read_bytes()[: full.stat().st_size // 2])
    with pytest.raises(ReaderError, match=r"cut\.mat: not a readable MATLAB v7\.3.*truncated"):
        read_mat(cut)
    with pytest.raises(ReaderError, match=r"cut\.mat: not a readable MATLAB v7\.3"):
        read(cut, fs=1.0)


def test_header_without_hdf5_data(tmp_path):
    """Only the MAT header survived: caught from the header alone, h5py or not."""
    stub = tmp_path / "stub.mat"
    stub.write_bytes(_mat_header()[:300])
    assert is_mat73(stub)
    with pytest.raises(ReaderError, match=r"stub\.mat.*v7\.3.*no HDF5 superblock"):
        read_mat(stub, fs=1.0)


def test_missing_h5py(tmp_path, monkeypatch):
    path = tmp_path / "big.mat"
    path.write_bytes(_mat_header() + b"\x89HDF\r\n\x1a\n" + b"\0" * 120)
    monkeypatch.setitem(sys.modules, "h5py", None)
    with pytest.raises(ImportError, match=r'h5py: pip install "gearvib\[hdf5\]"'):
        read_mat(path, fs=1.0)
