"""The P1 displacement space of a mesh: its dofs, numbered as scikit-fem numbers them, without scikit-fem's basis.

The bulk operators are the NumPy kernels of :mod:`.kernels`, which need of the space only its dofs: the dof of
component c at node i is ``nodal_dofs[c, i]`` = d·i + c (scikit-fem's numbering of ``ElementVector`` of P1). A
scikit-fem ``CellBasis`` would also hold the values and gradients of its d(d + 1) shape functions at the
quadrature points of every element, 1,152 bytes a tetrahedron: 4.5 GB and 10 s for the 3.9M tetrahedra of a
2M-dof mesh, none of it used. To use scikit-fem's forms on the space, make its basis:
``skfem.Basis(space.mesh, space.elem)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import skfem
from skfem import ElementTetP1, ElementTriP1, ElementVector, MeshTet1


@dataclass(frozen=True, eq=False)
class DisplacementSpace:
    """The P1 vector space on scikit-fem's ``mesh`` (MeshTri1 or MeshTet1): ``elem`` its vector element (the
    scalar one is ``elem.elem``), ``nodal_dofs`` (d, nodes) the dof of each component at each node."""

    mesh: skfem.Mesh
    elem: ElementVector
    nodal_dofs: np.ndarray

    @classmethod
    def of(cls, mesh: skfem.Mesh) -> "DisplacementSpace":
        """The space of P1 displacements on ``mesh``, numbered as scikit-fem's basis of ``ElementVector``."""
        d, nodes = mesh.p.shape
        element = ElementTetP1() if isinstance(mesh, MeshTet1) else ElementTriP1()
        return cls(mesh, ElementVector(element), np.arange(d * nodes, dtype=np.int32).reshape((d, nodes), order="F"))

    @property
    def N(self) -> int:
        """The number of dofs, d · nodes."""
        return self.nodal_dofs.size

    @property
    def nelems(self) -> int:
        """The number of elements."""
        return self.mesh.t.shape[1]
