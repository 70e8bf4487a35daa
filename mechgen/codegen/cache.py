"""Content-hash cache of built artefacts (stage: build -> cache -> load).

Input: a *kind* (a folder name such as ``"c"``), a *key* (:func:`content_key`
of everything that determines the artefacts) and a function that writes the
artefacts into an empty directory. Output: the path of a verified entry
directory ``cache_root()/kind/key`` holding the artefacts and a ``meta.json``
with the key and the sha256 of every artefact file.

Safety (DESIGN.md, "Safety rules of a code generator"):

* Writes are atomic: an entry is built in a temporary directory on the same
  filesystem and published with one ``os.rename``. A directory rename onto an
  existing entry fails, so when several processes build the same key at once
  exactly one wins; the others verify the winner and discard their own work.
* There are no lock files, so nothing can ever wait on a stale lock.
* Every lookup verifies the entry; a truncated, corrupted or foreign entry is
  moved aside, deleted and reported as missing, so the caller rebuilds it.
* Files inside a published entry are never modified in place (a shared library
  may be mapped by a running process); bad entries are renamed, then removed.
* Leftover temporary and trash directories older than an hour (from a crashed
  writer) are removed opportunistically on publish.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import tempfile
import time
import uuid
from pathlib import Path
from typing import Callable

import platformdirs

META = "meta.json"
FORMAT = 1
TMP_PREFIX = ".tmp-"
TRASH_PREFIX = ".trash-"
STALE_SECONDS = 3600.0
_KIND_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}")
_KEY_RE = re.compile(r"[0-9a-f]{64}")
_FILE_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]{0,127}")


def cache_root() -> Path:
    """The cache's root directory, created on demand.

    Returns:
        ``$MECHGEN_CACHE`` if set (and not empty), else the user cache
        directory of platformdirs for ``mechgen``.
    """
    env = os.environ.get("MECHGEN_CACHE")
    root = Path(env) if env else Path(platformdirs.user_cache_dir("mechgen"))
    root.mkdir(parents=True, exist_ok=True)
    return root


def content_key(*parts: str | bytes) -> str:
    """A sha256 hex digest over ``parts``, each length-prefixed.

    The length prefix makes the key unambiguous: ``("ab", "c")`` and
    ``("a", "bc")`` give different keys.

    Args:
        *parts: strings (hashed as UTF-8) or bytes.

    Returns:
        64 lowercase hex digits.
    """
    digest = hashlib.sha256()
    for part in parts:
        data = part.encode("utf-8") if isinstance(part, str) else bytes(part)
        digest.update(len(data).to_bytes(8, "little"))
        digest.update(data)
    return digest.hexdigest()


def file_sha256(path: Path) -> str:
    """The sha256 hex digest of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _check_kind_key(kind: str, key: str) -> None:
    if not _KIND_RE.fullmatch(kind):
        raise ValueError(f"invalid cache kind {kind!r}")
    if not _KEY_RE.fullmatch(key):
        raise ValueError(f"invalid cache key {key!r}: expected 64 lowercase hex digits")


def kind_dir(kind: str) -> Path:
    """The folder of one kind of entries (created on demand)."""
    if not _KIND_RE.fullmatch(kind):
        raise ValueError(f"invalid cache kind {kind!r}")
    folder = cache_root() / kind
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def entry_path(kind: str, key: str) -> Path:
    """Where the entry of ``key`` lives (whether or not it exists)."""
    _check_kind_key(kind, key)
    return kind_dir(kind) / key


def verify(entry: Path, key: str) -> bool:
    """Whether ``entry`` is a complete, untampered entry for ``key``.

    The entry must be a directory whose ``meta.json`` parses, names ``key``
    and this cache format, lists plain file names with their sha256, and the
    directory must hold exactly those files (plus ``meta.json``) with those
    digests.

    Args:
        entry: the entry directory.
        key: the key it should hold.

    Returns:
        True if every check passes.
    """
    try:
        if entry.is_symlink() or not entry.is_dir():
            return False
        meta = json.loads((entry / META).read_text(encoding="utf-8"))
        if not isinstance(meta, dict) or meta.get("key") != key or meta.get("format") != FORMAT:
            return False
        files = meta.get("files")
        if not isinstance(files, dict) or not files:
            return False
        if set(os.listdir(entry)) != set(files) | {META}:
            return False
        for name, digest in files.items():
            if not isinstance(name, str) or not _FILE_RE.fullmatch(name) or name == META:
                return False
            path = entry / name
            if path.is_symlink() or not path.is_file() or file_sha256(path) != digest:
                return False
    except (OSError, ValueError, UnicodeDecodeError):
        return False
    return True


