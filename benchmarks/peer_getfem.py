"""vpcontact against GetFEM on the same contact problem, whole processes: prints JSON.

The problem: examples/paper_ball.toml with a constant layer (contact.stiffness.beta = 0: K = c_v = 100),
its g = 0.2 rigid limit, E = 1000, ν = 0.3 plane strain, the roller on the axis and the traction
(0, −17.977 t) on the top arc, on a half disc of radius 1 centred at the origin (the probe (0, −1) is
its lowest point) meshed once by gmsh (benchmarks/half_disc.geo, element size h = 1.408 / level:
30,628 DOFs and 144 contact nodes at the level 128) into a gmsh 2.2 file that both codes read;
`--steps` time steps on [0, T]. Without gmsh on the PATH the file holds vpcontact's own `half_disc`
mesh of the same size, moved down by the radius ("mesher" says which).

Each of `--runs` pairs times, one after the other, the whole process of
- `vpcontact run CASE --out DIR` (a fresh DIR each run: every output a user gets), and
- GetFEM's model of the same problem (benchmarks/getfem_half_disc.py, by the Python that has GetFEM,
  `--getfem-python`): its own Newton method and MUMPS, writing the two compared steps;
and reports the medians, their ratio (GetFEM / vpcontact), the processor, the load average before and
after, GetFEM's version and the agreement of the two solutions (last pair) at the steps nearest to
t = 0.5 and at T: the penetration and pressure at the probe and at every contact node, the
displacement at a few nodes and at every node. Without GetFEM (its Python cannot import getfem)
vpcontact alone is timed and "getfem" is null.

    python benchmarks/peer_getfem.py                                # level 128, 141 steps, 3 pairs
    python benchmarks/peer_getfem.py --level 32 --steps 11 --runs 1 # seconds
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from vpcontact.io.contact_csv import read_contact
from vpcontact.io.solution import read_solution
from vpcontact.io.summary import read_summary

HERE = Path(__file__).resolve().parent
EXAMPLE = HERE.parent / "examples" / "paper_ball.toml"
GEOMETRY = HERE / "half_disc.geo"
GETFEM_MODEL = HERE / "getfem_half_disc.py"
#: The element size times the level: h = 0.011 at the level 128 gives the comparison's 30,628 DOFs.
H_TIMES_LEVEL = 1.408
#: Nodes whose displacements are reported: the probe, the end of Γ3 on the equator, the top of the axis,
#: the centre.
REPORTED_POINTS = ((0.0, -1.0), (1.0, 0.0), (0.0, 1.0), (0.0, 0.0))
PROBE = REPORTED_POINTS[0]


def make_mesh(level: int, folder: Path, mesher: str) -> tuple[Path, str]:
    """The gmsh 2.2 file of the half disc at `level` and the name and version of what meshed it."""
    path = folder / "half_disc.msh"
    h = H_TIMES_LEVEL / level
    if mesher == "gmsh":
        subprocess.run(["gmsh", str(GEOMETRY), "-2", "-setnumber", "h", repr(h), "-format", "msh22", "-o", str(path)],
                       check=True, capture_output=True, text=True)
        version = subprocess.run(["gmsh", "--version"], capture_output=True, text=True)
        return path, f"gmsh {(version.stdout + version.stderr).strip()}"
    import meshio

    from vpcontact.mesh import half_disc
    from vpcontact.mesh.gmsh import write_mesh

    write_mesh(half_disc(h), path)
    data = meshio.read(path)
    data.points[:, 1] -= 1.0  # the centre from (0, 1) to the origin, as half_disc.geo has it
    meshio.write(path, data, file_format="gmsh22", binary=False)
    return path, "vpcontact half_disc"


def write_case(mesh: Path, steps: int, folder: Path) -> tuple[Path, dict, list[int]]:
    """The example with the mesh file, the probe at its lowest point, K constant and `steps` steps, the
    steps nearest to t = 0.5 and T written as fields; returns its path, its table and those steps."""
    import tomli_w

    case = tomllib.loads(EXAMPLE.read_text())
    recorded = sorted({max(1, round(0.5 / case["time"]["T"] * steps)), steps})
    case["mesh"] = {"file": str(mesh)}
    case["contact"]["probe"] = list(PROBE)
    case["contact"]["stiffness"]["beta"] = 0.0
    case["time"]["steps"] = steps
    case["output"]["field_steps"] = recorded
    path = folder / "case.toml"
    path.write_text(tomli_w.dumps(case))
    return path, case, recorded


def getfem_arguments(case: dict) -> list[str]:
    """The law, loads, time grid and Newton tolerance of `case` as options of getfem_half_disc.py (K = c_v:
    β = 0); refused (SystemExit) where the case is not what that model solves."""
    from vpcontact.expressions.parse import parse_expression

    (traction,) = case["boundary"]["traction"]
    horizontal, vertical = (parse_expression(value, where="traction") for value in traction["value"])
    c = -float(vertical(x=0.0, y=0.0, t=1.0))
    if horizontal(x=0.0, y=0.0, t=1.0) != 0 or vertical(x=0.5, y=0.5, t=2.0) != -2 * c:
        raise SystemExit("peer_getfem: the example's traction is not (0, -c t): getfem_half_disc.py models only that")
    contact, material = case["contact"], case["material"]
    if (contact["stiffness"]["law"], contact["stiffness"]["beta"], contact["p"], contact.get("rho", 1.0),
            material.get("hypothesis", "plane_strain")) != ("power", 0.0, "positive_part", 1.0, "plane_strain"):
        raise SystemExit("peer_getfem: getfem_half_disc.py models K = c_v (the power law with beta = 0), p = r+, "
                         "rho = 1 and plane strain")
    return ["--E", repr(material["E"]), "--nu", repr(material["nu"]), "--K", repr(contact["stiffness"]["c_v"]),
            "--g", repr(contact["g"]), "--traction", repr(c), "--T", repr(case["time"]["T"]),
            "--tolerance", repr(case.get("solver", {}).get("tolerance", 1e-10))]


def timed(command: list[str], env: dict | None = None) -> float:
    """Wall seconds of `command`'s whole process (it must succeed)."""
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"peer_getfem: {' '.join(command)} failed ({done.returncode}): {done.stderr.strip()[-2000:]}")
    return seconds


