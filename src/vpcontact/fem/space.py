"""The coordinates of a body in d = 2 or 3 dimensions, by name: the one place that spells them.

The dimension itself comes from the mesh (``Mesh.dim``); vectors of a case (loads, probe, normal)
and their output columns (``contact_force_x``, …) have one entry per coordinate of that dimension.
"""

from __future__ import annotations

COORDINATES = ("x", "y", "z")


def coordinates(dim: int) -> tuple[str, ...]:
    """The coordinate names of a d-dimensional body: ("x", "y") or ("x", "y", "z")."""
    return COORDINATES[:dim]


def component(name: str) -> int:
    """The index of a coordinate by name: "x" → 0, "y" → 1, "z" → 2."""
    return COORDINATES.index(name)

