"""2D–3D consistency: a prism of the half disc with u_z = 0 on both end faces against the 2D
plane-strain solution on the same cross-section mesh.

The prism is the built-in half disc (h = 0.35: 24 nodes, 30 triangles, 6 contact nodes) extruded
into L layers of thickness h along z, each prism cut into 3 tetrahedra by the standard conforming
split (the triangle's nodes ordered by index: the diagonal of each lateral rectangle goes from the
lower-index node at the bottom to the higher-index node at the top, in every layer alike), written
as a gmsh file and run as a user's mesh. Both runs are the paper's example with its layer law
K = 100 (1 + 20 ξ)^-1, g = 0.2, 11 steps, a vertical traction 30 t on the upper arc, and a fixed
contact normal (0, -1[, 0]) with the initial gap y/2 (a foundation halfway between the arc and the
plane y = 0): the contact nodes go through all three states (3 in compliance at the first step, 2
separated, 2 in compliance and 2 at the limit g at the last), so that the comparison covers the
nonlinear states and the history ξ. (A fixed normal, because with "body" normals the 3D normals of a
user's mesh are averaged facet normals, which the split makes differ from the 2D ones at the end
faces.)

What holds exactly. Let P copy a 2D nodal field to every layer (u_z = 0). The P1 interpolant of a
z-independent field on a tetrahedron of a prism is the triangle's own linear function, so the
strain of every tetrahedron is the 2D plane strain and the Galerkin projection is exact:
Pᵀ A3 P = L_z A2, Pᵀ F3 = L_z F2, and the lumped contact weights of the copies of a 2D node sum to
L_z w2; more: the rows of A3 P, F3 and w3 of an interior layer are exactly h times the 2D ones.

Why the prism's solution is not P u2 node by node. By the divergence theorem the force at node a of
a prism's stress is a sum over its lateral faces of (the face's normal stress) × ∫φ_a. On a split
rectangle of area A, ∫φ_a is A/3 or A/6 (the diagonal through node a or not), against A/4 for the
z-independent hat; the lumped contact weights and the traction shares alike. So P u2 leaves the
residual ±(A/12) × (the jump of the normal traction across the edge) at a node. In a stack of
translated layers a node inside the stack gets A/3 from one layer and A/6 from the other: the
residual cancels exactly, and is left only on the two end faces, opposite on the two (checked
against this formula to rounding). Its stress part has no resultant, but the lumped contact forces
leave a net vertical force, opposite at the two ends: the prism bends on its soft layer. That
response decays away from the ends (Saint-Venant) at a rate set by the cross-section on its layer,
not by the element size: doubling the prism's length from 32 to 64 layers divides the largest
mid-plane difference by 21, while 64 layers of h/2 (the 32 layers' length) divide it only by 2;
slowest at the first step, when no node is yet on the rigid base. The response is nearly
antisymmetric about the mid-plane, so there the in-plane displacements match much better than u_z
and the stresses; all of them are compared. With Poisson's ratio, a second effect: the end response
also lengthens the end zones, and with u_z = 0 at both ends the rest of the prism then carries a
uniform axial strain ε0 with ε0 L fixed (the axial-force mode, which does not decay), coupled to the
cross-section through ν. Measured (largest relative difference at the mid-plane over the 11 steps:
displacement, u_z, penetration, ξ, K, pressures, stresses of the mid-layer tetrahedra; no node in
another state in any case):

    L (layers of h)          2        8        16       32       64       128      192      256
    ν = 0, all               1.3e-1   1.7e-2   3.9e-3   1.1e-3   5.3e-5   7.4e-7   2.5e-9
    ν = 0, displacement      3.9e-3   8.5e-4   1.4e-4   3.1e-5   7.9e-7   9.5e-10  3.4e-11
    ν = 0.3, displacement                      1.5e-4   2.9e-5   8.7e-7   1.7e-7   1.1e-7   8.4e-8
    ν = 0.3, stress                            4.4e-3   1.1e-3   3.2e-5   1.1e-6   7.3e-7   5.4e-7

With ν = 0.3, ε0 L = 2.775e-6 from 96 layers on, and from there the displacement difference is
2.15e-5 / L and the stress difference 1.4e-4 / L: the 1e-8 of the plane-strain comparison would take
about 14,000 layers. So: with ν = 0 the mid-plane of a 192-layer prism (34 radii from each end)
equals the plane-strain solution to 1e-8 in every quantity at every step; with the paper's ν = 0.3
the far field is checked as what it is, generalized plane strain (a uniform ε_zz, ε0 L independent
of L, the in-plane difference ∝ 1/L).
"""

