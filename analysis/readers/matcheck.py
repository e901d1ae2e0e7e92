"""Structure check of MATLAB v4 and v5/v7 MAT files before :func:`scipy.io.loadmat` reads them.

scipy's MAT v5 reader (the Cython module ``scipy.io.matlab._mio5_utils``) trusts the file in
places where a damaged file makes it read outside its memory and crash the process
(segmentation fault) or allocate what a corrupt header declares. This module walks the whole
element tree of a file the way scipy will read it and refuses, with a
:class:`~analysis.readers.layout.ReaderError` that names the offset and the structure, every
file that would reach one of those places:

* **the segfault**: ``VarReader5.read_numeric`` and ``read_char`` look the data-type code of
  an element up in a C array of 20 dtype pointers without a bounds or NULL check
  (``self.dtypes[mdtype]``). A code that is not one of the 13 registered ones (0, 8, 10, 11,
  14, 15 or anything >= 19, e.g. from one flipped bit in a tag, or from a complex flag set on
  a real array, which makes scipy read the next variable's ``miMATRIX`` tag as imaginary
  part) dereferences NULL or a wild pointer. Every numeric, sparse and char element's code is
  checked here against the registered set;
* struct field-name length 0 (``ZeroDivisionError``), negative dimensions and element counts
  that exceed what the element can hold (scipy allocates ``prod(dims)`` objects for cells and
  structs, and ``prod(dims)`` characters for an empty char element before reading anything);
* sparse matrices whose row indices or column pointers are out of range (scipy builds the
  ``csc`` array without a full index check, and compiled sparse routines then index out of
  bounds);
* nesting deeper than :data:`MAX_DEPTH` (each level is a C-level recursion in scipy);
* elements that extend beyond their parent or the file (truncation), ``miCOMPRESSED``
  elements that are not one complete zlib stream, decompressed sizes beyond the available
  memory, unknown classes, duplicate variable names;
* MAT v4: matrix sizes (``mrows * ncols``) and name lengths beyond the end of the file, and
  invalid type codes.

The walker only reads the file (through :mod:`mmap`) and decompresses one variable at a time;
it allocates nothing of a size declared by the file.
"""

from __future__ import annotations

import mmap
import os
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from analysis.readers.integrity import memory_budget, require_in_file, require_memory
from analysis.readers.layout import ReaderError

__all__ = ["MAX_DEPTH", "MatInfo", "check_mat"]

#: Deepest nesting of cells/structs accepted (MATLAB data is rarely deeper than a few levels).
MAX_DEPTH = 64

# MAT v5 data types (the "mi" codes) -> item size, as scipy registers them
_MI_NUMERIC = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8}
_MI_CHAR = {1: 1, 2: 1, 4: 2, 16: 1, 17: 2, 18: 4}  # int8, uint8, uint16, utf8/16/32
_MI_INT8, _MI_INT32, _MI_UINT32, _MI_MATRIX, _MI_COMPRESSED, _MI_UTF8 = 1, 5, 6, 14, 15, 16
_MI_NAMES = {
    1: "miINT8",
    2: "miUINT8",
    3: "miINT16",
    4: "miUINT16",
    5: "miINT32",
    6: "miUINT32",
    7: "miSINGLE",
    9: "miDOUBLE",
    12: "miINT64",
    13: "miUINT64",
    14: "miMATRIX",
    15: "miCOMPRESSED",
    16: "miUTF8",
    17: "miUTF16",
    18: "miUTF32",
}

# MAT v5 array classes (the "mx" codes)
_MX_CELL, _MX_STRUCT, _MX_OBJECT, _MX_CHAR, _MX_SPARSE = 1, 2, 3, 4, 5
_MX_NUMERIC = range(6, 16)
_MX_FUNCTION, _MX_OPAQUE = 16, 17
_MAX_DIMS = 32

# MAT v4 precision codes -> item size
_V4_ITEMSIZE = {0: 8, 1: 4, 2: 4, 3: 2, 4: 2, 5: 1}


