"""Every step solver on the same cases: the same displacements and contact quantities to 1e-8."""

import math

import numpy as np
import pytest

import vpcontact
from vpcontact.solvers.factorization import installed_backends
from conftest import half_disc_case, rectangle_case
from test_3d import ball_case, block_case, states

CASES = {
    "block beta=1": rectangle_case(),
    "block beta=-1": rectangle_case(stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}),
    "block alpha=0": rectangle_case(stiffness={"law": "power", "c_v": 100.0, "alpha": 0.0, "beta": 1.0}),
    "block g=inf": rectangle_case(g=math.inf),
    "block gap": rectangle_case(gap="0.01*x"),
    "disc beta=1": half_disc_case(h=0.1, load=20.0),
    "disc beta=-1": half_disc_case(h=0.1, load=20.0, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}),
    "disc signorini": half_disc_case(h=0.1, load=60.0, stiffness={"law": "constant", "value": 0.0}),
    "disc rho=1e-3": half_disc_case(h=0.1, load=20.0, rho=1e-3),
    "disc power p": half_disc_case(h=0.1, load=20.0, p="power", exponent=1.5),
    "disc exponential": half_disc_case(h=0.1, load=20.0, stiffness={"law": "exponential", "c_v": 100.0, "alpha": -5.0}),
    "3D ball on a flat foundation": ball_case(h=0.35, g=0.05, normal=[0, 0, -1], gap="z"),
    "3D block with a curved gap": block_case(g=0.02, gap="0.1*(x*x + y*y)"),
}
#: the cases with a step where nodes are separated, in compliance and at the limit
ALL_THREE_STATES = {"3D ball on a flat foundation", "3D block with a curved gap"}


def relative(a, b):
    scale = max(np.abs(a).max(), np.abs(b).max(), 1e-300)
    return np.abs(a - b).max() / scale


def assert_same_states(result, reference):
    """The nodes' states agree, except at weakly active nodes: at the limit with no force from the rigid
    base (to 1e-8 of the largest pressure), where "in compliance" and "at the limit" are both right
    and the rounding of λ decides (the iterative method's is its CG tolerance)."""
    status, expected = result.contact_history("status"), reference.contact_history("status")
    differ = status != expected
    pressure = np.abs(reference.contact_history("pressure_compliance")).max() + \
        np.abs(reference.contact_history("pressure_rigid")).max()
    weak = np.maximum(np.abs(result.contact_history("pressure_rigid")),
                      np.abs(reference.contact_history("pressure_rigid"))) <= 1e-8 * pressure
    assert np.all(np.isin(status[differ], (1, 2)) & np.isin(expected[differ], (1, 2)) & weak[differ]), \
        (np.argwhere(differ), status[differ], expected[differ])


#: the full and the condensed method with every factorization installed here, and the iterative one
METHODS = [("full", "superlu")] + [(method, backend) for backend in installed_backends()
                                   for method in ("condensed", "full") if (method, backend) != ("full", "superlu")] \
    + [("iterative", "auto")]


@pytest.mark.parametrize("name", CASES)
def test_methods_agree(name):
    results = {}
    for method, backend in METHODS:
        solver = {**CASES[name]["solver"], "method": method, "factorization": backend}
        results[method, backend] = vpcontact.solve({**CASES[name], "solver": solver, "output": {"field_steps": "all"}})
        assert results[method, backend].status == "complete", results[method, backend].message
        assert results[method, backend].method == method
    reference = results.pop(("full", "superlu"))
    if name in ALL_THREE_STATES:
        assert np.all(states(reference) > 0, axis=1).any(), states(reference)
    for method, result in results.items():
        for step, fields in reference.fields.items():
            assert relative(result.fields[step].displacement, fields.displacement) < 1e-8, (method, step)
            assert relative(result.fields[step].stress, fields.stress) < 1e-8, (method, step)
        for quantity in ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid"):
            assert relative(result.contact_history(quantity), reference.contact_history(quantity)) < 1e-8, quantity
        assert_same_states(result, reference)
        forces = [column for column in reference.columns if column.startswith("contact_force_")]
        assert len(forces) == reference.dim
        for column in forces:
            np.testing.assert_allclose(result.series(column), reference.series(column), rtol=1e-8,
                                       atol=1e-8 * np.abs(reference.series(column)).max())
