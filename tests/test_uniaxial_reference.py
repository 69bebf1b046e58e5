"""A block on rollers pressed onto the soft layer by a top traction that loads, unloads and reloads, the layer
reaching its rigid limit mid-run, leaving it and reaching it again: every run (2D plane strain and 3D, β = ±1, each
step method, and once through the command line) is the uniaxial closed form of tests/uniaxial.py, computed
without finite elements: the penetration, ξ, K and the two pressures at every contact node, the probe's history,
the contact force, the displacement at every node and the stress in every element, at every step; and the sums
of the internal forces over the held faces are the reactions of the closed form (what a prescribed top displacement
and the rollers will report).

The uniaxial state is the exact solution of the discrete problem on any mesh, so the meshes are coarse and the
agreement is that of rounding (measured: at most 1.1e-12 relative over these runs); RTOL asserts it to 1e-9.
The reference's displacement control, which the solver has not yet, is checked here against its traction control:
the same path gives the same state.
"""

import math
import tomllib

import numpy as np
import pandas as pd
import pytest

import vpcontact
from vpcontact import mesh as meshes

from conftest import run_cli, solved
from uniaxial import Block, Layer, under_displacement, under_traction

E, NU, HEIGHT, WIDTH, DEPTH, G = 1000.0, 0.3, 0.5, 1.0, 0.5, 0.2
T, STEPS = 3.0, 15
#: Relative agreement asserted (measured: at most 1.1e-12).
RTOL = 1e-9
#: The top traction's magnitude s(t)/S: up to 1 at t = 1, down to 0.05 at t = 2, up to 2.05 at t = 3; the same
#: function as an expression of the case and in Python, for the reference.
PATH = "0.05 + max(1 - abs(t - 1), 2*(t - 2))"


def path(t: float) -> float:
    return 0.05 + max(1.0 - abs(t - 1.0), 2.0 * (t - 2.0))


#: (dimension, β) -> the layer's K = c_v (1 + 20 ξ)^β with c_v = 100, p(r) = (r⁺)^m, ρ, and the load S that
#: brings it to the rigid limit mid-run, off it while unloading and back to it while reloading.
LAYERS = {(2, 1.0): {"exponent": 1.0, "rho": 1.0, "S": 100.0}, (2, -1.0): {"exponent": 1.0, "rho": 1.0, "S": 20.0},
          (3, 1.0): {"exponent": 1.5, "rho": 2.0, "S": 90.0}, (3, -1.0): {"exponent": 1.5, "rho": 2.0, "S": 8.0}}


def block(dim: int, hypothesis: str = "plane_strain") -> Block:
    return Block(E, NU, HEIGHT, WIDTH * (DEPTH if dim == 3 else 1.0), "3d" if dim == 3 else hypothesis)


def power_layer(beta: float, exponent: float, rho: float) -> Layer:
    return Layer(K=lambda xi: 100.0 * (1.0 + 20.0 * xi) ** beta, p=lambda r: max(r, 0.0) ** exponent, g=G, rho=rho)


def pressed(dim: int, beta: float, method: str, hypothesis: str = "plane_strain"):
    """The block of ``dim`` with the layer of LAYERS, composed and solved with every field kept; its reference."""
    layer = LAYERS[dim, beta]
    load = f"-{layer['S']}*({PATH})"
    if dim == 2:
        mesh, rollers, traction = meshes.rectangle(WIDTH, HEIGHT, 0.25), {"left": "x", "right": "x"}, ["0", load]
        probe = [0.5 * WIDTH, 0.0]
    else:
        mesh = meshes.block(WIDTH, DEPTH, HEIGHT, 0.25)
        rollers, traction = {"left": "x", "right": "x", "front": "y", "back": "y"}, ["0", "0", load]
        probe = [0.5 * WIDTH, 0.5 * DEPTH, 0.0]
    contact = {"part": "bottom", "g": G, "rho": layer["rho"], "probe": probe,
               "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": beta}}
    if layer["exponent"] != 1.0:
        contact.update(p="power", exponent=layer["exponent"])
    problem = vpcontact.compose(mesh, {"E": E, "nu": NU, **({"hypothesis": hypothesis} if dim == 2 else {})},
                                dirichlet=rollers, traction={"top": traction}, contact=contact,
                                time={"T": T, "steps": STEPS}, solver={"method": method, "tolerance": 1e-12})
    result = vpcontact.solve(problem, output={"field_steps": "all"})
    reference = under_traction(block(dim, hypothesis), power_layer(beta, layer["exponent"], layer["rho"]),
                               np.linspace(0.0, T, STEPS + 1), lambda t: layer["S"] * path(t))
    return result, reference


