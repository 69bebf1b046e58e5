"""What each step method will cost here: the cost model behind ``solver.method = "auto"`` and ``vpcontact check``.

Each method's wall time is predicted as its set-up plus its time loop, from what the work is (flops, or passes
over a matrix) and how fast this machine does it now:

- **the machine** (:class:`MachineRates`): the flop rate of a dense matrix product on one thread, and the seconds
  of one product with the problem's own stiffness A (a measure of the memory bandwidth that sparse and iterative
  work runs at): this machine kind's reference rates, by which "auto" chooses (the same case, the same method,
  on every run), and the rates probed in the process now (about 0.05 s), by which the times are reported;
- **the direct factor** (:func:`factor_work`): the flops and stored entries of the factorization of A0 that the
  condensed method makes (in Schur mode on its c contact dofs), as MKL PARDISO's symbolic analysis counts them
  (the ordering the factorization itself will use; a second or so at 10⁵ dofs), or without PARDISO a law in
  the dofs fitted to those counts;
- **constants measured on this machine kind** (below, each with its measurement): the rates PARDISO and the
  dense Cholesky reach against the dense probe, matrix passes per CG iteration, CG iterations per Newton
  iteration, GMRES iterations per condensed Newton iteration, Newton iterations per step.

The three methods, for n free dofs, m contact nodes, c contact dofs, and ``steps`` steps:

- condensed: set-up = factorization (flops / PARDISO's rate) + condensation (the Cholesky of the c × c Schur
  complement, c³/3, and S = N_C S_C⁻¹ N_Cᵀ, 2 c² m); time loop = the first Newton matrix's LU ((2/3) m³ on one
  thread) + per Newton iteration GMRES_PER_NEWTON × (two passes over an m × m matrix) + per step the solves
  with the factor that the step needs (one for a viscoplastic history, one for a written field);
- iterative: set-up = the multigrid hierarchy (AMG_SETUP_PASSES products with A); time loop = per Newton
  iteration CG_PER_NEWTON × CG_PASSES products with A;
- full: per Newton iteration one numerical factorization of the Newton matrix (the plain factor's flops).

and each method's memory: the process's own now (the problem) plus the method's peak (:func:`predict`).
"""

from __future__ import annotations

import os
import time
from dataclasses import asdict, dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from ..memory import available_memory
from .condensed import condensed_fits, condensed_memory
from .factorization import condensation_dofs, contact_dofs, installed_backends, rotates

#: The flop rate of PARDISO's numerical factorization (its two threads, supernodes of dense blocks) over the
#: one-thread dense product probe's.
PARDISO_SPEED = 0.3
#: The flop rate of SciPy's dense Cholesky and triangular solves (all threads) over the one-thread probe's.
DENSE_SPEED = 1.8
#: Passes over A (products with A) that one CG iteration preconditioned by pyamg's V-cycle costs, with the
#: Newton iteration's own work per CG iteration.
CG_PASSES = 25.0
#: CG iterations per Newton iteration, CG started along the last correction (:mod:`.full`): 5.5–6.1 on the quarter
#: ball at 24k, 71k and 300k dofs and on the punch at 30k (7.4–8.8 from zero, 71k to 2M dofs).
CG_PER_NEWTON = 6.0
#: Products with A that the multigrid set-up costs.
AMG_SETUP_PASSES = 700.0


class MultigridSpeed(NamedTuple):
    """A multigrid backend of the iterative method against pyamg's, which CG_PASSES, CG_PER_NEWTON and
    AMG_SETUP_PASSES were measured with: the time of a CG iteration, the CG iterations per Newton system and the
    time of the set-up, each as a share of pyamg's."""

    cg_iteration: float
    cg_iterations: float
    setup: float