def lookup(kind: str, key: str) -> Path | None:
    """The verified entry of ``key``, or None.

    A present but invalid entry (truncated, corrupted, foreign) is moved aside
    and removed, so the caller can rebuild it.

    Args:
        kind: the kind of artefact (a folder name).
        key: the entry's content key.

    Returns:
        The entry directory, or None if missing or invalid.
    """
    entry = entry_path(kind, key)
    if not os.path.lexists(entry):
        return None
    if verify(entry, key):
        return entry
    discard(entry, key)
    return None


def discard(entry: Path, key: str | None = None) -> None:
    """Move an entry aside under a unique trash name, then delete it.

    Never raises for filesystem errors. If the moved directory turns out to be
    a valid entry for ``key`` (another process published a fresh one between
    our verification and the move), it is put back when the name is free.

    Args:
        entry: the entry directory (or stray file) to remove.
        key: the key it should have held, to detect the race above.
    """
    trash = entry.parent / f"{TRASH_PREFIX}{entry.name[:16]}-{uuid.uuid4().hex}"
    try:
        os.rename(entry, trash)
    except FileNotFoundError:
        return
    except OSError:
        _remove(entry)
        return
    if key is not None and verify(trash, key):
        try:
            os.rename(trash, entry)
            return
        except OSError:
            pass
    _remove(trash)


def _remove(path: Path) -> None:
    """Delete a file or directory tree, ignoring errors."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        try:
            path.unlink()
        except OSError:
            pass


def _write_meta(tmp: Path, kind: str, key: str) -> None:
    """Write ``meta.json`` listing every file of ``tmp`` with its sha256."""
    files = {}
    for path in sorted(tmp.iterdir()):
        if path.name == META:
            continue
        if path.is_symlink() or not path.is_file() or not _FILE_RE.fullmatch(path.name):
            raise ValueError(f"cache entry may hold only plain files, found {path.name!r}")
        files[path.name] = file_sha256(path)
    if not files:
        raise ValueError("cache entry holds no artefact")
    meta = {"format": FORMAT, "kind": kind, "key": key, "files": files, "created": time.time()}
    (tmp / META).write_text(json.dumps(meta, indent=1, sort_keys=True), encoding="utf-8")


def clean_stale(kind: str, max_age: float = STALE_SECONDS) -> None:
    """Remove temporary and trash directories older than ``max_age`` seconds."""
    now = time.time()
    folder = kind_dir(kind)
    try:
        names = os.listdir(folder)
    except OSError:
        return
    for name in names:
        if not name.startswith((TMP_PREFIX, TRASH_PREFIX)):
            continue
        path = folder / name
        try:
            old = now - path.lstat().st_mtime > max_age
        except OSError:
            continue
        if old:
            _remove(path)


def publish(kind: str, key: str, fill: Callable[[Path], None], *, attempts: int = 3) -> Path:
    """Build an entry in a temporary directory and publish it atomically.

    Args:
        kind: the kind of artefact (a folder name).
        key: the entry's content key.
        fill: writes the artefact files into the (empty) directory it is given;
            whatever it raises propagates after the temporary directory is removed.
        attempts: how often to retry when an invalid entry occupies the name.

    Returns:
        The published entry directory: ours, or an equal one another writer
        published first.

    Raises:
        OSError: if the entry could not be published after ``attempts`` tries.
    """
    final = entry_path(kind, key)
    clean_stale(kind)
    tmp = Path(tempfile.mkdtemp(prefix=TMP_PREFIX, dir=final.parent))
    try:
        fill(tmp)
        _write_meta(tmp, kind, key)
        os.chmod(tmp, 0o755)
        for _ in range(attempts):
            try:
                os.rename(tmp, final)
                return final
            except OSError:
                if lookup(kind, key) is not None:
                    return final
        raise OSError(f"could not publish cache entry {final}")
    finally:
        if tmp.exists():
            _remove(tmp)


def get_or_create(kind: str, key: str, fill: Callable[[Path], None]) -> tuple[Path, bool]:
    """The verified entry of ``key``, built with ``fill`` if missing or invalid.

    Returns:
        ``(entry, created)``: ``created`` is False on a cache hit.
    """
    entry = lookup(kind, key)
    if entry is not None:
        return entry, False
    return publish(kind, key, fill), True


def sources_digest() -> str:
    """Digest of the mechgen sources that shape generated code and model facts (symbolic, codegen, templates).

    Part of every key of generated text (user cache and mechgen/generated/): an edit to one of these
    files makes every earlier generation a miss. Memoised per process.
    """
    global _SOURCES_DIGEST
    if _SOURCES_DIGEST is None:
        root = Path(__file__).resolve().parent.parent
        files = sorted(p for sub in ("symbolic", "codegen") for p in (root / sub).rglob("*")
                       if p.is_file() and p.suffix in (".py", ".j2") and "__pycache__" not in p.parts)
        _SOURCES_DIGEST = content_key(*(f"{p.relative_to(root).as_posix()}\n".encode() + p.read_bytes()
                                        for p in files))
    return _SOURCES_DIGEST


_SOURCES_DIGEST: str | None = None
