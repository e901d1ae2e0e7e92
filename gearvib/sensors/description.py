"""Descriptions of virtual sensors: accelerometers on the housing and a tacho.

``[[sensor]]`` tables of a description, or the dataclasses built in Python:

Accelerometer (``type = "accelerometer"``, the default)
    ``name``, ``angle_deg`` (position on the housing, counter-clockwise from the x axis),
    ``member`` (the housing member whose mesh forces it sees; default the fixed central member),
    ``window`` (``"hann"``, ``"exponential"`` or ``"rectangular"``) with ``width_deg``, the
    housing response as ``housing_modes = [{frequency_hz, damping_ratio, gain}, ...]`` or a
    measured ``frf`` (a file name, or ``{path, quantity, columns, set}``), and optional
    ``bearings = {member = gain, ...}`` transmission paths of central members' radial bearings.
Tacho (``type = "tacho"``)
    ``name``, ``pulses_per_rev``, ``member`` (default the input member), ``level_v``, ``duty``.

The transmission-path model and the window definitions: :mod:`gearvib.sensors.signal` and
``docs/faults-sensors.md``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gearvib.checks import ITEM, check_array, check_count, check_number, short
from gearvib.paths import is_file

__all__ = [
    "WINDOWS",
    "HousingMode",
    "HousingSensor",
    "MeasuredFrf",
    "SensorError",
    "Tacho",
    "check_unique",
    "sensor_from_dict",
    "sensors_from_list",
]


class SensorError(ValueError):
    """An invalid sensor description (names the sensor, the key and what is admissible)."""


WINDOWS = ("hann", "exponential", "rectangular")
"""Transmission-path windows over the angle between planet and sensor."""

_ACC_KEYS = {"name", "type", "angle_deg", "member", "window", "width_deg", "housing_modes",
             "frf", "bearings", "comment"}
_TACHO_KEYS = {"name", "type", "pulses_per_rev", "member", "level_v", "duty", "comment"}
_MODE_KEYS = {"frequency_hz", "damping_ratio", "gain"}
_FRF_KEYS = {"path", "quantity", "columns", "set"}
MAX_GAIN = 1e6
"""Largest housing gain [kg^-1] (a modal mass of 1 mg) and measured |accelerance| [m s-2 N-1]."""
MAX_MODE_HZ = 1e9
"""Highest housing mode [Hz]."""
MAX_PULSES_PER_REV = 10_000
"""Most tacho pulses per revolution."""
MAX_MEMBERS = 64
"""Most housing members one sensor sees."""


def _num(value: Any, where: str, key: str, *, low: float | None = None,
         high: float | None = None, low_open: bool = False, high_open: bool = False) -> float:
    return check_number(value, f"{where}: {key}", low=low, high=high, low_open=low_open,
                        high_open=high_open, symbol=key, error=SensorError,
                        types=(int, float, np.integer, np.floating), wording=ITEM)


def _name(value: Any, where: str, key: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise SensorError(f"{where}: {key} must be a non-empty string, got {short(value)}")
    return value


@dataclass(frozen=True)
class HousingMode:
    """One mode of the housing's accelerance ``H(w) = gain (-w^2) / (w_k^2 - w^2 + 2 i z w_k w)``.

    Parameters
    ----------
    frequency_hz : float
        Natural frequency [Hz] (> 0).
    damping_ratio : float
        Modal damping ratio, ``0 < z < 1``.
    gain : float
        Modal residue [kg^-1]: the accelerance far above the mode (``|H| = gain / (2 z)`` at
        resonance); its sign is the phase of the mode shape product.
    """

    frequency_hz: float
    damping_ratio: float
    gain: float

    def __post_init__(self) -> None:
        w = "housing mode"
        object.__setattr__(self, "frequency_hz", _num(self.frequency_hz, w, "frequency_hz",
                                                      low=0.0, low_open=True))
        object.__setattr__(self, "damping_ratio", _num(self.damping_ratio, w, "damping_ratio",
                                                       low=0.0, high=1.0, low_open=True,
                                                       high_open=True))
        object.__setattr__(self, "gain", _num(self.gain, w, "gain", low=-MAX_GAIN,
                                              high=MAX_GAIN))
        if self.frequency_hz > MAX_MODE_HZ:
            raise SensorError(f"{w}: frequency_hz = {short(self.frequency_hz)} is not admissible "
                              f"(admissible: 0 < frequency_hz <= {MAX_MODE_HZ:g})")

    def accelerance(self, frequency: np.ndarray) -> np.ndarray:
        """``H`` at frequencies [Hz] [m s-2 N-1]."""
        w = 2.0 * np.pi * np.asarray(frequency, dtype=float)
        wk = 2.0 * np.pi * self.frequency_hz
        return self.gain * (-w * w) / (wk * wk - w * w + 2j * self.damping_ratio * wk * w)

    def to_dict(self) -> dict:
        return {"frequency_hz": self.frequency_hz, "damping_ratio": self.damping_ratio,
                "gain": self.gain}


MAX_FRF_POINTS = 1_000_000
"""Most points of a measured FRF."""


@dataclass(frozen=True)
class MeasuredFrf:
    """A measured housing accelerance (from a UFF 58 or CSV file).

    Attributes
    ----------
    frequency : tuple of float
        [Hz], increasing.
    real, imag : tuple of float
        Accelerance [m s-2 N-1] at those frequencies (mobility and receptance are converted
        when read).
    source : str
        The file.
    """

    frequency: tuple[float, ...]
    real: tuple[float, ...]
    imag: tuple[float, ...]
    source: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.source, str):
            raise SensorError(f"frf: source must be a string, got {short(self.source)}")
        try:
            f = check_array(self.frequency, f"frf {short(self.source)}: frequency",
                                   ndim=1, min_size=2, max_abs=MAX_MODE_HZ * 100)
            re = check_array(self.real, f"frf {short(self.source)}: real", ndim=1,
                                    min_size=2, max_abs=MAX_GAIN)
            im = check_array(self.imag, f"frf {short(self.source)}: imag", ndim=1,
                                    min_size=2, max_abs=MAX_GAIN)
        except (TypeError, ValueError) as exc:
            raise SensorError(str(exc)) from None
        if not (f.size == re.size == im.size) or f.size > MAX_FRF_POINTS:
            raise SensorError(f"frf {short(self.source)}: frequency, real and imag need as many "
                              f"values (2 .. {MAX_FRF_POINTS})")
        if np.any(f < 0) or np.any(np.diff(f) <= 0):
            raise SensorError(f"frf {short(self.source)}: frequency must be >= 0 and strictly "
                              "increasing [Hz]")
        for key, arr in (("frequency", f), ("real", re), ("imag", im)):
            object.__setattr__(self, key, tuple(float(v) for v in arr))
        big = max((abs(complex(r, i)) for r, i in zip(self.real, self.imag, strict=False)),
                  default=0.0)
        if not big <= MAX_GAIN:  # NaN included
            raise SensorError(f"frf {short(self.source)}: |H| up to {big:g} m s-2 N-1 is not "
                              f"admissible (admissible: finite, <= {MAX_GAIN:g}; the values "
                              "are converted to accelerance in SI units)")

    def accelerance(self, frequency: np.ndarray) -> np.ndarray:
        """Linear interpolation of real and imaginary parts; 0 outside the measured band."""
        f = np.asarray(frequency, dtype=float)
        fm = np.asarray(self.frequency)
        re = np.interp(f, fm, np.asarray(self.real), left=0.0, right=0.0)
        im = np.interp(f, fm, np.asarray(self.imag), left=0.0, right=0.0)
        return re + 1j * im

    def to_dict(self) -> dict:
        return {"source": self.source, "frequency_hz": [self.frequency[0], self.frequency[-1]],
                "points": len(self.frequency)}

    @classmethod
    def read(cls, path: str | Path, *, quantity: str = "accelerance",
             columns: str = "real_imag", set_index: int = 0) -> MeasuredFrf:
        """Read a UFF 58 (function type 4) or CSV FRF (:mod:`analysis.readers.frf`)."""
        from analysis.readers.frf import read_frf_csv, read_frf_uff

        p = Path(path)
        try:
            if p.suffix.lower() in (".uff", ".unv"):
                frf = read_frf_uff(p, set_index=set_index)
            else:
                frf = read_frf_csv(p, quantity=quantity, columns=columns)
        except (ValueError, OSError) as exc:  # ReaderError is a ValueError
            raise SensorError(f"frf {str(p)!r}: {exc}") from None
        acc = frf.accelerance()
        return cls(tuple(frf.frequency.tolist()), tuple(acc.real.tolist()),
                   tuple(acc.imag.tolist()), str(p))


@dataclass(frozen=True)
class HousingSensor:
    """An accelerometer fixed to the housing (see the module docstring).

    Parameters
    ----------
    name : str
        Channel name.
    angle_deg : float
        Position on the housing, counter-clockwise from the x axis (planet 1 at 0 deg at the
        reference configuration) [deg].
    window : {"hann", "exponential", "rectangular"}
        Transmission-path weight over the angle between a planet and the sensor.
    width_deg : float
        ``hann``, ``rectangular``: half-width where the weight ends (0 < w <= 180); ``exponential``:
        the angle over which the weight falls by 1/e (> 0) [deg].
    housing_modes : tuple of HousingMode
        Modal housing accelerance; or
    frf : MeasuredFrf
        a measured one.
    member : str or tuple of str, optional
        The housing member whose meshes the sensor sees: a central gear (its meshes with
        planets) or a carrier (the meshes of its planets: a parallel stage's housing), or
        several of them (a list in TOML). Default: the fixed central member if the set has
        exactly one fixed member with meshes, else every fixed member with meshes (all stages
        of a multi-stage gearbox).
    bearings : tuple of (str, float)
        Radial bearing forces of central members reaching the sensor, with their gains [1]
        (projected on the sensor's radial direction).
    """

    name: str
    angle_deg: float
    window: str = "hann"
    width_deg: float = 90.0
    housing_modes: tuple[HousingMode, ...] = ()
    frf: MeasuredFrf | None = None
    member: str | tuple[str, ...] | None = None
    bearings: tuple[tuple[str, float], ...] = field(default=())

    def __post_init__(self) -> None:
        w = f"sensor {short(self.name)}"
        _name(self.name, "sensor", "name")
        object.__setattr__(self, "angle_deg", _num(self.angle_deg, w, "angle_deg"))
        if self.window not in WINDOWS:
            raise SensorError(f"{w}: window = {short(self.window)} is not admissible (admissible: "
                              f"{', '.join(WINDOWS)})")
        high = None if self.window == "exponential" else 180.0
        object.__setattr__(self, "width_deg", _num(self.width_deg, w, "width_deg", low=0.0,
                                                   high=high, low_open=True))
        modes = tuple(self.housing_modes)
        if any(not isinstance(m, HousingMode) for m in modes):
            raise SensorError(f"{w}: housing_modes must be HousingMode descriptions")
        object.__setattr__(self, "housing_modes", modes)
        if bool(modes) == (self.frf is not None):
            raise SensorError(f"{w}: give the housing response as housing_modes (a list of "
                              "{frequency_hz, damping_ratio, gain}) or as a measured frf, one of "
                              "them")
        if isinstance(self.member, list | tuple):
            if not self.member or len(self.member) > MAX_MEMBERS:
                raise SensorError(f"{w}: member must name 1 .. {MAX_MEMBERS} members, got "
                                  f"{len(self.member)}")
            names = tuple(_name(m, w, "member") for m in self.member)
            if len(set(names)) != len(names):
                raise SensorError(f"{w}: member names a member twice ({list(names)})")
            object.__setattr__(self, "member", names[0] if len(names) == 1 else names)
        elif self.member is not None:
            _name(self.member, w, "member")
        b = tuple((str(k), _num(v, w, f"bearings.{k}")) for k, v in self.bearings)
        for k, _ in b:
            _name(k, w, "bearings")
        object.__setattr__(self, "bearings", b)

    def accelerance(self, frequency: np.ndarray) -> np.ndarray:
        """Housing accelerance at frequencies [Hz] [m s-2 N-1]."""
        if self.frf is not None:
            return self.frf.accelerance(frequency)
        out = np.zeros(np.shape(frequency), dtype=complex)
        for mode in self.housing_modes:
            out += mode.accelerance(frequency)
        return out

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"type": "accelerometer", "name": self.name,
                             "angle_deg": self.angle_deg, "window": self.window,
                             "width_deg": self.width_deg}
        if self.housing_modes:
            d["housing_modes"] = [m.to_dict() for m in self.housing_modes]
        if self.frf is not None:
            d["frf"] = self.frf.to_dict()
        if self.member is not None:
            d["member"] = self.member if isinstance(self.member, str) else list(self.member)
        if self.bearings:
            d["bearings"] = dict(self.bearings)
        return d


@dataclass(frozen=True)
class Tacho:
    """A tacho on a shaft: a pulse train of ``pulses_per_rev`` pulses per revolution.

    Parameters
    ----------
    name : str
        Channel name (the Dataset variable is ``tacho``).
    pulses_per_rev : int
        Pulses per revolution, 1 .. 10000.
    member : str, optional
        The shaft (default: the input member).
    level_v : float
        High level [V] (> 0); low is 0 V.
    duty : float
        High fraction of each pulse period, ``0 < duty < 1``.
    """

    name: str = "tacho"
    pulses_per_rev: int = 1
    member: str | None = None
    level_v: float = 5.0
    duty: float = 0.5

    def __post_init__(self) -> None:
        w = f"tacho {short(self.name)}"
        _name(self.name, "tacho", "name")
        ppr = self.pulses_per_rev
        if isinstance(ppr, bool) or not isinstance(ppr, int | np.integer) or not (
                1 <= ppr <= MAX_PULSES_PER_REV):
            raise SensorError(f"{w}: pulses_per_rev = {short(ppr)} is not admissible (admissible: "
                              f"an integer 1 .. {MAX_PULSES_PER_REV})")
        object.__setattr__(self, "pulses_per_rev", int(ppr))
        if self.member is not None:
            _name(self.member, w, "member")
        object.__setattr__(self, "level_v", _num(self.level_v, w, "level_v", low=0.0,
                                                 low_open=True))
        object.__setattr__(self, "duty", _num(self.duty, w, "duty", low=0.0, high=1.0,
                                              low_open=True, high_open=True))

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"type": "tacho", "name": self.name,
                             "pulses_per_rev": self.pulses_per_rev, "level_v": self.level_v,
                             "duty": self.duty}
        if self.member is not None:
            d["member"] = self.member
        return d


def _frf(value: Any, where: str, base: Path | None) -> MeasuredFrf:
    table = {"path": value} if isinstance(value, str) else value
    if not isinstance(table, Mapping):
        raise SensorError(f"{where}: frf must be a file name or a table {{path, quantity, "
                          "columns, set}")
    unknown = sorted(set(table) - _FRF_KEYS)
    if unknown:
        raise SensorError(f"{where}: unknown key {short(unknown[0])} in frf (admissible: "
                          f"{', '.join(sorted(_FRF_KEYS))})")
    if "path" not in table or not isinstance(table["path"], str):
        raise SensorError(f"{where}: frf needs a path (a UFF 58 or CSV file)")
    path = Path(table["path"])
    if base is not None and not path.is_absolute():
        path = base / path
    quantity = table.get("quantity", "accelerance")
    if quantity not in ("accelerance", "mobility", "receptance"):
        raise SensorError(f"{where}: frf.quantity = {short(quantity)} is not admissible "
                          "(admissible: accelerance, mobility, receptance)")
    columns = table.get("columns", "real_imag")
    if columns not in ("real_imag", "magnitude_phase"):
        raise SensorError(f"{where}: frf.columns = {short(columns)} is not admissible (admissible: "
                          "real_imag, magnitude_phase)")
    set_index = table.get("set", 0)
    if isinstance(set_index, bool) or not isinstance(set_index, int) or set_index < 0:
        raise SensorError(f"{where}: frf.set = {short(set_index)} is not admissible "
                          "(admissible: an "
                          "integer >= 0)")
    if not is_file(path):
        raise SensorError(f"{where}: frf file {str(path)!r} does not exist")
    try:
        return MeasuredFrf.read(path, quantity=quantity, columns=columns, set_index=set_index)
    except SensorError as exc:
        raise SensorError(f"{where}: {exc}") from None


def sensor_from_dict(table: Mapping[str, Any] | HousingSensor | Tacho, *,
                     base: Path | None = None, index: int | None = None
                     ) -> HousingSensor | Tacho:
    """A sensor from a ``[[sensor]]`` table (or a description, returned as is).

    Raises
    ------
    SensorError
        Unknown type or key (named with the admissible ones), a missing key, a value of the
        wrong type or out of range, an unreadable FRF file.
    """
    if isinstance(table, HousingSensor | Tacho):
        return table
    index = check_count(index, "index", low=0, optional=True, error=SensorError)
    if base is not None and not isinstance(base, str | Path):
        raise SensorError(f"base must be a folder (a path), got {type(base).__name__}")
    head = "[[sensor]]" if index is None else f"[[sensor]] #{index + 1}"
    if not isinstance(table, Mapping):
        raise SensorError(f"{head}: a sensor must be a table, got {type(table).__name__}")
    kind = table.get("type", "accelerometer")
    if kind not in ("accelerometer", "tacho"):
        raise SensorError(f"{head}: type = {short(kind)} is not admissible (admissible: "
                          "accelerometer, tacho)")
    allowed = _ACC_KEYS if kind == "accelerometer" else _TACHO_KEYS
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise SensorError(f"{head}: unknown key {short(unknown[0])} (admissible for type = "
                          f"{short(kind)}: {', '.join(sorted(allowed))})")
    if "name" not in table:
        raise SensorError(f"{head}: missing key 'name'")
    where = f"{head} {short(table['name'])}"
    try:
        if kind == "tacho":
            return Tacho(**{k: v for k, v in table.items() if k not in ("type", "comment")})
        if "angle_deg" not in table:
            raise SensorError(f"{where}: missing key 'angle_deg'")
        kw: dict[str, Any] = {k: v for k, v in table.items()
                              if k in ("name", "angle_deg", "window", "width_deg", "member")}
        if "window" in kw and not isinstance(kw["window"], str):
            raise SensorError(f"{where}: window must be one of {', '.join(WINDOWS)}")
        modes = table.get("housing_modes")
        if modes is not None:
            if not isinstance(modes, list) or not modes:
                raise SensorError(f"{where}: housing_modes must be a non-empty list of tables "
                                  "{frequency_hz, damping_ratio, gain}")
            out = []
            for i, m in enumerate(modes):
                if not isinstance(m, Mapping):
                    raise SensorError(f"{where}: housing_modes[{i}] must be a table")
                bad = sorted(set(m) - _MODE_KEYS)
                missing = sorted(_MODE_KEYS - set(m))
                if bad or missing:
                    what = (f"unknown key {short(bad[0])}" if bad
                            else f"missing key {short(missing[0])}")
                    raise SensorError(f"{where}: {what} in housing_modes[{i}] (admissible: "
                                      "frequency_hz, damping_ratio, gain)")
                try:
                    out.append(HousingMode(**m))
                except SensorError as exc:
                    raise SensorError(f"{where}: housing_modes[{i}]: {exc}") from None
            kw["housing_modes"] = tuple(out)
        if "frf" in table:
            kw["frf"] = _frf(table["frf"], where, base)
        if "bearings" in table:
            b = table["bearings"]
            if not isinstance(b, Mapping):
                raise SensorError(f"{where}: bearings must be a table {{member = gain, ...}}")
            kw["bearings"] = tuple((k, _num(v, where, f"bearings.{k}")) for k, v in b.items())
        return HousingSensor(**kw)
    except SensorError as exc:
        msg = str(exc)
        raise SensorError(msg if msg.startswith(head) else f"{where}: {msg}") from None
    except TypeError as exc:
        raise SensorError(f"{where}: {exc}") from None


def sensors_from_list(tables: Sequence | None, *, base: Path | None = None
                      ) -> tuple[HousingSensor | Tacho, ...]:
    """Descriptions of a ``[[sensor]]`` array; names must be unique, at most one tacho."""
    if tables is None:
        return ()
    if isinstance(tables, Mapping) or not isinstance(tables, Sequence):
        raise SensorError("[[sensor]] must be an array of tables (one per sensor)")
    out = tuple(sensor_from_dict(t, base=base, index=i) for i, t in enumerate(tables))
    check_unique(out)
    return out


def check_unique(sensors: Sequence) -> None:
    """Sensor names must be unique and there is at most one tacho (SensorError otherwise)."""
    names = [s.name for s in sensors]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise SensorError(f"sensor name {short(dup[0])} is used twice (names must be unique)")
    if sum(isinstance(s, Tacho) for s in sensors) > 1:
        raise SensorError("more than one tacho: a run records one tacho channel")