#: The multigrid backends (``solver.multigrid``) against pyamg's. PETSc's GAMG, on the quarter ball's Newton
#: matrices at 69k and 172k free dofs (one Newton system to 1e-8, medians of 3, docs/performance.md, "The iterative
#: method with PETSc's GAMG"): 32 and 85 ms a CG iteration against 64 and 152, 15 and 17 iterations against 13,
#: set-up 2.3 and 5.5 s against 4.1 and 8.1.
MULTIGRID_SPEEDS = {"pyamg": MultigridSpeed(1.0, 1.0, 1.0), "petsc": MultigridSpeed(0.53, 1.2, 0.62)}
#: GMRES iterations per Newton iteration of the condensed method (about 6 on the quarter ball, 3 on the punch).
GMRES_PER_NEWTON = 5.0
#: Newton iterations per time step.
NEWTON_PER_STEP = 1.7
#: The iterative method's Newton iterations over the direct methods' (its inexact solves: 1.0 on the quarter
#: ball, 1.5 on the punch).
INEXACT_NEWTON = 1.0
#: Seconds of the time loop's own work per Newton iteration and per step whatever the method (evaluating the laws,
#: the step's records: the paper's half disc at 1/64 and 1/128, condensed, 1.6–2.4 ms per Newton iteration).
NEWTON_OVERHEAD_S = 1.5e-3
STEP_OVERHEAD_S = 1.5e-3
#: Bytes per stored entry of the stiffness matrix that the iterative method holds at its peak: the
#: stiffness, its absolute value, the rotated matrix and the Newton matrix (CSR: 12 bytes an entry
#: each), the multigrid hierarchy in nodal blocks and its construction's temporaries. Measured peak
#: resident memory over nnz(A) on the quarter ball: about 95 bytes per entry beyond the problem's own memory at
#: 300k and 2M dofs, since |A| is made a block of rows at a time and the earlier Newton matrix is released
#: before a hierarchy is built again (114–116 before; docs/performance.md, "Set-up that keeps up").
ITERATIVE_BYTES_PER_ENTRY = 100


def matrix_bytes(A: sp.csr_matrix) -> int:
    """Bytes a CSR matrix holds: its values, column indices and row pointers."""
    return int(A.data.nbytes + A.indices.nbytes + A.indptr.nbytes)


def iterative_memory(A: sp.spmatrix) -> int:
    """Bytes the iterative method needs for the stiffness A (free dofs), at its peak."""
    return ITERATIVE_BYTES_PER_ENTRY * A.nnz


#: This machine kind's rates (2-core AMD EPYC, 24 GB; ``MachineRates.probe`` on the quarter ball's stiffness at
#: 24k and 71k dofs, 2026-11-27, load average 2–3): 24.1 GF/s for the one-thread 512² product, 5–12 GB/s for a
#: product with A (the smaller matrix partly in cache).
REFERENCE_FLOPS = 25e9
REFERENCE_BANDWIDTH = 8e9


@dataclass(frozen=True)
class MachineRates:
    """How fast this process computes now: ``dense_flops`` (flop/s of a 512² matrix product on one thread) and
    ``matrix_pass`` (seconds of one product with the stiffness A)."""

    dense_flops: float
    matrix_pass: float

    @classmethod
    def reference(cls, A: sp.csr_matrix) -> "MachineRates":
        """The rates of this machine kind, quiet: REFERENCE_FLOPS, and a pass over A's 12 bytes an entry at
        REFERENCE_BANDWIDTH."""
        return cls(dense_flops=REFERENCE_FLOPS, matrix_pass=12 * A.nnz / REFERENCE_BANDWIDTH)

    @classmethod
    def probe(cls, A: sp.csr_matrix) -> "MachineRates":
        """Measure both (the best of three tries each, about 0.05 s in all)."""
        from threadpoolctl import threadpool_limits

        x = np.ones(A.shape[1])
        product = min(_timed(lambda: A @ x) for _ in range(3))
        with threadpool_limits(limits=1, user_api="blas"):
            return cls(dense_flops=_dense_flops(), matrix_pass=product)


@lru_cache(maxsize=1)
def _dense_flops() -> float:
    """Flop/s of a 512² matrix product on the BLAS's current threads (measured once per process: 11 ms a try)."""
    a = np.random.default_rng(0).standard_normal((512, 512))
    return 2 * 512**3 / min(_timed(lambda: a @ a) for _ in range(3))


def _timed(work) -> float:
    started = time.perf_counter()
    work()
    return max(time.perf_counter() - started, 1e-9)


