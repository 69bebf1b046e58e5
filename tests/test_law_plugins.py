"""Laws as plug-ins (vpcontact.laws: the registries STIFFNESS, COMPLIANCE, VISCOPLASTIC): every registered law
keeps the contract the schema and the solvers rely on, and a new law is one module and one registration: a
stiffness K(ξ) = c_v + α ξ written outside the package runs a case whose uniform block follows the closed form
of its scalar recursion, with the case's checks, messages and outputs of any other law."""

import json
import subprocess
import sys
import textwrap

import numpy as np
import pandas as pd
import pytest

from vpcontact.laws.compliance import COMPLIANCE
from vpcontact.laws.stiffness import STIFFNESS
from vpcontact.laws.viscoplastic import VISCOPLASTIC
from vpcontact.registry import Registry
from conftest import rectangle_case

#: The module a new stiffness law is: what src/vpcontact/laws/stiffness/linear.py would hold.
LINEAR = '''
"""K(ξ) = c_v + α ξ: a layer that stiffens in proportion to its history."""

from dataclasses import dataclass

import numpy as np

from vpcontact.laws.spec import Law, Parameter


@dataclass(frozen=True)
class LinearStiffness:
    """K(ξ) = c_v + α ξ."""

    c_v: float | np.ndarray
    alpha: float | np.ndarray

    def __call__(self, xi):
        return self.c_v + self.alpha * xi

    def derivative(self, xi):
        return np.zeros_like(xi, dtype=float) + self.alpha


LAW = Law(
    name="linear",
    summary="K(ξ) = c_v + α ξ.",
    parameters=(Parameter("c_v", "K(0)", minimum=0.0), Parameter("alpha", "the growth of K with ξ", minimum=0.0)),
    make=LinearStiffness,
)
'''

#: Registers the law (its one entry), then runs the case of argv[1] into argv[2] through the command line and
#: prints the messages of two bad cases.
RUNNER = '''
import copy, json, sys

import vpcontact
from vpcontact.cli import main
from vpcontact.laws.stiffness import STIFFNESS
import linear

STIFFNESS.register(linear.LAW)
case = json.loads(open(sys.argv[1]).read())
assert main(["run", sys.argv[1].replace(".json", ".toml"), "--out", sys.argv[2], "--quiet"]) == 0
messages = []
for stiffness in ({"law": "linear", "c_v": -1.0, "alpha": 1.0}, {"law": "quadratic", "c_v": 1.0}):
    bad = copy.deepcopy(case)
    bad["contact"]["stiffness"] = stiffness
    try:
        vpcontact.load_case(bad)
    except vpcontact.CaseError as error:
        messages.append(str(error))
print(json.dumps(messages))
'''

C_V, ALPHA, Q_RATE = 100.0, 50.0, 100.0


def closed_form(T=1.1, steps=11):
    """d_n and ξ_n of one contact point under q = 100 t: (c_v + α (ξ_{n−1} + k d)) d = q_n, the positive root."""
    k, xi, out = T / steps, 0.0, []
    for n in range(1, steps + 1):
        a, b = ALPHA * k, C_V + ALPHA * xi
        d = 2.0 * Q_RATE * n * k / (b + np.sqrt(b * b + 4.0 * a * Q_RATE * n * k))  # the root, without cancellation
        xi += k * d
        out.append((d, xi))
    return np.array(out)


def test_a_new_stiffness_law_is_one_module_and_one_registration(tmp_path):
    import tomli_w

    case = rectangle_case(g="inf", stiffness={"law": "linear", "c_v": C_V, "alpha": ALPHA})
    (tmp_path / "case.json").write_text(json.dumps(case))
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    (tmp_path / "linear.py").write_text(LINEAR)
    (tmp_path / "runner.py").write_text(RUNNER)
    out = tmp_path / "run"
    process = subprocess.run([sys.executable, "runner.py", "case.json", str(out)], cwd=tmp_path, capture_output=True,
                             text=True, timeout=300)
    assert process.returncode == 0, process.stderr
    positive, unknown = json.loads(process.stdout.splitlines()[-1])
    assert positive == "contact.stiffness.c_v: expected a number >= 0 or an expression in the coordinates, got -1.0"
    assert unknown == ('contact.stiffness.law = "quadratic": unknown law; expected one of "power", "constant", '
                       '"exponential", "table", "linear"')
    contact = pd.read_csv(out / "contact.csv")
    expected = closed_form()
    for name, column in (("penetration", 0), ("xi", 1)):
        table = contact.pivot(index="step", columns="node", values=name).to_numpy()
        np.testing.assert_allclose(table, np.repeat(expected[:, column:column + 1], table.shape[1], axis=1),
                                   rtol=1e-9, atol=0)
    np.testing.assert_allclose(contact["K"], C_V + ALPHA * contact["xi"], rtol=1e-12)
    assert (contact["c_v"] == C_V).all() and (contact["alpha"] == ALPHA).all()  # its parameters are the layer's
    resolved = (out / "case.resolved.toml").read_text()
    assert '[contact.stiffness]\nlaw = "linear"\nc_v = 100.0\nalpha = 50.0\n' in resolved


