"""The finite elements: the P1 displacement space, assembly of the stiffness and the loads, rigid motions, the contact
nodes of Γ3 (their normals, weights and gaps)."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.fem.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
