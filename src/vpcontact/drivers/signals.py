"""SIGINT and SIGTERM during a run or a study: the run stops at the end of its current step (a study stops its
runs), writes what exists, and the command line exits with EXIT_SIGNAL's status."""

import signal
import threading

SIGNAL_NAMES = {signal.SIGINT: "SIGINT", signal.SIGTERM: "SIGTERM"}
#: The exit status of the command line after a run or a study stopped by a signal.
EXIT_SIGNAL = {signal.SIGINT: 130, signal.SIGTERM: 143}


class StopOnSignals:
    """While active (main thread only), SIGINT and SIGTERM ask the time loop to stop at the end of the
    current step (a study: to stop its runs, see :func:`~vpcontact.drivers.studies.running.run_study`); a second
    signal of the same kind acts at once (the default action)."""

    def __init__(self):
        self.signal: int | None = None
        self._previous = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for number in SIGNAL_NAMES:
                self._previous[number] = signal.signal(number, self._handle)
        return self

    def __exit__(self, *exc):
        for number, handler in self._previous.items():
            signal.signal(number, handler)
        return False

    def _handle(self, number, frame):
        self.signal = number
        signal.signal(number, self._previous.get(number, signal.SIG_DFL))  # a second one is not deferred

    def reason(self) -> str | None:
        return None if self.signal is None else f"stopped by {SIGNAL_NAMES[self.signal]}"
