"""Shared helpers for the tests: small cases built as dicts."""

import copy

import pytest


def rectangle_case(**contact) -> dict:
    """A block [0, 1] × [0, 0.5] on rollers at its sides, pushed down by a uniform traction c·t on
    its top onto the foundation under its bottom (the uniform state: every contact node alike)."""
    stiffness = contact.pop("stiffness", {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0})
    return {
        "mesh": {"shape": "rectangle", "width": 1.0, "height": 0.5, "h": 0.125},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {
            "dirichlet": [{"part": "left", "components": ["x"]}, {"part": "right", "components": ["x"]}],
            "traction": [{"part": "top", "value": ["0", "-100*t"]}],
        },
        "contact": {"part": "bottom", "g": 0.2, "stiffness": stiffness, **contact},
        "time": {"T": 1.1, "steps": 11},
        "solver": {"tolerance": 1e-13},
        "output": {"field_steps": "none"},
    }


def half_disc_case(h=0.1, **contact) -> dict:
    """The paper's half disc (roller on the axis, vertical traction on the upper arc) on a coarse mesh."""
    stiffness = contact.pop("stiffness", {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0})
    load = contact.pop("load", 20.0)
    return {
        "mesh": {"shape": "half_disc", "h": h},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {
            "dirichlet": [{"part": "axis", "components": ["x"]}],
            "traction": [{"part": "top_arc", "value": ["0", f"-{load}*t"]}],
        },
        "contact": {"part": "bottom_arc", "g": 0.2, "probe": [0.0, 0.0], "stiffness": stiffness, **contact},
        "time": {"T": 1.1, "steps": 11},
        "solver": {"tolerance": 1e-12},
        "output": {"field_steps": "none"},
    }


def block_3d_case():
    """A block on rollers at x = 0 and y = 0 on a flat foundation with a curved gap x² + y²: a contact
    patch around the corner (0, 0) with nodes in all three states at the end."""
    return {
        "mesh": {"shape": "block", "h": 0.2, "width": 1.0, "depth": 1.0, "height": 0.5},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "left", "components": ["x"]}, {"part": "front", "components": ["y"]}],
                     "traction": [{"part": "top", "value": ["0", "0", "-30*t"]}]},
        "contact": {"part": "bottom", "g": 0.05, "normal": [0, 0, -1], "gap": "x*x + y*y", "probe": [0, 0, 0],
                    "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}},
        "time": {"T": 1.1, "steps": 11},
        "output": {"field_steps": [5, 11]},
    }


def solved(case, **laws):
    """(problem, result): the problem of ``case`` (a Case, or what load_case takes) and the result of its run,
    as ``vpcontact.solve(case, **laws)`` computes it; for the tests that compare a run with its problem's
    operators, loads or laws (a result holds no problem)."""
    import vpcontact

    case = case if isinstance(case, vpcontact.Case) else vpcontact.load_case(case)
    problem = vpcontact.build_problem(case, **laws)
    return problem, vpcontact.solve(problem, output=case.output)


@pytest.fixture
def deep_copy():
    return copy.deepcopy


# --- the exit-code contract (README "Exit status"), shared by the adversarial tests ------------------
def run_cli(*args, cwd=None, timeout=120, env=None):
    """``python -m vpcontact.cli ARGS`` in a subprocess (a hang fails the test): (status, stdout, stderr)."""
    import os
    import subprocess
    import sys

    environment = {**os.environ, **(env or {})}
    process = subprocess.run([sys.executable, "-m", "vpcontact.cli", *map(str, args)], cwd=cwd, env=environment,
                             capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
    return process.returncode, process.stdout, process.stderr


def snapshot_tree(folder):
    """{relative path: (size, mtime_ns)} of every file and folder under ``folder`` (None if absent)."""
    from pathlib import Path

    folder = Path(folder)
    if not folder.exists() and not folder.is_symlink():
        return None
    if not folder.is_dir():
        return {".": folder.lstat().st_size}
    return {str(p.relative_to(folder)): (p.lstat().st_size, p.lstat().st_mtime_ns) for p in sorted(folder.rglob("*"))}


def assert_refused(status, stderr, *words, untouched=()):
    """A refusal: exit 2, exactly one line ``vpcontact: error: ...`` naming ``words``, no traceback, no
    NumPy warning; ``untouched``: pairs (folder, snapshot_tree(folder) taken before) that must be
    unchanged (nothing written, nothing deleted)."""
    assert status == 2, (status, stderr)
    assert stderr.startswith("vpcontact: error: ") and stderr.count("\n") == 1, stderr
    assert "Traceback" not in stderr and "Warning" not in stderr, stderr
    assert len(stderr) < 1000, f"{len(stderr)} characters"
    for word in words:
        assert word in stderr, (word, stderr)
    for folder, before in untouched:
        assert snapshot_tree(folder) == before, f"{folder} changed"


def resumed_after(case, step: int, folder):
    """A time loop of ``case`` (a Case) stopped after ``step``, checkpointed into ``folder`` and restored into a
    new loop of the same case, not run yet: where a test of resuming starts."""
    from vpcontact.io import checkpoint
    from vpcontact import build_problem
    from vpcontact.case.translate import output_options
    from vpcontact.timeloop.loop import TimeLoop

    first = TimeLoop(build_problem(case), output_options(case.output))
    assert first.run(stop=lambda: "stopped" if first.state.step == step else None).status == "interrupted"
    folder.mkdir(parents=True, exist_ok=True)
    checkpoint.save(first, folder)
    second = TimeLoop(build_problem(case), output_options(case.output))
    assert checkpoint.restore(second, folder) == step
    return second


def require_gmsh() -> None:
    """Skip the calling test where gmsh's Python module is missing or its library does not load (a machine
    without its system libraries): the scripts that mesh with gmsh cannot run there."""
    gmsh = pytest.importorskip("gmsh")
    try:
        gmsh.initialize(interruptible=False)
        gmsh.finalize()
    except OSError:
        pytest.skip("gmsh's library does not load here")
