"""The compiler pipeline: declare -> derive -> lower -> emit -> build -> load.

``compile_model(model, spec, kernels, backend)`` returns a
:class:`~mechgen.runtime.system.System` ready for the analyses and a
:class:`BuildReport` saying which kernels were built, their operation counts,
the time of each stage and whether the artefact came from the cache.
"""
from __future__ import annotations

import json
import logging
import time
import warnings
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from mechgen.codegen.emit_c import emit_c
from mechgen.codegen.emit_casadi import emit_casadi
from mechgen.codegen.emit_numpy import emit_numpy
from mechgen.codegen.ir import KernelIR
from mechgen.codegen.lower_lattice import LATTICE_KERNELS, lower_lattice
from mechgen.codegen.lower_lumped import LUMPED_KERNELS, lower_lumped
from mechgen.codegen.spec import kernel_spec
from mechgen.errors import CompilerUnavailable, InputError
from mechgen.runtime.kernels import c_kernels, casadi_kernels, load_module, numpy_kernels
from mechgen.runtime.continuum import FieldSystem
from mechgen.runtime.system import System
from mechgen.symbolic.derive import derive_lumped
from mechgen.symbolic.field import derive_field
from mechgen.symbolic.lattice import derive_lattice
from mechgen.symbolic.model import Model
from mechgen.symbolic.specialize import Specialization

log = logging.getLogger("mechgen")
BACKENDS = ("c", "numpy", "casadi")
FIELD_KERNELS = ("residual", "tangent", "linear", "outputs")
_FIELD_CHOICES = ("discretisation", "N", "quadrature", "constraints", "joints")
#: kernels of a continuum's steady boundary value problem (mechgen.symbolic.steady)
STEADY_KERNELS = ("bvp_residual", "bvp_tangent", "bvp_outputs")
#: kernels of its Hamiltonian (stress) form, y = (u, n) (mechgen.symbolic.steady.derive_steady_hamiltonian)
HAMILTONIAN_KERNELS = ("hbvp_rates", "hbvp_rates_tangent", "hbvp_outputs")
_warned_no_compiler = False


@dataclass
class BuildReport:
    """What a compilation did: kernels, operation counts, stage times (s), cache use."""

    backend: str
    kernels: dict = field(default_factory=dict)
    seconds: dict = field(default_factory=dict)
    cached: bool = False

    def to_json(self) -> dict:
        """JSON form for results."""
        return {"backend": self.backend, "kernels": self.kernels, "seconds": self.seconds, "cached": self.cached}


def all_kernels(model: Model) -> tuple[str, ...]:
    """Every kernel a model can have."""
    if model.is_lattice:
        return LATTICE_KERNELS
    if model.is_field:
        return FIELD_KERNELS
    if model.internals:
        return LUMPED_KERNELS
    return tuple(k for k in LUMPED_KERNELS if not k.startswith("rates"))


def derive(model: Model, spec: Specialization):
    """Derived equations (lumped or lattice) of a specialisation."""
    if model.is_field:
        return derive_field(model, spec)
    return derive_lattice(model, spec) if model.is_lattice else derive_lumped(model, spec)


def lower_all(model: Model, eqs, kernels, *, cse: bool = True) -> list[KernelIR]:
    """KernelIRs of the requested kernels, in canonical order."""
    if model.is_field:
        wanted = [k for k in all_kernels(model) if k in kernels]
        irs = [lower_lumped(eqs.local, k, cse=cse) for k in wanted]
        irs += [replace(lower_lumped(local, k, cse=cse), name=f"{k}_at_{at}") for at, local in eqs.points.items()
                for k in wanted]
        meta = field_meta(eqs)
        for ir in irs:
            ir.meta["field"] = meta
        return _with_whirl(model, irs)
    lower = lower_lattice if model.is_lattice else lower_lumped
    return _with_whirl(model, [lower(eqs, k, cse=cse) for k in all_kernels(model) if k in kernels])


def _constraint_kernel(model: Model, spec: Specialization, eqs, cse: bool) -> list[KernelIR]:
    """The ``constraint`` and ``strain`` kernels (g_j, g_jj) of a continuum that declares them, beside its linear one."""
    from mechgen.codegen.lower_lumped import lower_matrices
    from mechgen.symbolic.constraint import constraint_matrices, constraint_of

    irs = []
    for name, fn, doc in (("constraint", model.constraint_fn, "the pointwise constraint g(jets) = 0"),
                          ("strain", model.strain_fn, "the axial strain measure g(jets)")):
        g = constraint_of(model, spec, fn)
        if g is not None:
            ir = lower_matrices(eqs.local, name, f"derivatives of {doc}", constraint_matrices(g, eqs.local, model),
                                cse=cse)
            ir.meta["field"] = field_meta(eqs)
            irs.append(ir)
    return irs


