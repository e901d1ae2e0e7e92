"""Tests of gearvib.stiffness: mesh stiffness models, ISO 6336-1, TOML/CSV input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearvib.geometry import Toothing, mesh_geometry
from gearvib.stiffness import (
    ConstantStiffness,
    FourierStiffness,
    PairSuperposition,
    RectangularStiffness,
    TabulatedPair,
    TrapezoidalStiffness,
    iso6336_stiffness,
    iso_rectangular,
    stiffness_from_dict,
)

N_FINE = 2**16


def table_integrals(model, l_max, n=N_FINE):
    """Mean and c_l from the model's own table (rectangle rule on s = i/n)."""
    t = model.table(n)
    c = np.fft.fft(t)[1 : l_max + 1] / n
    return t.mean(), c


def models():
    def hump(u):
        u = np.asarray(u, dtype=float)
        return 5e7 * (0.6 + np.sin(np.pi * u / 1.7))

    return [
        ConstantStiffness(1.1e8),
        RectangularStiffness(0.8e8, 1.3e8, 1.6),
        TrapezoidalStiffness(0.8e8, 1.3e8, 1.6, 0.2),
        FourierStiffness(1e8, cos=[1e7, -2e6], sin=[3e6, 0.0, 1e6]),
        PairSuperposition(hump, 1.7),
        TabulatedPair([0.0, 0.3, 1.0, 1.45], [4e7, 7e7, 8e7, 3e7], 1.45),
    ]


@pytest.mark.parametrize("model", models(), ids=lambda m: type(m).__name__)
def test_mean_and_harmonics_against_own_table(model):
    l_max = 6
    mean, c = table_integrals(model, l_max)
    span = max(model.max - model.min, 1.0)
    # discontinuous models: rectangle-rule error ~ jump / n
    assert model.mean == pytest.approx(mean, abs=5e-4 * span, rel=1e-9)
    assert np.allclose(model.harmonics(l_max), c, atol=5e-4 * span, rtol=0)
    # the series rebuilds the table (away from jumps: use a continuous model's full table)
    assert model.harmonics(0).shape == (0,)
    t = model.table(64)
    assert t.shape == (64,)
    assert model.min <= t.min() + 1e-6 and model.max >= t.max() - 1e-6
    # periodicity
    s = np.array([0.13, 0.77])
    assert np.allclose(model(s), model(s + 3.0)) and np.allclose(model(s), model(s - 2.0))


@pytest.mark.parametrize("model", models(), ids=lambda m: type(m).__name__)
def test_to_dict_round_trip_and_scaled(model):
    d = model.to_dict()
    assert isinstance(d["model"], str)
    back = stiffness_from_dict(d)
    assert np.allclose(
        back.table(256), model.table(256), rtol=1e-9 if d["model"] != "pairs" else 2e-3
    )
    sc = model.scaled(2.5)
    assert np.allclose(sc.table(128), 2.5 * model.table(128), rtol=1e-12)
    assert sc.mean == pytest.approx(2.5 * model.mean, rel=1e-7)
    with pytest.raises(ValueError, match="factor"):
        model.scaled(-1.0)


@pytest.mark.parametrize("eps", [1.0, 1.25, 1.6, 1.694, 1.999])
def test_rectangular_closed_form(eps):
    k_min, k_max = 0.8e8, 1.3e8
    r = RectangularStiffness(k_min, k_max, eps)
    d = eps - 1
    assert r.mean == pytest.approx(k_min + d * (k_max - k_min))
    ll = np.arange(1, 9)
    # physics.md 4.3: |k_l| = dk |sin(pi l c)| / (pi l)
    assert np.abs(r.harmonics(8)) == pytest.approx(
        (k_max - k_min) * np.abs(np.sin(np.pi * ll * eps)) / (np.pi * ll), abs=1e-6
    )
    # cell values exactly, no smoothing
    s = np.arange(1000) / 1000
    assert np.array_equal(r.table(1000), np.where(s < d, k_max, k_min))


