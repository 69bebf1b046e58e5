"""How far to refine after one estimate, in a run that adapts during the run (:mod:`.during_run`).

A level whose estimate η is r times the tolerance (r = η / (tolerance max ‖u_h‖_E) > 1) needs, if the estimate falls
at the optimal rate of P1 elements on adapted meshes (η ∝ N^{−1/d}, d the dimension), about N r^d dofs. One
Dörfler step (``theta``) adds far fewer near a singularity (a graded mesh deepens by one level a step), so the
refinement is repeated on *predicted* indicators, without solving, until the mesh has that many dofs (at most
GROWTH times the dofs it had, at least one refinement): a new element's predicted η_T² is its parent's times its
share of the parent's area or volume, and times REDUCTION where the parent was split (the error density of a refined
element falls). The next solve then checks the prediction.
"""

from __future__ import annotations

import numpy as np

from ..mesh.mesh import Mesh
from ..mesh.refinement import Lineage, refine_with_lineage
from ..mesh.simplex import measures
from .cycles import dorfler

#: The most a mesh's dofs grow between two solves.
GROWTH = 4.0
#: The predicted fall of the squared indicator density of a split element.
REDUCTION = 0.5


def wanted_dofs(dofs: int, ratio: float, dim: int) -> int:
    """The dofs a level with estimate ``ratio`` times the tolerance needs at the optimal rate, within GROWTH."""
    return int(dofs * min(max(ratio, 1.0) ** dim, GROWTH))


def refine_towards(mesh: Mesh, squared: np.ndarray, dofs: int, most: int,
                   theta: float) -> tuple[Mesh, Lineage] | None:
    """``mesh`` refined by Dörfler marking (``theta``) of the element indicators ``squared`` (η_T²), then of their
    predictions on each refined mesh (see the module docstring), until it has at least ``dofs`` dofs: the mesh and
    its lineage from ``mesh``. A refinement that would give more than ``most`` dofs is not made: the mesh before
    it, None if that is ``mesh`` itself (or if every indicator is zero)."""
    found, predicted = None, np.asarray(squared, dtype=float)
    while True:
        marked = dorfler(predicted, theta)
        if not marked.size:
            return found
        refined, step = refine_with_lineage(mesh, marked)
        old, new = mesh.mesh, refined.mesh
        if refined.dim * new.p.shape[1] > most:
            return found
        split = np.bincount(step.parent, minlength=old.t.shape[1]) > 1
        share = measures(new.p, new.t) / measures(old.p, old.t)[step.parent]
        predicted = predicted[step.parent] * share * np.where(split[step.parent], REDUCTION, 1.0)
        mesh = refined
        found = (refined, step if found is None else found[1].then(step))
        if refined.dim * new.p.shape[1] >= dofs:
            return found
