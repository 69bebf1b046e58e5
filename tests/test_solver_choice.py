"""solver.method = "auto" chooses from the sizes and the memory and says why; the iterative method
refuses up front what would not fit, and a Newton system it cannot solve cuts the step instead of
stopping the run with a traceback."""

import pytest
import tomli_w

import vpcontact
from vpcontact.cli import main
from vpcontact.solvers import amg, choice, cost, petsc_gamg
from conftest import rectangle_case
from test_3d import ball_case


def test_auto_runs_the_method_the_cost_model_predicts_fastest_and_says_why(monkeypatch):
    """The small ball: the condensed method is predicted fastest (one factor, then m × m algebra) and runs; with
    the iterative method's matrix passes made a thousand times cheaper it is the iterative one. Both give the
    same solution, and the reason names every method's predicted time."""
    case = {**ball_case(h=0.3), "output": {"field_steps": "final"}}
    small = vpcontact.solve(case)
    assert small.method == "condensed", small.method_reason
    assert small.method_reason == 'solver.method = "auto": the condensed method is predicted fastest here (then ' \
                                  'full, iterative)', small.method_reason
    assert set(small.predicted) == {"condensed", "iterative", "full"}
    assert small.predicted["condensed"]["total_s"] < small.predicted["iterative"]["total_s"]
    monkeypatch.setattr(cost, "CG_PASSES", cost.CG_PASSES / 1000)
    monkeypatch.setattr(cost, "AMG_SETUP_PASSES", cost.AMG_SETUP_PASSES / 1000)
    large = vpcontact.solve(case)
    assert large.method == "iterative" and large.status == "complete", large.method_reason
    assert large.method_reason.startswith('solver.method = "auto": the iterative method is predicted fastest here')
    # the same solution (both to the case's tolerance, 1e-12)
    (last, fields), = small.fields.items()
    scale = abs(fields.displacement).max()
    assert abs(large.fields[last].displacement - fields.displacement).max() <= 1e-8 * scale


def test_auto_never_chooses_a_method_that_does_not_fit(monkeypatch):
    """With the condensed method's dense algebra over its share of the memory, "auto" runs the iterative method and
    says the condensed one does not fit, however cheap its prediction."""
    monkeypatch.setattr(cost, "available_memory", lambda: 10_000)
    monkeypatch.setattr(cost, "ITERATIVE_BYTES_PER_ENTRY", 0)
    costs = {name: cost.MethodCost(name, 0.0, seconds, 0, name != "condensed")
             for name, seconds in (("condensed", 1.0), ("iterative", 50.0), ("full", 100.0))}
    method, reason = choice.chosen_method("auto", costs)
    assert method == "iterative"
    assert reason == 'solver.method = "auto": the iterative method is predicted fastest here (then full); ' \
                     'condensed would not fit in the memory available'


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
    case["solver"] = {**case["solver"], "method": "iterative", "multigrid": "pyamg", "max_step_cuts": 2}
    result = vpcontact.solve(case)
    assert result.status == "failed" and result.steps == 0
    assert "the Newton system was not solved (AMG-preconditioned CG reached a relative residual" in result.message
    assert "in 1 iterations" in result.message


def test_a_resumed_auto_run_keeps_the_method_of_the_run_it_continues():
    """The prediction weighs this session's speed: a run resumed from a checkpoint of the iterative method keeps
    it where "auto" would now choose the condensed one, and says so (a method changed on resuming would make the
    resumed run differ from the uninterrupted one beyond its last bits)."""
    from vpcontact.results.output_options import OutputOptions
    from vpcontact.timeloop.plan import free_operators, plan_run

    problem = vpcontact.build_problem(vpcontact.load_case(ball_case(h=0.3)))
    operators = free_operators(problem)
    assert plan_run(problem, OutputOptions(), *operators).method == "condensed"
    resumed = plan_run(problem, OutputOptions(), *operators, resumed_method="iterative")
    assert resumed.method == "iterative"
    assert resumed.method_reason == 'solver.method = "auto": the iterative method of the run resumed (this session ' \
                                    'predicts the condensed method fastest)'


