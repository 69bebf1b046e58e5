"""Meshes from memory: one geometry made in gmsh (SI units: a 20 mm × 5 mm block, its bottom the contact part and
its top clamped) given as a mesh file, as the open gmsh model, as the meshio.Mesh meshio reads from the file and
as a scikit-fem mesh with the same named boundaries is one Mesh (the same arrays, parts and regions) and one run,
bit for bit; a bad mesh in memory is refused in the one line a mesh file gets."""

import signal
import sys

import meshio
import numpy as np
import pytest
import skfem

import vpcontact
from vpcontact import mesh as meshes
from vpcontact.errors import CaseError

try:
    import gmsh
except (ImportError, OSError):  # gmsh's module (in the test extra) or its system libraries missing: only the tests
    # that make gmsh models skip
    gmsh = None

needs_gmsh = pytest.mark.skipif(gmsh is None, reason="gmsh's Python module is not installed (pip install gmsh)")

WIDTH, HEIGHT = 0.02, 0.005  # m


@pytest.fixture
def model():
    """An open gmsh session (closed after the test). Not interruptible: gmsh's default replaces Python's SIGINT
    handler for good (finalize does not restore it), and the tests run after this one in the same process would
    die of a Ctrl-C they send to themselves instead of raising KeyboardInterrupt."""
    handler = signal.getsignal(signal.SIGINT)
    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    yield gmsh
    gmsh.finalize()
    assert signal.getsignal(signal.SIGINT) is handler, "gmsh replaced the SIGINT handler of the test process"


def block(dim: int = 2, size: float = 0.002) -> None:
    """The block in the open gmsh session, meshed: physical groups "contact" (bottom, y = 0 or z = 0), "clamped"
    (top) and "body"."""
    gmsh.model.add(f"block{dim}d")
    if dim == 2:
        body = gmsh.model.occ.addRectangle(0, 0, 0, WIDTH, HEIGHT)
    else:
        body = gmsh.model.occ.addBox(0, 0, 0, WIDTH, HEIGHT, HEIGHT)
    gmsh.model.occ.synchronize()
    facets = [tag for _, tag in gmsh.model.getBoundary([(dim, body)], oriented=False)]
    height = [gmsh.model.occ.getCenterOfMass(dim - 1, tag)[dim - 1] for tag in facets]
    gmsh.model.addPhysicalGroup(dim - 1, [f for f, z in zip(facets, height) if z < 1e-12], name="contact")
    gmsh.model.addPhysicalGroup(dim - 1, [f for f, z in zip(facets, height) if z > HEIGHT - 1e-12], name="clamped")
    gmsh.model.addPhysicalGroup(dim, [body], name="body")
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.model.mesh.generate(dim)


def saved(tmp_path, name: str = "block.msh", binary: bool = True) -> str:
    """The open model saved as gmsh saves it (format 4.1; binary: the coordinates as they are)."""
    gmsh.option.setNumber("Mesh.Binary", int(binary))
    path = str(tmp_path / name)
    gmsh.write(path)
    return path


def four_ways(tmp_path, dim: int = 2):
    """The block as (a) a mesh file, (b) the open gmsh model, (c) meshio's reading of the file, (d) a scikit-fem
    mesh of the file's nodes and elements whose boundaries are named by where they are (with_boundaries)."""
    path = saved(tmp_path)
    read = meshio.read(path)
    kind = {2: ("triangle", skfem.MeshTri), 3: ("tetra", skfem.MeshTet)}[dim]
    elements = np.vstack([block.data for block in read.cells if block.type == kind[0]]).T
    used = np.unique(elements)
    renumber = np.full(len(read.points), -1)
    renumber[used] = np.arange(used.size)
    named = kind[1](read.points[used, :dim].T.copy(), renumber[elements]).with_boundaries({
        "contact": lambda x: x[dim - 1] < 1e-12, "clamped": lambda x: x[dim - 1] > HEIGHT - 1e-12})
    return {"file": path, "gmsh model": gmsh, "meshio.Mesh": read, "scikit-fem mesh": named}


