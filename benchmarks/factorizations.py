"""Benchmark sparse direct factorization backends for the condensed contact solver (DESIGN §4).

The matrix is the SPD stiffness of the paper's half disc (roller on the axis) plus the reference
contact compliance on the bottom arc, exactly as the condensed solver factors it:
    A0 = A + Nᵀ diag(w r) N,   r = median_i ν_iᵀ A_ii ν_i.
For one backend and one size it measures, in this process:
    factor_s   symbolic + numeric factorization of A0,
    solve_s    one solve with one dense right-hand side (median of 5),
    schur_s    building the dense m × m S = N A0⁻¹ Nᵀ by the backend's best route,
    residual   ‖A0 x − b‖ / ‖b‖ of the solve,
    schur_err  max |S − S_ref| / max |S_ref| against SuperLU (only when --check-schur),
    peak_rss_mb  ru_maxrss of the process (includes building A0; baseline_* give the state
                 after building A0, phase_peak_mb the peak after that point via /proc clear_refs).

Usage:
    python benchmarks/factorizations.py --backend mkl-direct --dofs-target 470000
    python benchmarks/factorizations.py --all [--sizes 30000 130000 470000] > results.json
    python benchmarks/factorizations.py --list
--all runs every importable backend at each size, each measurement in a fresh subprocess of the
same interpreter; backends that do not import are reported as {"available": false, "reason": ...}.

Schur routes: "schur-contact-dofs" factors A0 with the (≤ 2m) dofs that N touches ordered last and
returns their dense Schur complement S_C = A_CC − A_CI A_II⁻¹ A_IC; since (A0⁻¹)_CC = S_C⁻¹,
S = N_C S_C⁻¹ N_Cᵀ exactly (N_C = the columns of N on those dofs). "block-solves-64" solves
A0 X = Nᵀ[:, block] for dense blocks of 64 columns, S = N X. "cholmod-forward-sparse" uses
S = Wᵀ W with W = L⁻¹ P Nᵀ (one sparse forward solve with CHOLMOD's LLᵀ).
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np
import scipy.sparse as sp

SIZES = (30_000, 130_000, 470_000)
TRIANGLES_PER_INV_H2 = 3.63  # half_disc(h): ~3.63/h² triangles, and ~3.63/h² free dofs
BLOCK = 64
STEPS = 563  # time steps of the paper's run: one solve each


# ------------------------------------------------------------------------------------- matrix
def h_for_dofs(target: float) -> float:
    return float(np.sqrt(TRIANGLES_PER_INV_H2 / target))


def build_matrix(h: float):
    """A0 (CSC, SPD), N (CSR, m × n) and the assembly time, exactly as the condensed solver sees them."""
    from vpcontact.fem.assembly import displacement_space, stiffness
    from vpcontact.fem.contact_surface import contact_surface
    from vpcontact.laws.elasticity import Elasticity
    from vpcontact.mesh import half_disc

    t0 = time.perf_counter()
    m = half_disc(h)
    basis = displacement_space(m)
    A = stiffness(basis, Elasticity(1000.0, 0.3))
    free = np.setdiff1d(np.arange(basis.N), basis.nodal_dofs[0, m.nodes("axis")])  # roller on the axis
    surf = contact_surface(m, "bottom_arc", basis.nodal_dofs)
    N = surf.operator[:, free].tocsr()
    A = A[free][:, free]
    # (np.median of the np.matrix that .sum(axis=1) returns is a matrix: ravel it first)
    r = float(np.median(np.asarray(((N @ A).multiply(N)).sum(axis=1)).ravel()))
    A0 = (A + N.T @ sp.diags(surf.weights * r) @ N).tocsc()
    A0.sort_indices()
    N.eliminate_zeros()
    return A0, N, time.perf_counter() - t0


def contact_dofs(N):
    """The dofs N touches (sorted) and N restricted to them (dense, m × |C|)."""
    C = np.unique(N.indices)
    return C, N[:, C].toarray()


def schur_to_S(SC, Nc):
    """S = N_C S_C⁻¹ N_Cᵀ from the Schur complement S_C of A0 on the contact dofs."""
    SC = 0.5 * (SC + SC.T)
    import scipy.linalg as sla

    c, low = sla.cho_factor(SC)
    return Nc @ sla.cho_solve((c, low), Nc.T)


def block_solves(solve, N, n, block=BLOCK):
    """S = N A0⁻¹ Nᵀ by dense multi-RHS solves with blocks of Nᵀ."""
    m = N.shape[0]
    NT = N.T.tocsc()
    S = np.empty((m, m))
    for j in range(0, m, block):
        B = NT[:, j : j + block].toarray()
        X = solve(B)
        S[:, j : j + block] = N @ X
    return 0.5 * (S + S.T)


# ----------------------------------------------------------------------------------- backends
class Backend:
    name = ""
    schur_route = "block-solves-64"

    def factor(self, A0):  # symbolic + numeric
        raise NotImplementedError

    def solve(self, b):  # b: (n,) or (n, k) float64
        raise NotImplementedError

    def schur(self, A0, N):  # dense S = N A0⁻¹ Nᵀ; default: block solves with the factor
        return block_solves(self.solve, N, A0.shape[0])

    @classmethod
    def check(cls):  # raise ImportError/OSError when unavailable
        pass


class SuperLU(Backend):
    permc = "COLAMD"
    options: dict = {}

    @classmethod
    def check(cls):
        import scipy.sparse.linalg  # noqa: F401

    def factor(self, A0):
        from scipy.sparse.linalg import splu

        self.lu = splu(A0, permc_spec=self.permc, **self.options)

    def solve(self, b):
        return self.lu.solve(b)

    def info(self):
        return {"nnz_factor": int(self.lu.L.nnz + self.lu.U.nnz)}


class SuperLUColamd(SuperLU):
    name = "superlu-colamd"


class SuperLUMmd(SuperLU):
    """MMD on Aᵀ+A with symmetric mode and diagonal pivoting: SuperLU's setting for SPD matrices."""

    name = "superlu-mmd"
    permc = "MMD_AT_PLUS_A"
    options = {"diag_pivot_thresh": 0.0, "options": {"SymmetricMode": True}}


