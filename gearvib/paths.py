"""File-name checks that never raise: a name too long for the file system, or one with a NUL
character, is a file that does not exist (``Path.is_file`` raises ``OSError`` or
``ValueError`` for these)."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["exists", "is_file"]


def is_file(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is a regular file (``False`` for names the system cannot look up)."""
    try:
        return Path(path).is_file()
    except (OSError, ValueError):
        return False


def exists(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` exists (``False`` for names the system cannot look up)."""
    try:
        return Path(path).exists()
    except (OSError, ValueError):
        return False
