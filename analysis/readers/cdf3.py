"""Header check of netCDF-3 files (classic, 64-bit offset, 64-bit data) before netCDF-C opens them.

The netCDF C library allocates what a netCDF-3 header declares while it parses it: one
flipped byte in the length of an attribute string makes it allocate 4 GiB for a 1 kB file,
and a record count of 2**31 - 1 makes xarray allocate 16 GiB when it loads the variables.
:func:`check_cdf3` walks the header as the format specification defines it ("NetCDF
Classic and 64-bit Offset Format", and the CDF-5 extension) and checks, before the library
sees the file:

* every count (names, dimensions, attributes, variables, attribute values) against the
  bytes that are left in the file;
* type codes, dimension ids and the position of the record dimension;
* that every variable's data -- for record variables, every record up to ``numrecs`` -- lies
  inside the file (a truncated file is refused, not read with fill values).
"""

from __future__ import annotations

import os
import struct
from pathlib import Path

from analysis.readers.integrity import file_size
from analysis.readers.layout import ReaderError

__all__ = ["check_cdf3", "is_cdf3"]

_SIZES = {1: 1, 2: 1, 3: 2, 4: 4, 5: 4, 6: 8, 7: 1, 8: 2, 9: 4, 10: 8, 11: 8}
_DIM, _VAR, _ATT = 0x0A, 0x0B, 0x0C
_MAX_HEADER = 1 << 26  # a header beyond 64 MiB is not plausible; read no more than that
_STREAMING = 0xFFFFFFFF


def is_cdf3(path: str | os.PathLike[str]) -> bool:
    """Whether the file starts with a netCDF-3 magic number (``CDF`` + 1, 2 or 5)."""
    with open(os.fspath(path), "rb") as fh:  # fspath: an int would open a file descriptor
        head = fh.read(4)
    return len(head) == 4 and head[:3] == b"CDF" and head[3] in (1, 2, 5)


class _Bad(Exception):
    pass


class _Header:
    def __init__(self, buf: bytes, version: int, size: int) -> None:
        self.buf, self.size, self.pos = buf, size, 4
        self.count_fmt = ">Q" if version == 5 else ">I"
        self.count_len = 8 if version == 5 else 4
        self.types = _SIZES if version == 5 else {k: v for k, v in _SIZES.items() if k <= 6}

    def take(self, n: int, what: str) -> bytes:
        if self.pos + n > len(self.buf):
            raise _Bad(
                f"{what} at byte {self.pos} needs {n} bytes, beyond the end of the header "
                f"({self.size} bytes in the file): truncated or corrupt"
            )
        out = self.buf[self.pos : self.pos + n]
        self.pos += n
        return out

    def u32(self, what: str) -> int:
        return struct.unpack(">I", self.take(4, what))[0]

    def count(self, what: str, unit: int = 1) -> int:
        n = struct.unpack(self.count_fmt, self.take(self.count_len, what))[0]
        if n * unit > len(self.buf) - self.pos:
            raise _Bad(
                f"{what} = {n} at byte {self.pos - self.count_len} needs {n * unit} bytes; "
                f"only {len(self.buf) - self.pos} are left: corrupt header"
            )
        return n

    def name(self, what: str) -> str:
        n = self.count(f"{what} name length")
        raw = self.take(n + (-n % 4), f"{what} name")[:n]
        return raw.decode("utf-8", errors="replace")

    def list_tag(self, tag: int, what: str, unit: int) -> int:
        kind = self.u32(f"{what} list tag")
        n = self.count(f"number of {what}s", unit)
        if kind == 0 and n == 0:
            return 0
        if kind != tag:
            raise _Bad(f"{what} list tag {kind:#x} at byte {self.pos - 8} (expected {tag:#x})")
        return n

    def attributes(self, owner: str) -> None:
        for i in range(self.list_tag(_ATT, f"{owner} attribute", 12)):
            name = self.name(f"{owner} attribute {i}")
            code = self.u32(f"{owner} attribute {name!r} type")
            if code not in self.types:
                raise _Bad(f"{owner} attribute {name!r}: type code {code} is not admissible")
            n = self.count(f"{owner} attribute {name!r} length", self.types[code])
            nbytes = n * self.types[code]
            self.take(nbytes + (-nbytes % 4), f"{owner} attribute {name!r} values")


