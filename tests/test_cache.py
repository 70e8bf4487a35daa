"""The C build layer and the content-hash compile cache.

Every test uses a private cache under ``tmp_path`` (``MECHGEN_CACHE``). A
library that a test has loaded is never modified afterwards (truncating a
mapped file could crash the process): corruption tests corrupt entries that
were built but not loaded.
"""
from __future__ import annotations

import gc
import json
import os
import subprocess
import sys
import sysconfig
import time
import weakref
from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen.codegen import build, cache
from mechgen.errors import BuildError, CompilerUnavailable

REPO = Path(mechgen.__file__).resolve().parents[1]

# out[0][b, i] = scale * in[0][b, i] + in[1][i], returns sizes[1] (0 unless asked otherwise).
KERNEL = """\
int mg_affine(const double *const *in, double *const *out, const long *sizes, long nbatch)
{
    long b, i;
    const long n = sizes[0];
    for (b = 0; b < nbatch; b++) {
        for (i = 0; i < n; i++) {
            out[0][b * n + i] = SCALE * in[0][b * n + i] + in[1][i];
        }
    }
    return (int)sizes[1];
}
"""

needs_cc = pytest.mark.skipif(build.find_compiler() is None, reason="no C compiler")


def kernel(scale: float = 2.0) -> str:
    """The test kernel with a scale baked in (a different scale is a different key)."""
    return KERNEL.replace("SCALE", repr(float(scale)))


# The affine kernel plus filler that makes gcc -O3 slow enough, so that racers overlap.
SLOW_KERNEL = kernel(7.0) + "".join(
    f"double mg_filler{k}(const double *x)\n{{\n    return " + " + ".join(f"x[{j}] * x[{(j * 7 + k) % 64}]"
                                                                   for j in range(64)) + ";\n}\n"
    for k in range(15))


@pytest.fixture
def cache_dir(tmp_path, monkeypatch) -> Path:
    root = tmp_path / "cache"
    monkeypatch.setenv("MECHGEN_CACHE", str(root))
    return root


def entries(root: Path, kind: str = "c") -> list[str]:
    """Names in a kind folder of the cache."""
    folder = root / kind
    return sorted(os.listdir(folder)) if folder.exists() else []


def run_affine(caller, lib, scale: float, nbatch: int = 3, n: int = 4, rc: int = 0) -> None:
    """Bind the affine kernel through ``caller`` and check its numbers."""
    rng = np.random.default_rng(0)
    x = rng.standard_normal((nbatch, n))
    shift = rng.standard_normal(n)
    out = np.full((nbatch, n), np.nan)
    bound = caller.bind(build.function_address(lib, "mg_affine"), [x.ctypes.data, shift.ctypes.data],
                        [out.ctypes.data], [n, rc], nbatch, (x, shift, out, lib))
    assert bound() == rc
    np.testing.assert_array_equal(out, scale * x + shift)


def test_content_key_is_length_prefixed():
    assert cache.content_key("ab", "c") != cache.content_key("a", "bc")
    assert cache.content_key("ab", "c") == cache.content_key(b"ab", b"c")
    assert len(cache.content_key()) == 64


def test_cache_root_from_env(cache_dir):
    assert cache.cache_root() == cache_dir
    assert cache_dir.is_dir()


@needs_cc
def test_build_load_bind_and_cache_hit(cache_dir):
    compiles = build.STATS["compile"]
    path = build.build_shared(kernel(2.0), stem="affine")
    key = path.parent.name
    assert path.name == "libaffine.so"
    assert (path.parent / "libaffine.c").read_text() == build.marked_source(kernel(2.0), key)
    assert build.library_problem(path, key) is None
    assert path.parent.parent == cache_dir / "c"
    assert build.STATS["compile"] == compiles + 1
    mtime = path.stat().st_mtime_ns

    again = build.build_shared(kernel(2.0), stem="affine")
    assert again == path and path.stat().st_mtime_ns == mtime
    assert build.STATS["compile"] == compiles + 1

    lib = build.load_library(path)
    run_affine(build.get_caller(), lib, 2.0)
    run_affine(build.get_caller(), lib, 2.0, rc=7)
    assert path.parent.name in entries(cache_dir)
    assert not [e for e in entries(cache_dir) if e.startswith(".")]


