"""Every step solver on the same cases: the same displacements and contact quantities to 1e-8."""

import math

import numpy as np
import pytest

import vpcontact
from vpcontact.solvers.factorization import installed_backends
from conftest import half_disc_case, rectangle_case

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
}


def relative(a, b):
    scale = max(np.abs(a).max(), np.abs(b).max(), 1e-300)
    return np.abs(a - b).max() / scale


#: the full method, and the condensed one with every factorization installed here
METHODS = [("full", "auto")] + [("condensed", backend) for backend in installed_backends()]


@pytest.mark.parametrize("name", CASES)
def test_methods_agree(name):
    results = {}
    for method, backend in METHODS:
        solver = {**CASES[name]["solver"], "method": method, "factorization": backend}
        results[method, backend] = vpcontact.solve({**CASES[name], "solver": solver, "output": {"field_steps": "all"}})
        assert results[method, backend].status == "complete", results[method, backend].message
        assert results[method, backend].method == method
    reference = results.pop(("full", "auto"))
    for method, result in results.items():
        for step, fields in reference.fields.items():
            assert relative(result.fields[step].displacement, fields.displacement) < 1e-8, (method, step)
            assert relative(result.fields[step].stress, fields.stress) < 1e-8, (method, step)
        for quantity in ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid"):
            assert relative(result.contact_history(quantity), reference.contact_history(quantity)) < 1e-8, quantity
        np.testing.assert_array_equal(result.contact_history("status"), reference.contact_history("status"))
        np.testing.assert_allclose(result.series("contact_force_y"), reference.series("contact_force_y"), rtol=1e-8)