def the_mesh(source) -> meshes.Mesh:
    """The Mesh compose makes of `source` (the problem's mesh)."""
    return vpcontact.compose(source, **arguments(time={"T": 1.0, "steps": 1})).mesh


def arguments(**changes) -> dict:
    """The block clamped at its top, pulled down by its weight (a body force, N/m³) onto a layer under its bottom
    (K in Pa/m): a short run."""
    return {"material": {"E": 1e9, "nu": 0.3}, "dirichlet": {"clamped": None}, "body_force": ["0", "-8e7*t"],
            "contact": {"part": "contact", "g": 1e-4, "probe": [0.01, 0.0],
                        "stiffness": {"law": "power", "c_v": 1e12, "alpha": 1e3, "beta": 1.0}},
            "time": {"T": 1.0, "steps": 3}, **changes}


@needs_gmsh
def test_a_mesh_file_the_gmsh_model_meshio_and_scikit_fem_give_one_mesh(model, tmp_path):
    """The same nodes and elements (array for array), the same facets in each named part; the file, the model and
    meshio's reading also the same numbered groups and the region "body"."""
    block()
    ways = four_ways(tmp_path)
    file = the_mesh(ways["file"])
    assert file.part_names == ["1", "2", "clamped", "contact"] and sorted(file.regions) == ["3", "body"]
    assert file.parts["contact"].size == WIDTH / 0.002 and file.mesh.t.shape[1] > 50
    for way, source in ways.items():
        mesh = the_mesh(source)
        np.testing.assert_array_equal(mesh.mesh.p, file.mesh.p, err_msg=way)
        np.testing.assert_array_equal(mesh.mesh.t, file.mesh.t, err_msg=way)
        expected = ["contact", "clamped"] if way == "scikit-fem mesh" else file.part_names
        assert sorted(mesh.parts) == sorted(expected), way
        for name in expected:
            np.testing.assert_array_equal(mesh.parts[name], file.parts[name], err_msg=f"{way}: {name}")
            np.testing.assert_array_equal(mesh.mesh.boundaries[name], file.mesh.boundaries[name])
        if way != "scikit-fem mesh":
            assert {name: list(members) for name, members in mesh.regions.items()} == \
                {name: list(members) for name, members in file.regions.items()}
        assert mesh.file == (ways["file"] if way == "file" else None)


@needs_gmsh
def test_a_text_file_rounds_the_coordinates_that_the_model_holds_exactly(model, tmp_path):
    """gmsh's text files write 16 significant digits: the file's nodes are the model's to rounding (1e-16 of the
    size here), its elements and parts the same; the binary file, the model's exact coordinates."""
    block()
    text, binary, live = (meshes.read_mesh(saved(tmp_path, "text.msh", binary=False)),
                          meshes.read_mesh(saved(tmp_path)), meshes.from_gmsh())
    np.testing.assert_array_equal(binary.mesh.p, live.mesh.p)
    np.testing.assert_allclose(text.mesh.p, live.mesh.p, rtol=0, atol=1e-15 * WIDTH)
    np.testing.assert_array_equal(text.mesh.t, live.mesh.t)
    np.testing.assert_array_equal(text.parts["contact"], live.parts["contact"])


@needs_gmsh
def test_a_mesh_file_the_gmsh_model_meshio_and_scikit_fem_give_one_run(model, tmp_path):
    """The same short run on the four, bit for bit: displacements, stresses, the layer's history K(ξ), the contact
    force."""
    block()
    runs = {way: vpcontact.solve(vpcontact.compose(source, **arguments())) for way, source in four_ways(tmp_path).items()}
    reference = runs["file"]
    assert reference.status == "complete" and reference.final.displacement.min() < -1e-7  # pressed into the layer
    assert reference.series("K_probe")[-1] > reference.series("K_probe")[0] > 1e12  # the layer hardened
    for way, run in runs.items():
        np.testing.assert_array_equal(run.final.displacement, reference.final.displacement, err_msg=way)
        np.testing.assert_array_equal(run.final.stress, reference.final.stress, err_msg=way)
        for column in ("K_probe", "contact_force_y", "max_penetration"):
            np.testing.assert_array_equal(run.series(column), reference.series(column), err_msg=f"{way}: {column}")


