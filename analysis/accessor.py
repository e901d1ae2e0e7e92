"""The ``.gearvib`` accessor on xarray Datasets and DataArrays: spectra, maps and order analysis.

Registered when :mod:`analysis` is imported. Following xarray's advice on extending it
("Extending xarray using accessors": composition over inheritance, one namespace per library,
an ``__init__`` that takes only the object), the accessor keeps no state beyond the object and
forwards to the functions of :mod:`analysis.spectrum`, :mod:`analysis.maps` and
:mod:`analysis.orders`, so every keyword of those functions works here too::

    import analysis  # registers .gearvib
    ds.gearvib.order_map("acceleration")                 # all channels, reference found
    ds.gearvib.order_cuts("acceleration", [3, 7], speed="shaft_speed")
    ds["acceleration"].sel(channel="ring_x").gearvib.spectrum(resolution=2.0)

The speed reference is the variable named by ``speed=`` or ``angle=``, or the tacho (pulse)
channel named by ``tacho=`` (``pulses_per_rev=``, default its ``pulses_per_rev`` attribute,
else 1), or else the one the command line would use (:func:`analysis.measurement.
reference_channel`): a channel named ``tacho``, else one named ``speed`` or ``rpm``, else the
one found by its attributes (:func:`analysis.inputs.find_reference`: an angle in ``rad`` wins
over a speed in ``min-1``). A tacho gives the shaft angle (:func:`analysis.speed.from_tacho`).
For a DataArray the reference must be one of its coordinates along ``time`` (``ds["x"]``
keeps the Dataset's auxiliary coordinates along time).

The time axis may be float seconds or decoded (``datetime64``/``timedelta64``, what a plain
``xarray.open_dataset`` gives for a CF time coordinate): it is used from its first sample, and
its uniformity is checked relative to the step within the resolution of the decoded axis
(:func:`analysis.checks.uniform_rate`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

if TYPE_CHECKING:  # the methods import their modules when called: `import analysis` stays light
    from analysis.inputs import Reference
    from analysis.maps import OverallLevel, RpmFrequencyMap, RpmOrderMap
    from analysis.orders import OrderCut, OrderSpectrum
    from analysis.spectrum import Spectrum

__all__ = ["ACCESSOR", "DataArrayAccessor", "DatasetAccessor"]

#: Name of the accessor on Datasets and DataArrays.
ACCESSOR = "gearvib"


def _reference(obj: Any, speed: str | None, angle: str | None,
               options: dict[str, Any]) -> tuple[Reference, bool]:
    """The speed reference of ``obj`` and whether it comes from a tacho: named (``speed``,
    ``angle``, or ``tacho`` in ``options``, which loses it and ``pulses_per_rev``) or chosen
    as :func:`analysis.measurement.load_measurement` chooses it."""
    from analysis.inputs import Reference, find_reference

    tacho = options.pop("tacho", None)
    ppr = options.pop("pulses_per_rev", None)
    if tacho is not None and (speed is not None or angle is not None):
        raise ValueError("give one speed reference: speed=, angle= or tacho=")
    if ppr is not None and (speed is not None or angle is not None):
        raise ValueError("pulses_per_rev applies to a tacho channel, not to speed=/angle=")
    if speed is not None or angle is not None:
        return find_reference(obj, speed=speed, angle=angle), False
    from analysis.measurement import reference_channel, tacho_reference

    found = ("tacho", tacho) if tacho is not None else reference_channel(obj)
    if found is None or found[0] != "tacho":
        if ppr is not None:
            raise ValueError("pulses_per_rev applies to a tacho channel; none is named 'tacho' "
                             "(give tacho=<channel>)")
        if found is None:
            return find_reference(obj), False  # its message names the options
        return find_reference(obj, **{found[0]: found[1]}), False
    from analysis.cf import elapsed_seconds
    from analysis.checks import uniform_rate

    if "time" not in obj.coords:
        raise ValueError("a tacho reference needs a 'time' coordinate")
    raw = obj["time"].values
    fs = uniform_rate(raw, "time")  # float seconds or a decoded axis, within its resolution
    t0 = float(elapsed_seconds(raw)[0])
    t = t0 + np.arange(raw.size) / fs  # uniform: a decoded axis is rounded to 1 ns
    sref, text = tacho_reference(obj, found[1], ppr, t)
    return Reference("angle", np.asarray(sref.angle, dtype=float), text, found[1]), True


def _ref_kwargs(obj: Any, speed: str | None, angle: str | None,
                options: dict[str, Any]) -> dict[str, Any]:
    """``{"rpm": DataArray}`` or ``{"angle": DataArray}`` for the analysis functions; removes
    ``tacho`` and ``pulses_per_rev`` from ``options``."""
    ref, from_tacho = _reference(obj, speed, angle, options)
    if from_tacho:  # the shaft angle from the pulses, on obj's time
        return {"angle": xr.DataArray(ref.values, dims="time", coords={"time": obj["time"]},
                                      name=f"angle from {ref.label}", attrs={"units": "rad"})}
    return {ref.kind: obj[ref.variable]}


class DataArrayAccessor:
    """Spectra, maps and order analysis of a DataArray with a ``time`` dimension.

    Parameters
    ----------
    obj : xarray.DataArray
        Signal with a uniform ``time`` coordinate [s]; any other dimension (e.g. ``channel``)
        is carried through to the result.
    """

    def __init__(self, obj: xr.DataArray) -> None:
        self._obj = obj

    def reference(self, speed: str | None = None, angle: str | None = None, *,
                  tacho: str | None = None, pulses_per_rev: int | None = None) -> Reference:
        """The speed reference that order analysis would use (named or found, see the module
        notes; a tacho gives the shaft angle)."""
        return _reference(self._obj, speed, angle,
                          {"tacho": tacho, "pulses_per_rev": pulses_per_rev})[0]

    def spectrum(self, **kwargs: Any) -> Spectrum:
        """:func:`analysis.spectrum.spectrum` of the array."""
        from analysis.spectrum import spectrum

        return spectrum(self._obj, **kwargs)

    def frequency_map(
        self, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> RpmFrequencyMap:
        """:func:`analysis.maps.rpm_frequency_map` against a speed or angle coordinate."""
        from analysis.maps import rpm_frequency_map

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return rpm_frequency_map(self._obj, **ref, **kwargs)

    def order_map(
        self, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> RpmOrderMap:
        """:func:`analysis.maps.rpm_order_map` against a speed or angle coordinate."""
        from analysis.maps import rpm_order_map

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return rpm_order_map(self._obj, **ref, **kwargs)

    def order_cuts(
        self, orders: Any, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OrderCut:
        """:func:`analysis.orders.order_cuts` of ``orders``."""
        from analysis.orders import order_cuts

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return order_cuts(self._obj, orders=orders, **ref, **kwargs)

    def order_spectrum(
        self, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OrderSpectrum:
        """:func:`analysis.orders.order_spectrum` against a speed or angle coordinate."""
        from analysis.orders import order_spectrum

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return order_spectrum(self._obj, **ref, **kwargs)

    def overall_level(
        self, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OverallLevel:
        """:func:`analysis.maps.overall_level` against a speed or angle coordinate."""
        from analysis.maps import overall_level

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return overall_level(self._obj, **ref, **kwargs)


class DatasetAccessor:
    """Spectra, maps and order analysis of the variables of a Dataset.

    Every method takes the name of the analysed variable first; the speed reference is any
    variable or coordinate of the Dataset along ``time``.

    Parameters
    ----------
    obj : xarray.Dataset
        Recording or simulated run with a uniform ``time`` coordinate [s].
    """

    def __init__(self, obj: xr.Dataset) -> None:
        self._obj = obj

    def reference(self, speed: str | None = None, angle: str | None = None, *,
                  tacho: str | None = None, pulses_per_rev: int | None = None) -> Reference:
        """The speed reference that order analysis would use (named or found, see the module
        notes; a tacho gives the shaft angle)."""
        return _reference(self._obj, speed, angle,
                          {"tacho": tacho, "pulses_per_rev": pulses_per_rev})[0]

    def _var(self, variable: str) -> xr.DataArray:
        from analysis.inputs import dataset_variable

        return dataset_variable(self._obj, variable)

    def spectrum(self, variable: str, **kwargs: Any) -> Spectrum:
        """:func:`analysis.spectrum.spectrum` of ``ds[variable]``."""
        from analysis.spectrum import spectrum

        return spectrum(self._var(variable), **kwargs)

    def frequency_map(
        self, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> RpmFrequencyMap:
        """:func:`analysis.maps.rpm_frequency_map` of ``ds[variable]``."""
        from analysis.maps import rpm_frequency_map

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return rpm_frequency_map(self._var(variable), **ref, **kwargs)

    def order_map(
        self, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> RpmOrderMap:
        """:func:`analysis.maps.rpm_order_map` of ``ds[variable]``."""
        from analysis.maps import rpm_order_map

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return rpm_order_map(self._var(variable), **ref, **kwargs)

    def order_cuts(
        self,
        variable: str,
        orders: Any,
        speed: str | None = None,
        *,
        angle: str | None = None,
        **kwargs: Any,
    ) -> OrderCut:
        """:func:`analysis.orders.order_cuts` of ``ds[variable]``."""
        from analysis.orders import order_cuts

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return order_cuts(self._var(variable), orders=orders, **ref, **kwargs)

    def order_spectrum(
        self, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OrderSpectrum:
        """:func:`analysis.orders.order_spectrum` of ``ds[variable]``."""
        from analysis.orders import order_spectrum

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return order_spectrum(self._var(variable), **ref, **kwargs)

    def overall_level(
        self, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OverallLevel:
        """:func:`analysis.maps.overall_level` of ``ds[variable]``."""
        from analysis.maps import overall_level

        ref = _ref_kwargs(self._obj, speed, angle, kwargs)
        return overall_level(self._var(variable), **ref, **kwargs)


def register() -> None:
    """Register the accessors (done once when :mod:`analysis` is imported)."""
    if not hasattr(xr.Dataset, ACCESSOR):
        xr.register_dataset_accessor(ACCESSOR)(DatasetAccessor)
    if not hasattr(xr.DataArray, ACCESSOR):
        xr.register_dataarray_accessor(ACCESSOR)(DataArrayAccessor)


register()