@dataclass
class MatInfo:
    """What :func:`check_mat` found.

    Attributes
    ----------
    version : str
        ``"4"``, ``"5"`` (v5 covers v6 and v7, which differ only by compression) or
        ``"7.3"`` (the version field says HDF5; nothing else was checked).
    variables : list of str
        Top-level variable names in file order.
    decoded_bytes : int
        Bytes of variable data after decompression (what scipy will hold in memory).
    """

    version: str
    variables: list[str] = field(default_factory=list)
    decoded_bytes: int = 0


class _Damage(Exception):
    """Internal: a structure error at an offset (turned into ReaderError with the path)."""

    def __init__(self, offset: int, message: str) -> None:
        super().__init__(message)
        self.offset = offset


def _mi_name(code: int) -> str:
    return f"{code} ({_MI_NAMES[code]})" if code in _MI_NAMES else str(code)


class _V5Walker:
    """Walks MAT v5 matrix elements inside one buffer the way scipy's VarReader5 reads them."""

    def __init__(
        self, buf: bytes | mmap.mmap | memoryview, endian: Literal["<", ">"], base: int
    ) -> None:
        self.buf = buf
        self.e = endian
        self.base = base  # offset of buf in the file (0 inside decompressed data)
        self.u4 = struct.Struct(endian + "I")
        self.u4x2 = struct.Struct(endian + "II")

    def fail(self, pos: int, message: str) -> _Damage:
        return _Damage(self.base + pos, message)

    def need(self, pos: int, n: int, end: int, what: str) -> None:
        if pos + n > end:
            raise self.fail(pos, f"{what} needs {n} bytes, only {max(end - pos, 0)} left")

    def full_tag(self, pos: int, end: int, what: str) -> tuple[int, int]:
        self.need(pos, 8, end, what)
        return self.u4x2.unpack_from(self.buf, pos)

    def element(self, pos: int, end: int, what: str) -> tuple[int, int, int, int]:
        """(mdtype, nbytes, data offset, next offset) of a data element (full or small)."""
        self.need(pos, 8, end, what)
        first = self.u4.unpack_from(self.buf, pos)[0]
        if first >> 16:  # small data element: count and type in 4 bytes, data in the other 4
            nbytes, mdtype = first >> 16, first & 0xFFFF
            if nbytes > 4:
                raise self.fail(pos, f"{what}: small element declares {nbytes} bytes (max 4)")
            return mdtype, nbytes, pos + 4, pos + 8
        mdtype, nbytes = first, self.u4.unpack_from(self.buf, pos + 4)[0]
        start = pos + 8
        if start + nbytes > end:
            raise self.fail(
                pos,
                f"{what} declares {nbytes} bytes but only {end - start} remain in its "
                "enclosing element (truncated or corrupt)",
            )
        nxt = start + nbytes + (-nbytes % 8)
        if nxt > end:
            raise self.fail(pos, f"{what}: padding runs past the end of its enclosing element")
        return mdtype, nbytes, start, nxt

    def int8_string(self, pos: int, end: int, what: str) -> tuple[bytes, int]:
        mdtype, nbytes, start, nxt = self.element(pos, end, what)
        if mdtype not in (_MI_INT8, _MI_UTF8):
            raise self.fail(pos, f"{what} has data type {_mi_name(mdtype)}; expected miINT8")
        data = bytes(self.buf[start : start + nbytes])
        if mdtype == _MI_UTF8 and any(b > 127 for b in data):
            raise self.fail(pos, f"{what} is not ASCII")
        return data, nxt

    def int32s(self, pos: int, end: int, max_bytes: int, what: str) -> tuple[list[int], int]:
        mdtype, nbytes, start, nxt = self.element(pos, end, what)
        if mdtype not in (_MI_INT32, _MI_UINT32):
            raise self.fail(
                pos, f"{what} has data type {_mi_name(mdtype)}; expected miINT32 or miUINT32"
            )
        if nbytes > max_bytes or nbytes % 4:
            raise self.fail(
                pos, f"{what} holds {nbytes} bytes; expected a multiple of 4 up to {max_bytes}"
            )
        values = list(struct.unpack_from(f"{self.e}{nbytes // 4}i", self.buf, start))
        return values, nxt

    def numeric(
        self, pos: int, end: int, count: int | None, what: str, *, values: bool = False
    ) -> tuple[np.ndarray | None, int, int]:
        """A numeric data element: (values if asked for (a copy), bytes, next offset);
        ``count`` is the number of values the dimensions declare (None: not checked)."""
        mdtype, nbytes, start, nxt = self.element(pos, end, what)
        if mdtype not in _MI_NUMERIC:
            raise self.fail(
                pos,
                f"{what} has data type {_mi_name(mdtype)}; a numeric element must be one of "
                f"{sorted(_MI_NUMERIC)}",
            )
        size = _MI_NUMERIC[mdtype]
        if count is not None and nbytes != count * size:
            raise self.fail(
                pos,
                f"{what} holds {nbytes} bytes, but its dimensions declare {count} values "
                f"of {size} bytes",
            )
        dtype = np.dtype(
            {
                1: "i1",
                2: "u1",
                3: "i2",
                4: "u2",
                5: "i4",
                6: "u4",
                7: "f4",
                9: "f8",
                12: "i8",
                13: "u8",
            }[mdtype]
        ).newbyteorder(self.e)
        if not values:
            return None, nbytes, nxt
        n = nbytes // size
        return np.frombuffer(self.buf, dtype=dtype, count=n, offset=start).copy(), nbytes, nxt

    def matrix(self, pos: int, end: int, depth: int, what: str) -> tuple[int, int, str]:
        """Check the miMATRIX element at ``pos``; return (offset after it as scipy will be,
        data bytes, name)."""
        if depth > MAX_DEPTH:
            raise self.fail(pos, f"{what}: cells/structs nested deeper than {MAX_DEPTH} levels")
        mdtype, nbytes = self.full_tag(pos, end, what)
        if mdtype != _MI_MATRIX:
            raise self.fail(pos, f"{what} has data type {_mi_name(mdtype)}; expected miMATRIX")
        start, mend = pos + 8, pos + 8 + nbytes
        if mend > end:
            raise self.fail(
                pos,
                f"{what} declares {nbytes} bytes but only {end - start} remain "
                "(truncated or corrupt)",
            )
        if nbytes == 0:
            return start, 0, ""
        # array flags: scipy reads a full tag and two uint32 without looking at the tag
        flags_type, flags_bytes = self.full_tag(start, mend, f"{what} array flags")
        if flags_type != _MI_UINT32 or flags_bytes != 8:
            raise self.fail(start, f"{what}: array-flags element is not 8 bytes of miUINT32")
        self.need(start + 8, 8, mend, f"{what} array flags")
        flags, _nzmax = self.u4x2.unpack_from(self.buf, start + 8)
        mclass, is_complex, is_logical = flags & 0xFF, flags >> 11 & 1, flags >> 9 & 1
        p = start + 16
        if mclass == _MX_OPAQUE:  # name, type system, class name, then a matrix
            opaque_name, p = self.int8_string(p, mend, f"{what} name")
            for part in ("type system", "class name"):
                _, p = self.int8_string(p, mend, f"{what} {part}")
            p, size, _ = self.matrix(p, mend, depth + 1, f"{what} (opaque content)")
            return p, size, opaque_name.decode("latin-1")
        if not 1 <= mclass <= _MX_FUNCTION:
            raise self.fail(start, f"{what}: unknown array class {mclass} (admissible 1..17)")
        dims, p = self.int32s(p, mend, 4 * _MAX_DIMS, f"{what} dimensions")
        if not dims or any(d < 0 for d in dims):
            raise self.fail(
                start,
                f"{what}: dimensions {dims} are not admissible (1 to "
                f"{_MAX_DIMS} non-negative values)",
            )
        count = int(np.prod(dims, dtype=object))
        raw_name, p = self.int8_string(p, mend, f"{what} name")
        name = raw_name.decode("latin-1")
        label = f"variable {name!r}" if depth == 0 and name else what
        size = 0
        if mclass in _MX_NUMERIC:
            _, _, p = self.numeric(p, mend, count, f"{label} real part")
            size = count * 8
            if is_complex:
                _, _, p = self.numeric(p, mend, count, f"{label} imaginary part")
                size *= 2
        elif mclass == _MX_SPARSE:
            p, size = self.sparse(p, mend, dims, is_complex, is_logical, label)
        elif mclass == _MX_CHAR:
            p, size = self.char(p, mend, count, label)
        elif mclass == _MX_CELL:
            self.room(count, p, mend, label)
            for i in range(count):
                p, sub, _ = self.matrix(p, mend, depth + 1, f"{label} cell {i}")
                size += sub
        elif mclass in (_MX_STRUCT, _MX_OBJECT):
            if mclass == _MX_OBJECT:
                _, p = self.int8_string(p, mend, f"{label} class name")
            p, size = self.struct(p, mend, count, depth, label)
        else:  # function handle: one nested matrix
            p, size, _ = self.matrix(p, mend, depth + 1, f"{label} (function)")
        return p, size, name

    def room(self, count: int, pos: int, end: int, what: str) -> None:
        """Each nested matrix needs at least an 8-byte tag: bound element counts by bytes."""
        if count > (end - pos) // 8:
            raise self.fail(
                pos,
                f"{what} declares {count} elements, but only {end - pos} bytes "
                "remain (at least 8 per element)",
            )

    def struct(self, pos: int, end: int, count: int, depth: int, what: str) -> tuple[int, int]:
        lengths, p = self.int32s(pos, end, 4, f"{what} field-name length")
        if len(lengths) != 1 or lengths[0] <= 0:
            raise self.fail(pos, f"{what}: field-name length {lengths} is not one positive int")
        name_len = lengths[0]
        names, p = self.int8_string(p, end, f"{what} field names")
        n_fields = len(names) // name_len
        for i in range(n_fields):
            tail = names[i * name_len :]
            cut = tail.find(b"\0")
            try:
                (tail if cut < 0 else tail[:cut]).decode("utf-8")
            except UnicodeDecodeError:
                raise self.fail(pos, f"{what}: field name {i} is not UTF-8") from None
        self.room(count * n_fields, p, end, what)
        size = 0
        for i in range(count * n_fields):
            p, sub, _ = self.matrix(p, end, depth + 1, f"{what} field {i % n_fields}")
            size += sub
        return p, size

    def char(self, pos: int, end: int, count: int, what: str) -> tuple[int, int]:
        mdtype, nbytes, _, nxt = self.element(pos, end, f"{what} characters")
        if nbytes == 0:  # scipy builds count blanks: bound it by memory
            return nxt, count * 4
        if mdtype not in _MI_CHAR:
            raise self.fail(
                pos,
                f"{what} characters have data type {_mi_name(mdtype)}; admissible are "
                f"{sorted(_MI_CHAR)}",
            )
        return nxt, nbytes * 4

    def sparse(
        self, pos: int, end: int, dims: list[int], is_complex: int, is_logical: int, what: str
    ) -> tuple[int, int]:
        if len(dims) != 2:
            raise self.fail(pos, f"{what}: a sparse matrix needs 2 dimensions, not {dims}")
        rows, cols = dims
        rowind, _, p = self.numeric(pos, end, None, f"{what} row indices", values=True)
        indptr, _, p = self.numeric(p, end, None, f"{what} column pointers", values=True)
        assert rowind is not None and indptr is not None
        if indptr.size < cols + 1:
            raise self.fail(pos, f"{what}: {indptr.size} column pointers for {cols} columns")
        ptr = indptr[: cols + 1].astype(np.int64)
        nnz = int(ptr[-1])
        if ptr[0] != 0 or np.any(np.diff(ptr) < 0) or nnz > rowind.size:
            raise self.fail(pos, f"{what}: column pointers are not a valid CSC index")
        idx = rowind[:nnz].astype(np.int64)
        if nnz and (idx.min() < 0 or idx.max() >= rows):
            raise self.fail(pos, f"{what}: row indices outside 0..{rows - 1}")
        mdtype = self.element(p, end, f"{what} values")[0]
        _, nbytes, p = self.numeric(p, end, None, f"{what} values")
        size = _MI_NUMERIC[mdtype]
        n_values = nbytes // size
        if is_logical and size != 1 and nbytes == nnz:
            n_values = nnz  # scipy reads such logical values as one byte each
        if is_complex:
            _, imag_bytes, p = self.numeric(p, end, None, f"{what} imaginary values")
            n_values = min(n_values, imag_bytes // size)
        if n_values < nnz:
            raise self.fail(pos, f"{what}: {n_values} values for {nnz} non-zeros")
        return p, nnz * (16 if is_complex else 8) + (cols + 1 + nnz) * 8


def _file_bytes(fh) -> mmap.mmap | bytes:
    size = os.fstat(fh.fileno()).st_size
    if size == 0:
        return b""
    return mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)


