"""Tetrahedra of the quarter of the unit ball centred at (0, 0, 1): {x > 0, y > 0, x² + y² + (z − 1)² < 1}.

The quarter ball is two octants of the ball, above and below the plane z = 1. Each octant is the
image of the cube [0, 1]³ under the equiangular cube-to-ball map

    q ↦ s · T(q/s) / |T(q/s)|,   s = max(q₁, q₂, q₃),   T(v) = (tan(πv₁/4), tan(πv₂/4), tan(πv₃/4)),

which maps the cube's shell {max(q) = s} onto the sphere of radius s around the octant's centre: the
faces q₁ = 0 and q₂ = 0 onto the symmetry planes x = 0 and y = 0 exactly, the face q₃ = 0 onto the
plane z = 1, and the three faces max(q) = 1 onto the sphere. The map is positively homogeneous
(x(λq) = λ x(q)), so the cells near the centre are scaled copies of those near the sphere, and the
angles of the shell (tan) make the sphere's cells about equal: the radial spacing is 1/n, the
tangential one between 0.74/n and 0.79/n. A structured grid of n³ cells is split into tetrahedra
the Kuhn way (6 per cell, all around the cell's diagonal that points away from the octant's
centre); the lower octant is the mirror image of the upper one, so both cut the plane z = 1 into the
same triangles and share its nodes.

`graded_towards_bottom` then bisects the tetrahedra near the bottom point (0, 0, 0) (scikit-fem's
longest-edge bisection, `MeshTet1.refined(marked)`), one level at a time, and after each level moves
the new nodes of the spherical boundary radially onto the sphere.

`coated_tetrahedra` makes the quarter ball with a coating of thickness c: the grid's shells are moved
along the radius so that one shell of nodes lands on the sphere of radius 1 − c (the interface), and
its grading bisects the tetrahedra of the grid's box, where the shells are planes, before they are
mapped onto the ball: the nodes it adds on the interface and the sphere stay on them exactly.
"""

from __future__ import annotations

import logging
from contextlib import contextmanager
from itertools import permutations

import numpy as np
import skfem

from .simplex import determinants, longest_edges

#: n = ceil(CELLS_PER_RADIUS / h) cells along a radius give a longest edge ≤ h: the longest edge of the
#: structured octants is 1.24/n (n = 2) to 1.49/n (n → ∞), a cell's diagonal near the sphere.
CELLS_PER_RADIUS = 1.5
#: Within FINE_ZONE · h_bottom of the bottom point the longest edge is at most h_bottom ...
FINE_ZONE = 10.0
#: ... and at a distance d farther out at most h_bottom + GROWTH · (d − FINE_ZONE · h_bottom) (and h).
GROWTH = 0.5
#: The mean volume of the tetrahedra of the graded zone over the cube of their allowed longest edge
#: (`target_edge`), for estimates of their number (measured 0.018 to 0.028; the estimates are then
#: within −30 % and +30 % of the count for h ≤ 1/4, up to +85 % for h = 1).
VOLUME_PER_CUBED_EDGE = 0.02


