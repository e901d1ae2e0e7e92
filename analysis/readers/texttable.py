"""Lines of a small numeric text table (FRF files, per-tooth deviations).

A data line is split at ``;`` (decimal commas allowed), else at ``,``, else at white space;
empty lines and lines starting with ``#`` are skipped. What a field means is the caller's.
"""

from __future__ import annotations

from collections.abc import Iterator

__all__ = ["table_lines"]


def table_lines(text: str) -> Iterator[tuple[int, list[str]]]:
    """``(line number, fields)`` of every non-empty, non-comment line of ``text`` (from 1)."""
    if not isinstance(text, str):
        raise TypeError(f"text must be a str; got {type(text).__name__}")
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if ";" in line:
            yield lineno, [x.strip().replace(",", ".") for x in line.split(";")]
        elif "," in line:
            yield lineno, [x.strip() for x in line.split(",")]
        else:
            yield lineno, line.split()
