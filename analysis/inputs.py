"""Inputs of the spectral and order-analysis functions: signals, channels, speed references.

One set of rules for every function of :mod:`analysis.spectrum`, :mod:`analysis.maps`,
:mod:`analysis.orders` and :mod:`analysis.resample`:

* **Signal** ``x``: a NumPy array or an :class:`xarray.DataArray`. A DataArray needs a
  ``time`` dimension with a uniform ``time`` coordinate in seconds (it gives ``fs``); every
  other dimension (typically ``channel``) is carried through to the result with its
  coordinate. A 1-D array is one channel. An array with more dimensions needs ``axis=`` (its
  time axis) unless the length of ``rpm``/``angle``/``time`` singles out one axis: a
  ``(samples, channels)`` array is never analysed along the wrong axis. The other axis of a
  2-D array becomes the ``channel`` dimension of the result. Samples must be finite and at
  most :data:`MAX_SAMPLE` in magnitude (the error names the channel and the time sample).
* **Sampling**: ``fs`` [Hz] or ``time`` [s] (uniform; they must agree when both are given).
  ``fs`` is a real number (a bool or a string is a :class:`TypeError`), > 0, with a finite
  record duration ``n / fs``.
* **Speed reference**: ``rpm`` [min-1] or ``angle`` [rad] per sample, exactly one of them
  for order analysis. A tacho's angle is more accurate than the rpm derived from it, so give
  the angle when you have it. For a Dataset or DataArray the reference can be named
  (``speed="input_speed"``, ``angle="input_angle"``) or is found by its attributes
  (:func:`find_reference`).
* **Standstill**: order tracking needs a turning shaft. Leading and trailing parts below
  ``min_rpm`` (default 2 % of the highest speed) are left out and the result says so
  (:func:`moving_range`); a speed <= 0 inside the record is an error.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.cf import elapsed_seconds
from analysis.checks import (
    BLOCK_SAMPLES,
    require_finite_blocks,
    require_instance,
    require_int,
    require_positive,
    require_real,
    uniform_rate,
)

__all__ = [
    "ANGLE_UNITS",
    "MAX_SAMPLE",
    "SPEED_UNITS",
    "Reference",
    "Signal",
    "channel_coords",
    "dataset_reference",
    "dataset_variable",
    "find_reference",
    "moving_range",
    "one_channel",
    "reference_input",
    "select_channel",
    "signal_input",
]

#: Speed units understood (factor to min-1); Hz and s-1 only for variables named as speeds.
SPEED_UNITS = {
    "min-1": 1.0,
    "rpm": 1.0,
    "1/min": 1.0,
    "min^-1": 1.0,
    "r/min": 1.0,
    "rev/min": 1.0,
    "rad s-1": 60.0 / (2 * np.pi),
    "rad/s": 60.0 / (2 * np.pi),
    "rad.s-1": 60.0 / (2 * np.pi),
}
_FREQUENCY_UNITS = {"hz": 60.0, "s-1": 60.0, "1/s": 60.0}
#: Angle units understood (factor to rad).
ANGLE_UNITS = {
    "rad": 1.0,
    "radian": 1.0,
    "radians": 1.0,
    "degree": np.pi / 180.0,
    "degrees": np.pi / 180.0,
    "deg": np.pi / 180.0,
}
_SPEED_WORDS = ("speed", "rpm", "revolution", "rotation", "rotational")
_MIN_RPM_FRACTION = 0.02
#: Largest magnitude of a sample of a signal: the powers (squares summed over a record) of
#: larger values overflow float64, and no physical measurement reaches it in any unit.
MAX_SAMPLE = 1e100  # default standstill threshold: 2 % of the highest speed


@dataclass
class Signal:
    """A checked signal with time along its last axis.

    Attributes
    ----------
    values : numpy.ndarray
        Samples, shape ``(*channels, time)`` (a view of the input when possible).
    fs : float
        Sample rate [Hz].
    t0 : float
        Time of the first sample [s].
    time : numpy.ndarray or None
        The time axis when one was given (used as is), else ``None`` (``t0 + k / fs``).
    dims : tuple of str
        Names of the leading (channel) dimensions.
    coords : dict
        Coordinates of the leading dimensions (may be empty).
    units, name : str
        Metadata of the signal.
    reference : Reference or None
        Speed reference found in the coordinates of a DataArray.
    """

    values: np.ndarray
    fs: float
    t0: float
    time: np.ndarray | None
    dims: tuple[str, ...]
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    units: str = "1"
    name: str = "x"
    reference: Reference | None = None

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.values.shape[-1])

    @property
    def lead(self) -> tuple[int, ...]:
        """Shape of the leading (channel) dimensions."""
        return tuple(self.values.shape[:-1])


@dataclass
class Reference:
    """Speed reference of a record: speed [min-1] or angle [rad] per sample.

    Attributes
    ----------
    kind : {"rpm", "angle"}
        Which one ``values`` holds.
    values : numpy.ndarray
        Speed [min-1] or angle [rad], one value per sample.
    label : str
        Where it came from (e.g. ``"input_angle [rad]"``), reported in results.
    """

    kind: str
    values: np.ndarray = field(repr=False)
    label: str = ""
    variable: str | None = None


def _is_dataarray(x: Any) -> bool:
    try:
        import xarray as xr
    except ImportError:  # pragma: no cover - xarray is a hard dependency
        return False
    return isinstance(x, xr.DataArray)


def _require_dataset(ds: Any) -> None:
    import xarray as xr

    require_instance(ds, xr.Dataset, "ds")


def _speed_factor(name: str, attrs: dict[str, Any]) -> float | None:
    """Factor to min-1 if a variable with these attributes is a shaft speed, else ``None``."""
    units = str(attrs.get("units", "")).strip()
    if units in SPEED_UNITS:
        return SPEED_UNITS[units]
    text = f"{name} {attrs.get('long_name', '')} {attrs.get('standard_name', '')}".lower()
    if units.lower() in _FREQUENCY_UNITS and any(w in text for w in _SPEED_WORDS):
        return _FREQUENCY_UNITS[units.lower()]
    return None


def _angle_factor(attrs: dict[str, Any]) -> float | None:
    return ANGLE_UNITS.get(str(attrs.get("units", "")).strip().lower())


def find_reference(obj: Any, speed: str | None = None, angle: str | None = None) -> Reference:
    """Speed reference of a Dataset or DataArray, by name or by its attributes.

    Parameters
    ----------
    obj : xarray.Dataset or xarray.DataArray
        Record with a ``time`` dimension (for a DataArray, its coordinates are searched).
    speed, angle : str, optional
        Name of the speed variable (units ``min-1``, ``rad s-1``, ``Hz`` ... converted to
        min-1) or of the angle variable (``rad`` or ``degree``, converted to rad). Give at
        most one.

    Returns
    -------
    Reference
        Without a name, the reference is found among the variables and coordinates that
        depend on ``time`` only: one whose ``units`` are an angle wins (more accurate);
        otherwise one whose units are a rotational speed (``min-1``, ``rpm``, ``rad s-1``;
        ``Hz`` or ``s-1`` only when its name or ``long_name`` says speed, rpm or rotation,
        so that e.g. a mesh frequency is not taken). Several candidates of the winning kind
        raise an error that lists them.
    """
    import xarray as xr

    require_instance(obj, (xr.Dataset, xr.DataArray), "obj")
    if speed is not None and angle is not None:
        raise ValueError("give speed= or angle=, not both")
    pool = dict(obj.coords.items())
    if hasattr(obj, "data_vars"):
        pool.update(obj.data_vars.items())
    for key, kind in ((speed, "rpm"), (angle, "angle")):
        if key is None:
            continue
        if key not in pool:
            names = sorted(str(k) for k, v in pool.items() if v.dims == ("time",) and k != "time")
            raise ValueError(
                f"{'speed' if kind == 'rpm' else 'angle'} = {key!r} is not a variable or "
                f"coordinate along time; candidates: {names}"
            )
        var = pool[key]
        if var.dims != ("time",):
            raise ValueError(f"{key!r} must depend on 'time' only; it has dims {var.dims}")
        if kind == "rpm":
            factor = _speed_factor(str(key), var.attrs)
            if factor is None:
                units = var.attrs.get("units", "")
                raise ValueError(
                    f"speed {key!r} has units {units!r}; admissible: {sorted(SPEED_UNITS)} "
                    "(or Hz / s-1 for a variable named as a speed)"
                )
        else:
            factor = _angle_factor(var.attrs)
            if factor is None:
                units = var.attrs.get("units", "")
                raise ValueError(
                    f"angle {key!r} has units {units!r}; admissible: {sorted(ANGLE_UNITS)}"
                )
        values = np.asarray(var.values)
        values = values if factor == 1.0 else values * factor
        return Reference(kind, values, f"{key} [{var.attrs.get('units', '')}]", str(key))
    angles, speeds = [], []
    for key, var in pool.items():
        if key == "time" or var.dims != ("time",):
            continue
        if _angle_factor(var.attrs) is not None:
            angles.append(str(key))
        elif _speed_factor(str(key), var.attrs) is not None:
            speeds.append(str(key))
    if len(angles) == 1:
        return find_reference(obj, angle=angles[0])
    if len(angles) > 1:
        raise ValueError(
            f"several angle references {angles}; choose one with angle=<name> (or speed=<name>)"
        )
    if len(speeds) == 1:
        return find_reference(obj, speed=speeds[0])
    if len(speeds) > 1:
        raise ValueError(f"several speed references {speeds}; choose one with speed=<name>")
    raise ValueError(
        "no speed or angle reference found: give speed=<name> (units min-1, rpm, rad s-1) or "
        "angle=<name> (units rad) of a variable or coordinate along time"
    )


def dataset_reference(ds: Any, speed: str | None, angle: str | None) -> dict[str, Any]:
    """``{"rpm": ds[name]}`` or ``{"angle": ds[name]}``: the speed reference of a Dataset,
    named or found by its attributes (:func:`find_reference`), as keyword arguments."""
    _require_dataset(ds)
    ref = find_reference(ds, speed=speed, angle=angle)
    return {ref.kind: ds[ref.variable]}


def dataset_variable(ds: Any, variable: str) -> Any:
    """``ds[variable]`` with the Dataset's coordinates along time, checked."""
    _require_dataset(ds)
    if not isinstance(variable, str):
        raise TypeError(f"variable must be a str (a variable name); got {type(variable).__name__}")
    if variable not in ds.data_vars and variable not in ds.coords:
        raise ValueError(f"variable = {variable!r} is not in the dataset ({list(ds.data_vars)})")
    da = ds[variable]
    if "time" not in da.dims:
        raise ValueError(f"{variable} has dims {da.dims}; it needs a 'time' dimension")
    if "time" not in ds.coords:
        raise ValueError("the dataset needs a 'time' coordinate in seconds")
    return da


