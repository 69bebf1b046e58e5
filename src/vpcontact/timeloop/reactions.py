"""The forces of the Dirichlet conditions and the motion of the parts they hold, at a converged level.

At a converged level the discrete equilibrium of the step (README)

    A u + Σ_i N_iᵀ (w_i ρK(ξ)p(d_i) + λ_i) = F(t) − Bᵀz

holds at the free dofs. At a held dof it does not: the difference is the force the constraint exerts on the
body there, the reaction

    R = A u + Bᵀz + Σ_i N_iᵀ (w_i ρK(ξ)p(d_i) + λ_i) − F(t)      (at the held dofs).

A part's reaction in component c is the sum of R over the dofs of component c it holds (a dof held by several
parts is shared equally among them, so that the parts add up to the whole reaction); its displacement in
component c is the plain mean of u_c over its nodes (the prescribed u_D in a component it holds). Both are linear in
u: their rows, restricted to the free dofs, are one small matrix M (2 k rows, k = parts × d) that the step solver
applies to its solution (``solver.functionals``: the condensed method without recovering u), and their rows on the
held dofs, M_h, apply to the prescribed u_D(t) there (:mod:`vpcontact.problem.constraints`). Summed over every
dof, A u and Bᵀz vanish (a translation strains nothing), so the reactions, the applied force Σ F(t) and the
contact force −Σ_i (w_i ρKp + λ_i) ν_i balance, to the residual of the free dofs' equilibrium: summary.json
reports how well (:func:`vpcontact.results.balance.balance`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh.cells import coordinates
from ..results.columns import held_part_columns


class Reactions:
    """The reaction and mean displacement of each Dirichlet part of ``problem`` (see the module's docstring)."""

    def __init__(self, problem, parts: tuple[str, ...]):
        """``parts``: the Dirichlet parts (``Discretization.held_parts``), the order of the columns."""
        basis, dim = problem.basis, problem.mesh.dim
        dofs = basis.nodal_dofs  # (d, nodes)
        self.parts, self.dim, self._nodal_dofs = parts, dim, dofs
        held = np.zeros((len(parts), basis.N), dtype=bool)
        for entry in problem.constraints.entries:
            held[parts.index(entry.label), dofs[list(entry.components)][:, entry.nodes]] = True
        share = np.divide(1.0, held.sum(axis=0), out=np.zeros(basis.N), where=held.any(axis=0))
        rows, columns = [], []  # row p d + c of E: part p, component c
        for p in range(len(parts)):
            for c in range(dim):
                dofs_held = dofs[c][held[p, dofs[c]]]
                rows.append(np.full(dofs_held.size, p * dim + c))
                columns.append(dofs_held)
        columns = np.concatenate(columns) if parts else np.zeros(0, dtype=int)
        rows = np.concatenate(rows) if parts else np.zeros(0, dtype=int)
        #: E (k × dofs): the sum of a part's share of the held dofs of one component
        self.E = sp.csr_matrix((share[columns], (rows, columns)), shape=(len(parts) * dim, basis.N))
        mean = []
        for part in parts:
            nodes = np.unique(np.concatenate([e.nodes for e in problem.constraints.entries if e.label == part]))
            mean.append(sp.csr_matrix((np.full(dim * nodes.size, 1.0 / nodes.size),
                                       (np.repeat(np.arange(dim), nodes.size), dofs[:, nodes].ravel())),
                                      shape=(dim, basis.N)))
        free, constraints = problem.free, problem.constraints
        #: M (2k × free dofs): E A (the elastic part of the reactions) over the mean displacements
        whole = problem.ranks.sum_matrix  # on MPI ranks, E A from every rank's rows of A
        self.M = sp.vstack([whole(self.E @ problem.A[:, free]), *(m[:, free] for m in mean)]).tocsr() if parts else None
        #: M_h (2k × held dofs): the same rows on the held dofs, for a prescribed u_D (None: u_D = 0)
        self.M_held = None if not (parts and constraints.moves) else sp.vstack(
            [whole(self.E @ problem.A[:, constraints.held]), *(m[:, constraints.held] for m in mean)]).tocsr()
        self._contact = (self.E @ problem.surface.operator.T).tocsr()  # k × m: E Nᵀ
        self._weights = problem.surface.weights
        self.columns = held_part_columns(dim, parts)

    def row(self, functionals: np.ndarray, compliance: np.ndarray, lam: np.ndarray, load: np.ndarray,
            history_force: np.ndarray | None, held: np.ndarray | None) -> dict[str, float]:
        """The history columns of a level: ``functionals`` = M u (the step solver's), the compliance pressure and
        λ at the contact nodes, F(t) and Bᵀz (None: z = 0) at every dof, u_D(t) at the held dofs (None: u_D = 0);
        with ``applied_force_<c>``, Σ F(t)_c."""
        applied = load[self._nodal_dofs].sum(axis=1)
        values = {f"applied_force_{c}": applied[i] for i, c in enumerate(coordinates(self.dim))}
        if not self.parts:
            return values
        k = len(self.parts) * self.dim
        if held is not None:
            functionals = functionals + self.M_held @ held
        R = functionals[:k] + self._contact @ (self._weights * compliance + lam) - self.E @ load
        if history_force is not None:
            R += self.E @ history_force
        quantities = np.column_stack([R.reshape(-1, self.dim), functionals[k:].reshape(-1, self.dim)]).ravel()
        values.update(zip(self.columns, quantities.tolist()))
        return values
