"""The condensed method's Newton systems solved by GMRES (preconditioned by the inverse of an earlier
Newton matrix) against the dense LU of each: the same results to 1e-8, the same Newton iterations, few
factorizations; GMRES itself; the failures typed."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

import vpcontact
from vpcontact.case.translate import output_options
from vpcontact.solvers.condensed_systems import KRYLOV_TOLERANCE, MAX_KRYLOV_ITERATIONS, NewtonSystems
from vpcontact.solvers.errors import NotConvergedError, SingularMatrixError, SolverError
from vpcontact.solvers.gmres import gmres
from vpcontact.timeloop.loop import TimeLoop
from conftest import half_disc_case
from test_3d import ball_case, block_case, states

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"


def power_law(beta):
    return {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": beta}


def quarter_ball(h: float) -> dict:
    """examples/quarter_ball.toml at the element edge h, no figures."""
    case = tomllib.loads(EXAMPLE.read_text())
    case["mesh"]["h"], case["output"]["figures"] = h, False
    return case


CASES = {
    "2D half disc beta=1": half_disc_case(h=0.1, load=20.0, g=0.1, stiffness=power_law(1.0)),
    "2D half disc beta=-1": half_disc_case(h=0.1, load=20.0, g=0.1, stiffness=power_law(-1.0)),
    "3D quarter ball (the example)": quarter_ball(h=0.2),
    "3D ball on a flat foundation": ball_case(h=0.35, g=0.05, normal=[0, 0, -1], gap="z"),
    "3D block with a curved gap": block_case(g=0.02, gap="0.1*(x*x + y*y)"),
}
#: the layer holds the example's ball: no node reaches the limit
NOTHING_AT_THE_LIMIT = {"3D quarter ball (the example)"}
#: the cases with a step where nodes are separated, in compliance and at the limit
ALL_THREE_STATES = {"3D ball on a flat foundation", "3D block with a curved gap"}


#: ``krylov_from`` for a dense LU of every Newton system
DENSE = 10**9


def condensed_run(case, krylov_from: int | None = None):
    """The case by the condensed method, fields at every step; with ``krylov_from``: its Newton systems by
    GMRES from that many contact nodes on (0: always, DENSE: never)."""
    case = vpcontact.load_case(case, {"solver.method": "condensed", "output.field_steps": "all"})
    loop = TimeLoop(vpcontact.build_problem(case), output_options(case.output))
    if krylov_from is not None:
        loop.solver.krylov_from = krylov_from
    result = loop.run()
    assert result.status == "complete", result.message
    return result


def relative(a, b):
    return np.abs(a - b).max() / max(np.abs(a).max(), np.abs(b).max(), 1e-300)


@pytest.mark.parametrize("name", CASES)
def test_gmres_agrees_with_the_dense_newton_systems(name):
    dense, krylov = condensed_run(CASES[name], krylov_from=DENSE), condensed_run(CASES[name], krylov_from=0)
    assert dense.krylov_iterations == 0 and dense.newton_factorizations == dense.series("newton_iterations").sum()
    assert krylov.krylov_iterations > 0
    assert (states(dense)[:, 2].max() > 0) == (name not in NOTHING_AT_THE_LIMIT)  # the active set is exercised
    if name in ALL_THREE_STATES:
        assert np.all(states(dense) > 0, axis=1).any(), states(dense)
    for step, fields in dense.fields.items():
        assert relative(krylov.fields[step].displacement, fields.displacement) < 1e-8, step
        assert relative(krylov.fields[step].stress, fields.stress) < 1e-8, step
    for quantity in ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid"):
        assert relative(krylov.contact_history(quantity), dense.contact_history(quantity)) < 1e-8, quantity
    np.testing.assert_array_equal(krylov.contact_history("status"), dense.contact_history("status"))
    iterations, dense_iterations = krylov.series("newton_iterations"), dense.series("newton_iterations")
    assert np.abs(iterations - dense_iterations).max() <= 1
    assert abs(iterations.sum() - dense_iterations.sum()) <= 1
    assert krylov.step_cuts == dense.step_cuts == 0


def test_the_factor_of_one_newton_matrix_serves_many_iterations_and_steps():
    """The quarter ball, 11 steps: one LU for the whole run's Newton systems (a factor kept across
    iterations and steps, while the active set grows from nothing to the contact patch), a few GMRES
    iterations each; summary.json counts both."""
    result = condensed_run(CASES["3D quarter ball (the example)"], krylov_from=0)
    newton = int(result.series("newton_iterations").sum())
    assert newton >= 2 * result.steps and result.steps == 11
    assert result.newton_factorizations <= newton // 10
    assert newton <= result.krylov_iterations <= MAX_KRYLOV_ITERATIONS * newton // 2
    summary = result.summary()
    assert summary["krylov_iterations"] == result.krylov_iterations
    assert summary["newton_factorizations"] == result.newton_factorizations


# --- GMRES and the Newton systems on their own --------------------------------------------------------------
def test_gmres_preconditioned_by_a_stale_factor_converges_in_rank_plus_one_iterations():
    """K = K₀ + U Vᵀ with k = 4 columns in U: GMRES preconditioned by K₀'s LU needs at most k + 1
    iterations and reaches the tolerance on the true residual; with too few iterations it says so."""
    import scipy.linalg as la

    rng = np.random.default_rng(3)
    m, k = 200, 4
    K0 = rng.standard_normal((m, m)) + m ** 0.5 * np.eye(m)
    K = K0 + rng.standard_normal((m, k)) @ rng.standard_normal((k, m))
    factor = la.lu_factor(K0)
    b = rng.standard_normal(m)
    solution = gmres(lambda x: K @ x, lambda v: la.lu_solve(factor, v), b, 1e-12, 20)
    assert solution.converged and solution.iterations <= k + 1
    assert np.linalg.norm(b - K @ solution.x) <= 1e-12 * np.linalg.norm(b)
    short = gmres(lambda x: K @ x, lambda v: la.lu_solve(factor, v), b, 1e-12, k - 1)
    assert not short.converged and short.iterations == k - 1
    assert gmres(lambda x: K @ x, lambda v: v, np.zeros(m), 1e-12, 5).converged  # b = 0: x = 0, no iteration


def newton_systems(S):
    return NewtonSystems(S, np.abs(S).sum(axis=1))


def condensed_like(m=60, seed=4):
    """An S like the condensed operator's (symmetric positive definite), and the random generator."""
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((m, m))
    return B @ B.T / m + 0.1 * np.eye(m), rng


