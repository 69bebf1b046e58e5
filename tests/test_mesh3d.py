"""Tests of the 3D meshes of vpcontact.mesh: quarter_ball, block, read_mesh on tetrahedral gmsh files.

The gmsh files in tests/meshes/3d are real gmsh output (tests/meshes/make_meshes_3d.py; a few are
gmsh's cube with one hand edit, as other programs write them). Refusals are checked at the level of
`read_mesh`: one CaseError line naming the file, the problem and the fix.
"""

import itertools
import logging
import math
from pathlib import Path

import meshio
import numpy as np
import pytest
import skfem

import vpcontact.mesh
from vpcontact.mesh import ball
from vpcontact.errors import CaseError
from vpcontact.mesh import Mesh, block, quarter_ball, read_mesh
from vpcontact.mesh.checks_3d import check_tetrahedra

MESHES = Path(__file__).parent / "meshes" / "3d"
BALLS = [(0.25, 1.0), (0.3, 2.5), (0.37 / 9, 0.37)]


# --- helpers -------------------------------------------------------------------------------------
@pytest.fixture(scope="module", params=BALLS, ids=lambda c: f"h={c[0]:.4g},R={c[1]}")
def qball(request):
    h, R = request.param
    return h, R, quarter_ball(h, R)


@pytest.fixture(scope="module")
def graded():
    """h = 0.3, h_bottom = 0.05 on the ball of radius 2 (h/R = 0.15, h_bottom/R = 0.025)."""
    return quarter_ball(0.3, 2.0, 0.05)


def volumes(p, t):
    a = p[:, t[0]]
    return np.einsum("ij,ij->j", np.cross(p[:, t[1]] - a, p[:, t[2]] - a, axis=0), p[:, t[3]] - a) / 6.0


def edges(p, t):
    """(6, m) edge lengths of the tetrahedra."""
    return np.array([np.linalg.norm(p[:, t[i]] - p[:, t[j]], axis=0) for i, j in itertools.combinations(range(4), 2)])


def dihedral_angles(p, t):
    """(6, m) dihedral angles in degrees (at the edge shared by faces i and j, opposite nodes i and j)."""
    normals = []
    for opposite in range(4):
        a, b, c = (p[:, t[k]] for k in range(4) if k != opposite)
        n = np.cross(b - a, c - a, axis=0)
        n *= np.sign(((p[:, t[opposite]] - a) * n).sum(axis=0))  # towards the opposite node: inward
        normals.append(n / np.linalg.norm(n, axis=0))
    return np.array([180.0 - np.degrees(np.arccos(np.clip((normals[i] * normals[j]).sum(axis=0), -1.0, 1.0)))
                     for i, j in itertools.combinations(range(4), 2)])


def boundary_faces(t):
    """Sorted node triples (k, 3) of the faces of exactly one tetrahedron."""
    faces = np.sort(np.hstack([t[[i for i in range(4) if i != k]] for k in range(4)]), axis=0).T
    unique, count = np.unique(faces, axis=0, return_counts=True)
    return unique[count == 1]


def face_set(mesh: Mesh, part):
    """The part's facets as a set of node-coordinate triples, order-free."""
    p = mesh.mesh.p
    return {frozenset(map(tuple, p[:, f].T)) for f in mesh.mesh.facets[:, mesh.facets(part)].T}


def tetra_set(mesh: Mesh):
    p = mesh.mesh.p
    return {frozenset(map(tuple, p[:, tet].T)) for tet in mesh.mesh.t.T}


def area(mesh: Mesh, part) -> float:
    basis = skfem.FacetBasis(mesh.mesh, skfem.ElementTetP1(), facets=mesh.facets(part))
    return skfem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).assemble(basis)


def volume(mesh: Mesh) -> float:
    return skfem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).assemble(skfem.Basis(mesh.mesh, skfem.ElementTetP1()))


def check(mesh: Mesh):
    """The mesh checks of a file, on a built mesh."""
    check_tetrahedra("built", mesh.mesh.p, mesh.mesh.t, np.arange(mesh.mesh.p.shape[1]) + 1)


