"""The iterative method on several MPI ranks: one step problem solved by all of them (``mpiexec -n N``).

The mesh's nodes are partitioned (:mod:`vpcontact.parallel.partition`) and each rank holds its share of the Newton
iteration of :class:`~.full.IterativeNewton`: its rows of the stiffness matrix (the rows of its nodes' free dofs,
their columns its own dofs and its ghosts, :mod:`vpcontact.parallel.dofs`), its contact nodes (those of its nodes:
their normal frame, weights, gaps, multipliers and the law's values there), its rows of the rigid motions, and its
rows of PETSc's Newton matrix, solved by CG with GAMG on all ranks together, the rigid motions as near-null space
and the hierarchy kept across Newton matrices as in one process (:mod:`.petsc_gamg`). The iteration is
IterativeNewton's own, line for line: its products need the ghosts' values (one exchange with the neighbouring
ranks) and its decisions only reductions (norms, the dot products of CG's start, the complementarity maximum and
whether the active set changed), so every rank takes the same decisions.

The time loop runs on every rank, on the whole problem but for the stiffness (each rank assembled its rows alone,
:mod:`vpcontact.problem.build`) and the elements' history (each rank's own, :mod:`vpcontact.parallel.elements`): it
gives each step's data, and
:class:`DistributedNewton` hands each rank its share and gathers the step's solution (u, λ, d and the active
set) on every rank. The solution equals one process's iterative method's to the Newton tolerance (CG and GAMG on
partitioned matrices take other iterates), and what the solver keeps across steps (the last correction, the
Newton matrix of the hierarchy) is kept whole, in the order of one process: a checkpoint of a run on N ranks resumes
on any number of ranks, one included.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from ..parallel.dofs import RankDofs
from ..parallel.partition import NodePartition
from ..progress import SILENT, Progress, size
from .base import DisplacementSolution, SolverWork, StepData, StepSolution
from .cost import iterative_memory
from .full import IterativeNewton
from .normal_frame import NormalFrame
from .petsc_gamg import GAMGConjugateGradient, NodalBlocks


@dataclass(frozen=True)
class RankStep(StepData):
    """One rank's share of a step's data: its rows of b, its contact nodes' law and ξ, and ‖b‖ of the whole b."""

    whole_b_norm: float = 0.0

    @property
    def b_norm(self) -> float:
        return self.whole_b_norm


class RankLaw:
    """The contact law at one rank's contact nodes ``contact`` (among the m nodes), with the history ``xi_prev`` of
    all m: a law's values can vary from node to node, so it is evaluated at every node (the others unpressed,
    m values, few against the dofs) and kept at the rank's."""

    def __init__(self, law, contact: np.ndarray, xi_prev: np.ndarray):
        self._law, self._contact, self._xi_prev = law, contact, xi_prev
        self.g = law.g if np.ndim(law.g) == 0 else np.asarray(law.g)[contact]

    def limit(self, nodes: np.ndarray):
        """g at the rank's contact nodes ``nodes`` (an index or a mask)."""
        return self.g if np.ndim(self.g) == 0 else self.g[nodes]

    def pressure(self, d: np.ndarray, xi_prev: np.ndarray, k: float) -> tuple[np.ndarray, np.ndarray]:
        """The compliance pressure and its derivative at the rank's nodes (:meth:`ContactLaw.pressure`)."""
        whole = np.zeros(self._xi_prev.size)
        whole[self._contact] = d
        pressure, derivative = self._law.pressure(whole, self._xi_prev, k)
        return pressure[self._contact], derivative[self._contact]


class RankNewton(IterativeNewton):
    """IterativeNewton on one rank's share (see the module's docstring): ``A`` its rows, ``N`` its contact nodes'
    rows on its dofs, ``dofs`` its dofs and ghosts, ``ghost_frame`` the Q of its ghosts' columns, ``blocks`` where
    its rows sit in PETSc's matrix."""

    def __init__(self, *args, dofs: RankDofs, ghost_frame: sp.csr_matrix, blocks: NodalBlocks, dim: int,
                 near_nullspace: np.ndarray, progress: Progress = SILENT, expected_seconds: float | None = None):
        self.dofs, self._ghost_frame, self._blocks = dofs, ghost_frame, blocks
        super().__init__(*args, near_nullspace=near_nullspace, free=blocks.free, dim=dim, nodes=0,
                         multigrid="petsc", progress=progress, expected_seconds=expected_seconds)

    def _rotated(self, A: sp.csr_matrix) -> sp.csr_matrix:
        """Q A Q on the rank's rows, the columns turned by the frames of its own and its ghosts' contact nodes."""
        return self.frame.rotate(A, sp.block_diag((self.frame.Q, self._ghost_frame), format="csr"))

    def _linear_solver(self, factorization: str) -> tuple:
        """CG preconditioned by GAMG on every rank's rows together."""
        _, dim, _, near_nullspace = self._layout
        memory = f"{size(iterative_memory(self.A))} on this rank at the method's peak"
        expected = f"{self._expected}, {memory}" if self._expected else f"; expected: {memory}"
        return GAMGConjugateGradient(self._blocks.free, dim, 0, self.frame.Q @ near_nullspace, self.progress, expected,
                                     blocks=self._blocks), False


