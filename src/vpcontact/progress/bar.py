"""The bar of a terminal (tqdm, imported on a terminal only): the time steps or a study's runs counted, the other
lines written above it. Off a terminal (a pipe, a file, a batch queue) a bar's carriage returns show nothing
until the end: :func:`is_terminal` says where a bar is drawn."""

from __future__ import annotations

from typing import TextIO

from .reporter import StepReport


def is_terminal(stream: TextIO) -> bool:
    """Is ``stream`` a terminal (where a bar is drawn)?"""
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


class Bar:
    """A bar on ``stream`` counting ``total`` things (``unit``: "step", "run") from ``done``, named ``label``."""

    def __init__(self, stream: TextIO, total: int, done: int, unit: str, label: str):
        from tqdm import tqdm

        self.stream = stream
        self._tqdm = tqdm(total=total, initial=done, unit=unit, desc=label, file=stream)

    def step(self, report: StepReport) -> None:
        """A time step done: counted, its Newton iterations, residual, nodes at the limit and the run's step cuts
        beside the bar."""
        postfix = {"newton": report.newton_iterations, "residual": f"{report.residual:.1e}"}
        if report.at_limit is not None:
            postfix["at_limit"] = report.at_limit
        self._tqdm.set_postfix(**postfix, cuts=report.all_cuts, refresh=False)
        self._tqdm.update()

    def run(self, counts: dict) -> None:
        """A study's run ended: counted, with ``counts`` (runs done, failed, left) beside the bar."""
        self._tqdm.update()
        self._tqdm.set_postfix(**counts, refresh=False)

    def write(self, line: str) -> None:
        """A line above the bar."""
        self._tqdm.write(line, file=self.stream)

    def refresh(self) -> None:
        """Draw the bar again (its clock ticks)."""
        self._tqdm.refresh()

    def close(self) -> None:
        self._tqdm.close()
