"""The contact laws' values are checked where they are used: a K(ξ) or p(r) that is negative or not finite at a
contact node stops the run with one line naming the law, its value, the node (index and coordinates), the law's
argument there (ξ or r) and the time; the levels before are kept."""

import numpy as np
import pytest
import tomli_w

import vpcontact
from conftest import half_disc_case, rectangle_case, run_cli
from vpcontact import mesh


def composed(stiffness=None, p=None, **time):
    contact = {"part": "bottom_arc", "g": 0.2,
               "stiffness": stiffness or {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}}
    if p is not None:
        contact["p"] = p
    return vpcontact.compose(mesh.half_disc(h=0.1), material={"E": 1000.0, "nu": 0.3}, dirichlet={"axis": "x"},
                             traction={"top_arc": lambda x, y, t: (0 * x, -18.0 * t + 0 * y)}, contact=contact,
                             time={"T": 1.1, "steps": 11, **time})


def node_in_message(result, message_part: str):
    """The contact node's index and coordinates the message names, checked against the problem's surface."""
    import re

    match = re.search(r"at contact node (\d+) \(x, y\) = \(([^)]*)\)", result.message)
    assert match, result.message
    i = int(match.group(1))
    coordinates = np.array([float(c) for c in match.group(2).split(",")])
    np.testing.assert_allclose(coordinates, result.discretization.surface.coordinates[:, i], atol=1e-6)
    return i


def test_a_softening_python_law_that_turns_negative_stops_the_run_at_the_node_and_its_history():
    """K(ξ) = 100 − 5000 ξ is negative once ξ > 0.02: the run stops at the first level where a node's ξ passes it,
    naming that node, its ξ (K(ξ) recomputed from it matches the value printed) and the time."""
    K = lambda xi: 100.0 - 5000.0 * xi  # noqa: E731
    result = vpcontact.solve(composed(K))
    assert result.status == "failed" and "\n" not in result.message
    assert "the contact law K(ξ) is -" in result.message and "check contact.stiffness" in result.message
    i = node_in_message(result, "K")
    xi = float(result.message.split("where ξ = ")[1].split(";")[0])
    value = float(result.message.split("K(ξ) is ")[1].split(" at")[0])
    assert value == pytest.approx(K(xi), rel=1e-5) and value < 0
    # the levels before are kept, and at the last of them ξ was still below 0.02 everywhere
    assert np.all(result.contact_history("xi")[-1] <= 0.02) and result.contact_history("xi")[-1, i] > 0
    t = float(result.message.split("at t = ")[1].split(" ")[0])
    assert t > result.series("t")[-1]


def test_a_law_that_is_not_a_number_inside_the_newton_iteration_is_named_in_the_failure():
    """K(ξ) = 100 √(0.02 − ξ) is NaN beyond ξ = 0.02: the Newton iterates stop being finite, and the failure names
    the law and a node where it was NaN."""
    with np.errstate(invalid="ignore"):
        result = vpcontact.solve(composed(lambda xi: 100.0 * np.sqrt(0.02 - xi)))
    assert result.status == "failed" and "\n" not in result.message
    assert "the contact law K(ξ) is nan at contact node" in result.message
    node_in_message(result, "K")


def test_a_p_law_that_pulls_separated_nodes_stops_the_run_with_r():
    """p(r) = r (not r⁺) is negative where a node is separated (r < 0): the layer would pull. The message gives
    p's value and r = d at that node, and p(r) = r there."""
    case = vpcontact.Case.model_validate(rectangle_case(gap="2*x*x"))  # the nodes far from x = 0 stay separated
    result = vpcontact.solve(vpcontact.build_problem(case, p=lambda r: r))
    assert result.status == "failed"
    assert "the contact law p(r) is -" in result.message and "check contact.p" in result.message
    value = float(result.message.split("p(r) is ")[1].split(" at")[0])
    r = float(result.message.split("where r = ")[1].split(";")[0])
    assert value == pytest.approx(r, rel=1e-5) and r < 0


def test_an_overflowing_law_of_the_case_file_stops_the_command_line_with_exit_3_and_one_line(tmp_path):
    """K = c_v exp(α ξ) with α = 1e12: exp overflows to inf once α ξ > 709. Through the CLI: exit 3, one line naming
    K(ξ) = inf, the node and ξ; the steps before are written."""
    case = half_disc_case(stiffness={"law": "exponential", "c_v": 100.0, "alpha": 1e12})
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    status, _, stderr = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert status == 3, stderr
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert "the contact law K(ξ) is inf at contact node" in stderr and "where ξ = " in stderr
    assert (tmp_path / "out" / "history.csv").exists()


def test_valid_laws_are_not_refused_at_any_node():
    """The check lets every valid law through: the paper's law, p = r⁺ written by hand, K ≥ 0 everywhere."""
    result = vpcontact.solve(composed(lambda xi: 100.0 * (1 + 20 * xi), p=lambda r: np.maximum(r, 0.0)))
    assert result.status == "complete", result.message