class DistributedNewton(DisplacementSolution):
    """The iterative method on all the ranks of ``partition`` (see the module's docstring), with the interface of a
    step solver (:mod:`vpcontact.solvers`) over the whole problem: ``A`` and ``N`` on the free dofs ``free`` of
    a ``dim``-dimensional mesh, ``rigid`` the rigid motions held only by contact and ``near_nullspace`` all the rigid
    motions (free dofs, k)."""

    name = IterativeNewton.name
    reason = ""

    def __init__(self, A: sp.csr_matrix, N: sp.csr_matrix, weights, gap0, r, tolerance, max_iterations, length_scale,
                 rigid: np.ndarray, *, partition: NodePartition, free: np.ndarray, dim: int,
                 near_nullspace: np.ndarray, progress: Progress = SILENT, expected_seconds: float | None = None):
        started = time.perf_counter()
        ranks = partition.ranks
        self.ranks, self.Z, self._sizes = ranks, rigid, (A.shape[0], N.shape[0])
        self.dofs = dofs = RankDofs(partition, free, dim, A)
        N = sp.csr_matrix(N)
        has = np.diff(N.indptr) > 0  # a clamped node (an empty row) goes to rank 0
        first = np.zeros(N.shape[0], dtype=np.int64)
        first[has] = N.indices[N.indptr[:-1][has]]  # a contact node's first free dof: its node's rank owns it
        row_owner = np.where(has, partition.owner[free[first] // dim], 0)
        self.contact = np.flatnonzero(row_owner == ranks.rank)
        columns = np.concatenate([dofs.owned, dofs.ghosts])
        local_A = A[dofs.owned][:, columns].tocsr()
        ghost_rows = np.flatnonzero(has & (dofs.local[first] >= dofs.owned.size))
        ghost_frame = NormalFrame(N[ghost_rows][:, dofs.ghosts]).Q
        rows = partition.numbered[free[dofs.owned] // dim] - partition.offset
        blocks = NodalBlocks(dim * rows + free[dofs.owned] % dim, dofs.petsc, dim * partition.count,
                             dim * partition.offset, dim * partition.numbered.size, ranks)
        self.partition_time = time.perf_counter() - started
        self.rank = RankNewton(local_A, N[self.contact][:, dofs.owned], weights[self.contact], gap0[self.contact], r,
                               tolerance, max_iterations, length_scale, rigid[dofs.owned], dofs=dofs,
                               ghost_frame=ghost_frame, blocks=blocks, dim=dim,
                               near_nullspace=near_nullspace[dofs.owned], progress=progress,
                               expected_seconds=expected_seconds)
        #: each rank's share: its free dofs, its ghosts (the values it receives at each exchange), its contact nodes
        self.shares = {"free_dofs": ranks.each(int(dofs.owned.size)), "ghost_dofs": ranks.each(int(dofs.ghosts.size)),
                       "contact_nodes": ranks.each(int(self.contact.size))}
        self._correction = None  # the rank solver's, whole (kept)
        self._hierarchy = None  # the Newton matrix of the hierarchy, whole: (diagonal, fixed)
        self._setups = 0

    @property
    def r(self) -> float:
        return self.rank.r

    @property
    def timings(self) -> dict[str, float]:
        return {"partition": self.partition_time, **self.rank.timings}

    def work(self) -> SolverWork:
        return self.rank.work()

    def solve(self, step: StepData, previous: StepSolution | None) -> StepSolution:
        """The step's solution by all the ranks, whole on every rank."""
        owned, contact = self.dofs.owned, self.contact
        mine = RankStep(step.b[owned], RankLaw(step.law, contact, step.xi_prev), step.xi_prev[contact], step.k,
                        whole_b_norm=step.b_norm)
        start = None
        if previous is not None:
            start = replace(previous, u=previous.u[owned], lam=previous.lam[contact], d=previous.d[contact],
                            active=previous.active[contact])
        solution = self.rank.solve(mine, start)
        n, m = self._sizes
        u = self.dofs.gather(solution.u, n)
        whole = replace(solution, u=u, lam=self.ranks.gather(solution.lam, contact, m),
                        d=self.ranks.gather(solution.d, contact, m),
                        active=self.ranks.gather(solution.active, contact, m))
        if solution.converged:
            self._correction = u - (previous.u if previous is not None else 0.0)
        if self.rank.linear.setups != self._setups:
            self._setups = self.rank.linear.setups
            diagonal, fixed = self.rank._hierarchy_system
            self._hierarchy = (self.dofs.gather(diagonal, n), self.dofs.gather(fixed, n))
        return whole

    def kept(self) -> dict[str, np.ndarray]:
        """IterativeNewton's kept state, whole and in one process's order (a run resumes on any number of ranks)."""
        kept = {} if self._correction is None else {"correction": self._correction}
        if self._hierarchy is None:
            return kept
        diagonal, fixed = self._hierarchy
        return {**kept, "hierarchy_diagonal": diagonal, "hierarchy_fixed": fixed,
                "hierarchy_stale": np.array(self.rank.linear.stale)}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from the kept state of a run on any number of ranks: each rank takes its rows."""
        owned = self.dofs.owned
        mine = {key: arrays[key][owned] for key in ("correction", "hierarchy_diagonal", "hierarchy_fixed")
                if key in arrays}
        if "hierarchy_stale" in arrays:
            mine["hierarchy_stale"] = arrays["hierarchy_stale"]
        self.rank.restore(mine)
        self._correction = arrays.get("correction")
        if "hierarchy_diagonal" in arrays:
            self._hierarchy = (arrays["hierarchy_diagonal"], arrays["hierarchy_fixed"].astype(bool))
            self._setups = self.rank.linear.setups
