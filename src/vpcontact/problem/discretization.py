"""What a result needs of its problem to be read, written and drawn: the mesh, the contact nodes, the
time grid, the materials' ℰ and the layer's parameters at the contact nodes.

A :class:`~vpcontact.results.result.Result` holds this light view (``result.discretization``), never the
:class:`~vpcontact.problem.build.Problem` it was computed from: the operators, the loads, the laws and the
Python objects a problem may hold stay with the problem, and the writers, tables, plots and norms work from
the view alone (a result pickled to another process included).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..fem.contact_surface import ContactSurface
from ..laws.elasticity import Elasticity
from ..laws.materials import Materials
from ..mesh.mesh import Mesh
from .time_grid import TimeGrid


@dataclass(frozen=True, eq=False)
class Discretization:
    """The mesh, the contact surface (nodes, normals, weights), the step times, ℰ (numbers, or arrays over
    the elements) and each element's material entry (``material``: its index in the model's list), the
    layer's parameters per contact node (``layer``: g, those of K and p, and ``part`` with several contact
    parts, see :meth:`~vpcontact.laws.contact.ContactLaw.parameters`), the probe node and the resolved case the
    problem was built from (None for a problem composed in Python)."""

    mesh: Mesh
    surface: ContactSurface
    times: TimeGrid
    elasticity: Elasticity
    material: np.ndarray
    layer: dict[str, np.ndarray]
    probe: int | None
    source: str | None
    held_parts: tuple[str, ...] = ()  # the held parts, node sets and points, in the case's order (history columns)

    @classmethod
    def of(cls, problem) -> "Discretization":
        """The view of ``problem`` (no copies of its arrays)."""
        surface = problem.surface
        layer = problem.law.parameters(surface.size)
        if len(surface.parts) > 1:
            layer["part"] = np.asarray(surface.parts)[surface.owner]
        return cls(problem.mesh, surface, problem.times, problem.elasticity, problem.materials.owner, layer,
                   problem.probe, problem.source, held_parts(problem))

    @property
    def materials(self) -> Materials:
        """ℰ and the material entry of each element (E and ν per element: ``materials.E``, ``materials.nu``),
        without the viscoplastic law (a function of the problem, left behind with it)."""
        return Materials(self.material, self.elasticity, None)


def held_parts(problem) -> tuple[str, ...]:
    """The names of the parts, node sets and points that Dirichlet conditions hold (``boundary.dirichlet``,
    ``boundary.point``: :mod:`vpcontact.problem.constraints`), each once, in the order of their first entry."""
    return tuple(dict.fromkeys(entry.label for entry in problem.constraints.entries))
