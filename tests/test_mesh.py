"""Tests of vpcontact.mesh: half_disc, rectangle, read_mesh and the Mesh accessors."""

import math

import meshio
import numpy as np
import pytest
import skfem

from vpcontact.errors import CaseError
from vpcontact.mesh import Mesh, half_disc, read_mesh, rectangle

HALF_DISCS = [(1 / 16, 1.0), (0.1, 2.5), (0.37 / 23, 0.37)]


@pytest.fixture(scope="module", params=HALF_DISCS, ids=lambda c: f"h={c[0]:.4g},R={c[1]}")
def disc(request):
    h, R = request.param
    return h, R, half_disc(h, R)


def signed_areas(p, t):
    a, b, c = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def edge_lengths_and_angles(p, t):
    """(3, m) edge lengths (edge k opposite vertex k) and (3, m) angles in degrees."""
    e = np.array([np.linalg.norm(p[:, t[(k + 1) % 3]] - p[:, t[(k + 2) % 3]], axis=0) for k in range(3)])
    b, c = e[[1, 2, 0]], e[[2, 0, 1]]
    cos = (b**2 + c**2 - e**2) / (2 * b * c)
    return e, np.degrees(np.arccos(np.clip(cos, -1, 1)))


def boundary_edges(t):
    """Sorted node pairs (k, 2) of the edges that belong to exactly one triangle."""
    edges = np.sort(np.hstack((t[[0, 1]], t[[1, 2]], t[[2, 0]])), axis=0).T
    unique, count = np.unique(edges, axis=0, return_counts=True)
    return unique[count == 1]


def pair_set(mesh: Mesh, part):
    """The part's facets as a set of (node a, node b) coordinate pairs, order-free."""
    f = mesh.mesh.facets[:, mesh.facets(part)]
    p = mesh.mesh.p
    return {frozenset((tuple(p[:, a]), tuple(p[:, b]))) for a, b in f.T}


def triangle_set(mesh: Mesh):
    """The triangles as a set of node-coordinate triples, order-free."""
    p = mesh.mesh.p
    return {frozenset(map(tuple, p[:, tri].T)) for tri in mesh.mesh.t.T}


def test_half_disc_area_equals_inscribed_polygon(disc):
    h, R, m = disc
    n = 2 * math.ceil(0.5 * math.pi * R / h)  # arc facets; the axis is a diameter
    polygon = 0.5 * n * R**2 * math.sin(math.pi / n)
    areas = signed_areas(m.mesh.p, m.mesh.t)
    assert abs(np.abs(areas).sum() - polygon) <= 1e-12 * polygon
    assert np.abs(areas).min() > 0.05 * h**2
    # skfem integrates over the same domain (its element orientation is its own business)
    one = skfem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).assemble(skfem.Basis(m.mesh, skfem.ElementTriP1()))
    assert one == pytest.approx(polygon, rel=1e-12)


def test_half_disc_parts_partition_boundary(disc):
    h, R, m = disc
    assert m.part_names == ["axis", "bottom_arc", "top_arc"]
    found = boundary_edges(m.mesh.t)
    by_part = np.hstack([m.mesh.facets[:, m.facets(name)] for name in m.part_names])
    assert by_part.shape[1] == len(found)  # disjoint and covering, with the next line
    np.testing.assert_array_equal(np.unique(np.sort(by_part, axis=0).T, axis=0), found)
    n_arc = math.ceil(0.5 * math.pi * R / h)
    assert len(m.facets("bottom_arc")) == n_arc
    assert len(m.facets("top_arc")) == n_arc
    assert len(m.facets("axis")) == math.ceil(2 * R / h)
    for name, parts in m.parts.items():
        assert parts.dtype == np.int64 and np.all(np.diff(parts) > 0), name


def test_half_disc_boundary_geometry(disc):
    h, R, m = disc
    p = m.mesh.p
    bottom, top, axis = m.nodes("bottom_arc"), m.nodes("top_arc"), m.nodes("axis")
    assert np.abs(np.hypot(p[0, bottom], p[1, bottom] - R) - R).max() < 1e-12 * R
    assert np.abs(np.hypot(p[0, top], p[1, top] - R) - R).max() < 1e-12 * R
    assert p[1, bottom].max() == R and p[1, top].min() == R
    assert np.all(p[0, axis] == 0.0)
    assert len(bottom) == len(m.facets("bottom_arc")) + 1  # an open chain of nodes
    for corner in [(0.0, 0.0), (R, R), (0.0, 2 * R)]:
        assert np.any(np.all(p.T == corner, axis=1)), corner
    # equal spacing on the arc: all bottom_arc facets have the same length
    f = m.mesh.facets[:, m.facets("bottom_arc")]
    lengths = np.linalg.norm(p[:, f[0]] - p[:, f[1]], axis=0)
    chord = 2 * R * math.sin(math.pi / 4 / math.ceil(0.5 * math.pi * R / h))
    np.testing.assert_allclose(lengths, chord, rtol=1e-12)


