"""What the time loop checks at a level, and how it words a failed step: the viscoplastic law's rate
𝒢(σ, ε) of the right shape and the history z it makes finite, the contact laws K(ξ) and p(r) finite and
≥ 0 at every contact node, loads that no contact pressure can balance, and the one line of a step whose
Newton iteration failed even after its cuts (the residuals, the contact counts and what to try)."""

from __future__ import annotations

import numpy as np

from ..errors import point
from ..mesh.cells import coordinates
from ..laws.contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED, node_status
from ..solvers import StepSolution


class LawShapeError(ValueError):
    """A viscoplastic law whose values do not have the shape of its arguments (one that passed the check
    before the run, at t_0, and changes its shape later): the step fails with this message."""


def viscoplastic_rate(G, sigma: np.ndarray, strain: np.ndarray) -> np.ndarray:
    """𝒢(σ, ε) per element, checked: an array of the shape of σ, (d, d, nelements); LawShapeError otherwise."""
    rate = G(sigma.copy(), strain.copy())  # a law may not change the stored fields
    try:
        rate = np.broadcast_to(np.asarray(rate, dtype=float), sigma.shape)
    except (TypeError, ValueError):
        raise LawShapeError(f"the viscoplastic law returned an array of shape {np.shape(rate)}; expected "
                            f"{sigma.shape} (d, d, elements), like its arguments") from None
    return rate


def history_failure(problem, state, n: int, share) -> str | None:
    """The failure of step n when the history it starts from (``state``, the LoopState), z_n = z_{n−1} + k 𝒢
    (explicit), is not finite on the elements of any rank (``share``, an
    :class:`~vpcontact.parallel.elements.ElementShare`; no step cut can help: the sub-steps' z lie between z_{n−1}
    and z_n); None when it is."""
    with np.errstate(all="ignore"):  # a history that is not finite is reported
        finite = state.rate is None or share.all_finite(state.z_after(problem.k))
    if finite:
        return None
    return (f"step {n} (t = {problem.times[n - 1]:g}) failed: the viscoplastic history is not finite at its "
            f"start (is the explicit step k = {problem.k:g} small against the law's relaxation time?)")


def invalid_law(problem, n: int, t: float, d: np.ndarray, xi: np.ndarray) -> str | None:
    """The failure of step n at a level (time t) where the contact laws K(ξ) or p(r) are not finite numbers ≥ 0
    at some contact node (a layer cannot pull: a user's law that turns negative, or one evaluated beyond its
    range); None when they are valid everywhere."""
    wrong = law_violation(problem, d, xi)
    if wrong is None:
        return None
    return f"step {n} (t = {problem.times[n - 1]:g}) failed: at t = {t:.10g} {wrong}"


def pulled_off(problem, motions, n: int, attempt) -> str | None:
    """The failure of step n whose ``attempt`` has loads with a resultant on the rigid motions held only by
    contact (``motions``, :class:`~vpcontact.timeloop.resting.FreeMotions`) that no contact pressures can
    balance, by more than ``solver.tolerance`` relative to the loads (they pull the body off the foundation:
    no time step, however short, has a solution); None otherwise."""
    pull = motions.pull(attempt.step, attempt.resultant)
    if pull is None:
        return None
    k = motions.basis.shape[1]
    free = "a rigid motion" if k == 1 else f"{k} rigid motions"
    it, that = ("it", "that motion") if k == 1 else ("them", "those motions")
    return (f"step {n} (t = {problem.times[n - 1]:g}) failed: at t = {attempt.t:.10g} the loads pull the body "
            f"off the foundation: the Dirichlet conditions leave {free} of the body free, and {pull:.3g} of the "
            f"loads' resultant on {it} ({pull / attempt.resultant:.0%}) is a pull that no contact pressure can "
            f"balance, so nothing holds the body; keep the loads pressing it on the foundation, or hold {that} with "
            f"boundary.dirichlet entries")


