"""Module-level sweep functions for tests/test_sweep_executors.py (Dask workers import them by name:
the test puts this folder on the workers' PYTHONPATH)."""
from __future__ import annotations

import math
import time


def slow_square(x: float) -> float:
    """x^2 after 0.1 s (a point with real duration, so that a worker can be killed while it runs)."""
    time.sleep(0.1)
    return x * x


def root_or_fail(x: float) -> float:
    """sqrt(x); a negative x raises ValueError (math domain error): a failing point."""
    return math.sqrt(x)
