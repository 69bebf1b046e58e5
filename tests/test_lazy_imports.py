"""What a command imports: a run of a built-in shape or of a gmsh 2.2 text file writes its VTU files
without meshio, draws no figures without matplotlib, loads neither pandas nor pyvista (the tables and the
grids of the Python API) and no adaptive refinement; meshio reads the other mesh files."""

import subprocess
import sys
from pathlib import Path

import tomli_w

from conftest import half_disc_case

HEAVY = ("meshio", "matplotlib", "rich", "pandas", "pyvista")
MESHES = Path(__file__).parent / "meshes"


def modules_loaded(script: str) -> set[str]:
    """The modules loaded by ``script`` in a fresh process, and the packages of the top level."""
    script += "\nprint(' '.join(sorted(sys.modules)))"
    process = subprocess.run([sys.executable, "-c", "import sys\n" + script], capture_output=True, text=True,
                             timeout=120)
    assert process.returncode == 0, process.stderr
    names = process.stdout.split("\n")[-2].split()
    return set(names) | {name.split(".")[0] for name in names}


def modules_after_run(tmp_path, case) -> set[str]:
    """The modules loaded by a whole ``vpcontact run`` of ``case``."""
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    return modules_loaded(f"import vpcontact.cli\nassert vpcontact.cli.main(['run', {str(tmp_path / 'case.toml')!r}, "
                          f"'--out', {str(tmp_path / 'out')!r}, '--quiet']) == 0")


def test_a_run_of_a_built_in_shape_imports_no_mesh_io_and_no_plotting(tmp_path):
    case = half_disc_case(h=0.25)
    case["output"] = {"field_steps": "all"}
    loaded = modules_after_run(tmp_path, case)
    assert {"numpy", "scipy", "skfem", "pydantic"} <= loaded
    assert not set(HEAVY) & loaded
    assert not {"vpcontact.adaptivity.cycles", "vpcontact.mesh.refinement", "vpcontact.results.norms"} & loaded  # an adaptive run's
    assert len(list((tmp_path / "out" / "fields").glob("*.vtu"))) == 22


def test_a_run_of_a_gmsh_2_2_text_file_does_without_meshio(tmp_path):
    from vpcontact.mesh import half_disc
    from vpcontact.mesh.gmsh import write_mesh

    write_mesh(half_disc(0.25), tmp_path / "disc.msh")
    case = half_disc_case(h=0.25)
    case["mesh"] = {"file": str(tmp_path / "disc.msh")}
    assert not set(HEAVY) & modules_after_run(tmp_path, case)


def test_meshio_reads_the_other_mesh_files():
    """A gmsh 4.1 file (and any other format) is read by meshio, imported then."""
    script = f"from vpcontact.mesh import read_mesh\nread_mesh({str(MESHES / 'square.msh')!r})"
    assert "meshio" in modules_loaded(script)
