"""Meshes: the body's shapes, mesh files, checks, refinement, simplex geometry.

The public face: a :class:`Mesh` (scikit-fem's mesh with named parts and regions), the built-in shapes and the
reader of mesh files::

    from vpcontact import mesh
    body = mesh.half_disc(h=0.05)            # or rectangle, quarter_ball, block, read_mesh("part.msh")
"""

from .. import submodule
from .core import Mesh, block, half_disc, quarter_ball, read_mesh, rectangle

__all__ = ["Mesh", "block", "half_disc", "quarter_ball", "read_mesh", "rectangle"]


def __getattr__(name: str):
    """The submodules, imported on first use (``vpcontact.mesh.<module>`` after ``import vpcontact.mesh``)."""
    return submodule(__name__, name)