def has_getfem(python: str) -> bool:
    try:
        return subprocess.run([python, "-c", "import getfem"], capture_output=True, env=_plain_env()).returncode == 0
    except OSError:
        return False


def getfem_version() -> str | None:
    """The python3-getfem package's version (GetFEM's Python module does not say it), None when unknown."""
    if shutil.which("dpkg-query") is None:
        return None
    done = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-getfem"], capture_output=True, text=True)
    return done.stdout.strip() or None


def processor() -> str:
    """The first processor's model name, family and model in /proc/cpuinfo, and the number of processors."""
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:
        return "unknown"
    fields = {}
    for line in lines:
        key, _, value = line.partition(":")
        fields.setdefault(key.strip(), value.strip())
    count = sum(line.startswith("processor") for line in lines)
    if "model name" not in fields:
        return "unknown"
    family, model = fields.get("cpu family", "?"), fields.get("model", "?")
    return f"{fields['model name']} (family {family}, model {model}; {count} processors)"


def _plain_env() -> dict:
    """The environment without PYTHONPATH: the GetFEM side runs on another Python's own packages."""
    return {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}


def vpcontact_command(case: Path, out: Path) -> list[str]:
    """`vpcontact run CASE --out DIR`: the console script beside this Python when there is one."""
    script = Path(sys.executable).with_name("vpcontact")
    program = [str(script)] if script.exists() else [sys.executable, "-m", "vpcontact.cli"]
    return [*program, "run", str(case), "--out", str(out)]