# --- quarter_ball --------------------------------------------------------------------------------
def test_quarter_ball_counts_and_sizes(qball):
    h, R, m = qball
    n = math.ceil(1.5 * R / h)
    assert m.dim == 3 and isinstance(m.mesh, skfem.MeshTet1)
    assert m.mesh.t.shape == (4, 12 * n**3)
    assert m.mesh.p.shape == (3, (n + 1) ** 2 * (2 * n + 1))
    e = edges(m.mesh.p, m.mesh.t)
    assert m.h == pytest.approx(e.max(), rel=1e-15)
    assert 0.9 * h <= m.h <= h
    assert m.diameter == pytest.approx(math.sqrt(6) * R, rel=1e-14)  # the box [0, R]² × [0, 2R]
    assert np.all(volumes(m.mesh.p, m.mesh.t) > 0)
    check(m)


def test_quarter_ball_quality(qball):
    h, R, m = qball
    angles = dihedral_angles(m.mesh.p, m.mesh.t)
    assert angles.min() >= 29.0 and angles.max() <= 115.0
    assert np.median(angles.min(axis=0)) >= 44.0
    # longest edge over the inscribed sphere's diameter, √6 times that of a regular tetrahedron
    v = volumes(m.mesh.p, m.mesh.t)
    p, t = m.mesh.p, m.mesh.t
    surface = sum(0.5 * np.linalg.norm(np.cross(p[:, t[b]] - p[:, t[a]], p[:, t[c]] - p[:, t[a]], axis=0), axis=0)
                  for a, b, c in itertools.combinations(range(4), 3))
    aspect = edges(p, t).max(axis=0) / (2.0 * math.sqrt(6) * 3.0 * v / surface)
    assert aspect.max() <= 2.0


def test_quarter_ball_parts_partition_the_boundary(qball):
    h, R, m = qball
    assert m.part_names == ["bottom", "sym_x", "sym_y", "top"]
    found = boundary_faces(m.mesh.t)
    by_part = np.hstack([m.mesh.facets[:, m.facets(name)] for name in m.part_names])
    assert by_part.shape[1] == len(found)
    np.testing.assert_array_equal(np.unique(np.sort(by_part, axis=0).T, axis=0), found)
    for name, facets in m.parts.items():
        assert facets.dtype == np.int64 and np.all(np.diff(facets) > 0), name
    np.testing.assert_array_equal(m.mesh.boundaries["top"], m.facets("top"))


def test_quarter_ball_boundary_geometry(qball):
    h, R, m = qball
    p = m.mesh.p
    centre = np.array([[0.0], [0.0], [R]])
    for name in ("top", "bottom"):
        nodes = m.nodes(name)
        assert np.abs(np.linalg.norm(p[:, nodes] - centre, axis=0) - R).max() <= 4e-16 * R
    assert np.all(p[2, m.nodes("top")] >= R) and np.all(p[2, m.nodes("bottom")] <= R)
    assert np.all(p[0, m.nodes("sym_x")] == 0.0) and np.all(p[1, m.nodes("sym_y")] == 0.0)
    inside = np.linalg.norm(p - centre, axis=0)
    assert inside.max() <= R * (1 + 4e-16) and p[:2].min() == 0.0
    for corner in [(0, 0, 0), (0, 0, 2 * R), (R, 0, R), (0, R, R), (0, 0, R)]:
        assert np.any(np.all(p.T == corner, axis=1)), corner
    # the facet centroids of the spherical parts are on their side of z = R
    for name, side in (("top", 1), ("bottom", -1)):
        centroid = p[:, m.mesh.facets[:, m.facets(name)]].mean(axis=1)
        assert np.all(side * (centroid[2] - R) > 0)


