"""The element regions of meshes (issue 12): `Mesh.regions`, region name -> sorted element indices.

A mesh file's regions are its physical surfaces (2D) / volumes (3D), keyed like its parts; an element in
two such groups is one element of both, while cells repeated in one group still cover a region twice and
are refused. The built-in half disc and quarter ball take a coating (case key `mesh.coating`): regions
"core" and "coating" on a conforming interface, a half circle / quarter sphere of nodes at R − c."""

import itertools
import json
from pathlib import Path

import numpy as np
import pytest

from conftest import assert_refused, half_disc_case, run_cli, snapshot_tree
from test_3d_runs import ball_case
from test_robustness import read_csv, write
from vpcontact.errors import CaseError
from vpcontact.mesh import block, half_disc, quarter_ball, read_mesh, rectangle
from vpcontact.mesh.checks_2d import check_triangles
from vpcontact.mesh.checks_3d import check_tetrahedra

MESHES = Path(__file__).parent / "meshes"
#: The physical body groups of meshes/regions*.msh (2D) and meshes/3d/regions*.msh: name -> tag.
GROUPS = {2: {"core": "5", "shell": "6", "body": "7"}, 3: {"core": "3", "shell": "4", "body": "5"}}


def measures(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Areas (2D) or volumes (3D) of the elements t on the nodes p."""
    edges = p[:, t[1:]] - p[:, t[:1]]  # (d, d, m)
    return np.abs(np.linalg.det(edges.transpose(2, 0, 1))) / (2.0 if p.shape[0] == 2 else 6.0)


def smallest_angles(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Each triangle's smallest angle (degrees)."""
    angles = []
    for a, b, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        u, v = p[:, t[b]] - p[:, t[a]], p[:, t[c]] - p[:, t[a]]
        cosine = (u * v).sum(axis=0) / np.linalg.norm(u, axis=0) / np.linalg.norm(v, axis=0)
        angles.append(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))))
    return np.min(angles, axis=0)


def dihedral_angles(p: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each tetrahedron's smallest and largest dihedral angle (degrees)."""
    faces = [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)]
    normals = []
    for opposite, (a, b, c) in enumerate(faces):
        n = np.cross(p[:, t[b]] - p[:, t[a]], p[:, t[c]] - p[:, t[a]], axis=0)
        n /= np.linalg.norm(n, axis=0)
        outward = -np.sign((n * (p[:, t[opposite]] - p[:, t[a]])).sum(axis=0))
        normals.append(n * outward)
    angles = [180.0 - np.degrees(np.arccos(np.clip((normals[i] * normals[j]).sum(axis=0), -1.0, 1.0)))
              for i, j in itertools.combinations(range(4), 2)]
    return np.min(angles, axis=0), np.max(angles, axis=0)


