"""Children that take Ctrl-C as a terminal's process does, whoever started the tests.

A process started in the background by a shell without job control (``cmd &`` in a
script, some CI runners) has SIGINT ignored, and every process it starts inherits that:
Python then installs no ``KeyboardInterrupt`` handler at all, and a test that sends SIGINT
to its child to check what a user's Ctrl-C does checks nothing (the child runs on). Two
such tests failed so in full runs started that way, and pass when started from a
terminal. Their children are started with :func:`terminal_sigint` as ``preexec_fn``.
"""

from __future__ import annotations

import signal


def terminal_sigint() -> None:
    """In the child before it runs: SIGINT at its default, as under a terminal (POSIX)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