def test_quarter_ball_volume_and_areas_converge():
    """Volume πR³/3, the half discs πR²/2 on the symmetry planes and the sphere's quarter πR² (half of
    it on top), all approached from below at second order in h."""
    R = 1.5
    errors = []
    for h in (0.6, 0.3, 0.15):
        m = quarter_ball(h, R)
        assert np.abs(volumes(m.mesh.p, m.mesh.t)).sum() == pytest.approx(volume(m), rel=1e-12)
        exact = {"volume": math.pi * R**3 / 3, "sym_x": math.pi * R**2 / 2, "sym_y": math.pi * R**2 / 2,
                 "top": math.pi * R**2 / 2, "bottom": math.pi * R**2 / 2}
        found = {"volume": volume(m)} | {name: area(m, name) for name in m.part_names}
        relative = {key: (exact[key] - found[key]) / exact[key] for key in exact}
        assert all(0 < error < 0.7 * (h / R) ** 2 for error in relative.values()), relative
        assert relative["top"] == pytest.approx(relative["bottom"], rel=1e-12)
        errors.append(relative)
    for coarse, fine in zip(errors, errors[1:]):
        for key in coarse:
            assert 3.0 < coarse[key] / fine[key] < 4.5, (key, coarse[key] / fine[key])


def test_quarter_ball_exact_normals(qball):
    h, R, m = qball
    centre = np.array([[0.0], [0.0], [R]])
    for name in m.part_names:
        basis = skfem.FacetBasis(m.mesh, skfem.ElementTetP1(), facets=m.facets(name))
        x = np.asarray(basis.global_coordinates())  # (3, facets, points)
        n = m.exact_normals[name](x)
        assert n.shape == x.shape
        np.testing.assert_allclose(np.linalg.norm(n, axis=0), 1.0, rtol=1e-14)
        facet_normals = np.asarray(basis.normals)
        angle = np.arccos(np.clip((n * facet_normals).sum(axis=0), -1.0, 1.0))
        assert angle.max() <= 0.3 * h / R, name  # the facets' normals, to O(h)
        # a step along n leaves the quarter ball, a step against it stays inside
        mid = x.mean(axis=2)
        normal = m.exact_normals[name](mid)
        out, into = mid + 0.1 * h * normal, mid - 0.1 * h * normal
        assert np.all((out[0] < 0) | (out[1] < 0) | (np.linalg.norm(out - centre, axis=0) > R))
        assert np.all((into[0] > 0) & (into[1] > 0) & (np.linalg.norm(into - centre, axis=0) < R))


def test_quarter_ball_is_the_same_in_any_unit_of_length():
    unit = quarter_ball(0.25)
    for L in (2.0, 0.37, 1e-3):
        scaled = quarter_ball(0.25 * L, L)
        np.testing.assert_array_equal(scaled.mesh.t, unit.mesh.t)
        np.testing.assert_allclose(scaled.mesh.p, L * unit.mesh.p, rtol=1e-15, atol=0)
        for name in unit.part_names:
            np.testing.assert_array_equal(scaled.facets(name), unit.facets(name))
    graded_unit = quarter_ball(0.25, 1.0, 0.05)
    graded_scaled = quarter_ball(0.25 * 4.0, 4.0, 0.05 * 4.0)
    np.testing.assert_array_equal(graded_scaled.mesh.t, graded_unit.mesh.t)
    np.testing.assert_array_equal(graded_scaled.mesh.p, 4.0 * graded_unit.mesh.p)


@pytest.mark.parametrize("h, R, h_bottom", [(0.0, 1.0, None), (-0.1, 1.0, None), (float("nan"), 1.0, None),
                                            (0.1, 0.0, None), (1.5, 1.0, None), (0.1, 1.0, 0.2), (0.1, 1.0, 0.0),
                                            (0.1, 1.0, float("inf"))])
def test_quarter_ball_rejects_bad_sizes(h, R, h_bottom):
    with pytest.raises(CaseError):
        quarter_ball(h, R, h_bottom)


