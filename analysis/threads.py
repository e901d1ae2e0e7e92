"""One BLAS/OpenMP thread for serial work, without finding the libraries at every call.

Serial work (a run-up, a sweep case, a chunk of a stability chart) runs with one BLAS/OpenMP
thread: its small linear algebra gains nothing from more, a pool of workers would be
oversubscribed, and OpenBLAS's idle threads would spin on another core after every call.
``threadpoolctl.threadpool_limits`` finds the loaded BLAS and OpenMP libraries anew at each
call (it reads the process's memory map and opens every matching library): measured 0.8 ms
in a plain NumPy/SciPy process and about 2 ms once numba, netCDF and the rest are loaded,
as much as the whole set-up of a short run-up. :func:`one_blas_thread` keeps one
``ThreadpoolController`` per process and only sets and restores the limits (10 µs).

The controller knows the libraries loaded when it was made. NumPy's and SciPy's BLAS are
loaded before it is made; it is made again whenever more modules have been imported since
(a module that loads another BLAS or OpenMP runtime is an import), so a steady loop of runs
finds the libraries once. A forked worker inherits it with its parent's libraries, which are
the worker's too.
"""

from __future__ import annotations

import sys
import threading
from typing import Any

__all__ = ["one_blas_thread"]

_lock = threading.Lock()
_controller: Any = None
_modules_seen = -1


def _current_controller() -> Any:
    """The process's ``ThreadpoolController``, made again if modules were imported since."""
    global _controller, _modules_seen
    with _lock:
        if _controller is None or len(sys.modules) != _modules_seen:
            import scipy.linalg  # noqa: F401  (SciPy's BLAS loaded before the libraries are found)
            from threadpoolctl import ThreadpoolController  # on demand: ~15 ms of imports

            _controller = ThreadpoolController()
            _modules_seen = len(sys.modules)
        return _controller


def one_blas_thread() -> Any:
    """A context manager: one thread in every BLAS and OpenMP library of the process while
    it is entered, the previous limits restored on exit (``threadpoolctl``)."""
    return _current_controller().limit(limits=1)
