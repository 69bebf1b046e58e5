"""figures/*.png (``output.figures = true``), at the end of a complete or failed run: the figures of
:func:`vpcontact.results.plots.run_figures` the run has data for (the contact pressure, the deformed body,
the history), at :data:`~vpcontact.results.plots.DPI`. matplotlib is imported by the runs that draw them."""

from __future__ import annotations

from pathlib import Path

from ..results.plots import DPI, FIGURES, run_figures
from . import directory
from .files import replacing

FILES = tuple(f"figures/{stem}.png" for stem in FIGURES)


def wanted(result) -> bool:
    """Asked for (``output.figures``), and the run has ended: complete or failed (an interrupted run draws
    its figures when it is resumed and ends)."""
    return bool(result.output.figures) and result.status in ("complete", "failed")


def write(result, out: Path) -> None:
    """The PNG files of ``result`` in ``out``/figures (created if the run has a figure)."""
    folder = Path(out) / "figures"
    figures = run_figures(result)
    if figures:
        directory.mkdir(folder)
    for stem, figure in figures.items():
        with replacing(folder / f"{stem}.png") as temporary:
            figure.savefig(temporary, dpi=DPI)
