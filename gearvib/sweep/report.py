"""The sweep report: one figure per summary quantity against the swept parameters, and a page.

:func:`sweep_figures` builds matplotlib Figures from a combined sweep Dataset alone (``sweep.nc``),
:func:`build_sweep_report` writes them as PNG into ``DIR/figures/`` and a small HTML page
``DIR/sweep.html`` that links them (with the parameters, the definitions and the case table).

Which plot:

* one parameter: a line plot against it (one line per mesh; markers only for random samples);
* two parameters of a grid: a heat map (the largest value over the meshes);
* more parameters of a grid: small multiples, a heat map of the first two per combination of the
  others (at most :data:`MAX_PANELS`);
* a zip sweep: a line plot against the first parameter (or the case number);
* random samples: a scatter plot against each parameter (and each varying element of a
  list-valued one).

Quantities that have orders get one panel per order. Categorical parameters (strings, lists,
tables) are placed at equal spacing in the order of their values.
"""

from __future__ import annotations

import functools
import io
import json
import math
from dataclasses import dataclass
from html import escape
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from gearvib import __version__
from gearvib.io import atomic_write
from gearvib.sweep.combine import parameter_values, parameter_variable

__all__ = ["MAX_PANELS", "SweepFigure", "build_sweep_report", "sweep_figures"]

MAX_PANELS = 12
"""Most panels of one figure."""

QUANTITIES = ("dynamic_factor", "transmission_error_pp", "contact_loss_fraction",
              "back_contact_fraction", "floquet_growth_rate_max")
"""Summary variables plotted (when present), before order levels and sensor levels."""

_SCALE = {"m": (1e6, "µm"), "N": (1.0, "N"), "1": (1.0, "1"), "s-1": (1.0, "1/s")}


@dataclass(frozen=True)
class SweepFigure:
    """A figure of the report.

    Attributes
    ----------
    name : str
        File stem (the summary variable).
    title : str
        Caption.
    figure : matplotlib.figure.Figure
    """

    name: str
    title: str
    figure: Figure


