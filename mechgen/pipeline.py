"""The compiler pipeline: declare -> derive -> lower -> emit -> build -> load.

``compile_model(model, spec, kernels, backend)`` returns a
:class:`~mechgen.runtime.core.system.System` ready for the analyses and a
:class:`BuildReport` saying which kernels were built, their operation counts,
the time of each stage and whether the artefact came from the cache.
"""
from __future__ import annotations

import contextlib
import json
import logging
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np

from mechgen import buildlock
from mechgen.stage_clock import collecting, timed_stage
from mechgen.errors import CompilerUnavailable, InputError, MechgenError
from mechgen.runtime.core.kernels import c_kernels, casadi_kernels, load_module, numpy_kernels
from mechgen.runtime.core.system import System
# the kernel catalogue and the lowering live in codegen; their names stay importable from here
from mechgen.codegen.kernel_names import (FIELD_KERNELS, HAMILTONIAN_KERNELS, SALTATION,  # noqa: F401
                                          STEADY_KERNELS, all_kernels)
from mechgen.codegen.lower_model import lower_all  # noqa: F401

if TYPE_CHECKING:  # the symbolic side is imported only where text is derived (a cached run never needs it)
    from mechgen.codegen.ir import KernelIR
    from mechgen.symbolic.model import Model
    from mechgen.symbolic.specialize import Specialization

log = logging.getLogger("mechgen")
BACKENDS = ("c", "numpy", "casadi")
_FIELD_CHOICES = ("discretisation", "N", "quadrature", "constraints", "joints")
#: version of the request key (bump when what a key covers changes)
REQUEST_FORMAT = "request-1"
#: the committed layer of generated text for the built-in models (written by ``mechgen regen``, read-only)
GENERATED = Path(__file__).resolve().parent / "generated"
#: file suffix of a generated text in mechgen/generated/, by backend
SUFFIXES = {"c": ".c", "numpy": ".numpy.py", "casadi": ".casadi.py"}
_warned_no_compiler = False


@dataclass
class BuildReport:
    """What a compilation did: kernels, operation counts, stage times (s), cache use.

    ``seconds``: derive, lower, emit and build (C compile and load), which add up to the build; and, where they
    ran, declare (within derive), rewrite and cse (within lower).

    ``origin`` says where the generated text came from: ``"derived"`` (derived and emitted now),
    ``"cache"`` (the user compile cache) or ``"generated"`` (the committed mechgen/generated/).
    """

    backend: str
    kernels: dict = field(default_factory=dict)
    seconds: dict = field(default_factory=dict)
    cached: bool = False
    origin: str = "derived"

    def to_json(self) -> dict:
        """JSON form for results."""
        return {"backend": self.backend, "kernels": self.kernels, "seconds": self.seconds, "cached": self.cached,
                "origin": self.origin}