def test_petsc_multigrid_without_petsc4py_is_refused_in_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch):
    """solver.multigrid = "petsc" where petsc4py cannot be imported: exit 2, one line saying how to install it."""
    monkeypatch.setattr(petsc_gamg, "available", lambda: False)
    case = ball_case(h=0.3)
    case["solver"] = {**case["solver"], "method": "iterative", "multigrid": "petsc"}
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vpcontact: error: ") and err.count("\n") == 1, err
    assert 'solver.multigrid = "petsc": petsc4py is not installed here' in err
    assert 'pip install "vpcontact[petsc]"' in err and '"auto" or "pyamg"' in err
    assert not (tmp_path / "out").exists()


def test_auto_multigrid_without_petsc4py_runs_pyamg_and_says_so(monkeypatch):
    monkeypatch.setattr(petsc_gamg, "available", lambda: False)
    case = {**ball_case(h=0.3), "time": {"T": 0.2, "steps": 2}}
    case["solver"] = {**case["solver"], "method": "iterative"}
    result = vpcontact.solve(case)
    assert result.status == "complete", result.message
    assert result.method_reason == 'solver.method = "iterative"; its CG preconditioned by pyamg\'s smoothed ' \
                                   'aggregation (solver.multigrid = "auto": petsc4py is not installed)'


def test_the_iterative_method_is_predicted_at_the_speed_of_the_multigrid_that_would_run(monkeypatch):
    """With petsc4py installed "auto" runs PETSc's GAMG, and the plan names it; the cost model predicts its set-up at
    MULTIGRID_SPEEDS' share of pyamg's and its CG work at the product of the shares of an iteration's time and of
    the iterations (at the reference rates, which do not change between the two predictions)."""
    from vpcontact.results.output_options import OutputOptions
    from vpcontact.timeloop.plan import free_operators, plan_run

    problem = vpcontact.build_problem(vpcontact.load_case(ball_case(h=0.3)))
    A, N = free_operators(problem)
    monkeypatch.setattr(petsc_gamg, "available", lambda: False)
    assert plan_run(problem, OutputOptions(), A, N).multigrid == "pyamg"
    monkeypatch.setattr(petsc_gamg, "available", lambda: True)
    assert plan_run(problem, OutputOptions(), A, N).multigrid == "petsc"
    steps, rates = len(problem.times), cost.MachineRates.reference(A)
    before, after = (cost.predict(A, N, 3, steps, history=False, field_steps=0, rates=rates, factor=None, resident=0,
                                  multigrid=multigrid)["iterative"] for multigrid in ("pyamg", "petsc"))
    speed = cost.MULTIGRID_SPEEDS["petsc"]
    assert after.setup_s == pytest.approx(speed.setup * before.setup_s, rel=1e-12)
    overhead = cost.Prices.of(A, N, rates, None).overhead(steps, cost.NEWTON_PER_STEP * steps)
    assert after.loop_s - overhead == pytest.approx(speed.cg_iteration * speed.cg_iterations
                                                    * (before.loop_s - overhead), rel=1e-12)


def test_the_factor_is_counted_only_where_the_count_may_matter(monkeypatch):
    """PARDISO's analysis (the count of the direct factor's work) is made for "auto" only where it may change the
    choice: not on a 2D body where the condensed method is predicted far below the others with room to spare (the
    factorization makes that analysis again), but where its factor would not fit with four times the laws' memory
    (the laws' memory was 0.72 of the count's at 476k dofs); for an explicit direct method, only where it would not fit
    with four times the laws' memory (the report of the method asked for then rests on the count)."""
    pytest.importorskip("vpcontact.solvers.pardiso").library()
    from vpcontact.timeloop import plan

    case = rectangle_case()
    case["mesh"]["h"] = 0.01  # 10k dofs
    problem = vpcontact.build_problem(case)
    A, N = plan.free_operators(problem)

    def predicted(method):
        return plan.predicted_costs(method, A, N, 2, 11, False, 1)

    law = cost.factor_work(A, N, 2, count=False)
    roomy, _, factor = predicted("auto")
    assert factor == law and not factor.counted
    assert 4 * roomy["condensed"].total_s <= min(roomy["iterative"].total_s, roomy["full"].total_s)
    assert predicted("condensed")[2] == law and predicted("full")[2] == law
    dense = roomy["condensed"].memory_bytes - roomy["full"].memory_bytes  # the condensed method's m × m algebra
    monkeypatch.setattr(cost, "available_memory", lambda: int(dense + 2 * law.bytes))  # fits the laws, not 4×
    counted = predicted("auto")[2]
    assert counted.counted and counted.flops != law.flops
    assert predicted("condensed")[2].counted and predicted("full")[2].counted
