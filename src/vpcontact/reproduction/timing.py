"""How long each part of the reproduction took: wall time and CPU time, the study workers' included."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field


def clock() -> tuple[float, float, float]:
    """Now: wall time, CPU time of this process, CPU time of its ended child processes (s)."""
    cpu = os.times()
    return time.perf_counter(), cpu.user + cpu.system, cpu.children_user + cpu.children_system


@dataclass
class Timer:
    """Wall time and CPU time of the named parts of the reproduction. A part's CPU time is this
    process's; the study workers' CPU time is known once their pool has closed (`totals`)."""

    started: tuple = field(default_factory=clock)
    wall: dict = field(default_factory=dict)
    cpu: dict = field(default_factory=dict)

    def part(self, name: str, began: tuple) -> str:
        """Record part ``name``, begun at ``began`` (a `clock()`); returns its times as text."""
        now = clock()
        self.wall[name], self.cpu[name] = now[0] - began[0], now[1] - began[1]
        return f"{self.wall[name]:.1f} s (CPU {self.cpu[name]:.1f} s)"

    def totals(self) -> tuple[dict, dict]:
        """(wall time, CPU time) of the parts and in total since the start; the CPU time also
        has the study workers' ("study workers")."""
        now = clock()
        workers = now[2] - self.started[2]
        wall = {**self.wall, "total": now[0] - self.started[0]}
        cpu = {**self.cpu, "study workers": workers, "total": now[1] - self.started[1] + workers}
        return wall, cpu