@dataclass(frozen=True)
class CompileRequest:
    """Everything that determines a compiled system, known without importing the model or sympy.

    Attributes:
        model: the model's name (Model.name; its folder in mechgen/generated/).
        digest: sha256 of the model file's bytes ("" when unknown: nothing is cached).
        values: ``((name, value), ...)`` sorted by name: every parameter that is not free, defaults
            filled in (sizes, choices and runtime choices included).
        free: the free numeric parameters in declaration order (part parameters included).
        active: the active coordinates in declaration order, or None for all.
        kernels: the kernel names, sorted.
        backend, cse: code generation options.
        runtime: names of runtime-only choices (Param.runtime): in ``values``, not in :meth:`key`.
        free_values: ``((name, start value), ...)`` of the free parameters, in ``free`` order.
        kind: ``"lumped"``, ``"field"`` or ``"lattice"``.
        numeric: names of the numeric parameters (the continuum's fixed values).
        sites: a lattice's sites parameter.
        source: the model's canonical reference (mechgen.models.resolve), recorded in the system's
            meta so that analyses find the Model again in any process; not in :meth:`key` (the same
            model at another path makes the same kernels).

    Equality covers every field (a cached system is found by it); :meth:`key` covers only what
    shapes generated text, so starting values and runtime choices reuse the same kernels.
    """

    model: str
    digest: str
    values: tuple
    free: tuple
    active: tuple | None
    kernels: tuple
    backend: str = "c"
    cse: bool = True
    runtime: tuple = ()
    free_values: tuple = ()
    kind: str = "lumped"
    numeric: tuple = ()
    sites: str | None = None
    source: str = ""
    #: Model.derivation ("auto", "symbolic", "ad"): in :meth:`key` when not "auto"
    derivation: str = "auto"

    def spec_text(self) -> str:
        """The specialisation's canonical text (equal to Specialization.key() of the same specialisation)."""
        vals = ",".join(f"{k}={v!r}" for k, v in sorted(self.values) if k not in self.runtime)
        return f"values[{vals}] free[{','.join(self.free)}] active[{','.join(self.active or ())}]"

    def key(self) -> str | None:
        """Content key of the generated text: mechgen's sources, the model file and name, the specialisation,
        kernels, backend and cse (None when the model file is unknown)."""
        from mechgen.codegen.cache import content_key, sources_digest

        if not self.digest:
            return None
        forced = () if self.derivation == "auto" else (f"derivation={self.derivation}",)
        return content_key(REQUEST_FORMAT, sources_digest(), self.digest, self.model, self.spec_text(),
                           ",".join(self.kernels), self.backend, str(self.cse), *forced)

    def with_backend(self, backend: str) -> "CompileRequest":
        """The same request for another backend."""
        return replace(self, backend=backend)

    def describe(self) -> dict:
        """A JSON description (stored beside committed text, for readers and ``regen --check`` messages)."""
        return {"model": self.model, "spec": self.spec_text(), "kernels": list(self.kernels),
                "backend": self.backend, "cse": self.cse}


def file_digest(path) -> str:
    """sha256 of a model file's bytes, "" when there is no such file."""
    from mechgen.codegen.cache import file_sha256

    if not path or not Path(path).is_file():
        return ""
    return file_sha256(Path(path))


def request_of(model: Model, spec: Specialization, *, kernels=None, backend: str = "c",
               cse: bool = True) -> CompileRequest:
    """The :class:`CompileRequest` of a model and a specialisation."""
    kind = "field" if model.is_field else "plane" if model.is_plane else "lattice" if model.is_lattice else "lumped"
    free_values = tuple((n, spec.free_values.get(n, model.param(n).default)) for n in spec.free)
    return CompileRequest(model.name, file_digest(model.file), tuple(sorted(spec.values.items())), tuple(spec.free),
                          None if spec.active is None else tuple(spec.active),
                          tuple(sorted(set(kernels or all_kernels(model)))), backend, cse, tuple(spec.runtime),
                          free_values, kind, tuple(p.name for p in model.param_list if p.is_numeric),
                          model.chain_spec.sites if model.is_lattice else None, model.source or model.name,
                          getattr(model, "derivation_mode", "auto"))


def derive(model: Model, spec: Specialization):
    """Derived equations (lumped or lattice) of a specialisation."""
    from mechgen.symbolic.hybrid import check_hybrid

    check_hybrid(model)  # guards without modes, modes in a continuum or chain: refused for every kind of model
    if model.is_field:
        from mechgen.symbolic.field import derive_field

        return derive_field(model, spec)
    if model.is_plane:
        from mechgen.symbolic.plane import derive_plane

        return derive_plane(model, spec)
    if model.is_lattice:
        from mechgen.symbolic.lattice import derive_lattice

        return derive_lattice(model, spec)
    if model.is_hybrid:
        from mechgen.symbolic.hybrid_derive import derive_hybrid

        return derive_hybrid(model, spec)
    from mechgen.symbolic.derive import declared_lumped, derive_lumped
    from mechgen.symbolic.casadi_form import NotConvertible
    from mechgen.symbolic.derive_ad import derive_lumped_ad, wants_ad

    with timed_stage("declare"):
        declared = declared_lumped(model, spec)
    if wants_ad(model, declared):  # a large model: derivatives by AD on the energies' graph
        try:
            return derive_lumped_ad(model, spec, declared)
        except NotConvertible:  # a Piecewise, Heaviside, Min/Max ...: the symbolic path
            pass
    return derive_lumped(model, spec, declared=declared)


