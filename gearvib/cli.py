"""Command line: ``gearvib demo | modes | catalogue | simulate | preset | example | report |
sweep | diagnose | compare``.

Every subcommand has ``--help``. Errors are printed as one line on stderr with exit code 2
(bad input: a description, a setting, an option, an output that exists or cannot be
written, a run refused for its size) or 1 (a failed computation: a numerical blow-up, no
static equilibrium). SIGINT, SIGTERM and SIGHUP stop any command within a second or two with
exit code 130, 143 or 129, leaving no partial output and no temporary file
(:mod:`gearvib.interrupts`). Outputs follow one rule (:mod:`gearvib.outputs`): an existing file
is replaced only with ``--overwrite``, atomically, and every output is checked before the
work starts.

Each subcommand is one ``_cmd_<name>(args)`` function and one block in :func:`_parser`.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import signal
import sys
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, NoReturn

from gearvib import __version__
from gearvib.interrupts import Interrupted, exit_now, pending_signal, signals_as_exceptions

if TYPE_CHECKING:
    from gearvib.compile_helper import CompileHelper

__all__ = ["hide_unused_modules", "main", "prepare_process", "run"]

SINGLE_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""Thread-pool sizes of the BLAS libraries that ``gearvib simulate`` sets to 1 (when unset)."""


class CliError(Exception):
    """A user error to print as one line."""


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, like every other error of gearvib."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"gearvib: error: {self.prog}: {_one_line(message)} (see {self.prog} "
                  "--help)\n")


def _cmd_modes(args: argparse.Namespace) -> int:
    from gearvib.assembly import assemble
    from gearvib.config import load_gearset
    from gearvib.modal import modal_analysis

    model = assemble(load_gearset(args.config))
    result = modal_analysis(model, carrier_speed_rpm=args.carrier_speed)
    if args.json:
        print(result.to_json())
    else:
        print(f"gear set: {model.meta.get('name', args.config)}  ({model.n_dof} DOF, "
              f"{model.n_mesh} meshes)")
        print(result.table())
    return 0


MAX_SIDEBAND_LINES = 20_000
"""Most mesh-harmonic x sideband combinations ``gearvib catalogue`` lists (about 1 s, 1 MB)."""


def _cmd_catalogue(args: argparse.Namespace) -> int:
    from gearvib.catalogue import gear_set_catalogue
    from gearvib.config import load_description
    from gearvib.structure import GearSet

    combos = args.mesh_harmonics * (2 * args.sidebands + 1)
    if combos > MAX_SIDEBAND_LINES:
        raise CliError(f"--mesh-harmonics {args.mesh_harmonics} with --sidebands "
                       f"{args.sidebands} asks for {combos} sideband lines per mesh frequency; "
                       f"admissible: mesh harmonics x (2 sidebands + 1) <= {MAX_SIDEBAND_LINES}")
    described = load_description(args.config)
    if isinstance(described, GearSet):
        cat = gear_set_catalogue(described, reference=args.reference,
                                 speed_rpm=args.speed, mesh_harmonics=args.mesh_harmonics,
                                 harmonics=args.harmonics, sidebands=args.sidebands)
    else:  # shafts and bearings without gears: no meshes, no sidebands
        cat = described.catalogue(reference=args.reference, speed_rpm=args.speed,
                                  harmonics=args.harmonics)
    if args.json:
        print(cat.to_json(visible_only=True))
    else:
        kind = "gear set" if isinstance(described, GearSet) else "machine (shafts, bearings)"
        print(f"{kind}: {cat.name}; lines a sensor on {cat.sensor} can see "
              f"({int(cat.visible.sum())} of {len(cat)})")
        print(cat.table(visible_only=True))
    return 0


MAX_COUNT = 1000
"""Largest harmonic or sideband count accepted on the command line."""


def _int_range(low: int, high: int):
    """An argparse type: an integer in ``low..high`` (the message names the range)."""
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text[:40]!r} is not an integer") from None
        if not low <= v <= high:
            raise argparse.ArgumentTypeError(f"{text[:40]!r} is not admissible (admissible: "
                                             f"{low}..{high})")
        return v

    parse.__name__ = "integer"
    return parse


_non_negative_int = _int_range(0, MAX_COUNT)


MAX_RPM = 1e9
"""Largest speed accepted on the command line [min^-1] (as ``[simulation]``)."""


def _speed_range(text: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text[:40]!r}: expected START:END in min-1, e.g. 0:4000") from None
    if not all(math.isfinite(v) and 0 <= v <= MAX_RPM for v in (lo, hi)):
        raise argparse.ArgumentTypeError(f"{text[:40]!r}: speeds must be finite, 0 .. "
                                         f"{MAX_RPM:g} min-1")
    return lo, hi


def _number(text: str, low: float = -math.inf, high: float = math.inf, *,
            strict: bool = False) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a number") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not admissible (admissible: a "
                                         "finite number)")
    if v < low or (strict and v == low) or v > high:
        parts = [f"{'>' if strict else '>='} {low:g}" if low > -math.inf else "",
                 f"<= {high:g}" if high < math.inf else ""]
        rng = " and ".join(p for p in parts if p)
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not admissible (admissible: {rng})")
    return v


def _limits(low: float = -math.inf, high: float = math.inf, *, strict: bool = False):
    """An argparse type: a finite number in ``[low, high]`` (``strict``: ``> low``)."""
    def parse(text: str) -> float:
        return _number(text, low, high, strict=strict)

    parse.__name__ = "number"
    return parse


def _order_list(text: str) -> list[float]:
    """An argparse type: ``"1,2,24"``, orders > 0 and <= 1e4, at most MAX_CUT_ORDERS."""
    from gearvib.report.study import ANALYSIS_LIMITS, MAX_CUT_ORDERS

    parts = [p.strip() for p in text.split(",")]
    if not text.strip() or any(not p for p in parts):
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a list of orders (e.g. "
                                         "1,2,24)")
    if len(parts) > MAX_CUT_ORDERS:
        raise argparse.ArgumentTypeError(f"{len(parts)} orders; admissible: at most "
                                         f"{MAX_CUT_ORDERS}")
    return [_number(p, 0.0, ANALYSIS_LIMITS["cut_orders"][1], strict=True) for p in parts]


