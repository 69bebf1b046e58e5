"""The recovery (stress-averaging) error estimator: an a posteriori estimate that reads only σ_h.

The discrete stress σ_h is constant on each element. Its recovered stress σ* is the continuous P1 field
whose value at a node is the volume-weighted mean of σ_h over the elements around the node::

    σ*(x_i) = Σ_{K ∋ x_i} |K| σ_K / Σ_{K ∋ x_i} |K|,

taken over the elements of one material at a time: σ* is continuous inside each material and may jump
across an interface between two materials (where the tangential components of the exact stress jump
too: averaging across it would report that jump as an error). The element indicator is the energy norm
of the difference on K::

    η_K² = ∫_K (σ* − σ_h) : ℰ_K⁻¹ (σ* − σ_h) dx,   τ : ℰ⁻¹τ = (τ : τ − λ/(dλ + 2μ) (tr τ)²) / (2μ),

with the element's Lamé parameters (the in-plane λ* under plane stress) and d the dimension of the
tensors (2 in 2D). σ* − σ_h is linear on K, so the integral is exact with the P1 mass formula
∫_K φ ψ = :math:`|K|` (Σ_i φ_i ψ_i + Σ_i φ_i Σ_i ψ_i) / ((d + 1)(d + 2)) for linear φ, ψ of vertex values φ_i,
ψ_i. It is the Zienkiewicz–Zhu estimator in the energy norm; it is zero where σ_h is the same on all
elements around each node of K and of the same order as the error ‖σ − σ_h‖ where the stress is smooth.
"""

from __future__ import annotations

import numpy as np

from .estimators import Estimator
from .indicators import Indicators, Level
from ..mesh.simplex import barycentric_gradients


def recovered_stress(points: np.ndarray, cells: np.ndarray, stress: np.ndarray,
                     groups: np.ndarray | None = None) -> np.ndarray:
    """σ* at the vertices of each element (d + 1, elements, d, d): for vertex i of element K the
    volume-weighted mean of ``stress`` (elements, d, d) over the elements around that node that are in
    K's group (``groups`` (elements,), e.g. the material of each element; None: one group)."""
    cells = np.asarray(cells, dtype=np.int64)
    _, volumes = barycentric_gradients(points, cells)
    group = np.zeros(cells.shape[1], dtype=np.int64) if groups is None else np.asarray(groups, dtype=np.int64)
    keys = cells * (group.max(initial=0) + 1) + group  # (d + 1, elements): one key per (node, group)
    _, slot = np.unique(keys, return_inverse=True)
    slot = slot.reshape(cells.shape)
    weights = np.broadcast_to(volumes, cells.shape).ravel()
    total = np.bincount(slot.ravel(), weights=weights)
    flat = stress.reshape(stress.shape[0], -1)  # (elements, d²)
    sums = np.stack([np.bincount(slot.ravel(), weights=weights * np.broadcast_to(flat[:, c], cells.shape).ravel(),
                                 minlength=total.size) for c in range(flat.shape[1])], axis=1)
    means = sums / total[:, None]
    return means[slot].reshape(cells.shape + stress.shape[1:])


def energy_indicators(points: np.ndarray, cells: np.ndarray, difference: np.ndarray, lam, mu) -> np.ndarray:
    """∫_K τ : ℰ_K⁻¹ τ for each element K of the P1 tensor field τ of vertex values ``difference``
    (d + 1, elements, d, d) (exact), with ℰ_K of the Lamé parameters ``lam``, ``mu`` (numbers or arrays over
    the elements)."""
    _, volumes = barycentric_gradients(points, cells)
    vertices, d = difference.shape[0], difference.shape[-1]
    scale = volumes / (vertices * (vertices + 1))
    total = difference.sum(axis=0)  # (elements, d, d)
    frobenius = scale * (np.einsum("vkij,vkij->k", difference, difference) + np.einsum("kij,kij->k", total, total))
    trace = np.einsum("vkii->vk", difference)
    trace_squared = scale * ((trace * trace).sum(axis=0) + trace.sum(axis=0) ** 2)
    lam, mu = np.asarray(lam, dtype=float), np.asarray(mu, dtype=float)
    return (frobenius - lam / (d * lam + 2.0 * mu) * trace_squared) / (2.0 * mu)


def estimate(level: Level) -> Indicators:
    """The recovery estimator at a time level: η_K² = ‖σ* − σ_h‖²_{ℰ⁻¹, K} (one term, "recovery")."""
    problem = level.problem
    mesh = problem.mesh.mesh
    cells = np.asarray(mesh.t, dtype=np.int64)
    stress = np.asarray(level.fields.stress, dtype=float)
    difference = recovered_stress(mesh.p, cells, stress, problem.materials.owner) - stress[None]
    lam, mu = problem.elasticity.lame
    return Indicators({"recovery": energy_indicators(mesh.p, cells, difference, lam, mu)})


ESTIMATOR = Estimator(
    name="recovery",
    summary="The recovery (Zienkiewicz–Zhu) estimator: the energy norm of σ* − σ_h, σ* the averaged stress.",
    terms=("recovery",),
    prepare=lambda problem: estimate,
)
