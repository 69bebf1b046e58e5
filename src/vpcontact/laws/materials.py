"""Materials by region: the case's material entries on the elements of the mesh.

The paper lets the data of the body vary in space: ℰ(x) ∈ L∞(Ω) (2.16) and 𝒢(x, σ, ε) (2.17). A case
gives one ``[material]`` for the whole body or a list of entries, each naming the mesh regions
(``Mesh.regions``: gmsh physical surfaces in 2D, physical volumes in 3D, the core and coating of a
built-in shape) it is the material of; E and ν are numbers or expressions in the coordinates,
evaluated at the element centroids (P0 coefficients, exact for the P1 × P0 bulk forms). Every
element has exactly one material: a region no entry names, an element in no region, or two entries
claiming one element are refused before any computation.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError, point, quoted
from ..expressions.parse import values_at
from .elasticity import Elasticity
from .viscoplastic import VISCOPLASTIC
from ..mesh.mesh import Mesh
from ..mesh.cells import coordinates


@dataclass(frozen=True)
class RegionalViscoplastic:
    """𝒢(x, σ, ε) of (2.17) for materials by region: each law of ``laws`` on its elements, 0 on the
    elements of materials without one (their response is elastic)."""

    laws: tuple[tuple[np.ndarray, Callable], ...]  # (element indices, 𝒢 of their material)

    def __call__(self, sigma: np.ndarray, strain: np.ndarray) -> np.ndarray:
        rate = np.zeros(np.broadcast_shapes(np.shape(sigma), np.shape(strain)))
        for elements, law in self.laws:
            rate[..., elements] = law(sigma[..., elements], strain[..., elements])
        return rate

    def on(self, elements: np.ndarray) -> "RegionalViscoplastic":
        """𝒢 over the elements ``elements`` alone (sorted indices; the arrays it is given have their entries)."""
        return RegionalViscoplastic(tuple((np.searchsorted(elements, mine[np.isin(mine, elements)]), law)
                                          for mine, law in self.laws))


@dataclass(frozen=True, eq=False)
class AtCentroids:
    """A law 𝒢(σ, ε, x) of the API with x bound to the element centroids (d, nelements): 𝒢(x, σ, ε) of
    (2.17) as a law of (σ, ε) over the elements."""

    law: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    centroids: np.ndarray = field(repr=False)

    def __call__(self, sigma: np.ndarray, strain: np.ndarray) -> np.ndarray:
        return self.law(sigma, strain, self.centroids)

    def on(self, elements: np.ndarray) -> "AtCentroids":
        """𝒢 over the elements ``elements`` alone (indices): x bound to their centroids."""
        return AtCentroids(self.law, self.centroids[:, elements])


@dataclass(frozen=True)
class Materials:
    """The body's materials on the elements: which entry each element has, ℰ per element and 𝒢."""

    owner: np.ndarray  # the index of each element's entry in the case's materials (nelements,)
    elasticity: Elasticity  # E, ν floats for one homogeneous material, else arrays over the elements
    viscoplastic: Callable | None  # 𝒢(σ, ε) over arrays (d, d, nelements); None: 𝒢 = 0 everywhere

    @property
    def E(self) -> np.ndarray:
        """Young's modulus of each element."""
        return np.broadcast_to(np.asarray(self.elasticity.E, dtype=float), self.owner.shape)

    @property
    def nu(self) -> np.ndarray:
        """Poisson's ratio of each element."""
        return np.broadcast_to(np.asarray(self.elasticity.nu, dtype=float), self.owner.shape)


def body_materials(materials: Sequence, mesh: Mesh) -> Materials:
    """The case's ``materials`` (:class:`~vpcontact.problem.options.MaterialOptions`: key, E, ν, hypothesis,
    regions, viscoplastic law) on the elements of ``mesh`` (CaseError naming the entry, region or element where
    they do not assign exactly one admissible material to every element)."""
    entries = [(entry.key, entry) for entry in materials]
    owner = _owners(entries, mesh)
    dim = mesh.dim
    hypothesis = (materials[0].hypothesis or "plane_strain") if dim == 2 else None
    if len(entries) == 1 and not any(isinstance(v, str) for v in (materials[0].E, materials[0].nu)):
        entry = materials[0]
        elasticity = Elasticity(float(entry.E), float(entry.nu), hypothesis)  # homogeneous: the scalar form
    else:
        centroids = mesh.centroids
        E, nu = np.empty(owner.size), np.empty(owner.size)
        for i, (key, entry) in enumerate(entries):
            mine = owner == i
            E[mine] = _coefficient(f"{key}.E", entry.E, centroids[:, mine], minimum=0.0)
            nu[mine] = _coefficient(f"{key}.nu", entry.nu, centroids[:, mine], hypothesis=hypothesis)
        elasticity = Elasticity(E, nu, hypothesis)
    laws = [(np.flatnonzero(owner == i), _viscoplastic_law(entry.viscoplastic, hypothesis))
            for i, (_, entry) in enumerate(entries) if entry.viscoplastic is not None]
    if not laws:
        viscoplastic = None
    elif len(entries) == 1:
        viscoplastic = laws[0][1]
    else:
        viscoplastic = RegionalViscoplastic(tuple(laws))
    return Materials(owner, elasticity, viscoplastic)


