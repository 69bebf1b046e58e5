"""The length of the time loop's (sub-)steps: ``time.adaptive`` keeps the error in time within a share of the error
in space.

The steps of ``time.steps`` stay the run's steps: their times are those of the history's step rows, of the fields
and of the checkpoints. Under ``time.adaptive`` a step is done in sub-steps where the time estimate asks for them:
the sub-step of length h from a level is accepted when the time estimate it adds (θ = ‖D_n − D_{n−1}‖_E, of the
second-order companion, :mod:`vpcontact.timeloop.companion`) is within its share of the largest space estimate of the
run so far, max η_h (the attempted levels' included, and never below FLOOR · ‖u_h‖_E)::

    θ ≤ time.balance · max η_h · h / (T − t_0)

so that η_k(t_n) ≤ Σ θ ≤ ``time.balance`` · max η_h at every level (error per unit step). The largest estimate, not
the current one: near t_0, where the solution starts from rest, the first steps' error is a fixed fraction of a
solution that is itself O(h), and no halving would bring it under a share of the current η_h. A sub-step above its
share is done again as two halves (the path of a step whose Newton iteration fails), down to ``time.max_halvings``
halvings of the step, where it is accepted above its share (counted: ``time_over_share`` in summary.json; where a
node enters contact or an element starts to yield, the rates have a kink and θ does not fall as h²). θ ∝ h² and its
share ∝ h: from the last sub-step's ratio the next step starts in as many halvings as keep its sub-steps at half
their share (at least one sub-step: a step is never lengthened).
"""

from __future__ import annotations

import numpy as np

from ..problem.time_grid import TimeGrid

#: The budget's least value relative to the solution's energy norm ‖u_h‖_E: where the space estimate is zero (a
#: solution P1 represents exactly: a block pressed uniformly), an error in time below it is not resolved.
FLOOR = 1e-6



class TimeControl:
    """The (sub-)steps of a run on ``times`` (:class:`~vpcontact.problem.time_grid.TimeGrid`): ``balance`` the share
    of ``time.adaptive`` (None: not adaptive, each step in one), at most ``max_halvings`` halvings of a step."""

    def __init__(self, times: TimeGrid, balance: float | None, max_halvings: int):
        self.times, self.balance, self.max_halvings = times, balance, max_halvings
        self.halvings = 0  # of the next step, as the last sub-step predicts
        self.over_share = 0  # levels accepted above their share, at max_halvings
        self.largest = 0.0  # the largest space estimate of the run so far

    def meta(self) -> dict:
        """What a checkpoint keeps of the control: the next step's halvings, the levels over their share, the largest
        space estimate so far."""
        return {"halvings": self.halvings, "time_over_share": self.over_share, "time_largest": self.largest}

    def restore(self, meta: dict) -> None:
        """The control of :meth:`meta` (a checkpoint of before ``time.adaptive`` has none: a control at rest)."""
        self.halvings, self.over_share = int(meta.get("halvings", 0)), int(meta.get("time_over_share", 0))
        self.largest = float(meta.get("time_largest", 0.0))

    def sub_steps(self, n: int) -> list[tuple[float, float]]:
        """(t, h) of each sub-step that starts step n: 2^halvings of length k / 2^halvings, ending at t_n − j h
        (the times a step cut in halves reaches), the last at t_n exactly (``halvings`` as it is
        now: each sub-step's estimate predicts the next step's anew)."""
        times, pieces = self.times, 2**self.halvings
        end, h = times[n - 1], times.k / pieces
        return [(end - (pieces - j) * h, h) for j in range(1, pieces + 1)]

    def too_coarse(self, space_estimate: float, companion, h: float, halvings: int) -> bool:
        """Whether a (sub-)step of length h, its step's halved ``halvings`` times, must be done again as two halves:
        the time estimate θ it adds (``companion``: :class:`~vpcontact.timeloop.companion.CompanionLevel`) is above
        its share of the largest space estimate so far (the module docstring; ``space_estimate``: η_h at its level;
        a step where the companion failed is above it) and it can be halved again. The next step's halvings are
        predicted from it. Always False without ``time.adaptive``."""
        if self.balance is None:
            return False
        self.largest = max(self.largest, space_estimate, FLOOR * companion.norm)
        can_halve = halvings < self.max_halvings
        if not companion.known:
            self.over_share += not can_halve
            return can_halve
        times, theta = self.times, companion.step_estimate
        share = self.balance * self.largest * h / (times.T - times.start)
        ratio = theta / share if share > 0.0 else (0.0 if theta == 0.0 else np.inf)
        wanted = np.log2(max(2.0 * ratio * times.k / h, 1.0)) if np.isfinite(ratio) else self.max_halvings
        self.halvings = int(min(np.ceil(wanted - 1e-9), self.max_halvings))
        if ratio <= 1.0:
            return False
        self.over_share += not can_halve
        return can_halve