def agree(actual, expected, scale=None):
    """|actual − expected| ≤ RTOL · scale elementwise (scale: |expected|, or an array broadcast against them)."""
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    scale = np.abs(expected) if scale is None else np.asarray(scale, dtype=float)
    error = np.abs(actual - expected)
    assert np.all(error <= RTOL * scale), f"relative error {np.max(error / scale):.2e}"


def column(reference: pd.DataFrame, name: str) -> np.ndarray:
    """A reference column as a (steps, 1) array, to compare with (steps, nodes) arrays."""
    return reference[name].to_numpy()[:, None]


def assert_the_path_crosses_the_limit(reference: pd.DataFrame):
    """In compliance at the first step, at the rigid limit later, in compliance again, then at the limit again."""
    status = "".join(map(str, reference.status))
    assert status[0] == "1" and "2" in status and status.rstrip("2").endswith("1") and status.endswith("2"), status


def assert_the_fields_are_uniaxial(result, reference: pd.DataFrame, dim: int, hypothesis: str = "plane_strain"):
    """At every step: u = (0, (0,) −d + ε_zz z) at every node; σ_zz, the side stresses and no shear in every
    element (in 2D σ33 = L ε_zz in plane strain, 0 in plane stress); relative to the largest top displacement and
    the largest σ_zz of the run (a step may have none: a block lifted off the layer)."""
    vertical = result.discretization.mesh.mesh.p[dim - 1]
    u_top, stress_zz = reference.displacement_top.abs().max(), reference.stress_zz.abs().max()
    for n, row in enumerate(reference.itertuples(), start=1):
        fields = result.fields[n]
        agree(fields.displacement[:, dim - 1], -row.penetration + row.strain_zz * vertical, u_top)
        agree(fields.displacement[:, :dim - 1], 0.0, u_top)
        stress = fields.stress
        expected = np.diag([row.stress_side] * (dim - 1) + [row.stress_zz])
        agree(stress, np.broadcast_to(expected, stress.shape), stress_zz)
        if dim == 2:
            side = row.stress_side if hypothesis == "plane_strain" else 0.0
            agree(fields.stress33, side, stress_zz)


@pytest.mark.parametrize("method", ["condensed", "full", "iterative"])
@pytest.mark.parametrize("dim, beta", list(LAYERS))
def test_the_pressed_block_is_the_closed_form(dim, beta, method):
    result, reference = pressed(dim, beta, method)
    assert result.status == "complete" and result.step_cuts == 0 and result.method == method
    assert_the_path_crosses_the_limit(reference)
    np.testing.assert_array_equal(result.times, reference.t)
    total = column(reference, "pressure_compliance") + column(reference, "pressure_rigid")
    shape = result.contact_history("penetration").shape
    for name in ("penetration", "xi", "K", "pressure_compliance"):
        agree(result.contact_history(name), np.broadcast_to(column(reference, name), shape))
    agree(result.contact_history("pressure_rigid"), np.broadcast_to(column(reference, "pressure_rigid"), shape), total)
    np.testing.assert_array_equal(result.contact_history("status"), np.broadcast_to(column(reference, "status"), shape))
    agree(result.series("penetration_probe"), reference.penetration)
    agree(result.series("K_probe"), reference.K)
    agree(result.series("normal_stress_probe"), reference.stress_zz)
    vertical = "xyz"[dim - 1]
    agree(result.series(f"contact_force_{vertical}"), reference.contact_force)
    np.testing.assert_array_equal(result.series("nodes_at_limit"), (reference.status == 2) * shape[1])
    assert_the_fields_are_uniaxial(result, reference, dim)


