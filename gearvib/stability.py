"""Parametric stability of an assembled gear set at constant speed (Floquet, theory candidates).

This is the gear-set side of :mod:`analysis.instability`, which is generic: here the periodic
system ``M q'' + C q' + K(t) q = 0`` is built from an :class:`AssembledModel` at a given mesh
frequency, with every contact at its own phase and all flanks in contact (the linear system
about the loaded state), and the theory candidates get the mode families and the planetary
mesh-phasing rule of the gear set.

The input member is held by the same drive coupling the run-up simulation uses, so the
rigid-body mode is removed and the stability chart describes the simulated system.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from analysis.instability import (
    Candidates,
    MeshPhasingRule,
    PiecewiseConstant,
    StabilityChart,
    first_order_widths,
    instability_candidates,
    stability_chart,
)
from gearvib.modal import ModalResult, modal_analysis
from gearvib.model import AssembledModel
from gearvib.simulate import DriveCoupling, default_coupling

__all__ = [
    "PeriodicGearSystem",
    "first_order_regions",
    "gear_set_candidates",
    "mesh_phasing",
    "periodic_system",
    "stability_map",
    "stability_over_speed",
]


def _runs(table: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Breakpoints (fractions of a cycle) and values of a piecewise-constant table, or None."""
    n = table.size
    change = np.flatnonzero(table != np.roll(table, 1))
    if change.size == 0:
        return np.array([0.0]), table[:1].copy()
    if change.size > 16:
        return None
    return change / n, table[change]


@dataclass(frozen=True)
class PeriodicGearSystem:
    """The linearised periodic system of a gear set (all flanks in contact).

    Attributes
    ----------
    model : AssembledModel
        The gear set.
    mass, damping, stiffness : ndarray
        ``M``, constant ``C`` (bearings, meshes, drive) and constant ``K`` (bearings, drive).
    coupling : DriveCoupling
        The drive coupling holding the input member.
    """

    model: AssembledModel
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    coupling: DriveCoupling

    def mesh_stiffness_values(self, positions: np.ndarray) -> np.ndarray:
        """Left-flank stiffness of every mesh at the given positions [N/m]."""
        return self.model.mesh_stiffness_at(positions)

    def stiffness_at(self, t: float, mesh_frequency: float) -> np.ndarray:
        """``K(t)`` at constant mesh frequency [Hz]."""
        s = self.model.mesh_position_offsets + mesh_frequency * t
        return self.stiffness + self.model.mesh_stiffness_matrix(self.mesh_stiffness_values(s))

    def mean_stiffness(self) -> np.ndarray:
        """Cycle-mean stiffness matrix."""
        return self.stiffness + self.model.mesh_stiffness_matrix()

    def at(self, mesh_frequency: float):
        """``(M, C, K, period)`` for :func:`analysis.instability.floquet`.

        Piecewise-constant tables (rectangular stiffness) give an exact
        :class:`~analysis.instability.PiecewiseConstant`; otherwise ``K`` is a callable.
        """
        if not mesh_frequency > 0:
            raise ValueError(f"mesh_frequency = {mesh_frequency} must be > 0")
        period = 1.0 / mesh_frequency
        runs = [_runs(t) for t in self.model.mesh_stiffness_tables]
        if all(r is not None for r in runs):
            cuts = {0.0}
            for r, s0 in zip(runs, self.model.mesh_position_offsets, strict=True):
                cuts.update(((r[0] - s0) % 1.0).tolist())
            edges = np.array([*sorted(cuts), 1.0])
            edges = edges[np.concatenate([[True], np.diff(edges) > 1e-12])]
            mids = 0.5 * (edges[:-1] + edges[1:])
            mats = np.array([self.stiffness_at(m * period, mesh_frequency) for m in mids])
            durations = np.diff(edges) * period
            durations[-1] = period - durations[:-1].sum()
            return self.mass, self.damping, PiecewiseConstant(durations, mats), period
        return (self.mass, self.damping,
                lambda t: self.stiffness_at(t, mesh_frequency), period)

    def harmonics(self, l_max: int = 4) -> tuple[np.ndarray, np.ndarray]:
        """``(K_mean, K_hat)``: Fourier coefficients of ``K`` over one mesh cycle.

        ``K(t) = K_mean + sum_l (K_hat[l-1] exp(i l Omega t) + c.c.)``, computed from the
        stiffness tables by FFT with every mesh at its phase.
        """
        tables = self.model.mesh_stiffness_tables
        n_table = tables.shape[1]
        c = np.fft.rfft(tables, axis=1) / n_table  # coefficient of exp(+i 2 pi l s)
        v = self.model.mesh_vectors
        k_hat = np.zeros((l_max, *self.mass.shape), dtype=complex)
        for ell in range(1, l_max + 1):
            coef = c[:, ell] * np.exp(2j * math.pi * ell * self.model.mesh_position_offsets)
            k_hat[ell - 1] = (v.T * coef) @ v
        return self.mean_stiffness(), k_hat


