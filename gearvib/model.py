"""The assembled, flat description of a gear set that the modal analysis and the kernels use.

:class:`AssembledModel` is the contract between the model layer (``structure``, ``assembly``)
and everything numerical downstream (``modal``, ``kernels``, ``simulate``, stability charts).
It holds only numpy arrays and plain tuples, so the same numba kernel serves every gear-set
topology and a sweep can ship it to worker processes.

Coordinates
-----------
The generalised coordinates ``q`` follow Lin & Parker (1999), extended to large rotations:

* central members (suns, rings) and carriers: translations ``x``, ``y`` [m] in the frame that
  co-rotates with the carrier, optional axial ``z`` [m] (helical meshes), and the absolute
  rotation angle ``theta`` [rad];
* planets: radial ``zeta`` and tangential ``eta`` [m] displacement of the planet centre
  (``eta`` is absolute, so a rigid carrier rotation by ``theta_c`` moves it by ``a theta_c``),
  optional axial ``z`` [m], and the absolute rotation ``theta`` [rad].

A rigid bearing or a fixed member removes its DOF. Arrays that act on ``q`` have the
``(n_dof,)`` or ``(n_dof, n_dof)`` layout; time histories have the layout ``(n_time, n_dof)``.

Mesh conventions
----------------
For mesh ``m`` the normal deflection along the left flank's line of action is
``delta_m = mesh_vectors[m] @ q`` [m], along the right (back) flank's ``delta_R,m =
back_vectors[m] @ q`` (the mirror-image line of action: the same rotations, other in-plane
translations; :mod:`gearvib.assembly`). Flank ``left`` is loaded when ``delta_m > j_m / 2`` and
carries ``F_L = k_left(s) (delta - j/2)``; flank ``right`` is loaded when ``delta_R,m <
-j_m / 2`` and carries ``F_R = k_right(s) (delta_R + j/2)`` (negative). A negative backlash
loads both flanks at once. The generalised force of the mesh on ``q`` is ``-F_L
mesh_vectors[m] - F_R back_vectors[m]`` (damping included in the flank forces). The left flank
is the one that carries the load when the central gear drives the planet forward; which flank
carries the mean load of a gear set is :meth:`AssembledModel.loaded_flanks`, and
:meth:`AssembledModel.mesh_contacts` gives the flanks in contact as linear springs (the mean
system of the modal analysis, the drive coupling, the step choice and the stability analysis).

The mesh position ``s_m`` in mesh cycles is ``mesh_position_vectors[m] @ q +
mesh_position_offsets[m]``; ``s = 0`` (mod 1) is the instant a new tooth pair enters contact.
Stiffness tables hold ``k(s)`` at ``s = i / n_table`` and are interpolated linearly and
periodically.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from gearvib.checks import check_real

MESH_FREQUENCY_RTOL = 1e-9
"""Relative tolerance within which two meshes share one mesh frequency."""

FLANK_LEFT = 1
"""Loaded-flank code: the left (drive) flank."""
FLANK_RIGHT = 2
"""Loaded-flank code: the right (back) flank."""
FLANK_BOTH = 3
"""Loaded-flank code: both flanks (negative backlash, preloaded mesh)."""
FLANK_NAMES = {FLANK_LEFT: "left", FLANK_RIGHT: "right", FLANK_BOTH: "both"}
"""Names of the loaded-flank codes."""
_UNLOADED_RTOL = 1e-9
"""A mesh whose static deflection is below this fraction of the largest one is unloaded."""


@dataclass(frozen=True)
class MeshContacts:
    """The flanks in contact of every mesh at a mean load, as linear springs.

    One *contact* per loaded flank. A mesh loaded on both flanks whose two lines of action
    coincide (rigid in-plane bearings) is one contact with the summed stiffness ``k_L + k_R``
    and twice the mesh damping, as the run-up simulation sees it; with distinct lines of action
    it is two contacts.

    Attributes
    ----------
    flanks : ndarray of int, shape (n_mesh,)
        Loaded flank of every mesh: :data:`FLANK_LEFT`, :data:`FLANK_RIGHT` or
        :data:`FLANK_BOTH`.
    mesh : ndarray of int, shape (n_contact,)
        Mesh index of every contact.
    flank : tuple of str
        ``"left"``, ``"right"`` or ``"both"`` (two flanks on one line of action) per contact.
    vectors : ndarray, shape (n_contact, n)
        Deflection vector of every contact (the line of action of its flank).
    tables : ndarray, shape (n_contact, n_table)
        Stiffness over one mesh cycle [N/m].
    peak : ndarray, shape (n_contact,)
        Largest stiffness of every contact [N/m] (two flanks on one line: the sum of both
        flanks' largest values).
    damping : ndarray, shape (n_contact,)
        Viscous damping [N s/m] (the mesh damping once per flank in contact under the gated
        law; once per mesh under the viscous law, on the left contact of a preloaded mesh).
    torque_sign : float
        Sense of the mean load they belong to (+1: the input drives forward).
    """

    flanks: np.ndarray
    mesh: np.ndarray
    flank: tuple[str, ...]
    vectors: np.ndarray
    tables: np.ndarray
    peak: np.ndarray
    damping: np.ndarray
    torque_sign: float = 1.0

    @property
    def n_contact(self) -> int:
        """Number of contacts."""
        return int(self.mesh.size)

    def mean_stiffness(self) -> np.ndarray:
        """Cycle-mean stiffness of every contact [N/m]."""
        return self.tables.mean(axis=1)

    def stiffness_matrix(self, k: np.ndarray | None = None) -> np.ndarray:
        """``sum_c k_c u_c u_c^T`` over the contacts (the cycle means by default)."""
        kk = self.mean_stiffness() if k is None else np.asarray(k, dtype=float)
        v = self.vectors
        return (v.T * kk) @ v

    def damping_matrix(self) -> np.ndarray:
        """``sum_c c_c u_c u_c^T`` over the contacts."""
        v = self.vectors
        return (v.T * self.damping) @ v

    def stiffness_at(self, positions: np.ndarray) -> np.ndarray:
        """Stiffness of every contact at the mesh positions of its mesh [N/m].

        Parameters
        ----------
        positions : ndarray, shape (..., n_contact)
            Mesh position of every contact's mesh [cycles] (``s[..., contacts.mesh]``).
        """
        return interpolate_tables(self.tables, positions)

    def per_mesh(self, values: np.ndarray) -> np.ndarray:
        """Sum per-contact values (last axis) over the contacts of every mesh."""
        v = np.asarray(values)
        out = np.zeros((*v.shape[:-1], self.flanks.size), dtype=v.dtype)
        for c, m in enumerate(self.mesh):
            out[..., m] += v[..., c]
        return out


def interpolate_tables(tables: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Periodic linear interpolation of row ``m`` of ``tables`` at ``positions[..., m]``.

    Parameters
    ----------
    tables : numpy.ndarray
        One periodic table per row, shape ``(n_rows, n_table)``, sampled at positions
        ``0, 1/n_table, ...`` of its period.
    positions : numpy.ndarray
        Positions in periods, last axis one per row.
    """
    n_table = tables.shape[1]
    s = np.asarray(positions, dtype=float)
    u = (s - np.floor(s)) * n_table
    i0 = np.floor(u).astype(np.int64) % n_table
    i1 = (i0 + 1) % n_table
    w = u - np.floor(u)
    m = np.arange(tables.shape[0])
    return (1.0 - w) * tables[m, i0] + w * tables[m, i1]


@dataclass(frozen=True)
class MeshFrequencyGroup:
    """Meshes that share one mesh frequency (one stage, one planet toothing).

    Attributes
    ----------
    name : str
        Display name, e.g. ``"stage 2"`` or ``"ring2"``.
    frequency_per_rpm : float
        Mesh frequency per input speed [Hz per min^-1].
    meshes : tuple of int
        Indices of the meshes in the model.
    mesh_names : tuple of str
        Their names.
    """

    name: str
    frequency_per_rpm: float
    meshes: tuple[int, ...]
    mesh_names: tuple[str, ...]

    @property
    def order(self) -> float:
        """Mesh order: mesh cycles per input revolution (``60 x frequency_per_rpm``)."""
        return 60.0 * self.frequency_per_rpm


@dataclass(frozen=True)
class AssembledModel:
    """Flat arrays of one gear set (see the module docstring for conventions).

    Attributes
    ----------
    dof_names : tuple of str
        One name per coordinate, ``"<body>.<x|y|z|theta|zeta|eta>"``.
    dof_units : tuple of str
        ``"m"`` or ``"rad"`` per coordinate.
    mass : ndarray, shape (n, n)
        Mass matrix ``M`` [kg, kg m^2].
    stiffness : ndarray, shape (n, n)
        Constant stiffness: bearings, supports and shaft couplings, meshes excluded.
    damping : ndarray, shape (n, n)
        Constant damping of bearings, supports and couplings, meshes excluded.
    gyroscopic : ndarray, shape (n, n)
        ``G``; the carrier-rotation force is ``-Omega_c G qdot`` [Omega_c in rad/s].
    centripetal : ndarray, shape (n, n)
        ``K_Omega``; the centripetal force is ``+Omega_c**2 K_Omega q``.
    mesh_names : tuple of str
        E.g. ``"sun-planet1"``, ``"ring-planet1"``.
    mesh_vectors : ndarray, shape (n_mesh, n)
        Normal mesh deflection along the left (drive) flank's line of action per unit
        coordinate.
    mesh_position_vectors : ndarray, shape (n_mesh, n)
        Mesh cycles per unit coordinate (only rotations contribute).
    mesh_position_offsets : ndarray, shape (n_mesh,)
        Mesh position at ``q = 0`` [cycles]; carries the phase of every contact.
    mesh_stiffness_tables : ndarray, shape (n_mesh, n_table)
        Left (drive) flank stiffness [N/m] over one mesh cycle.
    mesh_back_tables : ndarray, shape (n_mesh, n_table)
        Right (back) flank stiffness [N/m] over one mesh cycle.
    mesh_backlash : ndarray, shape (n_mesh,)
        Total normal backlash ``j`` [m]; negative means both flanks in contact.
    mesh_damping : ndarray, shape (n_mesh,)
        Viscous mesh damping [N s/m]: under the gated law (default) acting only while a flank
        is in contact, under the viscous law always (:attr:`mesh_damping_laws`).
    bearing_names : tuple of str
        One per elastic bearing direction, e.g. ``"planet1.radial"``, ``"sun.x"``.
    bearing_vectors : ndarray, shape (n_bearing, n)
        Bearing deflection per unit coordinate.
    bearing_stiffness, bearing_damping : ndarray, shape (n_bearing,)
        Per bearing direction [N/m or N m/rad; N s/m or N m s/rad].
    rotation_dofs : dict of str to int
        Rotation-coordinate index of every member (``-1`` for a fixed member).
    carrier_dof : int
        Index of the carrier rotation used for the gyroscopic terms (``-1`` if fixed/none).
    input_member, output_member, fixed_members : str, str, tuple of str
        Operating roles from the gear-set description.
    kinematic_ratios : dict of str to float
        Speed of every member per unit input speed (rigid-body kinematics).
    mesh_frequencies_per_rpm : ndarray, shape (n_mesh,)
        Mesh frequency of every mesh [Hz] per input speed [min^-1], ``|z_1 (n_1 - n_c)| / 60``
        per unit input speed (paper eq. 5 for a simple set); NaN for a mesh without tooth
        numbers (lumped, constant stiffness). A two-stage or Wolfrom set has several distinct
        values: see :meth:`mesh_frequency_groups`; :attr:`mesh_frequency_per_rpm` is the
        single value of a one-frequency set.
    meta : dict
        Free-form description (gear-set name, configuration) for provenance.
    mesh_back_vectors : ndarray, shape (n_mesh, n), optional
        Deflection along the right (back) flank's line of action, the mirror image of the left
        one (:mod:`gearvib.assembly`); None when it equals :attr:`mesh_vectors` (no in-plane
        translation of a meshing gear is a coordinate). Use :attr:`back_vectors`.
    mesh_teeth : ndarray of int64, shape (n_mesh, 4), optional
        Tooth map (:mod:`gearvib.teeth`): pair-counter sign and tooth in pair 0 of gear1 and
        gear2; which teeth are in contact follows from the mesh position. None for a model not
        built by :func:`gearvib.assembly.assemble` (then local tooth faults cannot be placed).
    faults : tuple of Fault
        Local tooth faults and manufacturing errors (:mod:`gearvib.faults`); the arrays above
        describe the healthy gear set (except the backlash, which a planet-specific backlash
        error changes), and the run applies the faults. Empty: a healthy set.
    sensors : tuple
        Virtual sensors on the housing and the tacho (:mod:`gearvib.sensors`), computed by a run.
    mesh_damping_laws : tuple of str
        ``"gated"`` or ``"viscous"`` per mesh (:class:`gearvib.structure.Mesh`); empty: every
        mesh gated. Use :attr:`viscous_meshes`.
    """

    dof_names: tuple[str, ...]
    dof_units: tuple[str, ...]
    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    gyroscopic: np.ndarray
    centripetal: np.ndarray
    mesh_names: tuple[str, ...]
    mesh_vectors: np.ndarray
    mesh_position_vectors: np.ndarray
    mesh_position_offsets: np.ndarray
    mesh_stiffness_tables: np.ndarray
    mesh_back_tables: np.ndarray
    mesh_backlash: np.ndarray
    mesh_damping: np.ndarray
    bearing_names: tuple[str, ...]
    bearing_vectors: np.ndarray
    bearing_stiffness: np.ndarray
    bearing_damping: np.ndarray
    rotation_dofs: dict[str, int]
    carrier_dof: int
    input_member: str
    output_member: str
    fixed_members: tuple[str, ...]
    kinematic_ratios: dict[str, float]
    mesh_frequencies_per_rpm: np.ndarray
    meta: dict = field(default_factory=dict)
    mesh_back_vectors: np.ndarray | None = None
    mesh_teeth: np.ndarray | None = None
    faults: tuple = ()
    sensors: tuple = ()
    mesh_damping_laws: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "faults", tuple(self.faults))
        object.__setattr__(self, "sensors", tuple(self.sensors))
        laws = tuple(self.mesh_damping_laws)
        if laws and (len(laws) != len(self.mesh_names)
                     or any(law not in ("gated", "viscous") for law in laws)):
            raise ValueError(f"mesh_damping_laws must be empty or hold 'gated' or 'viscous' "
                             f"for each of the {len(self.mesh_names)} meshes")
        object.__setattr__(self, "mesh_damping_laws", laws)
        if self.mesh_back_vectors is not None:
            back = np.ascontiguousarray(self.mesh_back_vectors, dtype=float)
            if back.shape != np.shape(self.mesh_vectors):
                raise ValueError(
                    f"mesh_back_vectors has shape {back.shape}, mesh_vectors "
                    f"{np.shape(self.mesh_vectors)}; give one back-flank vector per mesh (or "
                    "None: the same lines of action)"
                )
            object.__setattr__(self, "mesh_back_vectors", back)
        object.__setattr__(self, "_contacts_cache", {})
        f = np.asarray(self.mesh_frequencies_per_rpm, dtype=float).reshape(-1)
        if f.size != len(self.mesh_names):
            raise ValueError(
                f"mesh_frequencies_per_rpm has {f.size} values for {len(self.mesh_names)} "
                "meshes; give one per mesh (NaN for a mesh without tooth numbers)"
            )
        if np.any(f[np.isfinite(f)] < 0) or np.any(np.isinf(f)):
            raise ValueError("mesh_frequencies_per_rpm must be finite and >= 0 (or NaN)")
        object.__setattr__(self, "mesh_frequencies_per_rpm", f)

    def with_faults(self, faults) -> AssembledModel:
        """This model with local tooth faults and manufacturing errors added.

        Parameters
        ----------
        faults : sequence of Fault or dict
            Descriptions (:mod:`gearvib.faults`) or ``[[fault]]`` tables; they are added to
            the model's own and checked against it (members, teeth, meshes). A planet-specific
            backlash changes :attr:`mesh_backlash`; every other fault is applied by the run.

        Raises
        ------
        gearvib.faults.FaultError
            Naming the fault and what is not admissible.
        """
        from gearvib.faults.apply import add_faults  # the fault layer builds on this module

        return add_faults(self, faults)

    def with_sensors(self, sensors) -> AssembledModel:
        """This model with virtual sensors (accelerometers on the housing, a tacho) added.

        Parameters
        ----------
        sensors : sequence of HousingSensor, Tacho or dict
            Descriptions (:mod:`gearvib.sensors`) or ``[[sensor]]`` tables, checked against
            the model.
        """
        from gearvib.sensors.apply import add_sensors

        return add_sensors(self, sensors)

    @property
    def mesh_frequency_per_rpm(self) -> float:
        """The mesh frequency per input speed of a single-frequency set [Hz per min^-1].

        Every simple planetary set (and a Ravigneaux set: its meshes all share the planets'
        carrier and tooth cycle) has one mesh frequency. NaN when no mesh has tooth numbers.

        Raises
        ------
        ValueError
            When the meshes have several distinct frequencies (two-stage, Wolfrom sets); use
            :attr:`mesh_frequencies_per_rpm` or :meth:`mesh_frequency_groups` there.
        """
        groups = self.mesh_frequency_groups()
        if not groups:
            return math.nan
        if len(groups) > 1:
            listed = ", ".join(f"{g.name} {g.frequency_per_rpm:.6g}" for g in groups)
            raise ValueError(
                f"the gear set has {len(groups)} mesh frequencies ({listed} Hz per min^-1); "
                "use model.mesh_frequencies_per_rpm (per mesh) or model.mesh_frequency_groups()"
            )
        return groups[0].frequency_per_rpm

    def mesh_frequency_groups(self, rtol: float = MESH_FREQUENCY_RTOL
                              ) -> tuple[MeshFrequencyGroup, ...]:
        """The distinct mesh frequencies and the meshes that share each one.

        Meshes whose frequencies per speed agree within ``rtol`` form one group; groups are in
        the order of their first mesh (for a two-stage set: stage 1, then stage 2). Meshes
        without tooth numbers (NaN) belong to no group. A group is named after the stage
        prefix its meshes share (``"s1.sun-planet1"``, ``"stage1.pinion-wheel"`` ... ->
        ``"stage 1"``), else after its
        central gears (``"sun, ring1"``, ``"ring2"``), else numbered (``"f_mesh,2"``).

        Returns
        -------
        tuple of MeshFrequencyGroup
        """
        f = self.mesh_frequencies_per_rpm
        members: list[list[int]] = []
        for m in range(f.size):
            if not np.isfinite(f[m]) or f[m] == 0.0:
                continue
            for g in members:
                if abs(f[m] - f[g[0]]) <= rtol * max(f[m], f[g[0]]):
                    g.append(m)
                    break
            else:
                members.append([m])
        names = _group_names(self, members)
        return tuple(
            MeshFrequencyGroup(name=names[i], frequency_per_rpm=float(np.mean(f[g])),
                               meshes=tuple(g),
                               mesh_names=tuple(self.mesh_names[m] for m in g))
            for i, g in enumerate(members)
        )

    def mesh_position_rates_per_rpm(self) -> np.ndarray:
        """Signed rate of every mesh position per input speed [mesh cycles/s per min^-1].

        ``w_m . r`` with ``r`` the rigid-body rotation rates of the members
        (:attr:`kinematic_ratios`) at 1 min^-1: the rate at which a steady rotation advances the
        mesh position, i.e. the direction in which the stiffness table is traversed. Its
        magnitude equals :attr:`mesh_frequencies_per_rpm` for a mesh with tooth numbers.
        """
        r = np.zeros(self.n_dof)
        for member, dof in self.rotation_dofs.items():
            if dof >= 0:
                r[dof] = float(self.kinematic_ratios.get(member, 0.0))
        return np.asarray(self.mesh_position_vectors, dtype=float) @ r * (2.0 * math.pi / 60.0)

    @property
    def n_dof(self) -> int:
        """Number of coordinates."""
        return len(self.dof_names)

    @property
    def n_mesh(self) -> int:
        """Number of tooth contacts (meshes)."""
        return len(self.mesh_names)

    @property
    def back_vectors(self) -> np.ndarray:
        """Back-flank deflection vectors, shape (n_mesh, n) (:attr:`mesh_back_vectors`, or
        :attr:`mesh_vectors` when the lines of action coincide)."""
        return self.mesh_vectors if self.mesh_back_vectors is None else self.mesh_back_vectors

    @property
    def viscous_meshes(self) -> np.ndarray:
        """True for every mesh under the always-on (viscous) damping law, shape (n_mesh,)."""
        return np.array([law == "viscous" for law in self.mesh_damping_laws]
                        or [False] * self.n_mesh, dtype=bool)

    def distinct_back_lines(self) -> np.ndarray:
        """True for every mesh whose back-flank line of action differs from the left one's."""
        if self.mesh_back_vectors is None:
            return np.zeros(self.n_mesh, dtype=bool)
        return np.any(self.mesh_back_vectors != self.mesh_vectors, axis=1)

    def mean_mesh_stiffness(self) -> np.ndarray:
        """Mean left-flank stiffness of every mesh over one cycle [N/m]."""
        return self.mesh_stiffness_tables.mean(axis=1)

    def nominal_load(self, torque_sign: float = 1.0) -> np.ndarray:
        """Generalised force of a unit input torque in steady operation, shape (n,).

        ``torque_sign`` N m at the input member and the lossless load at the output member
        that balances it (``-torque_sign r_in / r_out``, ``r`` the kinematic ratios), or,
        without a rotating output, the d'Alembert force of the rigid-body acceleration it
        causes. A model without a rigid-body motion (every member held by a support) gets the
        input torque alone.
        """
        sign = _torque_sign(torque_sign)
        f = np.zeros(self.n_dof)
        k_in = self.rotation_dofs.get(self.input_member, -1)
        if k_in < 0:
            raise ValueError(f"input member {self.input_member!r} has no rotation coordinate")
        f[k_in] = sign
        try:
            r = self.rigid_body_velocity()
        except ValueError:  # held by supports: no rigid-body motion to balance
            return f
        k_out = self.rotation_dofs.get(self.output_member, -1)
        r_out = r[k_out] if k_out >= 0 and k_out != k_in else 0.0
        if r_out != 0.0:
            f[k_out] -= sign * r[k_in] / r_out
        else:
            mr = np.asarray(self.mass, dtype=float) @ r
            f -= mr * (float(r @ f) / float(r @ mr))
        return f

    def loaded_flanks(self, torque_sign: float = 1.0) -> np.ndarray:
        """Flank of every mesh that carries the mean load [:data:`FLANK_LEFT`, ...].

        Both flanks for a negative backlash (preloaded mesh); otherwise the flank in contact at
        the static equilibrium under :meth:`nominal_load` with the cycle-mean flank stiffness
        and no backlash (the flank follows from the statics, not from the size of the load; a
        mesh that carries no load counts as left-loaded). The active set is iterated until the
        sign of every loaded flank's deflection agrees with its flank.

        Parameters
        ----------
        torque_sign : float
            +1: the input drives forward (traction); -1: the load torque reversed (coast).

        Returns
        -------
        ndarray of int, shape (n_mesh,)
        """
        return self.mesh_contacts(torque_sign).flanks.copy()

    def mesh_contacts(self, torque_sign: float = 1.0) -> MeshContacts:
        """The flanks in contact at the mean load as linear springs (cached per sign).

        The mean system of a gear set is ``K + contacts.stiffness_matrix()``: left flanks on
        the left lines of action, right flanks on the back lines, both for a negative backlash
        (see :class:`MeshContacts` and :meth:`loaded_flanks`). Modal analysis, the natural
        frequencies of a run, the default drive coupling, the step choice and the stability
        analysis all use it.
        """
        sign = _torque_sign(torque_sign)
        cache = self.__dict__["_contacts_cache"]
        if sign not in cache:
            cache[sign] = self._contacts(self._static_flanks(sign), sign)
        return cache[sign]

    def _contacts(self, flanks: np.ndarray, sign: float) -> MeshContacts:
        """Build the :class:`MeshContacts` of the given loaded flanks."""
        left_t, back_t = self.mesh_stiffness_tables, self.mesh_back_tables
        if np.all(flanks == FLANK_LEFT):  # the model's own arrays: results bit for bit as ever
            return MeshContacts(flanks, np.arange(self.n_mesh), ("left",) * self.n_mesh,
                                self.mesh_vectors, left_t, left_t.max(axis=1),
                                np.asarray(self.mesh_damping, dtype=float), sign)
        distinct = self.distinct_back_lines()
        vl, vr = self.mesh_vectors, self.back_vectors
        mesh, names, rows, tables, peak, damp = [], [], [], [], [], []

        def add(m, name, row, table, top, c):
            mesh.append(m)
            names.append(name)
            rows.append(row)
            tables.append(table)
            peak.append(top)
            damp.append(c)

        viscous = self.viscous_meshes
        for m, fl in enumerate(flanks):
            c = float(self.mesh_damping[m])
            # gated: each flank in contact damps; viscous: one damper, on the left line
            # unless only the back flank is loaded (gearvib.kernels.flank_forces_viscous)
            c_back = 0.0 if viscous[m] and fl == FLANK_BOTH else c
            if fl == FLANK_BOTH and not distinct[m]:
                add(m, "both", vl[m], left_t[m] + back_t[m], left_t[m].max() + back_t[m].max(),
                    c + c_back)
                continue
            if fl & FLANK_LEFT:
                add(m, "left", vl[m], left_t[m], left_t[m].max(), c)
            if fl & FLANK_RIGHT:
                add(m, "right", vr[m], back_t[m], back_t[m].max(), c_back)
        return MeshContacts(flanks, np.array(mesh, dtype=np.int64), tuple(names),
                            np.ascontiguousarray(np.array(rows).reshape(len(rows), self.n_dof)),
                            np.ascontiguousarray(np.array(tables).reshape(len(rows), -1)),
                            np.array(peak, dtype=float), np.array(damp, dtype=float), sign)

    def _static_flanks(self, sign: float) -> np.ndarray:
        """Loaded flanks of the static equilibrium under :meth:`nominal_load` (see
        :meth:`loaded_flanks`)."""
        both = np.asarray(self.mesh_backlash) < 0
        flanks = np.where(both, FLANK_BOTH, FLANK_LEFT).astype(np.int64)
        if both.all() or self.n_mesh == 0:
            return flanks
        f = self.nominal_load(sign)
        k_in = self.rotation_dofs[self.input_member]
        keep = np.ones(self.n_dof, dtype=bool)
        try:
            self.rigid_body_velocity()
            keep[k_in] = False  # pin the input (ratio 1): removes the rigid-body motion
        except ValueError:  # held by supports: no rigid-body motion
            pass
        vl, vr = self.mesh_vectors, self.back_vectors
        seen: set[bytes] = set()
        for _ in range(4 * self.n_mesh + 4):
            contacts = self._contacts(flanks, sign)
            k = self.stiffness + contacts.stiffness_matrix()
            q = np.zeros(self.n_dof)
            kk = k[np.ix_(keep, keep)]
            try:
                q[keep] = np.linalg.solve(kk, f[keep])
            except np.linalg.LinAlgError:
                q[keep] = np.linalg.lstsq(kk, f[keep], rcond=None)[0]
            dl, dr = vl @ q, vr @ q
            tiny = _UNLOADED_RTOL * max(np.abs(dl).max(), np.abs(dr).max(), 1e-300)
            new = flanks.copy()
            new[~both & (flanks == FLANK_LEFT) & (dl < -tiny)] = FLANK_RIGHT
            new[~both & (flanks == FLANK_RIGHT) & (dr > tiny)] = FLANK_LEFT
            if np.array_equal(new, flanks) or new.tobytes() in seen:
                return flanks
            seen.add(flanks.tobytes())
            flanks = new
        return flanks

    def mesh_stiffness_matrix(self, k: np.ndarray | None = None) -> np.ndarray:
        """Stiffness matrix of the meshes, ``sum_m k_m v_m v_m^T``.

        Parameters
        ----------
        k : ndarray, shape (n_mesh,), optional
            Mesh stiffness values [N/m]; the cycle means by default.
        """
        kk = self.mean_mesh_stiffness() if k is None else np.asarray(k, dtype=float)
        v = self.mesh_vectors
        return (v.T * kk) @ v

    def mean_stiffness_matrix(self, torque_sign: float = 1.0) -> np.ndarray:
        """Mean-system stiffness: constant part plus the mean stiffness of the flanks in
        contact at the mean load (:meth:`mesh_contacts`)."""
        return self.stiffness + self.mesh_contacts(torque_sign).stiffness_matrix()

    def rigid_body_velocity(self) -> np.ndarray:
        """Coordinate velocities per unit input speed (rigid-body kinematics).

        Rotations come from ``self.kinematic_ratios``; the other coordinates (e.g. the absolute
        tangential planet coordinate, which moves with the carrier) are solved so that the mean
        stiffness does no work, ``K r = 0``.

        Returns
        -------
        ndarray, shape (n,)
            ``r`` with ``qdot = r * Omega_in``.

        Raises
        ------
        ValueError
            If the kinematic ratios do not describe a rigid-body motion of the model (the
            message names members held by torsional supports to ground).
        """
        n = self.n_dof
        r = np.zeros(n)
        known = np.zeros(n, dtype=bool)
        for member, dof in self.rotation_dofs.items():
            if dof >= 0:
                if member not in self.kinematic_ratios:
                    raise ValueError(f"no kinematic ratio for member {member!r}")
                r[dof] = float(self.kinematic_ratios[member])
                known[dof] = True
        # the kinematics do not depend on the flanks (a rigid motion strains neither line of
        # action): the left-flank matrix, which also keeps loaded_flanks free of recursion
        k = self.stiffness + self.mesh_stiffness_matrix()
        free = ~known
        if free.any():
            kff = k[np.ix_(free, free)]
            rhs = -k[np.ix_(free, known)] @ r[known]
            r[free] = np.linalg.lstsq(kff, rhs, rcond=None)[0]
        scale = np.abs(k).max() * np.abs(r).max() + 1e-300
        resisted = np.abs(k @ r) > 1e-8 * scale
        if resisted.any():
            members = sorted(m for m, d in self.rotation_dofs.items()
                             if d >= 0 and resisted[d] and r[d] != 0.0)
            raise ValueError(
                "the kinematic motion of the model is resisted "
                f"(max |K r| = {np.abs(k @ r).max():.3g}): "
                + (f"members {members} turn in it but are held by torsional supports to ground "
                   "(drive and load stiffness of a modal model); a run needs them free: remove "
                   "those supports, or join motor and load by [[coupling]]"
                   if members else "the meshes or bearings are strained by it; check the "
                   "assembly")
            )
        return r

    def carrier_frame_operators(self) -> tuple[np.ndarray, np.ndarray]:
        """Gyroscopic and centripetal matrices acting on the motion relative to the carrier.

        ``G`` and ``K_Omega`` describe the Coriolis and centripetal forces of motion measured in
        the rotating carrier frame. The coordinates here are absolute (the tangential planet
        coordinate moves with the carrier, ``eta = a theta_c`` in a steady rotation), so the
        matrices are applied to ``P q`` with ``P = I - r e_c^T / r_c`` (``r`` the rigid-body
        velocity, ``c`` the carrier coordinate): the steady rotation itself then produces no
        force, and the terms act on the motion relative to the carrier. A model whose carrier
        does not rotate, has no carrier coordinate or no rigid-body rotation at all gets the
        matrices unchanged (its coordinates describe the vibration about the nominal rotation,
        as in Lin & Parker 1999).

        The frame follows the carrier's actual angle (it stays valid in run-ups and torque-driven
        runs), so the steady centrifugal load on the planet bearings is not included. For modes
        with carrier rotation the frequencies differ from the constant-rate frame of Lin &
        Parker, which :func:`gearvib.modal.modal_analysis` uses, by a second-order amount (at
        most 0.1 % at 3000 min^-1 carrier speed on ``paper-case1-elastic``).

        Returns
        -------
        gyroscopic, centripetal : ndarray, shape (n, n)
            ``G P`` and ``K_Omega P``.
        """
        c = self.carrier_dof
        g = np.asarray(self.gyroscopic, dtype=float)
        k_omega = np.asarray(self.centripetal, dtype=float)
        if c < 0 or not (np.any(g) or np.any(k_omega)):
            return g.copy(), k_omega.copy()
        try:
            r = self.rigid_body_velocity()
        except ValueError:  # no rigid-body rotation (e.g. every member held by a spring):
            return g.copy(), k_omega.copy()  # the coordinates are vibrations already
        if r[c] == 0.0:
            return g.copy(), k_omega.copy()
        p = np.eye(self.n_dof) - np.outer(r, np.eye(self.n_dof)[c]) / r[c]
        return g @ p, k_omega @ p

    def mesh_damping_matrix(self) -> np.ndarray:
        """Damping matrix of the meshes with every flank in contact."""
        v = self.mesh_vectors
        return (v.T * self.mesh_damping) @ v

    def mesh_stiffness_at(self, positions: np.ndarray, back: bool = False) -> np.ndarray:
        """Interpolate the stiffness tables at mesh positions.

        Parameters
        ----------
        positions : ndarray, shape (..., n_mesh)
            Mesh positions [cycles].
        back : bool
            Use the back-flank tables.

        Returns
        -------
        ndarray, shape (..., n_mesh)
            Stiffness [N/m], periodic linear interpolation.
        """
        tables = self.mesh_back_tables if back else self.mesh_stiffness_tables
        return interpolate_tables(tables, positions)