def test_newton_systems_in_node_order_match_the_dense_solve_whatever_the_active_set():
    """One factor, made for the first active set, preconditions the systems of other active sets and
    tangents (the node-ordered layout: a change of state or of a tangent changes a column, 2k columns
    here: at most 2k + 1 iterations); every solution is the dense one."""
    S, rng = condensed_like()
    systems, m = newton_systems(S), S.shape[0]
    tangent = -1.0 + 0.1 * rng.random(m)  # T − c0 < 0, as for a soft layer
    for changed in (0, 2, 5, 9):
        active = np.zeros(m, dtype=bool)
        active[:changed] = True
        drifted = tangent.copy()
        drifted[m - changed:] *= 1.1  # and the tangents of as many others change
        w = np.where(active, 1.0, drifted)
        rhs = rng.standard_normal(m)
        z = systems.solve_iterative(~active, w, rhs)
        np.testing.assert_allclose(z, systems.solve_direct(~active, w, rhs), rtol=1e-9, atol=0)
        K = systems.matrix(~active, w)
        assert np.linalg.norm(rhs - K @ z) <= KRYLOV_TOLERANCE * np.linalg.norm(rhs)
    assert systems.factorizations == 1 + 4  # one factor for GMRES, and the four dense solves
    assert systems.iterations <= sum(2 * changed + 1 for changed in (0, 2, 5, 9))


def test_the_kept_inverse_follows_changes_of_state_exactly_and_gmres_then_needs_one_iteration():
    """Nodes that reach the limit (or leave it) change their columns of K: the kept inverse is updated by the
    Sherman–Morrison–Woodbury formula, so with no tangent drifting it is K⁻¹ itself (to rounding), GMRES
    takes one iteration, and no new inverse is made; the solutions are the dense ones."""
    S, rng = condensed_like()
    systems, m = newton_systems(S), S.shape[0]
    tangent = -1.0 + 0.1 * rng.random(m)
    active = np.zeros(m, dtype=bool)
    iterations = []
    for newly in ([], [3, 7, 11], [12], [7, 40, 41, 42, 59]):
        active[newly] = ~active[newly]  # 7 reaches the limit, then leaves it
        w = np.where(active, 1.0, tangent)
        rhs = rng.standard_normal(m)
        before = systems.iterations
        z = systems.solve_iterative(~active, w, rhs)
        iterations.append(systems.iterations - before)
        np.testing.assert_allclose(z, systems.solve_direct(~active, w, rhs), rtol=1e-9, atol=0)
        K = systems.matrix(~active, w)
        assert np.abs(systems._factor.apply(K) - np.eye(m)).max() < 1e-10
    assert systems.updates == 3 and systems.factorizations == 1 + 4  # one inverse, four dense solves
    assert iterations == [1, 1, 1, 1]


def test_a_nearly_singular_newton_matrix_is_solved_as_accurately_as_by_the_dense_lu():
    """Separated nodes of a body held only by contact: K = I − (1 − 1e-12) c0 S with c0 S of largest
    eigenvalue 1 (cond(K) ≈ 1e12). The relative residual cannot reach KRYLOV_TOLERANCE (the dense LU's is
    about 1e-5), GMRES stops at the rounding level of K z instead, with the fresh factor and with a
    stale one, and its solution is the dense one to the accuracy of that (cond × ε ≈ 1e-4)."""
    S, rng = condensed_like()
    m = S.shape[0]
    values, vectors = np.linalg.eigh(S)
    S = (vectors * (values / values.max())) @ vectors.T  # c0 S, largest eigenvalue 1
    systems = newton_systems(S)
    inactive = np.ones(m, dtype=bool)
    for regularization in (1e-12, 2e-12):  # a fresh factor, then the stale one
        w = np.full(m, -(1.0 - regularization))
        rhs = rng.standard_normal(m)
        dense = systems.solve_direct(inactive, w, rhs)
        z = systems.solve_iterative(inactive, w, rhs)
        assert np.linalg.norm(z - dense) <= 1e-3 * np.linalg.norm(dense)
        residual = np.linalg.norm(rhs - systems.matrix(inactive, w) @ dense) / np.linalg.norm(rhs)
        assert residual > 100 * KRYLOV_TOLERANCE and np.linalg.norm(dense) > 1e8 * np.linalg.norm(rhs)
    assert systems.factorizations == 2 + 1


