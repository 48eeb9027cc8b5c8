"""Shared pieces of the case studies: per-operation timers, a progress line, the machine."""
from __future__ import annotations

import math
import statistics
import sys
import time

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
    """The benchmark's machine facts (``yggdrasil.bench.machine``) and networkx's version."""
    from ..bench import machine as bench_machine, package_version
    return {**bench_machine(), "networkx": package_version("networkx")}
