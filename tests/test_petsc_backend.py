"""The iterative method with PETSc's GAMG (solver.multigrid = "petsc", :mod:`vpcontact.solvers.petsc_gamg`):
the same solutions as with pyamg's hierarchy, one hierarchy for a whole run, the fixed dofs solved exactly.
Needs petsc4py (``pip install "vpcontact[petsc]"``); skipped without it (the refusal of "petsc" where it is
missing is tests/test_solver_choice.py's)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

pytest.importorskip("petsc4py")

from vpcontact.parallel.petsc import deep_binding_is_safe
from conftest import block_3d_case, half_disc_case
from test_3d import ball_case, states
from test_linear_solvers import quarter_ball_system
from test_solvers_agree import assert_same_states, relative

import vpcontact
from vpcontact import build_problem
from vpcontact.case.translate import output_options
from vpcontact.solvers import petsc_gamg
from vpcontact.solvers.errors import NotConvergedError
from vpcontact.solvers.factorization import installed_backends
from vpcontact.timeloop.loop import TimeLoop

#: a 3D and a 2D case, each with a step where nodes are separated, in compliance and at the limit
CASES = {
    "3D ball on a flat foundation": ball_case(h=0.35, g=0.05, normal=[0, 0, -1], gap="z"),
    "disc with a curved gap": half_disc_case(h=0.1, load=20.0, gap="0.3*x*x",
                                             stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}),
}


def iterative(case: dict, multigrid: str) -> dict:
    return {**case, "solver": {**case["solver"], "method": "iterative", "multigrid": multigrid},
            "output": {"field_steps": "all"}}


@pytest.mark.parametrize("name", CASES)
def test_petsc_and_pyamg_give_the_same_solution(name):
    results = {multigrid: vpcontact.solve(iterative(CASES[name], multigrid)) for multigrid in ("pyamg", "petsc")}
    reference, result = results["pyamg"], results["petsc"]
    assert reference.status == result.status == "complete", (reference.message, result.message)
    assert np.all(states(reference) > 0, axis=1).any(), states(reference)
    assert "PETSc's GAMG" in result.method_reason and "pyamg" in reference.method_reason
    for step, fields in reference.fields.items():
        assert relative(result.fields[step].displacement, fields.displacement) < 1e-8, step
        assert relative(result.fields[step].stress, fields.stress) < 1e-8, step
    for quantity in ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid"):
        assert relative(result.contact_history(quantity), reference.contact_history(quantity)) < 1e-8, quantity
    assert_same_states(result, reference)
    assert result.krylov_iterations > 0


def test_one_hierarchy_serves_a_whole_run_in_few_iterations():
    """The quarter ball over 11 steps (nodes coming into contact, into compliance and to the limit): one GAMG
    hierarchy, built on the first Newton matrix, at most 30 CG iterations for any Newton system."""
    loop = TimeLoop(build_problem(iterative(ball_case(h=0.25), "petsc")), output_options({"field_steps": "none"}))
    result = loop.run()
    assert result.status == "complete", result.message
    linear = loop.solver.linear
    assert linear.name == "gamg-cg"
    assert linear.setups == 1 and linear.factorizations == 0
    assert result.linear_solves >= 2 * result.steps and linear.iterations == result.krylov_iterations
    assert 0 < linear.most_iterations <= 30, linear.most_iterations
    assert linear.levels >= 2 and linear.operator_complexity > 1.0


def test_fixed_dofs_are_solved_exactly_on_the_same_hierarchy():
    """Normal dofs fixed (reduced to their diagonal) after the hierarchy was built on the matrix without
    them: solved exactly, the rest to the tolerance, no new setup; the true residual is within it."""
    frame, rotated, solver = quarter_ball_system(0.15)
    gamg = petsc_gamg.GAMGConjugateGradient(solver.free, 3, solver.size // 3, solver.near_nullspace)
    diagonal = frame.tangent_diagonal(np.full(frame.scale.size, 50.0))
    nothing_fixed = np.zeros(rotated.shape[0], dtype=bool)
    gamg.analyse(frame.constrained(diagonal, nothing_fixed))
    active = np.zeros(frame.scale.size, dtype=bool)
    active[::3] = True
    fixed = frame.normal_dofs(active)
    K = frame.constrained(diagonal, fixed)
    gamg.factor(K)
    b = np.random.default_rng(2).normal(size=K.shape[0])
    x = gamg.solve(b, rtol=1e-10)
    np.testing.assert_allclose(x[fixed], b[fixed] / K.diagonal()[fixed], rtol=1e-9)
    assert np.linalg.norm(K @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert gamg.setups == 1 and gamg.iterations <= 30, gamg.iterations


def test_another_pattern_and_a_solve_that_does_not_converge_are_refused(monkeypatch):
    _, rotated, solver = quarter_ball_system(0.3)
    gamg = petsc_gamg.GAMGConjugateGradient(solver.free, 3, solver.size // 3, solver.near_nullspace)
    gamg.analyse(rotated)
    with pytest.raises(ValueError, match="pattern"):
        gamg.factor(sp.csr_matrix(sp.diags(rotated.diagonal())))
    monkeypatch.setattr(petsc_gamg, "MAX_ITERATIONS", 2)
    gamg.factor(rotated)
    with pytest.raises(NotConvergedError, match=r"GAMG-preconditioned CG reached a relative residual of .* in 2 "
                                                r"iterations"):
        gamg.solve(np.ones(rotated.shape[0]), rtol=1e-12)
    assert gamg.stale  # a failed solve has the hierarchy built again on the next matrix


def test_a_matrix_far_from_the_hierarchys_is_solved_then_the_hierarchy_rebuilt():
    """The hierarchy built on a Newton matrix without fixed dofs, then a Newton matrix with ten times its contact
    stiffness and a third of the normal dofs fixed: solved to the tolerance (GAMG on the live matrix, without the
    copy, broke down here); past REBUILD_AFTER iterations, the next matrix gets a new hierarchy, on which it takes
    few."""
    frame, rotated, solver = quarter_ball_system(0.2)
    gamg = petsc_gamg.GAMGConjugateGradient(solver.free, 3, solver.size // 3, solver.near_nullspace)
    soft = frame.tangent_diagonal(np.full(frame.scale.size, 50.0))
    gamg.analyse(frame.constrained(soft, np.zeros(rotated.shape[0], dtype=bool)))
    active = np.zeros(frame.scale.size, dtype=bool)
    active[::3] = True
    rng = np.random.default_rng(0)

    def solve(K):
        gamg.factor(K)
        b = rng.normal(size=K.shape[0])
        assert np.linalg.norm(K @ gamg.solve(b, rtol=1e-10) - b) <= 1e-10 * np.linalg.norm(b)

    solve(frame.constrained(10 * soft, frame.normal_dofs(active)))
    stale = gamg.most_iterations > petsc_gamg.REBUILD_AFTER  # 42 iterations with PETSc 3.26
    assert gamg.stale == stale
    before = gamg.iterations
    solve(frame.constrained(3 * soft, frame.normal_dofs(~active)))
    assert gamg.setups == 1 + stale and gamg.iterations - before <= 30, gamg.iterations - before


def test_a_newton_matrix_nearly_singular_in_a_rigid_motion_is_solved():
    """The hierarchy built with a compliance stiffness of 50 at every contact node, then a Newton matrix with 1e-10
    there (nodes separated: the quarter ball held only by contact moves freely but for that): CG's residual rises by
    10⁴ before it falls, and the solve goes on to the asked tolerance, as pyamg's does (PETSc's divergence test
    stopped it after 12 iterations)."""
    frame, rotated, solver = quarter_ball_system(0.3)
    nothing_fixed = np.zeros(rotated.shape[0], dtype=bool)
    gamg = petsc_gamg.GAMGConjugateGradient(solver.free, 3, solver.size // 3, solver.near_nullspace)
    gamg.analyse(frame.constrained(frame.tangent_diagonal(np.full(frame.scale.size, 50.0)), nothing_fixed))
    K = frame.constrained(frame.tangent_diagonal(np.full(frame.scale.size, 1e-10)), nothing_fixed)
    gamg.factor(K)
    b = np.random.default_rng(0).normal(size=K.shape[0])
    x = gamg.solve(b, rtol=1e-2)
    assert np.linalg.norm(K @ x - b) <= 1e-2 * np.linalg.norm(b)
    assert gamg.most_iterations <= 40, gamg.most_iterations  # 26 with PETSc 3.26 (pyamg: 24)


def fresh_python(script: str, *args: str) -> str:
    """The standard output of ``script`` run by a Python process of its own, with none of the MPI variables an
    initialized PETSc leaves in this one's environment (it would pass them on)."""
    environment = {key: value for key, value in os.environ.items() if not key.startswith(("OMPI_", "PMIX_"))}
    process = subprocess.run([sys.executable, "-c", script, *args], capture_output=True, text=True, timeout=300,
                             env=environment, start_new_session=True)
    assert process.returncode == 0, process.stderr
    return process.stdout


