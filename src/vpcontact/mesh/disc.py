"""Triangles of the half disc of radius 1 centred at (0, 1): {x > 0, x² + (y − 1)² < 1}, with or without a coating.

`unit_half_disc` puts nodes of equal arc length on the arc and the axis, one layer of nodes parallel to the
arc inside it, staggered against the arc's nodes, and a hexagonal lattice inside that layer; the
triangulation is the lattice's own far from the boundary and scipy's Delaunay near it, and the interior
nodes are then Laplacian-smoothed (`smooth`). `coated_half_disc` makes the same mesh for the core of radius
1 − c and rows of nodes on half circles in the coating around it, so that the interface is a line of nodes.
`vpcontact.mesh.shapes.half_disc` scales them to the radius asked for and names their parts and regions.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import Delaunay

from .simplex import determinants


def unit_half_disc(h: float, n_arc: int, n_axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (2, n) and counter-clockwise triangles (3, m) of `half_disc` for R = 1 and h (relative to R), with
    n_arc facets on each quarter arc and n_axis on the axis: the arc's 2 n_arc + 1 nodes first, from (0, 0)
    counter-clockwise to (0, 2), then the axis' inner nodes downwards, then the interior nodes."""
    R = 1.0
    # Boundary: the arc counter-clockwise from (0, 0) to (0, 2R), then the axis downwards.
    angle = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2 * n_arc + 1)
    arc = np.vstack((R * np.cos(angle), R + R * np.sin(angle)))
    arc[0, [0, -1]] = 0.0
    arc[:, n_arc] = (R, R)
    axis_y = 2.0 * R * np.arange(n_axis - 1, 0, -1) / n_axis
    axis = np.vstack((np.zeros_like(axis_y), axis_y))

    # A layer of nodes at depth √3/2·h below the arc, between the arc nodes (spacing ≥ 0.8 h
    # when the mesh is so coarse that the inner circle is much shorter than the arc). Nodes
    # nearer than √3/2·h to the axis (at the corners) are moved out to x = √3/2·h, and
    # dropped if that brings them within h/2 of a node that was not moved.
    dx = 0.5 * np.sqrt(3.0) * h
    n_layer = max(0, min(2 * n_arc, int(np.ceil(np.pi * (R - dx) / (0.8 * h)))))
    layer_angle = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2 * n_layer + 1)[1::2]
    layer = np.vstack(((R - dx) * np.cos(layer_angle), R + (R - dx) * np.sin(layer_angle)))
    clamped = layer[0] < dx
    layer[0, clamped] = dx
    gap = np.linalg.norm(layer[:, clamped, None] - layer[:, None, ~clamped], axis=0).min(axis=1, initial=np.inf)
    layer = np.hstack((layer[:, ~clamped], layer[:, clamped][:, gap >= 0.5 * h]))

    # Interior: hexagonal lattice of spacing h, point (k, i) at k·a + i·b + (0, R) with
    # a = (√3/2·h, h/2), b = (0, h), k ≥ 1 (columns parallel to the axis); points closer
    # than h/2 to the layer's circle are dropped.
    n_col = int(R / dx)
    i_min = int(np.floor(-R / h - 0.5 * n_col)) - 1
    K, I = np.meshgrid(np.arange(1, n_col + 1), np.arange(i_min, int(np.ceil(R / h)) + 2), indexing="ij")
    lattice = np.stack((K * dx, R + (0.5 * K + I) * h))
    radius_of = np.hypot(lattice[0], lattice[1] - R)
    kept = radius_of <= R - dx - 0.5 * h

    p = np.hstack((arc, axis, layer, lattice[:, kept]))
    n_boundary = arc.shape[1] + axis.shape[1]
    index = np.full(kept.shape, -1, dtype=np.int64)
    index[kept] = np.arange(n_boundary + layer.shape[1], p.shape[1])

    # Far from the boundary the Delaunay triangulation is the lattice's own: take its
    # triangles there ("core": all vertices of column ≥ 2, 2h inside the layer's circle) and
    # triangulate only the remaining points. Cell (k, i) of the lattice holds the triangles
    # (k,i),(k+1,i),(k,i+1) and (k+1,i),(k+1,i+1),(k,i+1), both counter-clockwise.
    core_node = kept & (K >= 2) & (radius_of <= R - dx - 2.0 * h)
    lower = core_node[:-1, :-1] & core_node[1:, :-1] & core_node[:-1, 1:]
    upper = core_node[1:, :-1] & core_node[1:, 1:] & core_node[:-1, 1:]
    core_t = np.hstack((
        np.vstack((index[:-1, :-1][lower], index[1:, :-1][lower], index[:-1, 1:][lower])),
        np.vstack((index[1:, :-1][upper], index[1:, 1:][upper], index[:-1, 1:][upper])),
    ))
    inner = np.bincount(core_t.ravel(), minlength=p.shape[1]) == 6
    rest = np.flatnonzero(~inner)
    t = rest[Delaunay(p[:, rest].T).simplices.T]
    # drop the triangles filling the core: their centroid lies in a core lattice cell
    kf = p[0, t].mean(axis=0) / dx
    i_f = (p[1, t].mean(axis=0) - R) / h - 0.5 * kf
    k0, i0 = np.floor(kf).astype(np.int64), np.floor(i_f).astype(np.int64)
    in_upper = (kf - k0) + (i_f - i0) > 1.0
    # cell (k, i) is entry (k, i - i_min + 1) of the padded masks; out of range -> False border
    k0 = np.clip(k0, 0, lower.shape[0] + 1)
    i0 = np.clip(i0 - i_min + 1, 0, lower.shape[1] + 1)
    in_core = np.where(in_upper, np.pad(upper, 1)[k0, i0], np.pad(lower, 1)[k0, i0])
    t = t[:, ~in_core]
    flip = determinants(p, t) < 0
    t[1:, flip] = t[2:0:-1, flip]
    t = np.hstack((core_t, t))
    p = smooth(p, t, np.arange(p.shape[1]) >= n_boundary, sweeps=6)
    return p, t


