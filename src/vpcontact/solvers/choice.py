"""``solver.method = "auto"``: the method the cost model predicts to be the fastest here, among those that fit.

The prediction (:mod:`.cost`) weighs each method's set-up against its time loop for this problem's sizes and
steps on this machine now: the condensed method factors once and then solves on the contact nodes, the
iterative one builds a multigrid hierarchy and solves the whole system at every Newton iteration, the full one
factors at every Newton iteration. A method whose own algebra does not fit in the memory available is not
chosen (the condensed method's dense algebra in CONDENSED_SHARE of it, the others' in all of it).
"""

from __future__ import annotations

import scipy.sparse as sp

from ..errors import CaseError
from ..memory import available_memory
from ..parallel.ranks import ALONE, Ranks
from .cost import MethodCost, iterative_memory


def chosen_method(method: str, costs: dict[str, MethodCost]) -> tuple[str, str]:
    """The step method to run for ``solver.method`` and why, in words (summary.json's solver_reason), from the
    predicted ``costs`` of the methods (:func:`.cost.predict`)."""
    if method != "auto":
        return method, f"solver.method = \"{method}\""
    fitting = sorted((cost for cost in costs.values() if cost.fits), key=lambda cost: cost.total_s)
    if not fitting:
        return "iterative", "solver.method = \"auto\": no method's algebra fits in the memory available"
    best, others = fitting[0].method, [cost.method for cost in fitting[1:]]
    unfit = [cost.method for cost in costs.values() if not cost.fits]
    return best, (f"solver.method = \"auto\": the {best} method is predicted fastest here" +
                  (f" (then {', '.join(others)})" if others else "") +
                  (f"; {' and '.join(unfit)} would not fit in the memory available" if unfit else ""))


def check_iterative_memory(A: sp.spmatrix, ranks: Ranks = ALONE) -> None:
    """Refuse, before building anything, an iterative method that would not fit in memory: on MPI ranks
    (``ranks``), A is this rank's rows of the stiffness and the largest rank's share is weighed against the least
    memory available to a rank, the same refusal on every rank."""
    needed, available = ranks.max(iterative_memory(A)), -ranks.max(-available_memory())
    if needed > available:
        shared = f" on each of {ranks.size} ranks" if ranks.size > 1 else ""
        raise CaseError(f"solver.method = \"iterative\" needs about {needed / 2**30:.1f} GiB{shared} for "
                        f"{A.shape[0]} dofs ({int(ranks.sum(A.nnz))} stiffness entries), more than the "
                        f"{available / 2**30:.1f} GiB available; use a coarser mesh"
                        f"{' or more ranks' if ranks.size > 1 else ''}")
