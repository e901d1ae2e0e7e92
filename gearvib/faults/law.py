"""The contact law of meshes with faults: tooth pairs one by one (kernel arrays and a reference).

A mesh without faults keeps the summed stiffness table ``k(s)`` of the model. A mesh that a
fault or error touches is evaluated pair by pair (:mod:`gearvib.teeth` says which teeth form
each pair):

* pair ``j`` is in contact while ``0 <= u = s - j < eps`` (``u`` in base pitches); its healthy
  stiffness ``f(u)`` is the model's single-pair curve when the stiffness model is ``pairs`` or
  ``csv`` (``k(s) = sum_j f(s - j)``), otherwise the table shared equally among the
  ``n(s) = ceil(eps - (s mod 1))`` pairs in contact, ``f = k(s) / n(s)``: the decomposition
  that reproduces any table exactly and all that a lumped model tells;
* a faulty tooth multiplies the pair stiffness by its *factor* (crack ``1 - severity``, pitting
  ``1 - severity`` inside its zone, broken tooth 0, a crack curve ``c(u) / f(u)``) and adds its
  *gap* (pitting depth: material removed);
* deviations add to the pair's deflection: tooth position (pitch) errors
  ``cos(beta_b) sigma r_b dphi_k`` (both flanks, like a rotation of the tooth), the eccentricity
  of a gear ``+-cos(beta_b) E cos(theta - theta_c + phi - lambda)`` (its centre offset projected
  on the flank's line of action at angle ``lambda``; + for gear1, - for gear2), and a planet pin
  error on a rigid pin direction ``-+cos(beta_b) e . n``;
* pair ``i`` of the left flank carries ``k_i (delta + d_i - j/2)`` while that is positive, the
  right flank ``k_i (delta_R + d_i + j/2)`` while negative (gap: ``d_i`` lowered on the left
  flank, raised on the right), and the mesh damping acts on ``delta' + d_mesh'`` while any pair
  of the flank is in contact; the flank force is floored at zero as in the healthy law.

The kernel follows this law for a faulty mesh only while a pair with a faulty tooth is in
contact (and always when the mesh has deviations); elsewhere it uses the table, which the pairs
sum to. Two cases reduce exactly to the table law with shifted deflections: deviations that
are the same for every pair (eccentricity, rigid pin errors), and pitch errors alone on a mesh
whose pairs share the table (:attr:`FaultedMesh.offsets_only`: the mean offset of the pairs in
contact, kept per mesh cycle, while on each flank every pair is loaded or none is).
:class:`FaultLaw` builds the arrays, evaluates the law in Python (:meth:`forces`, the
reference for the kernel) and gives the static equilibrium its effective stiffness and gaps
(:meth:`flank_law`).

Stiffness jumps: the jump segments of every faulty pair (its entry, its exit, the edges of a
pitted zone) are listed once per period of the faulty teeth (``lcm`` of their tooth numbers)
and the integrator ends sub-steps there, as at the jumps of the tables.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gearvib.checks import check_instance
from gearvib.faults.apply import fault_targets, mesh_lines
from gearvib.faults.description import (
    BrokenTooth,
    Crack,
    Eccentricity,
    FaultError,
    PinError,
    PitchError,
    Pitting,
)
from gearvib.model import AssembledModel

__all__ = ["FaultLaw", "FaultedMesh", "build_fault_law", "single_pair_curve"]

JUMP_FRACTION = 0.05
"""A pair-curve segment whose change exceeds this fraction of the pair's range is a jump (as in
:data:`gearvib.kernels.JUMP_FRACTION`)."""

NEED_CELLS = 16
"""The kernel decides whether a faulty mesh needs its pair law per step from a table with this
many cells per mesh cycle (:meth:`FaultedMesh.need_table`)."""

NEED_MARGIN = 0.01
"""Margin [mesh cycles] around the contact of a faulty pair within which the pair law is used:
it covers the difference between the linearly extrapolated mesh positions of a step and those
of its stages (below 1e-5 cycles at the default step; the pairs sum to the table, so a wider
margin changes results only by rounding)."""

MAX_EVENTS_PER_MESH = 200_000
"""Largest number of long-period jump positions of one mesh (sizes are checked before
allocating)."""

# record layout of a faulty mesh in the packed integer array (offsets into the fault blocks)
R_NU, R_NPAIR, R_Z1, R_S1, R_T1, R_Z2, R_S2, R_T2 = range(8)
R_PAIR, R_PROF1, R_SHIFT1, R_PROF2, R_SHIFT2, R_PROFV = range(8, 14)
R_NECC, R_ECCI, R_ECCV, R_CONST, R_NEV, R_EVV, R_ALWAYS, R_NPER, R_SHARED, R_EPS = range(14, 24)
R_NEED, R_PERIOD, R_EXIT, R_NEEDRES = 24, 25, 26, 27
# R_LAW: the law the kernel evaluates while the mesh needs its own (LAW_*); R_RAMPOUT: the cell
# of the cycle in which a pair ramps out, ``exit_cell mod n_per``; R_MESHWIDE: 1 when the mesh
# has mesh-wide deviations (eccentricities, rigid pin errors)
R_LAW, R_RAMPOUT, R_MESHWIDE = 28, 29, 30
N_RECORD = 31
LAW_SHIFTED = 0
"""R_LAW: no tooth of its own, mesh-wide deviations only: the table law, shifted."""
LAW_MEAN_OFFSET = 1
"""R_LAW: pitch offsets alone (:attr:`FaultedMesh.offsets_only`): the mean-offset law where
it holds, else the pair law."""
LAW_PAIRS = 2
"""R_LAW: tooth pair by tooth pair."""
LAW_STIFFNESS = 3
"""R_LAW: tooth faults that change the stiffness only (:attr:`FaultedMesh.stiffness_only`):
the table law with the summed stiffness of the pairs present."""


@dataclass
class FaultedMesh:
    """Pair-by-pair data of one faulty mesh (see the module docstring).

    Attributes
    ----------
    mesh : int
        Mesh index.
    eps : float
        Contact ratio [base pitches].
    n_per : int
        Samples per base pitch of the per-pair arrays (the model's table length).
    shared : bool
        Healthy pairs share the table equally; else ``pair_left`` / ``pair_right`` hold the
        single-pair curve.
    pair_left, pair_right : ndarray, shape (n_u,)
        Single-pair stiffness [N/m] at ``u = i / n_per`` (``u`` clamped to ``eps``); empty when
        ``shared``.
    z, sign, tooth0 : list of int
        Per gear (gear1, gear2): ``|z|`` (0 when the gear has no tooth data here), the
        pair-counter sign and the tooth in pair 0.
    profile : list of ndarray of int
        Per gear: profile index of every tooth (-1: healthy).
    shift : list of ndarray
        Per gear: deflection offset of every tooth's pairs (pitch error) [m].
    profiles : list of ndarray, shape (4, n_u)
        ``factor_left, factor_right, gap_left, gap_right`` of every profile.
    const_left, const_right : float
        Constant deflection offsets (rigid-pin errors) [m].
    ecc : list of tuple
        ``(dof_gear, dof_carrier, amp_left, phase_left, amp_right, phase_right)``: deflection
        offset ``amp cos(theta_gear - theta_carrier + phase)`` [m].
    events, period : ndarray, float
        Long-period jump positions in ``[0, period)`` [cycles].
    cycle_jumps : ndarray
        Jump positions repeating every cycle, in ``[0, 1)``.
    always : bool
        The pair law holds at every position (deviations present).
    """

    mesh: int
    eps: float
    n_per: int
    shared: bool = True
    pair_left: np.ndarray = field(default_factory=lambda: np.zeros(0))
    pair_right: np.ndarray = field(default_factory=lambda: np.zeros(0))
    z: list[int] = field(default_factory=lambda: [0, 0])
    sign: list[int] = field(default_factory=lambda: [0, 0])
    tooth0: list[int] = field(default_factory=lambda: [0, 0])
    profile: list[np.ndarray] = field(default_factory=lambda: [np.zeros(0, np.int64)] * 2)
    shift: list[np.ndarray] = field(default_factory=lambda: [np.zeros(0)] * 2)
    profiles: list[np.ndarray] = field(default_factory=list)
    const_left: float = 0.0
    const_right: float = 0.0
    ecc: list[tuple] = field(default_factory=list)
    events: np.ndarray = field(default_factory=lambda: np.zeros(0))
    period: float = 1.0
    cycle_jumps: np.ndarray = field(default_factory=lambda: np.zeros(0))
    always: bool = False

    @property
    def n_u(self) -> int:
        """Samples of the per-pair arrays: ``u`` from 0 to ``ceil(eps)`` and one more."""
        return math.ceil(self.eps) * self.n_per + 2

    @property
    def n_slots(self) -> int:
        """Pair slots behind the entering one: ``ceil(eps)``."""
        return math.ceil(self.eps)

    @property
    def exit_cell(self) -> int:
        """Cell of the per-pair grid (``u`` in ``[c, c + 1) / n_per``) that holds ``eps``: a
        pair ramps out of contact across it."""
        return math.floor(self.eps * self.n_per)

    def presence(self, i: int, i0: int, w: float) -> float:
        """Weight of pair slot ``i`` (``u = frac(s) + i``) at cell ``i0``, weight ``w``: 1 on
        the path, ramping in over the cycle's last cell before entry (slot -1) and out over
        :attr:`exit_cell` - the pairs switch where the table's jumps ramp, and the force stays
        continuous in ``s`` (the integrator ends sub-steps at the cell ends)."""
        if i < 0:
            return w if i0 == self.n_per - 1 else 0.0
        iu = i0 + i * self.n_per
        if iu < self.exit_cell:
            return 1.0
        return 1.0 - w if iu == self.exit_cell else 0.0

    @property
    def offsets_only(self) -> bool:
        """The mean-offset law applies: healthy pairs share the table, no tooth has a fault
        profile and some tooth has a pitch deviation, and at least one pair stays on the path
        over a whole cycle (``exit_cell >= n_per``).

        Then a pair differs from the healthy one by its deflection offset only (the sum of its
        two teeth's pitch offsets ``o_i``, plus the mesh-wide ones), and while every pair
        present is in contact on a flank (or none is) the pair law sums to the table law
        with the presence-weighted mean offset: with ``k_i = p_i k(s) / P``, ``P = sum p_i``,
        ``sum_i k_i (delta + o_i - j/2) = k(s) (delta + o_mean - j/2)``,
        ``o_mean = sum p_i o_i / P``. Outside the two ramp cells of a cycle (the entering
        pair's and the leaving pair's) the presences are 0 or 1 and constant, so the kernel
        keeps ``o_mean`` and the extreme offsets of the two contact zones once per mesh cycle
        (:func:`gearvib.kernels._offset_cycle`) and evaluates the shifted table law; in the
        ramp cells, or when the pairs of a flank are partly in contact, it takes the pair law.
        """
        no_profiles = all(not np.any(p >= 0) for p in self.profile)
        return (self.shared and no_profiles and self.has_teeth
                and self.exit_cell >= self.n_per)

    @property
    def stiffness_only(self) -> bool:
        """The stiffness law applies: some tooth has a fault profile, no profile has a gap
        (crack, broken tooth; pitting has one) and no tooth a pitch deviation.

        Then every pair present meets the same deflection (``delta`` plus the mesh-wide
        offsets), so every pair with a positive stiffness is in contact on a flank or none
        is, and the pair law's force ``sum_i k_i (delta - j/2)`` is the table law's with the
        summed stiffness ``sum_i k_i`` (equal to rounding: the kernel multiplies once,
        :func:`gearvib.kernels._stiffness_flanks`); the loop over the pairs remains, without
        their offsets and contact tests.
        """
        has_profile = any(self.z[g] > 0 and np.any(self.profile[g] >= 0) for g in (0, 1))
        no_shift = all(not np.any(self.shift[g]) for g in (0, 1) if self.z[g] > 0)
        no_gap = all(not np.any(p[2:]) for p in self.profiles)
        return has_profile and no_shift and no_gap

    @property
    def has_teeth(self) -> bool:
        """Some tooth of the mesh has a fault profile or a pitch deviation."""
        return any(self.z[g] > 0 and (bool((self.profile[g] >= 0).any())
                                      or bool(self.shift[g].any())) for g in (0, 1))

    def faulty_pair(self, j: int) -> bool:
        """Pair ``j`` has a tooth with a fault profile."""
        for g in (0, 1):
            if self.z[g] > 0 and self.profile[g][(self.sign[g] * j + self.tooth0[g])
                                                  % self.z[g]] >= 0:
                return True
        return False

    def need_table(self) -> np.ndarray:
        """``need[floor(NEED_CELLS s) mod (NEED_CELLS L)]``: a faulty pair is in contact
        within :data:`NEED_MARGIN` of that cell (ramps included: pair ``j`` from
        ``s = j - 1 / n_per`` to ``j + (exit_cell + 1) / n_per``), over the period ``L`` of the
        faulty teeth; a single 1 when the mesh has deviations (the pair law always holds)."""
        if self.always:
            return np.ones(1, dtype=np.int64)
        period = 1
        for g in (0, 1):
            if self.z[g] > 0 and np.any(self.profile[g] >= 0):
                period = math.lcm(period, self.z[g])
        cells = NEED_CELLS * period
        need = np.zeros(cells, dtype=np.int64)
        first = -1.0 / self.n_per - NEED_MARGIN
        last = (self.exit_cell + 1) / self.n_per + NEED_MARGIN
        for j in range(period):
            if self.faulty_pair(j):
                c = np.arange(math.floor((j + first) * NEED_CELLS),
                              math.floor((j + last) * NEED_CELLS) + 1)
                need[c % cells] = 1
        return need


def _contact_ratio(model: AssembledModel, m: int) -> float | None:
    meta = model.meta["meshes"][m]
    eps = meta.get("stiffness", {}).get("contact_ratio")
    if eps is None:
        eps = meta.get("contact_ratio")
    return None if eps is None else float(eps)


def single_pair_curve(model: AssembledModel, m: int) -> tuple[np.ndarray | None, float, int]:
    """Single-pair stiffness of mesh ``m`` sampled per base pitch, if the model has one.

    Returns
    -------
    curve : ndarray or None
        ``f(min(i / n_per, eps))`` [N/m] for ``i = 0 .. ceil(eps) n_per + 1`` when the mesh's
        stiffness model is ``pairs`` (or ``csv``) and its pairs sum to the table; None when the
        pairs share the table equally (every other model).
    eps : float
        Contact ratio.
    n_per : int
        Samples per base pitch (the model's table length).

    Raises
    ------
    FaultError
        When the mesh has no contact ratio (a lumped constant or Fourier stiffness).
    """
    table = np.asarray(model.mesh_stiffness_tables[m], dtype=float)
    n_per = table.size
    eps = _contact_ratio(model, m)
    name = model.mesh_names[m]
    if eps is None:
        raise FaultError(f"mesh {name!r} has no contact ratio (a lumped mesh with a constant "
                         "or Fourier stiffness): local tooth faults need one; give the tooth "
                         "geometry or a rectangular or pairs stiffness with contact_ratio")
    stiff = model.meta["meshes"][m].get("stiffness", {})
    if stiff.get("model") != "pairs" or stiff.get("position_unit", "base_pitch") != "base_pitch":
        return None, eps, n_per
    n_u = math.ceil(eps) * n_per + 2
    u = np.minimum(np.arange(n_u) / n_per, eps)
    f = np.interp(u, np.asarray(stiff["position"], dtype=float),
                  np.asarray(stiff["stiffness"], dtype=float), left=0.0, right=0.0)
    x = np.arange(n_per) / n_per
    summed = np.zeros(n_per)
    for i in range(math.ceil(eps) + 1):
        inside = x + i < eps
        summed[inside] += f[np.arange(n_per)[inside] + i * n_per]
    if not np.allclose(summed, table, rtol=1e-9, atol=1e-9 * np.abs(table).max()):
        return None, eps, n_per
    return f, eps, n_per


def _jump_cells(curve: np.ndarray, span: float) -> set[int]:
    """Indices ``i`` and ``i + 1`` of the segments whose change exceeds the jump fraction."""
    if span <= 0.0 or curve.size < 2:
        return set()
    seg = np.flatnonzero(np.abs(np.diff(curve)) > JUMP_FRACTION * span)
    return {int(i) for i in seg} | {int(i) + 1 for i in seg}


def healthy_pair(model: AssembledModel, fm: FaultedMesh, back: bool = False) -> np.ndarray:
    """Healthy pair stiffness of a faulty mesh at ``u = i / n_per`` [N/m] (0 from ``eps`` on).

    The single-pair curve, or the table shared by the pairs in contact.
    """
    u = np.arange(fm.n_u) / fm.n_per
    if not fm.shared:
        curve = fm.pair_right if back else fm.pair_left
        return np.where(u < fm.eps, curve, 0.0)
    table = np.asarray(model.mesh_back_tables[fm.mesh] if back else
                       model.mesh_stiffness_tables[fm.mesh], dtype=float)
    x_idx = np.arange(fm.n_u) % fm.n_per
    n_pairs = np.ceil(fm.eps - x_idx / fm.n_per)
    return np.where(u < fm.eps, table[x_idx] / np.maximum(n_pairs, 1.0), 0.0)


@dataclass
class FaultLaw:
    """Faulty meshes of a model and the extra loads of its errors (:func:`build_fault_law`).

    Attributes
    ----------
    meshes : dict of int to FaultedMesh
        The faulty meshes.
    f_const : ndarray, shape (n,)
        Generalised force of elastic planet bearings whose pins are displaced [N, N m].
    bearing_offsets : ndarray, shape (n_bearing,)
        ``k_b e_b``: subtract from ``k_b u_b . q`` for the bearing force [N].
    n_mesh : int
        Meshes of the model.
    """

    meshes: dict[int, FaultedMesh]
    f_const: np.ndarray
    bearing_offsets: np.ndarray
    n_mesh: int

    def __bool__(self) -> bool:
        return bool(self.meshes) or bool(np.any(self.f_const))

    # ---- kernel arrays -------------------------------------------------------------------
    def pack(self, short_steps: tuple[float, float, float] = (0.0, 0.0, 0.0),
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(records, ints, floats)`` for :func:`gearvib.kernels.pack`.

        ``records[m]`` is the start of mesh ``m``'s record in ``ints`` (-1: healthy); the
        offsets in a record are relative to the start of ``ints`` or ``floats`` (the kernel
        adds the block bases). ``floats`` starts with ``short_steps``
        (:func:`gearvib.kernels.short_step_header`: the highest natural frequency and the
        coefficients of the short sub-steps; zeros: RK4 on every sub-step).
        """
        rec = np.full(self.n_mesh, -1, dtype=np.int64)
        ints: list[int] = []
        vals: list[np.ndarray] = [np.asarray(short_steps, dtype=np.float64)]
        nv = 3

        def put(a) -> int:
            nonlocal nv
            arr = np.asarray(a, dtype=np.float64).ravel()
            vals.append(arr)
            pos = nv
            nv += arr.size
            return pos

        for m, fm in sorted(self.meshes.items()):
            r = [0] * N_RECORD
            base = len(ints)
            rec[m] = base
            ints.extend(r)
            r[R_NU] = fm.n_u
            r[R_NPER] = fm.n_per
            r[R_NPAIR] = fm.n_slots
            r[R_EXIT] = fm.exit_cell
            r[R_RAMPOUT] = fm.exit_cell % fm.n_per
            r[R_LAW] = (LAW_MEAN_OFFSET if fm.offsets_only
                        else LAW_STIFFNESS if fm.stiffness_only
                        else LAW_PAIRS if fm.has_teeth else LAW_SHIFTED)
            r[R_MESHWIDE] = int(bool(fm.ecc) or fm.const_left != 0.0 or fm.const_right != 0.0)
            r[R_SHARED] = int(fm.shared)
            r[R_EPS] = put([fm.eps])
            r[R_PAIR] = put(np.concatenate([fm.pair_left, fm.pair_right]))
            teeth = fm.has_teeth
            for side, (zk, sk, tk, pk, hk) in enumerate(
                    ((R_Z1, R_S1, R_T1, R_PROF1, R_SHIFT1), (R_Z2, R_S2, R_T2, R_PROF2,
                                                              R_SHIFT2))):
                if not teeth:  # mesh-wide deviations only: the kernel shifts the table law
                    continue
                if fm.z[side] > 0 and not (np.any(fm.profile[side] >= 0)
                                           or np.any(fm.shift[side])):
                    continue  # a healthy gear: the kernel skips its tooth look-ups
                r[zk] = fm.z[side]
                r[sk] = fm.sign[side]
                r[tk] = fm.tooth0[side]
                if fm.z[side] > 0:
                    r[pk] = len(ints)
                    ints.extend(np.asarray(fm.profile[side], dtype=np.int64).tolist())
                    r[hk] = put(fm.shift[side])
            r[R_PROFV] = put(np.concatenate([p.ravel() for p in fm.profiles])
                             if fm.profiles else np.zeros(0))
            r[R_NECC] = len(fm.ecc)
            r[R_ECCI] = len(ints)
            for e in fm.ecc:
                ints.extend((int(e[0]), int(e[1])))
            r[R_ECCV] = put([v for e in fm.ecc for v in (
                e[2], math.cos(e[3]), math.sin(e[3]), e[4], math.cos(e[5]), math.sin(e[5]))])
            r[R_CONST] = put([fm.const_left, fm.const_right])
            r[R_NEV] = fm.events.size
            r[R_EVV] = put(np.concatenate([[fm.period], fm.events]))
            r[R_ALWAYS] = int(fm.always)
            need = fm.need_table()
            r[R_PERIOD] = need.size
            r[R_NEEDRES] = 1 if fm.always else NEED_CELLS
            r[R_NEED] = len(ints)
            ints.extend(need.tolist())
            ints[base:base + N_RECORD] = r
        flat = np.concatenate(vals) if vals else np.zeros(0)
        return rec, np.asarray(ints, dtype=np.int64), flat

    def cycle_jumps(self) -> dict[int, np.ndarray]:
        """Per-cycle jump positions of the faulty meshes (added to the tables' jumps)."""
        return {m: fm.cycle_jumps for m, fm in self.meshes.items() if fm.cycle_jumps.size}

    # ---- reference evaluation (Python) ---------------------------------------------------
    def _deviation(self, fm: FaultedMesh, q: np.ndarray, qd: np.ndarray | None):
        el, er = fm.const_left, fm.const_right
        edl = edr = 0.0
        for dg, dc, al, pl, ar, pr in fm.ecc:
            ang = (q[dg] if dg >= 0 else 0.0) - (q[dc] if dc >= 0 else 0.0)
            rate = 0.0
            if qd is not None:
                rate = (qd[dg] if dg >= 0 else 0.0) - (qd[dc] if dc >= 0 else 0.0)
            el += al * math.cos(ang + pl)
            er += ar * math.cos(ang + pr)
            edl -= al * math.sin(ang + pl) * rate
            edr -= ar * math.sin(ang + pr) * rate
        return el, er, edl, edr

    def pair_states(self, model: AssembledModel, m: int, s: float, q: np.ndarray,
                    qd: np.ndarray | None = None):
        """Stiffness and deflection offsets of the pairs of faulty mesh ``m`` in contact.

        Returns
        -------
        pairs : list of tuple
            ``(k_left, k_right, d_left, d_right, pair_counter)``; the offsets add to the mesh
            deflection along each flank's line of action.
        rates : tuple of float
            Rates of the mesh-wide offsets ``(d_left', d_right')`` (eccentricity).
        """
        fm = self.meshes[m]
        el, er, edl, edr = self._deviation(fm, q, qd)
        sf = math.floor(s)
        x0 = (s - sf) * fm.n_per
        i0 = int(x0)
        w = x0 - i0
        if i0 >= fm.n_per:
            i0, w = 0, 0.0
        slots = range(-1, fm.n_slots + 1)
        pres = [fm.presence(i, i0, w) for i in slots]
        psum = sum(pres)
        if fm.shared and psum > 0:
            tl, tr = model.mesh_stiffness_tables[m], model.mesh_back_tables[m]
            i1 = i0 + 1 if i0 + 1 < fm.n_per else 0
            share_l = ((1.0 - w) * tl[i0] + w * tl[i1]) / psum
            share_r = ((1.0 - w) * tr[i0] + w * tr[i1]) / psum
        out = []
        teeth = fm.has_teeth  # once per call (it scans the teeth)
        for i, p in zip(slots, pres, strict=True):
            if p <= 0.0:
                continue
            idx, wi = (i0 + i * fm.n_per, w) if i >= 0 else (0, 0.0)

            def at(a: np.ndarray, idx=idx, wi=wi) -> float:
                return (1.0 - wi) * a[idx] + wi * a[idx + 1]

            j = sf - i
            if fm.shared:
                kl, kr = share_l * p, share_r * p
            else:
                kl, kr = at(fm.pair_left) * p, at(fm.pair_right) * p
            dl, dr = el, er
            if teeth:
                for g in (0, 1):
                    if fm.z[g] == 0:
                        continue
                    tooth = (fm.sign[g] * j + fm.tooth0[g]) % fm.z[g]
                    sh = fm.shift[g][tooth]
                    dl += sh
                    dr += sh
                    pi = fm.profile[g][tooth]
                    if pi >= 0:
                        prof = fm.profiles[pi]
                        kl *= at(prof[0])
                        kr *= at(prof[1])
                        dl -= at(prof[2])
                        dr += at(prof[3])
            out.append((kl, kr, dl, dr, j))
        return out, (edl, edr)

    def forces(self, model: AssembledModel, q: np.ndarray, qd: np.ndarray) -> dict:
        """Flank forces of every faulty mesh, ``{m: (F_left, F_right, k_eff)}`` (reference
        evaluation of the kernel's law; ``F_right <= 0`` as in the kernel)."""
        j_all = np.asarray(model.mesh_backlash, dtype=float)
        vl, vr = model.mesh_vectors, model.back_vectors
        s_all = model.mesh_position_offsets + model.mesh_position_vectors @ q
        out = {}
        for m in self.meshes:
            half = 0.5 * j_all[m]
            d, dd = float(vl[m] @ q), float(vl[m] @ qd)
            dr, ddr = float(vr[m] @ q), float(vr[m] @ qd)
            pairs, (edl, edr) = self.pair_states(model, m, float(s_all[m]), q, qd)
            fl = fr = ke = 0.0
            on_l = on_r = False
            for kl, kr, ol, orr, _ in pairs:
                if kl > 0.0 and d + ol > half:
                    fl += kl * (d + ol - half)
                    ke += kl
                    on_l = True
                if kr > 0.0 and dr + orr < -half:
                    fr += kr * (dr + orr + half)
                    ke += kr
                    on_r = True
            c = float(model.mesh_damping[m])
            if model.viscous_meshes[m]:  # always-on damping: on the loaded line, no floor
                if on_r and not on_l:
                    fr += c * (ddr + edr)
                else:
                    fl += c * (dd + edl)
            else:
                if on_l:
                    fl = max(fl + c * (dd + edl), 0.0)
                if on_r:
                    fr = min(fr + c * (ddr + edr), 0.0)
            out[m] = (fl, fr, ke)
        return out

    def flank_law(self, model: AssembledModel, q: np.ndarray, backlash: np.ndarray,
                  all_pairs: bool) -> dict[int, tuple[float, float, float, float]]:
        """Effective ``(k_left, k_right, gap_left, gap_right)`` of every faulty mesh at ``q``.

        The pairs in contact act as one spring on each flank: left ``K (delta - g)`` with
        ``K = sum k_i`` and ``g = j/2 - sum k_i d_i / K``, right ``K (delta_R + g)`` with
        ``g = j/2 + sum k_i d_i / K``. ``all_pairs``: every pair counts as in contact (the first
        iteration of the static solution); otherwise those whose deflection at ``q`` is beyond
        the half backlash.
        """
        vl, vr = model.mesh_vectors, model.back_vectors
        s_all = model.mesh_position_offsets + model.mesh_position_vectors @ q
        out = {}
        for m in self.meshes:
            half = 0.5 * backlash[m]
            d, dr = float(vl[m] @ q), float(vr[m] @ q)
            pairs, _ = self.pair_states(model, m, float(s_all[m]), q)
            kl_sum = kr_sum = ml = mr = 0.0
            for kl, kr, ol, orr, _ in pairs:
                if kl > 0.0 and (all_pairs or d + ol > half):
                    kl_sum += kl
                    ml += kl * ol
                if kr > 0.0 and (all_pairs or dr + orr < -half):
                    kr_sum += kr
                    mr += kr * orr
            gl = half - ml / kl_sum if kl_sum > 0 else half
            gr = half + mr / kr_sum if kr_sum > 0 else half
            out[m] = (kl_sum, kr_sum, gl, gr)
        return out


def _profile(fm: FaultedMesh, side: int, tooth: int) -> np.ndarray:
    """The profile array of a tooth (created healthy: factor 1, gap 0)."""
    p = int(fm.profile[side][tooth])
    if p < 0:
        p = len(fm.profiles)
        prof = np.zeros((4, fm.n_u))
        prof[:2] = 1.0
        fm.profiles.append(prof)
        fm.profile[side][tooth] = p
    return fm.profiles[p]


def _new_mesh(model: AssembledModel, m: int, eps: float | None = None) -> FaultedMesh:
    if eps is None:
        curve, eps, n_per = single_pair_curve(model, m)
    else:
        curve, n_per = None, int(model.mesh_stiffness_tables.shape[1])
    same_back = np.array_equal(model.mesh_back_tables[m], model.mesh_stiffness_tables[m])
    if curve is not None and same_back:
        fm = FaultedMesh(m, eps, n_per, shared=False, pair_left=curve, pair_right=curve)
    else:
        fm = FaultedMesh(m, eps, n_per)
    teeth = model.mesh_teeth[m] if model.mesh_teeth is not None else np.zeros(4, np.int64)
    meta = model.meta["meshes"][m]
    for side in (0, 1):
        z = meta.get(f"z{side + 1}")
        if z is None or teeth[2 * side] == 0:
            continue
        fm.z[side] = abs(int(z))
        fm.sign[side] = int(teeth[2 * side])
        fm.tooth0[side] = int(teeth[2 * side + 1])
    fm.profile = [np.full(max(z, 0), -1, dtype=np.int64) for z in fm.z]
    fm.shift = [np.zeros(max(z, 0)) for z in fm.z]
    return fm


def build_fault_law(model: AssembledModel) -> FaultLaw:
    """Kernel arrays of the faults of a model (an empty law for a healthy model).

    Raises
    ------
    FaultError
        A fault that does not fit the model (see :func:`gearvib.faults.apply.fault_targets`),
        or a crack curve longer than the path of contact.
    """
    check_instance(model, AssembledModel, "model")
    n = model.n_dof
    law = FaultLaw({}, np.zeros(n), np.zeros(len(model.bearing_names)), model.n_mesh)
    if not model.faults:
        return law
    lines = mesh_lines(model)
    meta_meshes = model.meta["meshes"]
    planets = {p["name"]: p for p in model.meta.get("planets", [])}
    roles = {b["name"]: b["role"] for b in model.meta.get("bodies", [])}

    def mesh(m: int) -> FaultedMesh:
        if m not in law.meshes:
            law.meshes[m] = _new_mesh(model, m)
        return law.meshes[m]

    def mesh_for_deviations(m: int) -> FaultedMesh:
        """A faulty mesh for deviations: a constant stiffness needs no contact ratio."""
        if m not in law.meshes and _contact_ratio(model, m) is None:
            tabs = (model.mesh_stiffness_tables[m], model.mesh_back_tables[m])
            if all(np.ptp(t) == 0.0 for t in tabs):
                law.meshes[m] = _new_mesh(model, m, eps=1.0)
        return mesh(m)

    for f in model.faults:
        targets = fault_targets(model, f)
        if f.kind == "backlash":
            continue  # applied to the model's backlash by with_faults
        if isinstance(f, PinError):
            _pin_error(model, law, f, targets, lines, planets, mesh_for_deviations)
            continue
        if isinstance(f, Eccentricity):
            dof = model.rotation_dofs.get(f.member, -1)
            for t in targets:
                fm = mesh_for_deviations(t.mesh)
                line = lines[t.mesh]
                amp = line.cos_beta * (1.0 if t.side == 1 else -1.0) * f.eccentricity
                carrier = planets[meta_meshes[t.mesh]["gear2"]]["carrier"]
                dof_c = model.rotation_dofs.get(carrier, -1)
                phi = math.radians(f.phase_deg)
                lam_l = math.atan2(line.left[1], line.left[0])
                lam_r = math.atan2(line.right[1], line.right[0])
                fm.ecc.append((dof, dof_c, amp, phi - lam_l, amp, phi - lam_r))
                fm.always = True
            continue
        for t in targets:
            fm = mesh(t.mesh)
            side = t.side - 1
            if fm.z[side] == 0:
                raise FaultError(f"{f.label}: mesh {model.mesh_names[t.mesh]!r} has no tooth "
                                 "map")
            if isinstance(f, PitchError):
                line = lines[t.mesh]
                coef = line.theta_coefficient1 if t.side == 1 else line.theta_coefficient2
                z_signed = int(meta_meshes[t.mesh][f"z{t.side}"])
                alpha = math.radians(meta_meshes[t.mesh]["pressure_angle_deg"])
                rb = abs(meta_meshes[t.mesh][f"base_radius{t.side}"])
                r_pitch = rb / math.cos(alpha)
                # the direction of increasing tooth index in the gear's positive sense
                direction = 1.0 if roles.get(f.member) == "planet" else -math.copysign(
                    1.0, z_signed)
                dphi = direction * f.cumulative_deviations(abs(z_signed)) / r_pitch
                fm.shift[side] = fm.shift[side] + coef * dphi
                fm.always = True
                continue
            prof = _profile(fm, side, f.tooth)
            u = np.arange(fm.n_u) / fm.n_per
            if isinstance(f, BrokenTooth):
                prof[:2] = 0.0
            elif isinstance(f, Crack):
                if f.severity is not None:
                    prof[:2] *= 1.0 - f.severity
                else:
                    assert f.curve is not None  # Crack: a severity or a curve
                    pos = np.asarray(f.curve.position)
                    if f.curve.position_unit == "path_fraction":
                        pos = pos * fm.eps
                    if pos[-1] > fm.eps * (1 + 1e-6):
                        raise FaultError(f"{f.label}: the crack curve reaches {pos[-1]:.4g} "
                                         "base pitches, beyond the contact ratio "
                                         f"{fm.eps:.4g} of mesh "
                                         f"{model.mesh_names[t.mesh]!r}")
                    target = np.interp(np.minimum(u, fm.eps), pos,
                                       np.asarray(f.curve.stiffness), left=0.0, right=0.0)
                    healthy = healthy_pair(model, fm)
                    healthy[u >= fm.eps] = healthy[min(int(fm.eps * fm.n_per), fm.n_u - 1)]
                    tiny = 1e-9 * float(np.abs(healthy).max())
                    safe = np.where(healthy > tiny, healthy, 1.0)
                    prof[:2] *= np.where(healthy > tiny, target / safe, 0.0)
            elif isinstance(f, Pitting):
                zone = (u >= f.path_start * fm.eps) & (u <= f.path_end * fm.eps)
                flanks = {"left": (0,), "right": (1,), "both": (0, 1)}[f.flank]
                for fl in flanks:
                    prof[fl, zone] *= 1.0 - f.severity
                    prof[2 + fl, zone] += f.depth
    for fm in law.meshes.values():
        _events(model, fm)
    return law


def _pin_error(model, law, f, targets, lines, planets, mesh_for_deviations) -> None:
    """Rigid pin directions shift the meshes' deflections; elastic ones preload the bearing."""
    psi = math.radians(planets[f.member]["angle_deg"])
    e_r = np.array([math.cos(psi), math.sin(psi)])
    e_t = np.array([-math.sin(psi), math.cos(psi)])
    rigid = np.zeros(2)
    for comp, value, unit, coord in (("radial", f.radial, e_r, "zeta"),
                                     ("tangential", f.tangential, e_t, "eta")):
        if value == 0.0:
            continue
        if f"{f.member}.{coord}" not in model.dof_names:
            rigid += value * unit
            continue
        name = f"{f.member}.{comp}"
        if name in model.bearing_names:
            b = model.bearing_names.index(name)
            k = float(model.bearing_stiffness[b])
            law.f_const += k * value * np.asarray(model.bearing_vectors[b], dtype=float)
            law.bearing_offsets[b] += k * value
        # a free direction (no bearing): nothing holds the planet, the pin has no effect
    if not np.any(rigid):
        return
    for t in targets:
        line = lines[t.mesh]
        sgn = line.cos_beta * (1.0 if t.side == 1 else -1.0)
        fm = mesh_for_deviations(t.mesh)
        fm.const_left += sgn * float(rigid @ line.left)
        fm.const_right += sgn * float(rigid @ line.right)
        fm.always = True


def _events(model: AssembledModel, fm: FaultedMesh) -> None:
    """Per-cycle and long-period jump positions of a faulty mesh.

    Per cycle: the tables' own jumps are in the kernel's list already; with deviations every
    pair's entry (``s`` integer) and exit (``s = j + eps``) adds a force jump. Long period:
    every segment of a faulty pair where its stiffness or gap jumps, at the entries and exits
    of the pairs it shares the load with, and its own entry and exit.
    """
    n_per = fm.n_per
    # the cells where pairs ramp in (the cycle's last) and out (the one holding eps)
    ramp = {(n_per - 1) / n_per, 0.0, (fm.exit_cell % n_per) / n_per,
            ((fm.exit_cell + 1) % n_per) / n_per}
    cycle: set[float] = set(ramp) if fm.always else set()
    sides = [g for g in (0, 1) if fm.z[g] > 0 and np.any(fm.profile[g] >= 0)]
    if sides or not fm.shared:  # the healthy pair curves (not needed for deviations alone)
        healthy_l = healthy_pair(model, fm)
        healthy_r = healthy_pair(model, fm, back=True)
        span = float(max(np.ptp(healthy_l), np.ptp(healthy_r), 0.0))
        if not fm.shared:
            cycle |= {(i % n_per) / n_per for i in _jump_cells(healthy_l, span)
                      | _jump_cells(healthy_r, span)}
    fm.cycle_jumps = np.array(sorted(cycle), dtype=float)
    if not sides:
        return
    period = 1
    for g in sides:
        period = math.lcm(period, fm.z[g])
    events: set[float] = set()
    n_ev = 0
    # while a faulty pair is present its share changes where any pair ramps in or out
    own = [c + x - (1.0 if x > 0.5 and c == 0 and x == (n_per - 1) / n_per else 0.0)
           for c in range(fm.n_slots + 2) for x in ramp]
    own = [x for x in own if -1.0 / n_per - 1e-12 <= x <= (fm.exit_cell + 1) / n_per + 1e-12]
    for g in sides:
        for tooth in np.flatnonzero(fm.profile[g] >= 0):
            prof = fm.profiles[int(fm.profile[g][tooth])]
            cells: set[int] = set()
            for arr in (healthy_l * prof[0], healthy_r * prof[1]):
                cells |= _jump_cells(arr, span)
            gap_span = float(np.abs(prof[2:]).max())
            for arr in prof[2:]:
                cells |= _jump_cells(arr, gap_span)
            offsets = sorted({c / n_per for c in cells if c <= fm.exit_cell + 1} | set(own))
            j0 = (fm.sign[g] * (int(tooth) - fm.tooth0[g])) % fm.z[g]
            n_ev += len(offsets) * (period // fm.z[g])
            if n_ev > MAX_EVENTS_PER_MESH:
                raise FaultError(f"mesh {model.mesh_names[fm.mesh]!r}: the faults need "
                                 f"{n_ev} jump positions per period of {period} mesh cycles "
                                 f"(admissible: {MAX_EVENTS_PER_MESH}); fewer faulty teeth")
            for j in range(j0, period, fm.z[g]):
                for c in offsets:
                    events.add((j + c) % period)
    fm.events = np.array(sorted(events), dtype=float)
    fm.period = float(period)
