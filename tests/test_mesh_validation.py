"""Meshes and input files that would give meaningless numbers are refused before any computation.

Each refusal is checked at the command line (exit 2, one line naming the problem and the fix,
nothing written). The gmsh files in tests/meshes are real gmsh output (tests/meshes/make_meshes.py);
the other bad meshes are written here node by node. Valid meshes (the built-in shapes at many h,
the valid gmsh files) must pass every check.
"""

import contextlib
import math
import os
from pathlib import Path

import meshio
import numpy as np
import pytest
import tomli_w

import vpcontact.mesh
from conftest import assert_refused, run_cli, snapshot_tree
from vpcontact.errors import CaseError
from vpcontact.mesh import half_disc, read_mesh, rectangle
from vpcontact.mesh.checks_2d import check_triangles

MESHES = Path(__file__).parent / "meshes"


# --- helpers -------------------------------------------------------------------------------------
def square_case(mesh_file, dirichlet=None) -> dict:
    """A block on rollers at its sides (or `dirichlet`) pushed by its top onto the foundation under
    its bottom (the parts of tests/meshes/square.msh)."""
    case = {
        "mesh": {"file": str(mesh_file)},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {
            "dirichlet": [{"part": "left", "components": ["x"]}, {"part": "right", "components": ["x"]}],
            "traction": [{"part": "top", "value": ["0", "-10*t"]}],
        },
        "contact": {"part": "bottom", "g": 0.2,
                    "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
        "time": {"T": 1.0, "steps": 2},
        "output": {"field_steps": "none"},
    }
    if dirichlet is not None:
        case["boundary"]["dirichlet"] = dirichlet
    return case


def run_case(tmp_path, case: dict):
    """`vpcontact run` of `case` written to tmp_path/case.toml: (status, stdout, stderr, out folder)."""
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    out = tmp_path / "out"
    status, stdout, stderr = run_cli("run", path, "--out", out, "--quiet")
    return status, stdout, stderr, out


def refused(tmp_path, case: dict, *words):
    """Run `case` and assert the refusal contract: exit 2, one line with `words`, nothing written."""
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert_refused(status, stderr, *words, untouched=[(tmp_path, before)])
    return stderr


def write_msh(path, points, triangles):
    """A gmsh 2.2 file of `points` (n, 2) and `triangles` (m, 3) (physical surface 100)."""
    points = np.hstack((np.asarray(points, dtype=float), np.zeros((len(points), 1))))
    tags = [np.full(len(triangles), 100)]
    meshio.write(path, meshio.Mesh(points, [("triangle", np.asarray(triangles))],
                                   cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags}), file_format="gmsh22")
    return path


def grid(nx, ny, x0=0.0, y0=0.0, width=1.0, height=1.0, first=0):
    """Nodes (k, 2) and triangles (m, 3) (numbered from `first`) of a structured mesh of a rectangle."""
    X, Y = np.meshgrid(np.linspace(x0, x0 + width, nx + 1), np.linspace(y0, y0 + height, ny + 1), indexing="ij")
    index = np.arange(X.size).reshape(X.shape) + first
    a, b, c, d = index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    return np.column_stack((X.ravel(), Y.ravel())), np.vstack((np.column_stack((a, b, c)), np.column_stack((a, c, d))))


