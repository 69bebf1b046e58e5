"""Displacement control checked against the uniaxial closed form (issue 28, "Done when"): the block on rollers whose
top is moved down by a prescribed u_z = w(t) onto the soft layer, to its rigid limit at the peak, lifted off it
(w > 0: every contact node separated), pressed again to the limit. Every run (2D plane strain and 3D, β = ±1, each
step method, and once through the command line) is the closed form of tests/uniaxial.py (``under_displacement``):

    d_n: M (−w(t_n) − d) / H = ρ K(ξ_{n−1} + k d⁺) p(d) while that root is below g; else d = g and the rigid base
         carries the rest, λ/w = M (−w − g) / H − ρ K(ξ_{n−1} + k g) p(g); d = −w ≤ 0 where −w ≤ 0 (lifted off),
    ξ_n = ξ_{n−1} + k d_n⁺,  σ_zz = M (w + d) / H,  σ_side = L (w + d) / H,

with M = E (1 − ν) / ((1 + ν)(1 − 2ν)) (3D and plane strain) and L = E ν / ((1 + ν)(1 − 2ν)); the reaction of the top
(the force its constraint exerts on the body) σ_zz A ≤ 0, of the rollers ∓ σ_side × the side's area (the left and
front walls push the body inwards, + x and + y), the top's mean displacement w, the contact area A while d > 0 (0
lifted off) and the area at the limit A at the limit (else 0), the foundation's force (−σ_zz) A = −reaction.
"""

import numpy as np
import pandas as pd
import pytest

import vpcontact
from vpcontact import mesh as meshes

from conftest import run_cli
from test_uniaxial_reference import (DEPTH, G, HEIGHT, LAYERS, RTOL, STEPS, WIDTH, E, NU, T, agree,
                                     assert_the_fields_are_uniaxial, block, power_layer)
from uniaxial import under_displacement

#: The top's prescribed displacement w(t): down to −0.28 at t = 1 (the rigid limit), up to +0.02 at t = 2 (lifted
#: off the layer), down to −0.58 at t = 3 (the limit again); an expression of the case and the same in Python.
W = "0.02 - 0.3*max(1 - abs(t - 1), 2*(t - 2))"


def w(t: float) -> float:
    return 0.02 - 0.3 * max(1.0 - abs(t - 1.0), 2.0 * (t - 2.0))


def moved(dim: int, beta: float, method: str, top=W):
    """The block of ``dim`` with the layer of LAYERS, its top moved by ``top`` (an expression or a function),
    composed and solved with every field kept; its reference."""
    layer = LAYERS[dim, beta]
    vertical = "xyz"[dim - 1]
    if dim == 2:
        mesh, rollers = meshes.rectangle(WIDTH, HEIGHT, 0.25), {"left": "x", "right": "x"}
    else:
        mesh, rollers = meshes.block(WIDTH, DEPTH, HEIGHT, 0.25), {"left": "x", "right": "x", "front": "y", "back": "y"}
    contact = {"part": "bottom", "g": G, "rho": layer["rho"],
               "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": beta}}
    if layer["exponent"] != 1.0:
        contact.update(p="power", exponent=layer["exponent"])
    problem = vpcontact.compose(mesh, {"E": E, "nu": NU}, dirichlet={"top": {vertical: top}, **rollers},
                                contact=contact, time={"T": T, "steps": STEPS},
                                solver={"method": method, "tolerance": 1e-12})
    result = vpcontact.solve(problem, output={"field_steps": "all"})
    reference = under_displacement(block(dim), power_layer(beta, layer["exponent"], layer["rho"]),
                                   np.linspace(0.0, T, STEPS + 1), w)
    return result, reference


def side_areas(dim: int) -> dict[str, tuple[str, float]]:
    """Each roller part: its held component and its area (2D: its length) times its outward normal's sign."""
    if dim == 2:
        return {"left": ("x", -HEIGHT), "right": ("x", HEIGHT)}
    return {"left": ("x", -HEIGHT * DEPTH), "right": ("x", HEIGHT * DEPTH),
            "front": ("y", -HEIGHT * WIDTH), "back": ("y", HEIGHT * WIDTH)}


