"""Gear-set, run and mode tables of a simulated report.

:func:`parameter_rows` lists the gear-set description (geometry, meshes, bodies, planets), the
degrees of freedom, the mesh frequencies per input speed and the run; :func:`mode_rows` the
natural frequencies with their type, multiplicity and dominant mesh.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from gearvib.modal import ModalResult
from gearvib.model import AssembledModel
from gearvib.report.case_groups import MeshGroup
from gearvib.report.case_run import run_description
from gearvib.report.wording import count

__all__ = ["mode_rows", "parameter_rows"]


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return ", ".join(_fmt(x) for x in v)
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_fmt(x)}" for k, x in v.items()) + "}"
    return str(v)


def _tables(cfg: dict, key: str, prefix: str = "") -> list[tuple[str, dict]]:
    """Every ``key`` table of a description, also inside stages (``stage1.geometry``)."""
    out = []
    if isinstance(cfg.get(key), dict):
        out.append((prefix, cfg[key]))
    for k, v in cfg.items():
        if isinstance(v, dict) and k not in (key, "simulation") and (
                k.startswith("stage") or isinstance(v.get(key), dict)):
            out += _tables(v, key, f"{prefix}{k}.")
    return out


def _geometry_rows(gs: dict, model: AssembledModel | None) -> list[tuple[str, str]]:
    rows: list[tuple[str, str]] = []
    for prefix, geo in _tables(gs, "geometry"):
        text = ", ".join(f"{k} = {_fmt(v)}" for k, v in geo.items())
        rows.append((f"geometry{' [' + prefix.rstrip('.') + ']' if prefix else ''}", text))
    for key in ("body", "mesh", "coupling", "shaft"):  # [[body]], [[mesh]], ... lists
        for i, item in enumerate(gs.get(key, []) if isinstance(gs.get(key), list) else []):
            if isinstance(item, dict):
                label = str(item.get("name", "")) or (f"{i + 1}" if key == "shaft" else "")
                rows.append((f"{key} {label}".strip(),
                             ", ".join(f"{k} = {_fmt(v)}" for k, v in item.items()
                                       if k != "name")))
    handled = {"geometry", "operation", "meshes", "bodies", "simulation", "body", "mesh",
               "coupling"}
    for key, table in gs.items():  # e.g. the [shaft] between two stages
        if isinstance(table, dict) and key not in handled and not key.startswith("stage"):
            rows.append((key, ", ".join(f"{k} = {_fmt(v)}" for k, v in table.items())))
    if model is None:
        return rows
    # every mesh type: tooth numbers, centre distance, contact ratio and the phases
    kinds: dict[tuple, list[dict]] = {}
    for m in model.meta.get("meshes", []):
        if not isinstance(m, dict):
            continue
        kind = (str(m.get("gear1", "")), m.get("z1"), m.get("z2"),
                round(float(m.get("centre_distance") or 0.0), 9),
                round(float(m.get("contact_ratio") or 0.0), 6))
        kinds.setdefault(kind, []).append(m)
    for (_gear1, z1, z2, a, eps), ms in kinds.items():
        names = [str(m["name"]) for m in ms]
        label = names[0] if len(names) == 1 else f"{names[0]} … {names[-1]}"
        phases = ", ".join(f"{float(m.get('phase_lag', 0.0)):.4f}" for m in ms)
        parts = []
        if z1 is not None and z2 is not None:
            parts.append(f"z = {z1}/{z2}")
        if a:
            parts.append(f"centre distance {1e3 * a:.2f} mm")
        if eps:
            parts.append(f"contact ratio {eps:.3f}")
        parts.append(f"phase lag {phases} cycles")
        rows.append((f"meshes {label} ({len(ms)})", ", ".join(parts)))
    carriers: dict[str, list[tuple[str, float]]] = {}
    for p in model.meta.get("planets", []):
        carriers.setdefault(str(p.get("carrier", "carrier")), []).append(
            (str(p["name"]), float(p.get("angle_deg", 0.0))))
    for carrier, ps in carriers.items():
        rows.append((f"planets on {carrier}", ", ".join(f"{n} {a:.2f}°" for n, a in ps)))
    return rows


def parameter_rows(ds: xr.Dataset, caller: dict, model: AssembledModel | None, run: dict,
                   groups: Sequence[MeshGroup]) -> list[tuple[str, str]]:
    """Rows of the gear-set and run table: description, geometry, meshes, bodies, planets.

    Parameters
    ----------
    ds : xarray.Dataset
        The run (``fs_out``, speeds).
    caller : dict
        The caller's configuration (:func:`gearvib.report.case_run.caller_config`).
    model : AssembledModel or None
        The rebuilt gear set (mesh types, phases, planets, degrees of freedom).
    run : dict
        Run settings (:func:`gearvib.report.case_run.run_settings`).
    groups : sequence of MeshGroup
        Mesh-frequency groups.

    Returns
    -------
    list of (str, str)
        ``(parameter, value)`` rows.
    """
    rows: list[tuple[str, str]] = []
    gs = caller.get("gearset", {}) if isinstance(caller.get("gearset"), dict) else {}
    if gs:
        rows.append(("gear set", f"{gs.get('name', '')} ({gs.get('type', 'simple')})"))
        if gs.get("title"):
            rows.append(("description", str(gs["title"])))
    rows += _geometry_rows(gs, model)
    if gs:
        for prefix, op in _tables(gs, "operation"):
            rows.append((f"operation{' [' + prefix.rstrip('.') + ']' if prefix else ''}",
                         ", ".join(f"{k} {v}" for k, v in op.items())))
        for prefix, meshes in _tables(gs, "meshes"):
            for mname, m in sorted(meshes.items()):
                if not isinstance(m, dict):
                    continue
                st = m.get("stiffness", {})
                text = ", ".join(f"{k} = {_fmt(v)}" for k, v in st.items()) \
                    if isinstance(st, dict) else _fmt(st)
                extra = ", ".join(f"{k} = {v:g}" for k, v in m.items()
                                  if k in ("backlash", "damping_ratio", "damping"))
                rows.append((f"{prefix}{mname} meshes", text + (f"; {extra}" if extra else "")))
        for prefix, bodies in _tables(gs, "bodies"):
            for bname, b in sorted(bodies.items()):
                if not isinstance(b, dict):
                    continue
                sup = b.get("support", {})
                sup_text = ", ".join(f"{k} {_fmt(v)}" for k, v in sup.items()) \
                    if isinstance(sup, dict) else "-"
                rows.append((f"body {prefix}{bname}",
                             f"m = {b.get('mass')} kg, J = {b.get('inertia')} kg m²; "
                             f"support: {sup_text or '-'}"))
    if model is not None:
        rows.append(("degrees of freedom",
                     f"{model.n_dof} ({count(model.n_mesh, 'mesh', 'meshes')}, "
                     f"{count(len(model.bearing_names), 'elastic bearing')})"))
    for g in groups:
        what = "" if len(groups) == 1 else f", {g.name}"
        rows.append((f"mesh frequency per input speed{what}",
                     f"{g.frequency_per_rpm:.6g} Hz per min⁻¹ ({60 * g.frequency_per_rpm:.4g} "
                     f"mesh cycles per input revolution; meshes {', '.join(g.meshes)})"))
    rows.append(("run", run_description(run, ds)))
    rows.append(("output sample rate", f"{float(ds.attrs.get('fs_out', 0.0)):g} Hz"))
    return rows


def mode_rows(modal: ModalResult | None, ds: xr.Dataset) -> list[tuple]:
    """Rows of the mode table: ``(mode, f [Hz], kind, multiplicity, dominant mesh)``.

    Parameters
    ----------
    modal : ModalResult or None
        Modes of the mean system; without them the natural frequencies stored in the run are
        listed as ``f2, f3, ...`` with their type ``(not stored)``.
    ds : xarray.Dataset
        The run (``natural_frequency``).

    Returns
    -------
    list of tuple
    """
    if modal is None:
        f = np.asarray(ds["natural_frequency"].values, dtype=float)
        return [(i + 2, f"{fi:.1f}", "(not stored)", "", "") for i, fi in enumerate(f)]
    rows = []
    for i, (f, k, m) in enumerate(zip(modal.frequencies_hz, modal.kinds, modal.multiplicity,
                                      strict=True)):
        dom = ""
        if modal.mesh_energy.shape[1] and modal.mesh_energy[i].max() > 1e-6:
            j = int(np.argmax(modal.mesh_energy[i]))
            dom = f"{modal.mesh_names[j]} ({100 * modal.mesh_energy[i, j]:.0f} %)"
        rows.append((i + 1, f"{f:.1f}", k, str(m), dom))
    return rows

