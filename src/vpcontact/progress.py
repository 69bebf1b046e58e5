"""Progress as it happens, for whoever watches a run: its set-up phases, its time steps, a study's runs.

The numerics report through the reporter they are given (the ``progress`` arguments, passed down from the
command line: ``cli`` → ``rundir.run`` → ``build_problem``, ``TimeLoop``, ``make_solver``); they never print.
:data:`SILENT`, the default of the Python API, reports nothing. :class:`Log`, the command line's, writes
lines to a stream (stderr), each flushed as it is written and headed by the time since the run started::

    [00:05] factorization: A0 = A + r NᵀN, 100,776 dofs, by MKL PARDISO; expected: 43.9 s with ...
    [00:10] factorization: MKL PARDISO's analysis: the factor and the Schur complement take about 1.31 GiB ...
    [00:20] factorization: running for 14.3 s, about 43.9 s expected
    [01:23] factorization: a factor of 124,588,208 entries (1 min 17 s)

- a set-up phase (:meth:`Progress.phase`) prints a line when it ends, with its wall time; one that lasts
  more than START_SECONDS prints a line as it starts too, so that the last line says what is running, and
  then the notes made during it (say, the memory its factor will take: of no interest in a short phase);
- the time steps (:meth:`Progress.steps`): on a terminal, a tqdm bar, the other lines printed above it;
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
from dataclasses import dataclass
from typing import TextIO

from .errors import flag

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


def duration(seconds: float) -> str:
    """A wall time to read: 0.052 s, 12.3 s, 4 min 05 s, 2 h 03 min."""
    if seconds < 1.0:
        return f"{seconds:.2g} s"
    if seconds < 60.0:
        return f"{seconds:.1f} s"
    minutes, rest = divmod(round(seconds), 60)
    if minutes < 60:
        return f"{minutes} min {rest:02d} s"
    return f"{minutes // 60} h {minutes % 60:02d} min"


def size(nbytes: float) -> str:
    """A size in memory to read: MiB below a GiB, else GiB."""
    return f"{nbytes / 2**20:.3g} MiB" if nbytes < 2**30 else f"{nbytes / 2**30:.3g} GiB"


def stamp(seconds: float) -> str:
    """The time since the start that heads a line: [mm:ss], or [h:mm:ss] from an hour on."""
    whole = int(seconds)
    minutes, rest = divmod(whole, 60)
    if minutes < 60:
        return f"[{minutes:02d}:{rest:02d}]"
    return f"[{minutes // 60}:{minutes % 60:02d}:{rest:02d}]"


@dataclass(frozen=True)
class StepReport:
    """A time step done: its number n, t_n, the Newton iterations of its (sub-)steps, the last residual, its
    contact nodes at the limit and in compliance (None without contact), its step cuts, those of the run so
    far, and its wall time."""

    n: int
    t: float
    newton_iterations: int
    residual: float
    at_limit: int | None
    in_compliance: int | None
    cuts: int
    all_cuts: int
    seconds: float


class Progress:
    """The interface of a reporter, and the reporter that reports nothing (:data:`SILENT`).

    ``with progress.phase(name, text) as phase: ...; phase.done(detail)``: a set-up phase;
    ``progress.note(text)``: a line; ``with progress.steps(total, done) as steps: steps.started(n, t);
    steps.finished(report)``: the time steps; ``progress.newton(iteration, residual)``: a Newton iterate of
    the step that runs; ``with progress.runs(total, describe) as runs: runs.advance(**counts)``: a study's
    runs, ``describe()`` saying which run. ``with progress:`` closes it at the end (see :meth:`close`).
    """

    def phase(self, name: str, text: str = "", *, estimate: float | None = None) -> "Phase":
        """A phase ``name`` doing ``text`` (a context manager; its ``done(detail)`` says what it made, for its
        end line); ``estimate``: the seconds it is expected to take (life lines)."""
        return Phase(self, name, text, estimate)

    def steps(self, total: int, done: int = 0, label: str = "time steps") -> "Steps":
        """The time steps done + 1, …, total of a time loop."""
        return Steps(self, total, done, label)

    def runs(self, total: int, describe: Callable[[], str]) -> "Runs":
        """``total`` runs of a study; ``describe()``: the runs going on, for life lines."""
        return Runs(self, total, describe)

    #: The clock of the reporter's times (seconds).
    clock = staticmethod(time.monotonic)

    def note(self, text: str) -> None:
        """A line (within a phase, one of the phase's: see :class:`Log`)."""

    def newton(self, iteration: int, residual: float) -> None:
        """The Newton iterate ``iteration`` of the step that runs, and its residual."""

    def tick(self) -> None:
        """Do what is due between the reports (without a watcher thread: a study's polling loop calls it)."""

    def close(self, discard: bool = False) -> None:
        """The end: the lines held back are written (dropped with ``discard``: the run ended on an exception)."""

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, kind, value, traceback) -> bool:
        self.close(discard=kind is not None)
        return False

    # what Phase, Steps and Runs report (nothing here)
    def _opened(self, activity) -> None:
        pass

    def _closed(self, activity, failed: bool) -> None:
        pass

    def _step_started(self, steps: "Steps", n: int, t: float) -> None:
        pass

    def _step_finished(self, steps: "Steps", report: StepReport) -> None:
        pass

    def _run_advanced(self, runs: "Runs", counts: dict) -> None:
        pass