def _viscoplastic_law(choice, hypothesis: str | None) -> Callable:
    """𝒢 of a material's viscoplastic law ``choice`` (:class:`~vpcontact.problem.options.LawChoice`: a name of
    VISCOPLASTIC and its parameters by name) under the material's 2D ``hypothesis``."""
    return VISCOPLASTIC[choice.law].made(lambda parameter: choice.parameters[parameter.name], hypothesis=hypothesis)


def _owners(entries: list[tuple[str, object]], mesh: Mesh) -> np.ndarray:
    """The entry of each element; refused: a region the mesh does not have, an element claimed twice or
    by no entry (naming the regions)."""
    elements = mesh.mesh.t.shape[1]
    if len(entries) == 1 and not entries[0][1].regions:
        return np.zeros(elements, dtype=np.int64)
    owner = np.full(elements, -1, dtype=np.int64)
    for i, (key, entry) in enumerate(entries):
        for name in entry.regions:
            if name not in mesh.regions:
                raise CaseError(_unknown_region(key, name, mesh))
            claimed = mesh.regions[name]
            taken = owner[claimed]
            clash = taken[(taken >= 0) & (taken != i)]
            if clash.size:
                other_key, other = entries[int(clash[0])]
                raise CaseError(f"{key}.region '{name}' overlaps {other_key}.region ({', '.join(other.regions)}): "
                                f"{clash.size} elements would have two materials; give each element one material")
            owner[claimed] = i
    orphans = np.flatnonzero(owner < 0)
    if orphans.size:
        raise CaseError(f"material: {orphans.size} of {elements} elements have no material ({_where(owner, mesh)}; "
                        f"one is at ({', '.join(coordinates(mesh.dim))}) = {point(mesh.centroids[:, orphans[0]])}): "
                        f"add a material entry for them")
    return owner


def _where(owner: np.ndarray, mesh: Mesh) -> str:
    """Where elements without a material are: the regions holding some, each once (a gmsh group known by its
    number and by its name is named by its name), or in no region."""
    regions = [name for name, elements in mesh.regions.items() if np.any(owner[elements] < 0)]
    named = [name for name in regions
             if not (name.isdigit() and any(not other.isdigit() and np.array_equal(mesh.regions[other],
                                                                                mesh.regions[name])
                                            for other in regions))]
    if not named:
        return "they are in no region of the mesh"
    return f"in the mesh's region{'s' * (len(named) > 1)} {', '.join(repr(name) for name in named)}"


def _unknown_region(key: str, name: str, mesh: Mesh) -> str:
    """The message of a material region the mesh does not have."""
    if not mesh.regions:
        groups = "physical surfaces" if mesh.dim == 2 else "physical volumes"
        return (f"{key}.region = '{name}': the mesh has no regions (a mesh file's regions are its {groups}; the "
                f"built-in half_disc and quarter_ball have 'core' and 'coating' with mesh.coating)")
    return f"{key}.region = '{name}': unknown region; the mesh has regions: {', '.join(sorted(mesh.regions))}"


def _coefficient(key: str, value, centroids: np.ndarray, *, minimum: float | None = None,
                 hypothesis: str | None = None) -> np.ndarray:
    """E or ν of an entry at its elements' centroids: a number as it is, an expression evaluated there;
    refused (naming the element's centroid) where not finite, not > ``minimum``, or (ν) not admissible
    for ``hypothesis``."""
    names = coordinates(centroids.shape[0])
    values = values_at(value, key, centroids, names)
    if minimum is not None:
        wrong, expected = ~(values > minimum), f"a finite number > {minimum:g}"
    else:
        upper = (values <= 0.5) if hypothesis == "plane_stress" else (values < 0.5)
        wrong = ~((values > -1.0) & upper)
        expected = f"-1 < nu {'<=' if hypothesis == 'plane_stress' else '<'} 0.5 ({hypothesis or 'plane_strain and 3D'})"
    wrong |= ~np.isfinite(values)
    if wrong.any():
        element = np.flatnonzero(wrong)[0]
        raise CaseError(f"{key} = {quoted(str(value))} is {values[element]:g} at the element centroid "
                        f"({', '.join(names)}) = {point(centroids[:, element])} ({wrong.sum()} elements): expected "
                        f"{expected} in every element of the material")
    return values