def test_rectangular_harmonics_rebuild_waveform():
    r = RectangularStiffness(0.8e8, 1.3e8, 1.6)
    c = r.harmonics(4000)
    s = np.array([0.1, 0.3, 0.5, 0.9])  # away from the jumps at 0 and 0.6
    ll = np.arange(1, 4001)
    terms = 2 * np.real(c[None, :] * np.exp(2j * np.pi * ll[None, :] * s[:, None]))
    assert r.mean + terms.sum(axis=1) == pytest.approx(r(s), rel=2e-3)


def test_trapezoidal_is_rectangular_times_sinc_and_exact_ramps():
    r = RectangularStiffness(0.8e8, 1.3e8, 1.6)
    t = TrapezoidalStiffness(0.8e8, 1.3e8, 1.6, 0.1)
    ll = np.arange(1, 7)
    assert t.harmonics(6) == pytest.approx(r.harmonics(6) * np.sinc(ll * 0.1))
    assert t.mean == pytest.approx(r.mean)
    # ramp values: half-way at the transitions, linear in between
    assert t(0.0) == pytest.approx(1.05e8)
    assert t(0.6) == pytest.approx(1.05e8)
    assert t(0.025) == pytest.approx(0.8e8 + 0.75 * 0.5e8)
    assert t(0.3) == pytest.approx(1.3e8) and t(0.8) == pytest.approx(0.8e8)
    assert t.min == pytest.approx(0.8e8) and t.max == pytest.approx(1.3e8)
    assert np.array_equal(
        TrapezoidalStiffness(1, 2, 1.6, 0.0).table(100), RectangularStiffness(1, 2, 1.6).table(100)
    )
    with pytest.raises(ValueError, match=r"ramp = 0\.5 .*admissible: 0 <= ramp"):
        TrapezoidalStiffness(0.8e8, 1.3e8, 1.6, 0.5)


def test_pair_superposition_of_constant_pair_is_rectangular():
    k = 0.65e8
    for eps in (1.3, 1.6, 1.93):
        p = PairSuperposition(lambda u: np.full_like(u, k), eps)
        r = RectangularStiffness(k, 2 * k, eps)
        assert np.array_equal(p.table(997), r.table(997))
        assert p.mean == pytest.approx(r.mean, rel=1e-10)
        assert np.allclose(p.harmonics(8), r.harmonics(8), atol=1e-6 * k)
        assert p.min == pytest.approx(k) and p.max == pytest.approx(2 * k)
    # eps >= 2: two or three pairs in contact
    p = PairSuperposition(lambda u: np.full_like(u, k), 2.4)
    assert p(0.2) == pytest.approx(3 * k) and p(0.7) == pytest.approx(2 * k)
    assert p.mean == pytest.approx(2.4 * k, rel=1e-10)


def test_tabulated_exact_harmonics_match_quadrature_of_same_curve():
    pos, val = [0.0, 0.2, 0.9, 1.3, 1.55], [1e7, 6e7, 7e7, 5e7, 0.5e7]
    t = TabulatedPair(pos, val, 1.55)
    q = PairSuperposition(lambda u: np.interp(u, pos, val), 1.55, breakpoints=pos)
    assert t.mean == pytest.approx(q.mean, rel=1e-10)
    assert np.allclose(t.harmonics(10), q.harmonics(10), atol=1e-3, rtol=1e-8)
    assert np.allclose(t.table(500), q.table(500))


