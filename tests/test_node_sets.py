"""Tests of vpcontact.mesh.node_sets: the nodes where a condition holds and the node nearest to a point, on the
built-in meshes and on a cylinder made and meshed in gmsh, against NumPy's own selection on the nodes'
coordinates and against the parts the mesh's maker classified."""

from __future__ import annotations

import numpy as np
import pytest

from vpcontact import mesh
from vpcontact.errors import CaseError
from vpcontact.expressions.conditions import parse_condition

WHERE = "boundary.dirichlet[2].where"
AT = "boundary.point[0].at"
RADIUS, HEIGHT = 0.01, 0.02


@pytest.fixture(scope="module")
def block():
    return mesh.block(1.0, 0.5, 0.02, 0.02)


@pytest.fixture(scope="module")
def half_disc():
    return mesh.half_disc(0.1)


@pytest.fixture(scope="module")
def cylinder(tmp_path_factory):
    """A cylinder of radius 0.01 and height 0.02 on z = 0, made with gmsh's OCC kernel, meshed by gmsh with
    the physical surfaces "top", "bottom", "side" and read with vpcontact.mesh.read_mesh."""
    try:
        import gmsh
    except (ImportError, OSError) as error:
        pytest.skip(f"gmsh does not load: {error}")
    path = tmp_path_factory.mktemp("cylinder") / "cylinder.msh"
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("cylinder")
        volume = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, HEIGHT, RADIUS)
        gmsh.model.occ.synchronize()
        for _, face in gmsh.model.getBoundary([(3, volume)], oriented=False):
            x, _, z = gmsh.model.occ.getCenterOfMass(2, face)
            name = "side" if abs(x) > 1e-12 or abs(z - HEIGHT / 2) < 1e-12 else "top" if z > HEIGHT / 2 else "bottom"
            gmsh.model.addPhysicalGroup(2, [face], name=name)
        gmsh.model.addPhysicalGroup(3, [volume], name="body")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.004)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return mesh.read_mesh(path)


# --- nodes where a condition holds ------------------------------------------------------


def test_the_top_plane_of_a_block_is_its_top_part(block):
    p = block.mesh.p
    top = mesh.nodes_where(block, "abs(z - 0.02) < 1e-9", WHERE)
    assert top.dtype == np.int64 and np.all(np.diff(top) > 0)
    np.testing.assert_array_equal(top, np.flatnonzero(np.abs(p[2] - 0.02) < 1e-9))
    np.testing.assert_array_equal(top, block.nodes("top"))
    corner_line = mesh.nodes_where(block, "z >= 0.02 - 1e-9 and (x == 0 or y == 0.5)", WHERE)
    np.testing.assert_array_equal(corner_line, np.flatnonzero((p[2] >= 0.02 - 1e-9) & ((p[0] == 0) | (p[1] == 0.5))))
    assert 0 < corner_line.size < top.size


@pytest.mark.parametrize(("condition", "select"), [
    ("x <= 0.25 and y > 0.1", lambda x, y: (x <= 0.25) & (y > 0.1)),
    ("0.2 < x < 0.6 or not y < 0.4", lambda x, y: ((0.2 < x) & (x < 0.6)) | ~(y < 0.4)),
    ("abs(x - y) < 1e-12", lambda x, y: np.abs(x - y) < 1e-12),
])
def test_conditions_on_a_rectangle_select_as_numpy_does(condition, select):
    rectangle = mesh.rectangle(1.0, 0.5, 0.05)
    x, y = rectangle.mesh.p
    expected = np.flatnonzero(select(x, y))
    assert 0 < expected.size < x.size
    np.testing.assert_array_equal(mesh.nodes_where(rectangle, condition, WHERE), expected)


