"""CF-1.11 conventions of every file the toolkit writes: time, labels, provenance.

Decisions (documented in ``docs/files.md``), checked with the IOOS compliance-checker at
CF-1.11 in the tests (no message at any priority):

* **Time** stays float64 *elapsed* seconds in memory and on disk, so that analysis code and
  users never juggle datetimes, but its attributes make it a CF time coordinate:
  ``standard_name = "time"``, ``axis = "T"`` (so that cf_xarray and other tools find the axes),
  ``calendar = "standard"``, ``units_metadata = "leap_seconds: none"`` (CF-1.11 section 4.4:
  elapsed seconds without leap seconds) and ``units = "seconds since <reference>"``, where
  the reference is the absolute start of the recording when the file states it
  (``time_coverage_start``) and otherwise the Unix epoch ``1970-01-01T00:00:00Z`` as a
  conventional origin. CF and its checker leave no other choice for a dimension named
  ``time``: the checker requires ``standard_name = "time"`` on it (CF section 5.1) and a time
  coordinate needs a reference date (section 4.4). xarray decodes every ``units`` holding
  ``since`` into ``datetime64``, so a plain ``xarray.open_dataset`` gives datetimes (in
  January 1970 without an absolute start, read as time after the start); ``decode_times=False``
  or ``engine="gearvib"`` (:mod:`gearvib.xarray_backend`) give float seconds, and the analysis
  functions accept the decoded axes as well (:func:`elapsed_seconds`, time since the first
  sample).
* **String labels** (mesh, flank, sensor, channel names) are dimension coordinates in memory
  (``ds.sel(mesh=...)``). In a file each is a character array named after its dimension,
  ``char mesh(mesh, mesh_strlen)`` with ``_Encoding = "utf-8"``: the netCDF User Guide's form
  of a string coordinate variable and a CF section 6.1 label variable. A plain
  ``xarray.open_dataset`` decodes it into a string index, so ``ds.sel(mesh="sun-planet1")``
  works on any reader; the compliance-checker accepts it (a numeric-only CF *coordinate
  variable* is one-dimensional, a label array is two-dimensional). :func:`labels_to_cf` sets
  the encoding, :func:`labels_from_cf` restores ``str`` labels (and reads files of earlier
  versions, whose labels were ``<dim>_label`` variables).
* **Provenance**: :func:`cf_dataset` finishes every result Dataset with ``Conventions``,
  ``title``, ``source``, ``history``, the toolkit version and the inputs. ``history`` is
  deterministic (which program made the data, no time stamp), so the same input gives the
  same file bit for bit.
* **Levels in dB** are not UDUNITS units: such variables have ``units = "1"``, the decibel
  reference in ``long_name`` (as the run-up maps do).
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from analysis.checks import require_instance

__all__ = [
    "CONVENTIONS",
    "EPOCH",
    "LABEL_SUFFIX",
    "STRLEN_SUFFIX",
    "cf_dataset",
    "clean_attr_value",
    "elapsed_seconds",
    "is_elapsed_seconds",
    "label_encoding",
    "labels_from_cf",
    "labels_to_cf",
    "processing_attrs",
    "provenance_attrs",
    "time_attrs",
    "toolkit_version",
]

#: The CF version every file follows.
CONVENTIONS = "CF-1.11"
#: Reference of the time axis when the absolute start is not known.
EPOCH = "1970-01-01T00:00:00Z"
#: Suffix of the label variables of files written before labels became character arrays
#: (read by :func:`labels_from_cf`).
LABEL_SUFFIX = "_label"
#: Suffix of the string-length dimension of a label array: ``mesh(mesh, mesh_strlen)``.
STRLEN_SUFFIX = "_strlen"


def time_attrs(long_name: str, reference: str | None = None) -> dict[str, str]:
    """Attributes of a CF time coordinate holding elapsed seconds since ``reference``.

    Parameters
    ----------
    long_name : str
        Description, e.g. ``"time since start of run"``.
    reference : str, optional
        ISO 8601 instant of time 0 (``time_coverage_start``); default :data:`EPOCH`.
    """
    require_instance(long_name, str, "long_name")
    if reference is not None:
        require_instance(reference, str, "reference")
    ref = reference.strip() if reference else EPOCH
    return {
        "units": f"seconds since {ref}",
        "standard_name": "time",
        "axis": "T",
        "calendar": "standard",
        "units_metadata": "leap_seconds: none",
        "long_name": long_name,
    }


def processing_attrs(reference: str = "", notes: Any = ()) -> dict[str, str]:
    """Attributes that say how a result was obtained: the speed reference used
    (``speed_reference``) and what was done beyond the request (CF ``comment``, the notes
    joined by ``"; "``). Empty values give no attribute.

    Parameters
    ----------
    reference : str
        Name of the speed reference (tacho channel, shaft), or ``""``.
    notes : sequence of str
        Notes of the computation.
    """
    attrs: dict[str, str] = {}
    if reference:
        attrs["speed_reference"] = reference
    if notes:
        attrs["comment"] = "; ".join(notes)
    return attrs


def is_elapsed_seconds(units: Any) -> bool:
    """Whether ``units`` describe float seconds: ``"s"``, ``"seconds"`` or ``"seconds since
    ..."`` (the reference only shifts the origin)."""
    u = str(units).strip().lower()
    return u in ("s", "second", "seconds", "sec") or u.startswith(("seconds since", "s since"))


