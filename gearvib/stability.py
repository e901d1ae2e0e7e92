"""Parametric stability of an assembled gear set at constant speed (Floquet, theory candidates).

This is the gear-set side of :mod:`analysis.instability`, which is generic: here the periodic
system ``M q'' + C q' + K(t) q = 0`` is built from an :class:`AssembledModel` at a given mesh
frequency, with every contact at its own phase and the loaded flanks in contact (the linear
system about the loaded state: :meth:`AssembledModel.mesh_contacts`, i.e. the left or the back
flank on its own line of action, both flanks with stiffness and damping for a negative
backlash), and the theory candidates get the mode families and the planetary mesh-phasing rule
of the gear set.

The input member is held by the same drive coupling the run-up simulation uses, so the
rigid-body mode is removed and the stability chart describes the simulated system. The default
drive, a speed controller on the rigid-body mode, enters as the symmetric ``k p p^T``, ``c p
p^T`` (:func:`gearvib.simulate.coupling_matrices`): the simulated form (the torque on the
input member) has the same Floquet multipliers, and the elastic modes are those of the free
set.

Several mesh frequencies
------------------------
A two-stage or Wolfrom set has meshes at different frequencies (``model.mesh_frequency_groups``):
at constant input speed every group ``g`` runs at ``f_g = r_g f_1``, ``r_g`` a fixed kinematic
ratio, and ``K(t)`` is periodic only if all ``r_g`` are rational. The analysis uses one common
period of ``L`` reference mesh cycles (group 1) in which group ``g`` completes ``N_g`` cycles:

* **common period** (exact): ``r_g = N_g / L`` with ``L + sum N_g <= max_cycles`` (two equal
  stages of the paper's set: ``r_2 = 11/49``, 49 + 11 cycles);
* **commensurate approximation** otherwise (hunting-tooth ratios such as 1771/8900): the best
  ``N_g / L`` within the same cycle budget replaces ``r_g``, i.e. group ``g`` is detuned by
  ``delta_g = |N_g / (r_g L) - 1|``. Every region that group ``g`` causes moves in speed by
  that relative amount at most (its centres scale with ``1 / f_g``); the relative phase of the
  groups is sampled on a grid of ``1 / L`` cycle instead of densely. ``delta_g`` is reported
  (:attr:`PeriodicGearSystem.period`) and the analysis refuses a detuning above
  ``max_detuning`` (default 1e-3) instead of answering wrongly.

The cost of one Floquet evaluation is that of a single-frequency set times the number of mesh
cycles ``L + sum N_g`` in the period (at most ``max_cycles``, default 256): the stiffness pieces
of the common period are computed once per system, each evaluation is one product of matrix
exponentials.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from analysis.checks import require_instance, require_real_array
from analysis.instability import (
    Candidates,
    FirstOrderWidths,
    MeshPhasingRule,
    PiecewiseConstant,
    PiecewiseSmooth,
    StabilityChart,
    first_order_widths,
    instability_candidates,
    stability_chart,
)
from gearvib.checks import check_count, check_real, check_text, short
from gearvib.execution import default_workers, executor_for
from gearvib.kinematics import MAX_SPEED_RPM
from gearvib.modal import ModalResult, modal_analysis
from gearvib.model import AssembledModel, MeshContacts, MeshFrequencyGroup, interpolate_tables
from gearvib.simulate import DriveCoupling, coupling_matrices, default_coupling

__all__ = [
    "ATTRIBUTION_N_MAX",
    "CHART_ACCURACY",
    "MAX_CYCLES",
    "MAX_DETUNING",
    "CommonPeriod",
    "PeriodicGearSystem",
    "common_period",
    "cycle_budget",
    "first_order_regions",
    "gear_set_candidates",
    "mesh_phasing",
    "periodic_system",
    "stability_map",
    "stability_over_speed",
]

MAX_GROUPS = 1000
"""Most mesh-frequency groups (ratios) of :func:`common_period`."""
MAX_CYCLE_BUDGET = 100_000
"""Largest ``max_cycles`` (a search over that many periods)."""
MAX_N = 100
"""Largest order ``n`` of the theory candidates."""
MAX_HARMONICS = 1000
"""Most stiffness harmonics of :func:`first_order_regions`."""
MAX_CHART_POINTS = 200_000
"""Most points (speeds x parameter values) of a stability chart."""
MAX_CYCLES = 256
"""Default budget of mesh cycles (all groups) in the common period of several mesh frequencies."""

MAX_DETUNING = 1e-3
"""Default largest admissible relative detuning of a mesh frequency (commensurate approximation)."""

_EXACT_RTOL = 1e-9
_MAX_KINKS = 64  # a table with more slope changes per cycle is treated as smooth
_BANDWIDTH_RTOL = 1e-6  # harmonics below this fraction of the largest one are negligible


def _kinks(table: np.ndarray) -> np.ndarray | None:
    """Mesh positions [cycles] where the linear interpolant of a table changes slope.

    None when there are more than :data:`_MAX_KINKS` (a smooth table: every sample is one).
    """
    d2 = np.roll(table, -1) - 2.0 * table + np.roll(table, 1)
    scale = float(np.max(np.abs(table))) if table.size else 0.0
    idx = np.flatnonzero(np.abs(d2) > 1e-9 * scale)
    if idx.size > _MAX_KINKS:
        return None
    return idx / table.size


def _bandwidth_grid(table: np.ndarray) -> np.ndarray:
    """Uniform grid [cycles] for a smooth table: 8 points per period of its highest harmonic.

    The highest harmonic is the last one above :data:`_BANDWIDTH_RTOL` of the largest; the grid
    has 16 to 512 points per cycle. It only places the sub-steps of the Floquet product
    (:class:`~analysis.instability.PiecewiseSmooth`), whose number is refined until the result
    converges.
    """
    amp = np.abs(np.fft.rfft(table)[1:])
    keep = np.flatnonzero(amp > _BANDWIDTH_RTOL * amp.max()) if amp.size and amp.max() > 0 \
        else np.zeros(0, dtype=int)
    l_max = int(keep[-1]) + 1 if keep.size else 1
    n = int(np.clip(8 * l_max, 16, 512))
    return np.arange(n) / n


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
class CommonPeriod:
    """How a system with several mesh frequencies is made periodic.

    Attributes
    ----------
    method : str
        ``"single"`` (one mesh frequency), ``"common period"`` (exact) or
        ``"commensurate approximation"``.
    reference_cycles : int
        ``L``: the period is ``L`` cycles of the reference (first) mesh frequency.
    cycles : tuple of int
        ``N_g``: cycles of every group in one period (``cycles[0] == L``).
    ratios : tuple of float
        ``r_g = f_g / f_1`` of the gear set (kinematics).
    detuning : tuple of float
        ``|N_g / (r_g L) - 1|`` per group (0 when exact).
    """

    method: str
    reference_cycles: int
    cycles: tuple[int, ...]
    ratios: tuple[float, ...]
    detuning: tuple[float, ...]

    @property
    def used_ratios(self) -> tuple[float, ...]:
        """``N_g / L``: the ratios the analysis uses."""
        return tuple(n / self.reference_cycles for n in self.cycles)

    @property
    def max_detuning(self) -> float:
        """Largest relative detuning of a mesh frequency."""
        return max(self.detuning, default=0.0)

    def describe(self, names: Sequence[str] | None = None) -> str:
        """One line for reports and chart metadata.

        E.g. ``"common period (exact): 49 cycles of stage 1 = 11 of stage 2"``.
        """
        if self.method == "single":
            return "one mesh frequency: period = one mesh cycle"
        names = list(names) if names is not None else [f"f_mesh,{i + 1}"
                                                       for i in range(len(self.cycles))]
        first = f"{self.cycles[0]} cycles of {names[0]}"
        rest = ", ".join(f"{n} of {name}" for n, name in zip(self.cycles[1:], names[1:],
                                                             strict=True))
        if self.method == "common period":
            return f"common period (exact): {first} = {rest}"
        return (f"commensurate approximation: {first} ≈ {rest}, largest detuning "
                f"{self.max_detuning:.2g}")


def common_period(ratios: Sequence[float], *, max_cycles: int = MAX_CYCLES,
                  max_detuning: float = MAX_DETUNING) -> CommonPeriod:
    """Common period of mesh frequencies ``f_g = r_g f_1`` (exact or approximated).

    Parameters
    ----------
    ratios : sequence of float
        ``r_g = f_g / f_1``, first entry 1 (the reference), all > 0.
    max_cycles : int
        Budget of mesh cycles ``L + sum_g N_g`` over all groups in the period (cost bound).
    max_detuning : float
        Largest admissible relative detuning ``|N_g / (r_g L) - 1|`` when no exact common
        period fits the budget.

    Returns
    -------
    CommonPeriod
        The smallest exact common period within the budget, else the ``L`` whose largest
        detuning is smallest.

    Raises
    ------
    ValueError
        Inadmissible ratios or budget, or no period within ``max_cycles`` detunes every mesh
        frequency by at most ``max_detuning`` (the message names the detuning reached and how
        to proceed).
    """
    r = require_real_array(ratios, "ratios", min_size=0).ravel()
    if r.size == 0 or r.size > MAX_GROUPS or np.any(r <= 0) or r[0] != 1.0:
        raise ValueError(f"ratios = {short(list(r))} are not admissible: 1 .. {MAX_GROUPS} "
                         "finite ratios > 0, first entry 1")
    check_count(max_cycles, "max_cycles", high=MAX_CYCLE_BUDGET)
    if max_cycles < r.size:
        raise ValueError(f"max_cycles = {max_cycles!r} is not admissible: an integer >= "
                         f"{r.size} (one cycle per mesh frequency at least)")
    max_detuning = check_real(max_detuning, "max_detuning", low=0.0)
    if r.size == 1:
        return CommonPeriod("single", 1, (1,), (1.0,), (0.0,))
    best: tuple[float, int, np.ndarray, np.ndarray] | None = None
    for length in range(1, int(max_cycles) + 1):
        n = np.maximum(1, np.rint(r * length)).astype(np.int64)
        n[0] = length
        if n.sum() > max_cycles:  # the total never falls with L
            break
        det = np.abs(n / (r * length) - 1.0)
        if best is None or det.max() < best[0]:
            best = (float(det.max()), length, n, det)
        if det.max() <= _EXACT_RTOL:
            break
    assert best is not None
    worst, length, n, det = best
    if worst > max_detuning:
        raise ValueError(
            f"the mesh frequencies (ratios {', '.join(f'{x:.8g}' for x in r)} to the first) "
            f"have no common period within max_cycles = {max_cycles} mesh cycles: the best "
            f"commensurate approximation detunes them by {worst:.3g} > max_detuning = "
            f"{max_detuning:g}; raise max_cycles (cost grows in proportion) or max_detuning"
        )
    exact = worst <= _EXACT_RTOL
    return CommonPeriod("common period" if exact else "commensurate approximation", length,
                        tuple(int(x) for x in n), tuple(float(x) for x in r),
                        tuple(0.0 if exact else float(x) for x in det))


def _speeds(speeds_rpm: Any) -> np.ndarray:
    """Chart speeds: an increasing 1-D array of 2 .. MAX_CHART_POINTS speeds > 0 [min-1]."""
    speeds = require_real_array(speeds_rpm, "speeds_rpm", ndim=1, min_size=2,
                                max_abs=MAX_SPEED_RPM)
    if speeds.size > MAX_CHART_POINTS or not (speeds > 0).all():
        raise ValueError(f"speeds_rpm must be 2 .. {MAX_CHART_POINTS} speeds > 0 [min-1]")
    return speeds


def _chart_options(refine: Any, floquet_options: Any, progress: Any) -> None:
    if not isinstance(refine, bool):
        raise TypeError(f"refine must be a bool; got {type(refine).__name__}")
    if floquet_options is not None and not isinstance(floquet_options, dict):
        raise TypeError(f"floquet_options must be a dict; got {type(floquet_options).__name__}")
    if progress is not None and not isinstance(progress, bool):
        raise TypeError(f"progress must be a bool or None; got {type(progress).__name__}")


def cycle_budget(model: AssembledModel, *, max_detuning: float = MAX_DETUNING,
                 limit: int = 4 * MAX_CYCLES) -> int:
    """The smallest budget of mesh cycles (``MAX_CYCLES`` doubled up to ``limit``) at which
    the mesh frequencies of ``model`` have a common period within ``max_detuning``.

    A train of several stages (a wind-turbine gearbox: mesh ratios 1 : 4.73 : 18.1) needs
    more cycles than two stages; the cost of a Floquet evaluation grows in proportion.
    ``MAX_CYCLES`` when it suffices or when none up to ``limit`` does (the analysis then
    says so).

    Parameters
    ----------
    model : AssembledModel
        The gear set (its mesh-frequency groups).
    max_detuning : float
        Largest relative detuning admitted (:func:`common_period`).
    limit : int
        Largest budget tried.

    Returns
    -------
    int
        The budget to pass as ``max_cycles``.
    """
    require_instance(model, AssembledModel, "model")
    check_real(max_detuning, "max_detuning", low=0.0)
    check_count(limit, "limit", low=1, high=MAX_CYCLE_BUDGET)
    groups = model.mesh_frequency_groups()
    if len(groups) < 2:
        return MAX_CYCLES
    ratios = [g.frequency_per_rpm / groups[0].frequency_per_rpm for g in groups]
    budget = MAX_CYCLES
    while budget <= limit:
        try:
            common_period(ratios, max_cycles=budget, max_detuning=max_detuning)
            return budget
        except ValueError:
            budget *= 2
    return MAX_CYCLES


def _varying(model: AssembledModel) -> np.ndarray:
    """True for every mesh whose flank stiffness changes over the cycle."""
    out = np.zeros(model.n_mesh, dtype=bool)
    for t in (model.mesh_stiffness_tables, model.mesh_back_tables):
        out |= np.ptp(t, axis=1) > 1e-12 * np.maximum(np.abs(t).max(axis=1), 1e-300)
    return out


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
    groups : tuple of MeshFrequencyGroup
        The mesh frequencies of the model (first: the reference of :meth:`at`).
    period : CommonPeriod
        How several mesh frequencies share one period.
    mesh_rates : ndarray, shape (n_mesh,)
        Mesh cycles per reference mesh cycle as analysed (signed: the direction in which the
        stiffness table is traversed; ``N_g / L`` in magnitude, 0 for a mesh outside a group).
    contact_tables : ndarray, shape (n_contact, n_table)
        Stiffness of the flanks in contact over one mesh cycle [N/m], one row per contact of
        :attr:`contacts`. Default: the left-flank tables.
    contacts : MeshContacts, optional
        The flanks in contact (:meth:`AssembledModel.mesh_contacts`); default: every mesh on
        its left flank.
    """

    model: AssembledModel
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    coupling: DriveCoupling
    groups: tuple[MeshFrequencyGroup, ...] = ()
    period: CommonPeriod = CommonPeriod("single", 1, (1,), (1.0,), (0.0,))
    mesh_rates: np.ndarray | None = None
    contact_tables: np.ndarray | None = None
    contacts: MeshContacts | None = None

    @property
    def tables(self) -> np.ndarray:
        """:attr:`contact_tables`, or the tables of :attr:`contacts` (the model's left-flank
        tables when neither is given)."""
        if self.contact_tables is not None:
            return self.contact_tables
        if self.contacts is not None:
            return self.contacts.tables
        return self.model.mesh_stiffness_tables

    @property
    def contact_mesh(self) -> np.ndarray:
        """Mesh index of every contact."""
        if self.contacts is None:
            return np.arange(self.model.n_mesh)
        return self.contacts.mesh

    @property
    def contact_vectors(self) -> np.ndarray:
        """Deflection vector of every contact (its flank's line of action)."""
        if self.contacts is None:
            return self.model.mesh_vectors
        return self.contacts.vectors

    def _contact_matrix(self, k: np.ndarray) -> np.ndarray:
        v = self.contact_vectors
        return (v.T * np.asarray(k, dtype=float)) @ v

    @property
    def rates(self) -> np.ndarray:
        """:attr:`mesh_rates`, or +1 for every mesh when not given."""
        if self.mesh_rates is None:
            return np.ones(self.model.n_mesh)
        return self.mesh_rates

    @property
    def reference_frequency_per_rpm(self) -> float:
        """Reference (first) mesh frequency per input speed [Hz per min^-1]."""
        return self.groups[0].frequency_per_rpm if self.groups else math.nan

    def mesh_stiffness_values(self, positions: np.ndarray) -> np.ndarray:
        """Stiffness of every contact at the given positions of its mesh [N/m].

        ``positions`` has one entry per contact (``s[..., contact_mesh]``).
        """
        return interpolate_tables(self.tables, positions)

    def stiffness_at(self, t: float, mesh_frequency: float) -> np.ndarray:
        """``K(t)`` at constant reference mesh frequency [Hz]."""
        cm = self.contact_mesh
        s = self.model.mesh_position_offsets[cm] + self.rates[cm] * (mesh_frequency * t)
        return self.stiffness + self._contact_matrix(self.mesh_stiffness_values(s))

    def mean_stiffness(self) -> np.ndarray:
        """Cycle-mean stiffness matrix."""
        return self.stiffness + self._contact_matrix(self.tables.mean(axis=1))

    def stiffness_batch(self, t: np.ndarray, mesh_frequency: float) -> np.ndarray:
        """``K`` at an array of times [s] at constant reference mesh frequency [Hz].

        Returns an array ``(len(t), n, n)``; the same values as :meth:`stiffness_at`.
        """
        t = np.asarray(t, dtype=float).ravel()
        cm = self.contact_mesh
        s = (self.model.mesh_position_offsets[cm][None, :]
             + self.rates[cm][None, :] * (mesh_frequency * t[:, None]))
        values = self.mesh_stiffness_values(s)
        return self.stiffness[None] + np.einsum("kc,cij->kij", values, self._outer)

    @cached_property
    def _outer(self) -> np.ndarray:
        v = self.contact_vectors
        return np.einsum("ci,cj->cij", v, v)

    @cached_property
    def _smooth_edges(self) -> np.ndarray:
        """Breakpoints [reference mesh cycles] of ``K`` over one period, for tables that are
        not piecewise constant: every slope change of every contact's interpolated table
        (a trapezoid has 8 per cycle), or a grid sized by the bandwidth of a smooth table."""
        length = self.period.reference_cycles
        cuts = [np.array([0.0, float(length)])]
        cm = self.contact_mesh
        for table, s0, rate in zip(self.tables, self.model.mesh_position_offsets[cm],
                                   self.rates[cm], strict=True):
            if rate == 0.0 or np.ptp(table) <= 1e-12 * max(float(np.max(np.abs(table))),
                                                           1e-300):
                continue
            b = _kinks(table)
            if b is None:
                b = _bandwidth_grid(table)
            if b.size == 0:
                continue
            k = np.arange(math.floor(min(s0, s0 + rate * length)) - 1,
                          math.ceil(max(s0, s0 + rate * length)) + 1)
            u = ((b[None, :] + k[:, None]) - s0) / rate
            cuts.append(u[(u > 0) & (u < length)])
        edges = np.unique(np.concatenate(cuts))
        edges = edges[np.concatenate([[True], np.diff(edges) > 1e-12 * length])]
        edges[-1] = float(length)
        return edges

    @cached_property
    def _pieces(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Piece lengths [reference mesh cycles] and stiffness matrices over one period."""
        runs = [_runs(t) for t in self.tables]
        if not all(r is not None for r in runs):
            return None
        length = self.period.reference_cycles
        cuts = [np.array([0.0, float(length)])]
        cm = self.contact_mesh
        for r, s0, rate in zip(runs, self.model.mesh_position_offsets[cm], self.rates[cm],
                               strict=True):
            if r is None or r[0].size < 2 or rate == 0.0:  # constant table: no switching
                continue
            # s0 + rate u = b + k (mod 1) for u in [0, L)
            k = np.arange(math.floor(min(s0, s0 + rate * length)) - 1,
                          math.ceil(max(s0, s0 + rate * length)) + 1)
            u = ((r[0][None, :] + k[:, None]) - s0) / rate
            cuts.append(u[(u > 0) & (u < length)])
        edges = np.unique(np.concatenate(cuts))
        edges = edges[np.concatenate([[True], np.diff(edges) > 1e-12 * length])]
        if edges[-1] != length:
            edges[-1] = float(length)
        mids = 0.5 * (edges[:-1] + edges[1:])
        mats = np.array([self.stiffness_at(m, 1.0) for m in mids])
        return np.diff(edges), mats

    def at(self, mesh_frequency: float):
        """``(M, C, K, period)`` for :func:`analysis.instability.floquet`.

        ``mesh_frequency`` is the reference (first) mesh frequency [Hz]; the period is
        :attr:`period` ``.reference_cycles`` of its cycles. Piecewise-constant tables
        (rectangular stiffness) give an exact :class:`~analysis.instability.PiecewiseConstant`
        (pieces computed once per system); other tables a
        :class:`~analysis.instability.PiecewiseSmooth` with the slope changes of every
        contact's table as breakpoints (piecewise linear between them: trapezoidal, tabulated
        and ISO stiffness), or a grid sized by the bandwidth of a smooth table.
        """
        if not mesh_frequency > 0:
            raise ValueError(f"mesh_frequency = {mesh_frequency} must be > 0")
        period = self.period.reference_cycles / mesh_frequency
        pieces = self._pieces
        if pieces is not None:
            lengths, mats = pieces
            durations = lengths / mesh_frequency
            durations[-1] = period - durations[:-1].sum()
            return self.mass, self.damping, PiecewiseConstant(durations, mats), period
        edges = self._smooth_edges / mesh_frequency
        edges[-1] = period
        return (self.mass, self.damping,
                PiecewiseSmooth(edges, lambda t: self.stiffness_batch(t, mesh_frequency)),
                period)

    def harmonics(self, l_max: int = 4, group: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """``(K_mean, K_hat)``: Fourier coefficients of ``K`` over one cycle of a mesh frequency.

        ``K(t) = K_mean + sum_l (K_hat[l-1] exp(i l Omega_g t) + c.c.) + (other groups)``,
        computed from the stiffness tables by FFT with every mesh of group ``group`` at its
        phase and direction (the other groups enter the mean only; at first order the groups
        do not interact).
        """
        tables = self.tables
        n_table = tables.shape[1]
        c = np.fft.rfft(tables, axis=1) / n_table  # coefficient of exp(+i 2 pi l s)
        v = self.contact_vectors
        cm = self.contact_mesh
        members = np.zeros(self.model.n_mesh, dtype=bool)
        if self.groups:
            members[list(self.groups[group].meshes)] = True
        else:
            members[:] = True
        k_hat = np.zeros((l_max, *self.mass.shape), dtype=complex)
        for ell in range(1, l_max + 1):
            coef = c[:, ell] * np.exp(2j * math.pi * ell * self.model.mesh_position_offsets[cm])
            coef = np.where(self.rates[cm] < 0, np.conj(coef), coef) * members[cm]
            k_hat[ell - 1] = (v.T * coef) @ v
        return self.mean_stiffness(), k_hat


def periodic_system(model: AssembledModel, *, coupling: DriveCoupling | None = None,
                    max_cycles: int = MAX_CYCLES, max_detuning: float = MAX_DETUNING,
                    torque_sign: float = 1.0) -> PeriodicGearSystem:
    """Build the periodic system of ``model`` held at the input by a drive coupling.

    Parameters
    ----------
    model : AssembledModel
    coupling : DriveCoupling, optional
        Default: :func:`gearvib.simulate.default_coupling` (the run-up simulation's).
    max_cycles, max_detuning
        Budget and tolerance of the common period of several mesh frequencies (see
        :func:`common_period` and the module docstring).
    torque_sign : float
        Sense of the mean load (+1: the input drives forward): selects the loaded flanks.
    """
    require_instance(model, AssembledModel, "model")
    if coupling is not None:
        require_instance(coupling, DriveCoupling, "coupling")
    check_count(max_cycles, "max_cycles", low=1, high=MAX_CYCLE_BUDGET)
    check_real(max_detuning, "max_detuning", low=0.0)
    coupling = coupling or default_coupling(model, torque_sign)
    k_in = model.rotation_dofs[model.input_member]
    kd, cd = coupling_matrices(model.mass, model.rigid_body_velocity(), k_in, coupling)
    # the flanks in contact at the mean load, each on its line of action (both, with stiffness
    # and damping, for a negative backlash), as in the simulation
    contacts = model.mesh_contacts(torque_sign)
    damping = model.damping + contacts.damping_matrix() + cd
    varying = _varying(model)
    groups = tuple(g for g in model.mesh_frequency_groups() if varying[list(g.meshes)].any())
    rates = np.zeros(model.n_mesh)
    if groups:
        ref = groups[0].frequency_per_rpm
        period = common_period([g.frequency_per_rpm / ref for g in groups],
                               max_cycles=max_cycles, max_detuning=max_detuning)
        sign = np.sign(model.mesh_position_rates_per_rpm())
        sign[sign == 0] = 1.0
        for g, used in zip(groups, period.used_ratios, strict=True):
            rates[list(g.meshes)] = used * sign[list(g.meshes)]
    else:  # no varying mesh: a time-invariant system, any period
        period = common_period([1.0])
    return PeriodicGearSystem(model, model.mass, damping, model.stiffness + kd, coupling,
                              groups, period, rates, contacts=contacts)


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


def _concatenate(tables: Sequence, order_by: str):
    """Rows of several candidate or width tables (same dataclass) in one, sorted."""
    first = tables[0]
    if len(tables) == 1:
        return first
    kw: dict[str, Any] = {}
    for f in dataclasses.fields(first):
        values = [getattr(t, f.name) for t in tables]
        if f.name in ("notes",):
            kw[f.name] = tuple(dict.fromkeys(x for v in values for x in v))
        elif f.name == "natural_frequencies_hz":
            kw[f.name] = values[0]
        elif isinstance(values[0], np.ndarray):
            kw[f.name] = np.concatenate(values)
        else:
            kw[f.name] = values[0]
    order = np.argsort(kw[order_by], kind="stable")
    for f in dataclasses.fields(first):
        v = kw[f.name]
        if isinstance(v, np.ndarray) and f.name != "natural_frequencies_hz" and \
                v.shape[:1] == order.shape:
            kw[f.name] = v[order]
    return type(first)(**kw)


def mesh_phasing(model: AssembledModel, modal: ModalResult | None = None, *,
                 torque_sign: float = 1.0
                 ) -> tuple[MeshPhasingRule | None, list[tuple[str, int]] | None]:
    """The planetary mesh-phasing rule of a gear set and the family of every elastic mode.

    Returns ``(rule, families)``: for a simple set with equally spaced, identical planets the
    :class:`~analysis.instability.MeshPhasingRule` and one ``(kind, p)`` per elastic mode
    (rigid-body modes left out); ``(None, None)`` otherwise (unequal spacing, modes of no pure
    family). The modes are those of the loaded mean system (:func:`modal_analysis` with
    ``torque_sign``).
    """
    require_instance(model, AssembledModel, "model")
    if modal is not None:
        require_instance(modal, ModalResult, "modal")
    modal = modal or modal_analysis(model, torque_sign=torque_sign)
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
                        n_max: int = 4, speed_range: tuple[float, float] | None = None,
                        torque_sign: float = 1.0) -> Candidates:
    """Theory candidates ``2 f_i / n`` and ``(f_i + f_j) / n`` of a gear set, with speeds.

    For a simple planetary set with equally spaced, identical planets the mesh-phasing
    selection rule (Parker 2000; physics notes 4.5) marks the candidates the phasing
    suppresses. Each mode's family is its classification with the dominant circular harmonic
    ``p`` of the planets' motion (0 rotational, 1 translational, ``j`` planet modes); the rule
    is not applied when a mode is of no pure family (unequal spacing, ``other`` modes). The
    modes are those of the loaded mean system (:func:`gearvib.modal.modal_analysis`: the
    loaded flanks at the mean load of sense ``torque_sign``, both for a negative backlash).

    A set with several mesh frequencies (two-stage, Wolfrom) gets the candidates of every mesh
    frequency ``f_g`` (``f_g = 2 f_i / n`` ...), each row naming its mesh frequency
    (:attr:`Candidates.mesh_frequency`, e.g. ``"stage 2"``) with ``n`` its harmonic; rows are
    sorted by speed. Combination frequencies of two groups (``l f_1 + m f_2``) are second order
    in the stiffness variation and not listed; the Floquet chart contains them.
    """
    require_instance(model, AssembledModel, "model")
    if modal is not None:
        require_instance(modal, ModalResult, "modal")
    check_count(n_max, "n_max", low=1, high=MAX_N)
    if speed_range is not None:
        if not (isinstance(speed_range, tuple | list) and len(speed_range) == 2):
            raise ValueError(f"speed_range = {short(speed_range)} is not admissible (admissible: "
                             "(low, high) [min-1])")
        for i, v in enumerate(speed_range):
            check_real(v, f"speed_range[{i}]", low=0.0, high=MAX_SPEED_RPM)
    modal = modal or modal_analysis(model, torque_sign=torque_sign)
    keep = np.array([k != "rigid-body" for k in modal.kinds], dtype=bool)
    freqs = modal.frequencies_hz[keep]
    labels = [f"f{i + 1}" for i in np.flatnonzero(keep)]
    varying = _varying(model)
    every = model.mesh_frequency_groups()
    groups = tuple(g for g in every if varying[list(g.meshes)].any()) or every[:1]
    if len(groups) > 1:
        tables = [instability_candidates(
            freqs, n_max=n_max, mesh_frequency_per_rpm=g.frequency_per_rpm,
            speed_range=speed_range, mode_labels=labels, mesh_frequency_name=g.name)
            for g in groups]
        merged = _concatenate(tables, "rpm")
        return dataclasses.replace(merged,
                                   mesh_frequency_per_rpm=groups[0].frequency_per_rpm)
    rule, families = mesh_phasing(model, modal)
    return instability_candidates(
        freqs, n_max=n_max,
        mesh_frequency_per_rpm=groups[0].frequency_per_rpm if groups else None,
        speed_range=speed_range, mode_labels=labels,
        mode_families=families if rule else None, mesh_harmonic_rule=rule,
        mesh_frequency_name=groups[0].name if len(every) > 1 else None)


def _chart_metadata(system: PeriodicGearSystem) -> dict:
    if len(system.groups) < 2:
        return {}
    return {"mesh_frequency_names": tuple(g.name for g in system.groups),
            "mesh_frequency_ratios": system.period.ratios,
            "method": system.period.describe([g.name for g in system.groups])}


def _reference_factor(model: AssembledModel, system: PeriodicGearSystem) -> float:
    f = system.reference_frequency_per_rpm
    if not np.isfinite(f):
        groups = model.mesh_frequency_groups()
        f = groups[0].frequency_per_rpm if groups else math.nan
    if not (np.isfinite(f) and f > 0):
        raise ValueError("the gear set has no mesh with tooth numbers: no mesh frequency to "
                         "scan the speed with")
    return f


ATTRIBUTION_N_MAX = 10
"""Highest order ``n`` of the candidates Floquet regions are attributed to (a region of order 7
such as ``2 f2/7`` exists in the paper's case 1; the table shows ``n <= n_max`` plus the
candidates a region is attributed to)."""

CHART_ACCURACY = {"multiplier_atol": 1e-7, "unity_margin": 0.01}
"""Accuracy of the Floquet evaluations of a chart over speed (stiffness tables that are not
piecewise constant): ``max|mu|`` to 1e-7 near the stability limit, to 1 % of its distance from
1 elsewhere (growth rates to about 1 %)."""


def stability_over_speed(model: AssembledModel, speeds_rpm: np.ndarray, *,
                         coupling: DriveCoupling | None = None, n_max: int = 4,
                         refine: bool = True, max_cycles: int = MAX_CYCLES,
                         max_detuning: float = MAX_DETUNING,
                         torque_sign: float = 1.0, candidates: Candidates | None = None,
                         modal: ModalResult | None = None,
                         floquet_options: dict | None = None, workers: int | None = 1,
                         scheduler: str | None = None, executor: Executor | None = None,
                         progress: bool | None = False, xtol_rel: float = 1e-8
                         ) -> StabilityChart:
    """Floquet stability chart over input speed, with regions attributed to theory candidates.

    Parameters
    ----------
    model : AssembledModel
    speeds_rpm : array_like
        Increasing input speeds [min^-1] (> 0).
    coupling : DriveCoupling, optional
        Drive coupling at the input (default: the simulation's).
    n_max : int
        Highest order of the theory candidates listed; regions are attributed to candidates up
        to order ``max(n_max, ATTRIBUTION_N_MAX)``.
    refine : bool
        Refine the region boundaries by root finding.
    max_cycles, max_detuning
        Common period of several mesh frequencies (module docstring).
    torque_sign : float
        Sense of the mean load (+1: the input drives forward): selects the loaded flanks.
    candidates : Candidates, optional
        The candidates to attribute the regions to (default:
        :func:`gear_set_candidates` up to ``max(n_max, ATTRIBUTION_N_MAX)`` over the speeds;
        pass the table the caller shows, so that every label is one of its rows).
    modal : ModalResult, optional
        Modes of the mean system (default: computed). Their shapes decide which candidate the
        growing Floquet solution belongs to.
    floquet_options : dict, optional
        Options of :func:`analysis.instability.floquet` (default :data:`CHART_ACCURACY`).
    workers : int or None
        Local worker processes for the evaluations (None: every core available; 1: this
        process), the pool of the sweeps (:func:`gearvib.execution.executor_for`), used only
        when the chart is expected to take more than a few seconds. Results do not depend on
        it.
    scheduler : str, optional
        Address of a Dask scheduler whose workers evaluate the chart instead (``[dask]``
        extra).
    executor : concurrent.futures.Executor, optional
        An executor of the caller's (not shut down); ``workers`` then only sizes the chunks.
    progress : bool or None
        Progress bar (None: on a terminal only).
    xtol_rel : float
        Relative tolerance of the refined boundaries (1e-8: 4e-5 min^-1 at 4000 min^-1,
        finer than ``max|mu|`` to :data:`CHART_ACCURACY` places them).

    Returns
    -------
    StabilityChart
        Over the first mesh frequency (``mesh_frequency_per_rpm`` converts to speed); with
        several mesh frequencies the chart names them, gives their ratios and the method.
    """
    require_instance(model, AssembledModel, "model")
    _speeds(speeds_rpm)
    if coupling is not None:
        require_instance(coupling, DriveCoupling, "coupling")
    check_count(n_max, "n_max", low=1, high=MAX_N)
    check_count(max_cycles, "max_cycles", low=1, high=MAX_CYCLE_BUDGET)
    check_real(max_detuning, "max_detuning", low=0.0)
    if candidates is not None:
        require_instance(candidates, Candidates, "candidates")
    if modal is not None:
        require_instance(modal, ModalResult, "modal")
    _chart_options(refine, floquet_options, progress)
    speeds = np.asarray(speeds_rpm, dtype=float)
    if speeds.ndim != 1 or speeds.size < 2 or not (speeds > 0).all():
        raise ValueError("speeds_rpm must be an increasing 1-D array of positive speeds")
    system = periodic_system(model, coupling=coupling, max_cycles=max_cycles,
                             max_detuning=max_detuning, torque_sign=torque_sign)
    f_per_rpm = _reference_factor(model, system)
    modal = modal or modal_analysis(model, torque_sign=torque_sign)
    if candidates is None:  # a little beyond the speeds: centres may lie just outside a region
        candidates = gear_set_candidates(model, modal, n_max=max(n_max, ATTRIBUTION_N_MAX),
                                         speed_range=(0.97 * float(speeds[0]),
                                                      1.03 * float(speeds[-1])),
                                         torque_sign=torque_sign)
    keep = np.array([k != "rigid-body" for k in modal.kinds], dtype=bool)
    real_shapes = np.real(modal.shapes[:, keep])
    shapes: np.ndarray | None = real_shapes
    names: list[str] | None = [f"f{i + 1}" for i in np.flatnonzero(keep)]
    if real_shapes.shape[1] != candidates.natural_frequencies_hz.size:
        shapes, names = None, None  # candidates of other modes: frequency relation only
    opts = dict(CHART_ACCURACY if floquet_options is None else floquet_options)
    with _chart_executor(workers, scheduler, executor) as (pool, n):
        return stability_chart(system.at, speeds * f_per_rpm, mesh_frequency_per_rpm=f_per_rpm,
                               candidates=candidates, refine=refine, mode_shapes=shapes,
                               mode_names=names, floquet_options=opts, workers=n,
                               executor=pool, progress=progress, xtol_rel=xtol_rel,
                               **_chart_metadata(system))


@dataclass(frozen=True)
class _SystemsByParameter:
    """``system_at(f_mesh, value)`` of :func:`stability_map`: picklable (the systems of every
    value, built in the caller), so that any executor can evaluate the chart."""

    systems: dict[float, PeriodicGearSystem]

    def __call__(self, f: float, value: float):
        return self.systems[float(value)].at(f)


@contextlib.contextmanager
def _chart_executor(workers: int | None, scheduler: str | None, executor: Executor | None):
    """``(executor or None, worker count)`` for :func:`stability_chart`: None runs in this
    process; otherwise the sweeps' executors (:func:`gearvib.execution.executor_for`)."""
    n = default_workers() if workers is None else workers
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"workers = {short(workers)} is not admissible: an integer >= 1 or None")
    if executor is None and scheduler is None and n == 1:
        yield None, 1
        return
    with executor_for(n, scheduler, executor) as (pool, count):
        yield pool, count


def stability_map(model_for: Callable[[float], AssembledModel], speeds_rpm: np.ndarray,
                  values: np.ndarray, *, parameter_name: str = "parameter",
                  parameter_units: str = "1", refine: bool = False,
                  floquet_options: dict | None = None, workers: int | None = None,
                  scheduler: str | None = None, executor: Executor | None = None,
                  progress: bool | None = False) -> StabilityChart:
    """Ince-Strutt style chart of a gear set over input speed x one design parameter.

    Parameters
    ----------
    model_for : callable
        ``model_for(value) -> AssembledModel``, e.g. the gear set rebuilt with another mesh
        damping ratio, stiffness variation or contact ratio. Called once per value, in this
        process (it need not be picklable).
    speeds_rpm : array_like
        Increasing input speeds [min^-1].
    values : array_like
        Parameter values (one Floquet scan over speed each).
    parameter_name, parameter_units : str
        Metadata of the parameter axis.
    refine : bool
        Refine region boundaries (slower).
    floquet_options : dict, optional
        Options of :func:`analysis.instability.floquet` (default: its own).
    workers : int or None
        Local worker processes (None: every core available; 1: this process), the pool of
        the sweeps (:func:`gearvib.execution.executor_for`), started only when the chart is
        expected to take more than a few seconds. The chart is the same for any number.
    scheduler : str, optional
        Address of a Dask scheduler whose workers evaluate the chart (``[dask]`` extra).
    executor : concurrent.futures.Executor, optional
        An executor of the caller's (not shut down); ``workers`` then only sizes the chunks.
    progress : bool or None
        Progress bar over the evaluations (None: on a terminal only).
    """
    if not callable(model_for):
        raise TypeError(f"model_for must be callable; got {type(model_for).__name__}")
    n_speeds = _speeds(speeds_rpm).size
    v = require_real_array(values, "values", min_size=1).ravel()
    if v.size * n_speeds > MAX_CHART_POINTS:
        raise ValueError(f"values x speeds_rpm: {v.size} x {n_speeds} points, more than "
                         f"{MAX_CHART_POINTS} (each a Floquet computation of about 1-5 ms)")
    check_text(parameter_name, "parameter_name")
    check_text(parameter_units, "parameter_units")
    _chart_options(refine, floquet_options, progress)
    speeds = np.asarray(speeds_rpm, dtype=float)
    vals = [float(v) for v in np.asarray(values, dtype=float).ravel()]
    if speeds.ndim != 1 or speeds.size < 2 or not (speeds > 0).all() or not vals:
        raise ValueError("speeds_rpm must be increasing positive speeds and values non-empty")
    systems: dict[float, PeriodicGearSystem] = {}
    for value in vals:
        if value not in systems:
            systems[value] = periodic_system(model_for(value))
    first = systems[vals[0]]
    f_per_rpm = _reference_factor(first.model, first)
    for value, s in systems.items():
        if not math.isclose(s.reference_frequency_per_rpm, f_per_rpm, rel_tol=1e-9):
            raise ValueError(f"model_for({value}) changes the mesh frequency per speed "
                             f"({s.reference_frequency_per_rpm:.6g} against {f_per_rpm:.6g} "
                             "Hz per min^-1); the chart needs one speed axis")
    with _chart_executor(workers, scheduler, executor) as (pool, n):
        return stability_chart(_SystemsByParameter(systems), speeds * f_per_rpm,
                               parameter_values=vals, mesh_frequency_per_rpm=f_per_rpm,
                               refine=refine, parameter_name=parameter_name,
                               parameter_units=parameter_units,
                               floquet_options=floquet_options, workers=n, executor=pool,
                               progress=progress, **_chart_metadata(first))


def first_order_regions(model: AssembledModel, *, coupling: DriveCoupling | None = None,
                        l_max: int = 4, torque_sign: float = 1.0) -> FirstOrderWidths:
    """First-order perturbation widths of the principal and sum-type regions (Hsu 1963).

    With several mesh frequencies every group's harmonics give their own rows (their
    ``mesh_frequency`` names the group; widths in Hz of that mesh frequency, speeds from its
    factor), sorted by the lower speed.
    """
    require_instance(model, AssembledModel, "model")
    if coupling is not None:
        require_instance(coupling, DriveCoupling, "coupling")
    check_count(l_max, "l_max", low=1, high=MAX_HARMONICS)
    system = periodic_system(model, coupling=coupling, torque_sign=torque_sign)
    groups = system.groups or model.mesh_frequency_groups()
    if len(groups) < 2:
        k_mean, k_hat = system.harmonics(l_max)
        f = groups[0].frequency_per_rpm if groups else None
        return first_order_widths(system.mass, system.damping, k_mean, k_hat,
                                  mesh_frequency_per_rpm=f if f and np.isfinite(f) else None)
    tables = []
    for i, g in enumerate(groups):
        k_mean, k_hat = system.harmonics(l_max, group=i)
        w = first_order_widths(system.mass, system.damping, k_mean, k_hat,
                               mesh_frequency_per_rpm=g.frequency_per_rpm)
        tables.append(dataclasses.replace(
            w, mesh_frequency=np.full(len(w), g.name, dtype=object)))
    return _concatenate(tables, "lower_rpm")
