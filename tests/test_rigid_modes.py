"""Rigid-body motions: the null space of the stiffness, per connected body, and the part of it that the
Dirichlet conditions leave free."""

import numpy as np
import pytest
from skfem import MeshTri

import vpcontact
from vpcontact import build_problem
from vpcontact.fem.rigid_modes import RigidModes, bodies
from conftest import half_disc_case


def modes_of(case):
    problem = build_problem(vpcontact.load_case(case))
    mesh = problem.mesh.mesh
    return problem, RigidModes.of_mesh(mesh.p, mesh.t, problem.basis.nodal_dofs).matrix.toarray()


def test_the_stiffness_annihilates_the_rigid_modes_to_rounding():
    problem, modes = modes_of(half_disc_case(h=0.1))
    assert modes.shape == (problem.basis.N, 3)
    assert np.abs(problem.A @ modes).max() <= 100 * np.finfo(float).eps * abs(problem.A).max()
    # and they are motions: a translation moves every node alike, the rotation is orthogonal to the radius
    u = modes[problem.basis.nodal_dofs, 2]
    x = problem.mesh.mesh.p - problem.mesh.mesh.p.mean(axis=1, keepdims=True)
    np.testing.assert_allclose(np.sum(u * x, axis=0), 0.0, atol=1e-14)


def test_modes_are_the_same_in_any_unit_of_length():
    _, modes = modes_of(half_disc_case(h=0.1))
    scaled = half_disc_case(h=0.1e-3)
    scaled["mesh"]["radius"] = 1e-3
    _, modes_mm = modes_of(scaled)
    np.testing.assert_allclose(modes_mm, modes, atol=1e-12)


def test_two_bodies_have_their_own_modes():
    left = MeshTri.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 1, 3))
    right = MeshTri.init_tensor(np.linspace(2, 3, 3), np.linspace(0, 1, 3))
    p = np.hstack([left.p, right.p])
    t = np.hstack([left.t, right.t + left.p.shape[1]])
    count, body = bodies(t, p.shape[1])
    assert count == 2 and np.array_equal(np.bincount(body), [left.p.shape[1], right.p.shape[1]])
    nodal_dofs = np.arange(2 * p.shape[1]).reshape(-1, 2).T
    modes = RigidModes.of_mesh(p, t, nodal_dofs).matrix.toarray()
    assert modes.shape == (2 * p.shape[1], 6)
    on_left = np.zeros(2 * p.shape[1], dtype=bool)
    on_left[nodal_dofs[:, : left.p.shape[1]].ravel()] = True
    assert np.all(modes[~on_left, :3] == 0) and np.all(modes[on_left, 3:] == 0)


@pytest.mark.parametrize("fixed, expected", [
    ([], 3),                                    # floating: all three
    ([("left", 0)], 1),                         # a roller on one side: the vertical motion
    ([("left", 0), ("right", 0)], 1),
    ([("left", 0), ("left", 1)], 0),            # clamped
    ([("bottom", 1)], 1),                       # on rollers below: the horizontal motion
    ([("corner", 0), ("corner", 1)], 1),        # pinned at one node: the rotation about it
])
def test_the_modes_left_free_by_the_dirichlet_conditions(fixed, expected):
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 9), np.linspace(0, 0.5, 5))
    x, y = mesh.p
    nodes = {"left": x == 0, "right": x == 1, "bottom": y == 0, "corner": (x == 0) & (y == 0)}
    nodal_dofs = np.arange(2 * mesh.p.shape[1]).reshape(-1, 2).T
    held = np.concatenate([nodal_dofs[c, nodes[part]] for part, c in fixed] + [np.zeros(0, dtype=int)])
    free = np.setdiff1d(np.arange(nodal_dofs.size), held)
    Z = RigidModes.of_mesh(mesh.p, mesh.t, nodal_dofs).free_basis(free)
    assert Z.shape == (free.size, expected)
    np.testing.assert_allclose(Z.T @ Z, np.eye(expected), atol=1e-12)
    u = np.zeros((nodal_dofs.size, expected))
    u[free] = Z
    corners = np.stack([np.ones(mesh.t.shape), x[mesh.t], y[mesh.t]], axis=-1).transpose(1, 0, 2)  # (elements, 3, 3)
    for motion in u.T:  # each is rigid: no strain in any element
        gx, gy = (np.linalg.solve(corners, values[mesh.t].T[..., None])[:, 1:, 0] for values in motion[nodal_dofs])
        np.testing.assert_allclose([gx[:, 0], gy[:, 1], gx[:, 1] + gy[:, 0]], 0.0, atol=1e-12)
