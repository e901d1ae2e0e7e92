"""Mathieu-type theory for parametric instability: candidate regions, selection rules, widths.

* :func:`instability_candidates` lists the mesh frequencies (and input speeds) at which
  principal (``2 f_i / n``) and sum-type (``(f_i + f_j) / n``) instability regions can occur,
  and marks those that planetary mesh phasing suppresses (:class:`MeshPhasingRule`).
* :func:`first_order_widths` gives first-order (Hsu 1963; Nayfeh & Mook 1979) boundaries of the
  regions, undamped and damped, including degenerate (repeated) modes.
* :func:`rectangular_wave_harmonics` gives the Fourier coefficients of a rectangular
  (single/double tooth contact) mesh stiffness.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg

from analysis.cf import cf_dataset
from analysis.checks import (
    require_finite,
    require_mass_matrix,
    require_positive,
    require_square,
    shown,
)

__all__ = [
    "Candidates",
    "FirstOrderWidths",
    "MeshPhasingRule",
    "first_order_widths",
    "instability_candidates",
    "natural_frequencies",
    "rectangular_wave_harmonics",
    "rectangular_wave_pieces",
]

MAX_N = 1000
"""Largest order ``n`` of :func:`instability_candidates`."""

KINDS = ("principal", "sum", "difference")
FAMILY_KINDS = ("rotational", "translational", "planet")

DIFFERENCE_NOTE = (
    "difference-type regions (f_j - f_i)/n are not listed: for a symmetric system with positive "
    "definite mean stiffness all modes have the same Krein signature, Hsu's first-order "
    "condition b_ij b_ji < 0 never holds and no difference-type region exists at any order for "
    "small excitation (Yakubovich & Starzhinskii 1975). Pass gyroscopic=True for gyroscopic or "
    "non-symmetric systems (carrier-rotation Coriolis terms, mesh friction)."
)


def _cluster(freqs: np.ndarray, rtol: float) -> list[list[int]]:
    """Group indices of (sorted-by-value) frequencies equal within ``rtol``."""
    order = np.argsort(freqs, kind="stable")
    clusters: list[list[int]] = []
    for i in order:
        if clusters and abs(freqs[i] - freqs[clusters[-1][0]]) <= rtol * freqs[i]:
            clusters[-1].append(int(i))
        else:
            clusters.append([int(i)])
    return clusters


def _positive_frequencies(values: Any, name: str) -> np.ndarray:
    f = require_finite(values, name)
    if f.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional; got shape {f.shape}")
    if np.any(f <= 0):
        i = int(np.flatnonzero(f <= 0)[0])
        raise ValueError(
            f"{name}[{i}] = {f[i]!r} is not admissible: natural frequencies must be > 0 "
            "(remove rigid-body modes first)"
        )
    return f


def natural_frequencies(values: Any, name: str = "natural_frequencies_hz") -> np.ndarray:
    """Checked natural frequencies: a 1-D float array, every entry finite and > 0.

    Parameters
    ----------
    values : array_like
        Natural frequencies [Hz].
    name : str
        Parameter name for the error message.
    """
    return _positive_frequencies(values, name)


@dataclass(frozen=True)
class MeshPhasingRule:
    """Mesh-phasing selection rule for a planetary set with equally spaced, identical planets.

    Parameters
    ----------
    n_planets : int
        Number of planets ``N`` (>= 2).
    sun_teeth : int
        Sun tooth number ``z_s``.
    ring_teeth : int, optional
        Ring tooth number ``z_r``; if given, ``(z_s + z_r)/N`` must be an integer (assembly
        condition for equal spacing), and it enters :attr:`in_phase`.

    Notes
    -----
    Let ``k = l z_s mod N`` for the ``l``-th mesh harmonic. A mode family whose planet
    deflections carry circular harmonic ``p`` (rotational ``p = 0``, translational ``p = 1``,
    planet modes ``p = j``) is *forced* by harmonic ``l`` iff ``k = +-p (mod N)`` (Parker 2000;
    Ambarisha & Parker 2006). A first-order *parametric* region at harmonic ``l`` between
    families ``p`` and ``p'`` exists only if ``k = +-p +- p' (mod N)`` for some choice of signs
    (the same orthogonality argument; Lin & Parker 2002 for the planetary instability rules).
    With in-phase planets (``z_s/N`` and ``z_r/N`` integers) every mesh has the same stiffness
    history, the cyclic symmetry of the instantaneous system is exact, the families decouple and
    mixed-family regions are absent at every order.
    """

    n_planets: int
    sun_teeth: int
    ring_teeth: int | None = None

    def __post_init__(self) -> None:
        for name in ("n_planets", "sun_teeth"):
            v = getattr(self, name)
            if int(v) != v or v < (2 if name == "n_planets" else 1):
                low = 2 if name == "n_planets" else 1
                raise ValueError(f"{name} = {v!r} is not admissible: must be an integer >= {low}")
        if self.ring_teeth is not None:
            zr = self.ring_teeth
            if int(zr) != zr or zr < 1:
                raise ValueError(f"ring_teeth = {zr!r} is not admissible: must be an integer >= 1")
            if (self.sun_teeth + zr) % self.n_planets:
                raise ValueError(
                    f"ring_teeth = {zr}: (sun_teeth + ring_teeth) / n_planets = "
                    f"{(self.sun_teeth + zr) / self.n_planets:g} is not an integer, so equally "
                    "spaced planets cannot be assembled"
                )

    @property
    def in_phase(self) -> bool:
        """True if all sun meshes (and ring meshes, if ``ring_teeth`` given) are in phase."""
        n = self.n_planets
        return self.sun_teeth % n == 0 and (self.ring_teeth is None or self.ring_teeth % n == 0)

    def index(self, harmonic: int) -> int:
        """Circular index ``k = l z_s mod N`` of mesh harmonic ``l``."""
        return int(harmonic * self.sun_teeth) % self.n_planets

    def forced_harmonics(self, harmonic: int) -> tuple[int, ...]:
        """Circular harmonics ``p`` (0..N//2) of the families forced by mesh harmonic ``l``."""
        k = self.index(harmonic)
        return tuple(sorted({min(k, self.n_planets - k)}))

    def check_family(self, family: Any, name: str = "mode_families") -> int:
        """Validate a ``(kind, p)`` family and return ``p``."""
        try:
            kind, p = family
        except (TypeError, ValueError):
            raise ValueError(
                f"{name}: entry {family!r} is not admissible: use a (kind, p) pair with kind in "
                f"{FAMILY_KINDS}"
            ) from None
        if kind not in FAMILY_KINDS:
            raise ValueError(f"{name}: kind {kind!r} is not admissible: use one of {FAMILY_KINDS}")
        expected = {"rotational": 0, "translational": 1}.get(kind)
        if expected is not None and p != expected:
            raise ValueError(f"{name}: a {kind} family has circular harmonic p = {expected}, "
                             f"got {p!r}")
        if kind == "planet" and (int(p) != p or not 1 <= p <= self.n_planets - 1):
            raise ValueError(f"{name}: planet family harmonic p = {p!r} is not admissible: must "
                             f"be an integer in 1..{self.n_planets - 1}")
        return int(p)

    def allows(self, harmonic: int, p: int, p2: int) -> bool:
        """True if a region at mesh harmonic ``l`` between families ``p`` and ``p2`` can exist."""
        k = self.index(harmonic)
        n = self.n_planets
        return any((s1 * p + s2 * p2 - k) % n == 0 for s1 in (1, -1) for s2 in (1, -1))


def _family_reason(rule: MeshPhasingRule, n: int, fams_i: Sequence[tuple[Any, ...]],
                   fams_j: Sequence[tuple[Any, ...]]) -> tuple[bool, str]:
    k = rule.index(n)
    for fi in fams_i:
        for fj in fams_j:
            if rule.allows(n, fi[1], fj[1]):
                return True, ""
    fi, fj = fams_i[0], fams_j[0]
    if rule.in_phase and fi[1] != fj[1]:
        return False, (f"suppressed: in-phase planets (z_s/N integer), {fi[0]}({fi[1]}) and "
                       f"{fj[0]}({fj[1]}) families decouple exactly; absent at every order")
    return False, (f"suppressed by mesh phasing: k = {n}*{rule.sun_teeth} mod {rule.n_planets} "
                   f"= {k} is not +-{fi[1]} +- {fj[1]} (mod {rule.n_planets})")


@dataclass(frozen=True)
class Candidates:
    """Table of candidate instability regions (one row per region).

    Attributes
    ----------
    kind : ndarray of str
        ``"principal"``, ``"sum"`` or ``"difference"``.
    mode_i, mode_j : ndarray of int
        Zero-based index of the (first mode of the) cluster(s); equal for principal regions.
    n : ndarray of int
        Order ``n`` in ``f_mesh = (f_i + f_j)/n`` (also the mesh harmonic of a first-order
        region).
    f_mesh_hz : ndarray
        Centre mesh frequency [Hz].
    rpm : ndarray
        Centre input speed [min-1] (NaN without ``mesh_frequency_per_rpm``).
    allowed : ndarray of bool
        False if a selection rule suppresses the region.
    reason : ndarray of str
        Why a region is suppressed ("" if allowed).
    label : ndarray of str
        E.g. ``"2 f2/3"`` or ``"(f2 + f3=f4)/2"``.
    notes : tuple of str
        General remarks (e.g. why difference-type regions are not listed).
    mesh_frequency : ndarray of str, optional
        Name of the mesh frequency each row belongs to (e.g. ``"stage 2"``) when a system has
        several (two-stage, Wolfrom sets): the row's ``f_mesh_hz`` is that mesh frequency and
        ``n`` its harmonic. None (or empty names) for a single mesh frequency.
    """

    kind: np.ndarray
    mode_i: np.ndarray
    mode_j: np.ndarray
    n: np.ndarray
    f_mesh_hz: np.ndarray
    rpm: np.ndarray
    allowed: np.ndarray
    reason: np.ndarray
    label: np.ndarray
    notes: tuple[str, ...] = ()
    natural_frequencies_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mesh_frequency_per_rpm: float | None = None
    mesh_frequency: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.f_mesh_hz.size)

    def select(self, mask: np.ndarray) -> Candidates:
        """Rows where ``mask`` is true."""
        m = np.asarray(mask, dtype=bool)
        kw = {k: getattr(self, k)[m] for k in ("kind", "mode_i", "mode_j", "n", "f_mesh_hz",
                                               "rpm", "allowed", "reason", "label")}
        return Candidates(**kw, notes=self.notes,
                          natural_frequencies_hz=self.natural_frequencies_hz,
                          mesh_frequency_per_rpm=self.mesh_frequency_per_rpm,
                          mesh_frequency=None if self.mesh_frequency is None
                          else self.mesh_frequency[m])

    def modes(self, i: int, rtol: float = 1e-6) -> np.ndarray:
        """Indices of every mode of row ``i`` (both clusters, each with its repeated modes)."""
        f = self.natural_frequencies_hz
        out = []
        for j in {int(self.mode_i[i]), int(self.mode_j[i])}:
            out += list(np.flatnonzero(np.abs(f - f[j]) <= rtol * f[j]))
        return np.unique(np.asarray(out, dtype=int))

    def full_label(self, i: int) -> str:
        """Label of row ``i`` with its mesh frequency, e.g. ``"2 f3/4 [stage 2]"``."""
        name = "" if self.mesh_frequency is None else str(self.mesh_frequency[i])
        return f"{self.label[i]} [{name}]" if name else str(self.label[i])

    def nearest_speed(self, rpm: float, *, allowed_only: bool = True) -> int | None:
        """Row index of the candidate whose centre speed is nearest to ``rpm`` (or None).

        Use this when the rows belong to several mesh frequencies: their ``f_mesh_hz`` are then
        in different units of speed, their ``rpm`` in the same.
        """
        ok = np.isfinite(self.rpm)
        if allowed_only:
            ok &= self.allowed.astype(bool)
        idx = np.flatnonzero(ok)
        if idx.size == 0:
            return None
        return int(idx[np.argmin(np.abs(self.rpm[idx] - rpm))])

    def nearest(self, f_mesh_hz: float, *, allowed_only: bool = True) -> int | None:
        """Row index of the candidate whose centre is nearest to ``f_mesh_hz`` (or None)."""
        idx = np.flatnonzero(self.allowed) if allowed_only else np.arange(len(self))
        if idx.size == 0:
            return None
        return int(idx[np.argmin(np.abs(self.f_mesh_hz[idx] - f_mesh_hz))])

    def to_dataset(self):
        """Table as :class:`xarray.Dataset` with dimension ``candidate``."""
        import xarray as xr

        def v(x, units, long_name):
            return ("candidate", x, {"units": units, "long_name": long_name})

        extra = {}
        if self.mesh_frequency is not None:
            extra["mesh_frequency"] = v(np.asarray(self.mesh_frequency).astype(str), "1",
                                        "mesh frequency the candidate belongs to")
        ds = xr.Dataset(
            {
                **extra,
                "kind": v(self.kind.astype(str), "1", "region type (principal/sum/difference)"),
                "mode_i": v(self.mode_i, "1", "zero-based index of first mode"),
                "mode_j": v(self.mode_j, "1", "zero-based index of second mode"),
                "order": v(self.n, "1", "order n of f_mesh = (f_i + f_j)/n"),
                "f_mesh": v(self.f_mesh_hz, "Hz", "mesh frequency at region centre"),
                "speed": v(self.rpm, "min-1", "input speed at region centre"),
                "allowed": v(self.allowed.astype(np.int8), "1",
                             "1 if no selection rule suppresses the region"),
                "reason": v(self.reason.astype(str), "1", "reason for suppression"),
                "label": v(self.label.astype(str), "1", "theory label"),
            },
            coords={"candidate": ("candidate", np.arange(len(self)),
                                  {"units": "1", "long_name": "candidate index"})},
            attrs={"notes": " | ".join(self.notes)},
        )
        return cf_dataset(
            ds, title="parametric instability candidates",
            producer="analysis.instability.instability_candidates"
        )

    def __str__(self) -> str:
        lines = [f"{'f_mesh [Hz]':>12} {'speed [rpm]':>12}  {'kind':9} {'n':>2}  label / status"]
        for r in range(len(self)):
            status = "" if self.allowed[r] else f"  [{self.reason[r]}]"
            lines.append(f"{self.f_mesh_hz[r]:12.2f} {self.rpm[r]:12.1f}  {self.kind[r]:9} "
                         f"{self.n[r]:2d}  {self.label[r]}{status}")
        lines += [f"note: {s}" for s in self.notes]
        return "\n".join(lines)

    def plot(self, ax=None):
        """Candidate centres over order (delegates to ``plots.plot_candidates``)."""
        from analysis.instability.plots import plot_candidates

        return plot_candidates(self, ax=ax)


