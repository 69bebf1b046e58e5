"""Files: the run directory held while it is written, VTU/PVD, XDMF, CSV/JSON, npz, checkpoints."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.io.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
