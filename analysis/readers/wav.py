"""WAV (RIFF/WAVE PCM) reader and writer.

WAV files carry no engineering units: the user supplies a calibration factor. For integer PCM
files it is in *unit per count* (the true n-bit integer code, e.g. -8388608..8388607 for
24-bit), for float files in *unit per full scale* (sample value 1.0).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from analysis.readers.integrity import reading
from analysis.readers.layout import ChannelData, ReaderError, build_dataset, validate_dataset
from analysis.readers.riff import WAVE_FORMAT_IEEE_FLOAT, read_samples, wav_layout

__all__ = ["read_wav", "write_wav"]


def _per_channel(value: float | str | Sequence, n: int, name: str) -> list:
    if isinstance(value, str) or np.ndim(value) == 0:
        return [value] * n
    vals = list(value)  # type: ignore[arg-type]  # a sequence: scalars returned above
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

    The container (RIFF, big-endian RIFX, RF64/BW64 for files beyond 4 GiB) is parsed by
    :mod:`analysis.readers.riff`, which checks every declared size against the file before
    reading: a truncated or corrupt file is refused, never read with fewer samples.

    Parameters
    ----------
    path : path-like
        WAV file: PCM integer (1 to 64 valid bits, e.g. 8/16/24/32-bit) or 32/64-bit float,
        also as ``WAVE_FORMAT_EXTENSIBLE``.
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
        Truncated file (a data chunk or RIFF size beyond the end of the file, a partial
        frame), corrupt or unsupported header fields (named with the admissible values), not
        enough memory for the samples, or a channel-name count that does not match the file.
    ValueError
        Non-positive/non-finite calibration.
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"WAV file not found: {p}")
    with reading(p, "WAV"):
        layout = wav_layout(p)
    n_ch = layout.channels
    names = (
        list(channel_names) if channel_names is not None else [f"ch{i + 1}" for i in range(n_ch)]
    )
    if len(names) != n_ch:
        raise ReaderError(f"{p}: file has {n_ch} channel(s) but {len(names)} channel_names given")
    cals = _per_channel(calibration, n_ch, "calibration")
    units = _per_channel(unit, n_ch, "unit")
    is_float = layout.format_tag == WAVE_FORMAT_IEEE_FLOAT
    for i, cal in enumerate(cals):
        c = float(cal)
        if not np.isfinite(c) or c == 0.0:
            raise ValueError(
                f"calibration = {cal!r} for channel {names[i]!r}: must be finite and != 0"
            )
    with reading(p, "WAV"):
        data = read_samples(p, layout)
    channels = []
    for i in range(n_ch):
        cal = float(cals[i])
        channels.append(
            ChannelData(
                names[i],
                data[:, i] * cal,
                units=str(units[i]),
                attrs={
                    "calibration": cal,
                    "calibration_basis": "unit per full scale" if is_float else "unit per count",
                    "wav_bits_per_sample": int(layout.valid_bits),
                    "source_channel_index": i,
                },
            )
        )
    return build_dataset(
        channels, float(layout.sample_rate), source_format="wav", source_file=str(p)
    )


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