def _cluster_name(c: list[int], labels: Sequence[str]) -> str:
    name = "=".join(labels[i] for i in c)
    return f"({name})" if len(c) > 1 else name


def instability_candidates(
    natural_frequencies_hz: Any,
    *,
    n_max: int = 4,
    kinds: Sequence[str] = ("principal", "sum"),
    mesh_frequency_per_rpm: float | None = None,
    speed_range: tuple[float, float] | None = None,
    mode_labels: Sequence[str] | None = None,
    mode_families: Sequence[tuple[str, int]] | None = None,
    mesh_harmonic_rule: MeshPhasingRule | None = None,
    gyroscopic: bool = False,
    repeat_rtol: float = 1e-6,
    mesh_frequency_name: str | None = None,
) -> Candidates:
    """List the mesh frequencies at which parametric instability regions can occur.

    Parameters
    ----------
    natural_frequencies_hz : array_like, shape (m,)
        Natural frequencies [Hz] of the mean system; must be > 0.
    n_max : int
        Largest order ``n`` listed (``n = 1..n_max``).
    kinds : sequence of str
        Region types, from ``"principal"``, ``"sum"``, ``"difference"``.
    mesh_frequency_per_rpm : float, optional
        Mesh frequency per input speed [Hz/min-1]; if given, speeds are reported.
    speed_range : (float, float), optional
        Keep only candidates with ``speed_range[0] <= rpm <= speed_range[1]``
        (needs ``mesh_frequency_per_rpm``).
    mode_labels : sequence of str, optional
        Mode names (default ``f1, f2, ...``).
    mode_families : sequence of (str, int), optional
        Per mode ``(kind, p)`` with kind in ``{"rotational", "translational", "planet"}`` and
        circular harmonic ``p`` (0, 1, j); needed with ``mesh_harmonic_rule``.
    mesh_harmonic_rule : MeshPhasingRule, optional
        Planetary mesh-phasing selection rule; suppressed rows get ``allowed = False``.
    gyroscopic : bool
        Declare the system gyroscopic or non-symmetric; only then are difference-type regions
        listed when requested.
    repeat_rtol : float
        Relative tolerance within which natural frequencies count as repeated (one cluster).
    mesh_frequency_name : str, optional
        Name of the mesh frequency the candidates belong to (systems with several mesh
        frequencies: call once per mesh frequency with its ``mesh_frequency_per_rpm``); stored
        in :attr:`Candidates.mesh_frequency`.

    Returns
    -------
    Candidates

    Notes
    -----
    Principal regions are centred at ``f_mesh = 2 f_i / n``, sum-type at ``(f_i + f_j)/n``
    (``i < j``), difference-type at ``(f_j - f_i)/n`` (Hsu 1963; Nayfeh & Mook 1979, ch. 5;
    Bolotin 1964). For a mesh stiffness with harmonics, the region at ``n`` is both the
    first-order region of harmonic ``n`` and the ``n``-th order region of the fundamental; the
    selection rule is applied with ``l = n``. Repeated modes (degenerate planetary pairs) are
    listed once, as a cluster, e.g. ``"f3=f4"``. For symmetric systems with positive definite
    mean stiffness, difference-type regions do not exist (see ``notes`` in the result).
    """
    f = _positive_frequencies(natural_frequencies_hz, "natural_frequencies_hz")
    if isinstance(n_max, bool) or not isinstance(n_max, int | np.integer) \
            or not 1 <= n_max <= MAX_N:
        raise ValueError(f"n_max = {shown(n_max)} is not admissible: must be an integer "
                         f"1 .. {MAX_N}")
    kinds = tuple(kinds)
    bad = [k for k in kinds if k not in KINDS]
    if bad or not kinds:
        raise ValueError(f"kinds = {kinds!r} is not admissible: use a non-empty subset of {KINDS}")
    factor = None
    if mesh_frequency_per_rpm is not None:
        factor = require_positive(mesh_frequency_per_rpm, "mesh_frequency_per_rpm")
    if speed_range is not None:
        if factor is None:
            raise ValueError("speed_range needs mesh_frequency_per_rpm to convert to speed")
        lo, hi = (float(x) for x in speed_range)
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
            raise ValueError(f"speed_range = {speed_range!r} is not admissible: need "
                             "0 <= low < high")
    labels = list(mode_labels) if mode_labels is not None else [f"f{i + 1}" for i in
                                                                range(f.size)]
    if len(labels) != f.size:
        raise ValueError(f"mode_labels has {len(labels)} entries; natural_frequencies_hz has "
                         f"{f.size}")
    fams: list[tuple[Any, ...]] | None = None  # (kind, p) per mode, checked below
    if mesh_harmonic_rule is not None:
        if mode_families is None:
            raise ValueError("mesh_harmonic_rule needs mode_families ((kind, p) per mode)")
        if len(mode_families) != f.size:
            raise ValueError(f"mode_families has {len(mode_families)} entries; "
                             f"natural_frequencies_hz has {f.size}")
        fams = [tuple(fm) for fm in mode_families]
        for fm in fams:
            mesh_harmonic_rule.check_family(fm)

    notes: list[str] = []
    want_diff = "difference" in kinds and gyroscopic
    if not want_diff:
        notes.append(DIFFERENCE_NOTE)
    clusters = _cluster(f, require_positive(repeat_rtol, "repeat_rtol", allow_zero=True))
    rows: list[tuple] = []
    for n in range(1, int(n_max) + 1):
        for a, ca in enumerate(clusters):
            for b in range(a, len(clusters)):
                cb = clusters[b]
                fa, fb = f[ca].mean(), f[cb].mean()
                na, nb = _cluster_name(ca, labels), _cluster_name(cb, labels)
                items = []
                if a == b and "principal" in kinds:
                    lab = f"2 {na}" if n == 1 else (f"{na}" if n == 2 else f"2 {na}/{n}")
                    items.append(("principal", 2 * fa / n, lab))
                if a != b and "sum" in kinds:
                    lab = f"{na} + {nb}" if n == 1 else f"({na} + {nb})/{n}"
                    items.append(("sum", (fa + fb) / n, lab))
                if a != b and want_diff:
                    lab = f"{nb} - {na}" if n == 1 else f"({nb} - {na})/{n}"
                    items.append(("difference", (fb - fa) / n, lab))
                for kind, fm, lab in items:
                    ok, why = True, ""
                    if fams is not None and mesh_harmonic_rule is not None:
                        ok, why = _family_reason(mesh_harmonic_rule, n,
                                                 [fams[i] for i in ca],
                                                 [fams[i] for i in cb])
                    rpm = fm / factor if factor is not None else np.nan
                    rows.append((kind, ca[0], cb[0], n, fm, rpm, ok, why, lab))
    if speed_range is not None:
        rows = [r for r in rows if lo <= r[5] <= hi]
    rows.sort(key=lambda r: (r[4], r[3]))
    cols: list[Sequence[Any]] = list(zip(*rows, strict=True)) if rows else [[]] * 9

    def arr(i, dtype):
        return np.asarray(cols[i], dtype=dtype)

    return Candidates(
        kind=arr(0, object), mode_i=arr(1, int), mode_j=arr(2, int), n=arr(3, int),
        f_mesh_hz=arr(4, float), rpm=arr(5, float), allowed=arr(6, bool), reason=arr(7, object),
        label=arr(8, object), notes=tuple(notes), natural_frequencies_hz=f,
        mesh_frequency_per_rpm=factor,
        mesh_frequency=None if mesh_frequency_name is None
        else np.full(len(rows), str(mesh_frequency_name), dtype=object),
    )


