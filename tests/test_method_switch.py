"""solver.method = "auto" weighs the methods again during a run and switches when the work done says another
one will finish clearly sooner (vpcontact.solvers.switch): the decision follows the counted work, the switch
keeps the history (the numbers agree with each method's own run to the tolerance), and a run resumed before
or after its switch is the uninterrupted one bit for bit."""

import numpy as np
import pytest

import vpcontact
from vpcontact.results.output_options import OutputOptions
from vpcontact.solvers import SolverWork, cost, switch
from vpcontact.solvers.switch import MethodWeighing
from vpcontact.timeloop.loop import TimeLoop
from vpcontact.timeloop.plan import free_operators, plan_run
from conftest import half_disc_case
from test_3d import ball_case

#: History columns compared across methods: the contact state and the forces.
COLUMNS = ("max_penetration", "mean_penetration", "K_min", "K_max", "normal_stress_probe", "contact_area")


def viscoplastic_disc(steps: int = 12) -> dict:
    """The half disc of a Perzyna body (z ≠ 0) on a layer with β = −1: nodes reach the rigid limit."""
    case = half_disc_case(h=0.2, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    case["time"] = {"T": 1.1, "steps": steps}
    case["output"] = {"field_steps": "final"}
    return case


def with_method(case: dict, method: str) -> dict:
    return {**case, "solver": {**case["solver"], "method": method}}


def assert_agree(switched, reference) -> None:
    """The same levels, the same node states, every compared column to 1e-8 of its scale, the final fields too."""
    assert switched.steps == reference.steps and switched.status == reference.status == "complete"
    for name in ("nodes_separated", "nodes_in_compliance", "nodes_at_limit"):
        np.testing.assert_array_equal(switched.series(name), reference.series(name))
    for name in COLUMNS:
        a, b = switched.series(name), reference.series(name)
        assert np.max(np.abs(a - b)) <= 1e-8 * max(np.max(np.abs(b)), 1e-300), name
    for name in ("displacement", "stress", "z"):
        a, b = getattr(switched.final, name), getattr(reference.final, name)
        if b is None:  # z of an elastic body
            assert a is None
            continue
        assert np.max(np.abs(a - b)) <= 1e-8 * np.max(np.abs(b)), name


def test_a_viscoplastic_run_that_switches_keeps_its_history_and_agrees_with_both_methods(monkeypatch):
    """Every gain counted as worth a switch: the condensed method "auto" chose gives way after OBSERVED_STEPS
    steps to the method predicted next fastest; z, ξ and the last solution carry over, and the whole history
    agrees with each method's own run to 1e-8 (the tolerance is 1e-12)."""
    monkeypatch.setattr(switch, "SWITCH_GAIN", 1e-9)
    case = viscoplastic_disc()
    switched = vpcontact.solve(case)
    record = switched.method_switch
    assert record["step"] == switch.OBSERVED_STEPS and record["from"] == "condensed", record
    assert switched.method == record["to"] != "condensed"
    assert switched.method_reason.startswith('solver.method = "auto", switched: after step 3 of 12 the condensed '
                                             'method had done work that projects'), switched.method_reason
    assert switched.summary()["method_switch"] == record
    assert "method_switch" in switched.timings
    for method in ("condensed", record["to"]):
        assert_agree(switched, vpcontact.solve(with_method(case, method)))


def test_from_the_iterative_method_to_the_condensed_one_the_numbers_agree(monkeypatch):
    """The other way: with CG made a thousand times cheaper "auto" chooses the iterative method; told that any gain
    is worth it, it switches to the condensed one, which starts from the iterative method's (u, λ, d)."""
    monkeypatch.setattr(cost, "CG_PASSES", cost.CG_PASSES / 1000)
    monkeypatch.setattr(cost, "AMG_SETUP_PASSES", cost.AMG_SETUP_PASSES / 1000)
    monkeypatch.setattr(switch, "SWITCH_GAIN", 1e-9)
    case = ball_case(h=0.3)
    case["output"] = {"field_steps": "final"}
    case["time"] = {"T": 1.1, "steps": 8}
    switched = vpcontact.solve(case)
    assert (switched.method_switch["from"], switched.method) == ("iterative", "condensed"), switched.method_switch
    monkeypatch.undo()
    assert_agree(switched, vpcontact.solve(with_method(case, "condensed")))


@pytest.mark.parametrize("stop_after", [2, 3, 5])
def test_a_run_resumed_before_at_or_after_its_switch_is_the_uninterrupted_one_bit_for_bit(monkeypatch, stop_after):
    """Stopped after step 2 (it has not switched yet: the resumed session must switch at step 3 as the
    uninterrupted run did), after step 3 (the checkpoint is of the new method, not yet run) or step 5, and resumed
    from the loop's snapshot (what a checkpoint keeps) by a new loop: every history row equal to the last bit."""
    monkeypatch.setattr(switch, "SWITCH_GAIN", 1e-9)
    problem = vpcontact.build_problem(vpcontact.load_case(viscoplastic_disc(steps=8)))
    output = OutputOptions(field_steps="final")
    whole = TimeLoop(problem, output).run()
    first = TimeLoop(problem, output)
    first.run(stop=lambda: "stopped" if first.state.step >= stop_after else None)
    snapshot = first.snapshot()
    resumed = TimeLoop(problem, output, resumed_method=str(snapshot.arrays["solver_method"]))
    resumed.restore(snapshot)
    result = resumed.run()
    assert result.method_switch == whole.method_switch and whole.method_switch["step"] == 3
    assert result.method == whole.method
    assert len(result.rows) == len(whole.rows)
    for mine, theirs in zip(result.rows, whole.rows):
        assert mine == theirs
    np.testing.assert_array_equal(result.final.displacement, whole.final.displacement)
    np.testing.assert_array_equal(result.final.z, whole.final.z)
    assert result.krylov_iterations == whole.krylov_iterations


def test_the_weighing_switches_when_the_work_departs_from_the_prediction(monkeypatch):
    """The decision follows the counts: with CG cheap enough that "auto" chooses the iterative method, a run whose
    CG iterations per Newton iteration are the prediction's (or five times more) keeps it; one that needs fifty
    times more gives way to the condensed method, and only once a few steps have been observed. The loop's own
    work per step and Newton iteration is left out: at this size it would outweigh the algebra being weighed."""
    monkeypatch.setattr(cost, "CG_PASSES", cost.CG_PASSES / 1000)
    monkeypatch.setattr(cost, "AMG_SETUP_PASSES", cost.AMG_SETUP_PASSES / 1000)
    monkeypatch.setattr(cost, "NEWTON_OVERHEAD_S", 0.0)
    monkeypatch.setattr(cost, "STEP_OVERHEAD_S", 0.0)
    problem = vpcontact.build_problem(vpcontact.load_case({**ball_case(h=0.3), "time": {"T": 1.1, "steps": 100}}))
    A, N = free_operators(problem)
    plan = plan_run(problem, OutputOptions(), A, N)
    assert plan.method == "iterative"
    weighing = MethodWeighing(A, N, 3, plan.history, 100, plan.factor)
    newton = round(10 * cost.NEWTON_PER_STEP)

    def cg(per_newton):
        return SolverWork(linear_solves=newton, krylov_iterations=round(per_newton * newton))

    assert weighing.consider("iterative", 10, cg(cost.CG_PER_NEWTON), newton) is None
    assert weighing.consider("iterative", 10, cg(5 * cost.CG_PER_NEWTON), newton) is None
    departed = weighing.consider("iterative", 10, cg(50 * cost.CG_PER_NEWTON), newton)
    assert departed is not None and (departed.before, departed.after, departed.step) == ("iterative", "condensed", 10)
    assert departed.remaining_s["condensed"] * switch.SWITCH_GAIN <= departed.remaining_s["iterative"]
    assert weighing.consider("iterative", switch.OBSERVED_STEPS - 1, cg(50 * cost.CG_PER_NEWTON), newton) is None


def test_a_method_chosen_by_name_is_never_switched(monkeypatch):
    """solver.method = "condensed" is the user's choice: no weighing, whatever the gain."""
    monkeypatch.setattr(switch, "SWITCH_GAIN", 1e-9)
    result = vpcontact.solve(with_method(viscoplastic_disc(steps=6), "condensed"))
    assert result.method == "condensed" and result.method_switch is None
    assert result.summary()["method_switch"] is None
