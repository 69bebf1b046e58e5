"""The quasistatic time loop (Sect. 3 of the paper, DESIGN §2).

At t_n = n k:
    z_n   = σ_0 − ℰε(u_0) + Σ_{j=0}^{n−1} k 𝒢(σ_j, ε(u_j))   (explicit viscoplastic history, per element)
    b_n   = F(t_n) − Bᵀ z_n
    (u_n, λ_n) solves the step problem with ξ^{n−1}             (one solver call)
    ξ_n   = ξ_{n−1} + k (d_n)⁺                                  (implicit rectangle rule for (2.15))
    σ_n   = ℰε(u_n) + z_n                                       (the discrete (2.28))
with u_0 = 0 and a uniform σ_0 (``problem.initial_stress``), so z_1 = σ_0 + k 𝒢(σ_0, 0). The bulk
operator is the same at every step; with 𝒢 ≠ 0, u_n is computed at every step (σ_n feeds z_{n+1}).
"""

from __future__ import annotations

import time as clock

import numpy as np
from tqdm.auto import tqdm

from .assembly import element_strain, stress_force
from .contact import node_status
from .problem import Problem
from .material import von_mises
from .results import Fields, Result
from .solvers import StepData, make_solver


def solve_problem(problem: Problem, *, progress: bool = False) -> Result:
    """Run the time loop of ``problem`` and return the result (status "failed" if a step fails)."""
    started = clock.perf_counter()
    case, free, surface, law = problem.case, problem.free, problem.surface, problem.law
    options = case.solver
    solver = make_solver(options.method, problem.A[free][:, free].tocsr(), surface.operator[:, free].tocsr(),
                         surface.weights, surface.gap0, augmentation=options.augmentation,
                         tolerance=options.tolerance, max_iterations=options.max_iterations,
                         length_scale=problem.mesh.diameter, factorization=options.factorization)
    result = Result.start(problem, solver)
    loop_started = clock.perf_counter()
    nelements = problem.mesh.mesh.t.shape[1]
    u = np.zeros(problem.basis.N)
    xi = np.zeros(surface.size)
    G, k = problem.viscoplastic, problem.k
    sigma0 = np.repeat(np.asarray(problem.initial_stress, dtype=float)[:, :, None], nelements, axis=2)
    history = G is not None or np.any(sigma0 != 0.0)  # z ≠ 0 possible: the right-hand side carries Bᵀz
    z = sigma0.copy()  # σ_0 − ℰε(u_0), u_0 = 0
    if G is not None:
        z = z + k * viscoplastic_rate(G, sigma0, np.zeros_like(sigma0))  # the j = 0 term
    previous = None

    with tqdm(total=len(problem.times), disable=not progress, unit="step", desc="time steps") as bar:
        for n, t in enumerate(problem.times, start=1):
            b = problem.loads(t)
            if history:
                b -= stress_force(problem.basis, z)
            step = StepData(b[free], law, xi, problem.k)
            solution = solver.solve(step, previous)
            if not solution.converged:
                result.fail(n, t, solution)
                break
            previous, d = solution, solution.d
            compliance, _ = law.pressure(d, xi, problem.k)
            xi = xi + problem.k * np.maximum(d, 0.0)
            fields, blown_up = None, False
            if G is not None or n in result.field_steps or n == len(problem.times):
                u[free] = solver.displacement(step, solution)
                strain = element_strain(problem.basis, u)
                sigma = problem.elasticity.stress(strain) + z  # σ_n = ℰε(u_n) + z_n
                sigma33 = problem.elasticity.out_of_plane_stress(strain)
                fields = Fields(displacement=u[problem.basis.nodal_dofs].T.copy(), stress=np.moveaxis(sigma, -1, 0),
                                stress33=sigma33, von_mises=von_mises(sigma, sigma33),
                                z=np.moveaxis(z, -1, 0).copy() if history else None)
                if G is not None:
                    z = z + k * viscoplastic_rate(G, sigma, strain)  # z_{n+1}
                    blown_up = not np.all(np.isfinite(z))
            result.record(n, t, solution, fields, xi=xi, K=law.K(xi), compliance=compliance,
                          status=node_status(d, solution.active))
            row = result.rows[-1]
            bar.set_postfix(newton=row["newton_iterations"], residual=f"{row['residual']:.1e}",
                            at_limit=row["nodes_at_limit"], refresh=False)
            bar.update()
            if blown_up:
                result.status = "failed"
                result.message = (f"after step {n} (t = {t:g}): the viscoplastic history is not finite (is the explicit "
                                  f"step k = {k:g} small against the law's relaxation time?)")
                break
    now = clock.perf_counter()
    result.linear_solves = solver.solves
    result.finish({**problem.timings, **solver.timings, "time_loop": now - loop_started,
                   "total": problem.timings["build"] + now - started})
    return result


def viscoplastic_rate(G, sigma: np.ndarray, strain: np.ndarray) -> np.ndarray:
    """𝒢(σ, ε) per element, checked: an array of the shape of σ, (2, 2, nelements)."""
    rate = G(sigma.copy(), strain.copy())  # a law may not change the stored fields
    try:
        rate = np.broadcast_to(np.asarray(rate, dtype=float), sigma.shape)
    except (TypeError, ValueError):
        raise ValueError(f"the viscoplastic law returned an array of shape {np.shape(rate)}; expected "
                         f"{sigma.shape} (2, 2, elements), like its arguments") from None
    return rate