def periodic_system(model: AssembledModel, *, coupling: DriveCoupling | None = None
                    ) -> PeriodicGearSystem:
    """Build the periodic system of ``model`` held at the input by a drive coupling.

    Parameters
    ----------
    model : AssembledModel
    coupling : DriveCoupling, optional
        Default: :func:`gearvib.simulate.default_coupling` (the run-up simulation's).
    """
    coupling = coupling or default_coupling(model)
    k_in = model.rotation_dofs[model.input_member]
    kd = np.zeros_like(model.stiffness)
    kd[k_in, k_in] = coupling.stiffness
    cd = np.zeros_like(model.stiffness)
    cd[k_in, k_in] = coupling.damping
    damping = model.damping + model.mesh_damping_matrix() + cd
    return PeriodicGearSystem(model, model.mass, damping, model.stiffness + kd, coupling)


def _circular_harmonic(model: AssembledModel, shape: np.ndarray, planets: list[str]) -> int:
    """Dominant circular harmonic ``p`` (0 ... N//2) of the planets' motion in a mode."""
    n = len(planets)
    comps: dict[str, np.ndarray] = {}
    for i, name in enumerate(model.dof_names):
        body, comp = name.rsplit(".", 1)
        if body in planets:
            comps.setdefault(comp, np.zeros(n, dtype=complex))[planets.index(body)] = shape[i]
    energy = np.zeros(n)
    for values in comps.values():
        energy += np.abs(np.fft.fft(values)) ** 2
    folded = [energy[k] + (energy[n - k] if 0 < k < n - k else 0.0) for k in range(n // 2 + 1)]
    return int(np.argmax(folded))


def _mode_families(model: AssembledModel, modal: ModalResult, keep: np.ndarray
                   ) -> list[tuple[str, int]] | None:
    """``(kind, p)`` of every kept mode, or None when a mode is not of a pure family."""
    planets = [p["name"] for p in model.meta.get("planets", [])]
    fam = []
    for i in np.flatnonzero(keep):
        kind = modal.kinds[i]
        if kind not in ("rotational", "translational", "planet"):
            return None
        fam.append((kind, _circular_harmonic(model, modal.shapes[:, i], planets)))
    return fam


def mesh_phasing(model: AssembledModel, modal: ModalResult | None = None
                 ) -> tuple[MeshPhasingRule | None, list[tuple[str, int]] | None]:
    """The planetary mesh-phasing rule of a gear set and the family of every elastic mode.

    Returns ``(rule, families)``: for a simple set with equally spaced, identical planets the
    :class:`~analysis.instability.MeshPhasingRule` and one ``(kind, p)`` per elastic mode
    (rigid-body modes left out); ``(None, None)`` otherwise (unequal spacing, modes of no pure
    family).
    """
    modal = modal or modal_analysis(model)
    keep = np.array([k != "rigid-body" for k in modal.kinds], dtype=bool)
    planets = model.meta.get("planets", [])
    meshes = model.meta.get("meshes", [])
    z_sun = next((m["z1"] for m in meshes if m["z1"] and m["z1"] > 0), None)
    z_ring = next((-m["z1"] for m in meshes if m["z1"] and m["z1"] < 0), None)
    angles = [p["angle_deg"] for p in planets]
    n = len(angles)
    equal = n >= 2 and np.allclose(np.diff(np.sort(angles)), 360.0 / n, atol=1e-6)
    if not (equal and z_sun):
        return None, None
    families = _mode_families(model, modal, keep)
    if families is None:
        return None, None
    return MeshPhasingRule(n_planets=n, sun_teeth=int(z_sun),
                           ring_teeth=int(z_ring) if z_ring else None), families


def gear_set_candidates(model: AssembledModel, modal: ModalResult | None = None, *,
                        n_max: int = 4, speed_range: tuple[float, float] | None = None
                        ) -> Candidates:
    """Theory candidates ``2 f_i / n`` and ``(f_i + f_j) / n`` of a gear set, with speeds.

    For a simple planetary set with equally spaced, identical planets the mesh-phasing
    selection rule (Parker 2000; physics notes 4.5) marks the candidates the phasing
    suppresses. Each mode's family is its classification with the dominant circular harmonic
    ``p`` of the planets' motion (0 rotational, 1 translational, ``j`` planet modes); the rule
    is not applied when a mode is of no pure family (unequal spacing, ``other`` modes).
    """
    modal = modal or modal_analysis(model)
    keep = np.array([k != "rigid-body" for k in modal.kinds], dtype=bool)
    freqs = modal.frequencies_hz[keep]
    labels = [f"f{i + 1}" for i in np.flatnonzero(keep)]
    rule, families = mesh_phasing(model, modal)
    return instability_candidates(
        freqs, n_max=n_max, mesh_frequency_per_rpm=model.mesh_frequency_per_rpm,
        speed_range=speed_range, mode_labels=labels,
        mode_families=families if rule else None, mesh_harmonic_rule=rule)


def stability_over_speed(model: AssembledModel, speeds_rpm: np.ndarray, *,
                         coupling: DriveCoupling | None = None, n_max: int = 4,
                         refine: bool = True) -> StabilityChart:
    """Floquet stability chart over input speed, with regions attributed to theory candidates.

    Parameters
    ----------
    model : AssembledModel
    speeds_rpm : array_like
        Increasing input speeds [min^-1] (> 0).
    coupling : DriveCoupling, optional
        Drive coupling at the input (default: the simulation's).
    n_max : int
        Highest order of the theory candidates.
    refine : bool
        Refine the region boundaries by root finding.
    """
    speeds = np.asarray(speeds_rpm, dtype=float)
    if speeds.ndim != 1 or speeds.size < 2 or not (speeds > 0).all():
        raise ValueError("speeds_rpm must be an increasing 1-D array of positive speeds")
    system = periodic_system(model, coupling=coupling)
    f_per_rpm = model.mesh_frequency_per_rpm
    cands = gear_set_candidates(model, n_max=n_max,
                                speed_range=(float(speeds[0]), float(speeds[-1])))
    return stability_chart(system.at, speeds * f_per_rpm, mesh_frequency_per_rpm=f_per_rpm,
                           candidates=cands, refine=refine)


def stability_map(model_for: Callable[[float], AssembledModel], speeds_rpm: np.ndarray,
                  values: np.ndarray, *, parameter_name: str = "parameter",
                  parameter_units: str = "1", refine: bool = False) -> StabilityChart:
    """Ince-Strutt style chart of a gear set over input speed x one design parameter.

    Parameters
    ----------
    model_for : callable
        ``model_for(value) -> AssembledModel``, e.g. the gear set rebuilt with another mesh
        damping ratio, stiffness variation or contact ratio.
    speeds_rpm : array_like
        Increasing input speeds [min^-1].
    values : array_like
        Parameter values (one Floquet scan over speed each).
    parameter_name, parameter_units : str
        Metadata of the parameter axis.
    refine : bool
        Refine region boundaries (slower).
    """
    speeds = np.asarray(speeds_rpm, dtype=float)
    vals = [float(v) for v in np.asarray(values, dtype=float).ravel()]
    if speeds.ndim != 1 or speeds.size < 2 or not (speeds > 0).all() or not vals:
        raise ValueError("speeds_rpm must be increasing positive speeds and values non-empty")
    systems: dict[float, PeriodicGearSystem] = {}

    def system(value: float) -> PeriodicGearSystem:
        if value not in systems:
            systems[value] = periodic_system(model_for(value))
        return systems[value]

    f_per_rpm = system(vals[0]).model.mesh_frequency_per_rpm
    return stability_chart(lambda f, p: system(float(p)).at(f), speeds * f_per_rpm,
                           parameter_values=vals, mesh_frequency_per_rpm=f_per_rpm,
                           refine=refine, parameter_name=parameter_name,
                           parameter_units=parameter_units)


def first_order_regions(model: AssembledModel, *, coupling: DriveCoupling | None = None,
                        l_max: int = 4):
    """First-order perturbation widths of the principal and sum-type regions (Hsu 1963)."""
    system = periodic_system(model, coupling=coupling)
    k_mean, k_hat = system.harmonics(l_max)
    return first_order_widths(system.mass, system.damping, k_mean, k_hat,
                              mesh_frequency_per_rpm=model.mesh_frequency_per_rpm)
