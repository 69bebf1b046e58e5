"""The files of a run directory (all written into a staging folder, renamed into place at the end):

- ``summary.json``      status, sizes, wall time, the final values, versions;
- ``history.csv``       one row per time step (``results.HISTORY_COLUMNS``);
- ``contact.csv``       one row per contact node and step;
- ``fields/body.pvd``   displacement, stress, von Mises (and the viscoplastic history z when there is
                        one) at the field steps (VTU files, ParaView);
- ``fields/contact.pvd``  Γ3 with penetration, ξ, K, pressures, status, normal and contact force;
- ``solution.npz``      the fields at the field steps as arrays (see ``write_solution``);
- ``case.resolved.toml``  every value used, defaults included, with the versions as a header.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path

import meshio
import numpy as np

from .contact import STATUS_NAMES
from .results import CONTACT_ARRAYS, HISTORY_COLUMNS, Result

PACKAGES = ("vpcontact", "numpy", "scipy", "scikit-fem", "meshio", "pydantic")


def versions() -> dict[str, str]:
    """Installed versions of vpcontact and its main dependencies."""
    found = {}
    for name in PACKAGES:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "not installed"
    return found


def write_run(result: Result, out: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Write every output of ``result`` to ``out``: complete, or not at all (staging + rename)."""
    out = Path(out)
    if out.exists() and not overwrite and any(out.iterdir()):
        raise FileExistsError(f"output directory '{out}' is not empty (use --overwrite to replace it)")
    staging = out.with_name(f".{out.name}.partial")
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir(parents=True)
    try:
        _write_history(result, staging / "history.csv")
        _write_contact(result, staging / "contact.csv")
        _write_fields(result, staging / "fields")
        found = versions()
        header = "".join(f"# {name} {version}\n" for name, version in found.items())
        (staging / "case.resolved.toml").write_text(header + result.problem.case.to_toml(), encoding="utf-8")
        summary = {**result.summary(), "versions": found}
        (staging / "summary.json").write_text(json.dumps(_json_safe(summary), indent=2) + "\n", encoding="utf-8")
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    if out.exists():
        shutil.rmtree(out)
    staging.rename(out)
    return out


def _json_safe(value):
    """NaN and inf are not JSON: write them as null."""
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def _write_history(result: Result, path: Path) -> None:
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=HISTORY_COLUMNS)
        writer.writeheader()
        for row in result.rows:
            writer.writerow({k: (repr(float(v)) if isinstance(v, (float, np.floating)) else v) for k, v in row.items()})


def _write_contact(result: Result, path: Path) -> None:
    surface = result.problem.surface
    steps, m = result.steps, surface.size
    columns = {
        "step": np.repeat(np.arange(1, steps + 1), m),
        "t": np.repeat(result.times, m),
        "node": np.tile(surface.nodes, steps),
        "x": np.tile(surface.coordinates[0], steps),
        "y": np.tile(surface.coordinates[1], steps),
        "normal_x": np.tile(surface.normals[0], steps),
        "normal_y": np.tile(surface.normals[1], steps),
        "weight": np.tile(surface.weights, steps),
    }
    for name in CONTACT_ARRAYS:
        columns[name] = result.contact_history(name).ravel()
    columns["status"] = np.asarray(STATUS_NAMES)[columns["status"].astype(int)]
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        writer.writerows(zip(*(c.tolist() for c in columns.values())))


def _write_fields(result: Result, folder: Path) -> None:
    if not result.fields:
        return
    folder.mkdir()
    problem = result.problem
    points = np.column_stack([problem.mesh.mesh.p.T, np.zeros(result.nodes)])
    triangles = [("triangle", problem.mesh.mesh.t.T)]
    surface = problem.surface
    contact_points = np.column_stack([surface.coordinates.T, np.zeros(surface.size)])
    segments = [("line", surface.segments.T)]
    body, contact = [], []
    for step, fields in sorted(result.fields.items()):
        t = result.times[step - 1]
        stress = np.zeros((result.elements, 3, 3))
        stress[:, :2, :2] = fields.stress
        stress[:, 2, 2] = fields.stress33
        displacement = np.column_stack([fields.displacement, np.zeros(result.nodes)])
        name = f"body_{step:05d}.vtu"
        cell_data = {"stress": [stress.reshape(-1, 9)], "von_mises": [fields.von_mises]}
        if fields.z is not None:
            z = np.zeros((result.elements, 3, 3))
            z[:, :2, :2] = fields.z
            cell_data["z"] = [z.reshape(-1, 9)]
        meshio.write(folder / name, meshio.Mesh(points, triangles, point_data={"displacement": displacement},
                                                cell_data=cell_data))
        body.append((t, name))
        if surface.size:
            data = {key: result.contact[key][step - 1] for key in CONTACT_ARRAYS}
            pressure = data["pressure_compliance"] + data["pressure_rigid"]
            normal = np.column_stack([surface.normals.T, np.zeros(surface.size)])
            name = f"contact_{step:05d}.vtu"
            meshio.write(folder / name, meshio.Mesh(contact_points, segments, point_data={
                **{key: np.asarray(value, dtype=float) for key, value in data.items()},
                "pressure": pressure, "normal": normal,
                "contact_force": -normal * (surface.weights * pressure)[:, None],
                "displacement": displacement[surface.nodes]}))
            contact.append((t, name))
    _write_pvd(folder / "body.pvd", body)
    if contact:
        _write_pvd(folder / "contact.pvd", contact)
    write_solution(result, folder.parent / "solution.npz")


def write_solution(result: Result, path: Path) -> None:
    """solution.npz: ``points`` (2, nnodes), ``triangles`` (3, nelements), ``steps`` (s,), ``times`` (s,),
    ``displacement`` (s, nnodes, 2), ``stress`` (s, nelements, 2, 2) at the s field steps; with a
    viscoplastic law or an initial stress also ``z`` (s, nelements, 2, 2), the history of (2.28):
    stress = ℰε(u) + z."""
    steps = sorted(result.fields)
    mesh = result.problem.mesh.mesh
    arrays = dict(points=mesh.p, triangles=mesh.t, steps=np.array(steps),
                  times=np.array([result.times[s - 1] for s in steps]),
                  displacement=np.array([result.fields[s].displacement for s in steps]),
                  stress=np.array([result.fields[s].stress for s in steps]))
    if steps and result.fields[steps[0]].z is not None:
        arrays["z"] = np.array([result.fields[s].z for s in steps])
    np.savez_compressed(path, **arrays)


def _write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """A ParaView collection: one dataset per time."""
    root = ET.Element("VTKFile", type="Collection", version="0.1")
    collection = ET.SubElement(root, "Collection")
    for t, name in entries:
        ET.SubElement(collection, "DataSet", timestep=repr(float(t)), part="0", file=name)
    ET.ElementTree(root).write(path, xml_declaration=True, encoding="utf-8")