def elapsed_seconds(time: Any) -> np.ndarray:
    """Float seconds of a time axis; a decoded datetime64 axis counts from its first sample."""
    t = np.asarray(time)
    if np.issubdtype(t.dtype, np.datetime64):
        return (t - t[0]) / np.timedelta64(1, "s")
    if np.issubdtype(t.dtype, np.timedelta64):
        return t / np.timedelta64(1, "s")
    return t


# ---------------------------------------------------------------------------------------------
# labels
# ---------------------------------------------------------------------------------------------


def label_encoding(dim: str) -> dict[str, str]:
    """xarray encoding of the string labels of dimension ``dim``: a UTF-8 character array
    ``dim(dim, dim_strlen)`` (see the module notes)."""
    return {"dtype": "S1", "char_dim_name": f"{dim}{STRLEN_SUFFIX}"}


def _require_dataset(ds: Any) -> None:
    import xarray as xr

    require_instance(ds, xr.Dataset, "ds")


def _is_label(ds: Any, name: Any) -> bool:
    var = ds.variables[name]
    return var.dims == (name,) and var.dtype.kind in "USO"


def labels_to_cf(ds: Any) -> Any:
    """The Dataset with every string dimension coordinate encoded as a label array.

    A shallow copy whose string index coordinates get ``long_name`` (``"<dim> label"`` when
    missing) and the encoding :func:`label_encoding`, so that ``to_netcdf`` writes
    ``char <dim>(<dim>, <dim>_strlen)``; values stay ``str`` in memory. Inverse:
    :func:`labels_from_cf`.
    """
    _require_dataset(ds)
    out = ds.copy(deep=False)
    for name in list(out.coords):
        if not _is_label(out, name):
            continue
        var = out.variables[name]
        strlen = f"{name}{STRLEN_SUFFIX}"
        if strlen in out.dims:
            raise ValueError(f"dimension {strlen!r} exists; it is the string length of the "
                             f"labels of {name!r}")
        var.attrs.setdefault("long_name", f"{name} label")
        var.encoding = {**{k: v for k, v in var.encoding.items()
                           if k not in ("_FillValue", "zlib", "compression", "chunksizes")},
                        **label_encoding(str(name))}
    return out


def labels_from_cf(ds: Any) -> Any:
    """String dimension coordinates as ``str`` labels, as :func:`labels_to_cf` had them.

    A label array decoded by xarray holds Python strings (``object``); they become ``str``
    arrays. Label variables ``<dim>_label(<dim>)`` of files written by earlier versions become
    the coordinate of their dimension again.
    """
    _require_dataset(ds)
    out = ds
    for name in list(ds.variables):
        name = str(name)
        var = ds[name]
        if var.dims == (name,) and var.dtype.kind == "O" and name in ds.coords:
            values = np.asarray(var.values)
            if all(isinstance(v, str) for v in values.ravel()):
                out = out.assign_coords({name: ((name,), values.astype(str), dict(var.attrs))})
                out[name].encoding = dict(var.encoding)
            continue
        if not name.endswith(LABEL_SUFFIX):
            continue
        dim = name[: -len(LABEL_SUFFIX)]
        if var.dims == (dim,) and dim not in ds.variables and var.dtype.kind in "USO":
            out = out.drop_vars(name).assign_coords(
                {dim: ((dim,), np.asarray(var.values).astype(str), dict(var.attrs))}
            )
    return out


# ---------------------------------------------------------------------------------------------
# provenance and the finished result Dataset
# ---------------------------------------------------------------------------------------------


def toolkit_version() -> str:
    """Version of the installed toolkit (the ``gearvib`` distribution, which holds
    :mod:`analysis`), read from its metadata without importing :mod:`gearvib`;
    ``"unknown"`` when it is not installed."""
    from importlib import metadata

    try:
        return metadata.version("gearvib")
    except metadata.PackageNotFoundError:
        return "unknown"


def clean_attr_value(value: Any) -> Any:
    """An attribute value netCDF can store, or ``None`` (drop it).

    ``bool`` becomes ``int8`` (0/1), a mapping or a nested/non-numeric sequence JSON, numbers,
    strings and 1-D numeric arrays stay, ``None`` is dropped, anything else becomes ``str``.
    """
    if value is None:
        return None
    if isinstance(value, bool | np.bool_):
        return np.int8(bool(value))
    if isinstance(value, str | bytes | int | float | np.integer | np.floating):
        return value
    if isinstance(value, Mapping):
        return json.dumps(value, sort_keys=True, default=str)
    if isinstance(value, list | tuple | np.ndarray):
        arr = np.asarray(value)
        if arr.ndim == 1 and arr.dtype.kind in "biuf" and arr.size:
            return arr.astype(np.int8) if arr.dtype.kind == "b" else arr
        return json.dumps(arr.tolist() if arr.dtype != object else list(value), default=str)
    return str(value)


