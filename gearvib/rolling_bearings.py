"""Rolling-bearing geometry of a gear-set description, for the catalogue's defect lines.

A ``[[rolling_bearing]]`` table names the member a bearing supports, what it is mounted on and
its geometry::

    [[rolling_bearing]]
    name = "input bearing"
    member = "sun"                # the member (shaft) the bearing supports
    # on = "ground"               # what carries the other ring: default the housing ("ground"),
    #                             # for a planet its carrier (the pin)
    rotating_race = "inner"       # the ring that turns with `member`: inner (default; "outer"
    #                             # is the default for a planet: the ring is in the planet bore)
    n_rolling = 9                 # balls or rollers, 3..1000
    rolling_diameter = 7.94e-3    # ball / roller diameter d [m], 1e-4..10, d < D
    pitch_diameter = 39.04e-3     # pitch diameter D [m], 1e-4..10
    contact_angle_deg = 0.0       # 0 <= phi < 90

The defect frequencies (:mod:`analysis.catalogue`, families ``bearing_ftf``, ``bearing_bpfo``,
``bearing_bpfi``, ``bearing_bsf``) follow from the speed of the inner ring relative to the outer
ring; the rotating race decides which member carries which ring. Formulas and sources:
``docs/catalogue-identification.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from analysis.catalogue import GROUND, RollingBearing
from gearvib.checks import short

__all__ = [
    "MAX_ROLLING",
    "RACES",
    "RollingBearingError",
    "RollingBearingSpec",
    "rolling_bearings_from_list",
]

RACES = ("inner", "outer")
"""Admissible ``rotating_race`` values."""
MAX_ROLLING = 1000
"""Most rolling elements of a bearing."""
MIN_DIAMETER, MAX_DIAMETER = 1e-4, 10.0
"""Admissible ball and pitch diameters [m]."""
_KEYS = {"name", "member", "on", "rotating_race", "n_rolling", "rolling_diameter",
         "pitch_diameter", "contact_angle_deg", "comment"}
_REQUIRED = ("name", "member", "n_rolling", "rolling_diameter", "pitch_diameter")


class RollingBearingError(ValueError):
    """An invalid ``[[rolling_bearing]]`` table (names the bearing, the key and the range)."""


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _number(value: Any, where: str, key: str, low: float, high: float, *,
            high_open: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RollingBearingError(f"{where}: {key} must be a number, got {_short(value)}")
    try:
        v = float(value)
    except OverflowError:
        v = math.inf
    ok = math.isfinite(v) and low <= v and (v < high if high_open else v <= high)
    if not ok:
        raise RollingBearingError(f"{where}: {key} = {_short(value)} is not admissible "
                                  f"(admissible: {low:g} <= {key} {'<' if high_open else '<='} "
                                  f"{high:g})")
    return v


@dataclass(frozen=True)
class RollingBearingSpec:
    """A rolling bearing of a gear set: the member it supports and its geometry.

    Parameters
    ----------
    name : str
        Bearing name (unique in the set).
    member : str
        The member the bearing supports (a body of the set).
    n_rolling : int
        Number of balls or rollers (3..1000).
    rolling_diameter, pitch_diameter : float
        Ball or roller diameter ``d`` and pitch diameter ``D`` [m] (1e-4..10, ``d < D``).
    contact_angle_deg : float
        Contact angle [deg], ``0 <= phi < 90``.
    rotating_race : {"inner", "outer"}, optional
        The ring that turns with ``member`` (default: ``"outer"`` for a planet, else
        ``"inner"``).
    on : str, optional
        The member carrying the other ring (default: a planet's carrier, else ``"ground"``, the
        housing).
    """

    name: str
    member: str
    n_rolling: int
    rolling_diameter: float
    pitch_diameter: float
    contact_angle_deg: float = 0.0
    rotating_race: str | None = None
    on: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip() or len(self.name) > 100:
            raise RollingBearingError(f"name must be a non-empty string of at most 100 "
                                      f"characters, got {_short(self.name)}")
        where = f"bearing {short(self.name)}"
        for key in ("member", "on"):
            v = getattr(self, key)
            if (v is not None or key == "member") and (not isinstance(v, str) or not v):
                raise RollingBearingError(f"{where}: {key} must name a member (a string), got "
                                          f"{_short(v)}")
        n = self.n_rolling
        if isinstance(n, bool) or not isinstance(n, int | float) or not (
                isinstance(n, int) or (math.isfinite(n) and n == int(n))) \
                or not 3 <= n <= MAX_ROLLING:
            raise RollingBearingError(f"{where}: n_rolling = {_short(n)} is not admissible "
                                      f"(admissible: an integer 3..{MAX_ROLLING})")
        object.__setattr__(self, "n_rolling", int(n))
        d = _number(self.rolling_diameter, where, "rolling_diameter", MIN_DIAMETER, MAX_DIAMETER)
        big = _number(self.pitch_diameter, where, "pitch_diameter", MIN_DIAMETER, MAX_DIAMETER)
        if d >= big:
            raise RollingBearingError(f"{where}: rolling_diameter = {d:g} m must be smaller "
                                      f"than pitch_diameter = {big:g} m")
        object.__setattr__(self, "rolling_diameter", d)
        object.__setattr__(self, "pitch_diameter", big)
        object.__setattr__(self, "contact_angle_deg", _number(
            self.contact_angle_deg, where, "contact_angle_deg", 0.0, 90.0, high_open=True))
        if self.rotating_race is not None and self.rotating_race not in RACES:
            raise RollingBearingError(f"{where}: rotating_race = {_short(self.rotating_race)} "
                                      f"is not admissible (admissible: {', '.join(RACES)})")

    def resolve(self, members: Mapping[str, str | None]) -> RollingBearing:
        """The catalogue's :class:`~analysis.catalogue.RollingBearing` (inner and outer ring
        members) for a set whose members are ``members`` (name -> carrier of a planet, None
        otherwise).

        Raises
        ------
        RollingBearingError
            ``member`` or ``on`` is not a member of the set, or both are the same.
        """
        where = f"[[rolling_bearing]] {short(self.name)}"
        names = sorted(members)
        if self.member not in members:
            raise RollingBearingError(f"{where}: member = {short(self.member)} is not a member "
                                      f"of the gear set (admissible: {', '.join(names)})")
        planet_carrier = members[self.member]
        on = self.on if self.on is not None else (planet_carrier or GROUND)
        if on != GROUND and on not in members:
            raise RollingBearingError(f"{where}: on = {short(on)} is not a member of the gear set "
                                      f"(admissible: {GROUND}, {', '.join(names)})")
        if on == self.member:
            raise RollingBearingError(f"{where}: on = {short(on)} is the member the bearing "
                                      "supports; name what carries the other ring")
        race = self.rotating_race or ("outer" if planet_carrier else "inner")
        inner, outer = (self.member, on) if race == "inner" else (on, self.member)
        return RollingBearing(self.name, inner=inner, outer=outer, n_rolling=self.n_rolling,
                              rolling_diameter=self.rolling_diameter,
                              pitch_diameter=self.pitch_diameter,
                              contact_angle_deg=self.contact_angle_deg,
                              stationary="outer" if race == "inner" else "inner")

    def to_dict(self) -> dict:
        """The ``[[rolling_bearing]]`` table of this bearing."""
        d: dict[str, Any] = {"name": self.name, "member": self.member,
                             "n_rolling": self.n_rolling,
                             "rolling_diameter": self.rolling_diameter,
                             "pitch_diameter": self.pitch_diameter,
                             "contact_angle_deg": self.contact_angle_deg}
        if self.rotating_race is not None:
            d["rotating_race"] = self.rotating_race
        if self.on is not None:
            d["on"] = self.on
        return d


def rolling_bearings_from_list(tables: Any) -> tuple[RollingBearingSpec, ...]:
    """The bearings of a ``[[rolling_bearing]]`` array (tables or specs), checked.

    Raises
    ------
    RollingBearingError
        Not an array of tables, an unknown or missing key, a value of the wrong type or out of
        range, a name used twice.
    """
    if tables is None:
        return ()
    if isinstance(tables, Mapping | str) or not isinstance(tables, Sequence):
        raise RollingBearingError("[[rolling_bearing]] must be an array of tables (one per "
                                  "bearing)")
    if len(tables) > 200:
        raise RollingBearingError(f"[[rolling_bearing]] has {len(tables)} tables (admissible: "
                                  "at most 200)")
    out = []
    for i, t in enumerate(tables):
        if isinstance(t, RollingBearingSpec):
            out.append(t)
            continue
        where = f"[[rolling_bearing]] #{i + 1}"
        if not isinstance(t, Mapping):
            raise RollingBearingError(f"{where}: must be a table, got {type(t).__name__}")
        unknown = sorted(str(k) for k in set(t) - _KEYS)
        if unknown:
            raise RollingBearingError(f"{where}: unknown key {_short(unknown[0])} (admissible: "
                                      f"{', '.join(sorted(_KEYS))})")
        missing = [k for k in _REQUIRED if k not in t]
        if missing:
            raise RollingBearingError(f"{where}: missing key {short(missing[0])}")
        kw = {k: v for k, v in t.items() if k != "comment"}
        try:
            out.append(RollingBearingSpec(**kw))
        except RollingBearingError as exc:
            raise RollingBearingError(f"{where}, {exc}") from None
    names = [b.name for b in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise RollingBearingError(f"[[rolling_bearing]]: name {short(dup[0])} is used twice")
    return tuple(out)
