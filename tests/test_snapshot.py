"""The time loop's one snapshot and one restore (vpcontact.timeloop.snapshot), without files: a snapshot is
plain data (arrays, JSON values), and a loop restored from another loop's snapshot ends as the uninterrupted
run, bit for bit (tests/test_resume_matrix.py does the same through checkpoint files and the command line)."""

import json

import numpy as np
import pytest

import vpcontact
from conftest import half_disc_case
from vpcontact.case.translate import output_options
from vpcontact.results.columns import CONTACT_ARRAYS
from vpcontact.results.result import FIELD_NAMES
from vpcontact.timeloop.loop import TimeLoop


def viscoplastic_half_disc(method: str):
    """The half disc, viscoplastic (z and 𝒢 in the state), every step's fields kept, by ``method``."""
    case = half_disc_case(h=0.25, load=20.0, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["material"]["viscoplastic"] = {"law": "relaxation", "mu": 2.0, "E_inf": 500.0, "nu_inf": 0.3}
    case["solver"]["method"] = method
    case["output"] = {"field_steps": "all"}
    return vpcontact.load_case(case)


@pytest.mark.parametrize("method", ["condensed", "full"])
def test_a_loop_restored_from_a_snapshot_ends_as_the_uninterrupted_run(method):
    case = viscoplastic_half_disc(method)
    whole = TimeLoop(vpcontact.build_problem(case), output_options(case.output)).run()
    first = TimeLoop(vpcontact.build_problem(case), output_options(case.output))
    assert first.run(stop=lambda: "stopped" if first.state.step == 5 else None).status == "interrupted"
    snapshot = first.snapshot()

    assert all(isinstance(array, np.ndarray) for array in snapshot.arrays.values())
    assert json.loads(json.dumps(snapshot.meta)) == snapshot.meta  # JSON values, as a checkpoint writes them
    assert snapshot.meta["field_steps"] == [1, 2, 3, 4, 5] and sorted(snapshot.fields) == [1, 2, 3, 4, 5]
    assert set(snapshot.fields[5]) == {"displacement", "stress", "stress33", "von_mises", "z"}
    assert int(snapshot.arrays["step"]) == 5 and str(snapshot.arrays["solver_method"]) == method

    second = TimeLoop(vpcontact.build_problem(case), output_options(case.output))
    second.restore(snapshot)
    assert second.state.step == 5 and second.result.resumed_at == [5]
    resumed = second.run()
    assert resumed.status == "complete" and resumed.resumed_at == [5]
    for column in whole.columns:
        np.testing.assert_array_equal(resumed.series(column), whole.series(column), err_msg=column)
    for name in CONTACT_ARRAYS:
        np.testing.assert_array_equal(resumed.contact_history(name), whole.contact_history(name), err_msg=name)
    assert sorted(resumed.fields) == sorted(whole.fields)
    for n, fields in whole.fields.items():
        for name in FIELD_NAMES:
            np.testing.assert_array_equal(getattr(resumed.fields[n], name), getattr(fields, name), err_msg=(n, name))
