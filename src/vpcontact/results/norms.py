"""L² norms of discrete solutions and their differences against a reference solution.

A `Snapshot` is a discrete solution at one time: P1 displacement (nodal values) and P0 stress
(one symmetric tensor per element) on a simplex mesh (triangles in 2D, tetrahedra in 3D).
`differences` compares a solution with a reference on the reference's mesh (the paper's
convergence study)::

    V = ‖ε(I_ref u_h − u_ref)‖_{L²(Ω_ref)},   Q = ‖Π_ref σ_h − σ_ref‖_{L²(Ω_ref)},
    U = ‖I_ref u_h − u_ref‖_{L²(Ω_ref)},

where I_ref interpolates u_h at the reference nodes and Π_ref evaluates σ_h at the reference
element centroids (`transfer`). The norms are exact for these fields: ε(v) of a P1 field and a
P0 stress are constant on each element, so ‖·‖² is Σ_T :math:`|T|` · (the tensor's Frobenius norm)²; a
P1 field's square is integrated exactly by its element mass matrix.

`transfer` locates the target points in the source elements with `vpcontact.mesh.locate.Locator`: a point in
no source element (a finer mesh's nodes near a curved boundary lie outside a coarser mesh's inscribed
polygon or polyhedron) takes the nearest source element, and the P1 field is extrapolated linearly from it
(its barycentric coordinates, some negative).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh.locate import Locator
from ..mesh.simplex import affine_inverse, measures


@dataclass(frozen=True, eq=False)
class Snapshot:
    """A discrete solution at one time: its mesh, nodal displacement (nnodes, d), element stress
    (nelements, d, d)."""

    points: np.ndarray
    """Node coordinates (d, nnodes)."""
    elements: np.ndarray
    """Node indices of the elements (d + 1, nelements), any orientation."""
    displacement: np.ndarray
    """P1 displacement, its values at the nodes (nnodes, d)."""
    stress: np.ndarray
    """P0 stress, one symmetric tensor per element (nelements, d, d)."""
    lame: np.ndarray | None = None
    """The Lamé parameters (λ, μ) of each element (2, nelements), for the energy norm; None: not known."""

    def __post_init__(self):
        d = np.shape(self.points)[0] if np.ndim(self.points) == 2 else 0
        nnodes, nelements = np.shape(self.points)[-1], np.shape(self.elements)[-1]
        expected = {"points": (d, nnodes), "elements": (d + 1, nelements), "displacement": (nnodes, d),
                    "stress": (nelements, d, d)}
        if d not in (2, 3):
            raise ValueError(f"Snapshot.points has shape {np.shape(self.points)}, expected (d, nnodes) with d = 2 or 3")
        for name, shape in expected.items():
            if np.shape(getattr(self, name)) != shape:
                raise ValueError(f"Snapshot.{name} has shape {np.shape(getattr(self, name))}, expected {shape}")


def transfer(source: Snapshot, target_points, target_elements) -> Snapshot:
    """The source solution on the target mesh: the P1 displacement interpolated at the target nodes
    (its value at each node = the source's P1 field evaluated there), the P0 stress evaluated at the
    target element centroids.

    A target node or centroid in no source element (a finer mesh's boundary nodes lie outside a
    coarser mesh's polygon inscribed in a curved boundary) takes the source element nearest to it
    (Euclidean distance): the displacement is that element's linear function extrapolated to the
    point, the stress that element's value. A point on the boundary between source elements
    (within 1e-12 in barycentric coordinates) takes the element where it lies deepest.
    """
    target_points = np.asarray(target_points, dtype=float)
    target_elements = np.asarray(target_elements, dtype=np.int64)
    locator = Locator(source.points, source.elements)
    element, weights = locator.locate(target_points.T)
    nodal = np.asarray(source.displacement, dtype=float)[locator.elements[:, element]]  # (d + 1, q, d)
    displacement = np.einsum("qv,vqd->qd", weights, nodal)
    centroid_element, _ = locator.locate(target_points[:, target_elements].mean(axis=1).T)
    stress = np.asarray(source.stress, dtype=float)[centroid_element]
    return Snapshot(target_points, target_elements, displacement, stress)


def strain_norm(points, elements, displacement) -> float:
    """‖ε(u)‖_{L²(Ω_h)} = (Σ_T :math:`|T|` ε(u)|_T : ε(u)|_T)^½ for the P1 displacement u with nodal values
    `displacement` (nnodes, d) on the mesh (points (d, nnodes), elements (d + 1, nelements)); exact,
    ε(u) = sym ∇u being constant on each element."""
    (strain,), measure = _strains(points, elements, displacement)
    return float(np.sqrt(_squares(measure, strain)))


def _strains(points, elements, *displacements) -> tuple[list[np.ndarray], np.ndarray]:
    """ε(u) (m, d, d) on each element of the P1 displacement with nodal values (nnodes, d) of each of
    ``displacements`` (the mesh's maps computed once for all), and the elements' measures (m,)."""
    points = np.asarray(points, dtype=float)
    elements = np.asarray(elements, dtype=np.int64)
    d = points.shape[0]
    inverse = affine_inverse(points, elements)[0].transpose(2, 0, 1)  # (m, d, d)
    strains = []
    for displacement in displacements:
        u = np.asarray(displacement, dtype=float)[elements]  # (d + 1, m, d)
        gradient = sum((u[k + 1] - u[0])[:, :, None] * inverse[:, k, None, :] for k in range(d))  # ∂u_i/∂x_j
        strains.append(0.5 * (gradient + gradient.transpose(0, 2, 1)))
    return strains, measures(points, elements)


def _energies(strain: np.ndarray, measure: np.ndarray, lame) -> np.ndarray:
    """|T| (λ (tr ε)² + 2μ ε:ε) on each element of the strains ``strain`` (m, d, d)."""
    lam, mu = (np.asarray(value, dtype=float) for value in lame)
    trace = np.einsum("mii->m", strain)
    return measure * (lam * trace**2 + 2.0 * mu * (strain**2).sum(axis=(1, 2)))


def _squares(measure: np.ndarray, field: np.ndarray) -> float:
    """Σ_T |T| f_T : f_T of a field constant on each element (m, …)."""
    return float(np.sum(measure * (field**2).reshape(len(measure), -1).sum(axis=1)))


def element_energies(points, elements, displacement, lame) -> np.ndarray:
    """∫_T ℰε(u):ε(u) = :math:`|T|` (λ (tr ε)² + 2μ ε:ε) on each element T (m,) for the P1 displacement with nodal
    values ``displacement`` (nnodes, d); ``lame`` = (λ, μ), numbers or arrays over the elements (the
    isotropic ℰ of :class:`~vpcontact.laws.elasticity.Elasticity`; in 2D its plane hypothesis's λ)."""
    (strain,), measure = _strains(points, elements, displacement)
    return _energies(strain, measure, lame)


def energy_norm(points, elements, displacement, lame) -> float:
    """‖u‖_E = (∫_Ω ℰε(u):ε(u))^½ for the P1 displacement u (``element_energies``); exact."""
    return float(np.sqrt(element_energies(points, elements, displacement, lame).sum()))


def stress_norm(points, elements, stress) -> float:
    """‖σ‖_{L²(Ω_h)} = (Σ_T :math:`|T|` σ_T : σ_T)^½ for the P0 stress `stress` (nelements, d, d) on the mesh
    (points (d, nnodes), elements (d + 1, nelements)); σ : σ = σ_ij σ_ij."""
    measure = measures(np.asarray(points, dtype=float), np.asarray(elements, dtype=np.int64))
    return float(np.sqrt(_squares(measure, np.asarray(stress, dtype=float))))


def displacement_norm(points, elements, displacement) -> float:
    """‖u‖_{L²(Ω_h)} for the P1 displacement u with nodal values `displacement` (nnodes, d) on the mesh
    (points (d, nnodes), elements (d + 1, nelements)); exact (``_mean_squares``)."""
    points = np.asarray(points, dtype=float)
    elements = np.asarray(elements, dtype=np.int64)
    return float(np.sqrt(np.sum(measures(points, elements) * _mean_squares(elements, displacement))))


def _mean_squares(elements: np.ndarray, displacement) -> np.ndarray:
    """(1/|T|) ∫_T |u|² on each element of the P1 displacement with nodal values (nnodes, d): on a
    simplex T with vertex values u_0, …, u_d, ∫_T λ_i λ_j = |T| (1 + δ_ij) / ((d + 1)(d + 2)), so
    ∫_T |u|² = |T| (Σ_i |u_i|² + |Σ_i u_i|²) / ((d + 1)(d + 2))."""
    d = elements.shape[0] - 1
    u = np.asarray(displacement, dtype=float)[elements]  # (d + 1, m, d)
    return ((u**2).sum(axis=(0, 2)) + (u.sum(axis=0) ** 2).sum(axis=1)) / ((d + 1) * (d + 2))


#: The difference norms of :func:`differences` a parameter study compares at each compared time (study.csv).
COMPARED = ("V", "Q", "U", "energy")


def norm_column(norm: str, t: float) -> str:
    """The column of study.csv with the difference norm ``norm`` (one of COMPARED) at time t."""
    return f"norm_{norm}_t{t:g}"


def differences(solution: Snapshot, reference: Snapshot) -> dict[str, float]:
    """{"V": ‖ε(u − u_ref)‖_{L²}, "Q": ‖σ − σ_ref‖_{L²}, "U": ‖u − u_ref‖_{L²}, "V_reference": ‖ε(u_ref)‖,
    "Q_reference": ‖σ_ref‖, "U_reference": ‖u_ref‖} computed on the reference mesh after transferring
    `solution` to it (`transfer`); no transfer when the meshes are identical (equal points and
    elements arrays). When the reference knows its Lamé parameters also "energy": ‖u − u_ref‖_E =
    (∫ ℰε(u − u_ref):ε(u − u_ref))^½ with the reference's ℰ, and "energy_reference": ‖u_ref‖_E. The
    reference mesh's affine maps are computed once for all of them."""
    same_mesh = (np.array_equal(solution.points, reference.points)
                 and np.array_equal(solution.elements, reference.elements))
    if not same_mesh:
        solution = transfer(solution, reference.points, reference.elements)
    p, t = np.asarray(reference.points, dtype=float), np.asarray(reference.elements, dtype=np.int64)
    u_ref = np.asarray(reference.displacement, dtype=float)
    error = np.asarray(solution.displacement, dtype=float) - u_ref
    (strain_error, strain_ref), measure = _strains(p, t, error, u_ref)
    stress_ref = np.asarray(reference.stress, dtype=float)
    energy = {}
    if reference.lame is not None:
        energy = {"energy": float(np.sqrt(_energies(strain_error, measure, reference.lame).sum())),
                  "energy_reference": float(np.sqrt(_energies(strain_ref, measure, reference.lame).sum()))}
    return {
        **energy,
        "V": float(np.sqrt(_squares(measure, strain_error))),
        "Q": float(np.sqrt(_squares(measure, np.asarray(solution.stress, dtype=float) - stress_ref))),
        "U": float(np.sqrt(np.sum(measure * _mean_squares(t, error)))),
        "V_reference": float(np.sqrt(_squares(measure, strain_ref))),
        "Q_reference": float(np.sqrt(_squares(measure, stress_ref))),
        "U_reference": float(np.sqrt(np.sum(measure * _mean_squares(t, u_ref)))),
    }
