"""The facet tables vpcontact builds (mesh/facets.py) are scikit-fem's own: the same facets in the same order, the
same element → facet and facet → element tables, the same dtypes, on triangles and tetrahedra in any node order."""

import numpy as np
import pytest
import skfem

from vpcontact import mesh as meshes
from vpcontact.mesh.facets import facet_tables, refinable, with_facet_tables


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


@pytest.mark.parametrize("make", [lambda: meshes.rectangle(1.0, 0.5, 0.1).mesh, lambda: meshes.quarter_ball(0.3).mesh])
def test_a_refinable_mesh_refines_as_scikit_fem_does_and_builds_its_tables_here(make, monkeypatch):
    """scikit-fem's refinement of a `refinable` mesh gives the same nodes and elements (a graded mesh: random elements
    refined three times over), and scikit-fem builds no facet table of its own on the way (it did without)."""
    own = []
    build_entities = skfem.Mesh.build_entities
    monkeypatch.setattr(skfem.Mesh, "build_entities", staticmethod(lambda *args: own.append(1) or build_entities(*args)))
    m = make()
    for seed in range(3):
        marked = np.random.default_rng(seed).choice(m.t.shape[1], m.t.shape[1] // 8, replace=False)
        before = len(own)
        keyed = refinable(m).refined(marked)
        assert len(own) == before
        plain = type(m)(m.p, m.t).refined(marked)
        assert np.array_equal(plain.p, keyed.p) and np.array_equal(plain.t, keyed.t)
        assert len(own) > before or m.dim() == 3  # scikit-fem's bisection of tetrahedra uses no facet table
        m = plain
    for table, expected in zip(facet_tables(keyed.t, keyed.elem.refdom.facets, keyed.p.shape[1]), skfem_tables(plain)):
        assert np.array_equal(table, expected)
