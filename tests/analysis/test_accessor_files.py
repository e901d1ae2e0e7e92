"""The ``.gearvib`` accessor on files reopened by plain ``xarray.open_dataset`` (issue 25).

A plain open decodes the CF time coordinate into ``datetime64[ns]``: every sample is rounded
to 1 ns, so the steps of 1/25600 s (39062.5 ns) alternate between 39062 and 39063 ns. The
accessor accepts such axes (uniform within the step's ``rtol`` plus two quanta) at the common
sample rates and still refuses a gap; it finds a tacho channel as the command line does.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import analysis  # noqa: F401  (registers .gearvib)
from analysis.measurement import load_measurement
from analysis.readers import ChannelData, build_dataset, read_netcdf, write_netcdf

RATES = [25000.0, 25600.0, 44100.0, 48000.0, 51200.0]
ORDER = 7.0
PULSES = 30


def _record(fs: float, seconds: float = 1.0):
    """Order 7 of a shaft run up 1200 -> 1800 min-1, a 30-pulse tacho, a 1 kHz line."""
    t = np.arange(int(seconds * fs)) / fs
    rpm = 1200.0 + 600.0 * t / seconds
    theta = 2 * np.pi * np.cumsum(rpm / 60.0) / fs
    x = np.sin(ORDER * theta) + 0.5 * np.sin(2 * np.pi * 1000.0 * t)
    tacho = np.where((PULSES * theta / (2 * np.pi)) % 1.0 < 0.5, 5.0, 0.0)
    return build_dataset([ChannelData("acc", x, "m s-2"), ChannelData("tacho", tacho, "V")],
                         fs, source_format="test", attrs={"title": "rig"})


@pytest.mark.parametrize("fs", RATES)
def test_plain_reopened_measurement_at_common_rates(fs, tmp_path):
    path = write_netcdf(_record(fs), tmp_path / "rec.nc")
    with xr.open_dataset(path) as plain:
        ds = plain.load()
    assert ds["time"].dtype == np.dtype("datetime64[ns]")
    steps = np.unique(np.diff(ds["time"].values.astype(np.int64)))
    assert steps.size > 1 or fs == 25000.0  # the ns rounding that was refused before
    floats = read_netcdf(path)
    s, ref = ds.gearvib.spectrum("acc", resolution=2.0), floats.gearvib.spectrum(
        "acc", resolution=2.0)
    assert s.fs == pytest.approx(fs, rel=1e-9)
    np.testing.assert_allclose(s.values, ref.values, rtol=1e-6, atol=1e-12)
    assert abs(s.frequency[np.argmax(s.values)] - 1000.0) <= s.bin_spacing_hz
    # the tacho channel is found (a pulse train in V: no units of a speed or an angle)
    r = ds.gearvib.reference()
    assert (r.kind, r.variable) == ("angle", "tacho") and "tacho channel 'tacho'" in r.label
    m = load_measurement(path, pulses_per_rev=PULSES)
    np.testing.assert_allclose(ds.gearvib.reference(pulses_per_rev=PULSES).values,
                               m.angle.values, rtol=0, atol=1e-9)
    osp = ds.gearvib.order_spectrum("acc", pulses_per_rev=PULSES, resolution=0.25)
    assert osp.order[np.argmax(osp.values)] == pytest.approx(ORDER, abs=osp.bin_spacing_orders)
    assert "tacho channel 'tacho'" in osp.to_dataset().attrs["speed_reference"]
    # and on a timedelta64 axis (time since the start)
    td = ds.assign_coords(time=ds["time"] - ds["time"][0])
    assert td["time"].dtype.kind == "m"
    assert td.gearvib.spectrum("acc", resolution=2.0).fs == pytest.approx(fs, rel=1e-9)


def test_a_gap_in_a_decoded_axis_is_still_refused(tmp_path):
    path = write_netcdf(_record(25600.0, 0.5), tmp_path / "rec.nc")
    with xr.open_dataset(path) as plain:
        ds = plain.load()
    gap = ds.drop_isel(time=[6000])  # one sample missing: a step of 2/fs
    with pytest.raises(ValueError, match="not uniformly sampled"):
        gap.gearvib.spectrum("acc")
    slow = ds.isel(time=slice(0, 6000))  # a second segment 0.1 % slower
    t = slow["time"].values
    later = t[-1] + np.round((t[1:] - t[0]).astype(np.int64) * 1.001).astype("timedelta64[ns]")
    joined = xr.concat([slow, slow.isel(time=slice(1, None)).assign_coords(time=later)], "time")
    with pytest.raises(ValueError, match="not uniformly sampled"):
        joined.gearvib.spectrum("acc")


def test_reference_options_are_checked(tmp_path):
    ds = _record(25600.0, 0.5)
    with pytest.raises(ValueError, match="one speed reference"):
        ds.gearvib.order_map("acc", speed="acc", tacho="tacho")
    with pytest.raises(ValueError, match="pulses_per_rev"):
        ds.drop_vars("tacho").gearvib.reference(pulses_per_rev=4)
    with pytest.raises(ValueError, match="'nope' is not a channel"):
        ds.gearvib.order_map("acc", tacho="nope")
    with pytest.raises(ValueError, match="no speed or angle reference"):
        ds.drop_vars("tacho").gearvib.order_map("acc")
    named = ds.rename({"tacho": "TACHO"})  # case-insensitive, as load_measurement
    assert named.gearvib.reference().variable == "TACHO"