def emit(backend: str, irs: list[KernelIR], *, model: str, title: str) -> str:
    """Source text of one backend."""
    if backend == "c":
        from mechgen.codegen.emit_c import emit_c as emitter
    elif backend == "numpy":
        from mechgen.codegen.emit_numpy import emit_numpy as emitter
    else:
        from mechgen.codegen.emit_casadi import emit_casadi as emitter
    return emitter(irs, model=model, title=title)


def _store_text(kind: str, key: str, filename: str, text: str) -> tuple[Path, bool]:
    """A generated text as a verified, atomically published cache entry; returns the file and whether it was
    a hit. An entry whose file is not exactly ``text`` (forged under matching metadata) is refused and
    rebuilt; a cache that cannot take it gives a path in no cache (the text is loaded from memory anyway)."""
    from mechgen.codegen.cache import get_or_create, read_bounded

    data = text.encode("utf-8")

    def check(entry: Path) -> str | None:
        return None if read_bounded(entry / filename) == data else f"{filename} is not the text of its key"

    try:
        entry, created = get_or_create(kind, key, lambda folder: (folder / filename).write_bytes(data), check)
    except OSError as exc:
        log.info("generated module not cached: %s", exc)
        return Path(f"<mechgen {filename}>"), False
    return entry / filename, not created


def _fall_back_to_numpy(problem: Exception) -> None:
    """Warn (once per process) that the C backend is unusable and numpy is used instead."""
    global _warned_no_compiler
    if not _warned_no_compiler:
        what = "no C compiler available" if isinstance(problem, CompilerUnavailable) else "the C backend is unusable"
        warnings.warn(f"{what} ({problem}): falling back to the numpy backend", RuntimeWarning, stacklevel=4)
        _warned_no_compiler = True
    else:
        log.info("C backend unavailable (%s): numpy backend", problem)


def _load(backend: str, text: str, specs: dict, key: str, report: BuildReport):
    if backend == "c":
        from mechgen.codegen.build import STATS, get_caller, load_shared

        hits = STATS["hit"]
        try:
            lib = load_shared(text, stem="mgkernels", symbols=[f"mg_{name}" for name in specs])
            report.cached = STATS["hit"] > hits
        except (CompilerUnavailable, OSError) as exc:  # no usable compiler, or not even a temporary cache
            _fall_back_to_numpy(exc)
            report.backend = "numpy"
            return None
        return c_kernels(lib, specs, get_caller())
    name = f"mg_{backend}_{key[:16]}"
    path, report.cached = _store_text(backend, key, f"{name}.py", text)
    module = load_module(path, name, source=text)  # the verified text itself, never the file's bytes
    return numpy_kernels(module) if backend == "numpy" else casadi_kernels(module, specs)


def generate(model: Model, spec: Specialization, kernels, backend: str, cse: bool = True,
             report: BuildReport | None = None) -> dict:
    """derive -> lower -> emit; returns {'text', 'specs'} (timed into ``report`` when given: the stages, and
    within them declare, rewrite and cse, :mod:`mechgen.stage_clock`)."""
    report = report if report is not None else BuildReport(backend)
    with collecting(report.seconds):
        return _generate(model, spec, set(kernels), backend, cse, report)