def bad_meshes():
    """name -> (points, triangles, words of the refusal): meshes written node by node."""
    p, t = grid(2, 2)
    folded = p.copy()
    folded[4] = [1.4, 0.5]  # the centre node pulled out through the right side
    big, big_t = grid(2, 2, width=4.0, height=4.0)
    inner, inner_t = grid(1, 1, 1.0, 1.0, first=len(big))
    one, one_t = grid(1, 1)
    corner, corner_t = grid(1, 1, 1.0, 1.0, first=len(one))
    corner_t[corner_t == len(one)] = 3  # the second square's corner (1, 1) is the first one's node 3
    shifted, shifted_t = grid(2, 2, 0.5, 0.25, first=len(p))
    k = 7  # a fan around (0, 0) that goes round twice
    angle = 4 * np.pi * np.arange(k) / k
    fan = np.vstack(([0.0, 0.0], np.column_stack((np.cos(angle), np.sin(angle)))))
    fan_t = np.array([[0, 1 + j, 1 + (j + 1) % k] for j in range(k)])
    nan, inf = p.copy(), p.copy()
    nan[4, 0], inf[4, 1] = np.nan, -np.inf
    return {
        "nan coordinate": (nan, t, ["node 5", "nan", "finite number"]),
        "infinite coordinate": (inf, t, ["node 5", "-inf", "finite number"]),
        "zero-area triangle": (np.vstack((p, [[0.25, 0.0]])), np.vstack((t, [[0, 3, 9]])),
                               ["triangle 9 (nodes 1, 4, 10)", "(0, 0), (0.5, 0), (0.25, 0)", "has zero area"]),
        "triangle with a repeated node": (p, np.vstack((t, [[0, 1, 1]])), ["triangle 9 (nodes 1, 2, 2) has zero area"]),
        "folded": (folded, t, ["same side of their common edge", "folded", "(1.4, 0.5)"]),
        "edge of three triangles": (np.vstack((p, [[0.9, 0.1]])), np.vstack((t, [[0, 4, 9]])),
                                    ["belongs to 3 triangles", "covers a region twice"]),
        "triangle twice": (p, np.vstack((t, t[5:6])), ["belongs to", "triangles", "meshed once"]),
        "square inside a square": (np.vstack((big, inner)), np.vstack((big_t, inner_t)),
                                   ["lies on top of other triangles (covered 2 times)", "BooleanFragments"]),
        "overlapping squares": (np.vstack((p, shifted)), np.vstack((t, shifted_t)), ["cross", "on top of each other"]),
        "fan wound twice": (fan, fan_t, ["cross", "on top of each other"]),
        "hinge": (np.vstack((one, corner)), np.vstack((one_t, corner_t)),
                  ["node 4 at (1, 1)", "touch only at that node", "hinge"]),
        "hanging node": (np.array([[0, 0], [1, 0], [1, 1], [0, 1], [2, 0], [2, 1], [1, 0.5]]),
                         np.array([[0, 1, 2], [0, 2, 3], [1, 4, 6], [4, 5, 6], [6, 5, 2]]),
                         ["overlap along a line", "not joined", "Coherence"]),
    }


BAD_MESHES = bad_meshes()


# --- gmsh files: the mistakes every new user makes ---------------------------------------------
GMSH_REFUSALS = {
    "no_physical_surface": ["has no triangles", "only lines of physical curves", "gmsh saves only their elements",
                            "add a Physical Surface for the body"],
    "no_physical_groups": ["unknown part 'left'", "has no parts", "physical curves",
                           'Physical Curve("left") = {...};', "Physical Surface"],
    "second_order": ["second-order", "14 triangle6", "Mesh.ElementOrder = 1"],
    "quadrilaterals": ["6 quadrilaterals and 0 triangles", "Mesh.RecombineAll = 0", "Recombine"],
    "mixed_triangles_quads": ["6 quadrilaterals and 14 triangles", "linear triangles only", "Mesh.RecombineAll = 0"],
    "crack": ["nodes", "are both at (1, ", "cut along a seam", "Coherence"],
    "overlapping_squares": ["boundary edges", "cross", "BooleanFragments"],
    "surface_twice": ["same side of their common edge", "folded", "no surface may be listed twice"],
    "duplicate_names": ["two physical curves are named 'bottom' (groups 1 and 2)", "only one of them",
                        "give each group its own name"],
}


@pytest.mark.parametrize("name", GMSH_REFUSALS)
def test_gmsh_mistakes_are_refused_with_the_fix(tmp_path, name):
    refused(tmp_path, square_case(MESHES / f"{name}.msh"), f"{name}.msh", *GMSH_REFUSALS[name])


def other_cells():
    """name -> (file name, meshio cells, words): cells that are not linear triangles, written by meshio."""
    triangle = ("triangle", np.array([[0, 1, 2], [0, 2, 4]]))
    return {
        "cubic triangle": ("cubic.msh", [("triangle10", np.arange(10)[None])],
                           ["second-order or higher-order elements (1 triangle10)", "Mesh.ElementOrder = 1"]),
        "second-order quadrilateral": ("quad9.msh", [triangle, ("quad9", np.arange(9)[None])],
                                       ["1 quadrilaterals and 2 triangles", "Mesh.RecombineAll = 0"]),
        "second-order lines": ("lines.msh", [triangle, ("line3", np.array([[0, 1, 3]]))],
                               ["(1 line3)", "Mesh.ElementOrder = 1"]),
        "polygon": ("polygon.vtu", [triangle, ("polygon", np.array([[0, 1, 2, 3, 4]]))],
                    ["cells that are not linear triangles (1 polygon)", "linear triangles only"]),
        "no physical group, no triangle": ("lines_only.msh", [("line", np.array([[0, 1], [1, 2]]))],
                                           ["has no triangles: mesh the surface in 2D (gmsh -2)"]),
    }


