"""The case description: the one place that knows the keys of a case file.

A :class:`Model` is the problem as a mechanician states it (materials, boundary conditions, contact, initial
state, time grid, solver); a :class:`Case` adds its mesh, its outputs and its adaptive meshes, and writes itself
as the resolved TOML of a run directory (every value used, defaults included). A case is a TOML file (or a
dict) validated against these sections (:mod:`vpcontact.case.load`); every problem is reported as a
:class:`~vpcontact.errors.CaseError` with a one-line message naming the bad key and value
(:mod:`vpcontact.case.messages`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Optional

import tomli_w
from pydantic import Field, model_validator

from ..errors import brief
from .body import BoundarySection, InitialSection, MeshSection
from .contact import ContactSection
from .material import Materials, MaterialSection
from .run import AdaptSection, OutputSection, SolverSection, TimeSection
from .values import Section


class Model(Section):
    """The problem as a mechanician states it, without its mesh and without the settings of a run: the
    material(s), the boundary conditions, the contact condition, the initial state, the time grid and the
    solver options. A :class:`Case` is a Model with a mesh, outputs and adaptive meshes; a problem keeps
    its options (``Problem.options``, :mod:`vpcontact.case.translate`), so that it can be built again on another
    mesh. ``base_dir`` resolves relative file names (the case file's folder)."""

    material: Materials
    boundary: BoundarySection = BoundarySection()
    contact: Optional[ContactSection] = None
    initial: InitialSection = InitialSection()
    time: TimeSection
    solver: SolverSection = SolverSection()
    base_dir: Annotated[str, Field(exclude=True)] = "."

    @model_validator(mode="after")
    def _materials_by_region(self):
        """Admissible Poisson ratios; a list of materials: each entry names its regions, and all give one
        2D hypothesis."""
        for key, entry in self.keyed_materials():
            entry.check_poisson_ratios(key)
        if isinstance(self.material, list):
            for i, entry in enumerate(self.material):
                if entry.region is None and len(self.material) > 1:
                    raise ValueError(f"material[{i}] has no region and there are {len(self.material)} materials: give "
                                     f"each its material[{i}].region (a region of the mesh, or a list of them)")
            hypotheses = {entry.hypothesis or "plane_strain" for entry in self.material}
            if len(hypotheses) > 1:
                raise ValueError(f"material: the entries give different hypotheses ({', '.join(sorted(hypotheses))}); "
                                 f"plane strain or plane stress is one assumption for the whole 2D body")
        return self

    def keyed_materials(self) -> list[tuple[str, MaterialSection]]:
        """(key, entry) of each material: "material" for the single table, "material[i]" in a list."""
        if isinstance(self.material, list):
            return [(f"material[{i}]", entry) for i, entry in enumerate(self.material)]
        return [("material", self.material)]

    @property
    def materials(self) -> list[MaterialSection]:
        """The material entries: the single ``[material]`` as a list of one."""
        return self.material if isinstance(self.material, list) else [self.material]

    @property
    def from_run_path(self) -> Path | None:
        """initial.from_run, relative to the case file's folder."""
        return None if self.initial.from_run is None else Path(self.base_dir) / self.initial.from_run


#: The sections of a case file, in the order case.resolved.toml lists them.
SECTIONS = ("mesh", "material", "boundary", "contact", "initial", "time", "solver", "output", "adapt")


class Case(Model):
    """A whole case: the :class:`Model`, its mesh (``[mesh]``), the run's outputs and adaptive meshes."""

    mesh: MeshSection
    output: OutputSection = OutputSection()
    adapt: Optional[AdaptSection] = None

    @property
    def model(self) -> Model:
        """The case without its mesh, outputs and adaptive meshes (the same section objects)."""
        return Model.model_construct(**{name: getattr(self, name) for name in Model.model_fields})

    @model_validator(mode="after")
    def _adapt_from_the_case_mesh(self):
        if self.adapt is not None and self.initial.from_run is not None:
            raise ValueError("[adapt] with initial.from_run: the fields a restart starts from are on the mesh of that "
                             "run, and the adaptive cycles solve on other meshes; remove one of them")
        return self

    @model_validator(mode="after")
    def _field_steps_in_range(self):
        steps = self.output.field_steps
        if isinstance(steps, list) and steps and steps[-1] > self.time.steps:
            raise ValueError(f"output.field_steps: step {brief(steps[-1])} is after the last step ({self.time.steps})")
        return self

    @property
    def mesh_path(self) -> Path | None:
        return None if self.mesh.file is None else Path(self.base_dir) / self.mesh.file

    def resolved(self) -> dict:
        """Every value used, defaults included (the content of case.resolved.toml); a mesh file by its
        absolute path, so that the resolved case runs again from any folder (its run directory too)."""
        dumped = self.model_dump(mode="python", exclude_none=True)
        data = {name: dumped[name] for name in SECTIONS if name in dumped}
        if self.mesh.file is not None:
            data["mesh"]["file"] = os.path.abspath(self.mesh_path)
        if self.initial.from_run is not None:
            data["initial"]["from_run"] = os.path.abspath(self.from_run_path)
        return data

    def to_toml(self) -> str:
        return tomli_w.dumps(self.resolved())