def _generate(model: Model, spec: Specialization, kernels: set, backend: str, cse: bool,
              report: BuildReport) -> dict:
    from mechgen.codegen.lower_model import lower_model
    from mechgen.codegen.spec import kernel_spec

    clock = time.perf_counter()
    hamiltonian_only = model.is_field and set(kernels) <= set(HAMILTONIAN_KERNELS)
    # a steady state in stress form needs no dynamics (an inextensible string has no strain energy)
    eqs = None if hamiltonian_only else derive(model, spec)
    report.seconds["derive"] = time.perf_counter() - clock
    clock = time.perf_counter()
    irs = lower_model(model, spec, eqs, kernels, cse=cse)
    report.seconds["lower"] = time.perf_counter() - clock
    clock = time.perf_counter()
    text = emit(backend, irs, model=model.name, title=spec.key())
    report.seconds["emit"] = time.perf_counter() - clock
    return {"text": text, "specs": {ir.name: kernel_spec(ir) for ir in irs}}


# ----------------------------------------------------------------------------- the committed layer
def committed_paths(model: str, key: str, backend: str, root: Path = GENERATED) -> tuple[Path, Path]:
    """(text file, its JSON) of a request in mechgen/generated/: ``<model>/<key[:16]><suffix>`` and ``.json``."""
    return root / model / f"{key[:16]}{SUFFIXES[backend]}", root / model / f"{key[:16]}.{backend}.json"


def committed_document(request: CompileRequest, key: str, generated: dict, text_name: str) -> str:
    """The JSON beside a committed text: its full key, the request, the text's sha256 and the kernel specs."""
    import hashlib

    doc = {"format": REQUEST_FORMAT, "key": key, "request": request.describe(), "text": text_name,
           "sha256": hashlib.sha256(generated["text"].encode("utf-8")).hexdigest(),
           "kernels": list(generated["specs"]), "specs": generated["specs"]}
    return json.dumps(doc, indent=1) + "\n"


_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_")


def specs_problem(specs, text: str, backend: str, free=None, *, empty: bool = False) -> str | None:
    """Why ``specs`` are not kernel specs of ``text`` (None when they are).

    ``empty``: no specs at all is right (a request for no kernels: a scene whose analyses, such as an
    expression ``fit``, use none). Each spec is an object named by its key (an identifier) with lists of input and output ports, a list
    of size names and a meta object whose ``params`` are among ``free`` (when given); ``text`` defines
    each kernel (``mg_NAME(`` in C and numpy text, ``build_NAME(`` in CasADi text).
    """
    if not isinstance(specs, dict) or (not specs and not empty):
        return "no kernel specs"
    for name, spec in specs.items():
        if not (isinstance(name, str) and name and set(name) <= _NAME_CHARS and not name[0].isdigit()):
            return f"invalid kernel name {name!r}"
        if not isinstance(spec, dict) or spec.get("name") != name:
            return f"the spec of kernel {name} does not name it"
        ports = [spec.get("inputs"), spec.get("outputs")]
        if not all(isinstance(p, list) and all(isinstance(q, dict) and isinstance(q.get("name"), str)
                                               for q in p) for p in ports):
            return f"kernel {name}: invalid ports"
        if not isinstance(spec.get("sizes"), list) or not isinstance(spec.get("meta"), dict):
            return f"kernel {name}: invalid sizes or meta"
        params = spec["meta"].get("params", [])
        if free is not None and not (isinstance(params, list) and set(params) <= set(free)):
            return f"kernel {name}: parameters {params} are not the request's free ones"
        symbol = f"build_{name}(" if backend == "casadi" else f"mg_{name}("
        if symbol not in text:
            return f"the text defines no kernel {name}"
    return None


def document_problem(doc, key: str, request: CompileRequest | None, text: str, backend: str) -> str | None:
    """Why a stored generation (an index entry or a committed JSON) is not the one of ``key`` (None when it is).

    It must name ``key`` (and the request, when given), hold the sha256 of ``text`` and valid
    :func:`specs_problem` specs for it.
    """
    import hashlib

    if not isinstance(doc, dict):
        return "not a JSON object"
    if doc.get("key") != key:
        return "it names another key"
    if request is not None and doc.get("request") != request.describe():
        return "it names another request"
    if hashlib.sha256(text.encode("utf-8")).hexdigest() != doc.get("sha256"):
        return "the text does not have its recorded sha256"
    return specs_problem(doc.get("specs"), text, backend, None if request is None else request.free,
                         empty=request is not None and not request.kernels)