def test_meshes_too_large_for_the_memory_are_refused_before_they_are_made():
    with pytest.raises(CaseError) as info:
        quarter_ball(1e-3)
    words = str(info.value).split(": ")
    assert words[0] == "mesh.h = 0.001 on a quarter ball of radius 1"
    assert words[1].startswith("about 4e+10 tetrahedra, whose mesh") and "GiB" in words[1]
    assert words[-1] == "use a larger mesh.h"
    with pytest.raises(CaseError, match="mesh.h = 0.01 and mesh.h_bottom = 1e-05 on a quarter ball"):
        quarter_ball(0.01, 1.0, 1e-5)
    with pytest.raises(CaseError, match=r"mesh.h = 0.0001 on a 1 x 2 x 3 block: about 3.6e\+13 tetrahedra"):
        block(1.0, 2.0, 3.0, 1e-4)


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("make", [lambda: quarter_ball(1e-300), lambda: quarter_ball(0.1, 1.0, 1e-300),
                                  lambda: quarter_ball(1e-200, 1e100), lambda: block(1e300, 1e300, 1e300, 1e-300),
                                  lambda: vpcontact.mesh.half_disc(1e-300),
                                  lambda: vpcontact.mesh.rectangle(1e300, 1e300, 1e-300)],
                         ids=["ball", "ball h_bottom", "large ball", "block", "half disc", "rectangle"])
def test_counts_beyond_floats_are_refused_without_warnings(make):
    with pytest.raises(CaseError, match=r": more than 1e\+300 (triangles|tetrahedra), whose mesh, stiffness matrix and "
                                        r"solver need more than 1e\+290 GiB"):
        make()


# --- quarter_ball graded towards the bottom point ------------------------------------------------
def test_graded_quarter_ball_is_fine_near_the_bottom(graded):
    m, h, R, h_bottom = graded, 0.3, 2.0, 0.05
    p, t = m.mesh.p, m.mesh.t
    longest = edges(p, t).max(axis=0)
    distance = np.linalg.norm(p[:, t].mean(axis=1), axis=0)  # of the centroid from (0, 0, 0)
    near = distance <= 10 * h_bottom
    assert longest[near].max() <= h_bottom and longest[near].min() >= 0.4 * h_bottom
    allowed = np.minimum(h, h_bottom + 0.5 * (distance - 10 * h_bottom))
    assert np.all(longest[~near] <= allowed[~near] * (1 + 1e-12))
    assert m.h <= h and longest[distance > 1.5 * R].min() >= 0.5 * h  # the top is not refined
    assert np.all(volumes(p, t) > 0)
    angles = dihedral_angles(p, t)
    assert angles.min() >= 20.0 and angles.max() <= 150.0
    estimate = ball.estimated_tetrahedra(h / R, h_bottom / R)
    assert 0.7 * t.shape[1] <= estimate <= 1.3 * t.shape[1]


def test_graded_quarter_ball_keeps_the_sphere_and_the_parts(graded):
    m, R = graded, 2.0
    p = m.mesh.p
    check(m)  # conforming: every inner face of exactly two tetrahedra, on opposite sides
    found = boundary_faces(m.mesh.t)
    assert sum(len(m.facets(name)) for name in m.part_names) == len(found)
    for name in ("top", "bottom"):
        radius = np.linalg.norm(p[:, m.nodes(name)] - np.array([[0.0], [0.0], [R]]), axis=0)
        assert np.abs(radius - R).max() <= 1e-15 * R * 4
    assert np.all(p[0, m.nodes("sym_x")] == 0.0) and np.all(p[1, m.nodes("sym_y")] == 0.0)
    # the area of the bottom converges to πR²/2 faster than on the structured mesh alone
    assert 0 < math.pi * R**2 / 2 - area(m, "bottom") < math.pi * R**2 / 2 - area(quarter_ball(0.3, R), "bottom")


def test_grading_leaves_the_random_state_and_logs_nothing(caplog):
    np.random.seed(7)
    expected = np.random.random(3)
    np.random.seed(7)
    with caplog.at_level(logging.DEBUG):
        quarter_ball(0.25, 1.0, 0.1)
    assert np.array_equal(np.random.random(3), expected)
    assert not [record for record in caplog.records if record.levelno >= logging.WARNING]


