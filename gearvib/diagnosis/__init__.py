"""Fault-cause investigation: simulation in the loop against a measurement.

==============  =========================================================================
``candidates``  the candidate faults of a gear set (``[[fault]]`` tables with typical sizes)
``bearings``    the declared rolling bearings' faults, judged by their lines (not simulated)
``record``      :class:`Record`: the measured housing signal with the speed of a shaft
``lines``       the kinematic lines of the candidate members, in orders of the reference shaft
``engine``      :func:`diagnose`: simulate every candidate (sweep machinery), rank them
``rig``         the diagnosis of a machine without gears (its rolling bearings' lines)
``report``      HTML/PDF report and netCDF of a diagnosis
==============  =========================================================================

The evidence itself is computed by :mod:`analysis.diagnosis`. User page: ``docs/diagnosis.md``.
"""

from gearvib.diagnosis.candidates import KINDS, Candidate, candidate_faults
from gearvib.diagnosis.engine import ASSUMED_SENSORS, diagnose
from gearvib.diagnosis.record import Record

__all__ = ["ASSUMED_SENSORS", "KINDS", "Candidate", "Record", "candidate_faults", "diagnose"]
