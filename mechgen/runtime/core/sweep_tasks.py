"""One sweep point's task, shared by every executor (mechgen.runtime.core.sweep: serial and local processes;
mechgen.runtime.core.dask_sweep: a Dask cluster): the guarded call and its status, an inner analysis's spent
budget named with the point, the point's description in messages, and the check of a Dask scheduler's address
(issue 33: checked before anything connects)."""
from __future__ import annotations

import ipaddress
import re
from urllib.parse import urlsplit

from mechgen.errors import InputError, MechgenError
from mechgen.runtime.core.budget import BudgetExceeded, clock_depth

#: a point's status when its function returned
OK = "ok"
#: the schemes of a running Dask scheduler's address mechgen connects to (inproc:// lives in one process only)
SCHEDULER_SCHEMES = ("tcp", "tls")
#: what a scheduler address looks like, for messages
SCHEDULER_FORM = "a Dask scheduler address tcp://host:port or tls://host:port (port 1-65535)"
_HOST_LABEL = re.compile(r"[A-Za-z0-9](?:[A-Za-z0-9-]{0,61}[A-Za-z0-9])?\Z")


def scheduler_address(text: object) -> str:
    """``text`` if it is the address of a running Dask scheduler, scheme://host:port with a scheme of
    :data:`SCHEDULER_SCHEMES`, a host name or IP address and a port 1-65535, nothing else (no path, user,
    query); else ValueError saying what is wrong. Checked before anything connects (issue 33)."""
    if not isinstance(text, str) or not text or len(text) > 300 or not text.isprintable() or " " in text:
        raise ValueError("it is not a short address without spaces")
    scheme, sep, _ = text.partition("://")
    if not sep or scheme not in SCHEDULER_SCHEMES:
        raise ValueError(f"its scheme {scheme[:20]!r} is not " + " or ".join(SCHEDULER_SCHEMES) if sep
                         else "it has no scheme://")
    parts = urlsplit(text)
    if parts.path or parts.query or parts.fragment or "@" in parts.netloc:
        raise ValueError("it has more than scheme://host:port (a path, a query or a user)")
    try:
        port = parts.port
    except ValueError:
        port = 0
    if port is None or not 1 <= port <= 65535:
        raise ValueError("it has no port 1-65535")
    if not _valid_host(parts.hostname or ""):
        raise ValueError("its host is not a host name or an IP address")
    return text


def _valid_host(host: str) -> bool:
    """An IP address, or a DNS name of labels (letters, digits, inner hyphens) of at most 253 characters."""
    try:
        ipaddress.ip_address(host)
        return True
    except ValueError:
        pass
    labels = host.rstrip(".").split(".")
    return 0 < len(host) <= 253 and all(_HOST_LABEL.match(label) for label in labels)


class SweepError(MechgenError):
    """A sweep point failed; the message names the point."""


def guarded(func, point, inner: str, label, record: bool = True) -> tuple:
    """("ok", func(point)), or with ``record`` ("failed: <message>", None) for a failed computation. A
    user's mistake (InputError) and a spent budget (named with the point when ``label`` is given) are
    raised; without ``record`` so is every failure (a MechgenError as it is, another named with the point)."""
    depth = clock_depth()
    try:
        return OK, func(point)
    except BudgetExceeded as exc:
        if label is None or (exc.level is not None and exc.level < depth):
            raise  # in a worker the driver names the point; a timer set outside the point is the sweep's own
        raise inner_budget(exc, label, inner) from exc
    except InputError:
        raise
    except MechgenError as exc:
        if not record:
            raise
        return f"failed: {type(exc).__name__}: {exc}", None
    except Exception as exc:  # recorded, or raised with the point named
        if not record:  # in a worker (no label) the driver names the point
            raise SweepError(f"sweep point {describe(label)} failed: {exc}" if label is not None else str(exc)) from exc
        return f"failed: {type(exc).__name__}: {exc}", None


def inner_budget(exc: BudgetExceeded, point, inner: str) -> BudgetExceeded:
    """An inner analysis's spent budget, with the point and its key under ``inner``."""
    reached = f"{exc.reached} at sweep point {describe(point)}" if exc.reached else f"sweep point {describe(point)}"
    return BudgetExceeded(exc.message, key=f"{inner}.{exc.key}" if exc.key else None, reached=reached,
                          analysis=exc.analysis)


def describe(point) -> str:
    """A point as messages show it (the last dict of a task tuple: the grid point)."""
    if isinstance(point, tuple) and point and isinstance(point[-1], dict):
        point = point[-1]
    return repr(point)
