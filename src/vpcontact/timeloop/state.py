"""What the time loop carries from one converged time level to the next (:class:`LoopState`, from the
initial level t_0 on), the trend of a level's solution that starts the next Newton iteration
(:class:`Trend`), and a (sub-)step tried from a state (:class:`Attempt`). A state is all a checkpoint
keeps of the loop itself: :meth:`LoopState.arrays` and :meth:`LoopState.from_arrays` turn it into named
arrays and back, bit for bit."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..parallel.elements import ElementShare
from ..solvers import StepData, StepSolution
from .checks import viscoplastic_rate


def element_history_bytes(elements: int, dim: int) -> int:
    """Bytes of a viscoplastic body's element arrays the time loop holds from one level to the next, each of d × d
    doubles an element: z, 𝒢 and z + h𝒢 (:class:`LoopState`), the last level's ε and σ, and one more for the law's
    temporaries while 𝒢 is computed. On MPI ranks each rank holds its elements' (:mod:`vpcontact.parallel.elements`)."""
    return 6 * 8 * dim * dim * elements


@dataclass
class LoopState:
    """What the time loop carries from the last converged time level to the next one."""

    step: int  # time steps t_n done
    xi: np.ndarray  # ξ at the last level
    z: np.ndarray | None  # z at the last level, σ = ℰε(u) + z there (d, d, elements); None: z ≡ 0
    rate: np.ndarray | None  # 𝒢(σ, ε) at the last level; None: 𝒢 = 0
    previous: StepSolution | None  # the last level's solution
    trend: Trend | None = None  # how it changed since the level before (None: no level before)
    step_problem: StepData | None = None  # the last level's step problem (None: the initial level, or a resumed run)
    rigid: np.ndarray | None = None  # Zᵀu at the last level, where known (see TimeLoop.rigid_position)
    _z_after: tuple = field(default=(None, None), init=False, repr=False, compare=False)  # (h, z_after(h))

    @classmethod
    def initial(cls, problem, rigid: np.ndarray, share: ElementShare) -> "LoopState":
        """The level t_0 of ``problem``: ξ_0, z_0 = σ_0 − ℰε(u_0) and 𝒢(σ_0, ε(u_0)) (the j = 0 term of z) on the
        elements of ``share`` (this rank's), and u_0 with its penetrations as the start of the first Newton
        iteration (none when u_0 = 0), and Zᵀu_0 on the rigid motions ``rigid`` (Z) held only by contact."""
        initial = problem.initial
        u0 = initial.dofs(problem.basis)
        strain0, z0 = share.mine(problem.initial_strain), share.mine(problem.initial_history)
        G = share.viscoplastic
        history = G is not None or np.any(problem.initial_history != 0.0)  # z ≠ 0 possible: b carries Bᵀz
        rate = viscoplastic_rate(G, share.mine(initial.stress), strain0) if G is not None else None  # j = 0
        start = None
        if initial.moves:
            surface = problem.surface
            d0 = surface.operator @ u0 - surface.gap0
            start = StepSolution(u0[problem.free], np.zeros(surface.size), d0, np.zeros(surface.size, dtype=bool), 0,
                                 np.nan, np.nan, True)
        return cls(0, initial.xi.copy(), z0 if history else None, rate, start, rigid=rigid.T @ u0[problem.free])

    def z_after(self, h: float) -> np.ndarray | None:
        """z at the level h after the last one (explicit: z + h 𝒢), computed once per h (the loop checks it
        is finite after a step, the next step uses it)."""
        if self.rate is None:
            return self.z
        if self._z_after[0] != h:
            self._z_after = (h, self.z + h * self.rate)
        return self._z_after[1]

    def start(self, h: float) -> StepSolution | None:
        """The first Newton iterate of the level h after the last one: the last level's solution
        extrapolated linearly in time along its trend (λ kept ≥ 0; u where the trend has it: the level before a
        change of method may not have u); the last level's solution itself when it has no trend (the first
        step), None when there is none (start from zero)."""
        previous, trend = self.previous, self.trend
        if previous is None or trend is None:
            return previous
        u = previous.u if previous.u is None or trend.u is None else previous.u + h * trend.u
        return replace(previous, u=u, lam=np.maximum(previous.lam + h * trend.lam, 0.0), d=previous.d + h * trend.d)

    def arrays(self, rigid: np.ndarray, share: ElementShare) -> dict[str, np.ndarray]:
        """The state as named arrays, ``rigid`` its Zᵀu: ``step``, ``xi``, ``rigid``, ``z`` and ``rate`` (where
        there is a history, over all the elements: ``share`` holds this rank's; a collective call on several ranks),
        the last solution (``previous_u`` for a solver that returns u, ``previous_lam``, ``previous_d``,
        ``previous_active``, ``previous_report``: its iterations, residual and complementarity) and its trend
        (``trend_u``, ``trend_lam``, ``trend_d``). The step problem is not kept (see TimeLoop.rigid_position)."""
        arrays = {"step": np.array(self.step), "xi": self.xi, "rigid": rigid}
        if self.z is not None:
            arrays["z"] = share.whole(self.z)
        if self.rate is not None:
            arrays["rate"] = share.whole(self.rate)
        previous = self.previous
        if previous is not None:
            if previous.u is not None:
                arrays["previous_u"] = previous.u
            arrays.update(previous_lam=previous.lam, previous_d=previous.d, previous_active=previous.active,
                          previous_report=np.array([previous.iterations, previous.residual, previous.complementarity]))
        trend = self.trend
        if trend is not None:
            if trend.u is not None:
                arrays["trend_u"] = trend.u
            arrays.update(trend_lam=trend.lam, trend_d=trend.d)
        return arrays

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], share: ElementShare) -> "LoopState":
        """The state of :meth:`arrays`, z and 𝒢 at the elements of ``share`` (KeyError for one that is missing)."""
        previous = None
        if "previous_lam" in arrays:
            iterations, residual, complementarity = arrays["previous_report"]
            previous = StepSolution(arrays.get("previous_u"), arrays["previous_lam"], arrays["previous_d"],
                                    arrays["previous_active"].astype(bool), int(iterations), float(residual),
                                    float(complementarity), True)
        trend = Trend(arrays.get("trend_u"), arrays["trend_lam"], arrays["trend_d"]) if "trend_lam" in arrays else None
        return cls(int(arrays["step"]), arrays["xi"], share.mine(arrays.get("z")), share.mine(arrays.get("rate")),
                   previous, trend, rigid=arrays["rigid"])


