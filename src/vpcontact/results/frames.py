"""The fields of a run as the data of a 3D unstructured grid, the one data model of the field files
(VTU, XDMF) and of ``result.to_pyvista()``: the body's points and cells (triangles or tetrahedra) and
the contact part's (segments or triangles of Γ3), 2D points with z = 0; per field step the body's point
data (the displacement) and cell data (stress, von Mises, material, E, ν, and z and η_K when the run
has them), and the contact part's point data (the contact arrays, pressure, normal, contact force,
displacement and the local layer parameters). 2D vectors are padded to 3D and tensors to 3 × 3 (σ33 of
the plane reduction in the stress)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from ..mesh.cells import SIMPLICES
from .columns import CONTACT_ARRAYS

def in_space(vectors: np.ndarray) -> np.ndarray:
    """Vectors (n, d) as the 3D vectors (n, 3) of a field file (z = 0 in 2D)."""
    return np.column_stack([vectors, np.zeros((vectors.shape[0], 3 - vectors.shape[1]))])


def tensors_in_space(tensors: np.ndarray, t33: np.ndarray | None = None) -> np.ndarray:
    """Tensors (n, d, d) as the 3 × 3 tensors (n, 9) of a field file, row by row; in 2D the out-of-plane entry is
    ``t33`` (σ33 of the plane reduction), or 0."""
    n, d = tensors.shape[:2]
    full = np.zeros((n, 3, 3))
    full[:, :d, :d] = tensors
    if t33 is not None:
        full[:, 2, 2] = t33
    return full.reshape(n, 9)


def layer_columns(discretization) -> dict[str, np.ndarray]:
    """The local layer parameters per contact node, as the last columns of contact.csv and point data of
    the contact VTU: g, those of K (c_v, alpha, beta or value) and the exponent of p = power where the
    laws have them (empty, or NaN in a VTU, at the nodes of a part whose law has not that parameter), and
    with several contact parts each node's part (its name in contact.csv, its index in contact.parts in
    a VTU: ``part`` there): ``discretization.layer`` (:class:`~vpcontact.problem.discretization.Discretization`)."""
    return dict(discretization.layer)


@dataclass(frozen=True)
class FieldFrame:
    """The data of the field files at one field step n (t = t_n): the body's point and cell data, and the
    contact part's point data (None without contact); 2D vectors and tensors as the 3D ones of a file."""

    step: int
    t: float
    body_points: dict[str, np.ndarray]
    body_cells: dict[str, np.ndarray]
    contact_points: dict[str, np.ndarray] | None


def field_meshes(discretization) -> tuple[tuple[np.ndarray, str, np.ndarray],
                                          tuple[np.ndarray, str, np.ndarray] | None]:
    """(points (n, 3), cell type, cells (k, nodes per cell)) of the body and of the contact part (None
    without contact): the meshes of the field files, 2D points with z = 0."""
    dim = discretization.mesh.dim
    element_cells, facet_cells = SIMPLICES[dim].cell_type, SIMPLICES[dim - 1].cell_type
    body = (in_space(discretization.mesh.mesh.p.T), element_cells, discretization.mesh.mesh.t.T)
    surface = discretization.surface
    return body, (in_space(surface.coordinates.T), facet_cells, surface.facets.T) if surface.size else None


def body_data(discretization, fields) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The point data and the cell data of the body's field files for ``fields`` (the Fields of one step) on
    ``discretization``: point data the displacement (n, 3); cell data the stress (3 × 3 as 9 components row by
    row, σ33 of the plane reduction in 2D), the von Mises stress, each element's material (an integer, its
    index in the case's material list), E and ν, and the history z (9 components) and the error indicator
    η_K when the run has them."""
    cell_data = {"stress": tensors_in_space(fields.stress, fields.stress33), "von_mises": fields.von_mises,
                 "material": discretization.material.astype(np.int32), "E": np.array(discretization.materials.E),
                 "nu": np.array(discretization.materials.nu)}
    if fields.z is not None:
        cell_data["z"] = tensors_in_space(fields.z)
    if fields.error_indicator is not None:
        cell_data["error_indicator"] = fields.error_indicator
    return {"displacement": in_space(fields.displacement)}, cell_data


def field_frames(result) -> Iterator[FieldFrame]:
    """The field files' data at each field step, in step order: the body's (``body_data``); on the contact
    part the CONTACT_ARRAYS (``status`` an integer, the index in STATUS_NAMES), the pressure (compliance +
    rigid), the normal, the contact force, the displacement and the local layer parameters
    (``layer_columns``; ``part`` an integer)."""
    view = result.discretization
    surface = view.surface
    if surface.size:
        normal = in_space(surface.normals.T)
        layer = layer_columns(view)
        if "part" in layer:  # point data are numbers: the index in contact.parts
            layer["part"] = surface.owner
        layer = {key: np.asarray(value, dtype=np.int32 if key == "part" else float) for key, value in layer.items()}
        end_rows = result.end_of_step_rows()
    for step, fields in sorted(result.fields.items()):
        point_data, cell_data = body_data(view, fields)
        contact = None
        if surface.size:
            data = {key: np.asarray(result.contact[key][end_rows[step]], dtype=np.int32 if key == "status" else float)
                    for key in CONTACT_ARRAYS}
            pressure = data["pressure_compliance"] + data["pressure_rigid"]
            contact = {**data, "pressure": pressure, "normal": normal,
                       "contact_force": -normal * (surface.weights * pressure)[:, None],
                       "displacement": point_data["displacement"][surface.nodes], **layer}
        yield FieldFrame(step, float(view.times[step - 1]), point_data, cell_data, contact)
