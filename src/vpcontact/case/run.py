"""How the problem is run: ``[time]`` (the time grid), ``[solver]`` (the step solver), ``[output]`` (what a run
keeps and writes) and ``[adapt]`` (adaptive meshes)."""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional

from pydantic import Field, field_validator, model_validator

from ..errors import brief
from ..estimate.estimators import ESTIMATORS
from ..problem.time_grid import check_time_span
from ..solvers.factorization import FACTORIZATIONS
from ..solvers.linear import MULTIGRIDS
from .values import MAX_STEPS, NonNegativeFloat, PositiveFloat, Section, show


class TimeSection(Section):
    """[t_0, T] in ``steps`` equal steps k = (T − t_0) / steps; t_0 = ``start`` (default 0, or the time of
    the step a restart starts from, initial.from_run). ``adaptive = true``: each step in as many sub-steps as keep
    the error estimate in time within ``balance`` (default 1) times the estimate in space, a step halved at most
    ``max_halvings`` times (default 6)."""

    T: PositiveFloat
    steps: Annotated[int, Field(ge=1, le=MAX_STEPS)]
    start: Optional[float] = None
    adaptive: bool = False
    balance: Optional[PositiveFloat] = None
    max_halvings: Optional[Annotated[int, Field(ge=0, le=30)]] = None

    @model_validator(mode="after")
    def _start_before_end(self):
        if self.start is not None:
            check_time_span(self.start, self.T, self.steps, "time.start")
        for key in ("balance", "max_halvings"):
            if getattr(self, key) is not None and not self.adaptive:
                raise ValueError(f"time.{key} = {show(getattr(self, key))} is used only by time.adaptive = true: "
                                 f"remove it, or set time.adaptive = true")
        return self


class SolverSection(Section):
    """The step solver: "full" (Newton on the whole system), "condensed" (factor once, Newton on the
    contact nodes) or "auto" (condensed when its dense contact operator fits in memory)."""

    method: Literal["auto", "condensed", "full", "iterative"] = "auto"
    factorization: str = "auto"  # sparse direct backend of "condensed"
    multigrid: str = "auto"  # multigrid backend of "iterative": "petsc" (PETSc's GAMG) or "pyamg"
    tolerance: Annotated[float, Field(gt=0, lt=1)] = 1e-10
    max_iterations: Annotated[int, Field(ge=1)] = 50
    max_step_cuts: Annotated[int, Field(ge=0, le=30)] = 4  # halvings of a step whose Newton iteration fails
    augmentation: Optional[PositiveFloat] = None  # Alart–Curnier r; "auto": the median normal stiffness

    @field_validator("factorization")
    @classmethod
    def _known_backend(cls, value):
        """A backend's name (whether it is installed here is checked when the problem is built)."""
        if value != "auto" and value not in FACTORIZATIONS:
            raise ValueError(f"solver.factorization = {show(value)}: unknown; expected \"auto\" or one of "
                             f"{', '.join(repr(b) for b in FACTORIZATIONS)}")
        return value

    @field_validator("multigrid")
    @classmethod
    def _known_multigrid(cls, value):
        """A multigrid backend's name (whether it is installed here is checked when the problem is built)."""
        if value != "auto" and value not in MULTIGRIDS:
            raise ValueError(f"solver.multigrid = {show(value)}: unknown; expected \"auto\" or one of "
                             f"{', '.join(repr(b) for b in MULTIGRIDS)}")
        return value

    @field_validator("augmentation", mode="before")
    @classmethod
    def _automatic(cls, value):
        return None if value == "auto" else value

    @model_validator(mode="after")
    def _factorization_used(self):
        if self.method == "iterative" and self.factorization != "auto":
            raise ValueError(f"solver.factorization = {show(self.factorization)} is not used by solver.method = "
                             f"\"iterative\" (it factors nothing): remove it, or choose the method \"condensed\" "
                             f"or \"full\"")
        if self.method in ("condensed", "full") and self.multigrid != "auto":
            raise ValueError(f"solver.multigrid = {show(self.multigrid)} is not used by solver.method = "
                             f"\"{self.method}\" (it solves by factors): remove it, or choose the method \"iterative\"")
        return self


class OutputSection(Section):
    field_steps: Any = "final"  # "all", "final", "none" or a list of step numbers
    progress: bool = True
    checkpoint_every_steps: Annotated[int, Field(ge=0)] = 0  # 0: not by step count
    checkpoint_every_seconds: NonNegativeFloat = 60.0  # 0: not by time
    figures: bool = False  # figures/*.png at the end of a complete or failed run (vpcontact.results.plots)
    error_estimate: bool = False  # the residual error estimate at every step (vpcontact.estimate.residual)
    xdmf: bool = False  # fields/body.xdmf + body.h5 (contact too) beside the VTU files (vpcontact.io.xdmf)

    @field_validator("field_steps")
    @classmethod
    def _steps(cls, value):
        if value in ("all", "final", "none"):
            return value
        if isinstance(value, list) and all(isinstance(s, int) and not isinstance(s, bool) and s >= 1 for s in value):
            return sorted(set(value))
        raise ValueError(
            f"output.field_steps = {brief(value)}: expected \"all\", \"final\", \"none\" or a list of step numbers >= 1"
        )


class AdaptSection(Section):
    """Adaptive meshes. ``mode = "cycles"`` (:mod:`vpcontact.adaptivity.cycles`): up to ``cycles`` solves of the
    whole history, each on the mesh refined from the one before by Dörfler marking (the fewest elements holding
    ``theta`` of the sum of the time functional of the indicators). ``mode = "run"``
    (:mod:`vpcontact.adaptivity.during_run`): one run, the mesh refined between time steps until each level's
    estimate is at most ``tolerance`` times the largest energy norm of the solution so far. No mesh has more than
    ``max_dofs`` dofs."""

    mode: Literal["cycles", "run"] = "cycles"
    cycles: Optional[Annotated[int, Field(ge=1)]] = None
    tolerance: Optional[PositiveFloat] = None  # mode "run": η(t_n) ≤ tolerance · max_{m≤n} ‖u_h(t_m)‖_E
    theta: Annotated[float, Field(gt=0, le=1)] = 0.5
    max_dofs: Annotated[int, Field(gt=0)] = 1_000_000
    functional: Literal["max", "l2"] = "max"  # max over the steps of η_K²(t_n), or Σ_n k_n η_K²(t_n)
    estimator: Literal[ESTIMATORS.names] = "residual"  # vpcontact.estimate.estimators.ESTIMATORS

    @model_validator(mode="after")
    def _what_the_mode_needs(self):
        if self.mode == "cycles" and self.cycles is None:
            raise ValueError("missing required value 'adapt.cycles': mode = \"cycles\" needs the number of cycles (or "
                             "set adapt.mode = \"run\" with adapt.tolerance to adapt during one run)")
        if self.mode == "run" and self.tolerance is None:
            raise ValueError("missing required value 'adapt.tolerance': mode = \"run\" refines a level until its "
                             "estimate is at most adapt.tolerance times the largest energy norm of the solution so far "
                             "(e.g. 0.1)")
        if self.mode == "run" and self.cycles is not None:
            raise ValueError(f"adapt.cycles = {self.cycles} with mode = \"run\": one run adapts its mesh; remove "
                             f"adapt.cycles, or set mode = \"cycles\"")
        if self.mode == "cycles" and self.tolerance is not None:
            raise ValueError(f"adapt.tolerance = {show(self.tolerance)} with mode = \"cycles\": the cycles stop after "
                             f"adapt.cycles; remove it, or set mode = \"run\"")
        return self
