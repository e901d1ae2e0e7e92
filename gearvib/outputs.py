"""Output files of the command line: checked before the work starts, one overwrite rule.

The rule (every command): an output file that already exists is **not** replaced unless
``--overwrite`` is given -- a long simulation's result is never lost to a repeated command
or a typo -- and with ``--overwrite`` it is replaced atomically, only once the new file is
complete. Everything that can fail about an output (a directory given as a file name, a
missing or unwritable folder, an existing file) is checked before any computation; stale
temporary files of killed runs in the output folder are removed first
(:func:`gearvib.tempfiles.remove_stale`).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterable, Iterator
from pathlib import Path

from gearvib import tempfiles

__all__ = ["OutputError", "check_output_file", "check_output_folder", "removed_if_left_empty"]


class OutputError(OSError):
    """An output cannot be written (exists, is a directory, folder missing or unwritable)."""


def _probe(folder: Path) -> None:
    """Create and remove a temporary file in ``folder`` (its name follows the temp pattern)."""
    probe = tempfiles.temp_path(folder / "write-test")
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
    except OSError as exc:
        raise OutputError(f"output folder {str(folder)!r} is not writable "
                          f"({exc.strerror or type(exc).__name__})") from None
    with contextlib.suppress(OSError):
        probe.unlink()


def check_output_file(path: str | os.PathLike, *, overwrite: bool) -> tuple[Path, list[Path]]:
    """Check an output file before the work starts.

    Parameters
    ----------
    path : path-like
        The file to write.
    overwrite : bool
        Whether an existing file may be replaced.

    Returns
    -------
    (Path, list of Path)
        The path, and the stale temporary files removed from its folder.

    Raises
    ------
    OutputError
        The path is a directory, its folder is missing or not writable, or the file exists
        and ``overwrite`` is false.
    """
    p = Path(path)
    if str(path).endswith(os.sep) or p.is_dir():
        raise OutputError(f"output {str(p)!r} is a directory: give a file name such as "
                          f"{str(p / 'run.nc')!r}")
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"output folder {str(folder)!r} does not exist")
    if not os.access(folder, os.W_OK):
        raise OutputError(f"output folder {str(folder)!r} is not writable")
    if p.exists() or p.is_symlink():
        if not overwrite:
            raise OutputError(f"output {str(p)!r} exists; add --overwrite to replace it (or "
                              "choose another name)")
        if not p.is_file():
            raise OutputError(f"output {str(p)!r} exists and is not a regular file")
    removed = tempfiles.remove_stale(folder)
    _probe(folder)
    return p, removed


def check_output_folder(folder: str | os.PathLike, names: Iterable[str], *, overwrite: bool
                        ) -> tuple[Path, list[Path]]:
    """Check an output folder and the files a command will write into it.

    The folder itself may be missing (it is created by the command); when it exists, none of
    ``names`` may exist in it unless ``overwrite``.

    Returns
    -------
    (Path, list of Path)
        The folder, and the stale temporary files removed from it.

    Raises
    ------
    OutputError
        The folder is a file, or holds outputs of an earlier run and ``overwrite`` is false.
    """
    d = Path(folder)
    if d.exists() and not d.is_dir():
        raise OutputError(f"output folder {str(d)!r} exists and is not a directory")
    removed: list[Path] = []
    if d.is_dir():
        existing = [n for n in names if (d / n).exists() or (d / n).is_symlink()]
        if existing and not overwrite:
            shown = ", ".join(existing[:4]) + (", ..." if len(existing) > 4 else "")
            raise OutputError(f"output folder {str(d)!r} holds outputs of an earlier run "
                              f"({shown}); add --overwrite to replace them (or choose another "
                              "folder with -o)")
        for n in existing:
            if (d / n).is_dir():
                raise OutputError(f"output {str(d / n)!r} is a directory")
        removed = tempfiles.remove_stale(d)
    return d, removed


@contextlib.contextmanager
def removed_if_left_empty(folder: str | os.PathLike) -> Iterator[Path]:
    """An output folder that the block creates is removed again if the block fails (an error
    or an interrupt) before writing any file into it: with the empty folders the block made
    inside it (a diagnosis's ``candidates/runs``); a folder holding a file is kept."""
    d = Path(folder)
    existed = d.exists()
    try:
        yield d
    except BaseException:
        if not existed and d.is_dir() and not d.is_symlink():
            for root, _, _ in os.walk(d, topdown=False):  # deepest first; rmdir: empty only
                with contextlib.suppress(OSError):
                    Path(root).rmdir()
        raise
