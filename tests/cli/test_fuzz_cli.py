"""Property-based fuzz suite over command-line arguments (hypothesis).

Each example builds an argument list for ``gearvib`` -- a subcommand (or a wrong one), its
positional arguments (presets, missing or broken files, a study recipe, run files) and a
random subset of its options with random values (``inf``, ``nan``, ``1e400``, ``-1``, ``""``,
``0x10``, ``4000:0``, text, floats) and outputs (an existing directory, ``/proc/x.nc``, a
missing folder, an existing file with and without ``--overwrite``) -- and runs
:func:`gearvib.cli.main` in a fresh folder. Properties:

* the exit code is 0, 1 (a failed computation) or 2 (bad input), and ``main`` raises nothing
  else;
* an error is one line on stderr starting with ``gearvib: error:`` (exit 2) or
  ``gearvib: failed:`` (exit 1); no traceback is ever printed;
* no temporary file is left in the folder.

``diagnose`` runs its argument, input and output checks and a stand-in for the simulations
and the report (the checks the diagnosis makes first: the gear set and its candidates).
``simulate`` runs for real, with ``--max-steps 20000`` appended so that accepted runs stay
short (longer ones are refused by the run-size check); so does ``sweep`` (``--workers 1``
appended; sweep files of one or two 2 ms runs, one of 2 x 1000^3 cases, one with a wrong
value, one over a description with a fault and a sensor; outputs new, existing, finished
(resumed) or unwritable). ``catalogue`` meets descriptions with ``[[rolling_bearing]]``,
``[[fault]]`` and ``[[sensor]]`` tables and reference members of every kind. ``report`` and
``demo`` run their real argument and output checks, and a stand-in for the simulations and
the rendering (the checks a study makes before its first simulation: every case's
description, run settings and map size; for run files: reading them) -- the full commands
are tested in ``test_cli.py``.

``GEARVIB_FUZZ_EXAMPLES`` sets the number of examples (default 500 here, fixed seed).
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import tempfile
from pathlib import Path
from types import SimpleNamespace

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gearvib.report as report_pkg
from gearvib.cli import main
from gearvib.io import read_run
from gearvib.report.runner import check_output_dir
from tests.gearvib import fuzz_support as fz

REPO = Path(__file__).resolve().parents[2]
VALUES = ["0", "-1", "1", "0.003", "0.001", "1e-3", "inf", "nan", "-inf", "1e400", "1e308",
          "", "abc", "0x10", "1_000", " 5", "0:4000", "4000:0", "0:1e9", "1:2:3", "1400:1600",
          "25000", "1000", "1e-12", "-0", "20000:0", "1e9"]
value = st.one_of(st.sampled_from(VALUES), st.floats(allow_nan=True).map(repr),
                  st.text(max_size=5))
config = st.sampled_from(["paper-case1", "paper-case2", "wolfrom-example", "two-stage-example",
                          "paper-case9", "missing.toml", "broken.toml", "mine.toml", "adir",
                          "", "bearings.toml", "faulty.toml"])
output_file = st.sampled_from(["x.nc", "adir", "/proc/x.nc", "no/such/x.nc", "", "existing.nc",
                               "adir/y.nc", "broken.toml"])
output_dir = st.sampled_from(["out", "adir", "existing.nc", "/proc/out", "no/such/out", "filled"])


def options(names: list[str]) -> st.SearchStrategy[list[str]]:
    flags = {"-q", "--quiet", "--json", "--overwrite", "-f", "--help", "--list", "--no-report"}

    def one(name: str) -> st.SearchStrategy[list[str]]:
        return st.just([name]) if name in flags else value.map(lambda v: [name, v])

    return st.lists(st.sampled_from(names).flatmap(one), max_size=4).map(
        lambda parts: [x for p in parts for x in p])


simulate_args = st.tuples(config, output_file, options(
    ["--speed", "--duration", "--fs", "--dt", "--torque", "-q", "--overwrite", "--colour",
     "--max-steps"])).map(lambda t: ["simulate", t[0], "-o", t[1], *t[2], "--max-steps",
                                     "20000"])
modes_args = st.tuples(config, options(["--json", "--carrier-speed", "--colour"])).map(
    lambda t: ["modes", t[0], *t[1]])
reference = st.sampled_from(["sun", "ring", "carrier", "planet1", "ground", "s2.carrier",
                             "input bearing", "", "nope"])
catalogue_args = st.tuples(config, options(["--speed", "--reference", "--mesh-harmonics",
                                            "--harmonics", "--sidebands", "--json"]),
                           st.sampled_from([[], ["--speed", "1500"]]),
                           st.one_of(st.just([]), reference.map(lambda r: ["--reference", r]))
                           ).map(lambda t: ["catalogue", t[0], *t[2], *t[3], *t[1]])
sweep_file = st.sampled_from(["sweep.toml", "sweep-huge.toml", "sweep-bad.toml",
                              "sweep-faults.toml", "missing.toml", "broken.toml", "adir",
                              "existing.nc", "study.toml", ""])
sweep_args = st.tuples(sweep_file, st.sampled_from([[], ["-o"], *(
    ["-o", d] for d in ["out", "adir", "existing.nc", "/proc/out", "no/such/out", "filled",
                        "done"])]), options(["--workers", "--scheduler", "--list",
                                             "--no-report", "-q", "--no-report"])).map(
    lambda t: ["sweep", t[0], *t[1], *t[2], "--workers", "1"])
preset_args = st.one_of(st.sampled_from([[], ["paper-case1"], ["nope"], ["a", "b"]]),
                        st.lists(st.text(max_size=6), max_size=2)).map(
    lambda t: ["preset", *t])
report_inputs = st.sampled_from([["study.toml"], ["bad-study.toml"], ["existing.nc"],
                                 ["existing.nc", "existing.nc"], ["broken.nc"], ["missing.nc"],
                                 ["study.toml", "existing.nc"], ["mine.toml"], ["adir"]])
report_args = st.tuples(report_inputs, output_dir, options(
    ["--duration", "-q", "--overwrite", "--colour"])).map(
    lambda t: ["report", *t[0], "-o", t[1], *t[2]])
demo_args = st.tuples(output_dir, options(["--duration", "-q", "--overwrite", "--colour"])).map(
    lambda t: ["demo", "-o", t[0], *t[1]])
other_args = st.one_of(st.just([]), st.lists(st.sampled_from(
    ["bogus", "--version", "--help", "-x", "simulate", "modes", "catalogue"]), max_size=2))
diagnose_args = st.tuples(
    st.sampled_from([["meas.nc"], ["existing.nc"], ["missing.nc"], ["broken.nc"], ["adir"],
                     ["meas.nc", "meas.nc"], []]),
    config, output_dir, options(["--threshold", "--revolutions", "--workers", "--tacho",
                                 "--pulses-per-rev", "--speed", "--rpm", "--channel",
                                 "--baseline", "--reference", "--json", "-q", "--overwrite"]),
).map(lambda t: ["diagnose", *t[0], "--gearset", t[1], "-o", t[2], *t[3]])
compare_inputs = st.sampled_from([["long.nc", "long.nc"], ["long.nc", "long.nc"],
                                  ["meas.nc", "long.nc"], ["long.nc", "existing.nc"],
                                  ["existing.nc", "meas.nc"], ["meas.nc", "missing.nc"],
                                  ["broken.nc", "meas.nc"], ["meas.nc", "adir"], ["meas.nc"],
                                  ["study.toml", "meas.nc"]])
compare_args = st.tuples(
    compare_inputs, output_dir, st.one_of(st.just([]), config.map(lambda c: ["--gearset", c])),
    options(["--simulated-channel", "--max-order", "--order-resolution", "--normalise",
             "--tacho", "--pulses-per-rev", "--speed", "--rpm", "--channel", "--reference",
             "--overwrite"]),
).map(lambda t: ["compare", *t[0], "-o", t[1], *t[2], *t[3]])
argv = st.one_of(simulate_args, simulate_args, modes_args, catalogue_args, catalogue_args,
                 preset_args, report_args, demo_args, sweep_args, sweep_args, other_args)


def _fake_run_study(study, out_dir, *, progress=True, duration=None):
    """The checks of :func:`run_study` before its first simulation; no simulation."""
    if duration is not None:
        study = study.with_duration(duration)
    out = check_output_dir(out_dir)
    fz.check_study_cases(study)
    paths = SimpleNamespace(html=out / "report.html", pdf=out / "report.pdf")
    return SimpleNamespace(report=paths, runs={})


def _fake_build_report(inputs, out_dir, **kwargs):
    """Reading the runs and checking the folder, as :func:`build_report` does first."""
    for p in inputs:
        read_run(p)
    out = check_output_dir(out_dir)
    return SimpleNamespace(html=out / "report.html", pdf=out / "report.pdf")


def _fake_diagnose(rec, config, *, threshold=0.4, **kwargs):
    """The checks of :func:`gearvib.diagnosis.diagnose` before its first simulation."""
    from gearvib.config import load_config
    from gearvib.diagnosis import candidate_faults

    cfg, _ = load_config(config)
    candidate_faults(cfg)
    return SimpleNamespace(causes=[], threshold=threshold, attrs={}, to_json=lambda: "{}")


def _fake_write_diagnosis(d, out_dir, **kwargs):
    out = Path(out_dir)
    return SimpleNamespace(html=out / "report.html", pdf=out / "report.pdf",
                           dataset=out / "diagnosis.nc")


@pytest.fixture(scope="module")
def template(tmp_path_factory) -> Path:
    """Files every example finds in its folder."""
    d = tmp_path_factory.mktemp("cli-fuzz-template")
    assert main(["simulate", "paper-case1", "-o", str(d / "existing.nc"), "--speed",
                 "1400:1600", "--duration", "0.01", "-q"]) == 0
    from gearvib.diagnosis.synthetic import synthetic_measurement
    from gearvib.io import write_netcdf

    write_netcdf(synthetic_measurement("paper-case1", duration=0.05), d / "meas.nc")
    # long enough for a tacho speed (compare runs to the end on it)
    write_netcdf(synthetic_measurement("paper-case1", duration=0.3), d / "long.nc")
    (d / "adir").mkdir()
    (d / "filled").mkdir()
    (d / "filled" / "report.html").write_text("an earlier report")
    (d / "broken.nc").write_bytes(b"CDF\x01 truncated")
    (d / "broken.toml").write_text("this is [not toml")
    text = (REPO / "gearvib" / "presets" / "paper-case1.toml").read_text()
    (d / "mine.toml").write_text(text.replace("duration = 1.0", "duration = 0.002"))
    (d / "study.toml").write_text('[study]\ntitle = "t"\ncases = [{name = "a", config = '
                                  '"paper-case1"}]\n[run]\nduration = 0.05\n')
    (d / "bad-study.toml").write_text('[study]\ncases = [{name = "a/b", config = 3}]\n')
    (d / "bearings.toml").write_text(text + '\n[[rolling_bearing]]\nname = "input bearing"\n'
                                     'member = "sun"\nn_rolling = 9\nrolling_diameter = '
                                     '7.94e-3\npitch_diameter = 39.04e-3\n')
    (d / "faulty.toml").write_text(text.replace("duration = 1.0", "duration = 0.002") + (
        '\n[[fault]]\nkind = "crack"\nmember = "sun"\ntooth = 3\nseverity = 0.3\n'
        '[[sensor]]\nname = "top"\nangle_deg = 90.0\nhousing_modes = [{frequency_hz = 3000.0, '
        'damping_ratio = 0.02, gain = 1.0}]\n'))
    sweep = ('base = "{base}"\n[simulation]\nduration = 0.002\nspeed_start_rpm = 1500\n'
             'speed_end_rpm = 1500\n[[parameter]]\npath = "meshes.sun.damping_ratio"\n'
             'values = {values}\n[summary]\norders = [1]\n')
    (d / "sweep.toml").write_text(sweep.format(base="paper-case1", values="[0.01, 0.02]"))
    (d / "sweep-faults.toml").write_text(sweep.format(base="faulty.toml", values="[0.01]"))
    (d / "sweep-huge.toml").write_text(
        sweep.format(base="paper-case1", values="[0.01, 0.02]") + "".join(
            f'[[parameter]]\npath = "{k}"\nvalues = [{", ".join(["0.01"] * 1000)}]\n'
            for k in ("meshes.ring.damping_ratio", "bodies.sun.mass", "bodies.ring.mass")))
    (d / "sweep-bad.toml").write_text(sweep.format(base="paper-case1", values='["x", 0.01]'))
    assert main(["sweep", str(d / "sweep.toml"), "-o", str(d / "done"), "--workers", "1", "-q",
                 "--no-report"]) == 0
    return d


@pytest.fixture(scope="module", autouse=True)
def _stand_ins():
    import gearvib.diagnosis as diagnosis_pkg
    import gearvib.diagnosis.report as diagnosis_report

    old = report_pkg.run_study, report_pkg.build_report
    old_d = diagnosis_pkg.diagnose, diagnosis_report.write_diagnosis_report
    report_pkg.run_study, report_pkg.build_report = _fake_run_study, _fake_build_report
    diagnosis_pkg.diagnose = _fake_diagnose
    diagnosis_report.write_diagnosis_report = _fake_write_diagnosis
    yield
    report_pkg.run_study, report_pkg.build_report = old
    diagnosis_pkg.diagnose, diagnosis_report.write_diagnosis_report = old_d
    fz.write_report()


def run_cli(args: list[str], folder: Path) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
                fz.time_limit(60.0):
            try:
                code = main(args)
            except SystemExit as exc:  # argparse: --help, --version, one-line usage errors
                code = exc.code if isinstance(exc.code, int) else 2
    finally:
        os.chdir(cwd)
    return code, out.getvalue(), err.getvalue()


COMMANDS = ("simulate", "modes", "catalogue", "preset", "report", "demo", "sweep")


class CliOutcome(Exception):
    """An outcome that breaks the command line's promises."""


