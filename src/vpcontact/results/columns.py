"""The names of a run's numbers: the columns of its history (history.csv, one row per converged time
level) and its per-node contact arrays (contact.csv, one row per contact node and level).

Conventions: the penetration d = u·ν − g0 (> 0 into the foundation); pressures are forces per unit
length of Γ3 (per unit area in 3D), the compliance part ρK(ξ)p(d) and the rigid part λ_i / w_i;
the normal stress σ_ν = −(compliance + rigid) ≤ 0; the contact force is the resultant the
foundation exerts on the body, −Σ_i w_i (compliance_i + rigid_i) ν_i. ``contact_area`` is the lumped (nodal)
measure of Γ3 in contact, Σ w_i over the nodes with d_i > 0, ``limit_area`` that of the nodes at the rigid
limit (length in 2D, area in 3D); ``applied_force`` is the resultant of the applied loads F(t) (tractions and
body forces, per unit thickness in 2D).

Per Dirichlet part (:func:`held_part_columns`): ``reaction_<part>_<c>``, the force the constraint exerts on
the body, the sum over the part's held dofs of the residual (A u + Bᵀz + Σ N_iᵀ(w_i ρK p + λ_i) − F)_dof of the
equilibrium (a dof held by several parts is shared equally among them, so that the parts' reactions add up
to the whole reaction), 0 in a component the part does not hold; ``displacement_<part>_<c>``, the mean of u_c
over the part's nodes (the plain mean of the nodal values, not weighted; in a held component the prescribed u_D, 0
without a value). A node set or a point held (``where``, ``[[boundary.point]]``) counts as a part, named by its
``name`` (default ``dirichlet<i>``, ``point<i>``). At a converged level the reactions, the applied force and the
contact force balance (summary.json's ``final.balance_relative_residual``).
"""

from __future__ import annotations

from ..mesh.cells import coordinates


def history_columns(dim: int, held_parts: tuple[str, ...] = ()) -> tuple[str, ...]:
    """The columns of history.csv for a d-dimensional body (one force component per coordinate) held by the
    Dirichlet ``held_parts`` (their :func:`held_part_columns` before ``substep`` and ``k``)."""
    return ("step", "t", "newton_iterations", "residual", "complementarity", "max_penetration", "mean_penetration",
            "K_min", "K_max", "K_probe", "penetration_probe", "normal_stress_probe", "nodes_separated",
            "nodes_in_compliance", "nodes_at_limit", *(f"contact_force_{c}" for c in coordinates(dim)), "contact_area",
            "limit_area", *(f"applied_force_{c}" for c in coordinates(dim)), *held_part_columns(dim, held_parts),
            "substep", "k")


def held_part_columns(dim: int, parts: tuple[str, ...]) -> tuple[str, ...]:
    """The history columns of the Dirichlet ``parts`` of a d-dimensional body: per part its reaction and its mean
    displacement, one per coordinate (``reaction_<part>_<c>``, ``displacement_<part>_<c>``)."""
    return tuple(f"{quantity}_{part}_{c}" for part in parts for quantity in ("reaction", "displacement")
                 for c in coordinates(dim))


def estimate_columns(terms: tuple[str, ...]) -> tuple[str, ...]:
    """The history columns of the error estimates at every level (``output.error_estimate``, ``time.adaptive``): in
    space, of the estimator's ``terms``, η(t) = (Σ_K η_K²)^½ and each term's share (Σ_K η_K,term²)^½; in time
    (:mod:`vpcontact.timeloop.companion`), η_k(t) and θ, what the (sub-)step added to it; none without terms (no
    estimate)."""
    if not terms:
        return ()
    return ("error_estimate", *(f"error_estimate_{term}" for term in terms), "time_estimate", "time_estimate_step")


#: The history columns of a 2D body (the paper's case).
HISTORY_COLUMNS = history_columns(2)
#: History columns holding integers (the others are floats).
INTEGER_COLUMNS = ("step", "newton_iterations", "nodes_separated", "nodes_in_compliance", "nodes_at_limit", "substep")
#: The per-node contact arrays of a level: d, ξ, K, the two pressures and the node status (an index in
#: :data:`vpcontact.laws.contact.STATUS_NAMES`).
CONTACT_ARRAYS = ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid", "status")
