"""A battery of bad inputs, by family: every one is refused on one line that names the bad key or value (exit
status 2 through the command line, a CaseError through the API), with no traceback, no warning and nothing
left in --out; NumPy numbers and arrays are accepted wherever Python numbers and lists are; and no warning
reaches a user on a correct run.

The families: a case's keys and values (unknown, of the wrong type, out of range, not finite, empty, huge,
values the run would not use), expressions, ``--set`` syntax, mesh files, ``--out`` paths, the files of
``initial.from_run``, and the Python API (``compose``'s arguments, ``Mesh`` arrays, NumPy values, Python laws
and loads, the tables of ``vpcontact.solve`` and ``vpcontact.adapt``, ``Result.write``). The command line is
called in this process (``vpcontact.cli.main``): a subprocess costs a second each, and the exit status, the
one line on stderr and the files are the same (tests/test_bad_input.py, test_robustness.py run the CLI in
subprocesses)."""

import copy
import os
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
import skfem
import tomli_w

import vpcontact
from vpcontact import mesh as meshes
from vpcontact.cli import main
from vpcontact.case.translate import output_options
from vpcontact.errors import CaseError
from vpcontact.timeloop.loop import TimeLoop, solve_problem

from conftest import block_3d_case, half_disc_case, rectangle_case, snapshot_tree

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


# --- helpers -------------------------------------------------------------------------------------------
def one_line(message: str, *words: str) -> None:
    """``message`` is one line, no traceback, and names each of ``words``."""
    assert "\n" not in message and "Traceback" not in message and len(message) < 1000, message
    for word in words:
        assert word in message, (word, message)


def refused_by_cli(tmp_path, capsys, case, *arguments: str, words=(), out=None) -> str:
    """``vpcontact run`` of ``case`` (a dict, written as TOML, or a path) with ``arguments`` (--set ...): exit
    status 2, one line ``vpcontact: error: ...`` naming ``words`` on stderr, nothing on stdout, and nothing
    made at --out (nor changed where it exists). The message."""
    if isinstance(case, dict):
        path = tmp_path / "case.toml"
        path.write_text(tomli_w.dumps(case))
    else:
        path = case
    out = tmp_path / "out" if out is None else out
    before = snapshot_tree(out) if os.path.lexists(out) else None  # (lexists: False for a name too long)
    status = main(["run", str(path), "--out", str(out), "--quiet", *arguments])
    captured = capsys.readouterr()
    assert status == 2, (status, captured.err)
    assert captured.err.startswith("vpcontact: error: ") and captured.err.count("\n") == 1, captured.err
    assert "Warning" not in captured.err and not captured.out, captured
    one_line(captured.err.rstrip("\n"), *words)
    assert (snapshot_tree(out) if os.path.lexists(out) else None) == before, f"{out} changed"
    return captured.err


