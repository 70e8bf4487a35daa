"""Build C sources into cached shared libraries and load them (stage: emit -> build -> load).

Input: C source text (generated kernels with the mechgen ABI
``int NAME(const double *const *in, double *const *out, const long *sizes, long nbatch)``).
Output: the path of a verified shared library in the content-hash compile
cache (:mod:`mechgen.codegen.cache`), a loaded :class:`ctypes.CDLL`, function
addresses, and a *caller* whose ``bind`` prepares no-argument calls of a
kernel: the ``mgcall`` CPython extension (vectorcall, tens of ns per call), or
a ctypes fallback with the same semantics when the extension cannot be built.

The compiler is run with an argument list (never a shell) and a timeout; the
cache key covers the source, flags, include directories, compiler identity,
machine and a format version, so a cached library is reused only when it
would be rebuilt identically.

Every library carries its build key (``mechgen_build_key``, appended to the
source), and a cached entry is used only when its source is the requested one
and its library carries that key, checked on the file's bytes *before* it is
loaded (a library of another build under forged metadata is never dlopen'ed).
A compiler that exits 0 without writing such a library (``CC=/bin/true``, a
script writing garbage), or cannot build even a trivial library, is
unavailable (:class:`CompilerUnavailable`: the pipeline falls back to numpy);
a compiler that builds the trivial library but fails on the source raises
:class:`BuildError`.
"""
from __future__ import annotations

import ctypes
import importlib.machinery
import importlib.util
import logging
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from collections import Counter
from functools import lru_cache
from pathlib import Path
from typing import Callable, Sequence

from mechgen.codegen import cache
from mechgen.errors import BuildError, CompilerUnavailable

log = logging.getLogger("mechgen")

DEFAULT_CFLAGS = ("-std=c99", "-O3", "-fPIC", "-shared", "-Wall", "-Wextra", "-Werror", "-pedantic")
BUILD_FORMAT = "mechgen-build-2"
#: prefix of the build key string every library carries (see marked_source)
KEY_MARKER = "mechgen-build-key:"
KIND = "c"
COMPILE_TIMEOUT = 120.0
VERSION_TIMEOUT = 30.0
_STEM_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")
MGCALL_SOURCE = Path(__file__).parent / "templates" / "c99" / "mgcall.c"
#: environment variable: "0" builds every library portably, "1" for this machine's processor (:data:`NATIVE_FLAGS`),
#: unset: for this machine's processor where it names its instruction sets (:func:`native_tuning`)
NATIVE_ENV = "MECHGEN_NATIVE"
#: the host tuning: the processor's vector instructions (GCC and Clang vectorise the chain loops with them: the
#: FPU force kernel at N = 10^6 in 291 us instead of 514 with AVX-512), and no contraction of a*b + c into an FMA,
#: so the values stay those of the default build (GCC does not contract in ISO C mode; Clang would)
NATIVE_FLAGS = ("-march=native", "-ffp-contract=off")

#: Counters of this process: "compile" (compiler runs), "hit" (cache hits), "miss".
STATS: Counter = Counter()

_compilers: dict[tuple[str | None, str | None], tuple[str, str] | None] = {}
#: (command, flags) -> why the compiler cannot build a trivial shared library ("" when it can)
_trivial: dict[tuple, str] = {}
#: a library any working C compiler builds with mechgen's flags (it needs the C library's math.h)
TRIVIAL_SOURCE = """\
#include <math.h>
double mechgen_probe(double x);
double mechgen_probe(double x) { return sqrt(x); }
const char mechgen_probe_marker[] = "mechgen-probe-ok";
"""


# ---------------------------------------------------------------------------
# compiler


def reset_compiler_cache() -> None:
    """Forget the compilers found so far (tests change ``CC``/``PATH``)."""
    _compilers.clear()
    _trivial.clear()
    _NATIVE_REJECTED.clear()