def _png(fig: Figure) -> bytes:
    """PNG bytes without the ``Software`` metadata (the same figure gives the same bytes)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, metadata={"Software": None})
    return buf.getvalue()


def _params(ds: xr.Dataset) -> list[dict]:
    return json.loads(ds.attrs.get("parameters_json", "[]"))


def _axis(ds: xr.Dataset, p: dict) -> tuple[np.ndarray, list[str] | None, str]:
    """Positions along a parameter axis, tick labels for categories, axis label."""
    c = parameter_variable(ds, p)
    if p["kind"] == "number":
        factor, units = _SCALE.get(str(c.attrs.get("units", "")),
                                   (1.0, str(c.attrs.get("units", ""))))
        return c.values.astype(float) * factor, None, f"{p['path']} [{units}]"
    cats = list(dict.fromkeys(str(v) for v in c.values))
    return np.array([cats.index(str(v)) for v in c.values], dtype=float), cats, p["path"]


def _units(da: xr.DataArray) -> tuple[float, str]:
    u = str(da.attrs.get("units", "1"))
    return _SCALE.get(u, (1.0, u))


def _quantities(ds: xr.Dataset) -> list[str]:
    names = [q for q in QUANTITIES if q in ds.data_vars]
    for v in ds.data_vars:
        s = str(v)
        if s.endswith("_order_level") or s.endswith("_rms"):
            names.append(s)
    ok = ds["status"].values == "ok" if "status" in ds.coords else np.ones(ds.sizes["case"], bool)
    out = []
    for n in names:
        vals = ds[n].values[ok]
        if vals.dtype.kind == "f" and np.isfinite(vals).any():
            if n == "back_contact_fraction" and not np.any(vals > 0):
                continue
            out.append(n)
    return out


def _series(da: xr.DataArray) -> tuple[list[str], np.ndarray, list[Any], np.ndarray]:
    """Split ``da(case, ..., [order])``: series labels, values (series, case, panel)."""
    panel_dim = "order" if "order" in da.dims else None
    other = [d for d in da.dims if d not in ("case", panel_dim)]
    arr = da.transpose("case", *other, *([panel_dim] if panel_dim else [])).values
    n_case = arr.shape[0]
    n_panel = arr.shape[-1] if panel_dim else 1
    arr = arr.reshape(n_case, -1, n_panel)
    labels = [", ".join(str(da[d].values[i]) for d, i in zip(other, idx, strict=True))
              for idx in np.ndindex(*(da.sizes[d] for d in other))] or [""]
    panels = list(da["order"].values) if panel_dim else [None]
    return labels, np.moveaxis(arr, 1, 0), panels, np.asarray(other)


def _grid_shape(n: int) -> tuple[int, int]:
    cols = min(n, 3)
    return math.ceil(n / cols), cols


def _new_figure(n_panels: int) -> tuple[Figure, list]:
    rows, cols = _grid_shape(n_panels)
    fig = Figure(figsize=(4.2 * cols + 0.8, 3.3 * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel().tolist()
    for ax in axes[n_panels:]:
        ax.set_visible(False)
    return fig, axes[:n_panels]


def _set_categories(ax, which: str, cats: list[str] | None) -> None:
    if cats is None:
        return
    short = [c if len(c) <= 22 else c[:20] + "…" for c in cats]
    if which == "x":
        ax.set_xticks(range(len(cats)), short, rotation=20 if len(cats) > 3 else 0,
                      ha="right" if len(cats) > 3 else "center")
        ax.set_xlim(-0.5, len(cats) - 0.5)
    else:
        ax.set_yticks(range(len(cats)), short)


def _panel_title(panel: Any, da: xr.DataArray) -> str:
    if panel is None:
        return ""
    ref = str(da.attrs.get("reference", ""))
    return f"order {float(panel):g}" + (f" ({ref})" if ref.startswith("mesh") else "")


def _line_figure(ds, da, name, xpos, cats, xlabel, markers_only, ok) -> Figure:
    labels, vals, panels, _ = _series(da)
    scale, unit = _units(da)
    fig, axes = _new_figure(min(len(panels), MAX_PANELS))
    order = np.argsort(xpos[ok], kind="stable")
    x = xpos[ok][order]
    for ax, (k, panel) in zip(axes, enumerate(panels), strict=False):
        for s, lab in enumerate(labels):
            y = vals[s, ok, k][order] * scale
            if markers_only:
                ax.plot(x, y, "o", ms=4, label=lab or None)
            else:
                ax.plot(x, y, "o-", ms=4, lw=1.2, label=lab or None)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"{name} [{unit}]")
        ax.set_title(_panel_title(panel, da), fontsize=10)
        ax.grid(True, alpha=0.3)
        _set_categories(ax, "x", cats)
    if len(labels) > 1:
        axes[0].legend(fontsize=7, ncol=2 if len(labels) > 4 else 1)
    return fig


def _categories(ds: xr.Dataset, p: dict) -> tuple[np.ndarray, list[str], str]:
    """Cell index of every case along a heat-map axis, the cell labels and the axis label."""
    c = parameter_variable(ds, p)
    if p["kind"] == "number":
        vals = c.values.astype(float)
        cells = np.unique(vals)
        return (np.searchsorted(cells, vals), [f"{v:g}" for v in cells],
                f"{p['path']} [{c.attrs.get('units', '')}]")
    cats = list(dict.fromkeys(str(v) for v in c.values))
    return np.array([cats.index(str(v)) for v in c.values]), cats, p["path"]


def _heat_figure(ds, da, name, params, ok) -> Figure:
    """Heat maps of the first two parameters; panels: orders or the other parameters."""
    _, vals, panels, _ = _series(da)
    worst = np.nanmax(vals, axis=0) if vals.shape[0] > 1 else vals[0]
    xi, xc, xl = _categories(ds, params[0])
    yi, yc, yl = _categories(ds, params[1])
    rest = params[2:]
    combos: list[tuple] = [()]
    if rest:
        keys = [tuple(str(v) for v in row) for row in zip(*(parameter_variable(ds, p).values
                                                            for p in rest), strict=True)]
        combos = list(dict.fromkeys(keys))

    def shown(p: dict, v: str) -> str:
        if p["kind"] == "number":
            return f"{float(v):g} {parameter_variable(ds, p).attrs.get('units', '')}".strip()
        return v

    jobs = [(c, k) for c in combos for k in range(len(panels))][:MAX_PANELS]
    scale, unit = _units(da)
    fig, axes = _new_figure(len(jobs))
    finite = worst[ok][np.isfinite(worst[ok])]
    vmin, vmax = (float(finite.min()) * scale, float(finite.max()) * scale) if finite.size \
        else (0.0, 1.0)
    mesh = None
    for ax, (combo, k) in zip(axes, jobs, strict=True):
        img = np.full((len(yc), len(xc)), np.nan)
        for i in np.flatnonzero(ok):
            if rest and tuple(str(parameter_variable(ds, p).values[i]) for p in rest) != combo:
                continue
            img[yi[i], xi[i]] = worst[i, k] * scale
        mesh = ax.pcolormesh(np.arange(len(xc) + 1) - 0.5, np.arange(len(yc) + 1) - 0.5, img,
                             cmap="viridis", vmin=vmin, vmax=vmax, shading="flat")
        if img.size <= 64:
            for (r, c), v in np.ndenumerate(img):
                if np.isfinite(v):
                    ax.text(c, r, f"{v:.4g}", ha="center", va="center", fontsize=8,
                            color="w" if v < 0.5 * (vmin + vmax) else "k")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        title = [f"{p['path']} = {shown(p, v)}" for p, v in zip(rest, combo, strict=True)]
        if panels[k] is not None:
            title.append(_panel_title(panels[k], da))
        ax.set_title("\n".join(title), fontsize=9)
        _set_categories(ax, "x", xc)
        _set_categories(ax, "y", yc)
    if mesh is not None:
        fig.colorbar(mesh, ax=axes, label=f"{name} [{unit}]", shrink=0.9)
    if "mesh" in da.dims:
        fig.suptitle(f"{name}: largest value over the meshes", fontsize=10)
    return fig


def _write_bytes(data: bytes, path: Path) -> int:
    return path.write_bytes(data)


def _scatter_figure(ds, da, name, params, ok) -> Figure:
    _, vals, panels, _ = _series(da)
    worst = np.nanmax(vals, axis=0) if vals.shape[0] > 1 else vals[0]
    axes_spec: list[tuple[np.ndarray, list[str] | None, str]] = []
    for p in params:
        if p.get("has_values_coordinate") and p.get("distribution"):
            el = parameter_values(ds, p).values
            factor, unit = _SCALE.get(p["units"] or "1", (1.0, p["units"] or "1"))
            for j in range(el.shape[1]):
                if np.ptp(el[ok, j]) > 0:
                    axes_spec.append((el[:, j] * factor, None, f"{p['path']}[{j}] [{unit}]"))
        else:
            axes_spec.append(_axis(ds, p))
    axes_spec = axes_spec[:MAX_PANELS]
    # colour the points by the first categorical parameter with a few values
    groups: list[tuple[str, np.ndarray]] = [("", np.ones(ok.size, dtype=bool))]
    for p in params:
        if p["kind"] != "number":
            labels = [str(v) for v in parameter_variable(ds, p).values]
            cats = list(dict.fromkeys(labels))
            if 2 <= len(cats) <= 8:
                groups = [(f"{p['path']} = {c}", np.array([lab == c for lab in labels]))
                          for c in cats]
                break
    scale, unit = _units(da)
    fig, axes = _new_figure(len(axes_spec))
    over = " (largest over the meshes)" if "mesh" in da.dims else ""
    for ax, (x, ticks, label) in zip(axes, axes_spec, strict=True):
        for k, panel in enumerate(panels[:8]):
            for glabel, member in groups:
                sel = ok & member
                text = " ".join(t for t in (_panel_title(panel, da), glabel) if t)
                ax.plot(x[sel], worst[sel, k] * scale, "o", ms=3.5, alpha=0.75,
                        label=text or None)
        ax.set_xlabel(label)
        ax.set_ylabel(f"{name} [{unit}]")
        ax.grid(True, alpha=0.3)
        _set_categories(ax, "x", ticks)
    if panels[0] is not None or len(groups) > 1:
        axes[0].legend(fontsize=7)
    fig.suptitle(f"{name}{over}", fontsize=10)
    return fig


def sweep_figures(ds: xr.Dataset) -> list[SweepFigure]:
    """The report's figures of a combined sweep Dataset (see the module docstring)."""
    params = _params(ds)
    mode = str(ds.attrs.get("sweep_mode", "grid"))
    ok = ds["status"].values == "ok" if "status" in ds.coords else np.ones(ds.sizes["case"], bool)
    out = []
    for name in _quantities(ds):
        da = ds[name]
        long_name = str(da.attrs.get("long_name", name))
        if mode == "random":
            fig = _scatter_figure(ds, da, name, params, ok)
        elif len(params) == 1 or mode == "zip":
            x, cats, label = _axis(ds, params[0])
            fig = _line_figure(ds, da, name, x, cats, label, False, ok)
        else:
            fig = _heat_figure(ds, da, name, params, ok)
        out.append(SweepFigure(name, long_name, fig))
    return out