def coated_half_disc(h: float, c: float, n_arc: int) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], int]:
    """Nodes, counter-clockwise triangles, regions {"core", "coating"} and the number of axis facets of the
    half disc of radius R = 1 centred at (0, R) with a coating of thickness c, n_arc facets on each quarter
    of its arc (h and c relative to R).

    The core is `half_disc`'s mesh of radius R − c (size min(h, R − c)) moved to the center (0, R); its arc
    nodes are the interface. The coating holds L = max(1, round(c / (√3/2·h))) rows of nodes on the
    half circles of radius R − c + j·c/L (j = 1 ... L), ending on the axis: row j has ceil(π r_j / h)
    equal arcs, shifted by half of one for odd j below L (staggered against the row inside it), row L is
    `half_disc`'s arc (n_arc facets on each quarter, (R, R) a node). The coating's triangles are scipy's
    Delaunay triangles of the interface nodes and the rows (those between interface nodes only are the
    core's polygon and dropped); the interface chords are Delaunay edges, so no triangle crosses the
    interface."""
    R = 1.0
    inner = R - c
    h_core = min(h, inner)
    n_core = int(np.ceil(0.5 * np.pi * inner / h_core))
    n_core_axis = int(np.ceil(2.0 * inner / h_core))
    core_p, core_t = unit_half_disc(h_core / inner, n_core, n_core_axis)
    core_p = inner * core_p + np.array([[0.0], [c]])
    interface = np.arange(2 * n_core + 1)  # the core's arc nodes, from (0, c) to (0, 2R − c)

    L = max(1, round(c / (0.5 * np.sqrt(3.0) * h)))
    rows = []
    for j in range(1, L + 1):
        r = R if j == L else inner + j * c / L
        arcs = 2 * n_arc if j == L else int(np.ceil(np.pi * r / h))
        angle = np.linspace(-0.5 * np.pi, 0.5 * np.pi, arcs + 1)
        if j % 2 and j < L:  # staggered: the middles of the arcs, and the two ends on the axis
            angle = np.concatenate((angle[:1], 0.5 * (angle[1:] + angle[:-1]), angle[-1:]))
        row = np.vstack((r * np.cos(angle), R + r * np.sin(angle)))
        row[0, [0, -1]] = 0.0
        if j == L:
            row[:, n_arc] = (R, R)
        rows.append(row)
    p = np.hstack([core_p] + rows)
    nodes = np.concatenate((interface, np.arange(core_p.shape[1], p.shape[1])))
    t = nodes[Delaunay(p[:, nodes].T).simplices.T]
    t = t[:, ~(t < interface.size).all(axis=0)]
    flip = determinants(p, t) < 0
    t[1:, flip] = t[2:0:-1, flip]
    regions = {"core": np.arange(core_t.shape[1], dtype=np.int64),
               "coating": np.arange(core_t.shape[1], core_t.shape[1] + t.shape[1], dtype=np.int64)}
    return p, np.hstack((core_t, t)), regions, n_core_axis + 2 * L


def smooth(p: np.ndarray, t: np.ndarray, movable: np.ndarray, sweeps: int) -> np.ndarray:
    """Laplacian smoothing: each sweep moves the `movable` nodes to the mean of their
    neighbours; a sweep that would make a triangle's signed area drop below a tenth of
    its previous value (or invert it) is discarded and smoothing stops (the areas as twice their values, the
    determinants of `vpcontact.mesh.simplex`)."""
    n = p.shape[1]
    i = np.concatenate((t[0], t[1], t[2]))
    j = np.concatenate((t[1], t[2], t[0]))
    adjacency = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(n, n)).tocsr()
    adjacency = ((adjacency + adjacency.T) > 0).astype(float)
    averaging = sp.diags(1.0 / np.asarray(adjacency.sum(axis=1)).ravel()) @ adjacency
    area = determinants(p, t)
    for _ in range(sweeps):
        q = p.copy()
        q[:, movable] = (averaging @ p.T).T[:, movable]
        new_area = determinants(q, t)
        if np.any(new_area < 0.1 * area):
            break
        p, area = q, new_area
    return p