from functools import lru_cache

import meshio
import numpy as np
import pytest
import scipy.sparse as sp

import vpcontact
from vpcontact.mesh import half_disc, read_mesh

H = 0.35  # the cross-section's mesh size and the layers' thickness
LOAD = 30.0  # N/m on the upper arc: 2 of the 6 contact nodes end at the limit g
GAP = "0.5*y"  # the foundation halfway between the arc and the plane y = 0


# --- the prism ------------------------------------------------------------------------------------
def extruded_prism(section, layers: int, thickness: float) -> meshio.Mesh:
    """The 2D mesh ``section`` (a vpcontact Mesh) extruded along z into ``layers`` layers, as a gmsh
    mesh: node a of layer j (z = j × thickness) is node j n + a; each prism is cut into the tetrahedra
    (b0 b1 b2 t2), (b0 b1 t1 t2), (b0 t0 t1 t2) of its triangle's nodes v0 < v1 < v2 at the bottom (b)
    and top (t), so that the lateral rectangle of an edge (a < b) has the diagonal from a at the bottom
    to b at the top in both prisms that share it. Physical surfaces: the 2D parts' names for their
    lateral surfaces, "front" (z = 0) and "back" (the last layer); physical volume "body"."""
    p2, n = section.mesh.p, section.mesh.p.shape[1]
    shift = n * np.arange(layers)[:, None, None]  # (layers, 1, 1)
    points = np.vstack((np.tile(p2, layers + 1), np.repeat(thickness * np.arange(layers + 1), n)))
    bottom = np.sort(section.mesh.t, axis=0)[None] + shift  # (layers, 3, triangles)
    top = bottom + n
    tetrahedra = np.concatenate([np.stack(nodes, axis=-1) for nodes in (
        (bottom[:, 0], bottom[:, 1], bottom[:, 2], top[:, 2]),
        (bottom[:, 0], bottom[:, 1], top[:, 1], top[:, 2]),
        (bottom[:, 0], top[:, 0], top[:, 1], top[:, 2]))], axis=1).reshape(-1, 4)
    surfaces = {}
    for name in section.part_names:
        low, high = np.sort(section.mesh.facets[:, section.facets(name)], axis=0)[:, None, :] + shift[:, :, 0][None]
        surfaces[name] = np.concatenate((np.stack((low, high, high + n), axis=-1),
                                         np.stack((low, low + n, high + n), axis=-1)), axis=1).reshape(-1, 3)
    surfaces["front"] = section.mesh.t.T
    surfaces["back"] = section.mesh.t.T + layers * n
    tags = {name: tag for tag, name in enumerate(surfaces, start=1)}
    physical = [np.full(len(tetrahedra), 100)] + [np.full(len(f), tags[name]) for name, f in surfaces.items()]
    return meshio.Mesh(points.T, [("tetra", tetrahedra)] + [("triangle", f) for f in surfaces.values()],
                       cell_data={"gmsh:physical": physical, "gmsh:geometrical": physical},
                       field_data={"body": np.array([100, 3]), **{k: np.array([v, 2]) for k, v in tags.items()}})


