"""Admissible baseline calls of every public callable of gearvib's Python API, for the fuzz
suite :mod:`tests.gearvib.test_fuzz_python_api`.

:func:`public_callables` lists the API a scripting user sees: every function and class named
in the ``__all__`` of a module of the API reference (``docs/api/index.rst``; a package without
``__all__``, such as :mod:`gearvib.simulation`, stands for the ``__all__`` of its modules),
counted once where it is defined; exception classes are left out. :data:`BASELINES` holds an
admissible call of each (``(args, kwargs)``, built lazily, small: a paper-case1 run of 2 ms,
reports of a 20 ms run); :data:`NOT_FUZZED` names the classes that are not called by users
(result records gearvib builds, abstract bases), with the reason. A public callable in
neither fails the coverage test.
"""

from __future__ import annotations

import copy
import functools
import importlib
import inspect
import math
import pkgutil
import re
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from tests.fuzz_guard import lazy_call

REPO = Path(__file__).resolve().parents[2]
A = tuple[tuple, dict]


def api_modules() -> list[str]:
    """The gearvib modules of the API reference, in its order."""
    text = (REPO / "docs" / "api" / "index.rst").read_text()
    return re.findall(r"^\s+(gearvib\.[\w.]+)\s*$", text, re.M)


def public_callables() -> dict[str, Callable]:
    """``{"module.qualname": callable}`` of every public function and class (module
    docstring), keyed where it is defined."""
    out: dict[str, Callable] = {}
    for name in api_modules():
        mod = importlib.import_module(name)
        if hasattr(mod, "__all__"):
            members = [getattr(mod, n) for n in mod.__all__]
        else:  # a package that documents its modules: their __all__
            members = []
            for info in pkgutil.iter_modules(getattr(mod, "__path__", []), name + "."):
                sub = importlib.import_module(info.name)
                members += [getattr(sub, n) for n in getattr(sub, "__all__", ())]
        for obj in members:
            if inspect.isclass(obj) and issubclass(obj, BaseException):
                continue
            if inspect.isfunction(obj) or inspect.isclass(obj):
                out.setdefault(f"{obj.__module__}.{obj.__qualname__}", obj)
    return out


# ------------------------------------------------------------------------------------------
# small admissible inputs, built once
# ------------------------------------------------------------------------------------------


@functools.cache
def tmp() -> Path:
    return Path(tempfile.mkdtemp(prefix="gearvib-api-fuzz-"))


@functools.cache
def cfg() -> dict:
    from gearvib.config import load_config

    return load_config("paper-case1")[0]


def cfg_copy() -> dict:
    return copy.deepcopy(cfg())


@functools.cache
def gs() -> Any:
    from gearvib.config import gearset_from_dict

    return gearset_from_dict(cfg_copy())


@functools.cache
def model() -> Any:
    from gearvib.assembly import assemble

    return assemble(gs())


@functools.cache
def modal() -> Any:
    from gearvib.modal import modal_analysis

    return modal_analysis(model())


def ramp() -> Any:
    from gearvib.simulate import SpeedRamp

    return SpeedRamp(1000.0, 1000.0, 0.002, input_torque=60.0)


@functools.cache
def run() -> Any:
    from gearvib.simulate import simulate

    return simulate(model(), ramp(), max_steps=20_000, config=cfg())


@functools.cache
def run_ds() -> xr.Dataset:
    return run().to_dataset()


@functools.cache
def report_ds() -> xr.Dataset:
    """A 40 ms run at 1000 -> 1400 min-1, long enough for the reports' maps at 400 Hz."""
    from gearvib.simulate import SpeedRamp, simulate

    r = simulate(model(), SpeedRamp(1000.0, 1400.0, 0.04, input_torque=60.0),
                 max_steps=200_000, config=cfg(), fs_out=10_000.0)
    return r.to_dataset()


def analysis_settings() -> Any:
    from gearvib.report import AnalysisSettings

    return AnalysisSettings(stability="off", map_resolution_hz=400.0, n_max=2)


@functools.cache
def files() -> dict[str, Path]:
    """Small valid files: a run, a report run, a study, a sweep, a description."""
    from gearvib.io import write_netcdf

    d = tmp()
    out = {"run": d / "run.nc", "report_run": d / "report_run.nc"}
    write_netcdf(run_ds(), out["run"])
    write_netcdf(report_ds(), out["report_run"])
    out["toml"] = d / "set.toml"
    out["toml"].write_text((REPO / "gearvib" / "presets" / "paper-case1.toml").read_text())
    out["study"] = d / "study.toml"
    out["study"].write_text(
        '[study]\ntitle = "fuzz"\ncases = [{ name = "c1", config = "paper-case1" }]\n'
        "[run]\nspeed_start_rpm = 1000.0\nspeed_end_rpm = 1400.0\nduration = 0.04\n"
        'fs_out = 10000.0\n[analysis]\nstability = "off"\nmap_resolution_hz = 400.0\n')
    out["sweep"] = d / "sweep.toml"
    out["sweep"].write_text(
        'base = "paper-case1"\n[simulation]\nspeed_start_rpm = 1000.0\nspeed_end_rpm = 1000.0\n'
        'duration = 0.002\n[[parameter]]\npath = "meshes.sun.damping_ratio"\n'
        "values = [0.005]\n")
    out["text"] = d / "notes.txt"
    out["text"].write_text("not a run\n")
    return out