def longest_edges(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    return np.max([np.linalg.norm(p[:, t[i]] - p[:, t[j]], axis=0)
                   for i, j in itertools.combinations(range(t.shape[0]), 2)], axis=0)


def assert_partition(regions: dict, count: int, names) -> None:
    """The regions `names` are sorted int64 index arrays that split the `count` elements."""
    for name in names:
        r = regions[name]
        assert r.dtype == np.int64 and np.all(np.diff(r) > 0), name
    assert np.array_equal(np.sort(np.concatenate([regions[n] for n in names])), np.arange(count))


# --- mesh files ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["regions.msh", "regions_msh22.msh", "3d/regions.msh", "3d/regions_msh22.msh"])
def test_the_physical_body_groups_of_a_file_are_its_regions(name):
    """[0, 2] × [0, 1] (× [0, 1]) as "core" (x < 1) and "shell" (x > 1), and "body" = both: every element
    is in two physical groups (gmsh 2.2 writes it twice, 4.1 once with two groups) and is one element."""
    mesh = read_mesh(MESHES / name)
    count = {2: 28, 3: 200}[mesh.dim]
    assert mesh.mesh.t.shape[1] == count
    groups = GROUPS[mesh.dim]
    assert set(mesh.regions) == set(groups) | set(groups.values())
    for group, tag in groups.items():
        assert np.array_equal(mesh.regions[group], mesh.regions[tag])
    assert_partition(mesh.regions, count, ["core", "shell"])
    assert np.array_equal(mesh.regions["body"], np.arange(count))
    x = mesh.mesh.p[0, mesh.mesh.t].mean(axis=0)
    assert np.all(x[mesh.regions["core"]] < 1.0) and np.all(x[mesh.regions["shell"]] > 1.0)
    size = measures(mesh.mesh.p, mesh.mesh.t)
    assert size[mesh.regions["core"]].sum() == pytest.approx(1.0, rel=1e-12)
    assert size[mesh.regions["shell"]].sum() == pytest.approx(1.0, rel=1e-12)


def test_elements_of_no_physical_group_are_in_no_region():
    """regions_untagged_shell.msh: the triangles of x > 1 have the physical tag 0 (none): they stay in the
    body, in no region."""
    mesh = read_mesh(MESHES / "regions_untagged_shell.msh")
    assert mesh.mesh.t.shape[1] == 28 and set(mesh.regions) == {"5", "core"}
    x = mesh.mesh.p[0, mesh.mesh.t].mean(axis=0)
    assert np.array_equal(mesh.regions["core"], np.flatnonzero(x < 1.0)) and mesh.regions["core"].size == 14


@pytest.mark.parametrize("name", ["no_physical_groups.msh", "3d/no_physical_groups.msh"])
def test_a_file_without_physical_body_groups_has_no_regions(name):
    mesh = read_mesh(MESHES / name)
    assert mesh.regions == {} and mesh.mesh.t.shape[1] > 0


def test_built_in_shapes_without_coating_have_no_regions():
    for mesh in (half_disc(0.25), rectangle(1.0, 1.0, 0.5), quarter_ball(0.5), quarter_ball(0.5, 1.0, 0.25),
                 block(1.0, 1.0, 1.0, 0.5)):
        assert mesh.regions == {}


def repeat_element(text: str, kind: str, tag: str) -> str:
    """The msh 2.2 `text` with its first element of type `kind` and physical tag `tag` written once more."""
    head, rest = text.split("$Elements\n", 1)
    lines, tail = rest.split("$EndElements", 1)
    lines = lines.splitlines()[1:]
    first = next(line.split() for line in lines if line.split()[1] == kind and line.split()[3] == tag)
    lines.append(" ".join([str(len(lines) + 1)] + first[1:]))
    return f"{head}$Elements\n{len(lines)}\n" + "\n".join(lines) + "\n$EndElements" + tail


def test_an_element_repeated_in_one_group_is_still_refused(tmp_path):
    """Only cells in distinct physical groups are merged: a triangle (2D) or tetrahedron (3D) written twice
    in "core" covers its place twice (besides being in "body"), and the mesh checks refuse it."""
    with pytest.raises(CaseError, match="belongs to 4 triangles .*the mesh covers a region twice"):
        read_mesh(MESHES / "regions_triangle_twice.msh")
    path = tmp_path / "tetrahedron_twice.msh"
    path.write_text(repeat_element((MESHES / "3d" / "regions_msh22.msh").read_text(), "4", "3"))
    with pytest.raises(CaseError, match="belongs to [34] tetrahedra .*the mesh covers a region twice"):
        read_mesh(path)
    # the same files without the repetition are read
    assert read_mesh(MESHES / "3d" / "regions_msh22.msh").mesh.t.shape[1] == 200


def test_an_element_in_two_groups_with_its_nodes_in_another_order_is_one_element(tmp_path):
    """A cell of "core" written again in "shell" with its nodes in another order is the same element (in both
    regions); written in "shell" over other nodes it is another element, and overlaps: refused."""
    text = (MESHES / "regions_msh22.msh").read_text()
    head, rest = text.split("$Elements\n", 1)
    lines, tail = rest.split("$EndElements", 1)
    lines = lines.splitlines()[1:]
    core = [line.split() for line in lines if line.split()[1:4:2] == ["2", "5"]]
    fields = core[0][:3] + ["6"] + core[0][4:5] + core[0][5:][::-1]
    same = lines + [" ".join([str(len(lines) + 1)] + fields[1:])]
    path = tmp_path / "same.msh"
    path.write_text(f"{head}$Elements\n{len(same)}\n" + "\n".join(same) + "\n$EndElements" + tail)
    mesh = read_mesh(path)
    assert mesh.mesh.t.shape[1] == 28
    both = np.intersect1d(mesh.regions["core"], mesh.regions["shell"])
    assert both.size == 1 and np.array_equal(np.sort(mesh.mesh.t[:, both[0]]),
                                             np.sort(np.array(core[0][5:], dtype=int) - 1))
    other = core[0][:3] + ["6"] + core[0][4:5] + core[0][5:7] + core[1][5:6]  # two nodes of it, one of another
    overlapping = lines + [" ".join([str(len(lines) + 1)] + other[1:])]
    path.write_text(f"{head}$Elements\n{len(overlapping)}\n" + "\n".join(overlapping) + "\n$EndElements" + tail)
    with pytest.raises(CaseError, match="mesh file"):
        read_mesh(path)


def test_messages_name_elements_by_their_place_in_the_file(tmp_path):
    """After the cells of an element in two groups are merged, a bad triangle is still named by its position
    among the file's triangles: here the last of 56 (28 triangles, each in "core"/"shell" and in "body")."""
    text = (MESHES / "regions_msh22.msh").read_text()
    head, rest = text.split("$Elements\n", 1)
    lines, tail = rest.split("$EndElements", 1)
    lines = lines.splitlines()
    last = lines[-1].split()
    assert last[1] == "2" and sum(line.split()[1] == "2" for line in lines[1:]) == 56
    lines[-1] = " ".join(last[:-1] + [last[-3]])  # its first node again: zero area
    path = tmp_path / "flat.msh"
    path.write_text(f"{head}$Elements\n" + "\n".join(lines) + "\n$EndElements" + tail)
    with pytest.raises(CaseError, match=rf"triangle 56 \(nodes {last[-3]}, {last[-2]}, {last[-3]}\) has zero area"):
        read_mesh(path)


def test_two_physical_body_groups_of_one_name_are_refused():
    with pytest.raises(CaseError, match=r"two physical surfaces are named 'core' \(groups 5 and 6\); a region of "
                                        r"that name would hold only one of them"):
        read_mesh(MESHES / "regions_duplicate_names.msh")


# --- built-in shapes with a coating ---------------------------------------------------------------------
def interface_nodes(mesh) -> np.ndarray:
    """The nodes of both a core and a coating element."""
    t = mesh.mesh.t
    return np.intersect1d(t[:, mesh.regions["core"]], t[:, mesh.regions["coating"]])


def assert_conforming_coating(mesh, R: float, c: float) -> None:
    """The regions split the elements; the nodes of each element lie on one side of the circle / sphere of
    radius R − c about the center (to rounding); the nodes where the regions meet lie on it (1e-12 relative);
    the mesh covers its body once (the checks of mesh files)."""
    p, t, dim = mesh.mesh.p, mesh.mesh.t, mesh.dim
    assert set(mesh.regions) == {"core", "coating"}
    assert_partition(mesh.regions, t.shape[1], ["core", "coating"])
    center = np.array([0.0, R]) if dim == 2 else np.array([0.0, 0.0, R])
    r = np.linalg.norm(p - center[:, None], axis=0)
    inner = R - c
    assert np.all(r[t[:, mesh.regions["core"]]] <= inner * (1 + 1e-12))
    assert np.all(r[t[:, mesh.regions["coating"]]] >= inner * (1 - 1e-12))
    on = interface_nodes(mesh)
    assert on.size and np.all(np.abs(r[on] - inner) <= 1e-12 * inner)
    numbers = np.arange(1, p.shape[1] + 1)
    (check_triangles if dim == 2 else check_tetrahedra)("built-in", p, t, numbers)


@pytest.mark.parametrize("h, R, c", [(0.25, 1.0, 0.25), (0.1, 2.0, 0.5), (0.05, 1.0, 0.1), (0.2, 1.0, 0.05),
                                     (0.1, 1.0, 0.9), (1.0, 1.0, 0.5)])
def test_a_coated_half_disc_has_a_conforming_interface(h, R, c):
    mesh = half_disc(h, R, c)
    assert_conforming_coating(mesh, R, c)
    p = mesh.mesh.p
    # the interface is the whole half circle, from (0, c) to (0, 2R − c), in arcs of at most 1.5 h
    on = interface_nodes(mesh)
    angle = np.sort(np.arctan2(p[1, on] - R, p[0, on]))
    assert angle[0] == pytest.approx(-0.5 * np.pi, abs=1e-12) and angle[-1] == pytest.approx(0.5 * np.pi, abs=1e-12)
    assert np.diff(angle).max() * (R - c) <= 1.5 * h
    # the parts are those of the mesh without coating: the same nodes on the arcs, the axis at x = 0
    plain = half_disc(h, R)
    assert mesh.exact_normals.keys() == plain.exact_normals.keys()
    for part in ("bottom_arc", "top_arc"):
        assert mesh.parts[part].size == plain.parts[part].size
        np.testing.assert_allclose(p[:, mesh.nodes(part)], plain.mesh.p[:, plain.nodes(part)], rtol=0, atol=1e-15 * R)
    assert np.all(p[0, mesh.nodes("axis")] == 0.0)
    assert p[1, mesh.nodes("axis")].min() == 0.0 and p[1, mesh.nodes("axis")].max() == 2 * R


def test_a_coating_thinner_than_the_facets_cut_is_refused_or_conforming():
    """A coating thinner than the gap between the circle / sphere and the mesh's facets on it (about
    h²/(8R)) cannot be meshed: the interface's nodes would lie beyond the outer facets (in 2D the
    triangulation then left the boundary, e.g. h = (π/2)/(10·1.0005), c = 0.001, where the core's arc has
    one facet fewer than the outer one; in 3D the coating's tetrahedra folded). Such coatings are refused
    with the size that works; every other is meshed conforming."""
    refused = []
    for h in [(np.pi / 2) / (k * 1.0005) for k in (4, 10, 30)] + [1.0, 0.33, 0.1, 0.05]:
        for c in (0.0001, 0.001, 0.003, 0.01, 0.05):
            try:
                mesh = half_disc(h, 1.0, c)
            except CaseError as error:
                assert f"mesh.coating = {c:g} is too thin for mesh.h = {h:g}" in str(error)
                assert f"use mesh.h < sqrt(8 radius coating) = {np.sqrt(8 * c):.3g}" in str(error)
                assert c < h * h / 8
                refused.append((h, c))
            else:
                assert_conforming_coating(mesh, 1.0, c)
    assert ((np.pi / 2) / (10 * 1.0005), 0.001) in refused and len(refused) >= 10
    for h, h_bottom, c, thin in ((0.6, None, 0.01, True), (0.6, 0.2, 0.01, True), (0.3, None, 0.001, True),
                                 (0.3, None, 0.02, False), (0.3, 0.1, 0.02, False)):
        if thin:
            with pytest.raises(CaseError, match=rf"mesh.coating = {c:g} is too thin for mesh.h = {h:g}: the facets "
                                                r"of the mesh on the sphere of radius 1 cut"):
                quarter_ball(h, 1.0, h_bottom, c)
        else:
            assert_conforming_coating(quarter_ball(h, 1.0, h_bottom, c), 1.0, c)


#: (h, c) with h ≤ c ≤ R − h (R = 1): measured smallest angles 25.5° to 45.2° (smallest in the coating, h = 0.1,
#: c = 0.3), longest edges 0.99 h to 1.40 h.
QUALITY_2D = [(h, c) for h in (0.2, 0.1, 0.05, 0.02) for c in (0.05, 0.1, 0.2, 0.3, 0.5, 0.9) if h <= c <= 1 - h]


@pytest.mark.parametrize("h, c", QUALITY_2D)
def test_the_coated_half_disc_quality(h, c):
    mesh = half_disc(h, 1.0, c)
    p, t = mesh.mesh.p, mesh.mesh.t
    assert smallest_angles(p, t).min() >= 25.0
    assert longest_edges(p, t).max() <= 1.41 * h


def test_the_coated_half_disc_areas_converge():
    """Areas of the core and the coating against π(R − c)²/2 and π(R² − (R − c)²)/2, R = 2, c = 0.6.
    Measured relative errors for h/R = 0.2, 0.1, 0.05, 0.025: core 1.1e-2, 3.4e-3, 8.5e-4, 2.1e-4 (second
    order: the inscribed polygon), coating 1.6e-3, 1.1e-4, 2.9e-5, 9.2e-7 (the errors of the polygons
    inside and outside it nearly cancel)."""
    R, c = 2.0, 0.6
    exact = {"core": 0.5 * np.pi * (R - c) ** 2, "coating": 0.5 * np.pi * (R * R - (R - c) ** 2)}
    errors = {name: [] for name in exact}
    for h in (0.2, 0.1, 0.05, 0.025):
        mesh = half_disc(h * R, R, c)
        area = measures(mesh.mesh.p, mesh.mesh.t)
        for name, value in exact.items():
            errors[name].append(abs(area[mesh.regions[name]].sum() - value) / value)
        assert area.sum() == pytest.approx(area[mesh.regions["core"]].sum() + area[mesh.regions["coating"]].sum())
    core, coating = np.array(errors["core"]), np.array(errors["coating"])
    assert np.all(core <= 0.35 * np.array([0.2, 0.1, 0.05, 0.025]) ** 2)
    assert np.all(core[:-1] / core[1:] > 3.0)
    assert np.all(np.diff(coating) < 0) and coating[-1] < 1e-5


@pytest.mark.parametrize("h, R, h_bottom, c", [(0.5, 1.0, None, 0.5), (0.5, 2.0, None, 0.6), (0.25, 1.0, None, 0.05),
                                               (0.25, 1.0, 0.05, 0.1), (0.5, 2.0, 0.1, 0.4), (1.0, 1.0, 0.2, 0.3)])
def test_a_coated_quarter_ball_has_a_conforming_interface(h, R, h_bottom, c):
    """Also when graded towards the bottom point: the nodes the bisection adds on the interface lie on its
    sphere, and the elements follow the refinement into their regions."""
    mesh = quarter_ball(h, R, h_bottom, c)
    assert_conforming_coating(mesh, R, c)
    p, t = mesh.mesh.p, mesh.mesh.t
    # the sphere keeps its nodes: those of the parts top and bottom are at the radius R
    sphere = np.concatenate((mesh.nodes("top"), mesh.nodes("bottom")))
    np.testing.assert_allclose(np.linalg.norm(p[:, sphere] - np.array([[0.0], [0.0], [R]]), axis=0), R, rtol=1e-12)
    # the interface is the whole quarter sphere: its faces' area is π(R − c)², to the inscribed polyhedron
    core = np.zeros(t.shape[1], dtype=bool)
    core[mesh.regions["core"]] = True
    faces = np.sort(np.hstack([t[list(f)] for f in itertools.combinations(range(4), 3)]), axis=0)
    owner = np.tile(core, 4)
    _, index, counts = np.unique(faces, axis=1, return_inverse=True, return_counts=True)
    index = index.ravel()
    in_core = np.bincount(index, weights=owner, minlength=counts.size)
    between = np.flatnonzero((counts == 2) & (in_core == 1))
    first = np.zeros(counts.size, dtype=np.int64)
    first[index[::-1]] = np.arange(index.size)[::-1]
    a, b, d = (p[:, faces[i, first[between]]] for i in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, d - a, axis=0), axis=0).sum()
    assert area == pytest.approx(np.pi * (R - c) ** 2, rel=0.06)
    if h_bottom is not None:  # graded: finer elements at the bottom point than without the grading
        assert t.shape[1] > quarter_ball(h, R, None, c).mesh.t.shape[1]