def _table(header: list[str], rows: list[list[str]], caption: str) -> str:
    head = "".join(f"<th>{escape(h)}</th>" for h in header)
    body = "\n".join("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in r) + "</tr>"
                     for r in rows)
    return (f"<table><caption>{escape(caption)}</caption><thead><tr>{head}</tr></thead>"
            f"<tbody>{body}</tbody></table>")


_CSS = """body{font-family:system-ui,Helvetica,Arial,sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.4}h1{font-size:1.5em;border-bottom:2px solid #444}
h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #aaa}table{border-collapse:collapse;
margin:.6em 0 1.2em;font-size:.85em}caption{text-align:left;font-weight:600}th,td{border:1px
solid #bbb;padding:2px 6px;text-align:left}th{background:#eee}figure{margin:1em 0}figure img{
max-width:100%;border:1px solid #ddd}figcaption{font-size:.85em;color:#444}"""

MAX_TABLE_ROWS = 200
"""Most cases listed in the page's case table."""


def _values_text(p: dict) -> str:
    if p["labels"]:
        return ", ".join(p["labels"])
    if p["values"] is not None:
        return ", ".join(json.dumps(v) if not isinstance(v, str) else v for v in p["values"])
    args = ", ".join(f"{k} = {v}" for k, v in p.get("distribution_parameters", {}).items())
    return f"{p['distribution']} distribution ({args})"