def test_plane_stress_has_its_own_modulus():
    """Plane stress: the same penetrations (the traction fixes the pressure), but the block compresses by
    M = E / (1 − ν²) and σ33 = 0."""
    result, reference = pressed(2, 1.0, "full", hypothesis="plane_stress")
    assert result.status == "complete" and result.step_cuts == 0
    agree(result.series("penetration_probe"), reference.penetration)
    assert_the_fields_are_uniaxial(result, reference, 2, hypothesis="plane_stress")
    plane_strain = under_traction(block(2), power_layer(1.0, 1.0, 1.0), np.linspace(0.0, T, STEPS + 1),
                                  lambda t: 100.0 * path(t))
    assert not np.allclose(plane_strain.displacement_top, reference.displacement_top, rtol=1e-3)


CASE_3D = f"""\
[mesh]
shape = "block"
width = {WIDTH}
depth = {DEPTH}
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
part = "front"
components = ["y"]

[[boundary.dirichlet]]
part = "back"
components = ["y"]

[[boundary.traction]]
part = "top"
value = ["0", "0", "-10*({PATH})"]

[contact]
part = "bottom"
g = {G}
probe = [0.5, 0.25, 0.0]
stiffness = {{ law = "exponential", c_v = 100.0, alpha = -10.0 }}

[time]
T = {T}
steps = {STEPS}

[solver]
tolerance = 1e-12

[output]
field_steps = "none"
"""


def case_3d_reference() -> pd.DataFrame:
    """The closed form of CASE_3D: K = 100 exp(−10 ξ), p(r) = r⁺, ρ = 1, s(t) = 10 path(t)."""
    layer = Layer(K=lambda xi: 100.0 * math.exp(-10.0 * xi), p=lambda r: max(r, 0.0), g=G)
    return under_traction(block(3), layer, np.linspace(0.0, T, STEPS + 1), lambda t: 10.0 * path(t))


def test_the_command_line_run_is_the_closed_form(tmp_path):
    """3D, the exponential law K = 100 exp(−10 ξ) (softening), the solver's own choice of method, run by the
    command line: history.csv and contact.csv, read by pandas, are the closed form."""
    (tmp_path / "block.toml").write_text(CASE_3D)
    status, _, stderr = run_cli("run", tmp_path / "block.toml", "--out", tmp_path / "run", "--quiet")
    assert status == 0, stderr
    reference = case_3d_reference()
    assert_the_path_crosses_the_limit(reference)
    history = pd.read_csv(tmp_path / "run" / "history.csv")
    assert (history.substep == 1).all() and len(history) == STEPS
    np.testing.assert_allclose(history.t, reference.t, rtol=1e-15)
    agree(history.penetration_probe, reference.penetration)
    agree(history.K_probe, reference.K)
    agree(history.normal_stress_probe, reference.stress_zz)
    agree(history.contact_force_z, reference.contact_force)
    agree(history[["contact_force_x", "contact_force_y"]], 0.0, reference.contact_force.to_numpy()[:, None])
    nodes = history.nodes_at_limit + history.nodes_in_compliance
    assert (history.nodes_separated == 0).all() and (nodes == nodes[0]).all()
    np.testing.assert_array_equal(history.nodes_at_limit, (reference.status == 2) * nodes[0])
    contact = pd.read_csv(tmp_path / "run" / "contact.csv").merge(reference.assign(step=reference.index + 1), on="step",
                                                                  suffixes=("", "_reference"))
    assert len(contact) == STEPS * nodes[0]
    total = contact.pressure_compliance_reference + contact.pressure_rigid_reference
    for name in ("penetration", "xi", "K", "pressure_compliance"):
        agree(contact[name], contact[f"{name}_reference"])
    agree(contact.pressure_rigid, contact.pressure_rigid_reference, total)
    np.testing.assert_array_equal(contact.status, contact.status_reference.map({1: "in_compliance", 2: "at_limit"}))


