"""``python -m gearvib``: the command-line interface."""

import sys

from gearvib.cli import main

sys.exit(main())
