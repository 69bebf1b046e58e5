"""The result of a run: time series, per-node contact history and fields at the requested steps.

The history's columns and the contact arrays are named in :mod:`vpcontact.results.columns` (with the
conventions of their signs and units). Sub-steps: a step whose Newton iteration fails is cut in halves
(``timeloop``); every converged time level is a row of the history and of the per-node arrays, in time
order, and which rows are the steps t_n is decided by :mod:`vpcontact.results.steps`;
``series(..., substeps=False)`` and ``contact_history(..., substeps=False)`` keep only those rows.

Memory: the rows and the fields at the field steps are kept until the run is written; a case whose
outputs would not fit in the memory available is refused before its first step
(:func:`vpcontact.results.footprint.check_memory`).
"""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Collection
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError, shown
from ..mesh.cells import coordinates
from ..laws.contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED
from ..problem.discretization import Discretization
from .columns import CONTACT_ARRAYS, INTEGER_COLUMNS, estimate_columns, history_columns
from .balance import balance
from .steps import end_of_step_rows, field_step_numbers, step_ends

#: Most characters of a run's message that ``repr(result)`` shows (on its second line).
REPR_MESSAGE = 200


class UnknownName(CaseError, KeyError):
    """A history column or contact array that does not exist (a KeyError, and a CaseError: one line)."""

    __str__ = CaseError.__str__  # the message as it is, not quoted as a KeyError shows its key


def _unknown(kind: str, name, valid: Collection[str], elsewhere: tuple[Collection[str], str]) -> UnknownName:
    """The error for ``name`` not in ``valid``; ``elsewhere``: the names of the other accessor, and its call."""
    close = difflib.get_close_matches(str(name), valid, n=1)
    if name in elsewhere[0]:
        hint = f"{elsewhere[1]}({name!r}) has it; "
    else:
        hint = f"did you mean '{close[0]}'? " if close else ""
    return UnknownName(f"unknown {kind} {shown(repr(name))}; {hint}valid names: {', '.join(valid)}")


@dataclass(repr=False)
class Fields:
    """Displacement at the nodes (nnodes, d); per element: the stress (nelements, d, d), in 2D also the
    out-of-plane σ33 of the elastic response (None in 3D), and the von Mises stress of the 3D tensor;
    with a viscoplastic law or initial data with z_0 = σ_0 − ℰε(u_0) ≠ 0, the history z (nelements, d, d)
    of the step, so that stress = ℰε(u) + z (None otherwise: z = 0); with ``output.error_estimate`` the
    error indicator η_K of each element (nelements,) (None otherwise)."""

    displacement: np.ndarray
    stress: np.ndarray
    stress33: np.ndarray | None
    von_mises: np.ndarray
    z: np.ndarray | None = None
    error_indicator: np.ndarray | None = None

    def __repr__(self) -> str:
        """The shapes, not the values."""
        shapes = ", ".join(f"{name}{getattr(self, name).shape}" for name in FIELD_NAMES
                           if getattr(self, name) is not None)
        return f"Fields({shapes})"


#: The fields of a time level (:class:`Fields`), in their order: what a checkpoint keeps of a field step.
FIELD_NAMES = tuple(item.name for item in dataclasses.fields(Fields))