class Cholespy(Backend):
    name = "cholespy"

    @classmethod
    def check(cls):
        import cholespy  # noqa: F401

    def factor(self, A0):
        from cholespy import CholeskySolverD, MatrixType

        coo = A0.tocoo()
        self.n = A0.shape[0]
        self.s = CholeskySolverD(
            self.n,
            coo.row.astype(np.int32),
            coo.col.astype(np.int32),
            coo.data.astype(np.float64),
            MatrixType.COO,
        )

    def solve(self, b):
        b = np.ascontiguousarray(b, dtype=np.float64)
        x = np.empty_like(b)
        if b.ndim == 2 and b.shape[1] > 128:  # cholespy: at most 128 right-hand sides per call
            for j in range(0, b.shape[1], 128):
                x[:, j : j + 128] = self.solve(b[:, j : j + 128])
            return x
        self.s.solve(b, x)
        return x


class Cholmod(Backend):
    name = "cholmod"
    schur_route = "cholmod-forward-sparse"

    @classmethod
    def check(cls):
        import sksparse.cholmod  # noqa: F401

    def factor(self, A0):
        from sksparse.cholmod import cholesky

        self.f = cholesky(A0)

    def solve(self, b):
        return self.f(b)

    def schur(self, A0, N):
        # S = N A0⁻¹ Nᵀ = Wᵀ W with A0 = Pᵀ L Lᵀ P (LLᵀ mode) and W = L⁻¹ P Nᵀ (sparse RHS)
        NT = N.T.tocsc()
        PNT = self.f.apply_P(NT)
        W = self.f.solve_L(PNT, use_LDLt_decomposition=False)
        W = W.toarray() if sp.issparse(W) else W
        S = W.T @ W
        return 0.5 * (S + S.T)


class CholmodBlocks(Cholmod):
    name = "cholmod-blocks"
    schur_route = "block-solves-64"

    def schur(self, A0, N):
        return block_solves(self.solve, N, A0.shape[0])


class PyPardiso(Backend):
    """pypardiso's own API (mtype 11, real unsymmetric; it checks the matrix on every solve)."""

    name = "pypardiso"

    @classmethod
    def check(cls):
        import pypardiso  # noqa: F401

    def factor(self, A0):
        from pypardiso import PyPardisoSolver

        self.A = A0.tocsr()
        self.A.sort_indices()
        self.solver = PyPardisoSolver()
        self.solver.factorize(self.A)

    def solve(self, b):
        return self.solver.solve(self.A, b)


# --- MKL PARDISO called directly (SPD, mtype 2): the package's own binding ------------------
class MklDirect(Backend):
    name = "mkl-direct"
    schur_route = "schur-contact-dofs (iparm[35]=2)"

    @classmethod
    def check(cls):
        from vpcontact.solvers.pardiso import library

        library()

    def factor(self, A0):
        from vpcontact.solvers.pardiso import Pardiso

        self.p = Pardiso(A0)

    def solve(self, b):
        return self.p.solve(b)

    def schur(self, A0, N):
        # a second PARDISO handle whose factorization also returns the Schur complement on the
        # contact dofs; in the solver this handle would replace the plain one (its factor solves).
        C, Nc = contact_dofs(N)
        from vpcontact.solvers.pardiso import Pardiso

        self.ps = Pardiso(A0, schur_dofs=C)
        return schur_to_S(self.ps.schur, Nc)


