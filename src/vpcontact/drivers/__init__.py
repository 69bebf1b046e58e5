"""What a user runs: run directories, studies, check, the command line."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.drivers.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