def _probe(command: str) -> tuple[str, str] | None:
    """``(command, identity)`` if ``command --version`` runs, else None."""
    try:
        argv = shlex.split(command)
    except ValueError:
        return None
    if not argv:
        return None
    exe = shutil.which(argv[0])
    if exe is None:
        return None
    try:
        done = subprocess.run([exe, *argv[1:], "--version"], capture_output=True, text=True,
                              timeout=VERSION_TIMEOUT, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    lines = (done.stdout or done.stderr).strip().splitlines()
    if done.returncode != 0 or not lines:
        return None
    return command, lines[0].strip()


def _compiler() -> tuple[str, str] | None:
    """The compiler command and its identity, probed once per ``(CC, PATH)``."""
    env = (os.environ.get("CC"), os.environ.get("PATH"))
    if env not in _compilers:
        cc = env[0]
        found = _probe(cc) if cc else next(filter(None, map(_probe, ("cc", "gcc", "clang"))), None)
        if found is None:
            log.info("no working C compiler (CC=%r)", cc)
        _compilers[env] = found
    return _compilers[env]


def find_compiler() -> str | None:
    """The C compiler command to use, or None.

    ``$CC`` if set (it may hold arguments, e.g. ``"ccache gcc"``; a broken
    ``$CC`` is not silently replaced), else the first of ``cc``, ``gcc``,
    ``clang`` on ``PATH`` whose ``--version`` runs. Checked once per process
    (per value of ``CC`` and ``PATH``).
    """
    found = _compiler()
    return found[0] if found else None


def compiler_identity() -> str | None:
    """The first line of the compiler's ``--version``, or None without a compiler."""
    found = _compiler()
    return found[1] if found else None


# ---------------------------------------------------------------------------
# build


def _check_stem(stem: str) -> None:
    if not isinstance(stem, str) or not _STEM_RE.fullmatch(stem):
        raise ValueError(f"invalid library stem {stem!r}: expected an identifier of at most 64 characters")


def build_key(source: str, cflags: Sequence[str], include_dirs: Sequence[str], ldflags: Sequence[str],
              identity: str, *extra: str) -> str:
    """The cache key of a build: everything that changes the library."""
    return cache.content_key(BUILD_FORMAT, source, "\0".join(cflags), "\0".join(map(str, include_dirs)),
                             "\0".join(ldflags), identity, platform.machine(), *extra)


def marked_source(source: str, key: str) -> str:
    """The source as built: ``source`` and a definition of ``mechgen_build_key``, the string
    ``KEY_MARKER + key`` that the library's bytes are checked for before it is loaded."""
    body = source if source.endswith("\n") else source + "\n"
    return (f"{body}\n/* mechgen: the build key, checked in the library before it is loaded */\n"
            f"const char mechgen_build_key[] = \"{KEY_MARKER}{key}\";\n")


def library_problem(path: Path, key: str) -> str | None:
    """Why the file at ``path`` is not a library built for ``key`` (read, never loaded); None if it is.

    The library must be a regular file carrying exactly one build key string, ``KEY_MARKER + key``.
    """
    try:
        data = cache.read_bounded(path)
    except (OSError, ValueError) as exc:
        return f"{Path(path).name} is unreadable ({exc})"
    marker = KEY_MARKER.encode()
    if data.count(marker) != 1 or (marker + key.encode()) not in data:
        return f"{Path(path).name} does not carry its build key"
    return None


def entry_check(key: str, source_name: str, source: str, output_name: str) -> cache.Check:
    """The content check of a build entry: its source is ``source`` and its library carries ``key``."""
    expected = source.encode("utf-8")

    def check(entry: Path) -> str | None:
        if cache.read_bounded(entry / source_name) != expected:
            return f"{source_name} is not the requested source"
        return library_problem(entry / output_name, key)

    return check


def _failed_source_path(key: str, stem: str, source: str) -> Path | None:
    """Keep the source of a failed build in the cache for reading; return its path (None if not writable)."""
    try:
        folder = cache.kind_dir("failed")
        path = folder / f"{stem}-{key[:16]}.c"
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=cache.TMP_PREFIX)
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(source)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as exc:
        log.info("could not keep the failed source: %s", exc)
        return None
    return path


def run_compiler(command: str, source_path: Path, output: Path, cflags: Sequence[str],
                 include_dirs: Sequence[str], ldflags: Sequence[str]) -> subprocess.CompletedProcess:
    """Run the compiler once; raise CompilerUnavailable if it cannot be started."""
    argv = [*shlex.split(command), *cflags, *(f"-I{d}" for d in include_dirs),
            "-o", str(output), str(source_path), *ldflags]
    STATS["compile"] += 1
    return _run(command, argv)


