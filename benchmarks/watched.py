"""A benchmark level in its own process, watched: its resident memory sampled from /proc, stopped past
a memory or time limit (the benchmarks' scripts import it: they run from this folder)."""

import os
import subprocess
import time


def resident_mb(pid: int) -> float:
    """Resident memory of process ``pid`` in MB (Linux: /proc/PID/statm), 0 where it cannot be read."""
    try:
        with open(f"/proc/{pid}/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, ValueError, IndexError):
        return 0.0


def watched(command: list[str], memory_limit_mb: float, time_limit_s: float,
            interval_s: float = 0.1) -> tuple[int, str, str, str, float, float]:
    """Run ``command``, sampling its resident memory every ``interval_s``; stop it past the limits.
    Returns (exit status, stdout, stderr, why it was stopped or "", wall time in seconds, largest
    sample in MB)."""
    started = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stopped, largest = "", 0.0
    while process.poll() is None:
        largest = max(largest, resident_mb(process.pid))
        elapsed = time.perf_counter() - started
        if largest > memory_limit_mb:
            stopped = f"stopped at {largest:,.0f} MB resident, over the limit of {memory_limit_mb:,.0f} MB"
        elif elapsed > time_limit_s:
            stopped = f"stopped after {elapsed:.0f} s, over the limit of {time_limit_s:.0f} s"
        if stopped:
            process.kill()
            break
        time.sleep(interval_s)
    stdout, stderr = process.communicate()
    return process.returncode, stdout, stderr, stopped, time.perf_counter() - started, largest