def _f(key: str) -> Callable[[], Path]:
    return lambda: files()[key]


def toothing(z: int = 33) -> Any:
    from gearvib.geometry import Toothing

    return Toothing(z, 2.5e-3)


@functools.cache
def planetary_geometry() -> tuple:
    from gearvib.geometry import Toothing, planetary_meshes

    sun, ring, planet = Toothing(33, 2.5e-3), Toothing(-114, 2.5e-3), Toothing(40, 2.5e-3,
                                                                              profile_shift=0.2)
    return (sun, ring, planet, *planetary_meshes(sun, ring, planet))


def sun_mesh_geometry() -> Any:
    return planetary_geometry()[3]


def ring_mesh_geometry() -> Any:
    return planetary_geometry()[4]


def body(name: str = "sun", role: str = "central", **kw: Any) -> Any:
    from gearvib.structure import Body, Support

    if role == "planet":
        kw.setdefault("carrier", "carrier")
    return Body(name, role, 1.0, 1e-3, Support(), **kw)


def mesh_spec() -> Any:
    from gearvib.stiffness import ConstantStiffness
    from gearvib.structure import MeshSpec

    return MeshSpec(ConstantStiffness(3e8))


def constant_k() -> Any:
    from gearvib.stiffness import ConstantStiffness

    return ConstantStiffness(3e8)


def lumped_mesh() -> Any:
    from gearvib.structure import Mesh

    return Mesh("sun-planet", "sun", "planet", constant_k(), base_radius1=0.04,
                base_radius2=0.05, pressure_angle=0.35, z1=33, z2=40)


def simple_set() -> Any:
    from gearvib.structure import simple_planetary

    return simple_planetary(z_sun=33, z_ring=-114, z_planet=40, module=2.5e-3, sun=body("sun"),
                            ring=body("ring"), carrier=body("carrier", "carrier"),
                            planet=body("planet", "planet"), sun_mesh=mesh_spec(),
                            ring_mesh=mesh_spec(), n_planets=3)


def pair_set() -> Any:
    from gearvib.stages import parallel_stage

    return parallel_stage(z_pinion=20, z_wheel=50, module=3e-3, pinion=body("pinion"),
                          wheel=body("wheel"), mesh=mesh_spec(),
                          housing=body("housing", "carrier"))


@functools.cache
def base_structure() -> Any:
    from gearvib.structure import BaseStructure, Body, Support

    sun = Body("sun", "central", 1.0, 1e-3, Support())
    planet = Body("planet", "planet", 0.5, 2e-4, Support(), carrier="carrier")
    car = Body("carrier", "carrier", 3.0, 2e-2, Support())
    return BaseStructure(sun, planet, car, lumped_mesh())


@functools.cache
def setup() -> Any:
    from gearvib.simulate import prepare_run

    return prepare_run(model(), ramp(), False)


def step_choice() -> Any:
    from gearvib.simulate import choose_step

    return choose_step(2000.0, 1700.0)


@functools.cache
def catalogue() -> Any:
    from gearvib.catalogue import gear_set_catalogue

    return gear_set_catalogue(gs(), speed_rpm=1000.0, model=model())


@functools.cache
def bearing_measurement() -> Any:
    """A 1 s record at 8192 Hz of a shaft at 1800 min-1 with outer-race impacts."""
    from analysis.measurement import load_measurement

    fs, n = 8192.0, 8192
    t = np.arange(n) / fs
    rng = np.random.default_rng(3)
    x = 0.05 * rng.standard_normal(n)
    for t0 in np.arange(0.0, 1.0, 1.0 / 107.4):
        k = int(t0 * fs)
        m = min(n - k, 80)
        x[k:k + m] += np.exp(-np.arange(m) / 10.0) * np.sin(2 * np.pi * 3000.0 * np.arange(m)
                                                                / fs)
    ds = xr.Dataset(
        {"acc": ("time", x, {"units": "m s-2", "long_name": "acceleration"}),
         "speed": ("time", np.full(n, 1800.0), {"units": "min-1", "long_name": "shaft speed"})},
        coords={"time": ("time", t, {"units": "s", "long_name": "time"})})
    return load_measurement(ds, speed="speed")


@functools.cache
def rig_catalogue() -> Any:
    from gearvib.config import load_description

    return load_description("cwru-drive-end").catalogue(speed_rpm=1800.0)


def rig_families() -> list:
    from gearvib.fault_lines import catalogue_families

    return catalogue_families(rig_catalogue())