class MklDirectBlocks(MklDirect):
    name = "mkl-direct-blocks"
    schur_route = "block-solves-64"

    def schur(self, A0, N):
        return block_solves(self.solve, N, A0.shape[0])


class Mumps(Backend):
    """python-mumps (``import mumps``, wheels only up to 0.0.2 for cp311, built against numpy 1)
    in SPD mode (sym = 1, LLᵀ-type LDLᵀ without pivoting), METIS ordering."""

    name = "mumps"
    schur_route = "schur-contact-dofs (ICNTL(19)=1, sym=1)"
    ordering = "metis"

    @classmethod
    def check(cls):
        import mumps

        mumps.Context  # noqa: B018

    @staticmethod
    def _context(A0):
        import mumps
        from mumps import mumps as mm

        ctx = mumps.Context()
        # python-mumps only creates sym = 0 or 2 instances; build the SPD (sym = 1) one ourselves
        ctx.dtype = "d"
        ctx.mumps_instance = mm._mumps.dmumps(False, 1)
        ctx.set_matrix(sp.triu(A0, format="coo"), symmetric=True)
        return ctx

    def factor(self, A0):
        self.ctx = self._context(A0)
        self.ctx.factor(ordering=self.ordering, pivot_tol=0.0)

    def solve(self, b):
        return self.ctx.solve(b)

    def schur(self, A0, N):
        C, Nc = contact_dofs(N)
        ctx = self._context(A0)
        inst = ctx.mumps_instance
        SC = np.full((C.size, C.size), np.nan, order="C")
        inst.icntl[19] = 1  # centralized Schur complement, returned in SC
        inst.icntl[31] = 1  # discard the factors (they cannot solve the full system anyway)
        from mumps import mumps as mm

        idx = mm._makemumps_index_array(C)  # must stay referenced while MUMPS runs (it keeps a pointer)
        inst.set_schur(SC, idx)
        ctx.analyze(ordering=self.ordering)
        ctx.factor(reuse_analysis=True, pivot_tol=0.0)
        # symmetric MUMPS fills one triangle only (the other keeps our NaNs)
        lower_ok = not np.isnan(np.tril(SC)).any()
        T = np.tril(SC) if lower_ok else np.triu(SC)
        SC = T + T.T - np.diag(np.diag(T))
        del ctx, inst  # (python-mumps 0.0.2: Context.__exit__ re-runs the last job: avoid it)
        return schur_to_S(SC, Nc)


BACKENDS = {
    cls.name: cls
    for cls in (SuperLUColamd, SuperLUMmd, Cholespy, Cholmod, CholmodBlocks, PyPardiso, MklDirect, MklDirectBlocks, Mumps)
}


def available(name):
    try:
        BACKENDS[name].check()
        return True, ""
    except Exception as exc:  # ImportError, OSError, AttributeError
        return False, f"{type(exc).__name__}: {exc}"


