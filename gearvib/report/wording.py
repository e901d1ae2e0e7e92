"""Small helpers for the wording of report text."""

from __future__ import annotations

__all__ = ["count"]


def count(n: int, singular: str, plural: str | None = None) -> str:
    """A number with its noun in the right number: ``count(1, "region")`` is ``"1 region"``.

    Parameters
    ----------
    n : int
        How many.
    singular : str
        The noun (with any adjectives before it) for one.
    plural : str, optional
        The noun for zero or several (default: ``singular + "s"``).

    Returns
    -------
    str
        ``"1 region"``, ``"0 regions"``, ``"3 regions"``.
    """
    return f"{n} {singular if n == 1 else (plural or singular + 's')}"
