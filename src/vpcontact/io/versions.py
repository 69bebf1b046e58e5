"""The installed versions of vpcontact and its main dependencies, as a run directory records them
(summary.json, the header of case.resolved.toml, a checkpoint: a resumed run warns when they changed)."""

from __future__ import annotations

import functools
from importlib import metadata

PACKAGES = ("vpcontact", "numpy", "scipy", "scikit-fem", "meshio", "pydantic")


@functools.lru_cache(maxsize=1)
def _installed_versions() -> tuple:
    found = []
    for name in PACKAGES:
        try:
            found.append((name, metadata.version(name)))
        except metadata.PackageNotFoundError:
            found.append((name, "not installed"))
    return tuple(found)


def versions() -> dict[str, str]:
    """Installed versions of vpcontact and its main dependencies (read once per process)."""
    return dict(_installed_versions())
