"""The nodes a constraint holds, other than a whole part: where a condition on the coordinates holds, or the
node nearest to a point.

A case holds a set of nodes by a condition on their coordinates, ``where = "abs(z - 0.02) < 1e-9"``
(:func:`nodes_where`, the condition language of :mod:`vpcontact.expressions.conditions`), or one node by a
point, ``at = [0, 0, 0.02]`` (:func:`nearest_node`). Both look at the nodes' coordinates only (``mesh.mesh.p``),
computed at once for all the nodes (no loop over them), and are refused with one line naming the case's key
(``where``): a condition that holds at no node shows the range of the nodes' coordinates, so that the
tolerance can be fixed; a point is never refused for lying off the mesh (users give points roughly), its
distance to the node is returned for the caller to report.
"""

from __future__ import annotations

import numbers

import numpy as np

from ..errors import CaseError, brief, quoted
from ..expressions.conditions import Condition, parse_condition
from .cells import coordinates
from .mesh import Mesh


def nodes_where(mesh: Mesh, condition: str | Condition, where: str,
                within: str | np.ndarray | None = None) -> np.ndarray:
    """The sorted node indices (int64) of ``mesh`` whose coordinates satisfy ``condition``.

    ``condition`` is a string such as ``"abs(z - 0.02) < 1e-9"`` (or a parsed
    :class:`~vpcontact.expressions.conditions.Condition`, whose text is used) in the mesh's coordinates x, y
    (, z); ``where`` names it in the case, e.g. ``"boundary.dirichlet[2].where"``. ``within`` restricts the
    nodes to those of a part (its name) or to given node indices. A comparison with NaN is False (e.g.
    ``sqrt(x) < 1`` at ``x < 0``).

    Raises CaseError ``<where> = "<condition>": <problem>`` for a condition that does not parse or uses a
    name other than the coordinates (``t`` too: the nodes are chosen once), and
    ``<where> = "<condition>" holds at no node of the mesh (x in [0.0, 1.0], y in [...], z in [...])`` (``of
    part 'top'``, ``of the k given nodes``) when no node satisfies it, with the range of those nodes'
    coordinates.
    """
    names = coordinates(mesh.dim)
    source = condition.source if isinstance(condition, Condition) else condition
    parsed = parse_condition(source, names, where=where)
    candidates, among = _candidates(mesh, within)
    points = mesh.mesh.p[:, candidates]
    with np.errstate(all="ignore"):  # NaN and inf compare as documented; no warning for a user's x/0
        held = parsed(**dict(zip(names, points)))
    selected = candidates[held]
    if selected.size == 0:
        raise CaseError(f"{where} = {quoted(parsed.source)} holds at no node {among} ({bounding_box(points)})")
    return selected


def _candidates(mesh: Mesh, within: str | np.ndarray | None) -> tuple[np.ndarray, str]:
    """The sorted nodes a selection is made among and how a message names them."""
    if within is None:
        return np.arange(mesh.mesh.p.shape[1], dtype=np.int64), "of the mesh"
    if isinstance(within, str):
        return mesh.nodes(within), f"of part '{within}'"
    nodes = np.unique(np.asarray(within, dtype=np.int64))
    if nodes.size == 0 or nodes[0] < 0 or nodes[-1] >= mesh.mesh.p.shape[1]:
        raise ValueError(f"within: expected node indices of the mesh (0 to {mesh.mesh.p.shape[1] - 1}), "
                         f"got {brief(within)}")
    return nodes, f"of the {nodes.size} given nodes"


def bounding_box(points: np.ndarray) -> str:
    """``x in [0.0, 1.0], y in [-0.5, 0.020000000000000004]``: the range of each coordinate of points (d, k),
    k ≥ 1, each bound in full (Python's shortest repr): a tolerance is fixed by the digits it would hide."""
    low, high = points.min(axis=1), points.max(axis=1)
    return ", ".join(f"{name} in [{float(a) + 0.0!r}, {float(b) + 0.0!r}]"
                     for name, a, b in zip(coordinates(points.shape[0]), low, high))


def nearest_node(mesh: Mesh, point, where: str) -> tuple[int, float]:
    """The node of ``mesh`` nearest to ``point`` (d numbers, e.g. a case's ``at = [0, 0, 0.02]``) and its
    Euclidean distance to the point.

    A point off the mesh is not refused (the caller reports the distance); of nodes equally near, the lowest
    index. Raises CaseError naming ``where`` for a point that is not a list of d finite numbers:
    ``<where> = [1, 2]: expected a point of 3 coordinates (x, y, z), got 2 numbers``,
    ``<where> = [0, 'a']: coordinate y = 'a' is not a number``,
    ``<where> = [0, nan]: coordinate y = nan is not a finite number``.
    """
    target = _point(point, mesh.dim, where)
    offset = mesh.mesh.p - target[:, None]
    scale = float(np.abs(offset).max())  # the squares of a far point's offsets would overflow
    scaled = offset / scale if scale > 0 else offset
    squared = np.einsum("in,in->n", scaled, scaled)
    node = int(np.argmin(squared))  # the first of equal minima: the lowest index
    return node, float(np.sqrt(squared[node]) * scale)


def _point(point, dim: int, where: str) -> np.ndarray:
    """``point`` as d float64 coordinates, or a CaseError naming ``where``."""
    names = coordinates(dim)
    expected = f"expected a point of {dim} coordinates ({', '.join(names)})"
    if isinstance(point, np.ndarray) and point.ndim == 1:
        point = point.tolist()
    if not isinstance(point, (list, tuple)):
        raise CaseError(f"{where} = {brief(point)}: {expected}, got {type(point).__name__}")
    if len(point) != dim:
        raise CaseError(f"{where} = {brief(point)}: {expected}, got {len(point)} number{'s' * (len(point) != 1)}")
    for name, value in zip(names, point):
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise CaseError(f"{where} = {brief(point)}: coordinate {name} = {brief(value)} is not a number")
        if not np.isfinite(float(value)):
            raise CaseError(f"{where} = {brief(point)}: coordinate {name} = {float(value)} is not a finite number")
    return np.array([float(value) for value in point])
