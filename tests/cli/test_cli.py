"""The command line: modes, simulate, errors and exit codes."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from gearvib.cli import main


def test_modes_json(capsys):
    assert main(["modes", "paper-case1", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    modes = data["modes"]
    assert len(modes) == 5
    assert [m["kind"] for m in modes] == ["rigid-body", "rotational", "planet", "planet",
                                          "rotational"]
    assert modes[2]["multiplicity"] == modes[3]["multiplicity"] == 2
    assert 1240 <= modes[1]["frequency_hz"] <= 1280


def test_modes_table(capsys):
    assert main(["modes", "paper-case2"]) == 0
    out = capsys.readouterr().out
    assert "rotational" in out and "planet" in out and "paper-case2" in out


@pytest.mark.parametrize("argv", [
    ["modes", "paper-case9"],
    ["modes", "missing.toml"],
    ["simulate", "paper-case9", "-o", "x.nc"],
])
def test_bad_input_gives_one_line_and_exit_2(argv, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gearvib: error:")
    assert len(err.splitlines()) == 1
    assert not list(tmp_path.iterdir())


def test_unknown_toml_key_is_named(tmp_path, capsys):
    from importlib import resources

    text = resources.files("gearvib.presets").joinpath("paper-case1.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("[bodies.sun]\n", "[bodies.sun]\ncolour = 'red'\n"))
    assert main(["modes", str(bad)]) == 2
    assert "colour" in capsys.readouterr().err


def test_simulate_writes_a_readable_run(tmp_path, capsys):
    out = tmp_path / "run.nc"
    code = main(["simulate", "paper-case1", "-o", str(out), "--speed", "1400:1600",
                 "--duration", "0.05", "--fs", "25000", "-q"])
    assert code == 0
    assert str(out) in capsys.readouterr().out
    with xr.open_dataset(out, engine="netcdf4") as ds:
        assert ds.attrs["Conventions"] == "CF-1.11"
        speed = ds["input_speed"].values
        assert speed[0] == pytest.approx(1400, abs=1) and speed[-1] == pytest.approx(1600, abs=1)
        # CF time (analysis.cf): xarray decodes it to datetimes, 40 us apart
        dt = np.diff(ds["time"].values[:2])[0] / np.timedelta64(1, "s")
        assert 1 / dt == pytest.approx(25000)
        cfg = json.loads(ds.attrs["config_json"])
        assert cfg["model"]["gearset"]["name"] == "paper-case1"
        assert cfg["model"]["run"]["speed_end_rpm"] == 1600
    assert [p.name for p in tmp_path.iterdir()] == ["run.nc"]


def test_simulate_unwritable_folder(tmp_path, capsys, monkeypatch):
    # CI runs as root, who may write anywhere: simulate the missing permission
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda p, mode: False if mode == os.W_OK
                        else real_access(p, mode))
    assert main(["simulate", "paper-case1", "-o", str(tmp_path / "x.nc"),
                 "--duration", "0.01"]) == 2
    assert "not writable" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_simulate_missing_folder(tmp_path, capsys):
    assert main(["simulate", "paper-case1", "-o", str(tmp_path / "no" / "x.nc")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_bad_speed_option_is_rejected(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "paper-case1", "-o", "x.nc", "--speed", "fast"])
    assert exc.value.code == 2
    assert "START:END" in capsys.readouterr().err


def test_python_dash_m_help():
    res = subprocess.run([sys.executable, "-m", "gearvib", "--help"], capture_output=True,
                         text=True, check=False)
    assert res.returncode == 0
    for cmd in ("demo", "modes", "simulate", "preset", "report"):
        assert cmd in res.stdout


def test_demo_runs_end_to_end_on_a_short_run_up(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "-o", str(out), "--duration", "0.2", "-q"]) == 0
    printed = capsys.readouterr().out
    names = sorted(p.name for p in out.iterdir())
    assert names == ["paper-case1.nc", "paper-case2.nc", "report.html", "report.pdf"]
    assert str(out / "report.html") in printed
    html = (out / "report.html").read_text(encoding="utf-8")
    for section in ("parameters", "modes", "tooth-forces", "spectra", "mesh-stiffness",
                    "sonograms", "resonances", "stability", "comparison", "provenance"):
        assert f'id="{section}"' in html, section
    with xr.open_dataset(out / "paper-case2.nc", engine="netcdf4") as ds:
        assert float(ds["input_speed"].values[-1]) == pytest.approx(4000.0, rel=1e-6)


def test_report_from_unreadable_netcdf(tmp_path, capsys):
    bad = tmp_path / "broken.nc"
    bad.write_bytes(b"this is not a netCDF file")
    out = tmp_path / "rep"
    assert main(["report", str(bad), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "broken.nc" in err
    assert not out.exists()


def test_report_study_with_unknown_preset(tmp_path, capsys):
    recipe = tmp_path / "study.toml"
    recipe.write_text('[study]\ntitle = "x"\ncases = [{name = "a", config = "paper-case9"}]\n')
    out = tmp_path / "rep"
    assert main(["report", str(recipe), "-o", str(out), "-q"]) == 2
    assert "paper-case9" in capsys.readouterr().err
    assert not out.exists()


def test_demo_unwritable_output_folder(tmp_path, capsys, monkeypatch):
    target = tmp_path / "blocked"
    target.write_text("a file where the folder should be")
    assert main(["demo", "-o", str(target), "--duration", "0.05", "-q"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert target.read_text() == "a file where the folder should be"


def test_preset_lists_and_prints(capsys, tmp_path):
    import tomllib

    from gearvib.config import load_config

    assert main(["preset"]) == 0
    out = capsys.readouterr().out
    for name in ("paper-case1", "wolfrom-example", "ravigneaux-example", "two-stage-example"):
        assert name in out
    assert "Wolfrom set (stepped planets" in out  # titles
    assert main(["preset", "wolfrom-example"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("# A Wolfrom set")  # the comments come along
    assert tomllib.loads(text) == load_config("wolfrom-example")[0]
    own = tmp_path / "mine.toml"
    own.write_text(text.replace('name = "wolfrom-example"', 'name = "mine"'))
    assert main(["modes", str(own)]) == 0
    assert "mine" in capsys.readouterr().out
    assert main(["preset", "wolfrom"]) == 2
    assert "unknown preset 'wolfrom'" in capsys.readouterr().err


def test_simulate_a_motor_driven_description(tmp_path, capsys):
    from importlib import resources

    text = resources.files("gearvib.presets").joinpath("paper-case1.toml").read_text()
    sim = text[text.index("[simulation]"):]
    motor = ('[simulation]\ndrive = "motor"\nmotor = { synchronous_rpm = 1500.0, '
             'breakdown_torque = 150.0, breakdown_slip = 0.2 }\nload_torque = [0.0, 0.0, 0.05]\n'
             'load_inertia = 0.5\nduration = 0.05\n')
    path = tmp_path / "motor.toml"
    path.write_text(text.replace(sim, motor))
    out = tmp_path / "motor.nc"
    assert main(["simulate", str(path), "-o", str(out), "-q"]) == 0
    with xr.open_dataset(out, engine="netcdf4") as ds:
        assert ds.attrs["drive"] == "motor"
        assert float(ds["input_speed"].values[-1]) > 10.0  # the motor started the set
        assert json.loads(ds.attrs["config_json"])["model"]["run"]["motor"][
            "synchronous_rpm"] == 1500.0
    capsys.readouterr()
    path.write_text(text.replace(sim, '[simulation]\ndrive = "motor"\n'))
    assert main(["simulate", str(path), "-o", str(out), "-q"]) == 2
    assert "[simulation].motor is required" in capsys.readouterr().err
