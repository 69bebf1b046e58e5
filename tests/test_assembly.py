"""The NumPy assembly (fem/kernels.py behind assembly.py) gives scikit-fem's matrices and vectors to rounding.

The reference is scikit-fem's forms as vpcontact assembled with them before (kept in
benchmarks/assembly.py, which times the two): the stiffness for one material and for E, ν per
element, plane strain and plane stress, triangles and tetrahedra; ε(u) and Bᵀz; F(t) of tractions
and body forces. The stiffness is summed in chunks: a chunk of 7 elements gives the same matrix as
one chunk, and the memory it needs stays below the entries of all elements at once.
"""

import importlib.util
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from skfem import Basis, FacetBasis

import vpcontact
from vpcontact.errors import CaseError
from vpcontact.fem import kernels
from vpcontact.mesh import simplex
from vpcontact.fem.assembly import LoadVector, displacement_space, element_strain, stiffness, stress_force
from vpcontact.laws.elasticity import Elasticity
from vpcontact.mesh import block, half_disc, quarter_ball

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
sys.path.insert(0, str(BENCHMARKS))  # the benchmark imports its folder's modules, as when it runs as a script
_spec = importlib.util.spec_from_file_location("assembly_benchmark", BENCHMARKS / "assembly.py")
reference = importlib.util.module_from_spec(_spec)  # the scikit-fem forms vpcontact used before: the reference
_spec.loader.exec_module(reference)

MESHES = {"half disc": lambda: half_disc(0.15), "quarter ball": lambda: quarter_ball(0.35),
          "block": lambda: block(2.0, 1.0, 0.5, 0.25)}
HYPOTHESES = {"half disc": ("plane_strain", "plane_stress"), "quarter ball": (None,), "block": (None,)}
CASES = [(name, hypothesis) for name in MESHES for hypothesis in HYPOTHESES[name]]


def relative(new, old) -> float:
    """max |new − old| / max |old| (sparse or dense)."""
    difference = abs(new - old)
    return float(difference.max() / abs(old).max())


@pytest.fixture(scope="module", params=list(MESHES))
def mesh_and_basis(request):
    mesh = MESHES[request.param]()
    return request.param, mesh, displacement_space(mesh)


def per_element(basis, low, high, seed=0):
    return np.random.default_rng(seed).uniform(low, high, basis.nelems)


@pytest.mark.parametrize("name, hypothesis", CASES)
@pytest.mark.parametrize("varying", [False, True], ids=["one material", "E and nu per element"])
def test_the_stiffness_is_scikit_fems_to_rounding(name, hypothesis, varying):
    mesh = MESHES[name]()
    basis = displacement_space(mesh)
    E, nu = (per_element(basis, 10.0, 5000.0), per_element(basis, -0.2, 0.45, 1)) if varying else (1000.0, 0.3)
    elasticity = Elasticity(E, nu, hypothesis)
    A = stiffness(basis, elasticity)
    old = reference.skfem_stiffness(basis, *elasticity.lame)
    assert isinstance(A, sp.csr_matrix) and A.shape == old.shape == (basis.N, basis.N)
    assert relative(A, old) <= 1e-13
    assert abs(A - A.T).max() <= 1e-13 * abs(A).max()


def test_the_space_numbers_the_dofs_as_scikit_fems_basis(mesh_and_basis):
    """The displacement space holds no basis values, and its dofs are those of scikit-fem's vector basis."""
    _, mesh, space = mesh_and_basis
    basis = reference.skfem_basis(space)
    assert space.N == basis.N and space.nelems == basis.nelems
    assert space.nodal_dofs.dtype == basis.nodal_dofs.dtype and np.array_equal(space.nodal_dofs, basis.nodal_dofs)


def test_the_plane_hypothesis_changes_the_stiffness():
    basis = displacement_space(half_disc(0.3))
    strain, stress = (stiffness(basis, Elasticity(1000.0, 0.3, h)) for h in ("plane_strain", "plane_stress"))
    assert relative(stress, strain) > 0.1


