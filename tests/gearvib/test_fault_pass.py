"""The faulty-mesh pass compiled per fault configuration (:mod:`gearvib.fault_pass`) against
the generic pass of the kernel: the same right-hand side and the same runs, bit for bit, for
every fault law; one source per structure; the generic pass wherever no pass can be made."""

from __future__ import annotations

import copy
import sys

import numpy as np
import pytest

import gearvib.simulate as gsim
from gearvib import fault_pass as fp
from gearvib import kernels as kn
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config, load_gearset
from gearvib.faults import BrokenTooth, Crack, Eccentricity, PinError, PitchError, Pitting
from gearvib.simulate import SpeedRamp, prepare_run, simulate, static_equilibrium

COND = SpeedRamp(1000, 1000, 1.0, input_torque=60.0)
RNG_PITCH = list(np.random.default_rng(3).normal(0.0, 3e-6, 33))

# one fault set per law of the generic pass (gearvib.faults.law.LAW_*), and all at once
LAWS = {
    "shifted (eccentricity, pin error)": [Eccentricity("sun", 10e-6, 30.0),
                                          PinError("planet2", radial=4e-6, tangential=-6e-6)],
    "mean offset (pitch errors)": [PitchError("sun", cumulative=RNG_PITCH)],
    "pairs (pitting)": [Pitting("planet1", 5, severity=0.5, path_start=0.3, path_end=0.6,
                                depth=2e-6, flank="both")],
    "stiffness (crack, broken tooth)": [Crack("sun", 3, severity=0.3),
                                        BrokenTooth("ring", 7)],
    "every kind": [Crack("sun", 3, severity=0.4),
                   Pitting("planet2", 5, severity=0.3, path_start=0.2, path_end=0.6,
                           depth=3e-6, flank="both"),
                   PitchError("ring", tooth=7, deviation=5e-6),
                   Eccentricity("sun", 20e-6, 30.0),
                   Eccentricity("planet3", 5e-6),
                   PinError("planet1", radial=10e-6, tangential=-20e-6),
                   BrokenTooth("planet3", 11),
                   PitchError("planet1", cumulative=list(np.linspace(-3e-6, 3e-6, 40)))],
}


def viscous(preset: str):
    """``preset`` with the always-on mesh-damping law on every mesh family."""
    cfg, base = load_config(preset)
    cfg = copy.deepcopy(cfg)
    for family in cfg["meshes"].values():
        family["damping_law"] = "viscous"
    return assemble(gearset_from_dict(cfg, base=base))


def _packed(model):
    setup = prepare_run(model, COND, False)
    generic = setup.system.astuple()
    compiled = fp.with_fault_pass(tuple(np.array(a, copy=True) for a in generic))
    return setup, generic, compiled


# every law alone on the rigid presets, and all laws at once on every preset: each elastic
# variant compiles its own passes (~10 s each), and "every kind" holds every law's code
RHS_CASES = [(preset, law) for preset in ("paper-case1", "paper-case2") for law in LAWS] + [
    ("paper-case1-elastic", "every kind"), ("paper-case1-elastic viscous", "every kind")]


