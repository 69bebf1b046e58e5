"""``solver.method = "auto"`` during a run: the method weighed again against the work it has done, and switched
when another one will clearly finish sooner.

The choice before the first step (:mod:`.choice`) rests on predicted work per step: Newton iterations a step,
Krylov iterations a Newton iteration, one LU of the condensed method's Newton matrix. A run can depart from
that: a cyclic load whose every reversal changes the state of thousands of contact nodes (the condensed method
factors its m × m Newton matrix again), a body whose multigrid needs ten times the usual CG iterations. After
each step from OBSERVED_STEPS on, the running method's remaining time is projected from the work it has done
(its counters, :class:`~.base.SolverWork`, priced by the cost model at this machine kind's reference rates:
:func:`.cost.observed_loop_seconds`) and set against each other method's predicted remaining time, its set-up
included (:func:`.cost.predict` for the steps left, at the Newton iterations a step observed so far). A method
predicted to take less than 1 / SWITCH_GAIN of the running one's remaining time, and whose algebra fits in the
memory available, takes over; a run switches at most once.

The decision weighs counts, not clocks: the same run switches at the same step every time, whatever else the
machine is doing, and a run resumed from a checkpoint makes the decisions the uninterrupted run made. The
switch keeps the history exactly (ξ, z, the last level's solution: :class:`~vpcontact.timeloop.loop.TimeLoop`);
the methods solve the same step problems to the same tolerance, so the numbers after it agree with either
method's to that tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass

import scipy.sparse as sp

from .base import SolverWork
from .cost import FactorWork, MachineRates, Prices, observed_loop_seconds, predict, resident_memory

#: A run switches when another method's predicted remaining time (its set-up included) is below the running
#: method's projected remaining time divided by this: the cost model's predictions are within 1.4× of the
#: measured times on the ladder of docs/performance.md, so a gain of 2 is one the prediction cannot invent.
SWITCH_GAIN = 2.0
#: Steps a method runs before its work is weighed: the first steps are not typical (the condensed method's first
#: LU, the multigrid's first hierarchy, a contact zone being found).
OBSERVED_STEPS = 3


@dataclass(frozen=True)
class Switch:
    """A change of method decided after ``step``: from ``before`` to ``after``, with the seconds each was
    projected to need for the steps left (``remaining_s``), and why, in words."""

    step: int
    before: str
    after: str
    remaining_s: dict[str, float]
    reason: str

    def as_dict(self) -> dict:
        """summary.json's ``method_switch`` (and a checkpoint's record of it)."""
        return {"step": self.step, "from": self.before, "to": self.after,
                "remaining_s": {name: round(seconds, 3) for name, seconds in self.remaining_s.items()},
                "reason": self.reason}

    @classmethod
    def from_dict(cls, record: dict) -> "Switch":
        return cls(int(record["step"]), record["from"], record["to"], dict(record["remaining_s"]), record["reason"])


@dataclass(frozen=True)
class MethodWeighing:
    """What weighing the methods during a run needs: the stiffness A and contact operator N on the free dofs, the
    dimension, whether a viscoplastic history makes a bulk solve every step, the run's ``steps`` and the direct
    factor's work (the plan's, :func:`~vpcontact.timeloop.plan.predicted_costs`; None: the direct methods are not
    weighed) and the iterative method's ``multigrid`` backend (:data:`.cost.MULTIGRID_SPEEDS`)."""

    A: sp.csr_matrix
    N: sp.csr_matrix
    dim: int
    history: bool
    steps: int
    factor: FactorWork | None
    multigrid: str = "pyamg"

    def consider(self, method: str, done: int, work: SolverWork, newton: int) -> Switch | None:
        """The switch to make after step ``done`` of a run of ``method`` that has done ``work`` in ``newton``
        Newton iterations so far, or None."""
        left = self.steps - done
        if done < OBSERVED_STEPS or left <= 0:
            return None
        rates = MachineRates.reference(self.A)
        running = observed_loop_seconds(method, work, done, newton, self.history,
                                        Prices.of(self.A, self.N, rates, self.factor, self.multigrid)) * left / done
        others = predict(self.A, self.N, self.dim, left, history=self.history, field_steps=0, rates=rates,
                         factor=self.factor, resident=resident_memory(), newton_per_step=newton / done,
                         multigrid=self.multigrid)
        fitting = sorted((cost for name, cost in others.items() if name != method and cost.fits),
                         key=lambda cost: cost.total_s)
        if not fitting or fitting[0].total_s * SWITCH_GAIN > running:
            return None
        best = fitting[0]
        remaining = {method: running, best.method: best.total_s}
        reason = (f"after step {done} of {self.steps} the {method} method had done work that projects "
                  f"{running:.3g} s for the {left} steps left; the {best.method} method is predicted to take "
                  f"{best.total_s:.3g} s, its set-up included")
        return Switch(done, method, best.method, remaining, reason)