@dataclass(frozen=True)
class FactorWork:
    """The factorization of A0 that the condensed method makes: its ``flops`` and stored ``entries`` and the
    ``bytes`` it needs (PARDISO's counts, or the law's); ``counted``: by PARDISO's analysis."""

    flops: float
    entries: float
    bytes: float
    counted: bool


#: Without PARDISO's count, the factorization's flops and entries as laws of the free dofs n, fitted to PARDISO's
#: counts (Schur mode): in 3D flops ≈ FLOPS_3D (n / 10⁵)², entries ≈ ENTRIES_3D (n / 10⁵)^(4/3) (the quarter ball at
#: 23k, 69k, 172k free dofs: 2.1e11–2.3e11 and 8.2e7–9.7e7); in 2D flops ≈ FLOPS_2D (n / 10⁵)^1.5, entries ≈
#: ENTRIES_2D n / 10⁵ (the paper's half disc at 23k and 93k: 2.2e9–2.4e9 and 6.8e6–8.5e6).
FLOPS_3D, ENTRIES_3D = 2.2e11, 9.0e7
FLOPS_2D, ENTRIES_2D = 2.3e9, 8.0e6


def factor_work(A: sp.csr_matrix, N: sp.csr_matrix, dim: int, count: bool = True) -> FactorWork:
    """The work of factoring A0 = A + r NᵀN in Schur mode on the dofs of the condensation (the contact dofs, or
    in the normal frame the normal dofs: :func:`.factorization.condensation_dofs`): PARDISO's symbolic analysis
    of it when ``count`` and PARDISO is installed, else the laws above."""
    if count and "pardiso" in installed_backends():
        from .normal_frame import NormalFrame
        from .pardiso import Pardiso

        A0 = (A + N.T @ N).tocsr()  # A0's pattern, Q A0 Q's too (the values do not change the analysis' counts)
        if rotates(N):
            frame = NormalFrame(N)
            dofs = np.sort(frame.normal_dof[frame.has_normal])
        else:
            dofs = contact_dofs(N)
        analysis = Pardiso(A0, dofs, analyse_only=True)
        return FactorWork(analysis.factor_flops, analysis.factor_nonzeros, analysis.factor_bytes, True)
    n = A.shape[0] / 1e5
    flops, entries = (FLOPS_3D * n**2, ENTRIES_3D * n ** (4 / 3)) if dim == 3 else (FLOPS_2D * n**1.5, ENTRIES_2D * n)
    return FactorWork(flops, entries, 12 * entries, False)


@dataclass(frozen=True)
class MethodCost:
    """The predicted cost of one method: seconds of its set-up and time loop, bytes of memory at its peak (the
    process's own included), and whether its algebra fits in the memory available."""

    method: str
    setup_s: float
    loop_s: float
    memory_bytes: int
    fits: bool

    @property
    def total_s(self) -> float:
        return self.setup_s + self.loop_s

    def as_dict(self) -> dict:
        return {**asdict(self), "total_s": self.total_s}


@dataclass(frozen=True)
class Prices:
    """Seconds of each unit of work of a time loop at some rates: a CG iteration of the iterative method (its
    V-cycle and products with A), a GMRES iteration of the condensed method (two passes over m × m matrices), an
    LU of its m × m Newton matrix, a solve with the direct factor (a forward and a backward substitution), the
    direct factorization itself (the full method's per Newton iteration), and the loop's own work per Newton
    iteration and per step."""

    cg_iteration: float
    gmres_iteration: float
    newton_lu: float
    factor_solve: float
    factorization: float
    newton_overhead: float
    step_overhead: float

    @classmethod
    def of(cls, A: sp.csr_matrix, N: sp.csr_matrix, rates: MachineRates, factor: FactorWork | None,
           multigrid: str = "pyamg") -> "Prices":
        """The prices for stiffness A and contact operator N on the free dofs on a machine of ``rates``, with the
        direct factor's work ``factor`` (None: the direct methods' prices are NaN) and the iterative method's
        ``multigrid`` backend (a key of MULTIGRID_SPEEDS)."""
        m = N.shape[0]
        entry = rates.matrix_pass / max(A.nnz, 1)  # seconds per stored entry read, as in a product with A
        gmres = 2 * m * m * (8 / 12) * entry  # S and the LU read, 8 bytes an entry (A's: 12)
        direct = ((np.nan,) * 3 if factor is None else
                  ((2 / 3) * m**3 / rates.dense_flops, 2 * factor.entries * entry,
                   factor.flops / (PARDISO_SPEED * rates.dense_flops)))
        cg = CG_PASSES * rates.matrix_pass * MULTIGRID_SPEEDS[multigrid].cg_iteration
        return cls(cg, gmres, *direct, NEWTON_OVERHEAD_S, STEP_OVERHEAD_S)

    def overhead(self, steps: float, newton: float) -> float:
        """The loop's own work over ``steps`` steps of ``newton`` Newton iterations in all."""
        return steps * self.step_overhead + newton * self.newton_overhead


