"""Command-line usage mistakes get the same refusal as every other bad input: exit 2, one line naming
the problem and where to look, nothing written."""

import subprocess
import sys

import pytest

from conftest import assert_refused, run_cli, snapshot_tree

MISTAKES = [
    ([], "required: command"),
    (["run"], "required: case, --out"),
    (["run", "case.toml"], "required: --out"),
    (["run", "case.toml", "--out"], "--out: expected one argument"),
    (["run", "case.toml", "--out", "out", "--resume", "--overwrite"], "not allowed with"),
    (["run", "case.toml", "--out", "out", "--set"], "--set: expected one argument"),
    (["run", "case.toml", "--out", "out", "--colour"], "unrecognized arguments: --colour"),
    (["study", "study.toml"], "required: --out"),
    (["study", "study.toml", "--out", "out", "--workers", "two"], "invalid int value: 'two'"),
    (["study", "study.toml", "--out", "out", "--workers", "0"], "--workers 0: must be at least 1"),
    (["reproduce"], "required: --out"),
    (["reproduce", "--out", "out", "--workers", "-1"], "--workers -1: must be at least 1"),
    (["solve", "case.toml"], "invalid choice: 'solve'"),
]


@pytest.mark.parametrize("args, words", MISTAKES, ids=[" ".join(a) or "nothing" for a, _ in MISTAKES])
def test_usage_mistakes_are_refused_on_one_line(tmp_path, args, words):
    (tmp_path / "case.toml").write_text("")
    (tmp_path / "study.toml").write_text("")
    before = snapshot_tree(tmp_path)
    status, out, err = run_cli(*args, cwd=tmp_path)
    assert_refused(status, err, words, untouched=[(tmp_path, before)])
    assert out == ""


def test_help_and_version_still_work():
    status, out, err = run_cli("--help")
    assert status == 0 and "run" in out and err == ""
    status, out, _ = run_cli("--version")
    assert status == 0 and out.startswith("vpcontact ")


def test_help_and_import_load_no_numerics():
    """`vpcontact --help` and `import vpcontact` import neither NumPy, SciPy, scikit-fem nor pydantic (the
    API's names load on first use): start-up is the interpreter's."""
    script = ("import sys, contextlib, io, vpcontact, vpcontact.cli\n"
              "with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
              "    vpcontact.cli.main(['--help'])\n"
              "heavy = {'numpy', 'scipy', 'skfem', 'pydantic', 'matplotlib', 'pandas', 'pyvista'}\n"
              "print(sorted(heavy & set(sys.modules)))")
    loaded = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True).stdout
    assert loaded.strip() == "[]"
    script = "import vpcontact; print(vpcontact.load_case.__module__, type(vpcontact.solve).__name__)"
    assert subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True).stdout.split() == ["vpcontact.case.load", "function"]


def test_python_dash_m_vpcontact_is_the_command_line(tmp_path):
    """`python -m vpcontact ARGS` is `vpcontact ARGS`: the same help, and the same one-line refusal."""
    status, out, err = run_cli("--help")
    module = subprocess.run([sys.executable, "-m", "vpcontact", "--help"], capture_output=True, text=True, timeout=120)
    assert (module.returncode, module.stdout, module.stderr) == (status, out, err)
    before = snapshot_tree(tmp_path)
    refused = subprocess.run([sys.executable, "-m", "vpcontact", "run", str(tmp_path / "case.toml")],
                             capture_output=True, text=True, timeout=120)
    assert_refused(refused.returncode, refused.stderr, "required: --out", untouched=[(tmp_path, before)])
