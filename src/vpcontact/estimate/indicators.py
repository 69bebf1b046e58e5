"""What an a posteriori error estimator reads at one time level of a run, and what it returns.

An estimator maps a converged time level (`Level`: the problem, t_n, the discrete fields u_h and σ_h
and the contact state at t_n) to squared element indicators η_K² by term (`Indicators`); the
estimate of the level is η(t_n) = (Σ_K η_K²)^{1/2}. The estimators, by name, are those of
:data:`~vpcontact.estimate.estimators.ESTIMATORS`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CaseError
from ..results.columns import CONTACT_ARRAYS
from ..results.result import Fields, Result


@dataclass(frozen=True, eq=False)
class Level:
    """A converged time level t_n of a run: the discrete solution there and its contact state.

    ``contact`` holds one row of the run's per-node contact arrays (``CONTACT_ARRAYS``: penetration d,
    ξ, K, the compliance pressure ρK(ξ)p(d), the rigid pressure λ_i / w_i and the node status), each
    an array over the contact nodes; ``k`` is the length of the (sub-)step that reached t_n."""

    problem: object
    step: int
    t: float
    k: float
    fields: Fields
    contact: dict[str, np.ndarray]

    @classmethod
    def of(cls, result: Result, step: int, problem) -> "Level":
        """The level at the end of time step ``step`` of ``result``, a run of ``problem`` (a result is data:
        the problem's operators, loads and laws are not in it); its fields must have been kept
        (``output.field_steps``; the last step's are always kept)."""
        fields = result.fields.get(step)
        if fields is None and step == result.steps and result.final is not None:
            fields = result.final
        if fields is None:
            kept = ", ".join(map(str, sorted(result.fields))) or "none"
            raise CaseError(f"no fields kept at step {step} (steps kept: {kept}): an error estimate needs the fields "
                            f"of its steps; set output.field_steps to include them")
        row = result.end_of_step_rows().get(step)
        if row is None:
            raise CaseError(f"step {step} was not reached (the run reached step {result.steps})")
        contact = {name: np.asarray(result.contact[name][row]) for name in CONTACT_ARRAYS}
        return cls(problem, step, float(result.times[row]), float(result.rows[row]["k"]), fields, contact)


@dataclass(frozen=True, eq=False)
class Indicators:
    """Squared element indicators of one time level by term: ``terms[name]`` is (nelements,), ≥ 0."""

    terms: dict[str, np.ndarray]

    @property
    def squared(self) -> np.ndarray:
        """η_K² per element: the sum of the terms."""
        return np.sum(list(self.terms.values()), axis=0)

    @property
    def total(self) -> float:
        """η = (Σ_K η_K²)^{1/2}."""
        return float(np.sqrt(self.squared.sum()))
