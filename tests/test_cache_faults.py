"""Fault injection into the compile cache (issue 12, section 5): every fault is survived.

Each test copies a pristine cache (built once, never loaded in this process) into its own
``tmp_path`` cache, damages it, forges its metadata or makes it unusable, then compiles the
spring pendulum again and asserts:

* the kernels' numbers equal those of a fresh numpy build of the same specialisation that never
  touches a cache (generated from the model, loaded from memory);
* at most one RuntimeWarning, no exception;
* nothing forged is executed: forged libraries and modules write a sentinel file when they are
  loaded (a C constructor, module-level Python), and the sentinel never appears.

Forged files replace the originals with ``os.replace`` (a mapped library is never written in place).
"""
from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
import textwrap
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import mechgen
import mechgen.pipeline as pipeline
from mechgen import models
from mechgen.codegen import build, cache
from mechgen.errors import BuildError
from mechgen.runtime.core.kernels import load_module, numpy_kernels
from mechgen.runtime.core.pattern import extent
from mechgen.symbolic.specialize import specialize

REPO = Path(mechgen.__file__).resolve().parents[1]
MODEL = "spring_pendulum"
VALUES = {"k": 123.0}
OTHER = {"k": 7.0}
KERNELS = {"residual", "linear"}
needs_cc = pytest.mark.skipif(build.find_compiler() is None, reason="no C compiler")


# ----------------------------------------------------------------------------- helpers
def request_for(values: dict, backend: str = "c") -> pipeline.CompileRequest:
    model = models.get(MODEL)
    return pipeline.request_of(model, specialize(model, values), kernels=KERNELS, backend=backend)


def compile_(values: dict = VALUES, backend: str = "c"):
    model = models.get(MODEL)
    return pipeline.compile_model(model, specialize(model, values), kernels=KERNELS, backend=backend)


@pytest.fixture(scope="module")
def reference() -> dict:
    """Kernels of a fresh numpy generation of VALUES: derived now, loaded from memory, no cache involved."""
    model = models.get(MODEL)
    generated = pipeline.generate(model, specialize(model, VALUES), KERNELS, "numpy")
    return numpy_kernels(load_module(Path("<reference>"), "mg_reference_faults", source=generated["text"]))


def assert_numbers(system, reference: dict) -> None:
    """Every kernel of ``system`` gives the reference's outputs at random inputs."""
    assert set(system.kernels) == set(reference)
    rng = np.random.default_rng(12)
    for name, kernel in system.kernels.items():
        inputs = {p["name"]: rng.standard_normal((3, extent(p["extent"], {})))
                  for p in kernel.spec["inputs"] if not p["integer"]}
        got, want = kernel.evaluate(inputs), reference[name].evaluate(inputs)
        for out, value in want.items():
            np.testing.assert_allclose(got[out], value, rtol=1e-13, atol=1e-13 * (1 + np.abs(value).max(initial=0.0)))


def recorded(fn):
    """``(result, RuntimeWarnings)`` of ``fn()``: every warning is recorded, none is filtered."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn()
    return result, [w for w in caught if issubclass(w.category, RuntimeWarning)]


def survive(reference, backend: str = "c", *, at_most: int = 1, values: dict = VALUES):
    """Compile after a fault: right numbers, at most ``at_most`` warnings; returns (system, report, warnings)."""
    (system, report), caught = recorded(lambda: compile_(values, backend))
    assert len(caught) <= at_most, [str(w.message) for w in caught]
    assert_numbers(system, reference)
    return system, report, caught


def forge_meta(entry: Path) -> None:
    """Rewrite meta.json to match the entry's files, as a forger would."""
    meta = json.loads((entry / cache.META).read_text())
    names = sorted(p.name for p in entry.iterdir() if p.name != cache.META)
    meta["files"] = {n: cache.file_sha256(entry / n) for n in names}
    meta["bytes"] = {n: (entry / n).stat().st_size for n in names}
    replace_bytes(entry / cache.META, json.dumps(meta).encode())