def _time_axis(shape: tuple[int, ...], axis: int | None, lengths: list[int], where: str) -> int:
    if axis is not None:
        a = require_int(axis, "axis", -len(shape)) if axis < 0 else require_int(axis, "axis", 0)
        if not -len(shape) <= a < len(shape):
            raise ValueError(f"axis = {axis} is not admissible for {where} of shape {shape}")
        return a % len(shape)
    if len(shape) == 1:
        return 0
    for n in lengths:
        hits = [i for i, s in enumerate(shape) if s == n]
        if len(hits) == 1:
            return hits[0]
    raise ValueError(
        f"{where} has shape {shape}: give axis= (the time axis), e.g. axis=0 for a "
        "(samples, channels) array; it is never guessed"
    )


def signal_input(
    x: Any,
    fs: Any = None,
    *,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    lengths: tuple[int, ...] = (),
    where: str = "x",
) -> Signal:
    """Checked :class:`Signal` from the arguments of an analysis function (module docstring).

    ``lengths`` are the lengths of the references given with it (rpm, angle), which may
    single out the time axis of a multi-dimensional array.
    """
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = {}
    reference = None
    if _is_dataarray(x):
        if "time" not in x.dims:
            raise ValueError(f"{where}: DataArray needs a 'time' dimension; it has dims {x.dims}")
        if "time" not in x.coords:
            raise ValueError(f"{where}: DataArray needs a 'time' coordinate in seconds")
        if axis is not None:
            raise ValueError("axis= is for plain arrays; a DataArray has its 'time' dimension")
        t_raw = x["time"].values  # float seconds, or decoded datetimes: since the first
        fs_t = uniform_rate(t_raw, f"{where}.time")  # a decoded axis within its resolution
        t_coord = elapsed_seconds(t_raw)
        if fs is not None and abs(require_real(fs, "fs") - fs_t) > 1e-6 * fs_t:
            raise ValueError(
                f"sample-rate mismatch: fs = {fs!r} Hz but the time coordinate of {where} "
                f"gives {fs_t:.9g} Hz; omit fs or make them agree"
            )
        if time is not None:
            raise ValueError("time= is for plain arrays; a DataArray has its time coordinate")
        x = x.transpose(..., "time")
        dims = tuple(str(d) for d in x.dims[:-1])
        coords = {d: np.asarray(x[d].values) for d in dims if d in x.coords}
        units = units if units is not None else str(x.attrs.get("units", "1"))
        name = name if name is not None else (str(x.name) if x.name is not None else "x")
        try:
            reference = find_reference(x)
        except ValueError:
            reference = None
        arr = np.asarray(x.values)
        time_arr: np.ndarray | None = t_coord
        rate, t0 = fs_t, float(t_coord[0])
    else:
        arr = np.asarray(x)
        if np.iscomplexobj(arr) or not np.issubdtype(arr.dtype, np.number):
            raise ValueError(f"{where} must be a real numeric array; got dtype {arr.dtype}")
        if arr.ndim == 0:
            raise ValueError(f"{where} must have at least one dimension (time)")
        if arr.size == 0:
            raise ValueError(f"{where}: channel is empty (needs at least one sample)")
        t_len = [np.shape(time)[0]] if time is not None and np.ndim(time) == 1 else []
        ax = _time_axis(arr.shape, axis, [*lengths, *t_len], where)
        arr = np.moveaxis(arr, ax, -1)
        if arr.ndim == 2:
            dims = ("channel",)
        elif arr.ndim > 2:
            dims = tuple(f"dim_{i}" for i in range(arr.ndim - 1))
        time_arr = None
        if time is None:
            if fs is None:
                raise ValueError("fs (sample rate in Hz, > 0) or time (s) is required")
            rate = require_real(fs, "fs")
            if rate <= 0 or not np.isfinite(arr.shape[-1] / rate):
                raise ValueError(
                    f"fs = {fs!r} is not admissible: must be > 0 Hz with a finite record "
                    f"duration ({arr.shape[-1]} samples / fs)"
                )
            t0 = 0.0
        else:
            time_arr = np.asarray(time)
            if time_arr.ndim != 1 or time_arr.size != arr.shape[-1]:
                raise ValueError(
                    f"sample-count mismatch ({where}: {arr.shape[-1]}, time: {time_arr.size})"
                )
            rate = uniform_rate(time_arr, "time")
            if fs is not None and abs(require_real(fs, "fs") - rate) > 1e-6 * rate:
                raise ValueError(
                    f"sample-rate mismatch: fs = {fs!r} Hz but the time axis gives {rate:.9g} Hz"
                )
            t0 = float(time_arr[0])
    if np.iscomplexobj(arr) or not np.issubdtype(arr.dtype, np.number):
        raise ValueError(f"{where} must be a real numeric array; got dtype {arr.dtype}")
    require_finite_blocks(arr, name if name is not None else where, MAX_SAMPLE)
    return Signal(
        arr,
        rate,
        t0,
        time_arr,
        dims,
        coords,
        units if units is not None else "1",
        name if name is not None else "x",
        reference,
    )