#: A session that solves the 3D block (JSON, argv[1]) by the iterative method with PETSc's GAMG, after the same block
#: by the condensed method with PARDISO if argv[2] says so; prints a digest of the displacements of every step.
SESSION = """
import hashlib, json, sys
import numpy as np
import vpcontact
case = json.loads(sys.argv[1])
if sys.argv[2] == "pardiso first":
    vpcontact.solve({**case, "solver": {"method": "condensed", "factorization": "pardiso"}})
    assert any("libmkl" in line for line in open("/proc/self/maps"))
result = vpcontact.solve({**case, "solver": {"method": "iterative", "multigrid": "petsc"},
                          "output": {"field_steps": "all"}})
print(hashlib.sha256(np.stack([fields.displacement for fields in result.fields.values()]).tobytes()).hexdigest())
"""


@pytest.mark.skipif("pardiso" not in installed_backends() or not Path("/proc/self/maps").exists(),
                    reason="needs MKL's PARDISO (and /proc to see it loaded)")
@pytest.mark.skipif(not deep_binding_is_safe(), reason="a python executable with libpython linked in: PETSc cannot be "
                    "bound to its own BLAS there (vpcontact.parallel.petsc.deep_binding_is_safe)")
def test_a_run_has_the_same_bits_whatever_its_process_did_before():
    """The same run of the iterative method in a fresh process and in one that used PARDISO first (MKL, which puts its
    BLAS under the common names in the whole process): the same displacements, bit for bit (PETSc's vector
    operations called MKL's BLAS in the second, the reference BLAS in the first: the runs differed in the last bits
    from the first step on)."""
    case = json.dumps(block_3d_case())
    assert fresh_python(SESSION, case, "pardiso first") == fresh_python(SESSION, case, "alone")


#: Initializes PETSc as a run does, then prints its process group and, for each process it started, that
#: process's group.
PROCESS_GROUPS = """
import os
from vpcontact.solvers import petsc_gamg
petsc_gamg.petsc()
print(os.getpgrp())
for entry in filter(str.isdigit, os.listdir("/proc")):
    try:
        parent, group = open(f"/proc/{entry}/stat").read().rsplit(")", 1)[1].split()[1:3]
    except OSError:
        continue  # ended meanwhile
    if int(parent) == os.getpid():
        print(group)
"""


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table in /proc")
def test_petsc_starts_no_process_outside_the_runs_process_group():
    """Whatever PETSc's initialization starts stays in the run's process group, which a signal to the group (the
    way to stop a run and everything it started) reaches: Open MPI 4 started a daemon in a session of its own that
    held the run's standard output and error, so that one who read them to their end after killing the group
    waited for the daemon."""
    group, *children = fresh_python(PROCESS_GROUPS).split()
    assert all(child == group for child in children), (group, children)
