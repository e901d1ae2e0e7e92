"""Rigid-body kinematics of simple planetary sets and mesh frequencies.

Tooth numbers are signed (``z < 0`` for internal gears); speeds are in min^-1, frequencies
in Hz. For every central gear ``i`` that meshes with a planet ``p`` on carrier ``c``::

    z_i (n_i - n_c) = -z_p (n_p - n_c)

(the pitch-line velocities relative to the carrier are equal; the sign of ``z`` accounts for
the internal mesh). Eliminating the planet gives Willis' equation.
"""

from __future__ import annotations

from gearvib.checks import check_count, check_real, short
from gearvib.geometry import MAX_TEETH

__all__ = [
    "mesh_frequency",
    "paper_mesh_frequency",
    "simple_set_speeds",
    "willis_ratio",
]

_MEMBERS = ("sun", "ring", "carrier")
MAX_SPEED_RPM = 1e9
"""Largest speed accepted [min-1] (its products with tooth numbers stay finite)."""


def _z(name: str, z: int, *, sign: int = 0) -> int:
    check_count(z, name, low=-MAX_TEETH, high=MAX_TEETH)
    if z == 0:
        raise ValueError(f"{name} = {z!r} must be a non-zero integer (signed tooth number)")
    if sign > 0 and z < 0:
        raise ValueError(f"{name} = {z} is not admissible (admissible: > 0, external gear)")
    if sign < 0 and z > 0:
        raise ValueError(
            f"{name} = {z} is not admissible: the ring is internal, use the signed tooth "
            f"number {-z} (admissible: < 0)"
        )
    return int(z)


def _speed(name: str, n: float) -> float:
    return check_real(n, f"{name} [min-1]", low=-MAX_SPEED_RPM, high=MAX_SPEED_RPM)


def willis_ratio(z_central_a: int, z_central_b: int) -> float:
    """Stationary-carrier ratio ``(n_a - n_c) / (n_b - n_c) = z_b / z_a`` (signed ``z``).

    For sun ``a`` and ring ``b`` (``z_r < 0``) the ratio is negative: seen from the carrier,
    sun and ring turn in opposite senses. Both gears mesh with the same simple planet.
    """
    za = _z("z_central_a", z_central_a)
    zb = _z("z_central_b", z_central_b)
    return zb / za


def simple_set_speeds(
    z_sun: int,
    z_ring: int,
    *,
    fixed: str,
    input: str,
    input_speed: float,
    z_planet: int | None = None,
) -> dict[str, float]:
    """Speeds of sun, ring and carrier of a simple planetary set [min^-1].

    Parameters
    ----------
    z_sun, z_ring : int
        Signed tooth numbers (``z_sun > 0``, ``z_ring < 0``).
    fixed, input : {"sun", "ring", "carrier"}
        The member held at rest and the driven input member (different).
    input_speed : float
        Speed of the input member [min^-1].
    z_planet : int, optional
        Planet tooth number; if given the result also has ``"planet_relative"`` (spin relative
        to the carrier) and ``"planet"`` (absolute spin) [min^-1].

    Returns
    -------
    dict
        ``{"sun": n_s, "ring": n_r, "carrier": n_c, ...}``.

    Notes
    -----
    Willis: ``z_s (n_s - n_c) = z_r (n_r - n_c)``; planet: ``n_p - n_c = -z_s (n_s - n_c)/z_p``.
    """
    zs = _z("z_sun", z_sun, sign=1)
    zr = _z("z_ring", z_ring, sign=-1)
    for name, m in (("fixed", fixed), ("input", input)):
        if m not in _MEMBERS:
            raise ValueError(
                f"{name} = {short(m)} is not admissible (admissible: {', '.join(_MEMBERS)})"
            )
    if fixed == input:
        raise ValueError(f"fixed and input are both {fixed!r} (admissible: different members)")
    n_in = _speed("input_speed", input_speed)
    n = {fixed: 0.0, input: n_in}
    (free,) = (m for m in _MEMBERS if m not in n)
    # z_s n_s - z_r n_r - (z_s - z_r) n_c = 0
    coef = {"sun": float(zs), "ring": float(-zr), "carrier": float(-(zs - zr))}
    n[free] = -sum(coef[m] * n[m] for m in n) / coef[free]
    out = {m: n[m] + 0.0 for m in _MEMBERS}
    if z_planet is not None:
        zp = _z("z_planet", z_planet, sign=1)
        rel = -zs * (out["sun"] - out["carrier"]) / zp
        out["planet_relative"] = rel
        out["planet"] = rel + out["carrier"]
    return out


def mesh_frequency(z_central: int, n_central: float, n_carrier: float) -> float:
    """Tooth-mesh frequency ``f_m = |z (n - n_c)| / 60`` [Hz] (speeds in min^-1)."""
    z = _z("z_central", z_central)
    return abs(z * (_speed("n_central", n_central) - _speed("n_carrier", n_carrier))) / 60.0


def paper_mesh_frequency(n_sun: float, z_sun: int, z_ring: int) -> float:
    """Mesh frequency of the source paper, eq. (5), ring fixed, signed ``z_r < 0`` [Hz].

    ``f = n_s / 60 * (-z_r / (1 - z_r / z_s))``; z_s = 33, z_r = -114 at 1500 min^-1 gives
    639.8 Hz. Equals :func:`mesh_frequency` with ``n_c = n_s z_s / (z_s - z_r)``.
    """
    zs = _z("z_sun", z_sun, sign=1)
    zr = _z("z_ring", z_ring, sign=-1)
    return _speed("n_sun", n_sun) / 60.0 * (-zr / (1.0 - zr / zs))
