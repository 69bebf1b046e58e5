"""The condensed method's algebra at the sizes users bring: the Schur complement on one dof a contact node (the
nonzero columns of N on a flat face, the normal frame on a curved one), and the Newton preconditioner kept as LU
factors with low-rank corrections instead of a formed inverse."""

import numpy as np
import pytest

from vpcontact.solvers import factorization
from vpcontact.solvers.condensed import condensed_memory
from vpcontact.solvers.updated_factor import UpdatedFactor
from test_3d import ball_case
from test_split_solve import operators

BACKENDS = factorization.installed_backends()


def block_case(h: float = 0.25) -> dict:
    """A block on its flat bottom face (normals (0, 0, −1): one nonzero a row of N, two stored zeros)."""
    return {"mesh": {"shape": "block", "width": 1.0, "depth": 1.0, "height": 0.5, "h": h},
            "material": {"E": 1000.0, "nu": 0.3},
            "boundary": {"dirichlet": [{"part": "top", "components": ["x", "y"]}],
                         "traction": [{"part": "top", "value": ["0", "0", "-20*t"]}]},
            "contact": {"part": "bottom", "g": 0.1, "normal": [0, 0, -1],
                        "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
            "time": {"T": 1.0, "steps": 4}}


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("case, rotated", [(block_case(), False), (ball_case(h=0.5), True)], ids=["flat", "curved"])
def test_the_condensation_is_on_one_dof_a_contact_node_and_gives_the_dense_s(backend, case, rotated):
    """S = N A0⁻¹ Nᵀ against dense linear algebra to 1e-10, from a Schur complement on m dofs: N's nonzero
    columns on the flat face (it stores 3 entries a row), the normal dofs of Q A0 Q on the curved ball (its rows
    have 3 nonzeros each); the solves, split solves and the condensed method's memory likewise."""
    A0, N = operators(case)
    m = N.shape[0]
    assert N.nnz > m  # more than one entry stored a row: the flat face's zeros, the ball's normal components
    assert (factorization.contact_dofs(N).size > m) == rotated == factorization.rotates(N)
    assert factorization.condensation_dofs(N) == m
    dense = np.linalg.inv(A0.toarray())
    solver = factorization.factorize_on_normals(A0, N, backend)
    assert isinstance(solver, factorization.RotatedFactorization) == rotated
    S = solver.condensed_operator()
    expected = N @ dense @ N.T
    assert np.abs(S - expected).max() <= 1e-10 * np.abs(expected).max()
    b = np.random.default_rng(5).standard_normal(A0.shape[0])
    q = np.random.default_rng(6).standard_normal(m)
    np.testing.assert_allclose(solver.solve(b), dense @ b, rtol=0, atol=1e-10 * np.abs(dense @ b).max())
    split = solver.split(b)
    np.testing.assert_allclose(split.observed, N @ dense @ b, rtol=0, atol=1e-10 * np.abs(N @ dense @ b).max())
    finished = dense @ (b - N.T @ q)
    np.testing.assert_allclose(split.finish(q), finished, rtol=0, atol=1e-10 * np.abs(finished).max())
    c = m  # the Schur complement's size counted by the memory guard: m, not the 3m stored columns
    assert condensed_memory(N, A0.shape[0]) == 8 * (2 * c * c + 3 * m * m + 2 * 64 * A0.shape[0])


def test_the_updated_factor_inverts_each_matrix_its_columns_changed_to():
    """K₀ factored once, then 3 rounds of changed columns (9 in all, one column changed twice): apply() is K⁻¹ of the
    current K to 1e-12 (against numpy's solve), for one vector and for a block, the rank of the correction is the
    columns changed, and a factor restored from its arrays gives the same bits."""
    rng = np.random.default_rng(11)
    m = 60
    K = rng.standard_normal((m, m)) + 2 * np.sqrt(m) * np.eye(m)
    factor = UpdatedFactor(np.array(K, order="F"))
    for changed in ([3], [10, 11, 40, 59], [3, 20, 21, 30]):
        changed = np.array(changed)
        U = rng.standard_normal((m, changed.size))
        assert factor.update(U, changed)
        K[:, changed] += U
        r, R = rng.standard_normal(m), rng.standard_normal((m, 5))
        np.testing.assert_allclose(factor.apply(r), np.linalg.solve(K, r), rtol=0, atol=1e-12)
        np.testing.assert_allclose(factor.apply(R), np.linalg.solve(K, R), rtol=0, atol=1e-12)
    assert factor.rank == 9
    restored = UpdatedFactor.restored(**factor.arrays())
    r = rng.standard_normal(m)
    assert np.array_equal(restored.apply(r), factor.apply(r))


def test_a_change_that_makes_k_singular_is_refused_and_changes_nothing():
    """A column changed to a copy of another: the capacitance matrix is singular, update() says so and the factor
    still inverts the K it had."""
    rng = np.random.default_rng(12)
    m = 20
    K = rng.standard_normal((m, m)) + 2 * np.sqrt(m) * np.eye(m)
    factor = UpdatedFactor(np.array(K, order="F"))
    U = (K[:, 4] - K[:, 7])[:, None]  # column 7 becomes column 4
    assert not factor.update(U, np.array([7]))
    assert factor.rank == 0
    r = rng.standard_normal(m)
    np.testing.assert_allclose(factor.apply(r), np.linalg.solve(K, r), rtol=0, atol=1e-12)
