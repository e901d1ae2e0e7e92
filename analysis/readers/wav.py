"""WAV (RIFF/WAVE PCM) reader and writer.

WAV files carry no engineering units: the user supplies a calibration factor. For integer PCM
files it is in *unit per count* (the true n-bit integer code, e.g. -8388608..8388607 for
24-bit), for float files in *unit per full scale* (sample value 1.0).
"""

from __future__ import annotations

import os
import struct
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from analysis.readers.layout import ChannelData, ReaderError, build_dataset, validate_dataset

__all__ = ["read_wav", "write_wav"]


def _bits_per_sample(path: Path) -> int | None:
    """Container bits per sample from the ``fmt `` chunk (valid bits for WAVE_FORMAT_EXTENSIBLE)."""
    with path.open("rb") as f:
        head = f.read(12)
        if len(head) < 12 or head[8:12] != b"WAVE":
            return None
        while True:
            hdr = f.read(8)
            if len(hdr) < 8:
                return None
            cid, size = hdr[:4], struct.unpack("<I", hdr[4:])[0]
            if cid == b"fmt ":
                body = f.read(size)
                if len(body) < 16:
                    return None
                fmt_tag, bits = (
                    struct.unpack("<H", body[:2])[0],
                    struct.unpack("<H", body[14:16])[0],
                )
                if fmt_tag == 0xFFFE and len(body) >= 20:
                    valid = struct.unpack("<H", body[18:20])[0]
                    return valid or bits
                return bits
            f.seek(size + (size & 1), os.SEEK_CUR)


def _per_channel(value: float | str | Sequence, n: int, name: str) -> list:
    if isinstance(value, str) or np.ndim(value) == 0:
        return [value] * n
    vals = list(value)  # type: ignore[arg-type]
    if len(vals) != n:
        raise ValueError(f"{name}: {len(vals)} values given for {n} channel(s); give 1 or {n}")
    return vals


def read_wav(
    path: str | os.PathLike[str],
    calibration: float | Sequence[float] = 1.0,
    unit: str | Sequence[str] = "1",
    channel_names: Sequence[str] | None = None,
) -> xr.Dataset:
    """Read a PCM or float WAV file into the common layout.

    Parameters
    ----------
    path : path-like
        WAV file (PCM 8/16/24/32/64-bit integer or 32/64-bit float).
    calibration : float or sequence of float, optional
        Scale factor, one for all channels or one per channel: *unit per count* for integer
        files, *unit per full scale* for float files. Default 1.0 (raw counts / full scale).
    unit : str or sequence of str, optional
        UDUNITS unit of the calibrated values (``"m s-2"``, ``"Pa"``, ``"V"``, ...); default
        ``"1"``.
    channel_names : sequence of str, optional
        Channel names; default ``ch1``, ``ch2``, ...

    Returns
    -------
    xarray.Dataset
        Common layout; each channel has attrs ``calibration``, ``calibration_basis`` and
        ``wav_bits_per_sample``.

    Raises
    ------
    ReaderError
        Corrupt/truncated file, or a channel-name count that does not match the file.
    ValueError
        Non-positive/non-finite calibration.
    """
    from scipy.io import wavfile

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"WAV file not found: {p}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wavfile.WavFileWarning)
            fs, data = wavfile.read(p)
        bits = _bits_per_sample(p)
    except (ValueError, EOFError, OSError, struct.error) as exc:
        raise ReaderError(f"{p}: not a readable WAV file (truncated or corrupt?): {exc}") from None
    data = data.reshape(data.shape[0], -1) if data.ndim else data.reshape(0, 1)
    n_ch = data.shape[1]
    names = (
        list(channel_names) if channel_names is not None else [f"ch{i + 1}" for i in range(n_ch)]
    )
    if len(names) != n_ch:
        raise ReaderError(f"{p}: file has {n_ch} channel(s) but {len(names)} channel_names given")
    cals = _per_channel(calibration, n_ch, "calibration")
    units = _per_channel(unit, n_ch, "unit")
    kind = data.dtype.kind
    container = data.dtype.itemsize * 8
    if bits is None or bits > container:
        bits = container
    channels = []
    for i in range(n_ch):
        cal = float(cals[i])
        if not np.isfinite(cal) or cal == 0.0:
            raise ValueError(
                f"calibration = {cals[i]!r} for channel {names[i]!r}: must be finite, != 0"
            )
        raw = data[:, i]
        if kind == "u":  # 8-bit WAV is unsigned with offset 128
            counts = raw.astype(np.float64) - 2.0 ** (container - 1)
        elif kind == "i":
            counts = (raw >> (container - bits)).astype(np.float64)  # undo left-justification
        else:
            counts = raw.astype(np.float64)
        channels.append(
            ChannelData(
                names[i],
                counts * cal,
                units=str(units[i]),
                attrs={
                    "calibration": cal,
                    "calibration_basis": "unit per full scale" if kind == "f" else "unit per count",
                    "wav_bits_per_sample": int(bits),
                    "source_channel_index": i,
                },
            )
        )
    return build_dataset(channels, float(fs), source_format="wav", source_file=str(p))


def write_wav(
    ds: xr.Dataset,
    path: str | os.PathLike[str],
    *,
    dtype: str = "float32",
    calibration: float | None = None,
) -> float:
    """Write all data variables of ``ds`` as channels of one WAV file.

    Parameters
    ----------
    ds : xarray.Dataset
        Common layout; the sample rate must be an integer number of Hz (a WAV limitation).
    path : path-like
        Target file.
    dtype : {"float32", "int16", "int32"}, optional
        Sample format.
    calibration : float, optional
        Unit per full scale (float) or per count (int) used to scale the values; default: chosen
        so that the largest absolute value maps to full scale.

    Returns
    -------
    float
        The calibration to pass to :func:`read_wav` to get the values back.
    """
    from scipy.io import wavfile

    validate_dataset(ds, name="write_wav(ds)")
    fs = float(ds.attrs.get("sample_rate_hz", 0.0)) or 1.0 / float(ds.time[1] - ds.time[0])
    if abs(fs - round(fs)) > 1e-6 * fs:
        raise ValueError(f"sample rate {fs} Hz is not an integer; WAV stores integer rates only")
    names = list(ds.data_vars)
    x = np.stack([ds[v].values.astype(np.float64) for v in names], axis=1)
    full = {"float32": 1.0, "int16": 32767.0, "int32": 2147483647.0}
    if dtype not in full:
        raise ValueError(f"dtype = {dtype!r}: admissible are {sorted(full)}")
    if calibration is None:
        peak = float(np.max(np.abs(x))) or 1.0
        calibration = peak / full[dtype]
    scaled = x / calibration
    if np.max(np.abs(scaled)) > full[dtype] * (1 + 1e-12):
        raise ValueError(f"calibration {calibration} clips the signal in dtype {dtype}")
    out = scaled.astype(np.float32) if dtype == "float32" else np.round(scaled).astype(dtype)
    wavfile.write(Path(path), round(fs), out)
    return float(calibration)
