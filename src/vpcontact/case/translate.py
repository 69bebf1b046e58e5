"""The one translation of a case into the plain options the layers below it read.

A validated :class:`~vpcontact.case.model.Case` (or a :class:`~vpcontact.case.model.Model`, or one of its tables
given from Python) becomes frozen dataclasses of plain values: :class:`~vpcontact.problem.options.ProblemOptions`
(the materials, boundary conditions, contact layers, initial state, time grid, solver and mesh), which the
problem is built from; :class:`~vpcontact.results.output_options.OutputOptions`, which the time loop, the result
and the writers read; :class:`~vpcontact.adaptivity.options.AdaptOptions`, which the adaptation reads.
Nothing under problem/, timeloop/, solvers/, results/, io/ or estimate/ imports the case: the command line
(:mod:`vpcontact.drivers`), the Python API (:mod:`vpcontact.api`) and :func:`~vpcontact.compose` translate, then
call them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..adaptivity.options import AdaptOptions
from ..problem.options import (Boundary, BodyForce, ContactOptions, Dirichlet, InitialOptions, LawChoice, Layer,
                               MaterialOptions, MeshSource, ProblemOptions, SolverOptions, TimeOptions, Traction)
from ..results.output_options import OutputOptions
from .body import BoundarySection, InitialSection, MeshSection
from .contact import ContactSection
from .law_sections import compliance_parameters
from .load import section
from .material import MaterialSection
from .model import Case, Model
from .run import AdaptSection, OutputSection
from .values import Section


@dataclass(frozen=True)
class CaseOptions:
    """A whole case translated: its problem, its outputs and its adaptive settings (None: no ``[adapt]``)."""

    problem: ProblemOptions
    output: OutputOptions
    adapt: AdaptOptions | None


def translate(case: Case) -> CaseOptions:
    """The options of every part of ``case``."""
    return CaseOptions(problem_options(case), output_options(case.output),
                       None if case.adapt is None else adapt_options(case.adapt))


def problem_options(model: Model) -> ProblemOptions:
    """The options of the problem of ``model``; of a :class:`~vpcontact.case.model.Case` with its mesh and its
    resolved TOML (case.resolved.toml), of a Model (composed in Python) without either."""
    case = model if isinstance(model, Case) else None
    return ProblemOptions(
        materials=tuple(_material(key, entry) for key, entry in model.keyed_materials()),
        boundary=_boundary(model.boundary),
        contact=None if model.contact is None else _contact(model.contact),
        initial=_initial(model.initial, model.from_run_path),
        time=_time(model.time),
        solver=SolverOptions(**model.solver.model_dump()),
        mesh=None if case is None else mesh_source(case.mesh, case.base_dir),
        source=None if case is None else case.to_toml(),
    )


def _time(time) -> TimeOptions:
    """The ``[time]`` table as options, the defaults of time.adaptive's keys where they are not given."""
    given = {key: value for key, value in time.model_dump().items() if value is not None and key != "start"}
    return TimeOptions(start=time.start, **given)


def output_options(output) -> OutputOptions:
    """The ``[output]`` table as options: an :class:`~vpcontact.case.run.OutputSection`, or a dict checked as the
    case file's table (None: its defaults); anything else is a CaseError naming the key."""
    return OutputOptions(**section(OutputSection, output, "output").model_dump())


def adapt_options(adapt) -> AdaptOptions:
    """The ``[adapt]`` table as options: an :class:`~vpcontact.case.run.AdaptSection`, or a dict checked as the
    case file's table; anything else (None too: ``cycles`` has no default) is a CaseError naming the key."""
    return AdaptOptions(**section(AdaptSection, adapt, "adapt").model_dump())


def mesh_source(mesh: MeshSection, base_dir: str = ".") -> MeshSource:
    """The mesh of a ``[mesh]`` table; a mesh file's path relative to ``base_dir`` (the case file's folder)."""
    return MeshSource(mesh.shape, mesh.file, None if mesh.file is None else Path(base_dir) / mesh.file, mesh.h,
                      mesh.h_bottom, mesh.radius, mesh.width, mesh.depth, mesh.height, mesh.coating)


def _law(law: Section) -> LawChoice:
    """A law table (``{"law": "power", "c_v": ..., ...}``, :mod:`vpcontact.case.law_sections`) as the law's name
    and its parameters."""
    return LawChoice(law.law, law.model_dump(exclude={"law"}))


def _material(key: str, entry: MaterialSection) -> MaterialOptions:
    return MaterialOptions(key, entry.E, entry.nu, entry.hypothesis, tuple(entry.regions),
                           None if entry.viscoplastic is None else _law(entry.viscoplastic))


def _boundary(boundary: BoundarySection) -> Boundary:
    return Boundary(
        dirichlet=(*(Dirichlet(f"boundary.dirichlet[{i}]", item.part, _tuple(item.components), _tuple(item.value),
                               where=item.where, name=item.name) for i, item in enumerate(boundary.dirichlet)),
                   *(Dirichlet(f"boundary.point[{i}]", None, _tuple(item.components), _tuple(item.value),
                               at=tuple(item.at), name=item.name) for i, item in enumerate(boundary.point))),
        traction=tuple(Traction(item.part, list(item.value)) for item in boundary.traction),
        body_force=tuple(BodyForce(list(item.value)) for item in boundary.body_force),
    )


def _tuple(values: list | None) -> tuple | None:
    return None if values is None else tuple(values)


def _contact(contact: ContactSection) -> ContactOptions:
    layers = tuple(Layer(key, layer.part, layer.g, layer.gap,
                         None if layer.p is None else LawChoice(layer.p, compliance_parameters(layer)),
                         None if layer.stiffness is None else _law(layer.stiffness))
                   for key, layer in contact.layers())
    normal = contact.normal if isinstance(contact.normal, str) else list(contact.normal)
    return ContactOptions(layers, contact.rho, None if contact.probe is None else list(contact.probe), normal)


def _initial(initial: InitialSection, from_run_path: Path | None) -> InitialOptions:
    return InitialOptions(
        displacement=None if initial.displacement is None else list(initial.displacement),
        stress=None if initial.stress is None else [list(row) for row in initial.stress],
        xi=initial.xi, from_run=initial.from_run, from_run_path=from_run_path, step=initial.step,
    )
