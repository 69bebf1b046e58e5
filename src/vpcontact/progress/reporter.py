"""The interface of a reporter (:class:`Progress`), what it hears of (a set-up phase, the time steps, a study's
runs, each with the words of its lines), and the reporter that reports nothing, :data:`SILENT`."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass


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


@dataclass(frozen=True)
class StepReport:
    """A time step done: its number n, t_n, the Newton iterations of its (sub-)steps, the last residual, its
    contact nodes at the limit and in compliance (None without contact), its step cuts, those of the run so
    far, its wall time and the (sub-)steps it was done in."""

    n: int
    t: float
    newton_iterations: int
    residual: float
    at_limit: int | None
    in_compliance: int | None
    cuts: int
    all_cuts: int
    seconds: float
    substeps: int = 1

    @classmethod
    def of_rows(cls, n: int, rows: list[dict], contact: bool, cuts: int, all_cuts: int,
                seconds: float) -> "StepReport":
        """Step n from the history rows of its (sub-)steps (``contact``: whether the body has contact nodes)."""
        last = rows[-1]
        return cls(n, last["t"], sum(row["newton_iterations"] for row in rows), last["residual"],
                   last["nodes_at_limit"] if contact else None, last["nodes_in_compliance"] if contact else None,
                   cuts, all_cuts, seconds, len(rows))


class Progress:
    """The interface of a reporter, and the reporter that reports nothing (:data:`SILENT`).

    ``with progress.phase(name, text) as phase: ...; phase.done(detail)``: a set-up phase;
    ``progress.note(text)``: a line; ``with progress.steps(total, done) as steps: steps.started(n, t);
    steps.finished(report)``: the time steps; ``progress.newton(iteration, residual)``: a Newton iterate of
    the step that runs; ``with progress.runs(total, describe) as runs: runs.advance(**counts)``: a study's
    runs, ``describe()`` saying which run. ``with progress:`` closes it at the end (see :meth:`close`).
    """

    def phase(self, name: str, text: str = "", *, estimate: float | None = None) -> Phase:
        """A phase ``name`` doing ``text`` (a context manager; its ``done(detail)`` says what it made, for its
        end line); ``estimate``: the seconds it is expected to take (life lines)."""
        return Phase(self, name, text, estimate)

    def steps(self, total: int, done: int = 0, label: str = "time steps") -> Steps:
        """The time steps done + 1, …, total of a time loop."""
        return Steps(self, total, done, label)

    def runs(self, total: int, describe: Callable[[], str]) -> Runs:
        """``total`` runs of a study; ``describe()``: the runs going on, for life lines."""
        return Runs(self, total, describe)

    #: The clock of the reporter's times (seconds).
    clock = staticmethod(time.monotonic)

    def note(self, text: str) -> None:
        """A line (within a phase, one of the phase's: see :class:`~vpcontact.progress.log.Log`)."""

    def newton(self, iteration: int, residual: float) -> None:
        """The Newton iterate ``iteration`` of the step that runs, and its residual."""

    def tick(self) -> None:
        """Do what is due between the reports (without a watcher thread: a study's polling loop calls it)."""

    def close(self, discard: bool = False) -> None:
        """The end: the lines held back are written (dropped with ``discard``: the run ended on an exception)."""

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, kind, value, traceback) -> bool:
        self.close(discard=kind is not None)
        return False

    # what Phase, Steps and Runs report (nothing here)
    def _opened(self, activity: Activity) -> None:
        pass

    def _closed(self, activity: Activity, failed: bool) -> None:
        pass

    def _step_started(self, steps: Steps, n: int, t: float) -> None:
        pass

    def _step_finished(self, steps: Steps, report: StepReport) -> None:
        pass

    def _run_advanced(self, runs: Runs, counts: dict) -> None:
        pass


#: The reporter that reports nothing: the default of the Python API.
SILENT = Progress()