@pytest.mark.parametrize(("preset", "law"), RHS_CASES)
def test_compiled_pass_gives_the_generic_right_hand_side(preset, law) -> None:
    """At states near the loaded equilibrium (rigid rotation by a random angle, small
    deflections and velocities), the right-hand side and the mesh outputs of the compiled
    pass equal the generic pass's bit for bit (the elastic preset has distinct back lines;
    ``viscous``: every mesh under the always-on damping law, at states thrown across the
    backlash as well, so that every zone of the law is met)."""
    name, _, damping = preset.partition(" ")
    base = viscous(name) if damping else assemble(load_gearset(name))
    model = base.with_faults(LAWS[law])
    setup, generic, compiled = _packed(model)
    assert generic[0][kn.H_FPASS] == 0  # pack never stores an address
    assert compiled[0][kn.H_FPASS] != 0
    q0, _ = static_equilibrium(setup.system, setup.mass, setup.rigid,
                               setup.rigid * setup.omega0)
    rng = np.random.default_rng(11)
    zones = set()
    for k in range(60):
        spread = 4e-4 if damping and k % 2 else 2e-7
        q = q0 + setup.rigid * rng.uniform(0, 50) + rng.normal(0, spread, q0.size)
        qd = setup.rigid * setup.omega0 + rng.normal(0, 1e-3, q0.size)
        y = np.concatenate([q, qd])
        dy_g, out_g = kn.evaluate_rhs(0.0, y, generic)
        dy_c, out_c = kn.evaluate_rhs(0.0, y, compiled)
        np.testing.assert_array_equal(dy_c, dy_g)
        np.testing.assert_array_equal(out_c, out_g)
        zones.update(int(v) for v in out_g[:, 3])
    if damping:
        assert zones >= {0, 1, 2}  # backlash, left and back flank of the faulty meshes


def _record(model, monkeypatch, mode: str):
    monkeypatch.setenv(fp.PASS_ENV, mode)
    return simulate(model, SpeedRamp(0.0, 3000.0, 1.0, input_torque=60.0), duration=0.25,
                    progress=False)


@pytest.mark.parametrize(("preset", "law"), [
    ("paper-case1", "shifted (eccentricity, pin error)"),  # desynchronised in-phase planets
    ("paper-case1", "mean offset (pitch errors)"),
    ("paper-case1-elastic", "every kind"),
    ("paper-case2", "stiffness (crack, broken tooth)"),
    ("paper-case1-elastic viscous", "every kind"),
])
def test_runs_with_the_compiled_pass_are_bit_identical(preset, law, monkeypatch) -> None:
    """A run-up with the compiled pass (its kept eccentricity references, mean-offset cycles
    and need runs across steps included) gives the generic pass's result bit for bit."""
    name, _, damping = preset.partition(" ")
    model = (viscous(name) if damping else assemble(load_gearset(name))).with_faults(LAWS[law])
    used = []
    real = gsim.with_fault_pass

    def spy(packed):
        out = real(packed)
        used.append(int(out[0][kn.H_FPASS]))
        return out

    monkeypatch.setattr(gsim, "with_fault_pass", spy)
    a = _record(model, monkeypatch, "generic")
    b = _record(model, monkeypatch, "")
    assert used[0] == 0 and used[1] != 0  # the generic pass, then the compiled one
    for name in ("normal_force", "mesh_stiffness", "mesh_deflection", "bearing_force",
                 "displacement", "rotation", "speed", "flank_contact_changes"):
        np.testing.assert_array_equal(getattr(b, name), getattr(a, name), err_msg=name)


def test_one_source_per_structure() -> None:
    """Configurations that differ only in values (amplitude, phase, severity, tooth) share
    the source, and so the compiled pass; another member or kind does not. The source is
    deterministic and records the SHA-256 of the files it embeds."""
    base = assemble(load_gearset("paper-case1"))

    def source(faults):
        _, generic, _ = _packed(base.with_faults(faults))
        return fp.pass_source(generic[0], generic[2])

    crack = source([Crack("sun", 3, severity=0.3)])
    assert crack == source([Crack("sun", 3, severity=0.3)])
    assert crack == source([Crack("sun", 17, severity=0.8)])
    ecc = source([Eccentricity("sun", 10e-6)])
    assert ecc == source([Eccentricity("sun", 3e-6, 40.0)])
    assert ecc != source([Eccentricity("ring", 10e-6)])
    assert ecc != crack
    assert fp.dependency_digest() in crack
    compile(crack, "<fault pass>", "exec")  # valid Python