def test_h_bottom_equal_to_h_changes_nothing():
    np.testing.assert_array_equal(quarter_ball(0.25, 1.0, 0.25).mesh.t, quarter_ball(0.25).mesh.t)


# --- block ---------------------------------------------------------------------------------------
def test_block_counts_parts_volume():
    m = block(2.0, 1.0, 0.5, 0.3)  # 7 x 4 x 2 cells
    assert m.dim == 3
    assert m.mesh.p.shape == (3, 8 * 5 * 3) and m.mesh.t.shape == (4, 6 * 7 * 4 * 2)
    assert m.part_names == ["back", "bottom", "front", "left", "right", "top"]
    assert {k: len(v) for k, v in m.parts.items()} == {"left": 2 * 4 * 2, "right": 2 * 4 * 2, "front": 2 * 7 * 2,
                                                       "back": 2 * 7 * 2, "bottom": 2 * 7 * 4, "top": 2 * 7 * 4}
    assert sum(map(len, m.parts.values())) == len(boundary_faces(m.mesh.t))
    p = m.mesh.p
    for name, axis, value in [("left", 0, 0.0), ("right", 0, 2.0), ("front", 1, 0.0), ("back", 1, 1.0),
                              ("bottom", 2, 0.0), ("top", 2, 0.5)]:
        assert np.all(p[axis, m.nodes(name)] == value), name
        assert area(m, name) == pytest.approx({0: 0.5, 1: 1.0, 2: 2.0}[axis], rel=1e-14)
        x = np.random.default_rng(0).random((3, 4, 2))
        n = m.exact_normals[name](x)
        expected = np.zeros(3)
        expected[axis] = 1.0 if value > 0 else -1.0
        np.testing.assert_array_equal(n, np.broadcast_to(expected[:, None, None], x.shape))
    assert np.abs(volumes(p, m.mesh.t)).sum() == pytest.approx(1.0, rel=1e-14)
    # the longest edge is a cell's diagonal, inside the block: no facet has it
    assert m.h == pytest.approx(math.sqrt((2 / 7) ** 2 + 0.25**2 + 0.25**2), rel=1e-14)
    assert m.diameter == pytest.approx(math.sqrt(4 + 1 + 0.25), rel=1e-14)
    check(m)


def test_block_rejects_bad_sizes():
    for args in [(0.0, 1, 1, 0.1), (1, -1, 1, 0.1), (1, 1, float("nan"), 0.1), (1, 1, 1, 0.0)]:
        with pytest.raises(CaseError):
            block(*args)


# --- tetrahedral gmsh files ------------------------------------------------------------------------
CUBE_PARTS = ["1", "2", "3", "4", "5", "6", "7", "back", "bottom", "front", "left", "right", "sides", "top"]


@pytest.mark.parametrize("name", ["cube", "cube_msh22"])
def test_gmsh_cube(name):
    m = read_mesh(MESHES / f"{name}.msh")
    assert m.dim == 3 and isinstance(m.mesh, skfem.MeshTet1) and m.file == str(MESHES / f"{name}.msh")
    assert m.part_names == CUBE_PARTS
    assert m.exact_normals == {}
    assert volume(m) == pytest.approx(1.0, rel=1e-12)
    assert np.all(np.abs(volumes(m.mesh.p, m.mesh.t)) > 0)
    p = m.mesh.p
    for tag, (axis, value, face) in enumerate([(0, 0, "left"), (0, 1, "right"), (1, 0, "front"), (1, 1, "back"),
                                               (2, 0, "bottom"), (2, 1, "top")], start=1):
        np.testing.assert_array_equal(m.facets(face), m.facets(tag))
        assert np.all(p[axis, m.nodes(face)] == value)
        assert area(m, face) == pytest.approx(1.0, rel=1e-12)
    sides = np.concatenate([m.facets(face) for face in ("left", "right", "front", "back")])
    np.testing.assert_array_equal(m.facets("sides"), np.sort(sides))  # a face in two physical surfaces
    assert sum(len(m.facets(tag)) for tag in range(1, 7)) == len(boundary_faces(m.mesh.t))
    assert m.h == pytest.approx(edges(p, m.mesh.t).max(), rel=1e-15)


