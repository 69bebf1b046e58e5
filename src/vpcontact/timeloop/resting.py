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
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import nnls


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
