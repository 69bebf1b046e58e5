"""The case: its schema (the keys of a case file), its loading and overrides, and its translation into plain options."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.case.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
