"""Shared pieces of the case studies: per-operation timers, a progress line, the machine."""
from __future__ import annotations

import math
import os
import platform
import statistics
import sys
import time
from importlib import metadata

perf_ns = time.perf_counter_ns


class Timings:
    """Per-operation call times (ns) of one backend; ``calls`` counts every call, ``ns``
    holds the timed ones (all of them unless the operation is sampled)."""

    def __init__(self):
        self.ns = {}
        self.calls = {}

    def add(self, op, ns):
        self.ns.setdefault(op, []).append(ns)
        self.calls[op] = self.calls.get(op, 0) + 1

    def count(self, op, n=1):
        self.calls[op] = self.calls.get(op, 0) + n

    def median_us(self, op):
        return statistics.median(self.ns[op]) / 1e3

    def total_ms(self, op):
        """Calls times the mean timed call (exact when every call is timed)."""
        ns = self.ns.get(op)
        if not ns:
            return 0.0
        return self.calls[op] * statistics.fmean(ns) / 1e6


def euclid(a, b):
    """Euclidean distance over the first ``len(a)`` coordinates (as LP2's helper)."""
    return math.sqrt(sum((float(x) - float(y)) ** 2 for x, y in zip(a, b)))


class Progress:
    """A one-line progress bar on stderr (no tqdm dependency)."""

    def __init__(self, total, quiet=False):
        self.total, self.done, self.quiet = total, 0, quiet
        self.t0 = time.monotonic()
        self.stream = sys.stderr

    def step(self, label, n=1):
        self.done += n
        if self.quiet:
            return
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        elapsed = time.monotonic() - self.t0
        self.stream.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} "
                          f"{elapsed:6.1f}s {label[:60]:<60}")
        self.stream.flush()

    def close(self):
        if not self.quiet:
            self.stream.write("\n")
            self.stream.flush()


def machine():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass

    def version(name):
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            return "not installed"
    return {"cpu": cpu, "cores": os.cpu_count(),
            "loadavg": " ".join(f"{x:.2f}" for x in os.getloadavg()),
            "python": platform.python_version(), "spark_dsg": version("spark-dsg"),
            "networkx": version("networkx"), "numpy": version("numpy"), "scipy": version("scipy")}