def test_a_newton_system_gmres_cannot_solve_is_a_typed_error_and_a_zero_pivot_is_singular():
    """Wilkinson's matrix (1 on the diagonal and in the last column, −1 below the diagonal), its columns
    scaled so that its inverse is not exact in floating point: its LU with partial pivoting grows like
    2^(m − 1), so the inverse kept from it solves it to a relative residual of about 2.6, and GMRES needs
    2 iterations to correct that: allowed 1, NotConvergedError (a SolverError). An exactly zero pivot:
    SingularMatrixError, as the dense solve."""
    m = 60
    wilkinson = np.eye(m) - np.tril(np.ones((m, m)), -1)
    wilkinson[:, -1] = 1.0
    wilkinson *= np.random.default_rng(2).uniform(0.5, 2.0, m)[None, :]
    rhs = np.random.default_rng(5).standard_normal(m)
    assert np.linalg.norm(rhs - wilkinson @ (np.linalg.inv(wilkinson) @ rhs)) > 0.1 * np.linalg.norm(rhs)
    all_active = np.zeros(m, dtype=bool)  # K = S diag(1) = S
    solved = newton_systems(wilkinson).solve_iterative(all_active, np.ones(m), rhs)
    assert np.linalg.norm(rhs - wilkinson @ solved) <= KRYLOV_TOLERANCE * np.linalg.norm(rhs)
    systems = NewtonSystems(wilkinson, np.abs(wilkinson).sum(axis=1), max_iterations=1)
    with pytest.raises(NotConvergedError, match="in 1 iterations") as error:
        systems.solve_iterative(all_active, np.ones(m), rhs)
    assert isinstance(error.value, SolverError) and systems.factorizations == 1 and systems.iterations == 1
    with pytest.raises(SingularMatrixError):
        newton_systems(np.zeros((m, m))).solve_iterative(all_active, np.ones(m), rhs)


def test_a_newton_system_that_is_not_finite_has_a_direction_that_is_not_finite():
    """A tangent that is not finite (iterates that blew up): z is not finite, as the dense solve's, and
    the Newton iteration reports the iterates (tests/test_inputs_contract.py); no factorization."""
    S, rng = condensed_like()
    systems, m = newton_systems(S), S.shape[0]
    w = np.full(m, -0.5)
    w[3] = np.nan
    assert np.all(np.isnan(systems.solve_iterative(np.ones(m, dtype=bool), w, rng.standard_normal(m))))
    assert systems.factorizations == systems.iterations == 0


def failing(monkeypatch, fails_at):
    """NewtonSystems.solve_iterative raises NotConvergedError (the error of a system GMRES cannot solve,
    see above) at the Newton systems of a run whose numbers (1, 2, ...) ``fails_at`` accepts."""
    solve_iterative = NewtonSystems.solve_iterative
    calls = []

    def fails(self, inactive, w, rhs):
        calls.append(rhs.size)
        if fails_at(len(calls)):
            raise NotConvergedError(f"GMRES did not converge (Newton system {len(calls)})")
        return solve_iterative(self, inactive, w, rhs)

    monkeypatch.setattr(NewtonSystems, "solve_iterative", fails)


def test_a_newton_system_gmres_cannot_solve_is_a_step_cut(monkeypatch):
    """NotConvergedError from a Newton system is handled as a singular Newton matrix: the step is cut in
    two halves and the run goes on."""
    failing(monkeypatch, lambda call: call == 5)
    result = condensed_run(CASES["2D half disc beta=1"], krylov_from=0)
    assert result.step_cuts == 1 and result.steps == 11 and len(result.rows) == 12


def test_newton_systems_gmres_never_solves_fail_the_run_with_one_line(monkeypatch):
    failing(monkeypatch, lambda call: call >= 5)
    case = vpcontact.load_case(CASES["2D half disc beta=1"], {"solver.method": "condensed"})
    loop = TimeLoop(vpcontact.build_problem(case), output_options(case.output))
    loop.solver.krylov_from = 0
    result = loop.run()
    assert result.status == "failed" and "\n" not in result.message, result.message
    assert result.message.startswith(f"step {result.steps + 1} (t = ")
    assert "failed after 4 step cuts" in result.message
    assert "the Newton system was not solved (GMRES did not converge (Newton system " in result.message