def test_half_disc_quality(disc):
    h, R, m = disc
    e, angles = edge_lengths_and_angles(m.mesh.p, m.mesh.t)
    assert e.max() <= 1.5 * h
    assert m.h == pytest.approx(e.max(), rel=1e-15)
    assert angles.min() >= 20.0
    target = (0.5 * math.pi * R**2) / (math.sqrt(3) / 4 * h**2)
    assert 0.85 * target <= m.mesh.t.shape[1] <= 1.15 * target
    assert m.diameter == pytest.approx(math.sqrt(5) * R, rel=1e-14)


def test_half_disc_exact_normals_unit_and_outward(disc):
    h, R, m = disc
    p, e = m.mesh.p, skfem.ElementTriP1()
    for name in m.part_names:
        f = m.mesh.facets[:, m.facets(name)]
        mid = 0.5 * (p[:, f[0]] + p[:, f[1]])
        n = m.exact_normals[name](mid)
        assert n.shape == mid.shape
        np.testing.assert_allclose(np.linalg.norm(n, axis=0), 1.0, rtol=1e-14)
        # a step along n leaves the half disc, a step against it stays inside
        out, into = mid + 0.1 * h * n, mid - 0.1 * h * n
        assert np.all((out[0] < 0) | (np.hypot(out[0], out[1] - R) > R))
        assert np.all((into[0] > 0) & (np.hypot(into[0], into[1] - R) < R))
        # agrees with skfem's outward normals of the polygonal facets (angle < facet angle)
        fb = skfem.FacetBasis(m.mesh, e, facets=m.facets(name))
        exact = m.exact_normals[name](np.asarray(fb.global_coordinates()))
        cos = (exact * np.asarray(fb.normals)).sum(axis=0)
        assert cos.min() > math.cos(0.5 * math.pi / math.ceil(0.5 * math.pi * R / h)) - 1e-12


def test_half_disc_fine_mesh_sizes():
    m = half_disc(1 / 128)
    assert len(m.facets("bottom_arc")) == 202
    target = (0.5 * math.pi) / (math.sqrt(3) / 4 / 128**2)
    assert abs(m.mesh.t.shape[1] / target - 1) < 0.03
    assert m.h <= 1.5 / 128


@pytest.mark.parametrize("h, R", [(0.0, 1.0), (-0.1, 1.0), (float("nan"), 1.0), (0.1, 0.0), (1.5, 1.0)])
def test_half_disc_rejects_bad_sizes(h, R):
    with pytest.raises(CaseError):
        half_disc(h, R)


def test_mesh_part_lookup():
    m = half_disc(0.25)
    with pytest.raises(CaseError) as info:
        m.facets("foo")
    assert str(info.value) == "unknown part 'foo'; the mesh has parts: axis, bottom_arc, top_arc"
    with pytest.raises(CaseError, match="unknown part '3'"):
        m.nodes(3)
    f = m.mesh.facets[:, m.facets("axis")]
    np.testing.assert_array_equal(m.nodes("axis"), np.unique(f))
    assert len(m.nodes("axis")) == 9


def test_rectangle_counts_parts_area():
    m = rectangle(2.0, 1.0, 0.3)  # 7 x 4 cells
    assert m.mesh.p.shape == (2, 8 * 5)
    assert m.mesh.t.shape == (3, 2 * 7 * 4)
    assert m.part_names == ["bottom", "left", "right", "top"]
    assert {k: len(v) for k, v in m.parts.items()} == {"left": 4, "right": 4, "bottom": 7, "top": 7}
    p = m.mesh.p
    assert np.all(p[0, m.nodes("right")] == 2.0) and np.all(p[1, m.nodes("top")] == 1.0)
    assert np.abs(signed_areas(p, m.mesh.t)).sum() == pytest.approx(2.0, rel=1e-14)
    assert len(boundary_edges(m.mesh.t)) == 4 + 4 + 7 + 7
    assert m.h == pytest.approx(math.hypot(2 / 7, 1 / 4), rel=1e-14)
    assert m.diameter == pytest.approx(math.sqrt(5), rel=1e-14)
    x = np.array([[0.5, 1.0], [0.2, 0.3]])
    np.testing.assert_array_equal(m.exact_normals["bottom"](x), [[0, 0], [-1, -1]])
    np.testing.assert_array_equal(m.exact_normals["right"](x), [[1, 1], [0, 0]])


