"""The linear-solver layer: every backend solves the SPD Newton systems of the full-system methods;
PARDISO refactors on its analysed pattern; AMG-preconditioned CG converges in a number of iterations
that does not grow with the mesh, in nodal blocks, and fails with a typed error."""

import numpy as np
import pytest
import scipy.sparse as sp

import vpcontact
from vpcontact import build_problem
from vpcontact.fem.rigid_modes import RigidModes
from vpcontact.solvers import amg
from vpcontact.solvers.errors import NotConvergedError
from vpcontact.solvers.factorization import installed_backends
from vpcontact.solvers.linear import direct_solver
from vpcontact.solvers.normal_frame import NormalFrame

from pathlib import Path

QUARTER_BALL = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"


def quarter_ball_system(h: float):
    """The quarter ball's stiffness on the free dofs in the contact nodes' normal frame, with a
    compliance stiffness at every contact node (the Newton matrix of a step in compliance), and the
    AMG solver for it."""
    problem = build_problem(vpcontact.load_case(QUARTER_BALL, {"mesh.h": h}))
    free, mesh = problem.free, problem.mesh.mesh
    A, N = problem.A[free][:, free].tocsr(), problem.surface.operator[:, free].tocsr()
    frame = NormalFrame(N)
    rotated = frame.rotate(A)
    modes = RigidModes.of_mesh(mesh.p, mesh.t, problem.basis.nodal_dofs).matrix[free].toarray()
    solver = amg.AMGConjugateGradient(free, 3, mesh.p.shape[1], frame.Q @ modes)
    return frame, rotated, solver


@pytest.mark.parametrize("backend", installed_backends())
def test_a_direct_backend_refactors_the_values_of_one_pattern(backend):
    rng = np.random.default_rng(1)
    B = sp.random(60, 60, density=0.1, random_state=np.random.RandomState(1))
    pattern = sp.csr_matrix(B @ B.T + sp.eye(60))
    solver = direct_solver(backend)
    solver.analyse(pattern)
    for scale in (1.0, 3.0, 0.01):
        A = pattern.copy()
        A.data = A.data * scale + np.where(A.indices == np.repeat(np.arange(60), np.diff(A.indptr)), scale, 0.0)
        solver.factor(A)
        b = rng.normal(size=60)
        np.testing.assert_allclose(A @ solver.solve(b), b, rtol=0, atol=1e-10 * np.abs(b).max())
    assert solver.iterations == 0


def test_pardiso_refuses_to_refactor_another_pattern():
    if "pardiso" not in installed_backends():
        pytest.skip("MKL PARDISO is not installed")
    solver = direct_solver("pardiso")
    solver.analyse(sp.csr_matrix(np.diag([1.0, 2.0, 3.0])))
    with pytest.raises(ValueError, match="pattern"):
        solver.factor(sp.csr_matrix(np.array([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 1.0]])))


def test_amg_cg_iterations_do_not_grow_with_the_mesh():
    """CG to 1e-8 with the hierarchy built on the Newton matrix: about the same number of iterations
    from 1k to 24k dofs (the V-cycle's rate is mesh-independent), 40 at most; the result is the
    system's solution to that tolerance."""
    iterations = []
    for h in (0.3, 0.15, 0.1):
        frame, rotated, solver = quarter_ball_system(h)
        K = rotated + sp.diags(frame.tangent_diagonal(np.full(frame.scale.size, 50.0)))
        solver.analyse(K)
        solver.factor(K)
        b = K @ np.random.default_rng(0).normal(size=K.shape[0])
        x = solver.solve(b, rtol=1e-8)
        assert np.linalg.norm(K @ x - b) <= 1e-8 * np.linalg.norm(b)
        iterations.append(solver.iterations)
    assert max(iterations) <= 40, iterations
    assert max(iterations) - min(iterations) <= 8, iterations


def test_amg_cg_solves_with_fixed_dofs_on_the_same_hierarchy():
    """Normal dofs fixed (reduced to their diagonal) after the hierarchy was built on the matrix
    without them: solved to the tolerance in as few iterations, no new setup."""
    frame, rotated, solver = quarter_ball_system(0.15)
    diagonal = frame.tangent_diagonal(np.full(frame.scale.size, 50.0))
    K0 = rotated + sp.diags(diagonal)
    solver.analyse(K0)
    active = np.zeros(frame.scale.size, dtype=bool)
    active[::3] = True
    fixed = frame.normal_dofs(active)
    K = frame.constrained(diagonal, fixed)
    solver.factor(K)
    b = np.random.default_rng(2).normal(size=K.shape[0])
    x = solver.solve(b, rtol=1e-10)
    np.testing.assert_allclose(x[fixed], b[fixed] / K.diagonal()[fixed], rtol=1e-9)
    assert np.linalg.norm(K @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert solver.setups == 1 and solver.iterations <= 40


def test_amg_cg_that_does_not_converge_raises_a_typed_error(monkeypatch):
    frame, rotated, solver = quarter_ball_system(0.3)
    monkeypatch.setattr(amg, "MAX_ITERATIONS", 2)
    solver.analyse(rotated)
    solver.factor(rotated)
    with pytest.raises(NotConvergedError, match=r"relative residual of .* in 2 iterations"):
        solver.solve(np.ones(rotated.shape[0]), rtol=1e-12)