def replace_bytes(path: Path, data: bytes) -> None:
    """Replace a file by new bytes without writing into the old inode (it may be mapped)."""
    tmp = path.with_name(path.name + ".forging")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def c_entry(root: Path, values: dict = VALUES) -> Path:
    """The C entry holding the kernels of ``values`` (the key of its generated text)."""
    text = pipeline.read_index(request_for(values), request_for(values).key())["text"]
    for entry in (root / "c").iterdir():
        source = entry / "libmgkernels.c"
        if source.is_file() and source.read_text().startswith(text):
            return entry
    raise AssertionError("no C entry")


def index_entry(root: Path, values: dict = VALUES, backend: str = "c") -> Path:
    return root / "index" / request_for(values, backend).key()


def kind_entries(root: Path, kind: str) -> list[str]:
    folder = root / kind
    return sorted(os.listdir(folder)) if folder.is_dir() else []


SENTINEL_C = r"""
#include <stdio.h>
static void mg_forged(void) __attribute__((constructor));
static void mg_forged(void)
{
    FILE *f = fopen("SENTINEL", "w");
    if (f) { fputs("loaded", f); fclose(f); }
}
int mg_residual(const double *const *in, double *const *out, const long *sizes, long nbatch)
{ (void)in; (void)out; (void)sizes; (void)nbatch; return 0; }
int mg_linear(const double *const *in, double *const *out, const long *sizes, long nbatch)
{ (void)in; (void)out; (void)sizes; (void)nbatch; return 0; }
"""


def sentinel_library(tmp_path: Path, sentinel: Path, marker: str = "") -> bytes:
    """A shared library whose constructor writes ``sentinel`` when it is dlopen'ed (and exports the kernels)."""
    source = tmp_path / "forged.c"
    source.write_text(SENTINEL_C.replace("SENTINEL", str(sentinel)) + marker)
    output = tmp_path / "libforged.so"
    subprocess.run([*build.find_compiler().split(), "-shared", "-fPIC", "-o", str(output), str(source)], check=True)
    return output.read_bytes()


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    """A cache with the index and C library of VALUES and OTHER and the numpy module of VALUES.

    Built in this process without loading any library (build_shared compiles only), so each test's copy
    is loaded fresh.
    """
    root = tmp_path_factory.mktemp("pristine") / "cache"
    saved = os.environ.get("MECHGEN_CACHE")
    os.environ["MECHGEN_CACHE"] = str(root)
    try:
        model = models.get(MODEL)
        for values in (VALUES, OTHER):
            spec = specialize(model, values)
            request = pipeline.request_of(model, spec, kernels=KERNELS, backend="c")
            generated = pipeline.generated_text(request, lambda spec=spec: (model, spec), pipeline.BuildReport("c"))
            if build.find_compiler():
                build.build_shared(generated["text"], stem="mgkernels")
        compile_(VALUES, "numpy")  # (a numpy module is executed from memory: loading it here is harmless)
        if build.find_compiler():
            build.get_caller()  # the mgcall extension, loaded once per process: later copies need no build
    finally:
        if saved is None:
            os.environ.pop("MECHGEN_CACHE", None)
        else:
            os.environ["MECHGEN_CACHE"] = saved
    return root


@pytest.fixture
def root(tmp_path, monkeypatch, pristine) -> Path:
    """This test's cache: a copy of the pristine one."""
    here = tmp_path / "cache"
    shutil.copytree(pristine, here, symlinks=True)
    monkeypatch.setenv("MECHGEN_CACHE", str(here))
    monkeypatch.setattr(pipeline, "_warned_no_compiler", False)
    build.reset_compiler_cache()
    yield here
    build.reset_compiler_cache()


# ----------------------------------------------------------------------------- the index (generated text)
@needs_cc
def test_intact_cache_is_hit_without_warnings(root, reference):
    _, report, caught = survive(reference, at_most=0)
    assert report.origin == "cache" and report.cached and report.backend == "c"


