"""A measurement: vibration channels with the speed of a reference shaft, from any source.

:func:`load_measurement` turns what an engineer brings -- a file in any format
:mod:`analysis.readers` reads (UFF 58, TDMS, MAT, WAV, CSV, netCDF) or a simulated run-up
Dataset with virtual sensors (``sensor_acceleration(sensor, time)`` and ``tacho(time)``, see
``docs/faults-sensors.md``) -- into one :class:`Measurement`: the channels on a ``time``
coordinate in seconds, the reference-shaft speed [min-1] (and angle [rad], when known) on the
same coordinate, a sentence saying how the speed was obtained, and the provenance. The report,
the comparison with a simulation and the diagnosis all start from it.

Speed reference, first match wins:

1. the options: ``tacho=`` (a pulse channel, ``pulses_per_rev=``; default the channel's
   ``pulses_per_rev`` attribute, else 1), ``speed=`` (a channel in min-1, rpm, rad s-1, or Hz
   when named as a speed), ``angle=`` (a channel in rad or degree), ``rpm=`` (a constant speed
   the user states, e.g. from the test log, for a record without a speed channel);
2. a channel named ``tacho`` (pulse train, :func:`analysis.speed.from_tacho`);
3. a channel named ``speed`` or ``rpm``;
4. a single channel whose units are an angle or a rotational speed
   (:func:`analysis.inputs.find_reference`).

When none is found a :class:`ValueError` names the options and lists the channels.

A simulated run loaded with ``forces=True`` also offers its force and transmission-error
channels (:data:`RUN_CHANNELS`): ``normal_force:MESH`` (left minus right flank [N]),
``mesh_deflection:MESH`` (dynamic transmission error [m]) and ``bearing_force:BEARING`` [N];
such a run needs no virtual sensor, and without a tacho its speed reference is the run's own
input angle (``input_angle`` [rad]), or with ``angle="rotation:MEMBER"`` the stored rotation of
another member.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from analysis.cf import cf_dataset, elapsed_seconds, labels_from_cf
from analysis.checks import require_finite_blocks, require_instance, shown, uniform_rate
from analysis.inputs import ANGLE_UNITS, find_reference
from analysis.measurement_options import (
    apply_calibration,
    check_fs,
    check_rate,
    reader_options,
    scalar_speed,
)
from analysis.readers import FORMATS, ReaderError, read
from analysis.readers.cdf3 import check_cdf3, is_cdf3
from analysis.readers.integrity import require_memory
from analysis.readers.ncimage import file_image, load_image, open_image
from analysis.speed import SpeedReference, from_angle, from_rpm, from_tacho

__all__ = [
    "MIN_SAMPLES",
    "RUN_CHANNELS",
    "Measurement",
    "load_measurement",
    "reference_channel",
    "tacho_reference",
]

MIN_SAMPLES = 64
"""Fewest samples of a record that order analysis can use."""

MAX_PULSES_PER_REV = 10_000
"""Largest ``pulses_per_rev`` accepted (as the simulator's tacho)."""

MAX_RPM = 1e7
"""Largest constant speed ``rpm=`` accepted [min-1]."""

_REFERENCE_NAMES = {"tacho": "tacho", "speed": "speed", "rpm": "speed"}
_RUN_MARKER = "sensor_acceleration"
_RUN_FORCE = "normal_force"
_RUN_ANGLE = "input_angle"

RUN_CHANNELS = {
    "normal_force": ("mesh", "net normal tooth force of mesh {} (left minus right flank, "
                     "along the left flank's line of action)"),
    "mesh_deflection": ("mesh", "mesh deflection of {} along the line of action (dynamic "
                        "transmission error)"),
    "bearing_force": ("bearing", "bearing force {}"),
}
"""Force and transmission-error channels of a simulated run (``load_measurement(...,
forces=True)``): run variable -> (its dimension, long name); a channel is named
``VARIABLE:LABEL``, e.g. ``normal_force:ring-planet1`` or ``bearing_force:ring.x``."""


@dataclass(frozen=True)
class Measurement:
    """Vibration channels with the speed of their reference shaft.

    Attributes
    ----------
    signals : xarray.Dataset
        Every channel of the source along ``time`` [s] (``units`` and ``long_name`` on each),
        the tacho or speed channel included.
    speed_rpm : xarray.DataArray
        Reference-shaft speed [min-1] on the same ``time`` coordinate (positive).
    reference : str
        How the speed was obtained, e.g. ``"tacho channel 'tacho', 60 pulses/rev"``.
    source : dict
        Provenance: ``file``, ``format``, ``reader``, ``channels``, ``vibration_channels``,
        ``reference_channel`` (``None`` for a stated constant speed), ``kind``
        (``"file"``, ``"dataset"`` or ``"simulation"``) and, for a simulated run, its
        ``title`` and ``config_json``.
    angle : xarray.DataArray or None
        Reference-shaft angle [rad] from a tacho or angle channel (more accurate than the
        speed for order tracking); ``None`` for a speed channel or a stated speed.
    accuracy : dict
        Estimated accuracy of the speed reference (:class:`analysis.speed.SpeedAccuracy`).
    """

    signals: xr.Dataset
    speed_rpm: xr.DataArray
    reference: str
    source: dict
    angle: xr.DataArray | None = None
    accuracy: dict = field(default_factory=dict)

    @property
    def vibration_channels(self) -> tuple[str, ...]:
        """Channel names that are not the speed reference (tacho, speed, angle)."""
        return tuple(self.source.get("vibration_channels", ()))

    @property
    def time(self) -> np.ndarray:
        """Time [s]."""
        return np.asarray(self.signals["time"].values, dtype=float)

    @property
    def fs(self) -> float:
        """Sample rate [Hz]."""
        return float(self.signals.attrs.get("sample_rate_hz", 1.0 / np.median(np.diff(self.time))))

    @property
    def name(self) -> str:
        """Short name of the measurement (the file stem, else the title)."""
        f = self.source.get("file")
        return Path(str(f)).stem if f else str(self.source.get("title", "measurement"))

    def channel(self, name: str | None = None) -> xr.DataArray:
        """One channel along ``time``.

        Parameters
        ----------
        name : str, optional
            Channel name; default the first vibration channel (not the tacho or speed).

        Raises
        ------
        ValueError
            Unknown name (the channels are listed), or no vibration channel at all.
        """
        if name is None:
            if not self.vibration_channels:
                raise ValueError(
                    "the measurement has no vibration channel (only the speed reference "
                    f"{self.source.get('reference_channel')!r}); channels: "
                    f"{list(self.signals.data_vars)}"
                )
            name = self.vibration_channels[0]
        if name not in self.signals.data_vars:
            raise ValueError(
                f"channel = {shown(name)} is not a channel of the measurement; channels: "
                f"{list(self.signals.data_vars)}"
            )
        return self.signals[name]

    def to_dataset(self) -> xr.Dataset:
        """The channels plus ``reference_speed`` [min-1] (and ``reference_angle`` [rad]), with
        the reference and the provenance as global attributes (CF, netCDF-safe)."""
        ds = self.signals.copy()
        ds["reference_speed"] = self.speed_rpm.rename(None).assign_attrs(
            units="min-1", long_name=f"reference shaft speed ({self.reference})"
        )
        if self.angle is not None:
            ds["reference_angle"] = self.angle.rename(None).assign_attrs(
                units="rad", long_name=f"reference shaft angle ({self.reference})"
            )
        src = {k: v for k, v in self.source.items() if k != "config_json"}
        ds.attrs.update(
            speed_reference=self.reference,
            measurement_source=json.dumps(src, sort_keys=True, default=str),
        )
        for k, v in self.accuracy.items():
            ds.attrs[f"speed_{k}"] = v
        inputs = {k: src[k] for k in ("file", "format", "reader", "reference_channel")
                  if src.get(k)}
        return cf_dataset(ds, title=str(ds.attrs.get("title", "") or self.name),
                          producer="analysis.measurement.load_measurement", inputs=inputs)


# ---------------------------------------------------------------------------------------------
# sources
# ---------------------------------------------------------------------------------------------


def _is_run(ds: xr.Dataset) -> bool:
    return _RUN_MARKER in ds.variables


def _is_run_without_sensor(ds: xr.Dataset) -> bool:
    return _RUN_MARKER not in ds.variables and _RUN_FORCE in ds.variables


def _read_file(path: Path, options: dict | None, fs: float | None = None,
               time_column: Any = None) -> tuple[xr.Dataset, dict]:
    """The file's Dataset (common layout, or a gearvib run) and its provenance; ``fs`` and
    ``time_column`` as stated by the user (:mod:`analysis.measurement_options`)."""
    if not path.exists():
        raise FileNotFoundError(f"measurement file not found: {path}")
    if path.is_dir():
        raise ValueError(f"measurement {str(path)!r} is a directory; give a file")
    ext = path.suffix.lower()
    opts, compare_rate = reader_options(ext, options, fs, time_column)
    image = _netcdf_run_image(path) if ext in FORMATS["netcdf"][1] else None
    if image is not None:
        if time_column is not None or options:
            raise ValueError(f"{path} is a simulated run: reader options and time_column do "
                             "not apply")
        try:  # from the image, as every netCDF read here: see analysis.readers.ncimage
            ds = labels_from_cf(load_image(path, image, decode_times=False,
                                           decode_timedelta=False))
        except (OSError, ValueError, RuntimeError) as exc:
            raise ReaderError(f"{path}: not a readable netCDF file ({exc})") from None
        if fs is not None:
            check_rate(ds, fs, str(path))
        return ds, {"file": str(path), "format": "netcdf (gearvib run)",
                    "reader": "xarray.open_dataset"}
    if ext in FORMATS["csv"][1] and not opts:
        opts = {"time_column": "time"}  # the layout write_csv writes: "time [s]" first
        try:
            ds = read(path, **opts)
        except ValueError as exc:
            raise ValueError(f"{exc} (a CSV file needs its time column named 'time', or give "
                             "fs= (--fs HZ) or time_column= (--time-column NAME))") from None
    else:
        ds = read(path, **opts)
    if compare_rate and fs is not None:  # compare_rate is only True for a given fs
        check_rate(ds, fs, str(path))
    fmt = str(ds.attrs.get("source_format", ext.lstrip(".")))
    reader = next((f"analysis.readers.{fn.__name__}" for name, (fn, exts) in FORMATS.items()
                   if ext in exts), "analysis.readers.read")
    return ds, {"file": str(path), "format": fmt, "reader": reader}


def _netcdf_run_image(path: Path) -> bytes | None:
    """The bytes of a simulated run's netCDF file (``None``: not a gearvib run).

    Only the header is parsed (netCDF4, after the netCDF-3 header walk): xarray would load the
    index coordinates while opening, whatever size a corrupt header claims. A run's declared
    data must fit into memory (twice: the load and its copy).
    """
    if is_cdf3(path):
        check_cdf3(path)
    try:
        image = file_image(path)
        with open_image(path, image) as nc:
            if _RUN_MARKER not in nc.variables and _RUN_FORCE not in nc.variables:
                return None
            declared = sum(math.prod(int(n) for n in v.shape)
                           * max(getattr(v.dtype, "itemsize", 8), 1)
                           for v in nc.variables.values())
    except OSError as exc:
        raise ReaderError(f"{path}: not a readable netCDF file ({exc})") from None
    require_memory(2 * declared, path, f"the run's variables ({declared} bytes declared)")
    return image


def _time_seconds(ds: xr.Dataset, where: str) -> np.ndarray:
    if "time" not in ds.coords:
        raise ValueError(f"{where} has no 'time' coordinate; a measurement needs one in seconds")
    raw = np.asarray(ds["time"].values)
    t = np.asarray(elapsed_seconds(raw), dtype=float)
    if t.ndim != 1 or t.size < MIN_SAMPLES:
        raise ValueError(
            f"{where} has {t.size} samples; a measurement needs at least {MIN_SAMPLES}"
        )
    uniform_rate(raw, f"{where}: time")  # a decoded (datetime) axis within its resolution
    return t


def _channels_of_run(ds: xr.Dataset, t: np.ndarray, forces: bool = False
                     ) -> tuple[xr.Dataset, dict]:
    """Channels of a simulated run: one per virtual sensor, its tacho and, with ``forces``,
    its force and transmission-error channels (the default one first) and, without a tacho,
    its input angle."""
    variables: dict[str, Any] = {}
    names: list[str] = []
    if _RUN_MARKER in ds.variables:
        acc = ds[_RUN_MARKER]
        if "sensor" not in acc.dims or acc.dims[-1] != "time" or acc.ndim != 2:
            raise ValueError(f"{_RUN_MARKER} has dims {acc.dims}; expected (sensor, time)")
        names = ([str(s) for s in ds["sensor"].values] if "sensor" in ds.coords
                 else [f"sensor{i}" for i in range(acc.sizes["sensor"])])
        for i, n in enumerate(names):
            key = n if n not in _REFERENCE_NAMES and n not in variables else f"sensor_{n}"
            attrs: dict[str, Any] = {
                "units": str(acc.attrs.get("units", "m s-2")),
                "long_name": f"virtual accelerometer {n!r} (simulated housing acceleration)",
                "source_channel": f"{_RUN_MARKER}[sensor={n}]"}
            if "sensor_angle" in ds.variables:
                attrs["sensor_angle_deg"] = float(np.asarray(ds["sensor_angle"].values)[i])
            variables[key] = ("time", np.asarray(acc.isel(sensor=i).values, dtype=float),
                              attrs)
    has_tacho = "tacho" in ds.variables and ds["tacho"].dims == ("time",)
    if has_tacho:
        variables["tacho"] = ("time", np.asarray(ds["tacho"].values, dtype=float),
                              {k: v for k, v in ds["tacho"].attrs.items()
                               if isinstance(v, str | int | float | np.number)})
    if forces:
        variables.update(_force_channels(ds))
        if not has_tacho and _RUN_ANGLE in ds.variables and ds[_RUN_ANGLE].dims == ("time",):
            variables[_RUN_ANGLE] = ("time", np.asarray(ds[_RUN_ANGLE].values, dtype=float),
                                     {"units": "rad", "long_name": "input angle "
                                      f"({_input_member(ds)} shaft, drive side)"})
            rot = ds["rotation"] if "rotation" in ds.variables else None
            if rot is not None and rot.dims == ("member", "time") and "member" in ds.coords:
                for i, member in enumerate(str(v) for v in ds["member"].values):
                    variables[f"rotation:{member}"] = (
                        "time", np.asarray(rot.isel(member=i).values, dtype=float),
                        {"units": "rad", "long_name": f"rotation angle of the {member}"})
    signals = xr.Dataset(variables, coords={"time": ("time", t, {"units": "s",
                                                                  "long_name": "time",
                                                                  "standard_name": "time"})})
    fs = float(ds.attrs.get("fs_out", 1.0 / np.median(np.diff(t))))
    signals.attrs.update(Conventions="CF-1.11", sample_rate_hz=fs,
                         title=str(ds.attrs.get("title", "gearvib run")),
                         source_format="gearvib run")
    extra = {"kind": "simulation", "title": str(ds.attrs.get("title", "")),
             "config_json": str(ds.attrs.get("config_json", "")),
             "sensors": names}
    return signals, extra


def _input_member(ds: xr.Dataset) -> str:
    """The run's input member from its stored description ("input" when not stored)."""
    try:
        cfg = json.loads(str(ds.attrs.get("config_json", "")) or "{}")
        member = cfg["model"]["gearset"]["operation"]["input"]
    except (ValueError, KeyError, TypeError):
        return "input"
    return member if isinstance(member, str) and member else "input"


def _force_channels(ds: xr.Dataset) -> dict[str, Any]:
    """The run's :data:`RUN_CHANNELS`, the default one first: the first ring-planet mesh force
    (the ring carries the mesh forces into the housing; one mesh holds every mesh harmonic,
    while the sum over the planets, and so a ring bearing force, loses those that the planet
    phasing cancels), else the first mesh force."""
    out: dict[str, Any] = {}
    for var, (dim, long_name) in RUN_CHANNELS.items():
        if var not in ds.variables or dim not in ds[var].dims or ds[var].dims[-1] != "time":
            continue
        da = ds[var]
        if var == _RUN_FORCE:
            if "flank" in da.dims and da.sizes["flank"] == 2:
                da = da.isel(flank=0) - da.isel(flank=1)
            elif "flank" in da.dims:
                da = da.isel(flank=0)
        if da.ndim != 2:
            continue
        labels = ([str(v) for v in ds[dim].values] if dim in ds.coords
                  else [str(i) for i in range(da.sizes[dim])])
        units = str(ds[var].attrs.get("units", "1"))
        for i, lab in enumerate(labels):
            out[f"{var}:{lab}"] = ("time", np.asarray(da.isel({dim: i}).values, dtype=float),
                                   {"units": units, "long_name": long_name.format(lab),
                                    "source_channel": f"{var}[{dim}={lab}]"})
    mesh_forces = [k for k in out if k.startswith(f"{_RUN_FORCE}:")]
    first = next((k for k in mesh_forces if "ring-" in k.split(":", 1)[1]),
                 mesh_forces[0] if mesh_forces else None)
    if first is None:
        return out
    return {first: out[first], **{k: v for k, v in out.items() if k != first}}


def _channels_of_layout(ds: xr.Dataset, t: np.ndarray) -> xr.Dataset:
    """The channels (variables along ``time`` only) of a Dataset in the common layout."""
    keep = {str(k): v for k, v in ds.data_vars.items() if v.dims == ("time",)}
    if not keep:
        raise ValueError(
            "the dataset has no channel along 'time' (variables: "
            f"{[f'{k}{tuple(v.dims)}' for k, v in ds.data_vars.items()]})"
        )
    variables = {}
    for k, v in keep.items():
        arr = np.asarray(v.values)
        if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
            raise ValueError(f"channel {k!r} must hold real numbers; it has dtype {arr.dtype}")
        attrs = dict(v.attrs)
        attrs.setdefault("units", "1")
        attrs.setdefault("long_name", k)
        variables[k] = ("time", arr.astype(float), attrs)
    signals = xr.Dataset(variables, coords={"time": ("time", t, {"units": "s",
                                                                  "long_name": "time",
                                                                  "standard_name": "time"})})
    signals.attrs.update({k: v for k, v in ds.attrs.items() if k not in ("config_json",)})
    signals.attrs.setdefault("sample_rate_hz", float(1.0 / np.median(np.diff(t))))
    return signals


# ---------------------------------------------------------------------------------------------
# speed reference
# ---------------------------------------------------------------------------------------------


def _require_channel(signals: Any, name: str, option: str) -> xr.DataArray:
    names = list(signals.data_vars) if hasattr(signals, "data_vars") else \
        _channels_along_time(signals)
    if not isinstance(name, str) or name not in names:
        raise ValueError(
            f"{option} = {name!r} is not a channel of the measurement; channels: {names}"
        )
    return signals[name] if hasattr(signals, "data_vars") else signals.coords[name]


def _ppr(value: Any, channel: xr.DataArray) -> tuple[int, str]:
    """Pulses per revolution: the option, else the channel's attribute, else 1."""
    origin = "given"
    if value is None:
        value = channel.attrs.get("pulses_per_rev")
        origin = "from the channel's attributes"
        if value is None:
            return 1, "assumed (no pulses_per_rev given or stored)"
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or not (
        1 <= int(value) <= MAX_PULSES_PER_REV
    ):
        raise ValueError(
            f"pulses_per_rev = {value!r} is not admissible: an integer in "
            f"1..{MAX_PULSES_PER_REV}"
        )
    return int(value), origin


def tacho_reference(signals: Any, name: str, pulses_per_rev: Any, t: np.ndarray
                    ) -> tuple[SpeedReference, str]:
    """The speed and angle of the reference shaft from a tacho (pulse) channel.

    Parameters
    ----------
    signals : xarray.Dataset or xarray.DataArray
        Holds the tacho channel ``name`` along ``time`` (a data variable, or a coordinate of
        a DataArray).
    name : str
        The tacho channel.
    pulses_per_rev : int or None
        Pulses per revolution (1..10 000); ``None``: the channel's ``pulses_per_rev``
        attribute, else 1.
    t : numpy.ndarray
        Time [s] of the samples (uniform).

    Returns
    -------
    (analysis.speed.SpeedReference, str)
        The reference (:func:`analysis.speed.from_tacho` on ``t - t[0]``) and a sentence
        saying how it was obtained, e.g. ``"tacho channel 'tacho' (sun shaft), 60 pulses/rev
        (given), 1234 pulses"``.
    """
    require_instance(signals, (xr.Dataset, xr.DataArray), "signals")
    t = np.asarray(t)
    if t.ndim != 1 or t.size < 2 or t.dtype.kind not in "iuf" or not np.all(np.isfinite(t)):
        raise ValueError("t must be a 1-D array of at least two finite times [s]")
    ch = _require_channel(signals, name, "tacho")
    n, origin = _ppr(pulses_per_rev, ch)
    fs = (t.size - 1) / float(t[-1] - t[0])  # the mean step (a decoded axis: rounded steps)
    try:
        ref = from_tacho(np.asarray(ch.values, dtype=float), fs, pulses_per_rev=n,
                         output_time=t - t[0])
    except ValueError as exc:
        raise ValueError(f"tacho channel {name!r}: {exc}") from None
    member = ch.attrs.get("member")
    shaft = f" ({member} shaft)" if member else ""
    text = (f"tacho channel {name!r}{shaft}, {n} pulse{'s' if n != 1 else ''}/rev "
            f"({origin}), {ref.accuracy.n_pulses} pulses")
    return ref, text


def _speed_from_channel(signals: xr.Dataset, name: str, t: np.ndarray, kind: str
                        ) -> tuple[SpeedReference, str]:
    ch = _require_channel(signals, name, kind)
    found = find_reference(signals[[name]], **{kind: name})
    values = np.asarray(found.values, dtype=float)
    if kind == "speed":
        if np.nanmean(values) < 0:
            values = -values
            note = ", sign reversed (reverse rotation)"
        else:
            note = ""
        ref = from_rpm(t - t[0], values)
        return ref, f"speed channel {name!r} [{ch.attrs.get('units', '')}]{note}"
    if values[-1] < values[0]:
        values = -values
    try:
        ref = from_angle(t - t[0], values)
    except ValueError as exc:
        raise ValueError(f"angle channel {name!r}: {exc}") from None
    return ref, f"angle channel {name!r} [{ch.attrs.get('units', '')}]"


def _channels_along_time(signals: Any) -> list[str]:
    """Names of the data variables (and, for a DataArray, the coordinates) along ``time``."""
    pool = signals.data_vars if hasattr(signals, "data_vars") else signals.coords
    return [str(k) for k, v in pool.items() if v.dims == ("time",) and str(k) != "time"]


def reference_channel(signals: Any) -> tuple[str, str] | None:
    """The speed-reference channel that :func:`load_measurement` (and the command line) uses
    when none is named.

    Parameters
    ----------
    signals : xarray.Dataset or xarray.DataArray
        Channels along ``time`` (for a DataArray, its coordinates along ``time``).

    Returns
    -------
    (str, str) or None
        ``(kind, channel)`` with ``kind`` ``"tacho"``, ``"speed"`` or ``"angle"``: a channel
        named ``tacho`` (case-insensitive), else one named ``speed`` or ``rpm``, else the one
        whose units are an angle or a rotational speed
        (:func:`analysis.inputs.find_reference`); ``None`` when there is none.
    """
    require_instance(signals, (xr.Dataset, xr.DataArray), "signals")
    names = _channels_along_time(signals)
    for wanted in ("tacho", "speed"):
        for k in names:
            if _REFERENCE_NAMES.get(k.lower()) == wanted:
                return wanted, k
    try:
        ref = find_reference(signals)
    except ValueError:
        return None
    return ("angle" if ref.kind == "angle" else "speed"), str(ref.variable)


def _check_rpm(rpm: Any) -> float:
    try:
        v = float(rpm)
    except (TypeError, ValueError):
        raise ValueError(f"rpm = {rpm!r} is not a number (a constant speed in min-1)") from None
    if isinstance(rpm, bool) or not np.isfinite(v) or not 0 < v <= MAX_RPM:
        raise ValueError(f"rpm = {rpm!r} is not admissible: a speed in (0, {MAX_RPM:g}] min-1")
    return v


# ---------------------------------------------------------------------------------------------
# entry point
# ---------------------------------------------------------------------------------------------


def load_measurement(
    source: str | os.PathLike | xr.Dataset,
    *,
    channel: str | None = None,
    tacho: str | None = None,
    pulses_per_rev: int | None = None,
    speed: str | None = None,
    angle: str | None = None,
    rpm: float | None = None,
    rpm_from: str | None = None,
    fs: float | None = None,
    time_column: str | int | None = None,
    calibration: float | dict[str, float] | None = None,
    units: str | dict[str, str] | None = None,
    reader_options: dict | None = None,
    forces: bool = False,
) -> Measurement:
    """Load a measurement (file or Dataset) with the speed of its reference shaft.

    Parameters
    ----------
    source : path-like or xarray.Dataset
        A file :func:`analysis.readers.read` reads (by extension), a gearvib run file
        (``.nc`` with ``sensor_acceleration``), or a Dataset (common layout or a run).
    channel : str, optional
        The vibration channel to analyse first (checked here; default the first channel that
        is not the speed reference).
    tacho : str, optional
        Tacho (pulse) channel; ``pulses_per_rev`` pulses per revolution of the reference shaft
        (default its ``pulses_per_rev`` attribute, else 1).
    pulses_per_rev : int, optional
        1..10 000; only with a tacho.
    speed : str, optional
        Speed channel (min-1, rpm, rad s-1; Hz or s-1 when named as a speed).
    angle : str, optional
        Angle channel (rad or degree).
    rpm : float, optional
        A constant speed of the reference shaft [min-1] stated by the user, for records
        without a speed channel (stated in :attr:`Measurement.reference`).
    rpm_from : str, optional
        The name of a scalar variable of the file holding a constant speed [min-1] (a MAT
        scalar such as CWRU's ``X105RPM``, a netCDF scalar variable, a numeric global
        attribute).
    fs : float, optional
        Sample rate [Hz] of a file that does not state one (CSV without a time column, MAT
        without ``fs`` or time vector, TDMS without ``wf_increment``); for a file that
        states its rate (WAV, UFF, netCDF, a Dataset) it must agree with it.
    time_column : str or int, optional
        Time column of a CSV file (name or 0-based index) or time vector of a MAT file.
    calibration : float or dict, optional
        Factor in ``units`` per file unit, for every channel or per channel
        (:func:`analysis.measurement_options.apply_calibration`).
    units : str or dict, optional
        Unit of the (calibrated) values, for every channel or per channel, e.g. ``"g"``
        (converted to SI as the readers do: ``g`` -> ``m s-2``).
    reader_options : dict, optional
        Passed to the file's reader (e.g. ``{"fs": 25600}`` or ``{"time_column": "t"}`` for
        a CSV file, ``{"sets": [0, 1]}`` for UFF); a CSV file defaults to its ``time`` column.
    forces : bool
        For a simulated run: also its force and transmission-error channels
        (:data:`RUN_CHANNELS`, after the virtual sensors); a run without a virtual sensor then
        loads too (its first channel the first ring-planet mesh force, else the first mesh
        force), its speed reference the tacho, else the run's input angle. Default False: a
        run needs a virtual sensor.

    Returns
    -------
    Measurement

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    analysis.readers.ReaderError
        The file cannot be read (a :class:`ValueError`).
    ValueError
        More than one of ``tacho``/``speed``/``angle``/``rpm``/``rpm_from``;
        ``pulses_per_rev`` without a tacho; an unknown channel (the channels are listed); no
        speed reference found (the options are named, the channels listed); fewer than 64
        samples; a shaft that does not turn; ``fs`` outside (0, 1e9] Hz or against the
        file's own rate; ``time_column`` for a format without one; a calibration of 0 or a
        channel it names that the file does not hold; ``rpm_from`` naming no scalar of the
        file (its scalars are listed).
    TypeError
        ``fs`` or a calibration factor that is not a number (a bool or a string), a unit
        that is not a string.
    """
    given = {k: v for k, v in (("tacho", tacho), ("speed", speed), ("angle", angle),
                                ("rpm", rpm), ("rpm_from", rpm_from)) if v is not None}
    if len(given) > 1:
        raise ValueError(f"give one speed reference, not {' and '.join(given)}")
    if pulses_per_rev is not None and (speed is not None or angle is not None
                                       or rpm is not None or rpm_from is not None):
        raise ValueError("pulses_per_rev applies to a tacho channel, not to "
                         "speed/angle/rpm/rpm_from")
    fs = check_fs(fs)
    prov: dict[str, Any]
    if isinstance(source, xr.Dataset):
        if time_column is not None:
            raise ValueError("time_column applies to a CSV or MAT file, not to a Dataset")
        if fs is not None:
            check_rate(source, fs, "the dataset")
        ds, prov = source, {"file": str(source.attrs.get("source_file", "")) or None,
                            "format": str(source.attrs.get("source_format", "dataset")),
                            "reader": "in-memory Dataset"}
        where = "the dataset"
    elif isinstance(source, str | os.PathLike):
        p = Path(source)
        ds, prov = _read_file(p, reader_options, fs, time_column)
        where = str(p)
    else:
        raise TypeError(f"source must be a path or an xarray.Dataset, not {type(source).__name__}")
    t = _time_seconds(ds, where)
    if _is_run_without_sensor(ds) and not forces:
        raise ValueError(f"{where} is a simulated run without a virtual sensor: add a "
                         "[[sensor]] table to the gear set (docs/faults-sensors.md) and "
                         "simulate again")
    if _is_run(ds) or _is_run_without_sensor(ds):
        signals, extra = _channels_of_run(ds, t, forces=forces)
    else:
        signals = _channels_of_layout(ds, t)
        extra = {"kind": "file" if prov.get("reader") != "in-memory Dataset" else "dataset"}
    prov.update(extra)
    for name in signals.data_vars:  # a NaN sample (a netCDF gap) names channel and sample
        if signals[name].dtype.kind in "fc" and "time" in signals[name].dims:
            require_finite_blocks(np.asarray(signals[name].transpose(..., "time").values),
                                  f"{where}: channel {name!r}")
    signals = apply_calibration(signals, calibration, units)
    stated = {k: v for k, v in (("fs", fs), ("time_column", time_column),
                                ("calibration", calibration), ("units", units),
                                ("rpm_from", rpm_from)) if v is not None}
    if stated:
        prov["stated"] = stated
    if rpm_from is not None:
        rpm = scalar_speed(ds, rpm_from, MAX_RPM)
    angle_da = None
    accuracy: dict = {}
    if rpm is not None:
        v = _check_rpm(rpm)
        ref_channel = None
        speed_values = np.full(t.size, v)
        reference = (f"constant speed {v:g} min-1 from the file's scalar {rpm_from!r}"
                     if rpm_from is not None else
                     f"constant speed {v:g} min-1 stated by the user (no speed channel used)")
    else:
        if tacho is not None:
            kind, name = "tacho", tacho
        elif speed is not None:
            kind, name = "speed", speed
        elif angle is not None:
            kind, name = "angle", angle
        elif extra.get("kind") == "simulation" and _RUN_ANGLE in signals.data_vars:
            kind, name = "angle", _RUN_ANGLE  # a run without a tacho: its own input angle
        else:
            found = reference_channel(signals)
            if found is None:
                raise ValueError(
                    "no speed reference found: give --tacho CHANNEL [--pulses-per-rev N], "
                    "--speed CHANNEL (min-1), --angle CHANNEL (rad) or --rpm N (a constant "
                    "speed) (tacho=, speed=, angle=, rpm= in Python); no channel is named "
                    f"'tacho', 'speed' or 'rpm' or has speed/angle units; channels: "
                    f"{list(signals.data_vars)}"
                )
            kind, name = found
        if pulses_per_rev is not None and kind != "tacho":
            raise ValueError(f"pulses_per_rev applies to a tacho channel; the reference is the "
                             f"{kind} channel {name!r}")
        if kind == "tacho":
            sref, reference = tacho_reference(signals, name, pulses_per_rev, t)
        else:
            sref, reference = _speed_from_channel(signals, name, t, kind)
            if extra.get("kind") == "simulation" and (name == _RUN_ANGLE
                                                      or name.startswith("rotation:")):
                reference = (f"the run's own {signals[name].attrs['long_name']} "
                             f"{name!r} [rad] (the run has no tacho)")
        ref_channel = name
        speed_values = np.asarray(sref.rpm, dtype=float)
        if kind in ("tacho", "angle"):
            angle_da = xr.DataArray(np.asarray(sref.angle, dtype=float), dims="time",
                                    coords={"time": signals["time"]},
                                    attrs={"units": "rad",
                                           "long_name": "reference shaft angle"})
        accuracy = {k: (float(v) if isinstance(v, float) else int(v))
                    for k, v in sref.accuracy.__dict__.items()}
    if not np.all(np.isfinite(speed_values)) or float(np.max(speed_values)) <= 0:
        raise ValueError(f"the reference shaft does not turn ({reference}): highest speed "
                         f"{float(np.nanmax(speed_values)):.6g} min-1")
    reference_vars = {ref_channel} if ref_channel else set()
    if "tacho" in signals.data_vars and prov.get("kind") == "simulation":
        reference_vars.add("tacho")
    vib = [str(k) for k in signals.data_vars if str(k) not in reference_vars
           and _REFERENCE_NAMES.get(str(k).lower()) is None
           and str(signals[k].attrs.get("units", "")).strip().lower() not in ANGLE_UNITS]
    if channel is not None:
        _require_channel(signals, channel, "channel")
        if channel in reference_vars:
            raise ValueError(f"channel = {shown(channel)} is the speed reference; "
                             f"choose a vibration "
                             f"channel: {vib}")
        vib = [channel] + [c for c in vib if c != channel]
    prov.update(channels=[str(k) for k in signals.data_vars], vibration_channels=vib,
                reference_channel=ref_channel)
    speed_da = xr.DataArray(speed_values, dims="time", coords={"time": signals["time"]},
                            attrs={"units": "min-1", "long_name": "reference shaft speed"})
    return Measurement(signals=signals, speed_rpm=speed_da, reference=reference, source=prov,
                       angle=angle_da, accuracy=accuracy)
