"""Expressions of a case file: formulas in the coordinates and the time, checked and evaluated with NumPy."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.expressions.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
