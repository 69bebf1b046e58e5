"""Sparse direct factorizations of the SPD matrix A0, behind one small interface:

    factorization = factorize(A0, backend)
    x = factorization.solve(b)                      # b: (n,) or (n, k)
    S = factorization.condensed_operator(N)         # the dense m × m matrix N A0⁻¹ Nᵀ

Backends: "superlu" (SciPy, always installed) and those listed in ``BACKENDS`` that import here.
"""

from __future__ import annotations

import os

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import CaseError

#: Columns of Nᵀ solved at once when S is built by block solves.
BLOCK = 64


class SuperLUFactorization:
    """SciPy's SuperLU with the symmetric mode (minimum degree on A + Aᵀ, diagonal pivots)."""

    name = "superlu"

    def __init__(self, A: sp.spmatrix):
        self._lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                             options={"SymmetricMode": True})

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._lu.solve(b)

    def condensed_operator(self, N: sp.csr_matrix) -> np.ndarray:
        """S = N A0⁻¹ Nᵀ by block solves with BLOCK columns of Nᵀ at a time, symmetrized."""
        return block_condensed_operator(self.solve, N)


def block_condensed_operator(solve, N: sp.csr_matrix) -> np.ndarray:
    """S = N A0⁻¹ Nᵀ from solves with blocks of columns of Nᵀ."""
    m = N.shape[0]
    S = np.empty((m, m))
    NT = N.T.tocsc()
    for start in range(0, m, BLOCK):
        stop = min(start + BLOCK, m)
        S[:, start:stop] = N @ solve(NT[:, start:stop].toarray())
    return 0.5 * (S + S.T)


BACKENDS = {SuperLUFactorization.name: SuperLUFactorization}


def factorize(A: sp.spmatrix, backend: str = "auto"):
    """Factor the SPD matrix A with ``backend`` ("auto": the fastest one installed)."""
    if backend == "auto":
        backend = next(iter(BACKENDS))
    if backend not in BACKENDS:
        raise CaseError(f"solver.factorization = \"{backend}\" is not available here; installed: "
                        f"{', '.join(BACKENDS)}")
    return BACKENDS[backend](A)


def available_memory() -> int:
    """Bytes of memory available to this process now (MemAvailable, else physical memory)."""
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
