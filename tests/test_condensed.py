"""The condensed solver's own promises: no solve that is not needed, and a clear refusal when its
dense contact operator would not fit in memory."""

import numpy as np
import pytest
import scipy.sparse as sp
import tomli_w

import vpcontact
from vpcontact.cli import main
from vpcontact.solvers import condensed
from vpcontact.solvers.solved_span import SolvedSpan
from conftest import half_disc_case


def test_solved_span_reuses_solutions_of_combinations():
    """N A0⁻¹ b of right-hand sides in the span of those solved: the same as a solve, and no solve."""
    rng = np.random.default_rng(0)
    A = sp.random(40, 40, density=0.2, random_state=1) + 40 * sp.eye(40)
    lu = sp.linalg.splu(A.tocsc())
    N = sp.random(5, 40, density=0.3, random_state=2).tocsr()
    span = SolvedSpan(lu.solve, N.__matmul__, N.shape)
    a, b = rng.standard_normal(40), rng.standard_normal(40)
    np.testing.assert_array_equal(span(np.zeros(40)), np.zeros(5))
    for t in (0.1, 0.2, 0.7, 3.0):
        np.testing.assert_allclose(span(a + t * b), N @ lu.solve(a + t * b), rtol=1e-12, atol=1e-12)
    assert span.solves == 2  # a + 0.1 b and a + 0.2 b span every later right-hand side
    span(rng.standard_normal(40))
    assert span.solves == 3


def test_solved_span_on_a_support_projects_there_only_and_falls_back_off_it():
    """Right-hand sides that vanish off a support: the same N A0⁻¹ b as a solve, no solve for their
    combinations; one that does not vanish there (given without the support) is solved."""
    rng = np.random.default_rng(1)
    A = sp.random(40, 40, density=0.2, random_state=3) + 40 * sp.eye(40)
    lu = sp.linalg.splu(A.tocsc())
    N = sp.random(5, 40, density=0.3, random_state=4).tocsr()
    support = np.array([2, 7, 11, 30])
    a, b = np.zeros(40), np.zeros(40)
    a[support], b[support] = rng.standard_normal(4), rng.standard_normal(4)
    span = SolvedSpan(lu.solve, N.__matmul__, N.shape)
    for t in (0.1, 0.2, 0.7, 3.0):
        np.testing.assert_allclose(span(a + t * b, support), N @ lu.solve(a + t * b), rtol=1e-12, atol=1e-12)
    assert span.solves == 2
    c = a + rng.standard_normal(40)
    np.testing.assert_allclose(span(c), N @ lu.solve(c), rtol=1e-12, atol=1e-12)
    assert span.solves == 3


