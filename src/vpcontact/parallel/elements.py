"""The elements whose viscoplastic memory a rank holds: on N ranks, each element belongs to the rank that owns its
first node (:mod:`.partition`), and its strain, stress, z and 𝒢 are computed and kept there alone.

The time loop's element work goes through an :class:`ElementShare`: ε(u) and σ = ℰε(u) + z on the rank's elements,
𝒢(σ, ε) of its materials there, and the history's force Bᵀz: each rank's elements' part, summed over the ranks
into the whole vector every rank's step takes (one reduction of n numbers a step, as the gathered solution).
The whole arrays over all the elements are made only where a level's fields are kept or estimated and in a
checkpoint (:meth:`ElementShare.whole`), and a checkpoint's arrays, which are whole, are taken back by each rank at
its elements (:meth:`ElementShare.mine`): a run resumes on any number of ranks. In one process the share is all the
elements, in the mesh's order, and every operation is the whole one, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..fem.kernels import SimplexGeometry, geometry, strains, stress_work
from .partition import NodePartition
from .ranks import ALONE, Ranks


@dataclass(frozen=True)
class ElementShare:
    """The elements ``elements`` (sorted indices; None: all of them) of this rank among ``total``, their
    ``geometry``, and the body's ℰ (``elasticity``) and 𝒢 (``viscoplastic``, None: 𝒢 = 0) on them."""

    ranks: Ranks
    elements: np.ndarray | None
    total: int
    geometry: SimplexGeometry
    elasticity: object
    viscoplastic: object | None

    @classmethod
    def of(cls, problem, partition: NodePartition | None) -> "ElementShare":
        """The elements of this rank among those of ``problem``'s mesh shared by ``partition`` (None: one process,
        all of them)."""
        whole = geometry(problem.basis)
        elasticity, viscoplastic = problem.elasticity, problem.viscoplastic
        if partition is None:
            return cls(ALONE, None, whole.volumes.size, whole, elasticity, viscoplastic)
        ranks = partition.ranks
        elements = np.flatnonzero(partition.owner[whole.cells[0]] == ranks.rank)
        if viscoplastic is not None and hasattr(viscoplastic, "on"):  # a law with values per element
            viscoplastic = viscoplastic.on(elements)
        return cls(ranks, elements, whole.volumes.size, whole.of(elements), elasticity.on(elements), viscoplastic)

    @property
    def count(self) -> int:
        """The number of this rank's elements."""
        return self.geometry.volumes.size

    def strain(self, u: np.ndarray) -> np.ndarray:
        """ε(u) on the rank's elements (d, d, elements) of the displacement u at every dof."""
        return strains(self.geometry, u)

    def stress(self, strain: np.ndarray, z: np.ndarray | None) -> np.ndarray:
        """σ = ℰε + z on the rank's elements (the discrete (2.28))."""
        sigma = self.elasticity.stress(strain)
        return sigma if z is None else sigma + z

    def force(self, z: np.ndarray) -> np.ndarray:
        """Bᵀz = ∫_Ω z : ε(v) dx at every dof, of z on the rank's elements, summed over the ranks (on every one)."""
        return self.ranks.sum(stress_work(self.geometry, z))

    def all_finite(self, *arrays: np.ndarray | None) -> bool:
        """Whether the arrays (None: none) are finite on the elements of every rank."""
        return self.ranks.all(all(array is None or bool(np.all(np.isfinite(array))) for array in arrays))

    def mine(self, array: np.ndarray | None) -> np.ndarray | None:
        """The rank's elements of an array over all the elements (elements last; None: None)."""
        if array is None or self.elements is None:
            return array
        return np.ascontiguousarray(array[..., self.elements])

    def whole(self, array: np.ndarray | None) -> np.ndarray | None:
        """The array over all the elements (elements last, on every rank) of which each rank holds its elements'
        (None: None)."""
        if array is None or self.elements is None:
            return array
        rows = np.moveaxis(array, -1, 0)
        return np.ascontiguousarray(np.moveaxis(self.ranks.gather(rows, self.elements, self.total), 0, -1))
