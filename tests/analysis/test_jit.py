"""A read-only install runs a simulation (issue #14): numba's cache falls back to a writable
folder (analysis.jit) instead of failing with "no locator available".

The packages are copied into a folder that is then bind-mounted read-only in a private mount
namespace (``unshare -m``), together with a read-only home, so that neither the in-tree
``__pycache__`` nor numba's user-wide cache is writable -- as in a root-owned site-packages of
a container. Where mount namespaces are not available the test is skipped (without root,
file permissions are used instead).
"""

from __future__ import annotations

import getpass
import os
import shutil
import stat
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import pytest

import analysis
import gearvib
from analysis.jit import UnsafeCacheWarning, cache_candidates, prepare_cache, private_folder

_SIMULATE = """
import os, sys
# an editable install of the checkout would win over PYTHONPATH: leave it out
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in getattr(f, "__module__", "")]
import gearvib, analysis
assert gearvib.__file__.startswith({site!r}) and analysis.__file__.startswith({site!r})
from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.simulate import SpeedRamp, simulate
res = simulate(assemble(load_gearset("paper-case1")), SpeedRamp(0.0, 3000.0, 0.005))
print("NUMBA_CACHE_DIR=" + os.environ.get("NUMBA_CACHE_DIR", ""), res.time.size)
"""

_KERNEL = """
import os, sys
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in getattr(f, "__module__", "")]
import numpy as np
import gearvib
assert gearvib.__file__.startswith({site!r})
from gearvib.kernels import periodic_interp  # a small cached kernel of the simulator
print("NUMBA_CACHE_DIR=" + os.environ.get("NUMBA_CACHE_DIR", ""),
      periodic_interp(np.ones((1, 4)), 0, 0.3))
"""

_PLAIN = """
import sys
sys.path.insert(0, {site!r})
import plain_jit
"""


def _read_only_run(tmp_path: Path, script: str) -> subprocess.CompletedProcess:
    site, home, scratch = tmp_path / "site", tmp_path / "home", tmp_path / "scratch"
    ignore = shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc", "*.pyc")
    for pkg in (gearvib, analysis):
        src = Path(pkg.__file__).parent
        shutil.copytree(src, site / src.name, ignore=ignore)
    (site / "plain_jit.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x + 1\n"
    )
    home.mkdir()
    scratch.mkdir(exist_ok=True)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "XDG_"))}
    env.update(HOME=str(home), TMPDIR=str(scratch), PYTHONPATH=str(site),
               PYTHONDONTWRITEBYTECODE="1", MPLBACKEND="Agg")  # fmt: skip
    code = textwrap.dedent(script.format(site=str(site)))
    if os.geteuid() == 0:
        if shutil.which("unshare") is None:
            pytest.skip("unshare not available to make a read-only file system")
        probe = subprocess.run(["unshare", "-m", "true"], capture_output=True)
        if probe.returncode != 0:
            pytest.skip("mount namespaces not permitted here")
        shell = (
            f"mount --bind -o ro {site} {site} && mount --bind -o ro {home} {home} && "
            f'exec {sys.executable} -c "$CODE"'
        )
        env["CODE"] = code
        cmd = ["unshare", "-m", "sh", "-c", shell]
    else:
        for d in (site, home):
            for p in [d, *d.rglob("*")]:
                p.chmod(0o555 if p.is_dir() else 0o444)
        cmd = [sys.executable, "-c", code]
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600, cwd=scratch)


def test_read_only_install_runs_a_simulation(tmp_path):
    # the setup reproduces the failure: a plain cached function cannot be compiled there
    plain = _read_only_run(tmp_path / "plain", _PLAIN)
    assert plain.returncode != 0 and "no locator available" in plain.stderr
    # gearvib and analysis point numba at a writable folder and run
    out = _read_only_run(tmp_path / "gearvib", _SIMULATE)
    assert out.returncode == 0, out.stderr[-3000:]
    cache = out.stdout.split("NUMBA_CACHE_DIR=")[1].split()[0]
    assert cache.startswith(str(tmp_path / "gearvib" / "scratch"))
    assert any(Path(cache).rglob("*.nbi"))  # the compiled functions were cached there


def test_prepare_cache_respects_user_setting_and_writable_trees(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert prepare_cache(str(tmp_path / "module.py")) is None  # the user's choice stands
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    assert prepare_cache(str(tmp_path / "module.py")) is None  # __pycache__ writable
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_candidates()[0] == tmp_path / "xdg" / "gearvib" / "numba"


NOBODY = 65534


def test_a_planted_cache_folder_is_not_used(tmp_path):
    """Issue 26: with the package and home read-only, another user's folder at the fallback
    place (``<tmp>/gearvib-numba-<user>``, mode 777) is skipped with a warning; a private
    folder of this process is used, and nothing is written into the planted one."""
    scratch = tmp_path / "p" / "scratch"
    scratch.mkdir(parents=True)
    planted = scratch / f"gearvib-numba-{getpass.getuser()}"
    planted.mkdir()
    planted.chmod(0o777)
    if os.geteuid() == 0:
        os.chown(planted, NOBODY, NOBODY)  # another user's folder
    out = _read_only_run(tmp_path / "p", _KERNEL)  # (the whole simulation: the test above)
    assert out.returncode == 0, out.stderr[-3000:]
    assert "UnsafeCacheWarning" in out.stderr and str(planted) in out.stderr
    assert not any(planted.iterdir())
    cache = Path(out.stdout.split("NUMBA_CACHE_DIR=")[1].split()[0])
    assert cache != planted and cache.parent == scratch and private_folder(cache, create=False)
    assert any(cache.rglob("*.nbi"))


def test_private_folder(tmp_path):
    made = tmp_path / "a" / "b"
    assert private_folder(made)  # made with mode 0700
    assert stat.S_IMODE(made.stat().st_mode) == 0o700
    assert not private_folder(tmp_path / "missing", create=False)
    made.chmod(0o777)
    assert not private_folder(made)
    made.chmod(0o720)
    assert not private_folder(made)  # group-writable
    made.chmod(0o755)
    assert private_folder(made)
    link = tmp_path / "link"
    link.symlink_to(made)
    assert not private_folder(link)
    (tmp_path / "file").write_text("")
    assert not private_folder(tmp_path / "file")
    if os.geteuid() == 0:
        os.chown(made, NOBODY, NOBODY)
        assert not private_folder(made)


def test_unsafe_candidate_is_skipped_with_a_warning(tmp_path, monkeypatch):
    from analysis import jit

    unsafe = tmp_path / "unsafe"
    unsafe.mkdir()
    unsafe.chmod(0o777)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        assert not jit._usable(unsafe)
    assert [w.category for w in seen] == [UnsafeCacheWarning]


def test_generated_modules_refuse_a_folder_others_can_write(tmp_path):
    from gearvib.kernels_batch import write_once

    folder = tmp_path / "specialised"
    folder.mkdir(mode=0o700)
    write_once(folder / "m.py", "x = 1\n")
    assert (folder / "m.py").read_text() == "x = 1\n"
    folder.chmod(0o777)
    with pytest.raises(PermissionError, match="not private"):
        write_once(folder / "n.py", "x = 2\n")
    assert not (folder / "n.py").exists()