@pytest.mark.parametrize("size", [1e-200, 1e200, 1e300])
def test_solved_span_of_right_hand_sides_whose_squares_overflow_or_underflow(size):
    """Entries beyond 1e154 overflow the sum of squares of a norm, entries below 1e-154 underflow it: b is
    still solved (once), not taken as lying in the empty span (inf ≤ inf, or a norm of 0), and its
    multiples reuse it."""
    rng = np.random.default_rng(2)
    A = sp.random(30, 30, density=0.2, random_state=5) + 30 * sp.eye(30)
    lu = sp.linalg.splu(A.tocsc())
    N = sp.random(4, 30, density=0.3, random_state=6).tocsr()
    span = SolvedSpan(lu.solve, N.__matmul__, N.shape)
    b = size * rng.standard_normal(30)
    for t in (1.0, 0.5, 0.25):
        expected = N @ lu.solve(t * b)
        np.testing.assert_allclose(span(t * b), expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    assert span.solves == 1


def test_the_norm_of_the_solvers_does_not_overflow():
    from vpcontact.solvers.base import norm

    assert norm(np.array([3e200, -4e200])) == pytest.approx(5e200, rel=1e-15)
    assert norm(np.array([3e-200, 4e-200])) == pytest.approx(5e-200, rel=1e-15)
    assert norm(np.array([3.0, 4.0])) == 5.0 and norm(np.zeros(3)) == 0.0
    assert norm(np.array([np.inf, 1.0])) == np.inf and np.isnan(norm(np.array([np.nan, 1e200])))


def test_loads_linear_in_time_cost_one_solve_plus_the_recovered_steps():
    case = half_disc_case(h=0.1, load=20.0)
    case["output"]["field_steps"] = [4, 11]
    result = vpcontact.solve(case)
    assert result.method == "condensed" and result.steps == 11
    assert result.linear_solves == 1 + 2  # d_free of step 1 (then combinations), u at steps 4 and 11


def test_condensed_refuses_an_operator_that_does_not_fit(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(condensed, "available_memory", lambda: 10_000)
    case = half_disc_case(h=0.2)
    case["solver"]["method"] = "condensed"
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert 'solver.method = "iterative"' in err and "GiB" in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()
    case["solver"]["method"] = "auto"  # the default falls back to the fastest of the others (here the full one)
    assert vpcontact.solve(case).method == "full"


@pytest.mark.parametrize("backend", __import__("vpcontact.solvers.factorization", fromlist=["x"]).installed_backends())
def test_every_backend_solves_and_condenses_exactly(backend, monkeypatch):
    """A0 x = b and S = N A0⁻¹ Nᵀ against dense linear algebra, on the half-disc stiffness; PARDISO
    also after it swaps its Schur-mode factor for a plain one."""
    from vpcontact.solvers import factorization

    monkeypatch.setattr(factorization.PardisoFactorization, "PLAIN_AFTER", 2)
    problem = vpcontact.build_problem(vpcontact.load_case(half_disc_case(h=0.2)))
    free = problem.free
    N = problem.surface.operator[:, free].tocsr()
    A0 = (problem.A[free][:, free] + 1e3 * N.T @ N).tocsc()
    solver = factorization.factorize(A0, N, backend)
    dense = np.linalg.inv(A0.toarray())
    np.testing.assert_allclose(solver.condensed_operator(), N @ dense @ N.T.toarray(), rtol=1e-10, atol=1e-14)
    rng = np.random.default_rng(1)
    for _ in range(4):
        b = rng.standard_normal(free.size)
        np.testing.assert_allclose(solver.solve(b), dense @ b, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("backend", __import__("vpcontact.solvers.factorization", fromlist=["x"]).installed_backends())
def test_the_factor_size_is_counted(backend):
    """factor_nonzeros (reported by the scaling benchmarks) for a diagonal and a dense matrix: SuperLU
    counts L and U exactly (n and n(n + 1) each); PARDISO reports the entries of its supernodal storage
    (iparm[17]), at least the Cholesky factor's n and n(n + 1)/2 and at most a full square."""
    from vpcontact.solvers import factorization

    n, no_contact = 30, sp.csr_matrix((0, 30))
    diagonal = sp.diags(np.arange(1.0, n + 1)).tocsc()
    B = np.random.default_rng(2).standard_normal((n, n))
    dense = sp.csc_matrix(B @ B.T + n * np.eye(n))
    counts = [factorization.factorize(A, no_contact, backend).factor_nonzeros for A in (diagonal, dense)]
    if backend == "superlu":
        assert counts == [2 * n, n * (n + 1)]
    else:
        assert n <= counts[0] <= n + 1 and n * (n + 1) // 2 <= counts[1] <= n * n + 1


@pytest.mark.skipif("pardiso" not in __import__("vpcontact.solvers.factorization", fromlist=["x"]).installed_backends(),
                    reason="MKL PARDISO is not installed")
def test_a_factor_that_would_not_fit_is_refused_before_it_is_made(tmp_path, capsys, monkeypatch):
    """PARDISO's symbolic analysis estimates the factor's memory; over what is available the run is
    refused (one line, exit 2, nothing written) instead of being killed for lack of memory."""
    from vpcontact.solvers import pardiso

    monkeypatch.setattr(pardiso, "available_memory", lambda: 2**20)
    case = half_disc_case(h=0.2)
    case["solver"].update(method="condensed", factorization="pardiso")
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "not enough memory to factor the stiffness matrix" in err and "MKL PARDISO needs about" in err
    assert "0.0 GiB are available" in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()