def test_csv_round_trip(tmp_path):
    eps, b = 1.62, 0.012
    frac = np.linspace(0, 1, 41)
    c_pair = 14.0 * (0.7 + 0.3 * np.sin(np.pi * frac))  # N/(mm um)
    ref = TabulatedPair(frac * eps, c_pair * b * 1e9, eps)
    f1 = tmp_path / "lvr.csv"
    with f1.open("w") as fh:
        fh.write("# single pair stiffness, exported\nposition [-],flag,c [N/(mm um)]\n")
        for x, c in zip(frac, c_pair, strict=True):
            fh.write(f"{x:.17g},1,{c:.17g}\n")
    t1 = TabulatedPair.from_csv(
        f1, eps, stiffness_column=2, stiffness_unit="N/(mm um)", face_width=b
    )
    assert np.allclose(t1.table(300), ref.table(300), rtol=1e-12)
    # German export: semicolon, decimal comma, base pitches, N/m
    f2 = tmp_path / "kisssoft.csv"
    with f2.open("w") as fh:
        fh.write("Weg;Steifigkeit\n")
        for x, c in zip(frac * eps, c_pair * b * 1e9, strict=True):
            fh.write(f"{x:.17g};{c:.17g}\n".replace(".", ","))
    t2 = TabulatedPair.from_csv(f2, eps, position_unit="base_pitch")
    assert np.allclose(t2.table(300), ref.table(300), rtol=1e-12)
    # via the TOML table, relative path, contact ratio from the mesh
    mesh = mesh_geometry(Toothing(33, 1e-3, face_width=b), Toothing(40, 1e-3, face_width=b))
    t3 = stiffness_from_dict(
        {"model": "csv", "path": "lvr.csv", "stiffness_column": 2, "stiffness_unit": "N/(mm um)"},
        mesh=mesh,
        base_dir=tmp_path,
    )
    assert t3.contact_ratio == pytest.approx(mesh.contact_ratio)
    assert t3.mean == pytest.approx(np.trapezoid(c_pair, frac) * mesh.contact_ratio * b * 1e9)
    # dict round trip keeps the data
    assert np.allclose(stiffness_from_dict(t1.to_dict()).table(64), t1.table(64))


@pytest.mark.parametrize(
    ("content", "match"),
    [
        ("0,1e8\n0.5,1e8\n0.4,1e8\n", "not strictly increasing"),
        ("0,1e8\n0.5,-1e8\n1,1e8\n", "row 2 is -100000000.0 N/m"),
        ("0,1e8\n0.5,nan\n1,1e8\n", "NaN"),
        ("0,1e8\n0.5,abc\n1,1e8\n", "line 2"),
        ("0,1e8\n", "found 1 numeric rows"),
        ("0,1e8\n0.5,1e8\n1.5,1e8\n", "path_fraction positions span"),
        ("pos;k\n0;1e8\n0,5;x\n", "line 3"),
    ],
)
def test_csv_errors(tmp_path, content, match):
    f = tmp_path / "bad.csv"
    f.write_text(content)
    with pytest.raises(ValueError, match=match):
        TabulatedPair.from_csv(f, 1.6)