def _order_resolution(text: str) -> float:
    """An argparse type: 0 (automatic) or 0.01..10 orders."""
    from gearvib.report.study import ANALYSIS_LIMITS

    v = _number(text, 0.0, ANALYSIS_LIMITS["order_resolution"][1])
    if 0 < v < ANALYSIS_LIMITS["order_resolution"][0]:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not admissible (admissible: 0 for "
                                         "automatic, or 0.01..10)")
    return v


def _steps(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not an integer") from None
    if not 1 <= v <= 10**15:
        raise argparse.ArgumentTypeError(f"{v} is not admissible (admissible: 1..1e15)")
    return v


def _positive_int(text: str) -> int:
    v = _non_negative_int(text)
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} must be >= 1")
    return v


def run_settings(cfg: dict, args: argparse.Namespace | None = None) -> dict:
    """Run settings: the description's ``[simulation]`` table, overridden by CLI options.

    Checked by :func:`gearvib.simulation.settings.read_run_settings` (an error names the key).
    """
    from gearvib.simulation.settings import read_run_settings

    overrides: dict = {}
    if args is not None:
        if getattr(args, "speed", None):
            overrides["speed_start_rpm"], overrides["speed_end_rpm"] = args.speed
        for key in ("duration", "fs_out", "dt", "input_torque"):
            overrides[key] = getattr(args, key, None)
    return read_run_settings(cfg.get("simulation", {}), overrides)


def _cmd_simulate(args: argparse.Namespace) -> int:
    first = _first_run_start()
    from gearvib.assembly import assemble
    from gearvib.config import gearset_from_dict, load_config
    from gearvib.io import write_netcdf
    from gearvib.outputs import check_output_file
    from gearvib.simulate import simulate
    from gearvib.simulation.settings import conditions_from_settings

    cfg, base = load_config(args.config)  # inputs first, then the output, then the work
    run = run_settings(cfg, args)
    gearset = gearset_from_dict(cfg, base=base)
    cond = conditions_from_settings(run)
    out, removed = check_output_file(args.output, overwrite=args.overwrite)
    _report_removed(removed)
    model = assemble(gearset)
    _first_run(args.quiet, first)
    result = simulate(model, cond, dt=run["dt"], fs_out=run["fs_out"],
                      gyroscopic=run["gyroscopic"], progress=None if not args.quiet else False,
                      config={"gearset": cfg, "run": run}, max_steps=args.max_steps)
    path = write_netcdf(result.to_plain_dataset(), out)  # without importing xarray
    print(f"wrote {path}")
    return 0


def _first_run_start(report: bool = False) -> tuple[str | None, CompileHelper | None]:
    """Whether this run compiles the kernels, asked once at the command's start: the notice
    to print (None on a warm numba cache) and, on a cold one, the compile helper
    (:mod:`gearvib.compile_helper`; ``report``: its order analysis too), started at once so
    that it compiles while this process imports and checks its inputs (None when none could
    start). A command that stops before its run leaves the helper to end on its own after
    its current part."""
    from gearvib.jit_cache import first_run_notice

    notice = first_run_notice()
    if notice is None:
        return None, None
    from gearvib.compile_helper import start

    return notice, start(order_analysis=report)


def _first_run(quiet: bool, first: tuple[str | None, CompileHelper | None], *,
               report: bool = False) -> None:
    """Before the run, when :func:`_first_run_start` found a cold cache (``first``): the
    notice on stderr (unless ``quiet``), and the compilation shared with its helper, or with
    a helper started now (``report``: its order analysis too). The cache is not asked again:
    the helper may have filled part of it meanwhile."""
    notice, helper = first
    if notice is None:
        return
    if not quiet:
        print(notice, file=sys.stderr, flush=True)
    from gearvib.compile_helper import share_first_compilation

    share_first_compilation(order_analysis=report, helper=helper)


def _report_removed(removed: Sequence) -> None:
    if removed:
        names = ", ".join(p.name for p in removed[:3]) + (" ..." if len(removed) > 3 else "")
        print(f"gearvib: removed {len(removed)} temporary file(s) of killed runs: {names}",
              file=sys.stderr)


def _cmd_preset(args: argparse.Namespace) -> int:
    from gearvib.config import preset_text, preset_titles, rig_titles

    if args.name is None:
        titles = preset_titles()
        rigs = rig_titles()
        width = max(len(n) for n in [*titles, *rigs])
        for name, title in titles.items():
            print(f"{name:<{width}}  {title}")
        if rigs:
            print("\nmachines without gears (shafts and rolling bearings, for measured "
                  "reports):")
            for name, title in rigs.items():
                print(f"{name:<{width}}  {title}")
        print("\n`gearvib preset NAME > my-set.toml` writes one to start your own file from.")
        return 0
    sys.stdout.write(preset_text(args.name))
    return 0


def _cmd_example(args: argparse.Namespace) -> int:
    from gearvib.config import example_text, example_titles

    if args.name is None:
        titles = example_titles()
        width = max(len(n) for n in titles)
        for name, title in titles.items():
            print(f"{name:<{width}}  {title}")
        print("\n`gearvib example NAME > study.toml` writes one; `gearvib report study.toml` "
              "renders a study, `gearvib sweep study.toml -o DIR` runs a sweep.")
        return 0
    sys.stdout.write(example_text(args.name))
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from dataclasses import replace
    from pathlib import Path

    from gearvib.outputs import check_output_folder, removed_if_left_empty
    from gearvib.report import build_report, load_study, run_study

    inputs = [Path(i) for i in args.inputs]
    out = Path(args.output)
    report_files = ["report.html", "report.pdf"]
    if _is_measured_report(args, inputs):
        return _measured_report(args, inputs, out, report_files)
    if len(inputs) == 1 and inputs[0].suffix == ".toml":
        study = load_study(inputs[0])
        if args.duration is not None:
            study = study.with_duration(args.duration)
        study = replace(study, analysis=study.analysis.with_cuts(args.orders,
                                                                 args.order_resolution))
        _report_removed(check_output_folder(
            out, [f"{c.name}.nc" for c in study.cases] + report_files,
            overwrite=args.overwrite)[1])
        with removed_if_left_empty(out):
            paths = run_study(study, out, progress=not args.quiet).report
    else:
        for p in inputs:
            if p.suffix not in (".nc", ".nc4"):
                raise CliError(f"{str(p)!r}: expected a study .toml or run .nc files")
        if args.duration is not None:
            raise CliError("--duration applies to a study .toml, not to existing runs")
        _report_removed(check_output_folder(out, report_files, overwrite=args.overwrite)[1])
        with removed_if_left_empty(out):
            paths = build_report(inputs, out, cut_orders=args.orders,
                                 order_resolution=args.order_resolution)
    print(f"report: {paths.html}")
    print(f"        {paths.pdf}")
    return 0


