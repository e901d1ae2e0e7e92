"""Errors about files a description points to, and the static equilibrium's message."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest

from gearvib.config import ConfigError, gearset_from_dict, load_config
from gearvib.stiffness import TabulatedPair

SECRET = "s3cr3t-token-from-another-file"


@pytest.mark.parametrize("content, where", [
    (f"position,stiffness\n0,1e8\n0.5,{SECRET}\n1,1e8\n", "line 3, column 2: not a number"),
    (f"0;1e8\n{SECRET};2e8\n", "line 2, column 1: not a number"),
    (f"0 1e8\n0.5\n# {SECRET}\n", "line 2, column 2: missing"),
    (f"{SECRET}\n0,1e8\n0.5,{SECRET}\n", "line 3, column 2: not a number"),
])
def test_csv_errors_name_file_line_and_column_but_not_the_content(tmp_path, content, where):
    f = tmp_path / "curve.csv"
    f.write_text(content)
    with pytest.raises(ValueError) as exc:
        TabulatedPair.from_csv(f, 1.6)
    text = str(exc.value)
    assert SECRET not in text
    assert str(f) in text and where in text


def test_csv_stiffness_pointing_at_a_binary_or_huge_file(tmp_path):
    binary = tmp_path / "image.csv"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 4)
    with pytest.raises(ValueError, match=r"image.csv' is not a UTF-8 text file \(byte 0 cannot"):
        TabulatedPair.from_csv(binary, 1.6)
    big = tmp_path / "big.csv"
    with big.open("wb") as fh:
        fh.truncate(17 * 2**20)  # sparse: nothing read
    with pytest.raises(ValueError, match=r"big.csv' has 17825792 bytes \(admissible: <= "):
        TabulatedPair.from_csv(big, 1.6)


def test_a_description_with_a_bad_csv_names_the_key_and_file(tmp_path):
    cfg, _ = load_config("paper-case1")
    cfg = copy.deepcopy(cfg)
    (tmp_path / "k.csv").write_text(f"0,1e8\n0.5,{SECRET}\n")
    cfg["meshes"]["sun"]["stiffness"] = {"model": "csv", "path": "k.csv"}
    with pytest.raises(ConfigError) as exc:
        from gearvib.assembly import assemble

        assemble(gearset_from_dict(cfg, base=tmp_path))
    text = str(exc.value)
    assert SECRET not in text and "k.csv" in text and "line 2, column 2" in text


def test_static_equilibrium_that_does_not_converge_names_meshes_load_and_remedies(monkeypatch):
    """The message names the switching meshes, the load and what to try (issue #11)."""
    import gearvib.simulation.equilibrium as eq
    from gearvib.assembly import assemble
    from gearvib.simulate import SimulationError, SpeedRamp, prepare_run, static_equilibrium

    model = assemble(gearset_from_dict(load_config("paper-case1")[0]))
    j = np.array(model.mesh_backlash, dtype=float)
    j[[2, 5]] += 1e-5  # planet 3 floats: its contacts switch under a light load
    model = dataclasses.replace(model, mesh_backlash=j)
    monkeypatch.setattr(eq, "MAX_NEWTON", 0)  # the energy method would solve it: disable it
    setup = prepare_run(model, SpeedRamp(300, 300, 0.01, input_torque=10.0), False)
    with pytest.raises(SimulationError) as exc:
        static_equilibrium(setup.system, setup.mass, setup.rigid, setup.rigid * setup.omega0,
                           max_iter=1, mesh_names=model.mesh_names)
    text = str(exc.value)
    assert "sun-planet3" in text and "keeps switching" in text
    assert "load torque" in text and "N m at the output" in text
    assert "Try a start speed of 0" in text and "a larger load" in text and \
        "negative backlash" in text
    assert "\n" not in text  # one line on the command line


def test_the_command_line_prints_a_failed_equilibrium_as_one_line(monkeypatch, capsys,
                                                                  tmp_path):
    from gearvib.cli import main
    from gearvib.simulate import SimulationError

    def fails(*args, **kwargs):
        raise SimulationError("static equilibrium: the flank-contact sets do not converge: the "
                              "contact of sun-planet1 keeps switching ... Try a larger load")

    monkeypatch.setattr("gearvib.simulate.static_equilibrium", fails)
    assert main(["simulate", "paper-case1", "-o", str(tmp_path / "x.nc"), "--duration",
                 "0.01", "-q"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("gearvib: failed: static equilibrium:") and err.count("\n") == 1
    assert not list(tmp_path.iterdir())
