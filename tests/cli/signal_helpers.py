"""Run a gearvib command in a subprocess and stop it with a signal (for the interrupt tests)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from gearvib import tempfiles

_SIGTERM_BIT = 1 << (signal.SIGTERM - 1)


def handlers_installed(pid: int) -> bool:
    """Whether the process catches SIGTERM (gearvib's handlers are active; Linux /proc)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("SigCgt:"):
                return bool(int(line.split()[1], 16) & _SIGTERM_BIT)
    except (OSError, ValueError):
        return False
    return False


def temp_files(folder: Path, *, probes: bool = True) -> list[Path]:
    """Temporary files in ``folder`` (any naming, hidden ``.tmp`` files); ``probes=False``:
    not the write-test probes of the output checks."""
    return sorted(p for p in folder.iterdir() if p.name.endswith(".tmp") and (
        probes or not p.name.startswith(".write-test.")))


@dataclass
class Stopped:
    """Outcome of :func:`run_and_signal`."""

    returncode: int
    exit_seconds: float  # from the signal to the exit
    signalled: bool  # False: the command ended before the signal was due
    stderr: str
    moment: str


def run_and_signal(argv: list[str], cwd: Path, sig: int, *, delay: float | None = None,
                   at_temp_file: Path | None = None, timeout: float = 120.0) -> Stopped:
    """Start ``python -m gearvib *argv``; send ``sig`` after ``delay`` seconds (counted from
    the moment the handlers are active), or as soon as a temporary file appears in
    ``at_temp_file`` (a write in progress)."""
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.Popen([sys.executable, "-m", "gearvib", *argv], cwd=cwd, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    t_start = time.monotonic()
    try:
        while not handlers_installed(proc.pid):
            if proc.poll() is not None or time.monotonic() - t_start > timeout:
                break
            time.sleep(0.002)
        t_ready = time.monotonic()
        moment = ""
        while proc.poll() is None and time.monotonic() - t_start < timeout:
            if delay is not None and time.monotonic() - t_ready >= delay:
                moment = f"{delay:.3f} s after start-up"
                break
            if at_temp_file is not None and any(
                    (info := tempfiles.parse(p)) and info[0] != "write-test"
                    for p in at_temp_file.iterdir()):
                moment = "while a temporary file was being written"
                break
            time.sleep(0.001)
        if proc.poll() is not None:
            _, err = proc.communicate()
            return Stopped(proc.returncode, 0.0, False, err, "ended before the signal")
        t_sig = time.monotonic()
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=timeout)
        return Stopped(proc.returncode, time.monotonic() - t_sig, True, err, moment)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
