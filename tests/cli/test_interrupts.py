"""SIGINT and SIGTERM at random moments of ``simulate``, ``report``, ``demo`` and ``sweep``
(subprocesses).

Every test starts ``python -m gearvib ...``, waits until its signal handlers are active
(``/proc/<pid>/status``), and sends the signal after a random delay (seeded, printed with the
outcome) or the moment a temporary file of an atomic write appears (so that writes are
included: netCDF runs and the PDF report). Asserted: exit within 2 s of the signal, code 130
(SIGINT) or 143 (SIGTERM), no temporary file left, and every output present is complete (a
readable run, no report without both files). The temporary files of a process killed with
SIGKILL are removed by the next command in the same folder.

``sweep`` (2 local workers) is stopped at a random moment after its process pool started and
while ``sweep.nc`` is written: exit within 2 s with 130/143, no temporary file anywhere in the
folder, no ``sweep.nc`` or a complete one, every run file present complete (finished runs stay:
the sweep resumes), and no worker process left running. After SIGKILL of the command its
workers end too (``PR_SET_PDEATHSIG``) and the next call reuses the finished runs.

Before the fix, SIGINT during the netCDF write of ``simulate`` deadlocked the process (a
``KeyboardInterrupt`` raised inside xarray's backend lock, see ``gearvib.interrupts``).
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gearvib import tempfiles
from gearvib.io import read_run
from tests.cli.signal_helpers import handlers_installed, run_and_signal, temp_files

pytestmark = pytest.mark.skipif(not Path("/proc/self/status").exists(),
                                reason="needs Linux /proc to see when the handlers are active")

SEED = int(os.environ.get("GEARVIB_SIGNAL_SEED", "11"))
EXIT = {signal.SIGINT: 130, signal.SIGTERM: 143}


def check_one_line(stderr: str, where: str) -> None:
    """An interrupt prints one line and nothing else (no traceback, no "Exception ignored")."""
    assert "Traceback" not in stderr and "Exception ignored" not in stderr, where
    lines = [line for line in stderr.splitlines() if "interrupted" in line]
    assert len(lines) == 1 and stderr.rstrip().endswith(lines[0]), where


def check_stopped(r, sig: int, folder: Path, outputs: list[str]) -> None:
    """Exit code and time, no temporary file, complete outputs only."""
    where = f"({r.moment}; stderr {r.stderr.strip()[-300:]!r})"
    if r.signalled and r.returncode != 0:
        assert r.returncode == EXIT[sig], where
        assert r.exit_seconds < 2.0, where
        check_one_line(r.stderr, where)
    else:  # done before the signal was due, or the signal came after the last output was
        # committed (the process was already leaving): it succeeded, its outputs complete
        assert r.returncode == 0 and r.exit_seconds < 2.0, where
        assert all((folder / name).exists() for name in outputs), where
    assert not temp_files(folder) and not list(folder.rglob("*.tmp")), where
    for name in outputs:
        p = folder / name
        if p.exists() and p.suffix == ".nc":
            read_run(p)  # complete and readable
    for p in folder.rglob("report.pdf"):  # complete documents only
        data = p.read_bytes()
        assert data.startswith(b"%PDF") and b"%%EOF" in data[-64:], where
    for p in folder.rglob("report.html"):
        assert p.read_text(encoding="utf-8").rstrip().endswith("</html>"), where


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_simulate_interrupted_while_writing_its_netcdf(tmp_path, sig):
    """The signal arrives while the netCDF file is being written (its temporary file exists):
    the deadlock of the issue; now an exit within 2 s, nothing left."""
    r = run_and_signal(["simulate", "paper-case1", "-o", "run.nc", "--duration", "2", "-q"],
                       tmp_path, sig, at_temp_file=tmp_path)
    assert r.signalled and r.moment.startswith("while a temporary file"), r
    check_stopped(r, sig, tmp_path, ["run.nc"])
    assert not (tmp_path / "run.nc").exists()


@pytest.mark.parametrize("k", range(3))
def test_simulate_interrupted_at_random_moments(tmp_path, k):
    rng = random.Random(SEED * 100 + k)
    sig = rng.choice([signal.SIGINT, signal.SIGTERM])
    delay = rng.uniform(0.0, 2.5)  # start-up, set-up, integration, write (about 2.5 s in all)
    r = run_and_signal(["simulate", "paper-case1", "-o", "run.nc", "--duration", "1", "-q"],
                       tmp_path, sig, delay=delay)
    print(f"seed {SEED}, {sig.name} after {delay:.3f} s: exit {r.returncode} in "
          f"{r.exit_seconds:.3f} s")
    check_stopped(r, sig, tmp_path, ["run.nc"])


@pytest.fixture(scope="module")
def short_run(tmp_path_factory) -> Path:
    """A short run-up to build reports from."""
    d = tmp_path_factory.mktemp("report-input")
    res = subprocess.run([sys.executable, "-m", "gearvib", "simulate", "paper-case1", "-o",
                          str(d / "case1.nc"), "--duration", "0.25", "-q"], capture_output=True,
                         text=True, check=False)
    assert res.returncode == 0, res.stderr
    return d / "case1.nc"


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_report_interrupted_while_writing_the_pdf(tmp_path, short_run, sig):
    out = tmp_path / "rep"
    out.mkdir()
    r = run_and_signal(["report", str(short_run), "-o", str(out), "-q"], tmp_path, sig,
                       at_temp_file=out, timeout=120)
    assert r.signalled and r.moment.startswith("while a temporary file"), r
    check_stopped(r, sig, tmp_path, ["rep/report.pdf", "rep/report.html"])
    assert not (out / "report.html").exists() and not (out / "report.pdf").exists()


@pytest.mark.parametrize("k", range(3))
def test_report_interrupted_at_a_random_moment(tmp_path, short_run, k):
    rng = random.Random(SEED + 7 + 1000 * k)
    sig = rng.choice([signal.SIGINT, signal.SIGTERM])
    delay = rng.uniform(0.0, 8.0)  # start-up, reading, analysis, PDF and HTML (about 9 s)
    r = run_and_signal(["report", str(short_run), "-o", "rep", "-q"], tmp_path, sig,
                       delay=delay)
    print(f"seed {SEED}, {sig.name} after {delay:.3f} s: exit {r.returncode} in "
          f"{r.exit_seconds:.3f} s")
    check_stopped(r, sig, tmp_path, ["rep/report.pdf", "rep/report.html"])


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_demo_interrupted_while_writing_a_run(tmp_path, sig):
    out = tmp_path / "demo"
    out.mkdir()
    r = run_and_signal(["demo", "-o", str(out), "--duration", "0.2", "-q"], tmp_path, sig,
                       at_temp_file=out)
    assert r.signalled, r
    check_stopped(r, sig, out, ["paper-case1.nc", "paper-case2.nc"])
    assert not (out / "report.html").exists()


def test_demo_interrupted_at_a_random_moment(tmp_path):
    rng = random.Random(SEED + 13)
    sig = rng.choice([signal.SIGINT, signal.SIGTERM])
    delay = rng.uniform(0.0, 3.0)
    r = run_and_signal(["demo", "-o", "demo", "--duration", "0.2", "-q"], tmp_path, sig,
                       delay=delay)
    print(f"seed {SEED}, {sig.name} after {delay:.3f} s: exit {r.returncode} in "
          f"{r.exit_seconds:.3f} s")
    check_stopped(r, sig, tmp_path / "demo" if (tmp_path / "demo").exists() else tmp_path,
                  ["paper-case1.nc", "paper-case2.nc"])


def test_sigkill_leaves_a_recognisable_temp_file_that_the_next_run_removes(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "gearvib", "simulate", "paper-case1", "-o",
                             "run.nc", "--duration", "2", "-q"], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        t0 = time.monotonic()
        while not temp_files(tmp_path, probes=False) and proc.poll() is None and \
                time.monotonic() - t0 < 120:
            time.sleep(0.001)
        proc.kill()
    finally:
        proc.wait()
    left = temp_files(tmp_path)
    assert len(left) == 1, left
    name, host, pid = tempfiles.parse(left[0])
    assert name == "run.nc" and host == tempfiles.host_tag() and pid == proc.pid
    # a live writer's file (this process) and another host's file are kept
    mine = tmp_path / f".other.nc.gearvib-{tempfiles.host_tag()}-{os.getpid()}-abcdef12.tmp"
    remote = tmp_path / ".other.nc.gearvib-otherhost-1-abcdef12.tmp"
    mine.write_bytes(b"x")
    remote.write_bytes(b"x")
    res = subprocess.run([sys.executable, "-m", "gearvib", "simulate", "paper-case1", "-o",
                          "run.nc", "--duration", "0.01", "-q"], cwd=tmp_path,
                         capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stderr
    assert "removed 1 temporary file(s) of killed runs" in res.stderr
    assert not left[0].exists() and mine.exists() and remote.exists()
    read_run(tmp_path / "run.nc")


def test_remove_stale_keeps_live_and_foreign_files(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    pid = int(dead.stdout)  # a process that has exited
    host = tempfiles.host_tag()
    stale = tmp_path / f".a.nc.gearvib-{host}-{pid}-0123abcd.tmp"
    live = tmp_path / f".b.nc.gearvib-{host}-{os.getpid()}-0123abcd.tmp"
    other = tmp_path / f".c.nc.gearvib-elsewhere-{pid}-0123abcd.tmp"
    unrelated = tmp_path / ".d.nc.0123456789abcdef.tmp"
    for p in (stale, live, other, unrelated):
        p.write_bytes(b"")
    folder = tmp_path / f".e.nc.gearvib-{host}-{pid}-4567cdef.tmp"  # of an abandonable write
    folder.mkdir()
    (folder / "e.nc").write_bytes(b"partial")
    assert not tempfiles.pid_alive(pid)
    assert tempfiles.remove_stale(tmp_path) == [stale, folder]
    assert not folder.exists()
    assert live.exists() and other.exists() and unrelated.exists()
    t = tempfiles.temp_path(tmp_path / "run.nc")
    assert tempfiles.parse(t) == ("run.nc", host, os.getpid())


def test_handlers_are_installed_only_while_a_command_runs():
    from gearvib.interrupts import signals_as_exceptions

    before = signal.getsignal(signal.SIGTERM)
    with signals_as_exceptions():
        assert signal.getsignal(signal.SIGTERM) is not before
        assert handlers_installed(os.getpid())
    assert signal.getsignal(signal.SIGTERM) is before


# --------------------------------------------------------------------------------- sweep

SWEEP = ('base = "paper-case1"\n[simulation]\nduration = {duration}\n[[parameter]]\n'
         'path = "meshes.sun.damping_ratio"\nvalues = [0.01, 0.02, 0.03, 0.04]\n'
         '[summary]\norders = [1]\n')


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(x) for x in text.split()]


def _running(pid: int) -> bool:
    """Alive and not a zombie."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    return "\nState:\tZ" not in status