def _corrupt(entry: Path, how: str) -> None:
    so = entry / "libaffine.so"
    if how == "truncated":
        data = so.read_bytes()
        so.write_bytes(data[: len(data) // 2])
    elif how == "random_bytes":
        so.write_bytes(os.urandom(so.stat().st_size))
    elif how == "garbage_meta":
        (entry / "meta.json").write_bytes(os.urandom(64))
    elif how == "foreign_meta":
        meta = json.loads((entry / "meta.json").read_text())
        meta["key"] = "0" * 64
        (entry / "meta.json").write_text(json.dumps(meta))
    elif how == "missing_meta":
        (entry / "meta.json").unlink()
    elif how == "extra_file":
        (entry / "intruder.so").write_bytes(b"\x7fELF")
    elif how == "file_not_dir":
        for f in entry.iterdir():
            f.unlink()
        entry.rmdir()
        entry.write_bytes(os.urandom(100))
    else:
        raise AssertionError(how)


@needs_cc
@pytest.mark.parametrize("how", ["truncated", "random_bytes", "garbage_meta", "foreign_meta", "missing_meta",
                                 "extra_file", "file_not_dir"])
def test_bad_entry_is_detected_and_rebuilt(cache_dir, how):
    path = build.build_shared(kernel(3.0), stem="affine")
    _corrupt(path.parent, how)
    key = path.parent.name
    with pytest.warns(RuntimeWarning, match="damaged compile-cache entry"):
        assert cache.lookup("c", key) is None
    assert not os.path.lexists(path.parent)
    compiles = build.STATS["compile"]
    rebuilt = build.build_shared(kernel(3.0), stem="affine")
    assert rebuilt == path and build.STATS["compile"] == compiles + 1
    assert cache.verify(rebuilt.parent, key)
    run_affine(build.get_caller(), build.load_library(rebuilt), 3.0)
    assert entries(cache_dir) == [key]


@needs_cc
def test_forged_library_is_refused_before_loading_and_rebuilt(cache_dir):
    path = build.build_shared(kernel(5.0), stem="affine")
    # Corrupt the library *and* forge a matching meta.json: verification passes, dlopen fails.
    path.write_bytes(b"not an ELF file")
    meta = json.loads((path.parent / "meta.json").read_text())
    meta["files"][path.name] = cache.file_sha256(path)
    meta["bytes"][path.name] = path.stat().st_size
    (path.parent / "meta.json").write_text(json.dumps(meta))
    assert cache.lookup("c", path.parent.name) == path.parent  # meta.json alone cannot tell

    compiles = build.STATS["compile"]
    with pytest.warns(RuntimeWarning, match="does not carry its build key"):  # refused before dlopen
        lib = build.load_shared(kernel(5.0), stem="affine")
    assert build.STATS["compile"] == compiles + 1
    run_affine(build.get_caller(), lib, 5.0)


_RACER = r"""
import ctypes, pathlib, sys, time
from mechgen.codegen import build
go, ready, scale = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2]), float(sys.argv[3])
source = pathlib.Path(sys.argv[4]).read_text()
build.find_compiler()
ready.touch()
deadline = time.monotonic() + 30
while not go.exists() and time.monotonic() < deadline:
    time.sleep(0.001)
path = build.build_shared(source, stem="affine")
lib = build.load_library(path)
x = (ctypes.c_double * 2)(1.0, 2.0); s = (ctypes.c_double * 2)(0.5, 0.25); o = (ctypes.c_double * 2)()
bound = build.CtypesCaller.bind(build.function_address(lib, "mg_affine"), [ctypes.addressof(x),
    ctypes.addressof(s)], [ctypes.addressof(o)], [2, 0], 1, (x, s, o))
assert bound() == 0 and list(o) == [scale * 1.0 + 0.5, scale * 2.0 + 0.25], list(o)
print(path, build.STATS["compile"])
"""


@needs_cc
def test_concurrent_builders_publish_one_entry(cache_dir, tmp_path):
    env = {**os.environ, "MECHGEN_CACHE": str(cache_dir),
           "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}
    go, source = tmp_path / "go", tmp_path / "race.c"
    source.write_text(SLOW_KERNEL)
    procs = []
    for k in range(4):
        procs.append(subprocess.Popen([sys.executable, "-c", _RACER, str(go), str(tmp_path / f"ready{k}"), "7.0",
                                       str(source)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                      text=True, env=env))
    try:
        deadline = time.monotonic() + 30
        while not all((tmp_path / f"ready{k}").exists() for k in range(4)) and time.monotonic() < deadline:
            time.sleep(0.005)
        go.touch()
        results = [p.communicate(timeout=60) for p in procs]
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait()
    for p, (out, err) in zip(procs, results):
        assert p.returncode == 0, err
    paths = {out.split()[0] for out, _ in results}
    assert len(paths) == 1
    (path,) = paths
    assert entries(cache_dir) == [Path(path).parent.name]
    assert cache.verify(Path(path).parent, Path(path).parent.name)
    compiles = build.STATS["compile"]
    assert str(build.build_shared(SLOW_KERNEL, stem="affine")) == path
    assert build.STATS["compile"] == compiles


def test_publish_loser_keeps_winner_and_removes_temp(cache_dir):
    key = cache.content_key("race")

    def fill(text):
        return lambda tmp: (tmp / "artefact.txt").write_text(text)

    winner = cache.publish("t", key, fill("first"))
    loser = cache.publish("t", key, fill("second"))
    assert loser == winner and (winner / "artefact.txt").read_text() == "first"
    assert entries(cache_dir, "t") == [key]


def test_publish_failure_leaves_nothing(cache_dir):
    def fill(tmp):
        (tmp / "half.txt").write_text("x")
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError, match="boom"):
        cache.publish("t", cache.content_key("fail"), fill)
    assert entries(cache_dir, "t") == []


def test_stale_temp_dirs_are_cleaned(cache_dir):
    folder = cache.kind_dir("t")
    old, fresh = folder / f"{cache.TMP_PREFIX}old", folder / f"{cache.TMP_PREFIX}fresh"
    for d in (old, fresh):
        d.mkdir()
        (d / "x").write_text("x")
    os.utime(old, (time.time() - 7200, time.time() - 7200))
    key = cache.content_key("clean")
    cache.publish("t", key, lambda tmp: (tmp / "a.txt").write_text("a"))
    assert entries(cache_dir, "t") == sorted([fresh.name, key])


def test_invalid_stem_and_key():
    for stem in ("../evil", "a b", "x" * 65, "", "1abc", "lib;rm"):
        with pytest.raises(ValueError):
            build.build_shared("int x;", stem=stem)
    with pytest.raises(ValueError):
        cache.lookup("c", "../../etc")


@pytest.fixture
def no_compiler(tmp_path, monkeypatch):
    empty = tmp_path / "empty-bin"
    empty.mkdir()
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(empty))
    build.reset_compiler_cache()
    yield
    build.reset_compiler_cache()


def test_no_compiler_raises(cache_dir, no_compiler):
    assert build.find_compiler() is None
    with pytest.raises(CompilerUnavailable):
        build.build_shared(kernel(), stem="affine")
    with pytest.raises(CompilerUnavailable):
        build.load_shared(kernel(), stem="affine")
    assert isinstance(build.make_caller(), build.CtypesCaller)
    assert entries(cache_dir) == []


def test_broken_cc_is_unavailable(cache_dir, monkeypatch):
    monkeypatch.setenv("CC", "/nonexistent/cc")
    build.reset_compiler_cache()
    try:
        with pytest.raises(CompilerUnavailable):
            build.build_shared(kernel(), stem="affine")
    finally:
        build.reset_compiler_cache()


@needs_cc
def test_ctypes_fallback_matches_mgcall(cache_dir):
    has_headers = (Path(sysconfig.get_paths()["include"]) / "Python.h").is_file()
    caller = build.get_caller()
    if has_headers:
        assert not isinstance(caller, build.CtypesCaller), "mgcall should build where Python.h exists"
    mgcall = build.load_mgcall() if has_headers else pytest.skip("no Python headers")
    lib = build.load_shared(kernel(1.5), stem="affine")
    for c in (mgcall, build.CtypesCaller()):
        run_affine(c, lib, 1.5, nbatch=5, n=7)
        run_affine(c, lib, 1.5, nbatch=1, n=1, rc=-3)
        run_affine(c, lib, 1.5, nbatch=0, n=2)

    x, shift, out = np.ones((2, 3)), np.zeros(3), np.zeros((2, 3))
    alive = weakref.ref(out)
    bound = mgcall.bind(build.function_address(lib, "mg_affine"), [x.ctypes.data, shift.ctypes.data],
                        [out.ctypes.data], [3, 0], 2, [x, shift, out, lib])
    assert isinstance(bound, mgcall.Bound)
    with pytest.raises(TypeError):
        bound(1)
    del out
    gc.collect()
    assert alive() is not None and bound() == 0 and alive()[1, 2] == 1.5
    del bound
    gc.collect()
    assert alive() is None
    with pytest.raises(ValueError):
        mgcall.bind(0, [], [], [], 1, None)
    with pytest.raises(TypeError):
        mgcall.bind(1, 5, [], [], 1, None)


@needs_cc
def test_compile_error_raises_build_error(cache_dir):
    bad = "int mg_bad(void) { return undeclared_thing + 1; }\n"
    with pytest.raises(BuildError, match="undeclared_thing") as info:
        build.build_shared(bad, stem="bad")
    assert Path(info.value.source_path).read_text() == bad
    assert "undeclared_thing" in info.value.stderr
    # A warning is an error too (generated code must compile warning-free).
    with pytest.raises(BuildError, match="unused"):
        build.build_shared("int mg_w(void) { int unused_var; return 0; }\n", stem="warn")
    assert entries(cache_dir) == []