@pytest.mark.parametrize("registry", [STIFFNESS, COMPLIANCE])
def test_every_contact_law_has_its_parameters_and_its_derivative(registry):
    """The contract of a K or p law: its object has its parameters as attributes (per node: arrays work; a
    table's points: an increasing table from 0), is vectorized, and its derivative is the central difference
    of its values (away from a table's breakpoints)."""
    rng = np.random.default_rng(1)
    r = rng.uniform(0.05, 0.5, 7)

    def value(parameter):
        if parameter.choices:
            return parameter.choices[-1]
        if parameter.points:  # the abscissae, then the values, of a table whose breakpoints r avoids
            return np.array([0.0, 0.011, 0.6]) if parameter.minimum is None else np.array([0.0, 0.02, 0.9])
        return rng.uniform(1.0, 2.0, 7) if parameter.name != "beta" else rng.uniform(-2.0, 2.0, 7)

    for law in registry.values():
        values = {p.name: value(p) for p in law.parameters}
        made = law.made(lambda parameter: values[parameter.name])
        assert all(np.array_equal(getattr(made, name), value) for name, value in values.items()), law.name
        assert made(r).shape == r.shape, law.name
        delta = 1e-6
        np.testing.assert_allclose(made.derivative(r), (made(r + delta) - made(r - delta)) / (2 * delta), rtol=1e-6,
                                   err_msg=law.name)


def test_every_viscoplastic_law_is_a_lipschitz_map_of_the_stress():
    rng = np.random.default_rng(2)
    sigma = rng.normal(size=(2, 2, 50))
    sigma = sigma + sigma.transpose(1, 0, 2)
    other = sigma + 0.1 * rng.normal(size=sigma.shape)
    other = 0.5 * (other + other.transpose(1, 0, 2))
    strain = np.zeros_like(sigma)
    for law in VISCOPLASTIC.values():
        G = law.make(**{p.name: 0.3 if p.poisson_ratio else 2.0 for p in law.parameters}, hypothesis="plane_strain")
        rate = G(sigma, strain)
        assert rate.shape == sigma.shape, law.name
        change = np.sqrt(((G(other, strain) - rate) ** 2).sum(axis=(0, 1)))
        assert np.all(change <= G.lipschitz * np.sqrt(((other - sigma) ** 2).sum(axis=(0, 1))) * (1 + 1e-12)), law.name


def test_the_registries_list_the_case_names_in_order():
    assert STIFFNESS.names == ("power", "constant", "exponential", "table")
    assert COMPLIANCE.names == ("positive_part", "power", "table")
    assert VISCOPLASTIC.names == ("perzyna", "relaxation")
    assert [law.name for law in STIFFNESS.values()] == list(STIFFNESS)


def test_a_registry_refuses_a_taken_name_and_a_misnamed_module(tmp_path, monkeypatch):
    with pytest.raises(ValueError, match="'power' is registered already"):
        STIFFNESS.register(STIFFNESS["power"])
    (tmp_path / "plugins").mkdir()
    (tmp_path / "plugins" / "__init__.py").write_text("")
    (tmp_path / "plugins" / "cubic.py").write_text(textwrap.dedent('''
        from vpcontact.laws.stiffness.power import LAW
    '''))
    monkeypatch.syspath_prepend(str(tmp_path))
    misnamed = Registry("plugins", ("cubic",), "LAW")
    with pytest.raises(ValueError, match="plugins.cubic.LAW is named 'power'"):
        misnamed["cubic"]
    with pytest.raises(KeyError, match="'quartic': expected one of 'cubic'"):
        misnamed["quartic"]
