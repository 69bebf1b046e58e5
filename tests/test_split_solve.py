"""One solve per step for a viscoplastic body (the condensed method's split solve): its load
b_n = F(t_n) − Bᵀz_n changes everywhere at every step, and its contact problem needs only N A0⁻¹ b_n;
PARDISO's Schur-mode factor gives that from the forward substitution, and u_n = A0⁻¹ (b_n − Nᵀq_n)
from the rest of the same solve."""

import numpy as np
import pytest

import vpcontact
from vpcontact.solvers import factorization
from conftest import half_disc_case
from test_3d import ball_case

BACKENDS = factorization.installed_backends()
needs_pardiso = pytest.mark.skipif("pardiso" not in BACKENDS, reason="MKL PARDISO is not installed")
PERZYNA = {"law": "perzyna", "eta": 0.5, "yield_stress": 1.0}  # yields from the first step on


def operators(case):
    """A0 = A + c Nᵀ N and N at the free dofs of a case's problem."""
    problem = vpcontact.build_problem(vpcontact.load_case(case))
    free = problem.free
    N = problem.surface.operator[:, free].tocsr()
    return (problem.A[free][:, free] + 1e3 * N.T @ N).tocsc(), N


@pytest.mark.parametrize("case", [half_disc_case(h=0.2), ball_case(h=0.5)], ids=["2D", "3D"])
@pytest.mark.parametrize("backend", BACKENDS)
def test_a_split_solve_is_the_solve_of_b_minus_the_contact_load(backend, case):
    """N A0⁻¹ b first, A0⁻¹ (b − Nᵀq) after, against dense linear algebra; with PARDISO's Schur-mode
    factor the second half costs no further solve, with the plain factor (after PLAIN_AFTER solves) and
    with SuperLU one."""
    A0, N = operators(case)
    dense = np.linalg.inv(A0.toarray())
    solver = factorization.factorize(A0, N, backend)
    rng = np.random.default_rng(3)
    for plain in (False, True):
        if plain:
            if backend != "pardiso":
                continue
            for _ in range(solver.PLAIN_AFTER + 1):  # only full solves: the plain factor replaces the Schur one
                solver.solve(rng.standard_normal(A0.shape[0]))
        b, q = rng.standard_normal(A0.shape[0]), rng.standard_normal(N.shape[0])
        split = solver.split(b)
        np.testing.assert_allclose(split.observed, N @ dense @ b, rtol=1e-10, atol=1e-13 * np.abs(dense @ b).max())
        expected = dense @ (b - N.T @ q)
        np.testing.assert_allclose(split.finish(q), expected, rtol=1e-10, atol=1e-13 * np.abs(expected).max())
        assert split.finish_solves == (0 if backend == "pardiso" and not plain else 1)


@needs_pardiso
def test_a_run_that_splits_its_solves_keeps_the_schur_factor():
    """More split solves than full ones: no plain factor is made (the split solves need the Schur one)."""
    A0, N = operators(half_disc_case(h=0.2))
    solver = factorization.factorize(A0, N, "pardiso")
    rng = np.random.default_rng(4)
    for _ in range(2 * solver.PLAIN_AFTER):
        solver.split(rng.standard_normal(A0.shape[0])).finish(rng.standard_normal(N.shape[0]))
        solver.solve(rng.standard_normal(A0.shape[0]))
    assert solver.split(np.ones(A0.shape[0])).finish_solves == 0


def viscoplastic(case, method, backend):
    case["material"]["viscoplastic"] = PERZYNA
    case["time"] = {"T": 1.1, "steps": 11}
    case["solver"].update(method=method, factorization=backend)
    case["output"]["field_steps"] = "all"
    return vpcontact.solve(case)


def relative(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@needs_pardiso
@pytest.mark.parametrize("case", [half_disc_case(h=0.1, load=20.0), ball_case(h=0.35)], ids=["2D", "3D"])
def test_one_solve_per_step_and_the_full_methods_solution(case):
    """A Perzyna body whose history changes at every step: the condensed method with PARDISO does one
    solve per step and gives the full method's solution (SuperLU, uncondensed) to rounding."""
    import copy

    condensed = viscoplastic(copy.deepcopy(case), "condensed", "pardiso")
    full = viscoplastic(copy.deepcopy(case), "full", "superlu")
    assert (condensed.method, full.method, condensed.status, full.status) == ("condensed", "full", "complete",
                                                                              "complete")
    steps = condensed.steps
    changed = [relative(condensed.fields[n + 1].z, condensed.fields[n].z) for n in range(2, steps)]
    assert min(changed) > 1e-3  # z_n, so b_n, new at every step from step 2 on (z_1 = 0, z_2 = k 𝒢(σ_1) ≠ 0)
    assert condensed.linear_solves == steps
    for name in ("displacement", "stress", "z"):
        reference = np.stack([getattr(full.fields[n], name) for n in range(1, steps + 1)])
        assert relative(np.stack([getattr(condensed.fields[n], name) for n in range(1, steps + 1)]), reference) < 1e-10
    for quantity in ("penetration", "xi", "K", "pressure_compliance"):
        assert relative(condensed.contact_history(quantity), full.contact_history(quantity)) < 1e-10, quantity
