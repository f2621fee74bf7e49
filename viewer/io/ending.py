"""How a signal ends hmblur: SIGINT, SIGTERM and SIGHUP raise Terminated in the main thread
(a KeyboardInterrupt, so every `finally` and `except BaseException` that cleans up after
Ctrl-C runs for all three), except inside `held()`, where it waits until the block is done.

`held()` is what makes "create a temp file and note it" one step. A signal mask cannot:
the renderer's threads (numba, Embree, llvmpipe, x264) leave signals unblocked, the kernel
hands the signal to one of them, and Python then runs the handler in the main thread at
its next bytecode, mask or not.
"""
from __future__ import annotations

import signal
from contextlib import contextmanager

ENDING = ("SIGINT", "SIGTERM", "SIGHUP")
_state = {"depth": 0, "pending": None}
received: list[int] = []        # the signal that is ending the program, once one has come


class Terminated(KeyboardInterrupt):
    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _handler(signum, frame):
    if received:                    # already ending: let the clean-up run to its end
        return
    received.append(signum)
    if _state["depth"]:
        _state["pending"] = signum
        return
    raise Terminated(signum)


def catch_signals() -> dict:
    """Install the handler (main thread only); a signal ignored before the program
    started (nohup's SIGHUP) stays ignored. The handlers it replaced."""
    received.clear()
    _state["pending"] = None
    old = {}
    for name in ENDING:
        sig = getattr(signal, name, None)
        if sig is not None and signal.getsignal(sig) is not signal.SIG_IGN:
            old[sig] = signal.signal(sig, _handler)
    return old


def restore_signals(old: dict):
    for sig, handler in old.items():
        signal.signal(sig, handler)


@contextmanager
def held():
    """A signal that comes inside the block ends the program when the block is done."""
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        signum = _state["pending"]
        if not _state["depth"] and signum is not None:
            _state["pending"] = None
            raise Terminated(signum)
