"""Valid measured files of every reader format, built from given samples (test helpers).

Each builder returns a :class:`Sample`: the bytes of a file, the keyword arguments to read it
and the channel values the reader must return. WAV files are built byte by byte here from the
format specification (independently of the reader); the other formats are written by their
reference libraries (scipy.io, netCDF4/xarray, h5py, pyuff, npTDMS).
"""

from __future__ import annotations

import io
import struct
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "Sample",
    "csv_sample",
    "mat4_sample",
    "mat5_sample",
    "mat73_sample",
    "netcdf_sample",
    "tdms_bytes",
    "tdms_sample",
    "uff_bytes",
    "uff_sample",
    "wav_bytes",
    "wav_sample",
]


@dataclass
class Sample:
    """A valid file and what reading it must give.

    Attributes
    ----------
    data : bytes
        The file.
    suffix : str
        File extension (selects the reader in :func:`analysis.readers.read`).
    options : dict
        Keyword arguments for the reader.
    expected : dict
        Variable name -> the values it must hold.
    fs : float
        The sample rate the file states.
    rtol, atol : float
        How exactly the format stores the values.
    """

    data: bytes
    suffix: str
    options: dict[str, Any] = field(default_factory=dict)
    expected: dict[str, np.ndarray] = field(default_factory=dict)
    fs: float = 1.0
    rtol: float = 0.0
    atol: float = 0.0


# ----------------------------------------------------------------------------------------------
# WAV (built from the specification)
# ----------------------------------------------------------------------------------------------

# KSDATAFORMAT sub-format GUIDs {XXXXXXXX-0000-0010-8000-00AA00389B71}, bytes 4..16 as stored:
# the first three groups in the file's byte order, the rest as written
_GUID_TAIL = {
    "<": bytes.fromhex("00001000800000aa00389b71"),
    ">": bytes.fromhex("00000010800000aa00389b71"),
}


def wav_bytes(
    counts: np.ndarray,
    fs: int,
    *,
    sample_bytes: int,
    valid_bits: int,
    is_float: bool = False,
    container: str = "RIFF",
    extensible: bool = False,
    extra_chunk: bool = False,
) -> bytes:
    """A WAV file holding ``counts`` (frames x channels): integer codes of ``valid_bits`` bits
    left-justified in ``sample_bytes`` (1-byte containers unsigned), or float values."""
    frames, channels = counts.shape
    endian = ">" if container == "RIFX" else "<"
    if is_float:
        raw = counts.astype(f"{endian}f{sample_bytes}").tobytes()
    else:
        codes = counts.astype(np.int64) << (8 * sample_bytes - valid_bits)
        if sample_bytes == 1:
            codes = codes + 128
        full = np.ascontiguousarray(codes, dtype=f"{endian}i8").view(np.uint8).reshape(-1, 8)
        cols = slice(0, sample_bytes) if endian == "<" else slice(8 - sample_bytes, 8)
        raw = np.ascontiguousarray(full[:, cols]).tobytes()
    tag = 3 if is_float else 1
    block = channels * sample_bytes
    bits = 8 * sample_bytes if extensible else valid_bits  # plain fmt: bits = valid bits
    if extensible:
        fmt = (
            struct.pack(
                f"{endian}HHIIHHHHI",
                0xFFFE,
                channels,
                fs,
                fs * block,
                block,
                bits,
                22,
                valid_bits,
                0,
            )
            + struct.pack(f"{endian}I", tag)
            + _GUID_TAIL[endian]
        )
    else:
        fmt = struct.pack(f"{endian}HHIIHH", tag, channels, fs, fs * block, block, bits)
    u32 = struct.Struct(endian + "I")
    chunks = b"fmt " + u32.pack(len(fmt)) + fmt
    big = container in ("RF64", "BW64")
    chunks += b"data" + u32.pack(0xFFFFFFFF if big else len(raw)) + raw + b"\0" * (len(raw) & 1)
    if extra_chunk:
        note = b"gearvib test\0"
        chunks += b"LIST" + u32.pack(len(note) + 4) + b"INFO" + note + b"\0" * (len(note) & 1)
    if not big:
        return container.encode() + u32.pack(4 + len(chunks)) + b"WAVE" + chunks
    ds64 = struct.pack("<QQQI", 4 + 36 + len(chunks), len(raw), frames, 0)
    body = b"WAVE" + b"ds64" + struct.pack("<I", len(ds64)) + ds64 + chunks
    return container.encode() + struct.pack("<I", 0xFFFFFFFF) + body


