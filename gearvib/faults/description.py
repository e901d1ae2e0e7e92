"""Descriptions of local tooth faults and manufacturing errors (one dataclass per kind).

A description names the *member* (a body of the gear set: ``"sun"``, ``"planet2"``, ``"ring"``,
``"s1.sun"`` ...), the tooth where it applies and the parameters of its kind. It is plain data:
:mod:`gearvib.faults.law` turns a model and its faults into the arrays of the kernels. The same
descriptions come from ``[[fault]]`` tables of a TOML description (:func:`fault_from_dict`) or
are built in Python; ``to_dict()`` gives the table back (stored in the run's provenance).

Kinds (``kind`` key)
--------------------
``crack``         root crack: the faulty tooth's pair stiffness reduced by ``severity`` (0-1)
                  over its whole engagement, or replaced by a stiffness ``curve`` along the path
                  (CSV from a tooth-contact program)
``pitting``       pitting / spalling on ``flank`` over the path fractions ``path_start`` ..
                  ``path_end``: pair stiffness reduced by ``severity`` there, profile deviation
                  ``depth`` [m] (material removed: the pair loses deflection)
``broken_tooth``  the tooth is missing: its pairs carry nothing
``eccentricity``  geometric centre offset ``eccentricity`` [m] from the axis of rotation
                  (runout), direction ``phase_deg`` in the gear's reference orientation
``pitch_error``   tooth position deviations [m on the reference circle]: one tooth
                  (``tooth``, ``deviation``), every tooth (``single`` or ``cumulative`` lists)
                  or a ``file``
``pin_error``     planet pin position error ``radial``, ``tangential`` [m] (planets only)
``backlash``      planet-specific backlash: total normal ``backlash`` [m] of the planet's
                  meshes (planets only)

Every kind but ``pin_error`` takes ``mate``: the mating bodies whose meshes are affected
(default: every mesh of the member). All values are SI; every key, type and range is checked
and an error names the key and the admissible values.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from gearvib.checks import ITEM, check_array, check_count, check_integer, check_number, cut, short
from gearvib.paths import is_file

__all__ = [
    "FAULT_KINDS",
    "BrokenTooth",
    "Crack",
    "Eccentricity",
    "Fault",
    "FaultError",
    "PairCurve",
    "PinError",
    "PitchError",
    "Pitting",
    "PlanetBacklash",
    "fault_from_dict",
    "faults_from_list",
]


class FaultError(ValueError):
    """An invalid fault description (names the fault, the key and what is admissible)."""


MAX_DEVIATION = 1e-3
"""Largest admissible tooth deviation, eccentricity, pin error or backlash magnitude [m]."""

_COMMON = {"kind", "member", "name", "comment"}
_FLANKS = ("left", "right", "both")
_POSITION_UNITS = ("path_fraction", "base_pitch")
_STIFFNESS_UNITS = ("N/m", "N/(mm um)")
_CURVE_KEYS = {"path", "position_unit", "stiffness_unit", "position_column", "stiffness_column",
               "face_width", "position", "stiffness"}
_FILE_UNITS = {"m": 1.0, "um": 1e-6}


MAX_CURVE = 100_000
"""Most points of a single-pair stiffness curve."""


def _where(d: Mapping, index: int | None) -> str:
    kind = d.get("kind", "?") if isinstance(d, Mapping) else "?"
    head = "[[fault]]" if index is None else f"[[fault]] #{index + 1}"
    return f"{head} ({cut(str(kind))})"


def _number(value: Any, where: str, key: str, *, low: float | None = None,
            high: float | None = None, low_open: bool = False) -> float:
    return check_number(value, f"{where}: {key}", low=low, high=high, low_open=low_open,
                        symbol=key, error=FaultError,
                        types=(int, float, np.integer, np.floating), wording=ITEM)


def _integer(value: Any, where: str, key: str, *, low: int = 0) -> int:
    return check_integer(value, f"{where}: {key}", low=low, error=FaultError,
                         types=(int, float, np.integer), wording=ITEM)


def _name(value: Any, where: str, key: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise FaultError(f"{where}: {key} must be a non-empty string (a body name), "
                         f"got {short(value)}")
    return value


def _mate(value: Any, where: str) -> tuple[str, ...]:
    if value is None:
        return ()
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, list | tuple) or not items:
        raise FaultError(f"{where}: mate must be a body name or a non-empty list of body names, "
                         f"got {short(value)}")
    return tuple(_name(v, where, "mate") for v in items)


def _deviations(values: Any, where: str, key: str) -> tuple[float, ...]:
    if not isinstance(values, list | tuple | np.ndarray) or len(values) < 2:
        raise FaultError(f"{where}: {key} must be a list with one deviation [m] per tooth "
                         f"(>= 2 values), got {short(values)}")
    return tuple(_number(v, where, f"{key}[{i}]", low=-MAX_DEVIATION, high=MAX_DEVIATION)
                 for i, v in enumerate(values))


@dataclass(frozen=True)
class PairCurve:
    """Stiffness of the faulty tooth pair along the path of contact (tooth-contact program).

    Attributes
    ----------
    position : tuple of float
        Path positions, strictly increasing: fractions 0..1 of the active path
        (``position_unit = "path_fraction"``) or base pitches (``"base_pitch"``).
    stiffness : tuple of float
        Pair stiffness [N/m] at those positions (>= 0).
    position_unit : str
        ``"path_fraction"`` or ``"base_pitch"``.
    source : str, optional
        The CSV file it was read from.
    """

    position: tuple[float, ...]
    stiffness: tuple[float, ...]
    position_unit: str = "path_fraction"
    source: str | None = None

    def __post_init__(self) -> None:
        try:
            u = check_array(self.position, "crack curve: position", min_size=0,
                                   finite=False)
            k = check_array(self.stiffness, "crack curve: stiffness", min_size=0,
                                   finite=False)
        except (TypeError, ValueError) as exc:
            raise FaultError(str(exc)) from None
        if u.size > MAX_CURVE:
            raise FaultError(f"crack curve: {u.size} points (admissible: at most {MAX_CURVE})")
        if self.source is not None and not isinstance(self.source, str):
            raise FaultError(f"crack curve: source must be a string, got {short(self.source)}")
        if u.ndim != 1 or u.size < 2 or u.shape != k.shape:
            raise FaultError("crack curve: position and stiffness must be lists of equal "
                             "length >= 2")
        if not (np.all(np.isfinite(u)) and np.all(np.isfinite(k))):
            raise FaultError("crack curve: position and stiffness must be finite")
        if np.any(np.diff(u) <= 0):
            raise FaultError("crack curve: positions must be strictly increasing")
        if np.any(k < 0):
            raise FaultError("crack curve: stiffness must be >= 0 N/m")
        if self.position_unit not in _POSITION_UNITS:
            raise FaultError(f"crack curve: position_unit = {short(self.position_unit)} is not "
                             f"admissible (admissible: {', '.join(_POSITION_UNITS)})")
        if self.position_unit == "path_fraction" and (u[0] < -1e-9 or u[-1] > 1 + 1e-9):
            raise FaultError(f"crack curve: path fractions span [{u[0]:.6g}, {u[-1]:.6g}] "
                             "(admissible: within [0, 1])")
        if u[0] < -1e-9:
            raise FaultError(f"crack curve: position {u[0]:.6g} is negative (admissible: >= 0)")
        object.__setattr__(self, "position", tuple(float(x) for x in u))
        object.__setattr__(self, "stiffness", tuple(float(x) for x in k))

    def to_dict(self) -> dict:
        d = {"position": list(self.position), "stiffness": list(self.stiffness),
             "position_unit": self.position_unit, "stiffness_unit": "N/m"}
        if self.source is not None:
            d["source"] = self.source
        return d


def _curve(table: Any, where: str, base: Path | None) -> PairCurve:
    if not isinstance(table, Mapping):
        raise FaultError(f"{where}: curve must be a table such as {{path = \"cracked.csv\", "
                         "position_unit = \"path_fraction\", stiffness_unit = \"N/m\"}")
    unknown = sorted(set(table) - _CURVE_KEYS)
    if unknown:
        raise FaultError(f"{where}: unknown key {short(unknown[0])} in curve (admissible: "
                         f"{', '.join(sorted(_CURVE_KEYS))})")
    unit = table.get("position_unit", "path_fraction")
    if unit not in _POSITION_UNITS:
        raise FaultError(f"{where}: curve.position_unit = {short(unit)} is not admissible "
                         f"(admissible: {', '.join(_POSITION_UNITS)})")
    s_unit = table.get("stiffness_unit", "N/m")
    if s_unit not in (*_STIFFNESS_UNITS, "N/(mm µm)"):
        raise FaultError(f"{where}: curve.stiffness_unit = {short(s_unit)} is not admissible "
                         f"(admissible: {', '.join(_STIFFNESS_UNITS)})")
    if ("path" in table) == ("position" in table or "stiffness" in table):
        raise FaultError(f"{where}: curve needs either path (a CSV file) or position and "
                         "stiffness lists")
    # imported here: stiffness imports geometry, which a plain description does not need
    from gearvib.stiffness import TabulatedPair

    face = table.get("face_width")
    if face is not None:
        face = _number(face, where, "curve.face_width", low=0.0, low_open=True)
    try:
        if "path" in table:
            p = table["path"]
            if not isinstance(p, str):
                raise FaultError(f"{where}: curve.path must be a file name, got {short(p)}")
            path = Path(p)
            if base is not None and not path.is_absolute():
                path = base / path
            cols = {k: _integer(table.get(k, d), where, f"curve.{k}")
                    for k, d in (("position_column", 0), ("stiffness_column", 1))}
            # a large contact ratio only widens the admissible range of base-pitch positions;
            # path fractions keep their 0..1 values (contact ratio 1)
            eps = 1.0 if unit == "path_fraction" else 100.0
            pair = TabulatedPair.from_csv(path, eps, position_unit=unit,
                                          stiffness_unit=s_unit, face_width=face, **cols)
            src: str | None = str(path)
        else:
            for k in ("position_column", "stiffness_column"):
                if k in table:
                    raise FaultError(f"{where}: curve.{k} applies to a CSV path only")
            pos, stf = table.get("position"), table.get("stiffness")
            if not isinstance(pos, list | tuple) or not isinstance(stf, list | tuple):
                raise FaultError(f"{where}: curve.position and curve.stiffness must be lists")
            eps = 1.0 if unit == "path_fraction" else 100.0
            pair = TabulatedPair.from_arrays(
                [_number(v, where, "curve.position") for v in pos],
                [_number(v, where, "curve.stiffness") for v in stf], eps,
                position_unit=unit, stiffness_unit=s_unit, face_width=face)
            src = table.get("source") if isinstance(table.get("source"), str) else None
    except FaultError:
        raise
    except ValueError as exc:
        raise FaultError(f"{where}: curve: {exc}") from None
    return PairCurve(tuple(pair.position), tuple(pair.stiffness), unit, src)


FILE_MAX_BYTES = 16 * 2**20
"""Largest pitch-deviation file read [bytes]."""


def _read_deviation_file(path: Path, where: str, unit: str) -> tuple[float, ...]:
    """One deviation per tooth in tooth order: the last column of every numeric line; with
    two or more columns the first must be the tooth index 0, 1, 2, ..."""
    if not is_file(path):
        raise FaultError(f"{where}: file {str(path)!r} does not exist")
    try:
        size = path.stat().st_size
        if size > FILE_MAX_BYTES:
            raise FaultError(f"{where}: {path.name} has {size / 2**20:.1f} MiB (admissible: at "
                             f"most {FILE_MAX_BYTES // 2**20} MiB of deviations)")
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FaultError(f"{where}: {path.name} is not a UTF-8 text file (byte {exc.start}: "
                         f"{exc.reason})") from None
    except OSError as exc:
        raise FaultError(f"{where}: {path.name} cannot be read ({exc.strerror or exc})") \
            from None
    # on demand: the analysis.readers package loads xarray, which descriptions do not need
    from analysis.readers.texttable import table_lines

    rows: list[list[float]] = []
    for lineno, parts in table_lines(text):
        try:
            rows.append([float(p) for p in parts if p])
        except ValueError:
            if rows:
                raise FaultError(f"{where}: {path.name}, line {lineno}: not a number (the "
                                 "file holds one deviation per tooth)") from None
            continue  # header lines before the data
    if len(rows) < 2 or any(len(r) != len(rows[0]) or not r for r in rows):
        raise FaultError(f"{where}: {path.name} must hold one row per tooth (>= 2 rows, the "
                         "same number of columns in every row)")
    arr = np.array(rows)
    if arr.shape[1] >= 2 and not np.array_equal(arr[:, 0], np.arange(arr.shape[0])):
        raise FaultError(f"{where}: {path.name}: the first column must be the tooth index "
                         "0, 1, 2, ... in order")
    scale = _FILE_UNITS[unit]
    return _deviations([float(v) * scale for v in arr[:, -1]], where, path.name)


class Fault:
    """Base of every fault and error description (``kind`` names it in a ``[[fault]]``)."""

    kind: ClassVar[str] = ""
    member: str
    mate: tuple[str, ...]
    name: str | None

    def to_dict(self) -> dict:
        """The ``[[fault]]`` table of this description (JSON-serialisable)."""
        d: dict[str, Any] = {"kind": self.kind, "member": self.member}
        for k, v in self._params().items():
            if v is not None and v != ():
                d[k] = list(v) if isinstance(v, tuple) else v
        mate = getattr(self, "mate", ())
        if mate:
            d["mate"] = list(mate)
        if getattr(self, "name", None):
            d["name"] = self.name
        return d

    def _params(self) -> dict:
        raise NotImplementedError

    @property
    def label(self) -> str:
        """Short text, e.g. ``"crack sun tooth 3"``."""
        tooth = getattr(self, "tooth", None)
        return self.name or f"{self.kind} {self.member}" + (
            f" tooth {tooth}" if tooth is not None else "")


def _check_common(obj: Any) -> None:
    _name(obj.member, f"{obj.kind} fault", "member")
    object.__setattr__(obj, "mate", _mate(list(obj.mate) if obj.mate else None,
                                          f"{obj.kind} fault on {short(obj.member)}"))
    if obj.name is not None and not isinstance(obj.name, str):
        raise FaultError(f"{obj.kind} fault on {short(obj.member)}: name must be a string")


@dataclass(frozen=True)
class Crack(Fault):
    """Tooth root crack: the faulty tooth's pair stiffness reduced while it is in contact.

    Parameters
    ----------
    member : str
        Body with the cracked tooth.
    tooth : int
        Tooth index (from 0, numbered in the order the teeth enter a mesh in forward operation;
        ``docs/faults-sensors.md``).
    severity : float, optional
        Relative loss of the faulty pair's stiffness over its engagement, 0 (healthy) .. 1.
    curve : PairCurve, optional
        Instead of ``severity``: the faulty pair's stiffness along the path.
    mate : tuple of str
        Mating bodies whose meshes are affected (default all).
    name : str, optional
        Label.
    """

    kind: ClassVar[str] = "crack"
    member: str
    tooth: int
    severity: float | None = None
    curve: PairCurve | None = None
    mate: tuple[str, ...] = ()
    name: str | None = None

    def __post_init__(self) -> None:
        _check_common(self)
        w = f"crack on {short(self.member)}"
        object.__setattr__(self, "tooth", _integer(self.tooth, w, "tooth"))
        if (self.severity is None) == (self.curve is None):
            raise FaultError(f"{w}: give either severity (0..1) or a stiffness curve")
        if self.severity is not None:
            object.__setattr__(self, "severity", _number(self.severity, w, "severity",
                                                         low=0.0, high=1.0))
        if self.curve is not None and not isinstance(self.curve, PairCurve):
            raise FaultError(f"{w}: curve must be a PairCurve")

    def _params(self) -> dict:
        return {"tooth": self.tooth, "severity": self.severity,
                "curve": self.curve.to_dict() if self.curve is not None else None}


@dataclass(frozen=True)
class Pitting(Fault):
    """Pitting or spalling over part of the path of contact of one flank of a tooth.

    Parameters
    ----------
    member, tooth
        As :class:`Crack`.
    severity : float
        Relative loss of the pair stiffness inside the pitted zone, 0 .. 1 (the contact width
        lost).
    path_start, path_end : float
        The pitted zone as fractions of the active path, ``0 <= path_start < path_end <= 1``
        (0: where the pair enters contact, 1: where it leaves).
    depth : float
        Profile deviation inside the zone [m] (material removed, >= 0): a displacement
        excitation that lowers the pair's deflection.
    flank : {"left", "right", "both"}
        Mesh flank(s) on which the tooth is pitted (``left``: the flank loaded when the central
        gear drives the planet forward).
    mate, name
        As :class:`Crack`.
    """

    kind: ClassVar[str] = "pitting"
    member: str
    tooth: int
    severity: float
    path_start: float
    path_end: float
    depth: float = 0.0
    flank: str = "left"
    mate: tuple[str, ...] = ()
    name: str | None = None

    def __post_init__(self) -> None:
        _check_common(self)
        w = f"pitting on {short(self.member)}"
        object.__setattr__(self, "tooth", _integer(self.tooth, w, "tooth"))
        object.__setattr__(self, "severity", _number(self.severity, w, "severity", low=0.0,
                                                     high=1.0))
        a = _number(self.path_start, w, "path_start", low=0.0, high=1.0)
        b = _number(self.path_end, w, "path_end", low=0.0, high=1.0)
        if not a < b:
            raise FaultError(f"{w}: path_start = {a:g} must be below path_end = {b:g} "
                             "(admissible: 0 <= path_start < path_end <= 1)")
        object.__setattr__(self, "path_start", a)
        object.__setattr__(self, "path_end", b)
        object.__setattr__(self, "depth", _number(self.depth, w, "depth", low=0.0,
                                                  high=MAX_DEVIATION))
        if self.flank not in _FLANKS:
            raise FaultError(f"{w}: flank = {short(self.flank)} is not admissible (admissible: "
                             f"{', '.join(_FLANKS)})")

    def _params(self) -> dict:
        return {"tooth": self.tooth, "severity": self.severity, "path_start": self.path_start,
                "path_end": self.path_end, "depth": self.depth, "flank": self.flank}


@dataclass(frozen=True)
class BrokenTooth(Fault):
    """A missing tooth: its pairs carry no load (the others take it over or the mesh opens)."""

    kind: ClassVar[str] = "broken_tooth"
    member: str
    tooth: int
    mate: tuple[str, ...] = ()
    name: str | None = None

    def __post_init__(self) -> None:
        _check_common(self)
        object.__setattr__(self, "tooth", _integer(self.tooth, f"broken tooth on "
                                                   f"{short(self.member)}", "tooth"))

    def _params(self) -> dict:
        return {"tooth": self.tooth}


@dataclass(frozen=True)
class Eccentricity(Fault):
    """Eccentricity (runout) of a gear: its geometric centre is off its axis of rotation.

    Parameters
    ----------
    member : str
        The eccentric gear.
    eccentricity : float
        Offset of the geometric (tooth) centre from the axis of rotation [m] (half the radial
        runout), ``0 .. 1 mm``.
    phase_deg : float
        Direction of the offset at the reference configuration (every rotation angle zero),
        counter-clockwise from the carrier's x axis [deg]; it turns with the gear.
    mate, name
        As :class:`Crack`.
    """

    kind: ClassVar[str] = "eccentricity"
    member: str
    eccentricity: float
    phase_deg: float = 0.0
    mate: tuple[str, ...] = ()
    name: str | None = None

    def __post_init__(self) -> None:
        _check_common(self)
        w = f"eccentricity of {short(self.member)}"
        object.__setattr__(self, "eccentricity", _number(self.eccentricity, w, "eccentricity",
                                                         low=0.0, high=MAX_DEVIATION))
        object.__setattr__(self, "phase_deg", _number(self.phase_deg, w, "phase_deg"))

    def _params(self) -> dict:
        return {"eccentricity": self.eccentricity, "phase_deg": self.phase_deg}


@dataclass(frozen=True)
class PitchError(Fault):
    """Tooth pitch (position) errors of a gear.

    The cumulative pitch deviation ``F_p,k`` of tooth ``k`` is its position error on the
    reference circle [m], positive in the direction of increasing tooth index (ISO 1328-1:
    ``F_p,k`` is the sum of the single pitch deviations ``f_pt,1 .. f_pt,k``; tooth 0 is the
    reference, ``F_p,0 = 0`` for ``single``). Exactly one form:

    * ``tooth`` and ``deviation``: one tooth out of position (a single pitch error);
    * ``single``: single pitch deviations of teeth 0 .. z-1 (``f_pt,k`` the pitch from tooth
      ``k-1`` to ``k``; they must close: sum 0);
    * ``cumulative``: ``F_p,k`` of teeth 0 .. z-1.

    The list length must equal the member's tooth number (checked against the model).
    """

    kind: ClassVar[str] = "pitch_error"
    member: str
    tooth: int | None = None
    deviation: float | None = None
    single: tuple[float, ...] | None = None
    cumulative: tuple[float, ...] | None = None
    source: str | None = None
    mate: tuple[str, ...] = ()
    name: str | None = None

    def __post_init__(self) -> None:
        _check_common(self)
        w = f"pitch error of {short(self.member)}"
        if self.source is not None and not isinstance(self.source, str):
            raise FaultError(f"{w}: source must be a string, got {short(self.source)}")
        forms = [self.deviation is not None or self.tooth is not None,
                 self.single is not None, self.cumulative is not None]
        if sum(forms) != 1:
            raise FaultError(f"{w}: give exactly one of tooth and deviation, single, "
                             "cumulative (or file)")
        if forms[0]:
            if self.tooth is None or self.deviation is None:
                raise FaultError(f"{w}: a single-tooth error needs both tooth and deviation")
            object.__setattr__(self, "tooth", _integer(self.tooth, w, "tooth"))
            object.__setattr__(self, "deviation", _number(
                self.deviation, w, "deviation", low=-MAX_DEVIATION, high=MAX_DEVIATION))
        if self.single is not None:
            f = _deviations(self.single, w, "single")
            total = sum(f)
            if abs(total) > 1e-3 * max(abs(x) for x in f) + 1e-12:
                raise FaultError(f"{w}: the single pitch deviations sum to {total:.4g} m; they "
                                 "must close around the gear (sum 0): give cumulative "
                                 "deviations instead, or correct the list")
            object.__setattr__(self, "single", f)
        if self.cumulative is not None:
            object.__setattr__(self, "cumulative", _deviations(self.cumulative, w,
                                                               "cumulative"))

    def cumulative_deviations(self, z: int) -> np.ndarray:
        """``F_p,k`` of teeth 0 .. z-1 [m] (checked against the tooth number ``z``)."""
        w = f"pitch error of {short(self.member)}"
        if self.tooth is not None:
            if not 0 <= self.tooth < z:
                raise FaultError(f"{w}: tooth = {self.tooth} is not admissible (admissible: "
                                 f"0 .. {z - 1}, {short(self.member)} has {z} teeth)")
            out = np.zeros(z)
            out[self.tooth] = self.deviation
            return out
        values = self.single if self.single is not None else self.cumulative
        assert values is not None  # __post_init__: exactly one form is given
        if len(values) != z:
            raise FaultError(f"{w}: {len(values)} deviations given, {short(self.member)} has {z} "
                             "teeth (one per tooth, tooth 0 first)")
        if self.single is not None:
            f = np.asarray(self.single)
            return np.concatenate([[0.0], np.cumsum(f[1:])])
        return np.asarray(self.cumulative, dtype=float)

    def _params(self) -> dict:
        return {"tooth": self.tooth, "deviation": self.deviation, "single": self.single,
                "cumulative": self.cumulative, "source": self.source}


@dataclass(frozen=True)
class PinError(Fault):
    """Planet pin position error on the carrier (Bodas & Kahraman 2004).

    Parameters
    ----------
    member : str
        The planet.
    radial, tangential : float
        Displacement of the pin from its nominal position [m]: radially outwards and
        tangentially in the carrier's positive rotation sense, each within +-1 mm.
    """

    kind: ClassVar[str] = "pin_error"
    member: str
    radial: float = 0.0
    tangential: float = 0.0
    name: str | None = None
    mate: tuple[str, ...] = field(default=(), init=False)

    def __post_init__(self) -> None:
        _check_common(self)
        w = f"pin error of {short(self.member)}"
        for k in ("radial", "tangential"):
            object.__setattr__(self, k, _number(getattr(self, k), w, k, low=-MAX_DEVIATION,
                                                high=MAX_DEVIATION))

    def _params(self) -> dict:
        return {"radial": self.radial, "tangential": self.tangential}


@dataclass(frozen=True)
class PlanetBacklash(Fault):
    """Planet-specific backlash: the total normal backlash of the planet's meshes [m].

    Negative: both flanks in contact (preload), as for a mesh description.
    """

    kind: ClassVar[str] = "backlash"
    member: str
    backlash: float
    mate: tuple[str, ...] = ()
    name: str | None = None

    def __post_init__(self) -> None:
        _check_common(self)
        object.__setattr__(self, "backlash", _number(
            self.backlash, f"backlash of {short(self.member)}", "backlash", low=-MAX_DEVIATION,
            high=MAX_DEVIATION))

    def _params(self) -> dict:
        return {"backlash": self.backlash}


_CLASSES: dict[str, type] = {c.kind: c for c in (Crack, Pitting, BrokenTooth, Eccentricity,
                                                 PitchError, PinError, PlanetBacklash)}
FAULT_KINDS = tuple(_CLASSES)
"""Admissible ``kind`` values of a ``[[fault]]`` table."""

_KEYS = {
    "crack": {"tooth", "severity", "curve", "mate"},
    "pitting": {"tooth", "severity", "path_start", "path_end", "depth", "flank", "mate"},
    "broken_tooth": {"tooth", "mate"},
    "eccentricity": {"eccentricity", "phase_deg", "mate"},
    "pitch_error": {"tooth", "deviation", "single", "cumulative", "file", "unit", "mate",
                    "source"},
    "pin_error": {"radial", "tangential"},
    "backlash": {"backlash", "mate"},
}
_REQUIRED = {
    "crack": ("tooth",), "pitting": ("tooth", "severity", "path_start", "path_end"),
    "broken_tooth": ("tooth",), "eccentricity": ("eccentricity",), "pitch_error": (),
    "pin_error": (), "backlash": ("backlash",),
}


def fault_from_dict(table: Mapping[str, Any] | Fault, *, base: Path | None = None,
                    index: int | None = None) -> Fault:
    """A fault description from a ``[[fault]]`` table (or a description, returned as is).

    Parameters
    ----------
    table : mapping
        ``kind``, ``member`` and the kind's keys (module docstring).
    base : Path, optional
        Directory against which relative file paths are resolved.
    index : int, optional
        Position of the table in the ``[[fault]]`` array (for the messages).

    Raises
    ------
    FaultError
        Unknown kind or key (named with the admissible ones), a missing key, a value of the
        wrong type or out of range, an unreadable file.
    """
    index = check_count(index, "index", low=0, optional=True, error=FaultError)
    if base is not None and not isinstance(base, str | Path):
        raise FaultError(f"base must be a folder (a path), got {type(base).__name__}")
    if isinstance(table, Fault):
        return table
    if not isinstance(table, Mapping):
        raise FaultError(f"{_where({}, index)}: a fault must be a table, got "
                         f"{type(table).__name__}")
    where = _where(table, index)
    kind = table.get("kind")
    if not isinstance(kind, str) or kind not in _CLASSES:
        raise FaultError(f"{where}: unknown kind {short(kind)} (admissible: "
                         f"{', '.join(FAULT_KINDS)})" if kind is not None else
                         f"{where}: missing key 'kind' (admissible: {', '.join(FAULT_KINDS)})")
    allowed = _COMMON | _KEYS[kind]
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise FaultError(f"{where}: unknown key {short(unknown[0])} (admissible for kind = "
                         f"{short(kind)}: {', '.join(sorted(allowed))})")
    for key in ("member", *_REQUIRED[kind]):
        if key not in table:
            raise FaultError(f"{where}: missing key {short(key)}")
    kw: dict[str, Any] = {k: v for k, v in table.items()
                          if k not in ("kind", "comment", "file", "unit", "curve")}
    kw["member"] = _name(table["member"], where, "member")
    if "mate" in kw:
        kw["mate"] = _mate(kw["mate"], where)
    if "name" in kw and not isinstance(kw["name"], str):
        raise FaultError(f"{where}: name must be a string")
    if kind == "crack" and "curve" in table:
        kw["curve"] = _curve(table["curve"], where, base)
    if kind == "pitch_error":
        if "unit" in table and "file" not in table:
            raise FaultError(f"{where}: unit applies to a file only (lists are in metres)")
        if "file" in table:
            if any(k in table for k in ("single", "cumulative", "tooth", "deviation")):
                raise FaultError(f"{where}: give file or tooth/deviation, single, cumulative "
                                 "(one form)")
            f = table["file"]
            if not isinstance(f, str):
                raise FaultError(f"{where}: file must be a file name, got {short(f)}")
            unit = table.get("unit", "m")
            if not isinstance(unit, str) or unit not in _FILE_UNITS:
                raise FaultError(f"{where}: unit = {short(unit)} is not admissible (admissible: "
                                 f"{', '.join(_FILE_UNITS)})")
            path = Path(f)
            if base is not None and not path.is_absolute():
                path = base / path
            kw["cumulative"] = _read_deviation_file(path, where, unit)
            kw["source"] = str(path)
        for key in ("single", "cumulative"):
            if key in kw and not isinstance(kw[key], tuple):
                kw[key] = _deviations(kw[key], where, key)
    if kind == "pitting" and "flank" in kw and not isinstance(kw["flank"], str):
        raise FaultError(f"{where}: flank must be one of {', '.join(_FLANKS)}")
    try:
        return _CLASSES[kind](**kw)
    except FaultError as exc:
        raise FaultError(f"{where}: {exc}") from None
    except TypeError as exc:  # a wrongly typed value the dataclass could not take
        raise FaultError(f"{where}: {exc}") from None


def faults_from_list(tables: Sequence[Mapping[str, Any] | Fault] | None, *,
                     base: Path | None = None) -> tuple[Fault, ...]:
    """Descriptions of a ``[[fault]]`` array (tables or descriptions)."""
    if tables is None:
        return ()
    if isinstance(tables, Mapping | Fault) or not isinstance(tables, Sequence):
        raise FaultError("[[fault]] must be an array of tables (one per fault or error)")
    return tuple(fault_from_dict(t, base=base, index=i) for i, t in enumerate(tables))