_MEASURED_OPTIONS = ("gearset", "channel", "tacho", "pulses_per_rev", "speed", "angle", "rpm",
                     "reference", "rpm_from", "fs", "time_column", "calibration", "units")


def _is_measured_report(args: argparse.Namespace, inputs: Sequence) -> bool:
    """A measured report: measurement options given, or one input that is no study or run."""
    from gearvib.report.measured import is_simulated_run

    if any(getattr(args, k, None) is not None for k in _MEASURED_OPTIONS):
        return True
    if len(inputs) != 1 or inputs[0].suffix == ".toml":
        return False
    return not (inputs[0].suffix in (".nc", ".nc4") and is_simulated_run(inputs[0]))


def _speed_options(args: argparse.Namespace) -> dict:
    """The speed-reference and file options of a measurement, as load_measurement keywords
    (--calibration and --unit collected into one value or a channel mapping)."""
    out = {k: getattr(args, k) for k in ("tacho", "pulses_per_rev", "speed", "angle", "rpm",
                                         "rpm_from", "fs", "time_column")
           if getattr(args, k, None) is not None}
    for key, option in (("calibration", "--calibration"), ("units", "--unit")):
        pairs = getattr(args, key, None)
        if pairs:
            out[key] = _per_channel(pairs, option)
    return out


def _per_channel(pairs: Sequence[tuple[str | None, object]], option: str) -> object:
    """One value for every channel (``VALUE``) or a mapping (``CH=VALUE``, repeated)."""
    if any(ch is None for ch, _ in pairs):
        if len(pairs) > 1:
            raise CliError(f"{option}: give either one VALUE (every channel) or CH=VALUE per "
                           "channel, not both or twice")
        return pairs[0][1]
    names = [ch for ch, _ in pairs if ch is not None]  # (none is None here)
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise CliError(f"{option}: channel {twice[0]!r} is given twice")
    return dict(pairs)


def _fault_kinds(text: str) -> tuple[str, ...]:
    """An argparse type: ``"crack,eccentricity"``, candidate kinds of a diagnosis, each once."""
    from gearvib.diagnosis.candidates import KINDS

    parts = tuple(p.strip() for p in text.split(","))
    if any(p not in KINDS for p in parts) or len(set(parts)) != len(parts):
        raise argparse.ArgumentTypeError(
            f"{text[:40]!r} is not admissible (admissible: a comma-separated list of "
            f"{', '.join(KINDS)}, each at most once)")
    return parts


def _calibration(text: str) -> tuple[str | None, float]:
    """``CH=VALUE`` or ``VALUE``: a factor in the channel's unit per file unit."""
    ch, sep, value = text.rpartition("=")
    try:
        v = float(value)
    except ValueError:
        v = math.nan
    if (sep and not ch.strip()) or not math.isfinite(v) or not 1e-30 <= abs(v) <= 1e30:
        raise argparse.ArgumentTypeError(
            f"{text[:40]!r} is not admissible (admissible: CH=VALUE or VALUE, VALUE a finite "
            "factor with 1e-30 <= |VALUE| <= 1e30 in the unit per file unit, e.g. "
            "acc=0.102)")
    return (ch.strip() if sep else None), v


def _unit(text: str) -> tuple[str | None, str]:
    """``CH=UNIT`` or ``UNIT``."""
    ch, sep, unit = text.rpartition("=")
    if (sep and not ch.strip()) or not unit.strip() or len(unit) > 64:
        raise argparse.ArgumentTypeError(
            f"{text[:40]!r} is not admissible (admissible: CH=UNIT or UNIT, a unit of 1-64 "
            "characters, e.g. acc=g, acc=m/s2, V)")
    return (ch.strip() if sep else None), unit.strip()


def _measured_report(args: argparse.Namespace, inputs: Sequence, out, files: list[str]) -> int:
    from analysis.measurement import load_measurement
    from gearvib.outputs import check_output_folder, removed_if_left_empty
    from gearvib.report.measured import build_measured_report

    if len(inputs) != 1:
        raise CliError(f"a measured report takes one measurement file, got {len(inputs)} "
                       "inputs")
    if args.duration is not None:
        raise CliError("--duration applies to a study .toml, not to a measurement")
    if args.gearset is not None:  # inputs first: the description, then the file
        from gearvib.config import load_description

        gearset = load_description(args.gearset)  # a gear set, or shafts and bearings
    else:
        gearset = None
    from gearvib.report.study import AnalysisSettings

    settings = AnalysisSettings().with_cuts(args.orders, args.order_resolution)
    m = load_measurement(inputs[0], channel=args.channel, **_speed_options(args))
    _report_removed(check_output_folder(out, files, overwrite=args.overwrite)[1])
    with removed_if_left_empty(out):
        paths = build_measured_report(m, out, gearset=gearset, channel=args.channel,
                                      reference=args.reference, settings=settings)
    if paths.case.model is None and paths.case.rig is None:
        print("gearvib: no --gearset: the report shows the maps, spectra and orders of the "
              "reference shaft only", file=sys.stderr)
    print(f"report: {paths.html}")
    print(f"        {paths.pdf}")
    return 0