def refused_by_api(call, *words: str) -> str:
    """``call()`` raises a CaseError whose message is one line naming ``words`` (and no warning)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(CaseError) as caught:
            call()
    message = str(caught.value)
    one_line(message, *words)
    return message


def sets(*pairs: str) -> list[str]:
    return [argument for pair in pairs for argument in ("--set", pair)]


def composed(h=0.25, **changes):
    """The half disc of conftest.half_disc_case, composed in Python (``changes`` replace arguments)."""
    arguments = dict(
        material={"E": 1000.0, "nu": 0.3},
        dirichlet={"axis": "x"},
        traction={"top_arc": ["0", "-20.0*t"]},
        contact={"part": "bottom_arc", "g": 0.2, "probe": [0.0, 0.0],
                 "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
        time={"T": 1.1, "steps": 11},
        solver={"tolerance": 1e-12},
    )
    arguments.update(changes)
    mesh = arguments.pop("mesh", None) or meshes.half_disc(h)
    return vpcontact.compose(mesh, **arguments)


# --- 1. a case's keys and values, through --set ---------------------------------------------------------
#: (overrides of half_disc_case(h=0.25), words the message names); none of tests/test_bad_input.py's
KEYS_AND_VALUES = [
    # unknown keys, or keys the case would not use
    (["material.young=1000"], ["unknown key 'material.young'"]),
    (["contact.stiffness.gamma=1"], ["unknown key 'contact.stiffness.gamma'"]),
    (['contact.stiffness={law="constant", value=1, c_v=2}'], ["unknown key 'contact.stiffness.c_v'", "law, value"]),
    (["time.dt=0.1"], ["unknown key 'time.dt'"]),
    (["output.fields=1"], ["unknown key 'output.fields'", "did you mean"]),
    (["boundary.dirichlet[0].value=1"], ["boundary.dirichlet[0].value = 1", "expected a list"]),
    (['boundary.body_force=[{value=["0", "-1"], part="top_arc"}]'], ["unknown key 'boundary.body_force[0].part'"]),
    (["mesh.h_bottom=0.1"], ["mesh.h_bottom is only used with mesh.shape = \"quarter_ball\""]),
    (["contact.exponent=2"], ["contact.exponent is only used with contact.p = \"power\""]),
    (['solver.method="iterative"', 'solver.factorization="superlu"'],
     ['solver.factorization = "superlu" is not used by solver.method = "iterative"']),
    (['solver.method="full"', 'solver.multigrid="pyamg"'],
     ['solver.multigrid = "pyamg" is not used by solver.method = "full"', 'choose the method "iterative"']),
    (['solver.multigrid="hypre"'], ['solver.multigrid = "hypre": unknown', "\"auto\" or one of 'petsc', 'pyamg'"]),
    (["initial.step=1"], ["initial.step needs initial.from_run"]),
    (['contact.parts=[{part="bottom_arc", g=0.2, stiffness={law="constant", value=1}}]'],
     ["contact.part is given with contact.parts"]),
    (['contact.parts=[{part="bottom_arc", g=0.2, probe=[0, 0], stiffness={law="constant", value=1}}]',
     ], ["probe is one value for the whole contact"]),
    # wrong types
    (["material.nu=[0.3]"], ["material.nu: expected an expression", "got [0.3]"]),
    (['material.E={value=1}'], ["material.E", "expected a finite number > 0"]),
    (['time.T="1.1"'], ['time.T = "1.1"', "expected a number"]),
    (["time.steps=true"], ["time.steps = True", "expected an integer"]),
    (['output.progress="yes"'], ['output.progress = "yes"', "expected true or false"]),
    (["output.xdmf=1"], ["output.xdmf = 1", "expected true or false"]),
    (["output.field_steps=[true]"], ["output.field_steps = [True]"]),
    (['contact.probe=["a", "b"]'], ['contact.probe[0] = "a"', "expected a number"]),
    (['contact.normal="down"'], ['contact.normal = "down": expected "body" or a vector of 2 or 3 finite numbers']),
    (['contact.normal=[0, "a"]'], ["contact.normal = [0, 'a']: expected \"body\" or a vector"]),
    (["contact.normal=[0, 0, 0, -1]"], ["contact.normal = [0, 0, 0, -1]: expected"]),
    (['boundary.dirichlet[0].components="x"'], ['boundary.dirichlet[0].components = "x"', "expected a list"]),
    (['boundary.dirichlet[0].components=["w"]'], ['boundary.dirichlet[0].components[0] = "w"']),
    (["boundary.traction[0].part=true"], ["boundary.traction[0].part = True"]),
    (['material.region=1.5'], ["material.region", "expected a region name"]),
    (['mesh.shape=3'], ["mesh.shape = 3"]),
    # out of range
    (["material.E=-inf"], ["material.E = -inf"]),
    (['material.viscoplastic={law="perzyna", eta=0, yield_stress=1}'], ["material.viscoplastic.eta = 0", "> 0"]),
    (['material.viscoplastic={law="perzyna", eta=1}'], ["missing required value 'material.viscoplastic.yield_stress'"]),
    (['material.viscoplastic={law="relaxation", mu=1, E_inf=1, nu_inf=0.7}'], ["material.viscoplastic.nu_inf = 0.7"]),
    (['material.viscoplastic={law="maxwell"}'], ['material.viscoplastic.law = "maxwell": unknown law', '"perzyna"']),
    (["mesh.h=0"], ["mesh.h = 0", "> 0"]),
    (["mesh.radius=-1"], ["mesh.radius = -1"]),
    (["mesh.coating=2"], ["mesh.coating = 2", "less than mesh.radius"]),
    (['mesh.shape="circle"'], ['mesh.shape = "circle"']),
    (["contact.stiffness.c_v=-1"], ["contact.stiffness.c_v: expected a number >= 0", "got -1"]),
    (["contact.rho=-1"], ["contact.rho = -1", ">= 0"]),
    (['contact.p="power"', "contact.exponent=0.5"], ["contact.exponent", ">= 1"]),
    (["contact.probe=[0, 0, 0]"], ["contact.probe has 3 components and the mesh is 2D"]),
    (["contact.normal=[0, 0]"], ["contact.normal = [0.0, 0.0]", "nonzero vector"]),
    (["contact.normal=[0, -1e-200]"], ["contact.normal = [0.0, -1e-200]", "its length 1e-200", "[0, 0, -1]"]),
    (["contact.normal=[0, 1e300]"], ["contact.normal = [0.0, 1e+300]", "its length 1e+300"]),
    (["contact.normal=[0, 0, -1]"], ["contact.normal has 3 components and the mesh is 2D"]),
    (["boundary.dirichlet[0].components=[]"], ["boundary.dirichlet[0].components = []", "leave out components"]),
    (['boundary.dirichlet[0].components=["z"]'], ['boundary.dirichlet[0].components names "z"', "2D"]),
    (["boundary.traction[0].part=3"], ["unknown part '3'", "axis, bottom_arc, top_arc"]),
    (['boundary.body_force=[{value=["0"]}]'], ["boundary.body_force[0].value", "at least 2 values"]),
    (["time.T=-1"], ["time.T = -1", "> 0"]),
    (["time.steps=100000000000"], ["time.steps = 100000000000", "<= 100000000"]),
    (["time.start=2"], ["time.T = 1.1 must be > time.start = 2"]),
    (["solver.tolerance=1"], ["solver.tolerance = 1", "< 1"]),
    (["solver.max_iterations=0"], ["solver.max_iterations = 0", ">= 1"]),
    (["solver.max_step_cuts=31"], ["solver.max_step_cuts = 31", "<= 30"]),
    (['solver.factorization="umfpack2"'], ['solver.factorization = "umfpack2": unknown']),
    (['solver.augmentation="big"'], ['solver.augmentation = "big"', "expected a number"]),
    (["output.field_steps=[0]"], ["output.field_steps = [0]", ">= 1"]),
    (['output.field_steps="some"'], ['output.field_steps = \'some\'', '"all"']),
    (["output.checkpoint_every_steps=-1"], ["output.checkpoint_every_steps = -1", ">= 0"]),
    (["adapt.cycles=0"], ["adapt.cycles = 0", ">= 1"]),
    (["adapt.cycles=2", "adapt.theta=1.5"], ["adapt.theta = 1.5", "<= 1"]),
    (["adapt.cycles=2", 'adapt.estimator="magic"'], ['adapt.estimator = "magic"', "'residual'"]),
    (["initial.xi=-1"], ["initial.xi = -1 at the contact node", ">= 0"]),
    (['initial.displacement=["1", "0"]'], ["u_x = 1 at the node", "held by boundary.dirichlet[0] (part 'axis'",
                                            "u_0 must be 0 there"]),
    (["initial.stress=[[1, 2], [3, 4]]"], ["initial.stress", "symmetric"]),
    (['initial.from_run="nowhere"', "initial.step=1"], ['initial.from_run = "nowhere"', "is not a run directory"]),
    # not finite, empty, huge
    (["contact.g=-inf"], ["contact.g = -inf"]),
    (["contact.probe=[nan, 0]"], ["contact.probe[0] = nan", "finite"]),
    (["contact.stiffness.beta=inf"], ["contact.stiffness.beta: expected a finite number, got inf"]),
    (["time.T=nan"], ["time.T = nan"]),
    (["material.E=1e400"], ["material.E = inf"]),
    (["material={}"], ["missing required value 'material.E'"]),
    (['material.E=""'], ['material.E = ""', "empty"]),
    (["contact={}"], ["missing required value 'contact.part'"]),
    (["boundary.traction[0].value=[]"], ["boundary.traction[0].value = []", "at least 2 values"]),
    ([f"time.steps={10**30}"], [f"time.steps = {10**30}"]),
    ([f"contact.g={10**400}"], ["contact.g = an integer of about 401 digits", "beyond the range of float64"]),
    ([f"contact.stiffness.beta={10**400}"], ["contact.stiffness.beta: expected a finite number",
                                             "an integer of about 401 digits"]),
    ([f"contact.normal=[{10**400}, 0]"], ["contact.normal = [1000", "(406 characters): expected"]),
    ([f"material.E={'9' * 5000}"], ["material.E = \"9999", "(5000 characters)", "out of the float64 range"]),
    (["output.field_steps=[" + "1, " * 100_000 + "0]"], ["output.field_steps = [1, 1, 1", "characters)"]),
]


@pytest.mark.parametrize("overrides, words", KEYS_AND_VALUES, ids=[" ".join(o)[:60] for o, _ in KEYS_AND_VALUES])
def test_a_bad_key_or_value_is_refused_on_one_line(tmp_path, capsys, overrides, words):
    refused_by_cli(tmp_path, capsys, half_disc_case(h=0.25), *sets(*overrides), words=words)


def test_a_3d_case_with_a_plane_hypothesis_is_refused(tmp_path, capsys):
    refused_by_cli(tmp_path, capsys, block_3d_case(), *sets('material.hypothesis="plane_stress"'),
                   words=['material.hypothesis = "plane_stress" is a 2D reduction and the mesh is 3D'])


def test_a_list_of_materials_without_regions_is_refused(tmp_path, capsys):
    case = half_disc_case(h=0.25)
    case["material"] = [{"E": 1000.0, "nu": 0.3}, {"E": 10.0, "nu": 0.3}]
    refused_by_cli(tmp_path, capsys, case, words=["material[0] has no region and there are 2 materials"])


def test_a_region_the_mesh_does_not_have_is_refused(tmp_path, capsys):
    refused_by_cli(tmp_path, capsys, half_disc_case(h=0.25), *sets('material.region="core"'),
                   words=["material.region", "'core'"])


# --- 2. expressions -----------------------------------------------------------------------------------------
EXPRESSIONS = [
    (['material.nu="0.3 +"'], ['material.nu = "0.3 +"', "not a valid expression"]),
    (['material.E="1000*(1 + x"'], ["material.E", "not a valid expression"]),
    (['material.E="E0"'], ['material.E = "E0"', "unknown name 'E0'"]),
    (['material.E="1000*t"'], ["material.E", "unknown name 't'"]),
    (['contact.stiffness.alpha="x.real"'], ["contact.stiffness.alpha"]),
    (['contact.stiffness.beta="(lambda: 1)()"'], ["contact.stiffness.beta"]),
    (['contact.gap="10**(1000*x)"'], ['contact.gap = "10**(1000*x)": not finite (inf) at the contact node']),
    (['boundary.traction[0].value=["0", "-20*t if t else 0"]'], ["boundary.traction[0].value[1]"]),
    (['boundary.traction[0].value=["0", "sin"]'], ["boundary.traction[0].value[1]"]),
    (['boundary.traction[0].value=["0", "-20*t*z"]'], ["boundary.traction[0].value[1]", "uses z and the mesh is 2D"]),
    (['boundary.traction[0].value=["0", "' + "(" * 500 + "t" + ")" * 500 + '"]'], ["boundary.traction[0].value[1]"]),
    (['material.E="1000*log(x - 10)"'], ["material.E", "1000*log(x - 10)"]),
    (['contact.stiffness.beta="1/x"'], ['contact.stiffness.beta = "1/x" is inf at the contact node (x, y) = (0, 0)']),
    (['contact.g="x - 0.5"'], ['contact.g = "x - 0.5"', "expected a finite number > 0"]),
    (['contact.gap="sqrt(x - 1)"'], ["contact.gap", "sqrt(x - 1)", "contact node"]),
    (['initial.xi="-x"'], ["initial.xi", "must be >= 0"]),
    (['boundary.traction[0].value=["0", "-20/(t - 0.5)"]'], ["boundary.traction[0].value[1]", "t = 0.5"]),
    (['boundary.traction[0].value=["0", "exp(1000*t)"]'], ["boundary.traction[0].value[1]", "not finite"]),
]


@pytest.mark.parametrize("overrides, words", EXPRESSIONS, ids=[o[0][:60] for o, _ in EXPRESSIONS])
def test_a_bad_expression_is_refused_naming_its_key(tmp_path, capsys, overrides, words):
    refused_by_cli(tmp_path, capsys, half_disc_case(h=0.25), *sets(*overrides), words=words)


# --- 3. --set syntax -----------------------------------------------------------------------------------------
SET_SYNTAX = [
    ("novalue", ["--set 'novalue'", "expected key=value"]),
    ("=1", ["--set '=1'", "expected key=value"]),
    ("a..b=1", ["override key 'a..b'", "not a dotted key"]),
    ("material.E[x]=1", ["override key 'material.E[x]'", "not a dotted key"]),
    ("material E=1", ["override key 'material E'"]),
    ("contact.stiffness.beta[0]=1", ["override key 'contact.stiffness.beta[0]'", "no entry [0]"]),
    ("material.E.x=1", ["override key 'material.E.x'", "'x' is not inside a table"]),
    ("boundary.dirichlet[5].part=1", ["override key 'boundary.dirichlet[5].part'", "no entry [5]"]),
    ("boundary.neumann[0].part=1", ["no list 'neumann' to index"]),
    ("base_dir=1", ["unknown key 'base_dir'"]),
    ("material.E=[1, 2", ['material.E = "[1, 2"']),
    ("material.nu=1e999999", ["material.nu: expected a finite number, got inf"]),
]


@pytest.mark.parametrize("override, words", SET_SYNTAX, ids=[o for o, _ in SET_SYNTAX])
def test_a_bad_set_is_refused_on_one_line(tmp_path, capsys, override, words):
    refused_by_cli(tmp_path, capsys, half_disc_case(h=0.25), "--set", override, words=words)


# --- 4. mesh files -------------------------------------------------------------------------------------------
SQUARE = (Path(__file__).parent / "meshes" / "square_msh22.msh").read_text()

BROKEN_MESH_FILES = {
    "empty": ("", ["cannot read mesh file"]),
    "not a mesh": ("hello world\n", ["cannot read mesh file"]),
    "binary garbage": (bytes(range(256)) * 8, ["cannot read mesh file"]),
    "UTF-16": (SQUARE.encode("utf-16"), ["cannot read mesh file"]),
    "cut in half": (SQUARE[: len(SQUARE) // 2], ["cannot read mesh file"]),
    "more nodes announced": (SQUARE.replace("$Nodes\n12\n", "$Nodes\n13\n"), ["cannot read mesh file"]),
    "fewer nodes announced": (SQUARE.replace("$Nodes\n12\n", "$Nodes\n11\n"), ["cannot read mesh file"]),
    "a coordinate that is text": (SQUARE.replace("10 0.3749999999995795", "10 abc"), ["cannot read mesh file"]),
    "a coordinate that is nan": (SQUARE.replace("10 0.3749999999995795", "10 nan"),
                                 ["node 10 has the coordinates (nan", "finite number"]),
    "a triangle of a node that does not exist": (SQUARE.replace("9 2 2 5 1 6 3 11", "9 2 2 5 1 6 3 99"),
                                                 ["cannot read mesh file"]),
    "node number 0": (SQUARE.replace("1 0 0 0\n", "0 0 0 0\n", 1), ["refers to node 0", "the file is damaged"]),
    "an unknown element type": (SQUARE.replace("9 2 2 5 1 6 3 11", "9 99 2 5 1 6 3 11"), ["cannot read mesh file"]),
    "an unknown format version": (SQUARE.replace("2.2 0 8", "9.9 0 8"), ["cannot read mesh file", "9.9"]),
    "a node off the plane": (SQUARE.replace("10 0.3749999999995795 0.3750000000004207 0",
                                            "10 0.3749999999995795 0.3750000000004207 1"),
                             ["is not a 2D mesh (nonzero z coordinates)"]),
}


def square_case(mesh_file: str) -> dict:
    """The unit square of tests/meshes/square_msh22.msh, clamped at its bottom, pulled at its top."""
    return {"mesh": {"file": mesh_file}, "material": {"E": 1000.0, "nu": 0.3},
            "boundary": {"dirichlet": [{"part": "bottom"}], "traction": [{"part": "top", "value": ["0", "t"]}]},
            "time": {"T": 1.0, "steps": 2}, "output": {"field_steps": "none"}}


@pytest.mark.parametrize("name", BROKEN_MESH_FILES)
def test_a_broken_mesh_file_is_refused_naming_it(tmp_path, capsys, name):
    content, words = BROKEN_MESH_FILES[name]
    path = tmp_path / "broken.msh"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    refused_by_cli(tmp_path, capsys, square_case(str(path)), words=["broken.msh", *words])


@pytest.mark.parametrize("change, words", [
    ({"boundary": {"dirichlet": [{"part": "floor"}]}}, ["unknown part 'floor'", "bottom, left, right, top"]),
    ({"material": {"E": 1000.0, "nu": 0.3, "region": "steel"}}, ["material.region", "'steel'"]),
    ({"mesh": {"file": "tests"}}, ["is a directory, not a regular file"]),
    ({"mesh": {"file": "x" * 300 + ".msh"}}, ["cannot be read", "File name too long"]),
])
def test_a_mesh_file_without_what_the_case_names_is_refused(tmp_path, capsys, change, words):
    (tmp_path / "square.msh").write_text(SQUARE)
    (tmp_path / "tests").mkdir()
    case = square_case("square.msh")
    case.update(change)
    refused_by_cli(tmp_path, capsys, case, words=words)


# --- 5. --out paths ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("make, words", [
    (lambda tmp: tmp / ("a" * 300), ["has 300 bytes, more than the 255 the file system allows"]),
    (lambda tmp: tmp / ("é" * 200) / "run", ["has 400 bytes, more than the 255"]),
    (lambda tmp: tmp / Path(*["b"] * 2100), ["bytes of a path the file system allows"]),
    (lambda tmp: tmp / "case.toml" / "run", ["is not a directory"]),
], ids=["a name of 300 bytes", "a name of 200 two-byte characters", "a path of 4200 bytes", "below the case file"])
def test_an_out_the_file_system_cannot_hold_is_refused_before_the_run(tmp_path, capsys, make, words):
    out = make(tmp_path)
    refused_by_cli(tmp_path, capsys, half_disc_case(h=0.25), words=["--out", *words], out=out)
    assert sorted(os.listdir(tmp_path)) == ["case.toml"]


@pytest.mark.parametrize("out, overwrite, words", [
    (42, False, ["output directory = 42", "expected a folder's name"]),
    ("run\0dir", False, ["output directory = 'run\\x00dir'"]),
    ("a" * 300, False, ["has 300 bytes, more than the 255"]),
    ("fine", "no", ["overwrite = 'no': expected True or False"]),
    ("fine", 1, ["overwrite = 1: expected True or False"]),
])
def test_result_write_refuses_a_bad_path_or_flag(solved, tmp_path, monkeypatch, out, overwrite, words):
    monkeypatch.chdir(tmp_path)
    refused_by_api(lambda: vpcontact.write_run(solved, out, overwrite=overwrite), *words)
    assert os.listdir(tmp_path) == []


# --- 6. the files of initial.from_run -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def earlier_run(tmp_path_factory):
    """A 2D run directory of conftest.rectangle_case with fields at steps 2 and 4 (a restart starts there)."""
    case = rectangle_case()
    case["time"] = {"T": 0.4, "steps": 4}
    case["output"] = {"field_steps": [2, 4]}
    folder = tmp_path_factory.mktemp("earlier") / "run"
    vpcontact.write_run(vpcontact.solve(case), folder)
    with np.load(folder / "solution.npz") as solution:
        arrays = dict(solution)
    return folder, arrays


def damaged(arrays: dict, name: str) -> dict:
    """solution.npz's arrays with one changed the way ``name`` says (None: the file is not an npz at all)."""
    changed = copy.deepcopy(arrays)
    d = changed["displacement"]
    if name == "displacement with too few rows":
        changed["displacement"] = d[:, :-3]
    elif name == "xi of the wrong length":
        changed["xi"] = changed["xi"][:, :-1]
    elif name == "no displacement":
        del changed["displacement"]
    elif name == "xi without contact_nodes":
        del changed["contact_nodes"]
    elif name == "steps as fractions":
        changed["steps"] = changed["steps"] + 0.5
    elif name == "steps as a table":
        changed["steps"] = changed["steps"][None, :]
    elif name == "complex stress":
        changed["stress"] = changed["stress"] + 1j
    elif name == "times of the wrong length":
        changed["times"] = changed["times"][:1]
    elif name == "a time that is nan":
        changed["times"] = np.full_like(changed["times"], np.nan)
    elif name == "a displacement that is nan":
        changed["displacement"] = np.where(np.arange(d.shape[1])[None, :, None] == 7, np.nan, d)
    elif name == "stress of another dimension":
        changed["stress"] = changed["stress"][:, :, :1, :1]
    elif name == "contact nodes as text":
        changed["contact_nodes"] = changed["contact_nodes"].astype(str)
    return changed