def test_gmsh_cube_in_both_versions_is_the_same_mesh():
    new, old = read_mesh(MESHES / "cube.msh"), read_mesh(MESHES / "cube_msh22.msh")
    assert tetra_set(new) == tetra_set(old)
    for name in CUBE_PARTS:
        assert face_set(new, name) == face_set(old, name)


def test_gmsh_quarter_ball_matches_the_built_in_one():
    """gmsh's own quarter ball: its parts have the built-in shape's names, its sphere nodes are on the
    sphere and its volume and areas are those of the built-in mesh to within the meshes' O(h²)."""
    m = read_mesh(MESHES / "quarter_ball.msh")
    built = quarter_ball(0.25)
    assert m.dim == 3 and [name for name in m.part_names if not name.isdigit()] == built.part_names
    centre = np.array([[0.0], [0.0], [1.0]])
    for name in ("top", "bottom"):
        assert np.abs(np.linalg.norm(m.mesh.p[:, m.nodes(name)] - centre, axis=0) - 1.0).max() < 1e-9
        assert area(m, name) == pytest.approx(area(built, name), rel=0.03)
    assert volume(m) == pytest.approx(volume(built), rel=0.03)
    assert volume(m) < math.pi / 3
    assert np.abs(m.mesh.p[0, m.nodes("sym_x")]).max() < 1e-15 and np.abs(m.mesh.p[1, m.nodes("sym_y")]).max() < 1e-15


def test_gmsh_body_of_two_pieces_is_read():
    m = read_mesh(MESHES / "two_cubes_apart.msh")
    assert volume(m) == pytest.approx(2.0, rel=1e-12)
    assert m.part_names == ["1", "2", "bottom", "left"]
    assert area(m, "bottom") == pytest.approx(1.0, rel=1e-12)  # the first cube's faces
    assert np.all(m.mesh.p[:, m.nodes("left")][0] == 0.0)


def test_gmsh_file_without_physical_groups_has_no_parts():
    m = read_mesh(MESHES / "no_physical_groups.msh")
    assert m.parts == {} and volume(m) == pytest.approx(1.0, rel=1e-12)
    with pytest.raises(CaseError) as info:
        m.facets("bottom")
    assert str(info.value) == (
        f"unknown part 'bottom': mesh file '{MESHES / 'no_physical_groups.msh'}' has no parts; the parts of a mesh "
        f"file are its physical surfaces: in gmsh add Physical Surface(\"bottom\") = {{...}}; for each part the "
        f"case names (and a Physical Volume for the body) and mesh again")
    m = read_mesh(MESHES / "cube.msh")
    with pytest.raises(CaseError) as info:
        m.facets("sym_x")
    assert str(info.value) == f"unknown part 'sym_x'; the mesh has parts: {', '.join(CUBE_PARTS)}"


