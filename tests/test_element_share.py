"""Each MPI rank's elements (vpcontact.parallel.elements): what a rank computes on its elements alone is the whole
computation's there, checked in one process on a partition of a coated half disc into two parts (no MPI needed:
each part is computed as its rank would, the sum over the ranks done here).

- ε, σ = ℰε + z and 𝒢(σ, ε) of a part, with ℰ varying in space and a different viscoplastic law in each region
  (RegionalViscoplastic), and a law of the element centroids x (AtCentroids), equal the whole arrays at its elements
  bit for bit;
- the history's nodal force Bᵀz of the two parts sums to the whole one (to rounding: the same terms, added in
  another order);
- in one process the share is every element, and its force and strains are the whole ones bit for bit;
- the bytes of element history ``vpcontact check`` counts are those the time loop holds.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np

from vpcontact import build_problem, load_case
from vpcontact.fem.assembly import element_strain, stress_force
from vpcontact.laws.materials import AtCentroids
from vpcontact.parallel.elements import ElementShare
from vpcontact.parallel.partition import NodePartition
from vpcontact.parallel.ranks import Ranks
from vpcontact.timeloop.loop import TimeLoop
from vpcontact.timeloop.state import element_history_bytes

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def coated_problem():
    """The gallery's coated half disc with a relaxing core and a Perzyna coating of modulus varying in space."""
    case = tomllib.loads((EXAMPLES / "coated_ball.toml").read_text())
    core, coating = case["material"]
    core["viscoplastic"] = {"law": "relaxation", "mu": 2.0, "E_inf": 600.0, "nu_inf": 0.3}
    coating.update(E="100*(1 + 0.5*y)", viscoplastic={"law": "perzyna", "eta": 0.5, "yield_stress": 0.5})
    case["mesh"]["h"] = 0.1
    return build_problem(load_case(case))


def halves(problem) -> list[ElementShare]:
    """The shares of two ranks owning the nodes left and right of x = 0.4 (each computed as its rank would; the
    reductions among ranks are left to the caller)."""
    mesh = problem.mesh.mesh
    owner = (mesh.p[0] > 0.4).astype(np.int64)
    shares = []
    for rank in (0, 1):
        ranks = Ranks(rank, 2, None)  # the reductions are this rank's own values: the test adds them
        partition = NodePartition(ranks, owner, np.argsort(np.argsort(owner, kind="stable")), 0, 0)
        shares.append(ElementShare.of(problem, partition))
    return shares


def test_a_rank_computes_on_its_elements_what_the_whole_computes_there():
    problem = coated_problem()
    rng = np.random.default_rng(3)
    u = rng.normal(scale=0.01, size=problem.basis.N)
    z = rng.normal(size=element_strain(problem.basis, u).shape)
    strain = element_strain(problem.basis, u)
    sigma = problem.elasticity.stress(strain) + z
    rate = problem.viscoplastic(sigma, strain)
    shares = halves(problem)
    assert sorted(np.concatenate([share.elements for share in shares])) == list(range(strain.shape[-1]))
    assert min(share.count for share in shares) > 0
    for share in shares:
        mine = share.elements
        np.testing.assert_array_equal(share.strain(u), strain[..., mine])
        np.testing.assert_array_equal(share.stress(share.strain(u), share.mine(z)), sigma[..., mine])
        np.testing.assert_array_equal(share.viscoplastic(sigma[..., mine], strain[..., mine]), rate[..., mine])
    whole = stress_force(problem.basis, z)
    summed = sum(share.force(share.mine(z)) for share in shares)
    np.testing.assert_allclose(summed, whole, rtol=0, atol=1e-13 * np.abs(whole).max())


def test_a_law_of_the_centroids_is_taken_at_a_rank_s_elements():
    problem = coated_problem()
    centroids = problem.mesh.mesh.p[:, problem.mesh.mesh.t].mean(axis=1)
    law = AtCentroids(lambda sigma, strain, x: -(1.0 + x[0]) * sigma, centroids)
    sigma = np.random.default_rng(4).normal(size=(2, 2, centroids.shape[1]))
    for share in halves(problem):
        mine = share.elements
        np.testing.assert_array_equal(law.on(mine)(sigma[..., mine], sigma[..., mine]), law(sigma, sigma)[..., mine])


def test_one_process_holds_every_element_and_computes_the_whole_bit_for_bit():
    problem = coated_problem()
    share = ElementShare.of(problem, None)
    u = np.random.default_rng(5).normal(size=problem.basis.N)
    z = element_strain(problem.basis, u)
    assert share.count == z.shape[-1] and share.mine(z) is z and share.whole(z) is z
    np.testing.assert_array_equal(share.strain(u), element_strain(problem.basis, u))
    np.testing.assert_array_equal(share.force(z), stress_force(problem.basis, z))


def test_the_element_history_a_check_counts_is_what_the_loop_holds():
    """element_history_bytes (vpcontact check's share of a viscoplastic body) against the element arrays the time
    loop of the coated body holds after each step: z, 𝒢, z + h𝒢 and the level's ε and σ, plus one for 𝒢's
    temporaries."""
    problem = coated_problem()
    loop = TimeLoop(problem)
    held = []

    def after_step(loop: TimeLoop) -> None:
        state, level = loop.state, loop._level_without_fields  # (u, ε, σ, z); None at a field step (kept as fields)
        if level is not None:
            arrays = [state.z, state.rate, state.z_after(problem.k), *level[1:3]]
            held.append(sum(array.nbytes for array in arrays))

    assert loop.run(after_step=after_step).status == "complete"
    estimate = element_history_bytes(problem.mesh.mesh.t.shape[1], problem.mesh.dim)
    assert len(held) == len(problem.times) - len(loop.result.fields) > 0
    assert max(held) <= estimate <= 1.25 * min(held)
