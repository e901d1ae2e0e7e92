"""Summary of one run: the small Dataset a sweep keeps per case.

:func:`summarise_run` maps a run-up Dataset (as :meth:`gearvib.simulate.RunUpResult.to_dataset`
writes it) and its gear set to scalars and short vectors: the tooth-load summaries of
:mod:`gearvib.sweep.loadfactor` per mesh, the maximum level of chosen orders (order cuts of
:func:`analysis.orders.order_cuts`), the levels of virtual sensors when a run has any, and
Floquet growth rates over speed (:func:`gearvib.stability.stability_over_speed`) when asked.
What is summarised is set by :class:`SummarySettings` (the ``[summary]`` table of a sweep).

Virtual sensors
---------------
Every variable of the run whose ``gearvib_quantity`` attribute is
:data:`VIRTUAL_SENSOR_QUANTITY` (the ``[[sensor]]`` tables' accelerations) is summarised as
``<name>_rms`` (rms over the window) and, when orders are asked, as order levels, without any
setting. Runs without such variables give none of these summaries.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from analysis.checks import require_instance
from analysis.orders import order_cuts
from gearvib.checks import check_items, check_real
from gearvib.checks import short as _short
from gearvib.config import ConfigError, check_keys
from gearvib.model import AssembledModel
from gearvib.simulate import (
    Conditions,
    MotorDriven,
    SpeedRamp,
    SpeedTable,
    TorqueDriven,
    static_tooth_forces,
)
from gearvib.stability import stability_over_speed
from gearvib.sweep.loadfactor import mesh_loads

__all__ = [
    "ORDER_SIGNAL_VARIABLES",
    "PASSBAND_FRACTION",
    "VIRTUAL_SENSOR_QUANTITY",
    "OrderSignal",
    "SummarySettings",
    "summarise_run",
]

VIRTUAL_SENSOR_QUANTITY = "virtual_sensor"
"""``gearvib_quantity`` attribute that marks a virtual-sensor signal in a run (hook)."""

PASSBAND_FRACTION = 0.3
"""Highest frequency of a run's output, as a fraction of ``fs_out``, where the decimation
filter is flat (< 0.001 dB); order bands reaching beyond it are not summarised (NaN)."""

ORDER_SIGNAL_VARIABLES = ("normal_force", "mesh_stiffness", "mesh_deflection", "bearing_force",
                          "displacement", "speed", "drive_torque")
"""Run variables whose order levels a sweep can summarise."""

MAX_ORDERS = 64
"""Most orders per summary."""

_KEYS = {"window_s", "window_rpm", "orders", "order_reference", "order_signals",
         "order_resolution", "floquet_speed_rpm", "floquet_points"}
_SIGNAL = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?:\[(.*)\])?$")
_MIN_SPEED_FRACTION = 0.01


RUN_VARIABLES = ("time", "normal_force", "mesh_deflection", "input_speed", "mesh_frequency")
"""Variables of a run that :func:`summarise_run` reads."""

@dataclass(frozen=True)
class OrderSignal:
    """A run variable, optionally reduced by label selections, whose order levels are kept.

    Written ``"normal_force[flank=left]"`` or ``"drive_torque"`` in a sweep description.

    Attributes
    ----------
    variable : str
        Name of the run variable.
    select : tuple of (str, str)
        ``(dimension, label)`` pairs.
    """

    variable: str
    select: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.variable, str) or self.variable not in ORDER_SIGNAL_VARIABLES:
            raise ConfigError(f"OrderSignal.variable = {_short(self.variable)} is not "
                              f"admissible (admissible: {', '.join(ORDER_SIGNAL_VARIABLES)})")
        if not (isinstance(self.select, tuple) and all(
                isinstance(p, tuple) and len(p) == 2 and all(isinstance(x, str) for x in p)
                for p in self.select)):
            raise ConfigError(f"OrderSignal.select must be (dimension, label) pairs of "
                              f"strings, got {_short(self.select)}")

    @classmethod
    def parse(cls, text: Any, where: str) -> OrderSignal:
        """Parse ``"variable[dim=label, ...]"``."""
        m = _SIGNAL.match(text.strip()) if isinstance(text, str) else None
        if m is None:
            raise ConfigError(f"{where} = {_short(text)}: expected a run variable such as "
                              "'drive_torque' or 'normal_force[flank=left]'")
        var, sel_text = m.group(1), m.group(2)
        if var not in ORDER_SIGNAL_VARIABLES:
            raise ConfigError(f"{where}: unknown run variable {var!r} (admissible: "
                              f"{', '.join(ORDER_SIGNAL_VARIABLES)})")
        select = []
        if sel_text is not None:
            for item in sel_text.split(","):
                dim, eq, label = item.partition("=")
                if not eq or not dim.strip() or not label.strip():
                    raise ConfigError(f"{where} = {_short(text)}: a selection is "
                                      f"'dimension=label', got {_short(item.strip())}")
                select.append((dim.strip(), label.strip()))
        return cls(var, tuple(select))

    def __str__(self) -> str:
        if not self.select:
            return self.variable
        return f"{self.variable}[{','.join(f'{d}={lab}' for d, lab in self.select)}]"


def _pair(value: Any, where: str, *, minimum: float = 0.0) -> tuple[float, float]:
    if (not isinstance(value, list | tuple) or len(value) != 2
            or any(isinstance(v, bool) or not isinstance(v, int | float) for v in value)):
        raise ConfigError(f"{where} must be [start, end] (two numbers), got {_short(value)}")
    lo = check_real(value[0], f"{where}[0]", error=ConfigError)
    hi = check_real(value[1], f"{where}[1]", error=ConfigError)
    if lo < minimum or not hi > lo:
        raise ConfigError(f"{where} = {_short(value)}; admissible: {minimum:g} <= start < end, "
                          "finite")
    return lo, hi


@dataclass(frozen=True)
class SummarySettings:
    """What :func:`summarise_run` computes (the ``[summary]`` table of a sweep).

    Attributes
    ----------
    window_s : (float, float) or None
        Time window [s] of every summary (default: the whole run).
    window_rpm : (float, float) or None
        Input-speed window [min^-1]; combined with ``window_s`` (both must hold).
    orders : tuple of float
        Orders whose maximum level over the window is kept (none by default).
    order_reference : str
        ``"mesh"`` (orders of the mesh frequency; a set with several mesh frequencies needs
        ``"mesh:<mesh name>"``) or a member name: orders per revolution of that member
        (``"sun"``, ``"carrier"``, ...).
    order_signals : tuple of OrderSignal
        Signals analysed for ``orders`` (default the left-flank tooth force of every mesh).
    order_resolution : float
        Frame resolution of the order cuts [orders]; a frame spans ``1 / order_resolution``
        revolutions of the reference (Hann window, band of 4 lines).
    floquet_speed_rpm : (float, float) or None
        Input-speed range [min^-1] of the Floquet growth rates (not computed when None).
    floquet_points : int
        Speeds of that range.
    """

    window_s: tuple[float, float] | None = None
    window_rpm: tuple[float, float] | None = None
    orders: tuple[float, ...] = ()
    order_reference: str = "mesh"
    order_signals: tuple[OrderSignal, ...] = (OrderSignal("normal_force", (("flank", "left"),)),)
    order_resolution: float = 0.1
    floquet_speed_rpm: tuple[float, float] | None = None
    floquet_points: int = 40

    def __post_init__(self) -> None:
        w = "SummarySettings"
        table: dict[str, Any] = {k: getattr(self, k) for k in (
            "window_s", "window_rpm", "floquet_speed_rpm") if getattr(self, k) is not None}
        if not (isinstance(self.orders, tuple | list) and not self.orders):
            table["orders"] = list(self.orders) if isinstance(self.orders, tuple) else self.orders
        for k in ("order_reference", "order_resolution", "floquet_points"):
            table[k] = getattr(self, k)
        for k, v in _checked_summary(table, w).items():
            object.__setattr__(self, k, v)
        if isinstance(self.orders, list):
            object.__setattr__(self, "orders", tuple(self.orders))
        signals = check_items(self.order_signals, OrderSignal, f"{w}.order_signals",
                              error=ConfigError)
        if not signals:
            raise ConfigError(f"{w}.order_signals must not be empty")
        object.__setattr__(self, "order_signals", signals)

    @classmethod
    def from_dict(cls, table: Mapping, where: str = "[summary]") -> SummarySettings:
        """Checked settings from a ``[summary]`` table (unknown keys name the admissible)."""
        if not isinstance(table, Mapping):
            raise ConfigError(f"{where} must be a table, got {type(table).__name__}")
        check_keys(dict(table), _KEYS, where)
        kw = _checked_summary(table, where)
        if "order_signals" in table:
            sig = table["order_signals"]
            if not isinstance(sig, list) or not sig:
                raise ConfigError(f"{where}.order_signals must be a non-empty list such as "
                                  "['normal_force[flank=left]', 'drive_torque']")
            parsed = tuple(OrderSignal.parse(s, f"{where}.order_signals[{i}]")
                           for i, s in enumerate(sig))
            names = [p.variable for p in parsed]
            dup = sorted({n for n in names if names.count(n) > 1})
            if dup:
                raise ConfigError(f"{where}.order_signals lists {dup[0]!r} twice (one entry per "
                                  "variable; its other dimensions are kept)")
            kw["order_signals"] = parsed
        return cls(**kw)

    def to_dict(self) -> dict[str, Any]:
        """The settings as a TOML/JSON-like dict (round-trips through :meth:`from_dict`)."""
        d = asdict(self)
        d["order_signals"] = [str(s) for s in self.order_signals]
        d["orders"] = list(self.orders)
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in d.items()
                if v is not None}


def _checked_summary(table: Mapping, where: str) -> dict[str, Any]:
    """The ``[summary]`` values of ``table`` but ``order_signals``, checked."""
    kw: dict[str, Any] = {}
    if "window_s" in table:
        kw["window_s"] = _pair(table["window_s"], f"{where}.window_s")
    if "window_rpm" in table:
        kw["window_rpm"] = _pair(table["window_rpm"], f"{where}.window_rpm")
    if "orders" in table:
        o = table["orders"]
        if (not isinstance(o, list) or not o
                or any(isinstance(v, bool) or not isinstance(v, int | float) for v in o)
                or any(not (abs(v) < 1e300 and math.isfinite(v) and v > 0) for v in o)):
            raise ConfigError(f"{where}.orders must be a non-empty list of orders > 0, "
                              f"got {_short(o)}")
        if len(o) > MAX_ORDERS:
            raise ConfigError(f"{where}.orders lists {len(o)} orders; admissible: at most "
                              f"{MAX_ORDERS}")
        if len(set(o)) != len(o):
            raise ConfigError(f"{where}.orders lists an order twice: {_short(o)}")
        kw["orders"] = tuple(float(v) for v in o)
    if "order_reference" in table:
        ref = table["order_reference"]
        if not isinstance(ref, str) or not ref:
            raise ConfigError(f"{where}.order_reference must be 'mesh' or a member name")
        kw["order_reference"] = ref
    if "order_resolution" in table:
        r = table["order_resolution"]
        if isinstance(r, bool) or not isinstance(r, int | float) or not 0 < r < 1e300:
            raise ConfigError(f"{where}.order_resolution = {_short(r)}; admissible: a finite "
                              "number > 0 (orders)")
        kw["order_resolution"] = float(r)
    if "floquet_speed_rpm" in table:
        lo, hi = _pair(table["floquet_speed_rpm"], f"{where}.floquet_speed_rpm")
        if not lo > 0:
            raise ConfigError(f"{where}.floquet_speed_rpm: speeds must be > 0 min-1")
        kw["floquet_speed_rpm"] = (lo, hi)
    if "floquet_points" in table:
        p = table["floquet_points"]
        if isinstance(p, bool) or not isinstance(p, int) or not 2 <= p <= 2000:
            raise ConfigError(f"{where}.floquet_points = {_short(p)}; admissible: an integer "
                              "2..2000")
        kw["floquet_points"] = p
    return kw


@dataclass
class _Vars:
    data: dict[str, xr.Variable] = field(default_factory=dict)

    def add(self, name: str, dims: tuple[str, ...], values: Any, units: str | None,
            long_name: str, **attrs: Any) -> None:
        a = {"long_name": long_name, **attrs}
        if units is not None:
            a = {"units": units, **a}
        self.data[name] = xr.Variable(dims, np.asarray(values), a)


def _window_mask(ds: xr.Dataset, s: SummarySettings) -> np.ndarray:
    t = ds["time"].values
    keep = np.ones(t.size, dtype=bool)
    if s.window_s is not None:
        keep &= (t >= s.window_s[0] - 1e-12) & (t <= s.window_s[1] + 1e-12)
    if s.window_rpm is not None:
        rpm = ds["input_speed"].values
        keep &= (rpm >= s.window_rpm[0]) & (rpm <= s.window_rpm[1])
    if not keep.any():
        raise ValueError(f"the summary window (window_s = {s.window_s}, window_rpm = "
                         f"{s.window_rpm}) holds no output sample of the run "
                         f"(t = {t[0]:g} .. {t[-1]:g} s, input speed "
                         f"{ds['input_speed'].values.min():g} .. "
                         f"{ds['input_speed'].values.max():g} min-1)")
    return keep


def _reference_rpm(ds: xr.Dataset, model: AssembledModel, reference: str) -> np.ndarray:
    """Speed [min^-1] whose orders are counted: a mesh frequency x 60, or a member's speed."""
    if reference == "mesh" or reference.startswith("mesh:"):
        mf = ds["mesh_frequency"]
        names = [str(v) for v in ds["mesh"].values]
        if reference != "mesh" and reference[5:] not in names:
            raise ValueError(f"order_reference = {reference!r}: no mesh {reference[5:]!r} "
                             f"(meshes: {', '.join(names)})")
        if "mesh" not in mf.dims:  # one mesh frequency for the whole set
            return mf.values * 60.0
        if reference != "mesh":
            return mf.sel(mesh=reference[5:]).values * 60.0
        rows = mf.transpose("mesh", "time").values
        finite = [r for r in rows if np.isfinite(r).all()]
        if not finite:
            raise ValueError("order_reference = 'mesh': no mesh of this gear set has a mesh "
                             "frequency (tooth numbers)")
        if any(not np.allclose(r, finite[0], rtol=1e-9, atol=0.0) for r in finite[1:]):
            raise ValueError("order_reference = 'mesh': the meshes of this gear set have "
                             "different mesh frequencies; give order_reference = "
                             f"'mesh:<mesh name>' (meshes: {', '.join(names)})")
        return finite[0] * 60.0
    ratios = model.kinematic_ratios
    if reference not in ratios:
        raise ValueError(f"order_reference = {reference!r} is not a member of the gear set "
                         f"(admissible: 'mesh', 'mesh:<mesh name>', "
                         f"{', '.join(repr(k) for k in sorted(ratios))})")
    return np.abs(ds["input_speed"].values * float(ratios[reference]))


