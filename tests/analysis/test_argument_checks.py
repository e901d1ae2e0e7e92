"""The argument checks of issue 26, case by case (the fuzz suite samples 6 hostile calls per
function; these pin the guarantees the docs state, each with an independent computation)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from analysis import indicators as ind
from analysis.checks import require_instance, require_real_array


@pytest.fixture
def record() -> np.ndarray:
    rng = np.random.default_rng(7)
    return rng.standard_normal((2, 512)) + 0.3


def _no_warning(func, *args):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="warn"):
            return func(*args)


def test_indicators_have_the_bits_of_the_plain_formulas(record):
    x = record
    c = x - x.mean(axis=-1, keepdims=True)
    assert np.array_equal(ind.rms(x), np.sqrt(np.mean(x * x, axis=-1)))
    assert np.array_equal(ind.crest_factor(x),
                          np.max(np.abs(x), axis=-1) / np.sqrt(np.mean(x * x, axis=-1)))
    for k, f in ((4, ind.kurtosis), (6, ind.m6a), (8, ind.m8a)):
        m2 = np.mean(c * c, axis=-1)
        assert np.array_equal(f(x), np.mean(c**k, axis=-1) / m2 ** (k // 2))
    mv = 1.7
    assert np.array_equal(ind.na4(x, mv), np.mean(c**4, axis=-1) / mv**2)


@pytest.mark.parametrize("k", [997, -1020, 300, -300])
def test_indicators_of_extreme_records_are_exact_and_finite(record, k):
    """x 2^k: rms scales by 2^k exactly, the crest factor not at all, the normalised moments
    to rounding (libm's pow is not exactly scale-invariant); no warning (the plain formulas
    overflow or underflow to inf/NaN here)."""
    x = record
    y = np.ldexp(x, k)
    assert np.array_equal(_no_warning(ind.rms, y), np.ldexp(ind.rms(x), k))
    assert np.array_equal(_no_warning(ind.crest_factor, y), ind.crest_factor(x))
    for f in (ind.kurtosis, ind.m6a, ind.m8a):
        np.testing.assert_allclose(_no_warning(f, y), f(x), rtol=1e-14)


def test_constant_record_is_refused():
    with pytest.raises(ValueError, match="constant"):
        ind.kurtosis(np.full(64, 3.0))
    with pytest.raises(ValueError, match="zero throughout"):
        ind.crest_factor(np.zeros(64))
    with pytest.raises(ValueError, match="mesh_amplitudes are all zero"):
        ind.fm0(np.arange(8.0), [0.0, 0.0])


def test_interpolate_refuses_positions_beyond_its_block():
    from analysis.sinc import HALF_TAPS, interpolate

    x = np.sin(np.arange(200) / 7.0)[None, :]
    inside = np.arange(20, 180, dtype=float)
    got = interpolate(x, inside)  # the kernel is a delta at whole positions
    np.testing.assert_allclose(got[0], x[0, 20:180], atol=1e-12)
    block = x[:, 50:150]
    ok = np.array([50.0 + HALF_TAPS - 1, 150.0 - HALF_TAPS - 1])
    np.testing.assert_allclose(interpolate(block, ok, 50, 200)[0], x[0, ok.astype(int)],
                               atol=1e-12)
    for bad in ([40.0], [149.5], [np.nan], [1e300]):
        with pytest.raises(ValueError, match="pos"):
            interpolate(block, np.array(bad), 50, 200)


def test_sizes_are_bounded_before_loops():
    from analysis.sinc import kernel_table
    from analysis.vold_kalman_solver import difference_coefficients

    with pytest.raises(ValueError, match="degree"):
        kernel_table(degree=10**9)
    with pytest.raises(ValueError, match="p = "):
        difference_coefficients(10**9)
    np.testing.assert_array_equal(difference_coefficients(2), [1.0, -2.0, 1.0])


def test_type_errors_name_parameter_and_type():
    from analysis.plots import spectrum_figure

    with pytest.raises(TypeError, match=r"^spectrum must be an analysis\.spectrum\.Spectrum; "
                                        r"got int$"):
        spectrum_figure(3)
    with pytest.raises(TypeError, match=r"^v must be a float; got str$"):
        require_instance("1", float, "v")
    with pytest.raises(TypeError, match="real numbers; got dtype complex128"):
        _no_warning(require_real_array, np.ones(3, dtype=complex), "x")


def test_overflowing_conversions_are_refused():
    from analysis.instability.floquet import floquet
    from analysis.levels import power_of
    from analysis.speed import from_rpm
    from analysis.vold_kalman import bandwidth_to_weight, weight_to_bandwidth

    with pytest.raises(ValueError, match="bandwidth"):
        bandwidth_to_weight(0.0, 1000.0)
    with pytest.raises(ValueError, match="weight"):
        weight_to_bandwidth(1e300, 1000.0)
    b = np.array([1.0, 10.0, 100.0])
    np.testing.assert_allclose(weight_to_bandwidth(bandwidth_to_weight(b, 1e3), 1e3), b,
                               rtol=1e-12)
    with pytest.raises(ValueError, match="magnitude"):
        power_of(np.full(4, 1e200), "rms", "linear", 8)
    with pytest.raises(ValueError, match="dB"):
        power_of(np.full(4, 4000.0), "rms", "dB", 8)
    t = np.arange(10.0)
    with pytest.raises(ValueError, match="time"):
        from_rpm(t * 1e300, np.full(10, 600.0))
    with pytest.raises(ValueError, match="M, C"):
        floquet([[1.0]], [[1e300]], lambda s: np.array([[1.0]]), np.pi)


def test_signature_score_is_scale_free_and_exact():
    from analysis.diagnosis import signature_score

    rng = np.random.default_rng(3)
    a, b = rng.uniform(0, 10, 50), rng.uniform(0, 10, 50)
    plain = signature_score(a, b, deadband=1.0, signature_deadband=1.0)
    aa, bb = np.clip(a - 1.0, 0, None), np.clip(b - 1.0, 0, None)
    assert plain == min(1.0, max(0.0, np.dot(aa, bb) / (np.linalg.norm(aa) *
                                                         np.linalg.norm(bb))))
    def score(u: np.ndarray, v: np.ndarray) -> float:
        return signature_score(u, v, deadband=0.0, signature_deadband=0.0)

    assert score(aa, bb) == plain
    assert _no_warning(score, np.ldexp(aa, 1000), np.ldexp(bb, 1000)) == plain
    assert _no_warning(score, np.ldexp(aa, -1000), bb) == plain