def test_csv_missing_file_and_units(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        TabulatedPair.from_csv(tmp_path / "none.csv", 1.6)
    f = tmp_path / "ok.csv"
    f.write_text("0,14\n1,14\n")
    with pytest.raises(ValueError, match="face_width"):
        TabulatedPair.from_csv(f, 1.6, stiffness_unit="N/(mm um)")
    with pytest.raises(ValueError, match="stiffness_unit = 'kN/m'"):
        TabulatedPair.from_csv(f, 1.6, stiffness_unit="kN/m")
    with pytest.raises(ValueError, match="position_unit"):
        TabulatedPair.from_csv(f, 1.6, position_unit="mm")


def test_fourier_model():
    f = FourierStiffness(1e8, cos=[2e7], sin=[0.0, 1e7])
    s = np.linspace(0, 1, 7)
    assert f(s) == pytest.approx(1e8 + 2e7 * np.cos(2 * np.pi * s) + 1e7 * np.sin(4 * np.pi * s))
    assert f.harmonics(3) == pytest.approx([1e7, -0.5e7j, 0])
    g = FourierStiffness(1e8, cos=[3e7])
    assert g.min == pytest.approx(0.7e8, rel=1e-9) and g.max == pytest.approx(1.3e8, rel=1e-9)
    with pytest.raises(ValueError, match="becomes negative"):
        FourierStiffness(1e8, cos=[8e7], sin=[8e7])


# --- ISO 6336-1 ------------------------------------------------------------------------------
def test_iso6336_worked_numbers():
    b = 0.005
    m = mesh_geometry(Toothing(33, 1e-3, face_width=b), Toothing(40, 1e-3, face_width=b))
    iso = iso6336_stiffness(m)
    assert iso["c_prime_th"] == pytest.approx(17.13, abs=0.005)
    assert iso["C_B"] == pytest.approx(0.975)
    assert iso["c_prime"] == pytest.approx(13.36, abs=0.005)
    assert m.contact_ratio == pytest.approx(1.694, abs=5e-4)
    assert iso["c_gamma_alpha"] == pytest.approx(20.3, abs=0.02)
    assert iso["c_gamma_alpha"] == pytest.approx(iso["c_prime"] * (0.75 * m.contact_ratio + 0.25))
    # units: N/(mm um) * 5 mm = N/um -> 1e6 N/m; the paper's sun mesh is 0.8e8 .. 1.3e8 N/m
    assert iso["mean_mesh_stiffness"] == pytest.approx(iso["c_gamma_alpha"] * 5 * 1e6)
    assert 0.8e8 < iso["mean_mesh_stiffness"] < 1.3e8
    assert iso["in_validity_range"]
    # internal ring: z_n2 -> infinity, the planet is the pinion
    ring = mesh_geometry(Toothing(-114, 1e-3), Toothing(40, 1e-3))
    iso_r = iso6336_stiffness(ring)
    assert iso_r["pinion"] == "gear2" and math.isinf(iso_r["z_n2"])
    assert iso_r["c_prime_th"] == pytest.approx(19.56, abs=0.005)
    assert iso_r["c_prime"] == pytest.approx(15.26, abs=0.005)


def test_iso6336_helical_and_low_contact_ratio():
    beta = math.radians(20)
    g1 = Toothing(25, 2e-3, helix_angle=beta, profile_shift=0.2)
    g2 = Toothing(50, 2e-3, helix_angle=-beta, profile_shift=0.1)
    iso = iso6336_stiffness(mesh_geometry(g1, g2))
    zn1, zn2 = 25 / math.cos(beta) ** 3, 50 / math.cos(beta) ** 3
    q = (
        0.04723
        + 0.15551 / zn1
        + 0.25791 / zn2
        - 0.00635 * 0.2
        - 0.11654 * 0.2 / zn1
        - 0.00193 * 0.1
        - 0.24188 * 0.1 / zn2
        + 0.00529 * 0.04
        + 0.00182 * 0.01
    )
    assert iso["q_prime"] == pytest.approx(q, rel=1e-12)
    assert iso["c_prime"] == pytest.approx(0.8 * 0.975 * math.cos(beta) / q, rel=1e-12)
    # eps_alpha < 1.2: the ISO reduction (up to 10 %)
    low = mesh_geometry(Toothing(20, 1e-3, addendum=0.65), Toothing(20, 1e-3, addendum=0.65))
    assert low.contact_ratio < 1.2
    iso_l = iso6336_stiffness(low)
    assert iso_l["c_gamma_alpha"] == pytest.approx(
        0.9 * iso_l["c_prime"] * (0.75 * low.contact_ratio + 0.25)
    )
    with pytest.raises(ValueError, match="C_M"):
        iso6336_stiffness(low, C_M=1.5)


def test_iso_rectangular_reproduces_iso_mean():
    m = mesh_geometry(Toothing(33, 1e-3, face_width=0.01), Toothing(40, 1e-3, face_width=0.01))
    r = iso_rectangular(m)
    iso = iso6336_stiffness(m)
    assert r.mean == pytest.approx(iso["mean_mesh_stiffness"], rel=1e-12)
    assert r.k_min == pytest.approx(iso["single_pair_stiffness"])
    assert r.k_max / r.k_min == pytest.approx(1.75)


# --- TOML tables and errors -----------------------------------------------------------------
def test_stiffness_from_dict_models():
    m = mesh_geometry(Toothing(33, 1e-3, face_width=0.005), Toothing(40, 1e-3, face_width=0.005))
    r = stiffness_from_dict({"model": "rectangular", "k_min": 2.67e7, "k_max": 4.33e7}, mesh=m)
    assert r.contact_ratio == pytest.approx(m.contact_ratio)
    r2 = stiffness_from_dict(
        {"model": "rectangular", "k_min": 2.67e7, "k_max": 4.33e7, "contact_ratio": 1.6}
    )
    assert r2.mean == pytest.approx(2.67e7 + 0.6 * 1.66e7)
    iso = stiffness_from_dict({"model": "iso6336"}, mesh=m)
    assert iso.mean == pytest.approx(iso6336_stiffness(m)["mean_mesh_stiffness"])
    assert stiffness_from_dict({"model": "iso6336-rectangular", "C_M": 0.8}, mesh=m).mean == (
        pytest.approx(iso.mean)
    )
    f = stiffness_from_dict({"model": "fourier", "mean": 1e8, "cos": [1e7], "sin": [2e6]})
    assert f.harmonics(1)[0] == pytest.approx(0.5e7 - 1e6j)
    p = stiffness_from_dict(
        {
            "model": "pairs",
            "position": [0, 1],
            "stiffness": [14, 14],
            "position_unit": "path_fraction",
            "stiffness_unit": "N/(mm um)",
        },
        mesh=m,
    )
    assert p.mean == pytest.approx(14 * 5 * 1e6 * m.contact_ratio)


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ({"model": "parabolic"}, r"model 'parabolic' is unknown \(admissible: constant, csv"),
        ({"model": "constant", "k": 1e8, "kk": 1}, r"unknown key 'kk'.*admissible keys: k\)"),
        ({"model": "rectangular", "k_min": 1e8}, "needs key 'k_max'"),
        ({"model": "constant", "k": -1e8}, r"stiffness k = -1.*admissible: > 0"),
        ({"model": "constant", "k": 0.0}, r"stiffness k = 0.0"),
        ({"model": "constant", "k": float("nan")}, "k = nan"),
        (
            {"model": "rectangular", "k_min": 1e8, "k_max": float("nan"), "contact_ratio": 1.5},
            "k_max",
        ),
        (
            {"model": "rectangular", "k_min": 2e8, "k_max": 1e8, "contact_ratio": 1.5},
            "k_max >= k_min",
        ),
        (
            {"model": "rectangular", "k_min": 1e8, "k_max": 2e8, "contact_ratio": 0.93},
            r"contact ratio eps_alpha = 0.93 .*admissible: 1 <= eps < 2",
        ),
        (
            {"model": "rectangular", "k_min": 1e8, "k_max": 2e8, "contact_ratio": 2.2},
            "1 <= eps < 2",
        ),
        ({"model": "rectangular", "k_min": 1e8, "k_max": 2e8}, "give contact_ratio"),
        ({"model": "iso6336"}, "needs the mesh geometry"),
        (
            {"model": "pairs", "position": [0, 1], "stiffness": [1, -1], "contact_ratio": 1.5},
            "admissible: >= 0",
        ),
    ],
)
def test_stiffness_from_dict_errors(table, match):
    with pytest.raises(ValueError, match=match):
        stiffness_from_dict(table)


def test_pair_superposition_validation():
    with pytest.raises(ValueError, match="negative"):
        PairSuperposition(lambda u: u - 1.0, 1.5)
    with pytest.raises(ValueError, match="NaN"):
        PairSuperposition(lambda u: np.full_like(u, np.nan), 1.5)
    with pytest.raises(ValueError, match=r"eps_alpha = 0.9 .*admissible: >= 1"):
        PairSuperposition(lambda u: np.ones_like(u), 0.9)
