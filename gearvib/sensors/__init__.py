"""Virtual sensors: accelerometers on the housing and a tacho (issue #13).

Descriptions (:mod:`gearvib.sensors.description`): :class:`HousingSensor` (angle on the
housing, transmission-path window, housing modes or a measured FRF) and :class:`Tacho`, built
in Python or from ``[[sensor]]`` tables; add them with ``model.with_sensors([...])`` (or
``gear_set.with_sensors``). A run then stores ``sensor_acceleration(sensor, time)`` [m s-2] and
``tacho(time)`` [V] (:mod:`gearvib.sensors.signal`). Model and keys: ``docs/faults-sensors.md``.
"""

from gearvib.sensors.apply import add_sensors, housing_meshes
from gearvib.sensors.description import (
    WINDOWS,
    HousingMode,
    HousingSensor,
    MeasuredFrf,
    SensorError,
    Tacho,
    sensor_from_dict,
    sensors_from_list,
)
from gearvib.sensors.signal import (
    add_sensor_signals,
    housing_response,
    path_force,
    tacho_signal,
    window_weight,
)

__all__ = [
    "WINDOWS",
    "HousingMode",
    "HousingSensor",
    "MeasuredFrf",
    "SensorError",
    "Tacho",
    "add_sensor_signals",
    "add_sensors",
    "housing_meshes",
    "housing_response",
    "path_force",
    "sensor_from_dict",
    "sensors_from_list",
    "tacho_signal",
    "window_weight",
]
