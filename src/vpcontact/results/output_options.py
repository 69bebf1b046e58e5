"""What a run keeps and writes: the ``[output]`` table of a case as plain values
(:func:`vpcontact.case.translate.output_options`), read by the time loop, the result, the writers and the run
directory, none of which reads the case."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class OutputOptions:
    """The steps whose fields are kept (``field_steps``: "all", "final", "none" or a sorted list of step numbers),
    progress lines on stderr, checkpoints every so many steps and/or seconds (0: not by that), the figures at
    the end of a run (:mod:`vpcontact.results.plots`), the residual error estimate at every step
    (:mod:`vpcontact.estimate.residual`) and the XDMF time series beside the VTU files (:mod:`vpcontact.io.xdmf`).
    The defaults are the case's (a test checks that the two agree)."""

    field_steps: str | list = "final"
    progress: bool = True
    checkpoint_every_steps: int = 0
    checkpoint_every_seconds: float = 60.0
    figures: bool = False
    error_estimate: bool = False
    xdmf: bool = False