def test_the_arc_of_the_half_disc_by_a_condition_is_its_arc_parts(half_disc):
    y = half_disc.mesh.p[1]
    arc = mesh.nodes_where(half_disc, "abs(sqrt(x**2 + (y - 1)**2) - 1) < 1e-9", WHERE)
    np.testing.assert_array_equal(arc, np.union1d(half_disc.nodes("bottom_arc"), half_disc.nodes("top_arc")))
    lower = mesh.nodes_where(half_disc, "y < 1", WHERE, within="bottom_arc")
    np.testing.assert_array_equal(lower, np.intersect1d(half_disc.nodes("bottom_arc"), np.flatnonzero(y < 1)))
    given = np.array([7, 3, 3, 0, int(arc[-1])])
    np.testing.assert_array_equal(mesh.nodes_where(half_disc, "x >= 0", WHERE, within=given), [0, 3, 7, arc[-1]])
    parsed = parse_condition("x == 0", ("x", "y", "z"), where="elsewhere")  # its text, in the mesh's coordinates
    np.testing.assert_array_equal(mesh.nodes_where(half_disc, parsed, WHERE), half_disc.nodes("axis"))


def test_a_plane_and_the_side_of_a_gmsh_cylinder(cylinder):
    p = cylinder.mesh.p
    assert cylinder.dim == 3 and {"top", "bottom", "side"} <= set(cylinder.part_names)
    top = mesh.nodes_where(cylinder, f"abs(z - {HEIGHT}) < 1e-9", WHERE)
    np.testing.assert_array_equal(top, np.flatnonzero(np.isclose(p[2], HEIGHT, rtol=0, atol=1e-9)))
    np.testing.assert_array_equal(top, cylinder.nodes("top"))
    side = mesh.nodes_where(cylinder, f"x**2 + y**2 > ({RADIUS} - 1e-9)**2", WHERE)
    np.testing.assert_array_equal(side, cylinder.nodes("side"))
    half = mesh.nodes_where(cylinder, "x > 0 and z < 1e-9", WHERE, within="bottom")
    np.testing.assert_array_equal(half, np.intersect1d(cylinder.nodes("bottom"), np.flatnonzero(p[0] > 0)))
    assert 0 < half.size < cylinder.nodes("bottom").size


def test_a_condition_that_holds_at_no_node_gives_the_range_of_the_nodes(block):
    with pytest.raises(CaseError) as info:
        mesh.nodes_where(block, "abs(z - 0.03) < 1e-9", WHERE)
    assert str(info.value) == (f'{WHERE} = "abs(z - 0.03) < 1e-9" holds at no node of the mesh '
                               f"(x in [0.0, 1.0], y in [0.0, 0.5], z in [0.0, 0.02])")
    with pytest.raises(CaseError) as info:
        mesh.nodes_where(block, "x > 1", WHERE, within="top")
    assert str(info.value) == (f'{WHERE} = "x > 1" holds at no node of part \'top\' '
                               f"(x in [0.0, 1.0], y in [0.0, 0.5], z in [0.02, 0.02])")
    with pytest.raises(CaseError, match=r"holds at no node of the 2 given nodes \(x in \[0.0, 0.0\], y in \[0.0, "):
        mesh.nodes_where(block, "x > 1", WHERE, within=np.array([0, 0, 1]))
    with np.errstate(all="raise"), pytest.raises(CaseError, match="holds at no node"):
        mesh.nodes_where(block, "sqrt(-1 - x) < 1 or 1/x < 0", WHERE)  # NaN and 1/0 are no warning here


@pytest.mark.parametrize(("condition", "problem"), [
    ("t < 1", "unknown name 't' (allowed: x, y, z, pi, e and the functions"),
    ("x + 1", 'not a condition; expected a comparison such as "abs(z - 0.02) < 1e-9"'),
    ("z = 0.02", "equality is written =="),
])
def test_a_bad_condition_names_the_key(block, condition, problem):
    with pytest.raises(CaseError) as info:
        mesh.nodes_where(block, condition, WHERE)
    assert str(info.value).startswith(f'{WHERE} = "{condition}": ') and problem in str(info.value)


def test_z_on_a_plane_mesh_and_a_condition_that_is_no_string(half_disc):
    with pytest.raises(CaseError) as info:
        mesh.nodes_where(half_disc, "z == 0", WHERE)
    assert str(info.value).startswith(f'{WHERE} = "z == 0": unknown name \'z\' (allowed: x, y, pi, e and the functions')
    with pytest.raises(CaseError, match=r"= True: expected a condition string"):
        mesh.nodes_where(half_disc, True, WHERE)
    with pytest.raises(CaseError, match="unknown part 'nowhere'"):
        mesh.nodes_where(half_disc, "x > 0", WHERE, within="nowhere")


