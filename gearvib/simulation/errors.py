"""The exception of a failed run-up simulation."""

from __future__ import annotations

__all__ = ["SimulationError"]


class SimulationError(RuntimeError):
    """The integration failed (numerical blow-up or no static equilibrium)."""
