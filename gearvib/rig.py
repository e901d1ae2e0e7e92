"""A machine without gears: shafts and their rolling bearings (``type = "shafts"``).

A measurement need not come from a gearbox: a motor on a test bench, a fan, the CWRU bearing
rig. Describing such a machine as a gear set would give its report mesh orders and natural
frequencies of a model it does not have. A ``type = "shafts"`` description lists the shafts,
their speeds relative to the input shaft and the rolling bearings on them::

    name = "cwru-drive-end"
    type = "shafts"

    [operation]
    input = "motor"           # the shaft whose speed is the reference (default: the first)

    [[shaft]]
    name = "motor"
    # ratio = 1.0             # speed per input-shaft speed (default 1; negative: reversed)

    [[rolling_bearing]]
    name = "drive-end bearing"
    member = "motor"          # the shaft it supports; the other ring on the housing
    n_rolling = 9
    rolling_diameter = 7.94e-3
    pitch_diameter = 39.04e-3
    contact_angle_deg = 0.0

:class:`ShaftRig` gives the kinematic catalogue of the shafts' harmonics and the bearings'
defect lines (:func:`analysis.catalogue.kinematic_catalogue` with no mesh), which the
measured report checks in the envelope and order spectra. It cannot be simulated (there is
no dynamic model). ``gearvib.config.load_description`` reads either kind of description.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from analysis.catalogue import GROUND, KinematicCatalogue, RollingBearing, kinematic_catalogue
from gearvib.checks import check_items, check_real, check_text, short
from gearvib.rolling_bearings import RollingBearingSpec

__all__ = ["MAX_SHAFTS", "Shaft", "ShaftRig"]

MAX_SHAFTS = 100
"""Most shafts of a ``type = "shafts"`` description."""


@dataclass(frozen=True)
class Shaft:
    """A shaft of a rig.

    Parameters
    ----------
    name : str
        Shaft name (unique; not ``"ground"``).
    ratio : float
        Signed speed per speed of the input shaft (``1e-6 <= |ratio| <= 1e6``).
    """

    name: str
    ratio: float = 1.0

    def __post_init__(self) -> None:
        check_text(self.name, "name of a shaft")
        if self.name == GROUND:
            raise ValueError(f"name of a shaft = {self.name!r} is not admissible (the housing)")
        check_ratio(self.ratio, f"ratio of shaft {short(self.name)}")


@dataclass(frozen=True)
class ShaftRig:
    """Shafts and rolling bearings without gears (see the module docstring).

    Parameters
    ----------
    name : str
        Name of the rig.
    shafts : tuple of Shaft
        The shafts (at least one).
    input : str
        The shaft of ratio 1, whose speed the reference measures by default.
    rolling_bearings : tuple of RollingBearingSpec
        Bearings on the shafts (``member``: a shaft; ``on``: another shaft or the housing).
    title : str
        One-line description.
    config : dict
        The description it was built from.
    """

    name: str
    shafts: tuple[Shaft, ...]
    input: str
    rolling_bearings: tuple[RollingBearingSpec, ...] = ()
    title: str = ""
    config: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self) -> None:
        check_text(self.name, "name")
        object.__setattr__(self, "shafts", check_items(self.shafts, Shaft, "shafts"))
        if not 1 <= len(self.shafts) <= MAX_SHAFTS:
            raise ValueError(f"shafts: {len(self.shafts)} shafts (admissible: 1 .. {MAX_SHAFTS})")
        names = [sh.name for sh in self.shafts]
        if len(set(names)) != len(names):
            raise ValueError("shafts: every shaft needs its own name")
        check_text(self.input, "input")
        if self.input not in names:
            raise ValueError(f"input = {short(self.input)} is not a shaft of the rig "
                             f"(admissible: {short(names)})")
        object.__setattr__(self, "rolling_bearings", check_items(
            self.rolling_bearings, RollingBearingSpec, "rolling_bearings"))
        check_text(self.title, "title", empty=True)
        if not isinstance(self.config, dict):
            raise TypeError(f"config must be a dict; got {type(self.config).__name__}")

    @property
    def kinematic_ratios(self) -> dict[str, float]:
        """Signed speed of every shaft per input-shaft speed (the housing at rest)."""
        return {s.name: float(s.ratio) for s in self.shafts}

    @property
    def meta(self) -> dict[str, Any]:
        """``{"name": ..., "title": ...}`` (as an assembled model's ``meta``)."""
        return {"name": self.name, "title": self.title}

    def bearings(self) -> list[RollingBearing]:
        """The bearings with their rings on shafts or the housing (catalogue form)."""
        members: dict[str, str | None] = {s.name: None for s in self.shafts}
        return [b.resolve(members) for b in self.rolling_bearings]

    def relative_speed(self, bearing: str) -> float:
        """Speed of the inner ring relative to the outer one per input-shaft speed."""
        sp = {**self.kinematic_ratios, GROUND: 0.0}
        b = next((x for x in self.bearings() if x.name == bearing), None)
        if b is None:
            raise ValueError(f"bearing = {bearing!r} is not a bearing of the rig; admissible: "
                             f"{[x.name for x in self.rolling_bearings]}")
        return abs(sp[b.inner] - sp[b.outer])

    def catalogue(self, *, reference: str | None = None, speed_rpm: float | None = None,
                  harmonics: int = 3) -> KinematicCatalogue:
        """Shaft harmonics and bearing defect lines, in orders of ``reference``.

        Parameters
        ----------
        reference : str, optional
            Reference shaft (default :attr:`input`).
        speed_rpm : float, optional
            Reference speed [min-1] for the frequencies.
        harmonics : int
            Harmonics of every shaft and bearing line.

        Returns
        -------
        KinematicCatalogue
            Families ``shaft``, ``bearing_ftf``, ``bearing_bpfo``, ``bearing_bpfi``,
            ``bearing_bsf`` (:func:`analysis.catalogue.kinematic_catalogue`).
        """
        ref = self.input if reference is None else reference
        if ref not in self.kinematic_ratios:
            raise ValueError(f"reference = {ref!r} is not a shaft of the rig; admissible: "
                             f"{sorted(self.kinematic_ratios)}")
        return kinematic_catalogue(self.kinematic_ratios, [], reference=ref,
                                   bearings=self.bearings(), speed_rpm=speed_rpm,
                                   harmonics=harmonics, name=self.name)


def check_ratio(value: Any, where: str) -> float:
    """A shaft's speed ratio: a finite number with ``1e-6 <= |ratio| <= 1e6``."""
    v = check_real(value, where)
    if not 1e-6 <= abs(v) <= 1e6:
        raise ValueError(f"{where} = {value!r} is not admissible (admissible: 1e-6 <= |ratio| "
                         "<= 1e6, negative for a reversed shaft)")
    return v