class Activity:
    """What a reporter hears of while it goes on (a context manager that tells the reporter as it opens and
    closes): a set-up phase, the time steps of a time loop, a study's runs."""

    #: The bar that counts it on a terminal (:class:`~vpcontact.progress.bar.Bar`: the time steps, the runs), if any.
    bar = None

    def __init__(self, progress: Progress):
        self.progress = progress

    def __enter__(self):
        self.progress._opened(self)
        return self

    def __exit__(self, kind, value, traceback) -> bool:
        self.progress._closed(self, failed=kind is not None)
        return False


class Phase(Activity):
    """A set-up phase of a reporter: its name, what it does, when it started."""

    def __init__(self, progress: Progress, name: str, text: str, estimate: float | None):
        super().__init__(progress)
        self.name, self.text, self.estimate = name, text, estimate
        self.detail = ""  # what the end line adds: the phase's outcome (sizes, ...)
        self.started = 0.0
        self.shown = False  # its start line has been written (or held)
        self.notes: list[str] = []  # its notes until its start line is written (dropped if it ends before)

    def done(self, detail: str) -> None:
        """What the phase's end line says it made."""
        self.detail = detail

    def __enter__(self) -> Phase:
        self.started = self.progress.clock()
        return super().__enter__()

    def start_line(self) -> str:
        return f"{self.name}: {self.text} ..." if self.text else f"{self.name} ..."

    def end_line(self, seconds: float) -> str:
        said = [] if self.shown or not self.text else [self.text]
        words = ": ".join(said + ([self.detail] if self.detail else []))
        return f"{self.name}: {words or 'done'} ({duration(seconds)})"

    def life_line(self, now: float) -> str:
        expected = f", about {duration(self.estimate)} expected" if self.estimate else ""
        return f"{self.name}: running for {duration(now - self.started)}{expected}"


class Steps(Activity):
    """The time steps of a time loop: ``started(n, t)`` as step n begins, ``finished(report)`` once it is done."""

    def __init__(self, progress: Progress, total: int, done: int, label: str):
        super().__init__(progress)
        self.total, self.done, self.label = total, done, label
        self.current: tuple[int, float, float] | None = None  # (n, t, when it started) of the step that runs
        self.last: StepReport | None = None  # the last step finished
        self.printed: int | None = None  # the number of the last step printed

    def started(self, n: int, t: float) -> None:
        self.progress._step_started(self, n, t)

    def finished(self, report: StepReport) -> None:
        self.progress._step_finished(self, report)

    def line(self, r: StepReport) -> str:
        contact = (f", {r.at_limit:,} nodes at the limit, {r.in_compliance:,} in compliance"
                   if r.at_limit is not None else "")
        cuts = f", {r.cuts} step cut{'s' if r.cuts != 1 else ''}" if r.cuts else ""
        cuts += f", {r.substeps} sub-steps" if r.substeps > 1 else ""
        iterations = f"{r.newton_iterations} Newton iteration{'s' if r.newton_iterations != 1 else ''}"
        return f"step {r.n:,}/{self.total:,}: t = {r.t:.6g}, {iterations}{contact}{cuts} ({duration(r.seconds)})"

    def life_line(self, now: float, newton: tuple[int, float] | None) -> str | None:
        if self.current is None:
            return None
        n, t, since = self.current
        iterate = f": Newton iteration {newton[0]}, residual {newton[1]:.1e}" if newton else ""
        return f"step {n:,}/{self.total:,} (t = {t:.6g}) running for {duration(now - since)}{iterate}"


class Runs(Activity):
    """A study's runs: ``advance(**counts)`` as each one ends (a terminal's bar counts them, with ``counts``);
    ``describe()``: the runs going on, for life lines."""

    def __init__(self, progress: Progress, total: int, describe: Callable[[], str]):
        super().__init__(progress)
        self.total, self.describe = total, describe

    def advance(self, **counts) -> None:
        self.progress._run_advanced(self, counts)

    def life_line(self, now: float) -> str:
        return self.describe()
