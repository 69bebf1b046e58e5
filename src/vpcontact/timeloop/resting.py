"""Where a body that only the contact holds rests when nothing presses it on the foundation.

When the Dirichlet conditions leave rigid motions of the body free (the paper's half disc on its
roller: the vertical translation), only contact forces hold those motions. At a time level where
the loads have no resultant on them (a load cycle that unloads to exactly zero, a traction log(t) at
t = 1) and no contact node carries a force, the step problem does not determine the body's position:
its deformation is determined, but every rigid motion z = Z c of the free motions that keeps each
contact node out of reach of any force solves it. Of these, vpcontact takes the one with the least
change from the last level,

    c = argmin ‖c − c_prev‖   subject to   d + N Z (c − c_now) ≤ room,

(Z an orthonormal basis of the free motions over the free dofs, so ‖c − c_prev‖ is the Euclidean
norm of the rigid part of the change u − u_prev; c_now the position the Newton iteration returned, d
its penetrations): the body stays where it was if it can, and otherwise moves just far enough to
leave the layer unloaded, which is where it tends when a load decreases to zero. ``room`` is the
largest penetration at which a node carries no force: 0 (the layer's surface), or g where the layer
carries no force at all (K = 0, the Signorini condition with gap g).

This is a least-distance program, solved exactly by Lawson and Hanson's reduction to a non-negative
least-squares problem (*Solving Least Squares Problems*, 1974, ch. 23) with SciPy's ``nnls``: k ≤ 6
unknowns, one constraint per contact node.

When the loads do have a resultant on the free motions, contact pressures must balance it:
``unbalanced`` measures the part of it that no pressures can (a load that pulls the body off the
foundation), which no time step can solve.

:class:`FreeMotions` holds Z and N Z for the time loop, and what tells a force from the rounding of a
zero one there: the largest contact pressure and resultant of the levels so far, against
``solver.tolerance``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import nnls

from ..solvers import StepData, StepSolution


def least_shift(motions: np.ndarray, d: np.ndarray, room: np.ndarray, allowance: float = 0.0) -> np.ndarray | None:
    """The shift x of least norm with ``d + motions @ x ≤ room`` at every contact node (``motions``: (m, k),
    how the k free rigid coordinates move each node along its normal), or None when no shift satisfies them:
    a node that no free motion moves lies beyond its room by more than ``allowance`` (the rounding a
    converged penetration may carry: such a node is as the deformation puts it, whatever the shift)."""
    moved = np.linalg.norm(motions, axis=1)
    slack = room - d
    if np.any((moved == 0.0) & (slack < -allowance)):
        return None
    rows = moved > 0.0
    G, h = motions[rows] / moved[rows, None], slack[rows] / moved[rows]  # unit rows: G x ≤ h
    if h.size == 0 or np.all(h >= 0.0):
        return np.zeros(motions.shape[1])
    scale = np.abs(h).max()
    # Lawson–Hanson: min ‖x‖ s.t. (−G) x ≥ −h  ⇔  NNLS of E = [(−G)ᵀ; (−h)ᵀ] against e_{k+1}
    E = np.vstack([-G.T, -h[None, :] / scale])
    target = np.zeros(E.shape[0])
    target[-1] = 1.0
    weights, _ = nnls(E, target, maxiter=50 * E.shape[1])
    residual = E @ weights - target
    if abs(residual[-1]) <= np.finfo(float).eps:
        return None
    return -residual[:-1] / residual[-1] * scale


def unbalanced(motions: np.ndarray, resultant: np.ndarray) -> float:
    """‖r − (N Z)ᵀ μ‖ for the contact forces μ ≥ 0 that come closest to balancing the loads' resultant
    ``resultant`` = r = Zᵀ b on the free rigid motions (``motions`` = N Z, (m, k)): 0 when some contact
    pressures can hold the body, the size of the resultant's part that pulls it off the foundation else."""
    if resultant.size == 0:
        return 0.0
    if motions.shape[0] == 0:
        return float(np.linalg.norm(resultant))
    _, distance = nnls(motions.T, resultant, maxiter=50 * motions.shape[0])
    return float(distance)


def room(step: StepData) -> np.ndarray:
    """The largest penetration at which each contact node carries no force in the step problem ``step``: g
    where the layer carries none up to g (K = 0: the Signorini condition with gap g), else 0 (the layer's
    surface)."""
    law, m = step.law, step.xi_prev.size
    g = np.broadcast_to(np.asarray(law.g, dtype=float), (m,))
    room = np.zeros(m)
    finite = np.isfinite(g)
    if np.any(finite):
        pressure, _ = law.pressure(np.where(finite, g, 0.0), step.xi_prev, step.k)
        unloaded = finite & (pressure == 0.0)
        room[unloaded] = g[unloaded]
    return room


