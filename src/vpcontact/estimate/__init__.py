"""Error estimation: the estimators as plug-ins (:mod:`.estimators`), their element indicators at a time level
(:mod:`.indicators`), the residual and recovery estimators. The adaptive cycles they drive are in
:mod:`vpcontact.adaptivity`."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.estimate.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