def test_strains_and_nodal_forces_are_scikit_fems_to_rounding(mesh_and_basis):
    _, mesh, basis = mesh_and_basis
    rng = np.random.default_rng(2)
    u = rng.standard_normal(basis.N)
    z = rng.standard_normal((mesh.dim, mesh.dim, basis.nelems))  # not symmetric: z : ε(v) uses its symmetric part
    strain = element_strain(basis, u)
    assert strain.shape == (mesh.dim, mesh.dim, basis.nelems)
    assert relative(strain, reference.skfem_strain(basis, u)) <= 1e-13
    assert relative(stress_force(basis, z), reference.skfem_stress_force(basis, z)) <= 1e-13


def test_the_nodal_force_is_the_work_of_the_stress_on_the_strain(mesh_and_basis):
    """vᵀ Bᵀz = Σ_T |T| z : ε(v), and Bᵀ(ℰε(u)) = A u."""
    _, mesh, basis = mesh_and_basis
    rng = np.random.default_rng(3)
    v = rng.standard_normal(basis.N)
    z = rng.standard_normal((mesh.dim, mesh.dim, basis.nelems))
    volumes = kernels.geometry(basis).volumes
    work = np.einsum("ijn,ijn,n->", z, element_strain(basis, v), volumes)
    assert stress_force(basis, z) @ v == pytest.approx(work, rel=1e-12)
    elasticity = Elasticity(700.0, 0.25, "plane_strain" if mesh.dim == 2 else None)
    u = rng.standard_normal(basis.N)
    force = stress_force(basis, elasticity.stress(element_strain(basis, u)))
    np.testing.assert_allclose(force, stiffness(basis, elasticity) @ u, rtol=0, atol=1e-12 * abs(force).max())


def traction(*coordinates_and_time):
    *x, t = coordinates_and_time
    return tuple((1.0 + c * x[c] ** 2 + x[0] * x[-1]) * (t - 0.3 * c) for c in range(len(x)))


def gravity(*coordinates_and_time):
    *x, t = coordinates_and_time
    return tuple(np.sin(x[c] + t) if c < len(x) - 1 else -9.81 + 0.0 * x[0] for c in range(len(x)))


def test_the_load_vector_is_scikit_fems_to_rounding(mesh_and_basis):
    name, mesh, basis = mesh_and_basis
    part = {"half disc": "top_arc", "quarter ball": "top", "block": "top"}[name]
    loads = LoadVector(basis, mesh, [("traction", part, traction)], [("gravity", gravity)])
    facets = FacetBasis(mesh.mesh, basis.elem, facets=mesh.facets(part), intorder=4)
    body = Basis(mesh.mesh, basis.elem, intorder=4)
    for t in (0.0, 0.4, 1.3):
        old = sum(reference.skfem_load(b, np.stack(np.broadcast_arrays(*f(*b.global_coordinates(), t))))
                  for b, f in ((facets, traction), (body, gravity)))
        assert relative(loads(t), old) <= 1e-13


def test_the_load_on_chosen_dofs_is_the_load_vector_there_and_vanishes_off_its_support(mesh_and_basis):
    """F(t)[dofs] computed at the dofs the loads reach (a traction alone: the nodes of the elements on its
    part) is the whole vector restricted to the dofs, and zero off the support it reports, which holds
    the part's dofs and not every dof."""
    name, mesh, basis = mesh_and_basis
    part = {"half disc": "top_arc", "quarter ball": "top", "block": "top"}[name]
    loads = LoadVector(basis, mesh, [("traction", part, traction)], [])
    dofs = np.setdiff1d(np.arange(basis.N), basis.nodal_dofs[0, mesh.nodes(part)][::2])  # some of them held
    on = loads.on(dofs)
    part_dofs = np.unique(basis.nodal_dofs[:, mesh.nodes(part)])
    assert np.isin(np.flatnonzero(np.isin(dofs, part_dofs)), on.support).all() and on.support.size < dofs.size
    for t in (0.4, 1.3):
        F = on(t)
        np.testing.assert_array_equal(F, loads(t)[dofs])
        assert not np.any(np.delete(F, on.support))


@pytest.mark.parametrize("make", [lambda: half_disc(0.2), lambda: quarter_ball(0.4)], ids=["2D", "3D"])
def test_a_chunk_of_seven_elements_gives_the_same_matrix(make, monkeypatch):
    basis = displacement_space(make())
    elasticity = Elasticity(per_element(basis, 100.0, 200.0), 0.3, "plane_stress" if basis.mesh.dim() == 2 else None)
    whole = stiffness(basis, elasticity)
    monkeypatch.setattr(kernels, "CHUNK", 7)
    monkeypatch.setattr(kernels, "PATTERN_CHUNK", 5)
    assert relative(stiffness(basis, elasticity), whole) <= 1e-14


