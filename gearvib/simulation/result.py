"""The result of a run-up simulation and its CF-annotated Dataset."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from gearvib import __version__
from gearvib import kernels as kn
from gearvib.cfdata import PlainDataset, PlainVariable, time_attrs
from gearvib.checks import check_array, check_config, check_frequencies, check_instance, check_real
from gearvib.model import AssembledModel
from gearvib.phases import mesh_phase_table
from gearvib.simulation.conditions import (
    RAD_S_PER_RPM,
    Conditions,
    DriveCoupling,
    MotorDriven,
    SpeedRamp,
    SpeedTable,
    TorqueDriven,
)
from gearvib.simulation.frequencies import elastic_frequencies, undamped_frequencies
from gearvib.simulation.run_setup import RunSetup
from gearvib.simulation.step import StepChoice

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["INTEGRATOR", "RunUpResult", "build_result", "model_sha256"]

INTEGRATOR = "classical Runge-Kutta 4, fixed step, sub-steps ending at stiffness jumps"


def model_sha256(model: AssembledModel) -> str:
    """SHA-256 of every array and name of the model (provenance of a run)."""
    check_instance(model, AssembledModel, "model")
    h = hashlib.sha256()
    for name in (
        "mass",
        "stiffness",
        "damping",
        "gyroscopic",
        "centripetal",
        "mesh_vectors",
        "mesh_position_vectors",
        "mesh_position_offsets",
        "mesh_stiffness_tables",
        "mesh_back_tables",
        "mesh_backlash",
        "mesh_damping",
        "bearing_vectors",
        "bearing_stiffness",
        "bearing_damping",
    ):
        a = np.ascontiguousarray(getattr(model, name), dtype=np.float64)
        h.update(name.encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    if model.mesh_back_vectors is not None:  # distinct back-flank lines of action
        a = np.ascontiguousarray(model.mesh_back_vectors, dtype=np.float64)
        h.update(b"mesh_back_vectors")
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    if "viscous" in model.mesh_damping_laws:  # the damping laws (all gated: as before)
        h.update(b"mesh_damping_laws")
        h.update(json.dumps(list(model.mesh_damping_laws)).encode())
    if model.faults:  # local tooth faults and manufacturing errors (healthy: as before)
        h.update(b"faults")
        h.update(json.dumps([f.to_dict() for f in model.faults], sort_keys=True).encode())
    names = [
        model.dof_names,
        model.mesh_names,
        model.bearing_names,
        sorted(model.rotation_dofs.items()),
        model.input_member,
        model.output_member,
    ]
    h.update(json.dumps(names, default=str).encode())
    return h.hexdigest()


def _jsonable(obj: object) -> object:
    """Round-trip through JSON (tuples -> lists, numpy scalars -> numbers, others -> str)."""

    def default(o: object) -> object:
        if isinstance(o, np.ndarray):
            return o.tolist()
        if isinstance(o, np.generic):
            return o.item()
        return str(o)

    return json.loads(json.dumps(obj, default=default, sort_keys=True))


@dataclass
class RunUpResult:
    """Output of :func:`simulate`, sampled at ``fs_out`` (arrays are ``(channel, time)``).

    Attributes
    ----------
    time : ndarray, shape (n_time,)
        [s], ``k / fs_out``.
    mesh_names, bearing_names, members, translation_dofs : tuple of str
        Labels of the ``mesh``, ``bearing``, ``member`` and ``translation_dof`` dimensions.
    normal_force : ndarray, shape (n_mesh, 2, n_time)
        Compressive force on the left and right flank [N] (>= 0).
    mesh_stiffness : ndarray, shape (n_mesh, n_time)
        Effective mesh stiffness [N/m]: 0 in the backlash, sum of both flanks in double contact.
    mesh_deflection : ndarray, shape (n_mesh, n_time)
        ``v_m . q`` [m] (dynamic transmission error along the line of action).
    bearing_force : ndarray, shape (n_bearing, n_time)
        ``k_b (u_b . q) + c_b (u_b . qdot)`` [N or N m].
    displacement : ndarray, shape (n_translation, n_time)
        Translational coordinates [m].
    rotation, speed : ndarray, shape (n_member, n_time)
        Absolute rotation [rad] and speed [min^-1] of every rotating member.
    input_speed, input_angle : ndarray, shape (n_time,)
        Prescribed input speed [min^-1] and angle [rad] (speed-driven), or the simulated ones of
        the input member (torque-driven).
    drive_torque : ndarray, shape (n_time,)
        Torque applied to the input member by the coupling, the torque table or the motor
        characteristic at the input speed [N m].
    mesh_frequency : ndarray, shape (n_mesh, n_time)
        Mesh frequency of every mesh, ``|mesh_frequencies_per_rpm[m] * input_speed|`` [Hz]
        (NaN for a mesh without tooth numbers). Stages and planet toothings have their own.
    natural_frequencies : ndarray, shape (n_mode,)
        Elastic natural frequencies of the mean system [Hz].
    flank_contact_changes : ndarray of int64, shape (n_mesh,)
        Changes of the set of flanks in contact per mesh (internal steps up to the end).
    step : StepChoice
        Internal step, output rate and the frequencies they were chosen from.
    fir_numtaps : int
        Length of the decimation filter.
    config_json : str
        Full configuration, JSON with sorted keys.
    drive : str
        ``"speed"``, ``"torque"`` or ``"motor"``.
    gyroscopic : bool
        Gyroscopic/centripetal terms included.
    coupling : DriveCoupling or None
        Drive coupling of a speed-driven run.
    title : str
        Dataset title.
    wall_time : float
        Wall time of the call [s] (not stored in the dataset, which is deterministic).
    sensor_names : tuple of str
        Virtual housing sensors (:mod:`gearvib.sensors`), labels of the ``sensor`` dimension.
    sensor_acceleration : ndarray, shape (n_sensor, n_time), optional
        Their accelerations [m s-2].
    sensor_info : tuple of dict
        Their descriptions (angle, window, housing response).
    tacho : ndarray, shape (n_time,), optional
        Tacho pulse train of a shaft [V].
    tacho_info : dict, optional
        The tacho's description (member, pulses per revolution, level).
    mesh_phases_json : str
        The mesh phases of the model (:func:`gearvib.phases.mesh_phase_table`) as JSON, the
        run attribute ``mesh_phases_json`` (read back by :func:`gearvib.phases.run_mesh_phases`).
    """

    time: np.ndarray
    mesh_names: tuple[str, ...]
    bearing_names: tuple[str, ...]
    members: tuple[str, ...]
    translation_dofs: tuple[str, ...]
    normal_force: np.ndarray
    mesh_stiffness: np.ndarray
    mesh_deflection: np.ndarray
    bearing_force: np.ndarray
    displacement: np.ndarray
    rotation: np.ndarray
    speed: np.ndarray
    input_speed: np.ndarray
    input_angle: np.ndarray
    drive_torque: np.ndarray
    mesh_frequency: np.ndarray
    natural_frequencies: np.ndarray
    flank_contact_changes: np.ndarray
    step: StepChoice
    fir_numtaps: int
    config_json: str
    drive: str
    gyroscopic: bool
    coupling: DriveCoupling | None = None
    title: str = "gearvib run-up simulation"
    wall_time: float = field(default=0.0, compare=False)
    sensor_names: tuple[str, ...] = ()
    sensor_acceleration: np.ndarray | None = None
    sensor_info: tuple[dict, ...] = ()
    tacho: np.ndarray | None = None
    tacho_info: dict | None = None
    mesh_phases_json: str = ""

    @property
    def config_sha256(self) -> str:
        """SHA-256 of ``config_json``."""
        return hashlib.sha256(self.config_json.encode()).hexdigest()

    def to_dataset(self) -> xr.Dataset:
        """CF-1.11 annotated dataset (float64 data, netCDF-safe attributes).

        ``time`` holds float seconds since the start of the run, as a CF time coordinate
        (``units = "seconds since 1970-01-01T00:00:00Z"``, ``standard_name``, ``axis``; the
        epoch is a conventional origin, see :mod:`analysis.cf`).
        """
        return self.to_plain_dataset().to_xarray()

    def to_plain_dataset(self) -> PlainDataset:
        """The content of :meth:`to_dataset` as NumPy arrays, without importing xarray.

        :func:`gearvib.io.write_netcdf` writes it as the same file as the Dataset.
        """

        def var(
            dims: tuple[str, ...], data: np.ndarray, units: str, long_name: str, quantity: str
        ) -> PlainVariable:
            return PlainVariable(
                dims,
                np.ascontiguousarray(data),
                {"units": units, "long_name": long_name, "gearvib_quantity": quantity},
            )

        t = ("time",)
        coords = {
            "time": PlainVariable(
                t,
                np.ascontiguousarray(self.time),
                {**time_attrs("time since start of run"), "gearvib_quantity": "time"},
            ),
            "mesh": PlainVariable(
                ("mesh",),
                np.array(self.mesh_names, dtype=str),
                {"long_name": "tooth contact (mesh)"},
            ),
            "flank": PlainVariable(
                ("flank",),
                np.array(["left", "right"]),
                {"long_name": "tooth flank (left: loaded when the central gear drives the planet)"},
            ),
            "bearing": PlainVariable(
                ("bearing",),
                np.array(self.bearing_names, dtype=str),
                {"long_name": "elastic bearing direction"},
            ),
            "member": PlainVariable(
                ("member",), np.array(self.members, dtype=str), {"long_name": "rotating member"}
            ),
            "translation_dof": PlainVariable(
                ("translation_dof",),
                np.array(self.translation_dofs, dtype=str),
                {"long_name": "translational coordinate"},
            ),
            "mode": var(
                ("mode",),
                np.arange(1, self.natural_frequencies.size + 1, dtype=np.int64),
                "1",
                "elastic mode number of the mean system",
                "mode",
            ),
            "input_speed": var(
                t, self.input_speed, "min-1", "input speed (revolutions per minute)", "input_speed"
            ),
            "input_angle": var(t, self.input_angle, "rad", "input rotation angle", "input_angle"),
            "mesh_frequency": var(
                ("mesh", "time"),
                np.atleast_2d(self.mesh_frequency).reshape(len(self.mesh_names), -1),
                "Hz",
                "tooth-mesh frequency of the mesh at the input speed",
                "mesh_frequency",
            ),
        }
        data = {
            "normal_force": var(
                ("mesh", "flank", "time"),
                self.normal_force,
                "N",
                "normal tooth force on the flank (compressive)",
                "tooth_force",
            ),
            "mesh_stiffness": var(
                ("mesh", "time"),
                self.mesh_stiffness,
                "N m-1",
                "effective mesh stiffness (0 in the backlash)",
                "mesh_stiffness",
            ),
            "mesh_deflection": var(
                ("mesh", "time"),
                self.mesh_deflection,
                "m",
                "mesh deflection along the line of action (dynamic transmission error)",
                "mesh_deflection",
            ),
            "bearing_force": var(
                ("bearing", "time"),
                self.bearing_force,
                "N",
                "bearing force (N m for torsional supports)",
                "bearing_force",
            ),
            "displacement": var(
                ("translation_dof", "time"),
                self.displacement,
                "m",
                "translational displacement",
                "displacement",
            ),
            "rotation": var(
                ("member", "time"), self.rotation, "rad", "absolute rotation angle", "rotation"
            ),
            "speed": var(
                ("member", "time"),
                self.speed,
                "min-1",
                "rotational speed (revolutions per minute)",
                "speed",
            ),
            "drive_torque": var(
                t, self.drive_torque, "N m", "torque applied to the input member", "drive_torque"
            ),
            "natural_frequency": var(
                ("mode",),
                self.natural_frequencies,
                "Hz",
                "natural frequency of the mean system",
                "natural_frequency",
            ),
            "flank_contact_changes": var(
                ("mesh",),
                self.flank_contact_changes.astype(np.int64),
                "1",
                "number of flank-contact changes",
                "flank_contact_changes",
            ),
        }
        if self.sensor_acceleration is not None:
            coords["sensor"] = PlainVariable(("sensor",), np.array(self.sensor_names, dtype=str),
                                           {"long_name": "virtual sensor on the housing"})
            coords["sensor_angle"] = var(
                ("sensor",), np.array([i["angle_deg"] for i in self.sensor_info], dtype=float),
                "degree", "sensor position on the housing (counter-clockwise from x)",
                "sensor_angle")
            acc = var(("sensor", "time"), self.sensor_acceleration, "m s-2",
                      "housing acceleration at the virtual sensor", "virtual_sensor")
            acc.attrs["transmission_path"] = json.dumps(list(self.sensor_info), sort_keys=True)
            data["sensor_acceleration"] = acc
        if self.tacho is not None:
            info = dict(self.tacho_info or {})
            tacho = var(t, self.tacho, "V", f"tacho pulse train of the {info.get('member')} "
                        f"shaft, {info.get('pulses_per_rev')} pulses per revolution", "tacho")
            tacho.attrs.update({"pulses_per_rev": int(info.get("pulses_per_rev", 1)),
                                "member": str(info.get("member")),
                                "duty": float(info.get("duty", 0.5))})
            data["tacho"] = tacho
        attrs = {
            "Conventions": "CF-1.11",
            "title": self.title,
            "history": f"run-up simulated by gearvib {__version__} (gearvib.simulate)",
            "source": f"gearvib {__version__}",
            "gearvib_version": __version__,
            "integrator": INTEGRATOR,
            "dt": float(self.step.dt),
            "fs_out": float(self.step.fs_out),
            "decimation_factor": int(self.step.decimation),
            "fir_numtaps": int(self.fir_numtaps),
            "anti_alias_filter": "Kaiser-window FIR, -6 dB at 0.4 fs_out, >= 80 dB from 0.5 fs_out,"
            " zero phase (centred)",
            "highest_natural_frequency": float(self.step.highest_natural_frequency),
            "highest_mesh_frequency": float(self.step.highest_mesh_frequency),
            "drive": self.drive,
            "gyroscopic": np.int8(self.gyroscopic),
            "config_json": self.config_json,
            "config_sha256": self.config_sha256,
        }
        if self.mesh_phases_json:
            attrs["mesh_phases_json"] = self.mesh_phases_json
        if self.coupling is not None:
            attrs["drive_coupling_stiffness"] = float(self.coupling.stiffness)
            attrs["drive_coupling_damping"] = float(self.coupling.damping)
            if self.coupling.sensing != "input":  # (input couplings' files as before)
                attrs["drive_coupling_sensing"] = self.coupling.sensing
        return PlainDataset(data, coords, attrs)


def _conditions_dict(conditions: Conditions) -> dict:
    """The fields of the conditions, a drive coupling as :meth:`DriveCoupling.to_dict` gives
    it (an input coupling's text as before the sensing existed)."""
    out = asdict(conditions)
    coupling = getattr(conditions, "coupling", None)
    if coupling is not None:
        out["coupling"] = coupling.to_dict()
    return out


def build_result(
    model: AssembledModel,
    conditions: Conditions,
    setup: RunSetup,
    step: StepChoice,
    taps: np.ndarray,
    out: np.ndarray,
    changes: np.ndarray,
    duration: float,
    gyroscopic: bool,
    config: Mapping | str | None,
    natural_frequencies: Sequence[float] | np.ndarray | None,
    wall: float,
) -> RunUpResult:
    """Turn the decimated state history of a run into a :class:`RunUpResult`.

    ``out`` holds the decimated sample rows of the kernels (layout in :mod:`gearvib.kernels`);
    forces, deflections, bearing forces and speeds are derived from them here.
    """
    check_instance(model, AssembledModel, "model")
    check_instance(conditions, (SpeedRamp, SpeedTable, TorqueDriven, MotorDriven), "conditions")
    check_instance(setup, RunSetup, "setup")
    check_instance(step, StepChoice, "step")
    n, nm = model.n_dof, model.n_mesh
    taps = check_array(taps, "taps", ndim=1)
    out = check_array(out, "out", ndim=2, max_abs=1e100)
    if out.shape[1] != kn.n_signals(n, nm) or out.shape[0] < 1:
        raise ValueError(f"out must have {kn.n_signals(n, nm)} columns (the kernel signals of "
                         f"the model) and rows; got shape {out.shape}")
    changes = check_array(changes, "changes", ndim=1, min_size=0, max_abs=2.0**62)
    if changes.size != nm or np.any(changes < 0) or np.any(changes != np.round(changes)):
        raise ValueError(f"changes must hold {nm} counts >= 0 (one per mesh)")
    duration = check_real(duration, "duration [s]", low=0.0, low_open=True)
    if not isinstance(gyroscopic, bool | np.bool_):
        raise TypeError(f"gyroscopic must be a bool; got {type(gyroscopic).__name__}")
    config = check_config(config)
    natural_frequencies = check_frequencies(natural_frequencies)
    wall = check_real(wall, "wall [s]", low=0.0)
    system = setup.system
    n_out = out.shape[0]
    time = np.arange(n_out) * (step.decimation * step.dt)
    q = out[:, :n]
    qd = out[:, n : 2 * n]
    f_left = out[:, 2 * n : 2 * n + nm].T
    f_right = out[:, 2 * n + nm : 2 * n + 2 * nm].T
    # gated law: a flank never pulls, values below 0 are filter ringing (clipped); the viscous
    # law's forces carry the damping force, which may pull (kept)
    gated = ~model.viscous_meshes[:, None]
    f_left = np.where(gated, np.clip(f_left, 0.0, None), f_left)
    f_right = np.where(gated, np.clip(f_right, 0.0, None), f_right)
    k_eff = np.clip(out[:, 2 * n + 2 * nm :].T, 0.0, None)
    normal_force = np.ascontiguousarray(np.stack([f_left, f_right], axis=1))
    deflection = system.mesh_vectors @ q.T
    bv = np.asarray(model.bearing_vectors, dtype=float).reshape(len(model.bearing_names), n)
    bearing = np.asarray(model.bearing_stiffness)[:, None] * (bv @ q.T) + np.asarray(
        model.bearing_damping
    )[:, None] * (bv @ qd.T)
    if setup.faults is not None and np.any(setup.faults.bearing_offsets):
        bearing -= setup.faults.bearing_offsets[:, None]  # displaced planet pins
    trans = [i for i, u in enumerate(model.dof_units) if u == "m"]
    rot = sorted((d, name) for name, d in model.rotation_dofs.items() if d >= 0)
    members = tuple(name for _, name in rot)
    rot_idx = [d for d, _ in rot]
    k_in = int(system.ipar[kn.IP_INPUT])
    if setup.drive == "speed":
        angle = np.empty(n_out)
        w = np.empty(n_out)
        kn.speed_profile(system.speed_table, time, angle, w)
        if system.drive_sensing is None:  # a coupling on the input member
            theta, rate = q[:, k_in], qd[:, k_in]
        else:  # a controller on the rigid-body coordinate
            theta, rate = q @ system.drive_sensing, qd @ system.drive_sensing
        drive_torque = system.fpar[kn.FP_KC] * (angle - theta) + system.fpar[kn.FP_CC] * (
            w - rate
        )
        input_speed = w / RAD_S_PER_RPM
    else:
        angle = q[:, k_in].copy()
        input_speed = qd[:, k_in] / RAD_S_PER_RPM
        at = time if setup.drive == "torque" else qd[:, k_in]  # motor: its characteristic
        drive_torque = np.interp(at, system.torque_table[0], system.torque_table[1])
    if natural_frequencies is None:
        k_mean = model.mean_stiffness_matrix(setup.torque_sign)  # the loaded flanks
        nat = elastic_frequencies(undamped_frequencies(model.mass, k_mean), model.mass, k_mean)
    else:
        nat = np.asarray(natural_frequencies, dtype=float)
    if isinstance(config, str):
        cfg_model: object = json.loads(config)
    elif config is not None:
        cfg_model = dict(config)
    else:
        cfg_model = {"meta": model.meta}
    cfg = {
        "gearvib_version": __version__,
        "model": cfg_model,
        "model_sha256": model_sha256(model),
        "conditions": {"type": type(conditions).__name__, **_conditions_dict(conditions)},
        "simulation": {
            "dt": step.dt,
            "fs_out": step.fs_out,
            "decimation_factor": step.decimation,
            "duration": duration,
            "gyroscopic": bool(gyroscopic),
            "integrator": INTEGRATOR,
            "drive_coupling": None if setup.coupling is None else setup.coupling.to_dict(),
            "load_torque": list(setup.load),
        },
    }
    if model.faults:  # only then: healthy runs keep their configuration text bit for bit
        cfg["faults"] = [f.to_dict() for f in model.faults]
    if model.sensors:
        cfg["sensors"] = [sn.to_dict() for sn in model.sensors]
    config_json = json.dumps(_jsonable(cfg), sort_keys=True)
    name = model.meta.get("name") if isinstance(model.meta, Mapping) else None
    return RunUpResult(
        time=time,
        mesh_names=tuple(model.mesh_names),
        bearing_names=tuple(model.bearing_names),
        members=members,
        translation_dofs=tuple(model.dof_names[i] for i in trans),
        normal_force=normal_force,
        mesh_stiffness=np.ascontiguousarray(k_eff),
        mesh_deflection=np.ascontiguousarray(deflection),
        bearing_force=np.ascontiguousarray(bearing),
        displacement=np.ascontiguousarray(q[:, trans].T),
        rotation=np.ascontiguousarray(q[:, rot_idx].T),
        speed=np.ascontiguousarray(qd[:, rot_idx].T / RAD_S_PER_RPM),
        input_speed=input_speed,
        input_angle=angle,
        drive_torque=drive_torque,
        mesh_frequency=np.abs(np.outer(model.mesh_frequencies_per_rpm, input_speed)),
        natural_frequencies=nat,
        flank_contact_changes=changes.copy(),
        step=step,
        fir_numtaps=int(taps.size),
        config_json=config_json,
        drive=setup.drive,
        gyroscopic=bool(gyroscopic),
        coupling=setup.coupling,
        title=f"gearvib run-up simulation of {name}" if name else "gearvib run-up simulation",
        wall_time=wall,
        mesh_phases_json=json.dumps(mesh_phase_table(model)),
    )
