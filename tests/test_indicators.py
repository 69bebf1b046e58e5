"""The time level an error estimator reads (vpcontact.estimate.indicators)."""

import numpy as np
import pytest

import vpcontact
from vpcontact.errors import CaseError
from vpcontact.estimate.indicators import Indicators, Level


@pytest.fixture(scope="module")
def case():
    return vpcontact.load_case("examples/paper_ball.toml", {"mesh.h": 0.25, "time.steps": 4,
                                                           "output.field_steps": [2, 4]})


@pytest.fixture(scope="module")
def problem(case):
    return vpcontact.build_problem(case)


@pytest.fixture(scope="module")
def result(problem, case):
    return vpcontact.solve(problem, output=case.output)


def test_a_level_holds_the_fields_and_the_contact_row_of_its_step(result, problem):
    level = Level.of(result, 2, problem)
    assert level.t == pytest.approx(problem.times[1])
    assert level.fields is result.fields[2]
    row = np.flatnonzero(result.series("step") == 2)[-1]
    for name, values in level.contact.items():
        np.testing.assert_array_equal(values, result.contact_history(name)[row])


def test_a_step_without_kept_fields_is_refused_naming_the_kept_ones(result, problem):
    with pytest.raises(CaseError, match="no fields kept at step 3 .*steps kept: 2, 4"):
        Level.of(result, 3, problem)


def test_indicators_sum_their_terms():
    indicators = Indicators({"a": np.array([1.0, 4.0]), "b": np.array([3.0, 8.0])})
    np.testing.assert_array_equal(indicators.squared, [4.0, 12.0])
    assert indicators.total == pytest.approx(4.0)
