"""Where the reproduction ran: platform, processor, cores, memory and the versions that matter."""

from __future__ import annotations

import os
import platform
from pathlib import Path


def machine() -> dict:
    """Platform, processor, cores, memory and the versions that matter."""
    from ..io.versions import versions

    memory = None
    try:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    except (ValueError, OSError, AttributeError):
        pass
    processor = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                processor = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        from ..solvers.factorization import installed_backends

        backend = installed_backends()[0]
    except Exception:  # noqa: BLE001 - informational only
        backend = "unknown"
    try:
        import matplotlib

        mpl = matplotlib.__version__
    except ImportError:
        mpl = "not installed"
    return {
        "platform": platform.platform(),
        "processor": processor,
        "cores": os.cpu_count(),
        "memory_gb": round(memory, 1) if memory else None,
        "python": platform.python_version(),
        "factorization": backend,
        "versions": {**versions(), "matplotlib": mpl},
    }

