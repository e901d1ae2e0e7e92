"""Involute gear geometry, planetary assembly conditions and mesh phasing.

Conventions
-----------
* Tooth numbers are **signed**: ``z < 0`` is an internal gear (ring), as in the source paper
  and DIN 3960. Reference and base radii carry the sign of ``z``; tip and root radii are
  absolute values. Centre distances are positive (ISO 21771 convention).
* Profile shift ``x`` follows the DIN 3960 / ISO 21771 signed convention: ``x > 0`` moves the
  basic rack profile towards the tooth tip, i.e. it makes the teeth thicker at the reference
  circle for external **and** internal gears. For an internal gear the tip circle therefore
  moves *towards* the axis: ``r_a = |r| - (h_a* + x) m_n`` and ``r_f = |r| + (h_f* - x) m_n``.
  With this convention the operating pressure angle of every pair is
  ``inv a_wt = inv a_t + 2 tan a_n (x1 + x2) / (z1 + z2)`` with signed tooth numbers.
* Angles are in radians, lengths in metres.
* Mesh position ``s`` [mesh cycles]: ``s = 0`` (mod 1) when a new tooth pair enters contact at
  the start of the active path of contact; ``s`` grows with the forward motion (sun faster
  than the carrier). In a mesh whose first gear is external (sun) the first gear drives; in a
  mesh whose first gear is internal (ring) the second gear (planet) drives in the carrier frame.

Positions along a line of action are measured by the coordinate ``u`` [m] from the base
tangency point of ``gear2`` towards the pitch point (see :class:`MeshGeometry`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from gearvib.checks import check_array, check_count, check_real, short

__all__ = [
    "MAX_TEETH",
    "MeshGeometry",
    "Toothing",
    "admissible_planet_angles",
    "check_planet_angles",
    "inverse_involute",
    "involute",
    "mesh_geometry",
    "mesh_phases",
    "minimum_offset_angle",
    "planet_mesh_offsets",
    "planet_mesh_position",
    "planet_profile_shift",
    "planet_tooth_angle",
    "planet_tooth_number",
    "planetary_meshes",
    "sun_ring_phase",
]

_TOL = 1e-9
MAX_TEETH = 10_000
"""Largest tooth number (absolute value) accepted."""
MIN_MODULE, MAX_MODULE = 1e-5, 1.0
"""Admissible normal module [m] (the limits of a description's ``module``)."""


def involute(alpha: float | np.ndarray) -> float | np.ndarray:
    """Involute function ``inv(alpha) = tan(alpha) - alpha`` [rad].

    Raises
    ------
    ValueError, TypeError
        ``alpha`` is not a real number (or array of them) with ``|alpha| < pi/2``.
    """
    if isinstance(alpha, np.ndarray | list | tuple):
        a = check_array(alpha, "alpha", min_size=0, max_abs=0.5 * math.pi)
        if a.size and not float(np.abs(a).max()) < 0.5 * math.pi:
            raise ValueError("alpha: a magnitude of pi/2 or more (admissible: |alpha| < pi/2)")
        return np.tan(a) - a
    a = check_real(alpha, "alpha", low=-0.5 * math.pi, high=0.5 * math.pi, low_open=True,
                   high_open=True)
    return np.tan(a) - a


def inverse_involute(value: float) -> float:
    """Angle ``alpha`` in ``[0, pi/2)`` with ``inv(alpha) = value`` (value >= 0).

    Raises
    ------
    ValueError
        If ``value`` is negative or not finite.
    """
    value = check_real(value, "involute value", low=0.0)
    if value == 0.0:
        return 0.0
    # inv is monotonic on [0, pi/2); bracket up to 1.5 rad (inv(1.5) = 12.6). Near pi/2 the
    # largest float below it gives inv = 1.6e16: beyond that no angle exists (the loop would
    # never end)
    hi = 1.5
    for _ in range(64):
        if math.tan(hi) - hi >= value:
            break
        hi = 0.5 * (hi + 0.5 * math.pi)
    else:
        raise ValueError(f"involute value {value!r} is not admissible (the angle would be 90°; "
                         "a profile shift or tooth number out of range)")
    # Newton's method from above: inv is increasing and convex on [0, pi/2), so iterates that
    # start at or above the root decrease monotonically onto it, never overshooting.
    # (3 v)^(1/3) is such a start (inv(a) = a^3/3 + 2 a^5/15 + ... >= a^3/3). The loop ends
    # when an iterate no longer decreases: the root to the last bit (4-6 steps). Written out
    # rather than scipy.optimize.brentq: importing scipy.optimize takes 0.3 s of a 1 s run.
    a = min(hi, (3.0 * value) ** (1.0 / 3.0))
    for _ in range(200):
        t = math.tan(a)
        step = (t - a - value) / (t * t)
        if not step > 0.0:
            break
        a_next = a - step
        if not a_next < a:
            break
        a = a_next
    return a


def _finite(name: str, value: Any) -> float:
    return check_real(value, name)


def _toothings(**gears: Any) -> None:
    """Refuse an argument that is not a :class:`Toothing` (by its parameter name)."""
    for name, g in gears.items():
        if not isinstance(g, Toothing):
            raise TypeError(f"{name} must be a Toothing; got {type(g).__name__}")


def _deg(angle: float) -> float:
    return math.degrees(angle)


@dataclass(frozen=True)
class Toothing:
    """Involute toothing of one gear (ISO 21771 / DIN 3960 quantities).

    Parameters
    ----------
    z : int
        Signed number of teeth; negative for an internal gear (``|z| >= 3``).
    module : float
        Normal module ``m_n`` [m], > 0.
    pressure_angle : float
        Normal pressure angle ``alpha_n`` [rad] of the basic rack, 0 < alpha_n < 45°.
    helix_angle : float
        Helix angle ``beta`` at the reference circle [rad], ``|beta| < 45°``.
    profile_shift : float
        Profile shift coefficient ``x`` (DIN 3960 sign, see module docstring).
    face_width : float
        Face width ``b`` [m], > 0.
    addendum, dedendum : float
        Addendum and dedendum coefficients ``h_a*``, ``h_f*`` of the basic rack (times m_n).

    Notes
    -----
    Transverse quantities (ISO 21771 / DIN 3960):

    * ``m_t = m_n / cos(beta)``, ``tan(alpha_t) = tan(alpha_n) / cos(beta)``;
    * ``r = z m_t / 2`` (signed), ``r_b = r cos(alpha_t)`` (signed);
    * ``tan(beta_b) = tan(beta) cos(alpha_t)``;
    * external gear: ``r_a = r + (h_a* + x) m_n``, ``r_f = r - (h_f* - x) m_n``;
    * internal gear: ``r_a = |r| - (h_a* + x) m_n``, ``r_f = |r| + (h_f* - x) m_n``;
    * transverse tooth thickness on the reference circle ``s_t = m_t (pi/2 + 2 x tan(alpha_n))``
      (the ring tooth for an internal gear);
    * transverse base pitch ``p_bt = pi m_t cos(alpha_t)``.

    The tip radius of the internal gear uses the DIN 3960 sign of ``x`` (``x > 0`` thickens the
    ring teeth and moves its tip circle towards the axis). This is the convention under which
    the signed operating-pressure-angle formula holds for internal pairs; a positive ``x`` in
    the opposite ("tip moves outwards") convention must be entered with a negative sign.
    No tip shortening is applied.
    """

    z: int
    module: float
    pressure_angle: float = math.radians(20.0)
    helix_angle: float = 0.0
    profile_shift: float = 0.0
    face_width: float = 0.02
    addendum: float = 1.0
    dedendum: float = 1.25

    def __post_init__(self) -> None:
        check_count(self.z, "tooth number z", low=-MAX_TEETH, high=MAX_TEETH)
        if abs(int(self.z)) < 3:
            raise ValueError(f"tooth number z = {self.z} is not admissible (admissible: |z| >= 3)")
        m = _finite("module", self.module)
        if not MIN_MODULE <= m <= MAX_MODULE:
            raise ValueError(f"module = {m!r} m is not admissible (admissible: {MIN_MODULE:g} "
                             f"to {MAX_MODULE:g} m)")
        a = _finite("pressure_angle", self.pressure_angle)
        if not 0.0 < a < math.radians(45.0):
            raise ValueError(
                f"pressure_angle = {_deg(a):.4g}° is not admissible (admissible: 0° < alpha < 45°)"
            )
        b = _finite("helix_angle", self.helix_angle)
        if not abs(b) < math.radians(45.0):
            raise ValueError(
                f"helix_angle = {_deg(b):.4g}° is not admissible (admissible: |beta| < 45°)"
            )
        check_real(self.profile_shift, "profile_shift", low=-10.0, high=10.0)
        check_real(self.face_width, "face_width", low=0.0, low_open=True, high=10.0)
        for name in ("addendum", "dedendum"):
            check_real(getattr(self, name), name, low=0.0, low_open=True, high=10.0)
        if self.root_radius <= 0.0:
            raise ValueError(
                f"root radius of gear z = {self.z} is {self.root_radius:.4g} m "
                f"(profile shift {self.profile_shift} too small; admissible: root radius > 0)"
            )
        if self.internal:
            if self.tip_radius <= abs(self.base_radius):
                raise ValueError(
                    f"internal gear z = {self.z}: tip radius {self.tip_radius:.6g} m is inside the "
                    f"base circle {abs(self.base_radius):.6g} m (admissible: r_a > r_b; reduce "
                    f"profile shift {self.profile_shift} or addendum {self.addendum})"
                )
        elif self.tip_thickness_angle() <= 0.0:
            raise ValueError(
                f"gear z = {self.z} has pointed teeth: tip thickness "
                f"{self.tip_thickness_angle() * self.tip_radius:.4g} m (admissible: > 0; reduce "
                f"profile shift {self.profile_shift} or addendum {self.addendum})"
            )

    # --- transverse quantities -------------------------------------------------------------
    @property
    def internal(self) -> bool:
        """True for an internal gear (``z < 0``)."""
        return self.z < 0

    @property
    def transverse_module(self) -> float:
        """Transverse module ``m_t = m_n / cos(beta)`` [m]."""
        return self.module / math.cos(self.helix_angle)

    @property
    def transverse_pressure_angle(self) -> float:
        """Transverse pressure angle ``alpha_t`` [rad]."""
        return math.atan(math.tan(self.pressure_angle) / math.cos(self.helix_angle))

    @property
    def reference_radius(self) -> float:
        """Signed reference radius ``r = z m_t / 2`` [m]."""
        return self.z * self.transverse_module / 2.0

    @property
    def base_radius(self) -> float:
        """Signed base radius ``r_b = r cos(alpha_t)`` [m]."""
        return self.reference_radius * math.cos(self.transverse_pressure_angle)

    @property
    def tip_radius(self) -> float:
        """Tip radius (absolute) [m]; inside the reference circle for an internal gear."""
        r = abs(self.reference_radius)
        h = (self.addendum + self.profile_shift) * self.module
        return r - h if self.internal else r + h

    @property
    def root_radius(self) -> float:
        """Root radius (absolute) [m]; outside the reference circle for an internal gear."""
        r = abs(self.reference_radius)
        h = (self.dedendum - self.profile_shift) * self.module
        return r + h if self.internal else r - h

    @property
    def base_pitch(self) -> float:
        """Transverse base pitch ``p_bt = pi m_t cos(alpha_t)`` [m] (> 0)."""
        return math.pi * self.transverse_module * math.cos(self.transverse_pressure_angle)

    @property
    def base_helix_angle(self) -> float:
        """Base helix angle ``beta_b``, ``tan(beta_b) = tan(beta) cos(alpha_t)`` [rad]."""
        return math.atan(math.tan(self.helix_angle) * math.cos(self.transverse_pressure_angle))

    @property
    def tooth_thickness(self) -> float:
        """Transverse tooth thickness (arc) on the reference circle [m].

        ``s_t = m_t (pi/2 + 2 x tan(alpha_n))``; for an internal gear the ring tooth.
        """
        return self.transverse_module * (
            0.5 * math.pi + 2.0 * self.profile_shift * math.tan(self.pressure_angle)
        )

    def thickness_half_angle(self, radius: float) -> float:
        """Half tooth-thickness angle [rad] at ``radius`` (>= base radius, absolute).

        External gear: ``psi(r) = s_t/(2|r_ref|) + inv(alpha_t) - inv(alpha_r)``; internal gear:
        ``psi(r) = s_t/(2|r_ref|) - inv(alpha_t) + inv(alpha_r)`` with
        ``cos(alpha_r) = r_b / r`` (DIN 3960).
        """
        rb = abs(self.base_radius)
        if radius < rb * (1.0 - 1e-12):
            raise ValueError(f"radius {radius!r} m is inside the base circle {rb!r} m")
        a_r = math.acos(min(1.0, rb / radius))
        base = self.tooth_thickness / (2.0 * abs(self.reference_radius))
        d_inv = float(involute(self.transverse_pressure_angle) - involute(a_r))
        return base - d_inv if self.internal else base + d_inv

    def tip_thickness_angle(self) -> float:
        """Full tooth-thickness angle at the tip circle [rad] (external gears)."""
        return 2.0 * self.thickness_half_angle(self.tip_radius)


@dataclass(frozen=True)
class MeshGeometry:
    """Geometry of one gear pair at its operating centre distance.

    Attributes
    ----------
    gear1, gear2 : Toothing
        The two gears; in planetary sets gear1 is the central gear and gear2 the planet.
    centre_distance : float
        Operating centre distance ``a_w`` [m] (> 0).
    working_pressure_angle : float
        Transverse operating pressure angle ``alpha_wt`` [rad].
    contact_ratio, overlap_ratio, total_contact_ratio : float
        ``eps_alpha``, ``eps_beta``, ``eps_gamma = eps_alpha + eps_beta``.
    base_pitch : float
        Transverse base pitch ``p_bt`` [m].
    internal : bool
        True for an internal pair.
    base_helix_angle : float
        ``beta_b`` [rad] (>= 0; the hands are in the toothings).
    face_width : float
        Common face width ``min(b1, b2)`` [m].
    backlash_free_centre_distance : float
        Centre distance of zero circumferential backlash from the profile shifts [m].
    tangency1 : float
        Coordinate ``u`` of gear1's base tangency point [m].
    pitch_point : float
        Coordinate ``u`` of the pitch point [m].
    tip_point1, tip_point2 : float
        Coordinates ``u`` where the tip circles of gear1 and gear2 cut the line of action [m].
    path_start, path_end : float
        Coordinates ``u`` of the start and end of the active path in the forward motion [m]:
        the start is the tip point of the driven gear (gear2 if gear1 is external, gear1 if
        gear1 is internal).

    Notes
    -----
    ``u`` is the distance along the (transverse) line of action from gear2's base tangency
    point ``T2`` towards the pitch point ``C``. ``T1`` lies at ``u = a_w sin(alpha_wt)`` for an
    external pair or an internal gear2, and at ``u = -a_w sin(alpha_wt)`` when gear1 is the
    internal gear. Every tip point lies at ``sqrt(r_a^2 - r_b^2)`` from its own tangency point,
    on the side of the pitch point. The contact ratio is ``|tip_point1 - tip_point2| / p_bt``,
    identical to the closed forms of physics.md 3.2 (Niemann & Winter, Maschinenelemente II,
    ch. 21; ISO 21771 sec. 5).
    """

    gear1: Toothing
    gear2: Toothing
    centre_distance: float
    working_pressure_angle: float
    contact_ratio: float
    overlap_ratio: float
    total_contact_ratio: float
    base_pitch: float
    internal: bool
    base_helix_angle: float
    face_width: float
    backlash_free_centre_distance: float
    tangency1: float
    pitch_point: float
    tip_point1: float
    tip_point2: float
    path_start: float
    path_end: float

    @property
    def path_length(self) -> float:
        """Length of the active path of contact ``g_alpha`` [m]."""
        return abs(self.path_end - self.path_start)

    @property
    def forward_direction(self) -> int:
        """+1 if the contact point moves towards increasing ``u`` in the forward motion."""
        return 1 if self.path_end > self.path_start else -1

    @property
    def working_pitch_radius2(self) -> float:
        """Working pitch radius of gear2 [m] (absolute)."""
        return abs(self.gear2.base_radius) / math.cos(self.working_pressure_angle)

    @property
    def circumferential_backlash(self) -> float:
        """Circumferential backlash on the working pitch circles [m] (0 at the free distance).

        ``j_wt = p_wt - s_wt1 - s_wt2`` with the tooth thicknesses on the working pitch circles
        (for an internal gear the ring tooth, whose space width is ``p_wt - s_wt``), from
        :meth:`Toothing.thickness_half_angle`. Independent of the profile-shift formula, so it
        checks the sign convention of ``x``.
        """
        aw = self.working_pressure_angle
        rw2 = abs(self.gear2.base_radius) / math.cos(aw)
        pw = 2.0 * math.pi * rw2 / abs(self.gear2.z)
        s = 0.0
        for g in (self.gear1, self.gear2):
            rw = abs(g.base_radius) / math.cos(aw)
            s += 2.0 * g.thickness_half_angle(rw) * rw
        return pw - s


def _check_pair(gear1: Toothing, gear2: Toothing) -> None:
    _toothings(gear1=gear1, gear2=gear2)
    if gear1.internal and gear2.internal:
        raise ValueError("both gears are internal (z < 0); at most one gear may be internal")
    for name in ("module", "pressure_angle"):
        v1, v2 = getattr(gear1, name), getattr(gear2, name)
        if not math.isclose(v1, v2, rel_tol=1e-12):
            raise ValueError(f"{name} differs between the gears: {v1!r} vs {v2!r} (must be equal)")
    if not math.isclose(abs(gear1.helix_angle), abs(gear2.helix_angle), rel_tol=1e-12, abs_tol=0):
        raise ValueError(
            f"helix_angle magnitudes differ: {_deg(gear1.helix_angle):.6g}° vs "
            f"{_deg(gear2.helix_angle):.6g}° (must be equal)"
        )
    if gear1.helix_angle != 0.0:
        same_hand = math.copysign(1.0, gear1.helix_angle) == math.copysign(1.0, gear2.helix_angle)
        internal = gear1.internal or gear2.internal
        if same_hand != internal:
            raise ValueError(
                f"helix hands do not mesh: helix_angle {_deg(gear1.helix_angle):.6g}° and "
                f"{_deg(gear2.helix_angle):.6g}° (an external pair needs opposite hands, an "
                "internal pair the same hand: the ring has the planet's hand)"
            )
    if gear1.internal or gear2.internal:
        ext, ring = (gear2, gear1) if gear1.internal else (gear1, gear2)
        if abs(ring.z) - ext.z < 1:
            raise ValueError(
                f"internal pair: |z_internal| - z_external = {abs(ring.z) - ext.z} "
                "(admissible: >= 1; practically >= 10 to avoid tip interference)"
            )


def mesh_geometry(
    gear1: Toothing, gear2: Toothing, centre_distance: float | None = None
) -> MeshGeometry:
    """Operating geometry and contact ratios of an external or internal gear pair.

    Parameters
    ----------
    gear1, gear2 : Toothing
        The gears; at most one is internal (``z < 0``). For planetary sets pass the central
        gear first and the planet second.
    centre_distance : float, optional
        Operating centre distance [m] (> 0). By default the zero-backlash centre distance from
        the profile shifts.

    Returns
    -------
    MeshGeometry

    Raises
    ------
    ValueError
        For incompatible gears, a centre distance at which the teeth would overlap, tip
        interference (a tip point beyond the mating base tangency point), or ``eps_alpha < 1``.

    Notes
    -----
    Operating pressure angle (ISO 21771 eq. for zero backlash, signed ``z``)::

        inv(alpha_wt) = inv(alpha_t) + 2 tan(alpha_n) (x1 + x2) / (z1 + z2)
        a_w = |r1 + r2| cos(alpha_t) / cos(alpha_wt)

    or, for a given ``a_w``, ``cos(alpha_wt) = |r1 + r2| cos(alpha_t) / a_w``.

    Contact ratio (physics.md 3.2; Niemann & Winter vol. II)::

        external: eps_a = [sqrt(ra1²-rb1²) + sqrt(ra2²-rb2²) - a_w sin(alpha_wt)] / p_bt
        internal: eps_a = [sqrt(ra_ext²-rb_ext²) - sqrt(ra_int²-rb_int²) + a_w sin(alpha_wt)] / p_bt
        eps_b = b sin|beta| / (pi m_n),   b = min(b1, b2)
    """
    _check_pair(gear1, gear2)
    internal = gear1.internal or gear2.internal
    alpha_t = gear1.transverse_pressure_angle
    rb1, rb2 = abs(gear1.base_radius), abs(gear2.base_radius)
    a0 = abs(gear1.reference_radius + gear2.reference_radius)
    inv_w = float(involute(alpha_t)) + 2.0 * math.tan(gear1.pressure_angle) * (
        gear1.profile_shift + gear2.profile_shift
    ) / (gear1.z + gear2.z)
    if inv_w <= 0.0:
        raise ValueError(
            f"profile shifts x1 = {gear1.profile_shift}, x2 = {gear2.profile_shift} give "
            f"inv(alpha_wt) = {inv_w:.4g} <= 0: no operating pressure angle exists"
        )
    a_free = a0 * math.cos(alpha_t) / math.cos(inverse_involute(inv_w))
    if centre_distance is None:
        aw = a_free
    else:
        aw = _finite("centre_distance", centre_distance)
        if aw <= 0.0:
            raise ValueError(f"centre_distance = {aw!r} m is not admissible (admissible: > 0)")
        tol = 1e-9 * a_free
        if internal and aw > a_free + tol:
            raise ValueError(
                f"centre_distance = {aw!r} m is larger than the zero-backlash value "
                f"{a_free!r} m of this internal pair: the teeth would overlap "
                f"(admissible: <= {a_free!r} m)"
            )
        if not internal and aw < a_free - tol:
            raise ValueError(
                f"centre_distance = {aw!r} m is smaller than the zero-backlash value "
                f"{a_free!r} m: the teeth would overlap (admissible: >= {a_free!r} m)"
            )
        c = a0 * math.cos(alpha_t) / aw
        if c >= 1.0:
            raise ValueError(f"centre_distance = {aw!r} m gives no real pressure angle")
    alpha_wt = math.acos(a0 * math.cos(alpha_t) / aw)
    lam = aw * math.sin(alpha_wt)  # distance T1T2
    if internal and gear1.internal:
        t1, d1 = -lam, 1.0
    elif internal:
        t1, d1 = lam, 1.0
    else:
        t1, d1 = lam, -1.0
    g1 = math.sqrt(max(gear1.tip_radius**2 - rb1**2, 0.0))
    g2 = math.sqrt(max(gear2.tip_radius**2 - rb2**2, 0.0))
    tip1 = t1 + d1 * g1
    tip2 = g2
    pitch = abs(gear2.base_radius) * math.tan(alpha_wt)
    label = f"z1 = {gear1.z}, z2 = {gear2.z}"
    # Interference: every tip point must meet the mating flank on its involute, i.e. not
    # beyond the mating gear's base tangency point.
    if not internal:
        if tip1 < -_TOL * aw or tip2 > lam * (1 + _TOL):
            raise ValueError(
                f"tip interference in mesh {label}: a tip circle cuts the line of action beyond "
                "the mating base tangency point (reduce addendum or change profile shift)"
            )
        eps_a = (tip2 - tip1) / gear1.base_pitch
    else:
        ext_t, ring_tip, pin_tip = (0.0, tip1, tip2) if gear1.internal else (t1, tip2, tip1)
        if ring_tip < ext_t - _TOL * aw:
            raise ValueError(
                f"tip interference in mesh {label}: the internal gear's tip point lies below the "
                "base tangency point of the pinion (reduce the ring addendum or increase the "
                "ring profile shift)"
            )
        eps_a = (pin_tip - ring_tip) / gear1.base_pitch
    if eps_a < 1.0:
        raise ValueError(
            f"contact ratio eps_alpha = {eps_a:.4g} of mesh {label} is below 1 (admissible: >= 1)"
        )
    b = min(gear1.face_width, gear2.face_width)
    eps_b = b * abs(math.sin(gear1.helix_angle)) / (math.pi * gear1.module)
    if gear1.internal:
        start, end = tip1, tip2  # planet drives the ring in the carrier frame
    else:
        start, end = tip2, tip1  # external gear1 drives gear2
    return MeshGeometry(
        gear1=gear1,
        gear2=gear2,
        centre_distance=aw,
        working_pressure_angle=alpha_wt,
        contact_ratio=eps_a,
        overlap_ratio=eps_b,
        total_contact_ratio=eps_a + eps_b,
        base_pitch=gear1.base_pitch,
        internal=internal,
        base_helix_angle=abs(gear1.base_helix_angle),
        face_width=b,
        backlash_free_centre_distance=a_free,
        tangency1=t1,
        pitch_point=pitch,
        tip_point1=tip1,
        tip_point2=tip2,
        path_start=start,
        path_end=end,
    )


# --- planetary assembly ---------------------------------------------------------------------
def _check_set(z_sun: int, z_ring: int) -> tuple[int, int]:
    for name, v in (("z_sun", z_sun), ("z_ring", z_ring)):
        check_count(v, name, low=-MAX_TEETH, high=MAX_TEETH)
    if z_sun < 3:
        raise ValueError(f"z_sun = {z_sun} is not admissible (admissible: >= 3)")
    if z_ring >= 0:
        raise ValueError(
            f"z_ring = {z_ring} is not admissible: the ring is internal, use the signed "
            f"tooth number z_ring = {-abs(z_ring)} (admissible: z_ring < 0)"
        )
    if -z_ring - z_sun < 6:
        raise ValueError(
            f"|z_ring| - z_sun = {-z_ring - z_sun} is not admissible (admissible: >= 6, "
            "planets need at least 3 teeth)"
        )
    return int(z_sun), int(z_ring)


def minimum_offset_angle(z_sun: int, z_ring: int) -> float:
    """Smallest admissible planet spacing ``delta_min = 2 pi / (z_s + |z_r|)`` [rad].

    Paper eq. (4): z_s = 33, z_r = -114 gives 360°/147 = 2.4490°.
    """
    zs, zr = _check_set(z_sun, z_ring)
    return 2.0 * math.pi / (zs - zr)


def admissible_planet_angles(z_sun: int, z_ring: int, n_planets: int | None = None) -> np.ndarray:
    """Admissible planet positions on the carrier [rad], planet 1 at 0.

    Parameters
    ----------
    z_sun, z_ring : int
        Signed tooth numbers (``z_ring < 0``).
    n_planets : int, optional
        If given, the most nearly equally spaced admissible set of ``n_planets`` angles,
        ``psi_n = round(n (z_s + |z_r|) / N) delta_min``; otherwise every multiple of
        ``delta_min`` in ``[0, 2 pi)``.

    Notes
    -----
    A planet at ``psi`` can be assembled iff ``(z_s + |z_r|) psi / 2 pi`` is an integer
    (Seager 1975; Parker & Lin 2004; physics.md sec. 2).
    """
    zs, zr = _check_set(z_sun, z_ring)
    n_tot = zs - zr
    dmin = 2.0 * math.pi / n_tot
    if n_planets is None:
        return np.arange(n_tot) * dmin
    check_count(n_planets, "n_planets")
    if not 1 <= n_planets <= n_tot:
        raise ValueError(f"n_planets = {n_planets} is not admissible (admissible: 1..{n_tot})")
    k = np.array([int(Fraction(n * n_tot, n_planets).__round__()) for n in range(n_planets)])
    return k * dmin


def check_planet_angles(
    z_sun: int,
    z_ring: int,
    angles,
    *,
    centre_distance: float | None = None,
    planet_tip_radius: float | None = None,
    clearance: float = 0.0,
    tol: float = 1e-3,
) -> np.ndarray:
    """Check that planets at ``angles`` [rad] can be assembled and do not overlap.

    Parameters
    ----------
    z_sun, z_ring : int
        Signed tooth numbers (``z_ring < 0``).
    angles : array_like
        Planet angles on the carrier [rad]; relative positions to the first planet matter.
    centre_distance, planet_tip_radius : float, optional
        Operating centre distance ``a`` and planet tip radius ``r_a`` [m]; if both are given
        neighbouring planets must satisfy ``2 a sin(dpsi/2) > 2 r_a + clearance``.
    clearance : float
        Minimum tip-to-tip clearance [m] (>= 0).
    tol : float
        Tolerance on the integer assembly condition, in units of ``delta_min`` (default
        1e-3, so the paper's rounded 122.45° = 50.0004 delta_min passes). Phases computed from
        rounded angles carry that error; use :func:`admissible_planet_angles` for exact ones.

    Returns
    -------
    ndarray
        The angles as floats.

    Raises
    ------
    ValueError
        Not assemblable (message gives the nearest admissible angles), coincident or
        overlapping planets.
    """
    zs, zr = _check_set(z_sun, z_ring)
    psi = check_array(angles, "planet angles").ravel()
    tol = check_real(tol, "tol", low=0.0)
    n_tot = zs - zr
    if psi.size > n_tot:
        raise ValueError(f"planet angles: {psi.size} planets, more than the {n_tot} admissible "
                         "positions (z_sun + |z_ring|)")
    dmin_deg = 360.0 / n_tot
    for p in psi[1:]:
        rel = (p - psi[0]) % (2.0 * math.pi)
        k = n_tot * rel / (2.0 * math.pi)
        if abs(k - round(k)) > tol:
            deg = math.degrees(rel)
            raise ValueError(
                f"planet angle {deg:.6g}° is not admissible: (z_s + |z_r|)·psi/360° = "
                f"{k:.4g} must be an integer; nearest admissible {math.floor(k) * dmin_deg:.6g}° "
                f"or {math.ceil(k) * dmin_deg:.6g}°"
            )
    order = np.sort(psi % (2.0 * math.pi))
    gaps = np.diff(np.append(order, order[0] + 2.0 * math.pi)) if psi.size > 1 else np.array([])
    if psi.size > 1 and np.min(gaps) < 0.5 * 2.0 * math.pi / n_tot:
        raise ValueError("two planets are at the same angle (coincident planets)")
    if (centre_distance is None) != (planet_tip_radius is None):
        raise ValueError("give both centre_distance and planet_tip_radius for the overlap check")
    if centre_distance is not None and psi.size > 1:
        a = _finite("centre_distance", centre_distance)
        ra = _finite("planet_tip_radius", planet_tip_radius)
        c = _finite("clearance", clearance)
        if a <= 0 or ra <= 0 or c < 0:
            raise ValueError(
                "centre_distance and planet_tip_radius must be > 0 and clearance >= 0 "
                f"(got {a!r}, {ra!r}, {c!r})"
            )
        dist = 2.0 * a * np.sin(0.5 * np.minimum(gaps, 2.0 * math.pi - gaps))
        i = int(np.argmin(dist))
        if dist[i] <= 2.0 * ra + c:
            raise ValueError(
                f"neighbouring planets overlap: centre distance between planets "
                f"2·a·sin(dpsi/2) = {dist[i]:.6g} m with dpsi = {math.degrees(gaps[i]):.6g}° "
                f"(admissible: > 2·r_a + clearance = {2 * ra + c:.6g} m)"
            )
    return psi


def planet_tooth_number(z_sun: int, z_ring: int, rounding: str = "down") -> int:
    """Planet tooth number of a simple set, ``(|z_r| - z_s) / 2``.

    If ``|z_r| - z_s`` is odd the result is rounded (``rounding="down"`` or ``"up"``) and the
    centre distances must be equalised with :func:`planet_profile_shift`.
    """
    zs, zr = _check_set(z_sun, z_ring)
    if rounding not in ("down", "up"):
        raise ValueError(f"rounding = {short(rounding)} is not admissible (admissible: 'down', "
                         "'up')")
    d = -zr - zs
    return d // 2 if rounding == "down" else (d + 1) // 2


def _free_centre_distance(g1: Toothing, g2: Toothing) -> float:
    _check_pair(g1, g2)
    a0 = abs(g1.reference_radius + g2.reference_radius)
    at = g1.transverse_pressure_angle
    inv_w = float(involute(at)) + 2.0 * math.tan(g1.pressure_angle) * (
        g1.profile_shift + g2.profile_shift
    ) / (g1.z + g2.z)
    return a0 * math.cos(at) / math.cos(inverse_involute(max(inv_w, 0.0)))


def planet_profile_shift(
    sun: Toothing,
    ring: Toothing,
    z_planet: int,
    *,
    bracket: tuple[float, float] = (-1.0, 2.0),
) -> float:
    """Planet profile shift that equalises the sun-planet and ring-planet centre distances.

    Parameters
    ----------
    sun, ring : Toothing
        Sun (``z > 0``) and ring (``z < 0``) with their profile shifts.
    z_planet : int
        Planet tooth number (> 0), e.g. 40 or 41 for z_s = 33, z_r = -114.
    bracket : tuple of float
        Search interval for ``x_p``.

    Returns
    -------
    float
        ``x_p`` such that ``a_w(sun, planet) = a_w(ring, planet)`` (zero backlash in both).

    Notes
    -----
    ``a_sp(x_p)`` increases and ``a_rp(x_p)`` decreases monotonically with ``x_p`` (both from
    ``inv alpha_wt = inv alpha_t + 2 tan alpha_n (x1+x2)/(z1+z2)``, signed ``z``), so
    ``f(x_p) = a_sp - a_rp`` has one root, found by bisection to the last bit of ``x_p``.
    """
    _toothings(sun=sun, ring=ring)
    if sun.internal or not ring.internal:
        raise ValueError("sun must be external (z > 0) and ring internal (z < 0)")
    zp = check_count(z_planet, "z_planet", high=MAX_TEETH)
    if not (isinstance(bracket, tuple | list) and len(bracket) == 2):
        raise ValueError(f"bracket = {short(bracket)} is not admissible (admissible: two "
                         "numbers (low, high))")
    lo_b = check_real(bracket[0], "bracket[0]")
    hi_b = check_real(bracket[1], "bracket[1]", low=lo_b, low_open=True)
    bracket = (lo_b, hi_b)
    if zp < 3:
        raise ValueError(f"z_planet = {z_planet} is not admissible (admissible: >= 3)")
    mt = sun.transverse_module
    at = sun.transverse_pressure_angle
    tan_an = math.tan(sun.pressure_angle)

    def a_free(z1: int, x1: float, x: float) -> float:
        inv_w = float(involute(at)) + 2.0 * tan_an * (x1 + x) / (z1 + zp)
        return abs(z1 + zp) * mt / 2.0 * math.cos(at) / math.cos(inverse_involute(inv_w))

    def f(x: float) -> float:
        return a_free(sun.z, sun.profile_shift, x) - a_free(ring.z, ring.profile_shift, x)

    # restrict the bracket to shifts with a real operating pressure angle in both meshes
    inv_t = float(involute(at))
    x_lo = -inv_t * (sun.z + zp) / (2.0 * tan_an) - sun.profile_shift
    x_hi = inv_t * abs(ring.z + zp) / (2.0 * tan_an) - ring.profile_shift
    margin = 1e-9
    lo, hi = max(bracket[0], x_lo + margin), min(bracket[1], x_hi - margin)
    try:
        flo, fhi = f(lo), f(hi)
    except ValueError as exc:
        raise ValueError(
            f"planet profile shift bracket {bracket} is not admissible: {exc}"
        ) from exc
    if flo * fhi > 0:
        raise ValueError(
            f"no planet profile shift in {bracket} equalises the centre distances "
            f"(a_sp - a_rp = {flo:.3g} .. {fhi:.3g} m)"
        )
    # bisection to the last bit (f changes sign in [lo, hi]; ~60 halvings, under a millisecond)
    while True:
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            break
        fmid = f(mid)
        if fmid == 0.0:
            return mid
        if (fmid < 0.0) == (flo < 0.0):
            lo, flo = mid, fmid
        else:
            hi = mid
    return lo if abs(flo) <= abs(f(hi)) else hi


def planetary_meshes(
    sun: Toothing, ring: Toothing, planet: Toothing, centre_distance: float | None = None
) -> tuple[MeshGeometry, MeshGeometry]:
    """Sun-planet and ring-planet mesh geometries at one common centre distance.

    Parameters
    ----------
    sun, ring, planet : Toothing
        Sun (``z > 0``), ring (``z < 0``) and planet.
    centre_distance : float, optional
        Common operating centre distance [m]. By default the midpoint of the zero-backlash
        distances ``a_sp <= a <= a_rp`` (equal when the planet shift comes from
        :func:`planet_profile_shift`), which shares the backlash between both meshes.

    Raises
    ------
    ValueError
        If ``a_sp > a_rp`` (no common distance without tooth overlap) or a mesh is invalid.
    """
    _toothings(sun=sun, ring=ring, planet=planet)
    centre_distance = check_real(centre_distance, "centre_distance", optional=True)
    a_sp = _free_centre_distance(sun, planet)
    a_rp = _free_centre_distance(ring, planet)
    if centre_distance is None:
        if a_sp > a_rp * (1 + 1e-9):
            raise ValueError(
                f"sun-planet centre distance {a_sp!r} m exceeds ring-planet {a_rp!r} m: no "
                "common centre distance without tooth overlap (adjust profile shifts, see "
                "planet_profile_shift)"
            )
        centre_distance = min(max(0.5 * (a_sp + a_rp), a_sp), a_rp)
    return (
        mesh_geometry(sun, planet, centre_distance),
        mesh_geometry(ring, planet, centre_distance),
    )


# --- mesh phasing ---------------------------------------------------------------------------
def mesh_phases(z_central: int, planet_angles) -> np.ndarray:
    """Relative mesh phases ``gamma_n = frac(z psi_n / 2 pi)`` (paper eq. (3), physics.md 2).

    Parameters
    ----------
    z_central : int
        Signed tooth number of the central gear.
    planet_angles : array_like
        Planet angles ``psi_n`` [rad], measured in the direction of the forward rotation of
        the sun relative to the carrier.

    Returns
    -------
    ndarray
        ``gamma_n`` in ``[0, 1)``. The mesh of planet ``n`` lags planet 1 by ``gamma_n``:
        ``s_n = s_1 - gamma_n (mod 1)`` (see :func:`planet_mesh_offsets`). For an assemblable
        set the sun (``z_s``) and ring (signed ``z_r``) phases are equal.
    """
    check_count(z_central, "z_central", low=-MAX_TEETH, high=MAX_TEETH)
    psi = check_array(planet_angles, "planet_angles", min_size=0, max_abs=1e9)
    g = np.mod(z_central * psi / (2.0 * math.pi), 1.0)
    g[np.isclose(g, 1.0, rtol=0, atol=1e-9)] = 0.0
    return g


def _planet_base_half_angle(planet: Toothing) -> float:
    """Half tooth thickness angle of the planet on its base circle [rad]."""
    return planet.tooth_thickness / (2.0 * abs(planet.reference_radius)) + float(
        involute(planet.transverse_pressure_angle)
    )


def sun_ring_phase(sun_mesh: MeshGeometry, ring_mesh: MeshGeometry) -> float:
    """Ring-mesh position at one planet when its sun-mesh position is 0 [cycles, 0..1).

    Parameters
    ----------
    sun_mesh : MeshGeometry
        Sun (gear1, external) with the planet (gear2).
    ring_mesh : MeshGeometry
        Ring (gear1, internal) with the same planet (gear2).

    Returns
    -------
    float
        ``s_ring`` at ``s_sun = 0``, in ``[0, 1)``.

    Notes
    -----
    Derivation (carrier frame, planet centre at the origin, carrier axis at ``-a e_y``,
    forward motion: sun counter-clockwise, planet clockwise). With ``u(phi) = (cos, sin)`` the
    planet's base tangency points are ``T_s = r_b u(tau_s)``, ``tau_s = -pi/2 - alpha_ws`` and
    ``T_r = r_b u(tau_r)``, ``tau_r = pi/2 + alpha_wr``. The planet touches the sun with the
    counter-clockwise flanks of its teeth and the ring with the clockwise flanks. A
    counter-clockwise flank whose involute starts on the base circle at ``beta`` cuts the sun
    line of action at ``u_s = r_b (beta - tau_s)`` from ``T_s``; the clockwise flank of the
    same tooth starts at ``beta - 2 psi_b`` and cuts the ring line of action at
    ``u_r = r_b (tau_r - beta + 2 psi_b)`` from ``T_r`` (involute property: distance = unrolled
    base arc). ``psi_b = s_t / (2 r) + inv(alpha_t)`` is the half base tooth-thickness angle of
    the planet. Setting ``u_s`` to the sun path start and measuring ``u_r`` from the ring path
    start gives::

        s_ring = frac( z_p (pi + alpha_ws + alpha_wr + 2 psi_b) / (2 pi)
                       - (u_s,start + u_r,start) / p_bt )

    where both path starts are measured from the planet's tangency points towards the
    respective pitch points. The result is independent of the rotation sense (mirror
    symmetry). Verified in the tests against a brute-force intersection of the tooth profiles
    with the lines of action.
    """
    for name, m, want_internal in (("sun_mesh", sun_mesh, False), ("ring_mesh", ring_mesh, True)):
        if not isinstance(m, MeshGeometry):
            raise TypeError(f"{name} must be a MeshGeometry; got {type(m).__name__}")
        if m.gear1.internal != want_internal or m.gear2.internal:
            raise ValueError(
                f"{name}: gear1 must be the {'ring (z < 0)' if want_internal else 'sun (z > 0)'}"
                " and gear2 the planet (z > 0)"
            )
    p1, p2 = sun_mesh.gear2, ring_mesh.gear2
    if p1 != p2:
        raise ValueError("sun_mesh and ring_mesh must share the same planet toothing (gear2)")
    zp = p1.z
    psi_b = _planet_base_half_angle(p1)
    total = (
        zp
        * (
            math.pi
            + sun_mesh.working_pressure_angle
            + ring_mesh.working_pressure_angle
            + 2.0 * psi_b
        )
        / (2.0 * math.pi)
    )
    total -= (sun_mesh.path_start + ring_mesh.path_start) / p1.base_pitch
    ph = total % 1.0
    return 0.0 if math.isclose(ph, 1.0, abs_tol=1e-12) else ph


def _planet_line(mesh: MeshGeometry, planet_is_gear1: bool, mate_direction: float):
    """Tangency angle ``tau``, base radius, half base thickness angle and flank side of the
    planet on the loaded line of action (see :func:`planet_mesh_position`)."""
    if not isinstance(mesh, MeshGeometry):
        raise TypeError(f"mesh must be a MeshGeometry; got {type(mesh).__name__}")
    if not isinstance(planet_is_gear1, bool):
        raise TypeError(f"planet_is_gear1 must be a bool; got {short(planet_is_gear1)}")
    mate_direction = check_real(mate_direction, "mate_direction", low=-1e9, high=1e9)
    planet = mesh.gear1 if planet_is_gear1 else mesh.gear2
    if planet.internal:
        raise ValueError("planet_mesh_position needs an external planet (z > 0)")
    sigma = -1.0 if mesh.internal else 1.0
    alpha = mesh.working_pressure_angle
    e_angle = mate_direction if planet_is_gear1 else mate_direction + math.pi
    n_angle = e_angle + math.atan2(math.cos(alpha), sigma * math.sin(alpha))
    k = -1.0 if planet_is_gear1 else sigma
    tau = n_angle + 0.5 * math.pi + (0.0 if k > 0 else math.pi)
    zone = 1.0 if planet_is_gear1 else -1.0  # contact zone along zone * n from T
    counter_clockwise = zone == -k  # the counter-clockwise tangent at T is -k n
    return tau, abs(planet.base_radius), _planet_base_half_angle(planet), counter_clockwise


def planet_mesh_position(
    mesh: MeshGeometry, *, planet_is_gear1: bool, mate_direction: float, tooth_angle: float
) -> float:
    """Mesh position [cycles, 0..1) of a mesh of an external planet, from the planet's teeth.

    Parameters
    ----------
    mesh : MeshGeometry
        The mesh; the planet is ``mesh.gear1`` (``planet_is_gear1``, a planet-planet mesh) or
        ``mesh.gear2`` (a central-gear mesh, or the second planet of a planet-planet mesh).
    planet_is_gear1 : bool
        Which gear of ``mesh`` the planet is.
    mate_direction : float
        Direction [rad] from the planet centre to the centre of the mating gear (the main
        axis for a sun or ring), in the frame of the carrier.
    tooth_angle : float
        Direction [rad] of the centre line of one planet tooth, same frame.

    Returns
    -------
    float
        ``s`` in ``[0, 1)``: 0 when a tooth pair enters contact at the start of the active path.

    Notes
    -----
    The loaded ("left") flank of a mesh acts along ``n = cos(a) t + sigma sin(a) e``
    (``e`` the unit vector from gear1 to gear2, ``t`` = ``e`` turned by +90°, ``a`` the
    working pressure angle, ``sigma = -1`` for an internal pair), the line of action of
    :mod:`gearvib.assembly`. A compressive force along it turns gear2 by ``-sigma`` and gear1
    by ``-1`` (external gear1), which fixes on which side of the planet centre the line is
    tangent to the planet's base circle: at ``T = r_b k n_perp`` with ``n_perp`` = ``n`` turned
    by +90°, ``k = sigma`` for the planet as gear2 and ``k = -1`` as gear1 (external planet).
    From ``T`` the contact zone lies along ``-n`` (gear2) or ``+n`` (gear1). Involute property:
    the flank of a tooth whose involute starts on the base circle at angle ``beta`` meets the
    line at the distance ``r_b (beta - tau)`` from ``T`` (``tau`` the angle of ``T``) if the
    line leaves ``T`` counter-clockwise, and ``r_b (tau - beta)`` if it leaves clockwise; the
    counter-clockwise flank of the tooth at ``gamma`` starts at ``gamma + psi_b``, the
    clockwise one at ``gamma - psi_b`` (``psi_b`` half the base tooth-thickness angle). The
    distance gives the coordinate ``u`` of :class:`MeshGeometry` and
    ``s = forward_direction (u - path_start) / p_bt (mod 1)``. For the sun and ring meshes of
    one planet this reproduces :func:`sun_ring_phase` (tested to 1e-12).
    """
    tooth_angle = check_real(tooth_angle, "tooth_angle", low=-1e9, high=1e9)
    tau, rb, psi_b, counter_clockwise = _planet_line(mesh, planet_is_gear1, mate_direction)
    if counter_clockwise:
        dist = rb * (tooth_angle + psi_b - tau)
    else:
        dist = rb * (tau - tooth_angle + psi_b)
    u = mesh.tangency1 - dist if planet_is_gear1 else dist
    s = (mesh.forward_direction * (u - mesh.path_start) / mesh.base_pitch) % 1.0
    return 0.0 if math.isclose(s, 1.0, abs_tol=1e-12) else s


def planet_tooth_angle(
    mesh: MeshGeometry, *, planet_is_gear1: bool, mate_direction: float, position: float
) -> float:
    """Inverse of :func:`planet_mesh_position`: the planet tooth that entered contact last.

    Parameters
    ----------
    mesh, planet_is_gear1, mate_direction
        As in :func:`planet_mesh_position`.
    position : float
        Mesh position ``s`` [cycles].

    Returns
    -------
    float
        Direction [rad] of the centre line of the planet tooth that entered contact ``frac(s)``
        mesh cycles ago (its flank meets the line of action at
        ``u = path_start + forward_direction frac(s) p_bt``).
    """
    position = check_real(position, "position", low=-1e9, high=1e9)
    tau, rb, psi_b, counter_clockwise = _planet_line(mesh, planet_is_gear1, mate_direction)
    u = mesh.path_start + mesh.forward_direction * (position % 1.0) * mesh.base_pitch
    dist = mesh.tangency1 - u if planet_is_gear1 else u
    if counter_clockwise:
        return dist / rb - psi_b + tau
    return tau + psi_b - dist / rb


def planet_mesh_offsets(
    z_sun: int, z_ring: int, planet_angles, sun_ring: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Mesh positions of every planet's sun and ring mesh when planet 1's sun mesh is at 0.

    Parameters
    ----------
    z_sun, z_ring : int
        Signed tooth numbers (``z_ring < 0``).
    planet_angles : array_like
        Planet angles [rad] in the forward sense of the sun relative to the carrier; they are
        checked with :func:`check_planet_angles`.
    sun_ring : float
        :func:`sun_ring_phase` of the planet geometry.

    Returns
    -------
    sun_offsets, ring_offsets : ndarray
        ``frac(-gamma_n)`` and ``frac(sun_ring - gamma_n)`` [cycles], with
        ``gamma_n = mesh_phases(z_sun, psi_n - psi_1)``.

    Notes
    -----
    The mesh state at planet ``n`` depends on the central gear angle relative to the planet,
    ``s_n = z (theta - theta_c - psi_n) / 2 pi + const`` with signed ``z`` for sun and ring, so
    ``s_n - s_1 = -z psi_n / 2 pi``; the assembly condition makes this the same for both.
    """
    psi = check_planet_angles(z_sun, z_ring, planet_angles)
    sun_ring = check_real(sun_ring, "sun_ring")
    g = mesh_phases(z_sun, psi - psi[0])
    s = np.mod(-g, 1.0)
    r = np.mod(sun_ring - g, 1.0)
    return s, r
