"""One build per compile request across processes (issue 33): a lock file per key in the compile cache.

Concurrent first runs into one empty cache each derived and compiled every kernel (119 compiler runs for 30
cache entries). :func:`held` takes the key's lock, ``<cache>/locks/<name>``, by exclusive creation (as FFCx's
JIT does: ``os.open(O_CREAT | O_EXCL)``), writing the holder's pid, host and start time into it; another
process asking for the same key waits until the lock is gone, then finds the holder's entries in the cache.

Nothing waits forever: a lock whose holder is gone (its pid not alive on this host), older than
:data:`STALE_SECONDS`, or left empty for over :data:`EMPTY_SECONDS` (its writer died between creating and
writing it) is broken; a waiter gives up after :data:`WAIT_SECONDS` and builds itself (the cache publishes by
atomic rename, so two builders are still correct, only slower). A cache that cannot hold a lock builds without
one. This module lives outside ``codegen/`` on purpose: those sources key every generated text.

Two kinds of lock: ``request-<backend>-<key>`` (mechgen.pipeline.compile_request: a request's derivation,
generated text and kernel library) and ``library-<stem>-<sha>`` (:func:`load_shared_once`: the runtime's loop
libraries, hybrid_loop.c, radau_loop.c, field_flow.c, the variational and symplectic loops, the rod internals).
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import socket
import time
import uuid
from pathlib import Path
from typing import Iterator

#: a lock older than this is broken even when its holder cannot be checked (another host), s
STALE_SECONDS = 1800.0
#: an empty or unreadable lock older than this is broken (its writer died before writing it), s
EMPTY_SECONDS = 5.0
#: the longest a process waits for another's build of the same key before it builds itself, s
WAIT_SECONDS = 900.0
#: the folder of the locks inside the compile cache
FOLDER = "locks"
_NAME = re.compile(r"[A-Za-z0-9_.-]{1,200}\Z")


@contextlib.contextmanager
def held(name: str, *, wait: float | None = None) -> Iterator[bool]:
    """Hold the build lock ``name`` (a key) for the body; yields whether this process holds it (False: the
    wait ended, or no lock can be made here, and the body runs anyway)."""
    lock = acquire(name, wait=wait)
    try:
        yield lock is not None
    finally:
        release(lock)


def lock_path(name: str) -> Path | None:
    """Where the lock ``name`` lives in the compile cache, or None where the cache cannot hold one."""
    from mechgen.codegen.cache import configured_root

    if not _NAME.match(name):
        raise ValueError(f"not a lock name: {name!r}")
    folder = configured_root() / FOLDER
    try:  # quietly: a cache that cannot be written is the cache module's to report (and builds elsewhere)
        folder.mkdir(parents=True, exist_ok=True)
        if not (folder.is_dir() and not folder.is_symlink() and os.access(folder, os.W_OK | os.X_OK)):
            return None
    except OSError:
        return None
    return folder / name


def acquire(name: str, *, wait: float | None = None) -> Path | None:
    """Take the lock ``name`` by exclusive creation; while another live process holds it, wait (polling from
    10 ms up to 0.25 s) until it goes or ``wait`` seconds (default WAIT_SECONDS) pass. Returns the lock to
    release, or None (the wait ended, or no lock can be made)."""
    path = lock_path(name)
    if path is None:
        return None
    limit = time.monotonic() + (WAIT_SECONDS if wait is None else wait)
    pause = 0.01
    while True:
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            stale = stale_content(path)
            if stale is not None:
                _break(path, stale)
                continue
            if time.monotonic() > limit:
                return None
            time.sleep(pause)
            pause = min(2 * pause, 0.25)
            continue
        except OSError:
            return None
        with os.fdopen(fd, "w") as fh:
            fh.write(json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "time": time.time()}))
        return path


def release(lock: Path | None) -> None:
    """Remove a lock this process holds (None: none was taken)."""
    if lock is not None:
        with contextlib.suppress(OSError):
            os.unlink(lock)


def stale_content(path: Path) -> bytes | None:
    """The lock's bytes if its holder is gone (module doc), else None (alive, another host's and young, or the
    lock went meanwhile)."""
    try:
        age = time.time() - os.lstat(path).st_mtime
        data = _read(path)
    except OSError:
        return None
    if age > STALE_SECONDS:
        return data
    try:
        holder = json.loads(data)
    except ValueError:
        holder = None
    if not isinstance(holder, dict) or not isinstance(holder.get("pid"), int):
        return data if age > EMPTY_SECONDS else None
    if holder.get("host") != socket.gethostname():
        return None
    try:
        os.kill(holder["pid"], 0)
    except ProcessLookupError:
        return data
    except OSError:  # alive, another user's
        return None
    return None


def _read(path: Path) -> bytes:
    """At most 4 KiB of a lock, never following a link or blocking on a FIFO."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    with os.fdopen(fd, "rb") as fh:
        return fh.read(4096)


def _break(path: Path, stale: bytes) -> None:
    """Remove a stale lock: renamed aside, then removed if it is still the lock judged stale; a fresh lock that
    another breaker took meanwhile is put back."""
    aside = path.with_name(f".broken-{path.name}-{uuid.uuid4().hex}")
    try:
        os.rename(path, aside)
    except OSError:
        return
    with contextlib.suppress(OSError):
        if _read(aside) != stale:
            os.link(aside, path)
    with contextlib.suppress(OSError):
        os.unlink(aside)


def load_shared_once(source: str, *, stem: str, **options):
    """``mechgen.codegen.build.load_shared`` under the lock of this source (its sha256 and stem): concurrent first
    runs compile a runtime loop library (hybrid_loop.c, radau_loop.c ...) once, the others load that build."""
    import hashlib

    from mechgen.codegen.build import load_shared

    digest = hashlib.sha256(source.encode("utf-8")).hexdigest()[:32]
    with held(f"library-{stem}-{digest}"):
        return load_shared(source, stem=stem, **options)