@dataclass(repr=False)
class Result:
    """Everything a run computed, as plain data: its sizes, the history rows, the per-node contact arrays
    (rows, m): one row per converged time level, sub-steps included (see the module's docstring), the
    fields at the field steps, and ``discretization``, all it needs of the problem (the mesh, the contact
    nodes, the step times, ℰ, the layer's parameters) to be read, drawn and written; not the problem itself
    (its operators, loads and laws stay with it). ``times`` is the array of the rows' times."""

    dofs: int
    elements: int
    nodes: int
    contact_nodes: int
    dim: int
    probe: int | None
    field_steps: Collection[int]
    augmentation: float
    _times: list = field(default_factory=list)  # t of each row (a list: appending is cheap)
    rows: list = field(default_factory=list)
    contact: dict = field(default_factory=lambda: {name: [] for name in CONTACT_ARRAYS})
    fields: dict[int, Fields] = field(default_factory=dict)
    final: Fields | None = None
    status: str = "running"  # then "complete", "failed" or "interrupted"
    message: str = ""
    wall_time_s: float = 0.0
    timings: dict = field(default_factory=dict)
    method: str = ""
    method_reason: str = ""  # why that step method runs (solver.method, or what "auto" weighed)
    predicted: dict = field(default_factory=dict)  # each method's predicted cost (RunPlan.predicted)
    method_switch: dict | None = None  # the change of method during the run, if "auto" made one (switch.Switch)
    ranks: int = 1  # the MPI ranks that solved it (mpiexec -n N)
    ranks_detail: dict | None = None  # on several ranks, each one's share of the solve (RunMethod.ranks)
    peak_memory_bytes: list | None = None  # each rank's peak resident memory, at the end of the time loop
    linear_solves: int = 0  # solves with a factored matrix in the time loop
    krylov_iterations: int = 0  # GMRES iterations on Newton systems in the time loop
    newton_factorizations: int = 0  # LU factorizations of condensed Newton matrices in the time loop
    discretization: Discretization | None = None  # what the result needs of the problem, always there
    completed_steps: int = 0  # time steps t_n reached
    step_cuts: int = 0  # halvings of a step or sub-step whose Newton iteration failed
    time_cuts: int = 0  # halvings of a step or sub-step whose time estimate was above its share (time.adaptive)
    time_over_share: int = 0  # levels accepted above their share, at time.max_halvings (time.adaptive)
    resumed_at: list = field(default_factory=list)  # steps at which the run was resumed from a checkpoint
    estimate_terms: tuple[str, ...] = ()  # output.error_estimate: the estimator's terms (the rows' estimate_columns)
    output: object = None  # the OutputOptions the run was made with (what the writers write)
    adaptation: dict | None = None  # a run that adapted its mesh during the run: what it did (summary.json)

    @classmethod
    def start(cls, discretization: Discretization, dofs: int, solver, output,
              estimate_terms: tuple[str, ...] = ()) -> "Result":
        """The empty result of a run on ``discretization`` with ``dofs`` unknowns by the step ``solver`` (its
        method, why it runs, its augmentation r), with the options ``output`` (the fields kept and what the writers
        write), whose levels record the error estimate of ``estimate_terms`` (none: no estimate)."""
        mesh = discretization.mesh
        wanted = field_step_numbers(output.field_steps, len(discretization.times))
        return cls(dofs=dofs, elements=mesh.mesh.t.shape[1], nodes=mesh.mesh.p.shape[1],
                   contact_nodes=discretization.surface.size, dim=mesh.dim, probe=discretization.probe,
                   field_steps=wanted, augmentation=solver.r, method=solver.name, method_reason=solver.reason,
                   discretization=discretization, output=output, estimate_terms=tuple(estimate_terms))

    # --- filling in ------------------------------------------------------------------------------
    def record(self, n, t, solution, fields: Fields | None, *, xi, K, compliance, status, substep: int = 1,
               k: float = float("nan"), ends_step: bool = True, held: dict):
        """Store a converged time level of step n (the step itself, or its sub-step ``substep`` of
        length k; ``ends_step``: t = t_n): the solver report, the contact state, the fields if computed;
        ``held``: the applied force and the Dirichlet parts' columns (``held_part_columns``)."""
        surface = self.discretization.surface
        w, normals = surface.weights, surface.normals
        contact = level_contact(w, solution, xi, K, compliance, status)
        for name, value in contact.items():
            self.contact[name].append(value)
        d, rigid = contact["penetration"], contact["pressure_rigid"]
        force = -(normals * (w * (compliance + rigid))).sum(axis=1)
        positive = np.maximum(d, 0.0)
        has_contact = d.size > 0
        probe = self.probe
        self.rows.append({
            "step": n, "t": t, "newton_iterations": solution.iterations, "residual": solution.residual,
            "complementarity": solution.complementarity,
            "max_penetration": positive.max() if has_contact else np.nan,
            "mean_penetration": (w @ positive) / w.sum() if has_contact else np.nan,
            "K_min": K.min() if has_contact else np.nan, "K_max": K.max() if has_contact else np.nan,
            "K_probe": K[probe] if probe is not None else np.nan,
            "penetration_probe": d[probe] if probe is not None else np.nan,
            "normal_stress_probe": -(compliance[probe] + rigid[probe]) if probe is not None else np.nan,
            "nodes_separated": int(np.sum(status == SEPARATED)),
            "nodes_in_compliance": int(np.sum(status == IN_COMPLIANCE)),
            "nodes_at_limit": int(np.sum(status == AT_LIMIT)),
            **{f"contact_force_{c}": force[i] for i, c in enumerate(coordinates(self.dim))},
            "contact_area": w[d > 0].sum(), "limit_area": w[status == AT_LIMIT].sum(),
            **held, "substep": substep, "k": k,
        })
        self._times.append(t)
        if ends_step:
            self.completed_steps = n
        if fields is not None:
            self.final = fields
            if ends_step and n in self.field_steps:
                self.fields[n] = fields

    def contact_row(self, row: int = -1) -> dict[str, np.ndarray]:
        """The per-node contact arrays (CONTACT_ARRAYS) of one history row (default: the last)."""
        return {name: np.asarray(self.contact[name][row]) for name in CONTACT_ARRAYS}

    def record_estimate(self, indicators, fields: Fields, companion) -> None:
        """Add the error estimates of the last recorded level to its history row (the estimate_columns): in space
        (:class:`~vpcontact.estimate.indicators.Indicators`; its η_K to that level's ``fields`` too) and in time
        (``companion``, a :class:`~vpcontact.timeloop.companion.CompanionLevel`: η_k(t) and the step's θ)."""
        self.rows[-1].update({"error_estimate": indicators.total,
                              **{f"error_estimate_{term}": float(np.sqrt(indicators.terms[term].sum()))
                                 for term in self.estimate_terms},
                              "time_estimate": companion.estimate, "time_estimate_step": companion.step_estimate})
        fields.error_indicator = np.sqrt(indicators.squared)

    def fail(self, message: str) -> None:
        self.status, self.message = "failed", message

    def finish(self, timings: dict[str, float]) -> None:
        """Close the run with its timings in seconds (setup stages, time loop, total)."""
        if self.status == "running":
            self.status = "complete"
        self.timings = timings
        self.wall_time_s = timings["total"]

    # --- a checkpoint ----------------------------------------------------------------------------
    def arrays(self) -> dict[str, np.ndarray]:
        """The rows so far as named arrays: ``row_<column>`` for each of ``columns`` (int64 for the
        INTEGER_COLUMNS, else float64), ``row_time`` and ``contact_<name>`` (rows, contact nodes) for each of
        the CONTACT_ARRAYS; :meth:`resume` reads them back, bit for bit."""
        rows = len(self.rows)
        arrays = {f"row_{column}": np.array([row[column] for row in self.rows],
                                            dtype=np.int64 if column in INTEGER_COLUMNS else np.float64)
                  for column in self.columns}
        arrays["row_time"] = np.array(self.times, dtype=np.float64)
        arrays.update({f"contact_{name}": np.array(self.contact[name]).reshape(rows, self.contact_nodes)
                       for name in CONTACT_ARRAYS})
        return arrays

    def field_arrays(self) -> dict[int, dict[str, np.ndarray]]:
        """The Fields of each field step kept so far as named arrays (FIELD_NAMES; a field the run has not,
        None, is left out)."""
        return {n: {name: getattr(fields, name) for name in FIELD_NAMES if getattr(fields, name) is not None}
                for n, fields in sorted(self.fields.items())}

    def resume(self, arrays: dict[str, np.ndarray], fields: dict[int, dict[str, np.ndarray]], step: int,
               step_cuts: int, resumed_at: list[int]) -> None:
        """Take back the rows of :meth:`arrays` and the fields of :meth:`field_arrays` (a field left out is
        None), the ``step`` reached, its ``step_cuts`` and the steps where the run was resumed."""
        columns = {column: arrays[f"row_{column}"] for column in self.columns}
        count = len(arrays["row_time"])
        self.rows = [{column: (int(values[i]) if column in INTEGER_COLUMNS else np.float64(values[i]))
                      for column, values in columns.items()} for i in range(count)]
        self.times = [np.float64(t) for t in arrays["row_time"]]
        self.contact = {name: list(arrays[f"contact_{name}"]) for name in CONTACT_ARRAYS}
        self.completed_steps, self.step_cuts, self.resumed_at = step, step_cuts, resumed_at
        for n, data in fields.items():
            self.fields[n] = Fields(**{name: data.get(name) for name in FIELD_NAMES})
        if self.fields:
            self.final = self.fields[max(self.fields)]

    # --- reading ---------------------------------------------------------------------------------
    @property
    def columns(self) -> tuple[str, ...]:
        """The history columns (history.csv) of this run's dimension, and with ``output.error_estimate``
        the estimate_columns of the estimator's terms."""
        held = self.discretization.held_parts if self.discretization is not None else ()
        return history_columns(self.dim, held) + estimate_columns(self.estimate_terms)

    @property
    def steps(self) -> int:
        """Time steps t_n reached (the history has more rows when steps were cut)."""
        return self.completed_steps

    @property
    def times(self) -> np.ndarray:
        """The time t of each history row (a new array)."""
        return np.array(self._times, dtype=float)

    @times.setter
    def times(self, values) -> None:
        self._times = [np.float64(t) for t in values]

    def ends_step(self) -> np.ndarray:
        """Per history row: does it end a time step (t = t_n), rather than being an earlier sub-step
        (:func:`step_ends`)?"""
        return step_ends(self.series("step"), self.completed_steps)

    def end_of_step_rows(self) -> dict[int, int]:
        """Step n -> the history row at t_n, for the steps reached (:func:`end_of_step_rows`)."""
        return end_of_step_rows(self.series("step"), self.completed_steps)

    def series(self, column: str, *, substeps: bool = True) -> np.ndarray:
        """One column of the history (see ``columns``) over the rows done; ``substeps=False``: only the
        rows at the step times t_n. An unknown column is a KeyError naming the valid ones."""
        if column not in self.columns:
            raise _unknown("history column", column, self.columns, (CONTACT_ARRAYS, "contact_history"))
        values = np.array([row[column] for row in self.rows])
        return values if substeps else values[self.ends_step()]

    def contact_history(self, name: str, *, substeps: bool = True) -> np.ndarray:
        """(rows, m) array of a per-node quantity (see CONTACT_ARRAYS); ``substeps=False``: only the
        rows at the step times t_n. An unknown name is a KeyError naming the valid ones."""
        if name not in CONTACT_ARRAYS:
            raise _unknown("contact array", name, CONTACT_ARRAYS, (self.columns, "series"))
        values = np.array(self.contact[name]).reshape(len(self.rows), self.contact_nodes)
        return values if substeps else values[self.ends_step()]

    def snapshot(self, step: int | None = None):
        """The solution at a field step (default: the last computed) as a :class:`~vpcontact.results.norms.Snapshot`,
        for :func:`vpcontact.results.norms.differences`."""
        from .norms import Snapshot

        if step is not None and step not in self.fields:
            kept = ", ".join(map(str, sorted(self.fields))) or "none (output.field_steps)"
            raise UnknownName(f"no fields kept at step {shown(repr(step))}; steps kept: {kept}")
        if self.final is None:
            raise CaseError("no fields computed: the run did not complete a step")
        fields = self.final if step is None else self.fields[step]
        mesh = self.discretization.mesh.mesh
        return Snapshot(mesh.p, mesh.t, fields.displacement, fields.stress)

    def summary(self) -> dict:
        """The content of summary.json (without versions)."""
        final = {}
        if self.rows:
            last = self.rows[-1]
            final = {key: last[key] for key in ("t", "max_penetration", "mean_penetration", "K_min", "K_max", "K_probe",
                                                 "penetration_probe", "normal_stress_probe", "nodes_separated",
                                                 "nodes_in_compliance", "nodes_at_limit")}
            final["contact_force"] = [last[f"contact_force_{c}"] for c in coordinates(self.dim)]
            final.update(contact_area=last["contact_area"], limit_area=last["limit_area"],
                         **balance(last, self.dim, self.discretization.held_parts))
            if self.estimate_terms:
                final["error_estimate"], final["time_estimate"] = last["error_estimate"], last["time_estimate"]
        return {
            "status": self.status, "message": self.message, "dofs": self.dofs, "elements": self.elements,
            "nodes": self.nodes, "contact_nodes": self.contact_nodes, "steps": self.steps,
            "newton_iterations": int(sum(r["newton_iterations"] for r in self.rows)),
            "solver_method": self.method, "solver_reason": self.method_reason, "predicted_costs": self.predicted,
            "method_switch": self.method_switch, "ranks": self.ranks, "ranks_detail": self.ranks_detail,
            "peak_memory_bytes": self.peak_memory_bytes,
            "linear_solves": self.linear_solves,
            "krylov_iterations": self.krylov_iterations, "newton_factorizations": self.newton_factorizations,
            "augmentation_r": self.augmentation, "wall_time_s": self.wall_time_s,
            "timings_s": self.timings, "final": final,
            "history_rows": len(self.rows), "step_cuts": self.step_cuts, "time_cuts": self.time_cuts,
            "time_over_share": self.time_over_share, "resumed_at_steps": list(self.resumed_at),
            **({} if self.adaptation is None else {"adaptation": self.adaptation}),
        }

    @property
    def history(self):
        """The history as a pandas DataFrame (a new one at each access): one row per converged time level,
        the columns of history.csv (``columns``), integer columns as int64. ``result.history[result.ends_step()]``
        keeps the rows at the step times t_n (those of ``series(..., substeps=False)``). See
        :mod:`vpcontact.results.tables`."""
        from .tables import history_table

        return history_table(self)

    def contact_table(self, step: int | None = None):
        """The contact nodes at the end of ``step`` (default: the last step done) as a pandas DataFrame, one
        row per node: coordinates, normal, weight, arc length along Γ3 (2D), penetration, ξ, K, the two
        pressures, σ_ν and the status (a category); see :func:`vpcontact.results.tables.contact_table`."""
        from .tables import contact_table

        return contact_table(self, step)

    @property
    def plot(self):
        """The figures of this run (matplotlib Figures): ``result.plot.time_series(...)``,
        ``.contact_pressure(step=...)``, ``.states(step=...)``, ``.deformed(field=..., scale=...)``; see
        :class:`vpcontact.results.result_plots.ResultPlots`."""
        from .result_plots import ResultPlots

        return ResultPlots(self)

    def to_pyvista(self, step: int | None = None):
        """The body at a field step (default: the last one kept) as a ``pyvista.UnstructuredGrid`` with its
        fields as point and cell data (needs pyvista); see :func:`vpcontact.results.pyvista_grid.body_grid`."""
        from .pyvista_grid import body_grid

        return body_grid(self, step)

    def __repr__(self) -> str:
        """One line: status, dimension, sizes, steps done of those planned, step method and wall time (not the
        arrays); a second one with the message of a run that did not complete."""
        planned = len(self.discretization.times) if self.discretization is not None else "?"
        cuts = f", {self.step_cuts} step cut{'s' * (self.step_cuts > 1)}" if self.step_cuts else ""
        text = (f"Result({self.status}, {self.dim}D, {self.dofs} dofs, {self.contact_nodes} contact nodes, "
                f"{self.steps}/{planned} steps{cuts}, method {self.method or '?'}, {self.wall_time_s:.3g} s)")
        if not self.message:
            return text
        message = self.message if len(self.message) <= REPR_MESSAGE else self.message[:REPR_MESSAGE] + " …"
        return f"{text}\n  {message}"


def level_contact(weights: np.ndarray, solution, xi, K, compliance, status) -> dict[str, np.ndarray]:
    """The per-node contact arrays (CONTACT_ARRAYS) of a converged level: its ``solution``'s penetration, ξ, K, the
    compliance pressure, the rigid pressure λ_i / w_i (``weights``: the nodes' w_i) and the node status (new arrays)."""
    rigid = np.divide(solution.lam, weights, out=np.zeros_like(weights), where=weights > 0)
    values = (solution.d, xi, K, compliance, rigid, status)
    return {name: np.asarray(value).copy() for name, value in zip(CONTACT_ARRAYS, values)}
