"""Adaptive meshes, with the settings of a case's ``[adapt]`` (:mod:`.options`): cycles of whole runs, each on the
mesh refined where the estimator of the one before marks its elements (:mod:`.cycles`), or one run refined between
its time steps (:mod:`.during_run`: how far to refine after one estimate, :mod:`.marking`; the level carried to
the new mesh, :mod:`.transfer`). Above the time loop, which it drives; the estimators themselves are in
:mod:`vpcontact.estimate`."""

from .. import submodule


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.adaptivity.<module>`` after ``import vpcontact``)."""
    return submodule(__name__, name)
