"""MATLAB v7.3 MAT files (HDF5 behind a 512-byte MAT header), via h5py (optional extra).

MATLAB ``save(..., '-v7.3')`` writes an HDF5 file whose first 512 bytes (the HDF5 *userblock*)
hold the usual 128-byte MAT header, with the text ``MATLAB 7.3 MAT-file``. Every variable is
an HDF5 object at the root of the file carrying a ``MATLAB_class`` attribute:

* numeric and ``logical`` arrays are datasets stored column-major, so the HDF5 shape is the
  MATLAB shape reversed (a 1000x1 column vector is a (1, 1000) dataset);
* ``char`` arrays are ``uint16`` datasets of UTF-16 code units (``MATLAB_int_decode = 2``);
* empty arrays are a small ``uint64`` dataset holding the MATLAB dimensions, flagged with
  ``MATLAB_empty = 1``;
* complex arrays use a compound type with ``real`` and ``imag`` members;
* structs are groups (fields as members, their order in ``MATLAB_fields``); struct arrays and
  cell arrays hold object references into the hidden ``#refs#`` group;
* sparse matrices are groups with ``data``/``ir``/``jc`` and ``MATLAB_sparse`` (rows);
* class objects (``string``, ``datetime``, ``table``, ...) carry ``MATLAB_object_decode`` and
  cannot be decoded outside MATLAB.

:func:`load_mat73` decodes a file into the same Python values as
``scipy.io.loadmat(path, squeeze_me=True, chars_as_strings=True)`` gives for a v5 file (structs
become dicts, class objects an opaque :class:`MatlabObject`), so that
:func:`analysis.readers.mat.read_mat` treats both versions identically. h5py is imported only
when such a file is read: ``pip install "gearvib[hdf5]"``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from analysis.readers.integrity import describe, file_size, format_bytes, require_memory
from analysis.readers.layout import ReaderError

__all__ = ["MAT73_HEADER_TEXT", "MatlabObject", "is_mat73", "load_mat73"]

#: Start of the MAT header text of a v7.3 file.
MAT73_HEADER_TEXT = b"MATLAB 7.3 MAT-file"
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
_USERBLOCK = 512  # MATLAB's userblock; HDF5 also looks at 0 and further powers of two
_ZLIB_MAX_RATIO = 1032  # deflate's largest compression ratio

_NUMERIC: dict[str, type[np.generic]] = {
    "double": np.float64,
    "single": np.float32,
    "int8": np.int8,
    "uint8": np.uint8,
    "int16": np.int16,
    "uint16": np.uint16,
    "int32": np.int32,
    "uint32": np.uint32,
    "int64": np.int64,
    "uint64": np.uint64,
    "logical": np.uint8,  # scipy.io.loadmat returns v5 logicals as uint8 too
}


class MatlabObject:
    """Placeholder for a MATLAB value that cannot be decoded outside MATLAB.

    Class objects (``string``, ``datetime``, ``table``, user classes) and function handles end
    up here; the reader treats them like any other non-numeric variable.

    Parameters
    ----------
    matlab_class : str
        The ``MATLAB_class`` attribute of the HDF5 object.
    """

    def __init__(self, matlab_class: str) -> None:
        self.matlab_class = matlab_class

    def __repr__(self) -> str:
        return f"MatlabObject({self.matlab_class!r})"


def _import_h5py() -> Any:
    try:
        import h5py
    except ImportError:
        raise ImportError(
            'reading MATLAB v7.3 (HDF5) MAT files needs h5py: pip install "gearvib[hdf5]"'
        ) from None
    return h5py


def _unreadable(p: Path, detail: object) -> ReaderError:
    return ReaderError(
        f"{p}: not a readable MATLAB v7.3 (HDF5) MAT file (truncated or corrupt?): {detail}; "
        "if MATLAB still opens it, re-save it with save(file, ..., '-v7')"
    )


def is_mat73(path: str | os.PathLike[str]) -> bool:
    """Whether the MAT header of ``path`` announces a v7.3 (HDF5) file.

    Parameters
    ----------
    path : path-like
        A ``.mat`` file.

    Returns
    -------
    bool
        True when the header text starts with ``MATLAB 7.3 MAT-file``.
    """
    with open(os.fspath(path), "rb") as fh:  # fspath: an int would open a file descriptor
        return fh.read(len(MAT73_HEADER_TEXT)) == MAT73_HEADER_TEXT


def _has_hdf5_superblock(p: Path) -> bool:
    """Whether an HDF5 signature sits where HDF5 looks for it (0, 512, 1024, 2048, ...)."""
    size = p.stat().st_size
    offsets = [0]
    off = _USERBLOCK
    while off + len(_HDF5_SIGNATURE) <= size:
        offsets.append(off)
        off *= 2
    with open(p, "rb") as fh:
        for off in offsets:
            fh.seek(off)
            if fh.read(len(_HDF5_SIGNATURE)) == _HDF5_SIGNATURE:
                return True
    return False


# ----------------------------------------------------------------------------------------------
# decoding
# ----------------------------------------------------------------------------------------------


def _squeeze(arr: np.ndarray) -> Any:
    """What ``loadmat(squeeze_me=True)`` makes of an array: empty -> 1-D empty, unit axes
    dropped, a single element of a built-in dtype -> Python scalar."""
    if arr.size == 0:
        return np.array([], dtype=arr.dtype)
    out = np.squeeze(arr)
    if out.ndim == 0 and out.dtype.isbuiltin:
        return out.item()
    return out


def _text(value: Any) -> str:
    if isinstance(value, bytes | np.bytes_):
        return bytes(value).decode("ascii", errors="replace")
    return str(value)


def _class_of(obj: Any) -> str | None:
    value = obj.attrs.get("MATLAB_class")
    return None if value is None else _text(value)


def _flag(obj: Any, name: str) -> bool:
    """Whether the integer attribute ``name`` of ``obj`` is present and non-zero."""
    value = obj.attrs.get(name)
    return value is not None and bool(np.ravel(value)[0])


def _empty(cls: str | None) -> np.ndarray:
    if cls == "char":
        return np.array([], dtype="<U1")
    if cls in ("struct", "cell") or (cls is not None and cls not in _NUMERIC):
        return np.array([], dtype=object)
    return np.array([], dtype=_NUMERIC.get(cls or "double", np.float64))


def _chars(codes: np.ndarray) -> Any:
    """MATLAB char array (MATLAB shape) -> one string per row, like ``chars_as_strings``."""
    if codes.size == 0:
        return np.array([], dtype="<U1")
    if codes.ndim == 0:
        codes = codes.reshape(1, 1)
    encoding = {1: "latin-1", 2: "utf-16-le", 4: "utf-32-le"}.get(codes.dtype.itemsize)
    if encoding is None:
        raise ValueError(f"char data of dtype {codes.dtype}")
    flat = codes.reshape(-1, codes.shape[-1]).astype(f"<u{codes.dtype.itemsize}")
    rows = [row.tobytes().decode(encoding, errors="replace") for row in flat]
    strings = np.array(rows, dtype=f"<U{max([1, *(len(r) for r in rows)])}")
    return _squeeze(strings.reshape(codes.shape[:-1]))


def _numeric(raw: np.ndarray, cls: str | None) -> np.ndarray:
    if raw.dtype.names is not None:
        if not {"real", "imag"} <= set(raw.dtype.names):
            raise ValueError(f"compound dtype {raw.dtype} is not a MATLAB complex array")
        single = cls == "single" or raw.dtype["real"] == np.float32
        return (raw["real"] + 1j * raw["imag"]).astype(np.complex64 if single else np.complex128)
    if cls in _NUMERIC:
        return raw.astype(_NUMERIC[cls], copy=False)
    return raw


class _Decoder:
    """Decodes the objects of one open file (references are resolved through ``root``)."""

    def __init__(self, h5py: Any, root: Any) -> None:
        self.h5py = h5py
        self.root = root

    def _is_ref(self, dset: Any) -> bool:
        return self.h5py.check_dtype(ref=dset.dtype) is not None

    def _deref(self, ref: Any) -> Any:
        if not ref:
            return np.array([], dtype=np.float64)
        return self.decode(self.root[ref])

    def _objects(self, refs: np.ndarray, fn: Any) -> np.ndarray:
        """Object array (MATLAB shape) with ``fn(ref)`` for each stored reference."""
        out = np.empty(refs.shape, dtype=object)
        for idx in np.ndindex(refs.shape):
            out[idx] = fn(refs[idx])
        return out

    def decode(self, obj: Any) -> Any:
        """Decode an HDF5 dataset or group written by MATLAB into a loadmat-like value."""
        cls = _class_of(obj)
        if isinstance(obj, self.h5py.Group):
            return self._group(obj, cls)
        if _flag(obj, "MATLAB_empty"):
            return _empty(cls)
        if "MATLAB_object_decode" in obj.attrs or cls == "function_handle":
            return MatlabObject(cls or "object")
        if cls == "cell" or (cls is None and self._is_ref(obj)):
            return _squeeze(self._objects(obj[()].T, self._deref))
        raw = obj[()]
        data = np.asarray(raw).T
        if cls == "char":
            return _chars(data)
        if cls is not None and cls not in _NUMERIC:
            return MatlabObject(cls)
        if data.dtype.kind in "SUO":
            return _squeeze(data)
        return _squeeze(_numeric(data, cls))

    def _fields(self, group: Any) -> list[str]:
        names = [k for k in group if not k.startswith("#")]
        order: list[str] = []
        raw = group.attrs.get("MATLAB_fields")
        if raw is not None:
            for item in np.asarray(raw, dtype=object).ravel():
                chars = np.asarray(item).ravel()
                name = "".join(_text(c) for c in chars) if chars.dtype.kind in "SU" else ""
                if name in names and name not in order:
                    order.append(name)
        return order + [k for k in names if k not in order]

    def _group(self, group: Any, cls: str | None) -> Any:
        if _flag(group, "MATLAB_empty"):
            return _empty(cls)
        if "MATLAB_sparse" in group.attrs:
            return self._sparse(group, cls)
        if cls not in (None, "struct"):
            return MatlabObject(cls)
        fields = self._fields(group)
        members = [group[k] for k in fields]
        is_array = bool(members) and all(
            isinstance(m, self.h5py.Dataset) and "MATLAB_class" not in m.attrs and self._is_ref(m)
            for m in members
        )
        if not is_array:
            return {k: self.decode(m) for k, m in zip(fields, members, strict=True)}
        refs = {k: m[()].T for k, m in zip(fields, members, strict=True)}
        shape = next(iter(refs.values())).shape
        if any(r.shape != shape for r in refs.values()):
            raise ValueError(f"struct array {group.name!r}: fields of different shapes")
        out = np.empty(shape, dtype=object)
        for idx in np.ndindex(shape):
            out[idx] = {k: self._deref(r[idx]) for k, r in refs.items()}
        return _squeeze(out)

    def _sparse(self, group: Any, cls: str | None) -> Any:
        from scipy.sparse import csc_matrix

        rows = int(np.ravel(group.attrs["MATLAB_sparse"])[0])
        jc = np.ravel(group["jc"][()]).astype(np.int64)
        cols = jc.size - 1
        dtype = _NUMERIC.get(cls or "double", np.float64)
        if "data" in group:
            data = _numeric(np.ravel(group["data"][()]), cls)
            ir = np.ravel(group["ir"][()]).astype(np.int64)
        else:
            data, ir = np.zeros(0, dtype=dtype), np.zeros(0, dtype=np.int64)
        return csc_matrix((data, ir, jc), shape=(rows, cols))


def _file_order(h5py: Any, root: Any, names: list[str]) -> list[str]:
    """``names`` in the order MATLAB wrote them.

    HDF5 lists the members of a group alphabetically unless creation order is tracked, which
    MATLAB does not do; the object headers, however, are allocated as the variables are
    written, so their file addresses give the order of saving (like the order of a v5 file).
    """
    try:
        addr = {k: int(h5py.h5o.get_info(root[k].id).addr) for k in names}
    except (AttributeError, TypeError, ValueError, KeyError, OSError):
        return names
    return sorted(names, key=addr.__getitem__)


def _check_sizes(h5py: Any, fh: Any, p: Path) -> None:
    """Refuse datasets whose declared size the file cannot hold, and files that need more
    memory than available, before anything is read.

    Uncompressed data must lie in the file; gzip (deflate) cannot compress more than 1032:1.
    """
    size = file_size(p)
    total = 0

    def visit(name: str, obj: Any) -> None:
        nonlocal total
        if not isinstance(obj, h5py.Dataset):
            return
        nbytes = int(obj.size) * int(obj.dtype.itemsize)
        compression = obj.compression
        limit = {None: size, "gzip": _ZLIB_MAX_RATIO * size}.get(compression)
        if limit is not None and nbytes > limit + (1 << 20):
            raise ReaderError(
                f"{p}: dataset {name!r} declares shape {obj.shape} ({format_bytes(nbytes)}) "
                f"in a file of {format_bytes(size)}"
                + (" (zlib compresses at most 1032:1)" if compression else "")
                + ": the file is truncated or corrupt"
            )
        total += nbytes

    fh.visititems(visit)
    require_memory(2 * total, p, f"the variables ({format_bytes(total)} declared)")


def load_mat73(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read every variable of a MATLAB v7.3 file.

    Parameters
    ----------
    path : path-like
        MAT file whose header says ``MATLAB 7.3 MAT-file``.

    Returns
    -------
    dict
        Variable name -> value in the order of saving, decoded like
        ``scipy.io.loadmat(path, squeeze_me=True, chars_as_strings=True)`` decodes a v5 file:
        arrays in MATLAB orientation with unit dimensions squeezed, 1x1 arrays as Python
        scalars, empty arrays as 1-D empty arrays, ``logical`` as ``uint8``, ``char`` as
        ``str`` (one per row), cells as object arrays, sparse as ``scipy.sparse.csc_matrix``.
        Structs become dicts (struct arrays object arrays of dicts) and class objects
        :class:`MatlabObject`. HDF5 objects whose name starts with ``#`` (``#refs#``,
        ``#subsystem#``) are MATLAB internals and left out.

    Raises
    ------
    ImportError
        h5py is not installed (the message gives ``pip install "gearvib[hdf5]"``).
    ReaderError
        The file is truncated or corrupt (no HDF5 superblock, HDF5 errors, undecodable objects).
    """
    p = Path(path)
    if not _has_hdf5_superblock(p):
        raise _unreadable(p, f"no HDF5 superblock after the {_USERBLOCK}-byte MAT header")
    h5py = _import_h5py()
    try:
        with h5py.File(p, "r") as fh:
            _check_sizes(h5py, fh, p)
            decoder = _Decoder(h5py, fh)
            names = _file_order(h5py, fh, [k for k in fh if not k.startswith("#")])
            return {name: decoder.decode(fh[name]) for name in names}
    except ReaderError:
        raise
    except MemoryError:
        raise _unreadable(p, "it needs more memory than is available") from None
    except Exception as exc:  # h5py raises assorted errors on damaged files
        raise _unreadable(p, describe(exc)) from None
