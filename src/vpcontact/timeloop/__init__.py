"""The quasistatic time loop (Sect. 3 of the paper): history ξ and z, step cuts, a body at rest."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.timeloop.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
