"""The fields of a time level (:class:`~vpcontact.results.result.Fields`) from what the time loop computed there:
the displacement at every dof, and ε, σ and z on the elements of this rank, made whole on every rank."""

from __future__ import annotations

import numpy as np

from ..laws.elasticity import von_mises
from ..parallel.elements import ElementShare
from ..results.result import Fields


def level_fields(problem, share: ElementShare, u: np.ndarray, strain: np.ndarray, sigma: np.ndarray,
                 z: np.ndarray | None) -> Fields:
    """The Fields of a level of ``problem`` from u at every dof and ε, σ, z (elements last; None: z ≡ 0) on the
    elements of ``share``: the nodal displacements, σ with σ33 of a 2D body, its von Mises stress and z, over all
    the elements (a collective call on several ranks)."""
    strain, sigma, z = share.whole(strain), share.whole(sigma), share.whole(z)
    sigma33 = problem.elasticity.out_of_plane_stress(strain)
    return Fields(displacement=u[problem.basis.nodal_dofs].T.copy(), stress=np.moveaxis(sigma, -1, 0),
                  stress33=sigma33, von_mises=von_mises(sigma, sigma33),
                  z=None if z is None else np.moveaxis(z, -1, 0).copy())