FROM_RUN_FILES = {
    "displacement with too few rows": ["'displacement' of shape (2, ", "(steps, nodes, d)", "damaged"],
    "xi of the wrong length": ["'xi' of shape (2, 8)", "(2, 9) (steps, contact nodes)"],
    "no displacement": ["has no array 'displacement'"],
    "xi without contact_nodes": ["has the array 'xi' and not 'contact_nodes'"],
    "steps as fractions": ["'steps' of type float64, expected integers"],
    "steps as a table": ["'steps' of shape (1, 2)"],
    "complex stress": ["'stress' of type complex128, expected real numbers"],
    "times of the wrong length": ["'times' of shape (1,)"],
    "a time that is nan": ["gives step 2 the time nan"],
    "a displacement that is nan": ["(u) is not finite (nan) at the node"],
    "stress of another dimension": ["'stress' of shape (2, 64, 1, 1)"],
    "contact nodes as text": ["'contact_nodes' of type <U"],
}


def zip_of_text(path: Path) -> None:
    """A zip archive of every array of solution.npz, each of them text instead of a .npy file."""
    with zipfile.ZipFile(path, "w") as archive:
        for name in ("points", "triangles", "steps", "times", "displacement", "stress", "contact_nodes", "xi"):
            archive.writestr(f"{name}.npy", "text")