def _match(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orders ia, ib with a[:, ia] == b[:, ib]: the same points (d, n) listed in two orders."""
    ia, ib = np.lexsort(a), np.lexsort(b)
    if a.shape != b.shape or not np.allclose(a[:, ia], b[:, ib], rtol=0, atol=1e-12):
        raise SystemExit("peer_getfem: the two codes do not have the same nodes")
    return ia, ib


def agreement(run: Path, peer: Path) -> list[dict]:
    """vpcontact's run directory against GetFEM's .npz at the steps GetFEM recorded: at the probe and at a
    few nodes the two values, and the largest differences over the contact nodes and over every node."""
    solution, other = read_solution(run), np.load(peer)
    ia, ib = _match(solution["points"], other["nodes"])
    points = solution["points"][:, ia]
    nearest = [int(np.argmin(np.hypot(points[0] - x, points[1] - y))) for x, y in REPORTED_POINTS]
    records = []
    for k, step in enumerate(other["steps"]):
        contact = read_contact(run, int(step))  # the rows at t_n (a step cut into sub-steps has more)
        xy = contact["coordinates"]
        ca, cb = _match(xy, other["nodes"][:, other["contact_nodes"]])
        probe = int(np.argmin(np.hypot(*(xy[:, ca] - np.reshape(PROBE, (2, 1))))))
        d = contact["penetration"][ca], other["penetration"][k][cb]
        rigid = contact["pressure_rigid"][ca], other["pressure_rigid"][k][cb]
        pressure = contact["pressure_compliance"][ca] + rigid[0], other["pressure_compliance"][k][cb] + rigid[1]
        u = solution["displacement"][list(solution["steps"]).index(step)][ia], other["displacement"][k][ib]
        records.append({
            "step": int(step), "t": float(other["times"][k]),
            "probe": {"point": xy[:, ca][:, probe].tolist(), "penetration": [float(v[probe]) for v in d],
                      "pressure": [float(v[probe]) for v in pressure],
                      "pressure_rigid": [float(v[probe]) for v in rigid]},
            "displacements": [{"point": points[:, i].tolist(), "vpcontact": u[0][i].tolist(),
                               "getfem": u[1][i].tolist()} for i in nearest],
            "max_penetration_difference": float(np.abs(d[0] - d[1]).max()),
            "max_pressure_difference_relative":
                float(np.abs(pressure[0] - pressure[1]).max() / np.abs(pressure[0]).max()),
            "max_displacement_difference_relative": float(np.abs(u[0] - u[1]).max() / np.abs(u[0]).max()),
            "nodes_at_limit": [int((v > 0).sum()) for v in rigid],
        })
    return records


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--level", type=int, default=128, help="element size 1.408 / LEVEL (128: h = 0.011)")
    parser.add_argument("--steps", type=int, default=141)
    parser.add_argument("--runs", type=int, default=3, help="pairs of whole processes; medians are reported")
    parser.add_argument("--getfem-python", default="/usr/bin/python3", help="the Python that imports getfem")
    parser.add_argument("--mesher", choices=("gmsh", "vpcontact"),
                        default="gmsh" if shutil.which("gmsh") else "vpcontact",
                        help="what meshes the half disc (default: gmsh when it is on the PATH)")
    args = parser.parse_args()
    getfem = has_getfem(args.getfem_python)
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="peer_getfem_") as scratch:
        folder = Path(scratch)
        mesh, mesher = make_mesh(args.level, folder, args.mesher)
        case_path, case, recorded = write_case(mesh, args.steps, folder)
        peer_command = [args.getfem_python, str(GETFEM_MODEL), str(mesh), "--steps", str(args.steps),
                        "--record", *map(str, recorded), *getfem_arguments(case)]
        ours, theirs = [], []
        for run in range(args.runs):
            ours.append(timed(vpcontact_command(case_path, folder / f"run{run}")))
            if getfem:
                theirs.append(timed([*peer_command, "--out", str(folder / f"peer{run}.npz")], env=_plain_env()))
        last = folder / f"run{args.runs - 1}"
        summary = read_summary(last)
        record = {
            "level": f"1/{args.level}", "h": H_TIMES_LEVEL / args.level, "mesher": mesher,
            "dofs": summary["dofs"], "elements": summary["elements"], "contact_nodes": summary["contact_nodes"],
            "steps": summary["steps"], "T": case["time"]["T"], "processor": processor(),
            "load_average_before": list(load_before), "load_average_after": list(os.getloadavg()),
            "runs": args.runs,
            "vpcontact": {"command": "vpcontact run CASE --out DIR", "wall_s": ours,
                          "median_s": statistics.median(ours),
                          "solver_method": summary["solver_method"], "newton_iterations": summary["newton_iterations"],
                          "timings_s": summary["timings_s"]},
            "getfem": None, "ratio": None, "ratio_of_pairs": None, "agreement": None,
        }
        if getfem:
            peer = np.load(folder / f"peer{args.runs - 1}.npz")
            record["getfem"] = {"version": getfem_version(), "command": "python3 benchmarks/getfem_half_disc.py MESH",
                                "wall_s": theirs, "median_s": statistics.median(theirs), "dofs": int(peer["dofs"]),
                                "newton_iterations": int(peer["newton_iterations"].sum()),
                                "augmentation_r": float(peer["augmentation_r"])}
            record["ratio"] = record["getfem"]["median_s"] / record["vpcontact"]["median_s"]
            record["ratio_of_pairs"] = statistics.median(b / a for a, b in zip(ours, theirs))
            record["agreement"] = agreement(last, folder / f"peer{args.runs - 1}.npz")
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
