"""The `Mesh`: a triangle (2D) or tetrahedral (3D) P1 mesh with named boundary parts and element regions.

`Mesh` wraps a `skfem.MeshTri` or `skfem.MeshTet` and names sets of its boundary facets ("parts"): edges in
2D, triangles in 3D, and sets of its elements ("regions"). Meshes come from the built-in shapes
(`vpcontact.mesh.shapes`: `half_disc`, the paper's half ball, `rectangle`, `quarter_ball`, its 3D analogue,
`block`) or from a file (`vpcontact.mesh.read.read_mesh`: any triangle or tetrahedron file meshio reads,
e.g. gmsh .msh 2.2 / 4.1). A built-in shape knows its exact geometry: the outward normals of its parts
(`RadialNormal`, `ConstantNormal`) and the projections onto its curved parts and interfaces (`OntoSphere`).

Facet and node indices are those of the wrapped skfem mesh. skfem sorts the node
indices of every triangle (``MeshTri.sort_t``), and a file's tetrahedra keep their own
order, so ``mesh.mesh.t`` has no fixed orientation; skfem's P1 assembly and facet
normals do not depend on it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import skfem

from ..errors import CaseError, shown
from ..memory import available_memory
from .cells import SIMPLICES
from .checks_arrays import check_mesh
from .facets import ELEMENT_FACETS, FACET_ELEMENTS, FACETS
from .simplex import longest_edges

NormalField = Callable[[np.ndarray], np.ndarray]
Projection = Callable[[np.ndarray], np.ndarray]



@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle (2D) or tetrahedral (3D) mesh with named boundary parts."""

    mesh: skfem.Mesh
    """The scikit-fem mesh, MeshTri1 or MeshTet1 (p: (d, nnodes), t: (d + 1, nelems)); its ``boundaries``
    hold the parts too."""
    parts: dict[str, np.ndarray]
    """Part name -> sorted int64 indices of boundary facets (columns of ``mesh.facets``)."""
    exact_normals: dict[str, NormalField]
    """Part -> f(points (d, ...)) -> unit outward normals, same shape; only where the geometry is known exactly."""
    file: str | None = None
    """The mesh file it was read from (None for a built-in shape)."""
    regions: dict[str, np.ndarray] = field(default_factory=dict)
    """Region name -> sorted int64 indices of elements (columns of ``mesh.t``): the groups of elements
    materials are assigned to; empty when the mesh does not group its elements (one region, the body)."""
    curved_parts: dict[str, Projection] = field(default_factory=dict)
    """Part -> f(points (d, k)) -> the nearest points (d, k) of the exact curve or surface the part lies on: the
    curved parts of a built-in shape, where refinement (`vpcontact.mesh.refinement`) moves its new nodes."""
    curved_interfaces: dict[tuple[str, str], Projection] = field(default_factory=dict)
    """(region, region) -> the projection onto the exact curve or surface between the two regions (a coated
    shape's interface), like ``curved_parts``."""

    def __post_init__(self):
        """Refuse arrays that cannot be a mesh (`vpcontact.mesh.checks_arrays`: a Mesh made in Python may hold
        anything) and keep the parts and regions as sorted int64 indices."""
        parts, regions = check_mesh(self)
        object.__setattr__(self, "parts", parts)
        object.__setattr__(self, "regions", regions)

    def facets(self, part: str | int) -> np.ndarray:
        """Facet indices of `part` (an int n means the part named str(n))."""
        name = str(part)
        if name not in self.parts and not self.parts:
            facet, body = SIMPLICES[self.dim - 1].gmsh_group, SIMPLICES[self.dim].gmsh_group
            mesh = "the mesh" if self.file is None else f"mesh file '{self.file}'"
            raise CaseError(f"unknown part '{name}': {mesh} has no parts; the parts of a mesh file "
                            f"are its physical {facet.lower()}s: in gmsh add Physical {facet}(\"{name}\") = {{...}}; "
                            f"for each part the case names (and a Physical {body} for the body) and mesh again")
        if name not in self.parts:
            raise CaseError(f"unknown part '{shown(name)}'; the mesh has parts: {', '.join(self.part_names)}")
        return self.parts[name]

    def nodes(self, part: str | int) -> np.ndarray:
        """Sorted unique node indices of the facets of `part`."""
        return np.unique(self.mesh.facets[:, self.facets(part)]).astype(np.int64)

    @property
    def dim(self) -> int:
        """The dimension d of the body: 2 (triangles) or 3 (tetrahedra)."""
        return self.mesh.p.shape[0]

    @property
    def part_names(self) -> list[str]:
        """The part names, sorted."""
        return sorted(self.parts)

    @cached_property
    def h(self) -> float:
        """The longest edge length."""
        return float(longest_edges(self.mesh.p, self.mesh.t).max())

    @cached_property
    def centroids(self) -> np.ndarray:
        """The element centroids (d, nelements): where P0 data given as expressions are evaluated."""
        return self.mesh.p[:, self.mesh.t].mean(axis=1)

    @property
    def diameter(self) -> float:
        """The diameter (diagonal length) of the bounding box of the nodes."""
        p = self.mesh.p
        return float(np.linalg.norm(p.max(axis=1) - p.min(axis=1)))