def predict(A: sp.csr_matrix, N: sp.csr_matrix, dim: int, steps: int, *, history: bool, field_steps: int,
            rates: MachineRates, factor: FactorWork | None, resident: int,
            newton_per_step: float = NEWTON_PER_STEP, multigrid: str = "pyamg") -> dict[str, MethodCost]:
    """The cost of each method for stiffness A and contact operator N on the free dofs, ``steps`` time steps
    (``history``: a viscoplastic history, a bulk solve at every step; ``field_steps``: steps whose fields are
    written), on a machine of ``rates``, the condensed factor's work ``factor`` (None: not wanted, the condensed
    and full methods are not predicted), ``resident`` bytes the process holds already (the problem) and
    ``newton_per_step`` Newton iterations a step (NEWTON_PER_STEP, or as a run observes them); the iterative
    method's multigrid is ``multigrid`` (a key of MULTIGRID_SPEEDS)."""
    n, m, c = A.shape[0], N.shape[0], condensation_dofs(N)
    available = available_memory()
    flops1 = rates.dense_flops
    price = Prices.of(A, N, rates, factor, multigrid)
    speed = MULTIGRID_SPEEDS[multigrid]
    newton = newton_per_step * steps
    overhead = price.overhead(steps, newton)
    costs = {}
    amg = iterative_memory(A)
    costs["iterative"] = MethodCost("iterative", AMG_SETUP_PASSES * rates.matrix_pass * speed.setup,
                                    INEXACT_NEWTON * newton * CG_PER_NEWTON * speed.cg_iterations * price.cg_iteration
                                    + overhead,
                                    resident + amg, amg <= available)
    if factor is None:
        return costs
    condensation = (c**3 / 3 + 2 * c * c * m) / (DENSE_SPEED * flops1)
    dense = condensed_memory(N, n)
    solves = steps * (1.0 if history else 0.0) + field_steps
    costs["condensed"] = MethodCost("condensed", price.factorization + condensation,
                                    price.newton_lu + newton * GMRES_PER_NEWTON * price.gmres_iteration
                                    + solves * price.factor_solve + overhead,
                                    int(resident + factor.bytes + dense),
                                    condensed_fits(N, n)[0] and factor.bytes + dense <= available)
    costs["full"] = MethodCost("full", 0.0, newton * (price.factorization + price.factor_solve) + overhead,
                               int(resident + factor.bytes), factor.bytes <= available)
    return costs


def observed_loop_seconds(method: str, work, steps: int, newton: int, history: bool, price: Prices) -> float:
    """The time loop so far of a run of ``method``, priced at ``price``: its counted ``work`` (a
    :class:`~.base.SolverWork`: Krylov iterations, Newton matrices factored) over ``steps`` steps of ``newton``
    Newton iterations in all, ``history``: a bulk solve at every step. What the loop computes only for its
    outputs (the fields written) is left out, as in the choice (:func:`predict` with field_steps 0), and so is the
    condensed method's first LU, a one-off its prediction counts apart."""
    overhead = price.overhead(steps, newton)
    if method == "iterative":
        return work.krylov_iterations * price.cg_iteration + overhead
    if method == "condensed":
        return (work.krylov_iterations * price.gmres_iteration + max(work.newton_factorizations - 1, 0)
                * price.newton_lu + (steps if history else 0) * price.factor_solve + overhead)
    return work.newton_factorizations * (price.factorization + price.factor_solve) + overhead


def resident_memory() -> int:
    """Bytes this process holds now (its resident set), 0 where it cannot be read."""
    try:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0