def restart(folder: Path) -> dict:
    case = rectangle_case()
    case["initial"] = {"from_run": str(folder), "step": 2}
    case["time"] = {"T": 0.4, "steps": 2}
    return case


@pytest.mark.parametrize("name", FROM_RUN_FILES)
def test_a_damaged_solution_of_from_run_is_refused_before_anything_is_written(earlier_run, tmp_path, capsys, name):
    folder = tmp_path / "earlier"
    folder.mkdir()
    np.savez(folder / "solution.npz", **damaged(earlier_run[1], name))
    refused_by_cli(tmp_path, capsys, restart(folder), words=["initial.from_run", *FROM_RUN_FILES[name]])


FROM_RUN_FILE_KINDS = {
    "not a zip file": (lambda path: path.write_text("not an archive"), ["cannot be read"]),
    "cut": (lambda path: path.write_bytes(path.read_bytes()[:1000]), ["cannot be read"]),
    "a .npy file": (lambda path: np.save(open(path, "wb"), np.zeros(3)), ["not a NumPy .npz archive"]),
    "a pickled object array": (lambda path: np.savez(path, points=np.array([object()], dtype=object)),
                               ["cannot be read", "allow_pickle"]),
    "a directory": (lambda path: (path.unlink(), path.mkdir()), ["is a directory, not a regular file"]),
    "a zip of text": (lambda path: zip_of_text(path), ["holds 'points' that is not a NumPy array"]),
}


