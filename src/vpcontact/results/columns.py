"""The names of a run's numbers: the columns of its history (history.csv, one row per converged time
level) and its per-node contact arrays (contact.csv, one row per contact node and level).

Conventions: the penetration d = u·ν − g0 (> 0 into the foundation); pressures are forces per unit
length of Γ3 (per unit area in 3D), the compliance part ρK(ξ)p(d) and the rigid part λ_i / w_i;
the normal stress σ_ν = −(compliance + rigid) ≤ 0; the contact force is the resultant the
foundation exerts on the body, −Σ_i w_i (compliance_i + rigid_i) ν_i.
"""

from __future__ import annotations

from ..mesh.cells import coordinates


def history_columns(dim: int) -> tuple[str, ...]:
    """The columns of history.csv for a d-dimensional body (one contact force component per coordinate)."""
    return ("step", "t", "newton_iterations", "residual", "complementarity", "max_penetration", "mean_penetration",
            "K_min", "K_max", "K_probe", "penetration_probe", "normal_stress_probe", "nodes_separated",
            "nodes_in_compliance", "nodes_at_limit", *(f"contact_force_{c}" for c in coordinates(dim)), "substep", "k")


def estimate_columns(terms: tuple[str, ...]) -> tuple[str, ...]:
    """The history columns of an error estimate of ``terms`` at every level (``output.error_estimate``): η(t) =
    (Σ_K η_K²)^½ and each term's share (Σ_K η_K,term²)^½; none without terms (no estimate)."""
    return ("error_estimate", *(f"error_estimate_{term}" for term in terms)) if terms else ()


#: The history columns of a 2D body (the paper's case).
HISTORY_COLUMNS = history_columns(2)
#: History columns holding integers (the others are floats).
INTEGER_COLUMNS = ("step", "newton_iterations", "nodes_separated", "nodes_in_compliance", "nodes_at_limit", "substep")
#: The per-node contact arrays of a level: d, ξ, K, the two pressures and the node status (an index in
#: :data:`vpcontact.laws.contact.STATUS_NAMES`).
CONTACT_ARRAYS = ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid", "status")
