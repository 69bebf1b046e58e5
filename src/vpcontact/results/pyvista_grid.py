"""``result.to_pyvista()``: the body of a run at a field step as a ``pyvista.UnstructuredGrid``, to render
it in 3D (``grid.warp_by_vector("displacement").plot(scalars="von_mises")``) or hand it to VTK.

pyvista is optional (``pip install pyvista``, or the extra ``vpcontact[pyvista]``) and imported only here.
The grid holds the data of the body's VTU file of that step (:func:`vpcontact.results.frames.body_data`):
the same points and cells, the same arrays; 2D bodies lie in the plane z = 0 with their vectors padded to
3D and their tensors to 3 × 3 (σ33 of the plane reduction in the stress).
"""

from __future__ import annotations

from ..errors import CaseError
from .frames import body_data, field_meshes
from .steps import fields_at


def body_grid(result, step=None):
    """The body at the field ``step`` (default: the last one kept) as a ``pyvista.UnstructuredGrid`` of its
    triangles or tetrahedra, the points undeformed: point data ``displacement`` (n, 3); cell data
    ``stress`` (elements, 9), the 3 × 3 tensor row by row, ``von_mises``, ``material`` (each element's
    index in the case's material list), ``E``, ``nu`` and, when the run has them, ``z`` (elements, 9),
    the viscoplastic history of (2.28), and ``error_indicator`` η_K; field data ``step`` and ``t``.
    CaseError without pyvista, or without fields at ``step``."""
    try:
        import pyvista
    except ImportError:
        raise CaseError("to_pyvista needs pyvista, which is not installed: pip install pyvista") from None
    step, fields = fields_at(result, step, "no body to convert to pyvista")
    (points, cell_type, cells), _ = field_meshes(result.discretization)
    types = {"triangle": pyvista.CellType.TRIANGLE, "tetra": pyvista.CellType.TETRA}
    grid = pyvista.UnstructuredGrid({types[cell_type]: cells}, points)
    point_data, cell_data = body_data(result.discretization, fields)
    grid.point_data.update(point_data)
    grid.cell_data.update(cell_data)
    grid.field_data["step"] = [step]
    grid.field_data["t"] = [float(result.discretization.times[step - 1])]
    return grid
