"""The case: its schema (the keys of a case file), expressions, input files, and its translation into a problem."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.case.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