# ------------------------------------------------------------------------------- measurement
def _status_mb(key):
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def _maxrss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def measure(name, h, check_schur=False, nsolve=5, steps=0):
    A0, N, assembly_s = build_matrix(h)
    n, m = A0.shape[0], N.shape[0]
    rec = {"backend": name, "h": h, "dofs": n, "contact_nodes": m, "nnz_A0": int(A0.nnz), "assembly_s": assembly_s}
    gc.collect()
    rec["baseline_rss_mb"] = _status_mb("VmRSS")
    rec["baseline_peak_mb"] = _maxrss_mb()
    try:  # reset VmHWM so phase_peak_mb is the peak of the backend's phase only
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
    except OSError:
        pass
    be = BACKENDS[name]()
    t = time.perf_counter()
    be.factor(A0)
    rec["factor_s"] = time.perf_counter() - t

    rng = np.random.default_rng(0)
    b = rng.standard_normal(n)
    times = []
    for _ in range(nsolve):
        t = time.perf_counter()
        x = be.solve(b)
        times.append(time.perf_counter() - t)
    x = np.asarray(x).ravel()
    rec["solve_s"] = float(np.median(times))
    rec["residual"] = float(np.linalg.norm(A0 @ x - b) / np.linalg.norm(b))

    t = time.perf_counter()
    S = be.schur(A0, N)
    rec["schur_s"] = time.perf_counter() - t
    rec["schur_route"] = be.schur_route
    rec["schur_symmetry"] = float(np.abs(S - S.T).max() / np.abs(S).max())
    # S-check that needs no reference: S e_j against N A0⁻¹ Nᵀ e_j by one ordinary solve
    j = m // 2
    col = N @ np.asarray(be.solve(np.asarray(N.T[:, [j]].todense()).ravel())).ravel()
    rec["schur_col_err"] = float(np.abs(S[:, j] - col).max() / np.abs(S).max())
    if hasattr(be, "ps"):  # the Schur-enabled factorization must also solve
        times = []
        for _ in range(nsolve):
            t = time.perf_counter()
            xs = np.asarray(be.ps.solve(b)).ravel()
            times.append(time.perf_counter() - t)
        rec["schur_factor_solve_s"] = float(np.median(times))
        rec["schur_factor_residual"] = float(np.linalg.norm(A0 @ xs - b) / np.linalg.norm(b))
    if hasattr(be, "info"):
        rec.update(be.info())
    if steps:  # really run `steps` consecutive solves (new right-hand side each), as the time loop would
        solver = be  # the plain factorization (PARDISO's Schur-mode handle solves ~2x slower)
        B = rng.standard_normal((n, 2))
        t = time.perf_counter()
        for k in range(steps):
            x = np.asarray(solver.solve(B[:, 0] + (k / steps) * B[:, 1])).ravel()
        rec["steps"] = steps
        rec["steps_s"] = time.perf_counter() - t
    # the condensed solver's whole run: assembly, factor, S, one solve per step (STEPS steps), with
    # the plain factorization doing the solves. PARDISO's Schur-mode factorization (iparm[35]=2) can
    # solve too, so one factorization would do (total_one_factor_s), but its solves are slower.
    rec["total_condensed_s"] = assembly_s + rec["factor_s"] + rec["schur_s"] + STEPS * rec["solve_s"]
    if "schur_factor_solve_s" in rec:
        rec["total_one_factor_s"] = assembly_s + rec["schur_s"] + STEPS * rec["schur_factor_solve_s"]
    rec["phase_peak_mb"] = _status_mb("VmHWM")
    rec["peak_rss_mb"] = _maxrss_mb()
    if check_schur:
        del be
        gc.collect()
        from scipy.sparse.linalg import splu

        lu = splu(A0, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        Sref = block_solves(lu.solve, N, n)
        rec["schur_err_vs_superlu"] = float(np.abs(S - Sref).max() / np.abs(Sref).max())
    rec["threads"] = {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "MKL_NUM_THREADS") if os.environ.get(k)}
    rec["python"] = sys.executable
    rec["numpy"] = np.__version__
    return rec


def run_all(sizes, backends, check_schur_below=50_000, timeout=1800):
    out = []
    for name in backends:
        ok, why = available(name)
        if not ok:
            out.append({"backend": name, "available": False, "reason": why})
            continue
        for target in sizes:
            cmd = [sys.executable, os.path.abspath(__file__), "--backend", name, "--dofs-target", str(target)]
            if target < check_schur_below:
                cmd.append("--check-schur")
            try:
                p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
                if p.returncode == 0:
                    out.append(json.loads(p.stdout.strip().splitlines()[-1]))
                else:
                    out.append({"backend": name, "dofs_target": target, "failed": True, "rc": p.returncode,
                                "stderr": p.stderr[-2000:]})
            except subprocess.TimeoutExpired:
                out.append({"backend": name, "dofs_target": target, "failed": True, "reason": f"timeout {timeout}s"})
            print(json.dumps(out[-1]), file=sys.stderr, flush=True)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--backend", choices=sorted(BACKENDS))
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--dofs-target", type=float, help="pick h ≈ sqrt(3.63 / target)")
    g.add_argument("--h", type=float, help="element edge length")
    ap.add_argument("--check-schur", action="store_true", help="compare S with SuperLU (costly above ~100k dofs)")
    ap.add_argument("--all", action="store_true", help="every importable backend at --sizes, in subprocesses")
    ap.add_argument("--sizes", type=float, nargs="+", default=list(SIZES))
    ap.add_argument("--backends", nargs="+", default=None, help="with --all: restrict to these")
    ap.add_argument("--list", action="store_true", help="print which backends import here")
    ap.add_argument("--steps", type=int, default=0, help="also time this many consecutive solves (e.g. 563)")
    a = ap.parse_args(argv)
    if a.list:
        print(json.dumps({k: available(k) for k in BACKENDS}, indent=1))
        return
    if a.all:
        print(json.dumps(run_all([int(s) for s in a.sizes], a.backends or list(BACKENDS)), indent=1))
        return
    if not a.backend:
        ap.error("--backend, --all or --list is required")
    ok, why = available(a.backend)
    if not ok:
        print(json.dumps({"backend": a.backend, "available": False, "reason": why}))
        return
    h = a.h if a.h else h_for_dofs(a.dofs_target or SIZES[0])
    print(json.dumps(measure(a.backend, h, check_schur=a.check_schur, steps=a.steps)))


if __name__ == "__main__":
    main()
