"""The measured record a diagnosis takes: a housing signal with the speed of a shaft."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gearvib.checks import check_array, check_real, check_text, short

__all__ = ["Record"]


@dataclass(frozen=True)
class Record:
    """A housing signal with the speed of a shaft, sample by sample.

    Attributes
    ----------
    signal : numpy.ndarray
        Samples [units].
    fs : float
        Sample rate [Hz].
    speed_rpm : numpy.ndarray
        Speed of ``member`` at every sample [min-1].
    member : str
        The shaft the speed belongs to (default: the gear set's input member).
    units : str
    name : str
    channel : str, optional
        The channel of ``measurement`` the signal is.
    measurement : Measurement, optional
        The measurement the record was taken from (:meth:`from_measurement`): the bearing
        check uses its speed reference (tacho angle, stated speed) as it is.
    """

    signal: np.ndarray
    fs: float
    speed_rpm: np.ndarray
    member: str | None = None
    units: str = "m s-2"
    name: str = "measured"
    channel: str | None = None
    measurement: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_text(self.name, "name")
        w = short(self.name)
        for key in ("member", "channel"):
            check_text(getattr(self, key), f"{w}: {key}", optional=True)
        check_text(self.units, f"{w}: units", empty=True)
        try:
            s = check_array(self.signal, f"{w}: signal", finite=False)
            v = check_array(self.speed_rpm, f"{w}: speed_rpm", finite=False)
        except TypeError as exc:
            raise ValueError(str(exc)) from None
        if s.ndim != 1 or v.shape != s.shape:
            raise ValueError(f"{w}: signal and speed need one value per sample "
                             f"(signal {s.shape}, speed {v.shape})")
        if not np.all(np.isfinite(s)):
            raise ValueError(f"{w}: the signal has non-finite samples")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{w}: the speed has non-finite samples")
        if isinstance(self.fs, bool) or not isinstance(self.fs, int | float | np.integer
                                                        | np.floating):
            raise ValueError(f"{w}: sample rate fs = {short(self.fs)} is not a number")
        fs = check_real(self.fs, f"{w}: sample rate fs [Hz]")
        if not fs > 0:
            raise ValueError(f"{w}: sample rate {self.fs!r} Hz is not admissible "
                             "(admissible: finite, > 0)")
        if self.measurement is not None:
            from analysis.measurement import Measurement

            if not isinstance(self.measurement, Measurement):
                raise TypeError(f"measurement must be an analysis.measurement.Measurement; got "
                                f"{type(self.measurement).__name__}")

    @property
    def duration(self) -> float:
        """Record length [s]."""
        return self.signal.size / self.fs

    @classmethod
    def from_measurement(cls, m: Any, channel: str | None = None, member: str | None = None,
                         name: str = "measured") -> Record:
        """From an :class:`analysis.measurement.Measurement` (its channel and speed).

        ``member``: the shaft whose speed the measurement's reference gives (default: the
        ``member`` attribute of its reference channel, e.g. a simulated tacho's, else the
        gear set's input member).
        """
        x = m.channel(channel)
        t = np.asarray(x["time"].values, float)
        fs = (t.size - 1) / (t[-1] - t[0])
        sp = m.speed_rpm
        rpm = np.interp(t, np.asarray(sp["time"].values, float), np.asarray(sp.values, float))
        if member is None:
            ch = m.source.get("reference_channel")
            if ch and ch in m.signals:
                member = str(m.signals[ch].attrs.get("member", "")) or None
        return cls(np.asarray(x.values, float), float(fs), rpm, member,
                   str(x.attrs.get("units", "1")), name, str(x.name), m)

    def to_measurement(self) -> Any:
        """The record as an :class:`analysis.measurement.Measurement`: the one it was taken
        from, else its signal with its speed (a stated constant speed when the speed does not
        vary, a speed channel otherwise)."""
        if self.measurement is not None:
            return self.measurement
        import xarray as xr

        from analysis.measurement import load_measurement

        t = np.arange(self.signal.size) / self.fs
        ch = self.channel or self.name
        ds = xr.Dataset({ch: ("time", np.asarray(self.signal, float),
                              {"units": self.units, "long_name": f"{self.name} signal"})},
                        coords={"time": ("time", t, {"units": "s", "long_name": "time"})})
        rpm = np.abs(np.asarray(self.speed_rpm, float))
        if float(np.ptp(rpm)) == 0.0:
            return load_measurement(ds, channel=ch, rpm=float(rpm[0]))
        ds["speed"] = ("time", rpm, {"units": "min-1", "long_name": "shaft speed"})
        return load_measurement(ds, channel=ch, speed="speed")