def test_displacement_control_retraces_the_traction_path():
    """The reference's two controls on one path: the top displacement the traction s(t) gives, prescribed,
    gives back the same penetration, ξ, pressures and top force −s A (the displacement control's equation
    M (−w − d) / H = ρ K p(d) + λ/w has the traction's root); a top lifted above the layer (w > 0) separates the
    block from it: d = −w, no pressure, no contact area, ξ unchanged."""
    times = np.linspace(0.0, T, STEPS + 1)
    for (dim, beta), layer in LAYERS.items():
        law, S = power_layer(beta, layer["exponent"], layer["rho"]), layer["S"]
        traction = under_traction(block(dim), law, times, lambda t, S=S: S * path(t))
        top = dict(zip(traction.t, traction.displacement_top))
        displacement = under_displacement(block(dim), law, times, top.__getitem__)
        for name in ("penetration", "xi", "K", "pressure_compliance", "stress_zz", "top_force", "contact_force"):
            agree(displacement[name], traction[name])
        total = traction.pressure_compliance + traction.pressure_rigid
        agree(displacement.pressure_rigid, traction.pressure_rigid, total)
        np.testing.assert_array_equal(displacement.status, traction.status)
        agree(displacement.displacement_top, traction.displacement_top)
        agree(traction.top_force, -S * np.array([path(t) for t in traction.t]) * block(dim).area)
    lifted = under_displacement(block(3), power_layer(1.0, 1.0, 1.0), [0.0, 0.5, 1.0, 1.5],
                                lambda t: -0.6 * t if t < 1.0 else 0.01)
    assert list(lifted.status) == [2, 0, 0] and list(lifted.penetration) == [0.2, -0.01, -0.01]
    unloaded = lifted[["pressure_compliance", "pressure_rigid", "top_force", "contact_area", "limit_area"]].iloc[1:]
    assert (unloaded == 0.0).all().all()
    assert lifted.xi.tolist() == [0.1, 0.1, 0.1] and lifted.contact_area[0] == lifted.limit_area[0] == block(3).area


def test_the_internal_forces_on_the_held_faces_are_the_reactions_of_the_closed_form():
    """The sums of the internal forces A u over the nodes of a face, in the state of the closed form (3D, β = −1,
    every 5th step): on the rollers the reaction of the wall, ∓ L ε_zz × the face's area (the left and front walls
    push the body inwards, + x and + y); on the top, in z, σ_zz A, the force a prescribed top displacement's
    constraint exerts on the body in the same state (the reference's top_force: negative while pressing)."""
    case = tomllib.loads(CASE_3D)
    case["output"]["field_steps"] = [5, 10, 15]
    problem, result = solved(case)
    assert result.status == "complete"
    reference = case_3d_reference()
    mesh, dofs = problem.mesh, problem.basis.nodal_dofs
    faces = {"left": (0, -HEIGHT * DEPTH), "right": (0, HEIGHT * DEPTH), "front": (1, -HEIGHT * WIDTH),
             "back": (1, HEIGHT * WIDTH)}
    for n in (5, 10, 15):
        u = np.zeros(problem.basis.N)
        u[dofs] = result.fields[n].displacement.T
        internal = (problem.A @ u)[dofs]
        row = reference.iloc[n - 1]
        for part, (component, signed_area) in faces.items():
            agree(internal[component, mesh.nodes(part)].sum(), row.stress_side * signed_area)
        agree(internal[2, mesh.nodes("top")].sum(), row.top_force)