@functools.cache
def fault_lines() -> Any:
    from gearvib.fault_lines import check_fault_lines

    return check_fault_lines(bearing_measurement(), rig_families(), order_spectrum=False)


@functools.cache
def case_analysis() -> Any:
    from gearvib.report import analyse_case

    return analyse_case(report_ds(), name="c1", settings=analysis_settings())


def study() -> Any:
    from gearvib.report import Case, RunSettings, Study

    return Study("fuzz", (Case("c1", "paper-case1"),),
                 RunSettings(1000.0, 1400.0, 0.04, 60.0, 10_000.0), analysis_settings())


SWEEP = {"base": "paper-case1",
         "simulation": {"speed_start_rpm": 1000.0, "speed_end_rpm": 1000.0, "duration": 0.002},
         "parameter": [{"path": "meshes.sun.damping_ratio", "values": [0.005]}],
         "summary": {"orders": [1.0]}}


def sweep_dict() -> dict:
    return copy.deepcopy(SWEEP)


@functools.cache
def sweep() -> Any:
    from gearvib.sweep import sweep_from_dict

    return sweep_from_dict(sweep_dict())


def case_task() -> Any:
    from gearvib.sweep import CaseTask

    s = sweep()
    return CaseTask(s.cases()[0], str(tmp() / "case.nc"), s.summary, write_run=False)


def record() -> Any:
    from gearvib.diagnosis import Record

    rng = np.random.default_rng(0)
    return Record(rng.standard_normal(4096), 4096.0, np.full(4096, 1500.0))


def fault(kind: str = "crack") -> Any:
    from gearvib.faults import fault_from_dict

    tables = {"crack": {"kind": "crack", "member": "sun", "tooth": 3, "severity": 0.3},
              "pin": {"kind": "pin_error", "member": "planet1", "tangential": 1e-5}}
    return fault_from_dict(tables[kind])


def sensor() -> Any:
    from gearvib.sensors import HousingMode, HousingSensor

    return HousingSensor("acc", 90.0, housing_modes=(HousingMode(2000.0, 0.05, 1.0),))


def tacho() -> Any:
    from gearvib.sensors import Tacho

    return Tacho()


@functools.cache
def sensed_model() -> Any:
    from gearvib.sensors import add_sensors

    return add_sensors(model(), [sensor()])


@functools.cache
def sensed_run() -> Any:
    from gearvib.simulate import simulate

    return simulate(sensed_model(), ramp(), max_steps=20_000)


def pool() -> Any:
    from gearvib.execution import SerialExecutor

    return SerialExecutor()


# ------------------------------------------------------------------------------------------
# one admissible call per callable: name -> () -> (args, kwargs)
# ------------------------------------------------------------------------------------------


_c = lazy_call  # a baseline whose callable arguments are built when it is


def _literal(value: Any) -> Callable[[], Any]:
    """A callable argument passed as is (``_c`` evaluates callables)."""
    return lambda: value


def _model_for(value: float) -> Any:
    return model()


def _writer(path: Path) -> None:
    path.write_text("x")


def _pieces(name: str) -> Callable[[], Any]:
    """Arguments of :func:`gearvib.teeth.mesh_tooth_map` as :func:`assemble` builds them."""

    def build() -> Any:
        from gearvib.assembly import resolve_mesh

        g = gs()
        meta = {p["name"]: p["radius"] for p in model().meta["planets"]}
        centre = {b.name: np.zeros(2) for b in g.bodies}
        for b in g.planets:
            centre[b.name] = meta[b.name] * np.array([math.cos(b.angle), math.sin(b.angle)])
        return {"meshes": g.meshes, "bodies": {b.name: b for b in g.bodies},
                "resolved": {m.name: resolve_mesh(m) for m in g.meshes},
                "s0": model().mesh_position_offsets, "centre": centre}[name]

    return build


def _build_result_args() -> A:
    from gearvib.simulate import choose_step, decimation_filter

    s = setup()
    step = choose_step(2000.0, 1700.0)
    n, nm = model().n_dof, model().n_mesh
    from gearvib import kernels

    nsig = kernels.n_signals(n, nm)
    return (model(), ramp(), s, step, decimation_filter(step.decimation), np.zeros((5, nsig)),
            np.zeros(nm, dtype=np.int64), 4.0 / step.fs_out, False, None, None, 0.1), {}


def _equilibrium_args() -> A:
    s = setup()
    return (s.system, s.mass, s.rigid, s.rigid * s.omega0), {"free_rigid": s.free_rigid}


def _stiffness_mass() -> tuple:
    from gearvib.simulation.frequencies import stiffest_matrix

    s = setup()
    return s.mass, stiffest_matrix(model())