TAGS = {"axis": 1, "bottom_arc": 2, "top_arc": 3}


def write_gmsh(m: Mesh, path, file_format, flip=False):
    """Write `m` with one physical line group per part, plus an unused geometry point first."""
    points = np.vstack((np.full((1, 3), 9.0), np.hstack((m.mesh.p.T, np.zeros((m.mesh.p.shape[1], 1))))))
    t = m.mesh.t.T + 1
    if flip:  # mixed orientation: swap two nodes of every other triangle
        t[::2, [1, 2]] = t[::2, [2, 1]]
    cells = [("triangle", t)] + [("line", m.mesh.facets[:, m.facets(name)].T + 1) for name in TAGS]
    physical = [np.full(len(t), 10)] + [np.full(len(m.facets(name)), tag) for name, tag in TAGS.items()]
    geometrical = [np.full(len(t), 1)] + [np.full(len(m.facets(name)), tag) for name, tag in TAGS.items()]
    dim_tags = np.zeros((len(points), 2), dtype=int)
    dim_tags[0] = (0, 1)
    dim_tags[1:] = (2, 1)
    for name, tag in TAGS.items():
        dim_tags[m.nodes(name) + 1] = (1, tag)
    field_data = {name: np.array([tag, 1]) for name, tag in TAGS.items()} | {"domain": np.array([10, 2])}
    out = meshio.Mesh(
        points,
        cells,
        cell_data={"gmsh:physical": physical, "gmsh:geometrical": geometrical},
        field_data=field_data,
        point_data={"gmsh:dim_tags": dim_tags} if file_format == "gmsh" else {},
    )
    meshio.write(path, out, file_format=file_format)


@pytest.mark.parametrize("file_format", ["gmsh22", "gmsh"])
def test_read_mesh_round_trip(tmp_path, file_format):
    m = half_disc(0.2, 1.3)
    path = tmp_path / "disc.msh"
    write_gmsh(m, path, file_format)
    r = read_mesh(path)
    # same nodes (gmsh 4.1 groups them by entity, so compare as sets); the unused point is gone
    assert r.mesh.p.shape == m.mesh.p.shape
    assert sorted(map(tuple, r.mesh.p.T)) == sorted(map(tuple, m.mesh.p.T))
    assert triangle_set(r) == triangle_set(m)
    assert r.part_names == ["1", "2", "3", "axis", "bottom_arc", "top_arc"]
    for name, tag in TAGS.items():
        assert pair_set(r, name) == pair_set(m, name)
        np.testing.assert_array_equal(r.facets(tag), r.facets(name))
    assert len(r.facets("bottom_arc")) == math.ceil(0.5 * math.pi * 1.3 / 0.2)
    assert r.exact_normals == {}
    assert r.h == pytest.approx(m.h, rel=1e-15)


def test_read_mesh_accepts_any_orientation(tmp_path):
    m = half_disc(0.25)
    write_gmsh(m, tmp_path / "flip.msh", "gmsh22", flip=True)
    r = read_mesh(tmp_path / "flip.msh")
    np.testing.assert_array_equal(r.mesh.p, m.mesh.p)
    np.testing.assert_array_equal(r.mesh.t, m.mesh.t)  # skfem sorted every triangle's nodes
    assert pair_set(r, "axis") == pair_set(m, "axis")


def test_read_mesh_ignores_untagged_lines(tmp_path):
    m = half_disc(0.25)
    line = m.mesh.facets[:, m.facets("axis")].T
    meshio.write(
        tmp_path / "untagged.msh",
        meshio.Mesh(m.mesh.p.T, [("triangle", m.mesh.t.T), ("line", line)],
                    cell_data={"gmsh:physical": [np.full(len(m.mesh.t.T), 5), np.zeros(len(line), int)],
                               "gmsh:geometrical": [np.ones(len(m.mesh.t.T), int), np.ones(len(line), int)]}),
        file_format="gmsh22",
    )
    r = read_mesh(tmp_path / "untagged.msh")
    assert r.parts == {} and r.part_names == []
    assert triangle_set(r) == triangle_set(m)


