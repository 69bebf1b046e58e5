"""The result of a run: time series, per-node contact history and fields at the requested steps.

Conventions: the penetration d = u·ν − g0 (> 0 into the foundation); pressures are forces per unit
length of Γ3 (per unit area in 3D), the compliance part ρK(ξ)p(d) and the rigid part λ_i / w_i;
the normal stress σ_ν = −(compliance + rigid) ≤ 0; the contact force is the resultant the
foundation exerts on the body, −Σ_i w_i (compliance_i + rigid_i) ν_i.

Sub-steps: a step whose Newton iteration fails is cut in halves (``stepping``). Every converged
time level is a row of the history and of the per-node arrays, in time order: a step done whole is
one row (``substep`` 1, ``k`` the case's step), a step cut into s sub-steps is s rows with the same
``step`` n, ``substep`` 1, …, s, their own ``t`` and ``k``, the last one at t_n. Fields are kept per
step n, at t_n. ``series(..., substeps=False)`` and ``contact_history(..., substeps=False)`` keep
only the rows at the step times t_n.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED

HISTORY_COLUMNS = (
    "step", "t", "newton_iterations", "residual", "complementarity", "max_penetration", "mean_penetration",
    "K_min", "K_max", "K_probe", "penetration_probe", "normal_stress_probe", "nodes_separated",
    "nodes_in_compliance", "nodes_at_limit", "contact_force_x", "contact_force_y", "substep", "k",
)
#: History columns holding integers (the others are floats).
INTEGER_COLUMNS = ("step", "newton_iterations", "nodes_separated", "nodes_in_compliance", "nodes_at_limit", "substep")
CONTACT_ARRAYS = ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid", "status")


@dataclass
class Fields:
    """Displacement at the nodes (nnodes, 2); per element: in-plane stress (nelements, 2, 2), the
    out-of-plane σ33 of the elastic response and the von Mises stress of the 3D tensor; with a
    viscoplastic law or an initial stress, the history z (nelements, 2, 2) of the step, so that
    stress = ℰε(u) + z (None otherwise: z = 0)."""

    displacement: np.ndarray
    stress: np.ndarray
    stress33: np.ndarray
    von_mises: np.ndarray
    z: np.ndarray | None = None


@dataclass
class Result:
    """Everything a run computed. Arrays per contact node are (rows, m): one row per converged time
    level, sub-steps included (see the module's docstring)."""

    dofs: int
    elements: int
    nodes: int
    contact_nodes: int
    probe: int | None
    field_steps: set[int]
    augmentation: float
    times: list = field(default_factory=list)
    rows: list = field(default_factory=list)
    contact: dict = field(default_factory=lambda: {name: [] for name in CONTACT_ARRAYS})
    fields: dict[int, Fields] = field(default_factory=dict)
    final: Fields | None = None
    status: str = "running"  # then "complete", "failed" or "interrupted"
    message: str = ""
    wall_time_s: float = 0.0
    timings: dict = field(default_factory=dict)
    method: str = ""
    linear_solves: int = 0  # solves with a factored matrix in the time loop
    problem: object = None  # the Problem solved: mesh, contact surface, operators
    completed_steps: int = 0  # time steps t_n reached
    step_cuts: int = 0  # halvings of a step or sub-step whose Newton iteration failed
    resumed_at: list = field(default_factory=list)  # steps at which the run was resumed from a checkpoint

    @classmethod
    def start(cls, problem, solver) -> "Result":
        steps = problem.case.output.field_steps
        count = len(problem.times)
        wanted = {"all": set(range(1, count + 1)), "final": {count}, "none": set()}.get(steps) if isinstance(steps, str) else set(steps)
        return cls(dofs=problem.basis.N, elements=problem.mesh.mesh.t.shape[1], nodes=problem.mesh.mesh.p.shape[1],
                   contact_nodes=problem.surface.size, probe=problem.probe, field_steps=wanted,
                   augmentation=solver.r, method=solver.name, problem=problem)

    # --- filling in ------------------------------------------------------------------------------
    def record(self, n, t, solution, fields: Fields | None, *, xi, K, compliance, status, substep: int = 1,
               k: float = float("nan"), ends_step: bool = True):
        """Store a converged time level of step n (the step itself, or its sub-step ``substep`` of
        length k; ``ends_step``: t = t_n): the solver report, the contact state, the fields if computed."""
        w, normals = self.problem.surface.weights, self.problem.surface.normals
        rigid = np.divide(solution.lam, w, out=np.zeros_like(w), where=w > 0)
        d = solution.d
        for name, value in zip(CONTACT_ARRAYS, (d, xi, K, compliance, rigid, status)):
            self.contact[name].append(np.asarray(value).copy())
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
            "contact_force_x": force[0], "contact_force_y": force[1], "substep": substep, "k": k,
        })
        self.times.append(t)
        if ends_step:
            self.completed_steps = n
        if fields is not None:
            self.final = fields
            if ends_step and n in self.field_steps:
                self.fields[n] = fields

    def fail(self, message: str) -> None:
        self.status, self.message = "failed", message

    def finish(self, timings: dict[str, float]) -> None:
        """Close the run with its timings in seconds (setup stages, time loop, total)."""
        if self.status == "running":
            self.status = "complete"
        self.timings = timings
        self.wall_time_s = timings["total"]

    # --- reading ---------------------------------------------------------------------------------
    @property
    def steps(self) -> int:
        """Time steps t_n reached (the history has more rows when steps were cut)."""
        return self.completed_steps

    def ends_step(self) -> np.ndarray:
        """Per history row: does it end a time step (t = t_n), rather than being an earlier sub-step?"""
        times = self.problem.times
        return np.array([row["t"] == times[row["step"] - 1] for row in self.rows], dtype=bool)

    def series(self, column: str, *, substeps: bool = True) -> np.ndarray:
        """One column of the history (see HISTORY_COLUMNS) over the rows done; ``substeps=False``:
        only the rows at the step times t_n."""
        values = np.array([row[column] for row in self.rows])
        return values if substeps else values[self.ends_step()]

    def contact_history(self, name: str, *, substeps: bool = True) -> np.ndarray:
        """(rows, m) array of a per-node quantity (see CONTACT_ARRAYS); ``substeps=False``: only the
        rows at the step times t_n."""
        values = np.array(self.contact[name]).reshape(len(self.rows), self.contact_nodes)
        return values if substeps else values[self.ends_step()]

    def snapshot(self, step: int | None = None):
        """The solution at a field step (default: the last computed) as a :class:`~vpcontact.norms.Snapshot`,
        for :func:`vpcontact.norms.differences`."""
        from .norms import Snapshot

        fields = self.final if step is None else self.fields[step]
        mesh = self.problem.mesh.mesh
        return Snapshot(mesh.p, mesh.t, fields.displacement, fields.stress)

    def summary(self) -> dict:
        """The content of summary.json (without versions)."""
        final = {}
        if self.rows:
            last = self.rows[-1]
            final = {key: last[key] for key in ("t", "max_penetration", "mean_penetration", "K_min", "K_max", "K_probe",
                                                 "penetration_probe", "normal_stress_probe", "nodes_separated",
                                                 "nodes_in_compliance", "nodes_at_limit")}
            final["contact_force"] = [last["contact_force_x"], last["contact_force_y"]]
        return {
            "status": self.status, "message": self.message, "dofs": self.dofs, "elements": self.elements,
            "nodes": self.nodes, "contact_nodes": self.contact_nodes, "steps": self.steps,
            "newton_iterations": int(sum(r["newton_iterations"] for r in self.rows)),
            "solver_method": self.method, "linear_solves": self.linear_solves, "augmentation_r": self.augmentation, "wall_time_s": self.wall_time_s,
            "timings_s": self.timings, "final": final,
            "history_rows": len(self.rows), "step_cuts": self.step_cuts, "resumed_at_steps": list(self.resumed_at),
        }
