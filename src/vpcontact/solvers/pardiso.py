"""MKL PARDISO for real SPD matrices (mtype 2), called through ctypes.

The ``mkl`` wheel ships libmkl_rt; pypardiso's own interface uses the unsymmetric matrix type and
re-checks the matrix at every solve, about 10 times slower per solve (docs/factorizations.md), and
has no Schur complement. This binding passes the upper triangle in zero-based CSR (iparm[34] = 1),
orders with METIS (iparm[1] = 2) and can return the dense Schur complement of chosen dofs while it
factors (iparm[35] = 2); the factor stays usable for ordinary solves, and its solve can be run in its
three parts (phases 331, 332, 333: ``forward``, ``diagonal``, ``backward``). With the Schur complement
the factorization is A = L D Lᵀ with the Schur dofs C ordered last, L's block on C the identity and D's
block on C the Schur complement S_C (factored by PARDISO): the forward substitution leaves
y_C = b_C − A_CI A_II⁻¹ b_I on C (b reduced to C), the diagonal one x_C = S_C⁻¹ y_C there (A⁻¹ b on C),
the backward one the rest of A⁻¹ b (the MKL reference: "for iparm[35] > 0, phases 331, 332 and 333
perform a different decomposition").

Reproducibility: the factorization is bitwise reproducible with several threads, the solve phase is
not (measured with MKL 2026.2 on two threads: the same factor and right-hand side gave results that
differ in the last bits from one call to the next). Solves therefore run on one MKL thread, which
makes them reproducible at no cost (forward and backward substitution are memory bound: 30 ms on one
thread against 34 ms on two at 230k DOFs); MKL's conditional numerical reproducibility mode
(iparm[33] > 0, or MKL_CBWR) also makes them reproducible but 2–3 times slower.
"""

from __future__ import annotations

import ctypes
import glob
import os
import sys
from ctypes.util import find_library
from typing import Callable

import numpy as np
import scipy.sparse as sp

from .errors import SingularMatrixError, SolverError, SolverMemoryError
from ..memory import available_memory

_INT_P = ctypes.POINTER(ctypes.c_int32)
#: PARDISO's error codes (the MKL reference) as typed errors.
_ERRORS = {
    -2: (SolverMemoryError, "not enough memory"),
    -4: (SingularMatrixError, "zero pivot: the matrix is singular or not positive definite"),
    -7: (SingularMatrixError, "the diagonal is singular"),
    -9: (SolverMemoryError, "not enough memory for the out-of-core factorization"),
}
_LIBRARY = None
#: The solve (33) and its forward, diagonal and backward parts.
SOLVE_PHASES = (33, 331, 332, 333)


def library() -> ctypes.CDLL:
    """libmkl_rt (``$MKL_RT``, the environment's lib folder, or the system's); OSError if absent."""
    global _LIBRARY
    if _LIBRARY is None:
        if _gnu_openmp_loaded():
            os.environ.setdefault("MKL_THREADING_LAYER", "SEQUENTIAL")
        candidates = [os.environ.get("MKL_RT")]
        candidates += sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")), key=len)
        candidates.append(find_library("mkl_rt"))
        path = next((c for c in candidates if c), None)
        if path is None:
            raise OSError("libmkl_rt not found (pip install mkl)")
        lib = ctypes.CDLL(path)
        lib.pardiso.restype = None
        lib.MKL_Set_Num_Threads_Local.restype = ctypes.c_int
        lib.MKL_Set_Num_Threads_Local.argtypes = [ctypes.c_int]
        lib.pardiso.argtypes = ([ctypes.c_void_p] + [_INT_P] * 5 + [ctypes.c_void_p] + [_INT_P] * 6
                                + [ctypes.c_void_p, ctypes.c_void_p, _INT_P])
        lib.MKL_Get_Max_Threads()  # MKL chooses its threading layer at its first call: now, not after another library
        _LIBRARY = lib
    return _LIBRARY


def _gnu_openmp_loaded() -> bool:
    """Is GNU's OpenMP runtime (libgomp) in this process already (Linux: its memory map)? Another library brings
    it (gmsh's Python module does); MKL loaded after it runs its threads on it, which changes the last bits of
    PARDISO's results against a process without it (measured: the 3D block's stress sum −61423.53930740095 alone,
    …124 after ``import gmsh``) and hangs a forked child in its first parallel region. MKL then runs sequentially
    (``MKL_THREADING_LAYER``, unless the environment sets it): the bits of a process without it. Loaded before
    libgomp, MKL keeps the layer it chose at its first call (``library`` makes one at once)."""
    try:
        with open("/proc/self/maps") as maps:
            return "libgomp" in maps.read()
    except OSError:
        return False