def write22(path, points, cells, tags):
    """Write a gmsh 2.2 file; `tags` gives each cell block's physical (= geometrical) tag."""
    tag_data = [np.full(len(nodes), tag) for (_, nodes), tag in zip(cells, tags)]
    meshio.write(path, meshio.Mesh(np.asarray(points, dtype=float), cells,
                                   cell_data={"gmsh:physical": tag_data, "gmsh:geometrical": tag_data}),
                 file_format="gmsh22")


def test_read_mesh_missing_or_unreadable_file(tmp_path):
    with pytest.raises(CaseError, match="mesh file '.*nope.msh' not found"):
        read_mesh(tmp_path / "nope.msh")
    garbage = tmp_path / "garbage.msh"
    garbage.write_text("this is not a mesh\n")
    with pytest.raises(CaseError, match="cannot read mesh file '.*garbage.msh'") as info:
        read_mesh(garbage)
    assert "\n" not in str(info.value)


def test_read_mesh_without_triangles(tmp_path):
    path = tmp_path / "x.msh"
    write22(path, [[0, 0, 0], [1, 0, 0]], [("line", np.array([[0, 1]]))], [1])
    with pytest.raises(CaseError) as info:
        read_mesh(path)
    assert str(info.value).startswith(f"mesh file '{path}' has no triangles, only lines of physical curves: ")
    assert "add a Physical Surface for the body" in str(info.value)
    bare = tmp_path / "bare.msh"  # no physical group at all: a 1D mesh
    meshio.write(bare, meshio.Mesh(np.array([[0.0, 0, 0], [1, 0, 0]]), [("line", np.array([[0, 1]]))]),
                 file_format="gmsh22")
    with pytest.raises(CaseError) as info:
        read_mesh(bare)
    assert str(info.value) == f"mesh file '{bare}' has no triangles: mesh the surface in 2D (gmsh -2) and save it"


def test_read_mesh_rejects_nonplanar_mesh(tmp_path):
    path = tmp_path / "tilted.msh"
    write22(path, [[0, 0, 0], [1, 0, 0], [0, 1, 0.5]], [("triangle", np.array([[0, 1, 2]]))], [1])
    with pytest.raises(CaseError, match="'.*tilted.msh' is not a 2D mesh"):
        read_mesh(path)


def test_read_mesh_parts_must_be_boundary_edges(tmp_path):
    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    triangles = ("triangle", np.array([[0, 1, 2], [0, 2, 3]]))
    ok = tmp_path / "square.msh"
    write22(ok, square, [triangles, ("line", np.array([[1, 0], [1, 2]]))], [1, 4])
    r = read_mesh(ok)
    assert r.part_names == ["4"]
    assert {tuple(sorted(f)) for f in r.mesh.facets[:, r.facets(4)].T} == {(0, 1), (1, 2)}
    with pytest.raises(CaseError) as info:
        r.facets("bottom")
    assert str(info.value) == "unknown part 'bottom'; the mesh has parts: 4"
    diagonal = tmp_path / "diagonal.msh"  # the diagonal is an interior edge
    write22(diagonal, square, [triangles, ("line", np.array([[0, 2]]))], [1, 4])
    with pytest.raises(CaseError, match="physical group 4 is not a boundary edge"):
        read_mesh(diagonal)


@pytest.mark.parametrize("make", [lambda: half_disc(0.1), lambda: rectangle(1.0, 0.5, 0.1)])
def test_a_mesh_with_named_parts_keeps_its_facet_tables_and_they_are_the_meshs_own(make):
    """The named mesh carries the facet tables built to find its boundary (not built twice), and they are
    those scikit-fem builds from the elements alone: the parts' facet indices mean the same facets."""
    mesh = make().mesh
    assert {"_facets", "_t2f", "_f2t"} <= set(vars(mesh))
    fresh = type(mesh)(mesh.p, mesh.t)
    np.testing.assert_array_equal(mesh.facets, fresh.facets)
    np.testing.assert_array_equal(mesh.t2f, fresh.t2f)
    np.testing.assert_array_equal(mesh.f2t, fresh.f2t)
    boundary = fresh.boundary_facets()
    assert sum(facets.size for facets in mesh.boundaries.values()) == boundary.size
    for name, facets in mesh.boundaries.items():
        assert np.isin(facets, boundary).all(), name