def one_channel(sig: Signal, function: str) -> np.ndarray:
    """The samples of a one-channel :class:`Signal` as a 1-D array; raise for several
    channels (the functions that choose a band or an alarm per channel take one at a time)."""
    require_instance(sig, Signal, "sig")
    if int(np.prod(sig.lead, dtype=np.int64)) != 1:
        raise ValueError(
            f"{function} analyses one channel; x has {int(np.prod(sig.lead))} channels "
            f"(dims {sig.dims}, shape {sig.lead}): select one, e.g. x.sel(channel=...) or x[:, k]"
        )
    return sig.values.reshape(sig.n)


def _values_of(ref: Any, kind: str) -> tuple[np.ndarray, str]:
    """Array of a reference given as an array or a DataArray (units converted)."""
    if _is_dataarray(ref):
        attrs = ref.attrs
        if kind == "rpm":
            factor = _speed_factor(str(ref.name), attrs) if "units" in attrs else 1.0
        else:
            factor = _angle_factor(attrs) if "units" in attrs else 1.0
        if factor is None:
            raise ValueError(f"{kind} has units {attrs.get('units')!r}; cannot convert")
        values = np.asarray(ref.values)
        label = f"{ref.name} [{attrs.get('units', '')}]" if ref.name is not None else kind
        return (values if factor == 1.0 else values * factor), label
    return np.asarray(ref), kind


