"""Candidate causes of a diagnosis: the faults and errors simulated one by one.

Every candidate is a ``[[fault]]`` table of the gear-set description
(``docs/faults-sensors.md``), two sizes per kind and member (a light and a heavy one; a broken
tooth has one): which of a fault's lines reach above a measurement's noise depends on its size,
and the diagnosis keeps the better-scoring of the two. A candidate's *cause* is the fault
``kind`` and its *member* the body it sits on. Planets that the gear set cannot tell apart
(identical and equally spaced: a rotation of the carrier by the planet spacing maps one onto
the next, so without a carrier phase reference their faults give the same spectra) are one
candidate member ``planet``, simulated on ``planet1``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from gearvib.config import ConfigError

__all__ = ["KINDS", "Candidate", "candidate_faults", "planets_equivalent", "severity_text"]

KINDS = ("crack", "pitting", "broken_tooth", "eccentricity", "pin_error")
"""Fault kinds a diagnosis considers (a subset may be asked for)."""


@dataclass(frozen=True)
class Candidate:
    """One simulated candidate fault.

    Attributes
    ----------
    cause : str
        Fault kind.
    member : str
        Reported member (``planet`` for interchangeable planets).
    fault : dict
        The ``[[fault]]`` table simulated.
    label : str
        Short unique label, e.g. ``"crack sun 50 %"``.
    """

    cause: str
    member: str
    fault: dict
    label: str


def planets_equivalent(cfg: dict) -> bool:
    """Whether the planets of a simple set are equally spaced (and so interchangeable)."""
    angles = sorted(float(a) % 360.0 for a in cfg.get("geometry", {}).get("planet_angles_deg",
                                                                          []))
    n = len(angles)
    if n < 2:
        return True
    step = 360.0 / n
    return all(abs((a - angles[0]) - i * step) < 1e-6 for i, a in enumerate(angles))


CRACK_SEVERITIES = (0.3, 0.7)
"""Stiffness losses of the simulated tooth cracks (a light and a deep crack)."""

PITTING_VARIANTS = ((0.4, 0.35, 0.65, 3e-6), (0.5, 0.15, 0.45, 5e-6), (0.7, 0.2, 0.8, 10e-6))
"""Simulated pitting: (stiffness loss, path start, path end, depth [m]) — early pitting
about the pitch line and advanced spalling over most of the path."""

ECCENTRICITIES = (8e-6, 20e-6)
"""Simulated eccentricities [m]."""

PIN_ERRORS = (10e-6, 30e-6)
"""Simulated tangential pin position errors [m]."""


def _local(kind: str, member: str, target: str) -> list[Candidate]:
    if kind == "crack":
        return [Candidate(kind, member, {"kind": "crack", "member": target, "tooth": 0,
                                         "severity": s}, f"crack {member} {100 * s:.0f} %")
                for s in CRACK_SEVERITIES]
    if kind == "pitting":
        return [Candidate(kind, member, {"kind": "pitting", "member": target, "tooth": 0,
                                         "severity": s, "path_start": a, "path_end": b,
                                         "depth": d, "flank": "both"},
                          f"pitting {member} {100 * s:.0f} % {d * 1e6:.0f} um")
                for s, a, b, d in PITTING_VARIANTS]
    return [Candidate(kind, member, {"kind": "broken_tooth", "member": target, "tooth": 0},
                      f"broken_tooth {member}")]


def candidate_faults(cfg: dict, kinds: Sequence[str] = KINDS) -> list[Candidate]:
    """The candidate faults of a simple planetary gear set.

    Parameters
    ----------
    cfg : dict
        Gear-set description (``type = "simple"``).
    kinds : sequence of str
        Fault kinds to consider (default :data:`KINDS`).

    Raises
    ------
    ConfigError
        Another type of gear set, or an unknown kind.
    """
    bad = [k for k in kinds if k not in KINDS]
    if bad:
        raise ConfigError(f"diagnosis: unknown fault kind(s) {bad} (admissible: "
                          f"{', '.join(KINDS)})")
    if cfg.get("type", "simple") != "simple":
        raise ConfigError(f"diagnosis: gear-set type {cfg.get('type')!r} is not supported yet "
                          "(admissible: a simple planetary set, type = \"simple\")")
    if cfg.get("fault"):
        raise ConfigError("diagnosis: the gear set must describe the healthy gearbox (remove "
                          "its [[fault]] tables)")
    n = len(cfg.get("geometry", {}).get("planet_angles_deg", []))
    if n < 1:
        raise ConfigError("diagnosis: the gear set has no planets (geometry.planet_angles_deg)")
    if planets_equivalent(cfg):
        planets = [("planet", "planet1")]
    else:
        planets = [(f"planet{i + 1}", f"planet{i + 1}") for i in range(n)]
    out: list[Candidate] = []
    for kind in ("crack", "pitting", "broken_tooth"):
        if kind in kinds:
            for m, t in [("sun", "sun"), *planets, ("ring", "ring")]:
                out += _local(kind, m, t)
    if "eccentricity" in kinds:
        for m, t in [("sun", "sun"), *planets]:
            out += [Candidate("eccentricity", m, {"kind": "eccentricity", "member": t,
                                                  "eccentricity": e, "phase_deg": 0.0},
                              f"eccentricity {m} {e * 1e6:.0f} um") for e in ECCENTRICITIES]
    if "pin_error" in kinds:
        for m, t in planets:
            out += [Candidate("pin_error", m, {"kind": "pin_error", "member": t,
                                               "tangential": e, "radial": 0.0},
                              f"pin_error {m} {e * 1e6:.0f} um") for e in PIN_ERRORS]
    assert len({c.label for c in out}) == len(out)
    return out


def severity_text(c: Candidate) -> str:
    """What was simulated, for the evidence."""
    f = c.fault
    if c.cause == "crack":
        return f"tooth crack, stiffness loss {100 * f['severity']:.0f} %"
    if c.cause == "pitting":
        return (f"pitting {100 * f['severity']:.0f} %, {f['depth'] * 1e6:.0f} µm deep over "
                f"{100 * f['path_start']:.0f}-{100 * f['path_end']:.0f} % of the path")
    if c.cause == "broken_tooth":
        return "missing tooth"
    if c.cause == "eccentricity":
        return f"eccentricity {f['eccentricity'] * 1e6:.0f} µm"
    return f"pin position error {math.hypot(f['tangential'], f['radial']) * 1e6:.0f} µm"