def _run(command: str, argv: list[str]) -> subprocess.CompletedProcess:
    """The compiler's run (within COMPILE_TIMEOUT); CompilerUnavailable if it cannot be started."""
    try:
        return subprocess.run(argv, capture_output=True, text=True, timeout=COMPILE_TIMEOUT, check=False)
    except OSError as exc:
        raise CompilerUnavailable(f"cannot run C compiler {command!r}: {exc}") from exc


#: a generated source marks with this line where it may be cut into translation units (before each kernel)
UNIT_MARK = "/* mechgen: unit */"
#: a marked source of more lines than this is compiled as one unit per kernel, several at once, then linked: a
#: 64-link pendulum's every kernel (760,000 lines, two kernels of 270,000 each at -O0) in about half the time on
#: two cores (the largest kernel's time on more), where one compiler process held 2 GB and ran them in turn
UNIT_LINES = 50_000


def units(source: str) -> list[str] | None:
    """The translation units of a marked source: the text before the first :data:`UNIT_MARK` (the includes)
    followed by each marked part; None for a source that is unmarked or of at most :data:`UNIT_LINES` lines."""
    if UNIT_MARK not in source or source.count("\n") <= UNIT_LINES:
        return None
    head, *parts = source.split(UNIT_MARK)
    return [head + part for part in parts]


def compile_units(command: str, parts: list[str], output: Path, cflags: Sequence[str],
                  include_dirs: Sequence[str], ldflags: Sequence[str]) -> subprocess.CompletedProcess:
    """Compile ``parts`` to objects, as many at once as this process may use processors, and link them into
    ``output``; the first failure's result (its stderr) or the link's."""
    compile_flags = [f for f in cflags if f != "-shared"] + ["-c"]
    with tempfile.TemporaryDirectory(prefix="mechgen-units-") as tmp:
        sources = [Path(tmp) / f"unit{i}.c" for i in range(len(parts))]
        for path, text in zip(sources, parts):
            path.write_text(text, encoding="utf-8")
        objects = [path.with_suffix(".o") for path in sources]
        workers = max(1, min(len(parts), len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                                else os.cpu_count() or 1))
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(workers) as pool:
            done = list(pool.map(lambda so: run_compiler(command, so[0], so[1], compile_flags, include_dirs, ()),
                                 zip(sources, objects)))
        failed = next((d for d in done if d.returncode != 0), None)
        if failed is not None:
            return failed
        return _run(command, [*shlex.split(command), *cflags, "-o", str(output), *map(str, objects), *ldflags])


def trivial_problem(command: str, cflags: Sequence[str], include_dirs: Sequence[str],
                    ldflags: Sequence[str]) -> str:
    """Why ``command`` cannot build :data:`TRIVIAL_SOURCE` into a shared library with these flags
    ("" when it can: then a failed build is the source's fault). Memoised per process."""
    memo = (command, tuple(cflags), tuple(include_dirs), tuple(ldflags))
    if memo not in _trivial:
        with tempfile.TemporaryDirectory(prefix="mechgen-probe-") as tmp:
            source, output = Path(tmp) / "probe.c", Path(tmp) / "libprobe.so"
            source.write_text(TRIVIAL_SOURCE, encoding="utf-8")
            try:
                done = run_compiler(command, source, output, cflags, include_dirs, ldflags)
            except (CompilerUnavailable, subprocess.SubprocessError) as exc:
                problem = str(exc)
            else:
                if done.returncode != 0:
                    problem = f"exit {done.returncode}: {(done.stderr or done.stdout).strip()[:500]}"
                elif not output.is_file() or b"mechgen-probe-ok" not in output.read_bytes():
                    problem = "it exits 0 but writes no library"
                else:
                    problem = ""
        _trivial[memo] = problem
    return _trivial[memo]


def _build_error(message: str, stderr: str, key: str, stem: str, source: str) -> BuildError:
    path = _failed_source_path(key, stem, source)
    err = BuildError(f"{message} on {path or 'the generated source'}:\n{stderr.strip()}")
    err.stderr = stderr
    err.source_path = path
    return err


