"""The facet tables vpcontact builds (mesh/facets.py) are scikit-fem's own: the same facets in the same order, the
same element → facet and facet → element tables, the same dtypes, on triangles and tetrahedra in any node order."""

import numpy as np
import pytest
import skfem

from vpcontact import mesh as meshes
from vpcontact.mesh.facets import facet_tables, with_facet_tables


def skfem_tables(m):
    """The tables scikit-fem builds itself, on a fresh copy of ``m`` (its own np.unique over node triples)."""
    fresh = type(m)(m.p, m.t)
    return fresh.facets, fresh.t2f, fresh.f2t


def shuffled(m, seed=0):
    """``m`` with its elements in another order and each element's nodes in another order."""
    rng = np.random.default_rng(seed)
    t = rng.permuted(m.t[:, rng.permutation(m.t.shape[1])], axis=0)
    return type(m)(m.p, np.ascontiguousarray(t))


@pytest.mark.parametrize("make", [lambda: meshes.quarter_ball(0.25).mesh, lambda: meshes.half_disc(0.15).mesh,
                                  lambda: shuffled(meshes.quarter_ball(0.3).mesh),
                                  lambda: shuffled(meshes.rectangle(1.0, 0.5, 0.1).mesh),
                                  lambda: meshes.quarter_ball(0.3, coating=0.3).mesh])
def test_facet_tables_are_scikit_fems(make):
    m = make()
    ours = facet_tables(m.t, m.elem.refdom.facets, m.p.shape[1])
    for built, expected in zip(ours, skfem_tables(m)):
        assert built.dtype == expected.dtype
        assert np.array_equal(built, expected)


def test_a_mesh_made_here_has_them_built_once():
    """A built-in shape's scikit-fem mesh holds the tables before scikit-fem would build them; a mesh that has them
    keeps them (the same arrays)."""
    m = meshes.quarter_ball(0.3).mesh
    assert "_facets" in vars(m) and "_f2t" in vars(m)
    facets = m.facets
    assert with_facet_tables(m).facets is facets
    fresh = skfem.MeshTet1(m.p, m.t)
    assert "_facets" not in vars(fresh)
    assert np.array_equal(with_facet_tables(fresh).boundary_facets(), m.boundary_facets())
