"""Content-hash cache of built artefacts (stage: build -> cache -> load).

Input: a *kind* (a folder name such as ``"c"``), a *key* (:func:`content_key`
of everything that determines the artefacts) and a function that writes the
artefacts into an empty directory. Output: the path of a verified entry
directory ``cache_root()/kind/key`` holding the artefacts and a ``meta.json``
with the key, the kind and the sha256 and size of every artefact file.

Safety (DESIGN.md, "Safety rules of a code generator"):

* Writes are atomic: an entry is built in a temporary directory on the same
  filesystem and published with one ``os.rename``. A directory rename onto an
  existing entry fails, so when several processes build the same key at once
  exactly one wins; the others verify the winner and discard their own work.
* There are no lock files, so nothing can ever wait on a stale lock.
* Every lookup verifies the entry: ``meta.json`` (bounded in size and nesting
  before it is parsed), the sha256 of every artefact against it, and then the
  caller's own *check* of the artefacts' content against what the key stands
  for (``meta.json`` can be forged together with an artefact; a check such as
  "this file is the text whose hash is the key" or "this library carries its
  build key" cannot). A damaged, forged or foreign entry is reported once per
  process (RuntimeWarning), moved aside, deleted and reported as missing, so
  the caller rebuilds it; it is never loaded.
* A cache that cannot be written (``$MECHGEN_CACHE`` or a kind folder that is a
  file, a read-only directory, a cache removed while an entry was being built)
  is never fatal: entries are written to a temporary cache of this process
  instead (:func:`bypass`, one RuntimeWarning naming the problem); lookups
  still read the configured cache first.
* Files inside a published entry are never modified in place (a shared library
  may be mapped by a running process); bad entries are renamed, then removed.
* Leftover temporary and trash directories older than an hour (from a crashed
  writer) are removed opportunistically on publish.
"""
from __future__ import annotations

import atexit
import hashlib
import json
import logging
import os
import re
import shutil
import stat
import tempfile
import time
import uuid
import warnings
from pathlib import Path
from typing import Callable

import platformdirs

log = logging.getLogger("mechgen")

META = "meta.json"
FORMAT = 1
TMP_PREFIX = ".tmp-"
TRASH_PREFIX = ".trash-"
STALE_SECONDS = 3600.0
#: bounds checked before a JSON file of the cache is parsed
MAX_META_BYTES = 1 << 20
MAX_DOCUMENT_BYTES = 64 << 20
MAX_JSON_DEPTH = 64
#: no artefact is hashed (or read) beyond this size
MAX_ARTEFACT_BYTES = 1 << 30
_KIND_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}")
_KEY_RE = re.compile(r"[0-9a-f]{64}")
_FILE_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]{0,127}")
_JSON_STRING_RE = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"')
_JSON_BRACKET_RE = re.compile(r"[\[\]{}]")

#: a check of an entry's artefacts beyond meta.json: returns why the entry is refused, or None
Check = Callable[[Path], "str | None"]

#: configured root -> the temporary cache this process writes to instead (see bypass)
_fallbacks: dict[str, Path] = {}
#: (configured root, what) pairs already warned about in this process
_warned: set[tuple[str, str]] = set()


class CacheUnusable(OSError):
    """An entry could not be written in a cache directory (the caller bypasses it)."""

    def __init__(self, message: str, *, vanished: bool = False) -> None:
        super().__init__(message)
        self.vanished = vanished


# ----------------------------------------------------------------------------- roots
def configured_root() -> Path:
    """``$MECHGEN_CACHE`` if set (and not empty), else the user cache directory of platformdirs (not created)."""
    env = os.environ.get("MECHGEN_CACHE")
    return Path(env) if env else Path(platformdirs.user_cache_dir("mechgen"))


def _warn_once(root: Path, what: str, message: str) -> None:
    """One RuntimeWarning per configured root and kind of problem per process; later ones are logged."""
    tag = (str(root), what)
    if tag in _warned:
        log.info("%s", message)
        return
    _warned.add(tag)
    warnings.warn(message, RuntimeWarning, stacklevel=3)