def reference_input(
    rpm: Any, angle: Any, n: int, *, required: bool, signal: Signal | None = None
) -> Reference | None:
    """Checked speed reference: exactly one of ``rpm``/``angle`` (or one found in ``signal``).

    The values must be 1-D, one per sample, and finite; their sign and monotony are checked
    where order tracking needs them (:func:`moving_range`).
    """
    if rpm is not None and angle is not None:
        raise ValueError("give rpm= (min-1) or angle= (rad), not both")
    if rpm is None and angle is None:
        if signal is not None and signal.reference is not None:
            ref = signal.reference
        elif required:
            raise ValueError(
                "a speed reference is required: rpm= (min-1 per sample) or angle= (rad per "
                "sample)"
            )
        else:
            return None
    else:
        kind = "rpm" if rpm is not None else "angle"
        values, label = _values_of(rpm if rpm is not None else angle, kind)
        ref = Reference(kind, values, label)
    v = ref.values
    if v.ndim != 1 or v.size != n:
        raise ValueError(
            f"sample-count mismatch (x: {n}, {ref.kind}: {v.size}); {ref.kind} must be 1-D, one "
            "value per sample of x"
        )
    if not np.issubdtype(v.dtype, np.number) or np.iscomplexobj(v):
        raise ValueError(f"{ref.kind} must be real numbers; got dtype {v.dtype}")
    require_finite_blocks(v, ref.kind)
    return ref


