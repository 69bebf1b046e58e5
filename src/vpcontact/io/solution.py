"""solution.npz: the fields at the field steps as NumPy arrays, what a restart (``initial.from_run``),
a comparison of runs (a study's difference norms) and the paper's figures start from.

Its arrays: ``points`` (d, nnodes), the elements by their type, ``triangles`` (3, nelements) in 2D or
``tetrahedra`` (4, nelements) in 3D, ``steps`` (s,), ``times`` (s,), ``displacement`` (s, nnodes, d),
``stress`` (s, nelements, d, d) at the s field steps, ``lame`` (2, nelements) the Lamé parameters (λ, μ)
of each element (for energy norms); with a viscoplastic law or an initial stress also ``z`` (s,
nelements, d, d), the history of (2.28): stress = ℰε(u) + z; with a contact part also ``contact_nodes``
(m,), the node indices of Γ3, and ``xi`` (s, m), the layer's history ξ there.
"""

from __future__ import annotations

import os
import zipfile
from collections.abc import Collection
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..mesh.cells import SIMPLICES
from .files import replacing

if TYPE_CHECKING:
    from ..results.norms import Snapshot

FILES = ("solution.npz",)
SOLUTION_ARRAYS = ("steps", "times", "points", "displacement", "stress")
"""The arrays of solution.npz a comparison reads (besides the elements, and the Lamé parameters when
the run wrote them)."""


def wanted(result) -> bool:
    """A run that kept fields (``output.field_steps``) has them as arrays too."""
    return bool(result.fields)


def write(result, out: Path) -> None:
    """solution.npz of ``result`` in the run directory ``out`` (see the module's docstring)."""
    steps = sorted(result.fields)
    mesh = result.discretization.mesh.mesh
    arrays = dict(points=mesh.p, steps=np.array(steps), **{SIMPLICES[result.dim].plural: mesh.t},
                  times=np.array([result.discretization.times[s - 1] for s in steps]),
                  displacement=np.array([result.fields[s].displacement for s in steps]),
                  stress=np.array([result.fields[s].stress for s in steps]),
                  lame=np.array([np.broadcast_to(np.asarray(value, dtype=float), mesh.t.shape[1:])
                                 for value in result.discretization.elasticity.lame]))
    if steps and result.fields[steps[0]].z is not None:
        arrays["z"] = np.array([result.fields[s].z for s in steps])
    surface = result.discretization.surface
    if surface.size:
        end_rows = result.end_of_step_rows()
        arrays["contact_nodes"] = surface.nodes
        arrays["xi"] = np.array([result.contact["xi"][end_rows[s]] for s in steps]).reshape(len(steps), surface.size)
    with replacing(Path(out) / "solution.npz") as temporary:
        np.savez(temporary, **arrays)


def read_solution(folder: str | os.PathLike) -> dict[str, np.ndarray] | None:
    """The arrays of solution.npz of the run in ``folder`` a comparison or a figure reads: SOLUTION_ARRAYS,
    ``elements`` (triangles or tetrahedra) and ``lame`` (None for runs of earlier versions, which lack
    it); None when it is missing or damaged."""
    try:
        with np.load(Path(folder) / "solution.npz") as solution:
            data = {key: solution[key] for key in SOLUTION_ARRAYS}
            data["elements"] = solution[SIMPLICES[data["points"].shape[0]].plural]
            data["lame"] = solution["lame"] if "lame" in solution else None
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile):
        return None
    return data


def snapshots_at(folder: str | os.PathLike, times: Collection[float]) -> dict[float, Snapshot]:
    """The fields of the run in ``folder`` at those of ``times`` its solution.npz holds (none if it is
    missing or damaged), for :func:`vpcontact.results.norms.differences` (loaded here: a run needs no norms)."""
    from ..results.norms import Snapshot

    data = read_solution(folder)
    if data is None:
        return {}
    found = {}
    for t in times:
        index = np.flatnonzero(np.isclose(data["times"], t, rtol=1e-9, atol=1e-12))
        if index.size:
            i = index[0]
            found[t] = Snapshot(data["points"], data["elements"], data["displacement"][i], data["stress"][i],
                                data["lame"])
    return found
