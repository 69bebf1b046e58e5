"""The contact nodes' normal frame: the full Newton system as an SPD system with fixed dofs gives the
saddle-point system's solution, for every active set, on one sparsity pattern."""

import numpy as np
import pytest
import scipy.sparse as sp

from vpcontact.solvers.normal_frame import NormalFrame


def contact_operator(rng, nodes: int, dim: int, contact: list[int], clamped: dict[int, list[int]]):
    """N (contact nodes × free dofs): a random unit normal per contact node on its free components."""
    free = np.ones(dim * nodes, dtype=bool)
    for node, components in clamped.items():
        free[[dim * node + c for c in components]] = False
    index = -np.ones(dim * nodes, dtype=int)
    index[free] = np.arange(free.sum())
    rows, cols, values = [], [], []
    for row, node in enumerate(contact):
        normal = rng.normal(size=dim)
        normal /= np.linalg.norm(normal)
        for c in range(dim):
            if free[dim * node + c]:
                rows.append(row), cols.append(index[dim * node + c]), values.append(normal[c])
    return sp.csr_matrix((values, (rows, cols)), shape=(len(contact), free.sum()))


def spd_matrix(rng, n: int) -> sp.csr_matrix:
    """A sparse SPD matrix with a nodal-block pattern (a banded random one, diagonally dominant)."""
    B = sp.random(n, n, density=0.2, random_state=np.random.RandomState(rng.integers(1 << 31)))
    A = B @ B.T + sp.diags(np.full(n, 5.0))
    return sp.csr_matrix(A)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_rotation_is_orthogonal_and_takes_each_normal_onto_one_dof(dim):
    rng = np.random.default_rng(dim)
    N = contact_operator(rng, 8, dim, [0, 2, 3, 6, 7], {3: [0], 7: list(range(dim))})
    frame = NormalFrame(N)
    Q = frame.Q.toarray()
    np.testing.assert_allclose(Q @ Q, np.eye(Q.shape[0]), atol=1e-15)
    np.testing.assert_array_equal(Q, Q.T)
    E = np.zeros(N.shape)
    E[np.flatnonzero(frame.has_normal), frame.normal_dof[frame.has_normal]] = 1.0
    np.testing.assert_allclose(N.toarray() @ Q, frame.scale[:, None] * E, atol=1e-15)
    # a partly clamped node keeps the length of its free normal; a node clamped along every
    # component has none
    lengths = np.sqrt(np.asarray(N.multiply(N).sum(axis=1)).ravel())
    np.testing.assert_allclose(np.abs(frame.scale), np.where(frame.has_normal, lengths, 0.0), rtol=1e-15)
    assert frame.has_normal.tolist() == [True, True, True, True, False]


@pytest.mark.parametrize("dim", [2, 3])
def test_the_constrained_spd_system_solves_the_saddle_point_system(dim):
    rng = np.random.default_rng(10 + dim)
    nodes, contact = 10, [1, 2, 4, 5, 8, 9]
    N = contact_operator(rng, nodes, dim, contact, {2: [1]})
    n, m = N.shape[1], N.shape[0]
    A = spd_matrix(rng, n)
    frame = NormalFrame(N)
    rotated = frame.rotate(A)
    pattern = None
    for active in ([True, False, True, False, False, True], [False] * m, [True] * m):
        active = np.array(active)
        T = rng.uniform(0.0, 3.0, m)
        r_u, c = rng.normal(size=n), rng.normal(size=active.sum())
        # the saddle-point system, dense
        J = A.toarray() + N.T.toarray() @ np.diag(T) @ N.toarray()
        Na = N.toarray()[active]
        kkt = np.block([[J, Na.T], [Na, np.zeros((len(c), len(c)))]])
        expected = np.linalg.solve(kkt, np.concatenate([r_u, c]))
        # the SPD system in the normal frame
        fixed = frame.normal_dofs(active)
        diagonal = frame.tangent_diagonal(T)
        K = frame.constrained(diagonal, fixed)
        held = np.zeros(n)
        held[frame.normal_dof[active]] = c / frame.scale[active]
        rhs = frame.Q @ r_u
        system_rhs = np.where(fixed, K.diagonal() * held, rhs - (rotated @ held + diagonal * held))
        rotated_step = np.linalg.solve(K.toarray(), system_rhs)
        assert np.all(np.linalg.eigvalsh(K.toarray()) > 0)
        np.testing.assert_allclose(frame.Q @ rotated_step, expected[:n], rtol=1e-10, atol=1e-12)
        multipliers = (rhs - rotated @ rotated_step - diagonal * rotated_step)[frame.normal_dof[active]]
        np.testing.assert_allclose(multipliers / frame.scale[active], expected[n:], rtol=1e-10, atol=1e-12)
        # one stored pattern for every active set
        if pattern is None:
            pattern = (K.indptr.copy(), K.indices.copy())
        np.testing.assert_array_equal(K.indptr, pattern[0])
        np.testing.assert_array_equal(K.indices, pattern[1])


def test_rows_sharing_a_dof_are_refused():
    N = sp.csr_matrix(np.array([[1.0, 0.0, 0.0], [0.6, 0.8, 0.0]]))
    with pytest.raises(ValueError, match="share a dof"):
        NormalFrame(N)
