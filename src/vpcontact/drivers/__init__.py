"""What a user runs: run directories (with checkpoints and resume), parameter studies, the pre-run check;
the command line that calls them is :mod:`vpcontact.cli`."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.drivers.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
