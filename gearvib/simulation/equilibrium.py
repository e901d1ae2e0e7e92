"""Static (quasi-static) equilibrium at the start of a run, with the piecewise-linear contacts."""

from __future__ import annotations

import numpy as np

from gearvib import kernels as kn
from gearvib.simulation.errors import SimulationError

__all__ = ["static_equilibrium"]


def _contact_solve(a0, f, mr, v, j, kl, kr, k_in, free_rigid, max_iter):
    """Active-set (Newton) solution of the piecewise-linear static problem at fixed stiffness."""
    n = a0.shape[0]
    state = np.ones(v.shape[0], dtype=np.int64)
    acc = 0.0
    for _ in range(max_iter):
        a = a0.copy()
        b = f.copy()
        left = (state & 1).astype(bool)
        right = (state & 2).astype(bool)
        a += (v[left].T * kl[left]) @ v[left] + (v[right].T * kr[right]) @ v[right]
        b += v[left].T @ (kl[left] * j[left] / 2) - v[right].T @ (kr[right] * j[right] / 2)
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
        d = v @ q
        new = (d > j / 2).astype(np.int64) + 2 * (d < -j / 2).astype(np.int64)
        if np.array_equal(new, state):
            return q, acc, a, b, resid
        state = new
    raise SimulationError("static equilibrium: the flank-contact sets do not converge")


def static_equilibrium(
    system: kn.KernelSystem,
    mass: np.ndarray,
    rigid: np.ndarray,
    velocity: np.ndarray,
    *,
    rigid_acceleration: float = 0.0,
    free_rigid: bool = False,
    max_iter: int = 100,
) -> tuple[np.ndarray, float]:
    """Static (quasi-static) equilibrium at ``t = 0`` with the piecewise-linear contact law.

    Solves ``K q + sum_m F_m(q) v_m + M r a = f(0, q, qdot0)`` by Newton iterations on the
    flank-contact sets (exact for the piecewise-linear law). The flank stiffness is taken at the
    mesh positions of the solution itself (fixed-point iteration: the static wind-up of the
    drive coupling rotates the whole set and so shifts the mesh positions). The rigid-body
    acceleration ``a`` is prescribed (speed-driven runs) or, with ``free_rigid``, an unknown
    fixed by the torque balance; then the input rotation is pinned to 0.

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
        The rigid-body mode is free (torque-driven run).
    max_iter : int
        Maximum number of contact-set updates.

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
    n = system.n_dof
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
    if mode == kn.DRIVE_SPEED:
        phi = np.zeros(1)
        w = np.zeros(1)
        kn.speed_profile(system.speed_table, np.zeros(1), phi, w)
        a0[k_in, k_in] += fpar[kn.FP_KC]
        f[k_in] += fpar[kn.FP_KC] * phi[0] + fpar[kn.FP_CC] * (w[0] - qd0[k_in])
    elif mode == kn.DRIVE_TORQUE:
        f[k_in] += float(np.interp(0.0, system.torque_table[0], system.torque_table[1]))
    k_out = int(ipar[kn.IP_OUTPUT])
    if k_out >= 0:
        e = fpar[kn.FP_OUTDIR]
        wo = e * qd0[k_out]
        f[k_out] -= e * (fpar[kn.FP_T0] + fpar[kn.FP_C1] * wo + fpar[kn.FP_C2] * wo * abs(wo))
    mr = mass @ rigid
    if not free_rigid:
        f = f - mr * rigid_acceleration
    v = system.mesh_vectors
    j = system.backlash
    q = np.zeros(n)
    k_prev = None
    for _outer in range(20):  # flank stiffness at the mesh positions of the current solution
        pos = system.mesh_position_offsets + system.mesh_position_vectors @ q
        kl = np.array([kn.periodic_interp(system.left_tables, m, s) for m, s in enumerate(pos)])
        kr = np.array([kn.periodic_interp(system.right_tables, m, s) for m, s in enumerate(pos)])
        k_now = np.concatenate([kl, kr])
        if k_prev is not None and np.allclose(k_now, k_prev, rtol=1e-12, atol=0.0):
            break
        k_prev = k_now
        q, acc, a, b, resid = _contact_solve(a0, f, mr, v, j, kl, kr, k_in, free_rigid, max_iter)
        if not free_rigid:
            acc = float(rigid_acceleration)
    scale = np.abs(b).max() + np.abs(a).max() * np.abs(q).max() + 1e-300
    if np.abs(resid).max() > 1e-8 * scale:
        raise SimulationError(
            "no static equilibrium at t = 0: the initial load is not balanced (a member is "
            "free, or the drive and load torques do not match); max residual "
            f"{np.abs(resid).max():.3g}"
        )
    return q, acc
