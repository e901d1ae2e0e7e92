"""Command-line interface: ``gearvib demo | modes | simulate | report``.

Every subcommand has ``--help``. Errors are printed as one line on stderr with exit code 2
(bad input) or 1 (a failed computation); nothing is written half.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from gearvib import __version__

__all__ = ["main"]


class CliError(Exception):
    """A user error to print as one line."""


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


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
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
    m.add_argument("--carrier-speed", type=float, default=0.0, metavar="RPM",
                   help="carrier speed for gyroscopic/centripetal terms [min-1] (default 0)")
    m.set_defaults(func=_cmd_modes)

    for register in _EXTRA_COMMANDS:
        register(sub)
    return p


_EXTRA_COMMANDS: list = []


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print("gearvib: interrupted (nothing half-written was kept)", file=sys.stderr)
        return 130
    except (CliError, ValueError, FileNotFoundError, PermissionError, OSError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        print(f"gearvib: error: {msg}", file=sys.stderr)
        return 2
