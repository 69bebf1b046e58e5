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
    """summary.json's ``final.balance`` of a history ``row``: per component, the sum of the parts' reactions
    (``reaction``), the applied force (``applied``), the contact force (``contact``), their sum (``residual``) and
    ``relative_residual`` = |residual| / max(|reaction|, |applied|, |contact|) (Euclidean norms of the vectors; 0
    when all three are 0)."""
    names = coordinates(dim)
    reaction = np.array([sum(row[f"reaction_{part}_{c}"] for part in parts) for c in names], dtype=float)
    applied = np.array([row[f"applied_force_{c}"] for c in names], dtype=float)
    contact = np.array([row[f"contact_force_{c}"] for c in names], dtype=float)
    residual = reaction + applied + contact
    scale = max(np.linalg.norm(reaction), np.linalg.norm(applied), np.linalg.norm(contact))
    return {"reaction": reaction.tolist(), "applied": applied.tolist(), "contact": contact.tolist(),
            "residual": residual.tolist(), "relative_residual": float(np.linalg.norm(residual) / scale) if scale else 0.0}