def test_the_coated_quarter_ball_sides_for_many_grids_and_coatings():
    """The interface's shell is found exactly for every grid n = 2 ... 13 and coating (a value computed
    otherwise differs from it by one unit in the last place for some, e.g. n = 4, c = 0.05): no element on
    both sides, the nodes where the regions meet on the sphere, graded too."""
    for n in range(2, 14):
        for c in (0.05, 0.13, 0.2, 0.37, 0.5, 0.9):
            h = 1.5 / n
            mesh = quarter_ball(h, 1.0, h / 4 if n in (4, 7) else None, c)
            t, r = mesh.mesh.t, np.linalg.norm(mesh.mesh.p - np.array([[0.0], [0.0], [1.0]]), axis=0)
            assert_partition(mesh.regions, t.shape[1], ["core", "coating"])
            assert np.all(r[t[:, mesh.regions["core"]]] <= (1 - c) * (1 + 1e-12)), (n, c)
            assert np.all(r[t[:, mesh.regions["coating"]]] >= (1 - c) * (1 - 1e-12)), (n, c)
            assert np.all(np.abs(r[interface_nodes(mesh)] - (1 - c)) <= 1e-12), (n, c)


#: Measured smallest dihedral angles (R/h ≥ 4, h ≤ c ≤ R − h, R = 1): 24.1° to 45°, largest ≤ 116.4°; longest edge
#: ≤ 1.08 h. (R/h = 2, c = R/2: 15.7°, the core's cells half as thick as the coating's.)
QUALITY_3D = [(h, c) for h in (0.25, 0.125) for c in (0.1, 0.2, 0.3, 0.5, 0.9) if h <= c <= 1 - h]
#: Graded (h_bottom ≤ c): smallest 14.1° to 25.3°, largest ≤ 159.7°.
QUALITY_3D_GRADED = [(h, h / 5, c) for h in (1.0, 0.5, 0.25) for c in (0.1, 0.2, 0.3, 0.5) if c >= h / 5]


