"""The result of a run: time series, per-node contact history and fields at the requested steps.

Conventions: the penetration d = u·ν − g0 (> 0 into the foundation); pressures are forces per unit
length of Γ3 (per unit area in 3D), the compliance part ρK(ξ)p(d) and the rigid part λ_i / w_i;
the normal stress σ_ν = −(compliance + rigid) ≤ 0; the contact force is the resultant the
foundation exerts on the body, −Σ_i w_i (compliance_i + rigid_i) ν_i.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED

HISTORY_COLUMNS = (
    "step", "t", "newton_iterations", "residual", "complementarity", "max_penetration", "mean_penetration",
    "K_min", "K_max", "K_probe", "penetration_probe", "normal_stress_probe", "nodes_separated",
    "nodes_in_compliance", "nodes_at_limit", "contact_force_x", "contact_force_y",
)
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
    """Everything a run computed. Arrays per contact node are (steps done, m)."""

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
    status: str = "running"
    message: str = ""
    wall_time_s: float = 0.0
    timings: dict = field(default_factory=dict)
    method: str = ""
    linear_solves: int = 0  # solves with a factored matrix in the time loop
    problem: object = None  # the Problem solved: mesh, contact surface, operators

    @classmethod
    def start(cls, problem, solver) -> "Result":
        steps = problem.case.output.field_steps
        count = len(problem.times)
        wanted = {"all": set(range(1, count + 1)), "final": {count}, "none": set()}.get(steps) if isinstance(steps, str) else set(steps)
        return cls(dofs=problem.basis.N, elements=problem.mesh.mesh.t.shape[1], nodes=problem.mesh.mesh.p.shape[1],
                   contact_nodes=problem.surface.size, probe=problem.probe, field_steps=wanted,
                   augmentation=solver.r, method=solver.name, problem=problem)

    # --- filling in ------------------------------------------------------------------------------
    def record(self, n, t, solution, fields: Fields | None, *, xi, K, compliance, status):
        """Store step n: the solver report, the contact state and the fields if computed."""
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
            "contact_force_x": force[0], "contact_force_y": force[1],
        })
        self.times.append(t)
        if fields is not None:
            self.final = fields
            if n in self.field_steps:
                self.fields[n] = fields

    def fail(self, n, t, solution) -> None:
        self.status = "failed"
        self.message = (f"step {n} (t = {t:g}) failed: {solution.message}; residual {solution.residual:.3e}, "
                        f"complementarity {solution.complementarity:.3e}, active nodes {int(solution.active.sum())}")

    def finish(self, timings: dict[str, float]) -> None:
        """Close the run with its timings in seconds (setup stages, time loop, total)."""
        if self.status == "running":
            self.status = "complete"
        self.timings = timings
        self.wall_time_s = timings["total"]

    # --- reading ---------------------------------------------------------------------------------
    @property
    def steps(self) -> int:
        return len(self.rows)

    def series(self, column: str) -> np.ndarray:
        """One column of the history (see HISTORY_COLUMNS) over the steps done."""
        return np.array([row[column] for row in self.rows])

    def contact_history(self, name: str) -> np.ndarray:
        """(steps done, m) array of a per-node quantity (see CONTACT_ARRAYS)."""
        return np.array(self.contact[name]).reshape(self.steps, self.contact_nodes)

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
        }