def _build_entry(source: str, *, stem: str, output_name: str, cflags: Sequence[str],
                 include_dirs: Sequence[str], ldflags: Sequence[str], extra_key: Sequence[str] = ()) -> Path:
    """Build ``source`` into ``output_name`` inside a cache entry; return the output's path. With the host tuning
    (:func:`native_tuning`) first; a compiler that cannot build even a trivial library with it is asked once per
    process, on a failed build only, and the build is done portably (the probe costs nothing on a cache hit)."""
    _check_stem(stem)
    found = _compiler()
    if found is None:
        cc = os.environ.get("CC")
        raise CompilerUnavailable(f"CC={cc!r} does not run ({cc} --version failed)" if cc else
                                  "no working C compiler found (set CC, or install cc/gcc/clang)")
    command, _ = found
    tuning = native_tuning() if command not in _NATIVE_REJECTED else ((), ())
    try:
        return _build_tuned(source, stem, output_name, (cflags, include_dirs, ldflags, extra_key), found, tuning)
    except _NativeRejected:
        _NATIVE_REJECTED.add(command)
        log.info("%s does not build with %s: portable builds", command, " ".join(NATIVE_FLAGS))
        return _build_tuned(source, stem, output_name, (cflags, include_dirs, ldflags, extra_key), found, ((), ()))


class _NativeRejected(Exception):
    """The compiler builds no library with the host tuning's flags (an old or cross compiler)."""


#: compilers (commands) found in this process to reject :data:`NATIVE_FLAGS`
_NATIVE_REJECTED: set = set()


def _build_tuned(source: str, stem: str, output_name: str, flags: tuple, found: tuple, tuning: tuple) -> Path:
    """:func:`_build_entry` with ``tuning`` = (flags, key parts) of :func:`native_tuning`."""
    (cflags, include_dirs, ldflags, extra_key), (command, identity) = flags, found
    cflags, include_dirs, ldflags = tuple(cflags) + tuning[0], tuple(map(str, include_dirs)), tuple(ldflags)
    extra_key = tuple(extra_key) + tuning[1]
    # the file names are part of the entry: the same source under another stem is another entry
    key = build_key(source, cflags, include_dirs, ldflags, identity, stem, output_name, *extra_key)
    source_name = f"lib{stem}.c"
    built = marked_source(source, key)

    def fill(tmp: Path) -> None:
        source_path = tmp / source_name
        source_path.write_text(built, encoding="utf-8")
        parts = units(built)
        try:
            done = (compile_units(command, parts, tmp / output_name, cflags, include_dirs, ldflags) if parts
                    else run_compiler(command, source_path, tmp / output_name, cflags, include_dirs, ldflags))
        except subprocess.TimeoutExpired as exc:
            stderr = exc.stderr.decode(errors="replace") if isinstance(exc.stderr, bytes) else (exc.stderr or "")
            raise _build_error(f"C compiler timed out after {COMPILE_TIMEOUT:.0f} s", stderr, key, stem,
                               source) from exc
        if done.returncode != 0:
            if tuning[0] and trivial_problem(command, DEFAULT_CFLAGS + tuning[0], (), ()):
                raise _NativeRejected(command)
            if tmp.is_dir():  # (not when the cache was removed meanwhile: the cache layer retries)
                unusable = trivial_problem(command, cflags, include_dirs, ldflags)
                if unusable:
                    raise CompilerUnavailable(f"CC={command!r} cannot build a shared library ({unusable})")
            raise _build_error(f"C compiler {command!r} failed (exit {done.returncode})",
                               done.stderr or done.stdout, key, stem, source)
        problem = library_problem(tmp / output_name, key)
        if problem is not None and tmp.is_dir():
            raise CompilerUnavailable(f"CC={command!r} exited 0 but wrote no valid library ({problem})")

    entry, created = cache.get_or_create(KIND, key, fill, entry_check(key, source_name, built, output_name))
    STATS["miss" if created else "hit"] += 1
    return entry / output_name


