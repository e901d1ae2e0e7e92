"""The RIFF/WAVE container (RIFF, RIFX, RF64 and BW64), parsed with every size checked.

:func:`wav_layout` walks the chunks of a WAV file and returns where the samples are and how
they are coded; :func:`read_samples` reads them. Every size a header declares is compared with
the size of the file before anything is read or allocated, so that

* a truncated file (a data chunk that declares more bytes than the file holds, a RIFF/RF64
  size beyond the end of the file, a data chunk that ends inside a frame) is refused instead
  of being read with fewer samples;
* a corrupt header (an RF64 ``ds64`` chunk declaring 10^12 samples in a 2 kB file, zero
  channels, a block alignment that does not match the sample width) is refused with the
  offending field named, instead of an allocation of terabytes or a division by zero.

Supported codings: PCM integers of 1 to 64 valid bits in 1- to 8-byte containers (8-bit and
smaller containers unsigned, as the format defines), IEEE float of 32 or 64 bits, both also as
``WAVE_FORMAT_EXTENSIBLE`` (valid bits from the extension, sub-format from its GUID).
References: Microsoft "Multimedia Programming Interface and Data Specifications 1.0" (RIFF,
``fmt``), "WAVEFORMATEXTENSIBLE" documentation, EBU Tech 3306 (RF64) and ITU-R BS.2088 (BW64).
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from analysis.checks import require_instance
from analysis.readers.integrity import file_size, require_memory
from analysis.readers.layout import ReaderError

__all__ = ["WavLayout", "read_samples", "wav_layout"]

WAVE_FORMAT_PCM = 0x0001
WAVE_FORMAT_IEEE_FLOAT = 0x0003
WAVE_FORMAT_EXTENSIBLE = 0xFFFE
# KSDATAFORMAT_SUBTYPE_* GUIDs are {XXXXXXXX-0000-0010-8000-00AA00389B71}; bytes 4..16 as stored
_GUID_TAIL = {
    "<": bytes.fromhex("000010008000" "00aa00389b71"),
    ">": bytes.fromhex("000000108000" "00aa00389b71"),
}
_MAX_FMT_BYTES = 1024  # a fmt chunk is 16, 18 or 40 bytes; larger ones are corrupt


@dataclass(frozen=True)
class WavLayout:
    """Where the samples of a WAV file are and how they are coded.

    Attributes
    ----------
    container : str
        ``"RIFF"``, ``"RIFX"`` (big-endian), ``"RF64"`` or ``"BW64"``.
    format_tag : int
        1 (PCM integer) or 3 (IEEE float), after resolving ``WAVE_FORMAT_EXTENSIBLE``.
    extensible : bool
        Whether the fmt chunk is ``WAVE_FORMAT_EXTENSIBLE``.
    channels, sample_rate : int
        Number of channels and sample rate [Hz].
    sample_bytes : int
        Container size of one sample (``block_align / channels``).
    valid_bits : int
        Bits that carry the sample (left-justified in the container).
    data_offset, data_bytes : int
        Position and size of the sample data in the file.
    """

    container: str
    format_tag: int
    extensible: bool
    channels: int
    sample_rate: int
    sample_bytes: int
    valid_bits: int
    data_offset: int
    data_bytes: int

    @property
    def endian(self) -> str:
        """``">"`` for big-endian RIFX files, else ``"<"``."""
        return ">" if self.container == "RIFX" else "<"

    @property
    def frames(self) -> int:
        """Number of sample frames (one sample per channel)."""
        return self.data_bytes // (self.sample_bytes * self.channels)


class _Bad(Exception):
    pass


def _parse_fmt(body: bytes, endian: str) -> tuple[int, bool, int, int, int, int, int]:
    if len(body) < 16:
        raise _Bad(f"fmt chunk has {len(body)} bytes; it needs at least 16")
    tag, channels, rate, _byte_rate, block_align, bits = struct.unpack_from(
        endian + "HHIIHH", body
    )
    extensible = tag == WAVE_FORMAT_EXTENSIBLE
    valid = bits
    if extensible:
        if len(body) < 40:
            raise _Bad(f"WAVE_FORMAT_EXTENSIBLE fmt chunk has {len(body)} bytes; it needs 40")
        valid = struct.unpack_from(endian + "H", body, 18)[0] or bits
        guid = body[24:40]
        if guid[4:] != _GUID_TAIL[endian]:
            raise _Bad("WAVE_FORMAT_EXTENSIBLE sub-format GUID is not a standard KSDATAFORMAT")
        tag = struct.unpack_from(endian + "I", guid)[0]
    if tag not in (WAVE_FORMAT_PCM, WAVE_FORMAT_IEEE_FLOAT):
        raise _Bad(
            f"format tag {tag:#06x} is not supported; admissible are PCM (1) and IEEE float "
            "(3), also as WAVE_FORMAT_EXTENSIBLE"
        )
    if channels < 1:
        raise _Bad(f"channel count {channels} (must be >= 1)")
    if rate < 1:
        raise _Bad(f"sample rate {rate} Hz (must be >= 1)")
    if block_align < channels or block_align % channels:
        raise _Bad(f"block alignment {block_align} bytes is not a multiple of {channels} channels")
    sample_bytes = block_align // channels
    if not 1 <= sample_bytes <= 8:
        raise _Bad(f"{sample_bytes} bytes per sample (1 to 8 are admissible)")
    if not 1 <= bits <= 8 * sample_bytes or not 1 <= valid <= bits:
        raise _Bad(
            f"{bits} bits per sample ({valid} valid) in a {sample_bytes}-byte container "
            "(need 1 <= valid bits <= bits <= 8 x container bytes)"
        )
    if tag == WAVE_FORMAT_IEEE_FLOAT and (sample_bytes, valid) not in ((4, 32), (8, 64)):
        raise _Bad(f"IEEE float samples of {valid} bits in {sample_bytes} bytes (32 or 64)")
    return tag, extensible, channels, rate, block_align, sample_bytes, valid


def wav_layout(path: str | os.PathLike[str]) -> WavLayout:
    """Walk the chunks of a WAV file and check every declared size against the file.

    Parameters
    ----------
    path : path-like
        The file.

    Returns
    -------
    WavLayout

    Raises
    ------
    ReaderError
        Not a WAV file, truncated (a size beyond the end of the file, a partial frame),
        corrupt or unsupported header fields (each named with the admissible values), no or
        several ``data`` chunks.
    """
    p = Path(path)
    size = file_size(p)
    try:
        with open(p, "rb") as fh:
            return _walk(fh, size)
    except _Bad as exc:
        raise ReaderError(f"{p}: not a readable WAV file: {exc}") from None


def _walk(fh, size: int) -> WavLayout:
    head = fh.read(12)
    if len(head) < 12:
        raise _Bad(f"the file has {size} bytes; a WAV header needs 12")
    magic, form = head[:4], head[8:12]
    if magic not in (b"RIFF", b"RIFX", b"RF64", b"BW64") or form != b"WAVE":
        raise _Bad(f"signature {magic!r}/{form!r} is not RIFF/RIFX/RF64/BW64 + WAVE")
    endian = ">" if magic == b"RIFX" else "<"
    u32 = struct.Struct(endian + "I")
    riff_end = u32.unpack_from(head, 4)[0] + 8
    ds64_data: int | None = None
    pos = 12
    if magic in (b"RF64", b"BW64"):
        chunk = fh.read(8)
        if len(chunk) < 8 or chunk[:4] != b"ds64":
            raise _Bad(f"{magic.decode()} file without a ds64 chunk after the header")
        ds64_size = u32.unpack_from(chunk, 4)[0]
        if not 24 <= ds64_size <= min(size - 20, 1 << 20):
            raise _Bad(f"ds64 chunk of {ds64_size} bytes (24 .. file size)")
        body = fh.read(ds64_size)
        riff64, ds64_data, _samples = struct.unpack_from("<QQQ", body)
        riff_end = riff64 + 8
        pos = 20 + ds64_size + (ds64_size & 1)
    if riff_end > size + 1:  # one missing pad byte at the very end is common
        raise _Bad(
            f"the {magic.decode()} header declares {riff_end} bytes but the file has {size}: "
            "the file is truncated (or its header was never completed)"
        )
    limit = min(riff_end, size)
    fmt_body: bytes | None = None
    data: list[tuple[int, int]] = []
    while pos + 8 <= limit:
        fh.seek(pos)
        chunk = fh.read(8)
        cid, csize = chunk[:4], u32.unpack_from(chunk, 4)[0]
        if cid == b"data" and ds64_data is not None and csize == 0xFFFFFFFF:
            csize = ds64_data
        start, end = pos + 8, pos + 8 + csize
        if cid == b"data":
            data.append((start, csize))
            if end > size:
                raise _Bad(
                    f"the data chunk declares {csize} bytes from byte {start}, but only "
                    f"{size - start} follow: the file is truncated (or its header corrupt)"
                )
        elif end > limit:
            raise _Bad(
                f"chunk {cid!r} at byte {pos} declares {csize} bytes, beyond the end of the "
                f"{'file' if limit == size else 'RIFF data'} at byte {limit} (truncated?)"
            )
        if cid == b"fmt ":
            if fmt_body is not None:
                raise _Bad("two fmt chunks")
            if csize > _MAX_FMT_BYTES:
                raise _Bad(f"fmt chunk of {csize} bytes (a fmt chunk has 16 to 40)")
            fmt_body = fh.read(csize)
        pos = end + (csize & 1)
    if fmt_body is None:
        raise _Bad("no fmt chunk (sample format unknown)")
    if len(data) != 1:
        raise _Bad("no data chunk" if not data else f"{len(data)} data chunks (one expected)")
    tag, extensible, channels, rate, block_align, sample_bytes, valid = _parse_fmt(
        fmt_body, endian
    )
    data_offset, data_bytes = data[0]
    if data_bytes % block_align:
        raise _Bad(
            f"the data chunk holds {data_bytes} bytes, not a whole number of {block_align}-byte "
            "frames: the file is truncated or corrupt"
        )
    if data_bytes == 0:
        raise _Bad("the data chunk is empty (no samples)")
    return WavLayout(
        container=magic.decode(),
        format_tag=tag,
        extensible=extensible,
        channels=channels,
        sample_rate=rate,
        sample_bytes=sample_bytes,
        valid_bits=valid,
        data_offset=data_offset,
        data_bytes=data_bytes,
    )


def read_samples(path: str | os.PathLike[str], layout: WavLayout) -> np.ndarray:
    """Read and decode the samples: integer codes (as float64) or float values.

    Parameters
    ----------
    path : path-like
        The file ``layout`` was made from.
    layout : WavLayout
        From :func:`wav_layout`.

    Returns
    -------
    numpy.ndarray
        Shape ``(frames, channels)``, float64: for PCM the signed ``valid_bits`` integer code
        (1-byte containers, which are unsigned, are centred by subtracting 128 first), for
        float files the stored value.

    Raises
    ------
    ReaderError
        Not enough memory for the samples, or fewer bytes than the layout says (the file
        changed since).
    """
    require_instance(layout, WavLayout, "layout")
    p = Path(path)
    n_values = layout.frames * layout.channels
    require_memory(
        layout.data_bytes + 3 * 8 * n_values,
        p,
        f"{layout.frames} frames x {layout.channels} channel(s)",
    )
    with open(p, "rb") as fh:
        fh.seek(layout.data_offset)
        raw = np.fromfile(fh, dtype=np.uint8, count=layout.data_bytes)
    if raw.size != layout.data_bytes:
        raise ReaderError(
            f"{p}: the data chunk should hold {layout.data_bytes} bytes, {raw.size} were read "
            "(the file is truncated or changed while reading)"
        )
    e, c, bits = layout.endian, layout.sample_bytes, layout.valid_bits
    if layout.format_tag == WAVE_FORMAT_IEEE_FLOAT:
        values = raw.view(f"{e}f{c}").astype(np.float64)
    elif c == 1:  # unsigned, offset binary
        values = ((raw.astype(np.int16) - 128) >> (8 - bits)).astype(np.float64)
    elif c in (2, 4, 8) and bits == 8 * c:  # the common case: no shift
        values = raw.view(f"{e}i{c}").astype(np.float64)
    else:
        if c in (2, 4, 8):
            ints = raw.view(f"{e}i{c}").astype(np.int64)
        else:  # 3-, 5-, 6-, 7-byte containers: place the bytes at the top of an int64
            wide = np.zeros((n_values, 8), dtype=np.uint8)
            cols = slice(8 - c, 8) if e == "<" else slice(0, c)
            wide[:, cols] = raw.reshape(n_values, c)
            ints = wide.view(f"{e}i8").reshape(n_values) >> (8 * (8 - c))
        values = (ints >> (8 * c - bits)).astype(np.float64)
    return values.reshape(layout.frames, layout.channels)
