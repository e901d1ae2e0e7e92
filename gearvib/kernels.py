"""Numba kernels of the run-up simulator: contact law, right-hand side, RK4 loop, decimation.

Everything here works on flat float64 / int64 arrays and preallocated buffers; no Python objects
enter the compiled code, so the same compiled kernel serves every gear-set topology.

Equations of motion
-------------------
With the state ``y = [q, qdot]`` (``n`` coordinates each)::

    M qddot = f_const + f_drive(t, q, qdot) - K q - C qdot
              - g (Omega_c G qdot - Omega_c**2 K_Omega q) - sum_m (F_left,m + F_right,m) v_m

``Omega_c = qdot[carrier]`` is the current carrier speed and ``g`` switches the gyroscopic and
centripetal terms on (1) or off (0). For every mesh ``m`` (see :mod:`gearvib.model`):
``delta = v_m . q`` along the left flank's line of action, ``delta_R = u_m . q`` along the
right (back) flank's (``u_m = v_m`` unless the mesh has a distinct back line), ``s = w_m . q +
s0_m``, ``k_L = table_L(s)``, ``k_R = table_R(s)``, and :func:`flank_forces_two_lines` gives the
flank forces (paper eq. 2, superposed; the mesh damping acts only on a flank in contact, the
gated law), or :func:`flank_forces_viscous` for a mesh with the always-on damping of Kahraman
& Singh (``mesh_damping_law``: a flag per mesh in the packed block ``mlaw``). The force term
is ``F_L v_m + F_R u_m``. The mesh position uses the actual rotation angles, so vibration
feeds back into the mesh phase.

A mesh whose back line equals its left line (every mesh of a model with rigid in-plane
bearings) takes the one-line path: ``delta_R = delta`` and the force ``(F_L + F_R) v_m``, the
same floating-point operations as before back lines existed, so such runs are unchanged bit for
bit. A mesh with local tooth faults or manufacturing errors (:mod:`gearvib.faults.law`) is
evaluated by its own law while a faulty pair is in contact or the mesh has deviations, in a
second pass after the other meshes (:func:`_faulty_meshes`): the table law with shifted
deflections for mesh-wide deviations and for pitch offsets alone where every pair of a flank
is loaded or none is (:func:`_mean_offset`), stiffness-only tooth faults (crack, broken
tooth) by the table law with the pairs' summed stiffness (:func:`_stiffness_flanks`), else
tooth pair by tooth pair (:func:`_faulty_flanks`); its force acts along the same vectors.
Healthy meshes never enter that path, so runs without faults are unchanged bit for bit.
:func:`gearvib.simulate.simulate` runs that pass as straight-line code generated and compiled
for the fault configuration (:mod:`gearvib.fault_pass`; its address in ``ints[H_FPASS]``,
called by :func:`_call_pass`): the same floating-point operations without the sparse loops,
record reads and law dispatch. A packed system without that address takes the generic pass
(:func:`generic_pass`, the same laws as a C function of the same signature, compiled on first
use): :func:`integrate_chunk`, :func:`evaluate_rhs` and :func:`rhs_loop` hand the compiled
kernels a system whose ``ints[H_FPASS]`` holds one or the other (:func:`with_pass`). The
compiled right-hand side holds no fault law at all, so a run without faults compiles none.

The right-hand side itself is a C function too (:func:`rhs_address`, :data:`RHS_SIGNATURE`):
the RK4 loop, :func:`evaluate_rhs` and :func:`rhs_loop` call it through its address
(:func:`_call_rhs`; one indirect call per evaluation, no measurable cost: LLVM did not inline
the right-hand side into the loop either). So the loop compiles without the right-hand side
(in parallel with it on a first run, :mod:`gearvib.compile_helper`) and does not optimise the
right-hand side's code again inside its own.

Drive (``ipar[IP_MODE]``):

* ``DRIVE_NONE``: no drive; only ``f_const`` and the load act.
* ``DRIVE_SPEED``: torque ``k_c (phi - theta) + c_c (omega - theta')`` on the input coordinate,
  ``phi`` the exact integral of the piecewise-linear speed table. ``theta = q_in`` (a torsional
  spring-damper between the prescribed angle and the input coordinate), or, with a drive
  sensing row ``p`` (``KernelSystem.drive_sensing``, the packed blocks ``di``/``dv``),
  ``theta = p . q``: the rigid-body coordinate of a speed controller on the rigid-body mode
  (:class:`gearvib.simulate.DriveCoupling`).
* ``DRIVE_TORQUE``: input torque from a piecewise-linear table of time (constant outside).
* ``DRIVE_MOTOR``: input torque from the motor's torque-speed characteristic, a
  piecewise-linear table of the input speed [rad/s] (constant outside), evaluated at the
  current speed of the input coordinate.

Load at the output coordinate, in every mode: ``-e (T0 + c1 w + c2 w |w|)`` with
``w = e qdot_out`` and ``e = +-1`` the forward sense of the output member.

Integration
-----------
Classical RK4 with a fixed step ``dt``. The stiffness tables of rectangular or steep trapezoidal
models jump at the tooth-pair changes; a stage that straddles a jump costs RK4 its order. The
ends of every jump segment of the tables are found once (:func:`jump_positions`); at the start
of each step the mesh positions are extrapolated linearly and the step is split into RK4
sub-steps that end exactly at the predicted crossings (:func:`integrate_chunk`). Faulty meshes
add their own jump positions, once per period of their faulty teeth (a sorted list searched by
bisection). Samples stay on the fixed grid.

Short sub-steps (runs with faults only). A fault makes identical, in-phase planets deflect
differently, so their meshes reach the same stiffness jump at slightly different times and
the sub-steps between these times can be far shorter than ``dt``. A sub-step of length
``h <= h_E = c_E (omega dt)**2.5 / omega`` takes an explicit Euler step (its first stage is
computed anyway), one of ``h <= h_M = c_M (omega dt)**(5/3) / omega`` the midpoint rule
(:func:`short_step_header`; ``omega`` the highest natural frequency of the stiffest system).
Their local error on a mode of that frequency, ``(omega h)**(p+1) / (p+1)!``, stays below
:data:`SHORT_STEP_ERROR_FRACTION` of the RK4 step's ``(omega dt)**5 / 120``; both limits
shrink faster than ``dt`` and the number of such sub-steps per unit time is set by the
tooth-pair changes, not by ``dt``, so the scheme keeps the order of the RK4 steps. Runs
without faults take RK4 on every sub-step, unchanged bit for bit.

Layouts
-------
``system`` is the tuple of a few flat arrays built by :func:`pack` (via
:meth:`KernelSystem.astuple`): all operators premultiplied by ``M^-1`` and stored sparse.
A recorded sample row holds
``[q (n), qdot (n), F_left (n_mesh), -F_right (n_mesh), k_eff (n_mesh)]``: both flank forces as
compressive magnitudes (>= 0) and the effective mesh stiffness (0 in the backlash, ``k_L + k_R``
in double contact). Row ``i`` of a chunk is the state at the start of step ``i``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from functools import partial

import numpy as np
from llvmlite import ir
from numba import carray, cfunc, njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from analysis.jit import prepare_cache
from gearvib.lanes import WIDTH, lanes_load, lanes_madd, lanes_splat, lanes_store

prepare_cache(__file__)  # a writable numba cache also in read-only installs (before @njit)

__all__ = [
    "DAMPING_GATED",
    "DAMPING_VISCOUS",
    "DRIVE_MOTOR",
    "DRIVE_NONE",
    "DRIVE_SPEED",
    "DRIVE_TORQUE",
    "KERNEL_PARTS",
    "MESH_OUT_COLUMNS",
    "PASS_SIGNATURE",
    "RHS_SIGNATURE",
    "STATUS_DEFLECTION",
    "STATUS_NONFINITE",
    "STATUS_OK",
    "STATUS_SPEED",
    "KernelSystem",
    "compile_ahead",
    "csr",
    "evaluate_rhs",
    "fir_decimate",
    "flank_forces",
    "flank_forces_two_lines",
    "flank_forces_viscous",
    "generic_pass",
    "generic_pass_compiled",
    "insert_split",
    "integrate",
    "integrate_chunk",
    "integrate_chunk_compiled",
    "jump_positions",
    "n_signals",
    "need_interval",
    "operators",
    "pack",
    "periodic_interp",
    "rhs_address",
    "rhs_loop",
    "shift_rigid",
    "short_step_header",
    "speed_at",
    "speed_profile",
    "table_at",
    "with_pass",
    "work_shape",
]

STATUS_OK = 0
STATUS_NONFINITE = 1
STATUS_DEFLECTION = 2
STATUS_SPEED = 3

DRIVE_NONE = 0
DRIVE_SPEED = 1
DRIVE_TORQUE = 2
DRIVE_MOTOR = 3

#: Mesh-damping laws (``KernelSystem.mesh_damping_law``, the packed block ``mlaw``): the
#: damping acts only on a flank in contact and the flank force is floored at 0
#: (:func:`flank_forces_two_lines`), or it acts always (:func:`flank_forces_viscous`).
DAMPING_GATED = 0
DAMPING_VISCOUS = 1

# integer parameters
IP_MODE = 0
IP_INPUT = 1
IP_OUTPUT = 2
IP_CARRIER = 3
IP_GYRO = 4
N_IPAR = 5
# float parameters
FP_KC = 0
FP_CC = 1
FP_OUTDIR = 2
FP_T0 = 3
FP_C1 = 4
FP_C2 = 5
FP_SPEED_LIMIT = 6
N_FPAR = 7


@dataclass
class KernelSystem:
    """All arrays the kernels need, as plain contiguous float64/int64 arrays.

    Attributes
    ----------
    minv : ndarray, shape (n, n)
        Inverse mass matrix (load inertia included).
    stiffness, damping : ndarray, shape (n, n)
        Constant stiffness and damping (bearings, couplings; meshes excluded).
    gyroscopic, centripetal : ndarray, shape (n, n)
        ``G`` and ``K_Omega`` of the model.
    mesh_vectors, mesh_position_vectors : ndarray, shape (n_mesh, n)
        ``v_m`` (left flank's line of action) and ``w_m``.
    mesh_position_offsets : ndarray, shape (n_mesh,)
        ``s0_m`` [cycles].
    left_tables, right_tables : ndarray, shape (n_mesh, n_table)
        Flank stiffness over one mesh cycle [N/m].
    backlash, mesh_damping : ndarray, shape (n_mesh,)
        ``j_m`` [m] and the viscous mesh damping [N s/m].
    f_const : ndarray, shape (n,)
        Constant generalised force.
    ipar : ndarray of int64, shape (5,)
        ``[mode, input_dof, output_dof, carrier_dof, gyroscopic_on]`` (``-1`` = none).
    fpar : ndarray, shape (7,)
        ``[k_c, c_c, output_sense, T0, c1, c2, speed_limit]``.
    speed_table : ndarray, shape (3, n_speed)
        Rows: time [s], input speed [rad/s], input angle [rad] at the nodes.
    torque_table : ndarray, shape (2, n_torque)
        Rows: time [s] (``DRIVE_MOTOR``: input speed [rad/s]), input torque [N m].
    deflection_limit : ndarray, shape (n_mesh,)
        Blow-up threshold on ``|delta_m|`` and ``|delta_R,m|`` [m].
    mesh_back_vectors : ndarray, shape (n_mesh, n), optional
        ``u_m``, the right (back) flank's line of action; None: the same as ``v_m``.
    fault_records, fault_ints, fault_vals : ndarray, optional
        Faulty meshes (:meth:`gearvib.faults.law.FaultLaw.pack`): the record start of every
        mesh in ``fault_ints`` (-1: healthy) and the integer and float data.
    fault_jumps : dict of int to ndarray, optional
        Extra per-cycle jump positions of faulty meshes [cycles, 0..1).
    mesh_damping_law : ndarray of int64, shape (n_mesh,), optional
        :data:`DAMPING_GATED` (damping only on a flank in contact, the default) or
        :data:`DAMPING_VISCOUS` (always on) per mesh; None: gated everywhere.
    drive_sensing : ndarray, shape (n,), optional
        ``DRIVE_SPEED``: the row ``p`` whose product with ``q`` (``qdot``) is the angle
        (speed) the drive controls (rigid-body sensing); None: the input coordinate.
    """

    minv: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    gyroscopic: np.ndarray
    centripetal: np.ndarray
    mesh_vectors: np.ndarray
    mesh_position_vectors: np.ndarray
    mesh_position_offsets: np.ndarray
    left_tables: np.ndarray
    right_tables: np.ndarray
    backlash: np.ndarray
    mesh_damping: np.ndarray
    f_const: np.ndarray
    ipar: np.ndarray
    fpar: np.ndarray
    speed_table: np.ndarray
    torque_table: np.ndarray
    deflection_limit: np.ndarray
    mesh_back_vectors: np.ndarray | None = None
    fault_records: np.ndarray | None = None
    fault_ints: np.ndarray | None = None
    fault_vals: np.ndarray | None = None
    fault_jumps: dict | None = None
    mesh_damping_law: np.ndarray | None = None
    drive_sensing: np.ndarray | None = None

    def __post_init__(self) -> None:
        for f in fields(self):
            a = getattr(self, f.name)
            if a is None or f.name == "fault_jumps":
                continue
            dtype = np.int64 if f.name in ("ipar", "fault_records", "fault_ints",
                                           "mesh_damping_law") else np.float64
            setattr(self, f.name, np.ascontiguousarray(a, dtype=dtype))
        n = self.minv.shape[0]
        n_mesh = self.mesh_vectors.shape[0]
        if self.mesh_vectors.shape != (n_mesh, n) or self.stiffness.shape != (n, n):
            raise ValueError("inconsistent array shapes in KernelSystem")
        if self.mesh_back_vectors is not None and self.mesh_back_vectors.shape != (n_mesh, n):
            raise ValueError("mesh_back_vectors must have the shape of mesh_vectors")
        if self.ipar.shape != (N_IPAR,) or self.fpar.shape != (N_FPAR,):
            raise ValueError("ipar must have 5 and fpar 7 entries")
        law = self.mesh_damping_law
        if law is not None and (law.shape != (n_mesh,) or not np.all(
                (law == DAMPING_GATED) | (law == DAMPING_VISCOUS))):
            raise ValueError(f"mesh_damping_law must hold {n_mesh} values "
                             f"{DAMPING_GATED} (gated) or {DAMPING_VISCOUS} (viscous)")
        if self.drive_sensing is not None and (self.drive_sensing.shape != (n,) or not np.all(
                np.isfinite(self.drive_sensing)) or not np.any(self.drive_sensing)):
            raise ValueError(f"drive_sensing must be a finite, non-zero row of {n} values")

    @property
    def n_dof(self) -> int:
        """Number of coordinates."""
        return int(self.minv.shape[0])

    @property
    def n_mesh(self) -> int:
        """Number of meshes."""
        return int(self.mesh_vectors.shape[0])

    @property
    def back_vectors(self) -> np.ndarray:
        """``u_m``: the back-flank vectors (``mesh_vectors`` when none are given)."""
        return self.mesh_vectors if self.mesh_back_vectors is None else self.mesh_back_vectors

    def distinct_back_lines(self) -> np.ndarray:
        """True for every mesh whose back-flank line of action differs from the left one's."""
        if self.mesh_back_vectors is None:
            return np.zeros(self.n_mesh, dtype=bool)
        return np.any(self.mesh_back_vectors != self.mesh_vectors, axis=1)

    def astuple(self) -> tuple:
        """The ``system`` argument of the kernels (see :func:`pack`)."""
        return pack(self)


# Header of the packed integer array: counts, then ``ipar``, then the offsets of every block of
# the integer and the float array (see :func:`pack`).
H_N = 0
H_NMESH = 1
H_IPAR = 2
_INT_BLOCKS = (
    "lp", "li", "cp", "ci", "gp", "gi", "ii", "oi", "vp", "vi", "fp", "fi", "pp", "pi", "bp",
    "rflag", "rvp", "rvi", "rfp", "rfi", "frec", "fint", "mlaw", "di",
)
_FLOAT_BLOCKS = (
    "acc0", "lv", "cv", "gv", "iv", "ov", "vv", "fv", "pv", "s0", "bl", "mc", "fpar", "limit",
    "bv", "rvv", "rfv", "fval", "dv",
)
(
    H_LP, H_LI, H_CP, H_CI, H_GP, H_GI, H_II, H_OI, H_VP, H_VI, H_FP, H_FI, H_PP, H_PI, H_BP,
    H_RFLAG, H_RVP, H_RVI, H_RFP, H_RFI, H_FREC, H_FINT, H_MLAW, H_DI,
) = range(H_IPAR + N_IPAR, H_IPAR + N_IPAR + len(_INT_BLOCKS))
(
    H_ACC0, H_LV, H_CV, H_GV, H_IV, H_OV, H_VV, H_FV, H_PV, H_S0, H_BL, H_MC, H_FPAR, H_LIMIT,
    H_BV, H_RVV, H_RFV, H_FVAL, H_DV,
) = range(H_LP + len(_INT_BLOCKS), H_LP + len(_INT_BLOCKS) + len(_FLOAT_BLOCKS))
H_NI = H_DV + 1  # number of entries of the sparse input column
H_NO = H_DV + 2  # ... and of the output column
#: Address of the faulty-mesh pass compiled for this system (:mod:`gearvib.fault_pass`), 0:
#: the generic pass (:func:`with_pass`). Set only in the process that runs the kernel (an
#: address is no value to pickle): :func:`pack` writes 0.
H_FPASS = H_DV + 3
#: Number of entries of the drive sensing row (0: the drive acts on the input coordinate).
H_ND = H_DV + 4
N_HEADER = H_DV + 5

# record of a faulty mesh in the fault integer block (gearvib.faults.law.FaultLaw.pack); int
# entries that are offsets point into the fault int block or (``*V``) the fault float block
(F_NU, F_NSLOT, F_Z1, F_S1, F_T1, F_Z2, F_S2, F_T2, F_PAIRV, F_PROF1, F_SHIFT1V, F_PROF2,
 F_SHIFT2V, F_PROFV, F_NECC, F_ECCI, F_ECCV, F_CONSTV, F_NEV, F_EVV, F_ALWAYS, F_NPER, F_SHARED,
 F_EPSV, F_NEED, F_PERIOD, F_EXIT, F_NEEDRES, F_LAW, F_RAMPOUT, F_MESHWIDE) = range(31)

#: A table segment whose stiffness changes by more than this fraction of the table's range
#: within one table interval is a jump (e.g. the tooth-pair changes of a rectangular model).
JUMP_FRACTION = 0.05
#: At most this many jump segments per mesh are located; tables with more are smooth enough.
MAX_JUMPS_PER_MESH = 32
#: Index type of the hot loops: numba computes no negative-index wraparound for unsigned indices
#: (``_U(i)`` is a free cast; mixing it with signed integers would give float64, which numba
#: refuses as an index, so a slip cannot go unnoticed).
_U = np.uint64
_U1 = np.uint64(1)
#: An eccentricity angle within this distance [rad] of its cached reference gets its cosine
#: and sine from a Taylor series of the difference (exact to rounding).
ECC_TAYLOR_RANGE = 0.05
#: Local error of a short sub-step (Euler, midpoint) relative to that of a full RK4 step
#: on the highest natural frequency (module docstring, "Short sub-steps").
SHORT_STEP_ERROR_FRACTION = 0.1


def short_step_header(omega_max: float) -> tuple[float, float, float]:
    """``(omega, c_E, c_M)``: the header of the fault float block that sets the short
    sub-steps of a run with faults (module docstring).

    ``(omega h_E)**2 / 2 = rho (omega dt)**5 / 120`` and
    ``(omega h_M)**3 / 6 = rho (omega dt)**5 / 120`` with ``rho`` =
    :data:`SHORT_STEP_ERROR_FRACTION`; zeros (RK4 everywhere) when ``omega_max`` [rad/s] is
    not positive and finite.
    """
    rho = SHORT_STEP_ERROR_FRACTION
    if not (0.0 < omega_max < np.inf):
        return 0.0, 0.0, 0.0
    return float(omega_max), float(np.sqrt(rho / 60.0)), float((rho / 20.0) ** (1.0 / 3.0))


def jump_positions(left: np.ndarray, right: np.ndarray) -> list[np.ndarray]:
    """Mesh positions [cycles, in 0..1) of the ends of the jump segments of every mesh.

    A segment ``[i, i + 1) / n_table`` of the left or right table is a jump when its change
    exceeds ``JUMP_FRACTION`` of that table's range. The integrator ends its sub-steps at these
    positions, so no RK4 stage straddles a jump of the stiffness.
    """
    out = []
    for tl, tr in zip(np.atleast_2d(left), np.atleast_2d(right), strict=True):
        n = tl.size
        pos: set[int] = set()
        for tab in (tl, tr):
            span = float(tab.max() - tab.min())
            if span <= 0.0:
                continue
            step = np.abs(np.roll(tab, -1) - tab)
            seg = np.flatnonzero(step > JUMP_FRACTION * span)
            if seg.size <= MAX_JUMPS_PER_MESH:
                pos.update(int(i) for i in seg)
                pos.update(int(i + 1) % n for i in seg)
        out.append(np.array(sorted(pos), dtype=np.float64) / n)
    return out


def csr(mat: np.ndarray, pattern: np.ndarray | None = None
        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Compressed sparse rows ``(indptr, indices, data)`` of a dense matrix (exact zeros dropped).

    Entries keep the row-major order of the dense matrix, so the sums of the kernels are
    evaluated in a fixed order (deterministic results). ``pattern`` (boolean, the shape of
    ``mat``) stores these entries instead of the non-zeros (a batch's common pattern,
    :func:`gearvib.kernels_batch.pack_batch`; entries outside ``mat``'s non-zeros are stored
    as 0).
    """
    a = np.asarray(mat, dtype=np.float64)
    rows, cols = np.nonzero(a if pattern is None else pattern)
    indptr = np.zeros(a.shape[0] + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=a.shape[0]), out=indptr[1:])
    return indptr, cols.astype(np.int64), np.ascontiguousarray(a[rows, cols])


def operators(system: KernelSystem) -> list[np.ndarray]:
    """The dense operators :func:`pack` stores sparse, in its order.

    ``lin = -M^-1 [K C]``, ``cent = M^-1 K_Omega``, ``gyro = -M^-1 G``, the columns ``M^-1 e``
    of the input and output coordinates (as ``(1, n)`` rows; empty without such a
    coordinate), ``v_m``, ``(M^-1 v_m)^T``, ``w_m``, the back-flank ``u_m`` and
    ``(M^-1 u_m)^T`` (zero rows for meshes without a distinct back line), and the drive
    sensing row (``(1, n)``; zeros without one).
    """
    minv = system.minv

    def column(k: int) -> np.ndarray:
        return minv[:, k][None, :] if k >= 0 else np.zeros((1, 0))

    distinct = system.distinct_back_lines()
    back = np.where(distinct[:, None], system.back_vectors, 0.0)
    return [
        -np.hstack([minv @ system.stiffness, minv @ system.damping]),
        minv @ system.centripetal,
        -(minv @ system.gyroscopic),
        column(int(system.ipar[IP_INPUT])),
        column(int(system.ipar[IP_OUTPUT])),
        system.mesh_vectors,
        (minv @ system.mesh_vectors.T).T,
        system.mesh_position_vectors,
        back,
        (minv @ back.T).T,
        np.zeros((1, minv.shape[0])) if system.drive_sensing is None
        else system.drive_sensing[None, :],
    ]


def pack(system: KernelSystem, patterns: list[np.ndarray] | None = None,
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pack a :class:`KernelSystem` into the few flat arrays the compiled kernels take.

    The inverse mass matrix is multiplied into every operator once, here, and every operator is
    stored sparse (CSR), because bearing, coupling and mesh vectors touch only a few
    coordinates. Few arguments keep the per-call overhead of the right-hand side small (every
    array argument of a compiled function is passed as a struct and reference counted).

    Returns
    -------
    ints : ndarray of int64
        Header (``N_HEADER`` entries: ``n``, ``n_mesh``, ``ipar``, block offsets, sparse-column
        lengths), then the CSR pointers and indices of ``lin = -M^-1 [K C]`` (columns index the
        state ``y``), ``cent = M^-1 K_Omega``, ``gyro = -M^-1 G`` (columns index ``qdot``), the
        sparse columns ``M^-1 e`` of the input and output coordinates, the mesh vectors ``v_m``,
        the rows ``(M^-1 v_m)^T``, the mesh-position vectors ``w_m``, the jump counts, a flag
        per mesh (1: distinct back line), the back-flank vectors ``u_m`` and rows
        ``(M^-1 u_m)^T`` (empty rows for the meshes without a distinct back line), the fault
        record of every mesh (-1: healthy), the fault integer data, the mesh-damping law
        of every mesh (:data:`DAMPING_GATED`, :data:`DAMPING_VISCOUS`) and the coordinates of
        the drive sensing row.
    floats : ndarray
        ``M^-1 f_const``, the CSR data of the operators above, ``s0``, backlash, mesh damping,
        ``fpar``, the deflection limits, the jump positions, the fault float data and the
        drive sensing row's values.
    tables : ndarray, shape (2, n_mesh, n_table)
        Left and right flank stiffness tables.
    speed_table, torque_table : ndarray
        As in :class:`KernelSystem`.

    Notes
    -----
    ``floats`` holds a copy of ``deflection_limit``: pack after setting it. ``patterns`` (one
    boolean array per operator of :func:`operators`) stores those entries instead of each
    operator's non-zeros: the common pattern of a batch
    (:func:`gearvib.kernels_batch.pack_batch`).
    """
    n, n_mesh = system.n_dof, system.n_mesh
    ops = operators(system)
    pat = [None] * len(ops) if patterns is None else patterns
    (lp, li, lv), (cp, ci, cv), (gp, gi, gv), (_, ii, iv), (_, oi, ov), (vp, vi, vv), (
        fp, fi, fv), (pp, pi, pv), (rvp, rvi, rvv), (rfp, rfi, rfv), (_, di, dv) = (
        csr(a, q) for a, q in zip(ops, pat, strict=True))
    jumps = jump_positions(system.left_tables, system.right_tables)
    for m, extra in (system.fault_jumps or {}).items():
        jumps[m] = np.unique(np.concatenate([jumps[m], np.asarray(extra, dtype=np.float64)]))
    frec = (np.full(n_mesh, -1, dtype=np.int64) if system.fault_records is None
            else system.fault_records)
    fint = np.zeros(0, dtype=np.int64) if system.fault_ints is None else system.fault_ints
    fval = np.zeros(0) if system.fault_vals is None else system.fault_vals
    bp = np.concatenate([[0], np.cumsum([j.size for j in jumps])]).astype(np.int64)
    bv = np.concatenate([np.zeros(0), *jumps])
    rflag = system.distinct_back_lines().astype(np.int64)
    mlaw = (np.zeros(n_mesh, dtype=np.int64) if system.mesh_damping_law is None
            else system.mesh_damping_law)
    int_blocks = [lp, li, cp, ci, gp, gi, ii, oi, vp, vi, fp, fi, pp, pi, bp,
                  rflag, rvp, rvi, rfp, rfi, frec, fint, mlaw, di]
    float_blocks = [
        system.minv @ system.f_const, lv, cv, gv, iv, ov, vv, fv, pv, system.mesh_position_offsets,
        system.backlash, system.mesh_damping, system.fpar, system.deflection_limit, bv,
        rvv, rfv, fval, dv,
    ]
    header = np.zeros(N_HEADER, dtype=np.int64)
    header[H_N] = n
    header[H_NMESH] = n_mesh
    header[H_IPAR : H_IPAR + N_IPAR] = system.ipar
    pos = N_HEADER
    for h, block in zip(range(H_LP, H_LP + len(int_blocks)), int_blocks, strict=True):
        header[h] = pos
        pos += block.size
    pos = 0
    for h, block in zip(range(H_ACC0, H_ACC0 + len(float_blocks)), float_blocks, strict=True):
        header[h] = pos
        pos += block.size
    header[H_NI] = ii.size
    header[H_NO] = oi.size
    header[H_ND] = di.size
    ints = np.concatenate([header, *int_blocks]).astype(np.int64)
    floats = np.concatenate([np.asarray(b, dtype=np.float64).ravel() for b in float_blocks])
    tables = np.ascontiguousarray(np.stack([system.left_tables, system.right_tables]))
    return ints, floats, tables, system.speed_table, system.torque_table


MESH_OUT_COLUMNS = 31
"""Columns of the per-mesh scratch ``mesh_out``: ``F_L, -F_R, k_eff, state, delta, s,
delta_R``; for a faulty mesh whether its pair law is needed during the current step (set
before every step by :func:`_split_times`; 1 is always correct), the run of need-table cells
that flag holds for (:func:`_need_interval`), an interval of mesh positions free of its
long-period jump positions, and two reference angles of its eccentricities with their
cosines and sines (columns 12-17). Row 0, columns 18-20: the eccentricity angle evaluated
last in any mesh with its cosine and sine (the meshes of an eccentric gear share its angle:
one evaluation per right-hand side). Columns 21-23: a mesh cycle ``floor(s)`` of a faulty
mesh with the teeth of its next pair. Columns 24-30 (a mesh under the mean-offset law,
:func:`_offset_cycle`): the mesh cycle they were kept for, then ``(mean, lowest, highest)``
of the offsets of the pairs in contact before the leaving pair's ramp cell and the same
after it."""


def n_signals(n_dof: int, n_mesh: int) -> int:
    """Number of columns of a recorded sample row: ``2 n_dof + 3 n_mesh``."""
    return 2 * n_dof + 3 * n_mesh


@njit(cache=True)
def _interp_cell(n: int, s: float) -> tuple[int, int, float]:
    """Cell ``(i0, i1)`` and weight of ``i1`` for periodic linear interpolation at ``s``."""
    frac = s - np.floor(s)
    u = frac * n
    i0 = int(u)
    w = u - i0
    if i0 >= n:  # frac rounded up to exactly 1
        i0 = 0
        w = 0.0
    i1 = i0 + 1
    if i1 == n:
        i1 = 0
    return i0, i1, w


@njit(cache=True)
def periodic_interp(table: np.ndarray, row: int, s: float) -> float:
    """Periodic linear interpolation of ``table[row]`` (samples at ``s = i / n_table``)."""
    i0, i1, w = _interp_cell(table.shape[1], s)
    return (1.0 - w) * table[row, i0] + w * table[row, i1]


@njit(cache=True)
def flank_forces(
    delta: float, ddelta: float, k_left: float, k_right: float, backlash: float, damping: float
) -> tuple[float, float, float, int]:
    """Contact law of one mesh whose two flanks share one line of action.

    :func:`flank_forces_two_lines` with ``delta_right = delta`` (same operations, same
    results).
    """
    return flank_forces_two_lines(delta, ddelta, delta, ddelta, k_left, k_right, backlash,
                                  damping)


@njit(cache=True)
def flank_forces_two_lines(
    delta: float, ddelta: float, delta_right: float, ddelta_right: float, k_left: float,
    k_right: float, backlash: float, damping: float
) -> tuple[float, float, float, int]:
    """Contact law of one mesh (paper eq. 2, both flanks checked and superposed).

    Parameters
    ----------
    delta, ddelta : float
        Normal mesh deflection along the left flank's line of action [m] and its rate [m/s].
    delta_right, ddelta_right : float
        The same along the right (back) flank's line of action.
    k_left, k_right : float
        Flank stiffness at the current mesh position [N/m].
    backlash : float
        Total normal backlash ``j`` [m]; negative loads both flanks.
    damping : float
        Viscous mesh damping [N s/m], acting only on a flank in contact (the gated law;
        :func:`flank_forces_viscous` is the always-on law).

    Returns
    -------
    f_left : float
        ``k_L (delta - j/2) + c ddelta`` if ``delta > j/2``, floored at 0 (no tension), else 0.
    f_right : float
        ``k_R (delta_R + j/2) + c ddelta_R`` if ``delta_R < -j/2``, capped at 0 (no tension),
        else 0.
    k_eff : float
        Sum of the stiffness of the flanks in contact.
    state : int
        Bit 0: left flank in contact; bit 1: right flank in contact.
    """
    half = 0.5 * backlash
    f_left = 0.0
    f_right = 0.0
    k_eff = 0.0
    state = 0
    if delta > half:
        f_left = k_left * (delta - half) + damping * ddelta
        if f_left < 0.0:
            f_left = 0.0
        k_eff += k_left
        state += 1
    if delta_right < -half:
        f_right = k_right * (delta_right + half) + damping * ddelta_right
        if f_right > 0.0:
            f_right = 0.0
        k_eff += k_right
        state += 2
    return f_left, f_right, k_eff, state


@njit(cache=True)
def flank_forces_viscous(
    delta: float, ddelta: float, delta_right: float, ddelta_right: float, k_left: float,
    k_right: float, backlash: float, damping: float
) -> tuple[float, float, float, int]:
    """Contact law of one mesh with always-on viscous damping (Kahraman & Singh 1990).

    The flank springs of :func:`flank_forces_two_lines` (piecewise linear, the dead zone of
    the backlash between them) plus the viscous force ``c ddelta``, which acts whatever the
    contact and is neither floored nor capped: on a mesh with one line of action the total
    force along it is ``k f(delta) + c ddelta``, the published equation. The viscous force
    goes on the left flank's line (``c ddelta``) unless only the right flank is in contact
    (then ``c ddelta_R`` on the back line): with two lines of action it acts along the loaded
    line, inside the backlash along the left one.

    Parameters and returns as :func:`flank_forces_two_lines`; ``f_left`` may be negative
    and ``f_right`` positive (the viscous force), ``k_eff`` and ``state`` are those of the
    flank springs.

    References
    ----------
    Kahraman, A., Singh, R. (1990). Non-linear dynamics of a spur gear pair. J. Sound Vib.
    142(1), 49-75.
    """
    half = 0.5 * backlash
    f_left = 0.0
    f_right = 0.0
    k_eff = 0.0
    state = 0
    if delta > half:
        f_left = k_left * (delta - half)
        k_eff += k_left
        state += 1
    if delta_right < -half:
        f_right = k_right * (delta_right + half)
        k_eff += k_right
        state += 2
    if state == 2:  # the back flank alone: the viscous force on its line of action
        f_right += damping * ddelta_right
    else:
        f_left += damping * ddelta
    return f_left, f_right, k_eff, state


@njit(cache=True, inline="always")
def _viscous_sums(on_l, on_r, f_el, f_er, c_l, c_r):
    """Flank forces and state of the always-on law from the flank springs' forces ``f_el``,
    ``f_er`` (counted where ``on_l``, ``on_r``) and the viscous forces ``c_l``, ``c_r`` along
    the left and the back line (:func:`flank_forces_viscous`)."""
    fl = f_el if on_l else 0.0
    fr = f_er if on_r else 0.0
    st = 0
    if on_l:
        st += 1
    if on_r:
        st += 2
    if st == 2:
        fr += c_r
    else:
        fl += c_l
    return fl, fr, st


@njit(cache=True, _nrt=False)
def _segment(tt: np.ndarray, t: float) -> int:
    """Index ``i`` with ``tt[i] <= t < tt[i + 1]`` for ``tt[0] < t < tt[-1]`` (bisection).

    A scalar loop instead of ``np.searchsorted``: the speed table is read at every stage of
    every step.
    """
    lo = 0
    hi = tt.shape[0] - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if tt[mid] <= t:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True, _nrt=False)
def _speed_at(tab: np.ndarray, t: float) -> tuple[float, float]:
    """Prescribed input angle and speed at ``t`` (piecewise-linear speed, exact integral)."""
    tt = tab[0]
    w = tab[1]
    phi = tab[2]
    n = tt.shape[0]
    if n == 1 or t <= tt[0]:
        return phi[0] + w[0] * (t - tt[0]), w[0]
    if t >= tt[n - 1]:
        return phi[n - 1] + w[n - 1] * (t - tt[n - 1]), w[n - 1]
    i = _segment(tt, t)
    tau = t - tt[i]
    slope = (w[i + 1] - w[i]) / (tt[i + 1] - tt[i])
    return phi[i] + w[i] * tau + 0.5 * slope * tau * tau, w[i] + slope * tau


@njit(cache=True)
def speed_profile(tab: np.ndarray, times: np.ndarray, angle: np.ndarray, speed: np.ndarray) -> None:
    """Evaluate the prescribed input angle [rad] and speed [rad/s] at ``times`` (in place)."""
    for i in range(times.shape[0]):
        a, w = _speed_at(tab, times[i])
        angle[i] = a
        speed[i] = w


@njit(cache=True, _nrt=False)
def _table_at(tab: np.ndarray, t: float) -> float:
    """Piecewise-linear table of time, held constant outside its range."""
    tt = tab[0]
    v = tab[1]
    n = tt.shape[0]
    if n == 1 or t <= tt[0]:
        return v[0]
    if t >= tt[n - 1]:
        return v[n - 1]
    i = _segment(tt, t)
    return v[i] + (v[i + 1] - v[i]) * (t - tt[i]) / (tt[i + 1] - tt[i])


@njit(cache=True, _nrt=False)
def _need_interval(ints, rec, c_lo, c_hi):
    """Whether a faulty mesh needs its pair law somewhere in the cells ``c_lo .. c_hi`` of its
    need table (``F_NEEDRES`` cells per mesh cycle, over the period of the faulty teeth; a
    pair with a faulty tooth in contact, margin included, :meth:`gearvib.faults.law.
    FaultedMesh.need_table`), or always (deviations), with the run of cells around it with
    the same answer: ``(flag, a, b)``. Needed: every range of cells that meets ``a .. b`` (a
    run of needed cells holding the first needed one found) needs it; not needed: no range
    inside ``a .. b`` (the free run around ``c_lo .. c_hi``, at most a period either side)
    does. The caller keeps the run and asks again only when a step leaves it (about twice
    per period of the faulty teeth instead of at every change of the step's cells). Read in
    floating point: no integer division in the loop."""
    r = ints[H_FINT] + rec
    if ints[r + F_ALWAYS] != 0:
        return 1.0, -np.inf, np.inf
    period = ints[r + F_PERIOD]
    need = ints[H_FINT] + ints[r + F_NEED]
    x = float(c_lo)
    k = _tooth_index(x, period)  # c_lo mod period
    kk = k
    c = c_lo
    while c <= c_hi:
        if ints[need + kk] != 0:  # needed: the run of needed cells around c
            a = c
            ka = kk
            for _ in range(period):
                ka = ka - 1 if ka > 0 else period - 1
                if ints[need + ka] == 0:
                    break
                a -= 1.0
            b = c
            kb = kk
            for _ in range(period):
                kb = kb + 1 if kb < period - 1 else 0
                if ints[need + kb] == 0:
                    break
                b += 1.0
            return 1.0, a, b
        c += 1.0
        kk = kk + 1 if kk < period - 1 else 0
    a = c_lo  # not needed: the free run around c_lo .. c_hi
    ka = k
    for _ in range(period):
        ka = ka - 1 if ka > 0 else period - 1
        if ints[need + ka] != 0:
            break
        a -= 1.0
    b = c_hi
    kb = _tooth_index(float(c_hi), period)
    for _ in range(period):
        kb = kb + 1 if kb < period - 1 else 0
        if ints[need + kb] != 0:
            break
        b += 1.0
    return 0.0, a, b


@njit(cache=True, inline="always")
def _cos_sin(ang, mesh_out, m, term):
    """``cos(ang), sin(ang)`` from a reference angle cached in ``mesh_out[m, 12:18]`` (two
    terms per mesh): degree-9 Taylor series of the small difference (< ECC_TAYLOR_RANGE rad,
    truncation below 1e-18), else computed and cached as the new reference. The same angle
    as the last one evaluated (``mesh_out[0, 18:21]``, e.g. the sun's in its next planet
    mesh) takes the stored values."""
    if ang == mesh_out[0, 18]:  # NaN (nothing stored) fails the test
        return mesh_out[0, 19], mesh_out[0, 20]
    ca, sa = _cos_sin_ref(ang, mesh_out, m, term)
    mesh_out[0, 18] = ang
    mesh_out[0, 19] = ca
    mesh_out[0, 20] = sa
    return ca, sa


@njit(cache=True, inline="always")
def _cos_sin_ref(ang, mesh_out, m, term):
    """``cos(ang), sin(ang)`` from the reference of term ``term`` of mesh ``m``
    (:func:`_cos_sin`)."""
    if term > 1:
        return np.cos(ang), np.sin(ang)
    c0 = _U(12 + 3 * term)
    dlt = ang - mesh_out[m, c0]
    if abs(dlt) < ECC_TAYLOR_RANGE:  # NaN (no reference yet) fails the test
        d2 = dlt * dlt  # Estrin's scheme: the powers in parallel with the low terms
        d4 = d2 * d2
        cd = (1.0 - d2 * 0.5) + d4 * ((1.0 / 24.0 - d2 * (1.0 / 720.0)) + d4 * (1.0 / 40320.0))
        sd = dlt * ((1.0 - d2 * (1.0 / 6.0))
                    + d4 * ((1.0 / 120.0 - d2 * (1.0 / 5040.0)) + d4 * (1.0 / 362880.0)))
        cr = mesh_out[m, c0 + _U1]
        sr = mesh_out[m, c0 + _U(2)]
        return cr * cd - sr * sd, sr * cd + cr * sd
    ca = np.cos(ang)
    sa = np.sin(ang)
    mesh_out[m, c0] = ang
    mesh_out[m, c0 + _U1] = ca
    mesh_out[m, c0 + _U(2)] = sa
    return ca, sa


@njit(cache=True, inline="always")
def _presence(i, i0, w, nper, ce):
    """Weight of pair slot ``i`` (path position ``u = frac(s) + i``) at cell ``i0`` with
    weight ``w`` of the cycle: 1 inside the path, ramping in over the last cell before entry
    (slot -1) and out over the cell ``ce`` that holds the contact ratio."""
    if i < 0:
        return w if i0 == nper - 1 else 0.0
    iu = i0 + i * nper
    if iu < ce:
        return 1.0
    if iu == ce:
        return 1.0 - w
    return 0.0


@njit(cache=True, inline="always")
def _deviation_offsets(ints, vals, r, y, n, mesh_out, m):
    """Mesh-wide deviations of faulty mesh ``m`` (record at ``ints[r]``): the offsets of the
    left and right flank and their rates, from rigid pin errors and eccentricities.

    ``r``, ``n`` (coordinates) and ``m`` unsigned (:data:`_U`): no wraparound code.
    """
    fv0 = _U(ints[H_FVAL])
    cv = fv0 + _U(ints[r + _U(F_CONSTV)])
    el = vals[cv]
    er = vals[cv + _U1]
    edl = 0.0
    edr = 0.0
    n_ecc = ints[r + _U(F_NECC)]
    if n_ecc > 0:
        ei = _U(ints[H_FINT]) + _U(ints[r + _U(F_ECCI)])
        ev = fv0 + _U(ints[r + _U(F_ECCV)])
        for e in range(n_ecc):
            dg = ints[ei + _U(2 * e)]
            dc = ints[ei + _U(2 * e + 1)]
            ang = 0.0
            rate = 0.0
            if dg >= 0:
                ang += y[_U(dg)]
                rate += y[n + _U(dg)]
            if dc >= 0:
                ang -= y[_U(dc)]
                rate -= y[n + _U(dc)]
            ca, sa = _cos_sin(ang, mesh_out, m, e)
            # amp cos(ang + phase) with cos(phase), sin(phase) stored: one cos, sin per angle
            b = ev + _U(6 * e)
            al = vals[b]
            cl = vals[b + _U1]
            sl = vals[b + _U(2)]
            ar = vals[b + _U(3)]
            cr = vals[b + _U(4)]
            sr = vals[b + _U(5)]
            el += al * (ca * cl - sa * sl)
            er += ar * (ca * cr - sa * sr)
            edl -= al * (sa * cl + ca * sl) * rate
            edr -= ar * (sa * cr + ca * sr) * rate
    return el, er, edl, edr


@njit(cache=True, inline="always")
def _tooth_index(x, z):
    """``x mod z`` for a whole ``x`` and ``z > 0``, in floating point (no integer division)."""
    k = int(x - z * np.floor(x / z))
    if k >= z:
        k -= z
    elif k < 0:
        k += z
    return k


@njit(cache=True, inline="always")
def _pair_cell(ints, r, s, mesh_out, m):
    """Where faulty mesh ``m`` (record at ``ints[r]``) is at position ``s``: ``(i0, w, k1,
    k2)``, the cell ``i0`` of the ``F_NPER`` cells of the mesh cycle ``floor(s)`` and the weight
    ``w`` within it, and the teeth ``k1``, ``k2`` of the two gears in the next pair (counter
    ``floor(s) + 1``; each older pair steps back by the gear's sign, :func:`_older_tooth`).

    The teeth are kept in ``mesh_out[m, 21:24]`` for the mesh cycle (floating-point modulo,
    :func:`_tooth_index`, only when the cycle changes)."""
    nper = ints[r + F_NPER]
    sf = np.floor(s)
    frac = s - sf
    x0 = frac * nper
    i0 = int(x0)
    w = x0 - i0
    if i0 >= nper:
        i0 = 0
        w = 0.0
    if sf == mesh_out[m, 21]:  # NaN (nothing kept) fails the test
        k1 = int(mesh_out[m, 22])
        k2 = int(mesh_out[m, 23])
    else:
        z1 = ints[r + F_Z1]
        z2 = ints[r + F_Z2]
        k1 = 0
        k2 = 0
        if z1 > 0:
            k1 = _tooth_index(ints[r + F_S1] * (sf + 1.0) + ints[r + F_T1], z1)
        if z2 > 0:
            k2 = _tooth_index(ints[r + F_S2] * (sf + 1.0) + ints[r + F_T2], z2)
        mesh_out[m, 21] = sf
        mesh_out[m, 22] = k1
        mesh_out[m, 23] = k2
    return i0, w, k1, k2


@njit(cache=True, inline="always")
def _older_tooth(k, sg, z):
    """The tooth of a gear (``z`` teeth, pair-counter sign ``sg``) in the next older pair."""
    k -= sg
    if k < 0:
        k += z
    elif k >= z:
        k -= z
    return k


@njit(cache=True, inline="always")
def _pair_record(ints, r):
    """Fields of the pair law of the faulty mesh with record ``ints[r]``
    (:mod:`gearvib.faults.law`): ``(z1, z2, nu, nper, nslot, ce, sg1, sg2, p1, p2, shared, pv,
    prv)``, the teeth of the two gears (0: no tooth of its own), path samples, cells per
    cycle, pair slots, exit cell, pair-counter signs, the offsets of the gears' profile
    indices in ``ints``, whether the pairs share the mesh table, and the offsets of the pair
    table and the profiles in ``vals``."""
    fi0 = ints[H_FINT]
    fv0 = ints[H_FVAL]
    return (ints[r + F_Z1], ints[r + F_Z2], ints[r + F_NU], ints[r + F_NPER],
            ints[r + F_NSLOT], ints[r + F_EXIT], ints[r + F_S1], ints[r + F_S2],
            fi0 + ints[r + F_PROF1], fi0 + ints[r + F_PROF2], ints[r + F_SHARED] != 0,
            fv0 + ints[r + F_PAIRV], fv0 + ints[r + F_PROFV])


@njit(cache=True, inline="always")
def _profile_factor(vals, base, nu, idx, wi, k, row):
    """``k`` times row ``row`` (0: left, 1: right stiffness factor) of the tooth profile whose
    rows start at ``vals[base]``, at sample ``idx`` with weight ``wi``."""
    b = _U(base + row * nu + idx)
    return k * ((1.0 - wi) * vals[b] + wi * vals[b + _U1])


@njit(cache=True, inline="always")
def _tooth_profile(ints, vals, prv, nu, p, k, idx, wi, kl, kr):
    """``(q, kl, kr)`` for tooth ``k`` of a gear whose profile indices start at ``ints[p]``:
    where its profile rows start in ``vals`` (-1: a healthy profile) and the pair stiffness
    ``kl``, ``kr`` times its stiffness factors at sample ``idx``, weight ``wi``."""
    q = -1
    prof = ints[_U(p + k)]
    if prof >= 0:
        q = prv + prof * 4 * nu
        kl = _profile_factor(vals, q, nu, idx, wi, kl, 0)
        kr = _profile_factor(vals, q, nu, idx, wi, kr, 1)
    return q, kl, kr


@njit(cache=True, inline="always")
def _slot_pair(ints, vals, pv, prv, nu, p1, p2, z1, z2, k1, k2, i, i0, w, nper, pres, shared):
    """Pair slot ``i`` (presence ``pres``, teeth ``k1``, ``k2``): ``(idx, wi, kl, kr, q1,
    q2)``, its sample ``idx`` on the path grid and weight ``wi`` (path position ``u = frac +
    i``; the entering pair, ``u < 0``, takes the values at ``u = 0``), its stiffness on both
    flanks (the pair table at ``pv`` times ``pres``, or ``pres`` for a shared table, scaled by
    :func:`_table_shares`; times the profile factors of both teeth) and where the profile rows
    of each tooth start in ``vals`` (-1: no profile deviation; rows 2 and 3 hold the gaps)."""
    idx = 0
    wi = 0.0
    if i >= 0:
        idx = i0 + i * nper
        wi = w
    if shared:
        kl = pres
        kr = pres
    else:
        a = _U(pv + idx)  # offsets and counters >= 0: unsigned, no wraparound
        c = _U(pv + nu + idx)
        kl = ((1.0 - wi) * vals[a] + wi * vals[a + _U1]) * pres
        kr = ((1.0 - wi) * vals[c] + wi * vals[c + _U1]) * pres
    q1 = -1
    q2 = -1
    if z1 > 0:
        q1, kl, kr = _tooth_profile(ints, vals, prv, nu, p1, k1, idx, wi, kl, kr)
    if z2 > 0:
        q2, kl, kr = _tooth_profile(ints, vals, prv, nu, p2, k2, idx, wi, kl, kr)
    return idx, wi, kl, kr, q1, q2


@njit(cache=True, inline="always")
def _table_shares(tables, m, i0, w, nper, psum):
    """Shares ``(left, right)`` of the mesh table at cell ``i0``, weight ``w``, for pairs of
    summed presence ``psum`` (pairs that share the table carry ``table / psum`` each)."""
    if psum > 0.0:
        i1 = i0 + 1
        if i1 == nper:
            i1 = 0
        return (((1.0 - w) * tables[0, m, i0] + w * tables[0, m, i1]) / psum,
                ((1.0 - w) * tables[1, m, i0] + w * tables[1, m, i1]) / psum)
    return 0.0, 0.0


@njit(cache=True, _nrt=False)
def _offset_cycle(ints, vals, r, sf, mesh_out, m):
    """Keep the pair offsets of mesh cycle ``sf`` of a mesh under the mean-offset law.

    The law (:attr:`gearvib.faults.law.FaultedMesh.offsets_only`): pair slot ``i`` (pair
    counter ``sf - i``) carries the sum ``o_i`` of its two teeth's pitch offsets, constant
    over the cycle. Outside the two ramp cells the pairs in contact are the slots ``0 .. a``
    before the leaving pair's ramp cell (``i0 < c = exit_cell mod n_per``) and ``0 .. a - 1``
    after it (``a = exit_cell // n_per >= 1``). ``mesh_out[m, 24:31]`` receives ``sf`` and
    the mean, lowest and highest ``o_i`` of either zone (the mean clamped into its range, so
    the contact tests of :func:`_mean_offset` bound it). Called once per mesh cycle.
    """
    fv0 = ints[H_FVAL]
    z1 = ints[r + F_Z1]
    z2 = ints[r + F_Z2]
    sg1 = ints[r + F_S1]
    sg2 = ints[r + F_S2]
    h1 = fv0 + ints[r + F_SHIFT1V]
    h2 = fv0 + ints[r + F_SHIFT2V]
    a = ints[r + F_EXIT] // ints[r + F_NPER]
    k1 = _tooth_index(sg1 * sf + ints[r + F_T1], z1) if z1 > 0 else 0
    k2 = _tooth_index(sg2 * sf + ints[r + F_T2], z2) if z2 > 0 else 0
    total = 0.0
    lo = np.inf
    hi = -np.inf
    for i in range(a + 1):
        if i == a:  # slots 0 .. a - 1: the zone after the leaving pair's ramp
            mean = min(max(total / a, lo), hi)
            mesh_out[m, 28] = mean
            mesh_out[m, 29] = lo
            mesh_out[m, 30] = hi
        o = 0.0
        if z1 > 0:
            o += vals[h1 + k1]
            k1 -= sg1
            if k1 < 0:
                k1 += z1
            elif k1 >= z1:
                k1 -= z1
        if z2 > 0:
            o += vals[h2 + k2]
            k2 -= sg2
            if k2 < 0:
                k2 += z2
            elif k2 >= z2:
                k2 -= z2
        total += o
        lo = min(lo, o)
        hi = max(hi, o)
    mesh_out[m, 24] = sf
    mesh_out[m, 25] = min(max(total / (a + 1), lo), hi)
    mesh_out[m, 26] = lo
    mesh_out[m, 27] = hi


@njit(cache=True, inline="always")
def _mean_offset(ints, vals, r, s, i0, d, dr, el, er, kl, kr, half, mesh_out, m):
    """``(o_mean, holds)``: the mean pitch offset of the pairs in contact on a mesh under the
    mean-offset law, and whether that law holds here.

    It holds outside the two ramp cells of the cycle while on each flank every pair in
    contact is loaded (with a positive table stiffness) or none is; then the pair law equals
    the table law with the deflection offsets ``el + o_mean``, ``er + o_mean``. Otherwise the
    caller takes the pair law.
    """
    c = ints[r + _U(F_RAMPOUT)]
    if i0 == c or i0 == ints[r + _U(F_NPER)] - 1:
        return 0.0, False
    sf = np.floor(s)
    if sf != mesh_out[m, 24]:  # NaN (nothing kept) fails the test
        _offset_cycle(ints, vals, r, sf, mesh_out, m)
    col = _U(25) if i0 < c else _U(28)
    lo = mesh_out[m, col + _U1]
    hi = mesh_out[m, col + _U(2)]
    left = (d + (el + lo) > half and kl > 0.0) or d + (el + hi) <= half
    right = (dr + (er + hi) < -half and kr > 0.0) or dr + (er + lo) >= -half
    return mesh_out[m, col], left and right


@njit(cache=True, _nrt=False)
def _faulty_flanks(ints, vals, tables, m, r, s, d, dd, dr, ddr, el, er, edl, edr, half,
                   damping, mesh_out, viscous):
    """Contact law of a faulty mesh, tooth pair by tooth pair (:mod:`gearvib.faults.law`).

    ``r``: the mesh's record in ``ints``; ``el, er, edl, edr``: its mesh-wide deflection
    offsets and their rates (:func:`_deviation_offsets`); ``viscous``: the always-on damping
    law (:func:`flank_forces_viscous`) instead of the gated one. Returns ``(f_left, f_right,
    k_eff, state)`` like :func:`flank_forces_two_lines`.
    """
    z1, z2, nu, nper, nslot, ce, sg1, sg2, p1, p2, shared, pv, prv = _pair_record(ints, r)
    i0, w, k1, k2 = _pair_cell(ints, r, s, mesh_out, m)
    h1 = ints[H_FVAL] + ints[r + F_SHIFT1V]
    h2 = ints[H_FVAL] + ints[r + F_SHIFT2V]
    # one pass over the pair slots (the next pair, slot -1, ramps in over the last cell of the
    # cycle, a pair ramps out over the cell that holds the contact ratio, as the table ramps).
    # Shared pairs carry table / psum each: their sums are taken with a unit share and scaled
    # once psum is known.
    psum = 0.0
    f_el = 0.0
    f_er = 0.0
    ke_l = 0.0
    ke_r = 0.0
    on_l = False
    on_r = False
    for i in range(-1, nslot + 1):
        pres = _presence(i, i0, w, nper, ce)
        if pres > 0.0:
            psum += pres
            idx, wi, kl, kr, q1, q2 = _slot_pair(ints, vals, pv, prv, nu, p1, p2, z1, z2, k1,
                                                 k2, i, i0, w, nper, pres, shared)
            ol = el
            orr = er
            for g in range(2):  # the offsets of the pair's two teeth: pitch shift, profile gap
                if g == 0:
                    if z1 <= 0:
                        continue
                    sh = vals[_U(h1 + k1)]
                    base = q1
                else:
                    if z2 <= 0:
                        continue
                    sh = vals[_U(h2 + k2)]
                    base = q2
                ol += sh
                orr += sh
                if base >= 0:
                    b2 = _U(base + 2 * nu + idx)
                    b3 = _U(base + 3 * nu + idx)
                    ol -= (1.0 - wi) * vals[b2] + wi * vals[b2 + _U1]
                    orr += (1.0 - wi) * vals[b3] + wi * vals[b3 + _U1]
            if kl > 0.0 and d + ol > half:
                f_el += kl * (d + ol - half)
                ke_l += kl
                on_l = True
            if kr > 0.0 and dr + orr < -half:
                f_er += kr * (dr + orr + half)
                ke_r += kr
                on_r = True
        k1 = _older_tooth(k1, sg1, z1)  # the next older pair
        k2 = _older_tooth(k2, sg2, z2)
    if shared:
        share_l, share_r = _table_shares(tables, m, i0, w, nper, psum)
        on_l = on_l and share_l > 0.0
        on_r = on_r and share_r > 0.0
        f_el *= share_l
        f_er *= share_r
        ke_l *= share_l if on_l else 0.0
        ke_r *= share_r if on_r else 0.0
    ke = ke_l + ke_r
    if viscous:
        fl, fr, st = _viscous_sums(on_l, on_r, f_el, f_er, damping * (dd + edl),
                                   damping * (ddr + edr))
        return fl, fr, ke, st
    fl = 0.0
    fr = 0.0
    st = 0
    if on_l:
        fl = f_el + damping * (dd + edl)
        if fl < 0.0:
            fl = 0.0
        st += 1
    if on_r:
        fr = f_er + damping * (ddr + edr)
        if fr > 0.0:
            fr = 0.0
        st += 2
    return fl, fr, ke, st


@njit(cache=True, _nrt=False)
def _stiffness_flanks(ints, vals, tables, m, r, s, d, dd, dr, ddr, half, damping, mesh_out,
                      viscous):
    """Contact law of a faulty mesh whose tooth faults change the stiffness only
    (:attr:`gearvib.faults.law.FaultedMesh.stiffness_only`): the table law with the summed
    stiffness of the pairs present.

    ``d, dd, dr, ddr`` include the mesh-wide offsets. Every pair meets the same deflection, so
    the pair law's sums become one product per flank: the same stiffness sums as
    :func:`_faulty_flanks` (bit for bit), the force equal to rounding. ``viscous``: the
    always-on damping law. Returns ``(f_left, f_right, k_eff, state)`` like
    :func:`flank_forces_two_lines`.
    """
    z1, z2, nu, nper, nslot, ce, sg1, sg2, p1, p2, shared, pv, prv = _pair_record(ints, r)
    i0, w, k1, k2 = _pair_cell(ints, r, s, mesh_out, m)
    psum = 0.0
    ke_l = 0.0
    ke_r = 0.0
    for i in range(-1, nslot + 1):
        pres = _presence(i, i0, w, nper, ce)
        if pres > 0.0:
            psum += pres
            _, _, kl, kr, _, _ = _slot_pair(ints, vals, pv, prv, nu, p1, p2, z1, z2, k1, k2, i,
                                            i0, w, nper, pres, shared)
            if kl > 0.0:
                ke_l += kl
            if kr > 0.0:
                ke_r += kr
        k1 = _older_tooth(k1, sg1, z1)  # the next older pair
        k2 = _older_tooth(k2, sg2, z2)
    on_l = ke_l > 0.0 and d > half
    on_r = ke_r > 0.0 and dr < -half
    f_el = ke_l * (d - half)
    f_er = ke_r * (dr + half)
    if shared:
        share_l, share_r = _table_shares(tables, m, i0, w, nper, psum)
        on_l = on_l and share_l > 0.0
        on_r = on_r and share_r > 0.0
        f_el *= share_l
        f_er *= share_r
        ke_l *= share_l
        ke_r *= share_r
    if viscous:
        fl, fr, st = _viscous_sums(on_l, on_r, f_el, f_er, damping * dd, damping * ddr)
        ke = 0.0
        if on_l:
            ke += ke_l
        if on_r:
            ke += ke_r
        return fl, fr, ke, st
    ke = 0.0
    fl = 0.0
    fr = 0.0
    st = 0
    if on_l:
        fl = f_el + damping * dd
        if fl < 0.0:
            fl = 0.0
        ke += ke_l
        st += 1
    if on_r:
        fr = f_er + damping * ddr
        if fr > 0.0:
            fr = 0.0
        ke += ke_r
        st += 2
    return fl, fr, ke, st


@njit(cache=True, inline="always")
def _mesh_header(ints):
    """Offsets of the mesh operators in the packed system, unsigned (:func:`pack`): ``(vp, vi,
    vv, fp, fi, fv, pp, pi, pv, s0, bl, mc, rflag, rvp, rvi, rvv, rfp, rfi, rfv, frec,
    mlaw)``."""
    return (_U(ints[H_VP]), _U(ints[H_VI]), _U(ints[H_VV]), _U(ints[H_FP]), _U(ints[H_FI]),
            _U(ints[H_FV]), _U(ints[H_PP]), _U(ints[H_PI]), _U(ints[H_PV]), _U(ints[H_S0]),
            _U(ints[H_BL]), _U(ints[H_MC]), _U(ints[H_RFLAG]), _U(ints[H_RVP]),
            _U(ints[H_RVI]), _U(ints[H_RVV]), _U(ints[H_RFP]), _U(ints[H_RFI]),
            _U(ints[H_RFV]), _U(ints[H_FREC]), _U(ints[H_MLAW]))


@njit(cache=True, inline="always")
def _mesh_deflections(y, ints, vals, m, n, hdr):
    """``(d, dd, dr, ddr, s, two_lines)`` of mesh ``m``: the deflection along the line of
    action and its rate, the same of the back flank (its own line where the mesh has two,
    ``two_lines``; else ``d, dd``) and the mesh position ``s`` [mesh cycles]."""
    vp, vi, vv, _fp, _fi, _fv, pp, pi, pv, s0 = hdr[:10]
    rflag, rvp, rvi, rvv = hdr[12:16]
    d = 0.0
    dd = 0.0
    for p in range(_U(ints[vp + m]), _U(ints[vp + m + _U1])):
        j = _U(ints[vi + p])
        d += vals[vv + p] * y[j]
        dd += vals[vv + p] * y[n + j]
    two_lines = ints[rflag + m] != 0
    dr = d
    ddr = dd
    if two_lines:  # the back flank's own line of action
        dr = 0.0
        ddr = 0.0
        for p in range(_U(ints[rvp + m]), _U(ints[rvp + m + _U1])):
            j = _U(ints[rvi + p])
            dr += vals[rvv + p] * y[j]
            ddr += vals[rvv + p] * y[n + j]
    s = vals[s0 + m]
    for p in range(_U(ints[pp + m]), _U(ints[pp + m + _U1])):
        s += vals[pv + p] * y[_U(ints[pi + p])]
    return d, dd, dr, ddr, s, two_lines


@njit(cache=True, inline="always")
def _add_mesh_forces(dy, ints, vals, mesh_out, m, n, hdr, two_lines, fl, fr, ke, st, d, s, dr):
    """Subtract the flank forces ``fl``, ``fr`` of mesh ``m`` from the accelerations in ``dy``
    (one line of action: their sum, bit for bit as a one-line model) and write ``mesh_out[m,
    :7] = (F_L, -F_R, k_eff, state, delta, s, delta_R)``."""
    fp, fi, fv = hdr[3:6]
    rfp, rfi, rfv = hdr[16:19]
    if two_lines:
        if fl != 0.0:
            for p in range(_U(ints[fp + m]), _U(ints[fp + m + _U1])):
                dy[n + _U(ints[fi + p])] -= fl * vals[fv + p]
        if fr != 0.0:
            for p in range(_U(ints[rfp + m]), _U(ints[rfp + m + _U1])):
                dy[n + _U(ints[rfi + p])] -= fr * vals[rfv + p]
    else:
        f = fl + fr
        if f != 0.0:
            for p in range(_U(ints[fp + m]), _U(ints[fp + m + _U1])):
                dy[n + _U(ints[fi + p])] -= f * vals[fv + p]
    mesh_out[m, 0] = fl
    mesh_out[m, 1] = -fr
    mesh_out[m, 2] = ke
    mesh_out[m, 3] = st
    mesh_out[m, 4] = d
    mesh_out[m, 5] = s
    mesh_out[m, 6] = dr


@njit(cache=True, inline="always")
def _faulty_meshes(y, dy, mesh_out, ints, vals, tables, hdr):
    """The meshes with faults under their own law (``mesh_out[m, 7]`` set): forces added to
    ``dy`` and ``mesh_out[m, :7]`` written as in :func:`_rhs`.

    One pass after the healthy meshes, compiled apart as the generic pass
    (:func:`generic_pass`) and called by the right-hand side through ``ints[H_FPASS]``.
    Mesh-wide deviations (eccentricity, rigid pin errors) shift the table law; pitch offsets
    alone take the mean-offset law where it holds (:func:`_mean_offset`), stiffness-only
    tooth faults the stiffness law (:func:`_stiffness_flanks`), everything else the pair law
    (:func:`_faulty_flanks`).
    ``hdr``: the mesh header (:func:`_mesh_header`).
    """
    n = _U(ints[H_N])
    n_table = tables.shape[2]
    bl = hdr[10]
    mc = hdr[11]
    frec = hdr[19]
    ml = hdr[20]
    fi0 = _U(ints[H_FINT])
    for m in range(_U(ints[H_NMESH])):
        rec = ints[frec + m]
        if rec < 0 or mesh_out[m, 7] == 0.0:
            continue
        d, dd, dr, ddr, s, two_lines = _mesh_deflections(y, ints, vals, m, n, hdr)
        r = fi0 + _U(rec)
        half = 0.5 * vals[bl + m]
        el = 0.0
        er = 0.0
        edl = 0.0
        edr = 0.0
        if ints[r + _U(F_MESHWIDE)] != 0:
            el, er, edl, edr = _deviation_offsets(ints, vals, r, y, n, mesh_out, m)
        law = ints[r + _U(F_LAW)]  # gearvib.faults.law.LAW_*
        viscous = ints[ml + m] != 0
        if law == 3:  # stiffness-only tooth faults: the table law with the pairs' stiffness
            fl, fr, ke, st = _stiffness_flanks(ints, vals, tables, m, r, s, d + el, dd + edl,
                                               dr + er, ddr + edr, half, vals[mc + m],
                                               mesh_out, viscous)
        else:
            pairs = law == 2
            kl = 0.0
            kr = 0.0
            if not pairs:
                i0, i1, w = _interp_cell(n_table, s)
                kl = (1.0 - w) * tables[0, m, _U(i0)] + w * tables[0, m, _U(i1)]
                kr = (1.0 - w) * tables[1, m, _U(i0)] + w * tables[1, m, _U(i1)]
                if law == 1:  # pitch offsets only: the mean-offset law where it holds
                    mean, holds = _mean_offset(ints, vals, r, s, i0, d, dr, el, er, kl, kr,
                                               half, mesh_out, m)
                    if holds:
                        el += mean
                        er += mean
                    else:
                        pairs = True
            if pairs:  # tooth pair by tooth pair
                fl, fr, ke, st = _faulty_flanks(ints, vals, tables, m, r, s, d, dd, dr, ddr,
                                                el, er, edl, edr, half, vals[mc + m],
                                                mesh_out, viscous)
            elif viscous:  # the same offset on every pair in contact: the table law, shifted
                fl, fr, ke, st = flank_forces_viscous(d + el, dd + edl, dr + er, ddr + edr,
                                                      kl, kr, 2.0 * half, vals[mc + m])
            else:
                fl, fr, ke, st = flank_forces_two_lines(d + el, dd + edl, dr + er, ddr + edr,
                                                        kl, kr, 2.0 * half, vals[mc + m])
        _add_mesh_forces(dy, ints, vals, mesh_out, m, n, hdr, two_lines, fl, fr, ke, st, d, s,
                         dr)


def _call_address(builder: ir.IRBuilder, address: ir.Value, params: list[ir.Value]) -> None:
    """Emit the call of the C function at ``address`` (an integer) with the LLVM values
    ``params``, returning nothing (:func:`_call_pass`, :func:`_call_rhs`)."""
    fnty = ir.FunctionType(ir.VoidType(), [p.type for p in params])
    builder.call(builder.inttoptr(address, fnty.as_pointer()), params)


def _c_function(store: list, signature: types.Type, py_func: Callable) -> int:
    """Address of ``py_func`` compiled as a C function of ``signature`` (``cache=True``),
    compiled or loaded at the first call and kept in ``store`` (:func:`generic_pass`,
    :func:`rhs_address`)."""
    if not store:
        store.append(cfunc(signature, cache=True)(py_func))
    return int(store[0].address)


@intrinsic
def _call_pass(typingctx, address, y, dy, mesh_out, ints, vals, tables):
    """Call the compiled faulty-mesh pass at ``address``: a C function of the data pointers
    of ``y, dy, mesh_out, ints, vals, tables`` and the lengths of ``ints``, ``vals`` and
    ``tables`` (:data:`PASS_SIGNATURE`; :mod:`gearvib.fault_pass`, :func:`generic_pass`). An
    indirect call with plain pointers and integers: a compiled numba function would take
    every array as a struct."""
    sig = types.void(address, y, dy, mesh_out, ints, vals, tables)

    def codegen(context, builder, signature, args):
        arrays = [context.make_array(ty)(context, builder, val)
                  for ty, val in zip(signature.args[1:], args[1:], strict=True)]
        params = [a.data for a in arrays] + [arrays[3].nitems, arrays[4].nitems,
                                             arrays[5].nitems]
        _call_address(builder, args[0], params)
        return context.get_dummy_value()

    return sig, codegen


_F64P = types.CPointer(types.float64)
#: The C signature of a faulty-mesh pass (:func:`_call_pass`): pointers to ``y, dy, mesh_out,
#: ints, vals, tables`` and the lengths of ``ints``, ``vals`` and ``tables``.
PASS_SIGNATURE = types.void(_F64P, _F64P, _F64P, types.CPointer(types.int64), _F64P, _F64P,
                            types.intp, types.intp, types.intp)


def _generic_pass(yp, dyp, mp, ip, vp, tp, n_ints, n_vals, n_tab):  # pragma: no cover - jit
    """The generic faulty-mesh pass (:func:`_faulty_meshes`) as a C function of
    :data:`PASS_SIGNATURE`, compiled by :func:`generic_pass` on first use."""
    ints = carray(ip, (n_ints,))
    n = ints[H_N]
    n_mesh = ints[H_NMESH]
    y = carray(yp, (2 * n,))
    dy = carray(dyp, (2 * n,))
    mesh_out = carray(mp, (n_mesh, MESH_OUT_COLUMNS))
    vals = carray(vp, (n_vals,))
    tables = carray(tp, (2, n_mesh, n_tab // (2 * n_mesh)))
    _faulty_meshes(y, dy, mesh_out, ints, vals, tables, _mesh_header(ints))


_GENERIC_PASS: list = []


def generic_pass() -> int:
    """Address of the generic faulty-mesh pass (:func:`_faulty_meshes` as a C function),
    compiled at the first call in the process (loaded from numba's cache after the first
    run on a machine). The kernels call it for a system with faults whose ``ints[H_FPASS]``
    is 0 (:func:`integrate_chunk`, :func:`evaluate_rhs`, :func:`rhs_loop`); a run without
    faults never compiles it."""
    return _c_function(_GENERIC_PASS, PASS_SIGNATURE, _generic_pass)


def generic_pass_compiled() -> bool:
    """Whether this process has compiled (or loaded) the generic faulty-mesh pass."""
    return bool(_GENERIC_PASS)


def with_pass(system: tuple) -> tuple:
    """``system`` (:meth:`KernelSystem.astuple`) ready for the compiled kernels: itself when
    it has no faulty mesh or its ``ints[H_FPASS]`` holds a pass, else with a copy of ``ints``
    holding the address of the generic pass (:func:`generic_pass`; the caller's arrays are
    not changed)."""
    ints = system[0]
    if ints[H_FPASS] != 0:
        return system
    frec = int(ints[H_FREC])
    if not np.any(ints[frec: frec + int(ints[H_NMESH])] >= 0):
        return system
    ints = ints.copy()
    ints[H_FPASS] = generic_pass()
    return (ints, *system[1:])


@njit(cache=True, _nrt=False)
def _rhs(t, y, dy, mesh_out, ints, vals, tables, speed_tab, torque_tab):
    """Right-hand side ``dy = f(t, y)``; ``mesh_out[m] = (F_L, -F_R, k_eff, state, delta, s,
    delta_R)``.

    ``ints, vals, tables, speed_tab, torque_tab`` is the packed system of :func:`pack`; every
    product runs over the stored non-zeros only. Indices are unsigned (:data:`_U`), so no
    negative-index wraparound is computed on the hot path; negative sentinels (``-1``: none)
    are read signed.
    """
    n = _U(ints[H_N])
    n_mesh = _U(ints[H_NMESH])
    n_table = tables.shape[2]
    lp = _U(ints[H_LP])
    li = _U(ints[H_LI])
    lv = _U(ints[H_LV])
    a0 = _U(ints[H_ACC0])
    for i in range(n):
        dy[i] = y[n + i]
        acc = vals[a0 + i]
        for p in range(_U(ints[lp + i]), _U(ints[lp + i + _U1])):
            acc += vals[lv + p] * y[_U(ints[li + p])]
        dy[n + i] = acc
    fpar = _U(ints[H_FPAR])
    carrier = ints[H_IPAR + IP_CARRIER]
    if ints[H_IPAR + IP_GYRO] != 0 and carrier >= 0:
        om = y[n + _U(carrier)]
        om2 = om * om
        cp = _U(ints[H_CP])
        ci = _U(ints[H_CI])
        cv = _U(ints[H_CV])
        gp = _U(ints[H_GP])
        gi = _U(ints[H_GI])
        gv = _U(ints[H_GV])
        for i in range(n):
            acc = 0.0
            for p in range(_U(ints[cp + i]), _U(ints[cp + i + _U1])):
                acc += vals[cv + p] * y[_U(ints[ci + p])]
            acc2 = 0.0
            for p in range(_U(ints[gp + i]), _U(ints[gp + i + _U1])):
                acc2 += vals[gv + p] * y[n + _U(ints[gi + p])]
            dy[n + i] += om2 * acc + om * acc2
    mode = ints[H_IPAR + IP_MODE]
    k_in = _U(ints[H_IPAR + IP_INPUT])  # >= 0: every model has an input rotation
    torque = 0.0
    if mode == DRIVE_SPEED:
        phi, w = _speed_at(speed_tab, t)
        nd = _U(ints[H_ND])
        if nd == 0:  # a coupling on the input coordinate
            torque = vals[fpar + _U(FP_KC)] * (phi - y[k_in]) + vals[fpar + _U(FP_CC)] * (
                w - y[n + k_in])
        else:  # a controller on the rigid-body coordinate p . q
            di = _U(ints[H_DI])
            dv = _U(ints[H_DV])
            ang = 0.0
            rate = 0.0
            for p in range(nd):
                j = _U(ints[di + p])
                ang += vals[dv + p] * y[j]
                rate += vals[dv + p] * y[n + j]
            torque = vals[fpar + _U(FP_KC)] * (phi - ang) + vals[fpar + _U(FP_CC)] * (
                w - rate)
    elif mode == DRIVE_TORQUE:
        torque = _table_at(torque_tab, t)
    elif mode == DRIVE_MOTOR:
        torque = _table_at(torque_tab, y[n + k_in])
    if torque != 0.0:
        ii = _U(ints[H_II])
        iv = _U(ints[H_IV])
        for p in range(_U(ints[H_NI])):
            dy[n + _U(ints[ii + p])] += vals[iv + p] * torque
    k_out = ints[H_IPAR + IP_OUTPUT]
    if k_out >= 0:
        e = vals[fpar + _U(FP_OUTDIR)]
        wo = e * y[n + _U(k_out)]
        load = -e * (
            vals[fpar + _U(FP_T0)] + vals[fpar + _U(FP_C1)] * wo
            + vals[fpar + _U(FP_C2)] * wo * abs(wo)
        )
        oi = _U(ints[H_OI])
        ov = _U(ints[H_OV])
        for p in range(_U(ints[H_NO])):
            dy[n + _U(ints[oi + p])] += vals[ov + p] * load
    hdr = _mesh_header(ints)
    bl = hdr[10]
    mc = hdr[11]
    frec = hdr[19]
    ml = hdr[20]
    faulty = False
    for m in range(n_mesh):
        if ints[frec + m] >= 0 and mesh_out[m, 7] != 0.0:
            faulty = True  # a mesh with faults under its own law: the pass below
            continue
        d, dd, dr, ddr, s, two_lines = _mesh_deflections(y, ints, vals, m, n, hdr)
        i0, i1, w = _interp_cell(n_table, s)
        kl = (1.0 - w) * tables[0, m, _U(i0)] + w * tables[0, m, _U(i1)]
        kr = (1.0 - w) * tables[1, m, _U(i0)] + w * tables[1, m, _U(i1)]
        if ints[ml + m] != 0:  # DAMPING_VISCOUS: always-on damping (Kahraman & Singh)
            fl, fr, ke, st = flank_forces_viscous(d, dd, dr, ddr, kl, kr, vals[bl + m],
                                                  vals[mc + m])
        else:
            fl, fr, ke, st = flank_forces_two_lines(d, dd, dr, ddr, kl, kr, vals[bl + m],
                                                    vals[mc + m])
        _add_mesh_forces(dy, ints, vals, mesh_out, m, n, hdr, two_lines, fl, fr, ke, st, d, s,
                         dr)
    if faulty:  # the pass compiled for this system's faults, or the generic one
        _call_pass(ints[H_FPASS], y, dy, mesh_out, ints, vals, tables)


_I64P = types.CPointer(types.int64)
#: The C signature of the compiled right-hand side (:func:`rhs_address`): ``t``, pointers to
#: ``y, dy, mesh_out, ints, vals, tables, speed_tab, torque_tab``, the lengths of ``ints`` and
#: ``vals`` and the last extents of ``tables``, ``speed_tab`` and ``torque_tab``.
RHS_SIGNATURE = types.void(types.float64, _F64P, _F64P, _F64P, _I64P, _F64P, _F64P, _F64P,
                           _F64P, types.intp, types.intp, types.intp, types.intp, types.intp)


def _rhs_entry(t, yp, dyp, mp, ip, vp, tp, sp, qp, n_ints, n_vals, n_table, n_speed,
               n_torque):  # pragma: no cover - jit
    """:func:`_rhs` as a C function of :data:`RHS_SIGNATURE`, compiled by :func:`rhs_address`."""
    ints = carray(ip, (n_ints,))
    n2 = 2 * ints[H_N]
    n_mesh = ints[H_NMESH]
    _rhs(t, carray(yp, (n2,)), carray(dyp, (n2,)), carray(mp, (n_mesh, MESH_OUT_COLUMNS)),
         ints, carray(vp, (n_vals,)), carray(tp, (2, n_mesh, n_table)),
         carray(sp, (3, n_speed)), carray(qp, (2, n_torque)))


_RHS: list = []


def rhs_address() -> int:
    """Address of the compiled right-hand side (:func:`_rhs` as a C function of
    :data:`RHS_SIGNATURE`), compiled at the first call in the process (loaded from numba's
    cache after the first run on a machine). The compiled kernels call it through this
    address (:func:`_call_rhs`), so they compile without it and never compile it again."""
    return _c_function(_RHS, RHS_SIGNATURE, _rhs_entry)


@intrinsic
def _call_rhs(typingctx, address, t, y, dy, mesh_out, ints, vals, tables, speed_tab,
              torque_tab):
    """Call the compiled right-hand side at ``address`` (:func:`rhs_address`): an indirect
    call with the arrays' data pointers and extents."""
    sig = types.void(address, t, y, dy, mesh_out, ints, vals, tables, speed_tab, torque_tab)

    def codegen(context, builder, signature, args):
        arrays = [context.make_array(ty)(context, builder, val)
                  for ty, val in zip(signature.args[2:], args[2:], strict=True)]
        last = [cgutils.unpack_tuple(builder, a.shape)[-1] for a in arrays[5:]]
        params = [context.cast(builder, args[1], signature.args[1], types.float64),
                  *(a.data for a in arrays), arrays[3].nitems, arrays[4].nitems, *last]
        _call_address(builder, args[0], params)
        return context.get_dummy_value()

    return sig, codegen


def evaluate_rhs(t: float, y: np.ndarray, system: tuple) -> tuple[np.ndarray, np.ndarray]:
    """Right-hand side at one state (allocating; for tests and cross-checks, not for loops).

    Returns
    -------
    dy : ndarray, shape (2 n,)
        ``[qdot, qddot]``.
    mesh_out : ndarray, shape (n_mesh, 7)
        Per mesh ``F_left, -F_right, k_eff, contact state, delta``, the mesh position ``s`` and
        ``delta_R`` (the first columns of the kernels' scratch).
    """
    return _evaluate_rhs(t, y, with_pass(system), rhs_address())


@njit(cache=True)
def _evaluate_rhs(t, y, system, rhs):
    """:func:`evaluate_rhs` of a system ready for the kernels (:func:`with_pass`)."""
    ints, vals, tables, speed_tab, torque_tab = system
    dy = np.empty(2 * ints[H_N])
    mesh_out = np.zeros((ints[H_NMESH], MESH_OUT_COLUMNS))
    mesh_out[:, 7] = 1.0  # faulty meshes: their own law (exact everywhere)
    mesh_out[:, 12] = np.nan  # no cached eccentricity angles
    mesh_out[:, 15] = np.nan
    mesh_out[0, 18] = np.nan  # no shared eccentricity angle
    mesh_out[:, 21] = np.nan  # no kept mesh cycle
    mesh_out[:, 24] = np.nan  # no kept offsets of a mesh cycle
    _call_rhs(rhs, t, y, dy, mesh_out, ints, vals, tables, speed_tab, torque_tab)
    return dy, mesh_out[:, :7].copy()


def rhs_loop(states: np.ndarray, t0: float, dt: float, n_eval: int, system: tuple,
             dy: np.ndarray, mesh_out: np.ndarray) -> float:
    """``n_eval`` right-hand sides at the rows of ``states`` (cycled), times ``t0 + r dt``.

    For benchmarks (``benchmarks/bench_kernel.py``): the right-hand side of the kernels alone,
    without allocation; returns the sum of the last entries of ``dy`` (a check value).
    """
    return _rhs_loop(states, t0, dt, n_eval, with_pass(system), dy, mesh_out, rhs_address())


@njit(cache=True)
def _rhs_loop(states, t0, dt, n_eval, system, dy, mesh_out, rhs):
    """:func:`rhs_loop` of a system ready for the kernels (:func:`with_pass`)."""
    ints, vals, tables, speed_tab, torque_tab = system
    check = 0.0
    r = 0
    n2 = states.shape[1]
    for _ in range(n_eval):
        _call_rhs(rhs, t0 + r * dt, states[r], dy, mesh_out, ints, vals, tables, speed_tab,
                  torque_tab)
        check += dy[n2 - 1]
        r += 1
        if r == states.shape[0]:
            r = 0
    return check


def work_shape(n_dof: int, n_mesh: int) -> tuple[int, int]:
    """Shape of the ``work`` buffer of :func:`integrate_chunk`."""
    return 6, max(2 * n_dof, 4 * n_mesh + 4)


@njit(cache=True, inline="always")
def _insert_split(splits, count, tau, dt, tol):
    """Insert ``tau`` into the sorted ``splits[:count]`` unless out of ``(0, dt)``, a time this
    close is there already or the list is full; returns the new count."""
    if not (tol < tau < dt - tol):
        return count
    j = count
    while j > 0 and splits[j - 1] > tau:
        j -= 1
    if (j > 0 and tau - splits[j - 1] <= tol) or (j < count and splits[j] - tau <= tol):
        return count
    if count == splits.shape[0]:
        return count
    for r in range(count, j, -1):
        splits[r] = splits[r - 1]
    splits[j] = tau
    return count + 1


@njit(cache=True, _nrt=False)
def _split_times(y, dt, ints, vals, mesh_out, splits):
    """Times in ``(0, dt)`` at which a mesh position reaches a stiffness jump during the step.

    The mesh positions ``mesh_out[:, 5]`` (left there by the right-hand side evaluated at the
    start of the step, state ``y``) are extrapolated linearly with their rates ``w_m . qdot``;
    the sorted, de-duplicated times go to ``splits`` (as many as it holds). Faulty meshes add
    their long-period jump positions (sorted, one period of their faulty teeth; found by
    bisection). Returns their count.
    """
    n = ints[H_N]
    pp = ints[H_PP]
    pi = ints[H_PI]
    pv = ints[H_PV]
    bp = ints[H_BP]
    bv = ints[H_BV]
    frec = ints[H_FREC]
    fi0 = ints[H_FINT]
    fv0 = ints[H_FVAL]
    tol = 1e-9 * dt
    count = 0
    for m in range(ints[H_NMESH]):
        b0 = ints[bp + m]
        b1 = ints[bp + m + 1]
        rec = ints[frec + m]
        n_ev = 0
        if rec >= 0:
            n_ev = ints[fi0 + rec + F_NEV]
        elif b1 == b0:
            continue
        s = mesh_out[m, 5]
        sd = 0.0
        for p in range(ints[pp + m], ints[pp + m + 1]):
            sd += vals[pv + p] * y[n + ints[pi + p]]
        s_end = s + sd * dt
        lo = min(s, s_end)
        hi = max(s, s_end)
        if rec >= 0:  # the pair law of a faulty mesh during this step (cached per cell)
            res = ints[fi0 + rec + F_NEEDRES]
            flo = np.floor(lo * res)
            fhi = np.floor(hi * res)
            # kept: a run of cells (columns 8, 9) known to need it (column 7 = 1: needed by
            # every range meeting it) or known free (0: free for every range inside it)
            if mesh_out[m, 7] != 0.0:
                keep = flo <= mesh_out[m, 9] and mesh_out[m, 8] <= fhi  # NaN: ask
            else:
                keep = mesh_out[m, 8] <= flo and fhi <= mesh_out[m, 9]
            if not keep:
                flag, ca, cb = _need_interval(ints, rec, flo, fhi)
                mesh_out[m, 7] = flag
                mesh_out[m, 8] = ca
                mesh_out[m, 9] = cb
        if sd == 0.0:
            continue
        base = np.floor(lo)
        for k in range(int(np.floor(hi) - base) + 1):
            for q in range(b0, b1):
                tau = (base + k + vals[bv + q] - s) / sd
                count = _insert_split(splits, count, tau, dt, tol)
        # long-period positions, unless the step lies inside the event-free interval found
        # last time (columns 10, 11)
        if n_ev > 0 and not (mesh_out[m, 10] < lo and hi < mesh_out[m, 11]):
            ev = fv0 + ints[fi0 + rec + F_EVV]
            period = vals[ev]
            for kp in range(int(np.floor(lo / period)), int(np.floor(hi / period)) + 1):
                off = kp * period
                a = _first_beyond(vals, ev + 1, n_ev, lo - off)
                while a < n_ev and vals[ev + 1 + a] + off < hi:
                    count = _insert_split(splits, count, (vals[ev + 1 + a] + off - s) / sd,
                                          dt, tol)
                    a += 1
            off = np.floor(hi / period) * period
            a = _first_beyond(vals, ev + 1, n_ev, hi - off)
            mesh_out[m, 11] = (vals[ev + 1 + a] + off if a < n_ev
                               else vals[ev + 1] + off + period)
            mesh_out[m, 10] = (vals[ev + a] + off if a > 0
                               else vals[ev + n_ev] + off - period)
    return count


@njit(cache=True, inline="always")
def _first_beyond(vals, start, count, x):
    """Index of the first of ``vals[start : start + count]`` (sorted) that exceeds ``x``."""
    a = 0
    b = count
    while a < b:
        mid = (a + b) // 2
        if vals[start + mid] <= x:
            a = mid + 1
        else:
            b = mid
    return a


@njit(cache=True, _nrt=False)
def _rk4_step(rhs, t, h, y, k1, k2, k3, k4, tmp, mesh_out, ints, vals, tables, speed_tab,
              torque_tab):
    """One classical RK4 step of size ``h`` from ``(t, y)`` (in place); ``k1 = f(t, y)`` given."""
    n2 = _U(2 * ints[H_N])
    h2 = 0.5 * h
    h6 = h / 6.0
    for i in range(n2):
        tmp[i] = y[i] + h2 * k1[i]
    _call_rhs(rhs, t + h2, tmp, k2, mesh_out, ints, vals, tables, speed_tab, torque_tab)
    for i in range(n2):
        tmp[i] = y[i] + h2 * k2[i]
    _call_rhs(rhs, t + h2, tmp, k3, mesh_out, ints, vals, tables, speed_tab, torque_tab)
    for i in range(n2):
        tmp[i] = y[i] + h * k3[i]
    _call_rhs(rhs, t + h, tmp, k4, mesh_out, ints, vals, tables, speed_tab, torque_tab)
    for i in range(n2):
        y[i] += h6 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i])


@njit(cache=True, _nrt=False)
def _short_step_limits(vals, fv0, dt):
    """Longest sub-steps ``h_E, h_M`` [s] taken by the explicit Euler and the midpoint rule
    in a run with faults (header of the fault float block, :func:`short_step_header`)."""
    om = vals[fv0]
    if not om > 0.0:
        return 0.0, 0.0
    z = om * dt
    return vals[fv0 + 1] * z**2.5 / om, vals[fv0 + 2] * z ** (5.0 / 3.0) / om


def integrate_chunk(
    y: np.ndarray,
    first_step: int,
    n_steps: int,
    dt: float,
    system: tuple,
    record: np.ndarray,
    record_offset: int,
    flank_state: np.ndarray,
    contact_changes: np.ndarray,
    count_until: int,
    work: np.ndarray,
    mesh_out: np.ndarray,
    status: np.ndarray,
) -> None:
    """Advance ``y`` by ``n_steps`` classical RK4 steps, recording the state before every step.

    Steps are split at the stiffness jumps; in a run with faults the short sub-steps take
    Euler or midpoint steps (module docstring).

    Parameters
    ----------
    y : ndarray, shape (2 n,)
        State ``[q, qdot]`` at step ``first_step`` (time ``first_step * dt``); updated in place.
    first_step, n_steps : int
        Global index of the first step and number of steps.
    dt : float
        Step [s].
    system : tuple
        :meth:`KernelSystem.astuple`.
    record : ndarray, shape (>= record_offset + n_steps, 2 n + 3 n_mesh)
        Sample ``first_step + i`` goes to row ``record_offset + i`` (layout in the module doc).
    flank_state : ndarray of int64, shape (n_mesh,)
        Contact state of the previous sample (-1: unknown); updated.
    contact_changes : ndarray of int64, shape (n_mesh,)
        Incremented at every change of the contact state up to global step ``count_until``.
    work : ndarray, shape :func:`work_shape`
        Stage buffers; row 5 holds the sub-step times.
    mesh_out : ndarray, shape (n_mesh, MESH_OUT_COLUMNS)
        Scratch for the mesh quantities.
    status : ndarray of int64, shape (2,)
        Set to ``(STATUS_*, global step)``; ``STATUS_OK`` when all steps were done.
    """
    integrate_chunk_compiled(y, first_step, n_steps, dt, with_pass(system), record,
                             record_offset, flank_state, contact_changes, count_until, work,
                             mesh_out, status, rhs_address())


@njit(cache=True)
def integrate_chunk_compiled(y, first_step, n_steps, dt, system, record, record_offset,
                             flank_state, contact_changes, count_until, work, mesh_out,
                             status, rhs):
    """The compiled kernel of :func:`integrate_chunk`, for a system ready for it
    (:func:`with_pass`: a system with faults must hold the address of its faulty-mesh pass
    in ``ints[H_FPASS]``)."""
    ints, vals, tables, speed_tab, torque_tab = system
    n = ints[H_N]
    n_mesh = ints[H_NMESH]
    lim = ints[H_LIMIT]
    speed_limit = vals[ints[H_FPAR] + FP_SPEED_LIMIT]
    k_in = ints[H_IPAR + IP_INPUT]
    k1 = work[0]
    k2 = work[1]
    k3 = work[2]
    k4 = work[3]
    tmp = work[4]
    splits = work[5]
    n2 = 2 * n
    status[0] = STATUS_OK
    status[1] = first_step + n_steps
    h_euler = 0.0
    h_mid = 0.0
    for m in range(n_mesh):
        if ints[ints[H_FREC] + m] >= 0:  # a run with faults: short sub-steps (see above)
            h_euler, h_mid = _short_step_limits(vals, ints[H_FVAL], dt)
            break
    for m in range(n_mesh):
        mesh_out[m, 7] = 1.0  # until the first step decides (their own law is exact anywhere)
        mesh_out[m, 8] = np.nan  # no cached cycle range, no event-free interval
        mesh_out[m, 9] = np.nan
        mesh_out[m, 10] = np.nan
        mesh_out[m, 11] = np.nan
        mesh_out[m, 12] = np.nan
        mesh_out[m, 15] = np.nan
        mesh_out[m, 18] = np.nan
        mesh_out[m, 21] = np.nan
        mesh_out[m, 24] = np.nan
    for step in range(n_steps):
        g = first_step + step
        t = g * dt
        _call_rhs(rhs, t, y, k1, mesh_out, ints, vals, tables, speed_tab, torque_tab)
        row = record_offset + step
        bad = STATUS_OK
        for i in range(n2):
            v = y[i]
            record[row, i] = v
            if not np.isfinite(v):
                bad = STATUS_NONFINITE
        for m in range(n_mesh):
            record[row, n2 + m] = mesh_out[m, 0]
            record[row, n2 + n_mesh + m] = mesh_out[m, 1]
            record[row, n2 + 2 * n_mesh + m] = mesh_out[m, 2]
            st = int(mesh_out[m, 3])
            if flank_state[m] >= 0 and st != flank_state[m] and g <= count_until:
                contact_changes[m] += 1
            flank_state[m] = st
            if bad == STATUS_OK and not (abs(mesh_out[m, 4]) <= vals[lim + m]
                                         and abs(mesh_out[m, 6]) <= vals[lim + m]):
                bad = STATUS_DEFLECTION
        if bad == STATUS_OK and k_in >= 0 and not abs(y[n + k_in]) <= speed_limit:
            bad = STATUS_SPEED
        if bad != STATUS_OK:
            status[0] = bad
            status[1] = g
            return
        n_split = _split_times(y, dt, ints, vals, mesh_out, splits)
        t_a = 0.0
        for j in range(n_split + 1):
            t_b = splits[j] if j < n_split else dt
            if j > 0:
                _call_rhs(rhs, t + t_a, y, k1, mesh_out, ints, vals, tables, speed_tab,
                          torque_tab)
            h = t_b - t_a
            if h <= h_euler:
                for i in range(n2):
                    y[i] += h * k1[i]
            elif h <= h_mid:
                for i in range(n2):
                    tmp[i] = y[i] + 0.5 * h * k1[i]
                _call_rhs(rhs, t + t_a + 0.5 * h, tmp, k2, mesh_out, ints, vals, tables,
                          speed_tab, torque_tab)
                for i in range(n2):
                    y[i] += h * k2[i]
            else:
                _rk4_step(
                    rhs, t + t_a, h, y, k1, k2, k3, k4, tmp, mesh_out,
                    ints, vals, tables, speed_tab, torque_tab,
                )
            t_a = t_b


@njit(cache=True)
def shift_rigid(rows: np.ndarray, first: int, angle: np.ndarray, speed: np.ndarray,
                rigid: np.ndarray, add: bool) -> None:
    """Add (``add``) or subtract the rigid-body motion of recorded rows, in place.

    ``rows[first + i, j] +-= angle[i] * rigid[j]`` and ``rows[first + i, n + j] +-= speed[i]
    * rigid[j]`` for the ``n = rigid.size`` coordinates and their rates: each product rounded,
    then added, as NumPy's ``rows[...] -= angle[:, None] * rigid`` does, without its
    temporary arrays.
    """
    n = rigid.shape[0]
    for i in range(angle.shape[0]):
        r = first + i
        a = angle[i]
        w = speed[i]
        if add:
            for j in range(n):
                rows[r, j] += a * rigid[j]
            for j in range(n):
                rows[r, n + j] += w * rigid[j]
        else:
            for j in range(n):
                rows[r, j] -= a * rigid[j]
            for j in range(n):
                rows[r, n + j] -= w * rigid[j]


@njit(cache=True)
def fir_decimate(
    buf: np.ndarray,
    buf_first: int,
    taps: np.ndarray,
    factor: int,
    first_out: int,
    n_out: int,
    out: np.ndarray,
    out_offset: int,
) -> None:
    """Zero-delay FIR decimation of buffered samples.

    Output sample ``k`` (global index, time ``k * factor * dt``) is
    ``sum_i taps[i] * x[k * factor - L + i]`` with ``L = (len(taps) - 1) // 2``: the symmetric
    filter is centred on the output instant, so no delay remains.

    Parameters
    ----------
    buf : ndarray, shape (rows, n_signal)
        Samples; row ``r`` holds global internal sample ``buf_first + r``.
    buf_first : int
        Global index of row 0.
    taps : ndarray, shape (2 L + 1,)
        Symmetric FIR taps.
    factor : int
        Decimation factor ``D``.
    first_out, n_out : int
        Global index of the first output sample and count.
    out : ndarray, shape (>= out_offset + n_out, n_signal)
        Output rows ``out_offset ...``.
    out_offset : int
        First row of ``out`` to write.

    Notes
    -----
    Every output is summed tap by tap in the order of ``taps`` (``0 + taps[0] x[..] +
    taps[1] x[..] + ...``, each product rounded, no fused multiply-add). With eight or more
    signals (and ``out`` as wide as ``buf``) the sums run on :data:`gearvib.lanes.lanes8`
    vectors of eight signals, four outputs at a time held over the taps (the last vector
    overlaps the one before when the count is not a multiple of eight: its signals are summed
    twice, identically): the same operations per signal, in the same order, as one signal at
    a time. Both arrays must be C-contiguous.
    """
    n_taps = taps.shape[0]
    half = (n_taps - 1) // 2
    n_sig = buf.shape[1]
    if n_sig < WIDTH or out.shape[1] != n_sig:
        for k in range(n_out):
            r0 = (first_out + k) * factor - half - buf_first
            o = out_offset + k
            for c in range(n_sig):
                out[o, c] = 0.0
            for i in range(n_taps):
                tap = taps[i]
                r = r0 + i
                for c in range(n_sig):
                    out[o, c] += tap * buf[r, c]
        return
    zero = lanes_splat(0.0)
    step = factor * n_sig  # from one output's first row to the next output's
    for g in range((n_sig + WIDTH - 1) // WIDTH):
        c0 = min(g * WIDTH, n_sig - WIDTH)  # the last vector may overlap the one before
        k = 0
        while k + 4 <= n_out:  # four outputs at a time, their sums held over the taps
            b0 = ((first_out + k) * factor - half - buf_first) * n_sig + c0
            a0 = zero
            a1 = zero
            a2 = zero
            a3 = zero
            for i in range(n_taps):
                tap = lanes_splat(taps[i])
                b = b0 + i * n_sig
                a0 = lanes_madd(a0, tap, lanes_load(buf, b))
                a1 = lanes_madd(a1, tap, lanes_load(buf, b + step))
                a2 = lanes_madd(a2, tap, lanes_load(buf, b + 2 * step))
                a3 = lanes_madd(a3, tap, lanes_load(buf, b + 3 * step))
            o = (out_offset + k) * n_sig + c0
            lanes_store(out, o, a0)
            lanes_store(out, o + n_sig, a1)
            lanes_store(out, o + 2 * n_sig, a2)
            lanes_store(out, o + 3 * n_sig, a3)
            k += 4
        while k < n_out:
            b0 = ((first_out + k) * factor - half - buf_first) * n_sig + c0
            a0 = zero
            for i in range(n_taps):
                a0 = lanes_madd(a0, lanes_splat(taps[i]), lanes_load(buf, b0 + i * n_sig))
            lanes_store(out, (out_offset + k) * n_sig + c0, a0)
            k += 1


def integrate(
    system: KernelSystem, y0: np.ndarray, dt: float, n_steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate ``n_steps`` RK4 steps from ``y0`` and return every internal sample (allocating).

    A convenience for tests, cross-checks and small studies; :func:`gearvib.simulate.simulate`
    is the production driver (chunks, decimation, blow-up diagnostics).

    Parameters
    ----------
    system : KernelSystem
        Arrays of the system.
    y0 : ndarray, shape (2 n,)
        Initial state ``[q, qdot]`` at ``t = 0``.
    dt : float
        Step [s].
    n_steps : int
        Number of steps; samples ``0 .. n_steps`` are returned.

    Returns
    -------
    record : ndarray, shape (n_steps + 1, 2 n + 3 n_mesh)
        Samples at ``t = i dt`` (layout in the module docstring).
    contact_changes : ndarray of int64, shape (n_mesh,)
        Changes of the flank-contact state per mesh.
    status : ndarray of int64, shape (2,)
        ``(STATUS_*, step)``.
    y : ndarray, shape (2 n,)
        State after the last step.
    """
    n = system.n_dof
    nm = system.n_mesh
    y = np.array(y0, dtype=np.float64)
    record = np.empty((n_steps + 1, n_signals(n, nm)))
    flank_state = np.full(nm, -1, dtype=np.int64)
    changes = np.zeros(nm, dtype=np.int64)
    work = np.empty(work_shape(n, nm))
    mesh_out = np.empty((nm, MESH_OUT_COLUMNS))
    status = np.zeros(2, dtype=np.int64)
    integrate_chunk(
        y,
        0,
        n_steps + 1,
        float(dt),
        system.astuple(),
        record,
        0,
        flank_state,
        changes,
        n_steps,
        work,
        mesh_out,
        status,
    )
    return record, changes, status, y


# The per-variant pieces :mod:`gearvib.kernels_batch` evaluates exactly as here (public names
# of this module's compiled helpers).
insert_split = _insert_split
need_interval = _need_interval  # for tests
speed_at = _speed_at
table_at = _table_at
# ... and the pieces a generated faulty-mesh pass calls (:mod:`gearvib.fault_pass`)
interp_cell = _interp_cell
cos_sin = _cos_sin
mean_offset = _mean_offset
faulty_flanks = _faulty_flanks
stiffness_flanks = _stiffness_flanks


_A1, _A2, _A3 = (types.Array(types.float64, d, "C") for d in (1, 2, 3))
_I1 = types.Array(types.int64, 1, "C")
_F8, _I8 = types.float64, types.int64
_SYSTEM = types.Tuple((_I1, _A1, _A3, _A2, _A2))
#: ``part: (compile, ...)`` for :func:`compile_ahead`: the dispatchers compiled for the argument
#: types a run passes (every array C-contiguous, ``ints`` int64, the others float64; integers
#: int64), and the right-hand side's C function.
_PARTS: dict[str, tuple[Callable[[], object], ...]] = {
    "setup": (partial(speed_profile.compile, (_A2, _A1, _A1, _A1)),
              partial(periodic_interp.compile, (_A2, _I8, _F8))),
    "rhs": (rhs_address,),
    "step_search": (partial(_split_times.compile, (_A1, _F8, _I1, _A1, _A2, _A1)),),
    "kernel": (partial(integrate_chunk_compiled.compile,
                       (_A1, _I8, _I8, _F8, _SYSTEM, _A2, _I8, _I1, _I1, _I8, _A2, _A2, _I1,
                        _I8)),),
    "output": (partial(shift_rigid.compile, (_A2, _I8, _A1, _A1, _A1, types.boolean)),
               partial(fir_decimate.compile, (_A2, _I8, _A1, _I8, _I8, _I8, _A2, _I8))),
}
#: The parts of a run's kernels :func:`compile_ahead` compiles: ``"setup"`` (the speed profile
#: and the table look-up a run calls before its kernel), ``"rhs"`` (the right-hand side,
#: :func:`rhs_address`), ``"step_search"`` (the sub-step search), ``"kernel"`` (the RK4 loop
#: :func:`integrate_chunk_compiled`, which calls the sub-step search and, through its
#: address, the right-hand side) and ``"output"`` (the rigid-body shift and the anti-alias
#: decimation of the recorded rows).
KERNEL_PARTS = tuple(_PARTS)


def compile_ahead(part: str) -> None:
    """Compile a part of a run's kernels now, before the run calls it.

    The first compilation of :func:`integrate_chunk_compiled` takes each function it calls
    from this process when compiled here already, else from numba's cache, and compiles it
    only when neither holds it; it calls the right-hand side through its address, so it
    compiles without it. So two processes can share a first compilation: one compiles the
    right-hand side while the other compiles the sub-step search and the kernel into the
    cache. The machine code is the same either way.

    Parameters
    ----------
    part : str
        One of :data:`KERNEL_PARTS`. A part compiled or cached already is loaded, not
        compiled again.

    Raises
    ------
    ValueError
        ``part`` is not one of :data:`KERNEL_PARTS`.
    """
    if part not in _PARTS:
        raise ValueError(f"part must be one of {', '.join(KERNEL_PARTS)}; got {part!r}")
    for compile_part in _PARTS[part]:
        compile_part()