@needs_cc
@pytest.mark.parametrize("forged", ["{}", '{"text": "", "specs": {}}', "[]", "null", '"text"'])
def test_forged_empty_index_is_rederived(root, reference, forged):
    entry = index_entry(root)
    replace_bytes(entry / "generated.json", forged.encode())
    forge_meta(entry)
    _, report, caught = survive(reference)
    assert report.origin == "derived" and len(caught) == 1 and "damaged compile-cache entry" in str(caught[0].message)
    assert pipeline.read_index(request_for(VALUES), request_for(VALUES).key()) is not None  # rebuilt


@needs_cc
def test_index_of_another_request_is_refused(root, reference):
    mine, other = index_entry(root), index_entry(root, OTHER)
    shutil.copyfile(other / "generated.json", mine / "generated.json.new")
    os.replace(mine / "generated.json.new", mine / "generated.json")
    forge_meta(mine)
    _, report, caught = survive(reference)
    assert report.origin == "derived" and "another" in str(caught[0].message)


@needs_cc
def test_index_with_edited_text_is_refused(root, reference):
    """The text is changed (k = 123 -> 124) and meta.json forged: the recorded text sha256 no longer matches."""
    entry = index_entry(root)
    doc = json.loads((entry / "generated.json").read_text())
    assert "123.0" in doc["text"]
    doc["text"] = doc["text"].replace("123.0", "124.0")
    replace_bytes(entry / "generated.json", json.dumps(doc).encode())
    forge_meta(entry)
    _, report, _ = survive(reference)
    assert report.origin == "derived"


@needs_cc
@pytest.mark.parametrize("where", ["meta", "document"])
def test_deeply_nested_json_is_refused_before_parsing(root, reference, where):
    entry = index_entry(root)
    deep = b"[" * 200_000 + b"]" * 200_000
    if where == "meta":
        replace_bytes(entry / cache.META, deep)
    else:
        replace_bytes(entry / "generated.json", deep)
        forge_meta(entry)
    with pytest.raises(ValueError, match="nested deeper"):
        cache.parse_json(deep)
    _, report, _ = survive(reference)
    assert report.origin == "derived"


@needs_cc
def test_oversized_meta_is_refused(root, reference):
    entry = index_entry(root)
    meta = json.loads((entry / cache.META).read_text())
    meta["padding"] = "x" * (cache.MAX_META_BYTES + 1)
    replace_bytes(entry / cache.META, json.dumps(meta).encode())
    _, report, _ = survive(reference)
    assert report.origin == "derived"


@needs_cc
def test_meta_as_fifo_does_not_block(root, reference):
    entry = index_entry(root)
    (entry / cache.META).unlink()
    os.mkfifo(entry / cache.META)
    done = []
    worker = threading.Thread(target=lambda: done.append(survive(reference)), daemon=True)
    worker.start()
    worker.join(120)
    assert done, "compiling with a FIFO as meta.json blocked"


@needs_cc
def test_artefact_symlinked_to_a_device_is_refused(root, reference):
    entry = index_entry(root)
    (entry / "generated.json").unlink()
    os.symlink("/dev/zero", entry / "generated.json")
    _, report, _ = survive(reference)
    assert report.origin == "derived"


