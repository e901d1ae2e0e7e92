"""Whether numba's cache holds the simulation kernels for this machine (a first run or not).

The first ``gearvib simulate`` or ``gearvib demo`` on a machine compiles the kernels of
:mod:`gearvib.kernels` (about 10 s of CPU; the first report adds its order analysis); later
runs load them from numba's on-disk cache (:mod:`analysis.jit` chooses its folder). The
command line tells the user before a compilation starts (:func:`first_run_notice`), so a long
first run is not mistaken for a hang.

The test reads numba's cache index of the main kernel
(:func:`gearvib.kernels.integrate_chunk_compiled`): the file
``kernels.integrate_chunk_compiled-<line>.py<version>.nbi`` in the cache folder, as numba
itself loads it (its stamp must match the source file's modification time and size, else numba
ignores it), and looks for an entry compiled for this CPU (numba's codegen "magic tuple":
target triple, CPU name and features). Every kernel of a run is compiled at its first call and
cached in the same folder, so the main kernel stands for all of them; the rarely used ones
(fault passes, the batched kernel) compile on their own first use.

The index is read through numba's cache objects, which are not a public API: if they change,
:func:`kernels_cached` answers ``None`` (unknown) and no notice is printed.
"""

from __future__ import annotations

__all__ = ["FIRST_RUN_NOTICE", "first_run_notice", "kernels_cached"]

FIRST_RUN_NOTICE = (
    "gearvib: compiling the simulation kernels (first run on this machine, about 10-15 s "
    "of CPU; later runs load them from the cache)")
"""The line the command line prints before a run that compiles the kernels."""


def kernels_cached() -> bool | None:
    """Whether numba's cache holds the main simulation kernel compiled for this CPU.

    Returns
    -------
    bool or None
        True: a run loads the kernels from the cache. False: the first run compiles them (no
        index, a stale index, or no entry for this CPU). None: numba's cache objects could not
        be read (another numba version); nothing is known.
    """
    try:
        from gearvib import kernels

        dispatcher = kernels.integrate_chunk_compiled
        if dispatcher.signatures:  # compiled (or loaded) in this process already
            return True
        cache = dispatcher._cache  # numba's private cache objects
        index = cache._cache_file._load_index()  # {} when missing or stale
        magic = dispatcher.targetctx.codegen().magic_tuple()
        return any(isinstance(key, tuple) and len(key) > 1 and key[1] == magic
                   for key in index)
    except Exception:  # numba internals: anything means "unknown"
        return None


def first_run_notice() -> str | None:
    """:data:`FIRST_RUN_NOTICE` when the kernels are not cached for this machine, else None."""
    return FIRST_RUN_NOTICE if kernels_cached() is False else None
