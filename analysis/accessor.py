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

The speed reference is the variable named by ``speed=`` or ``angle=``, or else the one found
by its attributes (:func:`analysis.inputs.find_reference`: an angle in ``rad`` wins over a
speed in ``min-1``). For a DataArray the reference must be one of its coordinates along
``time`` (``ds["x"]`` keeps the Dataset's auxiliary coordinates along time).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import xarray as xr

if TYPE_CHECKING:  # the methods import their modules when called: `import analysis` stays light
    from analysis.inputs import Reference
    from analysis.maps import OverallLevel, RpmFrequencyMap, RpmOrderMap
    from analysis.orders import OrderCut, OrderSpectrum
    from analysis.spectrum import Spectrum

__all__ = ["ACCESSOR", "DataArrayAccessor", "DatasetAccessor"]

#: Name of the accessor on Datasets and DataArrays.
ACCESSOR = "gearvib"


def _ref_kwargs(obj: Any, speed: str | None, angle: str | None) -> dict[str, Any]:
    from analysis.inputs import find_reference

    ref = find_reference(obj, speed=speed, angle=angle)
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

    def reference(self, speed: str | None = None, angle: str | None = None) -> Reference:
        """The speed reference that order analysis would use (named or found)."""
        from analysis.inputs import find_reference

        return find_reference(self._obj, speed=speed, angle=angle)

    def spectrum(self, **kwargs: Any) -> Spectrum:
        """:func:`analysis.spectrum.spectrum` of the array."""
        from analysis.spectrum import spectrum

        return spectrum(self._obj, **kwargs)

    def frequency_map(
        self, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> RpmFrequencyMap:
        """:func:`analysis.maps.rpm_frequency_map` against a speed or angle coordinate."""
        from analysis.maps import rpm_frequency_map

        return rpm_frequency_map(self._obj, **_ref_kwargs(self._obj, speed, angle), **kwargs)

    def order_map(
        self, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> RpmOrderMap:
        """:func:`analysis.maps.rpm_order_map` against a speed or angle coordinate."""
        from analysis.maps import rpm_order_map

        return rpm_order_map(self._obj, **_ref_kwargs(self._obj, speed, angle), **kwargs)

    def order_cuts(
        self, orders: Any, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OrderCut:
        """:func:`analysis.orders.order_cuts` of ``orders``."""
        from analysis.orders import order_cuts

        ref = _ref_kwargs(self._obj, speed, angle)
        return order_cuts(self._obj, orders=orders, **ref, **kwargs)

    def order_spectrum(
        self, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OrderSpectrum:
        """:func:`analysis.orders.order_spectrum` against a speed or angle coordinate."""
        from analysis.orders import order_spectrum

        return order_spectrum(self._obj, **_ref_kwargs(self._obj, speed, angle), **kwargs)

    def overall_level(
        self, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OverallLevel:
        """:func:`analysis.maps.overall_level` against a speed or angle coordinate."""
        from analysis.maps import overall_level

        return overall_level(self._obj, **_ref_kwargs(self._obj, speed, angle), **kwargs)


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

    def reference(self, speed: str | None = None, angle: str | None = None) -> Reference:
        """The speed reference that order analysis would use (named or found)."""
        from analysis.inputs import find_reference

        return find_reference(self._obj, speed=speed, angle=angle)

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

        return rpm_frequency_map(
            self._var(variable), **_ref_kwargs(self._obj, speed, angle), **kwargs
        )

    def order_map(
        self, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> RpmOrderMap:
        """:func:`analysis.maps.rpm_order_map` of ``ds[variable]``."""
        from analysis.maps import rpm_order_map

        return rpm_order_map(self._var(variable), **_ref_kwargs(self._obj, speed, angle), **kwargs)

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

        ref = _ref_kwargs(self._obj, speed, angle)
        return order_cuts(self._var(variable), orders=orders, **ref, **kwargs)

    def order_spectrum(
        self, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OrderSpectrum:
        """:func:`analysis.orders.order_spectrum` of ``ds[variable]``."""
        from analysis.orders import order_spectrum

        return order_spectrum(
            self._var(variable), **_ref_kwargs(self._obj, speed, angle), **kwargs
        )

    def overall_level(
        self, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
    ) -> OverallLevel:
        """:func:`analysis.maps.overall_level` of ``ds[variable]``."""
        from analysis.maps import overall_level

        return overall_level(self._var(variable), **_ref_kwargs(self._obj, speed, angle), **kwargs)


def register() -> None:
    """Register the accessors (done once when :mod:`analysis` is imported)."""
    if not hasattr(xr.Dataset, ACCESSOR):
        xr.register_dataset_accessor(ACCESSOR)(DatasetAccessor)
    if not hasattr(xr.DataArray, ACCESSOR):
        xr.register_dataarray_accessor(ACCESSOR)(DataArrayAccessor)


register()
