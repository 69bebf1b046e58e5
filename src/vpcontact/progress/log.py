"""The command line's reporter, :class:`Log`: lines on a stream (stderr), each flushed as it is written and
headed by the time since the run started::

    [00:05] factorization: A0 = A + r NᵀN, 100,776 dofs, by MKL PARDISO; expected: 43.9 s with ...
    [00:10] factorization: MKL PARDISO's analysis: the factor and the Schur complement take about 1.31 GiB ...
    [00:20] factorization: running for 14.3 s, about 43.9 s expected
    [01:23] factorization: a factor of 124,588,208 entries (1 min 17 s)

- a set-up phase (:meth:`Progress.phase`) prints a line when it ends, with its wall time; one that lasts
  more than START_SECONDS prints a line as it starts too, so that the last line says what is running, and
  then the notes made during it (say, the memory its factor will take: of no interest in a short phase);
- the time steps (:meth:`Progress.steps`): on a terminal, a bar (:mod:`.bar`), the other lines printed above it;
  elsewhere (a pipe, a file, a batch queue: a bar's carriage returns show nothing there until the end) a
  line per step, throttled when steps are short (STEP_LINE_SECONDS, STEP_LINE_SHARE): the first and the
  last step of a session and every step that took LIFE_SECONDS or more, in between at most a line a second
  and a line per 1 % of the steps;
- life: while a phase, a step or a study's runs go on and nothing has been printed for LIFE_SECONDS, a line
  says what runs and for how long (a step: its Newton iteration and residual too), then again after 20,
  40 and every LIFE_MAX_SECONDS of silence (off a terminal; on one, the bar's clock is kept ticking);
  a compiled routine that keeps Python's interpreter lock while it works delays them until it returns
  (measured: the start line of a condensation of 1,951 contact nodes, due after a second, came after 8 s);
- held back: the lines of the first ``hold`` seconds (HOLD_SECONDS for a run) are kept until then, or
  until the first step, and dropped if the run ends on an exception before (:meth:`Progress.close` with
  ``discard``): a case refused in its set-up prints its one line of refusal and nothing else. (A case
  refused later, after a long set-up, has the lines of that set-up before its refusal.)

A watcher thread (started by the first phase or time loop of a :class:`Log`) does what happens between
the reports: the end of the hold, late start lines, life lines. A study's parent process, which forks its
workers, runs no thread: its loop calls :meth:`Progress.tick` as it polls them.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TextIO

from ..errors import flag
from .bar import Bar, is_terminal
from .reporter import SILENT, Phase, Progress, Runs, StepReport, Steps

#: A run's lines are held back for this long (see the module's docstring).
HOLD_SECONDS = 5.0
#: A phase that has lasted this long gets its start line.
START_SECONDS = 1.0
#: Silence after which a line says what is running; the next one after twice as long, and so on up to
#: LIFE_MAX_SECONDS.
LIFE_SECONDS = 10.0
LIFE_MAX_SECONDS = 60.0
#: Off a terminal, a time step's line is printed when at least STEP_LINE_SECONDS and STEP_LINE_SHARE of the
#: steps have passed since the last line (or LIFE_SECONDS, whatever the steps done); the first and the last
#: step of a session always, and a step that took LIFE_SECONDS or more.
STEP_LINE_SECONDS = 1.0
STEP_LINE_SHARE = 0.01
#: How often the watcher thread looks.
TICK_SECONDS = 0.2


def stamp(seconds: float) -> str:
    """The time since the start that heads a line: [mm:ss], or [h:mm:ss] from an hour on."""
    whole = int(seconds)
    minutes, rest = divmod(whole, 60)
    if minutes < 60:
        return f"[{minutes:02d}:{rest:02d}]"
    return f"[{minutes // 60}:{minutes % 60:02d}:{rest:02d}]"


@contextmanager
def reporting(progress: bool | Progress | None, **options) -> Iterator[Progress]:
    """The reporter ``progress`` stands for (the ``progress`` argument of the API's entry points): itself
    (its owner closes it), SILENT for False or None, for True a :class:`Log` on stderr (made with
    ``options``), closed at the end."""
    if isinstance(progress, Progress):
        yield progress
    elif flag("progress", False if progress is None else progress):
        with Log(**options) as log:
            yield log
    else:
        yield SILENT


class Log(Progress):
    """Lines on ``stream`` (default: stderr), a tqdm bar for the time steps and a study's runs when ``bar``
    (default: when the stream is a terminal); the lines of the first ``hold`` seconds held back; a watcher
    thread unless ``watch`` is False (see the module's docstring); times from ``clock``."""

    def __init__(self, stream: TextIO | None = None, *, bar: bool | None = None, hold: float = HOLD_SECONDS,
                 watch: bool = True, clock: Callable[[], float] = time.monotonic):
        self.stream = sys.stderr if stream is None else stream
        self.bars = is_terminal(self.stream) if bar is None else bar  # time steps and runs counted by a Bar
        self.clock = clock
        self.start = clock()
        self._held: list[tuple[str, Phase | None]] | None = [] if hold > 0 else None  # (line, phase it starts)
        self._release = self.start + hold
        self._lock = threading.RLock()
        self._running: list = []  # the phases, time loops and studies going on, outermost first
        self._last_line = self.start  # when the last line was written
        self._lives = 0  # life lines since the last other line
        self._newton: tuple[int, float] | None = None  # the Newton iterate of the step that runs
        self._refreshed = self.start  # when the watcher last refreshed a bar
        self._watch = watch
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._closed_down = False

    # --- the reports ------------------------------------------------------------------------------
    def note(self, text: str) -> None:
        """A line; within a phase, one of the phase's (headed by its name), held with its start line."""
        with self._lock:
            phase = self._running[-1] if self._running and isinstance(self._running[-1], Phase) else None
            if phase is None:
                self._line(text)
            elif phase.shown:
                self._line(f"{phase.name}: {text}")
            else:
                phase.notes.append(text)

    def newton(self, iteration: int, residual: float) -> None:
        self._newton = (iteration, residual)  # one assignment: read by the watcher

    def tick(self) -> None:
        with self._lock:
            now = self.clock()
            if self._held is not None and now >= self._release:
                self._flush()
            for activity in self._running:
                if isinstance(activity, Phase) and not activity.shown and now - activity.started >= START_SECONDS:
                    self._show_start(activity)
            if self._held is None and self._running:
                self._life(now)

    def close(self, discard: bool = False) -> None:
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()
        with self._lock:
            if self._held is not None and discard:
                self._held = None
            self._flush()
            self._closed_down = True

    def _opened(self, activity) -> None:
        with self._lock:
            if isinstance(activity, Steps):
                self._flush()  # the time loop starts: the set-up went through
                if self.bars:
                    activity.bar = Bar(self.stream, activity.total, activity.done, "step", activity.label)
            elif isinstance(activity, Runs) and self.bars:
                activity.bar = Bar(self.stream, activity.total, 0, "run", "runs")
            self._running.append(activity)
            self._lives = 0
        self._start_watching()

    def _closed(self, activity, failed: bool) -> None:
        with self._lock:
            now = self.clock()
            if activity in self._running:
                self._running.remove(activity)
            self._lives = 0
            if isinstance(activity, Phase):
                if failed:
                    return  # what stopped it is reported by whoever catches it
                if self._held and activity.shown and self._held[-1][1] is activity:
                    self._held.pop()  # held back, its start line says nothing its end line does not
                    activity.shown = False
                self._line(activity.end_line(now - activity.started), now)
                return
            if isinstance(activity, Steps) and activity.last is not None and activity.printed != activity.last.n:
                if not self.bars:
                    self._line(activity.line(activity.last), now)  # the last step of the session
            if activity.bar is not None:
                activity.bar.close()
                activity.bar = None

    def _step_started(self, steps: Steps, n: int, t: float) -> None:
        steps.current = (n, t, self.clock())
        self._newton = None

    def _step_finished(self, steps: Steps, report: StepReport) -> None:
        with self._lock:
            now = self.clock()
            first = steps.last is None
            steps.last, steps.current = report, None
            if steps.bar is not None:
                steps.bar.step(report)
                return
            quiet = now - self._last_line
            share = max(1, int(STEP_LINE_SHARE * steps.total))
            since = report.n - (steps.printed if steps.printed is not None else steps.done)
            if (first or report.n == steps.total or report.seconds >= LIFE_SECONDS or quiet >= LIFE_SECONDS
                    or (quiet >= STEP_LINE_SECONDS and since >= share)):
                steps.printed = report.n
                self._line(steps.line(report), now)

    def _run_advanced(self, runs: Runs, counts: dict) -> None:
        with self._lock:
            if runs.bar is not None:
                runs.bar.run(counts)

    # --- writing ----------------------------------------------------------------------------------
    def _line(self, text: str, when: float | None = None) -> None:
        """Write (or hold) a line, after the start lines not yet written of the phases going on."""
        for activity in self._running:
            if isinstance(activity, Phase) and not activity.shown:
                self._show_start(activity)
        self._put(text, when, None)

    def _show_start(self, phase: Phase) -> None:
        phase.shown = True
        self._put(phase.start_line(), phase.started, phase)
        for text in phase.notes:
            self._put(f"{phase.name}: {text}", None, None)
        phase.notes.clear()

    def _put(self, text: str, when: float | None, phase: Phase | None) -> None:
        now = self.clock()
        self._last_line, self._lives = now, 0
        line = f"{stamp((now if when is None else when) - self.start)} {text}"
        if self._held is not None:
            self._held.append((line, phase))
        else:
            self._write(line)

    def _flush(self) -> None:
        """Write the lines held back, and hold no more."""
        held, self._held = self._held, None
        for line, _ in held or ():
            self._write(line)

    def _write(self, line: str) -> None:
        if self._closed_down:
            return
        bar = next((a.bar for a in reversed(self._running) if a.bar is not None), None)
        try:
            if bar is not None:
                bar.write(line)
            else:
                self.stream.write(line + "\n")
            self.stream.flush()
        except (OSError, ValueError):  # the reader went away (a closed pipe): the run goes on, unreported
            self._closed_down = True

    def _life(self, now: float) -> None:
        """A line saying what runs, once the silence has lasted long enough (on a terminal, during a time
        loop or a study: the bar refreshed instead, so that its clock ticks)."""
        activity = self._running[-1]
        if activity.bar is not None:
            if isinstance(activity, Steps) and now - self._refreshed >= 1.0:
                self._refreshed = now
                activity.bar.refresh()
            return
        if now - self._last_line < min(LIFE_SECONDS * 2**self._lives, LIFE_MAX_SECONDS):
            return
        if isinstance(activity, Steps):
            text = activity.life_line(now, self._newton)
        else:
            text = activity.life_line(now)
        if text:
            lives = self._lives
            self._put(text, now, None)
            self._lives = lives + 1

    def _start_watching(self) -> None:
        if self._watch and self._thread is None and not self._stop.is_set():
            self._thread = threading.Thread(target=self._watcher, name="vpcontact-progress", daemon=True)
            self._thread.start()

    def _watcher(self) -> None:
        while not self._stop.wait(TICK_SECONDS):
            self.tick()
