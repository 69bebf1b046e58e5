"""Point and node-set constraints (issue 28, item 3): ``[[boundary.point]] at = [...]`` holds components at the node
nearest to a point, ``[[boundary.dirichlet]] where = "..."`` at the nodes where a condition holds; a full model
(no symmetry planes) pressed by a prescribed displacement, held against its rigid motions at two points, runs.

The checks: a full box made in gmsh (SI units) under a prescribed top displacement that presses, lifts off and
presses again is in uniaxial stress, exactly representable by P1 (u_x = −ν ε x, u_y = −ν ε y, u_z linear), so its
penetration, reaction and contact area are a scalar closed form to rounding, and the two points carry no force
(the x and y forces and the moment about z have no other source: their reactions vanish to rounding); a full
cylinder does the same up to its facetted mesh; a node set by a condition is the part it describes, bit for bit.
"""

import numpy as np
import pytest
import tomli_w

import vpcontact
from vpcontact.mesh.cells import coordinates

from conftest import assert_refused, run_cli, snapshot_tree

try:
    import gmsh
except (ImportError, OSError) as error:  # its module or the system libraries of its library missing
    pytest.skip(f"gmsh does not load: {error}", allow_module_level=True)

E, NU = 210e9, 0.3  # steel, Pa
WIDTH, DEPTH, HEIGHT = 10e-3, 8e-3, 6e-3  # m
G, C_V = 12e-6, 2e13  # the layer: 12 µm thick, K = C_V Pa/m
#: The top's displacement (m): down 30 µm at t = 1 (the rigid limit), lifted 5 µm at t = 2, down 40 µm at t = 3.
TOP = "5e-6 - 3.5e-5*max(1 - abs(t - 1), 1.3*(t - 2))"
STEPS = 12


def gmsh_mesh(make, size):
    """The mesh of the solid ``make()`` adds to a new gmsh model (OCC), its faces named by where they lie: "top"
    (z = max), "bottom" (z = 0), "side"; the volume "body"; as vpcontact reads it from memory."""
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("solid")
        volume = make()
        gmsh.model.occ.synchronize()
        top, bottom, side = [], [], []
        for _, tag in gmsh.model.getBoundary([(3, volume)], oriented=False):
            zmin, zmax = gmsh.model.getBoundingBox(2, tag)[2::3]
            (top if zmin > HEIGHT - 1e-6 else bottom if zmax < 1e-6 else side).append(tag)
        for name, tags in (("top", top), ("bottom", bottom), ("side", side)):
            gmsh.model.addPhysicalGroup(2, tags, name=name)
        gmsh.model.addPhysicalGroup(3, [volume], name="body")
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.mesh.generate(3)
        return vpcontact.mesh.from_gmsh()
    finally:
        gmsh.finalize()


def full_box():
    return gmsh_mesh(lambda: gmsh.model.occ.addBox(0, 0, 0, WIDTH, DEPTH, HEIGHT), 3e-3)


def full_cylinder():
    return gmsh_mesh(lambda: gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, HEIGHT, 5e-3), 2e-3)


def pressed(body, points, method="condensed", top=TOP):
    """``body`` pressed by the top displacement ``top`` onto the layer, held at ``points``."""
    problem = vpcontact.compose(
        body, {"E": E, "nu": NU}, dirichlet={"top": {"z": top}}, points=points,
        contact={"part": "bottom", "g": G, "normal": [0, 0, -1],
                 "stiffness": {"law": "power", "c_v": C_V, "alpha": 1e5, "beta": 1.0}},
        time={"T": 3.0, "steps": STEPS}, solver={"method": method, "tolerance": 1e-12})
    return problem, vpcontact.solve(problem)


def uniaxial_stress(T=3.0, steps=STEPS):
    """(penetration d, σ_zz) at every step of the uniform column in uniaxial stress: E (−w − d)/H = K(ξ + k d) d
    while below g (K = C_V (1 + α ξ) with β = 1: the power law), d = g at the limit, d = −w lifted off."""
    from scipy.optimize import brentq

    k, xi, out = T / steps, 0.0, []
    for n in range(1, steps + 1):
        t = n * k
        w = 5e-6 - 3.5e-5 * max(1 - abs(t - 1), 1.3 * (t - 2))
        stiffness = lambda d: C_V * (1 + 1e5 * (xi + k * max(d, 0.0)))  # noqa: E731
        if -w <= 0:
            d = -w
        elif stiffness(G) * G <= E * (-w - G) / HEIGHT:
            d = G
        else:
            d = brentq(lambda d: E * (-w - d) / HEIGHT - stiffness(d) * d, 0.0, min(G, -w), xtol=1e-300, rtol=1e-15)
        xi += k * max(d, 0.0)
        out.append((d, E * (w + d) / HEIGHT))
    return np.array(out)