@dataclass(frozen=True)
class FirstOrderWidths:
    """First-order instability regions (one row per harmonic and mode/cluster pair).

    Attributes
    ----------
    kind : ndarray of str
        ``"principal"`` or ``"sum"``.
    mode_i, mode_j : ndarray of int
        Zero-based index of the first mode of each cluster.
    harmonic : ndarray of int
        Mesh harmonic ``l``.
    centre_hz : ndarray
        Region centre ``(f_i + f_j)/l`` [Hz] of the mesh frequency.
    lower_hz, upper_hz, width_hz : ndarray
        Damped boundaries and width [Hz] of the mesh frequency (0 width: no region; inf: first
        order predicts instability at any detuning, see Notes).
    undamped_width_hz : ndarray
        Width [Hz] without damping.
    coupling : ndarray
        ``|D_ii|`` or ``|D_ij|`` (largest singular value of the cluster block) [rad2 s-2].
    lower_rpm, upper_rpm : ndarray
        Boundaries as input speed [min-1] (NaN without ``mesh_frequency_per_rpm``).
    label : ndarray of str
        Theory label.
    mesh_frequency : ndarray of str, optional
        Name of the mesh frequency whose harmonic ``l`` a row belongs to (systems with several
        mesh frequencies), None for a single one.
    """

    kind: np.ndarray
    mode_i: np.ndarray
    mode_j: np.ndarray
    harmonic: np.ndarray
    centre_hz: np.ndarray
    lower_hz: np.ndarray
    upper_hz: np.ndarray
    width_hz: np.ndarray
    undamped_width_hz: np.ndarray
    coupling: np.ndarray
    lower_rpm: np.ndarray
    upper_rpm: np.ndarray
    label: np.ndarray
    natural_frequencies_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mesh_frequency: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.centre_hz.size)

    def find(self, kind: str, mode_i: int, mode_j: int, harmonic: int = 1) -> int:
        """Row index of a region (mode indices of any cluster member accepted in order)."""
        hit = np.flatnonzero((self.kind == kind) & (self.mode_i == mode_i)
                             & (self.mode_j == mode_j) & (self.harmonic == harmonic))
        if hit.size == 0:
            raise KeyError(f"no {kind} region for modes ({mode_i}, {mode_j}) at l = {harmonic}")
        return int(hit[0])

    def to_dataset(self):
        """Table as :class:`xarray.Dataset` with dimension ``region``."""
        import xarray as xr

        def v(x, units, long_name):
            return ("region", x, {"units": units, "long_name": long_name})

        extra = {}
        if self.mesh_frequency is not None:
            extra["mesh_frequency"] = v(np.asarray(self.mesh_frequency).astype(str), "1",
                                        "mesh frequency whose harmonic l the region belongs to")
        ds = xr.Dataset(
            {
                **extra,
                "kind": v(self.kind.astype(str), "1", "region type"),
                "mode_i": v(self.mode_i, "1", "zero-based index of first mode"),
                "mode_j": v(self.mode_j, "1", "zero-based index of second mode"),
                "harmonic": v(self.harmonic, "1", "mesh harmonic l"),
                "centre": v(self.centre_hz, "Hz", "mesh frequency at region centre"),
                "lower": v(self.lower_hz, "Hz", "lower boundary mesh frequency (damped)"),
                "upper": v(self.upper_hz, "Hz", "upper boundary mesh frequency (damped)"),
                "width": v(self.width_hz, "Hz", "region width in mesh frequency (damped)"),
                "undamped_width": v(self.undamped_width_hz, "Hz",
                                    "region width in mesh frequency (undamped)"),
                "coupling": v(self.coupling, "rad2 s-2", "modal parametric coupling |D|"),
                "lower_speed": v(self.lower_rpm, "min-1", "lower boundary input speed"),
                "upper_speed": v(self.upper_rpm, "min-1", "upper boundary input speed"),
                "label": v(self.label.astype(str), "1", "theory label"),
            },
            coords={"region": ("region", np.arange(len(self)),
                               {"units": "1", "long_name": "region index"})},
        )
        return cf_dataset(
            ds, title="first-order widths of instability regions",
            producer="analysis.instability.first_order_widths"
        )

    def __str__(self) -> str:
        lines = [f"{'label':>20} {'l':>2} {'centre [Hz]':>12} {'width [Hz]':>12} "
                 f"{'undamped [Hz]':>13}"]
        for r in range(len(self)):
            lines.append(f"{self.label[r]:>20} {self.harmonic[r]:2d} {self.centre_hz[r]:12.4f} "
                         f"{self.width_hz[r]:12.6g} {self.undamped_width_hz[r]:13.6g}")
        return "\n".join(lines)