#: The reporter that reports nothing: the default of the Python API.
SILENT = Progress()


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


class Phase:
    """A set-up phase of a reporter (a context manager): its name, what it does, when it started."""

    def __init__(self, progress: Progress, name: str, text: str, estimate: float | None):
        self.progress, self.name, self.text, self.estimate = progress, name, text, estimate
        self.detail = ""  # what the end line adds: the phase's outcome (sizes, ...)
        self.started = 0.0
        self.shown = False  # its start line has been written (or held)
        self.notes: list[str] = []  # its notes until its start line is written (dropped if it ends before)

    def done(self, detail: str) -> None:
        """What the phase's end line says it made."""
        self.detail = detail

    def __enter__(self) -> "Phase":
        self.started = self.progress.clock()
        self.progress._opened(self)
        return self

    def __exit__(self, kind, value, traceback) -> bool:
        self.progress._closed(self, failed=kind is not None)
        return False

    def start_line(self) -> str:
        return f"{self.name}: {self.text} ..." if self.text else f"{self.name} ..."

    def end_line(self, seconds: float) -> str:
        said = [] if self.shown or not self.text else [self.text]
        words = ": ".join(said + ([self.detail] if self.detail else []))
        return f"{self.name}: {words or 'done'} ({duration(seconds)})"

    def life_line(self, now: float) -> str:
        expected = f", about {duration(self.estimate)} expected" if self.estimate else ""
        return f"{self.name}: running for {duration(now - self.started)}{expected}"


class Steps:
    """The time steps of a time loop (a context manager): ``started(n, t)`` as step n begins,
    ``finished(report)`` once it is done."""

    def __init__(self, progress: Progress, total: int, done: int, label: str):
        self.progress, self.total, self.done, self.label = progress, total, done, label
        self.current: tuple[int, float, float] | None = None  # (n, t, when it started) of the step that runs
        self.last: StepReport | None = None  # the last step finished
        self.printed: int | None = None  # the number of the last step printed
        self.bar = None  # the tqdm bar, on a terminal

    def started(self, n: int, t: float) -> None:
        self.progress._step_started(self, n, t)

    def finished(self, report: StepReport) -> None:
        self.progress._step_finished(self, report)

    def __enter__(self) -> "Steps":
        self.progress._opened(self)
        return self

    def __exit__(self, kind, value, traceback) -> bool:
        self.progress._closed(self, failed=kind is not None)
        return False

    def line(self, r: StepReport) -> str:
        contact = (f", {r.at_limit:,} nodes at the limit, {r.in_compliance:,} in compliance"
                   if r.at_limit is not None else "")
        cuts = f", {r.cuts} step cut{'s' if r.cuts != 1 else ''}" if r.cuts else ""
        iterations = f"{r.newton_iterations} Newton iteration{'s' if r.newton_iterations != 1 else ''}"
        return f"step {r.n:,}/{self.total:,}: t = {r.t:.6g}, {iterations}{contact}{cuts} ({duration(r.seconds)})"

    def life_line(self, now: float, newton: tuple[int, float] | None) -> str | None:
        if self.current is None:
            return None
        n, t, since = self.current
        iterate = f": Newton iteration {newton[0]}, residual {newton[1]:.1e}" if newton else ""
        return f"step {n:,}/{self.total:,} (t = {t:.6g}) running for {duration(now - since)}{iterate}"


