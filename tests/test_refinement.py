"""Conforming refinement that keeps the model's data (vpcontact.mesh.refinement) and the gmsh file of a mesh
(vpcontact.mesh.gmsh)."""

import math

import numpy as np
import pytest

from vpcontact import mesh as meshes
from vpcontact.mesh.gmsh import write_mesh
from vpcontact.mesh.locate import Locator, find_columns
from vpcontact.mesh.refinement import parents, refine
from vpcontact.mesh.simplex import determinants


def facet_measures(mesh, part):
    """The length (2D) or area (3D) of each facet of a part."""
    x = mesh.mesh.p[:, mesh.mesh.facets[:, mesh.facets(part)]]  # (d, d, facets)
    if mesh.dim == 2:
        return np.linalg.norm(x[:, 1] - x[:, 0], axis=0)
    return 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], axis=0), axis=0)


def volumes(mesh, elements=None):
    t = mesh.mesh.t if elements is None else mesh.mesh.t[:, elements]
    return np.abs(determinants(mesh.mesh.p, t)) / math.factorial(mesh.dim)


def random_elements(mesh, fraction, seed=0):
    count = mesh.mesh.t.shape[1]
    return np.random.default_rng(seed).choice(count, max(1, int(fraction * count)), replace=False)


def facet_node_sets(mesh, facets):
    return {tuple(sorted(column)) for column in mesh.mesh.facets[:, facets].T}


@pytest.mark.parametrize("make", [lambda: meshes.rectangle(2.0, 1.0, 0.25), lambda: meshes.block(1.0, 0.5, 0.5, 0.25)])
def test_flat_parts_and_the_volume_are_kept_exactly(make):
    mesh = make()
    refined = mesh
    for seed in range(3):
        refined = refine(refined, random_elements(refined, 0.2, seed))
    assert refined.mesh.t.shape[1] > 2 * mesh.mesh.t.shape[1]
    assert refined.part_names == mesh.part_names
    for part in mesh.parts:
        assert facet_measures(refined, part).sum() == pytest.approx(facet_measures(mesh, part).sum(), rel=1e-13)
        assert refined.facets(part).size > mesh.facets(part).size  # its new facets are found
    boundary = np.sort(np.concatenate(list(refined.parts.values())))
    np.testing.assert_array_equal(boundary, refined.mesh.boundary_facets())  # the parts still cover the boundary
    assert volumes(refined).sum() == pytest.approx(volumes(mesh).sum(), rel=1e-13)
    assert np.all(determinants(refined.mesh.p, refined.mesh.t) != 0.0)
    assert refined.exact_normals is mesh.exact_normals


def test_refining_every_triangle_is_the_uniform_refinement():
    mesh = meshes.half_disc(0.2)
    refined = refine(mesh, np.arange(mesh.mesh.t.shape[1]))
    uniform = mesh.mesh.refined(1)
    assert refined.mesh.p.shape == uniform.p.shape
    assert refined.mesh.t.shape == uniform.t.shape
    for part in mesh.parts:
        assert refined.facets(part).size == 2 * mesh.facets(part).size


def test_refining_every_tetrahedron_bisects_each_at_least_once():
    mesh = meshes.quarter_ball(0.5)
    refined = refine(mesh, np.arange(mesh.mesh.t.shape[1]))
    assert refined.mesh.t.shape[1] >= 2 * mesh.mesh.t.shape[1]
    assert volumes(refined).max() <= 0.5 * volumes(mesh).max() * (1 + 1e-9)


def on_sphere(mesh, nodes, center, radius):
    return np.abs(np.linalg.norm(mesh.mesh.p[:, nodes] - np.reshape(center, (-1, 1)), axis=0) - radius).max()


