"""Typed failures of the linear algebra: callers decide by type, never by the text of a message.

    SolverError            a linear solver failed (the base class)
    SingularMatrixError    a matrix that must be invertible (or positive definite) is not, to
                           working precision: a Newton matrix (the step is cut) or the stiffness
                           itself (a degenerate mesh: bad input)
    SolverMemoryError      a factorization ran out of memory
    NotConvergedError      an iterative solver did not reach its tolerance within its iterations (CG
                           of the iterative method, GMRES of the condensed one): the step is cut
"""


class SolverError(RuntimeError):
    """A linear solver failed."""


class SingularMatrixError(SolverError):
    """A matrix is singular (or not positive definite) to working precision."""


class SolverMemoryError(SolverError, MemoryError):
    """A factorization ran out of memory."""


class NotConvergedError(SolverError):
    """An iterative linear solver did not reach its tolerance."""