GMSH_REFUSALS = {
    "no_physical_volume": ["is not a 2D mesh", "has no tetrahedra, only triangles of physical surfaces",
                           "gmsh saves only their elements", 'add a Physical Volume for the body',
                           'Physical Volume("body") = {1};'],
    "second_order": ["second-order", "100 tetra10", "Mesh.ElementOrder = 1"],
    "hexahedra": ["8 hexahedron cells and 0 tetrahedra", "linear tetrahedra only", "Mesh.Recombine3DAll = 0"],
    "prisms": ["28 wedge cells", "linear tetrahedra only", "no Recombine in Extrude"],
    "pyramids": ["6 pyramid cells and 118 tetrahedra", "Mesh.RecombineAll = 0", "no Recombine Surface"],
    "internal_surface": ["triangle of physical group 2 is not a boundary face of the tetrahedra (28 such triangles)",
                         "a part must lie on the boundary of the body", "remove inner surfaces"],
    "duplicate_names": ["two physical surfaces are named 'left' (groups 1 and 2)", "only one of them",
                        "give each group its own name", 'Physical Surface("left") = {...};'],
    "nan_coordinate": ["node 45 has the coordinates (nan, 0.495117, 0.524414)", "finite number"],
    "zero_volume": ["tetrahedron 1 (nodes 37, 32, 27, 37) has zero volume", "lie in one plane",
                    "mesh the geometry again"],
    "face_of_three": ["the face with nodes 27, 32, 37 belongs to 3 tetrahedra", "covers a region twice",
                      "BooleanFragments"],
    "folded": ["tetrahedron 4 (nodes 33, 26, 25, 45) and tetrahedron 23 (nodes 33, 25, 26, 15) lie on the same side "
               "of their common face with nodes 25, 26, 33", "folded", "no volume may be listed twice"],
    "seam": ["are both at (1, ", "cut along a seam", "Coherence", "BooleanFragments"],
    "edge_hinge": ["along the edge from node 7 at (1, 1, 1) to node 21 at (1, 1, 0.5)", "touch only at that edge",
                   "4 boundary faces meet there", "join them along a surface or move them apart"],
    "vertex_hinge": ["at node 7 at (1, 1, 1) parts of the body touch only at that node", "2 separate fans",
                     "move them apart"],
}


@pytest.mark.parametrize("name", GMSH_REFUSALS)
def test_gmsh_mistakes_are_refused_with_the_fix(name):
    path = MESHES / f"{name}.msh"
    with pytest.raises(CaseError) as info:
        read_mesh(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"mesh file '{path}'")
    for words in GMSH_REFUSALS[name]:
        assert words in message, (words, message)


def write_tetrahedra(path, points, tetrahedra, triangles=None, tag=5):
    """A gmsh 2.2 file of `points` (n, 3), tetrahedra (m, 4) (physical volume 100) and triangles (k, 3)
    of physical surface `tag`."""
    cells = [("tetra", np.asarray(tetrahedra))]
    tags = [np.full(len(tetrahedra), 100)]
    if triangles is not None:
        cells.append(("triangle", np.asarray(triangles)))
        tags.append(np.full(len(triangles), tag))
    meshio.write(path, meshio.Mesh(np.asarray(points, dtype=float), cells,
                                   cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags}), file_format="gmsh22")
    return path


def unit_cube():
    """Nodes and the 6 tetrahedra of [0, 1]³ (skfem's cube)."""
    cube = skfem.MeshTet.init_tensor(*[np.array([0.0, 1.0])] * 3)
    return cube.p.T, cube.t.T


def test_read_mesh_accepts_any_orientation_and_drops_unused_nodes(tmp_path):
    p, t = unit_cube()
    t = t.copy()
    t[::2, :2] = t[::2, 1::-1]  # every other tetrahedron turned inside out
    points = np.vstack((p, [[5.0, 5.0, 5.0]]))  # a node no tetrahedron uses
    bottom = [f for f in boundary_faces(t.T) if np.all(points[f, 2] == 0)]
    r = read_mesh(write_tetrahedra(tmp_path / "cube.msh", points, t, bottom))
    np.testing.assert_array_equal(r.mesh.p, p.T)
    assert volume(r) == pytest.approx(1.0, rel=1e-14)
    assert r.part_names == ["5"] and area(r, 5) == pytest.approx(1.0, rel=1e-14)


def test_read_mesh_ignores_untagged_triangles_and_lines(tmp_path):
    p, t = unit_cube()
    faces = boundary_faces(t.T)
    cells = [("tetra", t), ("triangle", faces), ("line", np.array([[0, 1]]))]
    tags = [np.full(len(t), 1), np.zeros(len(faces), int), np.array([3])]
    meshio.write(tmp_path / "x.msh", meshio.Mesh(p, cells, cell_data={"gmsh:physical": tags,
                                                                        "gmsh:geometrical": tags}),
                 file_format="gmsh22")
    assert read_mesh(tmp_path / "x.msh").parts == {}