def native_tuning() -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(flags, key parts) of the host tuning: :data:`NATIVE_FLAGS`, keyed by :func:`processor_identity` (a cache
    shared by machines of other processors never hands one theirs); both empty for a portable build.

    The default where the processor names its instruction sets (/proc/cpuinfo's flags or Features, so that two
    processors that differ in them never share a build); $MECHGEN_NATIVE=0 asks for portable builds everywhere,
    =1 for the tuning everywhere. A compiler that rejects the flags builds portably (:func:`_build_entry`). A peer
    such as numba compiles for the host as well: this is the like-for-like build (issue 30: the chain loops
    vectorise with the processor's widest instructions)."""
    choice = os.environ.get(NATIVE_ENV, "")
    if choice == "0" or (choice != "1" and not processor_names_its_instructions()):
        return (), ()
    return NATIVE_FLAGS, (processor_identity(),)


def processor_names_its_instructions() -> bool:
    """Whether :func:`processor_identity` holds the processor's instruction sets (Linux: flags on x86, Features
    on ARM)."""
    identity = processor_identity()
    return " flags: " in identity or " Features: " in identity


@lru_cache(maxsize=1)
def processor_identity() -> str:
    """The host processor: its model and feature flags as /proc/cpuinfo states them (Linux), else platform's
    machine and processor names."""
    fields: dict[str, str] = {}
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace").splitlines():
            name, _, value = line.partition(":")
            name = name.strip()
            if name in ("model name", "flags", "Features", "CPU part", "CPU implementer") and name not in fields:
                fields[name] = " ".join(value.split())
    except OSError:
        pass
    return " | ".join([platform.machine(), platform.processor(), *(f"{k}: {v}" for k, v in sorted(fields.items()))])


def build_shared(source: str, *, stem: str, cflags: Sequence[str] = DEFAULT_CFLAGS,
                 include_dirs: Sequence[str] = (), ldflags: Sequence[str] = ()) -> Path:
    """Compile C source to a shared library in the compile cache.

    Args:
        source: the C source text.
        stem: library name: the file is ``lib{stem}.so`` (an identifier, at most 64 characters).
        cflags: compiler flags (default: C99, -O3, warnings are errors).
        include_dirs: directories passed as ``-I``.
        ldflags: flags appended after the source file (e.g. ``-lm``).

    Returns:
        The path of the cached, verified ``.so`` (``lib{stem}.c`` lies beside it).

    Raises:
        ValueError: if ``stem`` is not a plain identifier.
        CompilerUnavailable: if no working C compiler is found.
        BuildError: if compilation fails; carries ``stderr`` and ``source_path``.
    """
    return _build_entry(source, stem=stem, output_name=f"lib{stem}.so", cflags=cflags,
                        include_dirs=include_dirs, ldflags=ldflags)


def invalidate(path: Path) -> None:
    """Remove the cache entry holding ``path`` (a library that would not load)."""
    entry = Path(path).resolve().parent
    if cache.owns(entry):
        cache.discard(entry)


# ---------------------------------------------------------------------------
# load


def load_library(path: Path | str) -> ctypes.CDLL:
    """Load a shared library (``dlopen``); raises OSError if it cannot be loaded."""
    return ctypes.CDLL(str(path))


def _with_retry(build: Callable[[], Path], load: Callable[[Path], object]):
    """Build and load; if loading fails, invalidate the entry and rebuild once.

    When the library had vanished (the cache removed while in use), the rebuild goes to a temporary
    cache (:func:`mechgen.codegen.cache.bypass`) if it vanishes again.
    """
    path = build()
    try:
        return load(path)
    except (OSError, ImportError) as exc:
        log.warning("cached library %s would not load (%s); rebuilding", path, exc)
        vanished = not os.path.exists(path)
        invalidate(path)
    for last in (False, True):
        path = build()
        try:
            return load(path)
        except (OSError, ImportError) as exc:
            if last or not (vanished and not os.path.exists(path)):
                raise BuildError(f"freshly built library {path} would not load: {exc}") from exc
            cache.bypass(cache.configured_root(), f"{path} was removed while it was loaded")


def load_checked(path: Path | str, symbols: Sequence[str] = ()) -> ctypes.CDLL:
    """Load a shared library that must export every name of ``symbols`` (OSError otherwise)."""
    lib = load_library(path)
    missing = [name for name in symbols if not hasattr(lib, name)]
    if missing:
        raise OSError(f"{path} does not export {', '.join(missing)}")
    return lib


def load_shared(source: str, *, stem: str, cflags: Sequence[str] = DEFAULT_CFLAGS,
                include_dirs: Sequence[str] = (), ldflags: Sequence[str] = (),
                symbols: Sequence[str] = ()) -> ctypes.CDLL:
    """Build (or find in the cache) and load a shared library, rebuilding once if it will not load.

    Arguments and errors are those of :func:`build_shared`; ``symbols`` are the names the library
    must export. A library that still will not load (or lacks one of them) after a rebuild raises
    BuildError.
    """
    return _with_retry(lambda: build_shared(source, stem=stem, cflags=cflags, include_dirs=include_dirs,
                                            ldflags=ldflags), lambda path: load_checked(path, symbols))


def function_address(lib: ctypes.CDLL, name: str) -> int:
    """The address of the exported function ``name`` of ``lib`` (AttributeError if absent)."""
    return ctypes.cast(getattr(lib, name), ctypes.c_void_p).value


# ---------------------------------------------------------------------------
# callers


KERNEL_FUNCTYPE = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_long)


