"""What a command imports: a run of a built-in shape writes its VTU files without meshio (it reads mesh
files only) and draws no figures without matplotlib; reading a mesh file imports meshio then."""

import subprocess
import sys

import tomli_w

from conftest import half_disc_case

HEAVY = ("meshio", "matplotlib", "rich")


def modules_after_run(tmp_path, case) -> set[str]:
    """The top-level modules loaded by a whole ``vpcontact run`` of ``case`` (in a fresh process)."""
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    script = ("import sys, vpcontact.cli\n"
              f"status = vpcontact.cli.main(['run', {str(tmp_path / 'case.toml')!r}, '--out', "
              f"{str(tmp_path / 'out')!r}, '--quiet'])\n"
              "assert status == 0, status\n"
              "print(' '.join(sorted({name.split('.')[0] for name in sys.modules})))")
    process = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert process.returncode == 0, process.stderr
    return set(process.stdout.split("\n")[-2].split())


def test_a_run_of_a_built_in_shape_imports_no_mesh_io_and_no_plotting(tmp_path):
    case = half_disc_case(h=0.25)
    case["output"] = {"field_steps": "all"}
    loaded = modules_after_run(tmp_path, case)
    assert {"numpy", "scipy", "skfem", "pydantic"} <= loaded
    assert not set(HEAVY) & loaded
    assert len(list((tmp_path / "out" / "fields").glob("*.vtu"))) == 22


def test_a_run_of_a_mesh_file_imports_meshio(tmp_path):
    from vpcontact.mesh import half_disc
    from vpcontact.mesh_file import write_mesh

    write_mesh(half_disc(0.25), tmp_path / "disc.msh")
    case = half_disc_case(h=0.25)
    case["mesh"] = {"file": str(tmp_path / "disc.msh")}
    loaded = modules_after_run(tmp_path, case)
    assert "meshio" in loaded and "matplotlib" not in loaded