def _sweep_and_signal(folder: Path, sig: int, *, delay: float | None,
                      at_temp_file: bool = False, duration: float = 0.4,
                      extra: tuple[str, ...] = ()) -> tuple[object, list[int]]:
    """``gearvib sweep`` on 2 workers; the signal ``delay`` s after the pool started (or when
    sweep.nc's temporary file appears). Returns the outcome and the pool's worker pids."""
    (folder / "s.toml").write_text(SWEEP.format(duration=duration))
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.Popen([sys.executable, "-m", "gearvib", "sweep", "s.toml", "-o", "out",
                             "--workers", "2", "-q", *extra], cwd=folder, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    workers: list[int] = []
    try:
        t0 = time.monotonic()
        while proc.poll() is None and time.monotonic() - t0 < 120:
            workers = sorted(set(workers) | set(_children(proc.pid)))
            if at_temp_file:
                out = folder / "out"
                if out.is_dir() and any(p.name.startswith(".sweep.nc.") for p in out.iterdir()):
                    break
            elif len(workers) >= 2 and handlers_installed(proc.pid):
                time.sleep(delay or 0.0)
                break
            time.sleep(0.001)
        t_sig = time.monotonic()
        signalled = proc.poll() is None
        if signalled:
            proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
        from tests.cli.signal_helpers import Stopped

        r = Stopped(proc.returncode, time.monotonic() - t_sig, signalled, err,
                    f"{delay} s after the pool started" if not at_temp_file
                    else "while sweep.nc was written")
        return r, workers
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def check_sweep_stopped(r, sig: int, folder: Path, workers: list[int]) -> None:
    """Exit code and time, no temporary file, finished run files complete, no sweep.nc or a
    complete one, no worker left."""
    where = f"({r.moment}; exit {r.returncode} in {r.exit_seconds:.3f} s; stderr " \
            f"{r.stderr.strip()[-300:]!r})"
    out = folder / "out"
    if r.signalled and r.returncode != 0:
        assert r.returncode == EXIT[sig] and r.exit_seconds < 2.0, where
        check_one_line(r.stderr, where)
    else:
        assert r.returncode == 0 and (out / "sweep.nc").is_file(), where
    assert not list(folder.rglob("*.tmp")), (where, list(folder.rglob("*.tmp")))
    for p in sorted((out / "runs").glob("*.nc")) if (out / "runs").is_dir() else []:
        read_run(p)  # finished run files stay (the sweep resumes), each complete
    if (out / "sweep.nc").exists():
        import xarray as xr

        with xr.open_dataset(out / "sweep.nc") as ds:
            assert ds.sizes["case"] == 4, where
    time.sleep(0.2)
    assert not [w for w in workers if _running(w)], (where, workers)


def test_sweep_interrupted_while_its_pool_runs(tmp_path):
    rng = random.Random(SEED * 1000 + 1)
    sig = rng.choice([signal.SIGINT, signal.SIGTERM])
    delay = rng.uniform(0.0, 1.5)  # cases of 0.4 s on 2 workers: about 1.5 s of pool
    r, workers = _sweep_and_signal(tmp_path, sig, delay=delay)
    print(f"seed {SEED}, {sig.name} {delay:.3f} s after the pool started: exit {r.returncode} "
          f"in {r.exit_seconds:.3f} s, workers {workers}")
    assert len(workers) >= 2, r
    check_sweep_stopped(r, sig, tmp_path, workers)


def test_sweep_interrupted_while_writing_sweep_nc(tmp_path):
    sig = random.Random(SEED * 1000 + 2).choice([signal.SIGINT, signal.SIGTERM])
    r, workers = _sweep_and_signal(tmp_path, sig, delay=None, at_temp_file=True,
                                   duration=0.05, extra=("--no-report",))
    assert r.signalled and r.moment == "while sweep.nc was written", r
    check_sweep_stopped(r, sig, tmp_path, workers)
    assert not (tmp_path / "out" / "sweep.nc").exists()
    assert len(list((tmp_path / "out" / "runs").glob("*.nc"))) == 4  # all finished: kept


def test_sweep_killed_leaves_no_worker_and_resumes(tmp_path):
    """SIGKILL of the command: the kernel ends its workers (PR_SET_PDEATHSIG); the next call
    removes their temporary files and reuses the finished runs."""
    r, workers = _sweep_and_signal(tmp_path, signal.SIGKILL, delay=0.5, duration=0.2)
    assert r.returncode == -signal.SIGKILL and len(workers) >= 2, r
    time.sleep(0.3)
    assert not [w for w in workers if _running(w)], workers
    kept = sorted((tmp_path / "out" / "runs").glob("*.nc"))
    res = subprocess.run([sys.executable, "-m", "gearvib", "sweep", "s.toml", "-o", "out",
                          "--workers", "1", "--no-report"], cwd=tmp_path, capture_output=True,
                         text=True, check=False)
    assert res.returncode == 0, res.stderr
    assert f"{len(kept)} reused" in res.stdout, (res.stdout, kept)
    assert not list(tmp_path.rglob("*.tmp"))


@pytest.fixture(scope="module")
def measured_run(tmp_path_factory) -> Path:
    """A short constant-speed 'measurement': paper-case1 with a sun crack, a housing sensor
    and a tacho."""
    d = tmp_path_factory.mktemp("diagnose-input")
    text = subprocess.run([sys.executable, "-m", "gearvib", "preset", "paper-case1"],
                          capture_output=True, text=True, check=True).stdout
    (d / "g.toml").write_text(text + '\n[[fault]]\nkind = "crack"\nmember = "sun"\ntooth = 3\n'
                              'severity = 0.4\n\n[[sensor]]\nname = "acc"\nangle_deg = 90.0\n'
                              'housing_modes = [{ frequency_hz = 3000.0, damping_ratio = 0.02, '
                              'gain = 1.0 }]\n\n[[sensor]]\ntype = "tacho"\nname = "tacho"\n')
    res = subprocess.run([sys.executable, "-m", "gearvib", "simulate", "g.toml", "-o",
                          "meas.nc", "--speed", "1500:1500", "--duration", "1", "--fs", "20000",
                          "-q"], cwd=d, capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stderr
    return d / "meas.nc"


@pytest.mark.parametrize("k", range(2))
def test_diagnose_interrupted_at_a_random_moment(tmp_path, measured_run, k):
    """Candidates simulated on 2 workers, their profiles, the report: any moment."""
    rng = random.Random(SEED * 10 + 3 + k)
    sig = rng.choice([signal.SIGINT, signal.SIGTERM])
    delay = rng.uniform(0.0, 20.0)  # about 25 s in all on 2 cores
    r = run_and_signal(["diagnose", str(measured_run), "--gearset", "paper-case1", "-o", "dg",
                        "--revolutions", "4", "--workers", "2", "-q", "--library", "lib",
                        "--keep-runs"], tmp_path, sig,
                       delay=delay, timeout=300)
    print(f"seed {SEED}, {sig.name} after {delay:.3f} s: exit {r.returncode} in "
          f"{r.exit_seconds:.3f} s")
    check_stopped(r, sig, tmp_path, ["dg/report.pdf", "dg/report.html", "dg/diagnosis.nc"])
    for p in (tmp_path / "dg").rglob("*.nc"):
        if p.name != "diagnosis.nc":
            read_run(p)  # candidate runs that were kept are complete