@pytest.mark.parametrize("kind", FROM_RUN_FILE_KINDS)
def test_a_solution_npz_that_is_not_an_archive_of_arrays_is_refused(earlier_run, tmp_path, capsys, kind):
    folder = tmp_path / "earlier"
    folder.mkdir()
    path = folder / "solution.npz"
    np.savez(path, **earlier_run[1])
    make, words = FROM_RUN_FILE_KINDS[kind]
    make(path)
    refused_by_cli(tmp_path, capsys, restart(folder), words=["initial.from_run", *words])


def test_a_restart_from_the_intact_copy_runs(earlier_run, tmp_path, capsys):
    """The copies above are refused for their damage alone: the intact arrays restart."""
    folder = tmp_path / "earlier"
    folder.mkdir()
    np.savez(folder / "solution.npz", **earlier_run[1])
    assert main(["run", str(write_case(tmp_path, restart(folder))), "--out", str(tmp_path / "out"), "--quiet"]) == 0


def test_a_from_run_name_too_long_for_the_file_system_is_refused(tmp_path, capsys):
    refused_by_cli(tmp_path, capsys, restart(tmp_path / ("r" * 300)), words=["initial.from_run", "not a run directory"])


def write_case(tmp_path, case: dict) -> Path:
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    return path


# --- 7. compose's arguments -----------------------------------------------------------------------------------
COMPOSE = [
    # the mesh
    ({"mesh": skfem.MeshTri()}, ["mesh = a scikit-fem MeshTri1 without named boundaries", "with_boundaries",
                                 "vpcontact.mesh.Mesh(m, parts="]),
    ({"mesh": skfem.MeshQuad()}, ["mesh = a scikit-fem MeshQuad1", "linear triangles (skfem.MeshTri1)"]),
    ({"mesh": "nowhere.msh"}, ["mesh file 'nowhere.msh' not found"]),
    ({"mesh": {"shape": "half_disc"}}, ["missing required value 'mesh.h'"]),
    ({"mesh": {"shape": "half_disc", "h": 0.25, "side": 1}}, ["unknown key 'mesh.side'"]),
    ({"mesh": {"shape": "half_disc", "h": np.float64("nan")}}, ["mesh.h = nan"]),
    ({"mesh": [0.25]}, ["mesh = [0.25]", "expected a vpcontact.mesh.Mesh"]),
    # the material
    ({"material": "steel"}, ['material = "steel"', "expected a table"]),
    ({"material": [1000.0, 0.3]}, ["material[0] = 1000.0", "expected a table"]),
    ({"material": {"E": np.array([1000.0, 2.0]), "nu": 0.3}}, ["material.E = [1000.0, 2.0]"]),
    ({"material": {"E": np.complex128(1000), "nu": 0.3}}, ["material.E", "complex"]),
    ({"material": {"E": 1000.0, "nu": np.float32("inf")}}, ["material.nu: expected a finite number, got inf"]),
    ({"material": {"E": 1000.0, "nu": 0.3, "viscoplastic": "perzyna"}}, ["material.viscoplastic"]),
    # the Dirichlet conditions
    ({"dirichlet": {"axis": {"w": "-0.01*t"}}}, ["boundary.dirichlet[0].components[0] = \"w\""]),
    ({"dirichlet": {"axis": {}}}, ["dirichlet['axis'] = {}: no component"]),
    ({"dirichlet": {"axis": {"x": "-0.01*q"}}}, ["boundary.dirichlet[0].value[0]", "q"]),
    ({"dirichlet": {"axis": {"x": [0.1]}}}, ["boundary.dirichlet[0].value[0]"]),
    ({"dirichlet": {"axis": 0.0}}, ["dirichlet['axis'] = 0.0", "expected the components held at 0"]),
    ({"dirichlet": {"axis": lambda x, y, t: 0 * x}}, ["dirichlet['axis'] = <function", "expected the components"]),
    ({"dirichlet": {"axis": ["x", "w"]}}, ["boundary.dirichlet[0].components[1] = \"w\""]),
    ({"dirichlet": {"axis": []}}, ["boundary.dirichlet[0].components = []"]),
    ({"dirichlet": {("axis",): "x"}}, ["boundary.dirichlet[0].part"]),
    ({"dirichlet": ["axis"]}, ["boundary.dirichlet[0] = \"axis\"", "expected a table"]),
    ({"dirichlet": [{"part": "axis", "components": ["x"], "value": 0.1}]},
     ["boundary.dirichlet[0].value = 0.1", "expected a list"]),
    # the loads
    ({"traction": {"top_arc": {"y": "-t"}}}, ["boundary.traction[0].value = {...}", "expected a list"]),
    ({"traction": {"top_arc": "-20*t"}}, ["boundary.traction[0].value = \"-20*t\"", "expected a list"]),
    ({"traction": {"top_arc": ["0", "-20*t", "0"]}},
     ["boundary.traction[0].value has 3 components and the mesh is 2D"]),
    ({"traction": {"top_arc": lambda x, y: (0 * x, 0 * y)}},
     ["tractions['top_arc'] = <function", "takes 2 arguments (x, y)", "expected f(x, y, t) -> (fx, fy)"]),
    ({"traction": {"top_arc": lambda x, y, z, t: (0 * x, 0 * y)}}, ["takes 4 arguments (x, y, z, t)"]),
    ({"traction": {"top_arc": lambda x, y, t: (0j * x, 0 * y)}}, ["tractions['top_arc']: f(x, y, t) must return"]),
    ({"body_force": lambda x, t: (0 * x, 0 * x)}, ["body_force = <function", "expected f(x, y, t)"]),
    ({"traction": {"top_arc": lambda x, y, t: (0 * x, np.nan * y)}}, ["top_arc", "not finite"]),
    ({"traction": {"top_arc": lambda x, y, t: 0 * x}}, ["top_arc"]),
    ({"traction": {"top_arc": lambda x, y, t: (0 * x, 0 * y, 0 * x)}}, ["top_arc", "must return (fx, fy)"]),
    ({"traction": {"top_arc": lambda x, y, t: (0 * x, {}["load"])}},
     ["tractions['top_arc']: f(x, y, t) at t = 0.1 raised KeyError: 'load'"]),
    ({"body_force": {"y": "-1"}}, ["boundary.body_force[0].value = {...}", "expected a list"]),
    ({"body_force": lambda x, y, t: (0 * x, np.inf + 0 * y)}, ["body_force", "not finite"]),
    # the contact
    ({"contact": {"part": "bottom_arc", "g": 0.2, "stiffness": lambda xi, x, y: xi}},
     ["stiffness_law takes 3 arguments (xi, x, y)"]),
    ({"contact": {"part": "bottom_arc", "g": 0.2, "stiffness": lambda: 100.0}},
     ["stiffness_law takes no argument: expected f(r), or f(r, x)"]),
    ({"contact": {"part": "bottom_arc", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0},
                  "p": lambda r, *, x: r}}, ["p takes 2 arguments (r, x)"]),
    ({"contact": {"part": "bottom_arc", "g": 0.2, "stiffness": lambda xi: undefined_name * xi}},  # noqa: F821
     ["stiffness_law: stiffness_law(0.0, 0.001) raised NameError: name 'undefined_name' is not defined"]),
    ({"contact": {"part": "bottom_arc", "g": 0.2, "stiffness": lambda xi: xi * 1j}},
     ["stiffness_law", "ndarray of complex128, not numbers"]),
    ({"contact": {"part": "bottom_arc", "g": 0.2, "stiffness": lambda xi: xi > 0}},
     ["stiffness_law", "ndarray of bool"]),
    ({"contact": {"part": "bottom_arc", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0},
                  "p": lambda r: np.full(3, r[0])}}, ["p: p(0.0, 0.001) returned an array of shape (3,)"]),
    ({"contact": {"part": "bottom_arc", "g": 0.2, "stiffness": {"law": "constant", "value": 1.0},
                  "normal": np.array([0.0, -1e-200])}}, ["contact.normal = [0.0, -1e-200]"]),
    ({"contact": {"part": "bottom_arc", "g": np.float64("inf"), "stiffness": {"law": "constant", "value": -1.0}}},
     ["contact.stiffness.value", "got -1.0"]),
    ({"contact": ["bottom_arc", 0.2]}, ["contact = ['bottom_arc', 0.2]", "expected a table"]),
    # the time grid, the solver, the initial state, the viscoplastic law
    ({"time": {"T": 1.1, "steps": np.float64(2.5)}}, ["time.steps = 2.5", "expected an integer"]),
    ({"time": {"T": np.bool_(True), "steps": 2}}, ["time.T = True", "expected a number"]),
    ({"time": {"T": 1.1, "steps": np.int64(-3)}}, ["time.steps = -3", ">= 1"]),
    ({"time": (1.1, 11)}, ["time", "expected a table"]),
    ({"solver": {"method": np.str_("magic")}}, ['solver.method = "magic"']),
    ({"solver": {"tolerance": np.float16(2.0)}}, ["solver.tolerance = 2.0"]),
    ({"initial": {"xi": np.zeros(3)}}, ["initial_xi: an array of shape (3,)"]),
    ({"initial": {"displacement": np.zeros((40, 2)) + 1j}}, ["initial_displacement", "not complex128"]),
    ({"initial": {"stress": np.array(["a", "b"])}}, ["initial_stress", "not <U1"]),
    ({"initial": {"xi": np.array(-0.5)}}, ["initial.xi = -0.5 at the contact node"]),
    ({"viscoplastic": "perzyna"}, ["viscoplastic = 'perzyna': expected a function"]),
    ({"viscoplastic": lambda a, b, c, d: a}, ["viscoplastic takes 4 arguments (a, b, c, d)"]),
    ({"viscoplastic": lambda sigma, strain: sigma @ strain}, ["viscoplastic: G(initial.stress, 0) raised ValueError"]),
    ({"viscoplastic": lambda sigma: 0 * sigma}, ["viscoplastic takes 1 argument (sigma): expected G(sigma, strain)"]),
    ({"viscoplastic": lambda sigma, strain: sigma[0, 0, :3]}, ["viscoplastic", "returned an array of shape (3,)"]),
    ({"viscoplastic": lambda sigma, strain: 0 * sigma,
      "material": {"E": 1000.0, "nu": 0.3, "viscoplastic": {"law": "perzyna", "eta": 1.0, "yield_stress": 1.0}}},
     ["material.viscoplastic and viscoplastic = <function", "would not be used"]),
]