def field_meta(eqs) -> dict:
    """What the runtime needs to know of a continuum: fields, jets, length, ends, parts, constraints."""
    state = set(eqs.local.q + eqs.local.v) | {eqs.local.t}
    constant_mass = all(not (local.jacobian(local.residual, "a").free_symbols & state)
                        for local in [eqs.local, *eqs.points.values()])
    meta = {"fields": list(eqs.fields), "jets": [list(j) for j in eqs.jets],
            "length": eqs.length, "points": sorted(at for at in eqs.points if at not in eqs.parts),
            "constant_mass": constant_mass, "constraints": [[c.field, c.order, c.at] for c in eqs.constraints]}
    if eqs.parts:
        meta["parts"] = {k: list(v) for k, v in sorted(eqs.parts.items())}
    if eqs.shear_pairs:
        meta["shear_pairs"] = [list(p) for p in eqs.shear_pairs]
    if any(c.value != 0 for c in eqs.constraints):
        meta["boundary_values"] = True
    return meta


def _with_whirl(model: Model, irs: list[KernelIR]) -> list[KernelIR]:
    """Record the model's whirl pair (Model.whirl_pair) in every kernel's meta."""
    if model.whirl:
        for ir in irs:
            ir.meta["whirl"] = list(model.whirl)
    return irs


def emit(backend: str, irs: list[KernelIR], *, model: str, title: str) -> str:
    """Source text of one backend."""
    return {"c": emit_c, "numpy": emit_numpy, "casadi": emit_casadi}[backend](irs, model=model, title=title)


def _store_text(kind: str, key: str, filename: str, text: str) -> tuple[Path, bool]:
    """A generated text as a verified, atomically published cache entry; returns the file."""
    from mechgen.codegen.cache import get_or_create

    entry, created = get_or_create(kind, key, lambda folder: (folder / filename).write_text(text))
    return entry / filename, not created


def _load(backend: str, text: str, specs: dict, key: str, report: BuildReport):
    if backend == "c":
        from mechgen.codegen.build import STATS, get_caller, load_shared

        hits = STATS["hit"]
        try:
            lib = load_shared(text, stem="mgkernels")
            report.cached = STATS["hit"] > hits
        except CompilerUnavailable:
            global _warned_no_compiler
            if not _warned_no_compiler:
                warnings.warn("no C compiler found: falling back to the numpy backend", RuntimeWarning,
                              stacklevel=3)
                _warned_no_compiler = True
            report.backend = "numpy"
            return None
        return c_kernels(lib, specs, get_caller())
    name = f"mg_{backend}_{key[:16]}"
    path, report.cached = _store_text(backend, key, f"{name}.py", text)
    module = load_module(path, name)
    return numpy_kernels(module) if backend == "numpy" else casadi_kernels(module, specs)


@lru_cache(maxsize=1)
def _mechgen_sources_digest() -> str:
    """Digest of the sources that shape generated code (symbolic, codegen, templates)."""
    from mechgen.codegen.cache import content_key

    root = Path(__file__).resolve().parent
    files = sorted(p for sub in ("symbolic", "codegen") for p in (root / sub).rglob("*")
                   if p.is_file() and p.suffix in (".py", ".j2"))
    return content_key(*(f"{p.relative_to(root)}\n".encode() + p.read_bytes() for p in files))


def _index_key(model: Model, spec: Specialization, kernels: set, backend: str, cse: bool) -> str | None:
    """Key of the index entry mapping a compile request to its generated text (None: not cacheable)."""
    from mechgen.codegen.cache import content_key

    if not model.file or not Path(model.file).is_file():
        return None
    return content_key("index-1", _mechgen_sources_digest(), Path(model.file).read_bytes(), model.name, spec.key(),
                       ",".join(sorted(kernels)), backend, str(cse))