def not_finite(problem, n: int, t: float, share, values: dict[str, np.ndarray], fields, computed) -> str | None:
    """The failure of step n at a level (time t) where one of ``values`` (name: array), the displacement or the
    stress (of its ``fields``, else of what was ``computed`` there: (u, ε, σ, z) on the elements of ``share``) is
    not finite (a viscoplastic history that blows up, float64 overflow); None when all are."""
    values = dict(values)
    if fields is not None:
        values.update({"the displacement": fields.displacement, "the stress": fields.von_mises})
    elif computed is not None:
        values.update({"the displacement": computed[0]})
    wrong = [name for name, value in values.items() if not np.all(np.isfinite(value))]
    if fields is None and computed is not None and not share.all_finite(computed[2]):
        wrong.append("the stress")
    if not wrong:
        return None
    cause = (f"the viscoplastic history blows up: is the explicit step k = {problem.k:g} small against the "
             f"law's relaxation time?" if problem.viscoplastic is not None else
             "float64 overflow: state the loads, moduli and laws in units that keep them far from 1e308")
    return f"step {n} (t = {problem.times[n - 1]:g}) failed: {wrong[0]} is not finite at t = {t:.10g} ({cause})"


def failed_solve(problem, message: str, advice: str) -> StepSolution:
    """The record of a step of ``problem`` whose Newton iteration stopped on a failed linear solve."""
    m = problem.surface.size
    return StepSolution(None, np.zeros(m), np.full(m, np.nan), np.zeros(m, dtype=bool), 0, np.nan, np.nan, False,
                        message, advice)


def law_violation(problem, d: np.ndarray, xi: np.ndarray) -> str | None:
    """Where the contact laws of ``problem`` are not finite numbers ≥ 0 at the penetrations ``d`` and
    histories ``xi`` (see ContactLaw.violation), in words: the law, its value, the node, where it is and the
    law's argument there, and what to check; None if nowhere."""
    violation = problem.law.violation(d, xi)
    if violation is None:
        return None
    law, i, value, argument, at = violation
    surface = problem.surface
    names = ", ".join(coordinates(surface.coordinates.shape[0]))
    key = "contact.stiffness" if law.startswith("K") else "contact.p"
    return (f"the contact law {law} is {value:.6g} at contact node {i} ({names}) = "
            f"{point(surface.coordinates[:, i])}, where {argument} = {at:.6g}; it must be a finite number >= 0 (a "
            f"layer cannot pull): check {key} at this {argument}")


def failure_message(problem, state, n: int, attempt, cuts: int, share) -> str:
    """One line for step n of ``problem`` that failed at ``attempt`` (a (sub-)step from ``state``, the
    LoopState, z on the elements of ``share``, an :class:`~vpcontact.parallel.elements.ElementShare`) after
    ``cuts`` step cuts: the step, its time, where the cuts ended, the residuals, the contact counts and what to
    try."""
    t_n = problem.times[n - 1]
    s = attempt.solution
    where = (f" after {cuts} step cut{'s' if cuts != 1 else ''} (sub-step of length {attempt.h:g} ending at "
             f"t = {attempt.t:.10g})" if cuts else "")
    counts = ""
    if s.d.size and np.all(np.isfinite(s.d)):
        status = node_status(s.d, s.active)
        counts = (f"; contact nodes separated/in compliance/at limit = {int(np.sum(status == SEPARATED))}/"
                  f"{int(np.sum(status == IN_COMPLIANCE))}/{int(np.sum(status == AT_LIMIT))}")
    advice = f"; {s.advice}" if s.advice else ""
    if s.d.size and np.all(np.isfinite(s.d)):
        wrong = law_violation(problem, s.d, state.xi + attempt.h * np.maximum(s.d, 0.0))
        advice = f"; at the last iterate {wrong}" if wrong is not None else advice
    if attempt.z is not None and not np.isfinite(s.residual) and state.rate is not None:
        largest = share.ranks.max(float(np.abs(attempt.z).max(initial=0.0)))  # over every rank's elements
        advice = (f"; the viscoplastic history reaches |z| = {largest:.3g}: is the explicit step "
                  f"k = {problem.k:g} small against the law's relaxation time?")
    return (f"step {n} (t = {t_n:g}) failed{where}: {s.message}; residual {s.residual:.3e}, "
            f"complementarity {s.complementarity:.3e}{counts}{advice}")
