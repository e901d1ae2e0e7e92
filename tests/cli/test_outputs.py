"""Outputs of the command line: checked before the work, one overwrite rule for every command."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from gearvib.cli import main
from gearvib.io import read_run


def test_simulate_to_a_directory_or_proc_fails_before_simulating(tmp_path, capsys,
                                                                monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "adir").mkdir()

    def no_simulation(*a, **k):
        raise AssertionError("simulated although the output is unusable")

    monkeypatch.setattr("gearvib.simulate.simulate", no_simulation)
    for out, match in (("adir", "output 'adir' is a directory: give a file name such as "
                                "'adir/run.nc'"),
                       ("/proc/x.nc", "output folder '/proc' is not writable"),
                       ("no/such/x.nc", "output folder 'no/such' does not exist")):
        t0 = time.monotonic()
        assert main(["simulate", "paper-case1", "-o", out, "-q"]) == 2
        err = capsys.readouterr().err
        assert match in err and len(err.strip().splitlines()) == 1, err
        assert time.monotonic() - t0 < 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir"]
    assert not list((tmp_path / "adir").iterdir())


def test_simulate_refuses_to_overwrite_without_overwrite(tmp_path, capsys):
    out = tmp_path / "run.nc"
    args = ["simulate", "paper-case1", "-o", str(out), "--duration", "0.01", "-q"]
    assert main(args) == 0
    first = out.read_bytes()
    out.write_bytes(b"an earlier result")
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "exists; add --overwrite to replace it" in err
    assert out.read_bytes() == b"an earlier result"  # untouched
    assert main([*args, "--overwrite"]) == 0
    assert out.read_bytes() == first  # replaced, bit for bit the same run
    read_run(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]


def test_report_and_demo_refuse_an_earlier_run_in_the_folder(tmp_path, capsys, monkeypatch):
    out = tmp_path / "demo"
    out.mkdir()
    (out / "report.pdf").write_bytes(b"%PDF earlier")

    def no_study(*a, **k):
        raise AssertionError("started although the outputs exist")

    monkeypatch.setattr("gearvib.report.run_study", no_study)
    monkeypatch.setattr("gearvib.report.build_report", no_study)
    assert main(["demo", "-o", str(out), "--duration", "0.15", "-q"]) == 2
    err = capsys.readouterr().err
    assert "holds outputs of an earlier run (report.pdf); add --overwrite" in err
    run = tmp_path / "run.nc"
    assert main(["simulate", "paper-case1", "-o", str(run), "--duration", "0.01", "-q"]) == 0
    capsys.readouterr()
    assert main(["report", str(run), "-o", str(out), "-q"]) == 2
    assert "add --overwrite" in capsys.readouterr().err
    assert (out / "report.pdf").read_bytes() == b"%PDF earlier"
    assert main(["report", str(run), "-o", str(tmp_path / "new"), "-q", "--duration", "1"]) == 2
    assert "--duration applies to a study" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()


def test_an_interrupted_or_failed_report_leaves_no_empty_folder(tmp_path, capsys, monkeypatch):
    def failing(*a, **k):
        raise ValueError("stand-in failure")

    monkeypatch.setattr("gearvib.report.run_study", failing)
    out = tmp_path / "fresh"
    assert main(["demo", "-o", str(out), "-q"]) == 2
    assert not out.exists()
    assert "stand-in failure" in capsys.readouterr().err


def test_a_failed_block_removes_the_empty_folders_it_made_and_keeps_files(tmp_path):
    """A diagnosis that fails (a full disk, Ctrl-C) after making ``out/candidates/runs`` leaves
    no folder behind; a folder holding a file stays, and so does one that existed before."""
    from gearvib.outputs import removed_if_left_empty

    out = tmp_path / "diag"
    with pytest.raises(OSError), removed_if_left_empty(out):
        (out / "candidates" / "runs").mkdir(parents=True)
        raise OSError(28, "No space left on device")
    assert not out.exists()
    kept = tmp_path / "kept"
    with pytest.raises(KeyboardInterrupt), removed_if_left_empty(kept):
        (kept / "candidates" / "runs").mkdir(parents=True)
        (kept / "candidates" / "sweep.nc").write_bytes(b"x")
        raise KeyboardInterrupt
    assert (kept / "candidates" / "sweep.nc").is_file() and not (kept / "candidates" / "runs"
                                                                  ).exists()
    before = tmp_path / "before"
    before.mkdir()
    with pytest.raises(ValueError), removed_if_left_empty(before):
        raise ValueError("x")
    assert before.is_dir()


def test_stale_temp_files_are_named_and_removed_by_the_next_command(tmp_path, capsys):
    from gearvib import tempfiles

    stale = tmp_path / f".run.nc.gearvib-{tempfiles.host_tag()}-999999999-abcdef12.tmp"
    stale.write_bytes(b"half a file")
    assert not tempfiles.pid_alive(999999999)
    assert main(["simulate", "paper-case1", "-o", str(tmp_path / "x.nc"), "--duration", "0.01",
                 "-q"]) == 0
    assert "removed 1 temporary file(s) of killed runs" in capsys.readouterr().err
    assert not stale.exists()


@pytest.mark.parametrize("args, match", [
    (["--duration", "inf"], r"argument --duration: 'inf' is not admissible"),
    (["--duration", "0"], r"argument --duration: '0' is not admissible \(admissible: >= 1e-06 "
                          r"and <= 1e\+07\)"),
    (["--torque", "inf"], r"argument --torque: 'inf' is not admissible"),
    (["--torque", "nan"], r"argument --torque: 'nan' is not admissible"),
    (["--fs", "-5"], r"argument --fs: '-5' is not admissible \(admissible: > 0 and <= 1e\+12"),
    (["--speed", "0:nan"], r"argument --speed: '0:nan': speeds must be finite"),
    (["--max-steps", "1.5"], r"argument --max-steps: '1.5' is not an integer"),
    (["--colour", "red"], r"unrecognized arguments: --colour red"),
])
def test_cli_numbers_are_checked_in_one_line(args, match, capsys, tmp_path):
    import re

    with pytest.raises(SystemExit) as exc:
        main(["simulate", "paper-case1", "-o", str(tmp_path / "x.nc"), *args])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and err.startswith("gearvib: error: gearvib"), err
    assert re.search(match, err), err
    assert not list(tmp_path.iterdir())


def test_help_lists_every_command_and_the_overwrite_rule(capsys):
    for cmd in ("simulate", "report", "demo"):
        with pytest.raises(SystemExit):
            main([cmd, "--help"])
        assert "--overwrite" in capsys.readouterr().out


def test_warnings_are_one_line(capsys, monkeypatch):
    import warnings

    def titles():
        warnings.warn("a two-line\nwarning", UserWarning, stacklevel=1)
        return {"x": "a title"}

    monkeypatch.setattr("gearvib.config.preset_titles", titles)
    assert main(["preset"]) == 0
    assert capsys.readouterr().err == "gearvib: warning: a two-line warning\n"


def test_output_checks_do_not_leave_probe_files(tmp_path):
    from gearvib.outputs import check_output_file, check_output_folder

    check_output_file(tmp_path / "a.nc", overwrite=False)
    check_output_folder(tmp_path, ["report.html"], overwrite=False)
    assert not list(tmp_path.iterdir())
    assert os.access(tmp_path, os.W_OK) and Path(tmp_path).is_dir()
