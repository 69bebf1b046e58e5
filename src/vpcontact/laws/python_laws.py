"""Laws of the user: the Python functions of the API that replace the case's laws, checked before the run.

A contact law p(r) or K(ξ) (:func:`api_law`), or one of the contact nodes' coordinates too, p(r, x) or
K(ξ, x) (:class:`LawOfNodes`, tried once the nodes are known), and a viscoplastic law 𝒢(σ, ε) or 𝒢(σ, ε, x)
(:func:`api_viscoplastic`): each is refused on one line (a CaseError naming it) when it is not callable, takes
other arguments than these, raises, or returns values that are not finite numbers of the shape of its
arguments."""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import CaseError, brief
from ..mesh.core import Mesh
from .contact import AtNodes, CallableLaw
from .materials import AtCentroids


#: Where a law of the API is tried before the run: at 0 and just above (a penetration, a history ξ ≥ 0).
LAW_SAMPLE = (0.0, 1e-3)


def api_law(law, name: str):
    """A law p or K of the API: a law f(r) tried at LAW_SAMPLE (elementwise, finite), an object with a
    ``derivative`` method as it is, a plain function wrapped in CallableLaw; a law f(r, x) of the nodes'
    coordinates x is a LawOfNodes, tried when the contact nodes are known; else CaseError."""
    if not callable(law):
        raise CaseError(f"{name} = {brief(law)}: expected a function f(r) of a NumPy array (optionally with a "
                        f"method f.derivative(r)), or f(r, x) with x the coordinates of the contact nodes")
    derivative = getattr(law, "derivative", None)
    derivative = derivative if callable(derivative) else None
    arguments = _arguments(law, name)
    if derivative is not None and (other := _arguments(derivative, f"{name}.derivative")) != arguments:
        raise CaseError(f"{name} takes {arguments} argument(s) and {name}.derivative {other}: give both f(r) or "
                        f"both f(r, x)")
    if arguments == 2:
        return LawOfNodes(law, derivative, name)
    for what, f in ((name, law), (f"{name}.derivative", derivative)) if derivative else ((name, law),):
        sample = np.array(LAW_SAMPLE)
        call = f"{what}({', '.join(map(str, LAW_SAMPLE))})"
        check_returned(what, call, tried(what, call, f, sample.copy()), sample.shape)
    return law if derivative else CallableLaw(law)


def _arguments(law: Callable, name: str) -> int:
    """The arguments ``law`` takes, from its signature: 2 when it requires two (r, x), else 1 (r); CaseError when
    it requires more, or cannot take one (lambda: 1)."""
    required = required_arguments(law)
    if len(required) > 2 or not (len(required) == 2 or accepts(law, 1)):
        raise CaseError(f"{name} takes {parameters_in_words(law)}: expected f(r), or f(r, x) with x the coordinates "
                        f"of the contact nodes")
    return 2 if len(required) == 2 else 1


def accepts(function: Callable, count: int) -> bool:
    """May ``function`` be called with ``count`` positional arguments, as far as its signature tells (True when
    Python cannot tell, for a NumPy ufunc or some builtins)?"""
    try:
        inspect.signature(function).bind(*range(count))
    except TypeError:
        return False
    except ValueError:  # no signature
        return True
    return True


def parameters_in_words(function: Callable) -> str:
    """The parameters of ``function`` in words: "2 arguments (x, y)", "1 argument (r)", "no argument"."""
    try:
        names = list(inspect.signature(function).parameters)
    except (TypeError, ValueError):
        return "other arguments"
    count = f"{len(names)} argument{'s' * (len(names) != 1)}"
    return f"{count} ({', '.join(names)})" if names else "no argument"


def required_arguments(function: Callable) -> list[str]:
    """The names of the positional arguments ``function`` requires, from its signature; none when Python
    cannot tell (a NumPy ufunc) or when it takes any number (``*args``)."""
    try:
        parameters = list(inspect.signature(function).parameters.values())
    except (TypeError, ValueError):
        return []
    if any(p.kind == p.VAR_POSITIONAL for p in parameters):
        return []
    return [p.name for p in parameters
            if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.default is p.empty]


@dataclass(frozen=True)
class LawOfNodes:
    """A law f(r, x) of the API (and its derivative df(r, x), or None), waiting for the contact nodes."""

    function: Callable
    derivative: Callable | None
    name: str

    def at(self, points: np.ndarray) -> CallableLaw:
        """The law at the contact nodes ``points`` (d, m), tried at r = 0 and 10⁻³ at every node."""
        m = points.shape[1]
        for what, f in ((self.name, self.function), (f"{self.name}.derivative", self.derivative)):
            if f is None:
                continue
            for r in LAW_SAMPLE:
                call = f"{what}({r}, x) at the {m} contact nodes"
                check_returned(what, call, tried(what, call, f, np.full(m, r), points.copy()), (m,))
        derivative = None if self.derivative is None else AtNodes(self.derivative, points)
        return CallableLaw(AtNodes(self.function, points), derivative)


def tried(name: str, call: str, function: Callable, *arguments):
    """``function(*arguments)``, the trial ``call`` of the API's law ``name`` (values that are not finite are
    reported by the caller); CaseError, caused by the function's own exception, when it raises one."""
    try:
        with np.errstate(all="ignore"):
            return function(*arguments)
    except CaseError:
        raise
    except Exception as error:  # noqa: BLE001 - a user's function may raise anything
        raise CaseError(f"{name}: {call} raised {type(error).__name__}: {error}") from error


def check_returned(name: str, call: str, values, shape: tuple) -> None:
    """CaseError unless ``values`` (what ``call`` returned) are finite numbers broadcasting to ``shape``."""
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):  # a ragged list
        array = None
    if array is None or array.dtype.kind not in "iuf":  # complex, boolean, strings, objects: not real numbers
        what = f"ndarray of {array.dtype}" if isinstance(values, np.ndarray) else type(values).__name__
        raise CaseError(f"{name}: {call} returned a value of type {what}, not numbers")
    array = array.astype(float)
    try:
        broadcast = np.broadcast_shapes(array.shape, shape) == shape
    except ValueError:
        broadcast = False
    if not broadcast:
        raise CaseError(f"{name}: {call} returned an array of shape {array.shape} for arguments of shape {shape}; "
                        f"expected that shape (elementwise)")
    if not np.all(np.isfinite(array)):
        raise CaseError(f"{name}: {call} is not finite ({array.ravel()[~np.isfinite(array.ravel())][0]})")




def api_viscoplastic(G, mesh: Mesh) -> Callable:
    """𝒢 of the API: G(sigma, strain) of arrays (d, d, elements), or G(sigma, strain, x) of the element
    centroids x (d, elements) too (𝒢(x, σ, ε) of (2.17)), bound to the mesh's centroids; else CaseError."""
    if not callable(G):
        raise CaseError(f"viscoplastic = {brief(G)}: expected a function G(sigma, strain) of arrays of shape "
                        f"(d, d, elements), or G(sigma, strain, x) with x the element centroids (d, elements)")
    required = required_arguments(G)
    if len(required) > 3 or not (len(required) == 3 or accepts(G, 2)):
        raise CaseError(f"viscoplastic takes {parameters_in_words(G)}: expected G(sigma, strain) or "
                        f"G(sigma, strain, x)")
    if len(required) == 3:
        return AtCentroids(G, mesh.centroids)
    return G