def test_the_stiffness_takes_the_bases_dof_numbering():
    """A basis whose dofs are not numbered d·node + c gets its matrix renumbered the same way."""
    mesh = quarter_ball(0.5)
    basis = displacement_space(mesh)
    g = kernels.geometry(basis)
    nodes = mesh.mesh.p.shape[1]
    interleaved = kernels.elastic_stiffness(g, 2.0, 3.0, nodes, basis.nodal_dofs)
    blocked = np.arange(3 * nodes).reshape(3, nodes)  # dof c·nodes + node
    renumbered = kernels.elastic_stiffness(g, 2.0, 3.0, nodes, blocked)
    order = blocked.T.ravel()  # the interleaved dof k is the blocked dof order[k]
    assert abs(renumbered[order][:, order] - interleaved).max() == 0.0


def test_the_stiffness_of_many_elements_is_summed_in_bounded_memory(monkeypatch):
    """With chunks of 1,000 tetrahedra the assembly's peak allocation is a few times the matrix (its blocks
    and the CSR made of them), well below the 144 values, rows and columns per element that an assembly of
    all elements at once holds."""
    basis = displacement_space(quarter_ball(0.15))  # 12 · 10³ tetrahedra
    g = kernels.geometry(basis)
    monkeypatch.setattr(kernels, "CHUNK", 1000)
    monkeypatch.setattr(kernels, "PATTERN_CHUNK", 1000)
    tracemalloc.start()
    try:
        A = kernels.elastic_stiffness(g, 2.0, 3.0, basis.mesh.p.shape[1], basis.nodal_dofs)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    all_at_once = 144 * basis.nelems * (8 + 8 + 8)
    matrix = A.data.nbytes + A.indices.nbytes + A.indptr.nbytes
    assert peak < all_at_once / 4 and peak < 3 * matrix, (peak, all_at_once, matrix)


def test_the_memory_guard_counts_the_assembly_and_refuses_it_before_allocating(monkeypatch):
    """The bytes the guard counts for the assembly are its peak allocation (tracemalloc), to 25 %; with less memory
    available than that, the build refuses the mesh in one line naming the need and the memory available."""
    mesh = quarter_ball(0.1)
    basis = displacement_space(mesh)
    g = kernels.geometry(basis)
    blocks = kernels.node_pattern(g.cells, mesh.mesh.p.shape[1]).nnz
    tracemalloc.start()
    try:
        kernels.elastic_stiffness(g, 2.0, 3.0, mesh.mesh.p.shape[1], basis.nodal_dofs)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    counted = kernels.assembly_bytes(blocks, 3, basis.nelems)
    assert 0.8 * peak <= counted <= 1.25 * peak, (counted, peak)
    monkeypatch.setattr(kernels, "available_memory", lambda: counted - 1)
    with pytest.raises(CaseError) as refused:
        vpcontact.build_problem(vpcontact.load_case(EXAMPLES / "quarter_ball.toml"))
    message = str(refused.value)
    assert "\n" not in message and "40,500 elements" in message and "to assemble" in message
    assert f"{counted / 2**30:.3g} GiB" in message and "mesh.h" in message
    monkeypatch.setattr(kernels, "available_memory", lambda: counted)
    built = vpcontact.build_problem(vpcontact.load_case(EXAMPLES / "quarter_ball.toml"))  # just enough memory
    assert relative(built.A, stiffness(basis, Elasticity(1000.0, 0.3, None))) == 0.0


def test_a_flat_element_gives_gradients_that_are_not_finite():
    """The stiffness of a degenerate mesh is not finite (build_problem reports it) instead of raising."""
    points = np.array([[0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.0]])  # all in z = 0
    gradients, volumes = simplex.barycentric_gradients(points, np.array([[0], [1], [2], [3]]))
    assert volumes[0] == 0.0 and not np.isfinite(gradients).all()
    gradients, volumes = simplex.barycentric_gradients(points[:2, :3] * 2.0, np.array([[0], [1], [2]]))
    np.testing.assert_allclose(gradients[:, :, 0], [[-0.5, -0.5], [0.5, 0.0], [0.0, 0.5]])
    assert volumes[0] == pytest.approx(2.0)