@settings(max_examples=fz.examples(250), deadline=None, database=None,
          derandomize=fz.derandomize(),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(args=argv)
def test_command_line_gives_one_line_errors_and_clean_folders(template, args):
    _check_command(template, args)


@settings(max_examples=fz.examples(100), deadline=None, database=None,
          derandomize=fz.derandomize(),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(args=diagnose_args)
def test_diagnose_command_line_gives_one_line_errors_and_clean_folders(template, args):
    _check_command(template, args)


@settings(max_examples=fz.examples(40), deadline=None, database=None,
          derandomize=fz.derandomize(),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(args=compare_args)
def test_compare_command_line_gives_one_line_errors_and_clean_folders(template, args):
    _check_command(template, args)


def _check_command(template, args):
    folder = Path(tempfile.mkdtemp(prefix="gearvib-cli-fuzz-"))
    try:
        shutil.copytree(template, folder, dirs_exist_ok=True)
        err: BaseException | None = None
        try:
            code, _out, stderr = run_cli(args, folder)
        except Exception as exc:  # anything main lets escape breaks the promise
            err = exc
        else:
            lines = stderr.strip().splitlines()
            temps = [str(p) for p in folder.rglob("*.tmp")]
            if "Traceback" in stderr or code not in (0, 1, 2) or temps:
                err = CliOutcome(f"exit {code}, stderr {stderr!r}, temporary files {temps}")
            elif code in (1, 2):
                head = "gearvib: failed:" if code == 1 else "gearvib: error:"
                if not lines or not lines[-1].startswith(head) or not all(
                        ln.startswith("gearvib: ") for ln in lines) or sum(
                        ln.startswith(("gearvib: error:", "gearvib: failed:"))
                        for ln in lines) != 1:
                    err = CliOutcome(f"exit {code}: stderr is not one error line: {stderr!r}")
                elif code == 1:
                    err = fz.SimulationError(lines[-1])
                else:
                    err = fz.ConfigError(lines[-1])
        command = args[0] if args and args[0] in COMMANDS else "other"
        fz.record(f"command line: {command}", err)  # per subcommand, for the README
        fz.check("command line", err, args)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
