"""Small helpers for the wording of report text."""

from __future__ import annotations

__all__ = ["count", "span"]


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


def span(lo: float, hi: float, unit: str = "", digits: int = 0) -> str:
    """A range as printed in a report: ``"1500–3000 min⁻¹"``.

    Ends that print alike are written once (``"1500 min⁻¹"``, never "1500–1500"); ends that
    differ but would print alike at ``digits`` decimals get as many more decimals as they need
    (up to three).

    Parameters
    ----------
    lo, hi : float
        The ends.
    unit : str
        Appended after a space (none when empty).
    digits : int
        Decimals.

    Returns
    -------
    str
    """
    tail = f" {unit}" if unit else ""
    for d in range(digits, digits + 4):
        a, b = f"{lo:.{d}f}", f"{hi:.{d}f}"
        if a != b:
            return f"{a}–{b}{tail}"
    return f"{lo:.{digits}f}{tail}"
