"""solver.method = "auto" chooses from the sizes and the memory and says why; the iterative method
refuses up front what would not fit, and a Newton system it cannot solve cuts the step instead of
stopping the run with a traceback."""

import tomli_w

import vpcontact
from vpcontact.cli import main
from vpcontact.solvers import amg, choice
from conftest import half_disc_case
from test_3d import ball_case


def test_auto_runs_the_iterative_method_for_a_3d_body_beyond_the_direct_limit(monkeypatch):
    case = {**ball_case(h=0.3), "output": {"field_steps": "final"}}
    small = vpcontact.solve(case)
    assert small.method == "condensed", small.method_reason
    assert "free dofs in 3D are at most" in small.method_reason
    monkeypatch.setattr(choice, "DIRECT_LIMIT_3D", 100)
    large = vpcontact.solve(case)
    assert large.method == "iterative" and large.status == "complete"
    assert "free dofs in 3D, more than 100: the iterative method is faster" in large.method_reason
    # the same solution (both to the case's tolerance, 1e-12)
    (last, fields), = small.fields.items()
    scale = abs(fields.displacement).max()
    assert abs(large.fields[last].displacement - fields.displacement).max() <= 1e-8 * scale


def test_auto_keeps_the_condensed_method_in_2d_whatever_the_size(monkeypatch):
    monkeypatch.setattr(choice, "DIRECT_LIMIT_3D", 100)
    result = vpcontact.solve(half_disc_case(h=0.2))
    assert result.method == "condensed"
    assert "3D" not in result.method_reason


def test_the_iterative_method_refuses_a_body_that_does_not_fit(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(choice, "available_memory", lambda: 1_000_000)
    case = ball_case(h=0.3)
    case["solver"]["method"] = "iterative"
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vpcontact: error: ") and err.count("\n") == 1
    assert 'solver.method = "iterative" needs about' in err and "GiB available" in err and "coarser mesh" in err
    assert not (tmp_path / "out").exists()


def test_a_newton_system_cg_cannot_solve_cuts_the_step_then_fails_the_run_with_advice(monkeypatch):
    monkeypatch.setattr(amg, "MAX_ITERATIONS", 1)
    case = ball_case(h=0.3)
    case["solver"] = {**case["solver"], "method": "iterative", "max_step_cuts": 2}
    result = vpcontact.solve(case)
    assert result.status == "failed" and result.steps == 0
    assert "the Newton system was not solved (AMG-preconditioned CG reached a relative residual" in result.message
    assert "in 1 iterations" in result.message