def _reason(exc: BaseException) -> str:
    """A short reason for an OSError (its strerror and file), for messages."""
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.strerror}: {exc.filename}" if exc.filename else exc.strerror
    return str(exc) or type(exc).__name__


def _remove_fallback(path: Path, pid: int) -> None:
    if os.getpid() == pid:  # not in forked workers, which share it
        shutil.rmtree(path, ignore_errors=True)


def bypass(root: Path, reason: str) -> Path:
    """Write entries of ``root`` (a configured root) to a temporary cache of this process from now on.

    Warns once, naming the cache and ``reason``. The temporary cache is removed when the process exits.

    Returns:
        The temporary cache's root.
    """
    fallback = _fallbacks.get(str(root))
    if fallback is None:
        fallback = Path(tempfile.mkdtemp(prefix="mechgen-cache-"))
        _fallbacks[str(root)] = fallback
        atexit.register(_remove_fallback, fallback, os.getpid())
        _warn_once(root, "unusable", f"mechgen: the compile cache {root} is unusable ({reason}); building in a "
                                     f"temporary cache {fallback} for this process (set MECHGEN_CACHE to a "
                                     f"writable directory to keep what is built)")
    fallback.mkdir(parents=True, exist_ok=True)  # a temporary cache removed meanwhile is made again
    return fallback


def cache_root() -> Path:
    """The root entries are written to, created on demand.

    Returns:
        :func:`configured_root` when it is (or can be made) a writable directory, else this process's
        temporary cache (:func:`bypass`, one warning).
    """
    root = configured_root()
    if str(root) in _fallbacks:
        return bypass(root, "")
    try:
        root.mkdir(parents=True, exist_ok=True)
        if not root.is_dir():
            raise NotADirectoryError(f"{root} is not a directory")
        if not os.access(root, os.W_OK | os.X_OK):
            raise PermissionError(f"{root} is not writable")
    except OSError as exc:
        return bypass(root, _reason(exc))
    return root


def lookup_roots() -> list[Path]:
    """Where entries are looked up, in order: the configured root, then this process's temporary cache."""
    root = configured_root()
    fallback = _fallbacks.get(str(root))
    return [root] if fallback is None else [root, fallback]


def owns(entry: Path) -> bool:
    """Whether ``entry`` is an entry directory (``root/kind/key``) of one of the :func:`lookup_roots`."""
    try:
        parent = Path(entry).resolve().parent.parent
        return any(parent == root.resolve() for root in lookup_roots())
    except OSError:
        return False


# ----------------------------------------------------------------------------- hashing and bounded reading
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


