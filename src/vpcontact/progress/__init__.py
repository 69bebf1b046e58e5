"""Progress as it happens, for whoever watches a run: its set-up phases, its time steps, a study's runs.

The numerics report through the reporter they are given (the ``progress`` arguments, passed down from the
command line: ``cli`` → ``rundir.run`` → ``build_problem``, ``TimeLoop``, ``make_solver``); they never print.
:mod:`.reporter` holds the interface, :class:`Progress`, with what it hears of (a set-up phase, the time steps,
a study's runs), and :data:`SILENT`, the default of the Python API, which reports nothing; :mod:`.log` the
command line's reporter, :class:`Log` (lines on stderr, held back at first, throttled, kept alive while
nothing else is said), and :func:`reporting`, the reporter an API's ``progress`` argument stands for;
:mod:`.bar` the bar of a terminal that counts the time steps or the runs.
"""

from .log import Log, reporting
from .reporter import SILENT, Progress, StepReport, duration, size

__all__ = ["SILENT", "Log", "Progress", "StepReport", "duration", "reporting", "size"]