@pytest.mark.parametrize("changes, words", COMPOSE, ids=[f"{next(iter(c))} {i}" for i, (c, _) in enumerate(COMPOSE)])
def test_a_bad_argument_of_compose_is_refused_naming_it(changes, words):
    refused_by_api(lambda: composed(**changes), *words)


def test_numpy_numbers_and_arrays_are_the_numbers_and_lists_of_the_tables():
    """np.float32, np.int64, np.bool_, np.str_, 0-d and 1-d arrays and tuples anywhere in compose's tables: the
    problem of the plain Python values, the same operators and the same first steps."""
    plain = composed(material={"E": 1000.0, "nu": 0.3, "hypothesis": "plane_stress"}, time={"T": 0.2, "steps": 2})
    numpy = composed(
        material={"E": np.float32(1000.0), "nu": np.float64(0.3), "hypothesis": np.str_("plane_stress")},
        dirichlet={"axis": np.array(["x"])},
        traction={"top_arc": np.array(["0", "-20.0*t"])},
        contact={"part": "bottom_arc", "g": np.array(0.2), "probe": (np.float32(0.0), 0.0),
                 "stiffness": {"law": "power", "c_v": np.int16(100), "alpha": np.uint8(20), "beta": np.float64(1.0)}},
        time={"T": np.float64(0.2), "steps": np.int64(2)},
        solver={"tolerance": np.float64(1e-12), "max_iterations": np.int32(50)},
    )
    assert (numpy.A != plain.A).nnz == 0
    assert numpy.options == plain.options
    assert type(numpy.options.time.steps) is int and type(numpy.options.contact.probe[0]) is float
    np.testing.assert_array_equal(vpcontact.solve(numpy, output={"progress": np.bool_(False)}).final.displacement,
                                  vpcontact.solve(plain).final.displacement)