def _window_text(summary: dict) -> str:
    parts = []
    if "window_s" in summary:
        parts.append("t = {:g} .. {:g} s".format(*summary["window_s"]))
    if "window_rpm" in summary:
        parts.append("input speed {:g} .. {:g} min-1".format(*summary["window_rpm"]))
    return " and ".join(parts) or "the whole run"


def _cell(value: Any) -> str:
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    return str(value)


def build_sweep_report(ds: xr.Dataset, out_dir: str | Path) -> Path:
    """Write ``figures/<quantity>.png`` and ``sweep.html`` into ``out_dir``.

    Parameters
    ----------
    ds : xarray.Dataset
        A combined sweep Dataset (:func:`gearvib.sweep.run_sweep`, or ``sweep.nc`` read back).
    out_dir : path-like
        The sweep folder (must exist).

    Returns
    -------
    Path
        The HTML page.
    """
    out = Path(out_dir)
    figdir = out / "figures"
    figdir.mkdir(exist_ok=True)
    params = _params(ds)
    figs = sweep_figures(ds)
    parts = []
    for f in figs:
        png = _png(f.figure)
        atomic_write(figdir / f"{f.name}.png", functools.partial(_write_bytes, png))
        parts.append(f'<figure id="{escape(f.name)}"><img src="figures/{escape(f.name)}.png" '
                     f'alt="{escape(f.title)}"><figcaption>{escape(f.name)}: '
                     f"{escape(f.title)}</figcaption></figure>")
    n = int(ds.sizes["case"])
    n_failed = int(np.sum(ds["status"].values != "ok"))
    prow = [[p["path"], p["kind"], p["units"] or "", _values_text(p)] for p in params]
    kv = ds.get("dynamic_factor")
    rows = []
    for i in range(min(n, MAX_TABLE_ROWS)):
        kvmax = float(np.nanmax(kv.values[i])) if kv is not None and \
            np.isfinite(kv.values[i]).any() else float("nan")
        rows.append([str(i), *(_cell(parameter_variable(ds, p).values[i]) for p in params),
                     str(ds["status"].values[i]), f"{kvmax:.4g}",
                     str(ds["run_file"].values[i]), str(ds["failure"].values[i])])
    summary = json.loads(ds.attrs.get("summary_json", "{}"))
    text = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="generator" content="gearvib {__version__}">
<title>{escape(str(ds.attrs.get('title', 'gearvib sweep')))}</title><style>{_CSS}</style></head>
<body><h1>{escape(str(ds.attrs.get('title', 'gearvib sweep')))}</h1>
<p>Base gear set <code>{escape(str(ds.attrs.get('sweep_base', '')))}</code>,
mode <code>{escape(str(ds.attrs.get('sweep_mode', '')))}</code>: {n} cases, {n_failed} failed.
Data: <a href="sweep.nc">sweep.nc</a> (dimension <code>case</code>, one coordinate per swept
key path). Summary window: {escape(_window_text(summary))}; settings:
<code>{escape(json.dumps(summary))}</code>.</p>
{_table(["key path", "kind", "units", "values"], prow, "Swept parameters")}
<h2>Definitions</h2>
<p><b>dynamic_factor</b> K<sub>v</sub> = maximum normal force of the loaded flank over the
window / its static force in the static equilibrium at mean mesh stiffness under the same
torque (ISO 6336-1, method A). <b>transmission_error_pp</b>: peak-to-peak mesh deflection along
the line of action. <b>contact_loss_fraction</b>: time fraction with the loaded flank out of
contact. Heat maps show the largest value over the meshes. Details: docs/sweeps.md.</p>
<h2>Figures</h2>
{''.join(parts) or '<p>(no summary with finite values)</p>'}
<h2>Cases</h2>
{_table(["case", *(p["path"] for p in params), "status", "max K_v", "run file", "failure"],
        rows, f"Cases (first {min(n, MAX_TABLE_ROWS)} of {n})")}
<footer><p>Generated by gearvib {__version__}.</p></footer></body></html>
"""
    page = out / "sweep.html"
    atomic_write(page, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return page
