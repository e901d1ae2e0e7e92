"""analysis: spectra, order analysis and parametric-instability tools for run-ups.

Works on any :class:`xarray.Dataset` with a ``time`` coordinate (seconds) and a speed or angle
reference, simulated or measured. This package never imports :mod:`gearvib`. Importing it
registers the ``.gearvib`` accessor on Datasets and DataArrays (:mod:`analysis.accessor`).
"""

from analysis import accessor as accessor

__all__: list[str] = ["accessor"]
