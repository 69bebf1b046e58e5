"""How many MPI ranks a case wants for the memory of the machines it runs on (``vpcontact check``).

On N ranks (:mod:`.distributed`) every rank holds the rest of the problem whole (the mesh, the loads and the time
loop's results: ``replicated`` bytes) and 1/N of the stiffness (each rank assembles its rows), of the iterative
method's algebra (its rows of the Newton matrices, of the multigrid hierarchy and of CG's vectors) and of a
viscoplastic body's element history (``shared`` bytes in all). On M machines like this
one, one rank each, a rank needs replicated + shared / M; with r ranks on a machine, that machine needs
r · replicated + shared / M. So more ranks on one machine make a solve faster (its cores share the work) but never
let a larger one fit, and a case that does not fit in one process wants M = ⌈shared / (available − replicated)⌉
machines; none suffices when what every rank holds whole does not fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..progress import size


@dataclass(frozen=True)
class RanksWanted:
    """``ranks``: the fewest MPI ranks (one a machine like this one) whose memory holds the run (None: no number
    does); ``reason``: why, in words."""

    ranks: int | None
    reason: str


def ranks_wanted(replicated: int, shared: int, available: int, cores: int) -> RanksWanted:
    """The ranks a run wants for its memory: ``replicated`` bytes on every rank, ``shared`` among them, ``available``
    on each machine (this one's), ``cores`` a machine."""
    per_rank = (f"each rank holds the rest of the problem whole ({size(replicated)}) and its share of the "
                f"stiffness', the solver's and the element history's {size(shared)}")
    if replicated + shared <= available:
        here = min(cores, (available - shared) // max(replicated, 1))  # the ranks this machine's memory holds
        more = f"; mpiexec -n {here} shares the solve among this machine's cores" if here >= 2 else ""
        return RanksWanted(1, f"one process fits ({size(replicated + shared)} of {size(available)}){more}")
    if replicated >= available:
        return RanksWanted(None, f"no number of ranks fits: {per_rank}, and what every rank holds whole exceeds the "
                                 f"{size(available)} available here")
    machines = math.ceil(shared / (available - replicated))
    return RanksWanted(machines, f"{machines} ranks on {machines} machines like this one, one rank each: {per_rank} "
                                 f"({size(replicated + shared / machines)} a rank, {size(available)} available)")