def test_numpy_values_in_a_case_dict_and_its_overrides_are_numbers():
    case = half_disc_case(h=0.25)
    case["time"] = {"T": np.float64(1.1), "steps": np.int64(11)}
    overrides = {"contact.stiffness.beta": np.float32(-1.0), "output.field_steps": np.array([5])}
    loaded = vpcontact.load_case(case, overrides)
    assert loaded.time.steps == 11 and loaded.contact.stiffness.beta == -1.0 and loaded.output.field_steps == [5]
    assert "np." not in loaded.to_toml()


# --- 8. Mesh arrays --------------------------------------------------------------------------------------------
def square(**changes):
    """A Mesh of the unit square (8 triangles) from Python, with ``changes`` to its arguments."""
    m = skfem.MeshTri().refined(1)
    arguments = dict(mesh=m, parts={"bottom": m.facets_satisfying(lambda x: x[1] == 0.0),
                                    "top": m.facets_satisfying(lambda x: x[1] == 1.0)}, exact_normals={})
    arguments.update(changes)
    return meshes.Mesh(**arguments)


def triangles(p, t):
    return skfem.MeshTri(np.asarray(p, dtype=float), np.asarray(t))


MESH_ARRAYS = [
    ({"mesh": triangles([[0, 1, 0], [0, 0, 1], [0, 0, 0]], [[0], [1], [2]])},
     ["Mesh.mesh.p has the shape (3, 3) and the mesh is of triangles", "skfem.MeshTet1"]),
    ({"mesh": triangles([[0, 1, 0], [0, 0, 1]], [[0], [1], [5]])},
     ["Mesh.mesh.t: element 0 refers to node 5", "nodes 0 to 2"]),
    ({"mesh": triangles([[0, 1, 0], [0, 0, 1]], [[0], [1], [-1]])}, ["refers to node -1"]),
    ({"mesh": triangles([[0, 1, 0, 5], [0, 0, 1, 5]], [[0], [1], [2]])}, ["node 3 at (5, 5) is in no element"]),
    ({"mesh": triangles([[0, 1, np.nan], [0, 0, 1]], [[0], [1], [2]])}, ["node 2 has the coordinates (nan, 1)"]),
    ({"mesh": skfem.MeshTri2()}, ["Mesh.mesh = a skfem MeshTri2", "MeshTri1 (linear triangles)"]),
    ({"mesh": skfem.MeshQuad()}, ["Mesh.mesh = a skfem MeshQuad1"]),
    ({"mesh": "square.msh"}, ["Mesh.mesh = 'square.msh'"]),
    ({"parts": {"bottom": np.array([999])}}, ["Mesh.parts['bottom']: index 999 is not one of the mesh's facets"]),
    ({"parts": {"bottom": np.array([-1])}}, ["Mesh.parts['bottom']: index -1"]),
    ({"parts": {"bottom": np.array([0.0, 1.0])}}, ["Mesh.parts['bottom'] = an array of shape (2,) of float64"]),
    ({"parts": {"bottom": "0 1"}}, ["Mesh.parts['bottom'] = '0 1'", "1D array of integers"]),
    ({"parts": {"bottom": np.array([[0, 1]])}}, ["Mesh.parts['bottom'] = an array of shape (1, 2)"]),
    ({"parts": {"bottom": []}}, ["Mesh.parts['bottom'] has no facets"]),
    ({"parts": {3: [0]}}, ["Mesh.parts: the name 3 is not a string"]),
    ({"parts": [("bottom", [0])]}, ["Mesh.parts = [('bottom', [0])]", "expected a dict"]),
    ({"regions": {"core": np.array([0, 8])}}, ["Mesh.regions['core']: index 8 is not one of the mesh's elements"]),
    ({"exact_normals": {"left": lambda x: x}}, ["Mesh.exact_normals: the key 'left' is not one of the mesh's parts"]),
    ({"exact_normals": {"bottom": (0.0, -1.0)}}, ["Mesh.exact_normals['bottom'] = (0.0, -1.0)", "expected a function"]),
    ({"curved_parts": {"top": 1.0}}, ["Mesh.curved_parts", "expected a function"]),
    ({"curved_interfaces": {("core", "coating"): lambda x: x}},
     ["Mesh.curved_interfaces: the key ('core', 'coating')"]),
    ({"file": 42}, ["Mesh.file = 42"]),
]


@pytest.mark.parametrize("changes, words", MESH_ARRAYS,
                         ids=[f"{next(iter(c))} {i}" for i, (c, _) in enumerate(MESH_ARRAYS)])
def test_a_mesh_whose_arrays_cannot_be_a_mesh_is_refused_when_it_is_made(changes, words):
    refused_by_api(lambda: square(**changes), *words)


@pytest.mark.parametrize("call, words", [
    (lambda: meshes.half_disc("0.5"), ["h = '0.5': expected a number > 0"]),
    (lambda: meshes.half_disc(True), ["h = True: expected a number > 0"]),
    (lambda: meshes.half_disc(None), ["h = None"]),
    (lambda: meshes.rectangle(1.0, 1.0, [0.5]), ["h = [0.5]"]),
    (lambda: meshes.quarter_ball(0.5, h_bottom="fine"), ["h_bottom = 'fine'"]),
    (lambda: meshes.block(1.0, 1.0, np.float32("nan"), 0.5), ["height must be a positive number, got nan"]),
    (lambda: meshes.read_mesh(42), ["mesh file = 42: expected a file's name"]),
    (lambda: meshes.read_mesh(None), ["mesh file = None"]),
    (lambda: meshes.read_mesh(b"square.msh"), ["mesh file = b'square.msh'"]),
], ids=["h a string", "h a bool", "h None", "h a list", "h_bottom a string", "height nan", "a file number",
        "no file", "a file name in bytes"])
def test_a_bad_argument_of_a_mesh_builder_is_refused(call, words):
    refused_by_api(call, *words)


def test_a_part_inside_the_body_is_refused():
    m = skfem.MeshTri().refined(1)
    inner = np.setdiff1d(np.arange(m.facets.shape[1]), m.boundary_facets())
    refused_by_api(lambda: square(parts={"crack": inner[:2]}), "Mesh.parts['crack']: facet", "is inside the body")


def test_a_mesh_made_in_python_solves_the_uniform_block():
    """A scikit-fem mesh with parts given as lists: accepted, its parts kept as sorted int64 indices, and the
    block pulled at its top stretches by the load over E (ν = 0: no lateral contraction)."""
    mesh = square(parts={"bottom": list(square().parts["bottom"][::-1]), "top": square().parts["top"].astype(np.int32),
                         "left": skfem.MeshTri().refined(1).facets_satisfying(lambda x: x[0] == 0.0)})
    assert mesh.parts["bottom"].dtype == np.int64 and np.all(np.diff(mesh.parts["bottom"]) > 0)
    problem = vpcontact.compose(mesh, material={"E": 100.0, "nu": 0.0}, dirichlet={"bottom": "y", "left": "x"},
                                traction={"top": ["0", "t"]}, time={"T": 1.0, "steps": 1})
    result = vpcontact.solve(problem)
    top = mesh.nodes("top")
    np.testing.assert_allclose(result.final.displacement[top, 1], 1.0 / 100.0, rtol=1e-12)