@pytest.mark.parametrize("name", other_cells())
def test_cells_that_are_not_linear_triangles_are_refused(tmp_path, name):
    file, cells, words = other_cells()[name]
    points = np.column_stack((np.linspace(0, 1, 10), np.linspace(0, 1, 10) ** 2, np.zeros(10)))
    file_format = "gmsh22" if file.endswith(".msh") else None
    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):  # meshio's notes on missing tags
        meshio.write(tmp_path / file, meshio.Mesh(points, cells), file_format=file_format)
    refused(tmp_path, square_case(tmp_path / file), f"mesh file '{tmp_path / file}'", *words)


SQUARE = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])


@pytest.mark.parametrize("points, triangles, words", [
    (SQUARE, [[0, 1, 2], [0, 2, 7]], ["triangle 2 refers to node 8, but the file has nodes 1 to 4", "damaged"]),
    (SQUARE, [[0, 1, -1], [0, 2, 3]], ["triangle 1 refers to node 0, but the file has nodes 1 to 4", "damaged"]),
    (SQUARE * 1e150, [[0, 1, 2], [0, 2, 3]], ["the mesh is 1.41e+150 long", "between 1e-100 and 1e+100",
                                              "another length unit"]),
    (SQUARE * 1e-150, [[0, 1, 2], [0, 2, 3]], ["the mesh is 1.41e-150 long", "another length unit"]),
], ids=["node after the last", "negative node", "too long", "too short"])
def test_damaged_or_out_of_scale_meshes_are_refused(tmp_path, points, triangles, words):
    meshio.write(tmp_path / "mesh.vtu", meshio.Mesh(points, [("triangle", np.array(triangles))]))
    refused(tmp_path, square_case(tmp_path / "mesh.vtu"), "mesh file", "mesh.vtu", *words)


@pytest.mark.parametrize("scale", [1e-90, 1e-12, 1e12, 1e90])
def test_the_checks_do_not_depend_on_the_length_unit(scale):
    """A mesh far from the origin in any unit passes; a fold is found in any unit."""
    p, t = grid(3, 2)
    check_triangles("x", (p.T + 7.0) * scale, t.T, np.arange(len(p)) + 1)
    p[4] = [0.9, 0.6]  # the node at (1/3, 1/2) pulled past its neighbours on the right
    with pytest.raises(CaseError, match="folded"):
        check_triangles("x", (p.T + 7.0) * scale, t.T, np.arange(len(p)) + 1)


@pytest.mark.parametrize("name", BAD_MESHES)
def test_bad_meshes_are_refused_naming_the_place(tmp_path, name):
    points, triangles, words = BAD_MESHES[name]
    path = write_msh(tmp_path / "bad.msh", points, triangles)
    refused(tmp_path, square_case(path), "mesh file", "bad.msh", *words)


@pytest.mark.parametrize("name", BAD_MESHES)
def test_every_triangle_orientation_is_refused_alike(name):
    """skfem forgets the orientation in the file: the checks must not depend on it."""
    points, triangles, words = BAD_MESHES[name]
    if not np.isfinite(points).all():
        pytest.skip("refused before the triangles are looked at")
    flipped = np.array(triangles)
    flipped[::2, [1, 2]] = flipped[::2, [2, 1]]
    for t in (triangles, flipped, np.sort(triangles, axis=1)):
        with pytest.raises(CaseError) as info:
            check_triangles("x.msh", np.asarray(points, dtype=float).T, np.asarray(t).T, np.arange(len(points)) + 1)
        assert words[-1] in str(info.value)


def test_unknown_part_lists_the_parts(tmp_path):
    case = square_case(MESHES / "square.msh")
    case["contact"]["part"] = "botom"
    refused(tmp_path, case, "unknown part 'botom'", "the mesh has parts: 1, 2, 3, 4, bottom, left, right, top")