def test_new_contact_nodes_of_the_half_disc_lie_on_the_circle_and_the_arcs_converge():
    mesh = meshes.half_disc(0.25)
    lengths, areas = [], []
    for level in range(3):
        mesh = refine(mesh, np.arange(mesh.mesh.t.shape[1]))
        assert on_sphere(mesh, mesh.nodes("bottom_arc"), (0.0, 1.0), 1.0) < 1e-15
        assert on_sphere(mesh, mesh.nodes("top_arc"), (0.0, 1.0), 1.0) < 1e-15
        assert np.all(mesh.mesh.p[0, mesh.nodes("axis")] == 0.0)
        lengths.append(facet_measures(mesh, "bottom_arc").sum())
        areas.append(volumes(mesh).sum())
    assert facet_measures(mesh, "axis").sum() == pytest.approx(2.0, rel=1e-14)
    gaps = 0.5 * np.pi - np.array(lengths)  # the inscribed polygon is shorter, less so as it is refined
    assert np.all(gaps > 0) and np.all(np.diff(gaps) < 0)
    np.testing.assert_allclose(gaps[:-1] / gaps[1:], 4.0, rtol=0.02)  # the chords' error, O(h²)
    assert np.all(np.diff(np.array(areas)) > 0) and areas[-1] < 0.5 * np.pi


def test_the_coated_half_disc_keeps_its_regions_and_its_interface_on_the_circle():
    mesh = meshes.half_disc(0.25, coating=0.3)
    refined = refine(refine(mesh, random_elements(mesh, 0.3)), np.arange(0, 40))
    total = sum(volumes(refined, elements).sum() for elements in refined.regions.values())
    assert total == pytest.approx(volumes(refined).sum(), rel=1e-13)  # each element in one region
    core, coating = (np.zeros(refined.mesh.t.shape[1], dtype=bool) for _ in range(2))
    core[refined.regions["core"]], coating[refined.regions["coating"]] = True, True
    f2t = refined.mesh.f2t
    between = (f2t[1] >= 0) & (core[f2t[0]] != core[np.maximum(f2t[1], 0)])
    interface = np.unique(refined.mesh.facets[:, between])
    assert interface.size > 2 * 13  # the coarse interface's 13 nodes and new ones
    assert on_sphere(refined, interface, (0.0, 1.0), 0.7) < 1e-15
    assert volumes(refined, refined.regions["core"]).sum() < 0.5 * np.pi * 0.7**2


def test_the_quarter_ball_keeps_its_sphere_and_its_coating_interface():
    mesh = meshes.quarter_ball(0.5, coating=0.3)
    refined = refine(mesh, np.flatnonzero(mesh.centroids[2] < 0.6))
    assert refined.part_names == mesh.part_names
    center = (0.0, 0.0, 1.0)
    for part in ("top", "bottom"):
        assert on_sphere(refined, refined.nodes(part), center, 1.0) < 1e-14
    for part, axis in (("sym_x", 0), ("sym_y", 1)):
        assert np.all(refined.mesh.p[axis, refined.nodes(part)] == 0.0)
    core = np.zeros(refined.mesh.t.shape[1], dtype=bool)
    core[refined.regions["core"]] = True
    f2t = refined.mesh.f2t
    between = (f2t[1] >= 0) & (core[f2t[0]] != core[np.maximum(f2t[1], 0)])
    assert on_sphere(refined, np.unique(refined.mesh.facets[:, between]), center, 0.7) < 1e-14
    assert refined.regions["core"].size + refined.regions["coating"].size == refined.mesh.t.shape[1]


def test_a_mesh_file_keeps_its_new_nodes_on_its_flat_facets():
    mesh = meshes.read_mesh("tests/meshes/regions.msh")
    refined = refine(mesh, [0, 1, 2])
    assert refined.part_names == mesh.part_names and sorted(refined.regions) == sorted(mesh.regions)
    for part in mesh.parts:
        assert facet_measures(refined, part).sum() == pytest.approx(facet_measures(mesh, part).sum(), rel=1e-13)
    for name, elements in mesh.regions.items():
        assert volumes(refined, refined.regions[name]).sum() == pytest.approx(volumes(mesh, elements).sum(), rel=1e-13)