class Runs:
    """A study's runs (a context manager): ``advance(**counts)`` as each one ends (a terminal's bar counts them,
    with ``counts``); ``describe()``: the runs going on, for life lines."""

    def __init__(self, progress: Progress, total: int, describe: Callable[[], str]):
        self.progress, self.total, self.describe = progress, total, describe
        self.bar = None

    def advance(self, **counts) -> None:
        self.progress._run_advanced(self, counts)

    def __enter__(self) -> "Runs":
        self.progress._opened(self)
        return self

    def __exit__(self, kind, value, traceback) -> bool:
        self.progress._closed(self, failed=kind is not None)
        return False

    def life_line(self, now: float) -> str:
        return self.describe()


class Log(Progress):
    """Lines on ``stream`` (default: stderr), a tqdm bar for the time steps and a study's runs when ``bar``
    (default: when the stream is a terminal); the lines of the first ``hold`` seconds held back; a watcher
    thread unless ``watch`` is False (see the module's docstring); times from ``clock``."""

    def __init__(self, stream: TextIO | None = None, *, bar: bool | None = None, hold: float = HOLD_SECONDS,
                 watch: bool = True, clock: Callable[[], float] = time.monotonic):
        self.stream = sys.stderr if stream is None else stream
        self.bar = _is_terminal(self.stream) if bar is None else bar
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
                if self.bar:
                    activity.bar = self._tqdm(activity.total, activity.done, "step", activity.label)
            elif isinstance(activity, Runs) and self.bar:
                activity.bar = self._tqdm(activity.total, 0, "run", "runs")
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
                if not self.bar:
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
                postfix = {"newton": report.newton_iterations, "residual": f"{report.residual:.1e}"}
                if report.at_limit is not None:
                    postfix["at_limit"] = report.at_limit
                steps.bar.set_postfix(**postfix, cuts=report.all_cuts, refresh=False)
                steps.bar.update()
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
                runs.bar.update()
                runs.bar.set_postfix(**counts, refresh=False)

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
        bar = next((a.bar for a in reversed(self._running) if getattr(a, "bar", None) is not None), None)
        try:
            if bar is not None:
                bar.write(line, file=self.stream)
            else:
                self.stream.write(line + "\n")
            self.stream.flush()
        except (OSError, ValueError):  # the reader went away (a closed pipe): the run goes on, unreported
            self._closed_down = True

    def _life(self, now: float) -> None:
        """A line saying what runs, once the silence has lasted long enough (on a terminal, during a time
        loop or a study: the bar refreshed instead, so that its clock ticks)."""
        activity = self._running[-1]
        if getattr(activity, "bar", None) is not None:
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

    def _tqdm(self, total: int, initial: int, unit: str, label: str):
        from tqdm import tqdm  # on a terminal only

        return tqdm(total=total, initial=initial, unit=unit, desc=label, file=self.stream)

    def _start_watching(self) -> None:
        if self._watch and self._thread is None and not self._stop.is_set():
            self._thread = threading.Thread(target=self._watcher, name="vpcontact-progress", daemon=True)
            self._thread.start()

    def _watcher(self) -> None:
        while not self._stop.wait(TICK_SECONDS):
            self.tick()


def _is_terminal(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