@pytest.mark.parametrize("h, c", QUALITY_3D)
def test_the_coated_quarter_ball_quality(h, c):
    mesh = quarter_ball(h, 1.0, None, c)
    smallest, largest = dihedral_angles(mesh.mesh.p, mesh.mesh.t)
    assert smallest.min() >= 24.0 and largest.max() <= 117.0
    assert longest_edges(mesh.mesh.p, mesh.mesh.t).max() <= 1.08 * h


@pytest.mark.parametrize("h, h_bottom, c", QUALITY_3D_GRADED)
def test_the_graded_coated_quarter_ball_quality(h, h_bottom, c):
    mesh = quarter_ball(h, 1.0, h_bottom, c)
    smallest, largest = dihedral_angles(mesh.mesh.p, mesh.mesh.t)
    assert smallest.min() >= 14.0 and largest.max() <= 160.0


def test_the_coated_quarter_ball_volumes_converge():
    """Volumes of the core and the coating against π(R − c)³/3 and π(R³ − (R − c)³)/3, R = 1, c = 0.3.
    Measured relative errors for h = 0.5, 0.25, 0.125, 0.0625: core 6.1e-2, 1.6e-2, 4.0e-3, 8.8e-4,
    coating 1.0e-2, 2.5e-3, 6.1e-4, 2.1e-4 (second order: the inscribed polyhedra)."""
    R, c = 1.0, 0.3
    exact = {"core": np.pi * (R - c) ** 3 / 3, "coating": np.pi * (R**3 - (R - c) ** 3) / 3}
    errors = {name: [] for name in exact}
    hs = np.array([0.5, 0.25, 0.125])
    for h in hs:
        mesh = quarter_ball(h, R, None, c)
        volume = measures(mesh.mesh.p, mesh.mesh.t)
        for name, value in exact.items():
            errors[name].append(abs(volume[mesh.regions[name]].sum() - value) / value)
    core, coating = np.array(errors["core"]), np.array(errors["coating"])
    assert np.all(core <= 0.26 * hs**2) and np.all(coating <= 0.05 * hs**2)
    assert np.all(core[:-1] / core[1:] > 3.5) and np.all(coating[:-1] / coating[1:] > 3.5)