#: Peak memory of a run per triangle (bytes): mesh, stiffness matrix, its factorization and the solver's
#: arrays. Measured (peak resident memory of `vpcontact run`, PARDISO): the paper's example with 145k
#: triangles 0.53 GB, with 580k triangles 1.79 GB, i.e. 3.1 kB per triangle; SuperLU (no MKL) needs
#: about twice as much. A run is refused when even this estimate exceeds the available memory.
BYTES_PER_TRIANGLE = 4000
#: The same per tetrahedron, for the method that needs least, the iterative one (no factor: the
#: factorizations of the direct methods are checked before they are made, by PARDISO's analysis and
#: the condensed method's guard). Measured (peak resident memory of the quarter ball's 10 steps, the whole
#: process, ``python benchmarks/setup_phases.py --h H --steps 10``): 560k tetrahedra 1.67 GiB, 3.94M
#: tetrahedra 10.9 GiB, i.e. 3.0–3.2 kB each (4.4–5.3 kB before the set-up kept no scikit-fem basis and
#: mapping of the whole mesh).
BYTES_PER_TETRAHEDRON = 3500


def check_memory(elements: float, what: str, fix: str, dim: int = 2) -> None:
    """Refuse, before allocating, a mesh of about `elements` triangles (dim 2) or tetrahedra (dim 3) whose
    run would need more than the available memory; `what` names the mesh (e.g. "mesh.h = 0.001"), `fix`
    says what to change."""
    kind, per_element = SIMPLICES[dim].plural, {2: BYTES_PER_TRIANGLE, 3: BYTES_PER_TETRAHEDRON}[dim]
    needed = per_element * elements
    available = available_memory()
    if not needed <= available:
        count, size = (f"about {elements:.2g}", f"about {needed / 2**30:.3g}") if math.isfinite(needed) else \
            ("more than 1e+300", "more than 1e+290")
        raise CaseError(f"{what}: {count} {kind}, whose mesh, stiffness matrix and solver need {size} GiB, "
                        f"more than the {available / 2**30:.3g} GiB of memory available here: {fix}")


#: scikit-fem's tables of a mesh's facets (the facets, element to facets, facet to elements), attributes it
#: builds on first use and that depend only on the elements.
FACET_TABLES = (FACETS, ELEMENT_FACETS, FACET_ELEMENTS)


def with_parts(mesh, parts: dict[str, np.ndarray], built=None):
    """``mesh.with_boundaries(parts)`` (scikit-fem), keeping the facet tables already built on ``built`` (by
    default ``mesh``), a mesh of the same elements: with_boundaries copies the mesh without them, and building
    them again took 0.4–0.8 s at 475k triangles. A table scikit-fem no longer keeps under these names is
    simply built again."""
    named = mesh.with_boundaries(parts)
    source = mesh if built is None else built
    for name in FACET_TABLES:
        if name in vars(source) and name not in vars(named):
            setattr(named, name, getattr(source, name))
    return named


@dataclass(frozen=True, eq=False)
class OntoSphere:
    """The projection of points (d, ...) onto the circle (d = 2) or sphere (d = 3) of `radius` around `center`
    (along the radius through the point). A class, not a closure: a mesh pickles (a result is sent between
    processes with its mesh)."""

    center: np.ndarray
    radius: float

    def __call__(self, x: np.ndarray) -> np.ndarray:
        at = self.center.reshape((-1,) + (1,) * (x.ndim - 1))
        offset = x - at
        return at + self.radius * offset / np.sqrt((offset**2).sum(axis=0))


@dataclass(frozen=True, eq=False)
class RadialNormal:
    """The outward unit normal (d, ...) of a circle or sphere around `center` at points (d, ...)."""

    center: np.ndarray

    def __call__(self, x: np.ndarray) -> np.ndarray:
        d = x - self.center.reshape((-1,) + (1,) * (x.ndim - 1))
        return d / np.sqrt((d**2).sum(axis=0))


@dataclass(frozen=True)
class ConstantNormal:
    """The normal field equal to `normal` everywhere."""

    normal: tuple[float, ...]

    def __call__(self, x: np.ndarray) -> np.ndarray:
        out = np.empty_like(x, dtype=float)
        out[...] = np.reshape(self.normal, (-1,) + (1,) * (x.ndim - 1))
        return out


def onto_sphere(center: np.ndarray, radius: float) -> Projection:
    """The projection onto the circle or sphere of `radius` around `center` (:class:`OntoSphere`)."""
    return OntoSphere(np.asarray(center, dtype=float), float(radius))

