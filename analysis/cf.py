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

from typing import Any

import numpy as np

__all__ = [
    "EPOCH",
    "LABEL_SUFFIX",
    "elapsed_seconds",
    "is_elapsed_seconds",
    "labels_from_cf",
    "labels_to_cf",
    "processing_attrs",
    "result_dataset",
    "time_attrs",
]

#: Reference of the time axis when the absolute start is not known.
EPOCH = "1970-01-01T00:00:00Z"
#: Suffix of the label variable of a dimension with string labels.
LABEL_SUFFIX = "_label"


def time_attrs(long_name: str, reference: str | None = None) -> dict[str, str]:
    """Attributes of a CF time coordinate holding elapsed seconds since ``reference``.

    Parameters
    ----------
    long_name : str
        Description, e.g. ``"time since start of run"``.
    reference : str, optional
        ISO 8601 instant of time 0 (``time_coverage_start``); default :data:`EPOCH`.
    """
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


def result_dataset(ds: Any, title: str, history: str) -> Any:
    """``ds`` with the global ``title`` and ``history`` of a result (CF 2.6.2; deterministic
    text, no time stamp) and no ``_FillValue`` on its coordinates (CF 2.5.1), so that
    ``ds.to_netcdf(...)`` writes a file the CF checker accepts. Returns ``ds`` (modified)."""
    ds.attrs.setdefault("Conventions", "CF-1.11")
    ds.attrs["title"] = title
    ds.attrs["history"] = history
    for name in ds.coords:
        ds[name].encoding["_FillValue"] = None
    return ds


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


def labels_to_cf(ds: Any) -> Any:
    """The Dataset with every string dimension coordinate ``d`` as label variable ``d_label``.

    The label keeps the coordinate's attributes; the dimension loses its coordinate variable
    (CF coordinate variables are numeric). Inverse: :func:`labels_from_cf`.
    """
    out = ds
    for name in list(ds.coords):
        var = ds[name]
        if var.dims == (name,) and var.dtype.kind in "USO":
            label = f"{name}{LABEL_SUFFIX}"
            attrs = dict(var.attrs)
            attrs.setdefault("long_name", f"{name} label")
            out = out.drop_vars(name).assign_coords(
                {label: ((name,), np.asarray(var.values).astype(str), attrs)}
            )
    return out


def labels_from_cf(ds: Any) -> Any:
    """Restore dimension coordinates from label variables written by :func:`labels_to_cf`."""
    out = ds
    for name in list(ds.variables):
        name = str(name)
        if not name.endswith(LABEL_SUFFIX):
            continue
        dim = name[: -len(LABEL_SUFFIX)]
        var = ds[name]
        if var.dims == (dim,) and dim not in ds.variables and var.dtype.kind in "USO":
            out = out.drop_vars(name).assign_coords(
                {dim: ((dim,), np.asarray(var.values).astype(str), dict(var.attrs))}
            )
    return out