BASELINES: dict[str, Callable[[], A]] = {
    # structure
    "gearvib.structure.BaseStructure": _c(lambda: body("sun"),
                                          lambda: body("planet", "planet", carrier="carrier"),
                                          lambda: body("carrier", "carrier"), lumped_mesh),
    "gearvib.structure.Body": _c("sun", "central", 1.6, 1.7e-3),
    "gearvib.structure.Coupling": _c("sun", "carrier", 1e6, 10.0),
    "gearvib.structure.GearSet": _c("pair", lambda: pair_set().bodies,
                                    lambda: pair_set().meshes, ("housing",), "pinion", "wheel"),
    "gearvib.structure.Mesh": _c("sun-planet", "sun", "planet", constant_k, base_radius1=0.04,
                                 base_radius2=0.05, pressure_angle=0.35, z1=33, z2=40),
    "gearvib.structure.MeshSpec": _c(constant_k),
    "gearvib.structure.Support": _c(1e8, 1e8, 1e8, 0.0, 10.0, 10.0, 10.0, 0.0),
    "gearvib.structure.check_damping_law": _c("gated", "damping_law"),
    "gearvib.structure.check_ravigneaux_clearances": _c(
        3, a_short=0.05, a_long=0.06, offset=0.7, tip_short=0.02, tip_long=0.026,
        tip_ring=0.084, tip_sun_small=0.032),
    "gearvib.structure.check_ravigneaux_pairs": _c(30, 36, -84, 3),
    "gearvib.structure.check_stepped_planet_angles": _c(
        18, -69, 27, 24, lambda: [0.0, 2 * math.pi / 3, 4 * math.pi / 3]),
    "gearvib.structure.compose": _c("composed", lambda: [base_structure()],
                                    fixed=["carrier"], input="sun", output="planet"),
    "gearvib.structure.prefixed": _c(simple_set, "s1_"),
    "gearvib.structure.ravigneaux": _c(
        z_sun_small=30, z_sun_large=36, z_ring=-84, z_planet_short=18, z_planet_long=24,
        module=2e-3, sun_small=lambda: body("sun_small"), sun_large=lambda: body("sun_large"),
        ring=lambda: body("ring"), carrier=lambda: body("carrier", "carrier"),
        planet_short=lambda: body("short", "planet"), planet_long=lambda: body("long", "planet"),
        sun_mesh=mesh_spec, ring_mesh=mesh_spec, planet_mesh=mesh_spec),
    "gearvib.structure.simple_planetary": _c(
        z_sun=33, z_ring=-114, z_planet=40, module=2.5e-3, sun=lambda: body("sun"),
        ring=lambda: body("ring"), carrier=lambda: body("carrier", "carrier"),
        planet=lambda: body("planet", "planet"), sun_mesh=mesh_spec, ring_mesh=mesh_spec,
        n_planets=3),
    "gearvib.structure.two_stage": _c(simple_set, simple_set),
    "gearvib.structure.wolfrom": _c(
        z_sun=18, z_ring1=-72, z_ring2=-69, z_planet1=27, z_planet2=24, module=2e-3,
        module2=2e-3 * 45 / 45, sun=lambda: body("sun"), ring1=lambda: body("ring1"),
        ring2=lambda: body("ring2"), carrier=lambda: body("carrier", "carrier"),
        planet=lambda: body("planet", "planet"), sun_mesh=mesh_spec, ring_mesh=mesh_spec),
    # stages
    "gearvib.stages.multi_stage": _c(lambda: [pair_set(), pair_set()],
                                     shafts=[(1e6, 1.0)]),
    "gearvib.stages.parallel_stage": _c(z_pinion=20, z_wheel=50, module=3e-3,
                                        pinion=lambda: body("pinion"),
                                        wheel=lambda: body("wheel"), mesh=mesh_spec,
                                        housing=lambda: body("housing", "carrier")),
    "gearvib.stages.stage_prefix": _c(1),
    # rig
    "gearvib.rig.Shaft": _c("input", 1.0),
    "gearvib.rig.ShaftRig": _c("rig", lambda: (__import__("gearvib.rig").rig.Shaft("in"),),
                               "in"),
    # fault_lines
    "gearvib.fault_lines.FaultFamily": _c("bearing", "bpfo", 3.58, 0.0, 3, 0),
    "gearvib.fault_lines.catalogue_families": _c(rig_catalogue),
    "gearvib.fault_lines.check_fault_lines": _c(bearing_measurement, rig_families,
                                                order_spectrum=False),
    "gearvib.fault_lines.confirmed_catalogue": _c(rig_catalogue, fault_lines),
    "gearvib.fault_lines.known_families": _c(rig_catalogue, 10.0),
    # jit_cache
    "gearvib.jit_cache.first_run_notice": _c(),
    "gearvib.jit_cache.kernels_cached": _c(),
    # config
    "gearvib.config.check_keys": _c(lambda: {"a": 1}, {"a", "b"}, "[table]"),
    "gearvib.config.config_hash": _c(cfg_copy),
    "gearvib.config.description_from_dict": _c(cfg_copy),
    "gearvib.config.example_text": _c("paper-cases"),
    "gearvib.config.example_titles": _c(),
    "gearvib.config.gearset_from_dict": _c(cfg_copy),
    "gearvib.config.list_examples": _c(),
    "gearvib.config.list_presets": _c(),
    "gearvib.config.list_rigs": _c(),
    "gearvib.config.load_config": _c("paper-case1"),
    "gearvib.config.load_description": _c(_f("toml")),
    "gearvib.config.load_gearset": _c("paper-case1"),
    "gearvib.config.preset_text": _c("paper-case1"),
    "gearvib.config.preset_titles": _c(),
    "gearvib.config.read_toml": _c(_f("toml"), "gear set"),
    "gearvib.config.rig_from_dict": _c(lambda: __import__("gearvib.config").config.load_config(
        "cwru-drive-end")[0]),
    "gearvib.config.rig_titles": _c(),
    # geometry
    "gearvib.geometry.Toothing": _c(33, 2.5e-3, 0.35, 0.0, 0.1, 0.02, 1.0, 1.25),
    "gearvib.geometry.admissible_planet_angles": _c(33, -114, 3),
    "gearvib.geometry.check_planet_angles": _c(33, -114, lambda: np.radians([0, 120, 240])),
    "gearvib.geometry.inverse_involute": _c(0.015),
    "gearvib.geometry.involute": _c(0.35),
    "gearvib.geometry.mesh_geometry": _c(lambda: toothing(33), lambda: toothing(40)),
    "gearvib.geometry.mesh_phases": _c(33, lambda: np.radians([0, 120, 240])),
    "gearvib.geometry.minimum_offset_angle": _c(33, -114),
    "gearvib.geometry.planet_mesh_offsets": _c(33, -114, lambda: np.radians([0, 120, 240])),
    "gearvib.geometry.planet_mesh_position": _c(sun_mesh_geometry, planet_is_gear1=False,
                                                mate_direction=math.pi, tooth_angle=0.1),
    "gearvib.geometry.planet_profile_shift": _c(lambda: toothing(33), lambda: toothing(-114),
                                                40),
    "gearvib.geometry.planet_tooth_angle": _c(sun_mesh_geometry, planet_is_gear1=False,
                                              mate_direction=math.pi, position=0.3),
    "gearvib.geometry.planet_tooth_number": _c(33, -114, "down"),
    "gearvib.geometry.planetary_meshes": _c(lambda: planetary_geometry()[0],
                                            lambda: planetary_geometry()[1],
                                            lambda: planetary_geometry()[2]),
    "gearvib.geometry.sun_ring_phase": _c(sun_mesh_geometry, ring_mesh_geometry),
    # kinematics
    "gearvib.kinematics.mesh_frequency": _c(33, 1000.0, 224.5),
    "gearvib.kinematics.paper_mesh_frequency": _c(1000.0, 33, -114),
    "gearvib.kinematics.simple_set_speeds": _c(33, -114, fixed="ring", input="sun",
                                               input_speed=1000.0),
    "gearvib.kinematics.willis_ratio": _c(33, -114),
    # stiffness
    "gearvib.stiffness.ConstantStiffness": _c(3e8),
    "gearvib.stiffness.FourierStiffness": _c(3e8, lambda: [2e7, 1e7], lambda: [5e6]),
    "gearvib.stiffness.PairSuperposition": _c(_literal(lambda u: np.full(np.shape(u), 2e8)),
                                              1.6),
    "gearvib.stiffness.RectangularStiffness": _c(2.7e7, 4.3e7, 1.6),
    "gearvib.stiffness.TabulatedPair": _c(lambda: np.linspace(0, 1, 11),
                                          lambda: np.full(11, 2e8), 1.6),
    "gearvib.stiffness.TrapezoidalStiffness": _c(2.7e7, 4.3e7, 1.6, 0.1),
    "gearvib.stiffness.iso6336_stiffness": _c(sun_mesh_geometry),
    "gearvib.stiffness.iso_rectangular": _c(sun_mesh_geometry),
    "gearvib.stiffness.stiffness_from_dict": _c(
        lambda: {"model": "rectangular", "k_min": 2.7e7, "k_max": 4.3e7}, sun_mesh_geometry),
    # assembly
    "gearvib.assembly.assemble": _c(gs, n_table=256),
    "gearvib.assembly.resolve_mesh": _c(lambda: gs().meshes[0]),
    # teeth
    "gearvib.teeth.mesh_tooth_map": _c(_pieces("meshes"), _pieces("bodies"),
                                       _pieces("resolved"), _pieces("s0"), _pieces("centre")),
    "gearvib.teeth.pair_teeth": _c(lambda: model().mesh_teeth[0], 33, 40, 2),
    # modal
    "gearvib.modal.modal_analysis": _c(model, carrier_speed_rpm=100.0, stiffness_scale=1.0,
                                       torque_sign=1.0),
    "gearvib.modal.rigid_body_mask": _c(lambda: model().stiffness, lambda: modal().shapes),
    # simulate and simulation.*
    "gearvib.simulation.conditions.DriveCoupling": _c(3728.0, 9.4, "input"),
    "gearvib.simulation.conditions.MotorDriven": _c(lambda: [0.0, 1000.0, 2000.0],
                                                    lambda: [80.0, 80.0, 0.0], 0.1,
                                                    (60.0, 0.0, 0.0), 1000.0, 0.002),
    "gearvib.simulation.conditions.SpeedRamp": _c(1000.0, 1000.0, 0.002, 0.0, 60.0),
    "gearvib.simulation.conditions.SpeedTable": _c(lambda: [0.0, 0.002],
                                                   lambda: [1000.0, 1000.0], 0.0, 60.0),
    "gearvib.simulation.conditions.TorqueDriven": _c(60.0, 0.1, (60.0, 0.0, 0.0), 1000.0,
                                                     0.002, 6000.0),
    "gearvib.simulate.batch_groups": _c(lambda: [model(), model()], ramp, max_steps=20_000),
    "gearvib.simulation.run_size.check_run_size": _c(step_choice, 0.01, n_dof=5, n_mesh=6,
                                                     n_signals=40, n_stored=60),
    "gearvib.simulation.step.choose_step": _c(2000.0, 1700.0, min_decimation=4),
    "gearvib.simulation.run_setup.coupling_matrices": _c(
        lambda: setup().mass, lambda: setup().rigid, 0,
        lambda: __import__("gearvib.simulate").simulate.DriveCoupling(3728.0, 9.4)),
    "gearvib.simulation.decimation.decimation_filter": _c(4, 85.0),
    "gearvib.simulation.run_setup.default_coupling": _c(model, 1.0),
    "gearvib.simulation.run_setup.prepare_run": _c(model, ramp, False),
    "gearvib.simulate.simulate": _c(model, ramp, max_steps=20_000),
    "gearvib.simulate.simulate_batch": _c(lambda: [model()], ramp, max_steps=20_000),
    "gearvib.simulation.equilibrium.static_equilibrium": lambda: _equilibrium_args(),
    "gearvib.simulation.tooth_forces.static_tooth_forces": _c(model, ramp),
    "gearvib.simulation.run_setup.with_coupling": _c(
        lambda: _stiffness_mass()[1], lambda: setup().mass, lambda: setup().rigid, 0,
        lambda: __import__("gearvib.simulate").simulate.DriveCoupling(3728.0, 9.4)),
    "gearvib.simulation.decimation.filter_length": _c(4, 85.0),
    "gearvib.simulation.decimation.kaiser_design": _c(85.0, 0.1),
    "gearvib.simulation.frequencies.elastic_frequencies": _c(
        lambda: modal().frequencies_hz, lambda: _stiffness_mass()[0],
        lambda: _stiffness_mass()[1]),
    "gearvib.simulation.frequencies.check_mass": _c(lambda: _stiffness_mass()[0]),
    "gearvib.simulation.frequencies.stiffest_matrix": _c(model, 1.0),
    "gearvib.simulation.frequencies.undamped_frequencies": _c(lambda: _stiffness_mass()[0],
                                                              lambda: _stiffness_mass()[1]),
    "gearvib.simulation.result.build_result": lambda: _build_result_args(),
    "gearvib.simulation.result.model_sha256": _c(model),
    "gearvib.simulation.run_setup.check_model": _c(model),
    "gearvib.simulation.run_setup.drive_sensing": _c(lambda: setup().mass,
                                                     lambda: setup().rigid, 0),
    "gearvib.simulation.run_size.seconds_per_step": _c(5, 6),
    "gearvib.simulation.settings.conditions_from_settings": _c(
        lambda: __import__("gearvib.simulation.settings").simulation.settings.read_run_settings(
            {"speed_start_rpm": 1000.0, "speed_end_rpm": 1000.0, "duration": 0.002})),
    "gearvib.simulation.settings.read_run_settings": _c(
        lambda: {"speed_start_rpm": 1000.0, "speed_end_rpm": 1000.0, "duration": 0.002},
        lambda: {"duration": 0.001}),
    # faults
    "gearvib.faults.description.BrokenTooth": _c("sun", 3, ("planet1",), "broken"),
    "gearvib.faults.description.Crack": _c("sun", 3, 0.3, None, (), "crack"),
    "gearvib.faults.description.Eccentricity": _c("sun", 1e-5, 30.0, (), "ecc"),
    "gearvib.faults.description.PairCurve": _c((0.0, 0.5, 1.0), (2e8, 1.8e8, 2e8),
                                               "path_fraction"),
    "gearvib.faults.description.PinError": _c("planet1", 0.0, 1e-5, "pin"),
    "gearvib.faults.description.PitchError": _c("sun", 3, 5e-6),
    "gearvib.faults.description.Pitting": _c("sun", 3, 0.4, 0.2, 0.6, 5e-6, "left"),
    "gearvib.faults.description.PlanetBacklash": _c("planet1", 1e-4),
    "gearvib.faults.apply.add_faults": _c(model, lambda: [fault("crack"), fault("pin")]),
    "gearvib.faults.law.build_fault_law": _c(
        lambda: __import__("gearvib.faults").faults.add_faults(model(), [fault("crack")])),
    "gearvib.faults.description.fault_from_dict": _c(
        lambda: {"kind": "crack", "member": "sun", "tooth": 3, "severity": 0.3}, index=0),
    "gearvib.faults.apply.fault_targets": _c(model, lambda: fault("crack")),
    "gearvib.faults.description.faults_from_list": _c(
        lambda: [{"kind": "crack", "member": "sun", "tooth": 3, "severity": 0.3}]),
    "gearvib.faults.apply.mesh_lines": _c(model),
    # sensors
    "gearvib.sensors.description.HousingMode": _c(2000.0, 0.05, 1.0),
    "gearvib.sensors.description.HousingSensor": _c(
        "acc", 90.0, "hann", 90.0, lambda: (__import__("gearvib.sensors").sensors.HousingMode(
            2000.0, 0.05, 1.0),)),
    "gearvib.sensors.description.MeasuredFrf": _c((100.0, 200.0), (1e-3, 1e-3), (0.0, 0.0)),
    "gearvib.sensors.description.Tacho": _c("tacho", 1, "sun", 5.0, 0.5),
    "gearvib.sensors.signal.add_sensor_signals": _c(sensed_run, sensed_model),
    "gearvib.sensors.apply.add_sensors": _c(model, lambda: [sensor()]),
    "gearvib.sensors.apply.housing_meshes": _c(model, "ring"),
    "gearvib.sensors.signal.housing_response": _c(lambda: np.ones(64), 20_000.0, sensor),
    "gearvib.sensors.signal.path_force": _c(sensed_run, sensed_model,
                                            lambda: sensed_model().sensors[0]),
    "gearvib.sensors.description.sensor_from_dict": _c(
        lambda: {"name": "acc", "angle_deg": 90.0, "housing_modes": [
            {"frequency_hz": 2000.0, "damping_ratio": 0.05, "gain": 1.0}]}, index=0),
    "gearvib.sensors.description.sensors_from_list": _c(
        lambda: [{"name": "acc", "angle_deg": 90.0, "housing_modes": [
            {"frequency_hz": 2000.0, "damping_ratio": 0.05, "gain": 1.0}]}]),
    "gearvib.sensors.signal.tacho_signal": _c(lambda: np.linspace(0, 20, 64), tacho),
    "gearvib.sensors.signal.window_weight": _c("hann", 90.0, lambda: np.linspace(-1, 1, 9)),
    # rolling_bearings
    "gearvib.rolling_bearings.RollingBearingSpec": _c("input bearing", "sun", 9, 7.94e-3,
                                                      39.04e-3, 0.0),
    "gearvib.rolling_bearings.rolling_bearings_from_list": _c(
        lambda: [{"name": "b", "member": "sun", "n_rolling": 9, "rolling_diameter": 7.94e-3,
                  "pitch_diameter": 39.04e-3}]),
    # catalogue, phases
    "gearvib.catalogue.gear_set_catalogue": _c(gs, speed_rpm=1000.0, model=model),
    "gearvib.phases.mesh_phase_table": _c(model),
    "gearvib.phases.run_mesh_phases": _c(lambda: dict(run_ds().attrs)),
    # stability
    "gearvib.stability.common_period": _c(lambda: [1.0, 0.5], max_cycles=16),
    "gearvib.stability.cycle_budget": _c(model, limit=64),
    "gearvib.stability.first_order_regions": _c(model, l_max=2),
    "gearvib.stability.gear_set_candidates": _c(model, modal, n_max=2),
    "gearvib.stability.mesh_phasing": _c(model, modal),
    "gearvib.stability.periodic_system": _c(model, max_cycles=16),
    "gearvib.stability.stability_map": _c(_literal(_model_for), lambda: np.array([1000.0,
                                                                                  2000.0]),
                                          lambda: np.array([1.0]), workers=1),
    "gearvib.stability.stability_over_speed": _c(model, lambda: np.array([1000.0, 2000.0]),
                                                 refine=False, n_max=2),
    # io, xarray_backend
    "gearvib.io.atomic_write": _c(lambda: tmp() / "atomic.txt", _literal(_writer)),
    "gearvib.io.read_run": _c(_f("run")),
    "gearvib.io.sanitize_attrs": _c(lambda: {"a": 1.0, "b": True, "c": [1, 2]}),
    "gearvib.io.write_netcdf": _c(run_ds, lambda: tmp() / "written.nc"),
    "gearvib.xarray_backend.GearvibBackendEntrypoint": _c(),
    "gearvib.xarray_backend.file_kind": _c(_f("run")),
    # execution
    "gearvib.execution.SerialExecutor": _c(),
    "gearvib.execution.check_connect_timeout": _c(5.0),
    "gearvib.execution.dask_executor": _c("tcp://127.0.0.1:9", timeout=0.2),
    "gearvib.execution.default_start_method": _c(),
    "gearvib.execution.default_workers": _c(),
    "gearvib.execution.executor_for": _c(1),
    "gearvib.execution.local_executor": _c(1),
    "gearvib.execution.probe_scheduler": _c("tcp://127.0.0.1:9", 0.2),
    "gearvib.execution.stop_workers": _c(pool),
    "gearvib.execution.worker_environment": _c(),
    # report
    "gearvib.report.study.AnalysisSettings": _c(2, 30, 400.0, 0.9, 3, 6.0, 0.03, 0.0, "", 5,
                                                "off"),
    "gearvib.report.study.Case": _c("c1", "paper-case1", "case 1"),
    "gearvib.report.study.RunSettings": _c(1000.0, 1400.0, 0.04, 60.0, 10_000.0),
    "gearvib.report.study.Study": _c("fuzz", lambda: study().cases, lambda: study().run,
                                     analysis_settings),
    "gearvib.report.case.analyse_case": _c(report_ds, name="c1", settings=analysis_settings),
    "gearvib.report.runner.build_report": _c(lambda: [files()["report_run"]],
                                             lambda: tmp() / "report", analysis=analysis_settings),
    "gearvib.report.runner.check_output_dir": _c(lambda: tmp() / "out"),
    "gearvib.report.compare.compare_cases": _c(case_analysis, case_analysis),
    "gearvib.report.study.load_study": _c(_f("study")),
    "gearvib.report.runner.run_study": _c(study, lambda: tmp() / "study", progress=False),
    # sweep
    "gearvib.sweep.case.CaseTask": _c(lambda: sweep().cases()[0], "case.nc",
                                      lambda: sweep().summary, False),
    "gearvib.sweep.description.Parameter": _c("meshes.sun.damping_ratio", (0.005, 0.01)),
    "gearvib.sweep.summary.SummarySettings": _c(None, None, (1.0, 2.0), "mesh"),
    "gearvib.sweep.description.Sweep": _c("paper-case1", lambda: sweep().parameters, "grid",
                                          simulation=lambda: dict(SWEEP["simulation"])),
    "gearvib.sweep.description.load_sweep": _c(_f("sweep")),
    "gearvib.sweep.case.run_case": _c(case_task),
    "gearvib.sweep.runner.run_sweep": _c(sweep, lambda: tmp() / "sweep", workers=1,
                                         progress=False, report=False),
    "gearvib.sweep.summary.summarise_run": _c(run_ds, model, ramp),
    "gearvib.sweep.description.sweep_from_dict": _c(sweep_dict),
    # diagnosis
    "gearvib.diagnosis.record.Record": _c(lambda: np.ones(256), 4096.0,
                                          lambda: np.full(256, 1500.0), "sun"),
    "gearvib.diagnosis.candidates.candidate_faults": _c(cfg_copy, ("crack", "pin_error")),
    "gearvib.diagnosis.engine.diagnose": _c(record, "paper-case1", kinds=(), library=False,
                                            workers=1, revolutions=2, max_duration=0.1),
}

