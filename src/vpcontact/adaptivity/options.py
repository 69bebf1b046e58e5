"""The settings of an adaptation: the ``[adapt]`` table of a case as plain values
(:func:`vpcontact.case.translate.adapt_options`), read by :mod:`vpcontact.adaptivity.cycles`."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class AdaptOptions:
    """``mode`` "cycles": up to ``cycles`` solves of the whole history, each on the mesh refined from the one before
    by Dörfler marking of the fraction ``theta`` of the time functional ``functional`` ("max" or "l2") of the
    indicators of ``estimator`` (a name of :data:`vpcontact.estimate.estimators.ESTIMATORS`); ``mode`` "run": one
    run refined between its steps until η(t_n) ≤ ``tolerance`` max_{m≤n} ‖u_h(t_m)‖_E at each
    (:mod:`.during_run`); no mesh with more than ``max_dofs`` dofs."""

    cycles: int | None
    theta: float
    max_dofs: int
    functional: str
    estimator: str
    mode: str = "cycles"
    tolerance: float | None = None