def _speed_blocks(ref: Reference, fs: float, a: int, b: int) -> np.ndarray:
    """Speed [min-1] of samples ``[a, b)`` (for an angle: its forward difference)."""
    if ref.kind == "rpm":
        return np.asarray(ref.values[a:b], dtype=float)
    th = np.asarray(ref.values[a : min(ref.values.size, b + 1)], dtype=float)
    d = np.diff(th) * (fs * 60.0 / (2.0 * np.pi))
    return d if b < ref.values.size else np.append(d, d[-1] if d.size else 0.0)


def moving_range(
    ref: Reference, fs: float, t0: float, min_rpm: float | None
) -> tuple[int, int, float, str]:
    """Samples ``[a, b)`` of the record without standstill at its ends, and a note.

    Leading and trailing samples slower than ``min_rpm`` (default 2 % of the highest speed)
    are left out; for an angle reference the speed is its forward difference. Works block
    by block (no array as long as the record).

    Returns
    -------
    a, b : int
        First and stop sample of the moving part.
    threshold : float
        Speed threshold used [min-1].
    note : str
        What was left out ("" when nothing was).

    Raises
    ------
    ValueError
        A negative speed (decreasing angle) anywhere, or no sample above the threshold.
    """
    require_instance(ref, Reference, "ref")
    require_positive(require_real(fs, "fs"), "fs")
    require_real(t0, "t0")
    n = ref.values.size
    top = 0.0
    for s in range(0, n, BLOCK_SAMPLES):
        v = _speed_blocks(ref, fs, s, min(n, s + BLOCK_SAMPLES))
        if v.size and float(v.min()) < 0:
            i = s + int(np.flatnonzero(v < 0)[0])
            what = (
                f"rpm[{i}] = {ref.values[i]:.6g}"
                if ref.kind == "rpm"
                else f"the angle decreases between samples {i} and {i + 1}"
            )
            raise ValueError(
                f"rpm must be > 0 for order tracking (rotation in one direction); {what}. "
                "Negate a reference of reverse rotation"
            )
        if v.size:
            top = max(top, float(v.max()))
    if min_rpm is None:
        thr = _MIN_RPM_FRACTION * top
    else:
        thr = float(min_rpm)
        if not np.isfinite(thr) or thr < 0:
            raise ValueError(f"min_rpm = {min_rpm!r} is not admissible: must be finite and >= 0")
    if not top > 0 or top < thr:
        raise ValueError(
            f"the shaft does not turn (highest speed {top:.6g} min-1, threshold {thr:.6g} min-1)"
        )
    a = 0
    for s in range(0, n, BLOCK_SAMPLES):
        v = _speed_blocks(ref, fs, s, min(n, s + BLOCK_SAMPLES))
        hit = np.flatnonzero(v >= thr) if thr > 0 else np.flatnonzero(v > 0)
        if hit.size:
            a = s + int(hit[0])
            break
    b = n
    for e in range(n, 0, -BLOCK_SAMPLES):
        s = max(0, e - BLOCK_SAMPLES)
        v = _speed_blocks(ref, fs, s, e)
        hit = np.flatnonzero(v >= thr) if thr > 0 else np.flatnonzero(v > 0)
        if hit.size:
            b = s + int(hit[-1]) + 1
            break
    if ref.kind == "angle" and b < n:
        b += 1  # the forward difference of sample b - 1 needs sample b
    parts = []
    if a > 0:
        parts.append(f"the first {a} samples (t < {t0 + a / fs:.6g} s)")
    if b < n:
        parts.append(f"the last {n - b} samples (t > {t0 + (b - 1) / fs:.6g} s)")
    note = ""
    if parts:
        note = (
            f"{' and '.join(parts)} were left out: the shaft turns slower than "
            f"{thr:.6g} min-1 there (standstill; set min_rpm= to change the threshold)"
        )
    return a, b, thr, note