def _open_regular(path: Path, max_bytes: int):
    """A binary file object of ``path`` if it is a regular file (no symlink, FIFO, device) of at most
    ``max_bytes``; ValueError otherwise (nothing can block or read without bound)."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f"{Path(path).name} is not a regular file")
        if info.st_size > max_bytes:
            raise ValueError(f"{Path(path).name} is larger than {max_bytes} bytes")
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bounded(path: Path, max_bytes: int = MAX_ARTEFACT_BYTES) -> bytes:
    """The bytes of a regular file of at most ``max_bytes`` (ValueError otherwise, OSError if unreadable)."""
    with _open_regular(path, max_bytes) as fh:
        data = fh.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise ValueError(f"{Path(path).name} is larger than {max_bytes} bytes")
    return data


def artefact_sha256(path: Path, max_bytes: int = MAX_ARTEFACT_BYTES) -> str:
    """The sha256 of a regular file of at most ``max_bytes`` (ValueError for anything else)."""
    digest = hashlib.sha256()
    size = 0
    with _open_regular(path, max_bytes) as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            size += len(block)
            if size > max_bytes:
                raise ValueError(f"{Path(path).name} is larger than {max_bytes} bytes")
            digest.update(block)
    return digest.hexdigest()


def json_depth(text: str) -> int:
    """The deepest nesting of arrays and objects in JSON text (brackets inside strings do not count)."""
    depth = deepest = 0
    for bracket in _JSON_BRACKET_RE.findall(_JSON_STRING_RE.sub("", text)):
        depth += 1 if bracket in "[{" else -1
        deepest = max(deepest, depth)
    return deepest


def parse_json(data: bytes | str, *, max_bytes: int = MAX_META_BYTES, max_depth: int = MAX_JSON_DEPTH):
    """Parse JSON whose size and nesting are checked first.

    Raises:
        ValueError: if it is larger than ``max_bytes``, nested deeper than ``max_depth``, not UTF-8 or not JSON.
    """
    if len(data) > max_bytes:
        raise ValueError(f"JSON larger than {max_bytes} bytes")
    text = data.decode("utf-8") if isinstance(data, bytes) else data
    if json_depth(text) > max_depth:
        raise ValueError(f"JSON nested deeper than {max_depth} levels")
    try:
        return json.loads(text)
    except RecursionError as exc:  # cannot happen within the depth bound; a second line of defence
        raise ValueError("JSON nested too deeply") from exc


def read_json(path: Path, *, max_bytes: int = MAX_META_BYTES, max_depth: int = MAX_JSON_DEPTH):
    """:func:`parse_json` of a regular file (ValueError for a non-regular or oversized file, OSError)."""
    return parse_json(read_bounded(path, max_bytes), max_bytes=max_bytes, max_depth=max_depth)


# ----------------------------------------------------------------------------- entries
def _check_kind_key(kind: str, key: str) -> None:
    if not isinstance(kind, str) or not _KIND_RE.fullmatch(kind):
        raise ValueError(f"invalid cache kind {kind!r}")
    if not isinstance(key, str) or not _KEY_RE.fullmatch(key):
        raise ValueError(f"invalid cache key {key!r}: expected 64 lowercase hex digits")


def kind_dir(kind: str) -> Path:
    """The folder of one kind of entries in :func:`cache_root` (created on demand; bypassed if unusable)."""
    if not _KIND_RE.fullmatch(kind):
        raise ValueError(f"invalid cache kind {kind!r}")
    root = cache_root()
    try:
        return _make_kind_dir(root, kind)
    except OSError as exc:
        if str(configured_root()) in _fallbacks:
            raise
        return _make_kind_dir(bypass(configured_root(), _reason(exc)), kind)


def _make_kind_dir(root: Path, kind: str) -> Path:
    folder = root / kind
    folder.mkdir(parents=True, exist_ok=True)
    if folder.is_symlink() or not folder.is_dir():
        raise NotADirectoryError(f"{folder} is not a directory")
    return folder


def entry_path(kind: str, key: str) -> Path:
    """Where the entry of ``key`` is written (whether or not it exists)."""
    _check_kind_key(kind, key)
    return kind_dir(kind) / key


def entry_problem(entry: Path, key: str) -> str | None:
    """Why ``entry`` is not a complete, untampered entry for ``key``; None when it is.

    The entry must be a directory whose ``meta.json`` (at most MAX_META_BYTES, nested at most
    MAX_JSON_DEPTH deep) parses, names ``key``, the entry's kind folder and this cache format, lists
    plain file names with their sha256 (and size), and the directory must hold exactly those files
    (plus ``meta.json``), regular files with those digests; a ``.json`` artefact is at most
    MAX_DOCUMENT_BYTES and nested at most MAX_JSON_DEPTH deep.
    """
    try:
        if entry.is_symlink() or not entry.is_dir():
            return "not a directory"
        meta = read_json(entry / META)
        if not isinstance(meta, dict):
            return "meta.json is not an object"
        if meta.get("key") != key:
            return "meta.json names another key"
        if meta.get("format") != FORMAT:
            return "meta.json has another format"
        if meta.get("kind", entry.parent.name) != entry.parent.name:
            return "meta.json names another kind"
        files, sizes = meta.get("files"), meta.get("bytes", {})
        if not isinstance(files, dict) or not files or not isinstance(sizes, dict):
            return "meta.json lists no artefact"
        if set(os.listdir(entry)) != set(files) | {META}:
            return "the files differ from those meta.json lists"
        for name, digest in files.items():
            if not isinstance(name, str) or not _FILE_RE.fullmatch(name) or name == META:
                return f"meta.json lists an invalid file name {name!r}"
            if not isinstance(digest, str) or not _KEY_RE.fullmatch(digest):
                return f"meta.json lists an invalid sha256 for {name}"
            path = entry / name
            size = sizes.get(name)
            if size is not None and (not isinstance(size, int) or path.lstat().st_size != size):
                return f"{name} does not have the size meta.json lists"
            if name.endswith(".json"):  # bounded here, so that no reader of the entry parses without bound
                data = read_bounded(path, MAX_DOCUMENT_BYTES)
                if hashlib.sha256(data).hexdigest() != digest:
                    return f"{name} does not have the sha256 meta.json lists"
                if json_depth(data.decode("utf-8")) > MAX_JSON_DEPTH:
                    return f"{name} is nested deeper than {MAX_JSON_DEPTH} levels"
            elif artefact_sha256(path) != digest:
                return f"{name} does not have the sha256 meta.json lists"
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        return f"unreadable: {_reason(exc)}"
    return None


def verify(entry: Path, key: str) -> bool:
    """Whether ``entry`` is a complete, untampered entry for ``key`` (:func:`entry_problem` is None)."""
    return entry_problem(entry, key) is None


def _refusal(entry: Path, key: str, check: Check | None) -> str | None:
    """:func:`entry_problem`, then the caller's ``check`` of the artefacts' content (its errors refuse)."""
    problem = entry_problem(entry, key)
    if problem is None and check is not None:
        try:
            problem = check(entry)
        except (OSError, ValueError, UnicodeDecodeError, KeyError, TypeError) as exc:
            problem = f"its content could not be checked ({_reason(exc)})"
    return problem


def lookup(kind: str, key: str, check: Check | None = None) -> Path | None:
    """The verified entry of ``key``, or None.

    A present but invalid entry (truncated, corrupted, foreign, refused by ``check``) is reported with
    one warning per process, moved aside and removed, so the caller can rebuild it.

    Args:
        kind: the kind of artefact (a folder name).
        key: the entry's content key.
        check: checks the artefacts' content against what ``key`` stands for; returns why it refuses
            the entry, or None.

    Returns:
        The entry directory, or None if missing or invalid.
    """
    _check_kind_key(kind, key)
    for root in lookup_roots():
        entry = root / kind / key
        if not os.path.lexists(entry):
            continue
        problem = _refusal(entry, key, check)
        if problem is None:
            return entry
        _warn_once(configured_root(), "damaged", f"mechgen: ignored a damaged compile-cache entry {entry} "
                                                 f"({problem}); it is rebuilt, never loaded")
        discard(entry, key, check)
    return None


def discard(entry: Path, key: str | None = None, check: Check | None = None) -> None:
    """Move an entry aside under a unique trash name, then delete it.

    Never raises for filesystem errors. If the moved directory turns out to be
    a valid entry for ``key`` (another process published a fresh one between
    our verification and the move), it is put back when the name is free.

    Args:
        entry: the entry directory (or stray file) to remove.
        key: the key it should have held, to detect the race above.
        check: the content check of that key's entries.
    """
    trash = entry.parent / f"{TRASH_PREFIX}{entry.name[:16]}-{uuid.uuid4().hex}"
    try:
        os.rename(entry, trash)
    except FileNotFoundError:
        return
    except OSError:
        _remove(entry)
        return
    if key is not None and _refusal(trash, key, check) is None:
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


def write_meta(tmp: Path, kind: str, key: str) -> None:
    """Write ``meta.json`` listing every file of ``tmp`` with its sha256 and size."""
    files, sizes = {}, {}
    for path in sorted(tmp.iterdir()):
        if path.name == META:
            continue
        if not os.path.lexists(path):  # removed while the entry is written (the cache deleted): an OSError
            raise FileNotFoundError(f"{path} vanished while its cache entry was written")
        if path.is_symlink() or not path.is_file() or not _FILE_RE.fullmatch(path.name):
            raise ValueError(f"cache entry may hold only plain files, found {path.name!r}")
        files[path.name] = artefact_sha256(path)
        sizes[path.name] = path.stat().st_size
    if not files:
        raise ValueError("cache entry holds no artefact")
    meta = {"format": FORMAT, "kind": kind, "key": key, "files": files, "bytes": sizes, "created": time.time()}
    (tmp / META).write_text(json.dumps(meta, indent=1, sort_keys=True), encoding="utf-8")


def clean_stale(kind: str, max_age: float = STALE_SECONDS) -> None:
    """Remove temporary and trash directories older than ``max_age`` seconds."""
    _clean_stale_in(kind_dir(kind), max_age)


def _clean_stale_in(folder: Path, max_age: float = STALE_SECONDS) -> None:
    now = time.time()
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


def _publish_in(root: Path, kind: str, key: str, fill: Callable[[Path], None], attempts: int,
                check: Check | None) -> Path:
    """:func:`publish` in one root; CacheUnusable when the root cannot take the entry."""
    try:
        folder = _make_kind_dir(root, kind)
        _clean_stale_in(folder)
        tmp = Path(tempfile.mkdtemp(prefix=TMP_PREFIX, dir=folder))
    except OSError as exc:
        raise CacheUnusable(f"cannot write in {root / kind}: {_reason(exc)}") from exc
    final = folder / key
    try:
        try:
            fill(tmp)
        except Exception:
            if not tmp.is_dir():
                raise CacheUnusable(f"{tmp} was removed while the entry was built", vanished=True) from None
            raise
        try:
            write_meta(tmp, kind, key)
            os.chmod(tmp, 0o755)
        except OSError as exc:
            raise CacheUnusable(f"cannot write in {tmp}: {_reason(exc)}", vanished=not tmp.is_dir()) from exc
        for _ in range(attempts):
            try:
                os.rename(tmp, final)
                return final
            except OSError:
                if not tmp.is_dir():
                    raise CacheUnusable(f"{tmp} was removed before it was published", vanished=True) from None
                if os.path.lexists(final):
                    problem = _refusal(final, key, check)
                    if problem is None:
                        return final
                    discard(final, key, check)
        raise CacheUnusable(f"could not publish cache entry {final}")
    finally:
        if os.path.lexists(tmp):
            _remove(tmp)


def publish(kind: str, key: str, fill: Callable[[Path], None], *, attempts: int = 3,
            check: Check | None = None) -> Path:
    """Build an entry in a temporary directory and publish it atomically.

    When the cache cannot take it (not a directory, read-only, removed while the entry was built: a
    removal is retried once), the entry is built in this process's temporary cache (:func:`bypass`).

    Args:
        kind: the kind of artefact (a folder name).
        key: the entry's content key.
        fill: writes the artefact files into the (empty) directory it is given;
            whatever it raises propagates after the temporary directory is removed.
        attempts: how often to retry when an invalid entry occupies the name.
        check: the content check of the entry (see :func:`lookup`), applied to another writer's entry.

    Returns:
        The published entry directory: ours, or an equal one another writer
        published first.

    Raises:
        OSError: if even the temporary cache could not take the entry.
    """
    _check_kind_key(kind, key)
    retried = False
    while True:
        root = cache_root()
        try:
            return _publish_in(root, kind, key, fill, attempts, check)
        except CacheUnusable as exc:
            configured = configured_root()
            if exc.vanished and not retried:
                retried = True
                continue
            if str(configured) in _fallbacks and root == _fallbacks[str(configured)]:
                raise OSError(f"the temporary compile cache {root} is unusable too: {exc}") from exc
            bypass(configured, str(exc))


def get_or_create(kind: str, key: str, fill: Callable[[Path], None],
                  check: Check | None = None) -> tuple[Path, bool]:
    """The verified entry of ``key``, built with ``fill`` if missing or invalid.

    Returns:
        ``(entry, created)``: ``created`` is False on a cache hit.
    """
    entry = lookup(kind, key, check)
    if entry is not None:
        return entry, False
    return publish(kind, key, fill, check=check), True


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