def assert_the_history_is_the_closed_form(history: pd.DataFrame, reference: pd.DataFrame, dim: int):
    """history.csv (or result.history): the top's reaction and mean displacement, the rollers' reactions, the
    contact and limit areas, the contact force and the balance, at every step."""
    vertical = "xyz"[dim - 1]
    force = reference.top_force.abs().max()
    assert len(history) == STEPS and (history.substep == 1).all()
    agree(history[f"reaction_top_{vertical}"], reference.top_force, force)
    assert (history[f"reaction_top_{vertical}"] <= RTOL * force).all()  # the top pushes down (lifted: 0, rounded)
    agree(history[f"displacement_top_{vertical}"], reference.displacement_top)
    agree(history.contact_area, reference.contact_area, block(dim).area)
    agree(history.limit_area, reference.limit_area, block(dim).area)
    agree(history[f"contact_force_{vertical}"], reference.contact_force, force)
    agree(history[f"reaction_top_{vertical}"] + history[f"contact_force_{vertical}"], 0.0, force)
    for part, (component, signed_area) in side_areas(dim).items():
        side_force = reference.stress_side.abs().max() * abs(signed_area)
        agree(history[f"reaction_{part}_{component}"], reference.stress_side * signed_area, side_force)
        agree(history[f"displacement_{part}_{component}"], 0.0, abs(w(T)))
    separated = (reference.status == 0).to_numpy()
    assert separated.any() and (history.nodes_separated[separated] > 0).all()


@pytest.mark.parametrize("method", ["condensed", "full", "iterative"])
@pytest.mark.parametrize("dim, beta", list(LAYERS))
def test_the_moved_block_is_the_closed_form(dim, beta, method):
    result, reference = moved(dim, beta, method)
    assert result.status == "complete" and result.step_cuts == 0 and result.method == method
    status = "".join(map(str, reference.status))
    assert status.startswith("1") and "21" in status and "0" in status and status.endswith("2"), status
    np.testing.assert_array_equal(result.times, reference.t)
    shape = result.contact_history("penetration").shape
    pressure = (reference.pressure_compliance + reference.pressure_rigid).max()
    agree(result.contact_history("penetration"), np.broadcast_to(reference.penetration.to_numpy()[:, None], shape))
    for name in ("xi", "K"):
        agree(result.contact_history(name), np.broadcast_to(reference[name].to_numpy()[:, None], shape))
    for name in ("pressure_compliance", "pressure_rigid"):
        agree(result.contact_history(name), np.broadcast_to(reference[name].to_numpy()[:, None], shape), pressure)
    np.testing.assert_array_equal(result.contact_history("status"),
                                  np.broadcast_to(reference.status.to_numpy()[:, None], shape))
    assert_the_history_is_the_closed_form(result.history, reference, dim)
    assert_the_fields_are_uniaxial(result, reference, dim)


def test_a_python_function_prescribes_the_same_displacement():
    """The top's value as a Python function f(x, y, z, t) gives the run of the expression (3D, condensed)."""
    expression, _ = moved(3, 1.0, "condensed")
    function, reference = moved(3, 1.0, "condensed", top=lambda x, y, z, t: np.full_like(x, w(t)))
    assert function.status == "complete"
    np.testing.assert_allclose(function.contact_history("penetration"), expression.contact_history("penetration"),
                               rtol=RTOL)
    assert_the_history_is_the_closed_form(function.history, reference, 3)


CASE = f"""\
[mesh]
shape = "rectangle"
width = {WIDTH}
height = {HEIGHT}
h = 0.25

[material]
E = {E}
nu = {NU}

[[boundary.dirichlet]]
part = "left"
components = ["x"]

[[boundary.dirichlet]]
part = "right"
components = ["x"]

[[boundary.dirichlet]]
part = "top"
components = ["y"]
value = ["{W}"]

[contact]
part = "bottom"
g = {G}
stiffness = {{ law = "power", c_v = 100.0, alpha = 20.0, beta = -1.0 }}

[time]
T = {T}
steps = {STEPS}

[solver]
tolerance = 1e-12

[output]
field_steps = "none"
"""


def test_the_command_line_run_is_the_closed_form(tmp_path):
    """2D plane strain, β = −1, the solver's own method, run by the command line: history.csv and contact.csv,
    read by pandas, are the closed form."""
    (tmp_path / "block.toml").write_text(CASE)
    status, _, stderr = run_cli("run", tmp_path / "block.toml", "--out", tmp_path / "run", "--quiet")
    assert status == 0, stderr
    reference = under_displacement(block(2), power_layer(-1.0, 1.0, 1.0), np.linspace(0.0, T, STEPS + 1), w)
    history = pd.read_csv(tmp_path / "run" / "history.csv")
    np.testing.assert_allclose(history.t, reference.t, rtol=1e-15)
    assert_the_history_is_the_closed_form(history, reference, 2)
    contact = pd.read_csv(tmp_path / "run" / "contact.csv").merge(reference.assign(step=reference.index + 1), on="step",
                                                                  suffixes=("", "_reference"))
    pressure = (reference.pressure_compliance + reference.pressure_rigid).max()
    for name in ("penetration", "xi", "K"):
        agree(contact[name], contact[f"{name}_reference"])
    for name in ("pressure_compliance", "pressure_rigid"):
        agree(contact[name], contact[f"{name}_reference"], pressure)
    names = contact.status_reference.map({0: "separated", 1: "in_compliance", 2: "at_limit"})
    np.testing.assert_array_equal(contact.status, names)