def first_order_widths(
    M: Any,
    C: Any,
    K_mean: Any,
    K_harmonics: Any,
    *,
    mesh_frequency_per_rpm: float | None = None,
    kinds: Sequence[str] = ("principal", "sum"),
    mode_labels: Sequence[str] | None = None,
    repeat_rtol: float = 1e-6,
) -> FirstOrderWidths:
    """First-order widths of principal and sum-type instability regions.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix [kg], symmetric positive definite.
    C : array_like, shape (n, n)
        Damping matrix [N s/m]; only the diagonal of the modal damping enters.
    K_mean : array_like, shape (n, n)
        Period-mean stiffness [N/m], symmetric positive definite (rigid-body modes removed).
    K_harmonics : array_like, shape (L, n, n) or (n, n), complex
        ``K_harmonics[l-1]`` is the complex Fourier coefficient ``K^_l`` in
        ``K(t) = K_mean + sum_l (K^_l exp(i l Omega t) + c.c.)``; symmetric.
    mesh_frequency_per_rpm : float, optional
        Mesh frequency per input speed [Hz/min-1] for the speed columns.
    kinds : sequence of str
        Subset of ``("principal", "sum")``.
    mode_labels : sequence of str, optional
        Mode names (default ``f1, f2, ...``).
    repeat_rtol : float
        Relative tolerance for repeated natural frequencies (degenerate clusters).

    Returns
    -------
    FirstOrderWidths

    Notes
    -----
    Modal form ``q = Phi eta`` with ``Phi^T M Phi = I``, ``Phi^T K_mean Phi = diag(w^2)``,
    ``D_l = Phi^T K^_l Phi`` and ``mu_i = (Phi^T C Phi)_ii / 2 = zeta_i w_i``. With detuning
    ``sigma = l Omega - (w_i + w_j)`` (Hsu 1963; Nayfeh & Mook 1979, sec. 5.7):

    * principal ``l Omega ~ 2 w_i``: unstable iff ``sigma^2 < |D_ii|^2/w_i^2 - 4 mu_i^2``;
    * sum ``l Omega ~ w_i + w_j``: with ``Lambda = |D_ij|^2/(4 w_i w_j)``, undamped
      ``|sigma| < 2 sqrt(Lambda)``; damped
      ``sigma^2 < (mu_i + mu_j)^2 (Lambda - mu_i mu_j)/(mu_i mu_j)``.

    The unequal-damping sum formula does not tend to the undamped one as damping vanishes
    unless ``mu_i = mu_j`` (dissipation-induced destabilisation; Seyranian & Mailybaev 2003); if
    exactly one of ``mu_i, mu_j`` is zero, first order predicts instability at every detuning
    and the width is reported as ``inf``. Widths in ``Omega`` are the above divided by ``l``,
    in Hz further divided by ``2 pi``. For repeated modes (clusters ``I``, ``J``) ``|D_ij|`` is
    replaced by the largest singular value of the block ``D_l[I, J]`` (``I = J`` for the
    principal region of a degenerate pair); the cluster damping is the mean of its members.
    Difference-type regions do not exist for symmetric systems (see
    :func:`instability_candidates`). Higher-order regions (``n``-th region of one harmonic)
    need higher-order perturbation or :func:`analysis.instability.floquet.floquet`.
    """

    m = require_mass_matrix(M)
    n = m.shape[0]
    c = require_square(C, "C", n)
    k0 = require_square(K_mean, "K_mean", n)
    if not np.allclose(k0, k0.T, rtol=1e-10, atol=1e-14 * np.abs(k0).max()):
        raise ValueError("K_mean must be symmetric")
    kh = np.asarray(K_harmonics, dtype=complex)
    if kh.ndim == 2:
        kh = kh[None]
    if kh.ndim != 3 or kh.shape[1:] != (n, n) or kh.shape[0] < 1:
        raise ValueError(f"K_harmonics must have shape (L, {n}, {n}); got {kh.shape}")
    if not np.all(np.isfinite(kh)):
        raise ValueError("K_harmonics holds non-finite values; only finite values are admissible")
    scale = max(float(np.abs(kh).max()), 1e-300)
    if not np.allclose(kh, np.swapaxes(kh, 1, 2), rtol=0, atol=1e-10 * scale):
        raise ValueError("K_harmonics must be symmetric (each K^_l == K^_l.T); for "
                         "non-symmetric systems use floquet()")
    kinds = tuple(kinds)
    if not kinds or any(k not in ("principal", "sum") for k in kinds):
        raise ValueError(f"kinds = {kinds!r} is not admissible: use a subset of "
                         "('principal', 'sum')")
    factor = (require_positive(mesh_frequency_per_rpm, "mesh_frequency_per_rpm")
              if mesh_frequency_per_rpm is not None else None)
    labels = list(mode_labels) if mode_labels is not None else [f"f{i + 1}" for i in range(n)]
    if len(labels) != n:
        raise ValueError(f"mode_labels has {len(labels)} entries; the system has {n} modes")
    w2, phi = scipy.linalg.eigh(k0, m)
    if np.any(w2 <= 0):
        raise ValueError("K_mean must be positive definite with respect to M (rigid-body modes "
                         "must be removed or constrained first)")
    w = np.sqrt(w2)
    mu = 0.5 * np.diag(phi.T @ c @ phi)
    d = np.einsum("ai,lab,bj->lij", phi, kh, phi)
    clusters = _cluster(w, require_positive(repeat_rtol, "repeat_rtol", allow_zero=True))
    rows = []
    for li in range(kh.shape[0]):
        ell = li + 1
        for a, ca in enumerate(clusters):
            for b in range(a, len(clusters)):
                cb = clusters[b]
                kind = "principal" if a == b else "sum"
                if kind not in kinds:
                    continue
                wa, wb = w[ca].mean(), w[cb].mean()
                ma, mb = mu[ca].mean(), mu[cb].mean()
                coup = float(np.linalg.svd(d[li][np.ix_(ca, cb)], compute_uv=False)[0])
                if kind == "principal":
                    h0 = coup / wa
                    h2 = h0**2 - 4.0 * ma**2
                    h = np.sqrt(h2) if h2 > 0 else 0.0
                    name = _cluster_name(ca, labels)
                    lab = f"2 {name}" if ell == 1 else f"2 {name}/{ell}"
                else:
                    lam = coup**2 / (4.0 * wa * wb)
                    h0 = 2.0 * np.sqrt(lam)
                    if ma == 0 and mb == 0:
                        h = h0
                    elif ma * mb <= 0:
                        h = np.inf if lam > 0 else 0.0
                    elif lam > ma * mb:
                        h = (ma + mb) * np.sqrt((lam - ma * mb) / (ma * mb))
                    else:
                        h = 0.0
                    na, nb = _cluster_name(ca, labels), _cluster_name(cb, labels)
                    lab = f"{na} + {nb}" if ell == 1 else f"({na} + {nb})/{ell}"
                centre = (wa + wb) / ell / (2 * np.pi)
                half = h / ell / (2 * np.pi)
                lower = centre - half if h > 0 else centre
                upper = centre + half if h > 0 else centre
                rows.append((kind, ca[0], cb[0], ell, centre, lower, upper, 2 * half,
                             2 * h0 / ell / (2 * np.pi), coup, lab))
    cols = list(zip(*rows, strict=True))
    lower = np.asarray(cols[5], float)
    upper = np.asarray(cols[6], float)
    to_rpm = (lambda x: x / factor) if factor is not None else (lambda x: np.full_like(x, np.nan))
    return FirstOrderWidths(
        kind=np.asarray(cols[0], object), mode_i=np.asarray(cols[1], int),
        mode_j=np.asarray(cols[2], int), harmonic=np.asarray(cols[3], int),
        centre_hz=np.asarray(cols[4], float), lower_hz=lower, upper_hz=upper,
        width_hz=np.asarray(cols[7], float), undamped_width_hz=np.asarray(cols[8], float),
        coupling=np.asarray(cols[9], float), lower_rpm=to_rpm(lower), upper_rpm=to_rpm(upper),
        label=np.asarray(cols[10], object), natural_frequencies_hz=w / (2 * np.pi),
    )


