"""SIGTERM handled as Ctrl-C (issue 30).

Batch schedulers (Slurm, PBS) send SIGTERM at a job's wall-time limit, some time before SIGKILL.
Python's default for SIGTERM ends the process at once: a run in flight lost what it had simulated
since its last periodic checkpoint, and a sweep ended without its index and its invocation log.
With :func:`sigterm_as_interrupt` installed (the command line does, for every command) SIGTERM
raises KeyboardInterrupt in the main thread, exactly as Ctrl-C does, and both set
:data:`REQUESTED`, which the time loop checks after every chunk (:func:`check`): Python runs a
handler at the next bytecode, and where that is a finalizer the KeyboardInterrupt is printed as
"Exception ignored" and lost (seen under ``pytest -n 2``: the run went on); the flag is not lost.
Then the time loop stops its rows
with status ``interrupted`` and writes what it has, a sweep keeps its finished members and logs the
invocation, and the command exits with :func:`exit_code`, 143 (128 + SIGTERM) instead of Ctrl-C's
130. :data:`TERMINATED` says which of the two it was.
"""

from __future__ import annotations

import signal
import threading

TERMINATED = threading.Event()  # set once SIGTERM has arrived (a Ctrl-C leaves it clear)
REQUESTED = threading.Event()  # set by either signal: the time loop stops at its next chunk end
EXIT_INTERRUPTED = 130  # 128 + SIGINT
EXIT_TERMINATED = 143  # 128 + SIGTERM


def raise_interrupt(signum, frame) -> None:
    """A signal handler: KeyboardInterrupt, remembering it in :data:`REQUESTED` and a SIGTERM in
    :data:`TERMINATED`."""
    REQUESTED.set()
    if signum == signal.SIGTERM:
        TERMINATED.set()
    raise KeyboardInterrupt


def sigterm_as_interrupt() -> None:
    """Make SIGTERM raise KeyboardInterrupt, as Ctrl-C does, and both set :data:`REQUESTED` (only
    from the main thread, where Python delivers signals)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, raise_interrupt)
        signal.signal(signal.SIGINT, raise_interrupt)


def check() -> None:
    """Raise KeyboardInterrupt if a signal asked to stop, even if the KeyboardInterrupt that its
    handler raised was lost in a finalizer."""
    if REQUESTED.is_set():
        raise KeyboardInterrupt


def exit_code() -> int:
    """The exit status of an interrupted command: 143 after SIGTERM, else 130."""
    return EXIT_TERMINATED if TERMINATED.is_set() else EXIT_INTERRUPTED


def who() -> str:
    """Who stopped the run, for messages."""
    return "SIGTERM (a batch scheduler's time limit?)" if TERMINATED.is_set() else "the user"


__all__ = ["EXIT_INTERRUPTED", "EXIT_TERMINATED", "REQUESTED", "TERMINATED", "check", "exit_code", "raise_interrupt",
           "sigterm_as_interrupt", "who"]