def read_committed(model: str, key: str, backend: str, root: Path | None = None,
                   request: CompileRequest | None = None) -> dict | None:
    """{'text', 'specs'} of a request from mechgen/generated/ (or ``root``) when its full key, the request
    (when given), the text's sha256 and its specs match, else None.

    A committed generation that is present but does not match (edited text, damaged JSON) is ignored with
    a RuntimeWarning, so the request is derived instead.
    """
    from mechgen.codegen.cache import MAX_DOCUMENT_BYTES, parse_json, read_bounded

    text_path, json_path = committed_paths(model, key, backend, GENERATED if root is None else root)
    if not json_path.is_file():
        return None
    try:
        doc = parse_json(read_bounded(json_path, MAX_DOCUMENT_BYTES), max_bytes=MAX_DOCUMENT_BYTES)
        text = read_bounded(text_path, MAX_DOCUMENT_BYTES).decode("utf-8")
        problem = document_problem(doc, key, request, text, backend)
        if problem is None and (doc.get("text") != text_path.name or not isinstance(doc.get("kernels"), list)
                                or list(doc["kernels"]) != list(doc["specs"])):
            problem = "its kernel list or text name is not the one recorded"
    except (OSError, ValueError) as exc:
        problem = f"unreadable: {exc}"
    if problem is not None:
        warnings.warn(f"mechgen: ignored the committed generation {json_path} ({problem}); deriving instead",
                      RuntimeWarning, stacklevel=2)
        return None
    return {"text": text, "specs": {name: doc["specs"][name] for name in doc["kernels"]}}


def index_document(request: CompileRequest, key: str, generated: dict) -> str:
    """The user cache's index entry of a request: its key, the request, the text, its sha256 and the specs."""
    import hashlib

    return json.dumps({"format": REQUEST_FORMAT, "key": key, "request": request.describe(),
                       "sha256": hashlib.sha256(generated["text"].encode("utf-8")).hexdigest(),
                       "text": generated["text"], "specs": generated["specs"]})


def read_index(request: CompileRequest, key: str) -> dict | None:
    """{'text', 'specs'} of a request from the user cache's index, when a verified entry holds it.

    The entry's document is checked against the request (:func:`document_problem`); one that is not
    (empty, forged, another request's) is refused: warned about, removed and rebuilt by the caller.
    """
    from mechgen.codegen.cache import MAX_DOCUMENT_BYTES, lookup, read_json

    found: dict = {}

    def check(entry: Path) -> str | None:
        doc = read_json(entry / "generated.json", max_bytes=MAX_DOCUMENT_BYTES)
        text = doc.get("text") if isinstance(doc, dict) else None
        if not isinstance(text, str) or not text:
            return "it holds no generated text"
        problem = document_problem(doc, key, request, text, request.backend)
        if problem is None:
            found.update(text=text, specs=doc["specs"])
        return problem

    return found if lookup("index", key, check) is not None and found else None


def generated_text(request: CompileRequest, derive_with: Callable[[], tuple], report: BuildReport) -> dict:
    """The generated text and specs of a request: user cache index -> mechgen/generated/ -> derived (and stored).

    ``derive_with()`` gives ``(model, spec)``; it is called only when neither cache holds the request.
    """
    from mechgen.codegen.cache import get_or_create

    key = request.key()
    if key is not None:
        found = read_index(request, key)
        if found is not None:
            report.seconds.update(derive=0.0, lower=0.0, emit=0.0)
            report.origin = "cache"
            return found
        found = read_committed(request.model, key, request.backend, request=request)
        if found is not None:
            report.seconds.update(derive=0.0, lower=0.0, emit=0.0)
            report.origin = "generated"
            return found
    model, spec = derive_with()
    if spec.key() != request.spec_text():
        raise MechgenError(f"internal: the compile request of {request.model} ({request.spec_text()}) does not "
                           f"match the model's specialisation ({spec.key()})")
    result = generate(model, spec, request.kernels, request.backend, request.cse, report)
    report.origin = "derived"
    if key is not None:
        document = index_document(request, key, result)
        try:
            get_or_create("index", key, lambda folder: (folder / "generated.json").write_text(document))
        except OSError as exc:  # not even a temporary cache: the generation is used uncached
            log.info("generated text not cached: %s", exc)
    return result


