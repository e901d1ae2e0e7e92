"""Tests of analysis.gear_signals: regular, residual, difference and envelope signals.

The TSAs here are sums of known orders, built in the test, so every derived signal is known
exactly (a TSA spans one revolution: order k is DFT line k).
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.gear_signals import GearSignals, gear_signals

N = 512
TH = 2 * np.pi * np.arange(N) / N
Z = 20


def c(order: int, amp: float, phase: float = 0.0) -> np.ndarray:
    return amp * np.cos(order * TH + phase)


def components() -> dict[str, np.ndarray]:
    return {
        "mean": np.full(N, 0.7),
        "shaft": c(1, 0.5, 0.1) + c(2, 0.2, 1.0) + c(3, 0.1, -0.5),
        "mesh": c(Z, 1.0, 0.3) + c(2 * Z, 0.4, -1.0) + c(3 * Z, 0.1, 2.0),
        "sb1": c(Z - 1, 0.15, 0.2) + c(Z + 1, 0.12, -0.4) + c(2 * Z + 1, 0.05, 0.0),
        "sb2": c(Z - 2, 0.06, 0.9) + c(Z + 2, 0.05, 0.1),
        "other": c(7, 0.08, 0.3) + c(111, 0.03, 1.1),  # not regular: stays everywhere
    }


def test_signals_are_the_known_parts():
    p = components()
    x = sum(p.values())
    g = gear_signals(x, Z, harmonics=3, shaft_harmonics=3, sidebands=1)
    assert isinstance(g, GearSignals)
    np.testing.assert_allclose(g.regular, p["shaft"] + p["mesh"] + p["sb1"], atol=1e-12)
    np.testing.assert_allclose(g.residual, p["sb1"] + p["sb2"] + p["other"], atol=1e-12)
    np.testing.assert_allclose(g.difference, p["sb2"] + p["other"], atol=1e-12)
    assert list(g.mesh_lines) == [20, 40, 60]
    assert set(g.residual_orders) == {1, 2, 3, 20, 40, 60}
    assert set(g.regular_orders) == {1, 2, 3, 19, 20, 21, 39, 40, 41, 59, 60, 61}
    assert g.amplitudes[Z] == pytest.approx(1.0)
    assert g.amplitudes[Z - 1] == pytest.approx(0.15)
    assert g.amplitudes[0] == pytest.approx(0.7)


def test_second_order_sidebands_and_defaults():
    p = components()
    x = sum(p.values())
    g = gear_signals(x, Z, sidebands=2, shaft_harmonics=0)
    # default harmonics: all up to n/2 - 1 = 255 -> 12 harmonics of 20
    assert g.harmonics == 12 and g.mesh_lines[-1] == 240
    np.testing.assert_allclose(g.difference, p["shaft"] + p["other"], atol=1e-12)
    g2 = gear_signals(x, [Z, 37], harmonics=1)
    assert list(g2.mesh_lines) == [20, 37]


def test_envelope_of_an_amplitude_modulated_mesh():
    """(1 + m cos(theta)) cos(z theta): the envelope of the band around z is 1 + m cos."""
    m = 0.3
    x = (1 + m * np.cos(TH + 0.2)) * np.cos(Z * TH) + c(3 * Z, 0.5)
    g = gear_signals(x, Z, envelope_band=3)
    np.testing.assert_allclose(g.envelope, 1 + m * np.cos(TH + 0.2), atol=1e-12)
    assert g.envelope_band == (17, 23)
    assert gear_signals(x, Z).envelope_band == (11, 29)  # default half width z // 2 - 1


def test_multichannel_and_dataset():
    p = components()
    x = np.vstack([sum(p.values()), 2 * sum(p.values())])
    g = gear_signals(x, Z)
    assert g.difference.shape == (2, N)
    np.testing.assert_allclose(g.difference[1], 2 * g.difference[0], atol=1e-12)
    ds = g.to_dataset()
    for v in [*ds.data_vars, *ds.coords]:
        assert "long_name" in ds[v].attrs and "units" in ds[v].attrs, v
    fig = gear_signals(sum(p.values()), Z).plot()
    assert len(fig.axes) == 4 and all(ax.lines or ax.collections for ax in fig.axes)
    with pytest.raises(ValueError, match="channel"):
        g.plot()
    assert len(g.plot(channel=1).axes) == 4


@pytest.mark.parametrize(
    ("args", "kwargs", "error", "match"),
    [
        ((300,), {}, ValueError, "mesh_orders"),
        ((20.0,), {}, ValueError, "mesh_orders"),
        ((True,), {}, ValueError, "mesh_orders"),
        (([],), {}, ValueError, "mesh_orders"),
        ((1,), {}, ValueError, "mesh_orders"),
        ((Z,), {"harmonics": 0}, ValueError, "harmonics"),
        ((Z,), {"shaft_harmonics": -1}, ValueError, "shaft_harmonics"),
        ((Z,), {"sidebands": "1"}, ValueError, "sidebands"),
        ((Z,), {"envelope_band": 1.5}, ValueError, "envelope_band"),
    ],
)
def test_bad_parameters(args, kwargs, error, match):
    with pytest.raises(error, match=match):
        gear_signals(c(Z, 1.0), *args, **kwargs)


def test_bad_signals():
    x = c(Z, 1.0)
    x[3] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        gear_signals(x, Z)
    with pytest.raises(TypeError, match="tsa"):
        gear_signals(np.array(["a"] * 64), 5)
    with pytest.raises(ValueError, match="at least 8"):
        gear_signals(np.ones(4), 2)
