"""gearvib: vibration simulation of planetary gear sets.

The package is layered, and imports flow one way only::

    geometry, kinematics, stiffness  ->  structure, config  ->  assembly  ->  modal
    ->  kernels  ->  simulation/*  ->  simulate, io  ->  report, cli

The separate top-level package :mod:`analysis` (spectra, orders, instability) never imports
:mod:`gearvib`.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