@pytest.mark.parametrize("method", ["condensed", "full", "iterative"])
def test_a_full_box_held_at_two_corners_is_in_uniaxial_stress(method):
    body = full_box()
    points = [{"at": [0, 0, HEIGHT], "components": ["x", "y"], "name": "pin"},
              {"at": [WIDTH, 0, HEIGHT], "components": ["y"]}]
    problem, result = pressed(body, points, method)
    assert result.status == "complete"
    reference = uniaxial_stress()
    history = result.history
    force = np.abs(reference[:, 1]).max() * WIDTH * DEPTH
    penetration = np.maximum(reference[:, 0], 0.0)  # the history's penetrations are of d⁺
    np.testing.assert_allclose(history["max_penetration"], penetration, rtol=0, atol=1e-9 * G)
    np.testing.assert_allclose(history["mean_penetration"], penetration, rtol=0, atol=1e-9 * G)
    np.testing.assert_allclose(result.contact_history("penetration"),
                               np.broadcast_to(reference[:, :1], (STEPS, problem.surface.size)), rtol=0,
                               atol=1e-9 * G)
    np.testing.assert_allclose(history["reaction_top_z"], reference[:, 1] * WIDTH * DEPTH, rtol=0, atol=1e-9 * force)
    pressing = reference[:, 0] > 0
    np.testing.assert_allclose(history["contact_area"], np.where(pressing, WIDTH * DEPTH, 0.0), rtol=1e-12)
    assert history["limit_area"].max() == pytest.approx(WIDTH * DEPTH) and not pressing.all()
    for column in ("reaction_pin_x", "reaction_pin_y", "reaction_point1_x", "reaction_point1_y"):
        assert np.abs(history[column]).max() < 1e-9 * force, column
    # the free lateral expansion: u_x = −ν ε x at the top's far corner, ε = σ_zz / E
    p = body.mesh.p
    corner = np.argmin(np.sum((p - np.array([[WIDTH], [DEPTH], [HEIGHT]])) ** 2, axis=0))
    strain = reference[-1, 1] / E
    np.testing.assert_allclose(result.final.displacement[corner, :2], [-NU * strain * WIDTH, -NU * strain * DEPTH],
                               rtol=1e-8)


def test_a_full_cylinder_pressed_by_a_displacement_and_held_at_two_points_runs():
    body = full_cylinder()
    points = [{"at": [0, 0, HEIGHT], "components": ["x", "y"]}, {"at": [5e-3, 0, HEIGHT], "components": ["y"]}]
    problem, result = pressed(body, points)
    assert result.status == "complete", result.message
    history = result.history
    force = np.abs(history["reaction_top_z"]).max()
    balance = history["reaction_top_z"] + history["contact_force_z"]  # nothing else pushes along z
    assert np.abs(balance).max() < 1e-9 * force
    for column in ("reaction_point0_x", "reaction_point0_y", "reaction_point1_y"):
        assert np.abs(history[column]).max() < 1e-9 * force, column
    # the contact area is the bottom's facetted disc (the lumped weights add up to its facets' area) or nothing
    p, facets = body.mesh.p, body.mesh.facets[:, body.facets("bottom")]
    a, b, c = (p[:, facets[i]] for i in range(3))
    disc = 0.5 * np.linalg.norm(np.cross(b - a, c - a, axis=0), axis=0).sum()
    assert set(np.round(history["contact_area"] / disc, 12)) == {0.0, 1.0}
    # near the uniaxial stress of the column (the facetted sides are not vertical: 1 % at this mesh)
    reference = uniaxial_stress()
    pressing = reference[:, 0] > 0
    np.testing.assert_allclose(history["mean_penetration"][pressing], reference[pressing, 0], rtol=1e-2)