# --- case files --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("mesh, words", [
    ({"shape": "half_disc", "h": 0.25, "coating": 1.0}, ["mesh.coating = 1", "must be less than mesh.radius = 1"]),
    ({"shape": "quarter_ball", "h": 0.5, "radius": 2.0, "coating": 3.0},
     ["mesh.coating = 3", "must be less than mesh.radius = 2"]),
    ({"shape": "half_disc", "h": 0.25, "coating": 0.0}, ["mesh.coating = 0", "must be > 0"]),
    ({"shape": "half_disc", "h": 0.25, "coating": 0.001}, ["mesh.coating = 0.001 is too thin for mesh.h = 0.25",
                                                           "use mesh.h < sqrt(8 radius coating) = 0.0894"]),
    ({"shape": "rectangle", "h": 0.25, "coating": 0.1}, ["mesh.coating is only used with", "mesh.shape = \"rectangle\""]),
    ({"shape": "block", "h": 0.5, "coating": 0.1}, ["mesh.coating is only used with", "mesh.shape = \"block\""]),
    ({"file": "mesh.msh", "coating": 0.1}, ["mesh.coating is only used with", "mesh.file"]),
])
def test_a_misplaced_coating_is_refused(tmp_path, mesh, words):
    case = half_disc_case(h=0.25)
    case["mesh"] = mesh
    (tmp_path / "mesh.msh").write_bytes((MESHES / "regions.msh").read_bytes())
    path = write(tmp_path, case)
    before = snapshot_tree(tmp_path)
    status, _, err = run_cli("run", path, "--out", tmp_path / "out")
    assert_refused(status, err, *words, untouched=[(tmp_path, before)])


