"""gmsh 2.2 text files read with NumPy (vpcontact.mesh.gmsh.read_msh22): what meshio reads from them, array for
array, for every 2.2 file of the tests (gmsh's own and meshio's); the files it leaves to meshio; and a mesh file
read either way gives the same Mesh."""

from pathlib import Path

import meshio
import numpy as np
import pytest

from vpcontact.mesh import gmsh
from vpcontact.mesh import half_disc, read_mesh
from vpcontact.mesh.gmsh import write_mesh

MESHES = Path(__file__).parent / "meshes"
TEXT_22 = sorted(path for path in [*MESHES.glob("*.msh"), *MESHES.glob("3d/*.msh")]
                 if path.read_bytes().split(b"\n")[1].startswith(b"2.2 0"))


def assert_as_meshio_reads(path):
    mine, theirs = gmsh.read_msh22(path), meshio.read(path)
    assert mine is not None
    assert np.array_equal(mine.points, theirs.points, equal_nan=True)
    assert [(block.type, block.dim) for block in mine.cells] == [(block.type, block.dim) for block in theirs.cells]
    for block, their in zip(mine.cells, theirs.cells):
        assert np.array_equal(block.data, their.data)
    assert mine.cell_data.keys() == theirs.cell_data.keys()
    for name, arrays in theirs.cell_data.items():
        assert len(mine.cell_data[name]) == len(arrays)
        for array, their in zip(mine.cell_data[name], arrays):
            assert np.array_equal(array, their) and array.dtype == their.dtype
    assert {k: v.tolist() for k, v in mine.field_data.items()} == {k: v.tolist() for k, v in theirs.field_data.items()}
    assert not theirs.cell_sets


def test_the_gmsh_2_2_text_files_of_the_tests_read_as_meshio_reads_them():
    assert len(TEXT_22) >= 10
    for path in TEXT_22:
        assert_as_meshio_reads(path)


def test_a_written_mesh_reads_back_the_same_either_way(tmp_path):
    """write_mesh's file of the half disc (nodes not in element order, three parts): the same Mesh from
    the NumPy reader and from meshio."""
    write_mesh(half_disc(0.1), tmp_path / "disc.msh")
    assert_as_meshio_reads(tmp_path / "disc.msh")
    fast = read_mesh(tmp_path / "disc.msh")
    meshio.write(tmp_path / "binary.msh", meshio.read(tmp_path / "disc.msh"), file_format="gmsh22", binary=True)
    assert gmsh.read_msh22(tmp_path / "binary.msh") is None  # read by meshio
    slow = read_mesh(tmp_path / "binary.msh")
    assert np.array_equal(fast.mesh.p, slow.mesh.p) and np.array_equal(fast.mesh.t, slow.mesh.t)
    assert fast.parts.keys() == slow.parts.keys()
    assert all(np.array_equal(fast.parts[name], slow.parts[name]) for name in fast.parts)


def renumbered(text: str) -> str:
    """A 2.2 file with its node numbers doubled (gaps in the numbering) and its nodes listed backwards."""
    head, rest = text.split("$Nodes\n")
    nodes, rest = rest.split("$EndNodes\n")
    count, *rows = nodes.strip().split("\n")
    rows = [f"{2 * int(row.split()[0])} {row.split(' ', 1)[1]}" for row in rows][::-1]
    elements, tail = rest.split("$Elements\n")[1].split("$EndElements")
    count_e, *cells = elements.strip().split("\n")
    cells = [" ".join(cell.split()[:5] + [str(2 * int(n)) for n in cell.split()[5:]]) for cell in cells]
    return (head + "$Nodes\n" + count + "\n" + "\n".join(rows) + "\n$EndNodes\n$Elements\n" + count_e + "\n" +
            "\n".join(cells) + "\n$EndElements" + tail)


def test_node_numbers_with_gaps_in_any_order(tmp_path):
    (tmp_path / "gaps.msh").write_text(renumbered((MESHES / "square_msh22.msh").read_text()))
    assert_as_meshio_reads(tmp_path / "gaps.msh")


@pytest.mark.parametrize("change", [
    lambda text: text.replace("2.2 0 8", "2.2 1 8"),  # binary
    lambda text: text.replace("$MeshFormat\n2.2", "$MeshFormat\n4.1"),
    lambda text: text.replace(" 2 2 ", " 9 2 ", 1),  # a second-order triangle
    lambda text: text.replace(" 1 2 ", " 1 3 ", 1),  # three tags
    lambda text: text.replace("\n12\n1 0 0 0", "\n13\n1 0 0 0", 1),  # a node missing
    lambda text: text.replace("\n2 1 0 0\n", "\n1 1 0 0\n", 1),  # a node number twice
    lambda text: text.replace("\n2 1 0 0\n", "\n2 1 x 0\n", 1),  # not a number
    lambda text: text.replace("$EndElements", "1 2 2 0 1 1 2 99\n$EndElements"),  # no node 99, count off
    lambda text: text.replace("$EndNodes", ""),
    lambda text: text.replace("22 2 2 5 1 7 9 11\n$EndElements", "22\n$EndElements"),  # a row of one number
    lambda text: text.replace("\n12\n1 0 0 0\n", "\n12\n100000 0 0 0\n", 1),  # numbers far apart
])
def test_what_is_not_a_plain_2_2_text_file_is_left_to_meshio(tmp_path, change):
    text = (MESHES / "square_msh22.msh").read_text()
    assert change(text) != text
    (tmp_path / "odd.msh").write_text(change(text))
    assert gmsh.read_msh22(tmp_path / "odd.msh") is None
