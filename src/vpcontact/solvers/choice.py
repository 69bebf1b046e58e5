"""``solver.method = "auto"``: which step method runs, from the sizes and the memory available.

The condensed method (one factorization, Newton on the m contact nodes) is the fastest wherever its
factorization is cheap and its dense m × m algebra fits: every 2D case, and 3D bodies up to about
DIRECT_LIMIT_3D free dofs. Beyond that, in 3D, the factorization's cost grows like n² (nested
dissection: fill n^4/3) while the iterative method's grows like n, and the iterative method is
chosen; it is chosen as well wherever the condensed method's dense algebra does not fit in
CONDENSED_SHARE of the memory. The full method with a direct solver is never faster than one of
the two; it is the reference. The crossovers are measured in docs/performance.md ("Choosing the
method").
"""

from __future__ import annotations

import scipy.sparse as sp

from ..errors import CaseError
from ..memory import available_memory
from .condensed import CONDENSED_SHARE, condensed_fits

#: Free dofs beyond which, in 3D, the iterative method is faster than the condensed one (the quarter
#: ball: condensed 68 s against iterative 90 s at 172k free dofs, about 560 s against 185 s at 498k;
#: docs/performance.md, "Choosing the method").
DIRECT_LIMIT_3D = 250_000
#: Bytes per stored entry of the stiffness matrix that the iterative method holds at its peak: the
#: stiffness, its absolute value, the rotated matrix and the Newton matrix (CSR: 12 bytes an entry
#: each), the multigrid hierarchy in nodal blocks and its construction's temporaries. Measured peak
#: resident memory over nnz(A) on the quarter ball: 114–116 bytes per entry beyond the problem's own
#: memory at 0.5M–2M dofs (docs/performance.md).
ITERATIVE_BYTES_PER_ENTRY = 120


def iterative_memory(A: sp.spmatrix) -> int:
    """Bytes the iterative method needs for the stiffness A (free dofs), at its peak."""
    return ITERATIVE_BYTES_PER_ENTRY * A.nnz


def chosen_method(method: str, A: sp.spmatrix, N: sp.spmatrix, dim: int) -> tuple[str, str]:
    """The step method to run for ``solver.method`` and why, in words (summary.json's solver_reason)."""
    if method != "auto":
        return method, f"solver.method = \"{method}\""
    n, m = A.shape[0], N.shape[0]
    fits, needed, available = condensed_fits(N, n)
    dense = (f"the condensed method's dense algebra for {m} contact nodes ({needed / 2**30:.3g} GiB) "
             f"{'fits in' if fits else 'exceeds'} {CONDENSED_SHARE:.0%} of the {available / 2**30:.1f} GiB available")
    if not fits:
        return "iterative", f"solver.method = \"auto\": {dense}"
    if dim == 3 and n > DIRECT_LIMIT_3D:
        return "iterative", (f"solver.method = \"auto\": {n} free dofs in 3D, more than {DIRECT_LIMIT_3D}: the "
                             f"iterative method is faster than a factorization there")
    return "condensed", f"solver.method = \"auto\": {dense}" + \
        (f", and {n} free dofs in 3D are at most {DIRECT_LIMIT_3D}" if dim == 3 else "")


def check_iterative_memory(A: sp.spmatrix) -> None:
    """Refuse, before building anything, an iterative method that would not fit in memory."""
    needed, available = iterative_memory(A), available_memory()
    if needed > available:
        raise CaseError(f"solver.method = \"iterative\" needs about {needed / 2**30:.1f} GiB for {A.shape[0]} dofs "
                        f"({A.nnz} stiffness entries), more than the {available / 2**30:.1f} GiB available; use a "
                        f"coarser mesh")