def final_force(run: Path, component: str) -> float:
    header, rows = read_csv(run / "history.csv")
    return float(rows[-1][header.index(f"contact_force_{component}")])


@pytest.mark.parametrize("dim", [2, 3])
def test_a_coated_body_with_one_material_runs(tmp_path, dim):
    """A single [material] covers the whole coated body: the run completes, and the foundation carries
    the same vertical load as without the coating (the arcs / spheres keep their facets, so the loads
    are the same)."""
    if dim == 2:
        case, coating, vertical = half_disc_case(h=0.25), 0.25, "y"
    else:
        case, coating, vertical = ball_case(h=0.5, steps=3), 0.3, "z"
        case["time"] = {"T": 0.3, "steps": 3}
    forces = []
    for name, mesh in (("plain", dict(case["mesh"])), ("coated", {**case["mesh"], "coating": coating})):
        path = write(tmp_path, {**case, "mesh": mesh}, name=f"{name}.toml")
        status, _, err = run_cli("run", path, "--out", tmp_path / name, "--quiet")
        assert status == 0, err
        summary = json.loads((tmp_path / name / "summary.json").read_text())
        assert summary["status"] == "complete"
        forces.append(final_force(tmp_path / name, vertical))
    assert forces[1] != 0.0 and forces[1] == pytest.approx(forces[0], rel=1e-8)