class FreeMotions:
    """The rigid motions of the body that the Dirichlet conditions leave free, which only the contact holds:
    ``basis`` Z, an orthonormal basis of them over the free dofs (free dofs, k; k = 0 when the conditions
    hold every rigid motion), and ``at_contact`` N Z, how they move the contact nodes along their normals
    (m, k); with the largest contact pressure and the largest resultant of the contact forces on them over
    the levels so far (of a new run: none; of a resumed one: its recorded levels, see ``recall``), against
    which ``tolerance`` (``solver.tolerance``) tells a force from the rounding of a zero one."""

    def __init__(self, basis: np.ndarray, at_contact: np.ndarray, weights: np.ndarray, tolerance: float):
        self.basis, self.at_contact, self.weights, self.tolerance = basis, at_contact, weights, tolerance
        self.held_by_contact_only = basis.shape[1] > 0 and weights.size > 0
        self.largest_pressure = self.largest_resultant = 0.0

    def remember(self, compliance: np.ndarray, rigid: np.ndarray) -> None:
        """Take a level, its compliance and rigid-base pressures as recorded, into the largest pressure and
        resultant so far."""
        pressure = compliance + rigid
        resultant = float(np.linalg.norm(self.at_contact.T @ (self.weights * pressure)))
        self.largest_pressure = max(self.largest_pressure, float(np.max(pressure, initial=0.0)))
        self.largest_resultant = max(self.largest_resultant, resultant)

    def recall(self, contact: dict[str, list]) -> None:
        """The largest pressure and resultant of the levels recorded in ``contact`` (a result's per-node
        arrays): a resumed run decides as the uninterrupted run does."""
        self.largest_pressure = self.largest_resultant = 0.0
        for compliance, rigid in zip(contact["pressure_compliance"], contact["pressure_rigid"]):
            self.remember(compliance, rigid)

    def without_rounding_resultant(self, b: np.ndarray, support: np.ndarray | None) -> tuple:
        """(b, its support, ‖Zᵀb‖) for a body that only the contact holds: a resultant of the loads on its free
        rigid motions that is within ``tolerance`` of zero, relative to the largest one of the run so far
        (a load that passes through zero, evaluated at a time that misses the zero by a rounding: log(t) at
        t = 1 + 2e-16), is the rounding of a zero resultant, and is removed, b − Z Zᵀb: no contact force can
        pull, so a body pulled by a rounding error would have no solution."""
        if not self.held_by_contact_only:
            return b, support, 0.0
        Z = self.basis
        r = Z.T @ b if support is None else Z[support].T @ b[support]
        size = float(np.linalg.norm(r))
        if 0.0 < size <= self.tolerance * self.largest_resultant:
            return b - Z @ r, None, 0.0
        return b, support, size

    def pull(self, step: StepData, resultant: float) -> float | None:
        """The part of the loads' resultant on the free motions (``resultant`` = ‖Zᵀb‖ of ``step``) that no
        contact pressures can balance, when it exceeds ``tolerance`` relative to the loads (they pull the body
        off the foundation: no time step, however short, has a solution); None otherwise."""
        if not self.held_by_contact_only or resultant == 0.0:
            return None
        Z = self.basis
        loads = Z.T @ step.b if step.support is None else Z[step.support].T @ step.b[step.support]
        pull = unbalanced(self.at_contact, loads)
        return pull if pull > self.tolerance * step.b_norm else None

    def pressed(self, solution: StepSolution, compliance: np.ndarray) -> bool:
        """Does a contact node carry a force at a converged level: its pressure (``compliance`` and the rigid
        part λ_i / w_i) above ``tolerance`` times the largest pressure of the run so far (below is the
        rounding of a zero force)?"""
        w = self.weights
        rigid = np.divide(solution.lam, w, out=np.zeros_like(w), where=w > 0)
        return bool(np.max(compliance + rigid, initial=0.0) > self.tolerance * self.largest_pressure)

    def rest(self, attempt, before: np.ndarray, now: np.ndarray, length: float, step: str):
        """(The attempt of a level that nothing presses placed by :meth:`place` (its ``rigid`` the new position),
        within the complementarity Newton allows, ``tolerance`` × ``length``, the body's size; None), or (the attempt,
        the failure's message) when no place exists; ``step`` names the step ("step n (t = t_n)")."""
        placed = self.place(attempt.solution, before, now, room(attempt.step), self.tolerance * length)
        if placed is None:
            return attempt, (f"{step} failed: at t = {attempt.t:.10g} no contact node carries a force, the Dirichlet "
                             f"conditions leave a rigid motion of the body free, and no such motion takes every "
                             f"contact node off the layer: hold that motion with boundary.dirichlet entries")
        solution, place = placed
        return replace(attempt, solution=solution, rigid=place), None

    def place(self, solution: StepSolution, before: np.ndarray, now: np.ndarray, room: np.ndarray,
              allowance: float) -> tuple[StepSolution, np.ndarray] | None:
        """A level that nothing presses on the foundation, placed where its body changes least from the last
        level: (its solution moved by the least rigid shift that leaves every contact node within its
        ``room``, unloaded; the body's new position Zᵀu), from its position ``before`` (the last level's)
        and ``now`` (where the Newton iteration left it); None when no such place exists (a node that no
        free motion moves lies beyond its room by more than ``allowance``)."""
        NZ = self.at_contact
        shift = least_shift(NZ, solution.d + NZ @ (before - now), room, allowance)
        if shift is None:
            return None
        place = before + shift
        m = solution.d.size
        d = np.minimum(solution.d + NZ @ (place - now), room)  # the nodes placed at their room: exactly there
        placed = replace(solution, u=None if solution.u is None else solution.u + self.basis @ (place - now), d=d,
                         lam=np.zeros(m), active=np.zeros(m, dtype=bool))
        return placed, place
