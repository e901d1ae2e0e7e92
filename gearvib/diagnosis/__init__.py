"""Fault-cause investigation: simulation in the loop against a measurement.

==============  =========================================================================
``candidates``  the candidate faults of a gear set (``[[fault]]`` tables with typical sizes)
``bearings``    the declared rolling bearings' faults, judged by their lines (not simulated)
``engine``      :func:`diagnose`: simulate every candidate (sweep machinery), rank them
``report``      HTML/PDF report and netCDF of a diagnosis
==============  =========================================================================

The evidence itself is computed by :mod:`analysis.diagnosis`. User page: ``docs/diagnosis.md``.
"""

from gearvib.diagnosis.candidates import KINDS, Candidate, candidate_faults
from gearvib.diagnosis.engine import ASSUMED_SENSORS, Record, diagnose

__all__ = ["ASSUMED_SENSORS", "KINDS", "Candidate", "Record", "candidate_faults", "diagnose"]