@needs_cc
@pytest.mark.parametrize("how", ["truncated", "file_not_dir", "empty_dir", "missing_meta"])
def test_damaged_index_is_rebuilt(root, reference, how):
    entry = index_entry(root)
    if how == "truncated":
        data = (entry / "generated.json").read_bytes()
        replace_bytes(entry / "generated.json", data[: len(data) // 2])
    elif how == "file_not_dir":
        shutil.rmtree(entry)
        entry.write_bytes(b"junk")
    elif how == "empty_dir":
        shutil.rmtree(entry)
        entry.mkdir()
    else:
        (entry / cache.META).unlink()
    _, report, _ = survive(reference)
    assert report.origin == "derived"
    assert cache.verify(entry, entry.name)


# ----------------------------------------------------------------------------- the C library
@needs_cc
def test_library_of_another_model_under_forged_metadata_is_never_loaded(root, reference):
    """Another specialisation's library (the wrong numbers, the same symbols) put in this entry, meta.json forged."""
    mine, other = c_entry(root), c_entry(root, OTHER)
    replace_bytes(mine / "libmgkernels.so", (other / "libmgkernels.so").read_bytes())
    forge_meta(mine)
    assert cache.verify(mine, mine.name)  # meta.json alone cannot tell
    _, report, caught = survive(reference)
    assert len(caught) == 1 and "does not carry its build key" in str(caught[0].message)
    assert build.library_problem(mine / "libmgkernels.so", mine.name) is None  # rebuilt


@needs_cc
@pytest.mark.parametrize("with_source", [False, True])
def test_forged_library_with_a_constructor_is_never_dlopened(root, reference, tmp_path, with_source):
    """A library whose constructor writes a sentinel, under forged metadata (optionally with a forged source
    that claims the right key): the check runs on the file's bytes before dlopen."""
    sentinel = tmp_path / "SENTINEL"
    entry = c_entry(root)
    replace_bytes(entry / "libmgkernels.so", sentinel_library(tmp_path, sentinel))
    if with_source:
        replace_bytes(entry / "libmgkernels.c", SENTINEL_C.encode())
    forge_meta(entry)
    survive(reference)
    assert not sentinel.exists()


@needs_cc
def test_edited_source_under_forged_metadata_is_refused(root, reference):
    entry = c_entry(root)
    source = (entry / "libmgkernels.c").read_text()
    replace_bytes(entry / "libmgkernels.c", source.replace("123.0", "124.0").encode())
    forge_meta(entry)
    _, _, caught = survive(reference)
    assert len(caught) == 1 and "not the requested source" in str(caught[0].message)


@needs_cc
@pytest.mark.parametrize("how", ["truncated", "random", "deep_meta", "other_kind"])
def test_damaged_library_entry_is_rebuilt(root, reference, how):
    entry = c_entry(root)
    so = entry / "libmgkernels.so"
    if how == "truncated":
        data = so.read_bytes()
        replace_bytes(so, data[: len(data) // 2])
    elif how == "random":
        replace_bytes(so, os.urandom(so.stat().st_size))
    elif how == "deep_meta":
        replace_bytes(entry / cache.META, b'{"a":' * 100_000 + b"1" + b"}" * 100_000)
    else:
        meta = json.loads((entry / cache.META).read_text())
        meta["kind"] = "numpy"
        replace_bytes(entry / cache.META, json.dumps(meta).encode())
    _, report, _ = survive(reference)
    assert not report.cached and cache.verify(entry, entry.name)


# ----------------------------------------------------------------------------- the numpy module
def numpy_entry(root: Path) -> Path:
    (entry,) = [root / "numpy" / name for name in kind_entries(root, "numpy")]
    return entry


def test_numpy_module_under_forged_metadata_is_never_executed(root, reference, tmp_path):
    sentinel = tmp_path / "SENTINEL"
    entry = numpy_entry(root)
    (module,) = [p for p in entry.iterdir() if p.suffix == ".py"]
    evil = f"open({str(sentinel)!r}, 'w').write('executed')\n" + module.read_text().replace("123.0", "124.0")
    replace_bytes(module, evil.encode())
    forge_meta(entry)
    _, report, caught = survive(reference, "numpy")
    assert not sentinel.exists()
    assert len(caught) == 1 and "is not the text of its key" in str(caught[0].message)
    assert module.read_bytes() != evil.encode()  # rebuilt


def test_truncated_numpy_module_is_rebuilt(root, reference):
    entry = numpy_entry(root)
    (module,) = [p for p in entry.iterdir() if p.suffix == ".py"]
    data = module.read_bytes()
    replace_bytes(module, data[: len(data) // 2])
    survive(reference, "numpy")
    assert cache.verify(entry, entry.name)


# ----------------------------------------------------------------------------- unusable caches
def _bypassed(caught, root: Path) -> None:
    assert len(caught) == 1 and "unusable" in str(caught[0].message) and str(root) in str(caught[0].message)


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_cache_root_is_a_file(tmp_path, monkeypatch, reference, backend):
    if backend == "c" and build.find_compiler() is None:
        pytest.skip("no C compiler")
    path = tmp_path / "cache-file"
    path.write_text("not a directory")
    monkeypatch.setenv("MECHGEN_CACHE", str(path))
    _, report, caught = survive(reference, backend)
    _bypassed(caught, path)
    assert path.read_text() == "not a directory"  # left alone
    _, again, caught = survive(reference, backend, at_most=0)  # the temporary cache serves the process
    assert again.origin == "cache"


def test_cache_root_below_a_file(tmp_path, monkeypatch, reference):
    (tmp_path / "file").write_text("x")
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "file" / "cache"))
    _, _, caught = survive(reference, "numpy")
    _bypassed(caught, tmp_path / "file" / "cache")


@pytest.mark.parametrize("kind", ["c", "index", "numpy"])
def test_kind_folder_is_a_file(root, reference, kind):
    if kind == "c" and build.find_compiler() is None:
        pytest.skip("no C compiler")
    shutil.rmtree(root / kind)
    (root / kind).write_text("not a directory")
    _, report, caught = survive(reference, "numpy" if kind == "numpy" else "c")
    _bypassed(caught, root)
    assert (root / kind).read_text() == "not a directory"


def read_only(path: Path):
    """A context that makes ``path`` read-only (a read-only bind mount as root, else chmod), or skips."""
    import contextlib

    @contextlib.contextmanager
    def ctx():
        if os.geteuid() != 0:
            mode = path.stat().st_mode
            for p in [path, *path.rglob("*")]:
                if p.is_dir():
                    p.chmod(0o555)
            try:
                yield
            finally:
                for p in [path, *path.rglob("*")]:
                    if p.is_dir():
                        p.chmod(stat.S_IMODE(mode))
            return
        done = subprocess.run(["mount", "--bind", "-o", "ro", str(path), str(path)], capture_output=True)
        if done.returncode != 0:
            pytest.skip(f"cannot make a read-only directory as root: {done.stderr.decode().strip()}")
        try:
            yield
        finally:
            subprocess.run(["umount", "-l", str(path)], check=True)  # lazily: a loaded library keeps it busy

    return ctx()


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_empty_read_only_cache(tmp_path, monkeypatch, reference, backend):
    if backend == "c" and build.find_compiler() is None:
        pytest.skip("no C compiler")
    path = tmp_path / "ro-cache"
    path.mkdir()
    monkeypatch.setenv("MECHGEN_CACHE", str(path))
    with read_only(path):
        _, report, caught = survive(reference, backend)
        _bypassed(caught, path)
        assert os.listdir(path) == []


@needs_cc
def test_populated_read_only_cache_is_read(root, reference):
    with read_only(root):
        _, report, caught = survive(reference, at_most=0)
        assert report.origin == "cache" and report.cached


@needs_cc
def test_damaged_entry_in_a_read_only_cache(root, reference):
    """A damaged entry that cannot be removed: refused (one warning), rebuilt in a temporary cache (another)."""
    entry = c_entry(root)
    replace_bytes(entry / "libmgkernels.so", b"\x7fELF junk")
    forge_meta(entry)
    with read_only(root):
        _, _, caught = survive(reference, at_most=2)
        messages = [str(w.message) for w in caught]
        assert {"damaged compile-cache entry" in m for m in messages} == {True, False}, messages


# ----------------------------------------------------------------------------- the cache removed while running
def _remove_root(root: Path) -> None:
    shutil.rmtree(root, ignore_errors=True)


@needs_cc
def test_cache_removed_during_the_compile(root, reference, monkeypatch):
    shutil.rmtree(root / "c")  # a C build is due
    real = build.run_compiler
    calls = []

    def compile_and_remove(*args, **kwargs):
        if not calls:
            calls.append(1)
            _remove_root(root)
        return real(*args, **kwargs)

    monkeypatch.setattr(build, "run_compiler", compile_and_remove)
    _, report, _ = survive(reference)
    assert report.backend == "c"


@needs_cc
def test_cache_removed_between_lookup_and_dlopen(root, reference, monkeypatch):
    real = build.load_library
    calls = []

    def remove_then_load(path):
        if not calls:
            calls.append(1)
            _remove_root(root)
        return real(path)

    monkeypatch.setattr(build, "load_library", remove_then_load)
    _, report, _ = survive(reference)
    assert report.backend == "c"


@needs_cc
def test_cache_removed_between_generation_and_build(root, reference, monkeypatch):
    shutil.rmtree(root / "index")
    real = pipeline.generate

    def generate_then_remove(*args, **kwargs):
        result = real(*args, **kwargs)
        _remove_root(root)
        return result

    monkeypatch.setattr(pipeline, "generate", generate_then_remove)
    _, report, _ = survive(reference)
    assert report.origin == "derived"


@needs_cc
def test_cache_removed_while_an_entry_is_published(root, reference, monkeypatch):
    """Removed after the artefact was written and before meta.json: the publication is retried."""
    shutil.rmtree(root / "index")
    real = cache.write_meta
    calls = []

    def remove_then_write(tmp, kind, key):
        if not calls:
            calls.append(1)
            _remove_root(root)
        return real(tmp, kind, key)

    monkeypatch.setattr(cache, "write_meta", remove_then_write)
    _, report, _ = survive(reference)
    assert report.origin == "derived"


@needs_cc
def test_cache_removed_between_two_compiles_of_a_scene(root, reference):
    survive(reference, at_most=0)
    _remove_root(root)
    _, report, caught = survive(reference, at_most=0)
    assert report.origin in ("derived", "generated")


@needs_cc
def test_cache_removed_again_and_again_while_compiling(root, reference):
    """A thread removes the cache in a loop while the process compiles: never fatal, right numbers."""
    stop = threading.Event()

    def remover():
        while not stop.is_set():
            _remove_root(root)
            time.sleep(0.002)

    thread = threading.Thread(target=remover, daemon=True)
    thread.start()
    try:
        for _ in range(3):
            survive(reference, at_most=2)
    finally:
        stop.set()
        thread.join()


# ----------------------------------------------------------------------------- compilers that build nothing
def _script(tmp_path: Path, body: str) -> str:
    path = tmp_path / "fake-cc"
    path.write_text("#!/bin/sh\n" + textwrap.dedent(body))
    path.chmod(0o755)
    return str(path)


FAKE_COMPILERS = {
    "true": lambda tmp: "/bin/true",
    "false": lambda tmp: "/bin/false",
    "garbage": lambda tmp: _script(tmp, """\
        case "$1" in --version) echo "fake cc 1.0"; exit 0;; esac
        while [ $# -gt 0 ]; do if [ "$1" = -o ]; then head -c 4096 /dev/urandom > "$2"; fi; shift; done
        exit 0
        """),
    "elf_without_key": lambda tmp: _script(tmp, f"""\
        case "$1" in --version) echo "fake cc 1.0"; exit 0;; esac
        while [ $# -gt 0 ]; do if [ "$1" = -o ]; then cp {tmp / 'libforged.so'} "$2"; fi; shift; done
        exit 0
        """),
    "always_fails": lambda tmp: _script(tmp, """\
        case "$1" in --version) echo "fake cc 1.0"; exit 0;; esac
        echo "fake cc: cannot compile" >&2
        exit 1
        """),
}


@pytest.mark.parametrize("fake", sorted(FAKE_COMPILERS))
def test_compiler_that_builds_nothing_falls_back_to_numpy(tmp_path, monkeypatch, reference, fake):
    if fake == "elf_without_key":
        if build.find_compiler() is None:
            pytest.skip("no C compiler")
        sentinel = tmp_path / "SENTINEL"
        sentinel_library(tmp_path, sentinel)
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(pipeline, "_warned_no_compiler", False)
    cc = FAKE_COMPILERS[fake](tmp_path)
    monkeypatch.setenv("CC", cc)
    build.reset_compiler_cache()
    try:
        system, report, caught = survive(reference)
    finally:
        build.reset_compiler_cache()
    assert report.backend == "numpy" == system.backend
    assert len(caught) == 1 and "falling back to the numpy backend" in str(caught[0].message)
    assert cc in str(caught[0].message)
    assert kind_entries(tmp_path / "cache", "c") == [] or all(
        not (tmp_path / "cache" / "c" / e / "libmgkernels.so").exists() for e in kind_entries(tmp_path / "cache", "c"))
    if fake == "elf_without_key":
        assert not (tmp_path / "SENTINEL").exists()


@needs_cc
def test_a_real_compile_error_is_still_a_build_error(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "cache"))
    with pytest.raises(BuildError, match="undeclared_thing"):
        build.build_shared("int mg_bad(void) { return undeclared_thing; }\n", stem="bad")


# ----------------------------------------------------------------------------- the committed layer
def committed_request(tmp_path: Path, monkeypatch):
    """A copy of mechgen/generated/ used by the pipeline, and the spring pendulum scene's request it holds."""
    from mechgen.regen import planned_requests

    copy = tmp_path / "generated"
    shutil.copytree(pipeline.GENERATED, copy)
    monkeypatch.setattr(pipeline, "GENERATED", copy)
    for source, request in planned_requests([REPO / "scenes" / "spring_pendulum.toml"]):
        if pipeline.read_committed(request.model, request.key(), request.backend, request=request) is not None:
            return copy, source, request
    pytest.skip("mechgen/generated/ holds no generation of the spring pendulum scene")


@needs_cc
@pytest.mark.parametrize("how", ["text_edited", "json_nested", "json_garbage", "json_other_request"])
def test_committed_generation_that_does_not_match_is_ignored(tmp_path, monkeypatch, how):
    from mechgen.scene.plan import derive_with

    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "cache"))
    copy, source, request = committed_request(tmp_path, monkeypatch)
    key = request.key()
    text_path, json_path = pipeline.committed_paths(request.model, key, request.backend, copy)
    if how == "text_edited":
        text_path.write_text(text_path.read_text().replace("9.81", "9.82"))
    elif how == "json_nested":
        json_path.write_bytes(b"[" * 100_000 + b"]" * 100_000)
    elif how == "json_garbage":
        json_path.write_bytes(os.urandom(300))
    else:
        doc = json.loads(json_path.read_text())
        doc["request"]["spec"] += " "
        json_path.write_text(json.dumps(doc))
    (system, report), caught = recorded(lambda: pipeline.compile_request(request, derive_with(source, request)))
    assert report.origin == "derived"
    assert len(caught) == 1 and "committed generation" in str(caught[0].message)
    model, spec = derive_with(source, request)()
    generated = pipeline.generate(model, spec, set(request.kernels), "numpy")
    assert_numbers(system, numpy_kernels(load_module(Path("<ref>"), "mg_ref_committed", source=generated["text"])))


# ----------------------------------------------------------------------------- concurrent first compiles
_RACER = r"""
import json, pathlib, sys, time, warnings
go, ready = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.symbolic.specialize import specialize
from mechgen.codegen import build
model = models.get("spring_pendulum")
spec = specialize(model, {"k": 123.0})
build.find_compiler()
ready.touch()
deadline = time.monotonic() + 60
while not go.exists() and time.monotonic() < deadline:
    time.sleep(0.001)
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    system, report = compile_model(model, spec, kernels={"residual", "linear"}, backend="c")
out = system.kernels["linear"].evaluate({"q": [1.3, 0.4], "v": [0.2, -0.1], "p": []})
print(json.dumps({"backend": report.backend, "K": out["K"].tolist(), "M": out["M"].tolist(),
                  "warnings": [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]}))
"""


def _race(tmp_path: Path, rounds: int, processes: int = 4) -> None:
    model = models.get(MODEL)
    generated = pipeline.generate(model, specialize(model, VALUES), {"linear"}, "numpy")
    ref = numpy_kernels(load_module(Path("<ref>"), "mg_ref_race", source=generated["text"]))["linear"]
    want = ref.evaluate({"q": [1.3, 0.4], "v": [0.2, -0.1], "p": []})
    for r in range(rounds):
        here = tmp_path / f"round{r}"
        here.mkdir()
        root = here / "cache"
        env = {**os.environ, "MECHGEN_CACHE": str(root),
               "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}
        go = here / "go"
        procs = [subprocess.Popen([sys.executable, "-c", _RACER, str(go), str(here / f"ready{k}")],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
                 for k in range(processes)]
        try:
            deadline = time.monotonic() + 120
            while (not all((here / f"ready{k}").exists() for k in range(processes))
                   and time.monotonic() < deadline and all(p.poll() is None for p in procs)):
                time.sleep(0.005)
            go.touch()
            results = [p.communicate(timeout=300) for p in procs]
        finally:
            for p in procs:
                if p.poll() is None:
                    p.kill()
                    p.wait()
        for p, (out, err) in zip(procs, results):
            assert p.returncode == 0, err
            got = json.loads(out.splitlines()[-1])
            assert got["backend"] == "c" and got["warnings"] == []
            np.testing.assert_allclose(got["K"], want["K"], rtol=1e-13)
            np.testing.assert_allclose(got["M"], want["M"], rtol=1e-13)
        for kind in os.listdir(root):
            names = kind_entries(root, kind)
            assert not [n for n in names if n.startswith(".")], (kind, names)
        libraries = [e for e in kind_entries(root, "c") if (root / "c" / e / "libmgkernels.so").exists()]
        assert len(libraries) == 1 and len(kind_entries(root, "index")) == 1


@needs_cc
def test_concurrent_first_compiles(tmp_path):
    _race(tmp_path, rounds=1)


@needs_cc
@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("MECHGEN_TEST_LARGE"), reason="ten rounds of four processes (~30 s): set "
                    "MECHGEN_TEST_LARGE=1; the one-round case runs always")
def test_concurrent_first_compiles_ten_rounds(tmp_path):
    _race(tmp_path, rounds=10)


# ----------------------------------------------------------------------------- a scene run as a user runs it
@needs_cc
@pytest.mark.parametrize("fault", ["removed_repeatedly", "root_is_a_file", "index_folder_is_a_file"])
def test_scene_survives_the_cache_fault(tmp_path, fault):
    """``mechgen run`` of the spring pendulum (k = 123) with the cache removed again and again while it runs, or
    unusable: exit 0, at most two warnings, and the closed forms r_eq = l0 + m g / k, omega = sqrt(k / m) and
    sqrt(g / r_eq)."""
    root, out = tmp_path / "cache", tmp_path / "out.json"
    if fault == "root_is_a_file":
        root.write_text("x")
    elif fault == "index_folder_is_a_file":
        root.mkdir()
        (root / "index").write_text("x")
    env = {**os.environ, "MECHGEN_CACHE": str(root),
           "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}
    stop = threading.Event()

    def remover():
        while not stop.is_set():
            _remove_root(root)
            time.sleep(0.005)

    thread = threading.Thread(target=remover, daemon=True)
    if fault == "removed_repeatedly":
        thread.start()
    try:
        done = subprocess.run([sys.executable, "-m", "mechgen", "run", str(REPO / "scenes" / "spring_pendulum.toml"),
                               "--set", "k=123", "--json", str(out)], capture_output=True, text=True, env=env,
                              timeout=600)
    finally:
        stop.set()
        if thread.is_alive():
            thread.join()
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("RuntimeWarning") <= (2 if fault == "removed_repeatedly" else 1), done.stderr
    results = {a["name"]: a["outputs"] for a in json.loads(out.read_text())["analyses"]}
    m, k, l0, g = 1.0, 123.0, 1.0, 9.81
    r_eq = l0 + m * g / k
    assert results["equilibrium"]["coordinates"]["r"] == pytest.approx(r_eq, rel=1e-12)
    np.testing.assert_allclose(sorted(results["small_oscillations"]["frequencies"]),
                               sorted([np.sqrt(k / m), np.sqrt(g / r_eq)]), rtol=1e-10)


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_nowhere_to_write(tmp_path, monkeypatch, reference, backend):
    """The cache is a file and no temporary directory can be made: the kernels are built and loaded uncached
    (numpy from memory; C falls back to numpy), one warning."""
    import tempfile

    (tmp_path / "file").write_text("x")
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "file"))
    monkeypatch.setattr(pipeline, "_warned_no_compiler", False)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "file"))
    system, report, caught = survive(reference, backend)
    assert report.backend == "numpy"
    if backend == "c":
        assert len(caught) == 1 and "falling back to the numpy backend" in str(caught[0].message)
