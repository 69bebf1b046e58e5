"""The rigid motions that nothing holds, in words: "the translations along x and y and the rotation about z".

A body's rigid motions are u(x) = t + ω × (x − c): a translation t and a rotation ω (in 2D ω is along z, a
rotation in the plane). The motions the Dirichlet conditions and the contact normals leave free form a
subspace F of them (:meth:`vpcontact.fem.rigid_modes.RigidModes.unheld`). It is named in two groups:

- the free **translations**, F's motions without rotation: named by the coordinate axes when they span
  them ("the translations along x and y"), else by a direction ("the translation along (0.6, 0.8, 0)") or,
  two of three in 3D, by the plane's normal;
- the free **rotations**, one per direction of F's rotation vectors (the coordinate axes when they span
  those directions). A rotation's axis is where its motion vanishes, up to the free translations: when
  these include every direction across the axis, any parallel axis is as free and the rotation is named by
  its direction alone ("the rotation about z", "the rotation about the axis along (0, 0.6, 0.8)"; in 2D
  "the rotation in the plane"); otherwise by the axis
  nearest to the body's centroid ("the rotation about the axis through (1, 0, 0) along z"; in 2D "the
  rotation about (1, 0)"). A rotation that cannot be freed from a translation along its own axis is
  named as the screw motion it is.
"""

from __future__ import annotations

import numpy as np

from ..errors import point

#: Coefficients below this (relative to one) are rounding: the free subspace comes from an eigensolver.
ROUNDING = 1e-6
AXES = ("x", "y", "z")


def free_motions_in_words(free: np.ndarray, centroid: np.ndarray, size: float) -> str:
    """The rigid motions spanned by the columns of ``free`` (orthonormal, on the modes of
    :mod:`vpcontact.fem.rigid_modes`: d translations, then the rotations in the planes xy (2D) or xy, yz,
    zx (3D) about ``centroid`` scaled by ``size``), in words, e.g. "the translation along x", "the
    translations along x and y and the rotation about z" (at least one column)."""
    d = centroid.size
    translation, rotation = free[:d], free[d:]
    if d == 3:
        rotation = rotation[[1, 2, 0]]  # the planes yz, zx, xy: the rotation vector's x, y, z
    _, values, right = np.linalg.svd(rotation)
    turning = int(np.count_nonzero(values > ROUNDING))
    translations = _orthonormal(translation @ right[turning:].T)  # the combinations that do not turn
    phrases = [_translations(translations)] if translations.shape[1] else []
    if turning:
        axes, _ = _in_coordinates(_orthonormal(rotation @ right[:turning].T))
        steps = np.linalg.lstsq(rotation / size, axes, rcond=None)[0]  # a combination turning 1 about each axis
        shifts = translation @ steps
        shifts -= translations @ (translations.T @ shifts)  # the least translation that goes with each rotation
        phrases += _rotations(axes, shifts, translations, centroid, size)
    return _listed(phrases)


def _translations(directions: np.ndarray) -> str:
    """The translations along the orthonormal columns of ``directions`` (d, m), m ≥ 1."""
    m = directions.shape[1]
    spanned, axes = _in_coordinates(directions)
    if axes is not None:
        return f"the translation{'s' if m > 1 else ''} along {_listed([AXES[a] for a in axes])}"
    if m == 1:
        return f"the translation along {_direction(spanned[:, 0])}"
    normal = np.linalg.svd(directions.T)[2][-1]  # m = 2 of d = 3
    return f"the translations in the plane normal to {_direction(normal)}"


def _rotations(axes: np.ndarray, shifts: np.ndarray, translations: np.ndarray, centroid: np.ndarray,
               size: float) -> list[str]:
    """The rotations about the orthonormal rotation vectors ``axes`` (1 in 2D, 3 in 3D; r columns), each with the translation
    ``shifts`` (d, r) that goes with it (orthogonal to the free ``translations``), in words."""
    d = centroid.size
    if d == 2:
        if translations.shape[1] == 2:
            return ["the rotation in the plane"]
        center = centroid + np.array([-shifts[1, 0], shifts[0, 0]])  # e_z × (c − p) = shift
        return [f"the rotation about {_point(center, size)}"]
    phrases = []
    for axis, shift in zip(axes.T, shifts.T):
        axis = axis * np.sign(axis[np.argmax(np.abs(axis))])
        coordinate = np.isclose(np.abs(axis).max(), 1.0)
        along = AXES[int(np.argmax(np.abs(axis)))] if coordinate else _direction(axis)
        across = np.eye(3) - np.outer(axis, axis)
        free_across = np.linalg.norm(across - translations @ (translations.T @ across)) < ROUNDING
        advance = axis @ shift
        if free_across and abs(advance) <= ROUNDING * size:
            phrases.append(f"the rotation about {along}" if coordinate else f"the rotation about the axis along {along}")
            continue
        through = _point(centroid + np.cross(axis, shift - advance * axis), size)
        if abs(advance) <= ROUNDING * size:
            phrases.append(f"the rotation about the axis through {through} along {along}")
        else:
            phrases.append(f"the screw motion about the axis through {through} along {along}, advancing "
                           f"{advance:.6g} per radian")
    return phrases


def _in_coordinates(directions: np.ndarray) -> tuple[np.ndarray, list[int] | None]:
    """The space of the orthonormal columns of ``directions`` (n, m): (the coordinate axes that span it,
    as columns of the identity, and their indices) when some do, else (``directions``, None)."""
    projector = directions @ directions.T
    axes = np.flatnonzero(np.diag(projector) > 0.5)
    if axes.size == directions.shape[1] and np.allclose(projector, np.diag(np.isin(np.arange(len(projector)), axes)),
                                                        atol=ROUNDING):
        return np.eye(len(projector))[:, axes], [int(a) for a in axes]
    return directions, None


def _orthonormal(vectors: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the span of the columns of ``vectors`` (their rank, to rounding)."""
    if vectors.shape[1] == 0:
        return vectors
    left, values, _ = np.linalg.svd(vectors, full_matrices=False)
    return left[:, values > ROUNDING]


def _direction(vector: np.ndarray) -> str:
    """A unit direction, its largest component positive, as a message shows it: "(0.6, 0.8, 0)"."""
    vector = vector / np.linalg.norm(vector)
    vector = vector * np.sign(vector[np.argmax(np.abs(vector))])
    return point(np.round(vector, 12), 3)


def _point(x: np.ndarray, size: float) -> str:
    """A point of the body, without its rounding below 1e-9 of the body's ``size``."""
    return point(np.round(x / size, 9) * size, 6)


def _listed(words: list[str]) -> str:
    """"a", "a and b", "a, b and c"."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} and {words[-1]}"