def test_build_problem_refuses_a_scikit_fem_mesh_on_one_line():
    model = vpcontact.load_case(half_disc_case(h=0.25)).model
    refused_by_api(lambda: vpcontact.build_problem(model, mesh=skfem.MeshTri()), "mesh = <skfem MeshTri1 object>",
                   "expected a vpcontact.mesh.Mesh")


# --- 9. the tables and switches of solving ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def problem():
    return composed(time={"T": 0.3, "steps": 3})


@pytest.fixture(scope="module")
def solved(problem):
    return vpcontact.solve(problem)


@pytest.mark.parametrize("call", ["vpcontact.solve", "solve_problem", "TimeLoop"])
def test_an_output_table_is_a_dict_as_everywhere_in_compose(problem, call):
    output = {"field_steps": "all", "progress": np.bool_(False)}
    run = {"vpcontact.solve": lambda: vpcontact.solve(problem, output=output),
           "solve_problem": lambda: solve_problem(problem, output=output_options(output)),
           "TimeLoop": lambda: TimeLoop(problem, output_options(output)).run()}[call]
    result = run()
    assert result.status == "complete" and sorted(result.fields) == [1, 2, 3]


@pytest.mark.parametrize("output, words", [
    ({"field_steps": "some"}, ["output.field_steps = 'some'", '"all"']),
    ({"fields": "all"}, ["unknown key 'output.fields'"]),
    ("all", ["output = 'all': expected a table (dict) of the [output] keys"]),
    ({"progress": "no"}, ['output.progress = "no"', "expected true or false"]),
    ({"checkpoint_every_seconds": np.float64("nan")}, ["output.checkpoint_every_seconds = nan"]),
])
def test_a_bad_output_table_is_refused_naming_its_key(problem, output, words):
    for call in (lambda: vpcontact.solve(problem, output=output), lambda: TimeLoop(problem, output_options(output))):
        refused_by_api(call, *words)


@pytest.mark.parametrize("call, words", [
    (lambda problem: vpcontact.solve(problem, progress="yes"), ["progress = 'yes': expected True or False"]),
    (lambda problem: TimeLoop("problem"), ["problem = 'problem': expected a vpcontact.Problem"]),
    (lambda problem: solve_problem(None), ["problem = None: expected a vpcontact.Problem"]),
    (lambda problem: vpcontact.solve(half_disc_case(h=0.25), progress="no"), ["progress = 'no'"]),
    (lambda problem: vpcontact.adapt(problem, {"cycles": 0}), ["adapt.cycles = 0", ">= 1"]),
    (lambda problem: vpcontact.adapt(problem, {"cycles": 1, "theta": 2}), ["adapt.theta = 2"]),
    (lambda problem: vpcontact.adapt(problem, None), ["missing required value 'adapt.cycles'"]),
    (lambda problem: vpcontact.adapt(problem, {"cycles": 1}, {"xdmf": "yes"}), ["output.xdmf = \"yes\""]),
    (lambda problem: vpcontact.adapt("problem", {"cycles": 1}), ["problem = 'problem'"]),
    (lambda problem: vpcontact.solve(problem, output={("a",): 1}), ["in output: keys must be strings"]),
])
def test_a_bad_argument_of_solving_is_refused(problem, call, words):
    refused_by_api(lambda: call(problem), *words)


def test_adapt_takes_its_settings_and_outputs_as_dicts(problem):
    adaptation = vpcontact.adapt(problem, {"cycles": np.int64(2), "theta": 0.5}, {"field_steps": "none"})
    assert adaptation.status == "complete" and len(adaptation.rows) == 2


def test_a_case_error_is_one_line_whatever_it_quotes():
    assert str(CaseError("a value\nover two lines\r\x00")) == "a value\\nover two lines\\r\\x00"


# --- 10. no warning on a correct run ----------------------------------------------------------------------------
@pytest.mark.parametrize("case", [
    pytest.param(lambda: vpcontact.load_case(EXAMPLES / "paper_ball.toml", {
        "mesh.h": 0.1, "output.field_steps": "none"}), id="the paper example, coarse"),
    pytest.param(lambda: vpcontact.load_case(EXAMPLES / "paper_ball.toml", {
        "mesh.h": 0.1, "contact.stiffness.beta": -1, "output.field_steps": "none"}), id="the paper example, beta = -1"),
    pytest.param(lambda: vpcontact.load_case(EXAMPLES / "viscoplastic_ball.toml", {
        "mesh.h": 0.1, "output.field_steps": "none"}), id="the viscoplastic ball, coarse"),
    pytest.param(lambda: vpcontact.load_case(block_3d_case()), id="a 3D block with three contact states"),
    pytest.param(lambda: vpcontact.load_case(half_disc_case(h=0.1), {"solver.method": "full"}), id="full method"),
    pytest.param(lambda: vpcontact.load_case(half_disc_case(h=0.1), {"solver.method": "iterative"}),
                 id="iterative method"),
])
def test_a_correct_run_gives_no_warning(case):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = vpcontact.solve(case())
    assert result.status == "complete", result.message


def test_the_condensed_newton_matrix_of_a_floating_body_with_every_node_separated_gives_no_warning():
    """The paper's half disc is held vertically by its contact only. With every contact node separated the
    condensed Newton matrix K = I − S c0 is singular (K N r = 0 for the vertical translation r: cond(K) > 1e14),
    and the low-rank update of the kept inverse from a state with three nodes at the limit to that one solves
    with a capacitance matrix as singular: LAPACK warned (rcond 1e-16, scipy's LinAlgWarning, on a correct
    run). Now the conditioning is checked before that solve and no warning is given; GMRES still solves a
    system of that K to its tolerance (its residual measured here)."""
    from vpcontact.solvers.condensed_systems import KRYLOV_TOLERANCE

    case = vpcontact.load_case(half_disc_case(h=0.25), {"solver.method": "condensed"})
    solver = TimeLoop(vpcontact.build_problem(case), output_options(case.output)).solver
    systems, c0 = solver.systems, solver.reference
    m = c0.size
    inactive, w = np.ones(m), -c0.copy()
    inactive[:3], w[:3] = 0.0, 1.0  # three nodes at the limit
    separated, tangent = np.ones(m), -c0.copy()  # every node separated
    K = systems.matrix(separated, tangent)
    assert np.linalg.cond(K) > 1e14
    rhs = K @ np.linspace(1.0, 2.0, m)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        systems._factorize(inactive, w)
        z = systems.solve_iterative(separated, tangent, rhs)
    assert np.linalg.norm(rhs - K @ z) <= 10 * KRYLOV_TOLERANCE * np.linalg.norm(rhs)
