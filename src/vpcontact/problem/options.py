"""What a problem is built from: the case translated into plain values (:mod:`vpcontact.case.translate`).

Frozen dataclasses of numbers, strings and lists, no schema and no NumPy object: the problem, the laws of the
materials and the checks before a run read these, never the case file's tables. A value the case may give as
a number or as an expression in the coordinates stays as the case writes it (a float, or the expression's
text), with the key that names it in messages (``key``: "material[1]", "contact.parts[0]"); vectors and
tables stay lists, as the case file writes them; entries (materials, Dirichlet conditions, contact parts)
are tuples.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class LawChoice:
    """A law a case names: ``law``, its name in its family's registry (:mod:`vpcontact.laws.stiffness`,
    :mod:`vpcontact.laws.compliance`, :mod:`vpcontact.laws.viscoplastic`), and its ``parameters`` by name (numbers;
    a contact law's may be expressions in the coordinates)."""

    law: str
    parameters: dict


@dataclass(frozen=True)
class MaterialOptions:
    """One material of the body (the paper's ℰ (2.16) and 𝒢 (2.17)): E and ν (numbers or expressions in the
    coordinates, evaluated at the element centroids), the 2D hypothesis (None: plane strain in 2D, none in
    3D), the mesh regions it is the material of (empty: the whole body) and its viscoplastic law (None: 𝒢 = 0)."""

    key: str
    E: float | str
    nu: float | str
    hypothesis: str | None
    regions: tuple[str, ...]
    viscoplastic: LawChoice | None


@dataclass(frozen=True)
class Dirichlet:
    """u = u_D for the ``components`` named (None: all of them) at the nodes of ``part``, or at those where the
    condition ``where`` holds (of ``part`` when both are given), or at the node nearest to the point ``at``;
    ``value``: u_D, one expression in the coordinates and t (or a number) per component held (None: u_D = 0);
    ``key``: the entry's key in the case (``boundary.dirichlet[i]``, ``boundary.point[i]``); ``name``: the name of
    its columns (None: the part's name, or the key's section and index)."""

    key: str
    part: str | int | None
    components: tuple[str, ...] | None
    value: tuple | None = None
    where: str | None = None
    at: tuple[float, ...] | None = None
    name: str | None = None


@dataclass(frozen=True)
class Traction:
    """σν = f2 on ``part``: one expression in the coordinates and t (or a number) per component."""

    part: str | int
    value: list


@dataclass(frozen=True)
class BodyForce:
    """f0 in Ω: one expression in the coordinates and t (or a number) per component."""

    value: list


@dataclass(frozen=True)
class Boundary:
    """The boundary conditions and loads: Dirichlet conditions, tractions, body forces, in the case's order."""

    dirichlet: tuple[Dirichlet, ...]
    traction: tuple[Traction, ...]
    body_force: tuple[BodyForce, ...]


@dataclass(frozen=True)
class Layer:
    """The soft layer on one contact part (2.5): its thickness g (a number, inf, or an expression in the
    coordinates), the initial gap g0, the law p (2.19) and the stiffness law K (2.18) (a law of
    :data:`~vpcontact.laws.compliance.COMPLIANCE` and of :data:`~vpcontact.laws.stiffness.STIFFNESS`, each
    parameter a number or an expression in the coordinates); p and K are None where a Python law of the API
    replaces them."""

    key: str
    part: str | int
    g: float | str
    gap: float | str
    p: LawChoice | None
    stiffness: LawChoice | None


@dataclass(frozen=True)
class ContactOptions:
    """The contact condition on Γ3: its layers (one per contact part; a node shared by two parts takes the
    first one's), ρ, the probe point (None: the contact nodes' centroid) and the foundation's normal
    ("body": the body's outward normals, or a vector)."""

    layers: tuple[Layer, ...]
    rho: float
    probe: list | None
    normal: str | list


@dataclass(frozen=True)
class InitialOptions:
    """The initial state (2.7), (2.21) as the case gives it: u_0 (d expressions), σ_0 (a d × d table of
    expressions), ξ_0 (an expression), each None for 0; or a restart from the field step ``step`` of the run
    directory ``from_run`` (as written; ``from_run_path`` relative to the case file's folder)."""

    displacement: list | None
    stress: list | None
    xi: float | str | None
    from_run: str | None
    from_run_path: Path | None
    step: int | None


@dataclass(frozen=True)
class TimeOptions:
    """[t_0, T] in ``steps`` equal steps; t_0 = ``start`` (None: 0, or the time of a restart's step); ``adaptive``:
    each step in as many sub-steps as keep the time estimate within ``balance`` times the space estimate, halved at
    most ``max_halvings`` times (:mod:`vpcontact.timeloop.time_control`)."""

    T: float
    steps: int
    start: float | None
    adaptive: bool = False
    balance: float = 1.0
    max_halvings: int = 6


@dataclass(frozen=True)
class SolverOptions:
    """The step solver: its method, the sparse direct factorization, the iterative method's multigrid, the
    Newton tolerance and iteration limit, the halvings of a step that fails, and the Alart–Curnier r (None:
    automatic)."""

    method: str
    factorization: str
    multigrid: str
    tolerance: float
    max_iterations: int
    max_step_cuts: int
    augmentation: float | None


@dataclass(frozen=True)
class MeshSource:
    """The mesh of a case: a built-in ``shape`` of element size h and its sizes, or a mesh ``file`` (as the case
    writes it; ``path``: relative to the case file's folder)."""

    shape: str | None
    file: str | None
    path: Path | None
    h: float | None
    h_bottom: float | None
    radius: float | None
    width: float | None
    depth: float | None
    height: float | None
    coating: float | None


@dataclass(frozen=True)
class ProblemOptions:
    """Everything a problem is built from: the materials, the boundary conditions, the contact (None: no
    contact), the initial state, the time grid and the solver; the mesh the case makes (None: one is given to
    :func:`~vpcontact.problem.build.build_problem`) and the resolved case it was translated from (its TOML,
    for case.resolved.toml and checkpoints; None for a problem composed in Python)."""

    materials: tuple[MaterialOptions, ...]
    boundary: Boundary
    contact: ContactOptions | None
    initial: InitialOptions
    time: TimeOptions
    solver: SolverOptions
    mesh: MeshSource | None
    source: str | None