# --- the node nearest to a point --------------------------------------------------------


def brute_nearest(points: np.ndarray, point) -> tuple[int, float]:
    """The nearest node by NumPy's norm of every node's offset."""
    distances = np.linalg.norm(points - np.asarray(point, dtype=float)[:, None], axis=0)
    return int(np.argmin(distances)), float(distances.min())


def test_nearest_nodes_of_random_points_are_numpys(half_disc, block):
    rng = np.random.default_rng(3)
    for body, low, high in ((half_disc, [-0.2, -0.2], [1.2, 2.2]), (block, [-0.1, -0.1, -0.1], [1.1, 0.6, 0.1])):
        for point in rng.uniform(low, high, size=(50, body.dim)):
            node, distance = mesh.nearest_node(body, point.tolist(), AT)
            expected, expected_distance = brute_nearest(body.mesh.p, point)
            assert node == expected
            assert distance == pytest.approx(expected_distance, rel=1e-12)


def test_a_node_is_its_own_nearest_and_ties_take_the_lowest_index():
    rectangle = mesh.rectangle(1.0, 1.0, 0.5)  # nodes on the grid of step 0.5
    p = rectangle.mesh.p
    for node in range(p.shape[1]):
        assert mesh.nearest_node(rectangle, p[:, node].tolist(), AT) == (node, 0.0)
    centre = np.flatnonzero((p[0] == 0.5) & (p[1] == 0.5))[0]
    both = np.flatnonzero((p[1] == 0.5) & (p[0] != 1.0))  # (0, 0.5) and (0.5, 0.5), 0.25 from (0.25, 0.5)
    assert mesh.nearest_node(rectangle, [0.25, 0.5], AT) == (int(both.min()), 0.25)
    four = np.flatnonzero((p[0] <= 0.5) & (p[1] <= 0.5))  # (0.25, 0.25) is as far from four nodes
    node, distance = mesh.nearest_node(rectangle, (0.25, 0.25), AT)
    assert node == four.min() and distance == pytest.approx(np.hypot(0.25, 0.25), rel=1e-15)
    assert centre in four


def test_a_point_off_the_mesh_is_not_refused(block, cylinder):
    node, distance = mesh.nearest_node(block, [2.0, 0.25, 0.01], AT)
    assert (node, distance) == brute_nearest(block.mesh.p, [2.0, 0.25, 0.01]) and distance > 0.99
    node, distance = mesh.nearest_node(cylinder, [RADIUS, 0, HEIGHT / 2], AT)  # on the side
    assert (node, pytest.approx(distance, rel=1e-12)) == brute_nearest(cylinder.mesh.p, [RADIUS, 0, HEIGHT / 2])
    assert node in cylinder.nodes("side")
    node, distance = mesh.nearest_node(cylinder, np.array([0, 0, 1e300]), AT)  # squares would overflow
    assert cylinder.mesh.p[2, node] == HEIGHT and distance == 1e300


@pytest.mark.parametrize(("point", "message"), [
    ([1, 2], f"{AT} = [1, 2]: expected a point of 3 coordinates (x, y, z), got 2 numbers"),
    ([1, 2, 3, 4], f"{AT} = [1, 2, 3, 4]: expected a point of 3 coordinates (x, y, z), got 4 numbers"),
    ([], f"{AT} = []: expected a point of 3 coordinates (x, y, z), got 0 numbers"),
    ("0, 0, 0", f"{AT} = '0, 0, 0': expected a point of 3 coordinates (x, y, z), got str"),
    (0.5, f"{AT} = 0.5: expected a point of 3 coordinates (x, y, z), got float"),
    ([0, "a", 0], f"{AT} = [0, 'a', 0]: coordinate y = 'a' is not a number"),
    ([True, 0, 0], f"{AT} = [True, 0, 0]: coordinate x = True is not a number"),
    ([0, 0, float("nan")], f"{AT} = [0, 0, nan]: coordinate z = nan is not a finite number"),
    ([0, float("-inf"), 0], f"{AT} = [0, -inf, 0]: coordinate y = -inf is not a finite number"),
])
def test_a_bad_point_names_the_key(block, point, message):
    with pytest.raises(CaseError) as info:
        mesh.nearest_node(block, point, AT)
    assert str(info.value) == message