@needs_gmsh
def test_a_3d_gmsh_model_is_its_file(model, tmp_path):
    """A box of tetrahedra: the open model, meshio's reading and a scikit-fem MeshTet with named boundaries are
    the file's mesh (triangles of physical surfaces as parts)."""
    block(dim=3, size=0.004)
    ways = four_ways(tmp_path, dim=3)
    file = meshes.read_mesh(ways["file"])
    assert file.dim == 3 and file.parts["contact"].size >= 2 * 5
    for way, mesh in {"gmsh model": meshes.from_gmsh(), "meshio.Mesh": meshes.from_meshio(ways["meshio.Mesh"]),
                      "scikit-fem mesh": meshes.from_skfem(ways["scikit-fem mesh"])}.items():
        np.testing.assert_array_equal(mesh.mesh.p, file.mesh.p, err_msg=way)
        np.testing.assert_array_equal(mesh.mesh.t, file.mesh.t, err_msg=way)
        for name in ("contact", "clamped"):
            np.testing.assert_array_equal(mesh.parts[name], file.parts[name], err_msg=f"{way}: {name}")


@needs_gmsh
def test_scikit_fem_subdomains_are_regions_and_its_own_reader_agrees(tmp_path, model):
    """scikit-fem's reading of the file (its boundaries and subdomains from the physical groups, without meshio's
    bookkeeping set "gmsh:bounding_entities") is the file's mesh; its subdomains are the regions."""
    block()
    path = saved(tmp_path)
    file, loaded = meshes.read_mesh(path), meshes.from_skfem(skfem.MeshTri.load(path))
    np.testing.assert_array_equal(loaded.mesh.t, file.mesh.t)
    assert sorted(loaded.parts) == ["clamped", "contact"] and list(loaded.regions) == ["body"]
    np.testing.assert_array_equal(loaded.regions["body"], np.arange(file.mesh.t.shape[1]))


def refusal(source, **changes) -> str:
    """compose's one-line refusal of `source`."""
    with pytest.raises(CaseError) as refused:
        vpcontact.compose(source, **arguments(**changes))
    message = str(refused.value)
    assert "\n" not in message and "Traceback" not in message
    return message


SQUARE = np.array([[0.0, 0.0], [0.01, 0.0], [0.01, 0.01], [0.0, 0.01], [0.005, 0.005]])


def test_a_bad_mesh_in_memory_is_refused_in_one_line():
    """A zero-area triangle, a fold, a mesh without the part the problem names: refused before anything is
    assembled, naming the mesh, the element and its nodes (by Python's indices for meshio and scikit-fem)."""
    flat = np.array([[0, 1, 2], [0, 2, 3], [0, 1, 4]])
    points = SQUARE.copy()
    points[4] = [0.005, 0.0]  # node 4 on the bottom edge: triangle (0, 1, 4) has zero area
    message = refusal(meshio.Mesh(points, [("triangle", flat)]))
    assert message.startswith("the meshio.Mesh: triangle 2 (nodes 0, 1, 4) has zero area"), message

    square = skfem.MeshTri(SQUARE.T.copy(), np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]).T)
    folded = skfem.MeshTri(np.column_stack((square.p[:, :4], [0.02, 0.005])), square.t)  # the middle node outside
    message = refusal(folded.with_boundaries({"contact": lambda x: x[1] < 1e-12}))
    assert message.startswith("the scikit-fem MeshTri1: ") and "lie on the same side of" in message, message

    named = square.with_boundaries({"bottom": lambda x: x[1] < 1e-12, "top": lambda x: x[1] > 0.01 - 1e-12})
    assert refusal(named) == "unknown part 'clamped'; the mesh has parts: bottom, top"
    assert "without named boundaries" in refusal(square) and "with_boundaries" in refusal(square)
    assert refusal(skfem.MeshQuad()).startswith("mesh = a scikit-fem MeshQuad1: vpcontact uses linear triangles")
    empty = square.with_boundaries({"contact": lambda x: x[1] < -1.0})
    assert refusal(empty) == "mesh.boundaries['contact'] has no facets: remove it, or give its facets"


