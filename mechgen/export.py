"""``mechgen export``: a model's generated kernels out of mechgen, for use without it.

``export_model(ref, backend, out, sets=(), kernels=None)`` derives the model (a built-in
name, a path to a model file or ``module:attribute``, resolved by :mod:`mechgen.models`),
specialised like a scene: ``--set NAME=VALUE`` folds a value into the code, every other
numeric parameter stays a kernel input ``p`` (in declaration order). It writes

* ``backend="c"``: ``OUT/<model>.h`` and ``OUT/<model>.c``, standalone C99 (see
  :mod:`mechgen.codegen.emit_c_export`; the header documents every function, its input and
  output layout and, for chain kernels, the CSR pattern builder);
* ``backend="casadi"``: ``OUT/<model>_<kernel>.casadi`` (``casadi.Function.save``; load with
  ``casadi.Function.load``) and ``OUT/<model>.json``, a manifest naming every input and output
  entry and, for chain kernels (built for the ``sites`` the specialisation fixes), the CSR
  pattern of the sparse outputs.

The output folder is checked before anything is derived (a file in the way or no write
permission is an :class:`~mechgen.errors.InputError`); files are written into a temporary
folder beside it and moved into place only when all of them are complete.
"""
from __future__ import annotations

import importlib.util
import json
import math
import os
import shutil
import tempfile
from dataclasses import replace
from pathlib import Path

from mechgen.version import __version__
from mechgen.errors import InputError

EXPORT_BACKENDS = ("c", "casadi")
#: how the CasADi manifest's ports read (also stated in the manifest itself)
LAYOUT = ("Each Function takes the kernel's inputs in the order listed (column vectors; 'entries' names each entry) "
          "and returns its outputs in the order listed: a dense output of shape [rows, cols] is the row-major "
          "flat vector (ca.reshape(out, cols, rows).T is the matrix), a sparse output is the CSR data of "
          "'pattern'. A pointwise kernel of a continuum is one point: .map(n) evaluates n points.")


def _fail(key: str, message: str, expected: str | None = None) -> InputError:
    return InputError(message, key=key, expected=expected)


# --------------------------------------------------------------------------- inputs

def parse_sets(model, items) -> dict:
    """``NAME=VALUE`` strings -> {name: value}: numbers for numeric parameters and sizes, choices as given.

    A numeric value must be a finite number (an integer for a size), above 0 for a positive
    parameter and under a parameter's ``below`` bound; a choice must be one of its choices.
    """
    values: dict = {}
    names = [p.name for p in model.param_list]
    for item in items:
        if not isinstance(item, str) or "=" not in item:
            raise _fail(f"--set {item}", f"override {item!r} has no '='", "NAME=VALUE")
        name, text = (part.strip() for part in item.split("=", 1))
        key = f"--set {name}"
        if name not in names:
            raise _fail(key, f"model {model.name} has no parameter {name!r}", "one of: " + ", ".join(names))
        prm = model.param(name)
        if name in model.part_params():
            raise _fail(key, f"{name} is a parameter of a part kind, which stays a kernel input (its value "
                        "differs from part to part)", "a parameter that is not a part's")
        if prm.is_choice:
            if text not in prm.choices:
                raise _fail(key, f"{text!r} is not an allowed choice", "one of: " + ", ".join(prm.choices))
            values[name] = text
            continue
        try:
            number = int(text) if prm.integer else float(text)
        except ValueError:
            raise _fail(key, f"value {text!r} is not {'an integer' if prm.integer else 'a number'}",
                        "an integer" if prm.integer else "a finite number") from None
        if not math.isfinite(number):
            raise _fail(key, f"value {text!r} is not finite", "a finite number")
        if prm.size and number < 1:
            raise _fail(key, f"size {number} is below 1", "an integer of at least 1")
        if prm.positive and not number > 0:
            raise _fail(key, f"value {text!r} is not positive", "a number above 0")
        if prm.below is not None and not number < prm.below:
            raise _fail(key, f"value {text!r} is not below {prm.below!r}", f"a number below {prm.below!r}")
        values[name] = number
    return values


