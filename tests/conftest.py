"""Session set-up shared by every test package."""

from __future__ import annotations

import signal
import threading

# A pytest-xdist worker may run with SIGINT ignored; an ignored signal is inherited by every
# subprocess, so the interrupt tests' commands would not stop on Ctrl-C. Python's own handler
# here restores the default in the children (a handler is reset to SIG_DFL on exec).
if threading.current_thread() is threading.main_thread():
    signal.signal(signal.SIGINT, signal.default_int_handler)