def _order_levels(out: _Vars, name: str, da: xr.DataArray, ds: xr.Dataset, span: slice,
                  ref_rpm: np.ndarray, s: SummarySettings, label: str) -> None:
    """Maximum rms level of every order over the window, and the input speed where it is."""
    fs = float(ds.attrs["fs_out"])
    t = ds["time"].values[span]
    rpm = ref_rpm[span]
    inp = ds["input_speed"].values[span]
    ok = rpm >= _MIN_SPEED_FRACTION * rpm.max() if rpm.size and rpm.max() > 0 else None
    other = [str(d) for d in da.dims if d != "time"]
    orders = np.asarray(s.orders)
    shape = (*(da.sizes[d] for d in other), orders.size)
    level = np.full(shape, np.nan)
    speed = np.full(shape, np.nan)
    if ok is not None and ok.any():
        first, last = int(np.argmax(ok)), int(ok.size - np.argmax(ok[::-1]))
        seg = slice(first, last)
        max_order = 1.25 * float(orders.max())
        spr = max(8, 2 * math.ceil(1.6 * max_order))
        vals = da.transpose(*other, "time").values[..., span][..., seg]
        units = str(da.attrs.get("units", "1"))
        for idx in np.ndindex(*vals.shape[:-1]):
            x = vals[idx]
            try:
                cut = order_cuts(x, None, rpm[seg], orders, time=t[seg], window="hann",
                                 resolution=s.order_resolution, samples_per_rev=spr,
                                 max_order=max_order, units=units, name=name)
            except ValueError as exc:  # too short a window for one frame, etc.
                if "above the highest analysed order" in str(exc):
                    continue  # a window too short to resolve the orders: levels stay NaN
                raise ValueError(f"order levels of {label}: {exc}") from exc
            v = cut.values.copy()
            top = (orders[:, None] + 0.5 * cut.bandwidth) * cut.rpm[None, :] / 60.0
            v[top > PASSBAND_FRACTION * fs] = np.nan
            for k in range(orders.size):
                row = v[k]
                if np.isfinite(row).any():
                    j = int(np.nanargmax(row))
                    level[(*idx, k)] = row[j]
                    speed[(*idx, k)] = np.interp(cut.time[j], t[seg], inp[seg])
    dims = (*other, "order")
    units = str(da.attrs.get("units", "1"))
    out.add(f"{name}_order_level", dims, level, units,
            f"maximum rms level of the order of {label} over the window",
            reference=s.order_reference, order_resolution=s.order_resolution,
            method="order cut (analysis.orders.order_cuts, Hann, band of 4 lines); NaN where "
                   f"the band reaches beyond {PASSBAND_FRACTION:g} fs_out")
    out.add(f"{name}_order_level_speed", dims, speed, "min-1",
            f"input speed (revolutions per minute) at the maximum order level of {label}")


