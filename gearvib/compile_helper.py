"""A first compilation shared between two processes.

The first run on a machine compiles gearvib's numba kernels: about 10 s of CPU, on one core
(numba compiles one function at a time). When numba's cache does not hold them yet and the
machine has a second core, ``gearvib simulate`` and ``gearvib demo`` start a helper process
(``python -m gearvib.compile_helper``) that compiles some of the functions into numba's cache
while the command compiles the others (:func:`share_first_compilation`); the command's first
call of the kernel then loads the helper's functions from the cache. The machine code is the
same, and so are the results, bit for bit: only the first run's wall time drops, by the
helper's share (the CPU time does not).

The command compiles :data:`MAIN_PARTS` (the right-hand side, the set-up functions a run calls
before its kernel, the output functions), the helper :data:`HELPER_PARTS` (the sub-step search
and the RK4 loop, which calls the right-hand side through its address and so compiles without
it) and, for a report, the order analysis of :mod:`analysis.sinc`. The command line starts the
helper first thing (:func:`start`), so that it compiles while the command imports its modules
and checks its inputs, and hands it to :func:`share_first_compilation` before the run; the
report waits for the order analysis if the helper is still compiling it (:func:`await_part`).
The command waits for the helper's parts at most :data:`WAIT_S` seconds each; it compiles
itself what the helper has not delivered by the time it needs it.

The helper runs in a session of its own (a Ctrl-C at the terminal reaches the command only),
prints nothing to the terminal and stops between two parts once the command has ended, so it
outlives the command by one part at most (a few seconds). numba writes each cache file whole
(a temporary file renamed into place). No helper is started with ``GEARVIB_COMPILE_HELPER=0``
in the environment, with one usable core, or when the cache is warm (the command line asks
:func:`gearvib.jit_cache.kernels_cached`).
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path

__all__ = ["ENV_SWITCH", "HELPER_PARTS", "MAIN_PARTS", "ORDER_ANALYSIS", "WAIT_S",
           "CompileHelper", "await_part", "share_first_compilation", "start"]

#: Environment variable: ``0`` starts no helper.
ENV_SWITCH = "GEARVIB_COMPILE_HELPER"
#: Parts of :data:`gearvib.kernels.KERNEL_PARTS` the command compiles itself, after its
#: imports (together about as long as the helper's start and parts: both end together; the
#: set-up functions are cheap here, after the right-hand side's shared pieces).
MAIN_PARTS = ("rhs", "setup", "output")
#: Parts the helper compiles, in this order; then :data:`ORDER_ANALYSIS` when asked.
HELPER_PARTS = ("step_search", "kernel")
#: The helper's part for a report: :func:`analysis.sinc.compile_ahead`.
ORDER_ANALYSIS = "order_analysis"
#: Longest wait [s] for the helper's parts (all of :data:`HELPER_PARTS`, needed before the
#: kernel's first call).
WAIT_S = 60.0


class CompileHelper:
    """A running helper process: which parts it has delivered, and a wait for one.

    Parameters
    ----------
    process : subprocess.Popen
        The helper, its standard output a text pipe (one line per part compiled).
    parts : sequence of str, optional
        The parts it compiles, in order (:meth:`will_deliver`).
    """

    def __init__(self, process: subprocess.Popen, parts: Sequence[str] = ()) -> None:
        self._process = process
        self.parts = tuple(parts)
        self._done: list[str] = []
        self._ended = False
        self._changed = threading.Condition()
        self._reader = threading.Thread(target=self._read, name="gearvib-compile-helper",
                                        daemon=True)
        self._reader.start()

    def _read(self) -> None:
        stream = self._process.stdout
        try:
            if stream is not None:
                for line in stream:
                    with self._changed:
                        self._done.append(line.strip())
                        self._changed.notify_all()
        except (OSError, ValueError):
            pass
        finally:
            with self._changed:
                self._ended = True
                self._changed.notify_all()
            self._process.wait()  # reaped: no zombie left behind

    @property
    def delivered(self) -> tuple[str, ...]:
        """The parts compiled into the cache so far, in order."""
        with self._changed:
            return tuple(self._done)

    @property
    def ended(self) -> bool:
        """Whether the helper has closed its output (finished, failed or stopped)."""
        with self._changed:
            return self._ended

    def will_deliver(self, part: str) -> bool:
        """Whether ``part`` is among the helper's parts and it has not ended before it."""
        with self._changed:
            return part in self.parts and (part in self._done or not self._ended)

    def wait(self, part: str, timeout: float = WAIT_S) -> bool:
        """Wait until the helper has delivered ``part``, has ended, or ``timeout`` [s] passed.

        Returns
        -------
        bool
            Whether ``part`` is in the cache.
        """
        deadline = time.monotonic() + max(0.0, float(timeout))
        with self._changed:
            while part not in self._done and not self._ended:
                left = deadline - time.monotonic()
                if left <= 0.0:
                    break
                self._changed.wait(left)
            return part in self._done