def test_a_node_set_by_a_condition_is_the_part_it_describes_bit_for_bit():
    body = full_box()
    points = [{"at": [0, 0, HEIGHT], "components": ["x", "y"]}, {"at": [WIDTH, 0, HEIGHT], "components": ["y"]}]
    _, by_part = pressed(body, points)
    problem = vpcontact.compose(
        body, {"E": E, "nu": NU}, points=points,
        dirichlet=[{"where": f"abs(z - {HEIGHT!r}) < 1e-12", "components": ["z"], "value": [TOP], "name": "top"}],
        contact={"part": "bottom", "g": G, "normal": [0, 0, -1],
                 "stiffness": {"law": "power", "c_v": C_V, "alpha": 1e5, "beta": 1.0}},
        time={"T": 3.0, "steps": STEPS}, solver={"method": "condensed", "tolerance": 1e-12})
    by_condition = vpcontact.solve(problem)
    columns = [c for c in by_part.history.columns if c != "wall_time_s"]
    np.testing.assert_array_equal(by_condition.history[columns].to_numpy(), by_part.history[columns].to_numpy())
    np.testing.assert_array_equal(by_condition.final.displacement, by_part.final.displacement)


# --- through the case file, and refusals ---------------------------------------------------------------------------
def block_case(**boundary):
    return {"mesh": {"shape": "block", "width": 1.0, "depth": 1.0, "height": 0.5, "h": 0.25},
            "material": {"E": 1000.0, "nu": 0.3},
            "boundary": {"dirichlet": [{"part": "top", "components": ["z"], "value": ["-0.01*t"]}], **boundary},
            "contact": {"part": "bottom", "g": 0.05, "stiffness": {"law": "constant", "value": 1000.0}},
            "time": {"T": 1.0, "steps": 2}}


def test_a_case_file_holds_points_and_writes_their_reactions(tmp_path):
    import pandas as pd

    case = block_case(point=[{"at": [0.0, 0.0, 0.5], "components": ["x", "y"]},
                             {"at": [1.0, 0.0, 0.5], "components": ["y"], "name": "guide"}])
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    status, _, stderr = run_cli("run", tmp_path / "case.toml", "--out", tmp_path / "run", "--quiet")
    assert status == 0, stderr
    history = pd.read_csv(tmp_path / "run" / "history.csv")
    for part in ("point0", "guide"):
        for c in coordinates(3):
            assert f"reaction_{part}_{c}" in history and f"displacement_{part}_{c}" in history
    assert np.abs(history[["reaction_point0_x", "reaction_point0_y", "reaction_guide_y"]].to_numpy()).max() < \
        1e-9 * np.abs(history["reaction_top_z"]).max()


@pytest.mark.parametrize("boundary, words", [
    ({"point": [{"at": [0.0, 0.0], "components": ["x"]}]}, ["boundary.point[0].at has 2 components", "3D"]),
    ({"point": [{"at": [0.0, 0.0, 0.5], "components": ["w"]}]}, ["boundary.point[0].components[0]"]),
    ({"point": [{"components": ["x"]}]}, ["boundary.point[0].at"]),
    ({"point": [{"at": [0.0, 0.0, 0.5], "name": "a b"}]}, ["boundary.point[0].name"]),
    ({"dirichlet": [{"components": ["z"]}]}, ["boundary.dirichlet[0]", "give the nodes held"]),
    ({"dirichlet": [{"where": "z = 0.5", "components": ["x"]}]}, ["boundary.dirichlet[0].where", "=="]),
    ({"dirichlet": [{"where": "abs(z - 0.7) < 1e-9", "components": ["x"]}]},
     ["boundary.dirichlet[0].where", "holds at no node of the mesh", "z in [0.0, 0.5]"]),
    ({"dirichlet": [{"where": "t < 1", "components": ["x"]}]}, ["boundary.dirichlet[0].where", "'t'"]),
])
def test_a_wrong_point_or_node_set_is_refused_in_one_line(tmp_path, boundary, words):
    case = block_case()
    case["boundary"]["dirichlet"] += boundary.pop("dirichlet", [])
    case["boundary"].update(boundary)
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    out = tmp_path / "out"
    status, _, stderr = run_cli("run", tmp_path / "case.toml", "--out", out)
    words = [w.replace("boundary.dirichlet[0]", "boundary.dirichlet[1]") for w in words]
    assert_refused(status, stderr, *words, untouched=[(out, snapshot_tree(out))])