class CtypesBound:
    """A prepared kernel call (ctypes): ``bound()`` runs the kernel and returns its int."""

    __slots__ = ("_fn", "_in", "_out", "_sizes", "_nbatch", "_args", "keepalive")

    def __init__(self, fn_address: int, in_ptrs: Sequence[int], out_ptrs: Sequence[int],
                 sizes: Sequence[int], nbatch: int, keepalive: object) -> None:
        if not fn_address:
            raise ValueError("bind: fn_address is NULL")
        if nbatch < 0:
            raise ValueError("bind: nbatch must be >= 0")
        self._fn = KERNEL_FUNCTYPE(int(fn_address))
        self._in = (ctypes.c_void_p * max(len(in_ptrs), 1))(*map(int, in_ptrs))
        self._out = (ctypes.c_void_p * max(len(out_ptrs), 1))(*map(int, out_ptrs))
        self._sizes = (ctypes.c_long * max(len(sizes), 1))(*map(int, sizes))
        self._nbatch = int(nbatch)
        self._args = (ctypes.addressof(self._in), ctypes.addressof(self._out), ctypes.addressof(self._sizes),
                      self._nbatch)
        self.keepalive = keepalive

    def __call__(self) -> int:
        return self._fn(*self._args)


class CtypesCaller:
    """Pure-Python fallback of the ``mgcall`` module: the same ``bind``."""

    Bound = CtypesBound

    @staticmethod
    def bind(fn_address: int, in_ptrs: Sequence[int], out_ptrs: Sequence[int], sizes: Sequence[int],
             nbatch: int, keepalive: object) -> CtypesBound:
        """A no-argument callable running the kernel at ``fn_address`` with these pointers."""
        return CtypesBound(fn_address, in_ptrs, out_ptrs, sizes, nbatch, keepalive)


def _python_key() -> tuple[str, ...]:
    """What makes an extension module specific to this interpreter."""
    return (sys.version, sys.implementation.cache_tag or "", sysconfig.get_config_var("EXT_SUFFIX") or "",
            getattr(sys, "abiflags", ""))


def _import_extension(name: str, path: Path):
    """Import the extension module at ``path`` (no sys.path or sys.modules changes)."""
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def load_mgcall():
    """Build (or find in the cache) and import the ``mgcall`` extension module.

    Raises:
        CompilerUnavailable: without a compiler.
        BuildError: if it does not compile (e.g. no Python headers) or load.
    """
    include = sysconfig.get_paths()["include"]
    if not (Path(include) / "Python.h").is_file():
        raise BuildError(f"Python headers not found in {include}")
    source = MGCALL_SOURCE.read_text(encoding="utf-8")
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    cflags = tuple(f for f in DEFAULT_CFLAGS if f != "-pedantic")

    def build() -> Path:
        return _build_entry(source, stem="mgcall", output_name=f"mgcall{suffix}", cflags=cflags,
                            include_dirs=(include,), ldflags=(), extra_key=_python_key())

    return _with_retry(build, lambda path: _import_extension("mgcall", path))


def make_caller():
    """The mgcall module, or the ctypes fallback if it cannot be built."""
    try:
        return load_mgcall()
    except (CompilerUnavailable, BuildError, OSError) as exc:
        log.info("mgcall extension unavailable (%s); using the ctypes caller", exc)
        return CtypesCaller()


@lru_cache(maxsize=1)
def get_caller():
    """An object with ``bind(fn_address, in_ptrs, out_ptrs, sizes, nbatch, keepalive)``, cached per process.

    ``bind`` returns a callable with no arguments that runs the kernel with the
    stored pointers and returns its int result, keeping ``keepalive`` alive.
    """
    return make_caller()
