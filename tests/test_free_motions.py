"""A body whose rigid motions the Dirichlet conditions and the contact leave free is refused naming those
motions in words (vpcontact.problem.free_motions) and how to hold them: through the command line (exit 2, one
line, nothing written) and through compose (a CaseError with the same line)."""

import numpy as np
import pytest

import vpcontact
from vpcontact import mesh as meshes
from vpcontact.problem.free_motions import free_motions_in_words

from conftest import assert_refused, run_cli, snapshot_tree

FIX = ("boundary.dirichlet entries on parts that block", "e.g. rollers on the symmetry planes of a half or quarter "
       "model")


def rectangle(dirichlet=(), normal=(0, -1)) -> dict:
    """The rectangle [0, 1] × [0, 0.5] pressed on a flat foundation under its bottom."""
    case = {"mesh": {"shape": "rectangle", "width": 1.0, "height": 0.5, "h": 0.25},
            "material": {"E": 1000.0, "nu": 0.3},
            "boundary": {"dirichlet": list(dirichlet), "traction": [{"part": "top", "value": ["0", "-100*t"]}]},
            "contact": {"part": "bottom", "g": 0.2, "stiffness": {"law": "constant", "value": 100.0}},
            "time": {"T": 1.0, "steps": 1}}
    if normal is not None:
        case["contact"]["normal"] = list(normal)
    return case


def block(dirichlet=(), normal=(0, 0, -1)) -> dict:
    """The block [0, 1] × [0, 1] × [0, 0.5] (a full model, no symmetry planes) pressed on a foundation."""
    case = {"mesh": {"shape": "block", "h": 0.5, "width": 1.0, "depth": 1.0, "height": 0.5},
            "material": {"E": 1000.0, "nu": 0.3},
            "boundary": {"dirichlet": list(dirichlet), "traction": [{"part": "top", "value": ["0", "0", "-30*t"]}]},
            "contact": {"part": "bottom", "g": 0.05, "stiffness": {"law": "constant", "value": 100.0}},
            "time": {"T": 1.0, "steps": 1}}
    if normal is not None:
        case["contact"]["normal"] = list(normal)
    return case


def without_contact(case: dict) -> dict:
    del case["contact"]
    return case


CASES = {
    # 2D: a flat foundation holds y and the rotation (its nodes spread along x): x is free
    "2D, flat foundation": (rectangle(), "leave the translation along x of the body free: hold it with"),
    # the body's own normals of a flat bottom are the foundation's
    "2D, the body's normals": (rectangle(normal=None), "leave the translation along x of the body free"),
    # a tilted foundation holds the motion along its normal (0.6, -0.8) only
    "2D, tilted foundation": (rectangle(normal=(0.6, -0.8)), "leave the translation along (0.8, 0.6) of the body"),
    # x held on the line y = 0: the rotation about a point of that line is free, named at the centroid's x
    "2D, x held on the bottom": (without_contact(rectangle([{"part": "bottom", "components": ["x"]}])),
                                 "the Dirichlet conditions leave the translation along y and the rotation about "
                                 "(0.5, 0) of the body free: hold them with"),
    "2D, nothing": (without_contact(rectangle()), "the Dirichlet conditions leave the translations along x and y "
                                                  "and the rotation in the plane of the body free"),
    # 3D: frictionless contact on a flat foundation leaves x, y and the rotation about any vertical axis
    "3D, flat foundation": (block(), "the Dirichlet conditions and the contact part leave the translations along x "
                                     "and y and the rotation about z of the body free: hold them with"),
    "3D, x held on the left": (block([{"part": "left", "components": ["x"]}]),
                               "leave the translation along y of the body free: hold it with"),
    # a tilted foundation: the translations across its normal and the rotation about it
    "3D, tilted foundation": (block(normal=(0, 0.6, -0.8)), "leave the translations in the plane normal to "
                              "(0, -0.6, 0.8) and the rotation about the axis along (0, -0.6, 0.8) of the body free"),
    # y and z held on the plane x = 0: the rotations about lines of that plane, named through the point nearest
    # to the centroid (0.5, 0.5, 0.25)
    "3D, y and z held on the left": (without_contact(block([{"part": "left", "components": ["y", "z"]}])),
                                     "the Dirichlet conditions leave the translation along x, the rotation about the "
                                     "axis through (0, 0.5, 0.25) along y and the rotation about the axis through "
                                     "(0, 0.5, 0.25) along z of the body free"),
}