def plane_case(nu: float) -> dict:
    """The paper's example on the coarse half disc, pressed along (0, -1) onto the foundation GAP below."""
    return {
        "mesh": {"shape": "half_disc", "h": H},
        "material": {"E": 1000.0, "nu": nu, "hypothesis": "plane_strain"},
        "boundary": {"dirichlet": [{"part": "axis", "components": ["x"]}],
                     "traction": [{"part": "top_arc", "value": ["0", f"-{LOAD}*t"]}]},
        "contact": {"part": "bottom_arc", "g": 0.2, "normal": [0.0, -1.0], "gap": GAP,
                    "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}},
        "time": {"T": 1.1, "steps": 11},
        "solver": {"tolerance": 1e-13},
        "output": {"field_steps": "all"},
    }


def prism_case(nu: float, mesh_file) -> dict:
    """The same case on the prism: the roller on the axis becomes a roller on the plane x = 0, and
    u_z = 0 on both end faces."""
    case = plane_case(nu)
    case["mesh"] = {"file": str(mesh_file)}
    del case["material"]["hypothesis"]
    case["boundary"]["dirichlet"] += [{"part": "front", "components": ["z"]}, {"part": "back", "components": ["z"]}]
    case["boundary"]["traction"][0]["value"] = ["0", f"-{LOAD}*t", "0"]
    case["contact"]["normal"] = [0.0, -1.0, 0.0]
    return case


@lru_cache(maxsize=None)
def prism_file(layers: int, folder: str) -> str:
    path = f"{folder}/prism_{layers}.msh"
    meshio.write(path, extruded_prism(half_disc(H), layers, H), file_format="gmsh22")
    return path


@lru_cache(maxsize=None)
def plane_result(nu: float):
    result = vpcontact.solve(plane_case(nu))
    assert result.status == "complete"
    return result


@lru_cache(maxsize=None)
def prism_result(nu: float, layers: int, folder: str):
    result = vpcontact.solve(prism_case(nu, prism_file(layers, folder)))
    assert result.status == "complete"
    return result


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return str(tmp_path_factory.mktemp("prisms"))


def prolongation(plane, prism) -> sp.csr_matrix:
    """P: the 2D nodal dofs (x, y) copied to every layer, u_z = 0."""
    d2, d3 = plane.basis.nodal_dofs, prism.basis.nodal_dofs
    n = d2.shape[1]
    layers = d3.shape[1] // n
    rows = d3[:2].reshape(2, layers, n)
    cols = np.broadcast_to(d2[:, None, :], rows.shape)
    return sp.csr_matrix((np.ones(rows.size), (rows.ravel(), cols.ravel())), shape=(prism.basis.N, plane.basis.N))


def layer_rows(prism, n: int, layer: int, components=(0, 1)) -> np.ndarray:
    """The dofs of ``components`` of the nodes of ``layer``, (components, n)."""
    return prism.basis.nodal_dofs[list(components), layer * n:(layer + 1) * n]


def mid_plane_contact(plane, prism, layer: int) -> tuple[np.ndarray, np.ndarray]:
    """(3D contact indices of the nodes of ``layer``, the 2D contact index of each)."""
    n = plane.mesh.mesh.p.shape[1]
    nodes = prism.surface.nodes
    here = np.flatnonzero(nodes // n == layer)
    return here, np.searchsorted(plane.surface.nodes, nodes[here] % n)


def layer_triangles(plane, prism, layer: int) -> tuple[np.ndarray, np.ndarray]:
    """(the tetrahedra of ``layer``, the 2D triangle under each)."""
    n = plane.mesh.mesh.p.shape[1]
    t3 = prism.mesh.mesh.t
    inside = np.flatnonzero(t3.min(axis=0) // n == layer)
    corners = np.sort(t3[:, inside] % n, axis=0)  # one 2D node twice
    middle = np.where(corners[1] != corners[0], corners[1], corners[2])
    t2 = np.sort(plane.mesh.mesh.t, axis=0)

    def key(a, b, c):  # one integer per sorted node triple
        return (a * n + b) * n + c

    order = np.argsort(key(*t2))
    triangle = order[np.searchsorted(key(*t2)[order], key(corners[0], middle, corners[3]))]
    assert np.array_equal(np.sort(t2[:, triangle], axis=0), np.vstack((corners[0], middle, corners[3])))
    return inside, triangle


# --- the tests --------------------------------------------------------------------------------------
def test_the_prism_is_a_conforming_tetrahedral_mesh_of_the_extruded_half_disc(folder):
    """The split agrees across every shared face: the boundary of the tetrahedra is only the lateral
    surface and the two end faces (a split that disagreed would leave inner faces open); volume and
    parts are those of the extrusion."""
    layers = 4
    section = half_disc(H)
    prism = read_mesh(prism_file(layers, folder))
    n, triangles = section.mesh.p.shape[1], section.mesh.t.shape[1]
    np.testing.assert_array_equal(prism.mesh.p[:2].reshape(2, layers + 1, n),
                                  np.broadcast_to(section.mesh.p[:, None, :], (2, layers + 1, n)))
    assert prism.mesh.t.shape[1] == 3 * layers * triangles
    assert prism.mesh.boundary_facets().size == 2 * layers * section.mesh.boundary_facets().size + 2 * triangles
    assert {"axis", "bottom_arc", "top_arc", "front", "back"} <= set(prism.parts)
    for name in ("axis", "bottom_arc", "top_arc"):
        assert prism.facets(name).size == 2 * layers * section.facets(name).size
    p, t = prism.mesh.p, prism.mesh.t
    volumes = np.abs(np.einsum("ij,ij->j", np.cross(p[:, t[1]] - p[:, t[0]], p[:, t[2]] - p[:, t[0]], axis=0),
                               p[:, t[3]] - p[:, t[0]])) / 6.0
    (x0, y0), (x1, y1), (x2, y2) = (section.mesh.p[:, section.mesh.t[k]] for k in range(3))
    area = 0.5 * np.abs((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)).sum()
    assert volumes.min() > 0.0 and volumes.sum() == pytest.approx(area * layers * H, rel=1e-13)


def test_the_galerkin_projection_of_the_prism_is_the_plane_strain_problem(folder):
    """Pᵀ A3 P = L_z A2, Pᵀ F3 = L_z F2, Σ w3 over the copies of a node = L_z w2 (the paper's ν = 0.3),
    and stronger: the rows of an interior layer are h times the 2D rows (z rows: 0), the end faces'
    rows are not h/2 times them (the split)."""
    layers = 6
    plane = vpcontact.build_problem(vpcontact.load_case(plane_case(0.3)))
    prism = vpcontact.build_problem(vpcontact.load_case(prism_case(0.3, prism_file(layers, folder))))
    n = plane.mesh.mesh.p.shape[1]
    P = prolongation(plane, prism)
    A2, AP = plane.A.toarray(), (prism.A @ P).toarray()
    scale = np.abs(A2).max()
    length = layers * H
    assert np.abs(P.T @ AP - length * A2).max() <= 1e-13 * scale
    for layer in range(1, layers):
        assert np.abs(AP[layer_rows(prism, n, layer)] - H * A2[plane.basis.nodal_dofs]).max() <= 1e-13 * scale
        assert np.abs(AP[layer_rows(prism, n, layer, [2])]).max() <= 1e-13 * scale
    for end in (0, layers):
        assert np.abs(AP[layer_rows(prism, n, end)] - 0.5 * H * A2[plane.basis.nodal_dofs]).max() > 1e-2 * scale

    for t in (0.1, 1.1):
        F2, F3 = plane.loads(t), prism.loads(t)
        assert np.abs(P.T @ F3 - length * F2).max() <= 1e-13 * np.abs(F2).max()
        assert np.abs(F3[layer_rows(prism, n, layers // 2)] - H * F2[plane.basis.nodal_dofs]).max() \
            <= 1e-13 * np.abs(F2).max()

    s2, s3 = plane.surface, prism.surface
    copies = np.searchsorted(s2.nodes, s3.nodes % n)
    np.testing.assert_array_equal(s2.nodes[copies], s3.nodes % n)
    np.testing.assert_allclose(np.bincount(copies, weights=s3.weights), length * s2.weights, rtol=1e-13)
    inner = (s3.nodes // n > 0) & (s3.nodes // n < layers)
    np.testing.assert_allclose(s3.weights[inner], H * s2.weights[copies[inner]], rtol=1e-13)
    np.testing.assert_array_equal(s3.gap0, s2.gap0[copies])
    np.testing.assert_array_equal(s3.normals[:2], s2.normals[:, copies])
    assert np.all(s3.normals[2] == 0.0)
    # the penetrations of P u are the 2D penetrations copied
    u2 = np.random.default_rng(0).standard_normal(plane.basis.N)
    np.testing.assert_allclose(s3.operator @ (P @ u2), (s2.operator @ u2)[copies], rtol=0, atol=1e-15)


def split_prism_residual(plane_run, t: float) -> np.ndarray:
    """The docstring's prediction of the residual of P u2 at the front face (z = 0), (2, nodes): each
    edge e of the section (length ℓ) moves ℓh/12 of its face's share, +ℓh/12 to its lower-index node
    and −ℓh/12 from the other, for the normal stresses of the triangles on it, minus the traction on
    it (the upper arc), plus the contact force of each of its nodes (its pressure p along ν)."""
    plane = plane_run.discretization
    mesh, p = plane.mesh.mesh, plane.mesh.mesh.p
    edges = np.sort(mesh.facets, axis=0)
    tangent = p[:, edges[1]] - p[:, edges[0]]
    length = np.linalg.norm(tangent, axis=0)
    force = np.zeros((2, edges.shape[1]))  # Σ_T σ_T n_T (outward from T), minus the traction
    for side in mesh.f2t:
        on = side >= 0
        normal = np.array([tangent[1], -tangent[0]])[:, on] / length[on]
        outward = np.sign(np.einsum("ij,ij->j", normal, p[:, edges[0, on]] - p[:, mesh.t[:, side[on]]].mean(axis=1)))
        force[:, on] += np.einsum("eij,je->ie", plane_run.final.stress[side[on]], normal * outward)
    force[1, plane.mesh.facets("top_arc")] += LOAD * t
    share = np.vstack((+length, -length)) * H / 12.0  # (lower node, higher node) of each edge
    R = np.zeros_like(p)
    for end in range(2):
        np.add.at(R.T, edges[end], (share[end] * force).T)
    s = plane.surface
    pressure = (plane_run.contact_history("pressure_compliance") + plane_run.contact_history("pressure_rigid"))[-1]
    contact = plane.mesh.facets("bottom_arc")
    moved = np.zeros(p.shape[1])
    for end in range(2):
        np.add.at(moved, edges[end, contact], share[end, contact])
    R[:, s.nodes] += moved[s.nodes] * pressure * s.normals
    R[0, plane.mesh.nodes("axis")] = 0.0  # the roller's rows
    return R


def test_the_extruded_plane_strain_solution_is_out_of_balance_only_on_the_end_faces(folder):
    """The equations of the prism's last step at P u2 with the 2D contact pressures copied: balanced
    to rounding at every interior layer; on the end faces the split-prism residual of the module's
    docstring (±ℓh/12 × the normal-stress jump at each edge), opposite on the two faces."""
    layers = 6
    plane_run = plane_result(0.3)
    plane = vpcontact.build_problem(vpcontact.load_case(plane_case(0.3)))
    prism = vpcontact.build_problem(vpcontact.load_case(prism_case(0.3, prism_file(layers, folder))))
    n = plane.mesh.mesh.p.shape[1]
    P = prolongation(plane, prism)
    u2 = plane_run.final.displacement.ravel()  # (nodes, 2) row-major: the dofs of node i are 2i, 2i + 1
    assert np.array_equal(plane.basis.nodal_dofs, np.arange(2 * n).reshape(n, 2).T)
    pressure = (plane_run.contact_history("pressure_compliance") + plane_run.contact_history("pressure_rigid"))[-1]
    t = plane.times.at(11)

    def residual(problem, u, p):
        s = problem.surface
        R = problem.A @ u + s.operator.T @ (s.weights * p) - problem.loads(t)
        R[np.setdiff1d(np.arange(problem.basis.N), problem.free)] = 0.0
        return R

    R2 = residual(plane, u2, pressure)
    scale = np.abs(plane.loads(t)).max()
    assert np.abs(R2).max() <= 1e-10 * scale  # the 2D solution balances its own equations
    copies = np.searchsorted(plane.surface.nodes, prism.surface.nodes % n)
    R3 = residual(prism, P @ u2, pressure[copies])
    for layer in range(1, layers):
        assert np.abs(R3[layer_rows(prism, n, layer, [0, 1, 2])]).max() <= 1e-12 * H * scale
    front, back = R3[layer_rows(prism, n, 0)], R3[layer_rows(prism, n, layers)]
    assert np.abs(front).max() > 1e-2 * H * scale
    np.testing.assert_allclose(front, split_prism_residual(plane_run, t), rtol=0, atol=1e-11 * H * scale)
    np.testing.assert_allclose(back, -front, rtol=0, atol=1e-12 * H * scale)


def mid_plane_differences(plane_run, prism_run) -> dict[str, float]:
    """The largest differences between the prism's mid-plane (its nodes, the contact nodes on it, the
    tetrahedra of the layer above it) and the 2D solution over all steps, each relative to the 2D
    quantity's largest value at that step (the contact quantities: to the largest of their kind)."""
    plane, prism = plane_run.discretization, prism_run.discretization
    n = plane.mesh.mesh.p.shape[1]
    layers = prism.mesh.mesh.p.shape[1] // n - 1
    mid = layers // 2
    contact, copies = mid_plane_contact(plane, prism, mid)
    tetrahedra, triangles = layer_triangles(plane, prism, mid)
    out = {"displacement": 0.0, "u_z": 0.0, "stress": 0.0}
    for step in range(1, 12):
        two, three = plane_run.fields[step], prism_run.fields[step]
        u2 = two.displacement
        u3 = three.displacement.reshape(layers + 1, n, 3)[mid]
        scale = np.abs(u2).max()
        out["displacement"] = max(out["displacement"], np.abs(u3[:, :2] - u2).max() / scale)
        out["u_z"] = max(out["u_z"], np.abs(u3[:, 2]).max() / scale)
        s2 = np.zeros((triangles.size, 3, 3))
        s2[:, :2, :2] = two.stress[triangles]
        s2[:, 2, 2] = two.stress33[triangles]
        out["stress"] = max(out["stress"], np.abs(three.stress[tetrahedra] - s2).max() / np.abs(s2).max())
    for name in ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid"):
        a, b = plane_run.contact_history(name), prism_run.contact_history(name)[:, contact]
        out[name] = np.abs(b - a[:, copies]).max() / np.abs(a).max()
    out["states_differ"] = int(np.sum(prism_run.contact_history("status")[:, contact]
                                      != plane_run.contact_history("status")[:, copies]))
    return out


def largest(differences: dict) -> float:
    """The largest of the relative differences of :func:`mid_plane_differences` (states apart)."""
    return max(value for name, value in differences.items() if name != "states_differ")


def test_the_end_faces_effect_on_the_mid_plane_decays_with_the_prisms_length(folder):
    """ν = 0 (no axial mode, see the module's docstring): the end faces reach the mid-plane of a short
    prism, and their effect there falls by a steady factor per layer as the prism grows: at least
    e^0.12 per layer of the mid-plane's distance to the ends (measured: e^0.19 from 32 to 64 layers,
    e^0.16 from 64 to 192), and at most e^0.3: the rate of the cross-section on its soft layer, not
    of the element."""
    plane_run = plane_result(0.0)
    states = plane_run.contact_history("status")
    assert set(states[0]) == {0, 1} and set(states[-1]) == {0, 1, 2}  # all three states, states change
    at = {layers: largest(mid_plane_differences(plane_run, prism_result(0.0, layers, folder)))
          for layers in (16, 32, 64)}
    assert at[16] > at[32] > at[64] and at[16] > 1e-3
    rate = np.log(at[32] / at[64]) / 16  # per layer of the mid-plane's distance to the ends
    assert 0.12 <= rate <= 0.3, rate


def test_away_from_the_end_faces_the_prism_equals_the_plane_strain_solution(folder):
    """ν = 0: at 192 layers (34 cross-section radii from each end) the mid-plane equals the
    plane-strain solution to 1e-8 at every step: the displacements (u_z = 0), the contact nodes'
    penetration, ξ, K, both pressures and states, the stresses of the mid-layer tetrahedra (σ_zz
    and the out-of-plane shears included); the decay from 64 layers on is as steady as before it."""
    plane_run = plane_result(0.0)
    longest = mid_plane_differences(plane_run, prism_result(0.0, 192, folder))
    assert longest["states_differ"] == 0
    assert largest(longest) <= 1e-8, longest
    rate = np.log(largest(mid_plane_differences(plane_run, prism_result(0.0, 64, folder))) / largest(longest)) / 64
    assert 0.12 <= rate <= 0.3, rate


def test_with_the_papers_poisson_ratio_the_far_field_adds_a_uniform_axial_strain(folder):
    """ν = 0.3: far from the ends the prism is in generalized plane strain, the 2D solution plus a
    uniform axial strain ε0 (the same at every node of the cross-section) that the end zones'
    lengthening leaves in a prism held at u_z = 0 at both ends: ε0 L does not depend on L, and the
    mid-plane's in-plane difference is the Poisson response to it, ∝ 1/L, not exponential."""
    plane_run = plane_result(0.3)
    n = plane_run.discretization.mesh.mesh.p.shape[1]
    strain, moved = {}, {}
    for layers in (96, 128):
        prism_run = prism_result(0.3, layers, folder)
        mid = layers // 2
        u_z = prism_run.final.displacement.reshape(layers + 1, n, 3)[:, :, 2]
        eps = (u_z[mid + 1] - u_z[mid - 1]) / (2 * H)
        assert np.ptp(eps) <= 1e-2 * abs(eps.mean())  # uniform over the cross-section
        strain[layers] = eps.mean() * layers
        differences = mid_plane_differences(plane_run, prism_run)
        assert differences["states_differ"] == 0
        moved[layers] = differences["displacement"] * layers
    assert strain[128] == pytest.approx(strain[96], rel=0.01) and abs(strain[128]) > 1e-7
    assert moved[128] == pytest.approx(moved[96], rel=0.05) and moved[128] / 128 > 1e-7
