"""``gearvib sweep`` and the sweep report (files, figures, exit codes)."""

from __future__ import annotations

import json
import re
import time

import numpy as np
import pytest
import xarray as xr

from gearvib.cli import main
from gearvib.sweep.report import sweep_figures

SWEEP = """
title = "Sun-mesh damping"
base = "paper-case1"
[simulation]
duration = 0.02
speed_start_rpm = 2000
speed_end_rpm = 2200
[[parameter]]
path = "meshes.sun.damping_ratio"
values = [0.005, 0.01, 0.02]
[summary]
orders = [1, 2]
order_resolution = 0.25
"""


def test_cli_sweep_writes_runs_summary_and_report(tmp_path, capsys):
    spec = tmp_path / "sweep.toml"
    spec.write_text(SWEEP)
    assert main(["sweep", str(spec), "--list"]) == 0
    listing = capsys.readouterr().out.splitlines()
    assert listing[0].split() == ["case", "meshes.sun.damping_ratio"]
    assert [row.split()[1] for row in listing[1:]] == ["0.005", "0.01", "0.02"]

    out = tmp_path / "out"
    assert main(["sweep", str(spec), "-o", str(out), "--workers", "2", "-q"]) == 0
    text = capsys.readouterr().out
    assert "3 cases (3 simulated, 0 reused, 0 failed)" in text
    with xr.open_dataset(out / "sweep.nc") as ds:
        assert ds.sizes["case"] == 3
        np.testing.assert_array_equal(ds["meshes_sun_damping_ratio"].values, [0.005, 0.01, 0.02])
        assert ds["case"].attrs["long_name"] == "case number"
        files = [str(f) for f in ds.run_file.values]
    assert all((out / f).is_file() for f in files)
    html = (out / "sweep.html").read_text()
    images = re.findall(r'src="(figures/[^"]+\.png)"', html)
    assert {"figures/dynamic_factor.png", "figures/transmission_error_pp.png",
            "figures/normal_force_order_level.png"} <= set(images)
    for img in images:
        assert (out / img).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # outputs of a finished sweep are kept unless --overwrite, as by every command
    assert main(["sweep", str(spec), "-o", str(out), "--workers", "1", "-q", "--no-report"]) == 2
    assert "sweep.nc" in capsys.readouterr().err and (out / "sweep.nc").is_file()
    # with it, a second call finds every run finished
    assert main(["sweep", str(spec), "-o", str(out), "--workers", "1", "-q", "--no-report",
                 "-f"]) == 0
    assert "(0 simulated, 3 reused, 0 failed)" in capsys.readouterr().out


@pytest.mark.parametrize(("argv_tail", "message"), [
    (["missing.toml", "-o", "out"], "sweep file 'missing.toml' not found"),
    (["bad.toml", "-o", "out"], "unknown key 'sn' in [meshes]"),
    (["ok.toml"], "-o/--output DIR is required"),
    (["ok.toml", "-o", "out", "--scheduler", "tcp://127.0.0.1:9"], "cannot connect to the Dask "
     "scheduler at 'tcp://127.0.0.1:9': nothing listens there (connection refused)"),
])
def test_cli_sweep_errors_exit_2(argv_tail, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ok.toml").write_text(SWEEP)
    (tmp_path / "bad.toml").write_text(SWEEP.replace("meshes.sun.damping", "meshes.sn.damping"))
    if "--scheduler" in argv_tail:
        pytest.importorskip("distributed")
    t0 = time.perf_counter()
    assert main(["sweep", *argv_tail]) == 2
    # nothing listens on port 9: at once, not after Dask's 30 s connect timeout
    assert time.perf_counter() - t0 < 5.0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_cli_sweep_connect_timeout_is_checked(tmp_path, capsys):
    (tmp_path / "ok.toml").write_text(SWEEP)
    with pytest.raises(SystemExit):
        main(["sweep", str(tmp_path / "ok.toml"), "-o", str(tmp_path / "o"), "--scheduler",
              "tcp://127.0.0.1:9", "--connect-timeout", "0"])
    assert "--connect-timeout" in capsys.readouterr().err


def test_cli_sweep_failed_case_exit_1(tmp_path, capsys):
    spec = tmp_path / "sweep.toml"
    # the first case never reaches the summary window's speeds
    spec.write_text(SWEEP.replace('path = "meshes.sun.damping_ratio"',
                                  'path = "simulation.speed_end_rpm"').replace(
        "values = [0.005, 0.01, 0.02]", "values = [2050.0, 2200.0]").replace(
        "[summary]", "[summary]\nwindow_rpm = [2100, 2150]"))
    assert main(["sweep", str(spec), "-o", str(tmp_path / "out"), "-q", "--workers", "1"]) == 1
    captured = capsys.readouterr()
    assert "1 failed" in captured.out
    assert "case 0: the summary window" in captured.err


def test_report_kinds_of_figures(tmp_path):
    """Line plot for one parameter, heat map for two, scatter for random samples."""
    n = 6
    base = {"Conventions": "CF-1.11", "title": "t", "sweep_base": "x"}

    def make(mode: str, params: list[dict], coords: dict) -> xr.Dataset:
        kv = 1.0 + np.arange(n * 2, dtype=float).reshape(n, 2) / 10
        return xr.Dataset(
            {"dynamic_factor": (("case", "mesh"), kv, {"units": "1", "long_name": "K_v"}),
             "failure": (("case",), [""] * n)},
            coords={"case": np.arange(n), "mesh": ["a", "b"], "status": ("case", ["ok"] * n),
                    "run_file": ("case", [f"r{i}" for i in range(n)]), **coords},
            attrs={**base, "sweep_mode": mode, "parameters_json": json.dumps(params)})

    p1 = {"path": "a.x", "kind": "number", "units": "m", "labels": None, "values": None,
          "distribution": None, "has_values_coordinate": False}
    p2 = {**p1, "path": "b.y", "kind": "label", "units": "degree"}
    one = make("grid", [p1], {"a.x": ("case", np.linspace(1e-5, 6e-5, n), {"units": "m"})})
    two = make("grid", [p1, p2], {"a.x": ("case", np.repeat([1e-5, 2e-5, 3e-5], 2),
                                            {"units": "m"}),
                                   "b.y": ("case", ["p", "q"] * 3)})
    rnd = make("random", [{**p1, "distribution": "uniform"}, p2],
               {"a.x": ("case", np.random.default_rng(0).uniform(1e-5, 6e-5, n),
                        {"units": "m"}), "b.y": ("case", ["p", "q"] * 3)})
    kinds = {}
    for name, ds in (("one", one), ("two", two), ("rnd", rnd)):
        (sf,) = sweep_figures(ds)
        assert sf.name == "dynamic_factor"
        ax = sf.figure.axes[0]
        kinds[name] = (len(ax.lines), len(ax.collections))
        sf.figure.savefig(tmp_path / f"{name}.png")
    assert kinds["one"] == (2, 0)       # a line per mesh
    assert kinds["two"][1] == 1          # one heat map (QuadMesh)
    assert kinds["rnd"][0] == 2          # points coloured by the categorical parameter
    ax = sweep_figures(one)[0].figure.axes[0]
    assert ax.get_xlabel() == "a.x [µm]" and ax.get_ylabel() == "dynamic_factor [1]"