@pytest.mark.parametrize("name", CASES)
def test_the_command_line_names_the_free_motions(tmp_path, name):
    import tomli_w

    case, words = CASES[name]
    path = tmp_path / "case.toml"
    path.write_bytes(tomli_w.dumps(case).encode())
    before = snapshot_tree(tmp_path)
    status, stdout, stderr = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert_refused(status, stderr, words, *FIX, untouched=[(tmp_path, before)])
    assert stdout == "" and not (tmp_path / "out").exists()


def test_compose_names_the_free_motions_of_a_full_block():
    """The full block through compose: the same line as a CaseError."""
    with pytest.raises(vpcontact.CaseError) as error:
        vpcontact.compose(meshes.block(1.0, 1.0, 0.5, 0.5), {"E": 1000.0, "nu": 0.3},
                          traction={"top": ["0", "0", "-30*t"]}, time={"T": 1.0, "steps": 1},
                          contact={"part": "bottom", "g": 0.05, "normal": [0, 0, -1],
                                   "stiffness": {"law": "constant", "value": 100.0}})
    assert str(error.value) == (
        "the Dirichlet conditions and the contact part leave the translations along x and y and the rotation about z "
        "of the body free: hold them with boundary.dirichlet entries on parts that block them (holding a component "
        "on a part blocks the translation along it; a rotation needs a part held off its axis in the direction it "
        "turns there), e.g. rollers on the symmetry planes of a half or quarter model, or with boundary.point entries "
        "that hold components at single nodes (a full model: the translations at one point, the rotation at a second "
        "one off its axis)")


def test_compose_names_the_translation_of_a_rectangle():
    with pytest.raises(vpcontact.CaseError, match="leave the translation along x of the body free: hold it with"):
        vpcontact.compose(meshes.rectangle(1.0, 0.5, 0.25), {"E": 1000.0, "nu": 0.3},
                          traction={"top": ["0", "-100*t"]}, time={"T": 1.0, "steps": 1},
                          contact={"part": "bottom", "g": 0.2, "normal": [0, -1],
                                   "stiffness": {"law": "constant", "value": 100.0}})


def test_holding_what_was_named_runs():
    """The fix the refusal of the full block suggests: x held on the left and y on the front (both off the
    vertical axes through the block) hold the three motions; the run completes."""
    case = block([{"part": "left", "components": ["x"]}, {"part": "front", "components": ["y"]}])
    assert vpcontact.solve(vpcontact.load_case(case)).status == "complete"


@pytest.mark.parametrize("free, words", [
    # a rotation about z with 0.5 along z per radian (modes about the centroid (1, 2, 3), size 2)
    ([[0, 0, 0.5, 2, 0, 0]], "the screw motion about the axis through (1, 2, 3) along z, advancing 0.5 per radian"),
    # a rotation about z, not about the centroid: u = ω e_z × (x − p) with p = (1, 2, 3) + (0, 1, 0)
    ([[1, 0, 0, 2, 0, 0]], "the rotation about the axis through (1, 3, 3) along z"),
    # the same with the translation along x free too: the axis may be anywhere on the plane x = 1, named
    # through the centroid
    ([[1, 0, 0, 2, 0, 0], [1, 0, 0, 0, 0, 0]], "the translation along x and the rotation about the axis through "
                                                "(1, 2, 3) along z"),
    # the translations along y and z: any rotation about x then is free about any axis
    ([[0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0], [0, 1, 2, 0, 1, 0]], "the translations along y and z and the rotation "
                                                                    "about x"),
])
def test_free_motions_in_words(free, words):
    """Free subspaces given by hand, on the modes of a body of centroid (1, 2, 3) and size 2 (translations,
    then the rotations in the planes xy, yz, zx scaled by 1/size: a coefficient 2 turns by 1 radian)."""
    basis, _ = np.linalg.qr(np.array(free, dtype=float).T)
    assert free_motions_in_words(basis, np.array([1.0, 2.0, 3.0]), 2.0) == words
