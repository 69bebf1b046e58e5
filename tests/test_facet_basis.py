"""The FacetBasis of boundary facets made on the elements next to them (fem/facet_basis.py) is scikit-fem's
FacetBasis on the whole mesh, value for value, and building the loads and the contact surface leaves the mesh
unmapped (scikit-fem's mapping of every element and facet is never made)."""

import numpy as np
import pytest
from skfem import ElementTetP1, ElementTriP1, FacetBasis

from vpcontact.fem.assembly import LoadVector, displacement_space
from vpcontact.fem.contact_surface import contact_surface
from vpcontact.fem.facet_basis import facet_basis
from vpcontact.mesh import half_disc, quarter_ball


@pytest.mark.parametrize("make, part, element", [(lambda: quarter_ball(0.2, coating=0.3), "bottom", ElementTetP1()),
                                                 (lambda: half_disc(0.1), "top_arc", ElementTriP1())])
@pytest.mark.parametrize("intorder", [1, 4])
def test_the_facet_basis_is_scikit_fems_on_the_whole_mesh(make, part, element, intorder):
    mesh = make()
    facets = mesh.facets(part)
    near, nodes = facet_basis(mesh.mesh, facets, element, intorder)
    whole = FacetBasis(mesh.mesh, element, facets=facets, intorder=intorder)
    assert near.mesh.t.shape[1] < mesh.mesh.t.shape[1] / 3
    for ours, theirs in [(near.dx, whole.dx), (near.normals, whole.normals),
                         (near.global_coordinates(), whole.global_coordinates()),
                         (nodes[near.element_dofs], whole.element_dofs)]:
        assert np.array_equal(np.asarray(ours), np.asarray(theirs))
    for i in range(near.Nbfun):
        assert np.array_equal(np.asarray(near.basis[i][0]), np.asarray(whole.basis[i][0]))


def test_the_loads_and_the_contact_surface_do_not_map_the_whole_mesh():
    mesh = quarter_ball(0.2)
    space = displacement_space(mesh)
    loads = LoadVector(space, mesh, [("traction", "top", lambda x, y, z, t: (0 * x, 0 * y, -t + 0 * z))], [])
    surface = contact_surface(mesh, ["bottom"], space.nodal_dofs)
    assert "_cached_mapping" not in vars(mesh.mesh)
    top = np.unique(space.nodal_dofs[2, mesh.nodes("top")])
    assert loads(1.0)[top].sum() == pytest.approx(-areas(mesh, "top").sum(), rel=1e-12)  # Σ_i ∫ f φ_i = ∫ f
    assert surface.weights.sum() == pytest.approx(areas(mesh, "bottom").sum(), rel=1e-12)


def areas(mesh, part):
    """The areas of the triangles of a part, |(p1 − p0) × (p2 − p0)| / 2."""
    p0, p1, p2 = (mesh.mesh.p[:, mesh.mesh.facets[k, mesh.facets(part)]] for k in range(3))
    return 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0, axis=0), axis=0)