#: Public classes a scripting user does not call: results gearvib builds (their inputs are
#: checked where they are computed) and abstract bases.
NOT_FUZZED: dict[str, str] = {
    "gearvib.assembly.ResolvedMesh": "result of resolve_mesh",
    "gearvib.diagnosis.candidates.Candidate": "result of candidate_faults",
    "gearvib.fault_lines.FaultLines": "result of check_fault_lines",
    "gearvib.faults.description.Fault": "abstract base of the fault kinds",
    "gearvib.faults.law.FaultLaw": "result of build_fault_law",
    "gearvib.geometry.MeshGeometry": "result of mesh_geometry",
    "gearvib.modal.ModalResult": "result of modal_analysis",
    "gearvib.report.case_analysis.CaseAnalysis": "result of analyse_case",
    "gearvib.report.compare.Comparison": "result of compare_cases",
    "gearvib.report.runner.ReportPaths": "result of build_report",
    "gearvib.report.runner.StudyResult": "result of run_study",
    "gearvib.simulation.result.RunUpResult": "result of simulate",
    "gearvib.simulation.run_setup.RunSetup": "result of prepare_run",
    "gearvib.simulation.run_size.RunSize": "result of check_run_size",
    "gearvib.simulation.step.StepChoice": "result of choose_step",
    "gearvib.simulation.tooth_forces.StaticToothForces": "result of static_tooth_forces",
    "gearvib.stability.CommonPeriod": "result of common_period",
    "gearvib.stability.PeriodicGearSystem": "result of periodic_system",
    "gearvib.stiffness.MeshStiffness": "abstract base of the stiffness laws",
    "gearvib.sweep.case.CaseOutcome": "result of run_case",
    "gearvib.sweep.description.SweepCase": "result of Sweep.cases",
    "gearvib.sweep.runner.SweepResult": "result of run_sweep",
}