def channel_coords(dims: tuple[str, ...], coords: dict[str, np.ndarray]) -> dict[str, Any]:
    """CF coordinates of the leading (channel) dimensions of a result."""
    out: dict[str, Any] = {}
    for d in dims:
        if d in coords:
            values = np.asarray(coords[d])
            attrs = {"long_name": "channel" if d == "channel" else str(d)}
            if values.dtype.kind in "iuf":
                attrs["units"] = "1"
            out[d] = (d, values, attrs)
    return out


def select_channel(
    values: np.ndarray, dims: tuple[str, ...], coords: dict[str, np.ndarray], key: Any
) -> tuple[np.ndarray, tuple[str, ...], dict[str, np.ndarray], str]:
    """One channel of a multi-channel result: values, remaining dims and coords, label.

    ``key`` is a label of the first leading dimension's coordinate, or an integer index.
    """
    require_instance(values, np.ndarray, "values")
    require_instance(dims, (tuple, list), "dims")
    require_instance(coords, Mapping, "coords")
    if values.ndim == 0:
        raise ValueError(f"values must have a channel axis; got shape {values.shape}")
    if not dims:
        raise ValueError("the result has a single channel; there is nothing to select")
    d = dims[0]
    labels = coords.get(d)
    if labels is not None and not isinstance(key, int | np.integer):
        hits = np.flatnonzero(np.asarray(labels) == key)
        if hits.size != 1:
            raise ValueError(f"channel = {key!r} is not one of {list(np.asarray(labels))}")
        i = int(hits[0])
    else:
        n = values.shape[0]
        if not isinstance(key, int | np.integer) or not -n <= key < n:
            raise ValueError(f"channel = {key!r} is not admissible: an index in [0, {n})")
        i = int(key) % n
    label = str(np.asarray(labels)[i]) if labels is not None else f"{d} {i}"
    rest = {k: v for k, v in coords.items() if k != d}
    return values[i], dims[1:], rest, label