@dataclass
class Trend:
    """The rate of change in time of a level's solution: (x_n − x_{n−1}) / h_n for u, λ and d, from the
    level before it (u is None when a solver does not return it)."""

    u: np.ndarray | None
    lam: np.ndarray
    d: np.ndarray

    @classmethod
    def between(cls, before: StepSolution, after: StepSolution, h: float) -> "Trend":
        u = None if before.u is None or after.u is None else (after.u - before.u) / h
        return cls(u, (after.lam - before.lam) / h, (after.d - before.d) / h)


@dataclass
class Attempt:
    """A (sub-)step tried from the current state: it ends at t, h after the last level, with the step problem
    ``step``, the history z there and the solver's ``solution``; ``resultant``: ‖Zᵀb‖, the loads' resultant on
    the rigid motions held only by contact (0 when there are none); ``rigid``: Zᵀu where the time loop placed
    the body itself (a level where nothing presses it: :mod:`vpcontact.timeloop.resting`), else None; ``load``: F(t)
    and ``history_force``: Bᵀz at every dof (None: z = 0), for the reactions of the Dirichlet parts; ``held``: the
    prescribed u_D(t) at the held dofs (None: u_D = 0)."""

    t: float
    h: float
    step: StepData
    z: np.ndarray | None
    solution: StepSolution
    resultant: float = 0.0
    rigid: np.ndarray | None = None
    load: np.ndarray | None = None
    history_force: np.ndarray | None = None
    held: np.ndarray | None = None
