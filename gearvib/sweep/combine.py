"""The combined Dataset of a sweep (``sweep.nc``): every case's summary along ``case``.

Layout
------
* Dimension ``case`` (coordinate ``case`` = 0, 1, ...), plus the dimensions of the summaries
  (``mesh``, ``order``, ``floquet_speed``, ...). A label that only some cases have (e.g. a fourth
  planet's meshes) is NaN (or ``""``) for the others; labels keep the order of first appearance.
* One coordinate along ``case`` per swept parameter, named after its key path with every
  character that a CF name cannot hold replaced by ``_`` (``meshes.sun.damping_ratio`` ->
  ``meshes_sun_damping_ratio``; ``_2``, ``_3`` ... appended when that name is taken), with
  ``units``, ``long_name`` and the key path itself in ``gearvib_parameter_path``; the
  parameters in ``parameters_json`` name their coordinate (``variable``), and
  :func:`parameter_variable` finds it. Numbers are float64; strings and booleans stay as they
  are. A list- or table-valued parameter (e.g. ``geometry.planet_angles_deg``) is a **string
  coordinate**: the value's label from the sweep (``labels = [...]``) or else its compact
  JSON, e.g. ``"[0, 120, 240]"``. When its values are numeric lists of one length, the numbers
  are also in a 2-D coordinate ``<name>_values`` (dimensions ``case`` and ``<name>_index``;
  :func:`parameter_values`).
* Coordinates ``run_file`` (path of the case's run file relative to the sweep folder, ``""``
  for a failed case), ``case_sha256`` (the hash that identifies the finished run) and
  ``status`` (``"ok"`` or ``"failed"``), and the data variable ``failure`` (the message).
* Attributes: CF ``Conventions``, ``title``, ``source``, ``history``, the sweep description as JSON
  (``sweep_json``) with its SHA-256, the base gear-set description with the sweep's run
  settings merged (``base_json``), the parameters (``parameters_json``) and the summary
  settings. No time stamp: the same sweep gives the same file whatever the scheduler.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from analysis.cf import cf_dataset
from gearvib import __version__
from gearvib.sweep.case import CaseOutcome
from gearvib.sweep.description import Sweep, SweepCase
from gearvib.sweep.keys import path_units, value_kind

__all__ = ["cf_name", "combine_summaries", "parameter_values", "parameter_variable"]


def cf_name(path: str, taken: set[str]) -> str:
    """A CF variable name for the key path ``path`` that is not in ``taken`` (added to it).

    Characters other than letters, digits and ``_`` become ``_``; a name that does not start
    with a letter gets ``p_`` in front; ``_2``, ``_3`` ... are appended to a taken name.
    """
    name = re.sub(r"[^A-Za-z0-9_]", "_", path)
    if not name[:1].isalpha():
        name = f"p_{name}"
    base, i = name, 2
    while name in taken:
        name, i = f"{base}_{i}", i + 1
    taken.add(name)
    return name


def parameter_variable(ds: xr.Dataset, parameter: dict) -> xr.DataArray:
    """The coordinate of a swept parameter (an entry of ``parameters_json``) in a sweep
    Dataset; files of earlier versions named it by its key path."""
    return ds[parameter.get("variable", parameter["path"])]


def parameter_values(ds: xr.Dataset, parameter: dict) -> xr.DataArray:
    """The 2-D numeric coordinate of a list-valued swept parameter (``has_values_coordinate``)."""
    return ds[parameter.get("values_variable", f"{parameter['path']}.values")]


def _labels_union(datasets: list[xr.Dataset], dim: str) -> list[Any]:
    seen: dict[Any, None] = {}
    for ds in datasets:
        if dim in ds.coords:
            for v in ds[dim].values.tolist():
                seen.setdefault(v, None)
    return list(seen)


def _fill_value(dtype: np.dtype) -> Any:
    return "" if dtype.kind in "US" else np.nan


def _parameter_coords(sweep: Sweep, cases: Sequence[SweepCase], taken: set[str]
                      ) -> tuple[dict, list[dict]]:
    coords: dict[str, xr.Variable] = {}
    info = []
    kinds = sweep.coordinate_kinds()
    for i, (p, kind) in enumerate(zip(sweep.parameters, kinds, strict=True)):
        units = p.units or path_units(p.path)
        long_name = p.long_name or f"swept parameter {p.path}"
        attrs: dict[str, Any] = {"long_name": long_name, "gearvib_parameter_path": p.path}
        vals = [c.values[i] for c in cases]
        if kind == "number":
            data = np.asarray(vals, dtype=float)
            attrs = {"units": units or "1", **attrs}
        elif kind == "bool":
            data = np.asarray(vals, dtype=np.int8)
            attrs = {"units": "1", **attrs, "comment": "1 = true, 0 = false"}
        else:
            data = np.asarray([c.labels[i] for c in cases], dtype=str)
            if kind == "label":
                attrs["comment"] = ("list or table value: its label, or its JSON when the sweep "
                                    "gives no labels")
        name = cf_name(p.path, taken)
        coords[name] = xr.Variable(("case",), data, attrs)
        lists = [v for v in vals if value_kind(v) == "list"]
        numeric = len(lists) == len(vals) and len({len(v) for v in lists}) == 1 and all(
            value_kind(x) == "number" for v in lists for x in v)
        entry: dict[str, Any] = {"variable": name}
        if numeric and vals:
            values_name = cf_name(f"{name}_values", taken)
            coords[values_name] = xr.Variable(
                ("case", cf_name(f"{name}_index", taken)), np.asarray(vals, dtype=float),
                {"units": units or "1", "long_name": f"{long_name} (elements)",
                 "gearvib_parameter_path": p.path})
            entry["values_variable"] = values_name
        info.append({**entry, "path": p.path, "kind": kind, "units": units or "",
                     "long_name": long_name, "labels": list(p.labels) if p.labels else None,
                     "values": list(p.values) if p.values is not None else None,
                     "distribution": p.distribution,
                     "distribution_parameters": {k: getattr(p, k) for k in
                                                 ("low", "high", "mean", "std")
                                                 if getattr(p, k) is not None},
                     "has_values_coordinate": bool(numeric)})
    return coords, info


def combine_summaries(sweep: Sweep, cases: Sequence[SweepCase],
                      outcomes: Sequence[CaseOutcome], run_files: Sequence[str]) -> xr.Dataset:
    """Stack the summaries of all cases along ``case`` (see the module docstring).

    Parameters
    ----------
    sweep : Sweep
        The sweep (parameters, summary settings, provenance).
    cases : sequence of SweepCase
        Its cases, in index order.
    outcomes : sequence of CaseOutcome
        One per case, in index order.
    run_files : sequence of str
        Run file of each case, relative to the sweep folder.

    Returns
    -------
    xarray.Dataset
    """
    n = len(cases)
    if len(outcomes) != n or len(run_files) != n:
        raise ValueError("one outcome and one run file per case are needed")
    ok = [o.summary is not None for o in outcomes]
    summaries = [o.summary for o in outcomes if o.summary is not None]
    dims: dict[str, list[Any]] = {}
    for ds in summaries:
        for d in ds.dims:
            if d not in dims:
                dims[str(d)] = _labels_union(summaries, str(d))
    coords: dict[str, xr.Variable] = {}
    for d, labels in dims.items():
        src = next(ds for ds in summaries if d in ds.coords)
        coords[d] = xr.Variable((d,), np.asarray(labels, dtype=src[d].dtype), src[d].attrs)
    data: dict[str, xr.Variable] = {}
    names: list[str] = []
    for ds in summaries:
        names.extend(str(v) for v in ds.data_vars if str(v) not in names)
    for name in names:
        src = next(ds for ds in summaries if name in ds.data_vars)
        var = src[name]
        shape = (n, *(len(dims[str(d)]) for d in var.dims))
        arr = np.full(shape, _fill_value(var.dtype), dtype=var.dtype if var.dtype.kind in "US"
                      else np.result_type(var.dtype, np.float64))
        if var.dtype.kind in "US":
            arr = arr.astype(object)
        j = 0
        for i, o in enumerate(outcomes):
            if o.summary is None:
                continue
            s = summaries[j]
            j += 1
            if name not in s.data_vars:
                continue
            v = s[name]
            idx = tuple(np.asarray([dims[str(d)].index(x) for x in s[d].values.tolist()])
                        for d in v.dims)
            where: tuple[Any, ...] = (i, *np.ix_(*idx))
            arr[where] = v.values
        if arr.dtype == object:
            arr = arr.astype(str)
        data[name] = xr.Variable(("case", *map(str, var.dims)), arr, dict(var.attrs))
    taken = {*dims, *data, "case", "run_file", "case_sha256", "status", "failure"}
    pcoords, info = _parameter_coords(sweep, cases, taken)
    coords.update(pcoords)
    coords["case"] = xr.Variable(("case",), np.arange(n, dtype=np.int64),
                                 {"units": "1", "long_name": "case number"})
    coords["run_file"] = xr.Variable(("case",), np.asarray(run_files, dtype=str), {
        "long_name": "run file of the case, relative to the sweep folder ('' if failed)"})
    coords["case_sha256"] = xr.Variable(("case",), np.asarray([c.sha256 for c in cases],
                                                              dtype=str),
                                        {"long_name": "SHA-256 of the case's description and "
                                                      "run settings"})
    coords["status"] = xr.Variable(("case",), np.asarray(["ok" if k else "failed" for k in ok],
                                                         dtype=str),
                                   {"long_name": "outcome of the case (ok or failed)"})
    data["failure"] = xr.Variable(("case",), np.asarray([o.message for o in outcomes],
                                                        dtype=str),
                                  {"long_name": "why the case failed ('' if it did not)"})
    sweep_json = json.dumps(sweep.to_dict(), sort_keys=True, default=str)
    attrs = {
        "Conventions": "CF-1.11",
        "title": sweep.title or f"gearvib sweep of {sweep.base}",
        "source": f"gearvib {__version__}",
        "gearvib_version": __version__,
        "references": "ISO 6336-1:2019, dynamic factor K_v, method A",
        "comment": "one case per run; summaries over the window given in summary_json; "
                   "definitions in docs/sweeps.md",
        "sweep_json": sweep_json,
        "sweep_sha256": hashlib.sha256(sweep_json.encode()).hexdigest(),
        "sweep_mode": sweep.mode,
        "sweep_base": sweep.base,
        "base_json": json.dumps(sweep.load_base()[0], sort_keys=True, default=str),
        "parameters_json": json.dumps(info, sort_keys=True, default=str),
        "summary_json": json.dumps(sweep.summary.to_dict(), sort_keys=True),
        "n_cases": np.int64(n),
        "n_failed": np.int64(n - sum(ok)),
    }
    ds = xr.Dataset(data, coords=coords, attrs=attrs)
    return cf_dataset(ds, title=str(attrs["title"]), producer="gearvib.sweep.run_sweep")