def wav_sample(
    values: np.ndarray,
    fs: int,
    coding: str,
    container: str,
    extensible: bool,
    extra_chunk: bool = False,
) -> Sample:
    """``values`` (channels x frames, in [-1, 1]) as a WAV file of ``coding`` (``pcm<bits>``
    in a container of ``ceil(bits/8)`` bytes, ``pcm20in32``, ``float32``, ``float64``)."""
    x = np.asarray(values, dtype=np.float64).T
    if coding.startswith("float"):
        size = int(coding[5:]) // 8
        stored = x.astype(np.float32).astype(np.float64) if size == 4 else x
        data = wav_bytes(
            x,
            fs,
            sample_bytes=size,
            valid_bits=8 * size,
            is_float=True,
            container=container,
            extensible=extensible,
            extra_chunk=extra_chunk,
        )
        expected = stored
    else:
        spec = coding[3:]
        bits, size = (20, 4) if spec == "20in32" else (int(spec), -(-int(spec) // 8))
        top = 2 ** (bits - 1) - 1
        counts = np.round(x * top).astype(np.int64)
        data = wav_bytes(
            counts,
            fs,
            sample_bytes=size,
            valid_bits=bits,
            container=container,
            extensible=extensible or spec == "20in32",
            extra_chunk=extra_chunk,
        )
        expected = counts.astype(np.float64)
    names = [f"ch{i + 1}" for i in range(x.shape[1])]
    return Sample(data, ".wav", {}, {n: expected[:, i] for i, n in enumerate(names)}, float(fs))


# ----------------------------------------------------------------------------------------------
# CSV
# ----------------------------------------------------------------------------------------------


def csv_sample(
    values: np.ndarray,
    fs: float,
    *,
    time_format: str | None,
    value_format: str,
    delimiter: str = ",",
    header: bool = True,
    comment: bool = False,
) -> Sample:
    """``values`` (channels x samples) as delimited text; with ``time_format`` a time column
    printed that way is the first column (read with ``time_column=0``), else ``fs=`` is
    given."""
    n_ch, n = values.shape
    rows = []
    t = np.arange(n) / fs
    decimal_comma = delimiter == ";"
    for k in range(n):
        cols = [time_format % float(t[k])] if time_format else []
        cols += [value_format % float(values[i, k]) for i in range(n_ch)]
        if decimal_comma:
            cols = [c.replace(".", ",") for c in cols]
        rows.append(delimiter.join(cols))
    lines = ["# written by the gearvib tests"] if comment else []
    if header:
        names = (["time [s]"] if time_format else []) + [f"ch{i + 1} [m/s2]" for i in range(n_ch)]
        lines.append(delimiter.join(names))
    text = "\n".join(lines + rows) + "\n"
    parsed = np.array([[float(value_format % float(v)) for v in row] for row in values])
    options: dict[str, Any] = {"time_column": 0} if time_format else {"fs": fs}
    first = 1 if time_format and not header else 0  # without a header: ch<column number>
    names = [f"ch{i + 1 + first}" for i in range(n_ch)]
    return Sample(text.encode(), ".csv", options, dict(zip(names, parsed, strict=True)), fs)


# ----------------------------------------------------------------------------------------------
# MAT
# ----------------------------------------------------------------------------------------------


def mat5_sample(values: np.ndarray, fs: float, *, compressed: bool, extras: bool) -> Sample:
    """``values`` as vectors ``ch1``, ``ch2``, ... of a MAT v5 file with ``fs``; ``extras`` adds
    a units struct, a string, a cell, a sparse matrix, a complex and an int16 vector."""
    from scipy.io import savemat
    from scipy.sparse import csc_matrix

    content: dict[str, Any] = {f"ch{i + 1}": v for i, v in enumerate(values)}
    content["fs"] = fs
    if extras:
        content["units"] = {"ch1": "m/s2"}
        content["label"] = "run-up"
        content["cel"] = np.array([np.ones(2), "x"], dtype=object)
        content["sp"] = csc_matrix(np.eye(3))
        content["z"] = np.array([1 + 1j, 2 - 1j])
    buf = io.BytesIO()
    savemat(buf, content, do_compression=compressed)
    expected = {f"ch{i + 1}": v for i, v in enumerate(values)}
    return Sample(buf.getvalue(), ".mat", {}, expected, fs)


def mat4_sample(values: np.ndarray, fs: float) -> Sample:
    """``values`` as a MAT v4 file (``ch1`` ... and ``fs``)."""
    from scipy.io import savemat

    buf = io.BytesIO()
    content: dict[str, Any] = {f"ch{i + 1}": v for i, v in enumerate(values)}
    content["fs"] = fs
    savemat(buf, content, format="4")
    return Sample(buf.getvalue(), ".mat", {}, {f"ch{i + 1}": v for i, v in enumerate(values)}, fs)


def mat73_sample(values: np.ndarray, fs: float) -> Sample:
    """``values`` as a MATLAB v7.3 (HDF5) file, written like MATLAB does."""
    from tests.analysis.test_readers_mat73 import savemat73

    content: dict[str, Any] = {f"ch{i + 1}": v for i, v in enumerate(values)}
    content["fs"] = fs
    content["units"] = {"ch1": "m/s2"}
    with tempfile.TemporaryDirectory() as tmp:
        path = savemat73(Path(tmp) / "f.mat", content)
        data = path.read_bytes()
    return Sample(data, ".mat", {}, {f"ch{i + 1}": v for i, v in enumerate(values)}, fs)


# ----------------------------------------------------------------------------------------------
# netCDF
# ----------------------------------------------------------------------------------------------


def netcdf_sample(values: np.ndarray, fs: float, *, version: int) -> Sample:
    """``values`` in the common layout as netCDF-4 (:func:`write_netcdf`, compressed, with
    checksums) or netCDF-3 classic (``version=3``)."""
    from analysis.readers import ChannelData, build_dataset, write_netcdf

    ds = build_dataset(
        [ChannelData(f"ch{i + 1}", v, "m s-2") for i, v in enumerate(values)],
        fs,
        source_format="test",
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "f.nc"
        if version == 4:
            write_netcdf(ds, path)
        else:
            enc = {v: {"_FillValue": None} for v in ds.variables}
            ds.to_netcdf(path, format="NETCDF3_CLASSIC", engine="netcdf4", encoding=enc)
        data = path.read_bytes()
    return Sample(data, ".nc", {}, {f"ch{i + 1}": v for i, v in enumerate(values)}, fs)


# ----------------------------------------------------------------------------------------------
# UFF 58 / 58b
# ----------------------------------------------------------------------------------------------


def uff_bytes(values: np.ndarray, dt: float, binary: int) -> bytes:
    """Channels of ``values`` as UFF dataset-58 time histories (58b when ``binary``)."""
    import pyuff

    n = values.shape[1]
    x = np.arange(n) * dt
    sets = [
        pyuff.prepare_58(
            binary=binary,
            func_type=1,
            id1=f"acc {i}",
            rsp_ent_name=f"acc {i}",
            rsp_node=i + 1,
            rsp_dir=3,
            ref_node=0,
            ref_dir=0,
            ord_data_type=4,
            num_pts=n,
            abscissa_spacing=1,
            abscissa_min=0.0,
            abscissa_inc=dt,
            abscissa_spec_data_type=17,
            abscissa_axis_units_lab="s",
            ordinate_axis_units_lab="m/s2",
            ordinate_spec_data_type=12,
            orddenom_spec_data_type=0,
            data=v,
            x=x,
        )
        for i, v in enumerate(values)
    ]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "f.uff"
        # mode "add" on a new file: pyuff's "overwrite" truncates a binary set's own header
        pyuff.UFF(str(path)).write_sets(sets, mode="add")
        return path.read_bytes()


def uff_sample(values: np.ndarray, dt: float, binary: int) -> Sample:
    """UFF sample; ASCII 58 stores 12 significant digits (``E20.12``), 58b doubles."""
    names = [f"acc_{i}" for i in range(values.shape[0])]
    expected = dict(zip(names, values, strict=True))
    return Sample(
        uff_bytes(values, dt, binary),
        ".uff",
        {},
        expected,
        1.0 / dt,
        rtol=0.0 if binary else 1e-11,
        atol=0.0 if binary else 1e-300,
    )


# ----------------------------------------------------------------------------------------------
# TDMS
# ----------------------------------------------------------------------------------------------


def tdms_bytes(values: np.ndarray, dt: float, segments: int = 2) -> bytes:
    """Channels of ``values`` in group ``rig`` of a TDMS file, split over ``segments``."""
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    buf = io.BytesIO()
    parts = np.array_split(np.arange(values.shape[1]), segments)
    with TdmsWriter(buf) as writer:
        for idx in parts:
            objs: list[Any] = [RootObject({"title": "test"}), GroupObject("rig")]
            for i, v in enumerate(values):
                props = {"wf_increment": dt, "unit_string": "m/s^2"}
                objs.append(ChannelObject("rig", f"acc {i}", v[idx], properties=props))
            writer.write_segment(objs)
    return buf.getvalue()


def tdms_sample(values: np.ndarray, dt: float, segments: int = 2) -> Sample:
    """TDMS sample (float64 channels ``acc 0``, ``acc 1``, ...)."""
    names = [f"acc_{i}" for i in range(values.shape[0])]
    return Sample(
        tdms_bytes(values, dt, segments),
        ".tdms",
        {},
        dict(zip(names, values, strict=True)),
        1.0 / dt,
    )
