"""Memory estimates before large allocations: refuse up front what cannot fit, with the key to change.

Every allocation whose size a user sets (a continuum's ``N`` and ``quadrature``, a chain's number of
sites, a simulation's ``samples``) is estimated before it is made: a dense n x n float64 matrix takes
8 n^2 bytes, a Gauss rule of q points 8 q^2 (its companion matrix), an output grid of s samples of a
state of size d about 8 s (d + 1). :func:`require` compares the estimate (bytes) with the limit and
raises :class:`~mechgen.errors.InputError` (exit 2) naming what would be allocated, the estimate in
GiB, the limit and the memory available, and the key that sets the size. Nothing is allocated.

The limit is ``SAFE_FRACTION`` (0.8) of the memory available now (``MemAvailable`` in
``/proc/meminfo``, else ``os.sysconf`` available pages x page size; no limit where neither is known).
The environment variable ``MECHGEN_MEMORY_LIMIT`` overrides it: a size in bytes with an optional
unit (``64GiB``, ``500MB``, ``2e9``), or ``off`` for no check at all.

Estimates are Python integers (no overflow for N = 1e6: 2e6 x 2e6 doubles are 3.2e13 bytes = 29 TiB).
"""
from __future__ import annotations

import math
import os
import re

from mechgen.errors import InputError

#: the environment variable that overrides the limit (a size such as ``64GiB``, or ``off``)
ENV = "MECHGEN_MEMORY_LIMIT"
#: the fraction of the available memory one allocation may take
SAFE_FRACTION = 0.8
#: float64
DOUBLE = 8
#: allocations of at most this many bytes are not checked (unless MECHGEN_MEMORY_LIMIT is set)
SMALL = 64 << 20

_UNITS = {"": 1, "b": 1, "k": 1e3, "kb": 1e3, "m": 1e6, "mb": 1e6, "g": 1e9, "gb": 1e9, "t": 1e12, "tb": 1e12,
          "kib": 2**10, "mib": 2**20, "gib": 2**30, "tib": 2**40}
GIB = 2**30


def available_bytes() -> int | None:
    """Memory available to a new allocation now (bytes): MemAvailable of /proc/meminfo, else sysconf; None if unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def parse_size(text: str) -> float | None:
    """Bytes of a size such as ``64GiB``, ``500 MB``, ``2e9`` (None for ``off``/``none``/``unlimited``).

    Raises InputError (key ``MECHGEN_MEMORY_LIMIT``) for anything else.
    """
    value = text.strip().lower()
    if value in ("off", "none", "unlimited"):
        return None
    match = re.fullmatch(r"([0-9]*\.?[0-9]+(?:e[+-]?[0-9]+)?)\s*([a-z]*)", value)
    if match is None or match.group(2) not in _UNITS or not math.isfinite(float(match.group(1))):
        raise InputError(f"{ENV} = {text!r} is not a size", key=ENV,
                         expected="a number of bytes with an optional unit (64GiB, 500MB, 2e9) or 'off'")
    return float(match.group(1)) * _UNITS[match.group(2)]


def limit_bytes() -> tuple[float | None, str]:
    """(the most bytes one allocation may take, where that limit comes from); None: no check."""
    override = os.environ.get(ENV)
    if override is not None and override.strip():
        size = parse_size(override)
        return size, f"{ENV} = {override.strip()}"
    free = available_bytes()
    if free is None:
        return None, "available memory unknown"
    return SAFE_FRACTION * free, f"{SAFE_FRACTION:g} of the {free / GIB:.3g} GiB available"


def dense_bytes(*shape: int, itemsize: int = DOUBLE) -> int:
    """Bytes of a dense array of this shape (Python integers: no overflow)."""
    out = int(itemsize)
    for n in shape:
        out *= max(int(n), 0)
    return out


def require(nbytes: int | float, what: str, *, key: str, expected: str | None = None) -> None:
    """Refuse (InputError, exit 2) an allocation of ``nbytes`` bytes beyond the limit; nothing is allocated.

    ``what`` says what would be allocated ("the dense 2000000 x 2000000 mass matrix"), ``key`` the scene
    key that sets its size (``params.N``), ``expected`` what would fit (default: a smaller value, or the
    override).
    """
    if nbytes <= SMALL and not os.environ.get(ENV, "").strip():
        return  # far below any machine's memory: /proc/meminfo is not read (a Campbell speed, a sweep point)
    limit, source = limit_bytes()
    if limit is None or nbytes <= limit:
        return
    hint = expected or f"a smaller {key.rpartition('.')[2]}"
    raise InputError(f"{what} needs about {nbytes / GIB:.3g} GiB of memory, more than the "
                     f"{limit / GIB:.3g} GiB allowed ({source}); nothing was allocated", key=key,
                     expected=f"{hint}, or {ENV} set to allow more (for example {ENV}=off)")


def require_dense(n: int, copies: int, what: str, *, key: str = "params.N", expected: str | None = None) -> None:
    """Refuse dense linear algebra holding ``copies`` float64 n x n arrays (matrices, factors, eigenvectors,
    workspace) beyond the limit: ``what`` of n unknowns; by default the size to change is a continuum's or a
    chain's N (params.N), and the way out the sparse path (a ``count`` of the lowest modes, finite elements)."""
    require(dense_bytes(copies, n, n), f"{what} of {int(n)} unknowns (dense {int(n)} x {int(n)} arrays)", key=key,
            expected=expected or "a smaller N, or the sparse path: a count of the lowest modes with finite elements")
