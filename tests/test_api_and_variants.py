"""Python callables for the laws and loads, the initial gap, and mesh files, each checked against
the equivalent built-in setting."""

import meshio
import numpy as np
import tomli_w

import vpcontact
from vpcontact.contact import CallableLaw
from vpcontact.mesh import rectangle
from conftest import half_disc_case, rectangle_case


def test_python_callables_give_the_built_in_laws():
    reference = vpcontact.solve(half_disc_case(h=0.2, load=40.0))
    case = half_disc_case(h=0.2, load=40.0)
    case["boundary"]["traction"] = []
    result = vpcontact.solve(
        case,
        p=CallableLaw(lambda r: np.maximum(r, 0.0), lambda r: (r >= 0).astype(float)),
        stiffness_law=CallableLaw(lambda xi: 100.0 * (1.0 + 20.0 * xi), lambda xi: 2000.0 + 0.0 * xi),
        tractions={"top_arc": lambda x, y, t: (0.0 * x, -40.0 * t + 0.0 * x)},
    )
    np.testing.assert_allclose(result.final.displacement, reference.final.displacement, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(result.contact_history("K"), reference.contact_history("K"), rtol=1e-12)


def test_a_law_without_derivative_converges_to_the_same_solution():
    reference = vpcontact.solve(half_disc_case(h=0.2, load=40.0))
    result = vpcontact.solve(half_disc_case(h=0.2, load=40.0),
                             stiffness_law=CallableLaw(lambda xi: 100.0 * (1.0 + 20.0 * xi)))
    np.testing.assert_allclose(result.contact_history("penetration"), reference.contact_history("penetration"),
                               rtol=0, atol=1e-10)


def test_an_initial_gap_delays_contact_by_a_rigid_translation():
    """A uniform gap g0 on the block: the same penetrations and pressures, the body moved by −g0."""
    reference = vpcontact.solve(rectangle_case())
    result = vpcontact.solve(rectangle_case(gap="0.01"))
    np.testing.assert_allclose(result.contact_history("penetration"), reference.contact_history("penetration"),
                               atol=1e-12)
    shift = result.final.displacement - reference.final.displacement
    np.testing.assert_allclose(shift, np.tile([0.0, -0.01], (shift.shape[0], 1)), atol=1e-12)


def test_a_body_force_is_carried_by_the_foundation():
    """Gravity ρ_m g on the block instead of the traction: the foundation carries the weight."""
    case = rectangle_case(g=float("inf"))
    case["boundary"]["traction"] = []
    case["boundary"]["body_force"] = [{"value": ["0", "-50*t"]}]
    result = vpcontact.solve(case)
    np.testing.assert_allclose(result.series("contact_force_y"), 50.0 * result.series("t") * 0.5, rtol=1e-10)


def test_a_gmsh_file_gives_the_built_in_mesh_solution(tmp_path):
    built_in = rectangle(1.0, 0.5, 0.125)
    skmesh = built_in.mesh
    tags = {"left": 1, "right": 2, "bottom": 3, "top": 4}
    lines = np.hstack([skmesh.facets[:, built_in.facets(name)] for name in tags]).T
    physical = np.concatenate([np.full(built_in.facets(name).size, tag) for name, tag in tags.items()])
    mesh = meshio.Mesh(skmesh.p.T, [("triangle", skmesh.t.T), ("line", lines)],
                       cell_data={"gmsh:physical": [np.zeros(skmesh.t.shape[1], int), physical],
                                  "gmsh:geometrical": [np.zeros(skmesh.t.shape[1], int), physical]},
                       field_data={name: np.array([tag, 1]) for name, tag in tags.items()})
    meshio.write(tmp_path / "block.msh", mesh, file_format="gmsh22", binary=False)
    case = rectangle_case()
    case["mesh"] = {"file": "block.msh"}
    case["contact"]["part"] = 3  # by physical number
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    from_file = vpcontact.solve(tmp_path / "case.toml")
    reference = vpcontact.solve(rectangle_case())
    np.testing.assert_allclose(from_file.contact_history("penetration"), reference.contact_history("penetration"),
                               atol=1e-12)
    np.testing.assert_allclose(from_file.series("contact_force_y"), reference.series("contact_force_y"), rtol=1e-12)
