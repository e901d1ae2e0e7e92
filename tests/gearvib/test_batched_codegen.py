"""The batched kernel specialised to a topology (generated right-hand side,
:mod:`gearvib.batch_codegen`): bit-identical to the single runs and to the generic batched
kernel, written to disk once and atomically, reused from numba's cache, and replaced by the
generic kernel where nothing can be written."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from gearvib import kernels as kn
from gearvib import kernels_batch as kb
from gearvib.assembly import assemble
from gearvib.batch_codegen import rhs_source
from gearvib.config import gearset_from_dict, load_config, load_gearset
from gearvib.sweep.keys import set_path
from tests.gearvib.batch_support import start_state


def _preset_variants(preset: str, radial: bool = False, viscous: bool = False):
    cfg, base = load_config(preset)
    if viscous:  # the sun meshes under the always-on damping law, the ring meshes gated
        cfg = set_path(cfg, "meshes.sun.damping_law", "viscous")
    runs = []
    for k in range(3):
        d = set_path(cfg, "meshes.sun.damping_ratio", 0.005 * (1 + k))
        if radial:
            d = set_path(d, "bodies.planet.support.radial", 1.5e8 * (1 + 0.05 * k))
        runs.append(start_state(assemble(gearset_from_dict(d, base=base))))
    return runs


def _other_topology():
    """Another gear set with the gyroscopic and centripetal terms on: variants of the mesh
    damping and of the bearing stiffness (scaled, so every operator differs per lane)."""
    system, y0 = start_state(assemble(load_gearset("two-stage-example")), gyroscopic=True)
    assert system.ipar[kn.IP_GYRO] == 1
    runs = []
    for k in range(3):
        s = dataclasses.replace(system, mesh_damping=system.mesh_damping * (1 + 0.3 * k),
                                stiffness=system.stiffness * (1 + 0.02 * k))
        runs.append((s, y0))
    return runs


def _run(systems, y0, dt, n_steps, monkeypatch, kernel):
    monkeypatch.setenv(kb.KERNEL_ENV, kernel)
    return kb.integrate_batch(systems, np.array(y0), dt, n_steps)


# "viscous" holds the bearing stiffness per lane and both damping laws (sun meshes viscous,
# ring meshes gated): every case compiles its own kernel (~20 s), so none repeats another
@pytest.mark.parametrize("case", ["paper-case1", "paper-case1-elastic", "other", "viscous"])
def test_specialised_kernel_is_bit_identical(case, monkeypatch):
    if case == "other":
        runs, dt = _other_topology(), 5e-6
    elif case == "viscous":
        runs, dt = _preset_variants("paper-case1-elastic", radial=True, viscous=True), 8e-6
    else:
        runs, dt = _preset_variants(case), 1e-5 if case == "paper-case1" else 8e-6
    systems = [s for s, _ in runs]
    y0 = [y for _, y in runs]
    monkeypatch.delenv(kb.KERNEL_ENV, raising=False)
    kernels = kb.kernels_for(kb.pack_batch(systems).astuple())
    assert kernels.source is not None and kernels.source.is_file()  # specialised
    n_steps = 200
    spec = _run(systems, y0, dt, n_steps, monkeypatch, "specialised")
    generic = _run(systems, y0, dt, n_steps, monkeypatch, "generic")
    for b, (system, y) in enumerate(runs):
        r, ch, st, y1 = kn.integrate(system, y, dt, n_steps)
        assert st[0] == kn.STATUS_OK and spec[2][b, 0] == kn.STATUS_OK
        assert spec[0][b].tobytes() == r.tobytes(), f"variant {b}: specialised differs"
        assert generic[0][b].tobytes() == r.tobytes(), f"variant {b}: generic differs"
        assert np.array_equal(spec[1][b], ch)
        assert spec[3][b].tobytes() == y1.tobytes()
    assert not np.array_equal(spec[0][0], spec[0][2])  # the variants differ


def test_specialised_right_hand_side_per_lane():
    """The generated right-hand side against the single one, lane by lane, at its own time
    and a perturbed state, on a topology with gyroscopic terms and operators per lane."""
    runs = _other_topology()
    systems = [s for s, _ in runs]
    batch = kb.pack_batch(systems)
    assert batch.uniform[0] == 1 and batch.uniform[1] == 2  # stiffness per lane
    rng = np.random.default_rng(5)
    y = np.empty((runs[0][1].size, kb.WIDTH))
    t = 0.05 + 0.003 * np.arange(kb.WIDTH)
    for b in range(kb.WIDTH):
        y[:, b] = runs[b % 3][1] * (1 + 1e-3 * rng.standard_normal(y.shape[0]))
    dy, mo = kb.evaluate_rhs_batch(t, y, batch)
    for b in range(kb.WIDTH):
        system = systems[b] if b < 3 else systems[0]
        dy1, mo1 = kn.evaluate_rhs(t[b], np.ascontiguousarray(y[:, b]), system.astuple())
        assert dy[:, b].tobytes() == dy1.tobytes()
        assert mo[:, :, b].tobytes() == mo1.tobytes()


@pytest.mark.parametrize("kernel", ["specialised", "generic"])
def test_viscous_law_on_lanes_in_every_contact_zone(kernel, monkeypatch):
    """Sun meshes under the always-on damping law, ring meshes gated, bearing variants (two
    lines of action): at states thrown across the backlash (left flank, backlash, back flank,
    opening and closing) every lane's right-hand side equals the single one bit for bit, and
    a batch mixing the laws of a mesh is refused (the law is part of the topology)."""
    monkeypatch.setenv(kb.KERNEL_ENV, kernel)
    runs = _preset_variants("paper-case1-elastic", radial=True, viscous=True)
    systems = [s for s, _ in runs]
    assert list(systems[0].mesh_damping_law) == [1, 1, 1, 0, 0, 0]
    batch = kb.pack_batch(systems)
    rng = np.random.default_rng(8)
    zones = set()
    for _ in range(20):
        y = np.empty((runs[0][1].size, kb.WIDTH))
        for b in range(kb.WIDTH):
            y0 = runs[b % 3][1]
            n = y0.size // 2
            y[:, b] = y0 + np.concatenate([rng.normal(0, 4e-4, n), rng.normal(0, 0.5, n)])
        t = np.full(kb.WIDTH, 0.05)
        dy, mo = kb.evaluate_rhs_batch(t, y, batch)
        for b in range(kb.WIDTH):
            system = systems[b] if b < 3 else systems[0]
            dy1, mo1 = kn.evaluate_rhs(t[b], np.ascontiguousarray(y[:, b]), system.astuple())
            assert dy[:, b].tobytes() == dy1.tobytes()
            assert mo[:, :, b].tobytes() == mo1.tobytes()
            zones.update(int(v) for v in mo1[:3, 3])
    assert zones >= {0, 1, 2}  # every zone of the viscous meshes was visited (3: both lines)
    gated = _preset_variants("paper-case1-elastic", radial=True)[0][0]
    with pytest.raises(ValueError, match="mesh-damping laws"):
        kb.pack_batch([gated, systems[0]])


def test_generated_source_is_straight_line():
    """No sparse loops: every term with constant indices; one module per topology and
    operator modes (the same batch gives the same file name, other modes another)."""
    runs = _preset_variants("paper-case1-elastic")
    batch = kb.pack_batch([s for s, _ in runs])
    ints = batch.ints
    src = rhs_source(ints, dict.fromkeys(("lv", "cv", "gv", "vv", "fv", "pv", "rvv", "rfv"), 1),
                     kb.decode_rows(batch.rows, batch.n_dof))
    assert "for " not in src and "while " not in src and "ints[" not in src
    n_terms = src.count("lanes_madd(") + src.count("lanes_msub_nz(")
    lin = int(ints[ints[kn.H_LP] + batch.n_dof] - ints[ints[kn.H_LP]])
    assert n_terms > lin  # stiffness and damping terms, mesh vectors, mesh forces
    a = kb.specialised_source(batch.astuple())
    assert a == kb.specialised_source(kb.pack_batch([s for s, _ in runs]).astuple())
    bearing = kb.pack_batch([s for s, _ in _preset_variants("paper-case1-elastic", True)])
    assert bearing.uniform[0] == 0 and "lanes_madd_nz(" in kb.specialised_source(
        bearing.astuple())
    assert kb.specialised_source(bearing.astuple()) != a
    assert kb.dependency_digest(kb.SPECIALISED_DEPENDENCIES) in a


def test_write_once_is_atomic_and_keeps_an_existing_file(tmp_path):
    path = tmp_path / "sub" / "batch_x.py"
    text = "x = 1\n" * 20000
    errors = []

    def writer():
        try:
            kb.write_once(path, text)
        except Exception as exc:  # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=writer) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and path.read_text() == text
    assert [p.name for p in path.parent.iterdir()] == [path.name]  # no temporary left
    os.utime(path, (1e9, 1e9))
    kb.write_once(path, text)  # the same text: untouched (numba's index of it stays valid)
    assert path.stat().st_mtime == 1e9
    path.write_text(text[:100])  # a torn or older file: replaced
    kb.write_once(path, text)
    assert path.read_text() == text


def test_unwritable_folder_falls_back_to_the_generic_kernel(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setattr(kb, "specialised_folder", lambda: blocker / "specialised")
    monkeypatch.setattr(kb, "_KERNELS", {})
    monkeypatch.delenv(kb.KERNEL_ENV, raising=False)
    runs = _preset_variants("paper-case1")
    batch = kb.pack_batch([s for s, _ in runs])
    with pytest.warns(RuntimeWarning, match="runs generic"):
        kernels = kb.kernels_for(batch.astuple())
    assert kernels is kb.GENERIC
    rec, *_ = kb.integrate_batch([s for s, _ in runs], np.array([y for _, y in runs]),
                                 1e-5, 50)
    r, *_ = kn.integrate(runs[1][0], runs[1][1], 1e-5, 50)
    assert rec[1].tobytes() == r.tobytes()


_FRESH = """
import numpy as np
from gearvib import kernels_batch as kb
from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.simulate import SpeedRamp, prepare_run
s = prepare_run(assemble(load_gearset("paper-case1")), SpeedRamp(1500.0, 2500.0, 1.0), False)
batch = kb.pack_batch([s.system])
k = kb.kernels_for(batch.astuple())
rec = np.empty((kb.WIDTH, 3, 2 * s.system.n_dof + 3 * s.system.n_mesh))
y = np.zeros((2 * s.system.n_dof, kb.WIDTH))
k.integrate(y, 0, 2, 1e-5, batch.astuple(), rec, 0, np.full((kb.WIDTH, 6), -1),
            np.zeros((kb.WIDTH, 6), dtype=np.int64), 2, kb.batch_work(5, 6),
            np.zeros((kb.WIDTH, 2), dtype=np.int64))
print(k.source, sum(k.integrate.stats.cache_hits.values()))
"""


def test_a_fresh_process_loads_the_compiled_module_from_disk():
    """The second process finds the generated module and its compiled code (numba cache
    hits, no compilation)."""
    run = [sys.executable, "-c", _FRESH]
    env = {**os.environ}
    env.pop(kb.KERNEL_ENV, None)
    first = subprocess.run(run, env=env, capture_output=True, text=True, check=True)
    second = subprocess.run(run, env=env, capture_output=True, text=True, check=True)
    source, hits = second.stdout.split()
    assert source == first.stdout.split()[0] and Path(source).is_file()
    assert int(hits) >= 1
