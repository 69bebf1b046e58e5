"""The balance of the forces on the body at a converged level: the reactions of the Dirichlet parts, the applied
loads and the contact force sum to zero.

Summed over every dof, the equilibrium's A u and Bᵀz vanish (a translation strains nothing), so at a converged
level Σ_parts reaction + applied force + contact force = −(the free dofs' residual, summed per component): the
balance measures how well the step was solved (and the history columns that carry it, see
:mod:`vpcontact.results.columns`), not a tolerance of its own.
"""

from __future__ import annotations

import numpy as np

from ..mesh.cells import coordinates


def balance(row: dict, dim: int, parts: tuple[str, ...]) -> dict:
    """The balance of a history ``row``, as summary.json's ``final`` has it: per component, the sum of the parts'
    reactions (``reaction``), the applied force (``applied_force``), the sum of those and the contact force
    (``balance_residual``), and ``balance_relative_residual`` = ‖balance_residual‖ / max(‖reaction‖,
    ‖applied_force‖, ‖contact_force‖) (Euclidean norms of the vectors; 0 when all three are 0)."""
    names = coordinates(dim)
    reaction = np.array([sum(row[f"reaction_{part}_{c}"] for part in parts) for c in names], dtype=float)
    applied = np.array([row[f"applied_force_{c}"] for c in names], dtype=float)
    contact = np.array([row[f"contact_force_{c}"] for c in names], dtype=float)
    residual = reaction + applied + contact
    scale = max(np.linalg.norm(reaction), np.linalg.norm(applied), np.linalg.norm(contact))
    return {"reaction": reaction.tolist(), "applied_force": applied.tolist(), "balance_residual": residual.tolist(),
            "balance_relative_residual": float(np.linalg.norm(residual) / scale) if scale else 0.0}
