"""The uniaxial closed form of a block on rollers pressed onto the soft layer: an independent reference, without
finite elements, for the solver under traction control (a top traction s(t)) or displacement control (a
prescribed top displacement w(t)).

The setting. A block of height H whose bottom face z = 0, of area A, is the contact part Γ3 on the layer
(thickness g, stiffness K(ξ) with its history, compliance p(r), factor ρ); its side faces are on rollers (the
normal component held: u_x = 0 on the x faces, u_y = 0 on the y faces; no shear there); its top face z = H is
either pressed by the traction (0, 0, −s(t)), s ≥ 0, or moved by u_z = w(t) (down: w < 0). In 2D (plane strain
or plane stress) the vertical axis is y and A is the width (per unit thickness): read z as y below.

The solution. u = (0, 0, u_z(z)) with u_z linear in z: the strain ε_zz = (u_z(H) − u_z(0)) / H is uniform, the
stress too, σ_zz = M ε_zz and σ_xx = σ_yy = L ε_zz, with the constrained modulus M and the lateral one L:

    3D, 2D plane strain:  M = E (1 − ν) / ((1 + ν)(1 − 2ν)),  L = E ν / ((1 + ν)(1 − 2ν))  (σ33 = L ε_zz in 2D),
    2D plane stress:      M = E / (1 − ν²),                    L = E ν / (1 − ν²)          (σ33 = 0).

It is in equilibrium, satisfies the rollers (u·n = 0, no shear on the sides) and, the bottom being flat with the
normal ν = −e_z and no initial gap, has the same penetration d = u·ν = −u_z(0) at every point of Γ3. Being linear
it lies in the P1 space, and the consistent nodal loads of a uniform traction and the contact weights
w_i = ∫ φ_i over Γ3 make it the solution of the discrete problem too, at every node, on any mesh: the reference is
that of the computed solution, not of a limit h → 0.

The equation of a time step. The time loop (vpcontact.timeloop.loop, vpcontact.solvers.base) solves at t_n, with
k = t_n − t_{n−1}::

    A u + Σ_i N_iᵀ (w_i ρ K(ξ_i^{n−1} + k d_i⁺) p(d_i) + λ_i) = F(t_n),
    λ_i ≥ 0, d_i ≤ g, λ_i (d_i − g) = 0,   ξ_i^n = ξ_i^{n−1} + k (d_i^n)⁺,

ρ being ``contact.rho`` (ρK is the paper's K_ρ, and the ``K`` that vpcontact reports). Divided by w_i, the nodal
equation of the uniform state is a balance of pressures on the bottom,

    ρ K(ξ_{n−1} + k d⁺) p(d) + λ/w = q(d),

between what the layer (compliance, then the rigid base) carries and what the block demands, its compression
−σ_zz:

    traction control:      q = s(t_n)                      (−σ_zz = s whatever d is),
    displacement control:  q = M (−w(t_n) − d) / H         (ε_zz = (w + d) / H).

Hence, per step: where q(0) ≤ 0 nothing presses the layer: d = −w ≤ 0 under displacement control (the block is
lifted off the layer), d = 0 under a zero traction (the block rests on the unloaded layer, vpcontact's rest
position after a loaded level); a negative traction pulls the block off (no solution). Else, when the layer
crushed to g still carries less than the demand, ρK(ξ_{n−1} + k g) p(g) ≤ q(g), the rigid base takes the rest:
d = g, λ/w = q(g) − ρK(ξ_{n−1} + k g) p(g); otherwise d ∈ (0, g) is the root of ρK(ξ_{n−1} + k d) p(d) = q(d)
(Brent's method to rounding) and λ = 0. The root is unique when ρK(ξ_{n−1} + k d) p(d) increases with d, which
holds for the power law with β ≥ −1 and p = (r⁺)^m (c_v d (1 + α(ξ + k d))^β has the derivative
c_v (1 + αξ')^(β−1) (1 + αξ + (1 + β) α k d) > 0); for a law that is not monotone there, Brent's root is one of
several and the solver may find another. Then ξ_n = ξ_{n−1} + k d⁺.

What follows from d and the pressures: σ_zz = −(compliance + rigid pressure) (= −s, or M (w + d) / H), the side
stress L ε_zz, the top's displacement u_z(H) = −d + σ_zz H / M (= w under displacement control), the force on the
body through its top face σ_zz A (the reaction of the prescribed displacement: negative, downward, while the top
presses), the foundation's force on the body (compliance + rigid) A (upward, its opposite), the contact area
(the measure of Γ3 where d > 0: A or 0) and the area at the rigid limit (A or 0).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import brentq


@dataclass(frozen=True)
class Block:
    """The block's material and size: Young's modulus E, Poisson's ratio ν, height H, bottom area A (2D: the
    width); ``hypothesis`` "3d", "plane_strain" or "plane_stress"."""

    E: float
    nu: float
    height: float
    area: float
    hypothesis: str = "3d"

    @property
    def modulus(self) -> float:
        """M, σ_zz = M ε_zz in uniaxial strain (the constrained modulus; E / (1 − ν²) in plane stress)."""
        E, nu = self.E, self.nu
        if self.hypothesis == "plane_stress":
            return E / (1.0 - nu * nu)
        return E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))

    @property
    def lateral(self) -> float:
        """L, the side stress per unit ε_zz: σ_xx = σ_yy = L ε_zz (in 2D σ_xx, and σ33 = L ε_zz in plane strain)."""
        E, nu = self.E, self.nu
        if self.hypothesis == "plane_stress":
            return E * nu / (1.0 - nu * nu)
        return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


@dataclass(frozen=True)
class Layer:
    """The soft layer: K(ξ) and p(r) as plain functions of a float, its thickness g (inf: no rigid base) and
    the factor ρ of K (``contact.rho``)."""

    K: Callable[[float], float]
    p: Callable[[float], float]
    g: float
    rho: float = 1.0

    def pressure(self, xi_prev: float, k: float, d: float) -> float:
        """The compliance pressure ρ K(ξ_prev + k d⁺) p(d) (0 where d ≤ 0: p(r) = 0 there)."""
        return self.rho * self.K(xi_prev + k * max(d, 0.0)) * self.p(d) if d > 0.0 else 0.0


#: The columns of a reference, one row per time step t_1 … t_N.
COLUMNS = ("t", "k", "penetration", "xi", "K", "pressure_compliance", "pressure_rigid", "status", "stress_zz",
           "stress_side", "strain_zz", "displacement_top", "top_force", "contact_force", "contact_area", "limit_area")


def under_traction(block: Block, layer: Layer, times, s: Callable[[float], float]) -> pd.DataFrame:
    """The steps t_1 … t_N of ``times`` (t_0 … t_N, t_0 the initial state u = 0, ξ = 0) of the block pressed by
    the top traction (0, 0, −s(t)), s ≥ 0: :data:`COLUMNS` (see :func:`steps`)."""
    def demand(t):
        pressure = float(s(t))
        if pressure < 0.0:
            raise ValueError(f"s({t:g}) = {pressure:g} < 0 pulls the block off the layer: no solution")
        return (lambda d: pressure), math.inf
    return steps(block, layer, times, demand)


def under_displacement(block: Block, layer: Layer, times, w: Callable[[float], float]) -> pd.DataFrame:
    """The steps t_1 … t_N of ``times`` (t_0 … t_N) of the block whose top is moved by u_z = w(t) (down: w < 0):
    :data:`COLUMNS` (see :func:`steps`)."""
    M, H = block.modulus, block.height

    def demand(t):
        top = float(w(t))
        return (lambda d: M * (-top - d) / H), -top  # d ≤ −w: the block is not stretched by the layer
    return steps(block, layer, times, demand)


def steps(block: Block, layer: Layer, times, demand) -> pd.DataFrame:
    """The closed form at each step (the module's docstring): ``demand(t)`` gives the pressure q(d) the block
    demands of the bottom at t and an upper bound of d (inf: none but g). Columns: t, the step length k, the
    penetration d, ξ, K (ρK(ξ_n), as vpcontact reports it), the compliance and rigid pressures, the node status
    (0 separated, 1 in compliance, 2 at the limit), σ_zz, the side stress, ε_zz, the top's displacement u_z(H),
    the force σ_zz A on the body through its top face, the foundation's force on the body (upward, > 0), the
    contact area and the area at the rigid limit."""
    times = np.asarray(times, dtype=float)
    M, H, A = block.modulus, block.height, block.area
    xi, rows = 0.0, []
    for t_prev, t in itertools.pairwise(times):
        k = t - t_prev
        q, bound = demand(t)
        d, rigid = _penetration(layer, xi, k, q, bound)
        compliance = layer.pressure(xi, k, d)
        xi += k * max(d, 0.0)
        stress = -(compliance + rigid)
        strain = stress / M
        status = 0 if d <= 0.0 else 2 if rigid > 0.0 else 1
        areas = (A if d > 0.0 else 0.0, A if status == 2 else 0.0)
        rows.append((t, k, d, xi, layer.rho * layer.K(xi), compliance, rigid, status, stress, block.lateral * strain,
                     strain, -d + strain * H, stress * A, -stress * A, *areas))
    return pd.DataFrame(rows, columns=COLUMNS)


def _penetration(layer: Layer, xi: float, k: float, q: Callable[[float], float], bound: float) -> tuple[float, float]:
    """(d, λ/w) of a step from ξ_{n−1} = ``xi``: the case analysis of the module's docstring."""
    if q(0.0) <= 0.0:  # nothing presses the layer: lifted off by −bound ≥ 0, or resting on it (bound = inf)
        return (bound if math.isfinite(bound) else 0.0), 0.0

    def excess(d):  # > 0: the layer carries less than the block demands
        return q(d) - layer.pressure(xi, k, d)

    if math.isfinite(layer.g) and layer.g <= bound and excess(layer.g) >= 0.0:
        return layer.g, excess(layer.g)
    upper = min(layer.g, bound)
    if not math.isfinite(upper):  # no rigid base, a traction: bracket the root by doubling
        upper = 1e-6
        while excess(upper) > 0.0:
            upper *= 2.0
            if upper > 1e300:
                raise ValueError("the layer never carries the demanded pressure: no penetration found")
    if excess(upper) == 0.0:
        return upper, 0.0
    return brentq(excess, 0.0, upper, xtol=1e-16 * upper, rtol=4.0 * np.finfo(float).eps, maxiter=500), 0.0
