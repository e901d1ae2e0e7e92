"""CF-1.11 conventions of the files every tool reads: the time coordinate, labels, history.

Decisions (documented in ``docs/analysis-readers-speed.md``), checked with the IOOS
compliance-checker at CF-1.11 in the tests:

* **Time** stays float64 *elapsed* seconds in memory and on disk, so that analysis code and
  users never juggle datetimes, but its attributes make it a CF time coordinate:
  ``standard_name = "time"``, ``axis = "T"`` (so that cf_xarray and other tools find the axes),
  ``calendar = "standard"``, ``units_metadata = "leap_seconds: none"`` (CF-1.11 section 4.4:
  elapsed seconds without leap seconds) and ``units = "seconds since <reference>"``, where
  the reference is the absolute start of the recording when the file states it
  (``time_coverage_start``) and otherwise the Unix epoch ``1970-01-01T00:00:00Z`` as a
  conventional origin: a run or recording without an absolute
  start then decodes to dates in January 1970, read as "seconds after the start". A plain
  ``units = "s"`` is not a CF time unit (the checker refuses it). Open files with
  ``decode_times=False`` to keep float seconds; the analysis functions also accept the
  decoded datetimes (they use the time since the first sample).
* **String labels** (mesh, flank, bearing, member names) cannot be CF coordinate variables,
  which must be numeric. In memory they are dimension coordinates (``ds.sel(mesh=...)``); in
  a file each becomes a label variable ``<dim>_label(<dim>)`` (an auxiliary coordinate, CF
  section 6.1) and the dimension has no coordinate variable. :func:`labels_to_cf` and
  :func:`labels_from_cf` convert between the two.
* **history** is a deterministic global attribute (which program made the data, no time
  stamp, so that the same input gives the same file bit for bit).
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
