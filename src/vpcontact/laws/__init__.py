"""The laws of the model: elasticity ℰ (``elasticity``), the viscoplastic 𝒢 (``viscoplastic``), the materials by
region (``materials``), the layer's stiffness K(ξ) (``stiffness``) and compliance p(r) (``compliance``) and the
contact law they make (``contact``). The laws a case names are plug-ins: one module each, declared by a
:class:`~vpcontact.laws.spec.Law` and found by name in its family's registry."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.laws.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
