"""analysis.measurement: channels and a speed reference from files, Datasets and runs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from analysis.measurement import Measurement, load_measurement
from analysis.readers import ChannelData, ReaderError, build_dataset, write_csv, write_netcdf

FS = 5000.0
N = 10000  # 2 s


def ramp_angle(t: np.ndarray, n0: float = 600.0, n1: float = 1800.0) -> np.ndarray:
    """Angle [rad] of a linear run-up n0 -> n1 min-1 over the record."""
    dur = t[-1]
    return 2 * np.pi / 60 * (n0 * t + 0.5 * (n1 - n0) / dur * t**2)


def tacho_train(angle: np.ndarray, ppr: int) -> np.ndarray:
    return np.where((ppr * angle / (2 * np.pi)) % 1.0 < 0.5, 5.0, 0.0)


def layout(extra: dict | None = None, ppr: int = 10) -> xr.Dataset:
    t = np.arange(N) / FS
    th = ramp_angle(t)
    chans = [ChannelData("acc", np.sin(20 * th), "m s-2", "accelerometer"),
             ChannelData("tacho", tacho_train(th, ppr), "V", "tacho")]
    for name, (values, units) in (extra or {}).items():
        chans.append(ChannelData(name, values, units))
    return build_dataset(chans, FS, source_format="test")


def exact_rpm(t: np.ndarray) -> np.ndarray:
    return 600.0 + 1200.0 * t / t[-1]


def test_tacho_channel_found_by_name_gives_the_speed() -> None:
    m = load_measurement(layout(), pulses_per_rev=10)
    assert isinstance(m, Measurement)
    assert m.vibration_channels == ("acc",)
    assert m.channel().name == "acc" and m.channel().attrs["units"] == "m s-2"
    assert "tacho channel 'tacho'" in m.reference and "10 pulses/rev" in m.reference
    t = m.time
    inner = (t > 0.1) & (t < t[-1] - 0.1)
    np.testing.assert_allclose(m.speed_rpm.values[inner], exact_rpm(t)[inner], rtol=2e-3)
    assert m.speed_rpm.attrs["units"] == "min-1"
    assert m.angle is not None and m.angle.attrs["units"] == "rad"
    ds = m.to_dataset()
    assert {"acc", "tacho", "reference_speed", "reference_angle"} <= set(ds.data_vars)
    assert ds["reference_speed"].attrs["units"] == "min-1"
    assert "tacho" in ds.attrs["speed_reference"]


def test_pulses_per_rev_from_the_channel_attribute_and_the_wrong_count() -> None:
    ds = layout(ppr=4)
    ds["tacho"].attrs["pulses_per_rev"] = 4
    m = load_measurement(ds)
    assert "4 pulses/rev (from the channel's attributes)" in m.reference
    t = m.time
    inner = (t > 0.2) & (t < t[-1] - 0.2)
    np.testing.assert_allclose(m.speed_rpm.values[inner], exact_rpm(t)[inner], rtol=5e-3)
    # a wrong count scales the speed (nothing guesses it): 1 pulse/rev reads 4x the speed
    m1 = load_measurement(ds, pulses_per_rev=1)
    np.testing.assert_allclose(m1.speed_rpm.values[inner], 4 * m.speed_rpm.values[inner],
                               rtol=2e-2)


def test_speed_and_angle_channels_and_a_stated_speed() -> None:
    t = np.arange(N) / FS
    ds = layout({"shaft_rpm": (exact_rpm(t), "rpm"), "enc": (ramp_angle(t), "rad")})
    m = load_measurement(ds, speed="shaft_rpm")
    np.testing.assert_allclose(m.speed_rpm.values, exact_rpm(t), rtol=1e-12)
    assert m.angle is None and "speed channel 'shaft_rpm'" in m.reference
    assert "shaft_rpm" not in m.vibration_channels and "enc" not in m.vibration_channels
    m = load_measurement(ds, angle="enc")
    np.testing.assert_allclose(m.speed_rpm.values[5:-5], exact_rpm(t)[5:-5], rtol=1e-6)
    m = load_measurement(ds, rpm=1500)
    assert np.all(m.speed_rpm.values == 1500.0) and "stated by the user" in m.reference
    assert m.source["reference_channel"] is None


def test_a_file_goes_through_its_reader(tmp_path) -> None:
    ds = layout()
    path = write_csv(ds, tmp_path / "rec.csv")
    m = load_measurement(path, tacho="tacho", pulses_per_rev=10, channel="acc")
    assert m.source["file"] == str(path) and m.source["format"] == "csv"
    assert m.source["reader"] == "analysis.readers.read_csv"
    np.testing.assert_allclose(m.channel().values, ds["acc"].values)
    nc = write_netcdf(ds, tmp_path / "rec.nc")
    m2 = load_measurement(nc, pulses_per_rev=10)
    np.testing.assert_array_equal(m2.speed_rpm.values, load_measurement(
        ds, pulses_per_rev=10).speed_rpm.values)


def test_a_simulated_run_dataset_gives_sensor_channels_and_its_tacho() -> None:
    t = np.arange(N) / FS
    th = ramp_angle(t)
    run = xr.Dataset(
        {"sensor_acceleration": (("sensor", "time"), np.vstack([np.sin(20 * th),
                                                                np.cos(20 * th)]),
                                 {"units": "m s-2"}),
         "tacho": ("time", tacho_train(th, 30), {"units": "V", "pulses_per_rev": 30,
                                                  "member": "sun"}),
         "normal_force": (("mesh", "time"), np.zeros((2, N)), {"units": "N"})},
        coords={"time": ("time", t, {"units": "s"}), "sensor": ["top", "side"],
                "sensor_angle": ("sensor", [90.0, 120.0], {"units": "degree"})},
        attrs={"fs_out": FS, "title": "run"})
    m = load_measurement(run)
    assert m.source["kind"] == "simulation"
    assert m.vibration_channels == ("top", "side")
    assert "(sun shaft), 30 pulses/rev" in m.reference
    np.testing.assert_array_equal(m.channel("side").values, np.cos(20 * th))
    inner = (t > 0.1) & (t < t[-1] - 0.1)
    np.testing.assert_allclose(m.speed_rpm.values[inner], exact_rpm(t)[inner], rtol=2e-3)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"tacho": "nope"}, r"tacho = 'nope' is not a channel.*channels: \['acc', 'tacho'\]"),
    ({"speed": "acc"}, r"speed 'acc' has units 'm s-2'"),
    ({"tacho": "tacho", "speed": "acc"}, "give one speed reference"),
    ({"pulses_per_rev": 0}, r"pulses_per_rev = 0 is not admissible: an integer in 1..10000"),
    ({"pulses_per_rev": 2.5}, "pulses_per_rev = 2.5 is not admissible"),
    ({"rpm": -3}, r"rpm = -3 is not admissible"),
    ({"rpm": float("nan")}, r"rpm = nan is not admissible"),
    ({"speed": "acc", "pulses_per_rev": 3}, "pulses_per_rev applies to a tacho"),
    ({"channel": "x"}, r"channel = 'x' is not a channel.*\['acc', 'tacho'\]"),
    ({"channel": "tacho"}, "is the speed reference"),
])
def test_bad_options_are_named(kwargs, match) -> None:
    with pytest.raises(ValueError, match=match):
        load_measurement(layout(), **kwargs)


def test_no_reference_names_the_options_and_the_channels() -> None:
    ds = layout().drop_vars("tacho")
    with pytest.raises(ValueError, match=r"no speed reference found: give --tacho.*--speed.*"
                       r"channels: \['acc'\]"):
        load_measurement(ds)


def test_bad_sources(tmp_path) -> None:
    with pytest.raises(FileNotFoundError):
        load_measurement(tmp_path / "missing.uff")
    with pytest.raises(ValueError, match="is a directory"):
        load_measurement(tmp_path)
    bad = tmp_path / "x.nc"
    bad.write_bytes(b"not a netcdf file at all")
    with pytest.raises(ReaderError):
        load_measurement(bad)
    other = tmp_path / "x.xyz"
    other.write_text("1,2\n")
    with pytest.raises(ValueError, match="cannot tell the format"):
        load_measurement(other)
    with pytest.raises(TypeError):
        load_measurement(3)  # type: ignore[arg-type]
    short = layout().isel(time=slice(0, 20))
    with pytest.raises(ValueError, match="20 samples; a measurement needs at least 64"):
        load_measurement(short)
    flat = layout()
    flat["tacho"].values[:] = 1.0
    with pytest.raises(ValueError, match="tacho channel 'tacho': tacho signal: no pulses"):
        load_measurement(flat)
    run = layout().assign(normal_force=(("mesh", "time"), np.zeros((2, N))))
    with pytest.raises(ValueError, match="simulated run without a virtual sensor: add a "
                       r"\[\[sensor\]\] table"):
        load_measurement(run)
    still = layout({"speed": (np.zeros(N), "min-1")}).drop_vars("tacho")
    with pytest.raises(ValueError, match="does not turn"):
        load_measurement(still)


# ------------------------------------------------------------------ what a real export lacks

CWRU = Path("/work/shared/data/cwru")


def _bare_mat(tmp_path: Path) -> Path:
    """A MAT file as data sets export them: no rate, no units, the speed as a scalar."""
    from scipy.io import savemat

    t = np.arange(N) / FS
    path = tmp_path / "bare.mat"
    savemat(path, {"acc": 0.5 * np.sin(2 * np.pi * 100 * t), "mic": np.cos(t),
                   "RPM": np.uint16(1500)})
    return path


def test_rate_speed_calibration_and_units_stated_for_a_bare_mat_file(tmp_path) -> None:
    path = _bare_mat(tmp_path)
    with pytest.raises(ReaderError, match=r"no sample rate; pass fs=<Hz> \(gearvib: --fs HZ\)"):
        load_measurement(path, rpm=1500)
    m = load_measurement(path, fs=FS, rpm_from="RPM", calibration={"acc": 2.0},
                         units={"acc": "g"})
    assert m.fs == FS and m.time.size == N and m.time[1] == pytest.approx(1 / FS)
    assert np.all(m.speed_rpm.values == 1500.0)
    assert m.reference == "constant speed 1500 min-1 from the file's scalar 'RPM'"
    acc = m.channel("acc")
    t = np.arange(N) / FS
    # file value x 2 g per file unit x 9.80665 m s-2 per g
    np.testing.assert_allclose(acc.values, 0.5 * np.sin(2 * np.pi * 100 * t) * 2.0 * 9.80665,
                               rtol=1e-12)
    assert acc.attrs["units"] == "m s-2" and acc.attrs["source_units"] == "g"
    assert acc.attrs["calibration"] == 2.0 and acc.attrs["calibration_basis"] == \
        "g per file unit"
    # the other channel untouched, the options kept as provenance
    np.testing.assert_array_equal(m.channel("mic").values, np.cos(t))
    assert m.channel("mic").attrs["units"] == "1"
    assert m.source["stated"] == {"fs": FS, "calibration": {"acc": 2.0},
                                  "units": {"acc": "g"}, "rpm_from": "RPM"}
    # one unit / one factor for every channel
    m = load_measurement(path, fs=FS, rpm=100, units="V", calibration=-3.0)
    assert all(m.channel(c).attrs["units"] == "V" for c in ("acc", "mic"))
    np.testing.assert_allclose(m.channel("mic").values, -3.0 * np.cos(t), rtol=1e-12)


def test_rate_and_time_column_of_a_csv_file(tmp_path) -> None:
    ds = layout()
    with_time = write_csv(ds, tmp_path / "rec.csv")
    bare = tmp_path / "bare.csv"
    bare.write_text("acc,tacho\n" + "\n".join(f"{float(a)!r},{float(b)!r}" for a, b in zip(
        ds["acc"].values, ds["tacho"].values, strict=True)) + "\n")
    m = load_measurement(bare, fs=FS, tacho="tacho", pulses_per_rev=10)
    np.testing.assert_allclose(m.channel().values, ds["acc"].values, rtol=1e-15)
    assert m.fs == FS
    with pytest.raises(ValueError, match=r"--fs HZ\) or time_column= \(--time-column NAME\)"):
        load_measurement(bare, tacho="tacho")
    renamed = tmp_path / "t.csv"
    renamed.write_text(with_time.read_text().replace("time [s]", "t [s]", 1))
    m = load_measurement(renamed, time_column="t", pulses_per_rev=10)
    assert m.fs == pytest.approx(FS) and m.vibration_channels == ("acc",)
    m = load_measurement(renamed, time_column=0, fs=FS, pulses_per_rev=10)
    assert m.fs == pytest.approx(FS)
    with pytest.raises(ValueError, match="fs is given twice"):
        load_measurement(bare, fs=FS, reader_options={"fs": FS})


def test_a_rate_the_file_states_must_agree(tmp_path) -> None:
    from analysis.readers import write_wav

    ds = layout()
    wav = tmp_path / "rec.wav"
    write_wav(ds, wav)
    # a WAV file names no channels: ch1 (acc), ch2 (tacho)
    assert load_measurement(wav, fs=FS, tacho="ch2", pulses_per_rev=10).fs == FS
    with pytest.raises(ValueError, match=r"fs = 4000 Hz disagrees with the rate .*rec.wav "
                       r"states \(5000 Hz\)"):
        load_measurement(wav, fs=4000, tacho="ch2")
    with pytest.raises(ValueError, match=r"time_column = 't' applies to CSV files .* not to "
                       r"\.wav files"):
        load_measurement(wav, time_column="t", tacho="ch2")
    with pytest.raises(ValueError, match="fs = 4000 Hz disagrees with the rate the dataset"):
        load_measurement(ds, fs=4000.0)
    assert load_measurement(ds, fs=FS, pulses_per_rev=10).fs == FS


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"fs": 0}, ValueError, r"fs = 0 is not admissible: a sample rate in \(0, 1e\+09\] Hz"),
    ({"fs": float("inf")}, ValueError, "fs = inf is not admissible: must be finite"),
    ({"fs": True}, TypeError, "fs = True is not admissible: must be a real number"),
    ({"fs": "12000"}, TypeError, "fs = '12000' is not admissible"),
    ({"rpm_from": "RPMX"}, ValueError, r"rpm_from = 'RPMX' is not a numeric scalar of the "
     r"file; scalars: \['RPM'\]"),
    ({"rpm_from": "RPM", "rpm": 100}, ValueError, "give one speed reference, not rpm and "
     "rpm_from"),
    ({"rpm_from": 3}, TypeError, "rpm_from = 3 is not admissible"),
    ({"calibration": {"nope": 1.0}}, ValueError, r"calibration: 'nope' is not a channel of "
     r"the measurement; channels: \['acc', 'mic'\]"),
    ({"calibration": 0.0}, ValueError, r"calibration\['acc'\] = 0.0 is not admissible"),
    ({"calibration": {"acc": True}}, TypeError, r"calibration\['acc'\] = True"),
    ({"calibration": {"acc": "2"}}, TypeError, r"calibration\['acc'\] = '2'"),
    ({"calibration": float("nan")}, ValueError, r"calibration\['acc'\] = nan"),
    ({"calibration": 1e300}, ValueError, r"calibration\['acc'\] = 1e\+300 is not admissible"),
    ({"units": {"mic": ""}}, TypeError, r"units\['mic'\] = '' is not admissible"),
    ({"units": {"x": "g"}}, ValueError, "units: 'x' is not a channel"),
    ({"time_column": 0}, TypeError, "time_column = 0 is not admissible for a MAT file"),
])
def test_bad_export_options_are_named(tmp_path, kwargs, error, match) -> None:
    path = _bare_mat(tmp_path)
    base = {"fs": FS, "rpm_from": "RPM"}
    if "rpm" in kwargs or "rpm_from" in kwargs:
        base.pop("rpm_from")
    with pytest.raises(error, match=match):
        load_measurement(path, **{**base, **kwargs})


@pytest.mark.skipif(not CWRU.is_dir(), reason="CWRU records not available "
                    "(/work/shared/data/cwru)")
def test_the_cwru_record_with_its_rate_speed_and_unit_stated() -> None:
    m = load_measurement(CWRU / "IR007_0.mat", fs=12000, rpm_from="X105RPM",
                         units={"X105_DE_time": "g"})
    assert m.vibration_channels == ("X105_DE_time", "X105_FE_time", "X105_BA_time")
    assert m.time.size == 121265 and m.fs == 12000.0
    assert m.time[-1] == pytest.approx(121264 / 12000.0)
    assert np.all(m.speed_rpm.values == 1797.0)
    assert m.channel().attrs["units"] == "m s-2"