def provenance_attrs(producer: str, inputs: Any = None) -> dict[str, str]:
    """Global attributes that say which program made the data from what.

    Parameters
    ----------
    producer : str
        The function or program, e.g. ``"analysis.spectrum.spectrum"``.
    inputs : str, mapping or sequence, optional
        What it was computed from (signal names, files, the speed reference); a mapping or
        sequence is stored as JSON.

    Returns
    -------
    dict
        ``source`` (CF: the method of production), ``history`` (CF: deterministic, no time
        stamp), ``gearvib_version`` and, when given, ``inputs``.
    """
    version = toolkit_version()
    attrs = {
        "source": f"gearvib {version} ({producer})",
        "history": f"{producer} (gearvib {version})",
        "gearvib_version": version,
    }
    if inputs is not None and inputs != "" and inputs != {} and inputs != []:
        attrs["inputs"] = inputs if isinstance(inputs, str) else json.dumps(
            inputs, sort_keys=True, default=str)
    return attrs


_DB = re.compile(r"^\s*d[Bb]\b")


def cf_dataset(ds: Any, *, title: str, producer: str, inputs: Any = None) -> Any:
    """A result Dataset finished as a CF-1.11 file: what every ``to_dataset`` returns.

    ``ds.to_netcdf(path)`` then writes a file that the IOOS compliance-checker passes at
    CF-1.11 with no message, and a plain ``xarray.open_dataset`` reads it back with its labels
    as string indexes.

    Parameters
    ----------
    ds : xarray.Dataset
        The result's variables with ``units`` and ``long_name``.
    title : str
        CF ``title`` when ``ds`` has none.
    producer : str
        The function that computed the result (:func:`provenance_attrs`).
    inputs : str, mapping or sequence, optional
        What it was computed from (:func:`provenance_attrs`).

    Returns
    -------
    xarray.Dataset
        A shallow copy with:

        * global ``Conventions``, ``title``, ``source``, ``history``, ``gearvib_version`` and
          ``inputs`` (an existing ``title``, ``source`` or ``inputs`` is kept, ``history``
          gets a line for ``producer`` unless it has it);
        * ``time`` the last dimension of every data variable (CF section 2.4: further
          dimensions to the left of T);
        * a ``time`` dimension coordinate in seconds (``units = "s"``) as a CF time
          coordinate (:func:`time_attrs` from ``time_coverage_start`` when the Dataset states
          it, its ``long_name`` kept);
        * levels in dB (``units`` starting with ``dB``) with ``units = "1"`` and the decibel
          reference in ``long_name`` (UDUNITS has no decibel);
        * no ``_FillValue`` on coordinates (CF section 2.5.1) and string dimension coordinates
          written as label arrays (:func:`labels_to_cf`);
        * attributes netCDF can store (:func:`clean_attr_value`).
    """
    _require_dataset(ds)
    out = labels_to_cf(ds)
    attrs: dict[str, Any] = {"Conventions": CONVENTIONS, "title": title}
    attrs.update(provenance_attrs(producer, inputs))
    for key in ("Conventions", "title", "source", "inputs"):
        if str(out.attrs.get(key, "")).strip():
            attrs[key] = out.attrs[key]  # kept (a run's, a measurement's)
    before = str(out.attrs.get("history", "")).strip()
    if before and attrs["history"] not in before.splitlines():  # CF: one line per step
        attrs["history"] = f"{before}\n{attrs['history']}"
    elif before:
        attrs["history"] = before
    out.attrs = _clean({**out.attrs, **attrs})
    if "time" in out.coords and out["time"].dims == ("time",) and (
            out["time"].dtype.kind in "fiu"
            and is_elapsed_seconds(out["time"].attrs.get("units", "s"))
            and "since" not in str(out["time"].attrs.get("units", ""))):
        var = out.variables["time"]
        long_name = str(var.attrs.get("long_name", "time"))
        start = str(out.attrs.get("time_coverage_start", "")).strip() or None
        var.attrs = {**{k: v for k, v in var.attrs.items() if k != "units"},
                     **time_attrs(long_name, start)}
    for name in list(out.data_vars):  # CF 2.4: further dimensions left of T
        dims = out[name].dims
        if "time" in dims and dims[-1] != "time":
            out[name] = out[name].transpose(..., "time")
    for name, var in out.variables.items():
        units = var.attrs.get("units")
        if isinstance(units, str) and _DB.match(units):
            long_name = str(var.attrs.get("long_name", name))
            if "dB" not in long_name:
                long_name = f"{long_name} ({units.strip()})"
            var.attrs["units"] = "1"
            var.attrs["long_name"] = long_name
        var.attrs = _clean(var.attrs)
        if name in out.coords and var.dtype.kind in "fiuc":
            var.encoding["_FillValue"] = None
    return out


def _clean(attrs: Mapping[str, Any]) -> dict[str, Any]:
    out = {}
    for k, v in attrs.items():
        cv = clean_attr_value(v)
        if cv is not None:
            out[str(k)] = cv
    return out