def _decompress(buf, start: int, end: int, budget: float, path: Path, what: str) -> bytes:
    d = zlib.decompressobj()
    try:
        out = d.decompress(buf[start:end], int(budget) + 1)
    except zlib.error as exc:
        raise _Damage(start, f"{what}: compressed data are corrupt ({exc})") from None
    if len(out) > budget:
        require_memory(len(out) + len(d.unconsumed_tail) * 1032, path, what)
    if not d.eof:
        raise _Damage(
            start, f"{what}: compressed data end before the zlib stream does (truncated or corrupt)"
        )
    if d.unused_data:
        raise _Damage(start, f"{what}: {len(d.unused_data)} bytes after the end of the zlib stream")
    return out


def _check_v5(path: Path, buf, size: int, info: MatInfo) -> None:
    if size < 128:
        raise _Damage(0, f"a MAT v5 file starts with a 128-byte header; the file has {size} bytes")
    marker = bytes(buf[126:128])
    if marker not in (b"IM", b"MI"):
        raise _Damage(126, f"endian indicator {marker!r} is neither 'IM' nor 'MI'")
    endian: Literal["<", ">"] = "<" if marker == b"IM" else ">"
    walker = _V5Walker(buf, endian, 0)
    budget = memory_budget()
    seen: set[str] = set()
    pos = 128
    index = 0
    while pos < size:
        mdtype, nbytes = walker.full_tag(pos, size, f"variable {index} tag")
        start, end = pos + 8, pos + 8 + nbytes
        if nbytes == 0:
            raise _Damage(pos, f"variable {index}: element of 0 bytes")
        require_in_file(
            end, size, path, f"variable {index} (at byte {pos})", format_name="MAT", start=start
        )
        if mdtype == _MI_COMPRESSED:
            what = f"variable {index} (compressed, at byte {pos})"
            data = _decompress(buf, start, end, budget - info.decoded_bytes, path, what)
            inner = _V5Walker(data, endian, 0)
            try:
                _, used, name = inner.matrix(0, len(data), 0, what)
            except _Damage as exc:
                raise _Damage(
                    start, f"{exc} (at byte {exc.offset} of the decompressed data)"
                ) from None
            info.decoded_bytes += len(data) + used
        elif mdtype == _MI_MATRIX:
            _, used, name = walker.matrix(pos, end, 0, f"variable {index}")
            info.decoded_bytes += used
        else:
            raise _Damage(
                pos,
                f"variable {index} has data type {_mi_name(mdtype)}; expected "
                "miMATRIX (14) or miCOMPRESSED (15)",
            )
        if info.decoded_bytes > budget:
            require_memory(info.decoded_bytes, path, "the variables of the file")
        if name in seen:
            raise _Damage(pos, f"variable name {name!r} appears twice")
        seen.add(name)
        info.variables.append(name)
        pos = end
        index += 1