def _check_wave(k_min: float, k_max: float, contact_ratio: float, phase: float) -> float:
    kmin = require_positive(k_min, "k_min")
    kmax = float(k_max)
    if not (np.isfinite(kmax) and kmax >= kmin):
        raise ValueError(f"k_max = {k_max!r} is not admissible: must be finite and >= k_min")
    c = float(contact_ratio)
    if not (1.0 < c < 2.0):
        raise ValueError(f"contact_ratio = {contact_ratio!r} is not admissible: must be in (1, 2)")
    if not np.isfinite(float(phase)):
        raise ValueError(f"phase = {phase!r} is not admissible: must be finite (fraction of a "
                         "mesh period)")
    return c


def rectangular_wave_harmonics(
    k_min: float, k_max: float, contact_ratio: float, phase: float, l_max: int
) -> tuple[float, np.ndarray]:
    """Mean and complex Fourier coefficients of a rectangular mesh-stiffness wave.

    Parameters
    ----------
    k_min, k_max : float
        Single- and double-contact stiffness [N/m], ``0 < k_min <= k_max``.
    contact_ratio : float
        Contact ratio ``c`` with ``1 < c < 2``.
    phase : float
        Start of the double-contact interval as a fraction ``gamma`` of the mesh period.
    l_max : int
        Number of harmonics.

    Returns
    -------
    k_mean : float
        Mean stiffness [N/m].
    harmonics : ndarray, shape (l_max,), complex
        ``k^_l`` [N/m] for ``l = 1..l_max`` in ``k(t) = k_mean + sum (k^_l e^{il Omega t} + c.c.)``.

    Notes
    -----
    The stiffness is ``k_max`` for the fraction ``d = c - 1`` of the period starting at
    ``gamma`` and ``k_min`` otherwise (Lin & Parker 2002). With ``dk = k_max - k_min``:
    ``k_mean = k_min + d dk`` and
    ``k^_l = dk exp(-i 2 pi l gamma) exp(-i pi l c) sin(pi l c)/(pi l)``, so
    ``|k^_l| = dk |sin(pi l c)|/(pi l)``; harmonic ``l`` vanishes when ``l c`` is an integer.
    """
    c = _check_wave(k_min, k_max, contact_ratio, phase)
    if int(l_max) != l_max or l_max < 1:
        raise ValueError(f"l_max = {l_max!r} is not admissible: must be an integer >= 1")
    dk = float(k_max) - float(k_min)
    ell = np.arange(1, int(l_max) + 1)
    kh = (dk * np.exp(-2j * np.pi * ell * float(phase)) * np.exp(-1j * np.pi * ell * c)
          * np.sin(np.pi * ell * c) / (np.pi * ell))
    return float(k_min) + (c - 1.0) * dk, kh


