"""Plug-ins found by name: the laws a case names (contact.stiffness.law, contact.p, material.viscoplastic.law)
and the error estimators (adapt.estimator).

A registry lists the names of its plug-ins, in the order messages list them, without importing them: the
plug-in ``name`` is the attribute ``attribute`` of the module ``<package>.<name>``, imported on first use. A
new plug-in is therefore one file in the package and one name in its registry's list. ``register`` adds one
defined elsewhere (a user's module, a test); the case schema builds its tables from the names registered
when it is first imported, so a plug-in of a case file is registered before a case is loaded.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
from typing import TypeVar

Plugin = TypeVar("Plugin")


class Registry(Mapping[str, Plugin]):
    """The plug-ins of one kind by name (each an object with a ``name``), see the module: a mapping from the
    names, in order, to the plug-ins."""

    def __init__(self, package: str, names: tuple[str, ...], attribute: str):
        self.package, self.attribute = package, attribute
        self._names = tuple(names)
        self._loaded: dict[str, Plugin] = {}

    @property
    def names(self) -> tuple[str, ...]:
        """The names of the plug-ins, in the order messages list them."""
        return self._names

    def __getitem__(self, name: str) -> Plugin:
        """The plug-in ``name`` (KeyError naming the known ones if there is none)."""
        if name not in self._loaded:
            if name not in self._names:
                raise KeyError(f"{name!r}: expected one of {', '.join(map(repr, self._names))}")
            module = f"{self.package}.{name}"
            plugin = getattr(importlib.import_module(module), self.attribute)
            if plugin.name != name:
                raise ValueError(f"{module}.{self.attribute} is named {plugin.name!r}: a plug-in's module is named "
                                 f"after it")
            self._loaded[name] = plugin
        return self._loaded[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)

    def register(self, plugin: Plugin) -> Plugin:
        """Add ``plugin``, defined outside the package, after the others (ValueError if its name is taken)."""
        if plugin.name in self._names:
            raise ValueError(f"{plugin.name!r} is registered already (one of {', '.join(map(repr, self._names))})")
        self._names += (plugin.name,)
        self._loaded[plugin.name] = plugin
        return plugin
