"""Error estimation and adaptivity."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.estimate.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
