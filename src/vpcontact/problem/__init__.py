"""The assembled problem: operators, loads, contact surface, initial state, time grid."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.problem.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