def _add_speed_options(p: argparse.ArgumentParser) -> None:
    """--channel, --tacho, --pulses-per-rev, --speed, --angle, --rpm, --rpm-from, --fs,
    --time-column, --calibration, --unit (a measurement's)."""
    p.add_argument("--channel", metavar="CH", help="vibration channel of the measurement "
                   "(default: the first that is not the speed reference)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--tacho", metavar="CH", help="tacho (pulse) channel of the reference "
                   "shaft (default: a channel named 'tacho', else 'speed')")
    g.add_argument("--speed", metavar="CH", help="speed channel of the reference shaft "
                   "[min-1, rpm, rad/s]")
    g.add_argument("--angle", metavar="CH", help="angle channel of the reference shaft "
                   "[rad, degree]")
    g.add_argument("--rpm", type=_limits(0.0, 1e7, strict=True), metavar="N",
                   help="constant reference speed [min-1] for a record without a speed "
                   "channel")
    g.add_argument("--rpm-from", metavar="VAR", help="constant reference speed [min-1] held "
                   "by a scalar variable of the file (e.g. X105RPM of a CWRU record)")
    p.add_argument("--fs", type=_limits(0.0, 1e9, strict=True), metavar="HZ",
                   help="sample rate of a file that states none (CSV without a time column, "
                   "MAT without fs); must agree with a rate the file states")
    p.add_argument("--time-column", metavar="NAME", help="time column of a CSV file (time "
                   "vector of a MAT file), in seconds (default for CSV: 'time')")
    p.add_argument("--calibration", type=_calibration, action="append", metavar="CH=VALUE",
                   help="calibration of a channel in its unit per file unit (repeat per "
                   "channel; VALUE alone: every channel)")
    p.add_argument("--unit", dest="units", type=_unit, action="append", metavar="CH=UNIT",
                   help="unit of a channel's (calibrated) values, e.g. g, m/s2, V (repeat per "
                   "channel; UNIT alone: every channel); g is converted to m s-2")
    p.add_argument("--pulses-per-rev", type=_pulses, metavar="N",
                   help="tacho pulses per revolution, 1..10000 (default: the channel's "
                   "attribute, else 1)")
    p.add_argument("--reference", metavar="MEMBER", help="gear-set member whose speed the "
                   "reference measures (default: the tacho's member, else the input)")


_pulses = _int_range(1, 10_000)


def _cmd_diagnose(args: argparse.Namespace) -> int:
    from pathlib import Path

    from analysis.diagnosis import DEFAULT_THRESHOLD
    from analysis.measurement import load_measurement
    from gearvib.config import load_config
    from gearvib.diagnosis import Record, diagnose
    from gearvib.diagnosis.report import REPORT_FILES, write_diagnosis_report
    from gearvib.outputs import check_output_folder, removed_if_left_empty

    load_config(args.gearset)  # inputs first: the gear set, the records, then the outputs
    speed = _speed_options(args)
    measured = load_measurement(args.measured, channel=args.channel, **speed)
    rec = Record.from_measurement(measured, args.channel, args.reference)
    base = None
    if args.baseline is not None:
        mb = load_measurement(args.baseline, channel=args.channel, **speed)
        base = Record.from_measurement(mb, args.channel, args.reference, name="baseline")
    out = Path(args.output)
    _report_removed(check_output_folder(out, REPORT_FILES, overwrite=args.overwrite)[1])
    with removed_if_left_empty(out):
        d = diagnose(rec, args.gearset, baseline=base,
                     **({"kinds": args.kinds} if args.kinds else {}),
                     library=False if args.no_library else args.library,
                     work_dir=out / "candidates" if args.keep_runs else None,
                     keep_runs=args.keep_runs, workers=args.workers,
                     threshold=DEFAULT_THRESHOLD if args.threshold is None else args.threshold,
                     revolutions=args.revolutions,
                     progress=not (args.quiet or args.json))
        d.attrs["measurement"] = f"{measured.name}: {measured.reference}"
        if base is not None:
            d.attrs["baseline"] = f"measured: {mb.name}"
        paths = write_diagnosis_report(d, out, name=measured.name)
    if args.json:
        print(d.to_json())
        return 0
    for c in d.causes[:5]:
        flag = "" if c.verdict == "unlikely" else c.verdict
        print(f"  {c.score:5.2f}  {c.cause:<17s} {c.member or '-':<9s} {flag}")
    print(f"report: {paths.html}")
    print(f"        {paths.pdf}")
    print(f"        {paths.dataset}")
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    from pathlib import Path

    from analysis.comparison import simulated_channel_name
    from analysis.measurement import load_measurement
    from gearvib.outputs import check_output_folder, removed_if_left_empty
    from gearvib.report.measured_compare import (
        COMPARISON_FILES,
        build_comparison_report,
        compare_with_simulation,
        load_simulated,
    )

    gearset = None
    if args.gearset is not None:  # inputs first: the description, both files, then outputs
        from gearvib.config import load_gearset

        gearset = load_gearset(args.gearset)
    measured = load_measurement(args.measured, channel=args.channel, **_speed_options(args))
    simulated = load_simulated(args.simulated, reference=args.reference)
    channel_name = measured.channel().name
    simulated_channel_name(simulated, args.simulated_channel,
                           None if channel_name is None else str(channel_name))
    out = Path(args.output)
    _report_removed(check_output_folder(out, COMPARISON_FILES, overwrite=args.overwrite)[1])
    with removed_if_left_empty(out):
        cmp = compare_with_simulation(measured, simulated, gearset=gearset,
                                      channel=args.channel,
                                      simulated_channel=args.simulated_channel,
                                      max_order=args.max_order,
                                      order_resolution=args.order_resolution,
                                      calibrated=False if args.normalise else None,
                                      reference=args.reference)
        paths = build_comparison_report(cmp, out)
    print(f"compare: {cmp.result.summary()}")
    print(f"         {paths.html}")
    print(f"         {paths.pdf}")
    print(f"         {paths.netcdf}")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from pathlib import Path

    first = _first_run_start(report=True)  # before the report package's imports (about 2 s)
    from gearvib.outputs import check_output_folder, removed_if_left_empty
    from gearvib.report import Study, run_study
    from gearvib.report.runner import check_study

    out = Path(args.output)
    study = Study.for_presets(["paper-case1", "paper-case2"],
                              title="gearvib demo: the paper's cases 1 and 2")
    if args.duration is not None:
        study = study.with_duration(args.duration)
    check_study(study)  # a run too short for the report is refused before any work
    _report_removed(check_output_folder(
        out, [f"{c.name}.nc" for c in study.cases] + ["report.html", "report.pdf"],
        overwrite=args.overwrite)[1])
    print(f"gearvib demo: simulating the paper's run-ups (0 -> 4000 min-1 in "
          f"{args.duration or 1.0:g} s, cases 1 and 2) into {out}/ ...")
    _first_run(False, first, report=True)
    with removed_if_left_empty(out):
        result = run_study(study, out, progress=not args.quiet)
    for name, path in result.runs.items():
        print(f"  run {name}: {path}")
    print(f"  report: {result.report.html}")
    print(f"          {result.report.pdf}")
    return 0