def _check_v4(path: Path, buf, size: int, info: MatInfo) -> None:
    first = struct.unpack_from("<i", buf, 0)[0] if size >= 4 else 0
    endian = "<" if first == 0 or 0 <= first <= 5000 else ">"
    header = struct.Struct(endian + "5i")
    pos = 0
    index = 0
    while pos < size:
        if pos + 20 > size:
            raise _Damage(pos, f"variable {index}: header needs 20 bytes, {size - pos} left")
        mopt, mrows, ncols, imagf, namlen = header.unpack_from(buf, pos)
        if not 0 <= mopt <= 5000:
            raise _Damage(pos, f"variable {index}: type code {mopt} outside 0..5000")
        machine, rest = divmod(mopt, 1000)
        zero, rest = divmod(rest, 100)
        precision, mtype = divmod(rest, 10)
        if zero != 0 or precision not in _V4_ITEMSIZE or mtype not in (0, 1, 2) or machine > 1:
            raise _Damage(pos, f"variable {index}: type code {mopt} is not a MAT v4 code")
        if mrows < 0 or ncols < 0 or namlen <= 0:
            raise _Damage(
                pos,
                f"variable {index}: rows {mrows}, columns {ncols}, name length "
                f"{namlen} (need >= 0, >= 0, > 0)",
            )
        nbytes = mrows * ncols * _V4_ITEMSIZE[precision] * (2 if imagf == 1 else 1)
        start = pos + 20
        end = start + namlen + nbytes
        require_in_file(
            end,
            size,
            path,
            f"variable {index} ({mrows} x {ncols})",
            format_name="MAT",
            start=start,
        )
        if mtype == 2 and ncols not in (3, 4):
            raise _Damage(pos, f"variable {index}: sparse matrix with {ncols} columns (3 or 4)")
        name = bytes(buf[start : start + namlen]).strip(b"\0").decode("latin-1")
        if name in info.variables:
            raise _Damage(pos, f"variable name {name!r} appears twice")
        info.variables.append(name)
        info.decoded_bytes += nbytes * (2 if precision else 1)
        pos = end
        index += 1
    require_memory(info.decoded_bytes, path, "the variables of the file")