def check_out_dir(out: Path, files: list[str]) -> None:
    """Raise InputError unless ``out`` is (or can be made) a writable folder that can take ``files``."""
    if out.exists() and not out.is_dir():
        raise _fail("--out", f"{out} is a file, not a folder", "a folder to write the exported files into")
    probe = out
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise _fail("--out", f"{probe} (on the way to {out}) is a file, not a folder", "a path of folders")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise _fail("--out", f"folder {probe} is not writable", "a folder you may write into")
    for name in files:
        target = out / name
        if target.is_dir() or (target.exists() and not target.is_file()):
            raise _fail("--out", f"{target} exists and is not a file", "no folder in the way of an exported file")


def write_atomically(out: Path, contents: dict) -> list[Path]:
    """Write {file name: text or bytes} into ``out``: into a temporary folder first, then moved into place."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.export-"))
    try:
        for name, data in contents.items():
            (tmp / name).write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))
            os.chmod(tmp / name, 0o644)
        check_out_dir(out, list(contents))  # again, with every name: nothing is moved unless all can be
        if not out.exists():
            os.chmod(tmp, 0o755)
            os.rename(tmp, out)
        else:
            for name in contents:
                os.replace(tmp / name, out / name)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return [out / name for name in contents]


def _kernels(model, wanted) -> tuple[str, ...]:
    from mechgen.codegen.kernel_names import all_kernels

    available = all_kernels(model)
    if wanted is None:
        return available
    names = [k.strip() for k in (wanted.split(",") if isinstance(wanted, str) else wanted) if k.strip()]
    unknown = [k for k in names if k not in available]
    if unknown or not names:
        raise _fail("--kernels", f"unknown kernels {', '.join(unknown) or '(none given)'} of model {model.name}",
                    "a comma-separated list among: " + ", ".join(available))
    return tuple(k for k in available if k in names)


# --------------------------------------------------------------------------- derivation

def _specialised(model, values: dict):
    from mechgen.symbolic.specialize import specialize

    free = tuple(p.name for p in model.param_list if p.is_numeric and p.name not in values)
    try:
        return specialize(model, values, free=free)
    except InputError as exc:
        key = f"--set {exc.key}" if exc.key in values else exc.key
        raise InputError(exc.message, file=exc.file, key=key, expected=exc.expected) from None


def _lowered(model, spec, kernels):
    from mechgen.codegen.lower_model import lower_all
    from mechgen.pipeline import derive

    return lower_all(model, derive(model, spec), set(kernels))


def _fixed(model, spec) -> dict:
    """Folded parameter values (numbers, sizes and choices), in declaration order."""
    return {p.name: spec.values[p.name] for p in model.param_list if p.name in spec.values and not p.runtime}


def _facts(model, spec):
    from mechgen.codegen.emit_c_export import ExportFacts

    return ExportFacts(model.name, model.doc, spec.key(),
                       {p.name: (p.unit, p.doc) for p in model.param_list}, _fixed(model, spec),
                       {o.name: o.doc for o in model.outputs})


# --------------------------------------------------------------------------- casadi

def _entry_names(ir, port, sites: int | None) -> list[str] | None:
    """Names of a port's entries: coordinates (a chain's ``u_1 .. u_N``), their rates, parameters ..."""
    meta = ir.meta
    coords = list(meta.get("coordinates", []))
    if meta.get("kind") == "lattice":
        coords = [f"{coords[0]}_{e + 1}" for e in range(sites)]
    table = {"q": coords, "v": [f"d({c})/dt" for c in coords], "a": [f"d2({c})/dt2" for c in coords],
             "z": list(meta.get("internal", [])), "t": ["t"], "s": ["s"], "p": list(meta.get("params", []))}
    return table.get(port.name)


def _casadi_files(model, spec, irs) -> dict:
    from mechgen.codegen.emit_casadi import emit_casadi
    from mechgen.codegen.escape import py_docstring
    from mechgen.codegen.spec import kernel_spec
    from mechgen.runtime.core.kernels import load_module
    from mechgen.runtime.core.pattern import build_pattern

    named = [replace(ir, name=f"{model.name}_{ir.name}") for ir in irs]
    text = emit_casadi(named, model=model.name, title=spec.key())
    sites = int(spec.values[model.chain_spec.sites]) if model.is_lattice else None
    files: dict = {}
    manifest = {"model": model.name, "mechgen": __version__, "backend": "casadi", "doc": model.doc,
                "specialisation": spec.key(), "fixed": _fixed(model, spec),
                "free_params": [p for p in spec.free], "kind": irs[0].meta.get("kind") if irs else None,
                "sites": sites, "layout": LAYOUT, "kernels": {}}
    with tempfile.TemporaryDirectory(prefix="mechgen-export-") as work:
        path = Path(work) / f"mg_export_{model.name}.py"
        path.write_text(text, encoding="utf-8")
        module = load_module(path, path.stem)
        for ir, renamed in zip(irs, named):
            sizes, slots, pattern = {}, {}, None
            if ir.slot_ports():
                pattern = build_pattern(kernel_spec(renamed), sites)
                sizes, slots = {"sites": sites, "nnz": pattern.nnz}, pattern.slots
            elif ir.sizes:
                sizes = {"sites": sites}
            fn = getattr(module, f"build_{renamed.name}")(sizes, slots)
            fname = f"{renamed.name}.casadi"
            fn.save(str(Path(work) / fname))
            files[fname] = (Path(work) / fname).read_bytes()
            ins = [{"name": p.name, "length": p.extent.evaluate(sizes), "entries": _entry_names(ir, p, sites)}
                   for p in ir.inputs if not p.integer]
            outs = []
            for p in ir.outputs:
                o = {"name": p.name, "length": p.extent.evaluate(sizes), "shape": list(p.shape) if p.shape else None,
                     "sparse": p.sparse, "symmetric": p.symmetric}
                if p.sparse:
                    o["pattern"] = {"rows": sites, "cols": sites, "indptr": pattern.indptr.tolist(),
                                    "indices": pattern.indices.tolist()}
                outs.append(o)
            manifest["kernels"][ir.name] = {"file": fname, "function": renamed.name, "doc": ir.doc,
                                            "pointwise": ir.meta.get("kind") == "field",
                                            "inputs": ins, "outputs": outs}
    files[f"{model.name}.json"] = json.dumps(manifest, indent=2, sort_keys=False, default=str) + "\n"
    return files


# --------------------------------------------------------------------------- entry point

def planned_files(model, backend: str, kernels) -> list[str]:
    """Names of the files an export writes."""
    if backend == "c":
        return [f"{model.name}.h", f"{model.name}.c"]
    return [f"{model.name}_{k}.casadi" for k in kernels] + [f"{model.name}.json"]


def export_model(ref, backend: str, out, *, sets=(), kernels=None) -> list[Path]:
    """Export the kernels of model ``ref`` for ``backend`` ('c' or 'casadi') into folder ``out``.

    Returns the paths written. Raises InputError (naming ``--set NAME``, ``--kernels``,
    ``--out`` or ``--backend``) on bad input, before anything is written.
    """
    from mechgen import models

    if backend not in EXPORT_BACKENDS:
        raise _fail("--backend", f"unknown export backend {backend!r}", "one of: " + ", ".join(EXPORT_BACKENDS))
    if backend == "casadi" and importlib.util.find_spec("casadi") is None:
        raise _fail("--backend", "the casadi backend needs the casadi package, which is not installed",
                    "backend c, or casadi installed (pip install casadi)")
    model = ref if hasattr(ref, "param_list") else models.load_model(str(ref))
    out = Path(out)
    values = parse_sets(model, list(sets))
    names = _kernels(model, kernels)
    check_out_dir(out, planned_files(model, backend, names))
    spec = _specialised(model, values)
    irs = _lowered(model, spec, names)
    if backend == "c":
        from mechgen.codegen.emit_c_export import emit_c_export

        header, source = emit_c_export(irs, _facts(model, spec))
        contents = {f"{model.name}.h": header, f"{model.name}.c": source}
    else:
        contents = _casadi_files(model, spec, irs)
    return write_atomically(out, contents)


__all__ = ["EXPORT_BACKENDS", "export_model", "parse_sets", "check_out_dir", "write_atomically", "planned_files"]
