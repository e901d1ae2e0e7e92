"""Kinematic frequency catalogue of a planetary (or any epicyclic) gear train.

Every frequency an engineer looks for in a gearbox spectrum follows from the tooth numbers and
the speeds of the members: shaft orders, the mesh frequency of every distinct mesh and its
harmonics, planet-pass frequencies, local-fault frequencies of suns, rings and planets,
hunting-tooth and assembly-phase frequencies, the planet-pass sidebands of the mesh harmonics
(with the planet phasing that cancels some of them at a sensor on the housing) and
rolling-bearing defect frequencies. This module computes them from plain numbers (tooth counts,
member speeds, planet angles, bearing geometry), so it serves measurements of gearboxes that
were never simulated; :mod:`gearvib.catalogue` fills it from a gear-set description.

All lines are *order-locked*: each is a fixed multiple (its ``order``) of the speed of one
reference shaft, so one catalogue gives the frequencies at any speed and along a run-up.

Conventions
-----------
Speeds are signed (one sense of rotation is positive) and given per any common unit, e.g. per
unit input speed. Tooth numbers are signed: negative for internal toothing. The member named
``"ground"`` (the housing) is always at rest. Formulas and sources:
``docs/catalogue-identification.md``.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.cf import cf_dataset
from analysis.checks import (
    require_finite,
    require_instance,
    require_positive,
    require_real,
    shown,
)

__all__ = [
    "FAMILIES",
    "GROUND",
    "KinematicCatalogue",
    "RollingBearing",
    "ToothMesh",
    "kinematic_catalogue",
    "phasing_factor",
    "simple_planetary_catalogue",
    "simple_planetary_speeds",
]

GROUND = "ground"
"""Name of the housing (always at rest)."""

FAMILIES = {
    "shaft": "rotation frequency of a member (absolute) and its harmonics",
    "mesh": "tooth-mesh frequency of a distinct mesh, z |n_gear - n_carrier|, and harmonics",
    "planet_pass": "planets passing the sensor, N |n_carrier - n_sensor|, and harmonics",
    "sun_fault": "local fault on a sun (external central gear): N |n_sun - n_carrier|",
    "ring_fault": "local fault on a ring (internal central gear): N |n_ring - n_carrier|",
    "planet_fault": "local fault on a planet tooth: |n_planet - n_carrier| = f_mesh / z_p per "
                    "partner (harmonic 2: both flanks, or sun and ring)",
    "gear_fault": "local fault on a gear turning on a fixed axis (a parallel stage, a carrier "
                  "at rest): N |n_gear| with N its mates (pinion and wheel: once per "
                  "revolution; an idler: harmonic 2, both mates)",
    "hunting_tooth": "same tooth pair meets again: f_mesh gcd(z1, z2) / (z1 z2)",
    "assembly_phase": "assembly-phase frequency f_mesh / gcd(z1, z2) (listed when gcd > 1)",
    "sideband": "m f_mesh + s f_c: carrier-order sidebands of mesh harmonic m (s in carrier "
                "revolutions relative to the sensor; s = k N is m f_mesh + k f_pp)",
    "shaft_sideband": "m f_mesh ± k |n_gear|: sidebands of a fixed-axis mesh (parallel stage) at "
                      "the rotation of its gears, k = 1 .. sidebands (local fault, runout)",
    "eccentricity": "m f_mesh ± f_r: first sidebands of mesh harmonic m at the rotation of a "
                    "gear of the mesh relative to the carrier and relative to the sensor "
                    "(eccentricity, runout; the carrier's own ±f_c are sidebands s = ±1)",
    "bearing_ftf": "rolling bearing: cage frequency relative to the stationary (loaded) ring",
    "bearing_bpfo": "rolling bearing: ball pass frequency, outer race",
    "bearing_bpfi": "rolling bearing: ball pass frequency, inner race",
    "bearing_bsf": "rolling bearing: ball (roller) spin frequency",
}
"""Family names of the catalogue with their meaning."""

_TRAILING_DIGITS = re.compile(r"\d+$")


@dataclass(frozen=True)
class ToothMesh:
    """A tooth contact between a gear and a planet that sits on a carrier.

    Parameters
    ----------
    name : str
        Mesh name, e.g. ``"sun-planet1"``.
    gear : str
        Central member (sun, ring) or the first planet of a planet-planet mesh.
    planet : str
        The planet.
    z_gear, z_planet : int
        Signed tooth numbers (negative: internal toothing).
    carrier : str
        The carrier the planet sits on.
    """

    name: str
    gear: str
    planet: str
    z_gear: int
    z_planet: int
    carrier: str

    def __post_init__(self) -> None:
        for attr in ("z_gear", "z_planet"):
            z = getattr(self, attr)
            if isinstance(z, bool) or int(z) != z or z == 0:
                raise ValueError(f"mesh {self.name!r}: {attr} = {z!r} is not admissible: a "
                                 "non-zero integer (negative for internal toothing)")


@dataclass(frozen=True)
class RollingBearing:
    """Geometry of a rolling bearing and the members carrying its rings.

    Parameters
    ----------
    name : str
        Bearing name, e.g. ``"planet bearing"``.
    inner, outer : str
        Members carrying the inner and the outer ring (``"ground"`` for the housing). For a
        planet bearing: inner = the carrier (pin), outer = a planet.
    n_rolling : int
        Number of balls or rollers (>= 3).
    rolling_diameter : float
        Ball or roller diameter ``d`` [m].
    pitch_diameter : float
        Pitch diameter ``D`` [m] (> d).
    contact_angle_deg : float
        Contact angle ``phi`` [deg], 0 <= phi < 90.
    stationary : {"outer", "inner"}
        The ring that stands still relative to the load (the housing's ring of a shaft
        bearing: ``"outer"``; the pin of a planet bearing: ``"inner"``). The cage frequency
        FTF is counted relative to it: ``f_r (1 - gamma)/2`` for a stationary outer ring,
        ``f_r (1 + gamma)/2`` for a stationary inner ring (outer race rotating).
    """

    name: str
    inner: str
    outer: str
    n_rolling: int
    rolling_diameter: float
    pitch_diameter: float
    contact_angle_deg: float = 0.0
    stationary: str = "outer"

    def __post_init__(self) -> None:
        n = self.n_rolling
        if isinstance(n, bool) or int(n) != n or n < 3:
            raise ValueError(f"bearing {self.name!r}: n_rolling = {n!r} is not admissible: an "
                             "integer >= 3")
        d = require_positive(self.rolling_diameter, f"bearing {self.name!r} rolling_diameter")
        big = require_positive(self.pitch_diameter, f"bearing {self.name!r} pitch_diameter")
        if d >= big:
            raise ValueError(f"bearing {self.name!r}: rolling_diameter = {d!r} m must be smaller "
                             f"than pitch_diameter = {big!r} m")
        a = float(self.contact_angle_deg)
        if not (math.isfinite(a) and 0.0 <= a < 90.0):
            raise ValueError(f"bearing {self.name!r}: contact_angle_deg = {a!r} is not "
                             "admissible: 0 <= angle < 90")
        if self.stationary not in ("outer", "inner"):
            raise ValueError(f"bearing {self.name!r}: stationary = {self.stationary!r} is not "
                             "admissible: 'outer' or 'inner'")

    @property
    def ratio(self) -> float:
        """``gamma = d / D cos(phi)``."""
        return (self.rolling_diameter / self.pitch_diameter
                * math.cos(math.radians(self.contact_angle_deg)))


def phasing_factor(angles_rad: Sequence[float], index: int) -> float:
    """``|sum_n exp(i index psi_n)| / N``: how much of a carrier order survives the phasing.

    Parameters
    ----------
    angles_rad : sequence of float
        Planet angles ``psi_n`` [rad] on the carrier.
    index : int
        Circular index, ``q - m z_gear`` for carrier order ``q`` around mesh harmonic ``m``.

    Returns
    -------
    float
        1 for an index divisible by ``N`` with equally spaced planets, 0 for every other index
        (McFadden & Smith 1985); between 0 and 1 for unequal spacing.
    """
    psi = np.asarray(angles_rad, dtype=float)
    if psi.size == 0:
        return float("nan")
    v = abs(np.exp(1j * index * psi).sum()) / psi.size
    return 0.0 if v < 1e-9 else min(float(v), 1.0)


# ------------------------------------------------------------------------------- result


@dataclass(frozen=True)
class KinematicCatalogue:
    """The catalogue: one row per line (see :func:`kinematic_catalogue`).

    Attributes
    ----------
    family, member, formula : ndarray of str
        Line family (:data:`FAMILIES`), source member or mesh, formula.
    harmonic, sideband : ndarray of int
        Harmonic number and sideband index (carrier orders relative to the sensor; 0 if none).
    order : ndarray
        Frequency as an order of the reference shaft (cycles per reference revolution).
    phasing : ndarray
        Planet-phasing factor at a sensor on ``sensor`` (1 passes, 0 cancelled for equally
        spaced planets; NaN: not a planet-phased line).
    reference : str
        Reference shaft.
    sensor : str
        Member the sensor is fixed to.
    speed_rpm : float or None
        Reference speed of :attr:`frequency_hz` [min-1].
    speeds_rpm : ndarray or None
        Reference speeds of a run-up [min-1].
    member_speeds : dict
        Signed member speeds per unit reference speed.
    notes : tuple of str
        Remarks (skipped lines, assumptions).
    """

    family: np.ndarray
    harmonic: np.ndarray
    sideband: np.ndarray
    member: np.ndarray
    formula: np.ndarray
    order: np.ndarray
    phasing: np.ndarray
    reference: str
    sensor: str
    speed_rpm: float | None = None
    speeds_rpm: np.ndarray | None = None
    member_speeds: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    name: str = ""

    def __len__(self) -> int:
        return int(self.order.size)

    @property
    def visible(self) -> np.ndarray:
        """True for lines a sensor on :attr:`sensor` can see (phasing factor > 0 or n/a)."""
        return ~(self.phasing == 0.0)

    def frequency_hz(self, speed_rpm: float | None = None) -> np.ndarray:
        """Line frequencies [Hz] at a reference speed [min-1] (default :attr:`speed_rpm`)."""
        sp = self.speed_rpm if speed_rpm is None else speed_rpm
        if sp is None:
            raise ValueError("speed_rpm is needed: the catalogue has no reference speed")
        return self.order * abs(float(sp)) / 60.0

    def hz_per_rpm(self) -> np.ndarray:
        """Line frequency per reference speed [Hz per min-1]."""
        return self.order / 60.0

    def select(self, *, families: Iterable[str] | None = None, visible_only: bool = False,
               max_order: float | None = None) -> KinematicCatalogue:
        """Subset of the lines.

        Parameters
        ----------
        families : iterable of str, optional
            Keep these families.
        visible_only : bool
            Drop lines the planet phasing cancels at the sensor.
        max_order : float, optional
            Drop lines above this order.
        """
        keep = np.ones(len(self), dtype=bool)
        if families is not None:
            fams = set(families)
            unknown = fams - set(FAMILIES)
            if unknown:
                raise ValueError(f"families: unknown {sorted(unknown)}; admissible: "
                                 f"{', '.join(FAMILIES)}")
            keep &= np.isin(self.family, sorted(fams))
        if visible_only:
            keep &= self.visible
        if max_order is not None:
            keep &= self.order <= float(max_order)
        return self._subset(keep)

    def _subset(self, keep: np.ndarray) -> KinematicCatalogue:
        kw = {k: getattr(self, k)[keep] for k in ("family", "harmonic", "sideband", "member",
                                                  "formula", "order", "phasing")}
        return KinematicCatalogue(**kw, reference=self.reference, sensor=self.sensor,
                                  speed_rpm=self.speed_rpm, speeds_rpm=self.speeds_rpm,
                                  member_speeds=self.member_speeds, notes=self.notes,
                                  name=self.name)

    def to_dataset(self):
        """The catalogue as :class:`xarray.Dataset` (dimension ``line``, CF attributes).

        Variables: ``family``, ``harmonic``, ``sideband``, ``member``, ``formula``, ``order``,
        ``phasing``, ``housing_visible``, ``frequency`` [Hz] (with a reference speed) and
        ``frequency_runup(line, speed)`` [Hz] (with run-up speeds).
        """
        import xarray as xr

        def v(x, units, long_name):
            return ("line", x, {"units": units, "long_name": long_name})

        data = {
            "family": v(self.family.astype(str), "1", "line family"),
            "harmonic": v(self.harmonic, "1", "harmonic number"),
            "sideband": v(self.sideband, "1", "sideband index (carrier revolutions relative to "
                                              "the sensor; 0 if none)"),
            "member": v(self.member.astype(str), "1", "source member or mesh"),
            "formula": v(self.formula.astype(str), "1", "formula"),
            "order": v(self.order, "1", f"order of the reference shaft {self.reference}"),
            "phasing": v(self.phasing, "1", f"planet-phasing factor at a sensor on "
                                            f"{self.sensor} (NaN: not applicable)"),
            "housing_visible": v(self.visible.astype(np.int8), "1",
                                 f"1 if a sensor on {self.sensor} can see the line"),
        }
        coords: dict[str, Any] = {"line": ("line", np.arange(len(self)),
                                           {"units": "1", "long_name": "line index"})}
        if self.speed_rpm is not None:
            data["frequency"] = v(self.frequency_hz(), "Hz",
                                  f"frequency at {self.reference} speed {self.speed_rpm:g} min-1")
        if self.speeds_rpm is not None:
            sp = np.asarray(self.speeds_rpm, dtype=float)
            coords["speed"] = ("speed", sp, {"units": "min-1",
                                             "long_name": f"speed of {self.reference}"})
            data["frequency_runup"] = (("line", "speed"),
                                       self.order[:, None] * np.abs(sp)[None, :] / 60.0,
                                       {"units": "Hz", "long_name": "frequency along the run-up"})
        attrs = {
            "Conventions": "CF-1.11",
            "title": f"kinematic frequency catalogue {self.name}".strip(),
            "reference": self.reference,
            "sensor": self.sensor,
            "member_speeds_json": json.dumps(self.member_speeds, sort_keys=True),
            "families_json": json.dumps(FAMILIES, sort_keys=True),
            "notes": " | ".join(self.notes),
        }
        if self.speed_rpm is not None:
            attrs["reference_speed_rpm"] = float(self.speed_rpm)
        ds = xr.Dataset(data, coords=coords, attrs=attrs)
        return cf_dataset(ds, title="kinematic frequency catalogue",
                          producer="analysis.catalogue.kinematic_catalogue")

    def to_dict(self, *, visible_only: bool = True) -> dict:
        """``{"reference": {...}, "lines": [{family, harmonic, sideband, member,
        frequency_hz, order, phasing}, ...]}`` (the JSON of ``gearvib catalogue --json``;
        ``phasing`` is the planet-phasing factor at the sensor, ``null`` where it does not
        apply).

        Parameters
        ----------
        visible_only : bool
            Leave out the lines the planet phasing cancels at the sensor.
        """
        cat = self.select(visible_only=visible_only)
        f = cat.frequency_hz() if cat.speed_rpm is not None else np.full(len(cat), np.nan)
        lines = [{"family": str(cat.family[i]), "harmonic": int(cat.harmonic[i]),
                  "sideband": int(cat.sideband[i]), "member": str(cat.member[i]),
                  "frequency_hz": None if not np.isfinite(f[i]) else float(f[i]),
                  "order": float(cat.order[i]),
                  "phasing": None if not np.isfinite(cat.phasing[i]) else float(cat.phasing[i])}
                 for i in range(len(cat))]
        return {"reference": {"member": self.reference,
                              "speed_rpm": None if self.speed_rpm is None
                              else float(self.speed_rpm)},
                "lines": lines}

    def to_json(self, *, visible_only: bool = True) -> str:
        """:meth:`to_dict` as a JSON string."""
        return json.dumps(self.to_dict(visible_only=visible_only), indent=1)

    def table(self, *, visible_only: bool = False) -> str:
        """Plain-text table (one line per row)."""
        cat = self.select(visible_only=visible_only)
        has_f = cat.speed_rpm is not None
        head = (f"{'family':14} {'h':>2} {'sb':>3} {'member':28} {'order':>10} "
                + (f"{'f [Hz]':>10} " if has_f else "") + f"{'phasing':>7}  formula")
        rows = [f"reference: {self.reference}"
                + (f" at {self.speed_rpm:g} min-1" if has_f else "")
                + f"; sensor on {self.sensor}", head]
        f = cat.frequency_hz() if has_f else None
        for i in range(len(cat)):
            ph = "" if np.isnan(cat.phasing[i]) else f"{cat.phasing[i]:.3f}"
            rows.append(f"{cat.family[i]:14} {cat.harmonic[i]:2d} {cat.sideband[i]:3d} "
                        f"{str(cat.member[i])[:28]:28} {cat.order[i]:10.4f} "
                        + (f"{f[i]:10.2f} " if f is not None else "")
                        + f"{ph:>7}  {cat.formula[i]}")
        rows += [f"note: {n}" for n in self.notes]
        return "\n".join(rows)

    def __str__(self) -> str:
        return self.table()

    def plot(self, speed_rpm: float | None = None, *, families: Iterable[str] | None = None,
             frequency_max: float | None = None, ax: Any = None):
        """Stem chart of the lines at one speed, one colour per family.

        Lines the planet phasing cancels at the sensor are drawn dotted and grey.

        Parameters
        ----------
        speed_rpm : float, optional
            Reference speed [min-1] (default :attr:`speed_rpm`).
        families : iterable of str, optional
            Families to draw (default all).
        frequency_max : float, optional
            Upper frequency [Hz].
        ax : matplotlib Axes, optional
        """
        if ax is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(9, 4.5), layout="constrained")
            ax = fig.add_subplot()
        else:
            fig = ax.figure
        cat = self.select(families=families) if families is not None else self
        f = cat.frequency_hz(speed_rpm)
        fams = [k for k in FAMILIES if k in set(cat.family)]
        for j, fam in enumerate(fams):
            m = cat.family == fam
            vis = m & cat.visible
            y = len(fams) - j
            ax.vlines(f[vis], y - 0.4, y + 0.4, color=f"C{j % 10}", lw=1.0, label=fam)
            hid = m & ~cat.visible
            if hid.any():
                ax.vlines(f[hid], y - 0.4, y + 0.4, color="0.6", lw=0.8, ls=":")
        ax.set_yticks(range(1, len(fams) + 1), fams[::-1], fontsize=7)
        ax.set_ylim(0.4, len(fams) + 0.6)
        ax.set_xlim(0, frequency_max or (float(f.max()) * 1.02 if f.size else 1.0))
        ax.set_xlabel("frequency [Hz]")
        sp = self.speed_rpm if speed_rpm is None else speed_rpm
        title = f"kinematic catalogue{' of ' + self.name if self.name else ''}"
        ax.set_title(f"{title}: {self.reference} at {sp:g} min⁻¹\n(dotted grey: cancelled by "
                     f"the planet phasing at a sensor on the {self.sensor})", fontsize=9)
        ax.grid(True, axis="x", alpha=0.3)
        return fig


# ------------------------------------------------------------------------------- builder


def _group_name(names: Sequence[str]) -> str:
    stems = sorted({_TRAILING_DIGITS.sub("", n) or n for n in names})
    return stems[0] if len(stems) == 1 else "/".join(sorted(names))


def _pair_label(gear: str, planet: str) -> str:
    """``"s1.sun-planet"`` for ``("s1.sun", "s1.planet")``, ``"sun-planet"`` otherwise."""
    if "." in gear and "." in planet:
        pg, pp = gear.rsplit(".", 1)[0], planet.rsplit(".", 1)[0]
        if pg == pp:
            return f"{gear}-{planet.rsplit('.', 1)[1]}"
    return f"{gear}-{planet}"


def _int_param(value: Any, name: str, low: int) -> int:
    if isinstance(value, bool) or int(value) != value or value < low:
        raise ValueError(f"{name} = {value!r} is not admissible: an integer >= {low}")
    return int(value)


@dataclass
class _Rows:
    rows: list = field(default_factory=list)

    def add(self, family: str, harmonic: int, sideband: int, member: str, formula: str,
            rate: float, phasing: float = float("nan")) -> None:
        self.rows.append((family, harmonic, sideband, member, formula, abs(rate), phasing))


def kinematic_catalogue(
    speeds: Mapping[str, float],
    meshes: Sequence[ToothMesh],
    *,
    reference: str,
    planet_angles_deg: Mapping[str, float] | None = None,
    fixed: str | Sequence[str] = (),
    sensor: str | None = None,
    bearings: Sequence[RollingBearing] = (),
    speed_rpm: float | None = None,
    speeds_rpm: Any = None,
    mesh_harmonics: int = 7,
    harmonics: int = 3,
    sidebands: int = 2,
    name: str = "",
) -> KinematicCatalogue:
    """Kinematic frequency catalogue of a gear train from plain numbers.

    Parameters
    ----------
    speeds : mapping of str to float
        Signed speed of every member (central gears, carriers, planets) in a common unit, e.g.
        per unit input speed. ``"ground"`` is at rest and need not be given.
    meshes : sequence of ToothMesh
        Every tooth contact (gear, planet, signed tooth numbers, carrier).
    reference : str
        The shaft whose revolutions count the orders (e.g. the input, where the tacho is).
    planet_angles_deg : mapping of str to float, optional
        Angle of every planet on its carrier [deg]; needed for the planet-phasing factors.
    fixed : str or sequence of str
        Members held at rest (checked: their speed must be 0).
    sensor : str, optional
        Member the vibration sensor is fixed to (default: the first fixed member, else
        ``"ground"``); planet pass and sidebands count carrier revolutions relative to it.
    bearings : sequence of RollingBearing
        Rolling bearings with geometry.
    speed_rpm : float, optional
        Speed of the reference shaft [min-1] for the ``frequency`` column.
    speeds_rpm : array_like, optional
        Reference speeds of a run-up [min-1] for ``frequency_runup``.
    mesh_harmonics : int
        Mesh harmonics listed (``m = 1..mesh_harmonics``); sidebands are listed around each.
    harmonics : int
        Harmonics of shaft, planet-pass, fault and bearing lines.
    sidebands : int
        Sidebands up to ``sidebands`` planet-pass frequencies, i.e. ``|s| <= sidebands N``
        carrier orders, around every mesh harmonic; around a fixed-axis mesh up to
        ``sidebands`` orders of each of its gears.
    name : str
        Name of the gear train (for titles).

    Returns
    -------
    KinematicCatalogue

    Notes
    -----
    With ``n`` the signed speeds (``n_ground = 0``), ``N`` the planets on a carrier and
    ``f_ref = |n_reference|`` (see ``docs/catalogue-identification.md`` for sources):

    * shaft: ``h |n_member|``; planets are listed once per group of identical planets;
    * mesh: ``m |z_gear (n_gear - n_carrier)|``; meshes with the same frequency on one carrier
      (sun and ring meshes of one planet toothing) are one line;
    * planet_pass: ``h N |n_carrier - n_sensor|``;
    * sun_fault / ring_fault: ``h N |n_gear - n_carrier|`` for external / internal gears;
    * planet_fault: ``h |n_planet - n_carrier|`` (= ``h f_mesh / |z_planet|``);
    * gear_fault (gears of a carrier at rest: parallel stages, where the pinion is the central
      gear and the wheel the "planet"; a star set): ``h N |n_gear|`` for a central gear with
      ``N`` planets, ``h |n_gear|`` for a gear on a pin of the carrier. These replace sun_fault,
      ring_fault and planet_fault there;
    * shaft_sideband (meshes of a carrier at rest): ``m f_mesh ± k |n_gear|`` for every gear of
      the mesh, ``k = 1 .. sidebands``;
    * eccentricity: ``m f_mesh ± |n_gear - n_carrier|`` and ``m f_mesh ± |n_gear - n_sensor|``
      for every gear of a mesh (central gears and planet groups; rates equal to the carrier
      sidebands ``± |Omega|`` or to each other listed once), sideband index ``±1``;
    * hunting_tooth: ``f_mesh g / (|z_gear| |z_planet|)``, assembly_phase ``f_mesh / g``,
      ``g = gcd(z_gear, z_planet)``;
    * sideband: ``|m h_s + q Omega|`` with the signed mesh rate ``h_s = z_gear (n_gear -
      n_carrier)`` and ``Omega = n_carrier - n_sensor``; the listed index is
      ``s = q sign(h_s Omega)`` so that ``f = m f_mesh + s |Omega|``. The planet-phasing factor
      is ``|sum_n exp(i (q - m z_gear) psi_n)| / N``: with identical planets each planet's mesh
      vibration carries the phase ``-m z_gear psi_n`` and reaches the sensor through the same
      angle-dependent path, so for equally spaced planets only ``q - m z_gear`` divisible by
      ``N`` survives (McFadden & Smith 1985). The factor is also given for the mesh lines
      (``q = 0``) and the planet-pass lines;
    * bearings (relative speed ``f_r = |n_inner - n_outer|``, ``gamma = d/D cos phi``):
      FTF ``f_r (1 - gamma)/2`` relative to a stationary outer ring (``f_r (1 + gamma)/2``
      relative to a stationary inner ring), BPFO ``Z f_r (1 - gamma)/2``, BPFI
      ``Z f_r (1 + gamma)/2``, BSF ``D f_r (1 - gamma^2)/(2 d)``.

    Orders are ``rate / f_ref``. Lines with zero frequency (e.g. the planet pass of a fixed
    carrier) are left out, with a note.
    """
    require_instance(speeds, Mapping, "speeds")
    for name, items, cls in (("meshes", meshes, ToothMesh), ("bearings", bearings,
                                                            RollingBearing)):
        if isinstance(items, str) or not isinstance(items, Sequence):
            raise TypeError(f"{name} must be a sequence of {cls.__name__}; got "
                            f"{type(items).__name__}")
        for k, item in enumerate(items):
            require_instance(item, cls, f"{name}[{k}]")
    for sk, v in speeds.items():
        require_real(v, f"speeds[{sk!r}]")
    sp = {str(k): float(v) for k, v in dict(speeds).items()}
    for sk, v in sp.items():
        if not math.isfinite(v):
            raise ValueError(f"speeds[{sk!r}] = {v!r} is not admissible: finite")
    if GROUND in sp and sp[GROUND] != 0.0:
        raise ValueError(f"speeds[{GROUND!r}] must be 0 (the housing is at rest)")
    sp[GROUND] = 0.0
    if reference not in sp:
        raise ValueError(f"reference = {shown(reference)} is not a member with a speed (members: "
                         f"{', '.join(sorted(sp))})")
    f_ref = abs(sp[reference])
    if f_ref == 0.0:
        raise ValueError(f"reference = {shown(reference)} is at rest; choose a rotating shaft")
    fixed_list = [fixed] if isinstance(fixed, str) else list(fixed)
    for f in fixed_list:
        if f not in sp:
            raise ValueError(f"fixed member {f!r} has no speed in speeds")
        if abs(sp[f]) > 1e-12 * max(abs(v) for v in sp.values()):
            raise ValueError(f"fixed member {f!r} has speed {sp[f]!r}; a fixed member is at "
                             "rest")
    sensor = sensor if sensor is not None else (fixed_list[0] if fixed_list else GROUND)
    if sensor not in sp:
        raise ValueError(f"sensor = {shown(sensor)} is not a member with a speed")
    mesh_harmonics = _int_param(mesh_harmonics, "mesh_harmonics", 1)
    harmonics = _int_param(harmonics, "harmonics", 1)
    sidebands = _int_param(sidebands, "sidebands", 0)
    meshes = list(meshes)
    for m in meshes:
        for member in (m.gear, m.planet, m.carrier):
            if member not in sp:
                raise ValueError(f"mesh {m.name!r}: member {member!r} has no speed in speeds")
    angles = {str(k): math.radians(float(v)) for k, v in dict(planet_angles_deg or {}).items()}
    for ak, a in angles.items():
        if not math.isfinite(a):
            raise ValueError(f"planet_angles_deg[{ak!r}] is not finite")
    sref = require_positive(speed_rpm, "speed_rpm", allow_zero=True) if speed_rpm is not None \
        else None
    run = None
    if speeds_rpm is not None:
        run = require_finite(speeds_rpm, "speeds_rpm").ravel()
        if np.any(run < 0):
            raise ValueError("speeds_rpm must be >= 0 min-1 (speeds of the reference shaft)")
    notes: list[str] = []
    scale = max(abs(v) for v in sp.values())
    tiny = 1e-12 * scale
    out = _Rows()

    # ---- planet groups: identical planets on one carrier with the same speed -------------------
    planets = sorted({m.planet for m in meshes})
    gears_of: dict[str, set] = {p: set() for p in planets}
    for m in meshes:
        gears_of[m.planet].add((m.gear, m.z_gear, m.z_planet))
        if m.gear in gears_of:  # planet-planet mesh: the first planet also meshes
            gears_of[m.gear].add((m.planet, m.z_planet, m.z_gear))
    carrier_of = {m.planet: m.carrier for m in meshes}
    groups: dict[tuple, list[str]] = {}
    for p in planets:
        partner_gears = tuple(sorted((_TRAILING_DIGITS.sub("", g), zg, zp)
                                     for g, zg, zp in gears_of[p]))
        key = next((k for k in groups if k[0] == carrier_of[p] and k[2] == partner_gears
                    and abs(k[1] - sp[p]) <= 1e-7 * scale),
                   (carrier_of[p], sp[p], partner_gears))
        groups.setdefault(key, []).append(p)
    group_of = {p: _group_name(ps) for ps in groups.values() for p in ps}
    members_of_group = {_group_name(ps): ps for ps in groups.values()}

    # ---- shaft ----------------------------------------------------------------------------------
    planet_set = set(planets)
    shafts = [k for k in sp if k != GROUND and k not in planet_set]
    shafts += list(members_of_group)
    for shaft in shafts:
        n = sp[members_of_group[shaft][0]] if shaft in members_of_group else sp[shaft]
        if abs(n) <= tiny:
            continue
        for h in range(1, harmonics + 1):
            out.add("shaft", h, 0, shaft, f"{h} f_{shaft}" if h > 1 else f"f_{shaft}", h * n)

    # ---- meshes grouped by carrier and frequency ---------------------------------------------
    mgroups: dict[tuple, list[ToothMesh]] = {}
    for m in meshes:
        rate = abs(m.z_gear * (sp[m.gear] - sp[m.carrier]))
        # meshes of one carrier whose frequencies agree to 1e-7 (speeds come from a numerical
        # null space) are one line
        key = next((k for k in mgroups if k[0] == m.carrier
                    and abs(k[1] - rate) <= 1e-7 * max(rate, k[1], tiny)), (m.carrier, rate))
        mgroups.setdefault(key, []).append(m)
    central_gears = {m.gear for m in meshes if m.gear not in planet_set}
    # carriers at rest: their gears turn on fixed axes (a parallel stage's housing, a star set)
    at_rest = {m.carrier for m in meshes if abs(sp[m.carrier]) <= tiny}
    for (carrier, _), ms in mgroups.items():
        central = [m for m in ms if m.gear in central_gears]
        # the phasing follows one central gear and its planets: the internal one (the ring,
        # which carries the transmission path to the housing) when the group has it
        central.sort(key=lambda m: (m.z_gear > 0, m.gear))
        m0 = central[0] if central else ms[0]
        h_signed = m0.z_gear * (sp[m0.gear] - sp[m0.carrier])
        f_mesh = abs(h_signed)
        labels = []
        for m in ms:
            lab = _pair_label(group_of.get(m.gear, m.gear), group_of[m.planet])
            if lab not in labels:
                labels.append(lab)
        label = "/".join(labels)
        if f_mesh <= tiny:
            notes.append(f"mesh {label}: the gears do not turn relative to the carrier "
                         "(no mesh frequency)")
            continue
        set_planets = sorted({m.planet for m in central if m.gear == m0.gear}
                             or {m.planet for m in ms})
        psi = [angles[p] for p in set_planets if p in angles]
        have_phase = len(psi) == len(set_planets) and bool(central)
        omega = sp[carrier] - sp[sensor]
        for mh in range(1, mesh_harmonics + 1):
            ph = phasing_factor(psi, -mh * m0.z_gear) if have_phase else float("nan")
            out.add("mesh", mh, 0, label, "f_mesh" if mh == 1 else f"{mh} f_mesh",
                    mh * f_mesh, ph)
        # sidebands of the mesh harmonics, spaced by the carrier speed relative to the sensor
        n_pl = len(set_planets)
        if abs(omega) > tiny and sidebands and central:
            sgn = 1 if h_signed * omega > 0 else -1
            for mh in range(1, mesh_harmonics + 1):
                for s in range(-sidebands * n_pl, sidebands * n_pl + 1):
                    if s == 0:
                        continue
                    q = s * sgn
                    rate = mh * f_mesh + s * abs(omega)
                    if rate <= tiny:
                        continue
                    ph = phasing_factor(psi, q - mh * m0.z_gear) if have_phase \
                        else float("nan")
                    whole, rest = divmod(abs(s), n_pl)
                    sign = "+" if s > 0 else "−"
                    term = (f"{whole if whole > 1 else ''}{' ' if whole > 1 else ''}f_pp"
                            if rest == 0 else f"{abs(s)} f_c")
                    head = "f_mesh" if mh == 1 else f"{mh} f_mesh"
                    out.add("sideband", mh, s, label, f"{head} {sign} {term}", rate, ph)
        # eccentricity (runout) of a gear of the mesh: its rotation relative to the carrier
        # modulates the mesh (m f_mesh ± |n_g - n_c|); the planet-pass window shifts that by
        # the carrier speed, which gives its rotation relative to the sensor too
        ecc_members: dict[str, float] = {}
        for m in ms:
            for gm in (m.gear, m.planet):
                ecc_members.setdefault(group_of.get(gm, gm), sp[gm])
        for gname, n_g in ecc_members.items():
            rates: list[tuple[float, str]] = []
            rel_txt = f"f_{gname}" if carrier in at_rest else f"|f_{gname} − f_{carrier}|"
            for r, txt in ((abs(n_g - sp[carrier]), rel_txt),
                           (abs(n_g - sp[sensor]), f"f_{gname}" if sp[sensor] == 0.0
                            else f"|f_{gname} − f_{sensor}|")):
                if r > tiny and all(abs(r - q) > 1e-9 * scale for q, _ in rates) \
                        and abs(r - abs(omega)) > 1e-9 * scale:
                    rates.append((r, txt))
            for mh in range(1, mesh_harmonics + 1):
                head = "f_mesh" if mh == 1 else f"{mh} f_mesh"
                for r, txt in rates:
                    for sgn in (-1, 1):
                        rate = mh * f_mesh + sgn * r
                        if rate > tiny:
                            out.add("eccentricity", mh, sgn, gname,
                                    f"{head} {'+' if sgn > 0 else '−'} {txt}", rate)
        # a fixed-axis mesh: a local fault or runout of a gear modulates it at the gear's
        # rotation, sidebands k = 1 .. sidebands on either side
        if carrier in at_rest and sidebands:
            for gname, n_g in ecc_members.items():
                if abs(n_g) <= tiny:
                    continue
                for mh in range(1, mesh_harmonics + 1):
                    head = "f_mesh" if mh == 1 else f"{mh} f_mesh"
                    for k in range(1, sidebands + 1):
                        for sgn in (-1, 1):
                            rate = mh * f_mesh + sgn * k * abs(n_g)
                            if rate > tiny:
                                out.add("shaft_sideband", mh, sgn * k, gname,
                                        f"{head} {'+' if sgn > 0 else '−'} "
                                        f"{k if k > 1 else ''}{' ' if k > 1 else ''}f_{gname}",
                                        rate)
        # hunting tooth and assembly phase of every distinct tooth pair in the group
        pairs = sorted({(abs(m.z_gear), abs(m.z_planet), _pair_label(
            group_of.get(m.gear, m.gear), group_of[m.planet])) for m in ms})
        for z1, z2, lab in pairs:
            g = math.gcd(z1, z2)
            out.add("hunting_tooth", 1, 0, lab, f"f_mesh·{g}/({z1}·{z2})" if g > 1
                    else f"f_mesh/({z1}·{z2})", f_mesh * g / (z1 * z2))
            if g > 1:
                out.add("assembly_phase", 1, 0, lab, f"f_mesh/{g}", f_mesh / g)

    # ---- planet pass, central-gear and planet faults ------------------------------------------
    carriers = sorted({m.carrier for m in meshes})
    for c in carriers:
        omega = sp[c] - sp[sensor]
        for gname, ps in members_of_group.items():
            if carrier_of[ps[0]] != c:
                continue
            n_pl = len(ps)
            psi = [angles[p] for p in ps if p in angles]
            if abs(omega) <= tiny:
                if not (c in at_rest and n_pl == 1):  # not for a gear on a fixed axis
                    notes.append(f"carrier {c} does not turn relative to the sensor on "
                                 f"{sensor}: no planet pass of {gname}")
            else:
                for h in range(1, harmonics + 1):
                    ph = phasing_factor(psi, h * n_pl) if len(psi) == n_pl else float("nan")
                    out.add("planet_pass", h, 0, gname,
                            (f"{h} " if h > 1 else "") + f"N f_c (N = {n_pl})",
                            h * n_pl * omega, ph)
            rel = sp[ps[0]] - sp[c]
            z_p = sorted({abs(zp) for _, _, zp in gears_of[ps[0]]})
            if abs(rel) > tiny:
                zs = "/".join(str(z) for z in z_p)
                for h in range(1, harmonics + 1):
                    if c in at_rest:
                        out.add("gear_fault", h, 0, gname, f"{h} f_{gname}" if h > 1
                                else f"f_{gname}", h * rel)
                        continue
                    out.add("planet_fault", h, 0, gname,
                            f"{h} f_mesh/z_p (z_p = {zs})" if h > 1
                            else f"f_mesh/z_p (z_p = {zs})", h * rel)
    done: set = set()
    for m in meshes:
        if m.gear not in central_gears or (m.gear, m.carrier) in done:
            continue
        done.add((m.gear, m.carrier))
        n_pl = len({x.planet for x in meshes if x.gear == m.gear and x.carrier == m.carrier})
        rel = sp[m.gear] - sp[m.carrier]
        if abs(rel) <= tiny:
            continue
        if m.carrier in at_rest:
            for h in range(1, harmonics + 1):
                out.add("gear_fault", h, 0, m.gear, (f"{h * n_pl} " if h * n_pl > 1 else "")
                        + f"f_{m.gear}" + (f" (N = {n_pl} mates)" if n_pl > 1 else ""),
                        h * n_pl * rel)
            continue
        fam = "sun_fault" if m.z_gear > 0 else "ring_fault"
        for h in range(1, harmonics + 1):
            out.add(fam, h, 0, m.gear, (f"{h} " if h > 1 else "") + f"N |f_{m.gear} − f_c| "
                    f"(N = {n_pl})", h * n_pl * rel)

    # ---- rolling bearings ------------------------------------------------------------------
    for b in bearings:
        for member in (b.inner, b.outer):
            if member not in sp:
                raise ValueError(f"bearing {b.name!r}: member {member!r} has no speed")
        fr = abs(sp[b.inner] - sp[b.outer])
        if fr <= tiny:
            notes.append(f"bearing {b.name}: inner and outer ring turn together (no defect "
                         "frequencies)")
            continue
        gamma = b.ratio
        z = int(b.n_rolling)
        base = {
            "bearing_ftf": (fr * (1 - gamma) / 2, "f_r (1 − γ)/2") if b.stationary == "outer"
            else (fr * (1 + gamma) / 2, "f_r (1 + γ)/2"),
            "bearing_bpfo": (z * fr * (1 - gamma) / 2, f"{z} f_r (1 − γ)/2"),
            "bearing_bpfi": (z * fr * (1 + gamma) / 2, f"{z} f_r (1 + γ)/2"),
            "bearing_bsf": (b.pitch_diameter * fr * (1 - gamma * gamma)
                            / (2 * b.rolling_diameter), "D f_r (1 − γ²)/(2 d)"),
        }
        for fam, (rate, formula) in base.items():
            for h in range(1, harmonics + 1):
                out.add(fam, h, 0, b.name, (f"{h}·" if h > 1 else "") + formula
                        + f" (γ = {gamma:.4f})", h * rate)

    rows = sorted(out.rows, key=lambda r: (r[5], list(FAMILIES).index(r[0]), r[1], r[2]))

    def col(i, dtype):
        return np.asarray([r[i] for r in rows], dtype=dtype)

    return KinematicCatalogue(
        family=col(0, object), harmonic=col(1, int), sideband=col(2, int),
        member=col(3, object), formula=col(4, object), order=col(5, float) / f_ref,
        phasing=col(6, float), reference=reference, sensor=sensor, speed_rpm=sref,
        speeds_rpm=run, member_speeds={k: v / f_ref for k, v in sp.items()},
        notes=tuple(notes), name=name)


# ------------------------------------------------------------------------------- simple sets


def simple_planetary_speeds(z_sun: int, z_ring: int, z_planet: int, *, fixed: str = "ring",
                            input: str = "sun", input_speed: float = 1.0) -> dict[str, float]:
    """Signed speeds of sun, ring, carrier and planet of a simple planetary set.

    Parameters
    ----------
    z_sun, z_ring, z_planet : int
        Signed tooth numbers (``z_ring < 0``).
    fixed, input : {"sun", "ring", "carrier"}
        Member at rest and driven member.
    input_speed : float
        Speed of the input member (any unit).

    Returns
    -------
    dict
        ``{"sun", "ring", "carrier", "planet"}`` (planet: absolute speed).

    Notes
    -----
    Willis: ``z_s (n_s - n_c) = z_r (n_r - n_c)``; planet: ``z_p (n_p - n_c) = -z_s (n_s - n_c)``.
    """
    members = ("sun", "ring", "carrier")
    if z_sun <= 0 or z_ring >= 0 or z_planet <= 0:
        raise ValueError(f"tooth numbers z_sun = {z_sun}, z_ring = {z_ring}, z_planet = "
                         f"{z_planet}: admissible z_sun > 0, z_ring < 0 (internal), z_planet > 0")
    if fixed not in members or input not in members or fixed == input:
        raise ValueError(f"fixed = {fixed!r}, input = {input!r}: two different members of "
                         f"{members}")
    n = {fixed: 0.0, input: float(input_speed)}
    (free,) = (m for m in members if m not in n)
    coef = {"sun": float(z_sun), "ring": float(-z_ring), "carrier": float(-(z_sun - z_ring))}
    n[free] = -sum(coef[m] * n[m] for m in n) / coef[free]
    out = {m: n[m] + 0.0 for m in members}
    out["planet"] = out["carrier"] - z_sun * (out["sun"] - out["carrier"]) / z_planet
    return out


def simple_planetary_catalogue(z_sun: int, z_ring: int, z_planet: int, *,
                               n_planets: int | None = None,
                               planet_angles_deg: Sequence[float] | None = None,
                               fixed: str = "ring", input: str = "sun",
                               reference: str | None = None, **kwargs: Any
                               ) -> KinematicCatalogue:
    """Catalogue of a simple planetary set from its tooth numbers (plain numbers in).

    Parameters
    ----------
    z_sun, z_ring, z_planet : int
        Signed tooth numbers (``z_ring < 0``).
    n_planets : int, optional
        Number of equally spaced planets (or give ``planet_angles_deg``).
    planet_angles_deg : sequence of float, optional
        Planet angles [deg].
    fixed, input : {"sun", "ring", "carrier"}
        Member at rest and driven member.
    reference : str, optional
        Reference shaft (default: the input).
    **kwargs
        Passed to :func:`kinematic_catalogue` (``speed_rpm``, ``bearings``, ...).

    Returns
    -------
    KinematicCatalogue
    """
    if planet_angles_deg is None:
        if n_planets is None:
            raise ValueError("give n_planets or planet_angles_deg")
        n = _int_param(n_planets, "n_planets", 1)
        planet_angles_deg = [360.0 * i / n for i in range(n)]
    ang = [float(a) for a in planet_angles_deg]
    if not ang:
        raise ValueError("planet_angles_deg is empty: a planetary set has at least one planet")
    for a in ang:
        turns = (z_sun - z_ring) * a / 360.0
        if not math.isfinite(turns) or abs(turns - round(turns)) > 0.02:
            step = 360.0 / (z_sun - z_ring)
            raise ValueError(f"planet_angles_deg: a planet at {a:g}° cannot be assembled: "
                             f"(z_sun + |z_ring|) angle / 360° = {turns:.4g} is not an integer "
                             f"(admissible angles are multiples of {step:.4g}°)")
    base = simple_planetary_speeds(z_sun, z_ring, z_planet, fixed=fixed, input=input)
    speeds = {"sun": base["sun"], "ring": base["ring"], "carrier": base["carrier"]}
    meshes = []
    angles = {}
    for i, a in enumerate(ang, start=1):
        p = f"planet{i}"
        speeds[p] = base["planet"]
        angles[p] = a
        meshes.append(ToothMesh(f"sun-{p}", "sun", p, int(z_sun), int(z_planet), "carrier"))
        meshes.append(ToothMesh(f"ring-{p}", "ring", p, int(z_ring), int(z_planet), "carrier"))
    return kinematic_catalogue(speeds, meshes, reference=reference or input,
                               planet_angles_deg=angles, fixed=fixed, **kwargs)
