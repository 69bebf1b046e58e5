"""The viscoplastic laws 𝒢(σ, ε) of the constitutive law (2.1), by their names in ``material.viscoplastic.law``.

Each law is a module of this package, named after it, whose ``LAW`` (:class:`~vpcontact.laws.spec.Law`)
makes the law's object with ``make(hypothesis=..., **parameters)`` (numbers, one material's; ``hypothesis``
its 2D hypothesis, "plane_strain", "plane_stress" or None in 3D): a callable on arrays of shape (d, d, ...)
(one tensor of S^d per element), returning an array of the same shape, Lipschitz in (σ, ε) as (2.17)(b)
asks, with the constant ``lipschitz``. The norm of S^d is the paper's ‖τ‖ = (τ_ij τ_ij)^{1/2}; the deviator
is the one of S^d: dev τ = τ − (tr τ / d) I (in 2D tr τ = τ_11 + τ_22: σ33 is not part of the model's
stress). A new law is one module here and its name in VISCOPLASTIC.
"""

from ...registry import Registry

#: The laws of material.viscoplastic.law, in the order messages list them.
VISCOPLASTIC = Registry(__name__, ("perzyna", "relaxation"), "LAW")
