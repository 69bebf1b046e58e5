"""A time level carried from a mesh to its refinement (:class:`~vpcontact.mesh.refinement.Lineage`): what a run
that adapts its mesh between time steps (:mod:`.during_run`) continues from, as a time loop's snapshot
(:class:`~vpcontact.timeloop.snapshot.LoopSnapshot`) on the new mesh.

What each transfer keeps:

- **z and 𝒢** (the viscoplastic memory, per element): each new element takes its parent's value, bit for bit. The
  piecewise constant field is the same function, so ∫_Ω z and every norm of z are conserved exactly.
- **ξ and the other per-node arrays of Γ3** (the last level's and every history row's): the P1 interpolant of the
  old nodal values at the new nodes. On nested meshes that is the same function along Γ3, and the lumped weights
  integrate a P1 function exactly, so Σ_i w_i ξ_i (∫_Γ3 ξ) is conserved to rounding where Γ3 is flat; on a
  curved Γ3 the new nodes move onto the surface and the weights change by O(h²). The rigid reaction λ is
  interpolated as a pressure, λ_i / w_i. K is not interpolated: K = K(ξ) at every node, from the carried ξ;
  the status is kept where all the parent nodes share it, else it is SEPARATED or IN_COMPLIANCE by the sign of
  the interpolated d (AT_LIMIT needs every parent at the limit).
- **u** (per node): P1 interpolation, the same function. In this model u is not a history variable (u_n solves
  the step problem from ξ_{n−1} and z_n), so the carried u only starts the next Newton iteration; the trend
  that extrapolates it is dropped, and the solver's kept state too (it belongs to the old matrices).
- **The second-order companion of the estimate in time** (:mod:`vpcontact.timeloop.companion`): its ξ̃ and d̃ as ξ,
  its z̃ and 𝒢̃ as z, its ũ − u as u.
- **Fields of the steps kept so far**: the displacement interpolated, the element fields taken from the parent
  (the same functions: the coarse solution drawn on the new mesh), the error indicator scaled by the square root
  of the element's share of its parent's area or volume, so that Σ_T η_T² is conserved.

Where every old value an interpolated value is made of is the same, that value is copied: a uniform state
survives any refinement bit for bit. The history rows (forces, areas, counters) do not depend on the mesh and
are kept as they are.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..laws.contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED
from ..mesh.refinement import Lineage
from ..mesh.simplex import measures
from ..timeloop.snapshot import LoopSnapshot

#: The last level's trend (how it changed since the level before), not carried: the first step on the new mesh
#: starts from the carried level itself, not extrapolated.
DROPPED = ("trend_u", "trend_lam", "trend_d")


def interpolated(weights: sp.csr_matrix, values: np.ndarray) -> np.ndarray:
    """``weights @ values`` (rows of ``values``: the old nodes), each row whose old values with a nonzero weight are
    all the same given that value exactly (every row of ``weights`` has an entry)."""
    values = np.asarray(values, dtype=float)
    flat = values.reshape(values.shape[0], -1)
    result = np.asarray(weights @ flat)
    gathered = flat[weights.indices]
    starts = weights.indptr[:-1]
    low, high = np.minimum.reduceat(gathered, starts), np.maximum.reduceat(gathered, starts)
    same = low == high
    result[same] = low[same]
    return result.reshape((weights.shape[0],) + values.shape[1:])


class Transfer:
    """The transfer of a level from the problem ``old`` to the problem ``new`` on its refinement (``lineage``)."""

    def __init__(self, old, new, lineage: Lineage):
        self.old, self.new, self.lineage = old, new, lineage
        rows = lineage.interpolation[new.surface.nodes]
        self.on_surface = rows[:, old.surface.nodes].tocsr()  # Γ3's new nodes from its old ones
        if not np.allclose(np.asarray(self.on_surface.sum(axis=1)).ravel(), 1.0, rtol=0.0, atol=1e-9):
            raise ValueError("the new contact nodes do not lie on the old contact facets: not a refinement of Γ3")
        old_t, new_t = old.mesh.mesh, new.mesh.mesh
        self.volume_ratio = measures(new_t.p, new_t.t) / measures(old_t.p, old_t.t)[lineage.parent]

    # --- per-node and per-element values ------------------------------------------------------------
    def surface(self, values: np.ndarray) -> np.ndarray:
        """Values at Γ3's old nodes (m_old,) or history rows of them (rows, m_old) at its new nodes."""
        values = np.asarray(values)
        if values.ndim == 1:
            return interpolated(self.on_surface, values)
        return interpolated(self.on_surface, values.T).T

    def nodal(self, values: np.ndarray) -> np.ndarray:
        """Values at the old nodes (nodes, ...) at the new ones."""
        return interpolated(self.lineage.interpolation, values)

    def elemental(self, values: np.ndarray, axis: int = 0) -> np.ndarray:
        """Values per old element (along ``axis``) on the new elements: their parents'."""
        return np.take(np.asarray(values), self.lineage.parent, axis=axis)

    def status(self, status: np.ndarray, d: np.ndarray) -> np.ndarray:
        """The contact status at the new nodes (rows, m_new), from the old one and the carried d (rows, m_new)."""
        at_limit = self.surface((np.asarray(status) == AT_LIMIT).astype(float)) == 1.0
        return np.where(at_limit, AT_LIMIT, np.where(d > 0.0, IN_COMPLIANCE, SEPARATED)).astype(np.int8)

    def pressure_force(self, lam: np.ndarray) -> np.ndarray:
        """A nodal force on Γ3 (λ: the pressure times the node's weight) carried as a pressure."""
        old_w, new_w = self.old.surface.weights, self.new.surface.weights
        pressure = np.divide(lam, old_w, out=np.zeros_like(old_w), where=old_w > 0)
        return self.surface(pressure) * new_w

    def displacement(self, free_values: np.ndarray, t: float) -> np.ndarray:
        """The whole displacement (dofs,) on the new mesh from its free dofs' values on the old one at time t (the
        held dofs at their prescribed values there)."""
        old = self.old
        u = np.zeros(old.basis.N)
        u[old.free] = free_values
        if old.constraints.moves:
            u[old.constraints.held] = old.constraints(t)
        return self._whole(u)

    def free_difference(self, free_values: np.ndarray) -> np.ndarray:
        """A difference of two displacements that agree at the held dofs, given at the free ones, on the new mesh's
        free dofs (P1 interpolation)."""
        u = np.zeros(self.old.basis.N)
        u[self.old.free] = free_values
        return self._whole(u)[self.new.free]

    def _whole(self, u: np.ndarray) -> np.ndarray:
        """A displacement at every dof of the old mesh, interpolated at every dof of the new one."""
        whole = np.zeros(self.new.basis.N)
        whole[self.new.basis.nodal_dofs] = self.nodal(u[self.old.basis.nodal_dofs].T).T
        return whole

    # --- a whole snapshot --------------------------------------------------------------------------
    def snapshot(self, snapshot: LoopSnapshot) -> LoopSnapshot:
        """``snapshot`` (of a loop on the old problem) on the new mesh (see the module docstring; its ``rigid``, Zᵀu
        on the old loop's rigid motions, is left for the new loop to compute again)."""
        arrays = {key: value for key, value in snapshot.arrays.items()
                  if not key.startswith("solver_") and key not in DROPPED}
        law = self.new.law  # K per level, as the loop computes it (a law may vary along Γ3)
        t = float(arrays["row_time"][-1]) if len(arrays["row_time"]) else self.old.times.start
        for name in ("xi", "companion_xi", "companion_d"):
            if name in arrays:
                arrays[name] = self.surface(arrays[name])
        for name in ("z", "rate", "companion_z", "companion_rate"):  # (d, d, elements)
            if name in arrays:
                arrays[name] = self.elemental(arrays[name], axis=-1)
        if "companion_difference" in arrays:  # ũ − u of the error estimate in time: 0 at the held dofs
            arrays["companion_difference"] = self.free_difference(arrays["companion_difference"])
        if "previous_lam" in arrays:
            arrays["previous_d"] = self.surface(arrays["previous_d"])
            arrays["previous_lam"] = self.pressure_force(arrays["previous_lam"])
            arrays["previous_active"] = self.surface(arrays["previous_active"].astype(float)) == 1.0
        if "previous_u" in arrays:
            arrays["previous_u"] = self.displacement(arrays["previous_u"], t)[self.new.free]
        contact = {name[8:]: arrays[name] for name in arrays if name.startswith("contact_")}
        for name, values in contact.items():
            if name not in ("status", "K"):
                arrays[f"contact_{name}"] = self.surface(values)
        arrays["contact_K"] = np.array([law.K(xi) for xi in arrays["contact_xi"]]).reshape(-1, self.new.surface.size)
        arrays["contact_status"] = self.status(contact["status"], arrays["contact_penetration"])
        fields = {step: self._fields(values) for step, values in snapshot.fields.items()}
        return LoopSnapshot(arrays, dict(snapshot.meta), fields)

    def _fields(self, values: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The arrays of a step's Fields on the new mesh."""
        carried = {}
        for name, value in values.items():
            if name == "displacement":
                carried[name] = self.nodal(value)
            elif name == "error_indicator":
                carried[name] = self.elemental(value) * np.sqrt(self.volume_ratio)
            else:
                carried[name] = self.elemental(value)
        return carried

