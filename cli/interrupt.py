"""SIGINT, SIGTERM and SIGHUP unwind the command as Ctrl-C does, so what
is half written is removed on the way out.

Python turns SIGINT into ``KeyboardInterrupt``, but SIGTERM (``kill``, a batch
system's time limit, ``docker stop``) and SIGHUP (the terminal or the ssh
session closed) end the process where it stands: a temporary file being
written stays behind. :func:`signals_unwind` raises :class:`Terminated`, a
``KeyboardInterrupt``, for SIGTERM and SIGHUP, so every
``finally`` and ``except BaseException`` runs for both (the atomic writers
delete their temporary file, a LocalCluster is shut down) and ``main`` exits
130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP (128 + the signal's
number, as a shell reports a process the signal ended).

A second signal while the first unwinds ends the process at once, with the
signal's default action: for someone who does not want to wait for the clean
up. What that can leave (a hidden temporary file ``.NAME.*`` beside an output)
is removed by the next run writing the same output.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class Terminated(KeyboardInterrupt):
    """A signal other than SIGINT asked the process to stop."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        super().__init__(signal.Signals(signum).name)


def exit_code(interrupt: KeyboardInterrupt) -> int:
    """128 + the signal's number: 130 for SIGINT (or Ctrl-C), 143 for SIGTERM,
    129 for SIGHUP."""
    signum = interrupt.signum if isinstance(interrupt, Terminated) else signal.SIGINT
    return 128 + int(signum)


@contextmanager
def signals_unwind() -> Iterator[None]:
    """Inside the block, SIGINT raises ``KeyboardInterrupt`` and SIGTERM or
    SIGHUP :class:`Terminated`; a second one of any ends the process at once.
    The handlers in place before are restored on the way out. Only the main
    thread may install handlers: elsewhere the block changes nothing."""
    received: list[int] = []

    def unwind(signum: int, frame: FrameType | None) -> None:
        if received:  # already unwinding: stop now, as the signal would have
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
            return
        received.append(signum)
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Terminated(signum)

    try:
        previous = {signum: signal.signal(signum, unwind) for signum in SIGNALS}
    except ValueError:  # not the main thread (main() called from a thread)
        yield
        return
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