def _generate(model: Model, spec: Specialization, kernels: set, backend: str, cse: bool,
              report: BuildReport) -> dict:
    """derive -> lower -> emit; returns {'text', 'specs'} (timed into ``report``)."""
    clock = time.perf_counter()
    hamiltonian_only = model.is_field and set(kernels) <= set(HAMILTONIAN_KERNELS)
    # a steady state in stress form needs no dynamics (an inextensible string has no strain energy)
    eqs = None if hamiltonian_only else derive(model, spec)
    report.seconds["derive"] = time.perf_counter() - clock
    clock = time.perf_counter()
    irs = [] if hamiltonian_only else lower_all(model, eqs, kernels, cse=cse)
    if model.is_field and "linear" in kernels and not hamiltonian_only:
        irs += _constraint_kernel(model, spec, eqs, cse)
    steady = [k for k in STEADY_KERNELS if k in kernels] if model.is_field else []
    if steady:
        from mechgen.symbolic.steady import derive_steady

        form = derive_steady(model, spec)
        for k in steady:
            ir = replace(lower_lumped(form, k.removeprefix("bvp_"), cse=cse), name=k)
            ir.meta["field"] = field_meta(eqs)
            irs.append(_with_whirl(model, [ir])[0])
    hamiltonian = [k for k in HAMILTONIAN_KERNELS if k in kernels] if model.is_field else []
    if hamiltonian:
        from mechgen.symbolic.steady import derive_steady_hamiltonian

        from mechgen.symbolic.steady import steady_field_meta

        form = derive_steady_hamiltonian(model, spec)
        meta = steady_field_meta(model, spec) if eqs is None else field_meta(eqs)
        for k in hamiltonian:
            ir = replace(lower_lumped(form, k.removeprefix("hbvp_"), cse=cse), name=k)
            ir.meta["field"] = meta
            irs.append(ir)
    report.seconds["lower"] = time.perf_counter() - clock
    clock = time.perf_counter()
    text = emit(backend, irs, model=model.name, title=spec.key())
    report.seconds["emit"] = time.perf_counter() - clock
    return {"text": text, "specs": {ir.name: kernel_spec(ir) for ir in irs}}


def _generated(model: Model, spec: Specialization, kernels: set, backend: str, cse: bool,
               report: BuildReport) -> dict:
    """The generated text and specs, from the index cache when this exact request was seen before."""
    from mechgen.codegen.cache import get_or_create, lookup

    key = _index_key(model, spec, kernels, backend, cse)
    entry = lookup("index", key) if key else None
    if entry is not None:
        report.seconds.update(derive=0.0, lower=0.0, emit=0.0)
        return json.loads((entry / "generated.json").read_text())
    result = _generate(model, spec, kernels, backend, cse, report)
    if key:
        get_or_create("index", key, lambda folder: (folder / "generated.json").write_text(json.dumps(result)))
    return result


def compile_model(model: Model, spec: Specialization, *, kernels=None, backend: str = "c", cse: bool = True,
                  sites: int | None = None) -> tuple[System, BuildReport]:
    """Derive, generate, build and load the kernels a set of analyses needs."""
    from mechgen.codegen.cache import content_key

    if backend not in BACKENDS:
        raise InputError(f"unknown backend {backend!r}", key="backend", expected=", ".join(BACKENDS))
    kernels = set(kernels or all_kernels(model))
    report = BuildReport(backend)
    loaded = None
    while loaded is None:
        generated = _generated(model, spec, kernels, report.backend, cse, report)
        text, specs = generated["text"], generated["specs"]
        clock = time.perf_counter()
        loaded = _load(report.backend, text, specs, content_key(report.backend, text), report)
        report.seconds["build"] = time.perf_counter() - clock
    report.kernels = {name: {"ops": s["ops"]} for name, s in specs.items()}
    meta = dict(next(iter(specs.values()))["meta"]) if specs else {}
    meta["source"] = model.source or model.name  # the canonical reference (mechgen.models.resolve)
    values = np.array([float(spec_value(model, spec, n)) for n in meta.get("params", [])])
    if model.is_lattice:
        sites = int(sites if sites is not None else spec.values.get(model.chain_spec.sites,
                                                                    model.param(model.chain_spec.sites).default))
    if model.is_field:
        fixed = {k: v for k, v in spec.values.items() if model.param(k).is_numeric}
        choices = {k: spec.values.get(k, model.param(k).default) for k in
                   ("discretisation", "N", "quadrature", "constraints", "joints",
                    *(p.name for p in model.param_list if p.runtime and p.name not in _FIELD_CHOICES))}
        system = FieldSystem(loaded, meta, values, fixed, choices, report.backend)
    else:
        system = System(loaded, meta, values, sites or 0, report.backend)
    log.info("built %s [%s]: %s", model.name, report.backend, report.seconds)
    return system, report


def spec_value(model: Model, spec: Specialization, name: str) -> float:
    """Value of a free parameter: the scene's starting value, else the default."""
    return spec.free_values.get(name, model.param(name).default)
