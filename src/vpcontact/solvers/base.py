"""What every step solver shares: the step data, the solution record, the contact residual and the counters of work.

At step n the discrete problem (DESIGN §3) is: find u (free dofs) and λ (one per contact node) with
    A u + Nᵀ (f(d) + λ) = b,                 f_i(d) = w_i ρ K(ξ_i^{n−1} + k d_i⁺) p(d_i),
    C(d, λ) = λ − max(0, λ + r (d − g)) = 0  (Alart–Curnier: λ ≥ 0, d ≤ g, λ (d − g) = 0),
with d = N u − g0. C / r = min(λ / r, g − d) is the complementarity error in length units.
"""

from __future__ import annotations

from dataclasses import astuple, dataclass, fields
from functools import cached_property

import numpy as np

from ..laws.contact import ContactLaw
from ..parallel.dofs import norm  # noqa: F401  (the step solvers' norm, here with the rest they share)
from ..parallel.ranks import ALONE, Ranks


@dataclass(frozen=True)
class StepData:
    """The data of one step problem: right-hand side b_n = F(t_n) − Bᵀz_n, law, history ξ^{n−1}, k;
    ``support``: the positions where b may be nonzero, ascending (None: anywhere), so that a solver
    can skip the rest of a load that reaches few dofs."""

    b: np.ndarray
    law: ContactLaw
    xi_prev: np.ndarray
    k: float
    support: np.ndarray | None = None

    @cached_property
    def b_norm(self) -> float:
        """‖b‖, over the support only."""
        return norm(self.b if self.support is None else self.b[self.support])


@dataclass(frozen=True)
class StepSolution:
    """A step solver's answer and how it got there."""

    u: np.ndarray  # displacement at the free dofs
    lam: np.ndarray  # rigid-base nodal force λ_i ≥ 0
    d: np.ndarray  # penetration d_i
    active: np.ndarray  # nodes held by the rigid base (λ + r (d − g) > 0)
    iterations: int
    residual: float  # ‖A u + Nᵀ(f + λ) − b‖ / max(‖b‖, ‖Nᵀ(f + λ)‖)
    complementarity: float  # max_i |min(λ_i / r, g − d_i)|, a length
    converged: bool
    message: str = ""  # why it did not converge
    advice: str = ""  # what the user may try then


class DisplacementSolution:
    """What the time loop asks of a step solver whose StepSolution holds u at the free dofs (``self.Z``: the rigid
    motions held only by contact, on the free dofs)."""

    def displacement(self, step: StepData, solution: StepSolution) -> np.ndarray:
        """u at the free dofs (the iterate itself)."""
        return solution.u

    def functionals(self, M):
        """(step, solution) ↦ M u for a few rows M over the free dofs (the reactions of the Dirichlet parts)."""
        return lambda step, solution: M @ solution.u

    def rigid_coordinates(self, step: StepData, solution: StepSolution) -> np.ndarray:
        """Zᵀu: the coordinates of the solution's displacement on the rigid motions held only by contact."""
        return self.Z.T @ solution.u


@dataclass(frozen=True)
class ContactState:
    """The contact law evaluated at (d, λ): nodal forces, tangents, active set and C."""

    force: np.ndarray  # f_i(d), the soft layer's nodal force
    tangent: np.ndarray  # ∂f_i/∂d_i (generalized)
    active: np.ndarray
    C: np.ndarray

    @classmethod
    def evaluate(cls, step: StepData, weights: np.ndarray, d: np.ndarray, lam: np.ndarray, r: float):
        pressure, dpressure = step.law.pressure(d, step.xi_prev, step.k)
        trial = lam + r * (d - step.law.g)  # −∞ where g = ∞: never active
        C = lam - np.maximum(trial, 0.0)
        return cls(weights * pressure, weights * dpressure, trial > 0.0, C)


@dataclass(frozen=True)
class SolverWork:
    """A step solver's work in the time loop, counted (its ``work()``): summary.json reports these counters
    under their names here, summed over the sessions of a resumed run (``+``)."""

    linear_solves: int = 0  # solves with a factored matrix: the condensed method's A0, the full method's Newton ones
    krylov_iterations: int = 0  # Krylov iterations on Newton systems: GMRES (condensed), CG (iterative)
    newton_factorizations: int = 0  # Newton matrices factored: the condensed method's m × m ones, the full method's

    @classmethod
    def from_counts(cls, counts: dict) -> "SolverWork":
        """The counters named in ``counts`` (a checkpoint's meta: JSON numbers), 0 for one it lacks."""
        return cls(**{counter.name: int(counts.get(counter.name, 0)) for counter in fields(cls)})

    def __add__(self, other: "SolverWork") -> "SolverWork":
        return SolverWork(*(mine + theirs for mine, theirs in zip(astuple(self), astuple(other))))


def default_augmentation(A, N, ranks: Ranks = ALONE) -> float:
    """r = the median normal stiffness ν_iᵀ A_ii ν_i at the contact nodes: same units as the
    problem, so no tuning is needed. On MPI ranks (``ranks``) A is a rank's rows: each contact node's value comes
    from the rank that has its rows."""
    if N.shape[0] == 0:
        return 1.0
    diagonal = ranks.sum(np.asarray((N @ A).multiply(N).sum(axis=1)).ravel())
    positive = diagonal[diagonal > 0.0]
    return float(np.median(positive)) if positive.size else 1.0