# --- two bodies, clamped contact parts -----------------------------------------------------------
def test_a_second_body_without_support_is_refused(tmp_path):
    refused(tmp_path, square_case(MESHES / "two_bodies.msh"), "the mesh has 2 separate parts; the Dirichlet conditions "
            "and the contact part leave the translations along x and y and the rotation in the plane of the part of 12 "
            "nodes through the node at (2.375, 0.625) free: hold them with boundary.dirichlet entries on parts of it "
            "that block them, or join it to the rest of the mesh")


def test_two_bodies_each_supported_run(tmp_path):
    case = square_case(MESHES / "two_bodies.msh")
    case["boundary"]["dirichlet"].append({"part": "other_bottom"})
    status, stdout, stderr, out = run_case(tmp_path, case)
    assert status == 0 and stderr == "" and "complete" in stdout, stderr


@pytest.mark.parametrize("dirichlet, motion", [
    ([{"part": "left", "components": ["x"]}], "the translation along y"),
    ([{"part": "bottom", "components": ["x"]}, {"part": "left", "components": ["y"]}], "the rotation about (0, 0)"),
])
def test_a_free_rigid_motion_is_named(tmp_path, dirichlet, motion):
    """x fixed on the line y = 0 and y on the line x = 0 hold both translations but not the rotation about (0, 0)."""
    case = square_case(MESHES / "square.msh", dirichlet)
    del case["contact"]
    refused(tmp_path, case, f"the Dirichlet conditions leave {motion} of the body free: hold it with "
            "boundary.dirichlet entries")


@pytest.mark.parametrize("dirichlet, entry", [
    ([{"part": "bottom"}], "boundary.dirichlet[0] (part 'bottom', components x, y)"),
    ([{"part": "left", "components": ["x"]}, {"part": "bottom", "components": ["y"]}],
     "boundary.dirichlet[1] (part 'bottom', components y)"),
    ([{"part": "bottom", "components": ["x"]}, {"part": "1", "components": ["y"]}],
     "boundary.dirichlet[0] (part 'bottom', components x) and boundary.dirichlet[1] (part '1', components y)"),
])
def test_a_clamped_contact_part_is_refused(tmp_path, dirichlet, entry):
    case = square_case(MESHES / "square.msh", dirichlet)
    refused(tmp_path, case, "contact part 'bottom' is clamped", entry,
            "remove the contact part from boundary.dirichlet")


def test_contact_part_sharing_clamped_corners_runs(tmp_path):
    """The sides clamped in x and y hold the contact part's two end nodes: legitimate."""
    case = square_case(MESHES / "square.msh", [{"part": "left"}, {"part": "right"}])
    status, stdout, stderr, out = run_case(tmp_path, case)
    assert status == 0 and stderr == "" and "complete" in stdout, stderr


def test_contact_part_on_rollers_along_it_runs(tmp_path):
    """The contact part fixed along the foundation (x) still moves along its normal (y)."""
    case = square_case(MESHES / "square.msh", [{"part": "bottom", "components": ["x"]}])
    status, stdout, stderr, out = run_case(tmp_path, case)
    assert status == 0 and stderr == "" and "complete" in stdout, stderr


# --- input files that are not regular files --------------------------------------------------------
@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "pipe"
    os.mkfifo(path)
    return path


def special(kind, tmp_path, fifo):
    """(path, what the refusal calls it) of a FIFO, a device, a directory or a link to a FIFO."""
    (tmp_path / "folder").mkdir()
    (tmp_path / "link").symlink_to(fifo)
    return {"fifo": (fifo, "a FIFO (named pipe)"), "device": (Path("/dev/zero"), "a character device"),
            "directory": (tmp_path / "folder", "a directory"), "link": (tmp_path / "link", "a FIFO (named pipe)")}[kind]


KINDS = ["fifo", "device", "directory", "link"]


@pytest.mark.parametrize("kind", KINDS)
def test_mesh_file_that_is_not_a_regular_file(tmp_path, fifo, kind):
    path, what = special(kind, tmp_path, fifo)
    refused(tmp_path, square_case(path), f"mesh file '{path}' is {what}, not a regular file")


