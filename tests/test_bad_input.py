"""Every bad input gets a one-line error naming the bad value, exit status 2, no traceback, and no
output directory."""

import tomli_w
import pytest

from vpcontact.cli import main
from conftest import half_disc_case


def run_with(tmp_path, capsys, case: dict, *overrides: str):
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    out = tmp_path / "out"
    status = main(["run", str(path), "--out", str(out), "--quiet", *[a for o in overrides for a in ("--set", o)]])
    err = capsys.readouterr().err
    return status, err, out


CASES = [
    # (overrides, words the message must contain)
    (["mesh.hh=0.1"], ["unknown key 'mesh.hh'", "did you mean 'mesh.h'"]),
    (["contact.stiffnes.beta=1"], ["unknown key 'contact.stiffnes'", "did you mean 'contact.stiffness'"]),
    (["colour=1"], ["unknown key 'colour'"]),
    (["material.E=-5"], ["material.E = -5", "> 0"]),
    (["material.E=0"], ["material.E = 0", "> 0"]),
    (['material.E="abc"'], ['material.E = "abc"', "unknown name 'abc'"]),
    (['material.E=true'], ['material.E = True', "expected a finite number"]),
    (["material.E=nan"], ["material.E = nan", "finite"]),
    (["material.E=inf"], ["material.E = inf", "finite"]),
    (["material.nu=0.5"], ["material.nu = 0.5", "plane_strain"]),
    (["material.nu=-1.2"], ["material.nu = -1.2"]),
    (['material.hypothesis="plane_stress"', "material.nu=0.6"], ["material.nu = 0.6", "plane_stress"]),
    (['material.hypothesis="plain"'], ['material.hypothesis = "plain"', "plane_strain"]),
    (["contact.g=0"], ["contact.g = 0", "> 0"]),
    (["contact.g=-0.1"], ["contact.g = -0.1"]),
    (["contact.g=nan"], ["contact.g = nan"]),
    (["time.T=0"], ["time.T = 0", "> 0"]),
    (["time.steps=0"], ["time.steps = 0", ">= 1"]),
    (["time.steps=2.5"], ["time.steps = 2.5", "integer"]),
    (['contact.stiffness.law="linear"'], ['contact.stiffness.law = "linear"', '"power"']),
    (['contact.part="bottom"'], ["unknown part 'bottom'", "axis, bottom_arc, top_arc"]),
    (['boundary.dirichlet[0].part="left"'], ["unknown part 'left'", "axis, bottom_arc, top_arc"]),
    (['boundary.traction[0].value=["0", "-1000*tt"]'], ["boundary.traction[0].value[1]", "unknown name 'tt'"]),
    (['boundary.traction[0].value=["0", "-1000*"]'], ["boundary.traction[0].value[1]", "not a valid expression"]),
    (['boundary.traction[0].value=["__import__(\'os\')", "0"]'], ["boundary.traction[0].value[0]", "__import__"]),
    (['boundary.traction[0].value=["0"]'], ["boundary.traction[0].value", "expected at least 2 values"]),
    (['boundary.traction[0].value=["0", "0", "0", "0"]'], ["boundary.traction[0].value", "expected at most 3 values"]),
    (["contact.parts=[]"], ["contact.parts = []", "expected at least 1 value"]),
    (['contact.gap="t"'], ["contact.gap", "unknown name 't'"]),
    (['mesh.file="missing.msh"'], ["mesh: give exactly one of mesh.shape and mesh.file"]),
    (["mesh.width=2"], ['mesh.width is not used with mesh.shape = "half_disc"']),
    (['contact.p="power"'], ["contact.exponent"]),
    (["output.field_steps=[20]"], ["output.field_steps", "after the last step"]),
]


@pytest.mark.parametrize("overrides, words", CASES, ids=[c[0][0] for c in CASES])
def test_bad_value_is_named_on_one_line(tmp_path, capsys, overrides, words):
    status, err, out = run_with(tmp_path, capsys, half_disc_case(h=0.25), *overrides)
    assert status == 2
    assert err.startswith("vpcontact: error: ") and err.count("\n") == 1, err
    for word in words:
        assert word in err, (word, err)
    assert not out.exists()
    assert "Traceback" not in err


def test_missing_required_value(tmp_path, capsys):
    case = half_disc_case(h=0.25)
    del case["material"]["E"]
    status, err, out = run_with(tmp_path, capsys, case)
    assert status == 2 and "missing required value 'material.E'" in err and not out.exists()


@pytest.mark.parametrize("content, words", [
    (None, ["mesh file", "missing.msh"]),
    ("this is not a mesh", ["mesh file", "bad.msh"]),
])
def test_bad_mesh_file(tmp_path, capsys, content, words):
    case = half_disc_case(h=0.25)
    name = "missing.msh" if content is None else "bad.msh"
    if content is not None:
        (tmp_path / name).write_text(content)
    case["mesh"] = {"file": name}
    status, err, out = run_with(tmp_path, capsys, case)
    assert status == 2 and err.count("\n") == 1, err
    for word in words:
        assert word in err
    assert not out.exists()


def test_case_file_that_is_not_toml(tmp_path, capsys):
    path = tmp_path / "case.toml"
    path.write_text("[mesh\nshape = 1")
    status = main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert status == 2 and "not valid TOML" in err and err.count("\n") == 1


def test_free_rigid_motion_is_refused(tmp_path, capsys):
    case = half_disc_case(h=0.25)
    del case["contact"]
    status, err, out = run_with(tmp_path, capsys, case)
    assert status == 2 and "leave the translation along y of the body free" in err and not out.exists()