def structured_tetrahedra(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (3, (n + 1)²(2n + 1)) and positively oriented tetrahedra (4, 12n³) of the quarter ball of
    radius 1 centred at (0, 0, 1), n cells along each radius of each octant (see the module docstring)."""
    q, t = box_grid(n)
    p = to_ball(q)
    return p, positively_oriented(p, t)


def box_grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The points (i, j, k)/n (0 ≤ i, j ≤ n, −n ≤ k ≤ n) of the box [0, 1]² × [−1, 1] (3, (n + 1)²(2n + 1))
    and the tetrahedra (4, 12n³) of its cells, which `to_ball` maps onto the quarter ball (k > 0 above
    the plane z = 1, k < 0 below it)."""
    k = np.arange(-n, n + 1)
    I, J, K = np.meshgrid(np.arange(n + 1), np.arange(n + 1), k, indexing="ij")
    q = np.vstack((I.ravel(), J.ravel(), K.ravel())) / n

    index = np.arange(q.shape[1]).reshape(I.shape)
    cells = np.stack(np.meshgrid(np.arange(n), np.arange(n), np.arange(2 * n), indexing="ij")).reshape(3, -1)
    upper = cells[2] >= n  # the cell between k and k + 1 ≥ 1 (grid index k + n)
    # A Kuhn tetrahedron runs from a corner of its cell to the opposite corner along the cell's
    # edges, one axis after the other; the corner is the one nearest the plane z = 1.
    start = cells + np.where(upper, 0, 1) * np.array([[0], [0], [1]])
    step = np.where(upper, 1, -1)
    tetrahedra = []
    for order in permutations(range(3)):
        corner, corners = start.copy(), [index[tuple(start)]]
        for axis in order:
            corner[axis] += 1 if axis < 2 else step
            corners.append(index[tuple(corner)])
        tetrahedra.append(np.vstack(corners))
    return q, np.hstack(tetrahedra)


def to_ball(q: np.ndarray) -> np.ndarray:
    """The points of the quarter ball that points q (3, k) of the box [0, 1]² × [−1, 1] map to: the cube
    of q₃ ≥ 0 onto the octant above the plane z = 1 and that of q₃ ≤ 0 onto its mirror image below, by
    the equiangular map (the shell max(q₁, q₂, |q₃|) = s onto the sphere of radius s)."""
    octant = _equiangular(np.vstack((q[0], q[1], np.abs(q[2]))))
    return np.vstack((octant[0], octant[1], 1.0 + np.sign(q[2]) * octant[2]))


def coated_tetrahedra(n: int, coating: float, h: float, h_bottom: float | None) -> tuple[np.ndarray, np.ndarray,
                                                                                          np.ndarray]:
    """Nodes, tetrahedra (positively oriented in the box: also in the ball unless the coating is too thin
    for the grid, which folds it) and each node's side (−1 inside, 0 on, 1 outside) of the sphere of
    radius 1 − `coating` of the quarter ball of radius 1 centred at (0, 0, 1), n cells along each radius,
    graded towards the bottom point like `graded_towards_bottom` when h_bottom < h.

    The box grid's shells s = max(q₁, q₂, |q₃|) are moved to s' = (1 − c) s/s_m for s ≤ s_m and
    s' = 1 − c (1 − s)/(1 − s_m) for s ≥ s_m (piecewise linear, s_m = m/n, m = interface_shell(n, c)):
    the shell m onto the cube's shell 1 − c, which `to_ball` maps onto the sphere of that radius. The
    grading bisects the tetrahedra in that box (marking them by their lengths in the ball): the shells are
    planes there, which midpoints of their edges stay on exactly, so the nodes it adds on the interface
    and on the outer shell lie on their spheres once mapped, and each node's side is exact."""
    q, t = box_grid(n)
    s = np.vstack((q[0], q[1], np.abs(q[2]))).max(axis=0)
    s_m = interface_shell(n, coating) / n
    moved = np.where(s <= s_m, (1.0 - coating) * s / s_m, 1.0 - coating * (1.0 - s) / (1.0 - s_m))
    q = q * (moved / np.where(s > 0.0, s, 1.0))
    shell = np.vstack((q[0], q[1], np.abs(q[2]))).max(axis=0)
    interface = shell[s == s_m][0]  # the interface's nodes' shell: one product s_m · (s'/s_m) for all of them
    if h_bottom is not None and h_bottom < h:
        mesh = _BoxOfBall(q, t)
        with quiet_bisection():
            while (marked := _too_long(to_ball(mesh.p), mesh.t, h, h_bottom)).size:
                mesh = mesh.refined(marked)
        q, t = mesh.p, mesh.t
    side = np.sign(np.vstack((q[0], q[1], np.abs(q[2]))).max(axis=0) - interface).astype(np.int64)
    return to_ball(q), positively_oriented(q, t), side


class _BoxOfBall(skfem.MeshTet1):
    """Tetrahedra of the box that `to_ball` maps onto the ball, bisected (skfem's longest-edge bisection) at
    the edge that is longest once mapped: the same choices as bisecting the mapped tetrahedra. (It overrides
    a private method of scikit-fem 12; were it no longer called, the edges would be chosen by their lengths
    in the box: the mesh would still be conforming with its interface exact, only its angles would differ.)"""

    def _adaptive_sort_mesh(self, p, t, marked):
        return super()._adaptive_sort_mesh(to_ball(p), t, marked)


def interface_shell(n: int, coating: float) -> int:
    """The shell of nodes (of 0 ... n along a radius) that `coated_tetrahedra` puts on the sphere of radius
    1 − coating: the nearest to it, with at least one layer of cells on each side."""
    return min(max(round((1.0 - coating) * n), 1), n - 1)


def _equiangular(q: np.ndarray) -> np.ndarray:
    """The equiangular cube-to-ball map of points q (3, k) of [0, 1]³ into the unit ball's octant."""
    s = q.max(axis=0)
    direction = np.tan(0.25 * np.pi * q / np.where(s > 0.0, s, 1.0))
    return s * direction / np.where(s > 0.0, np.linalg.norm(direction, axis=0), 1.0)


def positively_oriented(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The tetrahedra t with the first two nodes of each negatively oriented one swapped."""
    t = t.copy()
    negative = determinants(p, t) < 0.0
    t[:2, negative] = t[1::-1, negative]
    return t


def target_edge(distance: np.ndarray, h: float, h_bottom: float) -> np.ndarray:
    """The longest edge allowed at `distance` from the bottom point (see FINE_ZONE and GROWTH)."""
    return np.minimum(h, h_bottom + GROWTH * np.maximum(distance - FINE_ZONE * h_bottom, 0.0))


def estimated_tetrahedra(h: float, h_bottom: float | None) -> float:
    """About how many tetrahedra `structured_tetrahedra` and `graded_towards_bottom` make for sizes h
    and h_bottom (computed before making them; inf when that is more than a float holds)."""
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        n = np.ceil(CELLS_PER_RADIUS / h)
        count = 12.0 * n * n * n
        if h_bottom is not None and h_bottom < h:
            # The body within distance d of the bottom point is at most a quarter of a half ball of
            # radius d: ∫ (π/2) d² / (VOLUME_PER_CUBED_EDGE · target_edge(d)³) dd over the graded zone.
            d = np.linspace(0.0, FINE_ZONE * h_bottom + (h - h_bottom) / GROWTH, 2001)
            size = target_edge(d, h, h_bottom)
            density = 0.5 * np.pi * d * d * (1.0 / (size * size * size) - 1.0 / (h * h * h))
            count += np.sum(0.5 * (density[1:] + density[:-1]) * np.diff(d)) / VOLUME_PER_CUBED_EDGE
    return float(count) if count == count else np.inf


def graded_towards_bottom(p: np.ndarray, t: np.ndarray, h: float, h_bottom: float) -> tuple[np.ndarray, np.ndarray]:
    """Bisect the tetrahedra (p, t) of the quarter ball of radius 1 centred at (0, 0, 1) until the
    longest edge of each is at most target_edge(distance of its centroid from (0, 0, 0)); after each
    bisection level, the new nodes on the sphere are moved radially onto it."""
    mesh = skfem.MeshTet1(p, t)
    centre = np.array([[0.0], [0.0], [1.0]])
    with quiet_bisection():
        while (marked := _too_long(mesh.p, mesh.t, h, h_bottom)).size:
            mesh = mesh.refined(marked)
            boundary = mesh.facets[:, mesh.boundary_facets()]
            centroid = mesh.p[:, boundary].mean(axis=1)
            on_sphere = np.unique(boundary[:, (centroid[0] > 1e-9 * h) & (centroid[1] > 1e-9 * h)])
            q = mesh.p.copy()
            offset = q[:, on_sphere] - centre
            q[:, on_sphere] = centre + offset / np.linalg.norm(offset, axis=0)
            mesh = skfem.MeshTet1(q, mesh.t)
    return mesh.p, positively_oriented(mesh.p, mesh.t)


def _too_long(p: np.ndarray, t: np.ndarray, h: float, h_bottom: float) -> np.ndarray:
    """The tetrahedra t on the nodes p whose longest edge exceeds target_edge(distance of their centroid
    from the bottom point (0, 0, 0))."""
    centroids = p[:, t].mean(axis=1)
    return np.flatnonzero(longest_edges(p, t) > target_edge(np.linalg.norm(centroids, axis=0), h, h_bottom))


@contextmanager
def quiet_bisection():
    """Around skfem's bisection, which seeds NumPy's global generator (the caller's state is kept) and logs
    a warning for each copy of its arrays (silenced)."""
    rng, log = np.random.get_state(), logging.getLogger("skfem.mesh.mesh")
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        yield
    finally:
        np.random.set_state(rng)
        log.setLevel(level)