def summarise_run(ds: xr.Dataset, model: AssembledModel, conditions: Conditions,
                  settings: SummarySettings | None = None, *,
                  gyroscopic: bool = False) -> xr.Dataset:
    """Summarise one run (see the module docstring and ``docs/sweeps.md``).

    Parameters
    ----------
    ds : xarray.Dataset
        The run (:meth:`gearvib.simulate.RunUpResult.to_dataset` or a run file).
    model : AssembledModel
        Its gear set.
    conditions : SpeedRamp, SpeedTable or TorqueDriven
        Its operating conditions (for the static tooth force).
    settings : SummarySettings, optional
        What to summarise (default: the tooth-load summaries only).
    gyroscopic : bool
        Whether the run included the gyroscopic terms.

    Returns
    -------
    xarray.Dataset
        Dimensions ``mesh`` (and ``order``, ``floquet_speed`` and the dimensions of the order
        signals when asked); every variable with ``units`` and ``long_name``.

    Raises
    ------
    ValueError
        The window holds no sample, an order signal's selection names an unknown label, or
        ``order_reference`` is not a member.
    """
    require_instance(ds, xr.Dataset, "ds")
    missing = [v for v in RUN_VARIABLES if v not in ds.variables]
    if missing:
        raise ValueError(f"ds is not a gearvib run: variable {missing[0]!r} is missing")
    require_instance(model, AssembledModel, "model")
    if not isinstance(conditions, SpeedRamp | SpeedTable | TorqueDriven | MotorDriven):
        raise TypeError(f"conditions must be SpeedRamp, SpeedTable, TorqueDriven or "
                        f"MotorDriven; got {type(conditions).__name__}")
    if settings is not None:
        require_instance(settings, SummarySettings, "settings")
    if not isinstance(gyroscopic, bool):
        raise TypeError(f"gyroscopic must be a bool; got {type(gyroscopic).__name__}")
    s = settings or SummarySettings()
    keep = _window_mask(ds, s)
    idx = np.flatnonzero(keep)
    span = slice(int(idx[0]), int(idx[-1]) + 1)
    static = static_tooth_forces(model, conditions, gyroscopic=gyroscopic)
    loads = mesh_loads(ds["normal_force"].transpose("mesh", "flank", "time").values[..., keep],
                       ds["mesh_deflection"].transpose("mesh", "time").values[..., keep],
                       np.asarray(model.mesh_backlash, dtype=float), static)
    out = _Vars()
    m = ("mesh",)
    out.add("dynamic_factor", m, loads.dynamic_factor, "1",
            "dynamic factor K_v (maximum dynamic / static tooth force of the loaded flank)",
            definition="ISO 6336-1 method A: max over the window of the loaded flank's normal "
                       "force / its static force at mean mesh stiffness under the same torque")
    out.add("max_tooth_force", m, loads.max_force, "N",
            "maximum normal tooth force of the loaded flank over the window")
    out.add("static_tooth_force", m, loads.static_force, "N",
            "static normal tooth force of the loaded flank (mean mesh stiffness, same torque)")
    out.add("transmission_error_pp", m, loads.transmission_error_pp, "m",
            "peak-to-peak dynamic transmission error (mesh deflection along the line of action)")
    out.add("contact_loss_fraction", m, loads.contact_loss_fraction, "1",
            "fraction of the window with the loaded flank out of contact")
    out.add("back_contact_fraction", m, loads.back_contact_fraction, "1",
            "fraction of the window with the back flank in contact")
    out.add("loaded_flank", m, loads.loaded_flank.astype(str), None,
            "flank carrying the static load")
    coords: dict[str, xr.Variable] = {
        "mesh": xr.Variable(m, np.asarray(ds["mesh"].values, dtype=str),
                            {"long_name": "tooth contact (mesh)"}),
    }
    signals: list[tuple[str, xr.DataArray, str]] = []
    if s.orders:
        for sig in s.order_signals:
            da = ds[sig.variable]
            for dim, lab in sig.select:
                if dim not in da.dims:
                    raise ValueError(f"order signal {sig}: {sig.variable} has no dimension "
                                     f"{dim!r} (dimensions: {', '.join(map(str, da.dims))})")
                labels = [str(v) for v in da[dim].values]
                if lab not in labels:
                    raise ValueError(f"order signal {sig}: no {dim} {lab!r} in this run "
                                     f"(admissible: {', '.join(labels)})")
                da = da.isel({dim: labels.index(lab)})
            signals.append((sig.variable, da, str(sig)))
    sensors = [str(n) for n, v in ds.data_vars.items()
               if v.attrs.get("gearvib_quantity") == VIRTUAL_SENSOR_QUANTITY and "time" in v.dims]
    for name in sensors:
        da = ds[name]
        other = [str(d) for d in da.dims if d != "time"]
        x = da.transpose(*other, "time").values[..., keep]
        out.add(f"{name}_rms", tuple(other), np.sqrt(np.mean(x * x, axis=-1)),
                str(da.attrs.get("units", "1")), f"rms of the virtual sensor {name} over the "
                "window")
        for d in other:  # the sensor names label the rms values, with or without orders
            if d in ds.coords and d not in coords:
                coords[str(d)] = ds[d].variable.copy()
        if s.orders:
            signals.append((name, da, name))
    if s.orders:
        ref_rpm = _reference_rpm(ds, model, s.order_reference)
        for name, da, label in signals:
            _order_levels(out, name, da, ds, span, ref_rpm, s, label)
            for axis_dim in da.dims:
                if axis_dim != "time" and axis_dim in ds.coords and axis_dim not in coords:
                    coords[str(axis_dim)] = ds[axis_dim].variable.copy()
        if s.order_reference.startswith("mesh"):
            what = "mesh orders" + (f" of {s.order_reference[5:]}"
                                    if s.order_reference != "mesh" else "")
        else:
            what = f"orders of the {s.order_reference} revolution"
        coords["order"] = xr.Variable(("order",), np.asarray(s.orders, dtype=float),
                                      {"units": "1", "long_name": what})
    if s.floquet_speed_rpm is not None:
        speeds = np.linspace(*s.floquet_speed_rpm, s.floquet_points)
        coupling = getattr(conditions, "coupling", None)
        chart = stability_over_speed(model, speeds, coupling=coupling, refine=False)
        fs = ("floquet_speed",)
        coords["floquet_speed"] = xr.Variable(fs, speeds, {
            "units": "min-1", "long_name": "input speed (revolutions per minute) of the Floquet "
            "analysis"})
        out.add("floquet_growth_rate", fs, np.asarray(chart.growth_rate, dtype=float), "s-1",
                "Floquet growth rate ln(max|multiplier|) / mesh period (> 0: unstable)")
        out.add("floquet_growth_rate_max", (), float(np.max(chart.growth_rate)), "s-1",
                "largest Floquet growth rate over the speed range")
    return xr.Dataset(out.data, coords=coords)
