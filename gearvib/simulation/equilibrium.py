"""Static (quasi-static) equilibrium at the start of a run, with the piecewise-linear contacts.

Every mesh has two lines of action: ``vl`` (left flank, ``system.mesh_vectors``) and ``vr``
(right flank, ``system.back_vectors``, the mirror-image line). The contact law is that of the
kernel: left flank in contact iff ``vl.q > j/2``, right flank iff ``vr.q < -j/2``. When the two
lines coincide (``vr is vl``: rigid in-plane bearings) the sums are formed as before back lines
existed (``v^T (F_L + F_R)``), so such runs start from the same state bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from gearvib import kernels as kn
from gearvib.checks import check_count, check_instance, check_items, check_real, check_vector
from gearvib.simulation.errors import SimulationError
from gearvib.simulation.frequencies import check_mass

__all__ = ["static_equilibrium"]


MAX_NEWTON = 200
"""Iterations of the damped Newton method on the potential energy (fallback solver)."""


def _contact_state(dl: np.ndarray, dr: np.ndarray, gl: np.ndarray, gr: np.ndarray
                   ) -> np.ndarray:
    """Flank-contact state per mesh: bit 0 left flank, bit 1 right flank (0: in the backlash).

    ``dl``, ``dr``: deflections along the left and the right flank's line of action; ``gl``,
    ``gr``: the half gaps of each flank (``j/2`` for a healthy mesh).
    """
    return (dl > gl).astype(np.int64) + 2 * (dr < -gr).astype(np.int64)


def _force_sum(vl, vr, fl, fr):
    """Generalised mesh force ``vl^T F_L + vr^T F_R`` (one product when the lines coincide)."""
    if vr is vl:
        return vl.T @ (fl + fr)
    return vl.T @ fl + vr.T @ fr


def _state_solve(a0, f, mr, vl, vr, gl, gr, kl, kr, k_in, free_rigid, state):
    """Linear solution with the flanks of ``state`` in contact (one active-set step).

    Returns ``q, acc, a, b, resid, new_state`` with ``a q + m_r acc = b`` the linear system of
    ``state`` and ``new_state`` the contact state of its solution.
    """
    n = a0.shape[0]
    acc = 0.0
    a = a0.copy()
    b = f.copy()
    left = (state & 1).astype(bool)
    right = (state & 2).astype(bool)
    a += (vl[left].T * kl[left]) @ vl[left] + (vr[right].T * kr[right]) @ vr[right]
    b += vl[left].T @ (kl[left] * gl[left]) - vr[right].T @ (kr[right] * gr[right])
    if free_rigid:
        # equilibrated: acceleration column and pin row scaled to the stiffness
        big = np.abs(a).max() + 1e-300
        col = big / (np.abs(mr).max() + 1e-300)
        aug = np.zeros((n + 1, n + 1))
        aug[:n, :n] = a
        aug[:n, n] = mr * col
        aug[n, k_in] = big
        rhs = np.append(b, 0.0)
        sol = np.linalg.lstsq(aug, rhs, rcond=None)[0]
        q, acc = sol[:n], float(sol[n] * col)
        resid = aug @ sol - rhs
    else:
        q = np.linalg.lstsq(a, b, rcond=None)[0]
        resid = a @ q - b
    return q, acc, a, b, resid, _contact_state(vl @ q, vr @ q, gl, gr)


def _flank_forces(dl, dr, gl, gr, kl, kr):
    """Left (>= 0) and right (<= 0) flank forces of the static contact law."""
    return kl * np.maximum(dl - gl, 0.0), -kr * np.maximum(-dr - gr, 0.0)


def _line_minimum(a0p, g0p, dl, dr, cl, cr, gl, gr, kl, kr, same: bool) -> float:
    """Exact minimiser ``t > 0`` of the energy along a descent direction ``p``.

    ``phi'(t) = t p.A.p + g0.p + sum_m [cl_m F_L,m(dl_m + t cl_m) + cr_m F_R,m(dr_m + t cr_m)]``
    (``cl = vl.p``, ``cr = vr.p``; ``same``: one line of action, ``cr = cl``) is piecewise
    linear and non-decreasing (convex energy); its root is found between the breakpoints where
    a flank opens or closes. ``inf`` if it stays negative (the energy is unbounded along
    ``p``).
    """
    mask = (cl != 0.0) if same else (cl != 0.0) | (cr != 0.0)
    cm, dm, glm, grm, klm, krm = cl[mask], dl[mask], gl[mask], gr[mask], kl[mask], kr[mask]
    cmr, dmr = cr[mask], dr[mask]
    with np.errstate(divide="ignore", invalid="ignore"):
        brk = np.concatenate([(glm - dm) / cm, (-grm - dmr) / cmr])
    brk = np.unique(brk[np.isfinite(brk) & (brk > 0.0)])

    def slope_and_value(t: float) -> tuple[float, float]:
        dd = dm + t * cm
        ddr = dmr + t * cmr
        fl, fr = _flank_forces(dd, ddr, glm, grm, klm, krm)
        if same:
            val = t * a0p + g0p + float(cm @ (fl + fr))
            stiff = a0p + float(np.sum(cm * cm * (klm * (dd > glm) + krm * (dd < -grm))))
        else:
            val = t * a0p + g0p + float(cm @ fl + cmr @ fr)
            stiff = a0p + float(np.sum(cm * cm * klm * (dd > glm)
                                       + cmr * cmr * krm * (ddr < -grm)))
        return val, stiff

    t0 = 0.0
    for t1 in [*brk, np.inf]:
        # phi' is linear on [t0, t1]: phi'(t) = val + stiff (t - tm)
        tm = t0 + 1.0 if np.isinf(t1) else 0.5 * (t0 + t1)
        val, stiff = slope_and_value(tm)
        end_val = (np.inf if stiff > 0.0 else val) if np.isinf(t1) else val + stiff * (t1 - tm)
        if end_val >= 0.0:
            return max(t0, tm - val / stiff) if stiff > 0.0 else t0
        t0 = t1
    return np.inf


def _energy_solve(a0, f, mr, rigid, vl, vr, gl, gr, kl, kr, k_in, free_rigid, max_iter):
    """Damped Newton method on the potential energy (symmetric ``a0``).

    The static problem is the minimum of the convex, piecewise-quadratic energy
    ``E(q) = q.a0.q / 2 - f.q + sum_m [k_L (vl_m.q - j/2)_+^2 + k_R (-vr_m.q - j/2)_+^2] / 2``:
    its gradient is the residual of the contact law. Newton steps use the flanks in contact at the
    current iterate; meshes inside the backlash get a small regularising stiffness so that a
    member that floats in its backlash does not make the step singular; every step is followed
    by the exact line minimum of ``E``, so the energy decreases monotonically and the active
    set cannot cycle. With a free rigid-body mode the acceleration is the torque balance
    ``r.f / r.M.r`` and the input rotation is pinned.

    Returns ``q, acc, history``: ``history`` is None when converged, else the last contact
    states. Raises :class:`SimulationError` if ``E`` is unbounded (the load is not balanced).
    """
    n = a0.shape[0]
    free = np.ones(n, dtype=bool)
    acc = 0.0
    f_eff = f.copy()
    if free_rigid:
        acc = float(rigid @ f) / float(rigid @ mr)
        f_eff = f - mr * acc
        free[k_in] = False
    same = vr is vl
    reg = 1e-3 * 0.5 * (kl + kr)
    # start from the bonded solution: every mesh a bilateral spring without backlash (half
    # of each flank on its line of action)
    if same:
        h0 = a0 + (vl.T * (0.5 * (kl + kr))) @ vl
    else:
        h0 = a0 + (vl.T * (0.5 * kl)) @ vl + (vr.T * (0.5 * kr)) @ vr
    q = np.zeros(n)
    h0f = h0[np.ix_(free, free)]
    q[free] = np.linalg.lstsq(h0f, f_eff[free], rcond=None)[0]
    scale = np.abs(f_eff).max() + 1e-300
    # a load component that no support, coupling or mesh resists (null space of the bonded
    # system) makes the energy unbounded: no equilibrium exists
    bonded_resid = np.abs(h0f @ q[free] - f_eff[free]).max()
    if bonded_resid > 1e-8 * (scale + np.abs(h0f).max() * np.abs(q).max()):
        raise SimulationError(
            "no static equilibrium at t = 0: the initial load is not balanced (a member is "
            "free, or the drive and load torques do not match); max residual "
            f"{bonded_resid:.3g}"
        )
    history = []
    for _ in range(max_iter):
        dl, dr = vl @ q, vr @ q
        fl, fr = _flank_forces(dl, dr, gl, gr, kl, kr)
        g = a0 @ q - f_eff + _force_sum(vl, vr, fl, fr)
        if np.abs(g[free]).max() <= 1e-12 * (scale + np.abs(_force_sum(vl, vr, fl, -fr)).max()):
            return q, acc, None
        history.append(_contact_state(dl, dr, gl, gr))
        on_l, on_r = dl > gl, dr < -gr
        off = ~(on_l | on_r)
        h = (a0 + (vl[on_l].T * kl[on_l]) @ vl[on_l] + (vr[on_r].T * kr[on_r]) @ vr[on_r]
             + (vl[off].T * reg[off]) @ vl[off])
        p = np.zeros(n)
        p[free] = np.linalg.lstsq(h[np.ix_(free, free)], -g[free], rcond=None)[0]
        cl = vl @ p
        cr = cl if same else vr @ p
        t = _line_minimum(float(p @ a0 @ p), float(p @ (a0 @ q - f_eff)), dl, dr, cl, cr, gl,
                          gr, kl, kr, same)
        if not np.isfinite(t):
            raise SimulationError(
                "no static equilibrium at t = 0: the initial load is not balanced (a member is "
                "free, or the drive and load torques do not match)"
            )
        q = q + t * p
    return q, acc, history[-10:]


def _balanced(a: np.ndarray, b: np.ndarray, q: np.ndarray, resid: np.ndarray) -> bool:
    """The residual of a linear solution is at rounding level (relative 1e-8)."""
    scale = np.abs(b).max() + np.abs(a).max() * np.abs(q).max() + 1e-300
    return bool(np.abs(resid).max() <= 1e-8 * scale)


class _NoConvergence(Exception):
    """The contact sets cycle; ``args[0]`` lists the indices of the meshes that switch."""


def _active_set(a0, f, mr, vl, vr, gl, gr, kl, kr, k_in, free_rigid, state, max_iter):
    """Active-set iterations (Newton's method on the piecewise-linear equations) from ``state``.

    Returns the solution ``(q, acc, a, b, resid)`` or None (a contact state repeats, or a
    consistent state leaves a member free), and the visited states.
    """
    seen = set()
    history = []
    for _ in range(max_iter):
        q, acc, a, b, resid, new = _state_solve(a0, f, mr, vl, vr, gl, gr, kl, kr, k_in,
                                                free_rigid, state)
        history.append(state)
        if np.array_equal(new, state):
            return ((q, acc, a, b, resid) if _balanced(a, b, q, resid) else None), history
        seen.add(state.tobytes())
        if new.tobytes() in seen:
            return None, [*history, new]
        state = new
    return None, [*history, new]


def _contact_solve(a0, f, mr, rigid, vl, vr, gl, gr, kl, kr, k_in, free_rigid, max_iter):
    """Solution of the piecewise-linear static problem at fixed flank stiffness.

    First the plain active-set iteration from every left flank in contact: exact and fast when
    it converges. It cycles when a step closes or opens a mesh in the wrong direction: a mesh
    whose loaded flank is the right one (e.g. a planet-planet mesh driven backwards) or one
    that opens under a light load is predicted inside its backlash, is opened, a member becomes
    free, the singular step throws the flanks back, and the same states repeat. A repeated
    state (or a free member) switches to the damped Newton method on the potential energy
    (:func:`_energy_solve`), which cannot cycle; its contact state then starts the active-set
    iteration again, which ends in one step at the exact piecewise-linear solution. A member
    that floats in its backlash (no exact linear solution) keeps the energy minimum.
    """
    n_mesh = vl.shape[0]
    sol, hist1 = _active_set(a0, f, mr, vl, vr, gl, gr, kl, kr, k_in, free_rigid,
                             np.ones(n_mesh, dtype=np.int64), max_iter)
    if sol is not None:
        return sol
    a_sym = 0.5 * (a0 + a0.T)
    symmetric = np.allclose(a0, a_sym, rtol=0.0, atol=1e-12 * (np.abs(a0).max() + 1e-300))
    q_e, acc_e, hist_e = _energy_solve(a_sym, f, mr, rigid, vl, vr, gl, gr, kl, kr, k_in,
                                       free_rigid, MAX_NEWTON)
    state = _contact_state(vl @ q_e, vr @ q_e, gl, gr)
    sol, hist2 = _active_set(a0, f, mr, vl, vr, gl, gr, kl, kr, k_in, free_rigid, state,
                             max_iter)
    if sol is not None:
        return sol
    if symmetric and hist_e is None:
        a = a0.copy()
        b = f.copy()
        left, right = (state & 1).astype(bool), (state & 2).astype(bool)
        a += (vl[left].T * kl[left]) @ vl[left] + (vr[right].T * kr[right]) @ vr[right]
        b += vl[left].T @ (kl[left] * gl[left]) - vr[right].T @ (kr[right] * gr[right])
        resid = a @ q_e + mr * acc_e - b
        if free_rigid:
            resid = np.append(resid, 0.0)
        return q_e, acc_e, a, b, resid
    states = np.array([*hist1, *(hist_e or []), *hist2])
    switching = np.flatnonzero(np.any(states != states[-1], axis=0))
    raise _NoConvergence([int(m) for m in switching])


def static_equilibrium(
    system: kn.KernelSystem,
    mass: np.ndarray,
    rigid: np.ndarray,
    velocity: np.ndarray,
    *,
    rigid_acceleration: float = 0.0,
    free_rigid: bool = False,
    max_iter: int = 100,
    mesh_names: Sequence[str] | None = None,
    flank_law: Callable | None = None,
) -> tuple[np.ndarray, float]:
    """Static (quasi-static) equilibrium at ``t = 0`` with the piecewise-linear contact law.

    Solves ``K q + sum_m F_m(q) v_m + M r a = f(0, q, qdot0)`` by Newton iterations on the
    flank-contact sets (exact for the piecewise-linear law). The flank stiffness is taken at the
    mesh positions of the solution itself (fixed-point iteration: the static wind-up of the
    drive coupling rotates the whole set and so shifts the mesh positions). The rigid-body
    acceleration ``a`` is prescribed (speed-driven runs) or, with ``free_rigid``, an unknown
    fixed by the torque balance; then the input rotation is pinned to 0. A speed drive on the
    rigid-body coordinate ``p . q`` (``system.drive_sensing``) is solved as a coupling on the
    input coordinate, and the solution turned rigidly until ``p . q`` equals its input angle:
    the drive torque, and so every deflection, is the same (exact when the rigid-body motion
    strains nothing, ``K r = 0``, which is when the default drive senses it; the residual of
    the run's own equations is checked).

    Parameters
    ----------
    system : KernelSystem
        Arrays of the run (drive and load parameters included).
    mass : ndarray, shape (n, n)
        Mass matrix of the run (load inertia included).
    rigid : ndarray, shape (n,)
        Rigid-body velocity per unit input speed.
    velocity : ndarray, shape (n,)
        Initial velocity ``qdot0``.
    rigid_acceleration : float
        Prescribed input acceleration [rad/s^2] (ignored with ``free_rigid``).
    free_rigid : bool
        The rigid-body mode is free (torque- or motor-driven run).
    max_iter : int
        Maximum number of contact-set updates.
    mesh_names : sequence of str, optional
        Mesh names for the error messages.
    flank_law : callable, optional
        ``flank_law(q, first) -> {mesh: (k_left, k_right, gap_left, gap_right)}``: the
        effective stiffness and half gaps of meshes with faults at ``q`` (``first``: the first
        iteration, every tooth pair counted in contact), which replace the table values and
        ``j/2`` of those meshes (:meth:`gearvib.faults.law.FaultLaw.flank_law`).

    Returns
    -------
    q0 : ndarray, shape (n,)
        Static coordinates.
    acceleration : float
        Rigid-body input acceleration [rad/s^2].

    Raises
    ------
    SimulationError
        If no equilibrium exists (unbalanced load on a free member) or the contact sets cycle.
    """
    check_instance(system, kn.KernelSystem, "system")
    n = system.n_dof
    mass = check_mass(mass)
    if mass.shape[0] != n:
        raise ValueError(f"mass must be ({n}, {n}) (the system's DOF); got {mass.shape}")
    rigid = check_vector(rigid, "rigid", n, max_abs=1e12)
    if not float(rigid @ mass @ rigid) > 0.0:
        raise ValueError("rigid must be a rigid-body motion (r^T M r > 0)")
    velocity = check_vector(velocity, "velocity", n, max_abs=1e9)
    rigid_acceleration = check_real(rigid_acceleration, "rigid_acceleration", low=-1e12,
                                    high=1e12)
    if not isinstance(free_rigid, bool | np.bool_):
        raise TypeError(f"free_rigid must be a bool; got {type(free_rigid).__name__}")
    max_iter = check_count(max_iter, "max_iter", low=1, high=10_000)
    if mesh_names is not None:
        mesh_names = check_items(mesh_names, str, "mesh_names")
    if flank_law is not None and not callable(flank_law):
        raise TypeError(f"flank_law must be callable; got {type(flank_law).__name__}")
    ipar, fpar = system.ipar, system.fpar
    qd0 = np.asarray(velocity, dtype=float)
    a0 = system.stiffness.copy()
    f = system.f_const - system.damping @ qd0
    carrier = int(ipar[kn.IP_CARRIER])
    if ipar[kn.IP_GYRO] and carrier >= 0:
        om = qd0[carrier]
        a0 -= om * om * system.centripetal
        f -= om * system.gyroscopic @ qd0
    k_in = int(ipar[kn.IP_INPUT])
    mode = int(ipar[kn.IP_MODE])
    sensing = system.drive_sensing if mode == kn.DRIVE_SPEED else None
    if mode == kn.DRIVE_SPEED:
        phi = np.zeros(1)
        w = np.zeros(1)
        kn.speed_profile(system.speed_table, np.zeros(1), phi, w)
        # a controller on the rigid-body coordinate (sensing p) is solved as a coupling on the
        # input coordinate (symmetric), then the set is turned rigidly until p . q equals that
        # input angle: the same torque, so the same deflections (K r = 0; see below)
        a0[k_in, k_in] += fpar[kn.FP_KC]
        rate = qd0[k_in] if sensing is None else float(sensing @ qd0)
        f[k_in] += fpar[kn.FP_KC] * phi[0] + fpar[kn.FP_CC] * (w[0] - rate)
    elif mode == kn.DRIVE_TORQUE:
        f[k_in] += float(np.interp(0.0, system.torque_table[0], system.torque_table[1]))
    elif mode == kn.DRIVE_MOTOR:
        f[k_in] += float(np.interp(qd0[k_in], system.torque_table[0], system.torque_table[1]))
    k_out = int(ipar[kn.IP_OUTPUT])
    load_text = f"load torque {float(fpar[kn.FP_T0]):.4g} N m at the output"
    if mode in (kn.DRIVE_TORQUE, kn.DRIVE_MOTOR):
        t_in = float(np.interp(0.0 if mode == kn.DRIVE_TORQUE else qd0[k_in],
                               system.torque_table[0], system.torque_table[1]))
        load_text = f"input torque {t_in:.4g} N m, " + load_text
    if k_out >= 0:
        e = fpar[kn.FP_OUTDIR]
        wo = e * qd0[k_out]
        f[k_out] -= e * (fpar[kn.FP_T0] + fpar[kn.FP_C1] * wo + fpar[kn.FP_C2] * wo * abs(wo))
    mr = mass @ rigid
    if not free_rigid:
        f = f - mr * rigid_acceleration
    vl = system.mesh_vectors
    vr = vl if system.mesh_back_vectors is None else system.mesh_back_vectors
    j = system.backlash
    q = np.zeros(n)
    k_seen: list[np.ndarray] = []
    for _outer in range(20):  # flank stiffness at the mesh positions of the current solution
        pos = system.mesh_position_offsets + system.mesh_position_vectors @ q
        kl = np.array([kn.periodic_interp(system.left_tables, m, s) for m, s in enumerate(pos)])
        kr = np.array([kn.periodic_interp(system.right_tables, m, s) for m, s in enumerate(pos)])
        gl = j / 2
        gr = gl
        k_now = np.concatenate([kl, kr])
        if flank_law is not None:  # faulty meshes: the tooth pairs in contact at q
            gr = gl.copy()
            for m, (klm, krm, glm, grm) in flank_law(q, _outer == 0).items():
                kl[m], kr[m], gl[m], gr[m] = klm, krm, glm, grm
            k_now = np.concatenate([kl, kr, gl, gr])
        # converged, or the solution sits on a jump of a stiffness table (k alternates between
        # both sides of it): either solution is the equilibrium to the table's resolution
        if any(np.allclose(k_now, k, rtol=1e-12, atol=0.0) for k in k_seen):
            break
        k_seen.append(k_now)
        try:
            q, acc, a, b, resid = _contact_solve(a0, f, mr, rigid, vl, vr, gl, gr, kl, kr, k_in,
                                                 free_rigid, max_iter)
        except _NoConvergence as exc:
            names = list(mesh_names) if mesh_names is not None else None
            which = [names[m] if names else f"mesh {m}" for m in exc.args[0]] or ["the meshes"]
            raise SimulationError(
                "static equilibrium: the flank-contact sets do not converge: the contact of "
                f"{', '.join(which)} keeps switching between its flanks and the backlash "
                f"({load_text} at t = 0). Try a start speed of 0 (no gyroscopic terms at "
                "t = 0), a larger load, or a negative backlash (both flanks in contact)"
            ) from None
        if not free_rigid:
            acc = float(rigid_acceleration)
        if sensing is not None:
            q = q + rigid * ((q[k_in] - float(sensing @ q)) / float(sensing @ rigid))
    if sensing is not None:  # the residual of the run's own (non-symmetric) drive
        a = a.copy()
        a[k_in, k_in] -= fpar[kn.FP_KC]
        a[k_in] += fpar[kn.FP_KC] * sensing
        resid = a @ q - b
    if not _balanced(a, b, q, resid):
        raise SimulationError(
            "no static equilibrium at t = 0: the initial load is not balanced (a member is "
            "free, or the drive and load torques do not match); max residual "
            f"{np.abs(resid).max():.3g}"
        )
    return q, acc
