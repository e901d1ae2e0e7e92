"""``python -m gearvib``: the command-line interface."""

from gearvib.cli import run

run()