def check_mat(path: str | os.PathLike[str]) -> MatInfo:
    """Walk a MAT v4 or v5/v7 file and refuse it if scipy could crash or over-allocate on it.

    Parameters
    ----------
    path : path-like
        A ``.mat`` file that is not v7.3 (HDF5; see :mod:`analysis.readers.mat73`).

    Returns
    -------
    MatInfo
        Version, variable names and decoded size.

    Raises
    ------
    ReaderError
        Naming the file, the byte offset and the structure that is damaged or truncated, or
        the memory the file needs when it exceeds what is available.
    """
    p = Path(path)
    with open(p, "rb") as fh:
        buf = _file_bytes(fh)
        size = len(buf)
        try:
            if size == 0:
                raise _Damage(0, "the file is empty")
            head = bytes(buf[:4])
            info = MatInfo("4" if 0 in head or size < 4 else "5")
            if info.version == "5":
                major = None
                if size >= 128:
                    major = buf[125] if buf[126] == ord("I") else buf[124]
                if major == 2:
                    return MatInfo("7.3")
                if major != 1:
                    raise _Damage(
                        124,
                        f"version field {bytes(buf[124:126]).hex()} is not a "
                        "MAT v5 file (and the header text is not v7.3)",
                    )
                _check_v5(p, buf, size, info)
            else:
                _check_v4(p, buf, size, info)
        except ReaderError:
            raise
        except _Damage as exc:
            raise ReaderError(
                f"{p}: not a readable MAT file: {exc} (at byte {exc.offset}); the file is "
                "truncated or corrupt"
            ) from None
        except (struct.error, IndexError, ValueError, OverflowError) as exc:
            raise ReaderError(f"{p}: not a readable MAT file (corrupt structure: {exc})") from None
        finally:
            if isinstance(buf, mmap.mmap):
                buf.close()
    return info
