"""CF-annotated data without xarray: :class:`PlainDataset`, the content of a run's file.

``gearvib simulate`` writes its run without importing xarray and pandas (0.4 s of a 1 s
command, issue 16): :meth:`gearvib.simulate.RunUpResult.to_plain_dataset` gives the variables
as NumPy arrays with their dimensions and attributes, :func:`gearvib.io.write_netcdf` writes
them with netCDF4 directly, and :meth:`PlainDataset.to_xarray` gives the same
:class:`xarray.Dataset` as before for everything else. The file is the one xarray writes for
``to_xarray()`` (the tests compare the bytes).

Two conventions of :mod:`analysis.cf` are repeated here, because importing any module of
:mod:`analysis` imports xarray (the package registers its accessor): the attributes of the time
coordinate (:func:`time_attrs`) and the suffix of the string-length dimension of a label array
(:data:`STRLEN_SUFFIX`). A test keeps them equal to the originals.

This module imports nothing of gearvib.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["EPOCH", "STRLEN_SUFFIX", "PlainDataset", "PlainVariable", "time_attrs"]

#: Reference of the time axis when the absolute start is not known (as :data:`analysis.cf.EPOCH`).
EPOCH = "1970-01-01T00:00:00Z"
#: Suffix of the string-length dimension of a label array (:data:`analysis.cf.STRLEN_SUFFIX`).
STRLEN_SUFFIX = "_strlen"


def time_attrs(long_name: str) -> dict[str, str]:
    """Attributes of a CF time coordinate of elapsed seconds since :data:`EPOCH`.

    The same as :func:`analysis.cf.time_attrs` without a reference (see there).
    """
    return {
        "units": f"seconds since {EPOCH}",
        "standard_name": "time",
        "axis": "T",
        "calendar": "standard",
        "units_metadata": "leap_seconds: none",
        "long_name": long_name,
    }


@dataclass(frozen=True)
class PlainVariable:
    """One variable: dimension names, a NumPy array of as many dimensions, attributes."""

    dims: tuple[str, ...]
    data: np.ndarray
    attrs: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.data.ndim != len(self.dims):
            raise ValueError(f"{self.data.ndim}-D data with dimensions {self.dims}")


@dataclass(frozen=True)
class PlainDataset:
    """Data variables, coordinates and attributes, in the order of an :class:`xarray.Dataset`.

    Attributes
    ----------
    data_vars, coords : dict of str to PlainVariable
        As the arguments of ``xarray.Dataset(data_vars, coords=coords, attrs=attrs)``; a
        coordinate named after its only dimension is a dimension coordinate (an index).
    attrs : dict
        Global attributes.
    """

    data_vars: dict[str, PlainVariable]
    coords: dict[str, PlainVariable]
    attrs: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        both = set(self.data_vars) & set(self.coords)
        if both:
            raise ValueError(f"names both data variable and coordinate: {sorted(both)}")
        sizes: dict[str, int] = {}
        for name, var in self.variables().items():
            for d, n in zip(var.dims, var.data.shape, strict=True):
                if sizes.setdefault(d, n) != n:
                    raise ValueError(f"variable {name!r}: dimension {d!r} has size {n}, "
                                     f"elsewhere {sizes[d]}")

    def variables(self) -> dict[str, PlainVariable]:
        """Every variable, data variables first (the order of ``xarray.Dataset.variables``)."""
        return {**self.data_vars, **self.coords}

    @property
    def sizes(self) -> dict[str, int]:
        """Dimension sizes, in the order of first use."""
        out: dict[str, int] = {}
        for var in self.variables().values():
            for d, n in zip(var.dims, var.data.shape, strict=True):
                out.setdefault(d, int(n))
        return out

    def to_xarray(self) -> xr.Dataset:
        """The :class:`xarray.Dataset` (arrays shared, attributes copied)."""
        import xarray as xr

        def conv(vs: Mapping[str, PlainVariable]) -> dict[str, xr.Variable]:
            return {k: xr.Variable(v.dims, v.data, dict(v.attrs)) for k, v in vs.items()}

        return xr.Dataset(conv(self.data_vars), coords=conv(self.coords), attrs=dict(self.attrs))
