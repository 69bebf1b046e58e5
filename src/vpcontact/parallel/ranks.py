"""The MPI ranks of a run: ``mpiexec -n N vpcontact run CASE --out DIR`` starts N processes that solve one problem.

Every rank reads the case and builds the problem, assembling only its rows of the stiffness
(:mod:`vpcontact.problem.build`); the step solver's vectors, matrices and multigrid are shared among the ranks
(:mod:`vpcontact.solvers.distributed`), each element's viscoplastic history is kept by one rank
(:mod:`.elements`), and rank 0 alone writes the run directory and reports
progress. :func:`launched` tells from the launcher's environment how many ranks were started, before MPI is
initialized, so that a launch on several ranks without mpi4py and petsc4py is refused in one line
(:func:`world`), not run N times over.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError

#: The environment variables in which MPI launchers give the number of ranks started: Open MPI's, MPICH's and
#: Intel MPI's (Hydra), Slurm's srun.
SIZE_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "SLURM_NTASKS")
#: ... and the rank of this process.
RANK_VARIABLES = ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK", "SLURM_PROCID")
#: What a launch on several ranks needs, in words.
INSTALL = ("pip install \"vpcontact[mpi]\" with PETSc's petsc4py built for the MPI of mpiexec (on Debian or "
           "Ubuntu: sh scripts/install-mpi.sh, see docs/mpi.md)")


def launched() -> tuple[int, int]:
    """(rank, size) as the MPI launcher set them in the environment; (0, 1) for a process started alone."""
    for size_name, rank_name in zip(SIZE_VARIABLES, RANK_VARIABLES):
        if size_name in os.environ and (size_name != "SLURM_NTASKS" or "SLURM_STEP_ID" in os.environ):
            try:
                return int(os.environ.get(rank_name, "0")), int(os.environ[size_name])
            except ValueError:
                continue
    return 0, 1


@dataclass(frozen=True)
class Ranks:
    """The ranks of a run and the reductions the step solver needs among them; ``comm`` is mpi4py's communicator
    (None for one process alone, whose reductions are the values themselves)."""

    rank: int = 0
    size: int = 1
    comm: object = None

    @property
    def root(self) -> bool:
        """Whether this is rank 0, the rank that writes and reports."""
        return self.rank == 0

    def sum(self, value):
        """The sum over the ranks of a number or an array (the same shape on every rank)."""
        if self.comm is None:
            return value
        if np.ndim(value) == 0:
            return self.comm.allreduce(float(value))
        total = np.empty_like(np.asarray(value, dtype=float))
        self.comm.Allreduce(np.ascontiguousarray(value, dtype=float), total)
        return total

    def max(self, value: float) -> float:
        """The largest of a number over the ranks (NaN if it is NaN on any rank)."""
        if self.comm is None:
            return value
        values = self.comm.allgather(float(value))  # one collective; MPI's MAX leaves NaN undefined
        return float("nan") if np.any(np.isnan(values)) else float(max(values))

    def all(self, flag: bool) -> bool:
        """Whether ``flag`` holds on every rank."""
        if self.comm is None:
            return bool(flag)
        from mpi4py import MPI

        return bool(self.comm.allreduce(bool(flag), op=MPI.LAND))

    def gather(self, pieces: np.ndarray, order: np.ndarray, total: int) -> np.ndarray:
        """The array of ``total`` rows (entries, or rows of any trailing shape) of which every rank holds ``pieces``
        at the rows ``order`` (the ranks' rows together cover 0..total − 1 once), on every rank."""
        whole = np.empty((total, *pieces.shape[1:]), dtype=pieces.dtype)
        if self.comm is None:
            whole[order] = pieces
            return whole
        row = int(np.prod(pieces.shape[1:], dtype=np.int64))
        counts = np.array(self.comm.allgather(pieces.shape[0]))
        values = np.empty((counts.sum(), *pieces.shape[1:]), dtype=pieces.dtype)
        self.comm.Allgatherv(np.ascontiguousarray(pieces), (values, counts * row))
        positions = np.empty(counts.sum(), dtype=np.int64)
        self.comm.Allgatherv(np.ascontiguousarray(order, dtype=np.int64), (positions, counts))
        whole[positions] = values
        return whole

    def sum_matrix(self, matrix: sp.spmatrix) -> sp.csr_matrix:
        """The sum over the ranks of a sparse matrix (the same shape on every rank; a rank's rows of a matrix whose
        other rows are empty, for the whole matrix), on every rank: one gather of every rank's entries."""
        if self.comm is None:
            return sp.csr_matrix(matrix)
        entries = sp.coo_matrix(matrix)
        pieces = self.comm.allgather((entries.row, entries.col, entries.data))
        rows, columns, values = (np.concatenate(part) for part in zip(*pieces))
        return sp.csr_matrix((values, (rows, columns)), shape=matrix.shape)

    def each(self, value) -> list:
        """Every rank's ``value`` (any picklable object), in the order of the ranks, on every rank."""
        return [value] if self.comm is None else self.comm.allgather(value)

    def first(self, value):
        """Rank 0's ``value`` (any picklable object), on every rank."""
        return value if self.comm is None else self.comm.bcast(value, root=0)

    def decided(self, decide):
        """Rank 0's ``decide()`` on every rank (a check of the run directory, which rank 0 alone holds): its
        value (picklable), or the CaseError it raised, raised on every rank."""
        if self.comm is None:
            return decide()
        outcome = None
        if self.root:
            try:
                outcome = (decide(), None)
            except CaseError as error:
                outcome = (None, str(error))
        value, error = self.comm.bcast(outcome, root=0)
        if error is not None:
            raise CaseError(error)
        return value

    def agreed(self, reason: str | None) -> str | None:
        """A reason to stop that any rank has (the first rank's that has one), on every rank, else None."""
        if self.comm is None:
            return reason
        return next((found for found in self.comm.allgather(reason) if found), None)


#: The ranks of a process started alone.
ALONE = Ranks()


def world() -> Ranks:
    """The ranks this process was launched among: ALONE when it was started alone, else MPI's world through
    mpi4py (initialized here, with PETSc: :func:`.petsc.petsc`). CaseError naming what to
    install when a launch on several ranks finds mpi4py or petsc4py missing."""
    rank, size = launched()
    if size == 1:
        return ALONE
    try:
        from mpi4py import MPI
        import petsc4py  # noqa: F401
    except ImportError as error:
        raise CaseError(f"launched on {size} MPI ranks, but {error.name} is not installed: {INSTALL}") from None
    from .petsc import petsc

    petsc()
    comm = MPI.COMM_WORLD
    return Ranks(comm.Get_rank(), comm.Get_size(), comm)