def check_cdf3(path: str | os.PathLike[str]) -> None:
    """Walk a netCDF-3 header and check every declared size against the file.

    Parameters
    ----------
    path : path-like
        A file that starts with ``CDF\\x01``, ``CDF\\x02`` or ``CDF\\x05``.

    Raises
    ------
    ReaderError
        Naming the structure and byte offset: counts beyond the file, bad type codes or
        dimension ids, variable data or records beyond the end of the file (truncation).
    """
    p = Path(path)
    size = file_size(p)
    with open(p, "rb") as fh:
        buf = fh.read(min(size, _MAX_HEADER))
    try:
        _walk(buf, size)
    except _Bad as exc:
        raise ReaderError(f"{p}: not a readable netCDF-3 file: {exc}") from None


def _walk(buf: bytes, size: int) -> None:
    if len(buf) < 8 or buf[:3] != b"CDF" or buf[3] not in (1, 2, 5):
        raise _Bad("no netCDF-3 magic number")
    version = buf[3]
    h = _Header(buf, version, size)
    numrecs = struct.unpack(h.count_fmt, h.take(h.count_len, "record count"))[0]
    streaming = numrecs == (_STREAMING if version != 5 else 2**64 - 1)
    dims: list[int] = []
    for i in range(h.list_tag(_DIM, "dimension", 8)):
        h.name(f"dimension {i}")
        dims.append(struct.unpack(h.count_fmt, h.take(h.count_len, f"dimension {i} length"))[0])
    if dims.count(0) > 1:
        raise _Bad("more than one record (unlimited) dimension")
    h.attributes("global")
    offset_fmt, offset_len = (">I", 4) if version == 1 else (">Q", 8)
    variables = []
    for i in range(h.list_tag(_VAR, "variable", 16)):
        name = h.name(f"variable {i}")
        ndims = h.count(f"variable {name!r} rank", h.count_len)
        ids = [
            struct.unpack(h.count_fmt, h.take(h.count_len, f"variable {name!r} dimension id"))[0]
            for _ in range(ndims)
        ]
        if any(d >= len(dims) for d in ids):
            raise _Bad(f"variable {name!r}: dimension id outside 0..{len(dims) - 1}")
        if any(dims[d] == 0 for d in ids[1:]):
            raise _Bad(f"variable {name!r}: the record dimension is not its first dimension")
        h.attributes(f"variable {name!r}")
        code = h.u32(f"variable {name!r} type")
        if code not in h.types:
            raise _Bad(f"variable {name!r}: type code {code} is not admissible")
        h.take(h.count_len, f"variable {name!r} size")
        begin = struct.unpack(offset_fmt, h.take(offset_len, f"variable {name!r} offset"))[0]
        is_record = bool(ids) and dims[ids[0]] == 0
        count = 1
        for d in ids[1:] if is_record else ids:
            count *= dims[d]
        variables.append((name, is_record, begin, count * h.types[code]))
    inside = [v for v in variables if v[2] < h.pos]
    if inside:
        raise _Bad(f"variable {inside[0][0]!r}: data offset {inside[0][2]} inside the header")
    if streaming:
        return  # the library derives the record count from the file size
    records = [v for v in variables if v[1]]
    # a single record variable is stored without padding
    padded = sum(n + (-n % 4) for *_, n in records)
    recsize = records[0][3] if len(records) == 1 else padded
    for name, is_record, begin, nbytes in variables:
        if is_record:
            end = begin + ((numrecs - 1) * recsize + nbytes if numrecs else 0)
            what = f"{numrecs} records of variable {name!r}"
        else:
            end, what = begin + nbytes, f"variable {name!r}"
        if end > size:
            raise _Bad(
                f"{what} end at byte {end}, but the file has {size} bytes: the file is "
                "truncated or its header (dimension or record count) is corrupt"
            )