@pytest.mark.parametrize("kind", KINDS)
def test_case_file_that_is_not_a_regular_file(tmp_path, fifo, kind):
    path, what = special(kind, tmp_path, fifo)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", path, "--out", tmp_path / "out", "--quiet", timeout=60)
    assert_refused(status, stderr, f"case file '{path}' is {what}, not a regular file", untouched=[(tmp_path, before)])


@pytest.mark.parametrize("kind", KINDS)
def test_study_file_that_is_not_a_regular_file(tmp_path, fifo, kind):
    path, what = special(kind, tmp_path, fifo)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("study", path, "--out", tmp_path / "study", "--quiet", timeout=60)
    assert_refused(status, stderr, f"study file '{path}' is {what}, not a regular file", untouched=[(tmp_path, before)])


@pytest.mark.parametrize("command", ["run", "study"])
def test_huge_case_or_study_file_is_refused_unread(tmp_path, command):
    path = tmp_path / "huge.toml"
    with open(path, "wb") as handle:  # sparse: 17 MiB of nothing, no disk used
        handle.truncate(17 * 2**20)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli(command, path, "--out", tmp_path / "out", "--quiet")
    kind = "case file" if command == "run" else "study file"
    assert_refused(status, stderr, f"{kind} '{path}' is {17 * 2**20} bytes", "more than the 16777216 bytes",
                   untouched=[(tmp_path, before)])


# --- memory ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("mesh, words", [
    ({"shape": "half_disc", "h": 1e-4}, ["mesh.h = 0.0001 on a half disc of radius 1", "about 3.6e+08 triangles"]),
    ({"shape": "rectangle", "width": 1.0, "height": 2.0, "h": 1e-4}, ["mesh.h = 0.0001 on a 1 x 2 rectangle",
                                                                        "about 4e+08 triangles"]),
])
def test_a_mesh_too_fine_for_the_memory_is_refused_before_it_is_built(tmp_path, mesh, words):
    case = square_case("unused.msh")
    case["mesh"] = mesh
    case["boundary"]["dirichlet"] = [{"part": "axis" if mesh["shape"] == "half_disc" else "left"}]
    del case["contact"], case["boundary"]["traction"]
    stderr = refused(tmp_path, case, *words, "GiB", "of memory available here: use a larger mesh.h")
    needed = float(stderr.split("need about ")[1].split(" GiB")[0])
    assert needed == pytest.approx(float(words[1].split()[1]) * vpcontact.mesh.mesh.BYTES_PER_TRIANGLE / 2**30, rel=0.01)


def test_memory_estimate_refuses_only_what_does_not_fit(monkeypatch):
    """With 3 GiB available: 500k triangles (2 GB estimated) are built, 890k (3.6 GB) refused."""
    monkeypatch.setattr(vpcontact.mesh.mesh, "available_memory", lambda: 3 * 2**30)
    assert rectangle(1.0, 1.0, 0.002).mesh.t.shape[1] == 500_000
    with pytest.raises(CaseError, match=r"mesh.h = 0.0015 on a 1 x 1 rectangle: about 8.9e\+05 triangles, .* need "
                                        r"about 3.31 GiB, more than the 3 GiB of memory available here: use a larger "
                                        r"mesh.h"):
        rectangle(1.0, 1.0, 0.0015)
    with pytest.raises(CaseError, match="about 1.6e.06 triangles"):
        half_disc(0.0015)
    # the paper's example at h = 0.0025 (580k triangles, peak 1.8 GB measured) fits a machine with 3 GiB free
    vpcontact.mesh.mesh.check_memory(0.5 * math.pi / (math.sqrt(3) / 4 * 0.0025**2), "x", "y")


def test_a_mesh_file_too_large_for_the_memory_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(vpcontact.mesh.mesh, "available_memory", lambda: 10_000)
    with pytest.raises(CaseError, match=r"mesh file '.*square.msh': about 14 triangles, .* use a coarser mesh"):
        read_mesh(MESHES / "square.msh")


# --- valid meshes pass ---------------------------------------------------------------------------
@pytest.mark.parametrize("h, R", [(1.0, 1.0), (0.7, 1.0), (0.3, 1.0), (0.1, 2.5), (1 / 16, 1.0), (0.37 / 23, 0.37),
                                  (0.02, 1.0), (1 / 128, 1.0)])
