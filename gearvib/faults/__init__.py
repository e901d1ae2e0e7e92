"""Local tooth faults and manufacturing errors of a gear set (issue #13).

Descriptions (:mod:`gearvib.faults.description`): :class:`Crack`, :class:`Pitting`,
:class:`BrokenTooth`, :class:`Eccentricity`, :class:`PitchError`, :class:`PinError`,
:class:`PlanetBacklash`, built in Python or from ``[[fault]]`` tables
(:func:`fault_from_dict`). Add them to a gear set or an assembled model with
``gear_set.with_faults([...])`` / ``model.with_faults([...])``; a run applies them
(:mod:`gearvib.faults.law`: the tooth pairs in contact follow from the rotation angles,
:mod:`gearvib.teeth`). Model and keys: ``docs/faults-sensors.md``.

Example::

    from gearvib.faults import Crack, Eccentricity
    faulty = model.with_faults([Crack("sun", tooth=3, severity=0.3),
                                {"kind": "eccentricity", "member": "sun",
                                 "eccentricity": 20e-6}])
"""

from gearvib.faults.apply import add_faults, fault_targets, mesh_lines
from gearvib.faults.description import (
    FAULT_KINDS,
    BrokenTooth,
    Crack,
    Eccentricity,
    Fault,
    FaultError,
    PairCurve,
    PinError,
    PitchError,
    Pitting,
    PlanetBacklash,
    fault_from_dict,
    faults_from_list,
)
from gearvib.faults.law import FaultLaw, build_fault_law

__all__ = [
    "FAULT_KINDS",
    "BrokenTooth",
    "Crack",
    "Eccentricity",
    "Fault",
    "FaultError",
    "FaultLaw",
    "PairCurve",
    "PinError",
    "PitchError",
    "Pitting",
    "PlanetBacklash",
    "add_faults",
    "build_fault_law",
    "fault_from_dict",
    "fault_targets",
    "faults_from_list",
    "mesh_lines",
]
