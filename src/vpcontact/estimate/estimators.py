"""The error estimators by name: ``adapt.estimator`` names one, ``output.error_estimate`` asks for EVERY_LEVEL's.

An estimator maps a converged time level (:class:`~vpcontact.estimate.indicators.Level`: the problem, t_n, the
fields u_h and σ_h and the contact state at t_n) to squared element indicators η_K² by named term
(:class:`~vpcontact.estimate.indicators.Indicators`). It is a module of this package, named after it, whose
``ESTIMATOR`` (:class:`Estimator`) states its terms and prepares it for a problem; the time loop records the
terms of EVERY_LEVEL's at each level (history columns ``error_estimate`` and ``error_estimate_<term>``, the cell
data ``error_indicator``), an adaptation folds those of ``adapt.estimator`` into its marking. A new estimator
is one module here and its name in ESTIMATORS.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..registry import Registry


@dataclass(frozen=True)
class Estimator:
    """An estimator: ``name`` (its case name), a one-line ``summary``, the names of its ``terms`` (the keys of
    its Indicators, in the order of the outputs) and ``prepare``: for a problem, the map from the problem's
    time levels to their Indicators (what it needs of the problem's mesh computed once)."""

    name: str
    summary: str
    terms: tuple[str, ...]
    prepare: Callable[[object], Callable]  # problem -> (Level -> Indicators)


#: The estimators, in the order messages list them.
ESTIMATORS = Registry(__package__, ("residual", "recovery"), "ESTIMATOR")
#: The estimator of every time level of a run with ``output.error_estimate = true``.
EVERY_LEVEL = "residual"