@needs_gmsh
def test_a_bad_gmsh_model_is_refused_as_its_file(model, tmp_path):
    """A gmsh model with a zero-area triangle (a discrete surface) gets the refusal of the file gmsh saves of it,
    naming the model instead of the file; a model of quadrilaterals, not meshed, or no gmsh session: one line
    with the fix."""
    gmsh.model.add("flat")
    surface = gmsh.model.addDiscreteEntity(2)
    corners = np.vstack((SQUARE[:4], [0.005, 0.0]))  # node 5 on the bottom edge
    gmsh.model.mesh.addNodes(2, surface, [1, 2, 3, 4, 5], np.column_stack((corners, np.zeros(5))).ravel().tolist())
    gmsh.model.mesh.addElementsByType(surface, 2, [], [1, 2, 3, 1, 3, 4, 1, 2, 5])
    gmsh.model.addPhysicalGroup(2, [surface], name="body")
    from_model = refusal(gmsh)
    path = saved(tmp_path, "flat.msh", binary=False)
    assert from_model == refusal(path).replace(f"mesh file '{path}'", "the gmsh model 'flat'")
    assert from_model.startswith("the gmsh model 'flat': triangle 3 (nodes 1, 2, 5) has zero area"), from_model

    gmsh.model.add("quads")
    gmsh.model.occ.addRectangle(0, 0, 0, WIDTH, HEIGHT)
    gmsh.model.occ.synchronize()
    assert refusal(gmsh) == "the gmsh model 'quads' has no mesh: gmsh.model.mesh.generate(2) (a plane body) or " \
                            "generate(3) first"
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.model.mesh.generate(2)
    assert refusal(gmsh).startswith("the gmsh model 'quads' has ") and "quadrilaterals" in refusal(gmsh)
    gmsh.finalize()
    assert refusal(gmsh).startswith("mesh = the gmsh model: gmsh is not initialized: gmsh.initialize()")
    gmsh.initialize(interruptible=False)  # for the fixture's finalize


def test_a_meshio_mesh_made_in_python_has_its_cell_sets_as_parts_and_regions():
    """Cell sets that no field_data entry numbers (a meshio.Mesh made in Python): the sets of lines are parts, the
    sets of triangles regions, keyed by name only; a line inside the body is refused naming its set."""
    triangles = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    lines = np.array([[0, 1], [2, 3], [0, 4]])
    made = meshio.Mesh(SQUARE, [("triangle", triangles), ("line", lines[:2])],
                       cell_sets={"bottom": [None, np.array([0])], "top": [np.zeros(0, int), np.array([1])],
                                  "left_half": [np.array([2, 3]), None]})
    mesh = meshes.from_meshio(made)
    assert sorted(mesh.parts) == ["bottom", "top"] and list(mesh.regions) == ["left_half"]
    np.testing.assert_array_equal(mesh.mesh.facets[:, mesh.parts["bottom"]].ravel(), [0, 1])
    np.testing.assert_array_equal(mesh.mesh.facets[:, mesh.parts["top"]].ravel(), [2, 3])
    np.testing.assert_array_equal(mesh.regions["left_half"], [2, 3])
    inner = meshio.Mesh(SQUARE, [("triangle", triangles), ("line", lines[2:])], cell_sets={"inner": [None, [0]]})
    with pytest.raises(CaseError, match=r"^the meshio.Mesh: line of group 'inner' is not a boundary edge"):
        meshes.from_meshio(inner)
    beyond = meshio.Mesh(SQUARE, [("triangle", triangles), ("line", lines[:2])], cell_sets={"top": [None, [2]]})
    with pytest.raises(CaseError, match=r"^the meshio.Mesh: cell_sets\['top'\] = array\(\[2\]\) for its 2 line cells: "
                                        r"expected indices of those cells, 0 to 1$"):
        meshes.from_meshio(beyond)


def test_from_gmsh_without_gmsh_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "gmsh", None)  # import gmsh raises ImportError
    with pytest.raises(CaseError, match=r"^mesh = the gmsh model: gmsh's Python module is not installed \(pip install "
                                        r"gmsh\)$"):
        meshes.from_gmsh()
