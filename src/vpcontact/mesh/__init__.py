"""Meshes: the body's shapes, mesh files, checks, refinement, simplex geometry and point location.

The public face: a :class:`Mesh` (scikit-fem's mesh with named parts and regions), the built-in shapes, the
reader of mesh files and the meshes in memory::

    from vpcontact import mesh
    body = mesh.half_disc(h=0.05)            # or rectangle, quarter_ball, block, read_mesh("part.msh")
    body = mesh.from_gmsh()                  # the model open in gmsh; or from_meshio(m), from_skfem(m)
    top = mesh.nodes_where(body, "abs(y) < 1e-9", where="where")   # nodes by a condition; or nearest_node

They and the submodules (``vpcontact.mesh.<module>``) are imported on first use.
"""

import importlib

from .. import submodule

#: The public names, by the module that defines them.
PUBLIC = {"Mesh": "mesh", "block": "shapes", "half_disc": "shapes", "quarter_ball": "shapes", "read_mesh": "read",
          "rectangle": "shapes", "from_gmsh": "gmsh_model", "from_meshio": "memory", "from_skfem": "memory",
          "nearest_node": "node_sets", "nodes_where": "node_sets"}

__all__ = ["Mesh", "block", "from_gmsh", "from_meshio", "from_skfem", "half_disc", "nearest_node", "nodes_where",
           "quarter_ball", "read_mesh", "rectangle"]


def __getattr__(name: str):
    """The public names and the submodules, imported on first use."""
    if name in PUBLIC:
        value = getattr(importlib.import_module(f".{PUBLIC[name]}", __name__), name)
        globals()[name] = value  # once
        return value
    return submodule(__name__, name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(PUBLIC))