def rectangular_wave_pieces(
    k_min: float, k_max: float, contact_ratio: float, phase: float, period: float
) -> tuple[np.ndarray, np.ndarray]:
    """Durations and stiffness values of a rectangular wave over one period from ``t = 0``.

    Parameters
    ----------
    k_min, k_max, contact_ratio, phase : float
        As in :func:`rectangular_wave_harmonics`.
    period : float
        Mesh period [s].

    Returns
    -------
    durations : ndarray
        Piece durations [s], summing to ``period``.
    values : ndarray
        Stiffness [N/m] during each piece (multiply by a mesh vector outer product and pass to
        :class:`analysis.instability.floquet.PiecewiseConstant`).
    """
    c = _check_wave(k_min, k_max, contact_ratio, phase)
    T = require_positive(period, "period")
    d = c - 1.0
    g = float(phase) % 1.0
    edges = sorted({0.0, 1.0, g, (g + d) % 1.0})
    durs, vals = [], []
    for a, b in itertools.pairwise(edges):
        if b - a <= 0:
            continue
        mid = 0.5 * (a + b)
        inside = (mid - g) % 1.0 < d
        durs.append((b - a) * T)
        vals.append(float(k_max) if inside else float(k_min))
    return np.asarray(durs), np.asarray(vals)
