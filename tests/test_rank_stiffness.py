"""One MPI rank's rows of the stiffness (``fem.assembly.stiffness`` with ``nodes``): assembled from the elements that
touch the rank's nodes alone, they are the whole matrix's rows, and the ranks' rows add up to the whole matrix. In
one process, with the nodes shared among three made-up ranks (bands of x, as METIS's parts are contiguous, and a
random sharing, where nearly every element touches two or three ranks)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from vpcontact import mesh as meshes
from vpcontact.fem.assembly import displacement_space, rows_of, stiffness
from vpcontact.laws.elasticity import Elasticity

MESHES = {"2d": lambda: meshes.half_disc(0.08), "3d": lambda: meshes.quarter_ball(0.25)}


def owners(mesh, sharing: str) -> np.ndarray:
    """The rank (0, 1 or 2) of every node: bands of x, or at random."""
    x = mesh.mesh.p[0]
    if sharing == "bands":
        return np.digitize(x, np.quantile(x, [1 / 3, 2 / 3]))
    return np.random.default_rng(7).integers(0, 3, x.size)


@pytest.mark.parametrize("sharing", ["bands", "random"])
@pytest.mark.parametrize("shape", MESHES)
def test_each_ranks_rows_are_the_whole_stiffness_rows(shape, sharing):
    mesh = MESHES[shape]()
    space = displacement_space(mesh)
    centroids = mesh.mesh.p[:, mesh.mesh.t].mean(axis=1)
    elasticity = Elasticity(1000.0 * (1.0 + centroids[1]), 0.3, "plane_strain" if shape == "2d" else None)
    whole = stiffness(space, elasticity)
    owner = owners(mesh, sharing)
    scale = abs(whole).max()
    total = sp.csr_matrix(whole.shape)
    for rank in range(3):
        mine = stiffness(space, elasticity, owner == rank)
        rows = np.zeros(space.N, dtype=bool)
        rows[space.nodal_dofs[:, owner == rank]] = True
        assert mine.shape == whole.shape and mine[~rows].nnz == 0
        assert abs(mine[rows] - whole[rows]).max() <= 1e-14 * scale
        total = total + mine
    assert abs(total - whole).max() <= 1e-14 * scale


def test_rows_of_keeps_the_masked_rows_and_the_shape():
    matrix = sp.random(7, 5, density=0.6, random_state=3, format="csr")
    rows = np.array([True, False, True, True, False, False, True])
    kept = rows_of(matrix, rows)
    assert kept.shape == (7, 5)
    np.testing.assert_array_equal(kept.toarray(), np.where(rows[:, None], matrix.toarray(), 0.0))