def test_half_discs_pass_every_check(h, R):
    m = half_disc(h, R)
    p, t = m.mesh.p, m.mesh.t
    check_triangles("half disc", p, t, np.arange(p.shape[1]) + 1)
    flipped = t.copy()
    flipped[[1, 2], ::3] = flipped[[2, 1], ::3]
    check_triangles("half disc", p, flipped, np.arange(p.shape[1]) + 1)


@pytest.mark.parametrize("width, height, h", [(1.0, 1.0, 1.0), (2.0, 1.0, 0.3), (1.0, 0.5, 0.125), (1e-6, 3e-6, 1e-7),
                                              (1e3, 1.0, 0.5), (1.0, 1.0, 0.01)])
def test_rectangles_pass_every_check(width, height, h):
    m = rectangle(width, height, h)
    check_triangles("rectangle", m.mesh.p, m.mesh.t, np.arange(m.mesh.p.shape[1]) + 1)


def test_an_annulus_and_a_separate_body_in_its_hole_pass():
    """A hole is not an overlap, and a body inside another's hole is not one either."""
    radius = np.linspace(1.0, 2.0, 5)
    angle = np.linspace(0.0, 2 * np.pi, 41)[:-1]
    R, A = np.meshgrid(radius, angle, indexing="ij")
    points = np.column_stack(((R * np.cos(A)).ravel(), (R * np.sin(A)).ravel()))
    index = np.arange(points.shape[0]).reshape(R.shape)
    nxt = np.roll(index, -1, axis=1)
    a, b, c, d = index[:-1].ravel(), index[1:].ravel(), nxt[1:].ravel(), nxt[:-1].ravel()
    triangles = np.vstack((np.column_stack((a, b, c)), np.column_stack((a, c, d))))
    plug, plug_t = grid(2, 2, -0.5, -0.5, first=len(points))
    points, triangles = np.vstack((points, plug)), np.vstack((triangles, plug_t))
    check_triangles("annulus", points.T, triangles.T, np.arange(len(points)) + 1)


@pytest.mark.parametrize("name", ["square", "square_msh22", "two_bodies", "no_physical_groups"])
def test_valid_gmsh_files_are_read(name):
    m = read_mesh(MESHES / f"{name}.msh")
    assert np.abs(m.mesh.p).max() <= 3.0 and m.mesh.t.shape[1] in (14, 28)


@pytest.mark.parametrize("file_format", ["gmsh", "gmsh22"])
def test_binary_gmsh_files_keep_their_physical_names(tmp_path, file_format):
    """The physical names are read from the file's head, also when the rest is binary."""
    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):
        meshio.write(tmp_path / "binary.msh", meshio.read(MESHES / "square.msh"), file_format=file_format, binary=True)
    assert b"\0" in (tmp_path / "binary.msh").read_bytes()
    m = read_mesh(tmp_path / "binary.msh")
    assert m.part_names == ["1", "2", "3", "4", "bottom", "left", "right", "top"]


def test_a_curve_and_a_surface_may_share_a_name(tmp_path):
    """gmsh names physical groups per dimension; the part is the curve."""
    text = (MESHES / "square_msh22.msh").read_text().replace('2 5 "body"', '2 5 "bottom"')
    (tmp_path / "named.msh").write_text(text)
    m = read_mesh(tmp_path / "named.msh")
    np.testing.assert_array_equal(m.facets("bottom"), m.facets(1))


@pytest.mark.parametrize("name", ["shared_curves", "shared_curves_msh22"])
def test_a_curve_in_two_named_groups_belongs_to_both(name):
    """msh 4.1 lists a curve's physical groups once (meshio's cell data keeps only the first): the
    bottom curve is in "corner" (declared first) and in "contact" = bottom + right."""
    m = read_mesh(MESHES / f"{name}.msh")
    p = m.mesh.p
    ends = lambda part: p[:, m.mesh.facets[:, m.facets(part)]]  # noqa: E731
    assert m.facets("contact").size == 4 and m.facets("corner").size == 2
    assert np.all(ends("corner")[1] == 0.0)
    on_bottom, on_right = ends("contact")[1] == 0.0, ends("contact")[0] == 1.0
    assert np.all(on_bottom.all(axis=0) | on_right.all(axis=0)) and on_bottom.all(axis=0).sum() == 2
    np.testing.assert_array_equal(m.facets("contact"), m.facets(2))