def test_tetrahedra_of_nodes_the_file_does_not_have_are_refused(tmp_path):
    p, t = unit_cube()
    meshio.write(tmp_path / "mesh.vtu", meshio.Mesh(p, [("tetra", np.vstack((t, [[0, 1, 2, 9]])))]))
    with pytest.raises(CaseError) as info:
        read_mesh(tmp_path / "mesh.vtu")
    assert str(info.value) == (f"mesh file '{tmp_path / 'mesh.vtu'}': tetrahedron 7 refers to node 10, but the file "
                               f"has nodes 1 to 8: the file is damaged")


@pytest.mark.parametrize("change, words", [
    (lambda p, t, f: (p, t, np.vstack((f, [[0, 1, 7]]))),
     ["triangle of physical group 5 is not a boundary face of the tetrahedra (1 such triangles)"]),
    (lambda p, t, f: (np.vstack((p, [[0.5, 0.5, 2.0]])), t, np.vstack((f, [[4, 5, 8]]))),
     ["triangle of physical group 5 is not a boundary face", "or add the volume they bound to the Physical Volume"]),
    (lambda p, t, f: (p * 1e150, t, f), ["the mesh is 1.73e+150 long", "another length unit"]),
], ids=["inner triangle", "triangle on a node of no tetrahedron", "too long"])
def test_damaged_or_out_of_scale_tetrahedral_meshes_are_refused(tmp_path, change, words):
    p, t = unit_cube()
    points, tetrahedra, faces = change(p, t, boundary_faces(t.T))
    path = write_tetrahedra(tmp_path / "bad.msh", points, tetrahedra, faces)
    with pytest.raises(CaseError) as info:
        read_mesh(path)
    assert str(info.value).startswith(f"mesh file '{path}'") and "\n" not in str(info.value)
    for w in words:
        assert w in str(info.value), (w, str(info.value))


@pytest.mark.parametrize("scale", [1e-90, 1e-12, 1e12, 1e90])
def test_the_3d_checks_do_not_depend_on_the_length_unit(scale):
    """A mesh far from the origin in any unit passes; a fold is found in any unit."""
    m = block(3.0, 3.0, 3.0, 1.0)
    p, t = m.mesh.p, m.mesh.t
    check_tetrahedra("x", (p + 7.0) * scale, t, np.arange(p.shape[1]) + 1)
    q = p.copy()
    q[:, np.flatnonzero((p == 1.0).all(axis=0))] = [[2.5], [1.1], [1.2]]  # an inner node pulled past another
    with pytest.raises(CaseError, match="folded"):
        check_tetrahedra("x", (q + 7.0) * scale, t, np.arange(p.shape[1]) + 1)


def test_a_3d_file_is_no_longer_refused_as_3d():
    """The 2D message for 3D cells is gone: vpcontact.mesh reads tetrahedra."""
    m = read_mesh(Path(__file__).parent / "meshes" / "cube.msh")  # the 2D tests' cube: 24 tetrahedra
    assert m.dim == 3 and m.mesh.t.shape == (4, 24)
    assert m.part_names == ["2", "bottom"] and area(m, "bottom") == pytest.approx(1.0, rel=1e-14)


def test_memory_estimate_counts_tetrahedra(monkeypatch):
    monkeypatch.setattr(vpcontact.mesh.mesh, "available_memory", lambda: 10**9)
    vpcontact.mesh.mesh.check_memory(2.8e5, "x", "y", dim=3)  # 3,500 bytes each
    vpcontact.mesh.mesh.check_memory(2.4e5, "x", "y")  # triangles
    with pytest.raises(CaseError) as info:
        vpcontact.mesh.mesh.check_memory(2.9e5, "x", "y", dim=3)
    assert str(info.value) == ("x: about 2.9e+05 tetrahedra, whose mesh, stiffness matrix and solver need about "
                               "0.945 GiB, more than the 0.931 GiB of memory available here: y")
