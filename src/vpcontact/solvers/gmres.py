"""GMRES with right preconditioning, one cycle of at most a given number of iterations.

SciPy's ``gmres`` preconditions on the left: its iterations watch the preconditioned residual
‖P⁻¹(b − K x)‖ and only the end of a restart cycle checks the true one, so with a preconditioner
that is not K itself a cycle often stops early on the first and fails the second (the condensed
Newton systems of the quarter ball: 3–5 iterations, then "not converged"), and a bound on the
iterations cannot be enforced without restarts. Preconditioned on the right, GMRES minimizes the true
residual ‖b − K P⁻¹ y‖ over the Krylov space of K P⁻¹, so the residual it watches is the one wanted
and one cycle is the whole solve. Orthogonalization: classical Gram–Schmidt done twice (two
matrix–vector products with the basis per iteration, orthogonal to working precision); the
least-squares problem by Givens rotations. After the cycle the true residual is computed again: the
solution is accepted only on it.

The stopping test is ‖b − K x‖ ≤ tolerance ‖b‖ + floor ‖x‖: a relative residual, or, with
floor = c ε ‖K‖, the rounding level of the product K x itself (a normwise backward error of c ε) for a
system too ill-conditioned for the relative residual to reach the tolerance in floating point (where a
direct solve stops too).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as la

Operator = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class KrylovSolution:
    """x, the iterations done, and whether the stopping test holds for the x returned (its true residual)."""

    x: np.ndarray
    iterations: int
    converged: bool


def gmres(K: Operator, P_inverse: Operator, b: np.ndarray, tolerance: float, max_iterations: int,
          floor: float = 0.0) -> KrylovSolution:
    """Solve K x = b by GMRES on K P⁻¹ y = b, x = P⁻¹ y, from x = 0, until the residual is at most
    ``tolerance`` ‖b‖ + ``floor`` ‖x‖ or after ``max_iterations`` iterations."""
    norm_b = np.linalg.norm(b)
    if norm_b == 0.0 or not np.isfinite(norm_b):
        return KrylovSolution(np.zeros_like(b), 0, bool(norm_b == 0.0))
    V = np.empty((max_iterations + 1, b.size))  # orthonormal basis of the Krylov space (rows)
    Z = np.empty((max_iterations, b.size))  # P⁻¹ of each basis vector
    H = np.zeros((max_iterations + 1, max_iterations))  # Hessenberg matrix, made triangular by the rotations
    rotations = np.zeros((max_iterations, 2))  # (cos, sin) of each Givens rotation
    g = np.zeros(max_iterations + 1)  # the rotated right-hand side ‖b‖ e_1: |g[j + 1]| is the residual
    V[0], g[0] = b / norm_b, norm_b
    iterations = 0
    for j in range(max_iterations):
        Z[j] = P_inverse(V[j])
        w = K(Z[j])
        for _ in range(2):  # classical Gram–Schmidt, twice
            h = V[: j + 1] @ w
            w -= h @ V[: j + 1]
            H[: j + 1, j] += h
        norm_w = H[j + 1, j] = np.linalg.norm(w)
        for i in range(j):  # the earlier rotations on the new column
            c, s = rotations[i]
            H[i, j], H[i + 1, j] = c * H[i, j] + s * H[i + 1, j], -s * H[i, j] + c * H[i + 1, j]
        radius = np.hypot(H[j, j], H[j + 1, j])
        if not (0.0 < radius < np.inf):  # K P⁻¹ singular on the Krylov space, or not finite: the last iterate
            break
        c, s = rotations[j] = H[j, j] / radius, H[j + 1, j] / radius
        H[j, j], H[j + 1, j] = radius, 0.0
        g[j], g[j + 1] = c * g[j], -s * g[j]
        iterations = j + 1
        if norm_w == 0.0 or abs(g[j + 1]) <= tolerance * norm_b:  # the exact solution, or converged
            break
        if floor > 0.0 and abs(g[j + 1]) <= tolerance * norm_b + floor * np.linalg.norm(_iterate(H, g, Z, iterations)):
            break
        V[j + 1] = w / norm_w
    if iterations == 0:
        return KrylovSolution(np.zeros_like(b), 0, False)
    x = _iterate(H, g, Z, iterations)
    residual = np.linalg.norm(b - K(x))
    return KrylovSolution(x, iterations, bool(residual <= tolerance * norm_b + floor * np.linalg.norm(x)))


def _iterate(H: np.ndarray, g: np.ndarray, Z: np.ndarray, iterations: int) -> np.ndarray:
    """x = P⁻¹ V y after ``iterations`` iterations, y minimizing the residual (the rotated triangular system)."""
    y, _ = la.lapack.dtrtrs(H[:iterations, :iterations], g[:iterations])  # LAPACK itself: a system of ≤ 20
    return y @ Z[:iterations]
