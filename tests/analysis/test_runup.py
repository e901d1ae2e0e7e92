"""Order-locked rays vs frequency-locked vertical lines in a synthetic run-up map."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from analysis.maps import rpm_frequency_map, rpm_order_map
from analysis.runup import map_features, map_levels

FS = 8192.0
T = 8.0


def _runup(rays=(10.0, 23.5), lines=(800.0, 1500.0), seed=1, noise=0.05, rpm=(600.0, 3000.0)):
    t = np.arange(int(FS * T)) / FS
    speed = rpm[0] + (rpm[1] - rpm[0]) * t / T
    phase = 2 * np.pi * np.cumsum(speed / 60.0) / FS
    rng = np.random.default_rng(seed)
    x = noise * rng.normal(size=t.size)
    for k, o in enumerate(rays):
        x += (1.0 if k == 0 else 0.5) * np.sin(o * phase + k)
    for f0 in lines:  # structural resonances excited by broadband noise
        b, a = scipy.signal.iirpeak(f0, 60.0, FS)
        x += 3.0 * scipy.signal.lfilter(b, a, rng.normal(size=t.size))
    m = rpm_frequency_map(x, FS, speed, resolution=4.0, window="hann", overlap=0.5,
                          amplitude="rms")
    return m.to_dataset()


def test_rays_and_vertical_lines_are_separated():
    feat = map_features(_runup())
    assert feat.orders == pytest.approx([10.0, 23.5], abs=0.05)
    assert feat.frequencies == pytest.approx([800.0, 1500.0], abs=4.0)
    assert np.all(feat.order_prominence_db > 6) and np.all(feat.frequency_prominence_db > 6)
    ds = feat.to_dataset()
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    from matplotlib.figure import Figure

    assert isinstance(feat.plot(), Figure)


@pytest.mark.parametrize(("rays", "lines"), [((10.0,), ()), ((), (1200.0,)), ((), ())])
def test_only_what_is_there(rays, lines):
    """A map with only rays has no vertical lines, and vice versa; noise has neither."""
    feat = map_features(_runup(rays=rays, lines=lines, seed=5))
    assert feat.orders == pytest.approx(list(rays), abs=0.05)
    assert feat.frequencies == pytest.approx(list(lines), abs=4.0)


def test_order_map_gives_the_same_features():
    t = np.arange(int(FS * T)) / FS
    speed = 600.0 + 2400.0 * t / T
    phase = 2 * np.pi * np.cumsum(speed / 60.0) / FS
    rng = np.random.default_rng(2)
    x = np.sin(10.0 * phase) + 0.5 * np.sin(23.5 * phase + 1) + 0.05 * rng.normal(size=t.size)
    for f0 in (800.0, 1500.0):
        b, a = scipy.signal.iirpeak(f0, 60.0, FS)
        x += 3.0 * scipy.signal.lfilter(b, a, rng.normal(size=t.size))
    # samples_per_rev 2 ceil(fs / 2 / 50 Hz) = 164, the sampling this test was written for
    # (given max_order alone, the default is now 2 ceil(1.28 max_order) = 154)
    om = rpm_order_map(x, FS, speed, resolution=0.1, window="hann", overlap=0.5,
                       max_order=60.0, samples_per_rev=164)
    feat = map_features(om.to_dataset())
    assert feat.orders == pytest.approx([10.0, 23.5], abs=0.05)
    assert feat.frequencies == pytest.approx([800.0, 1500.0], abs=8.0)


def test_constant_speed_cannot_separate_and_layout_errors():
    ds = _runup(rpm=(1500.0, 1600.0))
    with pytest.raises(ValueError, match="too narrow"):
        map_features(ds)
    with pytest.raises(ValueError, match="no data variable"):
        map_features(ds.rename({"amplitude": "level"}))
    with pytest.raises(ValueError, match="rpm"):
        map_features(ds.drop_vars("rpm"))
    with pytest.raises(ValueError, match="quantile"):
        map_features(_runup(), quantile=1.5)
    lv = map_levels(ds)
    assert lv.axis_name == "frequency" and lv.level.shape == (lv.time.size, lv.axis.size)
    assert lv.frame_duration == pytest.approx(ds.attrs["segment_length"] / FS)
    # a ray's width grows with its sweep inside one frame
    w = lv.ray_half_width(np.array([1.0, 10.0]))
    assert np.all(w[1] > w[0]) and np.all(w[0] >= 0.5 * lv.resolution)
