"""Child processes that Ctrl-C reaches, however the test run was started."""

from __future__ import annotations

import signal


def ctrl_c_default() -> None:
    """``preexec_fn`` for a child a test interrupts: SIGINT back to its default. A shell starts background
    jobs with SIGINT ignored and a child inherits that, so a suite run with ``&`` (or by a runner that ignores
    it) would otherwise send a Ctrl-C the command never sees."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
