"""Clean stops on SIGINT (Ctrl-C) and SIGTERM.

Inside :func:`handle_signals` a signal only sets a flag: the FMUs run python
code in this interpreter (pythonfmu), and an exception raised in the middle
of one of their calls would come back as an fmi2Fatal status.  The master
checks the flag between FMU calls (after every step, between the
instantiations) and raises :class:`Interrupted` from its own code, so that
every instance is terminated and freed and every extracted folder removed.
A second signal while the first is pending raises at once.
"""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["Interrupted", "handle_signals", "check", "PENDING", "exit_code"]

PENDING = [0]  # signal number received and not yet acted on, 0 if none


class Interrupted(KeyboardInterrupt):
    """The run was stopped by a signal.

    Attributes
    ----------
    signum : int
        The signal (``signal.SIGINT`` or ``signal.SIGTERM``).
    partial : ResultArray or None
        Set by :meth:`orchestration.Master.simulate`: the rows recorded
        before the stop.
    """

    def __init__(self, signum: int):
        self.signum = signum
        self.partial = None
        super().__init__(f"stopped by {signal.Signals(signum).name}")


def exit_code(signum: int) -> int:
    """Shell convention: 128 + signal number (130 for SIGINT, 143 for SIGTERM)."""
    return 128 + int(signum)


def check() -> None:
    """Raise :class:`Interrupted` if a signal arrived."""
    if PENDING[0]:
        signum, PENDING[0] = PENDING[0], 0
        raise Interrupted(signum)


def _handler(signum, frame) -> None:
    if PENDING[0]:
        PENDING[0] = 0
        raise Interrupted(signum)
    PENDING[0] = signum


@contextmanager
def handle_signals(signals=(signal.SIGINT, signal.SIGTERM)):
    """Within the block, SIGINT/SIGTERM set :data:`PENDING` instead of raising.

    Does nothing outside the main thread (Python delivers signals there only).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, _handler) for s in signals}
    PENDING[0] = 0
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
