"""Refusal of a :class:`~vpcontact.mesh.Mesh` whose arrays cannot be a mesh, when it is made.

A mesh read from a file is checked as the file is read (`vpcontact.mesh.checks_2d`, `vpcontact.mesh.checks_3d`);
a built-in shape is made right. A Mesh made in Python (``Mesh(skfem_mesh, parts, exact_normals)``) can hold
anything, and a wrong array would surface far from its cause (an IndexError in the assembly, a LinAlgError
in the rigid motions). `check_mesh` refuses, with a CaseError naming the attribute and the value:

- a scikit-fem mesh that is not of linear triangles (MeshTri1) or tetrahedra (MeshTet1), or whose nodes
  do not have the dimension of its elements (3D points with triangles);
- elements that name nodes that do not exist, no elements, nodes no element uses (their rows of the
  stiffness would be zero), coordinates that are not finite;
- parts that are not {name: indices of boundary facets}: a name that is not a string, indices that are not
  integers or not facets of the mesh, facets inside the body, a part without facets;
- regions that are not {name: indices of elements} alike;
- exact normals and curved parts of parts the mesh does not have, or that are not functions; curved
  interfaces between regions it does not have.

It returns the parts and regions as sorted int64 arrays of distinct indices (the form the Mesh documents),
so that lists or int32 arrays given in Python work as well. Every check is vectorized: a few ms at 10⁵
elements, against the seconds the assembly takes.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import skfem

from ..errors import CaseError, point, shown
from .cells import SIMPLICES

#: The scikit-fem mesh of each dimension: linear triangles (MeshTri1) and tetrahedra (MeshTet1), what
#: ``Mesh.mesh`` may be.
SKFEM_MESH = {2: skfem.MeshTri, 3: skfem.MeshTet}


def check_mesh(mesh) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """CaseError unless ``mesh`` (a :class:`~vpcontact.mesh.Mesh`) holds a linear triangle or tetrahedral mesh
    with well-formed parts, regions, normals and projections (see the module's docstring); its parts and
    regions as sorted distinct int64 indices."""
    m = mesh.mesh
    if type(m) not in SKFEM_MESH.values():
        raise CaseError(f"Mesh.mesh = {_kind(m)}: expected a scikit-fem MeshTri1 (linear triangles) or MeshTet1 "
                        f"(linear tetrahedra)")
    dim = {cls: d for d, cls in SKFEM_MESH.items()}[type(m)]
    p, t = np.asarray(m.p), np.asarray(m.t)
    if p.ndim != 2 or p.shape[0] != dim:
        raise CaseError(f"Mesh.mesh.p has the shape {p.shape} and the mesh is of {SIMPLICES[dim].plural}: expected "
                        f"{dim} rows (the coordinates {', '.join('xyz'[:dim])} of each node); for "
                        f"{SIMPLICES[5 - dim].plural} use skfem.{SKFEM_MESH[5 - dim].__name__}")
    if t.ndim != 2 or t.shape[0] != dim + 1 or t.shape[1] == 0 or t.dtype.kind not in "iu":
        raise CaseError(f"Mesh.mesh.t is an array of shape {t.shape} of {t.dtype}: expected the nodes of the "
                        f"{SIMPLICES[dim].plural}, integers of shape ({dim + 1}, elements), at least one element")
    nodes = p.shape[1]
    outside = (t < 0) | (t >= nodes)
    if outside.any():
        k = int(np.flatnonzero(outside.any(axis=0))[0])
        raise CaseError(f"Mesh.mesh.t: element {k} refers to node {int(t[outside[:, k], k][0])}, and the mesh has "
                        f"the nodes 0 to {nodes - 1} ({int(outside.any(axis=0).sum())} such elements)")
    bad = np.flatnonzero(~np.isfinite(p).all(axis=0))
    if bad.size:
        raise CaseError(f"Mesh.mesh.p: node {int(bad[0])} has the coordinates {point(p[:, bad[0]])} ({bad.size} such "
                        f"nodes): every coordinate must be a finite number")
    unused = np.flatnonzero(np.bincount(t.ravel(), minlength=nodes) == 0)
    if unused.size:
        raise CaseError(f"Mesh.mesh.p: node {int(unused[0])} at {point(p[:, unused[0]])} is in no element "
                        f"({unused.size} such nodes): remove the nodes no element uses")
    boundary = np.zeros(m.facets.shape[1], dtype=bool)
    boundary[m.boundary_facets()] = True
    parts = index_sets("parts", mesh.parts, boundary.size, "facets")
    for name, facets in parts.items():
        inner = facets[~boundary[facets]]
        if inner.size:
            raise CaseError(f"Mesh.parts[{_name(name)}]: facet {int(inner[0])} is inside the body ({inner.size} such "
                            f"facets): a part is a set of boundary facets (Mesh.mesh.boundary_facets())")
    regions = index_sets("regions", mesh.regions, t.shape[1], "elements")
    _check_functions("exact_normals", mesh.exact_normals, parts, "parts")
    _check_functions("curved_parts", mesh.curved_parts, parts, "parts")
    _check_functions("curved_interfaces", mesh.curved_interfaces, regions, "regions", pairs=True)
    if mesh.file is not None and not isinstance(mesh.file, str):
        raise CaseError(f"Mesh.file = {_kind(mesh.file)}: expected the name of the mesh file (a string) or None")
    return parts, regions


def index_sets(attribute: str, sets, count: int, what: str, owner: str = "Mesh") -> dict[str, np.ndarray]:
    """``sets`` ({name: indices}) as sorted distinct int64 arrays, each non-empty and in [0, count); else
    CaseError naming <owner>.<attribute>[name] (Mesh.parts, or a scikit-fem mesh's boundaries)."""
    if not isinstance(sets, Mapping):
        raise CaseError(f"{owner}.{attribute} = {_kind(sets)}: expected a dict {{name: indices of {what}}}")
    checked = {}
    for name, indices in sets.items():
        if not isinstance(name, str):
            raise CaseError(f"{owner}.{attribute}: the name {_kind(name)} is not a string (a case names parts and "
                            f"regions by strings; a number n as \"n\")")
        where = f"{owner}.{attribute}[{_name(name)}]"
        array = np.asarray(indices) if isinstance(indices, (np.ndarray, list, tuple, range)) else None
        if array is None or array.ndim != 1 or (array.size and array.dtype.kind not in "iu"):
            raise CaseError(f"{where} = {_kind(indices)}: expected a 1D array of integers, the indices of its {what}")
        if array.size == 0:
            raise CaseError(f"{where} has no {what}: remove it, or give its {what}")
        wrong = (array < 0) | (array >= count)
        if wrong.any():
            raise CaseError(f"{where}: index {int(array[wrong][0])} is not one of the mesh's {what} (0 to "
                            f"{count - 1}; {int(wrong.sum())} such indices)")
        checked[name] = np.unique(array).astype(np.int64)
    return checked


def _check_functions(attribute: str, functions, known: dict, what: str, pairs: bool = False) -> None:
    """``functions`` ({part or (region, region): f}) name known parts (regions) and are callable; else CaseError."""
    if not isinstance(functions, Mapping):
        raise CaseError(f"Mesh.{attribute} = {_kind(functions)}: expected a dict of functions by {what}")
    for key, function in functions.items():
        names = key if pairs and isinstance(key, tuple) and len(key) == 2 else (key,)
        missing = [name for name in names if not (isinstance(name, str) and name in known)]
        if missing or (pairs and names == (key,)):
            expected = f"a pair of the mesh's {what}" if pairs else f"one of the mesh's {what}"
            raise CaseError(f"Mesh.{attribute}: the key {_kind(key)} is not {expected} "
                            f"({', '.join(sorted(known)) or 'none'})")
        if not isinstance(function, Callable):
            raise CaseError(f"Mesh.{attribute}[{_kind(key)}] = {_kind(function)}: expected a function of the "
                            f"points (d, ...)")


def _name(name: str) -> str:
    return repr(shown(name))


def _kind(value) -> str:
    """A value of the API for a message, on one line and short."""
    if isinstance(value, (str, int, float, bool, type(None), tuple, list)):
        return shown(repr(value))
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape} of {value.dtype}"
    return f"a {type(value).__module__.split('.')[0]} {type(value).__name__}"