def _cmd_sweep(args: argparse.Namespace) -> int:
    from gearvib.execution import dask_executor
    from gearvib.sweep import load_sweep, run_sweep

    sweep = load_sweep(args.sweep)
    if args.list:
        cases = sweep.cases()
        paths = [p.path for p in sweep.parameters]
        print("case  " + "  ".join(paths))
        for c in cases:
            print(f"{c.index:<5d} " + "  ".join(c.labels))
        return 0
    if not args.output:
        raise CliError("gearvib sweep: -o/--output DIR is required (the output folder)")
    from gearvib.outputs import check_output_folder

    # the summary and the report follow the output rule of every command; finished case runs
    # (DIR/runs) are always reused: an interrupted sweep resumes without --overwrite
    _report_removed(check_output_folder(
        args.output, ["sweep.nc"] + ([] if args.no_report else ["sweep.html"]),
        overwrite=args.overwrite)[1])
    client = None
    executor = None
    if args.scheduler:
        try:
            executor, client = dask_executor(args.scheduler, timeout=args.connect_timeout)
        except ImportError as exc:
            raise CliError(str(exc)) from None
    try:
        result = run_sweep(sweep, args.output, workers=args.workers, executor=executor,
                           progress=not args.quiet, report=not args.no_report,
                           run_files=not args.no_run_files)
    finally:
        if client is not None:
            client.close()
    print(f"sweep: {result.dataset.sizes['case']} cases ({len(result.simulated)} simulated, "
          f"{len(result.reused)} reused, {len(result.failed)} failed) in "
          f"{result.wall_time_s:.1f} s")
    print(f"       {result.path}")
    if result.report is not None:
        print(f"       {result.report}")
    if result.failed:
        first = result.failed[0]
        print(f"gearvib: failed: {len(result.failed)} case(s), e.g. case {first}: "
              f"{result.dataset['failure'].values[first]}", file=sys.stderr)
        return 1
    return 0


