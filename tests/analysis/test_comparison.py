"""analysis.comparison: two records on one reference shaft, lines matched, levels in dB."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from analysis.comparison import compare_measurements
from analysis.measurement import load_measurement
from analysis.readers import ChannelData, build_dataset

FS = 8000.0
DUR = 4.0


def record(orders: dict[float, float], units: str = "m s-2", n0: float = 600.0,
           n1: float = 1800.0, line_hz: float | None = None, seed: int = 0,
           static: float = 0.0):
    """Run-up n0 -> n1 min-1 with order components {order: amplitude}, a 60-pulse tacho, a
    frequency-locked component (a resonance excited by broadband noise) and a little noise;
    ``static`` adds a static load rising by 20 % over the run (as a simulated force)."""
    t = np.arange(int(FS * DUR)) / FS
    th = 2 * np.pi / 60 * (n0 * t + 0.5 * (n1 - n0) / DUR * t**2)
    x = sum(a * np.sin(o * th) for o, a in orders.items()) + static * (1 + 0.2 * t / DUR)
    rng = np.random.default_rng(seed)
    x = x + 1e-3 * rng.standard_normal(t.size)
    if line_hz is not None:
        from scipy.signal import lfilter

        r = np.exp(-2 * np.pi * 15.0 / FS)  # a lightly damped resonance driven by noise
        w = 2 * np.pi * line_hz / FS
        x = x + lfilter([0.01], [1, -2 * r * np.cos(w), r * r], rng.standard_normal(t.size))
    tacho = np.where((60 * th / (2 * np.pi)) % 1.0 < 0.5, 5.0, 0.0)
    ds = build_dataset([ChannelData("acc", x, units), ChannelData("tacho", tacho, "V")], FS,
                       source_format="test")
    return load_measurement(ds, pulses_per_rev=60)


def by_status(c, status):
    return [p for p in c.peaks if p.status == status]


def test_lines_are_matched_with_order_and_level_differences():
    meas = record({10: 1.0, 20: 0.5, 33: 0.2}, line_hz=700.0, seed=1)
    sim = record({10: 2.0, 20: 0.5, 45: 0.3}, seed=2)
    c = compare_measurements(meas, sim, natural_frequencies_hz=[690.0, 1500.0],
                             mode_names=["f2", "f3"], max_order=60)
    assert c.level_basis.startswith("calibrated: dB re 1 m s-2")
    m = {round(p.order): p for p in by_status(c, "matched")}
    assert set(m) >= {10, 20}
    assert m[10].level_difference_db == pytest.approx(20 * np.log10(0.5), abs=0.3)
    assert m[20].level_difference_db == pytest.approx(0.0, abs=0.3)
    assert abs(m[10].order_difference) < 0.02
    assert [round(p.order) for p in by_status(c, "measured only")] == [33]
    assert [round(p.order) for p in by_status(c, "simulated only")] == [45]
    # the one-sided lines stand far above the other record's level there
    assert by_status(c, "measured only")[0].level_difference_db > 20
    # the resonance line of the measurement near f2 (+1.4 %), f3 not seen
    line = min(c.lines, key=lambda ln: abs(ln.frequency_hz - 700.0))
    assert abs(line.frequency_hz - 700.0) < 25.0 and line.mode == "f2" and line.seen
    assert line.offset == pytest.approx(700.0 / 690.0 - 1, abs=0.03)
    assert not line.in_simulation
    assert ("f3", 1500.0) in c.unseen_modes
    ds = c.to_dataset()
    assert ds["level_difference"].dims == ("rpm", "order")
    assert ds["order"].attrs["units"] == "1" and ds["rpm"].attrs["units"] == "min-1"
    assert ds.attrs["level_basis"] == c.level_basis
    np.testing.assert_allclose(ds["level_difference"].values, c.measured_db - c.simulated_db)
    assert isinstance(c.plot(), Figure)


def test_the_same_record_matches_itself_at_0_db():
    a = record({10: 1.0, 20: 0.5, 33: 0.2}, seed=3)
    c = compare_measurements(a, a, max_order=60)
    assert c.count("measured only") == 0 and c.count("simulated only") == 0
    assert c.count("matched") >= 3
    assert all(abs(p.level_difference_db) < 1e-9 for p in c.peaks)
    d = c.difference_db
    assert np.nanmax(np.abs(d)) < 1e-9


def test_normalised_levels_when_the_units_differ():
    meas = record({10: 1.0, 20: 0.5}, units="V", seed=4)
    sim = record({10: 3.0, 20: 0.75}, seed=5)
    c = compare_measurements(meas, sim, max_order=40)
    assert c.level_basis.startswith("normalised") and any("normalised" in n for n in c.notes)
    m = {round(p.order): p for p in by_status(c, "matched")}
    assert m[10].level_difference_db == pytest.approx(0.0, abs=0.3)  # both strongest = 0 dB
    assert m[20].level_difference_db == pytest.approx(20 * np.log10(0.5 / (0.75 / 3)),
                                                      abs=0.3)
    with pytest.raises(ValueError, match="calibrated comparison needs the same physical unit"):
        compare_measurements(meas, sim, calibrated=True)


def test_a_force_against_an_accelerometer_is_normalised_to_its_order_lines_not_its_load():
    """A simulated force in N with a static load 100 x its order lines against an acceleration:
    each record's strongest order line is 0 dB (the static load, near order 0, is no line), so
    the 20th order stands at 20 log10(0.5) and 20 log10(0.25) -- analytic -- and the note
    states the unit mismatch."""
    meas = record({10: 1.0, 20: 0.5}, seed=11)
    sim = record({10: 3.0, 20: 0.75}, units="N", seed=12, static=300.0)
    c = compare_measurements(meas, sim, max_order=40)
    assert c.level_basis.startswith("normalised: each record's strongest order line above "
                                    "order")
    assert c.units == "1" and c.level_unit == "dB re the strongest order line"
    assert (c.measured_units, c.simulated_units) == ("m s-2", "N")
    assert any("different quantities" in n and "'m s-2'" in n and "'N'" in n for n in c.notes)
    m = {round(p.order): p for p in by_status(c, "matched")}
    assert set(m) == {10, 20} and c.count("measured only") == c.count("simulated only") == 0
    assert m[10].level_measured_db == pytest.approx(0.0, abs=1e-9)
    assert m[10].level_simulated_db == pytest.approx(0.0, abs=1e-9)
    assert m[20].level_measured_db == pytest.approx(20 * np.log10(0.5), abs=0.3)
    assert m[20].level_simulated_db == pytest.approx(20 * np.log10(0.25), abs=0.3)
    assert m[20].level_difference_db == pytest.approx(20 * np.log10(2.0), abs=0.3)
    # no bin above the near-DC ones is above the strongest line (the static load removed)
    lines = c.order >= 2 * c.match_tolerance
    assert np.nanmax(c.simulated_spectrum_db[lines]) < 0.5
    ds = c.to_dataset()
    assert ds.attrs["level_basis"] == c.level_basis
    assert ds.attrs["level_unit"] == "dB re the strongest order line"
    assert (ds.attrs["measured_units"], ds.attrs["simulated_units"]) == ("m s-2", "N")
    assert c.level_basis in ds["simulated_order_spectrum"].attrs["long_name"]
    fig = c.plot()
    assert fig.axes[0].get_ylabel() == "level [dB re the strongest order line]"
    # calibrated levels are refused across units; the same record calibrated keeps its level
    with pytest.raises(ValueError, match="calibrated comparison needs the same physical unit"):
        compare_measurements(meas, sim, calibrated=True, max_order=40)
    same = compare_measurements(sim, sim, max_order=40)
    assert same.level_basis == "calibrated: dB re 1 N" and same.level_unit == "dB re 1 N"
    top = max(p.level_measured_db for p in same.peaks)
    assert top == pytest.approx(20 * np.log10(3.0 / np.sqrt(2)), abs=0.3)  # rms of 3 N


def test_a_wrong_simulated_channel_names_the_admissible_ones():
    a = record({10: 1.0}, seed=13)
    with pytest.raises(ValueError, match=r"^simulated_channel = 'nope' is not a channel of the "
                       r"simulated record '[^']*'; admissible: acc$"):
        compare_measurements(a, a, simulated_channel="nope")
    with pytest.raises(ValueError, match=r"admissible: acc$"):  # the tacho: no channel to compare
        compare_measurements(a, a, simulated_channel="tacho")


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"order_resolution": 0.0}, "order_resolution = 0.0 is not admissible: 0.01..10"),
    ({"rpm_bins": 0}, "rpm_bins = 0 is not admissible"),
    ({"max_order": -1}, "max_order = -1 is not admissible"),
    ({"prominence_db": float("nan")}, "prominence_db = nan is not admissible"),
    ({"natural_frequencies_hz": [-5.0]}, "natural_frequencies_hz must be finite and > 0"),
    ({"channel": "nope"}, "channel = 'nope' is not a channel"),
])
def test_bad_parameters_are_named(kwargs, match):
    a = record({10: 1.0}, seed=6)
    with pytest.raises(ValueError, match=match):
        compare_measurements(a, a, **kwargs)


def test_speed_ranges_must_overlap():
    a = record({10: 1.0}, n0=600, n1=900, seed=7)
    b = record({10: 1.0}, n0=1500, n1=2000, seed=8)
    with pytest.raises(ValueError, match=r"speed ranges do not overlap: measured 600–\d+ "
                       r"min-1, simulated 1\d+–2\d+"):
        compare_measurements(a, b)
    with pytest.raises(TypeError):
        compare_measurements(a, "b.nc")  # type: ignore[arg-type]