def test_out_of_range_marks_are_refused():
    mesh = meshes.rectangle(1.0, 1.0, 0.5)
    with pytest.raises(ValueError, match="marked elements must be in 0 ... 7"):
        refine(mesh, [8])
    assert refine(mesh, []) is mesh


@pytest.mark.parametrize("make", [lambda: refine(meshes.half_disc(0.25, coating=0.3), [1, 2, 3]),
                                  lambda: meshes.read_mesh("tests/meshes/regions.msh"),
                                  lambda: meshes.quarter_ball(0.5, coating=0.3)])
def test_a_written_mesh_reads_back_with_its_parts_and_regions(make, tmp_path):
    mesh = make()
    write_mesh(mesh, tmp_path / "mesh.msh")
    back = meshes.read_mesh(tmp_path / "mesh.msh")
    np.testing.assert_array_equal(back.mesh.p, mesh.mesh.p)
    elements = lambda m, members: {tuple(sorted(c)) for c in m.mesh.t[:, members].T}
    assert elements(back, slice(None)) == elements(mesh, slice(None))
    for name, facets in mesh.parts.items():
        assert facet_node_sets(back, back.facets(name)) == facet_node_sets(mesh, facets)
    for name, members in mesh.regions.items():
        assert elements(back, back.regions[name]) == elements(mesh, members)


def test_a_projection_that_folds_an_element_is_refused():
    """A 'curved' bottom whose projection lifts the new nodes above the row of nodes over them."""
    import dataclasses

    from vpcontact.errors import CaseError

    mesh = meshes.rectangle(1.0, 1.0, 0.25)
    lifted = dataclasses.replace(mesh, curved_parts={"bottom": lambda x: x + np.array([[0.0], [0.4]])})
    with pytest.raises(CaseError, match=r"refining the mesh turns \d+ element\(s\) inside out near \(.*smaller mesh.h"):
        refine(lifted, np.flatnonzero(mesh.centroids[1] < 0.25))


@pytest.mark.parametrize("make", [lambda: meshes.rectangle(1.0, 1.0, 0.1), lambda: meshes.block(1.0, 1.0, 1.0, 0.3)])
def test_each_new_element_lies_in_its_parent(make):
    """`parents` (old elements kept whole found by their vertices, the pieces located among the split elements only)
    names, for every element, the old element containing its centroid (located among all of them), on a mesh graded
    by refinements of a corner and of random elements."""
    mesh = make()
    for round_ in range(4):
        old = mesh.mesh
        corner = np.flatnonzero(old.p[:, old.t].mean(axis=1).sum(axis=0) < 0.3)
        mesh = refine(mesh, np.union1d(corner, random_elements(mesh, 0.05, seed=round_)))
        expected, _ = Locator(old.p, old.t).locate(mesh.mesh.p[:, mesh.mesh.t].mean(axis=1).T)
        found = parents(old, mesh.mesh)
        assert np.array_equal(found, expected)
        whole = (mesh.mesh.t < old.p.shape[1]).all(axis=0)
        assert 0 < whole.sum() < whole.size
        assert np.array_equal(np.sort(old.t[:, found[whole]], axis=0), np.sort(mesh.mesh.t[:, whole], axis=0))


def test_find_columns_matches_sets_in_any_order_and_reports_the_missing():
    table = np.array([[0, 1, 2], [1, 2, 3], [2, 3, 4], [5, 6, 7]]).T
    query = np.array([[3, 2, 1], [7, 5, 6], [0, 1, 3], [0, 2, 1], [4, 2, 3]]).T
    assert find_columns(table, query).tolist() == [1, 3, -1, 0, 2]
    assert find_columns(table, query[:, :0]).size == 0
    assert find_columns(table[:, :0], query).tolist() == [-1] * 5