def compile_request(request: CompileRequest, derive_with: Callable[[], tuple], *,
                    sites: int | None = None) -> tuple[System, BuildReport]:
    """Build and load the kernels of a request (deriving them only when no cache holds them).

    ``derive_with()`` returns ``(model, spec)`` and is called only on a cache miss, so a cached
    request never imports the model or sympy.
    """
    from mechgen.codegen.cache import content_key

    if request.backend not in BACKENDS:
        raise InputError(f"unknown backend {request.backend!r}", key="backend", expected=", ".join(BACKENDS))
    report = BuildReport(request.backend)
    key = request.key()
    # one derivation and build per request across processes (mechgen.buildlock): concurrent first runs wait
    with buildlock.held(f"request-{request.backend}-{key}") if key else contextlib.nullcontext():
        loaded = None
        while loaded is None:
            generated = generated_text(request.with_backend(report.backend), derive_with, report)
            text, specs = generated["text"], generated["specs"]
            clock = time.perf_counter()
            loaded = _load(report.backend, text, specs, content_key(report.backend, text), report)
            report.seconds["build"] = time.perf_counter() - clock
    report.kernels = {name: {"ops": s["ops"]} for name, s in specs.items()}
    meta = dict(next(iter(specs.values()))["meta"]) if specs else {}
    meta["source"] = request.source or request.model  # the canonical reference (mechgen.models.resolve)
    starts = dict(request.free_values)
    values = dict(request.values)
    params = np.array([float(starts[n]) for n in meta.get("params", [])])
    if request.kind == "lattice":
        sites = int(sites if sites is not None else values[request.sites])
    if request.kind == "field":
        from mechgen.runtime.fields.continuum import FieldSystem

        fixed = {k: v for k, v in values.items() if k in request.numeric}
        names = (*_FIELD_CHOICES, *(n for n in request.runtime if n not in _FIELD_CHOICES))
        choices = {k: values[k] for k in names if k in values}
        system = FieldSystem(loaded, meta, params, fixed, choices, report.backend)
    elif request.kind == "plane":
        from mechgen.runtime.plane.system import PlaneSystem

        fixed = {k: v for k, v in values.items() if k in request.numeric}
        choices = {k: values[k] for k in request.runtime if k in values}
        selections = {k: v for k, v in values.items() if isinstance(v, str) and k not in request.runtime}
        system = PlaneSystem(loaded, meta, params, fixed, choices, report.backend, selections=selections)
    elif "hybrid" in meta:
        from mechgen.runtime.core.hybrid_system import HybridSystem

        system = HybridSystem(loaded, meta, params, 0, report.backend)
    else:
        system = System(loaded, meta, params, sites or 0, report.backend)
    log.info("built %s [%s, %s]: %s", request.model, report.backend, report.origin, report.seconds)
    return system, report


def compile_model(model: Model, spec: Specialization, *, kernels=None, backend: str = "c", cse: bool = True,
                  sites: int | None = None) -> tuple[System, BuildReport]:
    """Derive, generate, build and load the kernels a set of analyses needs."""
    if backend not in BACKENDS:
        raise InputError(f"unknown backend {backend!r}", key="backend", expected=", ".join(BACKENDS))
    request = request_of(model, spec, kernels=kernels, backend=backend, cse=cse)
    return compile_request(request, lambda: (model, spec), sites=sites)


def spec_value(model: Model, spec: Specialization, name: str) -> float:
    """Value of a free parameter: the scene's starting value, else the default."""
    return spec.free_values.get(name, model.param(name).default)