def test_no_faults_or_generic_requested_keep_the_generic_pass(monkeypatch) -> None:
    base = assemble(load_gearset("paper-case1"))
    _, healthy, _ = _packed(base)
    assert fp.pass_address(healthy[0], healthy[2]) == 0
    with pytest.raises(ValueError, match="no faulty mesh"):
        fp.pass_source(healthy[0], healthy[2])
    _, faulty, _ = _packed(base.with_faults([Crack("sun", 3, severity=0.3)]))
    monkeypatch.setenv(fp.PASS_ENV, "Generic ")
    assert fp.pass_address(faulty[0], faulty[2]) == 0


def test_an_unwritable_folder_gives_the_generic_pass_with_a_warning(monkeypatch,
                                                                    tmp_path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setattr(fp, "_PASSES", {})
    monkeypatch.setattr(fp, "specialised_folder", lambda: blocker / "specialised")
    model = assemble(load_gearset("paper-case1")).with_faults([Crack("sun", 3, severity=0.3)])
    generic = prepare_run(model, COND, False).system.astuple()
    with pytest.warns(RuntimeWarning, match="generic pass"):
        assert fp.pass_address(generic[0], generic[2]) == 0
    assert list(tmp_path.iterdir()) == [blocker]  # nothing written


def test_a_source_numba_refuses_gives_the_generic_pass_with_a_warning(monkeypatch,
                                                                      tmp_path) -> None:
    """A pass that does not compile leaves the run to the generic pass (same results), with
    a warning instead of a traceback."""
    good = fp.pass_source
    monkeypatch.setattr(fp, "_PASSES", {})
    monkeypatch.setattr(fp, "specialised_folder", lambda: tmp_path)
    monkeypatch.setattr(fp, "pass_source", lambda *a: good(*a).replace(
        "    n_table =", "    n_table = 'not a number' +", 1))
    model = assemble(load_gearset("paper-case1")).with_faults([Crack("sun", 3, severity=0.3)])
    generic = prepare_run(model, COND, False).system.astuple()
    with pytest.warns(RuntimeWarning, match="generic pass"):
        assert fp.pass_address(generic[0], generic[2]) == 0
    assert not any(str(getattr(mod, "__file__", None) or "").startswith(str(tmp_path))
                   for mod in list(sys.modules.values()))  # the failed module not registered


def test_with_pass_hands_the_kernels_a_pass_without_changing_the_callers_arrays() -> None:
    """A healthy system goes to the compiled kernels as it is; a faulty one without a pass gets
    a copy of ``ints`` holding the generic pass's address (the caller's arrays unchanged); one
    with its compiled pass keeps it."""
    base = assemble(load_gearset("paper-case1"))
    _, healthy, _ = _packed(base)
    assert kn.with_pass(healthy) is healthy
    _, faulty, compiled = _packed(base.with_faults([Crack("sun", 3, severity=0.3)]))
    ready = kn.with_pass(faulty)
    assert faulty[0][kn.H_FPASS] == 0  # the caller's array is not changed
    assert ready[0] is not faulty[0]
    assert ready[0][kn.H_FPASS] == kn.generic_pass() != 0
    np.testing.assert_array_equal(np.delete(ready[0], kn.H_FPASS),
                                  np.delete(faulty[0], kn.H_FPASS))
    assert all(a is b for a, b in zip(ready[1:], faulty[1:], strict=True))
    assert kn.with_pass(compiled) is compiled


_HEALTHY_RUN = """
import gearvib.kernels as kn
from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.simulate import SpeedRamp, simulate
simulate(assemble(load_gearset("paper-case1")), SpeedRamp(1000, 1000, 0.002), progress=False)
print(kn.generic_pass_compiled())
"""


def test_a_run_without_faults_does_not_compile_the_generic_pass() -> None:
    """The generic pass is compiled on first use only (a fresh process, the kernels from the
    cache or compiled): a healthy run leaves it uncompiled."""
    import subprocess

    out = subprocess.run([sys.executable, "-c", _HEALTHY_RUN], capture_output=True, text=True,
                         check=True, timeout=600).stdout.split()
    assert out[-1] == "False"