def _cores() -> int:
    """CPU cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def start(order_analysis: bool = False) -> CompileHelper | None:
    """Start a helper that compiles :data:`HELPER_PARTS` (and, with ``order_analysis``, the
    order analysis of a report) into numba's cache.

    Returns
    -------
    CompileHelper or None
        None when no helper is started: ``GEARVIB_COMPILE_HELPER=0``, one usable core, no
        interpreter path, or the process could not be started.
    """
    if os.environ.get(ENV_SWITCH, "").strip() == "0" or _cores() < 2 or not sys.executable:
        return None
    parts = [*HELPER_PARTS, *([ORDER_ANALYSIS] if order_analysis else [])]
    # the helper imports this very gearvib (its cache entries are keyed by the source files)
    root = str(Path(__file__).resolve().parent.parent)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([root, *filter(None, [env.get("PYTHONPATH")])])
    try:
        process = subprocess.Popen(
            [sys.executable, "-m", "gearvib.compile_helper", str(os.getpid()), *parts],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
            env=env, text=True, start_new_session=True, close_fds=True)
    except (OSError, ValueError):
        return None
    return CompileHelper(process, parts)


def share_first_compilation(order_analysis: bool = False,
                            helper: CompileHelper | None = None) -> CompileHelper | None:
    """Compile a run's kernels in two processes: start a helper (:func:`start`) unless one
    is given, compile :data:`MAIN_PARTS` here meanwhile, then wait for :data:`HELPER_PARTS`.

    Call it before the first run of a process whose numba cache is cold; a run afterwards
    takes the helper's parts from the cache. Without a helper it does nothing (the run then
    compiles everything itself, as always).

    Parameters
    ----------
    order_analysis : bool
        The command writes a report: the helper started here also compiles its order
        analysis.
    helper : CompileHelper, optional
        A helper started earlier (:func:`start`: it compiles while the command imports and
        checks its inputs).

    Returns
    -------
    CompileHelper or None
        The helper (still compiling its later parts), or None when none was started.
    """
    if helper is None:
        helper = start(order_analysis)
    if helper is None:
        return None
    from gearvib.kernels import compile_ahead

    for part in MAIN_PARTS:
        compile_ahead(part)
    helper.wait(HELPER_PARTS[-1])  # the parts come in order: the earlier ones are there too
    _SHARED[:] = [helper]
    return helper


_SHARED: list[CompileHelper] = []  # the helper of this process's shared compilation


def await_part(part: str, timeout: float = WAIT_S) -> bool:
    """Wait for ``part`` from the helper of this process's shared compilation, if that helper
    compiles it and is still running: a command about to need it (the report's order analysis,
    :data:`ORDER_ANALYSIS`) then loads it from the cache instead of compiling it a second
    time. Returns at once when there is no such helper.

    Returns
    -------
    bool
        Whether the helper delivered ``part``.
    """
    if not _SHARED or not _SHARED[0].will_deliver(part):
        return False
    return _SHARED[0].wait(part, timeout)


def _compile(part: str) -> None:
    if part == ORDER_ANALYSIS:
        from analysis.sinc import compile_ahead as compile_order_analysis

        compile_order_analysis()
    else:
        from gearvib.kernels import compile_ahead

        compile_ahead(part)


def run_helper(argv: Sequence[str]) -> int:
    """The helper process: ``<parent pid> <part> ...``; compiles each part, prints its name.

    Stops (exit code 0) when the parent has ended or closed the pipe; exit code 1 when a
    part failed to compile (the command then compiles it itself), 2 on bad arguments.
    """
    if len(argv) < 1 or not argv[0].isdigit():
        return 2
    parent = int(argv[0])
    for part in argv[1:]:
        if os.getppid() != parent:  # the command has ended: nothing left to help
            return 0
        try:
            _compile(part)
        except Exception:
            return 1
        try:
            print(part, flush=True)
        except (BrokenPipeError, OSError):
            return 0
    return 0


if __name__ == "__main__":
    from gearvib.cli import prepare_process

    prepare_process(["simulate"])  # the kernels without the analysis package (0.5 s less)
    sys.exit(run_helper(sys.argv[1:]))