def use_one_thread() -> None:
    """MKL on one thread in this process from now on (nothing without MKL): what a worker of a local study's pool
    needs. Its workers share the cores, and a forked MKL whose OpenMP runtime is GNU's (loaded before MKL by another
    library: gmsh's Python module, imported by a script that meshes in memory) hangs in its first parallel region
    (measured: gmsh imported, a PARDISO solve, a fork, a solve in the child: it never returns; on one thread it
    does)."""
    try:
        lib = library()
    except OSError:
        return
    lib.MKL_Set_Num_Threads.restype = None
    lib.MKL_Set_Num_Threads.argtypes = [ctypes.c_int]
    lib.MKL_Set_Num_Threads(1)


class Pardiso:
    """One PARDISO handle: ``Pardiso(A, schur_dofs)`` factors (symbolic analysis, a memory check,
    numerical factorization), then ``solve(b)``; ``schur`` holds the dense Schur complement of A on
    ``schur_dofs`` (in ascending dof order) when they were given, and ``factor_nonzeros`` the entries
    PARDISO stores for its supernodal factor (iparm[17]; more than the factor's nonzeros).

    ``analysed(bytes)``, if given, hears of the memory the factorization will take, once the analysis
    has found it; ``factor_flops`` and ``factor_bytes`` are the analysis' counts of the factorization's work
    and memory. ``Pardiso(A, analyse_only=True)`` stops there (what the cost model of :mod:`.cost` asks).
    ``Pardiso(A, refactorable=True)`` only analyses A; ``refactor`` then factors each matrix of A's
    pattern. Such a handle runs every phase on one MKL thread: with MKL 2026.2 a refactorisation on
    two threads after a solve on one (or after an analysis on two) crashes the process (measured:
    a segmentation fault in phase 22, reproducible on a 3D contact matrix of 1,056 dofs).
    """

    def __init__(self, A: sp.spmatrix, schur_dofs: np.ndarray | None = None, refactorable: bool = False,
                 analysed: Callable[[int], None] | None = None, analyse_only: bool = False):
        upper = _upper(A)
        self.n = A.shape[0]
        self._data = np.ascontiguousarray(upper.data, dtype=np.float64)
        self._ia = np.ascontiguousarray(upper.indptr, dtype=np.int32)
        self._ja = np.ascontiguousarray(upper.indices, dtype=np.int32)
        self._pt = np.zeros(64, dtype=np.int64)
        self._iparm = np.zeros(64, dtype=np.int32)
        # own iparm; METIS; count the factor's nonzeros and its flops; zero-based
        self._iparm[[0, 1, 17, 18, 34]] = 1, 2, -1, -1, 1
        self._perm = np.zeros(self.n, dtype=np.int32)
        self.schur = None
        self._refactorable = refactorable or analyse_only
        size = 0 if schur_dofs is None else len(schur_dofs)
        if size:
            self._iparm[35] = 2
            self._perm[np.asarray(schur_dofs)] = 1
        self._call(11)
        #: the numerical factorization's flops (PARDISO's count, iparm[18] in Mflops) and the bytes it will take
        self.factor_flops = 1e6 * float(self._iparm[18])
        self.factor_bytes = self._memory(8 * size * size)
        if analyse_only:
            self.factor_nonzeros = int(self._iparm[17])
            return
        needed = self._check_memory(8 * size * size)
        if analysed is not None:
            analysed(needed)  # the bytes the factorization will take (a progress report)
        self.factor_nonzeros = int(self._iparm[17])
        if refactorable:
            return
        if size:
            out = np.zeros(size * size)
            self._call(22, np.zeros(self.n), out)
            self.schur = out.reshape(size, size)
        else:
            self._call(22)
        self.factor_nonzeros = int(self._iparm[17])

    def refactor(self, A: sp.spmatrix) -> None:
        """Factor A, whose upper triangle has the stored pattern of the matrix analysed, reusing the
        symbolic analysis and the METIS ordering (phase 22 only; a handle made ``refactorable``)."""
        upper = _upper(A)
        if not (np.array_equal(upper.indptr, self._ia) and np.array_equal(upper.indices, self._ja)):
            raise ValueError("refactor needs the sparsity pattern of the matrix analysed")
        self._data[:] = upper.data
        self._call(22)

    def _memory(self, schur_bytes: int) -> int:
        """After the symbolic analysis (phase 11): the bytes the factorization will take (PARDISO's estimate,
        max(iparm[14], iparm[15] + iparm[16]) kB, and the dense Schur complement it returns)."""
        return 1024 * max(int(self._iparm[14]), int(self._iparm[15]) + int(self._iparm[16])) + schur_bytes

    def _check_memory(self, schur_bytes: int) -> int:
        """Refuse, before allocating it, a factorization whose memory (``_memory``) is more than the memory
        available; else that memory (bytes)."""
        needed = self._memory(schur_bytes)
        available = available_memory()
        if needed > available:
            raise SolverMemoryError(f"MKL PARDISO needs about {needed / 2**30:.1f} GiB to factor this {self.n} x "
                                    f"{self.n} matrix, {available / 2**30:.1f} GiB are available")
        return needed

    def _call(self, phase: int, b: np.ndarray | None = None, x: np.ndarray | None = None, nrhs: int = 1) -> None:
        """One PARDISO phase; solves (reproducible: see the module's docstring) and every phase of a
        refactorable handle on one MKL thread."""
        one_thread = phase in SOLVE_PHASES or self._refactorable
        previous = library().MKL_Set_Num_Threads_Local(1) if one_thread else None
        try:
            self._pardiso(phase, b, x, nrhs)
        finally:
            if one_thread:
                library().MKL_Set_Num_Threads_Local(previous)

    def _pardiso(self, phase: int, b: np.ndarray | None, x: np.ndarray | None, nrhs: int) -> None:
        error = ctypes.c_int32(0)
        value = lambda v: ctypes.byref(ctypes.c_int32(v))  # noqa: E731
        library().pardiso(self._pt.ctypes.data, value(1), value(1), value(2), value(phase), value(self.n),
                          self._data.ctypes.data, self._ia.ctypes.data_as(_INT_P), self._ja.ctypes.data_as(_INT_P),
                          self._perm.ctypes.data_as(_INT_P), value(nrhs), self._iparm.ctypes.data_as(_INT_P),
                          value(0), None if b is None else b.ctypes.data, None if x is None else x.ctypes.data,
                          ctypes.byref(error))
        if error.value != 0:
            kind, meaning = _ERRORS.get(error.value, (SolverError, "see the MKL PARDISO error codes"))
            raise kind(f"MKL PARDISO phase {phase} failed with error {error.value} ({meaning})")

    def solve(self, b: np.ndarray) -> np.ndarray:
        """A⁻¹ b for b of shape (n,) or (n, k)."""
        return self._solve(33, b)

    def forward(self, b: np.ndarray) -> np.ndarray:
        """The forward substitution of b (phase 331); with a Schur complement, b reduced to the Schur dofs
        there (see the module's docstring)."""
        return self._solve(331, b)

    def diagonal(self, y: np.ndarray) -> np.ndarray:
        """The diagonal substitution of a forward-substituted y (phase 332); with a Schur complement, the
        solve with it on the Schur dofs."""
        return self._solve(332, y)

    def backward(self, y: np.ndarray) -> np.ndarray:
        """The backward substitution of a diagonally substituted y (phase 333): A⁻¹ b for the y of b."""
        return self._solve(333, y)

    def _solve(self, phase: int, b: np.ndarray) -> np.ndarray:
        """One solve phase on b of shape (n,) or (n, k)."""
        b = np.asarray(b, dtype=np.float64)
        B = np.asfortranarray(b.reshape(self.n, -1))
        X = np.zeros_like(B, order="F")
        self._call(phase, B, X, nrhs=B.shape[1])
        return X[:, 0] if b.ndim == 1 else X

    def __del__(self):
        if getattr(self, "_pt", None) is not None and self._pt.any():
            try:
                self._call(-1)
            except Exception:  # the library may already be unloaded at interpreter exit
                pass


def _upper(A: sp.spmatrix) -> sp.csr_matrix:
    """The upper triangle of A in sorted CSR, explicit zeros kept and every diagonal entry stored
    (zeros too: a missing one crashes PARDISO)."""
    upper = sp.triu(A, format="csr")
    upper.setdiag(upper.diagonal())
    upper.sort_indices()
    return upper
