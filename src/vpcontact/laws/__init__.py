"""The laws of the model: elasticity ℰ, the viscoplastic 𝒢, the materials by region, the contact laws K(ξ) and p(r)."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.laws.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
