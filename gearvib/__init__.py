"""gearvib: vibration simulation of planetary gear sets.

The package is layered, and imports flow one way only::

    geometry, kinematics, stiffness  ->  structure, config, memory  ->  assembly  ->  modal
    ->  kernels  ->  simulation/*  ->  simulate, io  ->  report, outputs, cli

``tempfiles`` and ``interrupts`` (temporary-file names, signals, abandonable I/O) import
nothing of gearvib but each other and are used from ``io`` upwards; ``cfdata`` (CF variables as
NumPy arrays, the content of a run's file without xarray) imports nothing of gearvib and is
used from ``simulation`` upwards.

The separate top-level package :mod:`analysis` (spectra, orders, instability) never imports
:mod:`gearvib`.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
