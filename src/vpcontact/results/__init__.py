"""Results as plain data: the history, the fields, tables, plots, norms."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.results.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