def _torque_sign(value: float) -> float:
    """+1.0 or -1.0 from a nonzero finite sign argument."""
    v = check_real(value, "torque_sign")
    if v == 0.0:
        raise ValueError(f"torque_sign = {value!r} is not admissible (admissible: +1 or -1)")
    return 1.0 if v > 0 else -1.0


def _group_names(model: AssembledModel, members: list[list[int]]) -> list[str]:
    """Display names of mesh-frequency groups (see :meth:`AssembledModel.mesh_frequency_groups`)."""
    if len(members) <= 1:
        return ["mesh"] * len(members)

    def prefix(g: list[int]) -> str:
        heads = {model.mesh_names[m].split(".", 1)[0] for m in g
                 if "." in model.mesh_names[m]}
        if len(heads) != 1 or any("." not in model.mesh_names[m] for m in g):
            return ""
        head = heads.pop()
        hit = re.fullmatch(r"s(?:tage)?(\d+)", head)
        return f"stage {hit.group(1)}" if hit else head

    gear1 = {d.get("name"): d.get("gear1") for d in model.meta.get("meshes", [])
             if isinstance(d, dict)}

    def centrals(g: list[int]) -> str:
        seen: list[str] = []
        for m in g:
            c = gear1.get(model.mesh_names[m])
            if c and c not in seen:
                seen.append(c)
        return ", ".join(seen)

    for rule in (prefix, centrals):
        names = [rule(g) for g in members]
        if all(names) and len(set(names)) == len(names):
            return names
    return [f"f_mesh,{i + 1}" for i in range(len(members))]
