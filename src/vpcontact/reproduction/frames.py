"""The deformed configurations the paper's Figs. 2, 3, 5 and 9 draw (`Frame`): the mesh, the
displacement, and on Γ3 the normals, the contact pressure and the node states at one time, from a
result in memory or from a run directory (:mod:`vpcontact.io.solution`, :mod:`vpcontact.io.contact_csv`). A
frame also chooses the contact nodes that get a force arrow: no more than `ARROWS`, evenly spaced along Γ3."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from ..errors import CaseError
from ..results.plots import along_curve
from ..case.load import read_case
from ..io.contact_csv import read_contact
from ..io.solution import read_solution
from .paper import CONTACT_CONDITIONS, FIGURE_TIMES, SHORT_LABELS
from .plan import Plan, figure_step
from .study_files import rho_id

MAGNIFICATION = 1.0
"""Displacements are drawn at true scale."""
ARROWS = 40
"""At most this many contact-force arrows per panel, at nodes evenly spaced along Γ3 (the figure
mesh has 127 contact nodes: an arrow at each would merge into a band)."""


@dataclass
class Frame:
    """A deformed configuration with its contact forces, at one time."""

    title: str
    points: np.ndarray
    """Node coordinates (2, n)."""
    triangles: np.ndarray
    """(3, elements)."""
    displacement: np.ndarray
    """(n, 2)."""
    nodes: np.ndarray
    """Mesh indices of the contact nodes (m,)."""
    normals: np.ndarray
    """Outward unit normals ν_i (2, m)."""
    pressure: np.ndarray
    """Contact pressure (compliance + rigid part), N/m (m,)."""
    status: np.ndarray
    """Node states (m,): 0 separated, 1 in compliance, 2 at the limit."""
    g: float
    t: float

    @classmethod
    def from_result(cls, result, step: int, title: str) -> "Frame":
        """Step ``step`` (1-based; a field step or the last) of a :class:`~vpcontact.results.result.Result`."""
        last = len(result.discretization.times)
        fields = result.fields.get(step) or (result.final if step == last else None)
        if fields is None:
            raise KeyError(f"step {step} has no fields (field steps: {sorted(result.fields)})")
        view = result.discretization
        g = view.layer["g"]
        if g.size and np.any(g != g[0]):
            raise CaseError("the paper's figures draw its foundation, a layer of one thickness g; this run's g varies "
                            "along Γ3 (contact.g an expression or contact.parts): draw it with vpcontact.results.plots")
        i = result.end_of_step_rows()[step]
        pressure = result.contact_history("pressure_compliance")[i] + result.contact_history("pressure_rigid")[i]
        return cls(
            title,
            view.mesh.mesh.p,
            view.mesh.mesh.t,
            fields.displacement,
            view.surface.nodes,
            view.surface.normals,
            pressure,
            result.contact_history("status")[i],
            float(g[0]),
            float(view.times[step - 1]),
        )

    @classmethod
    def from_run(cls, folder: Path, title: str) -> "Frame":
        """The last step of a run directory (solution.npz, contact.csv, case.resolved.toml)."""
        solution, contact = read_solution(folder), read_contact(folder)
        if solution is None:
            raise CaseError(f"the run in '{folder}' has no readable solution.npz: it kept no fields or did not end")
        g = read_case(folder).contact.g
        if not isinstance(g, (int, float)):
            raise CaseError(f"the paper's figures draw its foundation, a layer of one thickness g; the run in "
                            f"'{folder}' has contact.g = {g!r}: draw it with vpcontact.results.plots")
        pressure = contact["pressure_compliance"] + contact["pressure_rigid"]
        return cls(title, solution["points"], solution["elements"], solution["displacement"][-1], contact["node"],
                   contact["normals"], pressure, contact["status"], float(g), float(solution["times"][-1]))

    def deformed(self) -> np.ndarray:
        return self.points + MAGNIFICATION * self.displacement.T

    @cached_property
    def edges(self) -> tuple[np.ndarray, np.ndarray]:
        """The edges (2, e) of the mesh, each once, and the number of triangles of each (1: on the boundary)."""
        t = self.triangles
        ends = np.sort(np.hstack([t[[0, 1]], t[[1, 2]], t[[2, 0]]]), axis=0).astype(np.int64)
        n = self.points.shape[1]
        keys, count = np.unique(ends[0] * n + ends[1], return_counts=True)
        return np.vstack([keys // n, keys % n]), count

    def contact_segments(self) -> np.ndarray:
        """The edges of Γ3 (2, s) as indices into ``nodes``: boundary edges between two contact nodes."""
        edges, count = self.edges
        local = np.full(self.points.shape[1], -1)
        local[self.nodes] = np.arange(self.nodes.size)
        ends = local[edges[:, count == 1]]
        return ends[:, (ends >= 0).all(axis=0)]

    def arrow_nodes(self, count: int = ARROWS) -> np.ndarray:
        """Indices into ``nodes`` of the nodes drawn with an arrow: all when there are at most
        ``count``; else as many as every k-th node would give, for the smallest k that gives at
        most ``count``, at the nodes nearest to evenly spaced points of Γ3 (undeformed arc length)."""
        m = self.nodes.size
        if m <= count:
            return np.arange(m)
        order = along_curve(self.contact_segments(), m)
        xy = self.points[:, self.nodes[order]]
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xy, axis=1), axis=0))])
        targets = np.linspace(0.0, s[-1], math.ceil(m / math.ceil(m / count)))
        return np.unique(order[np.abs(s[None, :] - targets[:, None]).argmin(axis=1)])


def figure_frames(results: dict, plan: Plan) -> dict:
    """Deformed meshes and contact forces for Figs. 2, 3 (t = 0.2, 0.5, 0.8, 1.1) and 5 (t = 1.1)."""
    frames = {}
    for sign in ("+1", "-1"):
        result = results[f"beta{sign}_k0.1"]
        for t in FIGURE_TIMES:
            step = figure_step(t, plan.steps_coarse)
            frames[f"beta{sign}_t{t:g}"] = Frame.from_result(result, step, f"t = {t:g} s")
    for name in CONTACT_CONDITIONS:
        result = results[f"{name}_k0.1"]
        frames[f"final_{name}"] = Frame.from_result(result, len(result.discretization.times), SHORT_LABELS[name])
    return frames


def rho_frames(folder: Path, plan: Plan) -> dict:
    """Fig. 9: the final deformed meshes and contact forces of the ρ study, from its run directories."""
    return {f"rho_{rho:g}": Frame.from_run(folder / "runs" / rho_id(rho), f"ρ = {rho:g}") for rho in plan.fig9_rho}