def _workers(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--workers {text!r} is not an integer") from None
    if not 1 <= v <= 512:
        raise argparse.ArgumentTypeError(f"--workers {v}: admissible 1..512")
    return v


_revolutions = _int_range(4, 256)


_OVERWRITE_HELP = ("replace existing output files (atomically, once the new ones are "
                   "complete); without it an existing output is an error")


def _add_output_options(p: argparse.ArgumentParser, output_help: str, *,
                        required: bool = False, default: str | None = None) -> None:
    """The options every command that writes files has: ``-o``, ``-f`` and ``-q``."""
    p.add_argument("-o", "--output", required=required, default=default, help=output_help)
    p.add_argument("-f", "--overwrite", action="store_true", help=_OVERWRITE_HELP)
    p.add_argument("-q", "--quiet", action="store_true", help="no progress display")


def _parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="gearvib",
        description="Vibration simulation and order analysis of planetary gear sets.",
    )
    p.add_argument("--version", action="version", version=f"gearvib {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    m = sub.add_parser("modes", help="natural frequencies and mode types of a gear set",
                       description="Modal analysis of the mean-stiffness system.")
    m.add_argument("config", help="TOML file or preset name (e.g. paper-case1)")
    m.add_argument("--json", action="store_true", help="print JSON instead of a table")
    m.add_argument("--carrier-speed", type=_limits(-MAX_RPM, MAX_RPM), default=0.0,
                   metavar="RPM",
                   help="carrier speed for gyroscopic/centripetal terms [min-1] (default 0)")
    m.set_defaults(func=_cmd_modes)

    c = sub.add_parser("catalogue", help="kinematic frequency catalogue of a gear set",
                       description="Every order-locked frequency of the gear set at one speed: "
                       "shaft orders, mesh frequencies and harmonics of every stage, planet "
                       "pass, sun/planet/ring fault frequencies (gear_fault for gears on fixed "
                       "axes: parallel stages), hunting-tooth and assembly-phase frequencies, "
                       "planet-pass sidebands (only those the planet phasing lets through to a "
                       "sensor on the fixed member), the shaft-rate sidebands of fixed-axis "
                       "meshes, and the defect frequencies of the "
                       "description's [[rolling_bearing]] tables (bearing_ftf, bearing_bpfo, "
                       "bearing_bpfi, bearing_bsf). Families: see "
                       "docs/catalogue-identification.md.")
    c.add_argument("config", help="TOML file or preset name")
    c.add_argument("--speed", type=_limits(0.0, MAX_RPM, strict=True), required=True,
                   metavar="RPM",
                   help="speed of the reference shaft [min-1]")
    c.add_argument("--reference", metavar="MEMBER",
                   help="reference shaft of the orders (default: the input member)")
    c.add_argument("--mesh-harmonics", type=_positive_int, default=7, metavar="M",
                   help="mesh harmonics listed, with their sidebands (default 7)")
    c.add_argument("--harmonics", type=_positive_int, default=3, metavar="H",
                   help="harmonics of shaft, planet-pass and fault lines (default 3)")
    c.add_argument("--sidebands", type=_non_negative_int, default=2, metavar="K",
                   help="sidebands up to K planet-pass frequencies, or K orders of each gear "
                   "of a fixed-axis mesh (default 2)")
    c.add_argument("--json", action="store_true",
                   help='print {"reference": ..., "lines": [{"family", "harmonic", "sideband", '
                   '"member", "frequency_hz", "order", "phasing"}, ...]} (phasing: the '
                   'planet-phasing factor at the sensor, null where it does not apply)')
    c.set_defaults(func=_cmd_catalogue)

    s = sub.add_parser("simulate", help="simulate a run-up and write it as netCDF",
                       description="Simulate a run-up (speed ramp at the input, constant "
                       "torque) and write tooth forces, bearing forces, displacements and "
                       "speeds as a CF netCDF4 file.")
    s.add_argument("config", help="TOML file or preset name")
    _add_output_options(s, "output .nc file", required=True)
    s.add_argument("--speed", type=_speed_range, metavar="START:END",
                   help="input speed range [min-1], e.g. 0:4000")
    s.add_argument("--duration", type=_limits(1e-6, 1e7), metavar="S",
                   help="run-up duration [s]")
    s.add_argument("--fs", dest="fs_out", type=_limits(0.0, 1e12, strict=True), metavar="HZ",
                   help="output sample rate [Hz] (default >= 20 kHz)")
    s.add_argument("--dt", type=_limits(0.0, 1.0, strict=True), metavar="S",
                   help="integration step [s] (default: "
                   "from the highest natural and mesh frequency)")
    s.add_argument("--torque", dest="input_torque", type=_limits(-1e12, 1e12), metavar="NM",
                   help="input torque [N m] (default from the description)")
    s.add_argument("--max-steps", type=_steps, default=None, metavar="N",
                   help="time budget: refuse runs of more internal steps (default 1e9, about "
                   "50 min for a small set)")
    s.set_defaults(func=_cmd_simulate)

    pr = sub.add_parser("preset", help="list the built-in gear sets, or print one's TOML",
                        description="Without NAME: list the presets with their titles. With "
                        "NAME: print the preset's TOML (comments included) to start a file "
                        "from, e.g. `gearvib preset wolfrom-example > my-set.toml`.")
    pr.add_argument("name", nargs="?", metavar="NAME", help="preset name")
    pr.set_defaults(func=_cmd_preset)

    ex = sub.add_parser("example", help="list the example studies and sweeps, or print one",
                        description="Without NAME: list the example recipes shipped with "
                        "gearvib (studies for `gearvib report`, sweeps for `gearvib sweep`) "
                        "with their titles. With NAME: print its TOML to start from, e.g. "
                        "`gearvib example paper-cases > study.toml`.")
    ex.add_argument("name", nargs="?", metavar="NAME", help="example name")
    ex.set_defaults(func=_cmd_example)

    r = sub.add_parser("report", help="order-analysis report (HTML + PDF)",
                       description="Render a study recipe (TOML: simulates its cases), "
                       "existing run files (.nc) or one measurement (any readable format: "
                       "UFF, TDMS, MAT, WAV, CSV, netCDF; with --gearset CONFIG its mesh "
                       "orders, natural frequencies and catalogue) into report.html and "
                       "report.pdf. See docs/measurements.md.")
    r.add_argument("inputs", nargs="+", help="a study .toml, one or more run .nc files, or "
                   "one measurement file")
    r.add_argument("--gearset", metavar="CONFIG", help="gear set of a measurement (TOML file "
                   "or preset name), or a machine without gears (type = \"shafts\": shafts "
                   "and rolling bearings, e.g. the preset cwru-drive-end)")
    _add_speed_options(r)
    _add_output_options(r, "output folder (default ./gearvib-report)",
                        default="gearvib-report")
    r.add_argument("--duration", type=_limits(1e-6, 1e7), metavar="S",
                   help="override the run-up duration of a study [s]")
    r.add_argument("--orders", type=_order_list, metavar="O1,O2,...",
                   help="orders of the reference shaft to cut besides the 1x-3x mesh "
                   "orders, e.g. 1,2,24 (each > 0 and <= 1e4, at most 20); see "
                   "docs/reports.md")
    r.add_argument("--order-resolution", type=_order_resolution, metavar="R",
                   help="resolution of the order cuts [orders], 0.01..10 (default: "
                   "automatic, 1/4 order or finer where orders are closer)")
    r.set_defaults(func=_cmd_report)

    g = sub.add_parser("diagnose", help="fault-cause diagnosis of a measurement (simulation "
                       "in the loop)", description="Rank the candidate causes (tooth faults of "
                       "every member of every stage: suns, planets, rings, the pinions and "
                       "wheels of parallel stages; eccentricity, pin position errors) of what a "
                       "measurement shows beyond a healthy baseline: every candidate is "
                       "simulated on the gear set (sweep machinery, all cores) and scored by "
                       "how well its change explains the measured one. Writes report.html, "
                       "report.pdf and diagnosis.nc. The candidates' order profiles are kept in "
                       "a library and reused by the next diagnosis at the same operating "
                       "point. See docs/diagnosis.md.")
    g.add_argument("measured", metavar="MEASURED", help="measurement file (any readable "
                   "format) or a gearvib run .nc")
    g.add_argument("--gearset", metavar="CONFIG", required=True, help="the healthy gear set "
                   "(TOML file or preset name)")
    g.add_argument("--baseline", metavar="HEALTHY", help="a measurement of the healthy gearbox "
                   "with the same sensor (default: the healthy simulation)")
    _add_speed_options(g)
    _add_output_options(g, "output folder (default ./gearvib-diagnosis)",
                        default="gearvib-diagnosis")
    g.add_argument("--workers", type=_workers, metavar="N", help="local worker processes of "
                   "the candidate simulations (default: the CPUs available)")
    g.add_argument("--threshold", type=_limits(0.0, 1.0, strict=True), default=None,
                   metavar="S", help="score above which a cause is likely, 0 < S < 1 "
                   "(default 0.4)")
    g.add_argument("--revolutions", type=_revolutions, default=16, metavar="N",
                   help="revolutions of the reference shaft (the carrier of a planetary set; "
                   "docs/diagnosis.md) per averaged segment, 4..256 (resolution 1/N orders; "
                   "default 16)")
    g.add_argument("--kinds", type=_fault_kinds, metavar="K[,K...]", help="candidate gear "
                   "faults to simulate, from crack, pitting, broken_tooth, eccentricity, "
                   "pin_error (default: all; declared bearings are always checked)")
    lib = g.add_mutually_exclusive_group()
    lib.add_argument("--library", metavar="DIR", help="folder of the candidate library, private "
                     "to the user (default: $GEARVIB_DIAGNOSIS_LIBRARY, else "
                     "~/.cache/gearvib/diagnosis)")
    lib.add_argument("--no-library", action="store_true", help="simulate every candidate and "
                     "keep nothing")
    g.add_argument("--keep-runs", action="store_true", help="also write the simulated "
                   "candidate runs to DIR/candidates/runs")
    g.add_argument("--json", action="store_true", help='print {"threshold": ..., "causes": '
                   '[{"cause", "member", "score", "evidence"}, ...]}, best first')
    g.set_defaults(func=_cmd_diagnose)
    cp = sub.add_parser("compare", help="a measurement against a simulated run (HTML, PDF, "
                        "netCDF)", description="Compare a measurement with a simulated run "
                        "(its virtual sensor, or a force / transmission-error channel; its "
                        "tacho, else its input angle) on one reference shaft: order spectra "
                        "and rpm-order maps on common grids, matched / measured-only / "
                        "simulated-only order lines with order and level differences, the "
                        "measured natural-frequency lines against the model's modes and the "
                        "stiffnesses most likely responsible for an offset (modal strain "
                        "energy). Writes comparison.html, comparison.pdf and comparison.nc. "
                        "See docs/measurements.md.")
    cp.add_argument("measured", help="measurement file (any readable format)")
    cp.add_argument("simulated", help="simulated run (.nc; a virtual sensor and a tacho are "
                    "optional)")
    _add_output_options(cp, "output folder (default ./gearvib-compare)",
                        default="gearvib-compare")
    cp.add_argument("--gearset", metavar="CONFIG", help="the model (TOML file or preset; "
                    "default: the gear set stored in the simulated run)")
    _add_speed_options(cp)
    cp.add_argument("--simulated-channel", metavar="CH", help="channel of the simulated run: "
                    "a virtual sensor, normal_force:MESH (net tooth force [N]), "
                    "mesh_deflection:MESH (DTE [m]) or bearing_force:BEARING [N] (default: the "
                    "measured channel's name, else the first sensor, else the first "
                    "ring-planet mesh force); levels are normalised when the units differ")
    cp.add_argument("--max-order", type=_limits(0.0, 1e5, strict=True), metavar="N",
                    help="highest order compared (default: the alias-free order of both)")
    cp.add_argument("--order-resolution", type=_limits(0.01, 10.0), default=0.25,
                    metavar="R", help="order resolution (ENBW) of both analyses, 0.01..10 "
                    "(default 0.25)")
    cp.add_argument("--normalise", action="store_true", help="normalise each record to its "
                    "strongest order line (default: calibrated dB when the units agree)")
    cp.set_defaults(func=_cmd_compare)

    d = sub.add_parser("demo", help="the paper's example: two run-ups and their report",
                       description="Simulate the paper's cases 1 (planets at 120 deg) and 2 "
                       "(0, 122.45, 244.90 deg), 0 -> 4000 min-1 in 1 s at constant input "
                       "torque, and write the netCDF runs and an order-analysis report.")
    _add_output_options(d, "output folder (default ./gearvib-demo)", default="gearvib-demo")
    d.add_argument("--duration", type=_limits(1e-6, 1e7), metavar="S",
                   help="run-up duration [s] (default 1; shorter for a quick look)")
    d.set_defaults(func=_cmd_demo)

    w = sub.add_parser("sweep", help="parameter sweep: many runs, one summary (sweep.nc)",
                       description="Run every case of a sweep description (TOML: base gear set, "
                       "[simulation] settings, [[parameter]] tables with key paths and values) on "
                       "a local process pool or a Dask cluster; one netCDF run per case "
                       "(resumable), the combined summary DIR/sweep.nc and the report "
                       "DIR/sweep.html. See docs/sweeps.md.")
    w.add_argument("sweep", help="sweep description (.toml)")
    _add_output_options(w, "output folder (required unless --list)")
    w.add_argument("--workers", type=_workers, metavar="N",
                   help="local worker processes (default: the CPUs available; 1 runs in this "
                   "process)")
    w.add_argument("--scheduler", metavar="ADDRESS",
                   help="address of a Dask scheduler, e.g. tcp://10.0.0.5:8786 (needs "
                   "gearvib[dask]; the workers must see the output folder)")
    w.add_argument("--connect-timeout", type=_limits(0.0, 3600.0, strict=True), default=10.0,
                   metavar="S", help="seconds to reach the scheduler, 0 < S <= 3600 (default "
                   "10; where nothing listens the sweep fails at once)")
    w.add_argument("--list", action="store_true", help="print the cases and exit")
    w.add_argument("--no-report", action="store_true", help="write sweep.nc only")
    w.add_argument("--no-run-files", action="store_true",
                   help="keep the runs in memory for their summaries, write no DIR/runs/*.nc "
                   "(faster, most of all batched; nothing to resume from)")
    w.set_defaults(func=_cmd_sweep)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code.

    SIGINT, SIGTERM and SIGHUP raise :class:`gearvib.interrupts.Interrupted` while a command
    runs. After the clean-up (temporary files removed, the message printed) the process exits
    at once with ``128 + signal number`` (``os._exit``): work abandoned by the interrupt (a
    netCDF write in its worker thread) is not waited for, and the interpreter's shutdown,
    which takes 0.5-1.3 s once xarray and numba are loaded, is skipped. A signal whose
    exception library code swallowed or converted ends the command the same way.
    """
    with signals_as_exceptions():
        return _run_command(argv)


def run() -> None:
    """The ``gearvib`` command (console script, ``python -m gearvib``): :func:`main`, then exit.

    The process leaves with ``os._exit`` right after the command, with the signal handlers
    still active: the interpreter's shutdown (0.5-1.3 s with xarray and numba loaded) is
    skipped, so a signal cannot arrive in it and end the process with the default action
    instead of exit code 130/143. Standard streams and logging are flushed first; every output
    file is complete and closed by then.
    """
    import logging

    prepare_process(sys.argv[1:])
    with signals_as_exceptions():
        try:
            code = _run_command(None)
        except SystemExit as exc:  # --help, --version, option errors
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            if exc.code is not None and not isinstance(exc.code, int):
                print(exc.code, file=sys.stderr)
        if hasattr(signal, "pthread_sigmask"):  # done: a signal from now on changes nothing
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM,
                                                      *([signal.SIGHUP]
                                                        if hasattr(signal, "SIGHUP") else [])})
        logging.shutdown()
        exit_now(code)


def prepare_process(argv: Sequence[str]) -> None:
    """Set up the console script's process for the command in ``argv``, before any import.

    * :func:`hide_unused_modules`.
    * ``simulate``: one BLAS thread (:data:`SINGLE_THREAD_VARIABLES` = 1 unless set; read when
      NumPy loads its BLAS). Its matrices are small: more threads only spin on the other
      cores (30 % of the command's CPU time on 2 cores), and the results are those of the
      sweep workers and of a one-core machine, which run with one BLAS thread too (a
      multi-threaded product can round differently).
    * ``simulate``: ``yaml`` hidden (as by :func:`hide_unused_modules`) unless the working
      directory holds a ``.numba_config.yaml``: numba imports it (0.015 s) only to read that
      file.
    * ``simulate``: :mod:`analysis.jit` (numba's cache folder, which :mod:`gearvib.kernels`
      prepares), :mod:`analysis.threads` (the one-thread BLAS limit of
      :func:`gearvib.simulate.simulate`) and :mod:`analysis.netcdf_lock` (the lock of the
      run's file) are loaded without the package :mod:`analysis`,
      whose import registers its xarray accessor and so imports xarray and pandas (0.4 s) in
      a command that writes its run with netCDF4 directly
      (:class:`gearvib.cfdata.PlainDataset`). Each module is the same file under its own
      name; a later ``import analysis`` works as usual.

    Only the console script does this (its process ends with the command), never
    :func:`main`, which may run inside a user's program.
    """
    hide_unused_modules(argv)
    command = next((a for a in argv if not a.startswith("-")), None)
    if command != "simulate":
        return
    import os

    if "numpy" not in sys.modules:
        for name in SINGLE_THREAD_VARIABLES:
            os.environ.setdefault(name, "1")
    if not os.path.exists(".numba_config.yaml"):  # numba's config file, read from the cwd
        # None in sys.modules blocks the import (importlib's documented rule; not in the stub)
        sys.modules.setdefault("yaml", None)  # type: ignore[arg-type]
    _load_without_package("analysis.jit")
    _load_without_package("analysis.threads")
    _load_without_package("analysis.netcdf_lock")


def _load_without_package(name: str) -> None:
    """Put the submodule ``name`` into ``sys.modules`` without importing its package."""
    import importlib.util
    import os

    package, _, module = name.rpartition(".")
    if package in sys.modules or name in sys.modules:
        return
    spec = importlib.util.find_spec(package)  # a top-level package: found, not imported
    if spec is None or not spec.submodule_search_locations:
        return
    path = os.path.join(next(iter(spec.submodule_search_locations)), f"{module}.py")
    sub = importlib.util.spec_from_file_location(name, path)
    if sub is None or sub.loader is None or not os.path.isfile(path):
        return
    mod = importlib.util.module_from_spec(sub)
    sys.modules[name] = mod
    try:
        sub.loader.exec_module(mod)
    except BaseException:
        del sys.modules[name]
        raise


def hide_unused_modules(argv: Sequence[str]) -> None:
    """Make optional modules that libraries probe for, and gearvib never uses, unimportable.

    * ``dask`` and ``distributed``: with dask installed, xarray imports them to check every
      new variable and every netCDF write for dask arrays, 0.3-0.7 s of imports in a command
      that never holds one (half the whole time of a 1 s ``simulate``). Kept for ``sweep``,
      the one command that may use a Dask cluster.
    * ``cffi``: numba's typing registry imports it (and its C parser, 0.1 s) at the first
      compilation or cache load, for calling cffi functions, which gearvib does not do.

    An entry of ``None`` in ``sys.modules`` makes ``importlib.util.find_spec`` report the module
    as missing and ``import`` raise ImportError, so the libraries take their documented
    no-dask / no-cffi paths; the files written are the same. Only the console script does this
    (its process ends with the command), never :func:`main`, which may run inside a user's
    program.
    """
    hidden = ["cffi"] if "sweep" in argv else ["cffi", "dask", "distributed"]
    for name in hidden:
        # None in sys.modules blocks the import (importlib's documented rule; not in the stub)
        sys.modules.setdefault(name, None)  # type: ignore[arg-type]


EXIT_BROKEN_PIPE = 128 + 13
"""Exit code when the reader of the output went away (``gearvib ... | head``): 128 + SIGPIPE,
what the shell reports for a Unix tool ended by that signal; nothing is printed."""


def _quiet_broken_pipe() -> int:
    """Point stdout at ``/dev/null`` (the interpreter's final flush must not fail again)."""
    import os

    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    return EXIT_BROKEN_PIPE


def _run_command(argv: Sequence[str] | None) -> int:
    try:
        code = _main(argv)
        sys.stdout.flush()  # a closed pipe shows here at the latest
    except BrokenPipeError:
        return _quiet_broken_pipe()
    except BaseException as exc:
        sig = pending_signal()
        if sig is None and isinstance(exc, KeyboardInterrupt):
            sig = signal.SIGINT
        if sig is None:
            raise
        _exit_interrupted(sig)
    sig = pending_signal()
    if sig is not None:  # received, and its exception swallowed by library code
        _exit_interrupted(sig)
    return code


def _exit_interrupted(signum: int) -> None:
    try:
        name = signal.Signals(signum).name
    except ValueError:
        name = f"signal {signum}"
    print(f"gearvib: interrupted by {name} (nothing half-written was kept)", file=sys.stderr)
    exit_now(128 + signum)


def _main(argv: Sequence[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if getattr(args, "max_steps", 0) is None:
        from gearvib.simulation.run_size import DEFAULT_MAX_STEPS

        args.max_steps = DEFAULT_MAX_STEPS
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        try:
            return int(args.func(args) or 0)
        except BrokenPipeError:
            raise
        except Exception as exc:
            sig = pending_signal()
            if sig is not None:  # an interrupt that library code turned into another error
                raise Interrupted(sig) from None
            return _error(exc)


def _error(exc: Exception) -> int:
    """Print a documented error as one line; returns the exit code (re-raises the rest)."""
    from gearvib.config import ConfigError
    from gearvib.simulation.errors import SimulationError

    if isinstance(exc, SimulationError):  # a failed computation, e.g. a numerical blow-up
        print(f"gearvib: failed: {_one_line(exc)}", file=sys.stderr)
        return 1
    if isinstance(exc, CliError | ConfigError | ValueError | OSError):
        print(f"gearvib: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    if isinstance(exc, MemoryError):
        print("gearvib: failed: out of memory (a size the input checks did not foresee; "
              "please report it with the command)", file=sys.stderr)
        return 1
    if isinstance(exc, RuntimeError):
        print(f"gearvib: failed: {_one_line(exc)}", file=sys.stderr)
        return 1
    raise exc


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"gearvib: warning: {_one_line(message)}", file=sys.stderr)


MAX_WORD = 80
"""Longest run of non-blank characters an error message shows whole (longer ones are cut)."""

MAX_MESSAGE = 1000
"""Longest error message printed [characters]; the rest is cut."""


def _cut(word: str) -> str:
    """A long word's start and end (a path keeps its file name) and its length."""
    if len(word) <= MAX_WORD:
        return word
    return f"{word[:24]}...[{len(word)} characters]...{word[-40:]}"


def _one_line(exc: BaseException | Warning | str) -> str:
    """The message on one line, control characters escaped and long values cut (messages may
    echo input: a word longer than :data:`MAX_WORD` characters keeps its start and end, the
    message at most :data:`MAX_MESSAGE`)."""
    text = " ".join(_cut(w) for w in str(exc).split())
    if not text:
        return type(exc).__name__
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    return text if len(text) <= MAX_MESSAGE else text[:MAX_MESSAGE - 3] + "..."
